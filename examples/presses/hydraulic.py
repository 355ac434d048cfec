"""Hydraulic press (force-limited) driving the rkforge FMU: a pump feeds the cylinder, the oil
is compressible, a relief valve caps the pressure, so the ram presses at about Q / A until
the forging force reaches the tonnage p_relief A, and stalls there.

    m_r dv/dt = p A - F - c v             ram (v downward, F the forging force, N)
    (V / beta) dp/dt = Q - A v - q_relief  oil column; q_relief >= 0 keeps p <= p_relief

The ram starts at rest on the billet with the cylinder unpressurised (p = 0).

    python examples/presses/hydraulic.py --plot hydraulic.png
"""
import sys
from dataclasses import dataclass

from driver import argument_parser, require_positive, script


@dataclass
class HydraulicPress:
    """Parameters (SI units) and state of the press."""
    flow: float = 1.0e-3            # pump flow Q (m^3/s): 60 l/min
    area: float = 0.05              # ram (piston) area A (m^2): a 252 mm bore
    oil_volume: float = 0.005       # oil under compression V (m^3)
    bulk_modulus: float = 1.4e9     # oil bulk modulus beta (Pa)
    relief_pressure: float = 20.0e6  # relief valve setting (Pa): tonnage p_relief A = 1 MN
    ram_mass: float = 2000.0        # ram and moving platen m_r (kg)
    damping: float = 5.0e5          # seals and guides c (N s/m)
    substeps: int = 20              # plant steps per communication step
    v: float = 0.0                  # ram velocity (m/s, downward)
    p: float = 0.0                  # cylinder pressure (Pa)

    def __post_init__(self):
        require_positive(self, "flow", "area", "oil_volume", "bulk_modulus", "relief_pressure",
                         "ram_mass", "substeps")
        if self.damping < 0:
            raise ValueError(f"HydraulicPress.damping = {self.damping!r} must not be negative")

    @property
    def tonnage(self):
        """The largest force the press can exert, p_relief A (N)."""
        return self.relief_pressure * self.area

    @property
    def free_speed(self):
        """Ram speed when all the pump flow fills the cylinder, Q / A (m/s)."""
        return self.flow / self.area

    def velocity(self, h):
        return self.v

    def advance(self, out, h):
        """Semi-implicit Euler over the step with the forging force held at `out.force_N`."""
        dt = h / self.substeps
        stiff = self.bulk_modulus / self.oil_volume
        for _ in range(self.substeps):
            self.v += dt * (self.p * self.area - out.force - self.damping * self.v) / self.ram_mass
            self.p += dt * stiff * (self.flow - self.area * self.v)
            self.p = min(max(self.p, 0.0), self.relief_pressure)

    def finished(self):
        return False

    def state(self):
        return {"pressure": self.p}


def summary(press, hist):
    """What the run shows, in words."""
    reached = hist["t"][hist["force"] >= 0.98 * press.tonnage]
    stall = f"{reached[0]:.3f} s" if reached.size else "never"
    return (f"free speed Q/A = {press.free_speed * 1e3:.2f} mm/s, tonnage p_relief A = "
            f"{press.tonnage / 1e6:.3f} MN\nforce at 98 % of the tonnage: {stall}; at t = "
            f"{hist['t'][-1]:.3f} s: force {hist['force'][-1] / 1e6:.3f} MN, ram speed "
            f"{hist['v'][-1] * 1e3:.3f} mm/s, stroke {hist['stroke'][-1] * 1e3:.2f} mm, billet "
            f"height {hist['height'][-1] * 1e3:.2f} mm")


def main(argv=None):
    p = argument_parser(__doc__, step=2e-4, time=1.6, target_dt=2e-5)
    script(p, argv, lambda args: HydraulicPress(), summary, "hydraulic press")


if __name__ == "__main__":
    sys.exit(main())
