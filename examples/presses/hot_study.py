"""What the press does to a hot forging's force: the hot upsetting of scenes/hot_upsetting.toml
(C45 at 1150 C between dies at 250 C) as an FMU driven by the hydraulic press (slow: 20 mm/s),
by the same press after the billet has rested on the lower die for a dwell (the die chills its
foot before the ram presses), and by the screw press (fast: 0.48 m/s at contact). With a flow
stress of strain rate and temperature the force is no longer a function of the stroke alone:
the table compares the ram force and the billet's least and mean temperature at equal strokes.

    python examples/presses/hot_study.py [--grid 6 16] [--dwell 2.0] [--plot hot_study.png]

The figures in docs/hot_forging.md ("Press speed and dwell") are this script's output.
"""
import argparse
import pathlib
import sys
import tempfile

import numpy as np
from fmpy.fmi1 import FMICallException

from driver import ROOT, Slave, build_fmu, co_simulate, fmu_params
from hydraulic import HydraulicPress
from screw import ScrewPress

SCENE = ROOT / "scenes" / "hot_upsetting.toml"
STROKES_MM = [2.0, 5.0, 10.0, 15.0, 20.0]


class Dwell:
    """A plant that holds the ram still for `seconds` (the billet resting on the lower die, the
    ram just touching its top), then hands over to `press`."""

    def __init__(self, press, seconds):
        self.press, self.seconds, self.t = press, seconds, 0.0

    def velocity(self, h):
        return 0.0 if self.t < self.seconds else self.press.velocity(h)

    def advance(self, out, h):
        if self.t >= self.seconds:
            self.press.advance(out, h)
        self.t += h

    def finished(self):
        return self.press.finished()

    def state(self):
        return self.press.state()


def run(fmu, plant, h, t_max, grid, target_dt):
    """Co-simulates `plant` with the FMU; the history with the billet's temperatures."""
    slave = Slave(fmu, params=fmu_params(*grid, target_dt))
    rows = {"t": [], "stroke": [], "force": [], "t_min": [], "t_mean": []}
    try:
        history = co_simulate(TemperatureReader(slave, rows), plant, h, t_max)
    except FMICallException as e:
        raise RuntimeError(f"the FMU failed at t = {slave.t:.6g} s: {slave.last_error()}") from e
    finally:
        slave.close()
    return history, {k: np.array(v) for k, v in rows.items()}


class TemperatureReader:
    """The slave as `co_simulate` uses it, reading the temperatures after every step."""

    def __init__(self, slave, rows):
        self.slave, self.rows = slave, rows

    def set(self, name, value):
        self.slave.set(name, value)

    def step(self, h):
        self.slave.step(h)
        f, s, t_min, t_mean = self.slave.get("ram.force_N", "ram.stroke_m", "thermal.temperature_min_c",
                                             "thermal.temperature_mean_c")
        for k, v in zip(self.rows, [self.slave.t, s, -f, t_min, t_mean]):
            self.rows[k].append(v)

    def get(self, *names):
        return self.slave.get(*names)


def at_strokes(rows, strokes_mm):
    """Force (kN) and least and mean temperature (C) at each stroke (mm), interpolated; NaN past
    the run's last stroke."""
    s = rows["stroke"] * 1e3
    out = []
    for x in strokes_mm:
        if s.size == 0 or x > s.max():
            out.append((x, float("nan"), float("nan"), float("nan")))
            continue
        k = int(np.argmax(s >= x))
        out.append((x, rows["force"][k] / 1e3, rows["t_min"][k], rows["t_mean"][k]))
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--grid", type=int, nargs=2, default=[6, 16], metavar=("NR", "NZ"))
    p.add_argument("--dwell", type=float, default=2.0, help="dwell before pressing (s)")
    p.add_argument("--plot", type=pathlib.Path, help="write the force-stroke curves here")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as d:
        fmu = build_fmu(SCENE.read_text(), pathlib.Path(d) / "hot_upsetting.fmu")
        cases = {
            "hydraulic, 20 mm/s": run(fmu, HydraulicPress(), 2e-3, 1.25, args.grid, 20e-6),
            f"hydraulic after a {args.dwell:g} s dwell":
                run(fmu, Dwell(HydraulicPress(), args.dwell), 2e-3, args.dwell + 1.25, args.grid, 20e-6),
            "screw, 0.48 m/s": run(fmu, ScrewPress(), 1e-4, 0.2, args.grid, 2e-6),
        }
    print(f"hot upsetting, grid {args.grid[0]} x {args.grid[1]}: ram force (kN), least / mean "
          "temperature (C) at each stroke")
    print(f"{'press':32s}" + "".join(f"{s:>24.0f} mm" for s in STROKES_MM) + "   end of the run")
    for name, (_, rows) in cases.items():
        cells = "".join(f"{f:>11.1f} kN {lo:>5.0f}/{mean:<5.0f}" for _, f, lo, mean in
                        at_strokes(rows, STROKES_MM))
        end = f"   {rows['stroke'][-1] * 1e3:.1f} mm at {rows['t'][-1]:.3f} s"
        print(f"{name:32s}{cells}{end}")
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 4.5))
        for name, (_, rows) in cases.items():
            ax.plot(rows["stroke"] * 1e3, rows["force"] / 1e3, label=name)
        ax.set_xlabel("ram stroke (mm)")
        ax.set_ylabel("ram force (kN)")
        ax.set_title("hot upsetting of C45 at 1150 C, dies at 250 C")
        ax.grid(True, alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(args.plot, dpi=120)
    return 0


if __name__ == "__main__":
    sys.exit(main())
