"""The press plants of examples/presses as FMI 2.0 Co-Simulation FMUs (`rkforge fmu --press
NAME`): fmpy validates each, and each driving the forging FMU of scenes/press_upsetting.toml
reproduces its Python example's force-stroke history (stepped in the same order: the forging
FMU first, then the press with the forging outputs at the end of the step)."""
import subprocess

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from crank import RAM_GAP, CrankPress
from driver import Slave, build_fmu, fmu_params, simulate, upsetting_scene
from hammer import Hammer
from hydraulic import HydraulicPress
from screw import ScrewPress

NX, NY = 6, 16
PRESSES = ["hydraulic", "crank", "hammer", "screw"]


@pytest.fixture(scope="module")
def presses(rkforge_bin, tmp_path_factory):
    out = tmp_path_factory.mktemp("press_fmus")
    paths = {}
    for p in PRESSES:
        paths[p] = str(out / f"{p}.fmu")
        subprocess.run([rkforge_bin, "fmu", "--press", p, "--out", paths[p]], check=True,
                       capture_output=True, text=True)
    return paths


@pytest.fixture(scope="module")
def forging(rkforge_bin, tmp_path_factory):
    out = tmp_path_factory.mktemp("press_forging")
    return {"scaled": build_fmu(upsetting_scene(), out / "s.fmu", rkforge_bin),
            "unscaled": build_fmu(upsetting_scene(mass_scaling=False), out / "u.fmu", rkforge_bin),
            "crank": build_fmu(upsetting_scene(RAM_GAP), out / "c.fmu", rkforge_bin)}


def coupled(press_fmu, forging_fmu, h, t_max, target_dt):
    """The press FMU driving the forging FMU until the press is finished or `t_max`: per
    step of `h`, the press's ram.velocity_m_per_s to the forging FMU, the forging step, its force,
    stroke, tool work and height to the press, the press step. Rows (t, v, force, stroke)."""
    f = Slave(forging_fmu, params=fmu_params(NX, NY, target_dt))
    p = Slave(press_fmu)
    rows, n = [], 0
    while p.get("finished")[0] == 0.0 and (n + 1) * h <= t_max * (1 + 1e-12):
        v = p.get("ram.velocity_m_per_s")[0]
        f.set("ram.velocity_m_per_s", v)
        f.step(h)
        force, stroke, work, height = f.get("ram.force_N", "ram.stroke_m", "energy.tool_work_J",
                                            "workpiece.height_m")
        for name, x in [("ram.force_N", force), ("ram.stroke_m", stroke), ("ram.tool_work_J", work),
                        ("workpiece.height_m", height)]:
            p.set(name, x)
        p.step(h)
        n += 1
        rows.append((n * h, v, -force, stroke))
    f.close()
    p.close()
    return np.array(rows)


def test_every_press_fmu_validates(presses):
    for name, path in presses.items():
        assert validate_fmu(path) == [], name


@pytest.mark.parametrize("name, plant, fmu, h, t_max, target_dt, tolerance", [
    ("hydraulic", HydraulicPress, "scaled", 2e-4, 1.6, 2e-5, 0.0),
    ("screw", ScrewPress, "scaled", 1e-4, 1.0, 2e-6, 0.0),
    ("hammer", Hammer, "unscaled", 1e-5, 1.0, None, 0.0),
    # The crank FMU's first step moves at s'(theta0) omega0 (it cannot know the step yet).
    ("crank", CrankPress, "crank", 2e-4, 10.0, 2e-5, 1e-4),
])
def test_press_fmu_reproduces_its_python_example(presses, forging, name, plant, fmu, h, t_max,
                                                 target_dt, tolerance):
    py = simulate(forging[fmu], plant(), h, t_max, NX, NY, target_dt=target_dt)
    fm = coupled(presses[name], forging[fmu], h, t_max, target_dt)
    assert len(fm) == len(py["t"]) - 1 > 100
    force, stroke = py["force"][1:], py["stroke"][1:]
    if tolerance == 0.0:
        assert np.array_equal(fm[:, 2], force) and np.array_equal(fm[:, 3], stroke)
        assert np.array_equal(fm[:, 1], py["v"][1:])
    else:
        assert np.max(np.abs(fm[:, 2] - force)) <= tolerance * np.max(np.abs(force))
        assert np.max(np.abs(fm[:, 3] - stroke)) <= tolerance * np.max(np.abs(stroke))


def test_bad_press_parameters_are_refused_by_name(presses):
    s = Slave(presses["crank"], init=False)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.setReal([s.vr["crank_radius"]], [0.6])
    s.fmu.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.fmu.exitInitializationMode()
    assert "`crank_radius` = 0.6 must be shorter than `rod_length` = 0.5" in s.last_error()
    s.fmu.freeInstance()
    s = Slave(presses["hydraulic"], init=False)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.setReal([s.vr["area"]], [-1.0])
    s.fmu.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.fmu.exitInitializationMode()
    assert "`area` = -1: must be positive and finite" in s.last_error()
    s.fmu.freeInstance()
    for value, words in [(2.5, "`substeps` = 2.5: must be a whole number from 1 to 1000000"),
                         (1e12, "`substeps` = 1000000000000: must be a whole number")]:
        s = Slave(presses["hydraulic"], init=False)
        s.fmu.setupExperiment(startTime=0.0)
        s.fmu.setReal([s.vr["substeps"]], [value])
        s.fmu.enterInitializationMode()
        with pytest.raises(FMICallException):
            s.fmu.exitInitializationMode()
        assert words in s.last_error()
        s.fmu.freeInstance()


def test_a_press_refuses_a_step_past_its_stop_time(presses):
    s = Slave(presses["hydraulic"], stop_time=1e-3)
    s.step(1e-3)
    with pytest.raises(FMICallException):
        s.step(1e-4)
    assert "would pass the stop time 1e-3 s" in s.last_error()
    s.fmu.freeInstance()
