#!/usr/bin/env bash
# Volumetric locking at near-incompressibility (docs/accuracy.md): the Taylor bar on the
# 11 x 26 and 21 x 51 grids with Poisson's ratio 0.35 (the paper's copper), 0.49 and 0.499,
# each rule, adaptive step (dt_safety 0.5). Prints final radius and height per case.
#   scripts/locking.sh                                    (about 20 minutes on 2 cores)
#   GRIDS="21,51" NUS="0.499" scripts/locking.sh          (a subset)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p rkforge
out=$(mktemp -d)
echo "| grid | nu | rule | steps | wall (s) | radius (mm) | height (mm) | volume change |"
echo "|---|---|---|---|---|---|---|---|"
for grid in ${GRIDS:-11,26 21,51}; do
  grid=${grid/,/, }
  for nu in ${NUS:-0.35 0.49 0.499}; do
    sed -e "s/^particles = .*/particles = [$grid]/" -e "s/^poisson_ratio = .*/poisson_ratio = $nu/" \
        -e "s/^dt_s = .*/dt_safety = 0.5/" scenes/taylor_bar.toml > "$out/scene.toml"
    for rule in q4 q2 scni; do
      ./target/release/rkforge run "$out/scene.toml" --integration "$rule" --out "$out/run" --quiet --no-frames > /dev/null
      python3 -c "
import json, sys
s = json.load(open('$out/run/summary.json'))
w = s['workpiece']
print(f\"| ${grid/, /x} | $nu | $rule | {s['steps']} | {s['wall_s']:.1f} | {w['radius_m']*1e3:.3f} | {w['height_m']*1e3:.3f} | {w['volume_change_rel']:.2e} |\")"
    done
  done
done
