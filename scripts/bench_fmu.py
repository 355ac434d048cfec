"""FMU overhead: the full Taylor bar (paper settings) through the FMU with a 1 us
communication step (fmpy's simulate_fmu, every output read at each step) against
`rkforge run --no-frames` (history every 0.5 us), alternating, medians of N runs.

    .venv/bin/python scripts/bench_fmu.py [N=3]
"""
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

from fmpy import simulate_fmu

ROOT = pathlib.Path(__file__).resolve().parents[1]
n = int(sys.argv[1]) if len(sys.argv) > 1 else 3
exe = ROOT / "target" / "release" / "rkforge"
subprocess.run(["cargo", "build", "--release", "-q", "--workspace"], cwd=ROOT, check=True)
tmp_dir = tempfile.TemporaryDirectory()  # removed at exit
tmp = pathlib.Path(tmp_dir.name)
fmu = tmp / "taylor_bar.fmu"
subprocess.run([exe, "fmu", ROOT / "scenes" / "taylor_bar.toml", "--out", fmu], check=True, capture_output=True)
run_t, fmu_t = [], []
for _ in range(n):
    subprocess.run([exe, "run", ROOT / "scenes" / "taylor_bar.toml", "--out", tmp / "run", "--quiet", "--no-frames"],
                   check=True, capture_output=True)
    run_t.append(json.loads((tmp / "run" / "summary.json").read_text())["wall_s"])
    t0 = time.perf_counter()
    res = simulate_fmu(str(fmu), stop_time=80e-6, output_interval=1e-6)
    fmu_t.append(time.perf_counter() - t0)
r, f = statistics.median(run_t), statistics.median(fmu_t)
print(f"rkforge run: median {r:.2f} s {run_t}")
print(f"FMU (fmpy, 1 us steps, {len(res)} rows, radius {res[-1]['workpiece.radius_m'] * 1e3:.3f} mm): "
      f"median {f:.2f} s {[round(x, 2) for x in fmu_t]}")
print(f"FMU / run: {f / r:.3f}")
