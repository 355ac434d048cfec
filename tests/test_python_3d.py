"""The Python package on a 3D scene (scenes/taylor_ofhc_3d.toml, coarsened): the scene's
kind and its register, fields with three coordinates and the hexahedra, a tool command, a
study of 3D cases, and bad input as Python exceptions. (The bit-for-bit equality with the
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
