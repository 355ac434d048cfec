"""Laps through every front end: the coarse `scenes/lap_around_pin.toml` (two metal fronts
rejoining under a pin) run by `rkforge run` (summary, history, VTK frames, picture, MCAP), the
Python package, the FMU through fmpy and the ROS node's recording, each reporting the same lap."""
import csv
import json
import re
import subprocess

import numpy as np
import pytest
from fmpy import simulate_fmu
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

import rkforge
from conftest import ROOT, scene_variant
from ros_peer import start_node

COARSE = {"particles = [41, 21]": "particles = [21, 11]"}


@pytest.fixture(scope="module")
def pin(tmp_path_factory):
    path = tmp_path_factory.mktemp("pin") / "pin.toml"
    path.write_text(scene_variant("lap_around_pin.toml", COARSE))
    return path


def run_cli(rkforge_bin, pin, out, *extra):
    subprocess.run([rkforge_bin, "run", str(pin), "--out", str(out), "--quiet", *extra],
                   check=True, capture_output=True, text=True)
    with open(out / "history.csv") as f:
        rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(f)]
    return out, json.loads((out / "summary.json").read_text()), rows


@pytest.fixture(scope="module")
def cli(pin, rkforge_bin, tmp_path_factory):
    """`rkforge run --no-frames --mcap`: the steps of every other front end (frames add
    landing times and move the last digits)."""
    out = tmp_path_factory.mktemp("pin_run")
    return run_cli(rkforge_bin, pin, out, "--no-frames", "--mcap", str(out / "pin.mcap"))


def laps_messages(path):
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [(m.log_time, msg) for _, c, m, msg in reader.iter_decoded_messages(
            topics=["/rkforge/laps"], log_time_order=True)]


def test_the_command_line_reports_the_lap_in_summary_history_frames_and_picture(
        pin, rkforge_bin, tmp_path):
    out, summary, rows = run_cli(rkforge_bin, pin, tmp_path)
    [lap] = summary["laps"]
    assert abs(lap["start_m"][0]) < 1e-3 and -0.012 < lap["start_m"][1] < -0.006
    assert summary["contact"]["max_boundary_crossings"] == 0 and summary["warnings"] == []
    counts = [r["workpiece.laps"] for r in rows]
    first = next(k for k, c in enumerate(counts) if c > 0)
    assert set(counts[:first]) == {0.0} and set(counts[first:]) == {1.0}
    assert rows[first - 1]["time_s"] < lap["formed_s"] <= rows[first]["time_s"]
    # The last frame's `lap` field marks the lap's particles and no other.
    frames = sorted((out / "frames").glob("frame_*.vtu"))
    text = frames[-1].read_text()
    field = re.search(r'Name="lap" NumberOfComponents="1" format="ascii">(.*?)</DataArray>',
                      text, re.S).group(1).split()
    marked = {j for j, v in enumerate(field) if float(v) > 0}
    assert marked == set(lap["particles"]) and {float(field[j]) for j in marked} == {1.0}
    assert (out / "shape.png").stat().st_size > 0


def test_the_recording_carries_the_laps_topic(cli):
    out, summary, rows = cli
    msgs = laps_messages(out / "pin.mcap")
    assert [t for t, _ in msgs] == [round(r["time_s"] * 1e9) for r in rows]
    assert [len(m.formed_time) for _, m in msgs] == [r["workpiece.laps"] for r in rows]
    [lap] = summary["laps"]
    last = msgs[-1][1]
    assert list(last.tools) == ["die", "pin", "punch"]
    assert last.formed_time[0] == lap["formed_s"]
    assert list(last.formed_stroke) == [lap["formed_stroke_m"][t] for t in last.tools]
    assert (last.start_x[0], last.start_y[0]) == tuple(lap["start_m"])
    assert (last.end_x[0], last.end_y[0]) == tuple(lap["end_m"])
    assert last.length[0] == lap["length_m"]
    history = rkforge.read_mcap(out / "pin.mcap").history
    assert list(history["workpiece.laps"]) == [r["workpiece.laps"] for r in rows]


def test_python_gives_the_same_lap_and_marks_its_particles(pin, cli):
    _, summary, rows = cli
    scene = rkforge.Scene.from_file(str(pin))
    run_summary, history = rkforge.run(scene)
    assert run_summary["laps"] == summary["laps"]
    assert list(history["workpiece.laps"]) == [r["workpiece.laps"] for r in rows]
    # Stepped to the run's sample times, a Simulation takes the same steps.
    sim = rkforge.Simulation(scene)
    for t in scene.sample_times():
        if t > sim.time:
            sim.run_to(t)
    laps = sim.laps()
    assert laps == summary["laps"]
    lap = sim.fields()["lap"]
    assert lap.shape == (231,) and set(np.flatnonzero(lap)) == set(laps[0]["particles"])


def test_the_fmu_counts_the_lap(pin, rkforge_bin, tmp_path):
    fmu = tmp_path / "pin.fmu"
    subprocess.run([rkforge_bin, "fmu", str(pin), "--out", str(fmu)], check=True,
                   capture_output=True, text=True)
    result = simulate_fmu(str(fmu), stop_time=0.038, output_interval=0.002,
                          output=["workpiece.laps"])
    counts = list(result["workpiece.laps"])
    assert counts[0] == 0.0 and counts[-1] == 1.0 and counts == sorted(counts)


def test_the_node_records_the_lap(pin, cli, rkforge_ros_bin, tmp_path):
    out, summary, rows = cli
    path = tmp_path / "node.mcap"
    node = start_node(rkforge_ros_bin, pin, 171, "--record", str(path))
    _, err = node.communicate(timeout=300)
    assert node.returncode == 0, err
    msgs = laps_messages(path)
    assert [len(m.formed_time) for _, m in msgs] == [r["workpiece.laps"] for r in rows]
    assert msgs[-1][1].formed_time[0] == summary["laps"][0]["formed_s"]


def test_a_3d_fold_within_the_support_is_reported_where_its_faces_cross(rkforge_bin, tmp_path):
    """The conrod on its coarsest grid (15 x 5 x 7): the bar's top edge by the boss curls onto
    its side within a cell, where the self-contact and its lap rule do not look. The run's
    summary says so in a warning with when and where, the history counts the crossings of the
    surface's faces from that sample on, and no lap is claimed."""
    out, summary, rows = run_cli(
        rkforge_bin, ROOT / "scenes" / "conrod_3d.toml", tmp_path, "--no-frames",
        "--set", "workpiece.particles=[15, 5, 7]", "--set", "time.end_s=0.026")
    crossings = [r["workpiece.fold_crossings"] for r in rows]
    first = next(k for k, c in enumerate(crossings) if c > 0)
    assert 0.020 < rows[first]["time_s"] and set(crossings[:first]) == {0.0}
    assert summary["contact"]["max_fold_crossings"] == max(crossings)
    [warning] = summary["warnings"]
    assert warning.startswith("the root of a fold passed through itself"), warning
    at = float(re.search(r"first at t = (\S+) s", warning).group(1))
    assert abs(at - rows[first]["time_s"]) <= 1e-4 * at, warning
    assert summary["laps"] == []
