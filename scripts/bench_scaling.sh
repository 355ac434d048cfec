#!/usr/bin/env bash
# Cost per step against particle count (1 k to 100 k) for q4, q2 and SCNI: runs the
# criterion bench core/benches/step.rs and prints the Markdown table of docs/performance.md
# (criterion medians; time per particle-step and per integration point-step; memory per
# particle from Simulation::memory_bytes; the ratio of the largest to the smallest model).
#   scripts/bench_scaling.sh            (about 2 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
log=$(mktemp)
cargo bench -q -p rkforge-core --bench step 2> "$log" > /dev/null
python3 - "$log" <<'PY'
import json, re, sys
setup = {}
for line in open(sys.argv[1]):
    m = re.match(r"(\w+) (\d+)x(\d+): (\d+) particles, (\d+) integration points, setup ([\d.]+) s, memory ([\d.]+) MB = (\d+) B/particle", line)
    if m:
        rule, particles = m.group(1), int(m.group(4))
        setup[(rule, particles)] = (int(m.group(5)), float(m.group(6)), float(m.group(7)), int(m.group(8)))
print("| rule | particles | points | setup (s) | step, median | ns / particle-step | ns / point-step | memory (MB) | B / particle |")
print("|---|---|---|---|---|---|---|---|---|")
for rule in ("q4", "q2", "scni"):
    per = []
    for (r, n), (pts, st, mb, bpp) in sorted(setup.items(), key=lambda kv: (kv[0][0], kv[0][1])):
        if r != rule:
            continue
        est = json.load(open(f"target/criterion/step/{rule}/{n}/new/estimates.json"))
        t = est["median"]["point_estimate"]  # ns per step
        per.append(t / n)
        step = f"{t / 1e6:.2f} ms" if t >= 1e6 else f"{t / 1e3:.0f} us"
        print(f"| {rule} | {n} | {pts} | {st:.2f} | {step} | {t / n:.0f} | {t / pts:.0f} | {mb:.1f} | {bpp} |")
    if per:
        print(f"| {rule} | 100 k / 1 k | | | | {per[-1] / per[0]:.2f} | | | |")
PY
