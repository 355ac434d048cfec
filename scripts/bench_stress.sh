#!/usr/bin/env bash
# Cost of the stress stage per integration point and step for q4, q2 and SCNI on the Taylor
# bar (21 x 51 and 81 x 201, 20 us into the impact): runs the criterion benchmark
# `core/benches/stress.rs` and prints each median in us per stage and ns per point-step.
#   scripts/bench_stress.sh            (rayon's default threads)
#   RAYON_NUM_THREADS=1 scripts/bench_stress.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo bench -q -p rkforge-core --bench stress > /dev/null
python3 - <<'PY'
import json, pathlib
root = pathlib.Path("target/criterion/stress_stage")
print("| rule | grid | points | stage median (us) | ns / point-step |")
print("|---|---|---|---|---|")
for rule in ("q4", "q2", "scni"):
    for grid in ("21x51", "81x201"):
        d = root / rule / grid / "new"
        median = json.loads((d / "estimates.json").read_text())["median"]["point_estimate"]
        points = json.loads((d / "benchmark.json").read_text())["throughput"]["Elements"]
        print(f"| {rule} | {grid} | {points} | {median / 1e3:.1f} | {median / points:.2f} |")
PY
