"""`rkforge ssp SCENE --press NAME`: a press FMU and the scene's forging FMU connected in an
SSP 1.0 system. fmpy reads the system description against the SSP schema and simulates it
(its SSP runner exchanges the connections after every component has stepped, starting from
zero, so the system lags the Python examples' loop by about one communication step): the
force-stroke curve of each press follows its Python example (examples/presses) within what
that lag moves."""
import pathlib
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.ssp.simulation import simulate_ssp
from fmpy.validation import validate_fmu
from fmpy.ssp.ssd import Parameter, ParameterSet, read_ssd

from crank import RAM_GAP, CrankPress
from driver import build_fmu, simulate, upsetting_scene
from hammer import Hammer
from hydraulic import HydraulicPress
from screw import ScrewPress

NX, NY = 6, 16


def coarse(text, target_dt):
    """The scene at the grid of tests/test_presses.py, with the press's mass scaling."""
    text = text.replace("particles = [11, 31]", f"particles = [{NX}, {NY}]")
    if target_dt is not None:
        text = text.replace("mass_scaling = { target_dt_s = 20.0e-6 }",
                            f"mass_scaling = {{ target_dt_s = {target_dt!r} }}")
    return text


def system(rkforge_bin, tmp_path, name, text):
    scene = tmp_path / f"{name}.toml"
    scene.write_text(text)
    out = tmp_path / f"{name}.ssp"
    subprocess.run([rkforge_bin, "ssp", str(scene), "--press", name, "--out", str(out)],
                   check=True, capture_output=True, text=True)
    return str(out)


@pytest.mark.parametrize("name, plant, text, h, t_max, target_dt, tolerance", [
    ("hydraulic", HydraulicPress, upsetting_scene(), 2e-4, 1.6, 2e-5, 0.005),
    ("screw", ScrewPress, upsetting_scene(), 1e-4, 1.0, 2e-6, 0.005),
])
def test_the_ssp_gives_the_force_stroke_curve_of_the_python_example(
        rkforge_bin, tmp_path, name, plant, text, h, t_max, target_dt, tolerance):
    ssp = system(rkforge_bin, tmp_path, name, coarse(text, target_dt))
    ssd = read_ssd(ssp, validate=True)
    assert {c.name for c in ssd.system.elements} == {"press", "forging"}
    py = simulate(build_fmu(text, tmp_path / "f.fmu", rkforge_bin), plant(), h, t_max, NX, NY,
                  target_dt=target_dt)
    r = simulate_ssp(ssp, stop_time=py["t"][-1] - h / 2, step_size=h)
    assert len(r) == len(py["t"]) - 1
    stroke, force = r["press.ram.stroke_m"], -r["press.ram.force_N"]
    # The pressing part of the stroke, up to its deepest point (the crank turns back past
    # bottom dead centre), the Python curve interpolated at the system's strokes.
    deepest = int(np.argmax(stroke))
    s, f = stroke[:deepest + 1], force[:deepest + 1]
    pk = int(np.argmax(py["stroke"]))
    keep = s <= py["stroke"][pk]
    expected = np.interp(s[keep], py["stroke"][:pk + 1], py["force"][:pk + 1])
    error = np.max(np.abs(f[keep] - expected)) / py["force"].max()
    print(f"{name}: force-stroke within {error:.2e} of the peak force")
    assert error <= tolerance
    assert stroke[deepest] == pytest.approx(py["stroke"][pk], rel=0.01)


def test_the_crank_ssp_follows_the_python_example_within_a_step(rkforge_bin, tmp_path):
    """Near bottom dead centre the crank's stroke hardly moves while the force climbs, so a
    force-stroke comparison there measures the slope, not the coupling: the system's stroke
    stays within one communication step of ram travel of the Python example's at every time,
    and its peak force within 1 % of the example's."""
    h = 2e-4
    text = upsetting_scene(RAM_GAP)
    ssp = system(rkforge_bin, tmp_path, "crank", coarse(text, 2e-5))
    py = simulate(build_fmu(text, tmp_path / "f.fmu", rkforge_bin), CrankPress(), h, 10.0, NX, NY,
                  target_dt=2e-5)
    r = simulate_ssp(ssp, stop_time=py["t"][-1] - h / 2, step_size=h)
    assert len(r) == len(py["t"]) - 1
    travel = np.max(np.abs(py["v"])) * h
    lag = np.max(np.abs(r["press.ram.stroke_m"] - py["stroke"][1:]))
    peak = -r["press.ram.force_N"].min()
    print(f"crank: stroke within {lag / travel:.3f} steps of travel, peak force "
          f"{peak / py['force'].max() - 1:+.2e}")
    assert lag <= travel
    assert peak == pytest.approx(py["force"].max(), rel=0.01)


def test_the_hammer_ssp_forges_the_python_examples_blows(rkforge_bin, tmp_path):
    """Hammer blows are steep (3 ms): the system's blows end at the billet heights of the
    Python example's within 1 % of the height change, with as many blows."""
    text = upsetting_scene(mass_scaling=False)
    ssp = system(rkforge_bin, tmp_path, "hammer", coarse(text, None))
    hammer = Hammer()
    py = simulate(build_fmu(text, tmp_path / "f.fmu", rkforge_bin), hammer, 1e-5, 1.0, NX, NY)
    r = simulate_ssp(ssp, stop_time=py["t"][-1] + 2e-3, step_size=1e-5)
    assert r["press.finished"][-1] == 1.0
    assert r["press.blow"][-1] == len(hammer.blows)
    drop = 0.060 - py["height"][-1]
    assert abs(r["press.workpiece.height_m"][-1] - py["height"][-1]) <= 0.01 * drop


def test_the_fmu_manipulation_toolbox_builds_and_runs_a_container_from_the_ssp(rkforge_bin,
                                                                               tmp_path):
    """A second SSP tool: the FMU Manipulation Toolbox's `fmucontainer` makes one FMU of the
    hydraulic press system from the SSP; fmpy validates and simulates it, and its
    force-stroke curve follows the Python example as fmpy's SSP runner's does."""
    h = 2e-4
    text = upsetting_scene()
    ssp = system(rkforge_bin, tmp_path, "hydraulic", coarse(text, 2e-5))
    with zipfile.ZipFile(ssp) as z:
        for name in z.namelist():
            if name.startswith("resources/") and name.endswith(".fmu"):
                (tmp_path / pathlib.Path(name).name).write_bytes(z.read(name))
    made = subprocess.run([sys.executable, "-m", "fmu_manipulation_toolbox.cli.fmucontainer",
                           "-container", f"{pathlib.Path(ssp).name}:{h}",
                           "-fmu-directory", str(tmp_path)],
                          cwd=tmp_path, capture_output=True, text=True)
    container = tmp_path / "hydraulic.fmu"
    assert made.returncode == 0 and container.is_file(), made.stdout + made.stderr
    assert validate_fmu(str(container)) == []
    py = simulate(build_fmu(text, tmp_path / "f.fmu", rkforge_bin), HydraulicPress(), h, 1.6,
                  NX, NY, target_dt=2e-5)
    r = simulate_fmu(str(container), stop_time=1.6, step_size=h, output_interval=h)
    stroke, force = r["forging.ram.stroke_m"], -r["forging.ram.force_N"]
    deepest = int(np.argmax(stroke))
    pk = int(np.argmax(py["stroke"]))
    s, f = stroke[:deepest + 1], force[:deepest + 1]
    keep = s <= py["stroke"][pk]
    expected = np.interp(s[keep], py["stroke"][:pk + 1], py["force"][:pk + 1])
    error = np.max(np.abs(f[keep] - expected)) / py["force"].max()
    print(f"container: force-stroke within {error:.2e} of the peak force")
    assert error <= 0.005


def test_the_parameters_are_bound_in_the_system(rkforge_bin, tmp_path):
    """Every parameter of both FMUs is bound inline in the SSD at its start value (the
    press's defaults, the scene's keys with the scene's values). fmpy's runner takes a
    parameter set rather than applying bindings itself: the bindings given to it, with the
    relief valve set to 10 MPa, make the hydraulic press stall at half its tonnage."""
    text = coarse(upsetting_scene(), 2e-5)
    ssp = system(rkforge_bin, tmp_path, "hydraulic", text)
    ssd = read_ssd(ssp, validate=True)
    bound = {}
    for c in ssd.system.elements:
        for b in c.parameterBindings:
            for values in b.parameterValues:
                for p in values.parameters:
                    bound[f"{c.name}.{p.name}"] = p
    assert bound["press.relief_pressure"].value == "20000000"
    assert bound["press.area"].value == "0.05"
    assert bound["forging.workpiece.particles[0]"].value == str(NX)
    assert bound["forging.discretization.integration"].value == "q2"
    relief = ParameterSet(name="relief")
    relief.parameters = [Parameter(name=name, type=p.type, value=p.value)
                         for name, p in bound.items() if name.startswith("press.")]
    for p in relief.parameters:
        if p.name == "press.relief_pressure":
            p.value = "10.0e6"
    r = simulate_ssp(ssp, stop_time=1.6, step_size=2e-4, parameter_set=relief)
    assert -r["press.ram.force_N"][-1] == pytest.approx(10.0e6 * 0.05, rel=0.01)
