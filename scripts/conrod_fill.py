#!/usr/bin/env python3
"""How far the metal of `scenes/conrod_3d.toml` came into its die's corners and out into
the flash, read from the last VTU frame of a run (docs/forging.md, "A forging that is not
round").

    python3 scripts/conrod_fill.py out/conrod_3d/frames/frame_0006.vtu

For each of the scene's fill points, moved with the die to the end of its 9 mm stroke: the
nearest particle's distance (mm). Then the flash: how far the farthest particle lies outside
the part's outline in plan, and how many particles lie outside it. Plain Python, no
packages; the outline is `scripts/conrod_die.py`'s.
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


def points(path):
    """The points of an ASCII VTU file (mm)."""
    text = open(path).read()
    block = re.search(r"<Points>\s*<DataArray[^>]*>(.*?)</DataArray>", text, re.S)
    values = [1e3 * float(v) for v in block.group(1).split()]
    return [values[k:k + 3] for k in range(0, len(values), 3)]


def main():
    p = points(sys.argv[1])
    print(f"{len(p)} particles")
    for name, (x, y, z) in FILL_POINTS.items():
        at = (x, y, z - STROKE)
        d = min(math.dist(at, q) for q in p)
        print(f"{name:10s} at ({at[0]:.1f}, {at[1]:.1f}, {at[2]:.1f}) mm: nearest particle {d:.3f} mm")
    out = [max(boss_distance(q[0], q[1]), web_distance(q[0], q[1])) for q in p]
    flash = [s for s in out if s < 0.0]
    print(f"flash: {len(flash)} particles outside the outline, the farthest {-min(out):.2f} mm out "
          f"(land 3 mm wide, then the gutter)")


if __name__ == "__main__":
    main()
