#!/usr/bin/env python3
"""How close a mass-scaled forging comes to inertia, particle by particle.

The quasi-static watch reads the whole body's kinetic over internal energy; a few heavy
particles that move fast do not move that ratio (docs/forging.md, "One mass for every
grid"). This reads the local counterpart at every interval of the stroke: the largest
particle speed v_max and its dynamic pressure over the material's initial yield stress,
I = f rho v_max^2 / sigma_y (-), f the uniform mass scaling factor, rho the density; the
99th percentile of the speeds; the die's force; the whole-body ratio and the largest the
quasi-static watch kept (from its start, `checks.kinetic_to_internal_from`). It steps the scene
through the rkforge Python package (Simulation.run_to, fields, outputs), one run per
factor, one thread each, and writes one JSON file per factor into --out, then prints
each run's largest I with when and where, and the watch's largest whole-body ratio.

    scripts/local_inertia.py scenes/conrod_3d.toml --factors 2000,8000 --out out/inertia

sigma_y is read from the scene's hardening law (`power`: k eps0^n; `linear`: its yield
stress) or given with --sigma-pa. The tool whose force is read is the scene's first.
"""
import argparse
import json
import pathlib
import time
import tomllib

import numpy as np
import rkforge


def yield_stress(material):
    h = material["hardening"]
    if h["law"] == "power":
        return h["k_pa"] * h["eps0"] ** h["n"]
    if h["law"] == "linear":
        return h["yield_stress_pa"]
    raise SystemExit(f"hardening law {h['law']!r}: give --sigma-pa")


def run(path, factor, every, sigma, rho, tool):
    scene = rkforge.Scene.from_file(str(path))
    scene.set("time.mass_scaling", {"factor": factor})
    sim = rkforge.Simulation(scene, threads=1)
    end = tomllib.loads(path.read_text())["time"]["end_s"]
    rows, t = [], 0.0
    while t < end - 1e-12 * end:
        t = min(t + every, end)
        sim.run_to(t)
        f = sim.fields()
        speed = np.linalg.norm(f["velocity"], axis=1)
        i = int(np.argmax(speed))
        out = sim.outputs()
        kinetic, internal = out["energy.kinetic_J"], out["energy.internal_J"]
        rows.append({
            "t_s": t,
            "stroke_m": out[f"{tool}.stroke_m"],
            "force_N": out[f"{tool}.force_N"],
            "v_max_m_per_s": float(speed[i]),
            "v_99_m_per_s": float(np.percentile(speed, 99)),
            "at_m": f["positions"][i].tolist(),
            "inertia": factor * rho * float(speed[i]) ** 2 / sigma,
            "kinetic_to_internal": kinetic / internal if internal > 0 else 0.0,
            "kinetic_to_internal_max": out["energy.kinetic_to_internal_max"],
        })
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene", type=pathlib.Path)
    p.add_argument("--factors", default="2000,8000", help="mass scaling factors, comma-separated")
    p.add_argument("--every-s", type=float, default=5e-5, help="interval of the readings (s)")
    p.add_argument("--sigma-pa", type=float, help="the yield stress to divide by (Pa)")
    p.add_argument("--out", type=pathlib.Path, required=True)
    a = p.parse_args()
    doc = tomllib.loads(a.scene.read_text())
    sigma = a.sigma_pa or yield_stress(doc["material"])
    rho, tool = doc["material"]["density_kg_per_m3"], doc["tools"][0]["name"]
    a.out.mkdir(parents=True, exist_ok=True)
    for factor in (float(x) for x in a.factors.split(",")):
        t0 = time.time()
        rows = run(a.scene, factor, a.every_s, sigma, rho, tool)
        (a.out / f"inertia_{factor:g}.json").write_text(json.dumps(rows))
        top = max(rows, key=lambda r: r["inertia"])
        print(f"factor {factor:g}: largest I {top['inertia']:.3f} at stroke "
              f"{1e3 * top['stroke_m']:.3f} mm (v_max {top['v_max_m_per_s']:.2f} m/s at "
              f"{[round(1e3 * x, 1) for x in top['at_m']]} mm); v_99 at most "
              f"{max(r['v_99_m_per_s'] for r in rows):.2f} m/s; the quasi-static watch's largest "
              f"kinetic / internal {rows[-1]['kinetic_to_internal_max']:.4f}; "
              f"{time.time() - t0:.0f} s")


if __name__ == "__main__":
    main()
