#!/usr/bin/env python3
"""Two rkforge builds on the shipped scenes, run whole: what a change of the bits moves.

    scripts/compare_builds.py OLD_BINARY NEW_BINARY --out DIR [--scenes a,b]

Runs each scene (default: every shipped scene whose step is not a fixed `time.dt_s`) through
both binaries, one after the other on one thread, without frames, and prints per scene:
- the steps taken by each;
- cut samples: history rows whose last step (`dt_s`) is below 0.9 of the last steps of
  both rows beside it, the trace of a landing that cut a step before a sample (the natural
  step's own drift, a few per cent a sample, and its jumps at a re-reference are not);
- spikes: samples of a tool's force more than 10 % above the median of the nine samples
  around them, among samples above a twentieth of the tool's peak;
- the relative change of the workpiece's radius, height and largest plastic strain, of
  each tool's force at the end and its peak, and the median relative change of the tools'
  sampled forces (samples above a fifth of the peak in both builds).
Runs already in DIR (DIR/<scene>.old, DIR/<scene>.new, with their summary.json) are read, not
run again.
"""

import argparse
import csv
import json
import statistics
import subprocess
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def natural_step_scenes():
    names = []
    for path in sorted((ROOT / "scenes").glob("*.toml")):
        scene = tomllib.loads(path.read_text())
        if scene.get("time", {}).get("dt_s") is None:
            names.append(path.stem)
    return names


def run(binary, scene, out):
    cmd = [binary, "run", str(ROOT / "scenes" / f"{scene}.toml"), "--quiet", "--no-frames",
           "--threads", "1", "--out", str(out)]
    print(" ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def history(out):
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def window_median(values, i):
    lo, hi = max(0, i - 4), min(len(values), i + 5)
    return statistics.median(values[lo:hi])


def cut_samples(h):
    dt = h["dt_s"]
    return sum(1 for i in range(2, len(dt) - 1) if dt[i] < 0.9 * min(dt[i - 1], dt[i + 1]))


def force_columns(h):
    return [k for k in h if k.endswith(".force_N")]


def spikes(h):
    count = 0
    for k in force_columns(h):
        f = [abs(v) for v in h[k]]
        peak = max(f)
        for i in range(1, len(f) - 1):
            if f[i] > 0.05 * peak and f[i] > 1.1 * window_median(f, i):
                count += 1
    return count


def rel(a, b):
    if a == b:
        return 0.0
    return (b - a) / abs(a) if a != 0.0 else float("inf")


def compare(old, new):
    so = json.loads((old / "summary.json").read_text())
    sn = json.loads((new / "summary.json").read_text())
    ho, hn = history(old), history(new)
    moves = {}
    for key in ("radius_m", "height_m", "max_plastic_strain"):
        if key in so["workpiece"]:
            moves[key] = rel(so["workpiece"][key], sn["workpiece"][key])
    for to, tn in zip(so["tools"], sn["tools"]):
        if to["peak_force_N"] == 0.0:
            continue
        end_o = sum(v * v for v in to["force_N"]) ** 0.5
        end_n = sum(v * v for v in tn["force_N"]) ** 0.5
        if end_o > 0.2 * to["peak_force_N"]:
            moves[f"{to['name']} end"] = rel(end_o, end_n)
        moves[f"{to['name']} peak"] = rel(to["peak_force_N"], tn["peak_force_N"])
    sampled = []
    if len(ho["time_s"]) == len(hn["time_s"]):
        for k in force_columns(ho):
            fo, fn = [abs(v) for v in ho[k]], [abs(v) for v in hn[k]]
            peak = max(max(fo), max(fn))
            sampled += [abs(rel(a, b)) for a, b in zip(fo, fn) if min(a, b) > 0.2 * peak]
    return {
        "steps": (so["steps"], sn["steps"]),
        "cut": (cut_samples(ho), cut_samples(hn)),
        "spikes": (spikes(ho), spikes(hn)),
        "moves": moves,
        "sampled_median": statistics.median(sampled) if sampled else None,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old")
    parser.add_argument("new")
    parser.add_argument("--out", required=True, type=Path)
    parser.add_argument("--scenes", help="comma-separated scene names (default: every "
                        "shipped scene with a natural step)")
    args = parser.parse_args()
    scenes = args.scenes.split(",") if args.scenes else natural_step_scenes()
    args.out.mkdir(parents=True, exist_ok=True)
    print("| scene | steps old / new | cut samples old / new | spikes old / new | "
          "figures moved (relative) | sampled forces, median change |")
    print("|---|---|---|---|---|---|")
    for scene in scenes:
        old, new = args.out / f"{scene}.old", args.out / f"{scene}.new"
        for binary, out in ((args.old, old), (args.new, new)):
            if not (out / "summary.json").exists():
                run(binary, scene, out)
        c = compare(old, new)
        moved = ", ".join(f"{k} {100 * v:+.3f} %" for k, v in c["moves"].items())
        med = "-" if c["sampled_median"] is None else f"{100 * c['sampled_median']:.3f} %"
        print(f"| {scene} | {c['steps'][0]} / {c['steps'][1]} | {c['cut'][0]} / {c['cut'][1]} "
              f"| {c['spikes'][0]} / {c['spikes'][1]} | {moved} | {med} |", flush=True)


if __name__ == "__main__":
    main()
