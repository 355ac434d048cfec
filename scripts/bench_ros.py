#!/usr/bin/env python3
"""Publishing overhead of `rkforge-ros` at the default rate (one sample per history interval of
the scene), against `rkforge run --no-frames`, which samples its history at the same instants
but publishes nothing.

Variants, alternated over N rounds so that drifts in machine load hit all of them alike:
  run       rkforge run SCENE --no-frames --quiet                      (baseline)
  mcap      rkforge run SCENE --no-frames --quiet --mcap FILE          (recording, no DDS;
            zstd-compressed chunks, the default)
  mcap-none the same with --mcap-compression none                      (uncompressed chunks)
  ros       rkforge-ros SCENE                                          (DDS, nobody subscribed)
  ros+peer  rkforge-ros SCENE, a Cyclone DDS peer subscribed to every topic (with --peer;
            needs the tests' virtual environment, e.g. .venv/bin/python scripts/bench_ros.py)
  ros-end   rkforge-ros SCENE --publish-rate 1/end_s: the same node publishing only at t = 0
            and at the end, which isolates the cost of publishing from the node's other costs

Three figures per run: the process's wall time (includes DDS start-up and the node's 300 ms
linger after the last sample), the simulation loop's wall time (summary.json's wall_s for
rkforge run; the "in X s wall" the node prints, from scene setup to the last sample), and the
process's CPU time (user + system over all its threads, from wait4), which a busy machine
disturbs least. Ratios are to the median of `run`. The recording variants also print the
size of their MCAP file.

  scripts/bench_ros.py [--runs 5] [--scene scenes/taylor_bar.toml] [--peer] [--threads N]
                       [--variants run,mcap,mcap-none,ros-end,ros]
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
from ros_peer import (Clock, Energy, JointState, Peer, PointCloud2, WrenchStamped, take)
p = Peer(int(sys.argv[2]))
tools = sys.argv[3].split(",")
readers = [p.reader("/rkforge/tools", JointState), p.reader("/clock", Clock),
           p.reader("/rkforge/workpiece", PointCloud2, reliable=False),
           p.reader("/rkforge/energy", Energy)]
readers += [p.reader(f"/rkforge/{t}/wrench", WrenchStamped) for t in tools]
print("ready", flush=True)
n = 0
while True:
    for r in readers:
        n += len(take(r, 100))
    time.sleep(0.001)
"""


def timed(cmd, env=None):
    """Run `cmd`: its wall time, CPU time (user + system, all threads) and stderr."""
    t0 = time.perf_counter()
    with tempfile.TemporaryFile("w+") as err:
        p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=err, text=True)
        _, status, usage = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
        wall = time.perf_counter() - t0
        err.seek(0)
        text = err.read()
    if p.returncode != 0:
        sys.exit(f"{' '.join(map(str, cmd))} failed:\n{text}")
    return wall, usage.ru_utime + usage.ru_stime, text


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--scene", default=str(ROOT / "scenes" / "taylor_bar.toml"))
    ap.add_argument("--peer", action="store_true")
    ap.add_argument("--threads", type=int)
    ap.add_argument("--variants", help="comma-separated subset of the variants (with run)")
    a = ap.parse_args()
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "rkforge", "-p", "rkforge-ros"],
                   cwd=ROOT, check=True)
    threads = ["--threads", str(a.threads)] if a.threads else []
    env = {**os.environ, "ROS_DOMAIN_ID": DOMAIN}
    out_dir = tempfile.TemporaryDirectory()  # removed when main returns
    out = pathlib.Path(out_dir.name)
    tools = re.findall(r'^name = "(\w+)"', pathlib.Path(a.scene).read_text(), re.M)[1:]
    peer = None
    if a.peer:
        peer = subprocess.Popen([sys.executable, "-c", PEER, str(ROOT / "tests"), DOMAIN,
                                 ",".join(tools)], cwd=ROOT, stdout=subprocess.PIPE, text=True)
        assert peer.stdout.readline().strip() == "ready"
    end = tomllib.loads(pathlib.Path(a.scene).read_text())["time"]["end_s"]
    variants = ["run", "mcap", "mcap-none", "ros-end", "ros+peer" if a.peer else "ros"]
    if a.variants:
        chosen = set(a.variants.replace("ros+peer", "ros").split(",")) | {"run"}
        variants = [v for v in variants if v.replace("ros+peer", "ros") in chosen]
    proc = {v: [] for v in variants}
    loop = {v: [] for v in variants}
    cpu = {v: [] for v in variants}
    size = {}
    try:
        for _ in range(a.runs):
            for v in variants:
                if v in ("run", "mcap", "mcap-none"):
                    mcap = out / f"{v}.mcap"
                    extra = {"run": [], "mcap": ["--mcap", str(mcap)],
                             "mcap-none": ["--mcap", str(mcap), "--mcap-compression", "none"]}[v]
                    w, c, _ = timed([BIN / "rkforge", "run", a.scene, "--no-frames", "--quiet",
                                     "--out", str(out / v), *threads, *extra])
                    s = json.loads((out / v / "summary.json").read_text())
                    loop[v].append(s["wall_s"])
                    if extra:
                        size[v] = mcap.stat().st_size
                else:
                    rate = ["--publish-rate", repr(1.0 / end)] if v == "ros-end" else []
                    w, c, err = timed([BIN / "rkforge-ros", a.scene, *threads, *rate], env=env)
                    loop[v].append(float(re.search(r" in ([0-9.]+) s wall", err)[1]))
                proc[v].append(w)
                cpu[v].append(c)
    finally:
        if peer:
            peer.kill()
    print(f"scene {a.scene}, {a.runs} rounds, threads {a.threads or 'all'}, medians (min-max):")
    base = {k: statistics.median(d["run"]) for k, d in
            (("proc", proc), ("loop", loop), ("cpu", cpu))}
    for v in variants:
        parts = []
        for k, d in (("process wall", proc), ("loop wall", loop), ("process CPU", cpu)):
            m = statistics.median(d[v])
            key = {"process wall": "proc", "loop wall": "loop", "process CPU": "cpu"}[k]
            parts.append(f"{k} {m:6.3f} s ({min(d[v]):.3f}-{max(d[v]):.3f}) x{m / base[key]:.3f}")
        if v in size:
            parts.append(f"file {size[v] / 1e6:.2f} MB")
        print(f"  {v:9s} " + " | ".join(parts))


if __name__ == "__main__":
    main()
