#!/usr/bin/env python3
"""Cost of parameter studies through the Python package and Dask.

1. The 8-case study of tests/test_study.py (friction x press speed on a coarse block
   forging) run serially in this process against the same study on a local Dask cluster of
   two single-threaded workers (`dask scheduler` + 2 x `dask worker`, separate processes on
   127.0.0.1), alternated over the rounds; the ratio is serial / cluster wall time.
2. Per-case overhead on a short scene (the block at 9 x 9 particles, 2 ms): the wall time of
   `rkforge run --no-frames --quiet` (process), of `rkforge.run` in this process, and of one
   case submitted to the cluster and fetched back (`rkforge.study` with one case), each
   beside the run loop's own `wall_s` from its summary.

Needs the tests' virtual environment with the package installed (tests/run.sh):

  .venv/bin/python scripts/bench_study.py [--rounds 3] [--repeat 10]
"""
import argparse
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

import rkforge  # noqa: E402
from conftest import scene_variant  # noqa: E402
from test_study import CASES, Cluster, block_scene  # noqa: E402

SHORT = {"particles = [21, 21]": "particles = [9, 9]", "end_s = 0.015": "end_s = 0.002"}


def timed(f):
    start = time.perf_counter()
    value = f()
    return time.perf_counter() - start, value


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--rounds", type=int, default=3, help="rounds of the 8-case study (each: serial, cluster)")
    p.add_argument("--repeat", type=int, default=10, help="repeats of each short run")
    p.add_argument("--rkforge", default=str(ROOT / "target" / "release" / "rkforge"))
    a = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        cluster = Cluster(tmp)
        try:
            scene = block_scene()
            serial, dask = [], []
            for r in range(a.rounds):
                t, _ = timed(lambda: rkforge.study(scene, CASES, progress=False))
                serial.append(t)
                t, _ = timed(lambda: rkforge.study(scene, CASES, client=cluster.client, progress=False))
                dask.append(t)
                print(f"round {r + 1}: serial {serial[-1]:.2f} s, 2 workers {dask[-1]:.2f} s", flush=True)
            ms, md = statistics.median(serial), statistics.median(dask)
            print(f"8-case study, medians of {a.rounds}: serial {ms:.2f} s, 2 workers {md:.2f} s, "
                  f"serial / cluster = {ms / md:.2f}")

            path = tmp / "short.toml"
            path.write_text(scene_variant("block_forging.toml", SHORT))
            short = rkforge.Scene.from_file(path)
            cli, py, remote = [], [], []
            for k in range(a.repeat):
                out = tmp / f"o{k}"
                t, _ = timed(lambda: subprocess.run([a.rkforge, "run", str(path), "--no-frames", "--quiet",
                                                     "--out", str(out)], check=True, capture_output=True))
                loop = json.loads((out / "summary.json").read_text())["wall_s"]
                cli.append((t, loop))
                t, (summary, _) = timed(lambda: rkforge.run(short))
                py.append((t, summary["wall_s"]))
                t, table = timed(lambda: rkforge.study(short, [{}], client=cluster.client, progress=False))
                remote.append((t, table["wall_s"][0]))
            print(f"short scene ({short.name}, 9 x 9, 2 ms), medians of {a.repeat}: wall / run loop wall_s / overhead")
            for name, xs in [("rkforge run (process)", cli), ("rkforge.run (in process)", py),
                             ("study, 1 case on the cluster", remote)]:
                w = statistics.median(x[0] for x in xs)
                loop = statistics.median(x[1] for x in xs)
                print(f"  {name:32s} {w * 1e3:8.1f} ms  {loop * 1e3:8.1f} ms  {(w - loop) * 1e3:8.1f} ms")
        finally:
            cluster.close()


if __name__ == "__main__":
    main()
