"""FMU rollback cost: the wheel forging's FMI 2.0 FMU (30 x 30 particles, the shipped grid)
after 20 steps, then 20 rounds of fmi2GetFMUstate, one 1 us step and fmi2SetFMUstate;
prints the rounds' median wall time (ms). Alternate two builds' FMUs (each packed by its
build's rkforge), several times each:

    .venv/bin/python scripts/bench_fmu_state.py NEW.fmu OLD.fmu [REPEATS=5]
"""
import statistics
import sys
import time

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave



def rounds(path):
    """The median wall time (s) of a get-step-set round."""
    md = read_model_description(path)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(path),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    t, h = 0.0, 1e-6
    for _ in range(20):
        fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        t += h
    times = []
    for _ in range(20):
        t0 = time.perf_counter()
        state = fmu.getFMUstate()
        fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        fmu.setFMUstate(state)
        times.append(time.perf_counter() - t0)
        fmu.freeFMUstate(state)
    fmu.terminate()
    fmu.freeInstance()
    return statistics.median(times)


paths = sys.argv[1:3]
repeats = int(sys.argv[3]) if len(sys.argv) > 3 else 5
results = {p: [] for p in paths}
for _ in range(repeats):
    for p in paths:
        results[p].append(rounds(p))
medians = [statistics.median(results[p]) for p in paths]
for p, m in zip(paths, medians):
    print(f"{p}: median round {m * 1e3:.2f} ms {[round(x * 1e3, 2) for x in results[p]]}")
if len(paths) == 2:
    print(f"ratio {medians[0] / medians[1]:.3f}")
