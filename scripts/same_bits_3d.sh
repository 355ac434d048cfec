#!/usr/bin/env bash
# Do two rkforge binaries give the same bits on the 3D scenes? Runs each shipped 3D scene
# (every scenes/*.toml with `kinematics = "3d"`), shortened to a fraction of its end time
# (FRACTION, default 0.2: contact in every scene), single-threaded and without frames,
# through both binaries and compares history.csv byte for byte (scripts/same_bits.sh does
# the 2D scenes, frames and summaries).
#   scripts/same_bits_3d.sh OLD_BINARY NEW_BINARY [OUT_DIR]
# IGNORE_OUTPUTS="name ..." leaves out the history columns `<...>.name` that the new build
#   adds (as scripts/same_bits.sh does); every other column must match byte for byte.
set -euo pipefail
old=$1 new=$2 out=${3:-/tmp/same_bits_3d}
fraction=${FRACTION:-0.2}
cd "$(dirname "$0")/.."
rm -rf "$out" && mkdir -p "$out"
status=0
for scene in $(grep -l '^kinematics = "3d"' scenes/*.toml); do
  name=$(basename "$scene" .toml)
  end=$(python3 -c "import tomllib; print(tomllib.load(open('$scene', 'rb'))['time']['end_s'] * $fraction)")
  run() {
    "$1" run "$scene" --no-frames --quiet --threads 1 --set "time.end_s=$end" \
      --out "$out/$name.$2" > "$out/$name.$2.log" 2>&1
  }
  if ! run "$new" new; then
    echo "failed: $name with the new binary, see $out/$name.new.log"
    status=1
    continue
  fi
  if ! run "$old" old; then
    echo "only the new binary runs: $name (see $out/$name.old.log)"
    continue
  fi
  if python3 - "$out/$name.old/history.csv" "$out/$name.new/history.csv" <<'PY'
import os, sys
ignored = set(os.environ.get("IGNORE_OUTPUTS", "").split())
def kept(path):
    rows = [line.rstrip("\n").split(",") for line in open(path)]
    keep = [k for k, c in enumerate(rows[0]) if c.rsplit(".", 1)[-1] not in ignored]
    return [[r[k] for k in keep] for r in rows]
sys.exit(0 if kept(sys.argv[1]) == kept(sys.argv[2]) else 1)
PY
  then
    echo "same bits: $name (to t = $end s)"
  else
    echo "DIFFERENT: $name (to t = $end s)"
    status=1
  fi
done
exit $status
