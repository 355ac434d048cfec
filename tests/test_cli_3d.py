"""End-to-end tests of `rkforge run` and `rkforge sweep` on the shipped 3D scene
(scenes/taylor_bar_3d.toml, coarsened): the files they write, their values, and their
answers to bad 3D scene files and options."""
import csv
import json
import math
import re
import subprocess
import xml.etree.ElementTree as ET

import pytest

from conftest import ROOT, assert_stages_account_for_the_wall_time, scene_variant, stl_box

COARSE = {"cells = [8, 4, 60]": "cells = [4, 2, 24]"}


@pytest.fixture(scope="module")
def coarse_run(rkforge_bin, tmp_path_factory):
    """The quarter Taylor bar on a coarse O-grid, to the end (80 us), with frames."""
    tmp = tmp_path_factory.mktemp("taylor3d")
    scene = tmp / "taylor_3d_coarse.toml"
    scene.write_text(scene_variant("taylor_bar_3d.toml", COARSE))
    out = tmp / "out"
    proc = subprocess.run(
        [rkforge_bin, "run", str(scene), "--out", str(out), "--quiet"],
        capture_output=True, text=True, timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    return out, proc.stdout


def test_summary_is_the_bar_after_impact(coarse_run):
    out, stdout = coarse_run
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "ok" and s["kinematics"] == "3d" and s["integration"] == "q2"
    # A quarter O-grid of 4 core cells per side and 2 ring layers: 3 x 3 + 2 x 5 particles
    # per layer, 25 layers; q2 puts 4 points in each of (2 x 2 + 2 x 4) x 24 cells.
    assert s["particles"] == 19 * 25 and s["integration_points"] == 4 * 12 * 24
    assert abs(s["end_time_s"] - 80e-6) < 1e-12
    w = s["workpiece"]
    assert 6.8e-3 < w["radius_m"] < 7.5e-3, w
    assert 21.2e-3 < w["height_m"] < 21.9e-3, w
    assert s["energy"]["balance_error_rel"] < 0.01
    assert s["contact"]["max_penetration_m"] < 0.1 * s["smallest_spacing_m"]
    assert s["contact"]["max_beyond_plane_m"] < 0.1 * s["smallest_spacing_m"]
    (wall,) = s["tools"]
    assert wall["name"] == "wall" and wall["peak_force_N"] > 1e4
    assert "Foulk et al. 2021, converged FE" in stdout and "us per particle-step" in stdout


def test_stage_timers_account_for_the_wall_time(coarse_run):
    # As in 2D; the 3D run counts its samples, frames and pictures as output too.
    assert_stages_account_for_the_wall_time(*coarse_run)


def test_history_has_the_readings_and_the_wall_force(coarse_run):
    out, _ = coarse_run
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 81
    assert float(rows[0]["workpiece.radius_m"]) == pytest.approx(3.2e-3, abs=1e-12)
    radius = [float(r["workpiece.radius_m"]) for r in rows]
    assert radius[-1] > 2 * radius[0]
    assert max(float(r["wall.force_N"]) for r in rows) > 1e4


def test_frames_are_hexahedra_with_plastic_strain_and_a_picture(coarse_run):
    out, _ = coarse_run
    pvd = ET.parse(out / "frames.pvd").getroot()
    files = [d.get("file") for d in pvd.iter("DataSet")]
    assert len(files) == 6
    grid = ET.parse(out / files[-1]).getroot().find("UnstructuredGrid/Piece")
    assert int(grid.get("NumberOfPoints")) == 19 * 25
    assert int(grid.get("NumberOfCells")) == 12 * 24
    types = grid.find("Cells/DataArray[@Name='types']").text.split()
    assert set(types) == {"12"}
    strain = [float(x) for x in grid.find("CellData/DataArray[@Name='plastic_strain']").text.split()]
    assert len(strain) == 12 * 24 and max(strain) > 1.0
    mises = [float(x) for x in grid.find("CellData/DataArray[@Name='von_mises_Pa']").text.split()]
    assert len(mises) == 12 * 24 and 100e6 < max(mises) < 1e9
    # Displacements and velocities per particle, as the 2D frames have them: at the start
    # every particle flies at 227 m/s toward the wall and has not moved; at the end the bar
    # has about stopped, its top having come down some 11 mm (32.4 to 21.6 mm long).
    first = ET.parse(out / files[0]).getroot().find("UnstructuredGrid/Piece")

    def vectors(piece, name):
        a = piece.find(f"PointData/DataArray[@Name='{name}']")
        assert a.get("NumberOfComponents") == "3", name
        v = [float(x) for x in a.text.split()]
        assert len(v) == 3 * 19 * 25, name
        return [v[i:i + 3] for i in range(0, len(v), 3)]

    assert all(v[:2] == [0.0, 0.0] and abs(v[2] + 227.0) < 1e-9
               for v in vectors(first, "velocity_m_per_s"))
    assert all(u == [0.0, 0.0, 0.0] for u in vectors(first, "displacement_m"))
    assert max(abs(v[2]) for v in vectors(grid, "velocity_m_per_s")) < 50.0
    assert -11.5e-3 < min(u[2] for u in vectors(grid, "displacement_m")) < -10e-3
    # The history's plots, as a 2D run draws them; the wall is fixed: no force-stroke curve.
    for png in ["stages.png", "radius_history.png", "height_history.png", "energy.png", "forces.png"]:
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", png
    assert not (out / "force_stroke.png").exists()


def test_a_box_has_the_history_plots_but_no_radius(rkforge_bin, tmp_path):
    # A box's largest distance from the z axis is no size of the part: no radius plot.
    out = tmp_path / "box"
    subprocess.run([rkforge_bin, "run", str(ROOT / "scenes" / "block_upsetting_3d.toml"), "--set",
                    "workpiece.particles=[3, 3, 3]", "--set", "time.end_s=0.02", "--quiet", "--out", str(out)],
                   check=True, capture_output=True, text=True, timeout=600)
    for png in ["height_history.png", "forces.png", "force_stroke.png", "energy.png"]:
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", png
    assert not (out / "radius_history.png").exists()


@pytest.mark.parametrize("old, new, expected", [
    ("cells = [8, 4, 60]", "cells = [7, 4, 60]", "taylor_bar_3d.toml:29: `workpiece.cells`"),
    ("normal = [0.0, 0.0, 1.0]", "normal = [0.0, 0.0, 0.5]", "`tools[0].normal`"),
    ("part = \"quarter\"", "part = \"third\"", "third"),
])
def test_bad_3d_scene_is_refused_with_key_and_line(rkforge_bin, tmp_path, old, new, expected):
    scene = tmp_path / "taylor_bar_3d.toml"
    scene.write_text(scene_variant("taylor_bar_3d.toml", {old: new}))
    proc = subprocess.run([rkforge_bin, "run", str(scene), "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode != 0 and expected in proc.stderr, proc.stderr


def test_a_3d_run_watches_its_kinetic_energy_and_stops_past_the_bound(rkforge_bin, tmp_path):
    """The quasi-static watch in 3D, as in 2D: the mass-scaled block (its first 2 mm of
    stroke) keeps the largest ratio of kinetic to internal energy after the start-up small
    and reports it; with a bound below it the run stops at the step that passed it, naming
    the key and the energies, and keeps its history."""
    base = ["--quiet", "--no-frames", "--set", "time.end_s=0.1"]
    scene = str(ROOT / "scenes" / "block_upsetting_3d.toml")
    ok = subprocess.run([rkforge_bin, "run", scene, "--out", str(tmp_path / "ok"), *base],
                        capture_output=True, text=True, timeout=300)
    assert ok.returncode == 0, ok.stderr
    summary = json.loads((tmp_path / "ok" / "summary.json").read_text())
    ratio = summary["energy"]["kinetic_to_internal_max"]
    assert 0.0 < ratio < 0.01, ratio
    assert summary["warnings"] == []
    out = tmp_path / "stop"
    stop = subprocess.run(
        [rkforge_bin, "run", scene, "--out", str(out), *base,
         "--set", f"checks.kinetic_to_internal_max={ratio / 2}"],
        capture_output=True, text=True, timeout=300)
    assert stop.returncode != 0, stop.stderr
    assert "checks.kinetic_to_internal_max" in stop.stderr and "kinetic" in stop.stderr, stop.stderr
    stopped = json.loads((out / "summary.json").read_text())
    assert stopped["status"] == "error" and stopped["end_time_s"] < 0.1, stopped["end_time_s"]
    assert (out / "history.csv").read_text().count("\n") > 2


def test_3d_overrides_name_the_dotted_key(rkforge_bin, tmp_path):
    proc = subprocess.run(
        [rkforge_bin, "run", str(ROOT / "scenes" / "taylor_bar_3d.toml"), "--out", str(tmp_path / "o"),
         "--set", "discretization.support=9"],
        capture_output=True, text=True, timeout=60)
    assert proc.returncode != 0 and "discretization.support" in proc.stderr, proc.stderr


def test_a_crushing_impact_stops_with_a_diagnosis_and_keeps_its_files(rkforge_bin, tmp_path):
    """At 3000 m/s on the coarsest grid the foot's cells are crushed: the run stops naming
    the step and why instead of crawling on at ever shorter steps, and still writes its
    history and a summary with the error."""
    out = tmp_path / "o"
    proc = subprocess.run(
        [rkforge_bin, "run", str(ROOT / "scenes" / "taylor_bar_3d.toml"), "--out", str(out), "--quiet",
         "--no-frames", "--set", "workpiece.cells=[2, 1, 8]",
         "--set", "workpiece.initial_velocity_m_per_s=[0.0, 0.0, -3000.0]"],
        capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0 and "the stable step fell" in proc.stderr, proc.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "error" and "crushed" in s["error"]
    with open(out / "history.csv") as f:
        assert len(list(csv.DictReader(f))) > 10


BAR_3D = str(ROOT / "scenes" / "taylor_bar_3d.toml")


def test_sweep_of_the_3d_bar_on_two_grids(rkforge_bin, tmp_path):
    """`rkforge sweep` on the shipped 3D bar, cut short, on two O-grids (the axial cells 10
    and 16, the core's 2 and 4): a row per run with the grid as the cylinder's cells, finite
    readings, an error against the Richardson reference of the two grids at the axial
    spacing ratio, which sweep.md states."""
    out = tmp_path / "sweep"
    proc = subprocess.run(
        [rkforge_bin, "sweep", BAR_3D, "--resolution", "2x1x10,4x2x16", "--integration", "q2",
         "--set", "time.end_s=20e-6", "--out", str(out)],
        capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    with open(out / "sweep.csv") as f:
        reader = csv.DictReader(f)
        header, rows = reader.fieldnames, list(reader)
    assert header[:3] == ["time.end_s", "integration", "cells"] and "nx" not in header
    # The fixed wall's peak force is not compared (as in 2D).
    assert "peak_force_N" not in header and header[-3:] == ["error_rel", "pareto", "failure"]
    assert [(r["integration"], r["cells"], r["time.end_s"]) for r in rows] == [
        ("q2", "2x1x10", "20e-6"), ("q2", "4x2x16", "20e-6")]
    radius = [float(r["radius_m"]) for r in rows]
    height = [float(r["height_m"]) for r in rows]
    for r, rad, h in zip(rows, radius, height):
        assert math.isfinite(rad) and 3.2e-3 < rad < 10e-3, r
        assert math.isfinite(h) and 20e-3 < h < 32.4e-3, r
        assert int(r["steps"]) > 0 and float(r["wall_s"]) > 0 and float(r["memory_MB"]) > 0, r
        assert math.isfinite(float(r["error_rel"])) and float(r["error_rel"]) >= 0, r
    # The finer grid holds more.
    assert float(rows[0]["memory_MB"]) < float(rows[1]["memory_MB"])
    # Two grids of spacing ratio 1.6 (10 to 16 axial cells): order 1, f + (f - c) / 0.6.
    ref_radius = radius[1] + (radius[1] - radius[0]) / 0.6
    ref_height = height[1] + (height[1] - height[0]) / 0.6
    md = (out / "sweep.md").read_text()
    match = re.search(r"Reference \(extrapolated, \+- uncertainty\): radius_m = (\S+) \+- \S+, "
                      r"height_m = (\S+) \+-", md)
    assert match, md
    assert float(match[1]) == pytest.approx(ref_radius, rel=1e-5)
    assert float(match[2]) == pytest.approx(ref_height, rel=1e-5)
    assert "| q2 | 4x2x16 |" in md and "workpiece.cells" in md
    expected = max(abs(radius[1] - ref_radius) / ref_radius, abs(height[1] - ref_height) / ref_height)
    assert float(rows[1]["error_rel"]) == pytest.approx(expected, rel=1e-4)
    s = json.loads((out / "time.end_s=20e-6" / "q2_4x2x16_0.5" / "summary.json").read_text())
    assert s["kinematics"] == "3d" and s["end_time_s"] == pytest.approx(20e-6)
    assert (out / "sweep.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_sweep_of_a_3d_scene_takes_q4_and_q2_by_default(rkforge_bin, tmp_path):
    out = tmp_path / "sweep"
    proc = subprocess.run(
        [rkforge_bin, "sweep", BAR_3D, "--resolution", "2x1x8", "--set", "time.end_s=5e-6",
         "--out", str(out)],
        capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    with open(out / "sweep.csv") as f:
        assert [r["integration"] for r in csv.DictReader(f)] == ["q4", "q2", "scni"]


@pytest.mark.parametrize("scene, args, expected", [
    (BAR_3D, ["--resolution", "8x60"], ["--resolution `8x60`", "three numbers", "8x4x60"]),
    (BAR_3D, ["--resolution", "7x4x60"], ["--resolution `7x4x60`", "workpiece.cells"]),
    (BAR_3D, ["--integration", "q2,q3"], ["--integration `q3`", "expected q4, q2 or scni"]),
    (BAR_3D, ["--set", "discretization.support=2,9"], ["discretization.support"]),
    (str(ROOT / "scenes" / "taylor_bar.toml"), ["--resolution", "21x51x3"],
     ["--resolution `21x51x3`", "NXxNY"]),
])
def test_sweep_refuses_a_grid_or_rule_of_the_other_kind(rkforge_bin, tmp_path, scene, args, expected):
    proc = subprocess.run([rkforge_bin, "sweep", scene, *args, "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1 and "panicked" not in proc.stderr, proc.stderr
    for e in expected:
        assert e in proc.stderr, (e, proc.stderr)
    assert not (tmp_path / "o" / "sweep.csv").exists()


BLOCK_STL = """
name = "block_stl"
[model]
kinematics = "3d"
[workpiece]
shape = "box"
origin_m = [0.0, 0.0, 0.0]
size_m = [0.005, 0.005, 0.01]
particles = [5, 5, 9]
symmetry = ["x_min", "y_min"]
[material]
density_kg_per_m3 = 2700.0
youngs_modulus_pa = 70e9
poisson_ratio = 0.33
hardening = { law = "linear", yield_stress_pa = 100e6, modulus_pa = 500e6 }
[discretization]
integration = "q2"
[time]
end_s = 400e-6
[[tools]]
name = "anvil"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, -1.0]
motion = { kind = "fixed" }
[[tools]]
name = "ram"
shape = "stl"
file = "dies/ram.stl"
unit = "mm"
axis = [0.0, 0.0, -1.0]
motion = { kind = "constant", velocity_m_per_s = 2.0 }
[[tools.fill_points]]
name = "corner"
at_m = [0.005, 0.005, 0.0105]
[[tools.fill_points]]
name = "beyond"
at_m = [0.012, 0.0, 0.0105]
[output]
frames = 2
fill_distance_rel = 0.1
"""


def test_an_stl_die_is_written_with_its_pressure_and_its_fill_points(rkforge_bin, tmp_path):
    """A quarter block pressed by an STL ram from 0.5 mm above it by 0.8 mm (2 m/s, 400 us)
    onto a plane anvil: the frames hold the ram's triangles where it is with the pressure on
    each, and the anvil's contact patch, each integrating to its tool's normal force (the
    axial force: flat frictionless faces); the summary says which
    fill point filled, when and at which stroke (0.375 mm: 0.5 mm less the fill distance of
    0.1 spacings), and the history has the contact area, its share and the mean pressure."""
    (tmp_path / "dies").mkdir()
    stl_box(tmp_path / "dies" / "ram.stl", [-5.0, -5.0, 10.5], [15.0, 15.0, 15.5])
    scene = tmp_path / "block_stl.toml"
    scene.write_text(BLOCK_STL)
    out = tmp_path / "out"
    subprocess.run([rkforge_bin, "run", str(scene), "--out", str(out), "--quiet"],
                   check=True, capture_output=True, text=True, timeout=300)
    s = json.loads((out / "summary.json").read_text())
    anvil, ram = s["tools"]
    assert anvil["fill_points"] == []
    corner, beyond = ram["fill_points"]
    assert corner["name"] == "corner" and corner["filled"]
    assert 0.375e-3 <= corner["filled_stroke_m"] < 0.376e-3, corner
    assert abs(corner["filled_s"] - corner["filled_stroke_m"] / 2.0) < 1e-12
    assert not beyond["filled"] and beyond["filled_s"] is None
    assert ram["contact_area_m2"] > 0.99 * 25e-6 and 0.1 < ram["surface_fraction"] < 0.3
    assert abs(ram["pressure_mean_Pa"] * ram["contact_area_m2"] / abs(ram["axial_force_N"]) - 1) < 1e-3
    pvd = ET.parse(out / "die_ram.pvd").getroot()
    files = [d.get("file") for d in pvd.iter("DataSet")]
    assert len(files) == 3
    piece = ET.parse(out / files[-1]).getroot().find("UnstructuredGrid/Piece")
    assert int(piece.get("NumberOfCells")) == 12
    assert set(piece.find("Cells/DataArray[@Name='types']").text.split()) == {"5"}
    z = [float(v) for v in piece.find("Points/DataArray").text.split()][2::3]
    assert min(z) == pytest.approx(10.5e-3 - 0.8e-3, abs=1e-9)
    pressure = [float(v) for v in piece.find("CellData/DataArray[@Name='pressure_Pa']").text.split()]
    force = [float(v) for v in piece.find("CellData/DataArray[@Name='force_N']").text.split()]
    assert sum(force) == pytest.approx(abs(ram["axial_force_N"]), rel=1e-9)
    assert max(pressure) > 0.0
    anvil_pvd = ET.parse(out / "die_anvil.pvd").getroot()
    last = [d.get("file") for d in anvil_pvd.iter("DataSet")][-1]
    piece = ET.parse(out / last).getroot().find("UnstructuredGrid/Piece")
    force = [float(v) for v in piece.find("CellData/DataArray[@Name='force_N']").text.split()]
    assert sum(force) == pytest.approx(anvil["axial_force_N"], rel=1e-9), "the anvil's contact patch"
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    assert float(rows[-1]["ram.contact_area_m2"]) == ram["contact_area_m2"]
    assert float(rows[0]["ram.corner.filled"]) == 0.0 and float(rows[-1]["ram.corner.filled"]) == 1.0
