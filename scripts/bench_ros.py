#!/usr/bin/env python3
"""Publishing overhead of `rkforge-ros` at the default rate (one sample per history interval of
the scene), against `rkforge run --no-frames`, which samples its history at the same instants
but publishes nothing.

Variants, alternated over N rounds so that drifts in machine load hit all of them alike:
  run       rkforge run SCENE --no-frames --quiet                      (baseline)
  mcap      rkforge run SCENE --no-frames --quiet --mcap FILE          (recording, no DDS)
  ros       rkforge-ros SCENE                                          (DDS, nobody subscribed)
  ros+peer  rkforge-ros SCENE, a Cyclone DDS peer subscribed to every topic (with --peer;
            needs the tests' virtual environment, e.g. .venv/bin/python scripts/bench_ros.py)
  ros-end   rkforge-ros SCENE --publish-rate 1/end_s: the same node publishing only at t = 0
            and at the end, which isolates the cost of publishing from the node's other costs

Two figures per run: the process's wall time (includes DDS start-up and the node's 300 ms
linger after the last sample), and the simulation loop's wall time (summary.json's wall_s
for rkforge run; the "in X s wall" the node prints, from scene setup to the last sample).

  scripts/bench_ros.py [--runs 5] [--scene scenes/taylor_bar.toml] [--peer] [--threads N]
"""
import argparse
import json
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib

ROOT = pathlib.Path(__file__).resolve().parents[1]
BIN = ROOT / "target" / "release"
DOMAIN = "199"

PEER = r"""
import sys, time
sys.path.insert(0, sys.argv[1])
from ros_peer import (Clock, JointState, Peer, PointCloud2, WrenchStamped, take)
p = Peer(int(sys.argv[2]))
tools = sys.argv[3].split(",")
readers = [p.reader("/rkforge/tools", JointState), p.reader("/clock", Clock),
           p.reader("/rkforge/workpiece", PointCloud2, reliable=False)]
readers += [p.reader(f"/rkforge/{t}/wrench", WrenchStamped) for t in tools]
print("ready", flush=True)
n = 0
while True:
    for r in readers:
        n += len(take(r, 100))
    time.sleep(0.001)
"""


def timed(cmd, env=None):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit(f"{' '.join(map(str, cmd))} failed:\n{p.stderr}")
    return wall, p


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--scene", default=str(ROOT / "scenes" / "taylor_bar.toml"))
    ap.add_argument("--peer", action="store_true")
    ap.add_argument("--threads", type=int)
    a = ap.parse_args()
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "rkforge", "-p", "rkforge-ros"],
                   cwd=ROOT, check=True)
    threads = ["--threads", str(a.threads)] if a.threads else []
    env = {**os.environ, "ROS_DOMAIN_ID": DOMAIN}
    out = pathlib.Path(tempfile.mkdtemp())
    tools = re.findall(r'^name = "(\w+)"', pathlib.Path(a.scene).read_text(), re.M)[1:]
    peer = None
    if a.peer:
        peer = subprocess.Popen([sys.executable, "-c", PEER, str(ROOT / "tests"), DOMAIN,
                                 ",".join(tools)], cwd=ROOT, stdout=subprocess.PIPE, text=True)
        assert peer.stdout.readline().strip() == "ready"
    end = tomllib.loads(pathlib.Path(a.scene).read_text())["time"]["end_s"]
    variants = ["run", "mcap", "ros-end", "ros+peer" if a.peer else "ros"]
    proc = {v: [] for v in variants}
    loop = {v: [] for v in variants}
    try:
        for _ in range(a.runs):
            for v in variants:
                if v in ("run", "mcap"):
                    extra = ["--mcap", str(out / "b.mcap")] if v == "mcap" else []
                    w, _ = timed([BIN / "rkforge", "run", a.scene, "--no-frames", "--quiet",
                                  "--out", str(out / v), *threads, *extra])
                    s = json.loads((out / v / "summary.json").read_text())
                    loop[v].append(s["wall_s"])
                else:
                    rate = ["--publish-rate", repr(1.0 / end)] if v == "ros-end" else []
                    w, p = timed([BIN / "rkforge-ros", a.scene, *threads, *rate], env=env)
                    loop[v].append(float(re.search(r" in ([0-9.]+) s wall", p.stderr)[1]))
                proc[v].append(w)
    finally:
        if peer:
            peer.kill()
    print(f"scene {a.scene}, {a.runs} rounds, threads {a.threads or 'all'}, medians (min-max):")
    base_p, base_l = statistics.median(proc["run"]), statistics.median(loop["run"])
    for v in variants:
        mp, ml = statistics.median(proc[v]), statistics.median(loop[v])
        print(f"  {v:9s} process {mp:7.3f} s ({min(proc[v]):.3f}-{max(proc[v]):.3f}), ratio "
              f"{mp / base_p:.3f} | loop {ml:7.3f} s ({min(loop[v]):.3f}-{max(loop[v]):.3f}), "
              f"ratio {ml / base_l:.3f}")


if __name__ == "__main__":
    main()
