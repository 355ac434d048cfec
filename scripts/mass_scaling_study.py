#!/usr/bin/env python3
"""Mass scaling at press speeds: what each scaling costs and buys.

Runs a shipped forging scene at a press speed unscaled (the reference) and with each mass
scaling given, and compares the tool force at chosen strokes, the final shape and the
largest kinetic-to-internal energy ratio against the reference, with the wall time and
step count of each run. Writes study.csv, study.md and (with matplotlib) force_stroke.png.

    scripts/mass_scaling_study.py block --particles 21x21 --speed 0.025 \\
        --scaling none,factor=1e2,factor=1e4,factor=1e6,target=2e-4 --out out/mass_scaling_block
    scripts/mass_scaling_study.py wheel --particles 12x12 --speed 0.02 ...
    scripts/mass_scaling_study.py ring --particles 21x14 --speed 0.01 ...

--reuse redraws the tables and the curves from the runs already in --out.

Uses target/release/rkforge (or $RKFORGE_BIN). Runs go one after the other; the wall
times are each run's own `wall_s`.
"""

import argparse
import csv
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENES = {
    # scene file, moving tools, total stroke per unit tool travel, strokes to compare (m)
    "block": ("scenes/block_forging.toml", ["top", "bottom"], 2.0, [0.03, 0.1, 0.2, 0.3]),
    "wheel": ("scenes/wheel_forging.toml", ["punch"], 1.0, [0.005, 0.01, 0.015, 0.02]),
    "ring": ("scenes/ring_compression.toml", ["platen"], 1.0, [0.001, 0.0025, 0.004, 0.005]),
}


def scene_text(name, particles, speed, scaling, samples):
    path, tools, per_travel, strokes = SCENES[name]
    text = (ROOT / path).read_text()
    end = strokes[-1] / per_travel / speed
    text = re.sub(r"(?m)^particles = .*$", f"particles = [{particles[0]}, {particles[1]}]", text)
    text = re.sub(r"velocity_m_per_s = [0-9.eE+-]+", f"velocity_m_per_s = {speed!r}", text)
    text = re.sub(r'motion = \{ kind = "table".*\}',
                  f'motion = {{ kind = "constant", velocity_m_per_s = {speed!r} }}', text)
    text = re.sub(r"(?m)^end_s = .*$", f"end_s = {end!r}", text)
    text = re.sub(r"(?m)^dt_s = .*$", "", text)
    text = re.sub(r"(?m)^dt_safety = .*$", "", text)
    text = re.sub(r"(?m)^history_interval_s = .*$", f"history_interval_s = {end / samples!r}", text)
    text = re.sub(r"(?m)^frames = .*$", "frames = 0", text)
    time = "[time]\ndt_safety = 0.9\n"
    if scaling != "none":
        kind, value = scaling.split("=")
        key = {"factor": "factor", "target": "target_dt_s"}[kind]
        time += f"mass_scaling = {{ {key} = {float(value)!r} }}\n"
    return text.replace("[time]\n", time), tools, per_travel, strokes, end


def run(binary, text, out, overrides, reuse):
    scene = out / "scene.toml"
    done = reuse and scene.exists() and scene.read_text() == text and (out / "summary.json").exists()
    if not done:
        out.mkdir(parents=True, exist_ok=True)
        scene.write_text(text)
        sets = [arg for kv in overrides for arg in ("--set", kv)]
        subprocess.run([binary, "run", str(scene), "--out", str(out), "--no-frames", "--quiet", *sets],
                       check=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    summary = json.loads((out / "summary.json").read_text())
    with open(out / "history.csv") as f:
        history = list(csv.DictReader(f))
    return summary, history


def stroke_force(row, tools):
    """Total stroke of the moving tools (m) and the force (N) along the first tool's axis,
    resisting the stroke, in one history row."""
    return sum(abs(float(row[f"{t}.stroke_m"])) for t in tools), -float(row[f"{tools[0]}.force_N"])


def force_at(history, tools, stroke):
    """Tool force (N) at the history row nearest the total stroke `stroke` (m)."""
    row = min(history, key=lambda r: abs(stroke_force(r, tools)[0] - stroke))
    return stroke_force(row, tools)[1]


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", choices=sorted(SCENES))
    p.add_argument("--particles", default="21x21")
    p.add_argument("--speed", type=float, required=True, help="tool speed (m/s)")
    p.add_argument("--scaling", default="none,factor=1e2,factor=1e4,factor=1e6",
                   help="comma-separated: none, factor=F, target=DT_S")
    p.add_argument("--samples", type=int, default=300, help="history rows over the stroke")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="scene override for every run (rkforge run --set), repeatable")
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--reuse", action="store_true",
                   help="read the runs already in --out (same scene text) instead of rerunning them "
                        "(to redraw the tables and curves; the overrides are not compared)")
    a = p.parse_args()
    binary = os.environ.get("RKFORGE_BIN", str(ROOT / "target/release/rkforge"))
    particles = [int(x) for x in a.particles.split("x")]
    rows = []
    curves = {}
    for scaling in a.scaling.split(","):
        text, tools, per_travel, strokes, end = scene_text(a.scene, particles, a.speed, scaling, a.samples)
        summary, history = run(binary, text, a.out / scaling.replace("=", "_"), a.set, a.reuse)
        ms = summary.get("mass_scaling") or {}
        row = {
            "scaling": scaling,
            "status": summary["status"],
            "steps": summary["steps"],
            "wall_s": summary["wall_s"],
            "added_mass_rel": ms.get("added_mass_rel", 0.0),
            "kinetic_to_internal_max": summary["energy"].get("kinetic_to_internal_max"),
            "height_m": summary["workpiece"]["height_m"],
            "lateral_m": summary["workpiece"].get("width_m", summary["workpiece"].get("radius_m")),
        }
        for s in strokes:
            row[f"force_at_{s * 1e3:g}mm_N"] = force_at(history, tools, s)
        rows.append(row)
        curves[scaling] = [stroke_force(h, tools) for h in history]
        print(json.dumps(row), flush=True)
    ref = rows[0]
    a.out.mkdir(parents=True, exist_ok=True)
    with open(a.out / "study.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(ref))
        w.writeheader()
        w.writerows(rows)
    force_keys = [k for k in ref if k.startswith("force_at_")]
    lines = [f"{a.scene} at {a.speed * 1e3:g} mm/s per tool, {a.particles}, dt_safety 0.9"
             f"{''.join(', ' + s for s in a.set)}; "
             f"reference: {ref['scaling']} ({ref['steps']} steps, {ref['wall_s']:.1f} s)", "",
             "| scaling | added mass | steps | wall (s) | wall / ref | KE/IE max | "
             + " | ".join(k[len('force_at_'):-2] + " force dev." for k in force_keys)
             + " | height dev. | lateral dev. |",
             "|---" * (8 + len(force_keys)) + "|"]
    for r in rows:
        dev = lambda k: (r[k] / ref[k] - 1.0) * 100.0 if ref[k] else float("nan")
        ke = r["kinetic_to_internal_max"]
        lines.append(
            f"| {r['scaling']} | {r['added_mass_rel']:.3g} | {r['steps']} | {r['wall_s']:.2f} | "
            f"{r['wall_s'] / ref['wall_s']:.4f} | {ke if ke is None else f'{ke:.3g}'} | "
            + " | ".join(f"{dev(k):+.2f} %" for k in force_keys)
            + f" | {dev('height_m'):+.3f} % | {dev('lateral_m'):+.3f} % |"
            + ("" if r["status"] == "ok" else f" ({r['status']})"))
    (a.out / "study.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not installed: no force_stroke.png", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(8, 5))
    for scaling, pts in curves.items():
        ax.plot([s * 1e3 for s, _ in pts], [f for _, f in pts], label=scaling, lw=1.2)
    ax.set_xlabel("total stroke (mm)")
    ax.set_ylabel(f"{SCENES[a.scene][1][0]} force (N)")
    ax.set_title(f"{a.scene} at {a.speed * 1e3:g} mm/s, {a.particles}")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.savefig(a.out / "force_stroke.png", dpi=110, bbox_inches="tight")


if __name__ == "__main__":
    main()
