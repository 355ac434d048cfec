#!/usr/bin/env python3
"""Writes the upper die of `scenes/conrod_3d.toml` as a binary STL file (millimetres).

The part is a small connecting-rod-like forging: two round bosses joined by a web, with
flash round its parting line. It is symmetric about x = 0, y = 0 and its parting plane
z = 0, so the scene models an eighth (x, y, z >= 0) and only the upper die; the lower die
is the plane z = 0 of symmetry.

The die is the solid above a height field z = z_land + depth(x, y) over a rectangle (x
from -1 to 40 mm, y from -1 to 22 mm, so it covers the symmetry planes), closed by side
walls and a flat top. The depth comes from the part's planform (all in mm):

- a boss: the disk of radius 10 about (22, 0), cavity 6 deep (the boss 16 thick at the
  end of the stroke, with the flash gap 4);
- the web: |y| <= 4 from x = 0 to the boss centre, cavity 1.5 deep (the web 7 thick);
- walls with a 7 degree draft, their upper and lower edges rounded (parabolic blends
  0.2 mm wide in plan, so the metal meets no sharp edge);
- the flash land: 3 mm wide round the part, depth 0;
- beyond it, the gutter: 3 mm deeper, so the flash is free once it leaves the land.

The die starts with its land at z_land = 11 mm, on the billet's top face, and comes down
9 mm to z_land = 2 (half the flash gap). Run:
    python3 scripts/conrod_die.py scenes/dies/conrod_upper.stl
A second argument places the land at another height (mm) for a lower bar, as the billets
tried in docs/forging.md ("A billet that fills the boss"):
    python3 scripts/conrod_die.py /tmp/conrod_upper_10.stl 10
"""

import math
import struct
import sys

BOSS_X = 22.0
BOSS_R = 10.0
WEB_HALF_WIDTH = 4.0
BOSS_DEPTH = 6.0
WEB_DEPTH = 1.5
DRAFT_DEG = 7.0
BLEND = 0.2
LAND = 3.0
GUTTER_DEPTH = 3.0
Z_LAND = 11.0
TOP = Z_LAND + BOSS_DEPTH + 5.0
X_RANGE = (-1.0, 40.0)
Y_RANGE = (-1.0, 22.0)
STEP = 0.25


def smooth_relu(t, w):
    """max(t, 0) with its kink replaced by a parabola over |t| < w (C1)."""
    if t <= -w:
        return 0.0
    if t >= w:
        return t
    return (t + w) ** 2 / (4.0 * w)


def ramp(s, depth):
    """Depth of a drafted wall at distance s (mm) inside its edge: 0 outside, rising
    with the draft's slope, `depth` beyond; both edges blended."""
    slope = 1.0 / math.tan(math.radians(DRAFT_DEG))
    run = depth / slope
    return slope * (smooth_relu(s, BLEND) - smooth_relu(s - run, BLEND))


def boss_distance(x, y):
    """Signed distance (mm) into the boss disk, positive inside."""
    return BOSS_R - math.hypot(abs(x) - BOSS_X, y)


def web_distance(x, y):
    """Signed distance (mm) into the web's rectangle |y| <= 4, |x| <= 22."""
    dx = abs(x) - BOSS_X
    dy = abs(y) - WEB_HALF_WIDTH
    if dx <= 0.0 and dy <= 0.0:
        return -max(dx, dy)
    return -math.hypot(max(dx, 0.0), max(dy, 0.0))


def depth(x, y):
    """Height of the die's face above its land (mm) at (x, y)."""
    boss = boss_distance(x, y)
    web = web_distance(x, y)
    outline = max(boss, web)
    cavity = max(ramp(boss, BOSS_DEPTH), ramp(web, WEB_DEPTH))
    gutter = ramp(-outline - LAND, GUTTER_DEPTH)
    return cavity + gutter


def triangles(z_land=Z_LAND):
    """The die's closed surface with its land at `z_land` (mm), each triangle wound with
    its normal out of the die."""
    nx = round((X_RANGE[1] - X_RANGE[0]) / STEP)
    ny = round((Y_RANGE[1] - Y_RANGE[0]) / STEP)
    xs = [X_RANGE[0] + i * STEP for i in range(nx + 1)]
    ys = [Y_RANGE[0] + j * STEP for j in range(ny + 1)]
    face = [[(x, y, z_land + depth(x, y)) for y in ys] for x in xs]
    top = [[(x, y, TOP + z_land - Z_LAND) for y in ys] for x in xs]
    out = []
    for i in range(nx):
        for j in range(ny):
            a, b, c, d = face[i][j], face[i + 1][j], face[i + 1][j + 1], face[i][j + 1]
            # The face looks down (out of the die, towards the workpiece).
            out += [(a, c, b), (a, d, c)]
    # Side walls between the face's rim and the top's rim, and the top as a fan from its
    # centre; the rim walked counter-clockwise seen from above.
    rim = [(i, 0) for i in range(nx)] + [(nx, j) for j in range(ny)]
    rim += [(i, ny) for i in range(nx, 0, -1)] + [(0, j) for j in range(ny, 0, -1)]
    centre = ((X_RANGE[0] + X_RANGE[1]) / 2.0, (Y_RANGE[0] + Y_RANGE[1]) / 2.0,
              TOP + z_land - Z_LAND)
    for k, (i, j) in enumerate(rim):
        i2, j2 = rim[(k + 1) % len(rim)]
        lo0, lo1 = face[i][j], face[i2][j2]
        hi0, hi1 = top[i][j], top[i2][j2]
        out += [(lo0, lo1, hi1), (lo0, hi1, hi0)]
        out.append((hi0, hi1, centre))
    return out


def cavity_volume(z_land):
    """The cavity's volume (mm^3) between z = 0 and the die with its land at z_land,
    within the land's outer edge (midpoint sums on the generating grid)."""
    total = 0.0
    n = round(40.0 / STEP)
    for i in range(n):
        for j in range(n):
            x, y = (i + 0.5) * STEP, (j + 0.5) * STEP
            if max(boss_distance(x, y), web_distance(x, y)) > -LAND:
                total += (z_land + depth(x, y)) * STEP * STEP
    return total


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "scenes/dies/conrod_upper.stl"
    z_land = float(sys.argv[2]) if len(sys.argv) > 2 else Z_LAND
    tris = triangles(z_land)
    with open(path, "wb") as f:
        f.write(b"rkforge conrod upper die, mm (scripts/conrod_die.py)".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for t in tris:
            f.write(struct.pack("<3f", 0.0, 0.0, 0.0))
            for v in t:
                f.write(struct.pack("<3f", *v))
            f.write(b"\0\0")
    print(f"{path}: {len(tris)} triangles")
    print(f"eighth cavity within the land's edge at the end (mm^3): {cavity_volume(2.0):.1f}")


if __name__ == "__main__":
    main()
