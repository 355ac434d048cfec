#!/usr/bin/env bash
# The 3D quarter Taylor bar (scenes/taylor_bar_3d.toml) on three grids, each cell count
# doubled in every direction, against the converged finite-element answer (Foulk et al.
# 2021: 7.226 / 21.42 mm) and rkforge's own axisymmetric run with the same wall and rule
# (docs/accuracy.md, issue 17: q2 with the FE wall extrapolates to 7.2266 / 21.4303 mm).
# Prints a row per run (particles, steps, wall time, us per particle-step, impact-face
# radius, length, deepest penetration of the wall and beyond a symmetry plane), then the
# Richardson extrapolation of the three grids: observed order p = log2((f1 - f2) / (f2 -
# f3)), limit f3 + (f3 - f2) / (2^p - 1), with the finest run's distance from it as the
# uncertainty, against each of REFERENCES ("label:radius_mm,length_mm ...").
#   scripts/taylor_3d.sh                      (the finest grid, about 26,000 particles, takes minutes)
#   GRIDS="4,2,30 8,4,60" RULES="q2 q4" SETS="discretization.support=1.5" scripts/taylor_3d.sh
# Another bar: SCENE=taylor_ofhc_3d GRIDS="4,2,24 8,4,48 16,8,96" REFERENCES="axisymmetric:R,L"
# (the OFHC bar against its axisymmetric run, docs/accuracy.md).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p rkforge
out=${OUT:-$(mktemp -d)}
mkdir -p "$out"
sets=()
for s in ${SETS:-}; do sets+=(--set "$s"); done
echo "| cells | rule | particles | steps | wall time (s) | us per particle-step | radius (mm) | length (mm) | in the wall (um) | beyond a plane (um) |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for rule in ${RULES:-q2}; do
  for grid in ${GRIDS:-4,2,30 8,4,60 16,8,120}; do
    name="${grid//,/x}_$rule"
    ./target/release/rkforge run "scenes/${SCENE:-taylor_bar_3d}.toml" --integration "$rule" \
      --set "workpiece.cells=[${grid//,/, }]" "${sets[@]}" --out "$out/$name" --quiet --no-frames > /dev/null
    python3 - "$out/$name/summary.json" "$grid" "$rule" >> "$out/rows" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
w, c = s['workpiece'], s['contact']
print(f"{sys.argv[2]} {sys.argv[3]} {w['radius_m']*1e3:.6f} {w['height_m']*1e3:.6f}")
print(f"| {sys.argv[2]} | {sys.argv[3]} | {s['particles']} | {s['steps']} | {s['wall_s']:.1f} | {s['us_per_particle_step']:.3f} | "
      f"{w['radius_m']*1e3:.4f} | {w['height_m']*1e3:.4f} | {c['max_penetration_m']*1e6:.3f} | {c['max_beyond_plane_m']*1e6:.3f} |", file=sys.stderr)
PY
  done
done
python3 - "$out/rows" "${REFERENCES:-FE:7.226,21.42 axisymmetric_q2:7.2266,21.4303}" <<'PY'
import math, sys
rows = [l.split() for l in open(sys.argv[1])]
refs = [(label, [float(x) for x in values.split(",")])
        for label, values in (r.split(":") for r in sys.argv[2].split())]
by_rule = {}
for grid, rule, r, l in rows:
    by_rule.setdefault(rule, []).append((float(r), float(l)))
print()
print("| rule | quantity | observed order | extrapolated (mm) | uncertainty (mm) | " + " | ".join(f"against {l}" for l, _ in refs) + " |")
print("|---|---|---|---|---|" + "---|" * len(refs))
for rule, fs in by_rule.items():
    if len(fs) != 3:
        continue
    for k, name in enumerate(["radius", "length"]):
        f1, f2, f3 = (f[k] for f in fs)
        if (f1 - f2) * (f2 - f3) <= 0:
            against = " | ".join(f"{100*(f3/v[k]-1):+.2f} % (finest)" for _, v in refs)
            print(f"| {rule} | {name} | not monotone ({f1:.4f}, {f2:.4f}, {f3:.4f}) | - | - | {against} |")
            continue
        p = math.log2((f1 - f2) / (f2 - f3))
        lim = f3 + (f3 - f2) / (2**p - 1)
        against = " | ".join(f"{100*(lim/v[k]-1):+.2f} %" for _, v in refs)
        print(f"| {rule} | {name} | {p:.2f} | {lim:.4f} | {abs(f3 - lim):.4f} | {against} |")
PY
