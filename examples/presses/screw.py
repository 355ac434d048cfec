"""Screw press (energy-limited) driving the rkforge FMU: a spinning flywheel drives the ram
through a screw of lead p and gives up its energy I w^2 / 2 as forging work; the stroke
ends when the flywheel has stopped.

    v = w p / (2 pi),     I dw/dt = -F p / (2 pi)

I is the inertia of flywheel, screw and ram referred to the screw (the ram's mass m adds
m (p / 2 pi)^2); the screw's friction is neglected. When w reaches zero the press holds the
ram (the clutch lets go and the return stroke begins), which ends the co-simulation.

    python examples/presses/screw.py --plot screw.png
"""
import math
import sys
from dataclasses import dataclass

from driver import argument_parser, require_positive, script


@dataclass
class ScrewPress:
    """Parameters (SI units) and state of the press."""
    inertia: float = 40.0         # I (kg m^2)
    lead: float = 0.25            # screw lead p, ram travel per turn (m)
    omega: float = 12.0           # flywheel speed w at contact (rad/s): 2.88 kJ, v = 0.48 m/s
    stopped_at: float = None      # stroke where the flywheel stopped (m)

    def __post_init__(self):
        require_positive(self, "inertia", "lead", "omega")

    def flywheel_energy(self):
        return self.inertia * self.omega ** 2 / 2

    def velocity(self, h):
        return self.omega * self.lead / (2 * math.pi)

    def advance(self, out, h):
        self.omega -= h * out.force * self.lead / (2 * math.pi * self.inertia)
        if self.omega <= 0.0:
            self.omega = 0.0
            self.stopped_at = out.stroke

    def finished(self):
        return self.stopped_at is not None

    def state(self):
        return {"omega": self.omega, "flywheel_energy": self.flywheel_energy()}


def summary(press, hist):
    """What the run shows, in words."""
    e0, work = hist["flywheel_energy"][0], hist["tool_work"][-1]
    return (f"flywheel energy {e0 / 1e3:.3f} kJ, ram speed at contact {hist['v'][0]:.3f} m/s\n"
            f"the flywheel stopped after {hist['t'][-1] * 1e3:.2f} ms at a stroke of "
            f"{hist['stroke'][-1] * 1e3:.2f} mm; work on the billet {work / 1e3:.4f} kJ "
            f"({(work / e0 - 1) * 100:+.2f} % of the flywheel energy), largest force "
            f"{hist['force'].max() / 1e6:.3f} MN, billet height {hist['height'][-1] * 1e3:.2f} mm")


def main(argv=None):
    p = argument_parser(__doc__, step=1e-4, time=1.0, target_dt=2e-6)
    p.add_argument("--omega", type=float, default=12.0, help="flywheel speed at contact (rad/s)")
    script(p, argv, lambda a: ScrewPress(omega=a.omega), summary, "screw press")


if __name__ == "__main__":
    sys.exit(main())
