"""The Python package `rkforge`: results equal to the command line's bit for bit (also
after a saved state is restored), simulations on threads, and bad input as Python
exceptions."""
import csv
import json
import pickle
import subprocess
import sys
import threading
import time

import numpy as np
import pandas as pd
import pytest

import rkforge
from conftest import ROOT, scene_variant

#: Summary keys that hold timings or the machine's thread count, not results.
TIMING = ("wall_s", "stage_seconds", "threads", "us_per_particle_step")

SCENES = {
    "block": ("block_forging.toml", {"particles = [21, 21]": "particles = [9, 9]",
                                      "end_s = 0.015": "end_s = 0.002"}),
    "taylor": ("taylor_bar.toml", {"particles = [21, 51]": "particles = [11, 26]",
                                   "end_s = 80.0e-6": "end_s = 20.0e-6"}),
    "hot": ("hot_upsetting.toml", {"particles = [11, 31]": "particles = [5, 13]",
                                   "end_s = 1.5 ": "end_s = 0.05 "}),
    # 3D: the quarter OFHC bar with Johnson-Cook and adiabatic heating, the 3D register.
    "ofhc3d": ("taylor_ofhc_3d.toml", {"cells = [8, 4, 48]": "cells = [4, 2, 16]",
                                       "end_s = 100.0e-6": "end_s = 20.0e-6"}),
    # 3D forging: the rectangular block upset between flat dies with friction, mass-scaled
    # at press speed, 1 mm of its stroke.
    "block3d": ("block_upsetting_3d.toml", {"end_s = 1.0 ": "end_s = 0.05 "}),
}


def results(summary):
    return {k: v for k, v in summary.items() if k not in TIMING}


def read_history(path):
    """history.csv as a DataFrame of exact floats (the CLI writes round-trip numbers)."""
    with open(path) as f:
        rows = list(csv.reader(f))
    return pd.DataFrame([[float(x) for x in r] for r in rows[1:]], columns=rows[0])


@pytest.fixture(scope="module", params=sorted(SCENES))
def cli_run(request, rkforge_bin, tmp_path_factory):
    """A scene file and what `rkforge run --no-frames` wrote for it."""
    src, changes = SCENES[request.param]
    tmp = tmp_path_factory.mktemp(request.param)
    path = tmp / src
    path.write_text(scene_variant(src, changes))
    out = tmp / "out"
    proc = subprocess.run([rkforge_bin, "run", str(path), "--out", str(out), "--quiet", "--no-frames"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return path, json.loads((out / "summary.json").read_text()), read_history(out / "history.csv")


def assert_same_history(a, b):
    assert list(a.columns) == list(b.columns)
    assert a.shape == b.shape
    # Bit for bit: every value equal, compared as the raw float64 bits.
    assert np.array_equal(a.to_numpy().view(np.uint64), b.to_numpy().view(np.uint64))


def test_run_equals_the_command_line_bit_for_bit(cli_run):
    path, cli_summary, cli_history = cli_run
    summary, history = rkforge.run(rkforge.Scene.from_file(path))
    assert results(summary) == results(cli_summary)
    assert_same_history(history, cli_history)


def stepped(scene, times, sim=None, rows=None):
    """Step a Simulation to each time, recording a history row there."""
    sim = sim or rkforge.Simulation(scene)
    rows = rows if rows is not None else [sim.sample()]
    end = times[-1]
    for t in times:
        if t > sim.time + 1e-12 * end:
            sim.run_to(t)
        rows.append(sim.sample())
    return sim, rows


def test_stepping_a_simulation_to_the_sample_times_gives_the_same_bits(cli_run):
    path, cli_summary, cli_history = cli_run
    scene = rkforge.Scene.from_file(path)
    sim, rows = stepped(scene, scene.sample_times())
    assert_same_history(pd.DataFrame(rows), cli_history)
    assert results(sim.summary()) == results(cli_summary)


def test_a_restored_state_continues_bit_for_bit(cli_run):
    path, cli_summary, cli_history = cli_run
    scene = rkforge.Scene.from_file(path)
    times = scene.sample_times()
    half = len(times) // 2
    first, rows = stepped(scene, times[:half])
    saved = first.save_state()
    # Continue in a new simulation from the saved state (and let the first one run on).
    second = rkforge.Simulation(scene, threads=1)
    second.restore_state(saved)
    sim, rows = stepped(scene, times[half:], sim=second, rows=rows)
    assert_same_history(pd.DataFrame(rows), cli_history)
    assert results(sim.summary()) == results(cli_summary)
    # The state also goes back in time in the simulation it came from.
    stepped(scene, times[half:], sim=first, rows=[])
    first.restore_state(saved)
    _, again = stepped(scene, times[half:], sim=first, rows=list(rows[: half + 1]))
    assert_same_history(pd.DataFrame(again), cli_history)


def block_scene():
    src, changes = SCENES["block"]
    return rkforge.Scene.from_toml(scene_variant(src, changes), "block.toml")


def test_simulations_on_threads_give_the_bits_of_a_serial_run():
    scene = block_scene()
    speeds = [5.0, 10.0, 15.0]
    serial = {}
    for v in speeds:
        s = scene.copy()
        s.set("tools.top.motion.velocity_m_per_s", v)
        serial[v] = rkforge.run(s)
    threaded = {}

    def work(v):
        s = scene.copy()
        s.set("tools.top.motion.velocity_m_per_s", v)
        threaded[v] = rkforge.run(s, threads=1)

    threads = [threading.Thread(target=work, args=(v,)) for v in speeds]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=600)
    for v in speeds:
        assert results(threaded[v][0]) == results(serial[v][0])
        assert_same_history(threaded[v][1], serial[v][1])
    # Different speeds, different results: the override reached the run.
    assert serial[5.0][1]["top.stroke_m"].iloc[-1] != serial[10.0][1]["top.stroke_m"].iloc[-1]


def test_fields_tools_and_commands():
    scene = block_scene()
    sim = rkforge.Simulation(scene, integration="q4")
    assert sim.summary()["integration"] == "q4"
    sim.set_tool_velocity("top", 4.0)
    sim.set_tool_velocity("bottom", 0.0)
    sim.run_to(1e-3)
    assert sim.time == 1e-3
    strokes = sim.tool_strokes()
    assert strokes["top"] == pytest.approx(4.0e-3, rel=1e-9) and strokes["bottom"] == 0.0
    forces = sim.tool_forces()
    assert set(forces) == {"top", "bottom"} and forces["top"] < 0
    f = sim.fields()
    assert f["positions"].shape == (81, 2) and f["plastic_strain"].shape == (81,)
    assert np.allclose(f["positions"] - f["displacement"], sim.fields()["positions"] - f["displacement"])
    assert f["von_mises"].max() > 0 and np.isfinite(f["velocity"]).all()
    tools = sim.tools()
    assert [t["name"] for t in tools] == ["top", "bottom"] and tools[0]["axial_force_N"] == forces["top"]
    steps = sim.steps
    assert sim.step() > 1e-3 and sim.steps == steps + 1


def test_a_hot_scene_gives_its_temperature_as_a_numpy_field():
    """A scene with `[thermal]`: `fields()["temperature"]` (degrees C, one per particle),
    between the dies' 250 C and the billet's 1150 C plus its plastic heating; the history's
    thermal columns; an isothermal scene has no temperature field."""
    src, changes = SCENES["hot"]
    sim = rkforge.Simulation(rkforge.Scene.from_toml(scene_variant(src, changes), "hot.toml"))
    sim.run_to(0.05)
    f = sim.fields()
    t = f["temperature"]
    assert t.shape == f["plastic_strain"].shape == (65,)
    assert 250.0 < t.min() < 1150.0 < t.max() < 1200.0
    summary = sim.summary()
    assert summary["thermal"]["temperature_min_c"] < 1150.0
    assert abs(summary["thermal"]["heat_balance_rel"]) < 1e-9
    assert "temperature" not in rkforge.Simulation(block_scene()).fields()


def test_scenes_pickle_with_their_overrides():
    scene = block_scene()
    scene.set("tools.top.friction", 0.3)
    scene.set("workpiece.particles", [7, 7])
    back = pickle.loads(pickle.dumps(scene))
    assert back == scene and back.overrides == [("tools.top.friction", 0.3), ("workpiece.particles", [7, 7])]
    assert "friction = 0.3" in back.to_toml()


@pytest.mark.parametrize(
    "key, value, error, words",
    [
        ("tools.top.frction", 0.1, rkforge.SceneError, ["tools.top.frction", "unknown field `frction`"]),
        ("tools.middle.friction", 0.1, rkforge.SceneError, ["no entry of `tools` is named `middle`"]),
        ("tools.top.friction", "high", rkforge.SceneError, ["tools.top.friction", "invalid type"]),
        ("tools.top.friction", object(), TypeError, ["tools.top.friction", "object"]),
        ("material.poisson_ratio", 0.5, rkforge.SceneError, ["material.poisson_ratio", "(-1, 0.5)"]),
        ("tools.top.friction", float("nan"), rkforge.SceneError, ["tools.top.friction", "must be zero or positive"]),
        ("time.end_s.x", 1, rkforge.SceneError, ["`time.end_s` is a number, not a table"]),
    ],
)
def test_bad_overrides_raise_naming_the_key(key, value, error, words):
    scene = block_scene()
    with pytest.raises(error) as e:
        scene.set(key, value)
    for w in words:
        assert w in str(e.value), (w, str(e.value))
    assert scene.overrides == []


def test_bad_input_raises_and_the_interpreter_lives_on(tmp_path):
    with pytest.raises(rkforge.SceneError, match="bad.toml: line 30: `material.poisson_ratio`: invalid type"):
        src, changes = SCENES["block"]
        text = scene_variant(src, changes).replace("poisson_ratio = 0.35", 'poisson_ratio = "soft"')
        rkforge.Scene.from_toml(text, "bad.toml")
    with pytest.raises(rkforge.SceneError, match="cannot read"):
        rkforge.Scene.from_file(tmp_path / "nope.toml")
    scene = block_scene()
    sim = rkforge.Simulation(scene)
    with pytest.raises(ValueError, match="not finite"):
        sim.set_tool_velocity("top", float("nan"))
    with pytest.raises(ValueError, match="no tool named `middle`"):
        sim.set_tool_velocity("middle", 1.0)
    with pytest.raises(ValueError, match="finite"):
        sim.run_to(float("nan"))
    with pytest.raises(ValueError, match="integration `q9`"):
        rkforge.Simulation(scene, integration="q9")
    with pytest.raises(ValueError, match="threads must be at least 1"):
        rkforge.Simulation(scene, threads=0)
    # A million threads never finished starting: refused by name, at once.
    with pytest.raises(ValueError, match="threads = 1000000: at most 256"):
        rkforge.Simulation(scene, threads=1_000_000)
    with pytest.raises(ValueError, match="threads = 257: at most 256"):
        rkforge.run(scene, threads=257)
    other = scene.copy()
    other.set("tools.top.friction", 0.05)
    with pytest.raises(rkforge.StateError, match="other settings"):
        sim.restore_state(rkforge.Simulation(other).save_state())
    taylor = rkforge.Scene.from_file(ROOT / "scenes" / "taylor_bar.toml")
    with pytest.raises(rkforge.StateError, match="saved from scene `taylor_bar`, not `block_forging`"):
        sim.restore_state(rkforge.Simulation(taylor).save_state())
    with pytest.raises(rkforge.StateError, match="not a saved rkforge state"):
        sim.restore_state(b"\x00garbage")
    # A velocity that would take the tool past particles in one step (1e300 m/s once took it
    # through the block with a force of 0) stops the step before anything changes.
    sim.set_tool_velocity("top", 1e300)
    with pytest.raises(ValueError, match="tool `top`: velocity 1.0000e300 m/s \\(commanded\\)"):
        sim.step()
    sim.set_tool_velocity("top", 10.0)
    # Still usable after every refusal.
    sim.run_to(2e-4)
    assert sim.time == pytest.approx(2e-4, rel=1e-12)


def test_numpy_integers_and_bools_set_integer_and_boolean_keys():
    scene = rkforge.Scene.from_file(ROOT / "scenes" / "block_forging.toml")
    scene.set("output.frames", np.int64(3))
    scene.set("workpiece.particles", list(np.array([9, 7], dtype=np.int32)))
    scene.set("tools.top.separation", np.bool_(False))
    scene.set("tools.top.friction", np.float32(0.25))
    set_to = dict(scene.overrides)
    assert set_to["output.frames"] == 3 and type(set_to["output.frames"]) is int
    assert set_to["workpiece.particles"] == [9, 7]
    assert set_to["tools.top.separation"] is False
    assert set_to["tools.top.friction"] == 0.25
    with pytest.raises(rkforge.SceneError, match="expected usize"):
        scene.set("output.frames", np.float64(3.5))


INTERRUPTED = """
import os, signal, sys, threading, time
import rkforge
# Python leaves SIGINT ignored when it starts ignored (a job started with & by a script, as a
# CI runner may start the tests): Ctrl-C's own handler, as an interactive session has it.
signal.signal(signal.SIGINT, signal.default_int_handler)
scene = rkforge.Scene.from_file(sys.argv[1])
scene.set("workpiece.particles", [61, 61])
scene.set("time.dt_s", 5e-7)
scene.set("time.end_s", 0.011)
call = sys.argv[2]
threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
start = time.perf_counter()
try:
    if call == "run":
        rkforge.run(scene, threads=1)
    else:
        rkforge.Simulation(scene, threads=1).run_to(0.011)
    print("finished", time.perf_counter() - start)
except KeyboardInterrupt:
    print("interrupted", time.perf_counter() - start)
"""


@pytest.mark.parametrize("call", ["run", "run_to"])
def test_ctrl_c_stops_a_run_with_keyboard_interrupt(call, tmp_path):
    """The 61 x 61 block at half its step to 11 ms (22 000 steps, about 8 s on one thread):
    a SIGINT 1 s in stops it with KeyboardInterrupt (before, the run went on to its end, and
    a first call then panicked in numpy's import with the interrupt pending)."""
    script = tmp_path / "interrupted.py"
    script.write_text(INTERRUPTED)
    proc = subprocess.run([sys.executable, str(script), str(ROOT / "scenes" / "block_forging.toml"), call],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    word, seconds = proc.stdout.split()
    assert word == "interrupted" and float(seconds) < 20, proc.stdout
    assert "panic" not in proc.stderr.lower()



def test_a_grid_beyond_the_machines_memory_raises_and_python_lives_on():
    """Under a 3 GB address-space limit a 2000 x 2000 block raises MemoryError naming the key
    (before, the failed allocation aborted the interpreter); the session goes on."""
    script = """
import resource, sys
import rkforge
resource.setrlimit(resource.RLIMIT_AS, (3_000_000_000, resource.RLIM_INFINITY))
scene = rkforge.Scene.from_file(sys.argv[1])
scene.set("workpiece.particles", [2000, 2000])
try:
    rkforge.Simulation(scene)
    print("NOT REFUSED")
except MemoryError as e:
    print("REFUSED:", e)
scene.set("workpiece.particles", [11, 11])
summary, history = rkforge.run(scene)
print("RAN", summary["status"])
"""
    proc = subprocess.run([sys.executable, "-c", script, str(ROOT / "scenes" / "block_forging.toml")],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "REFUSED: `workpiece.particles`: 4000000 particles" in proc.stdout, proc.stdout
    assert "RAN ok" in proc.stdout, proc.stdout


def test_the_type_stubs_match_the_built_module(tmp_path):
    """mypy's stubtest: every name, signature and class of the installed package (the Rust
    extension and the Python modules) against its stubs, as a user's type checker reads
    them (`Simulation(...)` through `__new__`, the classes final). pandas and tqdm ship no
    stubs here: their imports are left untyped."""
    config = tmp_path / "mypy.ini"
    config.write_text(f"[mypy]\nignore_missing_imports = True\ncache_dir = {tmp_path / 'cache'}\n")
    proc = subprocess.run([sys.executable, "-m", "mypy.stubtest", "rkforge", "--mypy-config-file", str(config)],
                          capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-2000:]
    assert "Success: no issues found" in proc.stdout, proc.stdout

def test_a_failed_run_raises_with_its_summary_and_history():
    scene = block_scene()
    # An energy bound that the second step breaks.
    scene.set("checks.energy_balance_tol", 1e-9)
    with pytest.raises(rkforge.SimulationError) as e:
        rkforge.run(scene)
    assert e.value.summary["status"] == "error" and "energy balance error" in str(e.value)
    # The row at t = 0 and the last state.
    assert len(e.value.history) == 2 and e.value.history["time_s"].iloc[-1] > 0
    # A step above the stable step is refused at setup, before any history.
    unstable = block_scene()
    unstable.set("time.dt_s", 2e-5)
    with pytest.raises(rkforge.SimulationError, match="exceeds the stable step"):
        rkforge.run(unstable)
    summary, history = rkforge.run(scene, check=False)
    assert summary["status"] == "error" and summary["error"] == str(e.value)


def test_read_mcap_gives_the_history_columns_and_the_point_clouds(rkforge_bin, tmp_path):
    src, changes = SCENES["block"]
    path = tmp_path / src
    path.write_text(scene_variant(src, changes))
    out, mcap = tmp_path / "out", tmp_path / "run.mcap"
    proc = subprocess.run([rkforge_bin, "run", str(path), "--out", str(out), "--quiet", "--no-frames",
                           "--mcap", str(mcap)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    history = read_history(out / "history.csv")
    rec = rkforge.read_mcap(mcap)
    tools = [f"{t}.{c}" for t in ("top", "bottom")
             for c in ("stroke_m", "velocity_m_per_s", "force_N", "force_x_N", "force_y_N", "contact_fraction")]
    energy = [f"energy.{c}" for c in ("kinetic_J", "elastic_J", "plastic_J", "internal_J", "contact_J",
                                      "tool_work_J")]
    assert list(rec.history.columns) == ["time_s", *tools, "workpiece.laps", *energy,
                                         "energy.initial_J"]
    assert len(rec.history) == len(history)
    assert (rec.history["workpiece.laps"] == 0.0).all()
    # Log times are the sample times rounded to the nanosecond.
    assert np.abs(rec.history["time_s"].to_numpy() - history["time_s"].to_numpy()).max() < 1e-9
    same = tools + ["workpiece.laps"] + energy
    assert_same_history(rec.history[same], history[same])
    # The block starts at rest; the account closes: the tools' work went into the block.
    assert (rec.history["energy.initial_J"] == 0.0).all()
    end = rec.history.iloc[-1]
    assert end["energy.internal_J"] == pytest.approx(end["energy.contact_J"] - end["energy.kinetic_J"], rel=1e-3)
    assert len(rec.clouds) == len(history) and np.array_equal(rec.cloud_times_s, rec.history["time_s"])
    # The register's outputs: history.csv's columns under the same names and bits, units
    # beside them, and outputs the history does not show (the summary's figures).
    assert_same_history(rec.outputs[list(history.columns)], history)
    assert rec.units["top.pressure_mean_Pa"] == "Pa" and rec.units["top.force_N"] == "N"
    assert "top.peak_force_N" in rec.outputs.columns
    for cloud, (_, row) in zip(rec.clouds, history.iterrows()):
        assert set(cloud) == {"x", "y", "z", "plastic_strain", "von_mises"}
        assert cloud["x"].shape == (81,) and cloud["x"].dtype == np.float32
        assert cloud["x"].min() == pytest.approx(row["workpiece.x_min_m"], abs=1e-6)
        assert cloud["y"].max() == pytest.approx(row["workpiece.y_max_m"], abs=1e-6)
        assert cloud["plastic_strain"].max() <= row["workpiece.max_plastic_strain"] + 1e-6


def test_read_mcap_gives_a_3d_runs_forces_in_three_directions(rkforge_bin, tmp_path):
    """A 3D recording: the wrenches' z components are history columns as history.csv has
    them (a 2D recording has none, the test above), the clouds carry three coordinates."""
    from ros_peer import upset_bar_3d

    scene = upset_bar_3d(tmp_path)
    out, mcap = tmp_path / "out", tmp_path / "run3d.mcap"
    proc = subprocess.run([rkforge_bin, "run", str(scene), "--out", str(out), "--quiet", "--no-frames",
                           "--mcap", str(mcap)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    history = read_history(out / "history.csv")
    rec = rkforge.read_mcap(mcap)
    tools = [f"{t}.{c}" for t in ("wall", "ram")
             for c in ("stroke_m", "velocity_m_per_s", "force_N", "force_x_N", "force_y_N", "force_z_N")]
    assert list(rec.history.columns)[:len(tools) + 1] == ["time_s", *tools]
    assert_same_history(rec.history[tools], history[tools])
    assert rec.history["ram.force_z_N"].abs().max() > 1e3, "the ram presses"
    last = rec.clouds[-1]
    assert {"x", "y", "z"} <= set(last)
    assert last["z"].max() == pytest.approx(history["workpiece.z_max_m"].iloc[-1], abs=1e-6)


def test_outputs_come_from_the_register():
    """`Simulation.outputs()` and `Scene.outputs()`: every output of the register under its
    one name, the history's columns with the bits of `sample()`, the figures only the
    summary shows with the summary's bits (the mean contact pressure among them), the fields
    as numpy arrays."""
    scene = block_scene()
    sim = rkforge.Simulation(scene)
    sim.run_to(1e-3)
    values = sim.outputs()
    row = sim.sample()
    assert {c: values[c] for c in row} == row
    summary = sim.summary()
    for k, tool in enumerate(summary["tools"]):
        for key in ("pressure_mean_Pa", "contact_length_m", "peak_force_N", "stroke_m"):
            assert values[f"{tool['name']}.{key}"] == tool[key]
    assert values["top.pressure_mean_Pa"] > 0 and values["energy.initial_J"] == 0.0
    assert values["particles.plastic_strain"].shape == (81,)
    assert values["points.jacobian"].shape == (summary["integration_points"],)
    register = {o["name"]: o for o in scene.outputs()}
    assert list(register) == list(values)
    p = register["top.pressure_mean_Pa"]
    assert (p["unit"], p["kind"], p["history"], p["summary"], p["fmu"]) == (
        "Pa", "per tool", True, True, True)
    assert "tool top" in p["description"]
    assert [o["name"] for o in scene.outputs() if o["history"]] == list(row)
    assert register["time_s"]["fmu"] is False
    assert register["particles.von_mises_Pa"]["kind"] == "per particle"
    # The force averaged since the last sample(): the impulse's change over the time's.
    sim.run_to(2e-3)
    later = sim.outputs()
    mean = (later["top.impulse_N_s"] - row["top.impulse_N_s"]) / (later["time_s"] - row["time_s"])
    assert later["top.force_mean_N"] == mean < 0.0
    assert sum(later[f"{t['name']}.work_J"] for t in summary["tools"]) == pytest.approx(
        later["energy.tool_work_J"], rel=1e-12)


def test_stepping_releases_the_gil():
    """While a simulation steps in one thread, Python code runs in another: the main thread
    counts the iterations it makes in the middle half of the worker's run (none if the GIL
    were held during the run; a thread switch just before or after the call can only add
    iterations near its ends)."""
    scene = block_scene()
    scene.set("workpiece.particles", [17, 17])
    scene.set("time.end_s", 0.008)
    sim = rkforge.Simulation(scene)
    marks = {}

    def work():
        marks["start"] = time.perf_counter()
        sim.run_to(0.008)
        marks["end"] = time.perf_counter()

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
    worker.join()
    quarter = (marks["end"] - marks["start"]) / 4
    during = [t for t in ticks if marks["start"] + quarter < t < marks["end"] - quarter]
    assert len(during) > 100, (len(during), 4 * quarter)
    assert pickle.loads(pickle.dumps(rkforge.SceneError("x"))).args == ("x",)
    assert rkforge.SceneError.__module__ == "rkforge"
