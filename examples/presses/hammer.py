"""Forging hammer (energy-limited) driving the rkforge FMU: a ram of mass m strikes the billet
at v0 and is braked by the forging force alone, m dv/dt = -F, until it rebounds off the
billet; blows repeat until the billet is down to the target height.

Each blow delivers m v0^2 / 2 (the blow energy); the billet takes the work integral F ds
(plastic and elastic work, friction and contact losses), and the ram leaves with what the
billet gives back elastically. Between blows the ram is backed off by `gap` at `lift_speed`
and launched again at v0 (the lift and the fall are not simulated: the billet's material is
rate-independent, so the pause between blows does not matter).

    python examples/presses/hammer.py --plot hammer.png
"""
import sys
from dataclasses import dataclass, field

from driver import argument_parser, require_positive, script


@dataclass
class Blow:
    """One blow: ram speeds (m/s) and the tool work (J) at its start and end, billet height
    (m) after it."""
    v_start: float
    work_start: float
    v_end: float = None
    work_end: float = None
    height: float = None

    def kinetic_energy_lost(self, mass):
        """m (v_start^2 - v_end^2) / 2 (J)."""
        return mass * (self.v_start ** 2 - self.v_end ** 2) / 2

    @property
    def work(self):
        """Work the ram did on the billet during the blow, the integral of F ds (J)."""
        return self.work_end - self.work_start


@dataclass
class Hammer:
    """Parameters (SI units) and state of the hammer."""
    ram_mass: float = 200.0       # m (kg)
    impact_speed: float = 5.0     # v0 (m/s): blow energy m v0^2 / 2 = 2.5 kJ
    target_height: float = 0.045  # billet height that ends the forging (m)
    gap: float = 1.0e-3           # ram backed off above the billet between blows (m)
    lift_speed: float = 1.0       # (m/s)
    max_blows: int = 20
    v: float = field(init=False)  # ram velocity (m/s, downward)
    blows: list = field(default_factory=list)
    lifting_to: float = None      # stroke the ram is lifted to (m), between blows

    def __post_init__(self):
        require_positive(self, "ram_mass", "impact_speed", "target_height", "gap", "lift_speed",
                         "max_blows")
        self.v = self.impact_speed
        self.blows.append(Blow(self.v, 0.0))

    def velocity(self, h):
        return -self.lift_speed if self.lifting_to is not None else self.v

    def advance(self, out, h):
        if self.lifting_to is not None:
            if out.stroke <= self.lifting_to:
                self.lifting_to = None
                self.v = self.impact_speed
                self.blows.append(Blow(self.v, out.tool_work))
            return
        self.v -= h * out.force / self.ram_mass
        if self.v < 0 and out.force <= 0.0:  # rebounded off the billet: the blow is over
            b = self.blows[-1]
            b.v_end, b.work_end, b.height = self.v, out.tool_work, out.height
            if not self.finished():
                self.lifting_to = out.stroke - self.gap

    def finished(self):
        done = [b for b in self.blows if b.height is not None]
        return bool(done) and (done[-1].height <= self.target_height
                               or len(done) >= self.max_blows)

    def state(self):
        return {"blow": len(self.blows)}


def summary(hammer, hist):
    """What the run shows, in words: each blow's energy account."""
    lines = [f"blow energy {hammer.ram_mass * hammer.impact_speed ** 2 / 2 / 1e3:.3f} kJ"]
    for k, b in enumerate(hammer.blows, 1):
        if b.height is not None:
            lost = b.kinetic_energy_lost(hammer.ram_mass)
            lines.append(f"blow {k}: work on the billet {b.work / 1e3:.4f} kJ, ram energy lost "
                         f"{lost / 1e3:.4f} kJ ({(b.work / lost - 1) * 100:+.2f} %), rebound "
                         f"{b.v_end:.3f} m/s, height {b.height * 1e3:.2f} mm")
    return "\n".join(lines)


def main(argv=None):
    p = argument_parser(__doc__, step=1e-5, time=1.0)
    p.add_argument("--target-height", type=float, default=0.045, help="billet height (m)")
    p.add_argument("--impact-speed", type=float, default=5.0, help="v0 (m/s)")
    script(p, argv, lambda a: Hammer(target_height=a.target_height, impact_speed=a.impact_speed),
           summary, "hammer")


if __name__ == "__main__":
    sys.exit(main())
