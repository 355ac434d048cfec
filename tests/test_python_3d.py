"""The Python package on a 3D scene (scenes/taylor_ofhc_3d.toml, coarsened): the scene's
kind and its register, fields with three coordinates and the hexahedra, a tool command, a
study of 3D cases, and bad input as Python exceptions; the 3D forging scenes
(scenes/block_upsetting_3d.toml, scenes/press_upsetting_3d.toml) at press speed. (The bit-for-bit equality with the
command line, stepping and restored states run on the 3D scene in test_python.py.)"""
import numpy as np
import pytest

import rkforge
from conftest import ROOT, scene_variant

COARSE = {"cells = [8, 4, 48]": "cells = [4, 2, 16]", "end_s = 100.0e-6": "end_s = 20.0e-6"}


def scene():
    return rkforge.Scene.from_toml(scene_variant("taylor_ofhc_3d.toml", COARSE), "ofhc3d.toml")


def test_a_3d_scene_names_its_kind_and_its_register():
    s = scene()
    assert s.kinematics == "3d" and s.tools == ["wall"]
    outputs = {o["name"]: o for o in s.outputs()}
    assert outputs["wall.force_z_N"]["kind"] == "per tool" and outputs["wall.force_z_N"]["unit"] == "N"
    assert outputs["workpiece.z_max_m"]["history"] and not outputs["workpiece.z_max_m"]["summary"]
    assert outputs["thermal.temperature_max_c"]["unit"] == "degC"
    assert outputs["points.temperature_c"]["kind"] == "per point"
    assert "workpiece.laps" not in outputs and "wall.contact_fraction" not in outputs
    assert rkforge.Scene.from_file(ROOT / "scenes" / "taylor_bar.toml").kinematics == "axisymmetric"


def test_fields_have_three_coordinates_and_the_cells():
    sim = rkforge.Simulation(scene())
    sim.run_to(10e-6)
    f = sim.fields()
    n = f["positions"].shape[0]
    # 3 x 3 + 2 x 5 particles per layer of the quarter O-grid, 17 layers.
    assert n == 19 * 17
    for key in ("positions", "displacement", "velocity"):
        assert f[key].shape == (n, 3) and np.isfinite(f[key]).all()
    cells = f["cells"]
    assert cells.shape == (12 * 16, 8) and cells.min() >= 0 and cells.max() < n
    for key in ("plastic_strain", "von_mises", "temperature"):
        assert f[key].shape == (cells.shape[0],)
    # The foot is flattened: the lowest particles have moved out from the axis, and the
    # bar moves down at most its impact speed.
    assert f["displacement"][:, 2].min() < -1e-4
    assert f["velocity"][:, 2].min() > -190.0 * 1.01
    assert f["plastic_strain"].max() > 0.5 and f["temperature"].max() > 50.0
    # The register's point fields are the cells' points, cell by cell.
    o = sim.outputs()
    eps = o["points.plastic_strain"].reshape(cells.shape[0], -1).mean(axis=1)
    assert np.array_equal(eps, f["plastic_strain"])
    assert o["workpiece.z_max_m"] == pytest.approx(f["positions"][:, 2].max(), rel=0, abs=0)


def test_a_study_of_3d_cases_gives_a_row_each():
    table = rkforge.study(scene(), {"workpiece.initial_velocity_m_per_s": [[0.0, 0.0, -150.0],
                                                                         [0.0, 0.0, -190.0]]},
                          progress=False)
    assert list(table["status"]) == ["ok", "ok"]
    heights = list(table["workpiece.height_m"])
    assert heights[0] > heights[1]


def test_bad_3d_input_is_a_python_error():
    s = scene()
    with pytest.raises(ValueError, match="integration `q8`"):
        rkforge.Simulation(s, integration="q8")
    with pytest.raises(rkforge.SceneError, match="workpiece.cells"):
        s.set("workpiece.cells", [3, 2, 16])
    sim = rkforge.Simulation(s)
    with pytest.raises(ValueError, match="`wall` is fixed"):
        sim.set_tool_velocity("wall", -1.0)
    with pytest.raises(ValueError, match="no tool named `anvil`"):
        sim.set_tool_velocity("anvil", -1.0)
    # A 3D run reports its laps as 2D's (none before it folds).
    assert sim.laps() == []
    other = rkforge.Simulation(rkforge.Scene.from_file(ROOT / "scenes" / "taylor_bar.toml"))
    with pytest.raises(rkforge.StateError, match="taylor_bar"):
        sim.restore_state(other.save_state())


#: The anvil's force against the ram's: the box's flat faces balance within 0.03 %; the
#: quarter cylinder's coarse O-grid (4, 2, 12 cells) puts 1.5 % more on the anvil (0.24 % on
#: 8, 4, 24 cells; 0.07 % in the axisymmetric scene at 1 mm).
@pytest.mark.parametrize("src, changes, size, balance", [
    ("block_upsetting_3d.toml", {"end_s = 1.0 ": "end_s = 0.05 "}, (0.030, 0.020, 0.040), 1e-3),
    ("press_upsetting_3d.toml", {"end_s = 1.5 ": "end_s = 0.05 "}, (0.020, 0.020, 0.060), 0.02),
])
def test_a_3d_forging_scene_presses_from_python(src, changes, size, balance):
    """50 ms of each 3D forging scene at its press speed (1 mm of stroke): the ram has moved
    v t, the top of the workpiece with it; the anvil carries the ram's force (quasi-static:
    the kinetic energy is 2e-4 of the internal); the symmetry planes hold the quarter at
    x = y = 0 (within 1e-3 of the 5 mm spacing) and the free faces bulge out; the volume of the metal stays within 1 % (elastic compression only); and commanding
    the ram twice as fast from Python doubles its stroke."""
    scene = rkforge.Scene.from_toml(scene_variant(src, changes), src)
    summary, history = rkforge.run(scene)
    assert summary["status"] == "ok"
    last = history.iloc[-1]
    assert last["ram.stroke_m"] == pytest.approx(0.020 * 0.05, rel=1e-9)
    assert last["workpiece.z_max_m"] == pytest.approx(size[2] - last["ram.stroke_m"], abs=1e-5)
    assert last["ram.force_N"] < -5e4, "the ram presses the metal past its yield"
    assert last["anvil.force_N"] == pytest.approx(-last["ram.force_N"], rel=balance)
    assert last["energy.kinetic_to_internal"] < 1e-3
    assert abs(last["workpiece.x_min_m"]) < 5e-6 and abs(last["workpiece.y_min_m"]) < 5e-6
    assert last["workpiece.x_max_m"] > size[0] and last["workpiece.y_max_m"] > size[1]
    assert abs(last["workpiece.integrated_volume_change_rel"]) < 0.01
    assert abs(last["workpiece.volume_change_rel"]) < 0.01
    sim = rkforge.Simulation(scene)
    sim.set_tool_velocity("ram", 0.040)
    sim.run_to(0.05)
    assert sim.tool_strokes()["ram"] == pytest.approx(2 * last["ram.stroke_m"], rel=1e-9)
    assert sim.tool_forces()["ram"] < last["ram.force_N"], "further, more force"
