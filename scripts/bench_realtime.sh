#!/usr/bin/env bash
# Can a controller developer run a press in real time? The mass-scaled block forging at a
# hydraulic press's speed (scenes/block_forging_press.toml: 6 s of press time) at several
# resolutions: the solver's wall time against the 6 s it simulates (rkforge run --no-frames,
# the loop the ROS node runs; the node adds its publishing, measured at 4-9 % in README's
# table), then the ROS node itself at --real-time-factor 1 at the largest resolution that
# kept pace, timed as a whole process (it paces to 6 s when it keeps up, and takes longer
# when it falls behind).
#   scripts/bench_realtime.sh [N...]     default: 11 16 21 26 31 41
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${RKFORGE_BIN:-target/release/rkforge}
ros=${RKFORGE_ROS_BIN:-target/release/rkforge-ros}
sizes=${*:-11 16 21 26 31 41}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
best=""
for n in $sizes; do
  "$bin" run scenes/block_forging_press.toml --set "workpiece.particles=[$n,$n]" --out "$out/run" --no-frames --quiet > /dev/null
  wall=$(python3 -c "import json,sys; s=json.load(open(sys.argv[1])); print(s['wall_s'])" "$out/run/summary.json")
  keeps=$(python3 -c "import sys; print('yes' if float(sys.argv[1]) < 6.0 / 1.1 else 'no')" "$wall")
  echo "${n}x${n}: ${wall} s wall for 6 s of press time; keeps pace with 10 % margin: $keeps"
  [ "$keeps" = yes ] && best=$n
done
if [ -n "$best" ] && [ -x "$ros" ]; then
  sed "s/^particles = .*/particles = [$best, $best]/" scenes/block_forging_press.toml > "$out/scene.toml"
  start=$(date +%s.%N)
  ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-199} "$ros" "$out/scene.toml" --real-time-factor 1 2> "$out/ros.log"
  end=$(date +%s.%N)
  python3 -c "import sys; print(f'rkforge-ros {sys.argv[3]}x{sys.argv[3]} at --real-time-factor 1: {float(sys.argv[2]) - float(sys.argv[1]):.2f} s for 6 s of press time (start-up and a 0.3 s linger included)')" "$start" "$end" "$best"
fi
