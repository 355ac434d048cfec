"""The FMU of a 3D scene (`model.kinematics = "3d"`) through fmpy, FMI 2.0 and 3.0: it
validates, has the 2D FMU's interface (tool velocity inputs, the 3D register's outputs under
their history names, the scene's keys as parameters), and its outputs at the communication
points are the bits of `rkforge run`'s history of the same scene."""
import csv
import subprocess

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from conftest import scene_variant, stl_box
from ros_peer import upset_bar_3d
from test_fmu3 import Slave3, pack

# The Taylor bar in 3D, coarse and 10 us long (history rows every 1 us).
COARSE = {"cells = [8, 4, 60]": "cells = [2, 1, 8]", "end_s = 80.0e-6": "end_s = 10.0e-6"}


@pytest.fixture(scope="module")
def bar(tmp_path_factory):
    path = tmp_path_factory.mktemp("fmu3d") / "taylor_bar_3d.toml"
    path.write_text(scene_variant("taylor_bar_3d.toml", COARSE))
    return path


@pytest.fixture(scope="module")
def history(bar, rkforge_bin, tmp_path_factory):
    out = tmp_path_factory.mktemp("run3d")
    subprocess.run([rkforge_bin, "run", str(bar), "--out", str(out), "--quiet", "--no-frames"],
                   check=True, capture_output=True, text=True, timeout=300)
    with open(out / "history.csv") as f:
        return list(csv.DictReader(f))


@pytest.mark.parametrize("fmi", ["2", "3"])
def test_a_3d_fmu_validates_with_the_2d_interface(bar, rkforge_bin, tmp_path, fmi):
    path = pack(rkforge_bin, bar, tmp_path / f"bar{fmi}.fmu", fmi)
    assert validate_fmu(path) == []
    md = read_model_description(path)
    assert md.fmiVersion == ("2.0" if fmi == "2" else "3.0")
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    by = {v.name: v for v in md.modelVariables}
    outputs = {n for n, v in by.items() if v.causality == "output"}
    assert {"wall.force_N", "wall.stroke_m", "workpiece.height_m", "workpiece.radius_m",
            "energy.kinetic_J"} <= outputs
    assert by["wall.force_N"].unit == "N" and by["energy.kinetic_J"].unit == "J"
    # The wall is fixed: no input; the scene's keys are the parameters.
    assert not [n for n, v in by.items() if v.causality == "input"]
    assert by["workpiece.cells[2]"].causality == "parameter"
    assert by["discretization.integration"].start == "q2"
    assert not any("contact_pressure" in n for n in by)
    if fmi == "3":
        assert {"wall.early_return.contact", "wall.early_return.force"} <= set(by)


@pytest.mark.parametrize("fmi", ["2", "3"])
def test_a_3d_fmu_gives_the_bits_of_rkforge_run(bar, history, rkforge_bin, tmp_path, fmi):
    """Communication step = history interval: the wall's force and the bar's height at every
    communication point are the history's rows to the bit."""
    path = pack(rkforge_bin, bar, tmp_path / f"bar{fmi}.fmu", fmi)
    names = ["wall.force_N", "workpiece.height_m"]
    res = simulate_fmu(path, stop_time=10.0e-6, output_interval=1.0e-6, output=names)
    assert len(res) == len(history) == 11
    for r, row in zip(res, history):
        assert r["time"] == pytest.approx(float(row["time_s"]), abs=1e-15)
        for n in names:
            assert r[n] == float(row[n]), (n, row["time_s"])
    assert res["wall.force_N"][-1] != 0.0 and res["workpiece.height_m"][-1] < 0.0324


def test_a_3d_fmu3_rolls_back_and_commands_its_tool(bar, rkforge_bin, tmp_path):
    """The wall commanded from outside: its stroke follows the velocity; a state saved,
    serialized and restored continues with the same bits."""
    text = bar.read_text().replace('motion = { kind = "fixed" }', 'motion = { kind = "external" }')
    scene = tmp_path / "bar_external.toml"
    scene.write_text(text)
    path = pack(rkforge_bin, scene, tmp_path / "bar_ext.fmu", "3")
    s = Slave3(path, {"wall.velocity_m_per_s": -2.0})
    s.step(1e-6)
    state = s.fmu.serializeFMUState(s.fmu.getFMUState())
    s.step(1e-6)
    first = s.get("wall.force_N", "wall.stroke_m", "workpiece.height_m")
    assert first[1] == pytest.approx(-4e-6, rel=1e-12)
    s.fmu.setFMUState(s.fmu.deserializeFMUState(state))
    s.t = 1e-6
    s.step(1e-6)
    assert s.get("wall.force_N", "wall.stroke_m", "workpiece.height_m") == first
    s.fmu.freeInstance()


def test_a_3d_fmu3_returns_early_where_its_intermediate_updates_see_the_event(bar, rkforge_bin,
                                                                           tmp_path):
    """One 5 us communication step of the bar: the intermediate updates see every solver
    step (time and wall force); with early return on contact the step returns after the
    first solver step (the bar lies on the wall), and with early return at a force level
    at the first solver step whose force magnitude reaches it, as the updates saw it."""
    path = pack(rkforge_bin, bar, tmp_path / "bar3.fmu", "3")
    seen, holder = [], {}

    def update(env, time, set_requested, get_allowed, finished, can_return, early, when):
        s = holder["s"]
        seen.append((time, *s.fmu.getFloat64([s.vr["time"], s.vr["wall.force_N"]])))

    holder["s"] = s = Slave3(path, intermediate_update=update)
    assert s.step(5e-6) == (False, 5e-6)
    assert len(seen) > 5 and seen[-1][0] == 5e-6
    assert all(t == u for t, u, _ in seen) and seen[-1][2] == s.get("wall.force_N")[0]
    s.fmu.freeInstance()

    touch = Slave3(path, {"wall.early_return.contact": True}, early_return=True)
    early, last = touch.step(5e-6)
    assert early and last == seen[0][0], (last, seen[0])
    early, end = touch.step(5e-6 - last)
    assert not early and end == pytest.approx(5e-6, rel=1e-12)
    touch.fmu.freeInstance()

    level = 0.5 * max(abs(f) for _, _, f in seen)
    expected = next(t for t, _, f in seen if abs(f) >= level)
    forced = Slave3(path, {"wall.early_return.force": True, "wall.early_return.force_level": level},
                    early_return=True)
    early, last = forced.step(5e-6)
    assert early and last == expected, (last, expected)
    assert abs(forced.get("wall.force_N")[0]) >= level
    forced.fmu.freeInstance()


@pytest.mark.parametrize("fmi", ["2", "3"])
def test_an_fmu_carries_its_stl_dies(rkforge_bin, tmp_path, fmi):
    """A 3D scene whose ram is an STL file (dies/ram.stl beside the scene, in mm): the FMU
    holds the file in resources/ where the scene names it, and pressed by fmpy it gives the
    history of `rkforge run` to the bit; a die file outside the scene's folder is refused by
    its key when packing."""
    import zipfile

    (tmp_path / "dies").mkdir()
    stl_box(tmp_path / "dies" / "ram.stl", [-2.0, -2.0, 32.4], [10.0, 10.0, 40.0])
    ram_plane = """point_m = [0.0, 0.0, 0.0324]
normal = [0.0, 0.0, -1.0]
"""
    scene = tmp_path / "upset_stl.toml"
    scene.write_text(upset_bar_3d(tmp_path).read_text().replace(
        ram_plane, 'shape = "stl"\nfile = "dies/ram.stl"\nunit = "mm"\n'))
    assert 'file = "dies/ram.stl"' in scene.read_text()
    out = tmp_path / "out"
    subprocess.run([rkforge_bin, "run", str(scene), "--out", str(out), "--quiet", "--no-frames"],
                   check=True, capture_output=True, text=True, timeout=300)
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    path = pack(rkforge_bin, scene, tmp_path / f"upset{fmi}.fmu", fmi)
    with zipfile.ZipFile(path) as z:
        assert z.read("resources/dies/ram.stl") == (tmp_path / "dies" / "ram.stl").read_bytes()
    assert validate_fmu(path) == []
    names = ["ram.force_z_N", "workpiece.height_m"]
    res = simulate_fmu(path, stop_time=10.0e-6, output_interval=1.0e-6, output=names)
    assert len(res) == len(rows) == 11
    for r, row in zip(res, rows):
        for n in names:
            assert r[n] == float(row[n]), (n, row["time_s"])
    assert res["ram.force_z_N"][-1] > 1e3, "the STL ram presses"
    # A die outside the scene's folder cannot sit in resources/ at the path the scene gives.
    outside = tmp_path / "sub"
    outside.mkdir()
    (outside / "upset.toml").write_text(scene.read_text().replace("dies/ram.stl", "../dies/ram.stl"))
    proc = subprocess.run([rkforge_bin, "fmu", str(outside / "upset.toml"), "--out", str(tmp_path / "x.fmu")],
                          capture_output=True, text=True)
    assert proc.returncode != 0 and "tools[1].file" in proc.stderr and ".." in proc.stderr, proc.stderr


@pytest.mark.parametrize("fmi", ["2", "3"])
def test_a_3d_forging_fmu_at_press_speed_gives_the_bits_of_rkforge_run(rkforge_bin, tmp_path, fmi):
    """The rectangular block of scenes/block_upsetting_3d.toml, mass-scaled at its press
    speed, 50 ms (1 mm of stroke, history rows every 10 ms): the FMU validates, the ram is an
    input and the mass scaling's target a parameter; simulated by fmpy with the target step
    changed to 10 us (`time.mass_scaling.target_dt_s`), its outputs at the communication
    points are the rows of `rkforge run --set time.mass_scaling.target_dt_s=1e-5`, bit for bit,
    and the scaling changed the run (other forces than at 20 us)."""
    scene = tmp_path / "block3d.toml"
    scene.write_text(scene_variant("block_upsetting_3d.toml", {"end_s = 1.0 ": "end_s = 0.05 "}))
    rows = {}
    for target in ("2e-5", "1e-5"):
        out = tmp_path / f"run{target}"
        subprocess.run([rkforge_bin, "run", str(scene), "--out", str(out), "--quiet", "--no-frames",
                        f"--set=time.mass_scaling.target_dt_s={target}"],
                       check=True, capture_output=True, text=True, timeout=300)
        with open(out / "history.csv") as f:
            rows[target] = list(csv.DictReader(f))
    path = pack(rkforge_bin, scene, tmp_path / f"block{fmi}.fmu", fmi)
    assert validate_fmu(path) == []
    by = {v.name: v for v in read_model_description(path).modelVariables}
    assert by["ram.velocity_m_per_s"].causality == "input"
    assert by["time.mass_scaling.target_dt_s"].causality == "parameter"
    names = ["ram.force_N", "anvil.force_N", "ram.stroke_m", "workpiece.height_m",
             "workpiece.x_max_m", "energy.kinetic_J"]
    res = simulate_fmu(path, stop_time=0.05, output_interval=0.01, output=names,
                       start_values={"time.mass_scaling.target_dt_s": 1e-5})
    assert len(res) == len(rows["1e-5"]) == 6
    for r, row in zip(res, rows["1e-5"]):
        for n in names:
            assert r[n] == float(row[n]), (n, row["time_s"])
    assert res["ram.stroke_m"][-1] == pytest.approx(1e-3, rel=1e-9)
    assert res["ram.force_N"][-1] < -5e4
    assert float(rows["2e-5"][-1]["ram.force_N"]) != res["ram.force_N"][-1]
