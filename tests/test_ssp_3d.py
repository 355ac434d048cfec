"""`rkforge ssp` with a 3D forging FMU: the hydraulic press of examples/presses driving the
quarter-model cylinder of scenes/press_upsetting_3d.toml (coarse) through the same system and
the same fmpy runner as the 2D test (tests/test_ssp.py), with the 2D system's connections.

A quarter model's `ram.force_N` is a quarter of the billet's: the press of the system has
`model_copies = 4` (bound in the SSD and the start value of the press FMU in the archive), so
it works against the whole billet. The truths: the ram's stroke is the press's velocity
integrated over the communication steps; the press's pressure follows the Python example's
plant driven by the same forging FMU with four times its force; it agrees with the same
press upsetting the axisymmetric billet (scenes/press_upsetting.toml); and the work the
forging FMU books for the ram is the integral of the whole force over the stroke."""
import subprocess
import numpy as np
import pytest
from fmpy.ssp.simulation import simulate_ssp
from fmpy.ssp.ssd import read_ssd

from conftest import scene_variant
from driver import Outputs, Slave
from hydraulic import HydraulicPress

#: The quarter cylinder at 2 core cells per side, 1 ring layer, 6 cells along the axis (49
#: particles), and the axisymmetric billet at the 2D SSP test's grid.
CYLINDER = {"cells = [4, 2, 12]": "cells = [2, 1, 6]"}
AXISYMMETRIC = {"particles = [11, 31]": "particles = [6, 16]"}
#: Communication step and press time: 0.4 s is about 7.4 mm of stroke.
H, T = 2e-4, 0.4


def system(rkforge_bin, tmp_path, name, text, press="hydraulic", tool="ram"):
    scene = tmp_path / f"{name}.toml"
    scene.write_text(text)
    out = tmp_path / f"{name}.ssp"
    subprocess.run([rkforge_bin, "ssp", str(scene), "--press", press, "--tool", tool,
                    "--out", str(out)], check=True, capture_output=True, text=True)
    return str(out)


def connections(ssd):
    return sorted((c.startElement, c.startConnector, c.endElement, c.endConnector)
                  for c in ssd.system.connections)


def bound(ssd, component, name):
    for c in ssd.system.elements:
        if c.name == component:
            for b in c.parameterBindings:
                for values in b.parameterValues:
                    for p in values.parameters:
                        if p.name == name:
                            return p.value
    raise KeyError(f"{component}.{name}")


def python_example(fmu, plant, copies):
    """The Python examples' loop (examples/presses/driver.py, `co_simulate`) of `plant` on the
    forging FMU `fmu`, the plant reading `copies` times its force and work: rows of time,
    stroke and the plant's pressure at every communication point, the first at t = 0. (The
    3D FMU has no `energy.kinetic_to_internal_max`, which the driver also reads.)"""
    slave = Slave(str(fmu))
    rows = [(0.0, 0.0, plant.p)]
    try:
        while (len(rows)) * H <= T * (1 + 1e-12):
            slave.set("ram.velocity_m_per_s", plant.velocity(H))
            slave.step(H)
            f, s, w, height = slave.get("ram.force_N", "ram.stroke_m", "energy.tool_work_J",
                                        "workpiece.height_m")
            plant.advance(Outputs(force=-f * copies, stroke=s, tool_work=w * copies,
                                  height=height, kinetic_to_internal_max=float("nan")), H)
            rows.append((len(rows) * H, s, plant.p))
    finally:
        slave.close()
    return np.array(rows)


@pytest.fixture(scope="module")
def runs(rkforge_bin, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("ssp3d")
    solid = system(rkforge_bin, tmp, "cylinder",
                   scene_variant("press_upsetting_3d.toml", CYLINDER))
    axi = system(rkforge_bin, tmp, "axisymmetric",
                 scene_variant("press_upsetting.toml", AXISYMMETRIC))
    return {"solid": solid, "axi": axi,
            "r": simulate_ssp(solid, stop_time=T - H / 2, step_size=H),
            "r_axi": simulate_ssp(axi, stop_time=T - H / 2, step_size=H), "tmp": tmp}


def test_the_3d_forging_fmu_takes_the_2d_place_in_the_system(runs):
    solid, axi = read_ssd(runs["solid"], validate=True), read_ssd(runs["axi"], validate=True)
    assert {c.name for c in solid.system.elements} == {"press", "forging"}
    assert connections(solid) == connections(axi)
    assert ("forging", "ram.force_N", "press", "ram.force_N") in connections(solid)
    # The quarter model's copies for the press; the axisymmetric model is the whole billet.
    assert bound(solid, "press", "model_copies") == "4"
    assert bound(axi, "press", "model_copies") == "1"
    assert bound(solid, "forging", "workpiece.cells[2]") == "6"


def test_the_ram_strokes_as_the_press_moves_it(runs):
    """fmpy's runner hands each component the other's outputs of the step before, so the
    forging's stroke after step n is h times the press velocities of steps 0..n-1."""
    r = runs["r"]
    assert len(r) == round(T / H)
    stroke, v = r["forging.ram.stroke_m"], r["press.ram.velocity_m_per_s"]
    moved = H * np.concatenate([[0.0], np.cumsum(v)[:-1]])
    assert np.max(np.abs(stroke - moved)) <= 1e-12 * stroke[-1]
    assert 0.0070 < stroke[-1] < 0.0080, "about Q / A = 20 mm/s for 0.4 s, less the oil's squeeze"
    assert np.array_equal(r["press.ram.stroke_m"], stroke)
    assert np.array_equal(r["press.ram.force_N"], r["forging.ram.force_N"])


def test_the_press_follows_its_python_example_against_four_quarters(runs, rkforge_bin):
    """The Python example's hydraulic plant, driven by the same forging FMU (stepped in the
    example's order) with four times its force: the system's pressure-stroke curve within
    what the runner's lag of one step moves, 0.2 % of the peak pressure from 0.5 mm of stroke
    on (before, while the billet loads elastically, the pressure climbs so steeply over the
    stroke that the lag moves it by 1.7 %)."""
    fmu = runs["tmp"] / "forging.fmu"
    subprocess.run([rkforge_bin, "fmu", str(runs["tmp"] / "cylinder.toml"), "--out", str(fmu)],
                   check=True, capture_output=True, text=True)
    py = python_example(fmu, HydraulicPress(), 4.0)
    r = runs["r"]
    assert len(r) == len(py) - 1
    stroke, pressure = r["forging.ram.stroke_m"], r["press.pressure_Pa"]
    keep = stroke >= 0.5e-3
    expected = np.interp(stroke[keep], py[:, 1], py[:, 2])
    error = np.max(np.abs(pressure[keep] - expected)) / py[:, 2].max()
    print(f"3D hydraulic: pressure-stroke within {error:.2e} of the peak pressure")
    assert error <= 0.002


def test_the_quarter_in_the_press_is_the_axisymmetric_billet(runs):
    """The same press upsetting the axisymmetric billet: pressure and whole force at the same
    stroke within 3 % (both grids coarse; a press fed the quarter's force alone would be 75 %
    low), from 1 mm of stroke on."""
    r, a = runs["r"], runs["r_axi"]
    stroke = r["forging.ram.stroke_m"]
    keep = stroke >= 1e-3
    pressure = np.interp(stroke[keep], a["forging.ram.stroke_m"], a["press.pressure_Pa"])
    force = np.interp(stroke[keep], a["forging.ram.stroke_m"], -a["forging.ram.force_N"])
    dp = np.max(np.abs(r["press.pressure_Pa"][keep] / pressure - 1))
    df = np.max(np.abs(-4 * r["forging.ram.force_N"][keep] / force - 1))
    print(f"3D against axisymmetric in the press: pressure {dp:.2%}, force {df:.2%}")
    assert dp <= 0.03 and df <= 0.03


def test_the_work_booked_is_the_whole_force_over_the_stroke(runs):
    """The forging FMU's `energy.tool_work_J` (the anvil is fixed: the ram's alone), times
    the four quarters, against the trapezoidal integral of the whole force over the stroke
    at the communication points: within 1 %."""
    r = runs["r"]
    force, stroke = -4 * r["forging.ram.force_N"], r["forging.ram.stroke_m"]
    integral = np.trapezoid(force, stroke)
    work = 4 * r["forging.energy.tool_work_J"][-1]
    print(f"work: {work:.1f} J booked, {integral:.1f} J integrated")
    assert work == pytest.approx(integral, rel=0.01)
    assert np.array_equal(r["press.ram.tool_work_J"], r["forging.energy.tool_work_J"])


@pytest.mark.parametrize("src, changes, copies, tool", [
    ("block_upsetting_3d.toml", {}, "4", "ram"),
    ("block_upsetting_3d.toml", {'symmetry = ["x_min", "y_min"]': 'symmetry = ["x_min"]'}, "2", "ram"),
    ("press_upsetting_3d.toml", {'part = "quarter"': 'part = "half"'}, "2", "ram"),
    ("press_upsetting_3d.toml", {'part = "quarter"': 'part = "full"'}, "1", "ram"),
    ("flash_quarter.toml", {}, "2", "die"),
    ("ring_compression.toml", {}, "1", "platen"),
])
def test_model_copies_follow_the_symmetry_planes(rkforge_bin, tmp_path, src, changes, copies, tool):
    """Each symmetry plane along the ram's axis (z) doubles what the ram feels: the box
    with two planes and with one, the half and the whole cylinder. In 2D the plane-strain
    quarter (edges x = 0 and y = 0, the die along y) counts its x = 0 edge only, and the
    axisymmetric half ring (mid-plane z = 0) is the whole revolution."""
    ssd = read_ssd(system(rkforge_bin, tmp_path, "s", scene_variant(src, changes), tool=tool),
                   validate=True)
    assert bound(ssd, "press", "model_copies") == copies


def test_a_ram_oblique_to_a_symmetry_plane_is_refused(rkforge_bin, tmp_path):
    """A ram whose axis leans against the plane x = 0 has no whole force that is a multiple
    of the model's: `rkforge ssp` refuses it, naming the tool and the plane."""
    scene = tmp_path / "oblique.toml"
    scene.write_text(scene_variant("block_upsetting_3d.toml", {
        "axis = [0.0, 0.0, -1.0]          # moves down":
        "axis = [0.6, 0.0, -0.8]          # moves down"}))
    p = subprocess.run([rkforge_bin, "ssp", str(scene), "--press", "hydraulic", "--out",
                        str(tmp_path / "o.ssp")], capture_output=True, text=True)
    assert p.returncode != 0
    assert "--tool ram" in p.stderr and "x = 0" in p.stderr, p.stderr
