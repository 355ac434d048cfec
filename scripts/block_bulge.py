#!/usr/bin/env python3
"""How the upset block's section bulges at mid-height: the middles of its two free faces and
its corner, read from a VTU frame of `scenes/block_upsetting_3d.toml` (docs/forging.md, "The
rectangular block in 3D").

    python3 scripts/block_bulge.py out/block_upsetting_3d/frames/frame_0004.vtu 7 5 9

The last three arguments are the scene's `workpiece.particles`; the frame's points are the
particles in lattice order (index i + nx (j + ny k)), the quarter x, y >= 0 of a block whose
undeformed faces are x = x_max and y = y_max. Plain Python, no packages.
"""
import math
import re
import sys


def points(path):
    """The points of an ASCII VTU file (m)."""
    text = open(path).read()
    block = re.search(r"<Points>\s*<DataArray[^>]*>(.*?)</DataArray>", text, re.S)
    values = [float(v) for v in block.group(1).split()]
    return [values[k:k + 3] for k in range(0, len(values), 3)]


def main():
    path, nx, ny, nz = sys.argv[1], *map(int, sys.argv[2:5])
    p = points(path)
    if len(p) != nx * ny * nz:
        sys.exit(f"{path}: {len(p)} points, not {nx} x {ny} x {nz}")

    def at(i, j, k):
        return p[i + nx * (j + ny * k)]

    k = (nz - 1) // 2
    end, side, corner = at(nx - 1, 0, k), at(0, ny - 1, k), at(nx - 1, ny - 1, k)
    mm = 1e3
    print(f"mid-height layer k = {k}, z = {corner[2] * mm:.3f} mm")
    print(f"end face middle:  x = {end[0] * mm:.3f} mm")
    print(f"side face middle: y = {side[1] * mm:.3f} mm")
    print(f"corner: x = {corner[0] * mm:.3f} mm, y = {corner[1] * mm:.3f} mm, "
          f"{math.hypot(corner[0], corner[1]) * mm:.3f} mm from the axis")
    print(f"corner behind the end face by {(end[0] - corner[0]) * mm:.3f} mm, "
          f"behind the side face by {(side[1] - corner[1]) * mm:.3f} mm")


if __name__ == "__main__":
    main()
