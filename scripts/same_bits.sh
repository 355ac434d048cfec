#!/usr/bin/env bash
# Do two rkforge binaries give the same bits? Runs coarse versions of every shipped scene with
# every rule (fixed and adaptive steps, with and without frames) through both and compares
# history.csv, the VTK frames and summary.json (less the wall and stage times) byte for byte.
#   scripts/same_bits.sh OLD_BINARY NEW_BINARY
#   FULL=1 scripts/same_bits.sh OLD_BINARY NEW_BINARY   the shipped scenes as they are (minutes)
#   scripts/same_bits.sh OLD_DIR NEW_DIR   two build directories (target/release): the command
#     line as above, then every case through the FMU (DIR/rkforge fmu, simulated by fmpy), the
#     ROS node's recording (DIR/rkforge-ros --record) and, where DIR/same_bits_python holds the
#     build's Python package, rkforge.run (scripts/same_bits_front_ends.py, run by $PYTHON,
#     default .venv/bin/python, which needs fmpy, mcap, numpy and pandas).
# An older build: git worktree add /tmp/old <commit> && cd /tmp/old &&
#   CARGO_TARGET_DIR=/tmp/old/target cargo build --release --workspace
#   (its binaries are in /tmp/old/target/release); its Python package:
#   maturin build --release -m python/Cargo.toml --out /tmp/old/wheel && pip install --no-deps
#   --target /tmp/old/target/release/same_bits_python /tmp/old/wheel/rkforge-*.whl
# IGNORE_OUTPUTS="name ..." leaves out of the comparison the register's outputs of those names
#   (rkforge_core::outputs, e.g. pressure_mean_Pa) that the new build adds: their history.csv
#   columns (`<...>.name`) and summary.json keys are removed from both sides before comparing;
#   everything else must match byte for byte.
# Exit status 0 when every case matches, 1 otherwise (each difference is printed).
set -euo pipefail
cd "$(dirname "$0")/.."
old=$1; new=$2
dirs=0
if [ -d "$old" ] && [ -d "$new" ]; then
  dirs=1; old_dir=$(cd "$old" && pwd); new_dir=$(cd "$new" && pwd)
  old=$old_dir/rkforge; new=$new_dir/rkforge
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# name  scene  particles  end_s  keep the fixed step (1) or use dt_safety (0)
cases="taylor scenes/taylor_bar.toml [11,26] 40.0e-6 1
taylor_adaptive scenes/taylor_bar.toml [11,26] 40.0e-6 0
block scenes/block_forging.toml [11,11] 0.015 1
wheel scenes/wheel_forging.toml [15,15] 1.0e-3 1
hub scenes/closed_die_hub.toml [11,31] 0.03 1
ring scenes/ring_compression.toml [11,7] 1.025e-3 1
upsetting scenes/press_upsetting.toml [6,16] 0.3 1
block_press scenes/block_forging_press.toml [11,11] 1.0 1
wheel_press scenes/wheel_forging_press.toml [15,15] 0.2 1
flash scenes/flash_quarter.toml [21,13] 0.044 1
pin scenes/lap_around_pin.toml [21,11] 0.038 1
hot_upsetting scenes/hot_upsetting.toml [6,16] 0.3 1
hot_hub scenes/closed_die_hub_hot.toml [11,31] 0.03 1
ofhc scenes/taylor_ofhc.toml [6,34] 40.0e-6 1"
if [ "${FULL:-0}" = 1 ]; then
  cases=$(for f in scenes/*.toml; do echo "$(basename "$f" .toml) $f - - 1"; done)
fi
strip() {
  python3 - "$1" <<'PY'
import json, os, sys
ignored = set(os.environ.get("IGNORE_OUTPUTS", "").split())
def drop(v):
    if isinstance(v, dict):
        return {k: drop(x) for k, x in v.items() if k not in ignored}
    if isinstance(v, list):
        return [drop(x) for x in v]
    return v
s = drop(json.load(open(sys.argv[1])))
for k in ("wall_s", "stage_seconds", "us_per_particle_step"):
    s.pop(k, None)
print(json.dumps(s, indent=1, sort_keys=True))
PY
}
# history.csv less the IGNORE_OUTPUTS columns, as it is when there are none.
history() {
  if [ -z "${IGNORE_OUTPUTS:-}" ]; then cat "$1"; return; fi
  python3 - "$1" <<'PY'
import os, sys
ignored = set(os.environ["IGNORE_OUTPUTS"].split())
lines = open(sys.argv[1]).read().splitlines()
keep = [k for k, c in enumerate(lines[0].split(",")) if c.rsplit(".", 1)[-1] not in ignored]
for line in lines:
    cells = line.split(",")
    print(",".join(cells[k] for k in keep))
PY
}
failed=0
front_cases=""
while read -r name scene particles end fixed; do
  if [ "$particles" = - ]; then
    cp "$scene" "$work/$name.toml"
  else
    sed -e "s/^particles = .*/particles = $particles/" -e "s/^end_s = .*/end_s = $end/" "$scene" > "$work/$name.toml"
  fi
  if [ "$fixed" = 0 ]; then sed -i -e '/^dt_s = /d' "$work/$name.toml"; fi
  for rule in q4 q2 scni; do
    for frames in "--no-frames" ""; do
      tag="$name $rule ${frames:-frames}"
      for b in old new; do
        bin=$old; [ "$b" = new ] && bin=$new
        rm -rf "$work/$b"
        "$bin" run "$work/$name.toml" --integration "$rule" --out "$work/$b" --quiet $frames > "$work/$b.log" 2>&1 || true
        strip "$work/$b/summary.json" > "$work/$b.summary"
        history "$work/$b/history.csv" > "$work/$b.history" || true
      done
      if ! grep -q '"status": "ok"' "$work/new/summary.json"; then
        echo "FAILED run: $tag"; cat "$work/new.log"; failed=1
      elif ! cmp -s "$work/old.history" "$work/new.history"; then
        echo "DIFFERENT history.csv: $tag"; failed=1
      elif ! cmp -s "$work/old.summary" "$work/new.summary"; then
        echo "DIFFERENT summary.json: $tag"; { diff "$work/old.summary" "$work/new.summary" || true; } | head -20; failed=1
      elif [ -z "$frames" ] && ! diff -rq "$work/old/frames" "$work/new/frames" > /dev/null; then
        echo "DIFFERENT frames: $tag"; failed=1
      else
        echo "same bits: $tag ($(wc -l < "$work/new/history.csv") history rows)"
      fi
    done
  done
  front_cases="$front_cases $work/$name.toml:q4 $work/$name.toml:q2 $work/$name.toml:scni"
done <<< "$cases"
if [ "$dirs" = 1 ]; then
  "${PYTHON:-.venv/bin/python}" scripts/same_bits_front_ends.py "$old_dir" "$new_dir" $front_cases || failed=1
fi
exit $failed
