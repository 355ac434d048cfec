#!/usr/bin/env python3
"""How far the metal of `scenes/conrod_3d.toml` came into its die's cavity and out into the
flash, read from the last VTU frames of a run (docs/forging.md, "A forging that is not
round").

    python3 scripts/conrod_fill.py out/conrod_3d/frames/frame_0006.vtu

For each of the scene's fill points, moved with the die to the end of its 9 mm stroke: the
nearest particle's distance (mm). Then the cavity: the die's face inside the part's outline
(the ceilings and drafted walls of the boss and the web, not the land), read from the die's
frame of the same number (`die_die_0006.vtu` beside it), and how much of its area
- carries contact pressure (the die feels metal there), and
- lies within 0.5, 0.75 and 1 spacing of a particle (the spacing: the particles' nearest
  distance at the start, from `frame_0000.vtu`); a face the metal filled has a surface
  particle within about 0.7 spacings of every point of it (half the diagonal of a square of
  surface particles);
and where the largest area without pressure lies. Then the flash: how far the farthest
particle lies outside the part's outline in plan, and how many particles lie outside it.
Plain Python, no packages; the outline is `scripts/conrod_die.py`'s.
"""
import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from conrod_die import boss_distance, web_distance  # noqa: E402

STROKE = 9.0
FILL_POINTS = {
    "boss_end": (31.0, 0.0, 17.0),
    "boss_side": (22.0, 9.0, 17.0),
    "web_side": (6.0, 3.5, 12.5),
    "land_web": (0.0, 6.8, 11.0),
    "land_boss": (22.0, 12.8, 11.0),
}
# The die's flat top lies 11 mm above its land; its faces below 9.6 mm are the cavity's.
TOP_ABOVE_LAND = 9.6


def array(text, name):
    """The values of an ASCII VTU file's data array `name`."""
    block = re.search(r'Name="%s"[^>]*>(.*?)</DataArray>' % name, text, re.S)
    return block.group(1).split()


def points(path):
    """The points of an ASCII VTU file (mm)."""
    values = [1e3 * float(v) for v in array(open(path).read(), "Points")]
    return [values[k:k + 3] for k in range(0, len(values), 3)]


def outline(x, y):
    """Signed distance (mm) into the part's outline in plan, positive inside."""
    return max(boss_distance(x, y), web_distance(x, y))


class Bins:
    """Particles binned in cubes of `size` (mm), for nearest-distance queries."""

    def __init__(self, p, size):
        self.size, self.bins = size, {}
        for q in p:
            self.bins.setdefault(self.key(q), []).append(q)

    def key(self, q):
        return tuple(int(math.floor(c / self.size)) for c in q)

    def within(self, at, r):
        """Whether a particle lies within r <= size of `at`."""
        i, j, k = self.key(at)
        for a in (i - 1, i, i + 1):
            for b in (j - 1, j, j + 1):
                for c in (k - 1, k, k + 1):
                    for q in self.bins.get((a, b, c), ()):
                        if math.dist(at, q) <= r:
                            return True
        return False


def cavity(die_path, p, h):
    """The cavity's area (mm^2), that in contact, those within 0.5 / 0.75 / 1 spacing `h`
    of a particle, and the area without pressure by 2 mm squares in plan."""
    text = open(die_path).read()
    pressure = [float(v) for v in array(text, "pressure_Pa")]
    x = [1e3 * float(v) for v in array(text, "Points")]
    x = [x[k:k + 3] for k in range(0, len(x), 3)]
    conn = [int(v) for v in array(text, "connectivity")]
    land = min(q[2] for q in x)
    bins = Bins(p, h)
    total, pressed, near, dry = 0.0, 0.0, [0.0, 0.0, 0.0], {}
    for t, pr in enumerate(pressure):
        a, b, c = (x[i] for i in conn[3 * t:3 * t + 3])
        m = [(a[k] + b[k] + c[k]) / 3.0 for k in range(3)]
        if m[0] < 0.0 or m[1] < 0.0 or m[2] - land > TOP_ABOVE_LAND:
            continue
        if outline(m[0], m[1]) <= 0.0:
            continue
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        area = 0.5 * math.sqrt(sum(e * e for e in n))
        total += area
        if pr > 0.0:
            pressed += area
        else:
            key = (2 * int(m[0] // 2), 2 * int(m[1] // 2))
            dry[key] = dry.get(key, 0.0) + area
        for i, f in enumerate((0.5, 0.75, 1.0)):
            if bins.within(m, f * h):
                near[i] += area
    return total, pressed, near, dry


def main():
    frame = sys.argv[1]
    p = points(frame)
    print(f"{len(p)} particles")
    for name, (x, y, z) in FILL_POINTS.items():
        at = (x, y, z - STROKE)
        d = min(math.dist(at, q) for q in p)
        print(f"{name:10s} at ({at[0]:.1f}, {at[1]:.1f}, {at[2]:.1f}) mm: nearest particle {d:.3f} mm")
    folder, name = os.path.split(frame)
    start = points(os.path.join(folder, "frame_0000.vtu"))
    h = min(math.dist(start[0], q) for q in start[1:])
    die = os.path.join(folder, "die_die_" + name.split("_")[-1])
    total, pressed, near, dry = cavity(die, p, h)
    print(f"cavity: {total:.1f} mm^2 of die face inside the part's outline; "
          f"{100 * pressed / total:.1f} % carries pressure; within 0.5 / 0.75 / 1 spacing "
          f"({h:.3f} mm) of a particle: " + " / ".join(f"{100 * a / total:.1f} %" for a in near))
    worst = sorted(dry.items(), key=lambda kv: -kv[1])[:3]
    print("  most area without pressure, by 2 mm squares in plan (x, y mm): "
          + ", ".join(f"({k[0]}-{k[0] + 2}, {k[1]}-{k[1] + 2}) {a:.1f} mm^2" for k, a in worst))
    out = [outline(q[0], q[1]) for q in p]
    flash = [s for s in out if s < 0.0]
    print(f"flash: {len(flash)} particles outside the outline, the farthest {-min(out):.2f} mm out "
          f"(land 3 mm wide, then the gutter)")


if __name__ == "__main__":
    main()
