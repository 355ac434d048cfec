#!/usr/bin/env bash
# Taylor bar convergence against the finite-element benchmark (docs/accuracy.md, issue 17):
# each grid and rule with the rkforge wall (particles may lift off, `separation = true`)
# and the FE wall (`separation = false`: a particle that reached the wall stays on it),
# adaptive step (dt_safety 0.5). Prints one table row per run: the bar's largest radius
# and height, the impact-face radius (largest r of the particles that started on z = 0)
# and the free-face length (largest z of the particles that started on the top face), and
# the largest distance of an impact-face particle from the wall (z = 0) at the end.
#   scripts/taylor_wall.sh                                  (81 x 201 runs take minutes each)
#   GRIDS="21,51 41,101" RULES="scni" WALLS="false" scripts/taylor_wall.sh
# WALLS="constraint" holds the impact face by an essential condition instead (u_z = 0 on
# the edge y_min, on the physical displacement), the wall still there, lifting off.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p rkforge
out=${OUT:-$(mktemp -d)}
mkdir -p "$out"
echo "| grid | rule | wall | steps | wall time (s) | radius (mm) | height (mm) | impact-face radius (mm) | free-face length (mm) | impact face off the wall (um) |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for grid in ${GRIDS:-21,51 41,101 81,201}; do
  g=${grid/,/, }
  for sep in ${WALLS:-true false}; do
    for rule in ${RULES:-scni q2}; do
      while [ -n "${QUIET_FILE:-}" ] && [ -e "$QUIET_FILE" ]; do sleep 30; done
      name="${grid/,/x}_${rule}_sep_$sep"
      held=$sep; extra=()
      if [ "$sep" = constraint ]; then
        held=true
        extra=(-e 's/^\[\[tools\]\]/[[constraints]]\nedge = "y_min"\nfix = ["y"]\n\n[[tools]]/')
      fi
      sed -e "s/^particles = .*/particles = [$g]/" -e "s/^dt_s = .*/dt_safety = 0.5/" \
          -e "s/^friction = 0.0/friction = 0.0\nseparation = $held/" "${extra[@]}" \
          -e "s/^frames = .*/frames = 0\nfaces = [\"y_min\", \"y_max\"]/" \
          scenes/taylor_bar.toml > "$out/$name.toml"
      ./target/release/rkforge run "$out/$name.toml" --integration "$rule" --out "$out/$name" --quiet --no-frames > /dev/null
      python3 -c "
import json
s = json.load(open('$out/$name/summary.json'))
w = s['workpiece']
a, b = w['face_y_min'], w['face_y_max']
print(f\"| ${grid/,/x} | $rule | {dict(true='lift-off', false='FE (held)', constraint='u_z = 0 (constraint)')['$sep']} | {s['steps']} | {s['wall_s']:.1f} | {w['radius_m']*1e3:.4f} | {w['height_m']*1e3:.4f} | {a['x_max_m']*1e3:.4f} | {b['y_max_m']*1e3:.4f} | {max(abs(a['y_min_m']), abs(a['y_max_m']))*1e6:.2f} |\")"
    done
  done
done
# Richardson extrapolation from the three finest grids of each rule and wall: observed
# order p = log2((f1 - f2) / (f2 - f3)), limit f3 + (f3 - f2) / (2^p - 1); the uncertainty
# is the distance of the finest run from its limit.
python3 - "$out" ${GRIDS:-21,51 41,101 81,201} <<'PY'
import json, math, os, sys
out, grids = sys.argv[1], [g.replace(',', 'x') for g in sys.argv[2:]]
print()
print("| rule | wall | quantity | grids | observed order | extrapolated (mm) | finest - extrapolated (mm) | against FE (7.226 / 21.42 mm) |")
print("|---|---|---|---|---|---|---|---|")
for sep in ("true", "false"):
    for rule in ("scni", "q2"):
        runs = []
        for g in grids:
            p = os.path.join(out, f"{g}_{rule}_sep_{sep}", "summary.json")
            if os.path.exists(p):
                w = json.load(open(p))["workpiece"]
                runs.append((g, w["face_y_min"]["x_max_m"] * 1e3, w["face_y_max"]["y_max_m"] * 1e3))
        if len(runs) < 3:
            continue
        runs = runs[-3:]
        for k, (name, fe) in enumerate((("impact-face radius", 7.226), ("free-face length", 21.42))):
            f1, f2, f3 = (r[k + 1] for r in runs)
            wall = "lift-off" if sep == "true" else "FE (held)"
            if (f1 - f2) * (f2 - f3) <= 0:
                print(f"| {rule} | {wall} | {name} | {'/'.join(r[0] for r in runs)} | not monotone | - | - | finest {100 * (f3 / fe - 1):+.2f} % |")
                continue
            p = math.log2((f1 - f2) / (f2 - f3))
            lim = f3 + (f3 - f2) / (2 ** p - 1)
            print(f"| {rule} | {wall} | {name} | {'/'.join(r[0] for r in runs)} | {p:.2f} | {lim:.4f} | {f3 - lim:+.4f} | {100 * (lim / fe - 1):+.2f} % (finest {100 * (f3 / fe - 1):+.2f} %) |")
PY
