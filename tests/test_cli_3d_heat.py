"""End-to-end tests of `rkforge run` on the shipped 3D OFHC copper bar
(scenes/taylor_ofhc_3d.toml, coarsened): Johnson-Cook with adiabatic heating in 3D, the heat
it books against the energy account's plastic work, the softening heating gives (the sign
the axisymmetric run shows), its files, friction heat and thermal strain in 3D, and the
refusal of a tool's heat transfer without its temperature; and the shipped 3D hot
upsetting (scenes/hot_upsetting_3d.toml, coarsened): the heat that moves, to the dies and
the air, with its account and its picture."""
import csv
import json
import subprocess
import xml.etree.ElementTree as ET

import pytest

from conftest import ROOT, scene_variant

COARSE = "workpiece.cells=[4, 2, 24]"


def run(rkforge_bin, out, *sets, frames=True):
    args = [rkforge_bin, "run", str(ROOT / "scenes" / "taylor_ofhc_3d.toml"), "--out", str(out),
            "--quiet", "--set", COARSE]
    for s in sets:
        args += ["--set", s]
    if not frames:
        args.append("--no-frames")
    proc = subprocess.run(args, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return json.loads((out / "summary.json").read_text())


@pytest.fixture(scope="module")
def heated(rkforge_bin, tmp_path_factory):
    out = tmp_path_factory.mktemp("ofhc3d") / "heated"
    return out, run(rkforge_bin, out)


def test_heat_held_is_the_plastic_works_share(heated):
    """Adiabatic: every joule the points hold above 22 C is beta = 0.9 of the plastic work
    the energy account dissipated, and nothing left the body."""
    _, s = heated
    t = s["thermal"]
    assert s["status"] == "ok"
    assert t["heat_content_J"] == pytest.approx(0.9 * s["energy"]["plastic_J"], rel=1e-9)
    assert t["plastic_heat_J"] == pytest.approx(t["heat_content_J"], rel=1e-9)
    assert abs(t["heat_balance_rel"]) < 1e-9
    assert t["heat_to_tools_J"] == 0.0 and t["heat_to_surroundings_J"] == 0.0
    # The foot heats by hundreds of kelvin, the far end stays at the start's 22 C.
    assert 150.0 < t["temperature_max_c"] < 600.0, t
    assert t["temperature_min_c"] == pytest.approx(22.0, abs=0.5)
    assert 22.0 < t["temperature_mean_c"] < t["temperature_max_c"]
    assert s["energy"]["balance_error_rel"] < 0.01


def test_heating_softens_the_foot(rkforge_bin, heated, tmp_path):
    """As in the axisymmetric run (docs/accuracy.md: 0.11 mm shorter and 0.46 mm wider with
    heating on 11 x 67): the heated bar ends shorter with a wider foot than with beta = 0."""
    _, hot = heated
    cold = run(rkforge_bin, tmp_path / "cold", "thermal.taylor_quinney=0.0", frames=False)
    assert cold["thermal"]["temperature_max_c"] == pytest.approx(22.0, abs=1e-9)
    assert hot["workpiece"]["height_m"] < cold["workpiece"]["height_m"] - 2e-5
    assert hot["workpiece"]["radius_m"] > cold["workpiece"]["radius_m"] + 5e-5


def test_history_frames_and_picture_carry_the_temperature(heated):
    out, _ = heated
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 101
    hottest = [float(r["thermal.temperature_max_c"]) for r in rows]
    assert hottest[0] == pytest.approx(22.0) and hottest[-1] > 150.0
    assert all(b >= a - 1e-9 for a, b in zip(hottest, hottest[1:]))
    pvd = ET.parse(out / "frames.pvd").getroot()
    last = [d.get("file") for d in pvd.iter("DataSet")][-1]
    grid = ET.parse(out / last).getroot().find("UnstructuredGrid/Piece")
    temps = [float(x) for x in
             grid.find("CellData/DataArray[@Name='temperature_C']").text.split()]
    assert len(temps) == int(grid.get("NumberOfCells")) and max(temps) > 100.0
    assert (out / "temperature.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_friction_heat_runs_in_3d(rkforge_bin, tmp_path):
    """The wall with Coulomb friction: the summary books the friction heat (the heat stage
    runs for it, as in 2D) and the heat account closes with the workpiece's half of it."""
    s = run(rkforge_bin, tmp_path / "friction", "tools[0].friction=0.1", frames=False)
    t = s["thermal"]
    assert s["status"] == "ok"
    assert t["friction_heat_J"] > 0.0
    assert abs(t["heat_balance_rel"]) < 1e-9
    assert t["heat_content_J"] == pytest.approx(
        t["plastic_heat_J"] + 0.5 * t["friction_heat_J"], rel=1e-9)
    assert s["energy"]["balance_error_rel"] < 0.01


def test_thermal_strain_runs_in_3d(rkforge_bin, tmp_path):
    """The copper with a thermal expansion: the summary books the elastic energy the
    heating put in, and the energy account closes with it. (With friction on the wall as
    well, the bar stops at 49 us with a return map that does not converge at the foot, in
    2D's axisymmetric scene alike.)"""
    s = run(rkforge_bin, tmp_path / "expansion", "thermal.expansion_per_k=1.7e-5",
            frames=False)
    assert s["status"] == "ok"
    assert s["energy"]["thermoelastic_J"] > 0.0
    assert s["energy"]["balance_error_rel"] < 0.01


@pytest.mark.parametrize("old, new, expected", [
    ('motion = { kind = "fixed" }', 'motion = { kind = "fixed" }\nheat_transfer_w_per_m2_k = 1.0e4',
     "taylor_ofhc_3d.toml:61: `tools[0].heat_transfer_w_per_m2_k`"),
    ("[thermal]\ninitial_temperature_c = 22.0\nspecific_heat_j_per_kg_k = 383.0\ntaylor_quinney = 0.9\n",
     "", "`material.hardening.law`"),
])
def test_heat_3d_refuses_what_it_lacks(rkforge_bin, tmp_path, old, new, expected):
    scene = tmp_path / "taylor_ofhc_3d.toml"
    scene.write_text(scene_variant("taylor_ofhc_3d.toml", {old: new}))
    proc = subprocess.run([rkforge_bin, "run", str(scene), "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode != 0 and expected in proc.stderr, proc.stderr


UPSET_COARSE = ["workpiece.cells=[2, 1, 6]", "time.end_s=0.15"]


@pytest.fixture(scope="module")
def upset(rkforge_bin, tmp_path_factory):
    out = tmp_path_factory.mktemp("upset3d") / "hot_upsetting_3d"
    args = [rkforge_bin, "run", str(ROOT / "scenes" / "hot_upsetting_3d.toml"), "--out", str(out),
            "--quiet"]
    for s in UPSET_COARSE:
        args += ["--set", s]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return out, json.loads((out / "summary.json").read_text())


def test_upset_gives_heat_to_the_dies_and_the_air(upset):
    """The billet at 1150 C on dies at 250 C for 0.15 s (3 mm of stroke, cells of 10 mm
    along the radius and the axis): the dies take heat (725 J, as much from each; the
    semi-infinite solution with surface resistance at the end faces' area gives 680 J at
    1150 C's properties), the air some (50 J), the points next to the dies chill (1114 C)
    while the core stays at 1150 C plus its plastic heat, and the heat account closes to
    round-off (heat held + to the tools + to the air = the plastic work's)."""
    _, s = upset
    t = s["thermal"]
    assert s["status"] == "ok"
    assert abs(t["heat_balance_rel"]) < 1e-9
    assert t["heat_to_tools_J"] > 10.0 * t["heat_to_surroundings_J"] > 0.0
    assert t["heat_content_J"] < 0.0 < t["plastic_heat_J"]
    assert t["temperature_min_c"] < 1125.0
    assert 1150.0 <= t["temperature_max_c"] < 1200.0
    anvil, ram = s["tools"]
    assert anvil["heat_J"] == pytest.approx(ram["heat_J"], rel=0.01)
    assert anvil["heat_J"] + ram["heat_J"] == pytest.approx(t["heat_to_tools_J"], rel=1e-12)
    assert t["plastic_heat_J"] == pytest.approx(0.9 * s["energy"]["plastic_J"], rel=1e-2)


def test_upset_history_frames_and_picture_carry_the_chill(upset):
    out, _ = upset
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    to_tools = [float(r["thermal.heat_to_tools_J"]) for r in rows]
    assert to_tools[0] == 0.0 and to_tools[-1] > 0.0
    assert all(b >= a for a, b in zip(to_tools, to_tools[1:]))
    coldest = [float(r["thermal.temperature_min_c"]) for r in rows]
    assert coldest[0] == pytest.approx(1150.0) and coldest[-1] < 1125.0
    pvd = ET.parse(out / "frames.pvd").getroot()
    last = [d.get("file") for d in pvd.iter("DataSet")][-1]
    grid = ET.parse(out / last).getroot().find("UnstructuredGrid/Piece")
    temps = [float(x) for x in
             grid.find("CellData/DataArray[@Name='temperature_C']").text.split()]
    assert min(temps) < 1135.0 and max(temps) > 1145.0
    assert (out / "temperature.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
