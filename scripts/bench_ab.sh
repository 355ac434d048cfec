#!/usr/bin/env bash
# Wall time of a run (summary.json's wall_s: setup and steps, in the process) for two or
# more rkforge binaries, alternated run by run (the machine's speed drifts over minutes, so
# builds measured one after the other are not comparable), then the median and minimum per
# binary and each median over the first binary's. The Taylor bar at the paper's settings
# unless SCENE names another scene file.
#   scripts/bench_ab.sh N RULE BINARY...   e.g. scripts/bench_ab.sh 9 q2 /tmp/old/rkforge target/release/rkforge
#   SCENE=scenes/block_forging.toml scripts/bench_ab.sh 5 q2 OLD NEW
# An older build: git worktree add /tmp/old <commit> && cargo build --release -p rkforge
#   --manifest-path /tmp/old/Cargo.toml (its binary is /tmp/old/target/release/rkforge).
set -euo pipefail
cd "$(dirname "$0")/.."
n=$1; rule=$2; shift 2
out=$(mktemp -d)
for _ in $(seq "$n"); do
  for b in "$@"; do
    "$b" run "${SCENE:-scenes/taylor_bar.toml}" --integration "$rule" --out "$out/run" --no-frames --quiet > /dev/null
    python3 -c "import json,sys; print(sys.argv[1], json.load(open(sys.argv[2]))['wall_s'])" "$b" "$out/run/summary.json" >> "$out/times"
  done
done
python3 - "$out/times" "$rule" <<'PY'
import collections, statistics, sys
times = collections.defaultdict(list)
for line in open(sys.argv[1]):
    b, t = line.rsplit(" ", 1)
    times[b].append(float(t))
first = statistics.median(next(iter(times.values())))
for b, t in times.items():
    m = statistics.median(t)
    print(f"{sys.argv[2]} {b}: median {m:.3f} s, min {min(t):.3f} s, {len(t)} runs, {m / first:.3f} of the first")
PY
