#!/usr/bin/env bash
# Stage profile of the shipped scenes (docs/performance.md): runs each scene with each rule
# (`rkforge run --no-frames`) and prints the stage times of summary.json as a Markdown table.
#   scripts/stage_profile.sh [scene.toml ...]   (default: the three shipped scenes)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p rkforge
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(scenes/taylor_bar.toml scenes/block_forging.toml scenes/wheel_forging.toml)
out=$(mktemp -d)
echo "| scene | rule | steps | wall (s) | setup (s) | of which shape functions | stress + scatter | force gather + predictor | contact | integration | output | other | us / step | ns / point-step |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for scene in "${scenes[@]}"; do
  for rule in q4 q2 scni; do
    ./target/release/rkforge run "$scene" --integration "$rule" --out "$out/run" --quiet --no-frames > /dev/null
    python3 - "$out/run/summary.json" "$(basename "$scene" .toml)" "$rule" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); t = s["stage_seconds"]; wall = s["wall_s"]
run = wall - t["setup"]
pct = lambda k: f"{t[k]:.2f} s ({100 * t[k] / run:.0f} %)"
other = run - t["stress"] - t["internal_force"] - t["contact"] - t["integration"] - t["output"]
steps = s["steps"]
print(f"| {sys.argv[2]} | {sys.argv[3]} | {steps} | {wall:.2f} | {t['setup']:.2f} | {t['shape_functions']:.2f} | "
      f"{pct('stress')} | {pct('internal_force')} | {pct('contact')} | {pct('integration')} | {pct('output')} | "
      f"{other:.2f} s ({100 * other / run:.0f} %) | {1e6 * run / steps:.0f} | {1e9 * t['stress'] / steps / s['integration_points']:.0f} |")
PY
  done
done
