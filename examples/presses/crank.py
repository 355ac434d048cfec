"""Mechanical crank press (stroke-limited) driving the rkforge FMU: a flywheel turns the
crank, a slider-crank moves the ram, and the flywheel slows as it delivers the forging work.

    s(theta) = r (1 - cos theta) + l (1 - sqrt(1 - lambda^2 sin^2 theta)),  lambda = r / l
    v = s'(theta) omega,     I d omega/dt = -F s'(theta)

theta is the crank angle from top dead centre (TDC, s = 0) to bottom dead centre (BDC,
theta = pi, s = 2 r); I is the flywheel's inertia referred to the crankshaft (the motor is
declutched during the stroke: the work comes from the flywheel alone). The press is rated
for `rated_force` at `rated_angle` before BDC; nearer BDC the frame limits the force to
that value, farther from BDC the crankshaft's torque does, F_allow = rated_force
s'(rated) / s'(theta). A forging force above F_allow is an overload: the run stops and
reports the crank angle and force; a flywheel that stops before BDC is a stall.

The co-simulation starts with the ram `ram_gap` above the billet, at the crank angle that
puts the ram at `shut_height` (the billet's height at BDC) at the bottom of the stroke, and
runs to `end_angle` after BDC.

    python examples/presses/crank.py --plot crank.png
"""
import math
import sys
from dataclasses import dataclass, field

from driver import argument_parser, require_positive, script

BILLET_HEIGHT = 0.060  # m, scenes/press_upsetting.toml
RAM_GAP = 0.150        # m, ram above the billet in the crank press's FMU


def stroke(theta, r, l):
    """Ram travel from TDC at crank angle `theta` (rad) for crank radius r and rod l (m)."""
    lam = r / l
    return r * (1 - math.cos(theta)) + l * (1 - math.sqrt(1 - (lam * math.sin(theta)) ** 2))


def stroke_rate(theta, r, l):
    """d s / d theta (m/rad)."""
    lam = r / l
    sin, cos = math.sin(theta), math.cos(theta)
    return r * sin * (1 + lam * cos / math.sqrt(1 - (lam * sin) ** 2))


@dataclass
class CrankPress:
    """Parameters (SI units) and state of the press."""
    crank_radius: float = 0.10       # r (m): a 200 mm stroke
    rod_length: float = 0.50         # l (m)
    strokes_per_minute: float = 20.0  # at no load: omega_0 = 2 pi n / 60 (rad/s)
    inertia: float = 3.0e4           # flywheel inertia referred to the crankshaft I (kg m^2)
    rated_force: float = 1.2e6       # rated tonnage (N)
    rated_angle: float = math.radians(20.0)  # before BDC (rad)
    shut_height: float = 0.040       # billet height at BDC (m)
    ram_gap: float = RAM_GAP         # ram above the billet when the co-simulation starts (m)
    end_angle: float = math.radians(15.0)  # after BDC, where the run ends (rad)
    theta0: float = field(init=False)  # crank angle where the co-simulation starts (rad)
    theta: float = field(init=False)  # crank angle from TDC (rad)
    omega: float = field(init=False)  # crank speed (rad/s)
    overload: tuple = None           # (crank angle, force, allowed force) of the first overload
    stall: float = None              # crank angle where the flywheel stopped, if it did

    def __post_init__(self):
        require_positive(self, "crank_radius", "rod_length", "strokes_per_minute", "inertia",
                         "rated_force", "rated_angle", "shut_height")
        r, l = self.crank_radius, self.rod_length
        if r >= l:
            raise ValueError(f"CrankPress.crank_radius = {r} must be shorter than rod_length = {l}")
        s0 = 2 * r - self.ram_gap - (BILLET_HEIGHT - self.shut_height)
        if not 0.0 <= s0 < 2 * r:
            raise ValueError(f"ram_gap {self.ram_gap} m and shut_height {self.shut_height} m do "
                             f"not fit the stroke 2 r = {2 * r} m of the crank")
        self.theta = self.theta0 = bisect(lambda t: stroke(t, r, l) - s0)
        self.omega = 2 * math.pi * self.strokes_per_minute / 60

    def s(self, theta):
        return stroke(theta, self.crank_radius, self.rod_length)

    def s_rate(self, theta):
        return stroke_rate(theta, self.crank_radius, self.rod_length)

    def allowed_force(self, theta):
        """The press's load limit at crank angle `theta` (N)."""
        before_bdc = math.pi - theta
        if before_bdc <= self.rated_angle:
            return self.rated_force
        return self.rated_force * self.s_rate(math.pi - self.rated_angle) / self.s_rate(theta)

    def flywheel_energy(self):
        return self.inertia * self.omega ** 2 / 2

    def velocity(self, h):
        """The ram velocity that moves it exactly from s(theta) to s(theta + omega h) over the
        next step of `h` (s): the FMU's stroke stays on the slider-crank curve."""
        return (self.s(self.theta + self.omega * h) - self.s(self.theta)) / h

    def advance(self, out, h):
        mid = self.theta + self.omega * h / 2
        self.theta += self.omega * h
        self.omega -= h * out.force * self.s_rate(mid) / self.inertia
        allowed = self.allowed_force(self.theta)
        if self.overload is None and out.force > allowed:
            self.overload = (self.theta, out.force, allowed)
        if self.omega <= 0.0 and self.stall is None:
            self.stall = self.theta
            self.omega = 0.0

    def finished(self):
        return (self.overload is not None or self.stall is not None
                or self.theta >= math.pi + self.end_angle)

    def state(self):
        return {"theta": self.theta, "omega": self.omega, "flywheel_energy": self.flywheel_energy(),
                "allowed_force": self.allowed_force(self.theta)}


def bisect(f, lo=0.0, hi=math.pi):
    """The root of f, increasing on [lo, hi], to rounding."""
    for _ in range(100):
        mid = (lo + hi) / 2
        if f(mid) < 0:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def summary(press, hist):
    """What the run shows, in words."""
    lines = [f"start at {math.degrees(press.theta0):.1f} deg from TDC, {hist['t'][-1]:.3f} s of "
             f"press time, crank at {math.degrees(press.theta):.1f} deg",
             f"largest force {hist['force'].max() / 1e6:.3f} MN, billet height "
             f"{hist['height'][-1] * 1e3:.2f} mm; flywheel energy "
             f"{hist['flywheel_energy'][0] / 1e3:.2f} -> {press.flywheel_energy() / 1e3:.2f} kJ, "
             f"work on the billet {hist['tool_work'][-1] / 1e3:.2f} kJ"]
    if press.overload:
        theta, f, allowed = press.overload
        lines.append(f"OVERLOAD at {math.degrees(math.pi - theta):.2f} deg before BDC: "
                     f"{f / 1e6:.3f} MN > {allowed / 1e6:.3f} MN allowed")
    if press.stall is not None:
        lines.append(f"STALL: the flywheel stopped at {math.degrees(math.pi - press.stall):.2f} "
                     "deg before BDC")
    return "\n".join(lines)


def main(argv=None):
    p = argument_parser(__doc__, step=2e-4, time=10.0, target_dt=2e-5, ram_gap_m=RAM_GAP)
    p.add_argument("--shut-height", type=float, default=0.040,
                   help="billet height at BDC (m); 0.030 overloads the press")
    p.add_argument("--inertia", type=float, default=3.0e4,
                   help="flywheel inertia referred to the crankshaft (kg m^2)")
    script(p, argv, lambda a: CrankPress(shut_height=a.shut_height, inertia=a.inertia), summary,
           "crank press")


if __name__ == "__main__":
    sys.exit(main())
