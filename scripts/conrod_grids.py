#!/usr/bin/env python3
"""The conrod's grid study: the die's force and work on several grids, with one mass scaling.

Runs `scenes/conrod_3d.toml` on the grids given (particles along x, y, z of the eighth bar),
each with the same mass scaling (every mass times 2000 unless told: the scene's target step
would add more mass on a finer grid, docs/forging.md "One mass for every grid"), and
prints one row per grid: the force at chosen strokes, the end force at 9 mm, the mean force
over the last half millimetre (the die's work from 8.5 to 9 mm over 0.5 mm), the work to
9 mm, the stroke at which the force first reaches 300 and 350 kN (`s@300`, `s@350`: the end's
steep rise read along the stroke, where a force read at one stroke moves with the instant
the cavity fills), the added mass and the largest kinetic to internal
energy ratio. Then, for each figure, the three finest grids' Richardson estimate
as Celik et al. (2008, "Procedure for estimation and reporting of uncertainty due to
discretization in CFD applications", J. Fluids Eng. 130, 078001) give it for grids refined
by unequal ratios: the observed order p, the extrapolated value and the fine grid's
convergence index GCI = 1.25 |e_a| / (r^p - 1); for differences of alternating sign whose
size falls as the grid refines (oscillating convergence), the uncertainty as half the
range of the three (Stern et al. 2001, "Comprehensive approach to verification and
validation of CFD simulations - Part 1", J. Fluids Eng. 123, 793-802); or why there is none.
Given four grids or more, the force at 9 mm is also assessed on every triple of neighbouring
grids, to show whether the grids before the finest three behave alike.

    scripts/conrod_grids.py --out out/conrod_grids
    scripts/conrod_grids.py --out out/conrod_grids --grids 29x8x12,41x11x17,57x15x23 --reuse

The grid spacing is h = (V / cells)^(1/3), V the eighth bar's volume and cells the lattice's
(nx - 1)(ny - 1)(nz - 1). Runs go one after the other on one thread each (`--threads`);
`--reuse` reads the runs already in --out. Uses target/release/rkforge (or $RKFORGE_BIN).
A run on the 0.42 mm grid at one mass takes two hours here (6861 s, 55 127 steps).
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "conrod_3d.toml"
BAR_MM = (28.0, 7.0, 11.0)
GRIDS = ["29x8x12", "41x11x17", "57x15x23", "68x18x27"]
STROKES_MM = [5.0, 7.0, 8.0, 8.5, 9.0]
FORCES_KN = [300.0, 350.0]


def spacing_mm(grid):
    nx, ny, nz = grid
    return (BAR_MM[0] * BAR_MM[1] * BAR_MM[2] / ((nx - 1) * (ny - 1) * (nz - 1))) ** (1 / 3)


def scaling_override(scaling):
    kind, _, value = scaling.partition("=")
    key = {"factor": "factor", "target": "target_dt_s"}.get(kind)
    try:
        number = float(value)
    except ValueError:
        number = None
    if key is None or number is None or number <= 0.0:
        sys.exit(f"--scaling: `{scaling}` is not factor=F, target=T (a positive number) or scene")
    return f"time.mass_scaling={{{key}={number!r}}}"


def run(binary, grid, scaling, out, threads):
    cmd = [binary, "run", str(SCENE), "--quiet", "--no-frames", "--threads", str(threads),
           "--set", f"workpiece.particles=[{grid[0]}, {grid[1]}, {grid[2]}]", "--out", str(out)]
    if scaling != "scene":
        cmd += ["--set", scaling_override(scaling)]
    print(" ".join(cmd), flush=True)
    subprocess.run(cmd, check=True)


def figures(out):
    """The run's figures (kN, J, -) from its history.csv and summary.json."""
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    stroke = [float(r["die.stroke_m"]) * 1e3 for r in rows]
    force = [abs(float(r["die.force_N"])) / 1e3 for r in rows]
    work = [float(r["energy.tool_work_J"]) for r in rows]

    def at(values, s):
        for k in range(1, len(stroke)):
            if stroke[k] >= s - 1e-9:
                t = (s - stroke[k - 1]) / (stroke[k] - stroke[k - 1])
                return values[k - 1] + t * (values[k] - values[k - 1])
        raise SystemExit(f"{out}: the run ends at {stroke[-1]:.3f} mm, before {s} mm")

    def reaching(f):
        """The stroke (mm) at which the force first reaches f kN, interpolated."""
        for k in range(1, len(stroke)):
            if force[k] >= f:
                t = (f - force[k - 1]) / (force[k] - force[k - 1])
                return stroke[k - 1] + t * (stroke[k] - stroke[k - 1])
        return math.nan

    summary = json.loads((out / "summary.json").read_text())
    fig = {f"F{s:g}": at(force, s) for s in STROKES_MM}
    fig["mean8.5-9"] = (at(work, 9.0) - at(work, 8.5)) / 0.5
    fig["W9"] = at(work, 9.0)
    for f in FORCES_KN:
        fig[f"s@{f:g}"] = reaching(f)
    fig["added"] = summary.get("mass_scaling", {}).get("added_mass_rel", 0.0)
    fig["K/I"] = summary["energy"]["kinetic_to_internal_max"]
    fig["steps"] = summary["steps"]
    return fig


def celik(h, phi, digits=1):
    """Celik et al. (2008) for three grids, h[0] the finest: (p, extrapolated, GCI) or a
    reason why no estimate exists."""
    if any(math.isnan(v) for v in phi):
        return "a grid never reaches it"
    r21, r32 = h[1] / h[0], h[2] / h[1]
    e21, e32 = phi[1] - phi[0], phi[2] - phi[1]
    if e21 == 0.0 or e32 == 0.0:
        return "two grids agree exactly"
    diffs = f"differences {e21:+.{digits + 1}f} fine, {e32:+.{digits + 1}f} coarse"
    if e32 / e21 < 0.0:
        if abs(e21) < abs(e32):
            half = (max(phi) - min(phi)) / 2.0
            mid = (max(phi) + min(phi)) / 2.0
            return (f"oscillating convergence ({diffs}): {mid:.{digits}f} +- {half:.{digits}f} "
                    f"({100 * half / mid:.2f} %, half the range)")
        return f"oscillates with a growing amplitude ({diffs})"
    if abs(e32) <= abs(e21):
        return f"diverges ({diffs}: they grow as the grid refines)"
    p = math.log(abs(e32 / e21)) / math.log(r21)
    for _ in range(200):
        q = math.log((r21**p - 1.0) / (r32**p - 1.0))
        p_new = abs(math.log(abs(e32 / e21)) + q) / math.log(r21)
        if abs(p_new - p) < 1e-12:
            break
        p = p_new
    ext = (r21**p * phi[0] - phi[1]) / (r21**p - 1.0)
    gci = 1.25 * abs((phi[0] - phi[1]) / phi[0]) / (r21**p - 1.0)
    return p, ext, gci


def describe(est, digits=1):
    """One line for a `celik` result: the estimate, or the reason there is none."""
    if isinstance(est, str):
        return est
    p, ext, gci = est
    return f"order {p:.2f}, extrapolated {ext:.{digits}f}, GCI {100 * gci:.2f} %"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--grids", default=",".join(GRIDS),
                    help="particles along x, y, z per grid, coarse to fine: 29x8x12,41x11x17,...")
    ap.add_argument("--scaling", default="factor=2000",
                    help="factor=F (every mass times F; the default, 2000, is the 1 mm grid's "
                         "with the scene's target step), target=T (selective, to a step of T "
                         "s: more mass on a finer grid) or scene")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--reuse", action="store_true", help="read the runs already in --out")
    args = ap.parse_args()
    binary = os.environ.get("RKFORGE_BIN", str(ROOT / "target" / "release" / "rkforge"))
    if args.scaling != "scene":
        scaling_override(args.scaling)
    grids = []
    for g in args.grids.split(","):
        try:
            nx, ny, nz = (int(n) for n in g.split("x"))
        except ValueError:
            sys.exit(f"--grids: `{g}` is not NXxNYxNZ (three whole numbers)")
        grids.append((nx, ny, nz))
    rows = []
    for grid in grids:
        out = args.out / "x".join(map(str, grid))
        if not args.reuse:
            run(binary, grid, args.scaling, out, args.threads)
        rows.append((spacing_mm(grid), figures(out)))
    keys = list(rows[0][1])
    print(f"\nmass scaling: {args.scaling}\n")
    print("| h (mm) | " + " | ".join(keys) + " |")
    print("|---" * (len(keys) + 1) + "|")
    for h, fig in rows:
        cells = [f"{fig[k]:.4f}" if k == "K/I" else f"{fig[k]:.3f}" if k.startswith("s@")
                 else f"{fig[k]:.1f}" if isinstance(fig[k], float)
                 else str(fig[k]) for k in keys]
        print(f"| {h:.3f} | " + " | ".join(cells) + " |")
    if len(rows) >= 3:
        fine = rows[-3:][::-1]
        h = [r[0] for r in fine]
        print(f"\nthe three finest grids (h = {h[0]:.3f}, {h[1]:.3f}, {h[2]:.3f} mm):")
        for k in keys[: len(STROKES_MM) + 2] + [f"s@{f:g}" for f in FORCES_KN]:
            digits = 3 if k.startswith("s@") else 1
            print(f"  {k}: {describe(celik(h, [r[1][k] for r in fine], digits), digits)}")
    if len(rows) >= 4:
        print("\nthe force at 9 mm over each triple of neighbouring grids (coarse to fine):")
        for k in range(len(rows) - 2):
            triple = rows[k:k + 3][::-1]
            h = [r[0] for r in triple]
            est = describe(celik(h, [r[1]["F9"] for r in triple]))
            print(f"  h = {h[2]:.3f} / {h[1]:.3f} / {h[0]:.3f} mm: {est}")


if __name__ == "__main__":
    main()
