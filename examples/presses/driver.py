"""The co-simulation loop shared by the press plants: an rkforge FMU driven through
`fmpy.fmi2.FMU2Slave`, the plant integrating its own equations against the FMU's force.

Coupling (one communication step of length h, press time t_k -> t_k + h):

1. the plant gives the ram velocity v_k, held over the step (zero-order hold): the FMU moves
   its tool by exactly v_k h (`ram.stroke_m` is the ram's position);
2. the FMU sub-cycles its explicit solver over the step and returns the force F at t_k + h
   (`-ram.force_N`, the force resisting the stroke, N) and the work its tool delivered over the
   step (`energy.tool_work_J`, the solver's own integral of F v dt);
3. the plant integrates its equations over the step with F held at that value.

The plant sees the force only at the communication points, one value per step, while the
workpiece received the solver's work. The difference, the coupling error, grows with
h |dF/dt| / F; the tests measure it as the mismatch between the plant's energy balance and
`energy.tool_work_J` (for the hammer's 3 ms blows: 1.4-1.9 % per blow at h = 100 us, below
0.4 % at 40 us and less).
"""
import argparse
import ctypes
import math
import os
import pathlib
import subprocess
import tempfile
from dataclasses import dataclass

import numpy as np
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
from fmpy.logging import addLoggerProxy

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "press_upsetting.toml"
RAM_LINE = "points_m = [[0.080, 0.060], [-0.002, 0.060]]"
MASS_SCALING_LINE = "mass_scaling = { target_dt_s = 20.0e-6 }"


class Slave:
    """One FMU instance driven step by step, with its log messages captured; `stop_time` (s)
    is the stop time set up (none when None), `logging_on` the instance's debug logging
    (errors are logged either way)."""

    def __init__(self, path, name="rkforge", params=None, unzip=None, init=True, stop_time=None,
                 logging_on=True):
        self.md = read_model_description(path)
        self.dir = unzip or extract(path)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages = []

        def logger(env, instance, status, category, message):
            self.messages.append((status, message.decode()))

        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(ctypes.byref(self.callbacks))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=logging_on)
        self.t = 0.0
        if init:
            self.fmu.setupExperiment(startTime=0.0, stopTime=stop_time)
            unknown = [k for k in (params or {}) if k not in self.vr]
            if unknown:
                known = sorted(v.name for v in self.md.modelVariables if v.causality == "parameter")
                raise ValueError(f"{path}: no parameter {', '.join(unknown)} (its parameters: "
                                 f"{', '.join(known)})")
            for k, v in (params or {}).items():
                if isinstance(v, str):
                    self.fmu.setString([self.vr[k]], [v])
                elif isinstance(v, int):
                    self.fmu.setInteger([self.vr[k]], [v])
                else:
                    self.fmu.setReal([self.vr[k]], [v])
            self.fmu.enterInitializationMode()
            self.fmu.exitInitializationMode()

    def step(self, h):
        self.fmu.doStep(currentCommunicationPoint=self.t, communicationStepSize=h)
        self.t += h

    def get(self, *names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def set(self, name, value):
        self.fmu.setReal([self.vr[name]], [value])

    def last_error(self):
        return self.messages[-1][1] if self.messages else ""

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def upsetting_scene(ram_gap_m=0.0, mass_scaling=True):
    """The text of scenes/press_upsetting.toml with the ram `ram_gap_m` (m) above the billet;
    without its selective mass scaling when `mass_scaling` is false (a key the scene leaves
    out is no FMU parameter: the scene decides what is modelled)."""
    text = SCENE.read_text()
    for line in [RAM_LINE] + ([] if mass_scaling else [MASS_SCALING_LINE]):
        if text.count(line) != 1:
            raise ValueError(f"{SCENE}: the line {line!r} is not there exactly once")
    y = 0.060 + ram_gap_m
    text = text.replace(RAM_LINE, f"points_m = [[0.080, {y!r}], [-0.002, {y!r}]]")
    return text if mass_scaling else text.replace(MASS_SCALING_LINE + "\n", "")


def rkforge_binary():
    """The `rkforge` executable: $RKFORGE_BIN, else the release build of this checkout."""
    path = pathlib.Path(os.environ.get("RKFORGE_BIN", ROOT / "target" / "release" / "rkforge"))
    if not path.is_file():
        raise FileNotFoundError(f"no rkforge executable at {path}: run `cargo build --release "
                                "-p rkforge -p rkforge-fmu` or set RKFORGE_BIN")
    return str(path)


def build_fmu(scene_text, out, rkforge=None):
    """Packs the scene given as TOML text into the FMU `out` with `rkforge fmu`; returns `out`."""
    out = pathlib.Path(out)
    with tempfile.TemporaryDirectory() as d:
        scene = pathlib.Path(d) / "press_upsetting.toml"
        scene.write_text(scene_text)
        subprocess.run([rkforge or rkforge_binary(), "fmu", str(scene), "--out", str(out)],
                       check=True, capture_output=True, text=True)
    return str(out)


@dataclass
class Outputs:
    """What the plant reads from the FMU after a step."""
    force: float      # force resisting the stroke, -ram.force_N (N)
    stroke: float     # ram displacement, downward positive (m)
    tool_work: float  # work the ram delivered since the start (J)
    height: float     # billet height (m)
    kinetic_to_internal_max: float  # the FMU's quasi-static watch (-)


def co_simulate(slave, plant, h, t_max):
    """Steps `slave` and `plant` together with the communication step `h` (s) until the plant
    is finished or the press time reaches `t_max` (s). The plant provides `velocity(h)` (m/s,
    the ram velocity for the next step), `advance(outputs, h)`, `finished()` and `state()`
    (a dict of its own quantities). Returns the history as a dict of arrays: `t` (s), `v`
    (m/s, held over the step ending at t), `force` (N), `stroke` (m), `tool_work` (J),
    `height` (m), `kinetic_to_internal_max` (-) and the plant's quantities, one row per
    communication point, the first at t = 0."""
    out = read_outputs(slave)
    rows = [{"t": 0.0, "v": plant.velocity(h), **vars(out), **plant.state()}]
    n = 0
    while not plant.finished() and (n + 1) * h <= t_max * (1 + 1e-12):
        v = plant.velocity(h)
        slave.set("ram.velocity_m_per_s", v)
        slave.step(h)
        n += 1
        out = read_outputs(slave)
        plant.advance(out, h)
        rows.append({"t": n * h, "v": v, **vars(out), **plant.state()})
    return {k: np.array([r[k] for r in rows]) for k in rows[0]}


def read_outputs(slave):
    """The FMU outputs a plant needs."""
    f, s, w, height, ratio = slave.get("ram.force_N", "ram.stroke_m", "energy.tool_work_J",
                                       "workpiece.height_m", "energy.kinetic_to_internal_max")
    return Outputs(force=-f, stroke=s, tool_work=w, height=height, kinetic_to_internal_max=ratio)


def fmu_params(nx, ny, target_dt=None):
    """FMU parameters, the scene's own keys: the particle grid (`workpiece.particles`, along
    r and z) and, when given, the target step (s) of the scene's selective mass scaling
    (`time.mass_scaling.target_dt_s`)."""
    params = {"workpiece.particles[0]": nx, "workpiece.particles[1]": ny}
    if target_dt is not None:
        params["time.mass_scaling.target_dt_s"] = target_dt
    return params


def simulate(path, plant, h, t_max, nx, ny, target_dt=None):
    """`co_simulate` on a fresh instance of the FMU `path` with the given grid and mass
    scaling target (see `fmu_params`)."""
    slave = Slave(path, params=fmu_params(nx, ny, target_dt))
    try:
        return co_simulate(slave, plant, h, t_max)
    except FMICallException as e:
        raise RuntimeError(f"the FMU failed in the step from t = {slave.t:.6g} s: "
                           f"{slave.last_error()}") from e
    finally:
        slave.close()


def require_positive(plant, *names):
    """Raises ValueError naming each parameter of `plant` (a dataclass) that is not a positive
    finite number."""
    values = {n: getattr(plant, n) for n in names}
    bad = [f"{type(plant).__name__}.{n} = {x!r}" for n, x in values.items()
           if not (isinstance(x, (int, float)) and 0 < x < math.inf)]
    if bad:
        raise ValueError("must be positive and finite: " + ", ".join(bad))


def argument_parser(doc, step, time, target_dt=None, ram_gap_m=0.0, nx=6, ny=16):
    """Command-line options shared by the press scripts (described by the first paragraph of
    `doc`), for an FMU of the billet with the ram `ram_gap_m` (m) above it, with defaults for
    the communication step and the press time (s); `--target-dt` (selective mass scaling)
    when `target_dt` (s) is given as its default."""
    p = argparse.ArgumentParser(description=doc.split("\n\n")[0],
                                formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.set_defaults(ram_gap=ram_gap_m, target_dt=None)
    where = "on the billet" if ram_gap_m == 0 else f"{ram_gap_m * 1e3:g} mm above the billet"
    p.add_argument("--fmu", help=f"an FMU of scenes/press_upsetting.toml with the ram {where} "
                   "(built with `rkforge fmu` into a temporary directory when not given)")
    p.add_argument("--nx", type=int, default=nx, help="particles along r")
    p.add_argument("--ny", type=int, default=ny, help="particles along z")
    p.add_argument("--step", type=float, default=step, help="communication step (s)")
    p.add_argument("--time", type=float, default=time,
                   help="largest press time (s); the press may finish earlier")
    if target_dt is not None:
        p.add_argument("--target-dt", type=float, default=target_dt,
                       help="selective mass scaling: target solver step (s)")
    p.add_argument("--csv", help="write the history to this CSV file")
    p.add_argument("--plot", help="plot force and speed against stroke into this image "
                   "(needs matplotlib)")
    return p


def script(parser, argv, make_plant, summarise, title):
    """A press script: parses `argv` with `parser`, makes the plant from the arguments, runs
    it against the FMU given (or built), prints `summarise(plant, history)` and writes the
    CSV and the plot asked for."""
    args = parser.parse_args(argv)
    plant = make_plant(args)
    with tempfile.TemporaryDirectory() as d:
        scaled = args.target_dt is not None
        path = args.fmu or build_fmu(upsetting_scene(args.ram_gap, mass_scaling=scaled),
                                     pathlib.Path(d) / "press_upsetting.fmu")
        hist = simulate(path, plant, args.step, args.time, args.nx, args.ny,
                        target_dt=args.target_dt)
    print(summarise(plant, hist))
    report(hist, args, title)


def report(history, args, title):
    """Writes the history as CSV and plots force and ram speed against stroke, as asked."""
    if args.csv:
        keys = list(history)
        np.savetxt(args.csv, np.column_stack([history[k] for k in keys]), delimiter=",",
                   header=",".join(keys), comments="")
        print(f"history: {args.csv}")
    if args.plot:
        try:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError as e:
            raise SystemExit(f"--plot needs matplotlib ({e}); pip install matplotlib") from e
        fig, (a, b) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
        a.plot(history["stroke"] * 1e3, history["force"] / 1e6)
        a.set_ylabel("force (MN)")
        a.set_title(title)
        b.plot(history["stroke"] * 1e3, history["v"] * 1e3)
        b.set_ylabel("ram speed (mm/s)")
        b.set_xlabel("stroke (mm)")
        fig.tight_layout()
        fig.savefig(args.plot, dpi=120)
        print(f"plot: {args.plot}")
