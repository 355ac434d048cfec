"""The rkforge FMU through fmpy: validation, simulation against `rkforge run`, process-control
loops that drive the press, rollback and serialization, bad inputs, and threads."""
import csv
import math
import shutil
import subprocess
import sys
import threading

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from conftest import ROOT
from driver import Slave

SCENES = ["taylor_bar", "block_forging", "wheel_forging", "closed_die_hub", "hot_upsetting"]


@pytest.fixture(scope="module")
def fmus(rkforge_bin, tmp_path_factory):
    out = tmp_path_factory.mktemp("fmus")
    paths = {}
    for s in SCENES:
        p = out / f"{s}.fmu"
        subprocess.run([rkforge_bin, "fmu", str(ROOT / "scenes" / f"{s}.toml"), "--out", str(p)],
                       check=True, capture_output=True, text=True)
        paths[s] = str(p)
    return paths


@pytest.fixture(scope="module")
def adaptive_fmus(rkforge_bin, tmp_path_factory):
    """The block and the wheel with their fixed step left out (`dt_safety` times the stable
    step): the coarse grids of the control loops run at their own stable step. A key the
    scene leaves out is no FMU parameter: the scene decides what is modelled."""
    out = tmp_path_factory.mktemp("adaptive")
    paths = {}
    for s in ["block_forging", "wheel_forging"]:
        text = (ROOT / "scenes" / f"{s}.toml").read_text()
        scene = out / f"{s}.toml"
        scene.write_text("\n".join(l for l in text.splitlines() if not l.startswith("dt_s =")))
        paths[s] = str(out / f"{s}.fmu")
        subprocess.run([rkforge_bin, "fmu", str(scene), "--out", paths[s]], check=True,
                       capture_output=True, text=True)
    return paths


def grid(nx, ny):
    """The FMU parameters of the particle grid: the scene key `workpiece.particles`."""
    return {"workpiece.particles[0]": nx, "workpiece.particles[1]": ny}


COARSE = grid(11, 11)


def test_every_shipped_scene_validates(fmus):
    for s, p in fmus.items():
        assert validate_fmu(p) == [], s
        md = read_model_description(p)
        names = {v.name for v in md.modelVariables}
        tools = {"taylor_bar": ["wall"], "block_forging": ["top", "bottom"], "wheel_forging": ["die", "punch"],
                 "closed_die_hub": ["die", "punch"], "hot_upsetting": ["anvil", "ram"]}[s]
        for t in tools:
            assert f"{t}.force_N" in names and f"{t}.stroke_m" in names and f"{t}.contact_fraction" in names
        if s == "closed_die_hub":
            assert {"die.flange_corner.filled", "punch.hub_top_corner.filled", "punch.land_end.filled"} <= names
        assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
        assert md.coSimulation.canHandleVariableCommunicationStepSize


def test_input_table_drives_the_block_like_rkforge_run(fmus, rkforge_bin, tmp_path):
    """Same scene, same inputs, communication step a multiple of the solver step: same bits."""
    subprocess.run([rkforge_bin, "run", str(ROOT / "scenes/block_forging.toml"), "--out", str(tmp_path),
                    "--quiet", "--no-frames"], check=True)
    with open(tmp_path / "history.csv") as f:
        rows = list(csv.DictReader(f))
    inp = np.array([(0.0, 10.0, 10.0), (0.015, 10.0, 10.0)],
                   dtype=[("time", float), ("top.velocity_m_per_s", float), ("bottom.velocity_m_per_s", float)])
    res = simulate_fmu(fmus["block_forging"], stop_time=0.015, output_interval=0.15e-3, input=inp,
                       output=["top.force_N", "top.stroke_m", "bottom.force_N", "workpiece.width_m"])
    assert len(res) == len(rows)
    for r, row in zip(res, rows):
        assert r["top.force_N"] == float(row["top.force_N"])
        assert r["bottom.force_N"] == float(row["bottom.force_N"])
        assert r["workpiece.width_m"] == float(row["workpiece.width_m"])
        assert r["top.stroke_m"] == pytest.approx(10.0 * r["time"], rel=1e-9, abs=1e-15)


def test_the_wall_takes_the_bars_momentum_and_the_mean_force_is_its_impulse_over_each_step(fmus):
    """The Taylor bar's FMU stepped at 0.5 us (100 solver steps): the wall's force averaged over
    each communication step times the step sums to the wall's impulse, and the impulse at 80 us
    is the copper bar's momentum m v0 (rho pi r^2 L v0 = 2.114 N s, the whole ring) and the
    little it rebounds with: an elastic rebound of the order sigma_y / (rho c0), some 12 m/s,
    bounds it by 5 %. The samples of the force miss the first contact's spike; the mean over
    the first step carries it."""
    h = 0.5e-6
    res = simulate_fmu(fmus["taylor_bar"], stop_time=80e-6, output_interval=h,
                       output=["wall.force_N", "wall.force_mean_N", "wall.impulse_N_s", "wall.work_J"])
    impulse = res["wall.impulse_N_s"]
    steps = np.diff(res["time"])
    assert np.allclose(steps, h, rtol=1e-9)
    summed = np.cumsum(res["wall.force_mean_N"][1:] * steps)
    assert np.allclose(summed, impulse[1:], rtol=1e-9, atol=1e-12)
    momentum = 8930.0 * math.pi * 3.2e-3 ** 2 * 32.4e-3 * 227.0
    assert 1.0 < impulse[-1] / momentum < 1.05, (impulse[-1], momentum)
    assert np.all(res["wall.work_J"] == 0.0)
    # The first 0.5 us: 199 kN on average, above every sampled force (127 kN at its end).
    assert res["wall.force_mean_N"][1] > 1.2 * res["wall.force_N"].max()


def test_stroke_follows_a_changing_velocity_input(adaptive_fmus):
    """Strokes are the integrals of piecewise-constant velocity inputs."""
    s = Slave(adaptive_fmus["block_forging"], params=COARSE)
    stroke = 0.0
    for k in range(40):
        v = 10.0 * math.sin(0.2 * k) + 2.0
        s.set("top.velocity_m_per_s", v)
        s.step(20e-6)
        stroke += v * 20e-6
        assert s.get("top.stroke_m")[0] == pytest.approx(stroke, rel=1e-9, abs=1e-12)
        assert s.get("top.velocity_m_per_s")[0] == v
    s.close()


def force_limited_press(path, set_point, t_end, h):
    """PI control of the punch velocity holding the punch force at a set point: mostly
    proportional (the plant integrates: force follows stroke), a small integral term, a
    first-order filter on the measured force, and a velocity range that lets the press back
    off (a stopped punch keeps its load in a plastic workpiece)."""
    s = Slave(path, params=grid(15, 15))
    kp, ki, v_min, v_max, alpha = 15.0, 500.0, -5.0, 10.0, 0.5
    integral, filtered, history = 0.0, None, []
    while s.t < t_end - 1e-12:
        force = -s.get("punch.force_N")[0]  # the force resisting the stroke
        filtered = force if filtered is None else alpha * force + (1 - alpha) * filtered
        e = (set_point - filtered) / set_point
        integral += e * h
        v = kp * e + ki * integral
        if not v_min <= v <= v_max:
            integral -= e * h  # anti-windup
            v = min(max(v, v_min), v_max)
        s.set("punch.velocity_m_per_s", v)
        s.step(h)
        history.append((s.t, -s.get("punch.force_N")[0], v, s.get("punch.stroke_m")[0]))
    s.close()
    return history


def test_force_limited_press_settles_within_5_percent(adaptive_fmus):
    set_point = 2.0e6
    hist = force_limited_press(adaptive_fmus["wheel_forging"], set_point, 3.0e-3, 10e-6)
    settled = [f for t, f, v, s in hist if t > 2.0e-3]
    assert settled and all(abs(f - set_point) < 0.05 * set_point for f in settled), \
        (min(settled), max(settled))
    assert max(f for t, f, v, s in hist) < 1.2 * set_point, "no large overshoot"
    assert hist[-1][3] > 1e-3, "the punch advanced"


def test_hydraulic_press_slows_with_load(adaptive_fmus):
    """A hydraulic press whose speed falls with load, v = v_max (1 - F / F_max), on both tools
    of the block forging. The valve is a first-order lag (0.5 ms): a press cannot jump its
    speed, and an instant jump of dv changes the contact stress elastically by rho c dv
    (266 MPa for 6.5 m/s in copper), which would make the loop chatter."""
    s = Slave(adaptive_fmus["block_forging"], params=COARSE)
    v_max, f_max, h, tau = 10.0, 0.3e9, 20e-6, 0.5e-3
    v, stroke, speeds = v_max, 0.0, []
    for _ in range(750):
        f = -s.get("top.force_N")[0]
        v += (v_max * max(0.0, 1.0 - f / f_max) - v) * h / tau
        s.set("top.velocity_m_per_s", v)
        s.set("bottom.velocity_m_per_s", v)
        s.step(h)
        stroke += v * h
        speeds.append(v)
        assert s.get("top.stroke_m")[0] == pytest.approx(stroke, rel=1e-9, abs=1e-12)
    f = -s.get("top.force_N")[0]
    target = v_max * max(0.0, 1.0 - f / f_max)
    assert abs(v - target) < 0.05 * v_max, "the speed follows the load law"
    assert v < 0.2 * v_max and f > 0.9 * f_max, (v, f)
    windows = [sum(speeds[k:k + 100]) / 100 for k in range(50, 750, 100)]
    assert all(b < a for a, b in zip(windows, windows[1:])), ("the press keeps slowing", windows)
    assert s.get("bottom.force_N")[0] == pytest.approx(s.get("top.force_N")[0], rel=0.02)
    s.close()


def test_rollback_and_serialization_continue_identically(fmus):
    a = Slave(fmus["taylor_bar"], params=grid(7, 15))
    out = ["wall.force_N", "workpiece.radius_m", "workpiece.height_m", "energy.plastic_J"]
    h = 2e-6
    for _ in range(3):
        a.step(h)
    state = a.fmu.getFMUstate()
    t_saved = a.t
    a.step(h)
    a.step(h)
    first = a.get(*out)
    a.fmu.setFMUstate(state)
    a.t = t_saved
    a.step(h)
    a.step(h)
    assert a.get(*out) == first
    a.fmu.setFMUstate(state)
    a.t = t_saved
    blob = a.fmu.serializeFMUstate(state)
    a.fmu.freeFMUstate(state)
    b = Slave(fmus["taylor_bar"], name="fresh", params=grid(7, 15))
    restored = b.fmu.deSerializeFMUstate(blob)
    b.fmu.setFMUstate(restored)
    b.fmu.freeFMUstate(restored)
    b.t = t_saved
    for s in (a, b):
        s.step(h)
        s.step(h)
    assert a.get(*out) == b.get(*out) == first
    a.close()
    b.close()


def raises(slave, call, *words):
    with pytest.raises(FMICallException):
        call()
    for w in words:
        assert w in slave.last_error(), (w, slave.messages[-3:])


def test_bad_inputs_are_refused_with_a_message_and_the_instance_lives_on(adaptive_fmus):
    s = Slave(adaptive_fmus["block_forging"], params=COARSE)
    fmu, vr = s.fmu, s.vr
    raises(s, lambda: s.set("top.velocity_m_per_s", float("nan")), "top.velocity_m_per_s", "not finite")
    raises(s, lambda: s.set("top.velocity_m_per_s", float("inf")), "not finite")
    raises(s, lambda: fmu.doStep(0.0, 0.0), "must be positive")
    raises(s, lambda: fmu.doStep(0.0, -1e-6), "must be positive")
    raises(s, lambda: fmu.doStep(1.0, 1e-6), "does not match")
    raises(s, lambda: fmu.getReal([9999]), "unknown value reference 9999")
    raises(s, lambda: fmu.setInteger([vr["workpiece.particles[0]"]], [31]), "workpiece.particles[0]",
           "cannot be set")
    raises(s, lambda: fmu.setReal([vr["top.force_N"]], [1.0]), "output")
    raises(s, lambda: fmu.enterInitializationMode(), "not allowed")
    raises(s, lambda: fmu.fmi2GetReal(fmu.component, None, 1, None), "null pointer")
    raises(s, lambda: fmu.fmi2SetReal(fmu.component, None, 2, None), "null pointer")
    # Still usable: a normal step after all of the above.
    s.set("top.velocity_m_per_s", 10.0)
    s.step(20e-6)
    assert s.get("top.stroke_m")[0] == pytest.approx(10.0 * 20e-6)
    s.close()


def test_a_step_past_the_stop_time_is_refused_and_logged_with_debug_logging_off(adaptive_fmus):
    """FMI 2.0, 4.2.2: with a stop time set up, computing past it is an error. The error is
    logged although the host switched debug logging off (fmpy's default), so that a failed
    call names what failed."""
    s = Slave(adaptive_fmus["block_forging"], params=COARSE, stop_time=50e-6, logging_on=False)
    s.set("top.velocity_m_per_s", 10.0)
    s.step(30e-6)
    raises(s, lambda: s.fmu.doStep(30e-6, 30e-6), "would pass the stop time 5e-5 s")
    assert s.messages[-1][0] == 3  # fmi2Error
    # The instance lives on: up to the stop time exactly, within an importer's rounding.
    s.step(20e-6 * (1 + 1e-12))
    assert s.get("top.stroke_m")[0] == pytest.approx(10.0 * 50e-6)
    raises(s, lambda: s.fmu.doStep(s.t, 1e-9), "would pass the stop time")
    # Debug messages stay off: the refusals are the only messages.
    assert [m[0] for m in s.messages] == [3, 3]
    s.close()
    with pytest.raises(FMICallException):
        Slave(adaptive_fmus["block_forging"], params=COARSE, stop_time=-1.0)


def test_a_tools_direction_is_set_component_by_component_and_checked_whole(adaptive_fmus):
    """A unit vector cannot be turned into another one component at a time: the components
    are taken as set, and the direction is checked whole when the simulation is built."""
    s = Slave(adaptive_fmus["block_forging"], params=COARSE, init=False)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.setReal([s.vr["tools.top.axis[0]"], s.vr["tools.top.axis[1]"]], [0.6, -0.8])
    s.fmu.enterInitializationMode()
    s.fmu.exitInitializationMode()
    s.set("top.velocity_m_per_s", 10.0)
    s.step(1e-5)
    assert s.get("top.stroke_m")[0] == pytest.approx(1e-4)
    s.close()
    s = Slave(adaptive_fmus["block_forging"], params=COARSE, init=False)
    s.fmu.setupExperiment(startTime=0.0)
    s.fmu.setReal([s.vr["tools.top.axis[0]"]], [1.0])
    s.fmu.enterInitializationMode()
    raises(s, lambda: s.fmu.exitInitializationMode(), "fmi2ExitInitializationMode", "axis")
    s.fmu.freeInstance()


def test_parameters_out_of_range_and_wrong_state_calls(fmus):
    s = Slave(fmus["taylor_bar"], init=False)
    raises(s, lambda: s.fmu.doStep(0.0, 1e-6), "not allowed")
    raises(s, lambda: s.fmu.setInteger([s.vr["workpiece.particles[0]"]], [1]), "workpiece.particles[0]",
           "at least 2 particles")
    raises(s, lambda: s.fmu.setString([s.vr["discretization.integration"]], ["q3"]),
           "discretization.integration", "q4")
    raises(s, lambda: s.fmu.setReal([s.vr["time.dt_safety"]], [1.5]), "time.dt_safety",
           "must lie in (0, 1]")
    raises(s, lambda: s.fmu.setReal([s.vr["tools.wall.friction"]], [-0.1]), "tools.wall.friction",
           "zero or positive")
    raises(s, lambda: s.fmu.setReal([s.vr["workpiece.particles[0]"]], [11.0]),
           "workpiece.particles[0]", "not a Real variable")
    s.fmu.freeInstance()


def test_missing_or_corrupt_resources_fail_cleanly(fmus, tmp_path):
    base = extract(fmus["taylor_bar"])
    missing = tmp_path / "missing"
    shutil.copytree(base, missing)
    (missing / "resources" / "scene.toml").unlink()
    with pytest.raises(Exception):
        Slave(fmus["taylor_bar"], unzip=str(missing))
    corrupt = tmp_path / "corrupt"
    shutil.copytree(base, corrupt)
    (corrupt / "resources" / "scene.toml").write_text("name = \n")
    with pytest.raises(Exception):
        Slave(fmus["taylor_bar"], unzip=str(corrupt))


def run_block(path, name, out):
    s = Slave(path, name=name, params=COARSE)
    for _ in range(30):
        s.step(50e-6)
    out[name] = s.get("top.force_N", "workpiece.width_m", "energy.plastic_J")
    s.close()


def test_two_instances_on_two_threads_match_sequential_runs(adaptive_fmus):
    seq = {}
    run_block(adaptive_fmus["block_forging"], "a", seq)
    run_block(adaptive_fmus["block_forging"], "b", seq)
    par = {}
    threads = [threading.Thread(target=run_block, args=(adaptive_fmus["block_forging"], n, par)) for n in "ab"]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert par["a"] == par["b"] == seq["a"] == seq["b"]


def test_a_velocity_that_would_pass_particles_in_one_step_is_refused_naming_the_tool(adaptive_fmus):
    # 1e300 m/s used to take the top tool through the block with a force of 0.
    s = Slave(adaptive_fmus["block_forging"], params=COARSE)
    s.set("top.velocity_m_per_s", 1e300)
    raises(s, lambda: s.step(20e-6), "tool `top`", "1.0000e300 m/s", "commanded")
    s.close()


def test_die_fill_and_contact_outputs_match_rkforge_run(fmus, rkforge_bin, tmp_path):
    """The wheel's fill points and contact fractions as FMU outputs: the same bits as the
    history of `rkforge run` at the same grid and times, first 0 (nothing touches, nothing
    filled), then a growing contact."""
    grid = ["--set", "workpiece.particles=[11,11]", "--set", "time.end_s=1.0e-3"]
    subprocess.run([rkforge_bin, "run", str(ROOT / "scenes/wheel_forging.toml"), "--out", str(tmp_path),
                    "--quiet", "--no-frames", *grid], check=True)
    with open(tmp_path / "history.csv") as f:
        rows = list(csv.DictReader(f))
    names = ["die.contact_fraction", "punch.contact_fraction", "die.hub_corner.filled",
             "die.rim_corner.filled", "punch.hub_corner.filled", "punch.rim_corner.filled"]
    s = Slave(fmus["wheel_forging"], params=COARSE)
    assert s.get(*names) == [0.0] * len(names)
    h = float(rows[1]["time_s"])
    for row in rows[1:]:
        s.step(h)
        assert s.get(*names) == [float(row[n]) for n in names], row["time_s"]
    assert 0.0 < s.get("punch.contact_fraction")[0] < 1.0
    s.close()


def test_every_output_is_the_history_column_of_its_name(fmus, rkforge_bin, tmp_path):
    """The FMU's outputs come from the register of outputs: each that `history.csv` has is its
    column of the same name and unit, the same bits at every sample of the coarse block, among them
    the mean contact pressure, which on the flat dies is the axial force over the contact
    area (`contact_length_m` times the depth, 1 m)."""
    grid = ["--set", "workpiece.particles=[11,11]", "--set", "time.end_s=4.0e-3"]
    subprocess.run([rkforge_bin, "run", str(ROOT / "scenes/block_forging.toml"), "--out", str(tmp_path),
                    "--quiet", "--no-frames", *grid], check=True)
    with open(tmp_path / "history.csv") as f:
        rows = list(csv.DictReader(f))
    md = read_model_description(fmus["block_forging"])
    outputs = {v.name: v.unit for v in md.modelVariables if v.causality == "output"}
    assert outputs["top.pressure_mean_Pa"] == "Pa" and outputs["top.force_N"] == "N"
    assert outputs["energy.kinetic_J"] == "J" and outputs["workpiece.width_m"] == "m"
    # The register keeps a few out of the history (a tool's peak force and contact length,
    # the initial energy, the interface's and the quasi-static largest: summary figures).
    names = sorted(n for n in outputs if n in rows[0])
    assert len(names) >= len(outputs) - 7 and "top.pressure_mean_Pa" in names
    s = Slave(fmus["block_forging"], params=COARSE)
    for before, row in zip(rows, rows[1:]):
        s.step(float(row["time_s"]) - float(before["time_s"]))
        assert s.get(*names) == [float(row[n]) for n in names], row["time_s"]
    p, f, length = s.get("top.pressure_mean_Pa", "top.force_N", "top.contact_length_m")
    assert p > 0.0 and abs(p * length * 1.0 + f) <= 1e-9 * abs(f), (p, f, length)
    s.close()


def parameters(md):
    """The parameters of a model description: {name: (type, start)}."""
    return {v.name: (v.type, v.start) for v in md.modelVariables if v.causality == "parameter"}


def test_every_parameter_is_a_scene_key_settable_to_its_start(fmus):
    """The FMU's parameters are the scene's own dotted keys (as `--set` takes them), every
    number and enumeration of the scene; fmpy sets each to its start value, the instance
    initialises, and reads back what was set."""
    for scene, path in fmus.items():
        md = read_model_description(path)
        params = parameters(md)
        assert {"time.end_s", "workpiece.particles[0]", "workpiece.particles[1]",
                "discretization.integration", "material.youngs_modulus_pa"} <= set(params), scene
        assert params["discretization.integration"][0] == "String"
        assert params["workpiece.particles[0]"][0] == "Integer"
        s = Slave(path, init=False)
        s.fmu.setupExperiment(startTime=0.0)
        for name, (kind, start) in params.items():
            vr = [s.vr[name]]
            {"Real": lambda: s.fmu.setReal(vr, [float(start)]),
             "Integer": lambda: s.fmu.setInteger(vr, [int(start)]),
             "String": lambda: s.fmu.setString(vr, [start])}[kind]()
        for name, (kind, start) in params.items():
            vr = [s.vr[name]]
            got = {"Real": lambda: s.fmu.getReal(vr)[0], "Integer": lambda: s.fmu.getInteger(vr)[0],
                   "String": lambda: s.fmu.getString(vr)[0].decode()}[kind]()
            assert str(got) == start or float(got) == float(start), (scene, name, got, start)
        s.fmu.enterInitializationMode()
        s.fmu.exitInitializationMode()
        s.close()
    hub = parameters(read_model_description(fmus["closed_die_hub"]))
    # A shear-factor tool's factor, under the law's own key.
    assert hub["tools.punch.friction.m"] == ("Real", "0.1") and "tools.punch.friction" not in hub


def test_a_shear_factor_set_through_the_fmu_gives_the_bits_of_the_scene_file(rkforge_bin, tmp_path):
    """closed_die_hub (shear factor m = 0.1 on both tools): m = 0.3 on the punch set through
    the FMU and m = 0.3 written in the scene give the same outputs, bit for bit."""
    text = (ROOT / "scenes/closed_die_hub.toml").read_text()
    lines = text.splitlines()
    punch = lines.index('name = "punch"')
    at = next(i for i in range(punch, len(lines)) if lines[i].startswith("friction ="))
    lines[at] = 'friction = { model = "shear", m = 0.3 }'
    paths = {}
    for name, t in [("shipped", text), ("written", "\n".join(lines))]:
        (tmp_path / f"{name}.toml").write_text(t)
        paths[name] = str(tmp_path / f"{name}.fmu")
        subprocess.run([rkforge_bin, "fmu", str(tmp_path / f"{name}.toml"), "--out", paths[name]],
                       check=True, capture_output=True)
    outputs = ["punch.force_N", "punch.stroke_m", "die.force_N", "workpiece.height_m", "energy.plastic_J"]
    coarse = {**grid(9, 13), "time.end_s": 0.02}
    set_through_fmu = simulate_fmu(paths["shipped"], stop_time=0.02, output_interval=2.0e-3,
                                   start_values={**coarse, "tools.punch.friction.m": 0.3},
                                   output=outputs)
    written = simulate_fmu(paths["written"], stop_time=0.02, output_interval=2.0e-3,
                           start_values=coarse, output=outputs)
    shipped = simulate_fmu(paths["shipped"], stop_time=0.02, output_interval=2.0e-3,
                           start_values=coarse, output=outputs)
    assert set_through_fmu.tobytes() == written.tobytes()
    # And it is a different run from the shipped m = 0.1 once the punch presses.
    assert set_through_fmu.tobytes() != shipped.tobytes()


def test_a_hot_forging_fmu_reports_temperatures_and_heat(fmus):
    """The hot upsetting's FMU: temperatures and heat flows are outputs (degC, J, W), the
    initial billet temperature and the dies' temperatures and transfer coefficients are
    parameters; set through fmpy, they start the billet where set and chill it at the dies."""
    path = fmus["hot_upsetting"]
    md = read_model_description(path)
    variables = {v.name: v for v in md.modelVariables}
    for name, unit in [("thermal.temperature_min_c", "degC"), ("thermal.temperature_max_c", "degC"),
                       ("thermal.plastic_heat_J", "J"), ("thermal.heat_to_tools_J", "J"),
                       ("thermal.ram.heat_flow_W", "W"), ("thermal.anvil.heat_flow_W", "W")]:
        assert variables[name].causality == "output" and variables[name].unit == unit, name
    for name, unit in [("thermal.initial_temperature_c", "degC"),
                       ("tools.ram.temperature_c", "degC"),
                       ("tools.ram.heat_transfer_w_per_m2_k", "W/(m2.K)"),
                       ("thermal.conductivity_w_per_m_k", "W/(m.K)"),
                       ("thermal.specific_heat_j_per_kg_k", "J/(kg.K)")]:
        assert variables[name].causality == "parameter" and variables[name].unit == unit, name
    res = simulate_fmu(path, stop_time=0.05, output_interval=0.01,
                       start_values={"workpiece.particles[0]": 5, "workpiece.particles[1]": 13,
                                     "thermal.initial_temperature_c": 1100.0,
                                     "tools.ram.temperature_c": 300.0,
                                     "tools.anvil.temperature_c": 300.0},
                       output=["thermal.temperature_min_c", "thermal.temperature_max_c",
                               "thermal.heat_to_tools_J", "thermal.ram.heat_flow_W", "thermal.anvil.heat_flow_W"])
    assert res["thermal.temperature_max_c"][0] == 1100.0
    # The anvil chills the billet's foot from the start; the ram's face once it arrives.
    assert res["thermal.temperature_min_c"][-1] < 1090.0
    assert res["thermal.anvil.heat_flow_W"][-1] > 0.0 and res["thermal.heat_to_tools_J"][-1] > 0.0



def test_a_grid_beyond_the_hosts_memory_is_refused_and_the_host_lives_on(adaptive_fmus):
    """A 2000 x 2000 block under a 3 GB address-space limit (`ulimit -v`): the FMU refuses it
    at initialization, naming the key and the sizes, where the failed allocation aborted the
    host before. The host (a Python process with fmpy) then goes on with a coarse grid."""
    script = f"""
import resource, sys
sys.path.insert(0, {str(ROOT / "examples" / "presses")!r})
from fmpy.fmi1 import FMICallException
from driver import Slave
resource.setrlimit(resource.RLIMIT_AS, (3_000_000_000, resource.RLIM_INFINITY))
path = {adaptive_fmus["block_forging"]!r}
s = Slave(path, init=False)
s.fmu.setupExperiment(startTime=0.0)
s.fmu.setInteger([s.vr["workpiece.particles[0]"], s.vr["workpiece.particles[1]"]], [2000, 2000])
s.fmu.enterInitializationMode()
try:
    s.fmu.exitInitializationMode()
    print("NOT REFUSED")
except FMICallException:
    print("REFUSED:", s.last_error())
s.fmu.freeInstance()
s = Slave(path, params={{"workpiece.particles[0]": 11, "workpiece.particles[1]": 11}})
s.set("top.velocity_m_per_s", 10.0)
s.step(1e-5)
print("STROKE", s.get("top.stroke_m")[0])
s.close()
"""
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    lines = r.stdout.splitlines()
    refused = next(l for l in lines if l.startswith(("REFUSED", "NOT REFUSED")))
    for w in ["REFUSED:", "workpiece.particles", "4000000 particles", "need at least", "GB of address space"]:
        assert w in refused, (w, refused)
    stroke = float(next(l for l in lines if l.startswith("STROKE")).split()[1])
    assert stroke == pytest.approx(10.0 * 1e-5)
