#!/usr/bin/env bash
# Wall time of the full Taylor bar (paper settings: 21 x 51 particles, dt 5e-9 s, 16 000
# steps) with q2 and q4, alternating the rules over N runs, then medians and their ratio.
#   scripts/bench_taylor.sh [N=5] [extra rkforge args, e.g. --threads 1]
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-5}; shift || true
cargo build --release -q -p rkforge
out=$(mktemp -d)
for i in $(seq "$n"); do
  for rule in q2 q4; do
    ./target/release/rkforge run scenes/taylor_bar.toml --integration "$rule" --out "$out/$rule" --quiet --no-frames "$@" > /dev/null
    python3 -c "import json,sys; s=json.load(open('$out/$rule/summary.json')); print(sys.argv[1], s['wall_s'], s['steps'], s['threads'], s['workpiece']['radius_m'], s['workpiece']['height_m'])" "$rule" >> "$out/times"
  done
done
python3 - "$out/times" <<'PY'
import statistics, sys
rows = [l.split() for l in open(sys.argv[1])]
med = {}
for rule in ("q2", "q4"):
    t = [float(r[1]) for r in rows if r[0] == rule]
    last = [r for r in rows if r[0] == rule][-1]
    med[rule] = statistics.median(t)
    print(f"{rule}: median {med[rule]:.2f} s over {len(t)} runs (min {min(t):.2f}, max {max(t):.2f}), "
          f"{last[2]} steps, {last[3]} threads, radius {float(last[4])*1e3:.3f} mm, height {float(last[5])*1e3:.3f} mm")
print(f"q2 / q4 wall time: {med['q2'] / med['q4']:.3f} (paper Table 5: 0.52)")
PY
