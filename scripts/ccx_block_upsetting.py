#!/usr/bin/env python3
"""An independent finite-element reference for scenes/block_upsetting_3d.toml (CalculiX).

The block 60 x 40 x 40 mm upset to half its height between flat dies with Coulomb
friction 0.3 is symmetric about x = 0, y = 0 and its mid-height (inertia is negligible at
20 mm/s), so CalculiX models an eighth, 30 x 20 x 20 mm, under a rigid die (every node
moved) that travels down by half the stroke; four times its reaction is the whole block's
force, four times rkforge's quarter model's `ram.force_N`. Implicit static increments with
NLGEOM; J2 with the scene's Swift law `sigma_y = K (eps0 + eps_p)^n` as a table to a
plastic strain of 5 (CalculiX integrates isotropic hardening at finite strain
multiplicatively); a penalty contact from the block's top and free faces (so the faces
that roll over onto the die are held) to the die's face, with Coulomb friction. Units mm,
N, MPa. docs/forging.md, "An independent reference: the block in CalculiX", has the
figures and what limits the runs (no static run reaches 20 mm, as the free faces roll
onto the die; the explicit one, `--explicit`, does).

    apt-get install calculix-ccx
    python3 scripts/ccx_block_upsetting.py run out/ccx_q4 --cells 6 4 4
    python3 scripts/ccx_block_upsetting.py compare out/block_upsetting_3d/history.csv \
        out/ccx_q4/block.dat
    python3 scripts/ccx_block_upsetting.py shape out/ccx_q4/block.frd --stroke 15

`run` writes `block.inp` and runs `ccx` in the directory (the run ends where CalculiX stops
converging; it says how far it got); `compare` prints the whole block's force (MN) at every
2 mm of stroke from rkforge histories and CalculiX `.dat` files, beside the frictionless
homogeneous upset `F = sigma_y(ln(h0 / h)) A0 h0 / h` (rigid-plastic: the plastic strain
taken as the whole logarithmic strain); `shape` prints the mid-height section's end-face
middle, side-face middle and corner, as `scripts/block_bulge.py` does for rkforge's frames.
"""
import argparse
import csv
import math
import os
import subprocess

E, NU = 71000.0, 0.3  # MPa, -
K, EPS0, N = 576.79, 0.01658, 0.3593  # MPa, -, - (paper Table 4)
LX, LY, LZ = 30.0, 20.0, 20.0  # the eighth, mm
A0 = 2400.0  # the block's cross-section, mm^2
WHOLE = 4.0  # the whole block's force over the quarter model's (the eighth's die)
H0 = 40.0  # the block's height, mm
STROKE = 10.0  # the die's travel on the eighth: half of the 20 mm stroke

# C3D8 node order: the bottom face counter-clockwise, then the top face.
CORNERS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
# C3D20's mid-side nodes, on a lattice of half-cells: bottom edges, top edges, vertical.
MIDSIDE = [(1, 0, 0), (2, 1, 0), (1, 2, 0), (0, 1, 0), (1, 0, 2), (2, 1, 2), (1, 2, 2), (0, 1, 2),
           (0, 0, 1), (2, 0, 1), (2, 2, 1), (0, 2, 1)]


def block_deck(cells, element, mu, penalty, stick, dt_max, contact, explicit=None):
    """The CalculiX input for the eighth with `cells` elements along x, y, z."""
    nx, ny, nz = cells
    q = 2 if element.startswith("C3D20") else 1
    lines = ["*HEADING", f"rkforge block_upsetting_3d, eighth, {element} {nx}x{ny}x{nz}, mu {mu}"]
    lines.append("*NODE, NSET=NALL")
    nid, n = {}, 0
    for k in range(q * nz + 1):
        for j in range(q * ny + 1):
            for i in range(q * nx + 1):
                if q == 2 and i % 2 + j % 2 + k % 2 > 1:
                    continue  # a face or cell centre: no node of a 20-node brick
                n += 1
                nid[i, j, k] = n
                lines.append(f"{n}, {LX * i / (q * nx):.9g}, {LY * j / (q * ny):.9g}, "
                             f"{LZ * k / (q * nz):.9g}")
    die_nodes, mx, my = {}, 12, 8  # a plate twice the eighth's plan, 2 mm thick
    for k in range(2):
        for j in range(my + 1):
            for i in range(mx + 1):
                n += 1
                die_nodes[i, j, k] = n
                lines.append(f"{n}, {2 * LX * i / mx:.9g}, {2 * LY * j / my:.9g}, {LZ + 2.0 * k:.9g}")

    lines.append(f"*ELEMENT, TYPE={element}, ELSET=BLOCK")
    e, top, xface, yface = 0, [], [], []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                e += 1
                a, b, c = q * i, q * j, q * k
                conn = [nid[a + q * u, b + q * v, c + q * w] for u, v, w in CORNERS]
                if q == 2:
                    conn += [nid[a + u, b + v, c + w] for u, v, w in MIDSIDE]
                ids = ", ".join(map(str, conn[:15]))
                lines.append(f"{e}, {ids}" + ("," if len(conn) > 15 else ""))
                if len(conn) > 15:
                    lines.append(", ".join(map(str, conn[15:])))
                top += [e] if k == nz - 1 else []
                xface += [e] if i == nx - 1 else []
                yface += [e] if j == ny - 1 else []
    lines.append("*ELEMENT, TYPE=C3D8, ELSET=DIE")
    die = []
    for j in range(my):
        for i in range(mx):
            e += 1
            conn = [die_nodes[i + u, j + v, w] for u, v, w in CORNERS]
            lines.append(f"{e}, " + ", ".join(map(str, conn)))
            die.append(e)

    sets = {"XSYM": sorted(v for (i, _, _), v in nid.items() if i == 0),
            "YSYM": sorted(v for (_, j, _), v in nid.items() if j == 0),
            "ZSYM": sorted(v for (_, _, k), v in nid.items() if k == 0)}
    # faces: S2 the top (z+), S4 x+, S5 y+ of the block; S1 the die's underside (z-)
    surfaces = {"SBLOCK": [f"{x}, S2" for x in top] + [f"{x}, S4" for x in xface]
                + [f"{x}, S5" for x in yface],
                "SDIE": [f"{x}, S1" for x in die]}
    fixed = ["XSYM, 1, 1", "YSYM, 2, 2", "ZSYM, 3, 3", "DIEN, 1, 2"]
    travel = f"DIEN, 3, 3, {-STROKE}"  # every node of the die moved: a rigid die

    def nset(name, ids):
        lines.append(f"*NSET, NSET={name}")
        lines.extend(", ".join(map(str, ids[a:a + 12])) for a in range(0, len(ids), 12))

    for name, ids in sets.items():
        nset(name, ids)
    nset("DIEN", sorted(die_nodes.values()))
    for name, faces in surfaces.items():
        lines.append(f"*SURFACE, NAME={name}, TYPE=ELEMENT")
        lines += faces
    lines += ["*MATERIAL, NAME=AL", "*ELASTIC", f"{E}, {NU}"]
    if explicit:  # the densities (t/mm^3) times the mass scale
        lines += ["*DENSITY", f"{2.7e-9 * explicit:.6g}"]
    lines += ["*PLASTIC"]
    eps = [0.0]
    while eps[-1] < 5.0:
        eps.append(eps[-1] + (0.002 if eps[-1] < 0.05 else 0.01 if eps[-1] < 0.5 else 0.05))
    lines += [f"{K * (EPS0 + p) ** N:.8g}, {p:.6g}" for p in eps]
    lines += [
        "*MATERIAL, NAME=DIESTEEL", "*ELASTIC", "210000., 0.3",
        *(["*DENSITY", f"{7.8e-9 * explicit:.6g}"] if explicit else []),
        "*SOLID SECTION, ELSET=BLOCK, MATERIAL=AL",
        "*SOLID SECTION, ELSET=DIE, MATERIAL=DIESTEEL",
        "*SURFACE INTERACTION, NAME=SI",
        "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR",
        # node to surface: a tension of 0.01 MPa at clearances beyond 1e-3 mm, as the law asks
        f"{penalty}" + (", 0.01, 1e-3" if contact == "node" else ""),
    ]
    if mu > 0:
        lines += ["*FRICTION", f"{mu}, {stick}"]
    lines += [
        f"*CONTACT PAIR, INTERACTION=SI, TYPE={contact.upper()} TO SURFACE",
        "SBLOCK, SDIE",
        "*BOUNDARY", *fixed,
    ]
    if explicit:
        # central differences, the die at constant speed from the start; the force printed
        # every 100 increments (the step is about 1.6e-4 at a mass scale of 1e6)
        lines += [
            "*AMPLITUDE, NAME=RAMP", "0., 0., 1., 1.",
            "*STEP, NLGEOM, INC=100000000",
            "*DYNAMIC, EXPLICIT", "1e-4, 1.0",
            "*BOUNDARY, AMPLITUDE=RAMP", travel,
            "*NODE PRINT, NSET=DIEN, FREQUENCY=100, TOTALS=ONLY", "RF",
            "*NODE FILE, FREQUENCY=1000", "U",
        ]
    else:
        lines += [
            "*STEP, NLGEOM, INC=100000",
            # more iterations and cutbacks than the defaults for the late, rolled-over faces
            "*CONTROLS, PARAMETERS=TIME INCREMENTATION", "4, 8, 9, 60, 10, 4, , 20",
            "*STATIC", f"0.005, 1.0, 1e-7, {dt_max}",
            "*BOUNDARY", travel,
            "*NODE PRINT, NSET=DIEN, FREQUENCY=1, TOTALS=ONLY", "RF",
            "*NODE FILE, FREQUENCY=1", "U",
            "*EL FILE, FREQUENCY=1", "S, PEEQ",
        ]
    lines += [
        "*END STEP",
    ]
    return "\n".join(lines) + "\n"


def rkforge_curve(path):
    """(stroke mm, the whole block's force MN) from an rkforge history.csv (quarter model)."""
    with open(path, newline="") as f:
        return [(float(r["ram.stroke_m"]) * 1e3, -WHOLE * float(r["ram.force_N"]) / 1e6)
                for r in csv.DictReader(f)]


def ccx_curve(path):
    """(stroke mm, the whole block's force MN) from a CalculiX .dat file of `run`."""
    lines = open(path).read().split("\n")
    out = [(0.0, 0.0)]
    for i, line in enumerate(lines):
        if "total force (fx,fy,fz) for set DIEN" in line:
            t, fz = float(line.split()[-1]), float(lines[i + 2].split()[2])
            out.append((2 * STROKE * t, -WHOLE * fz / 1e6))
    return out


def at(curve, s):
    """Linear interpolation at stroke `s`; None beyond the curve's end."""
    for (a, fa), (b, fb) in zip(curve, curve[1:]):
        if a - 1e-4 <= s <= b + 1e-4 and b > a:
            return fa + (fb - fa) * (s - a) / (b - a)
    return None


def uniform(s):
    """The frictionless upset's force on the whole block (MN) at stroke `s` (mm)."""
    h = H0 - s
    return K * (EPS0 + math.log(H0 / h)) ** N * A0 * H0 / h / 1e6


def frd_shape(path, stroke):
    """The mid-height section's end-face middle x, side-face middle y and corner (x, y), mm,
    from the displacements in a CalculiX .frd file at the increment nearest `stroke` (mm),
    on the eighth's plane z = 0; and that increment's stroke."""
    coords, disp, best, block, t = {}, None, None, None, None
    with open(path) as f:
        for line in f:
            if line.startswith("    2C"):
                block = coords
            elif line.startswith("  100CL"):
                t = float(line[12:24])
            elif line.startswith(" -4  DISP"):
                block = {}
            elif line.startswith(" -4"):
                block = None
            elif line.startswith(" -1") and block is not None:
                block[int(line[3:13])] = (float(line[13:25]), float(line[25:37]),
                                          float(line[37:49]))
            elif line.startswith(" -3"):
                if block is not None and block is not coords and (
                        best is None or abs(2 * STROKE * t - stroke) < abs(best - stroke)):
                    disp, best = block, 2 * STROKE * t
                block = None

    def moved(x, y):
        node = next(n for n, c in coords.items()
                    if abs(c[0] - x) < 1e-6 and abs(c[1] - y) < 1e-6 and abs(c[2]) < 1e-6)
        return [coords[node][i] + disp[node][i] for i in range(3)]

    end, side, corner = moved(LX, 0.0), moved(0.0, LY), moved(LX, LY)
    return end[0], side[1], corner[0], corner[1], best


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="write the deck and run ccx")
    r.add_argument("out")
    r.add_argument("--cells", type=int, nargs=3, default=[12, 8, 8], metavar=("NX", "NY", "NZ"))
    r.add_argument("--element", default="C3D20R", choices=["C3D20R", "C3D8R"],
                   help="quadratic or linear bricks, reduced integration")
    r.add_argument("--mu", type=float, default=0.3, help="Coulomb friction (0: none)")
    r.add_argument("--penalty", type=float, default=1.0e7,
                   help="contact stiffness, MPa/mm (the force converges from 1e7 on)")
    r.add_argument("--stick-slope", type=float, default=2.0e5,
                   help="friction's stick slope, MPa per mm of elastic slip")
    r.add_argument("--contact", default="surface", choices=["surface", "node"],
                   help="CalculiX's contact: surface to surface, or node to surface")
    r.add_argument("--explicit", type=float, default=None, metavar="MASS_SCALE",
                   help="explicit dynamics with the densities times MASS_SCALE, not static")
    r.add_argument("--dt-max", type=float, default=0.004, help="largest increment, of the step")
    sh = sub.add_parser("shape", help="the mid-height section at the end of a run")
    sh.add_argument("frd", help="the run's block.frd")
    sh.add_argument("--stroke", type=float, default=20.0, help="mm of the 20 mm stroke")
    c = sub.add_parser("compare", help="the force at every 2 mm of stroke")
    c.add_argument("files", nargs="+", help="rkforge history.csv or CalculiX .dat files")
    a = p.parse_args()
    if a.cmd == "run":
        os.makedirs(a.out, exist_ok=True)
        with open(os.path.join(a.out, "block.inp"), "w") as f:
            f.write(block_deck(a.cells, a.element, a.mu, a.penalty, a.stick_slope, a.dt_max, a.contact, a.explicit))
        with open(os.path.join(a.out, "ccx.log"), "w") as log:
            rc = subprocess.run(["ccx", "-i", "block"], cwd=a.out, stdout=log,
                                stderr=subprocess.STDOUT).returncode
        reached = ccx_curve(os.path.join(a.out, "block.dat"))[-1][0]
        print(f"ccx exit {rc}; reached {reached:.2f} mm of the {2 * STROKE:g} mm stroke")
    elif a.cmd == "shape":
        x_end, y_side, x_corner, y_corner, at_stroke = frd_shape(a.frd, a.stroke)
        print(f"at {at_stroke:.2f} mm: end face middle x = {x_end:.3f} mm, side face middle y = {y_side:.3f} mm, "
              f"corner ({x_corner:.3f}, {y_corner:.3f}) mm")
    else:
        curves = [rkforge_curve(f) if f.endswith(".csv") else ccx_curve(f) for f in a.files]
        print("| stroke (mm) | " + " | ".join(a.files) + " | uniform, frictionless |")
        print("|---" * (len(a.files) + 2) + "|")
        for s in range(2, 21, 2):
            cells = ["-" if v is None else f"{v:.4f}" for v in (at(cv, s) for cv in curves)]
            print(f"| {s} | " + " | ".join(cells) + f" | {uniform(s):.4f} |")


if __name__ == "__main__":
    main()
