"""MCAP recordings (`rkforge run --mcap`, `rkforge-ros --record`) read back by two independent
readers, `mcap` + `mcap-ros2-support` and `rosbags`, zstd-compressed (the default) and
uncompressed: every message decodes and the values match history.csv; the metadata and the
attached scene read back equal to the run's scene and summary; SIGINT/SIGTERM finish the file;
a killed process leaves a file readable up to its last chunk. A 3D run's recording (its own
topics: no die fill, no laps) reads back the same way."""
import json
import math
import signal
import struct
import subprocess
import time

import pytest
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.stream_reader import StreamReader
from mcap.records import Chunk, Message, Channel, Schema
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader

from conftest import scene_variant
from ros_peer import (ROOT, block_3d, history, run_history, small_bar_3d, small_block,
                      start_node, upset_bar_3d)

TOPICS = {
    "/rkforge/top/wrench": "geometry_msgs/msg/WrenchStamped",
    "/rkforge/bottom/wrench": "geometry_msgs/msg/WrenchStamped",
    "/rkforge/tools": "sensor_msgs/msg/JointState",
    "/rkforge/workpiece": "sensor_msgs/msg/PointCloud2",
    "/rkforge/tool_markers": "visualization_msgs/msg/MarkerArray",
    "/rkforge/die_fill": "rkforge_msgs/msg/DieFill",
    "/rkforge/laps": "rkforge_msgs/msg/Laps",
    "/rkforge/energy": "rkforge_msgs/msg/Energy",
    "/rkforge/outputs": "rkforge_msgs/msg/Outputs",
    "/clock": "rosgraph_msgs/msg/Clock",
}

# The fields of rkforge_msgs/msg/Energy and the history.csv columns with the same figures.
ENERGY = {"kinetic": "kinetic_J", "elastic": "elastic_J", "plastic": "plastic_J",
          "internal": "internal_J", "contact_work": "contact_J", "tool_work": "tool_work_J"}


@pytest.fixture(scope="module", params=["zstd", "none"])
def recorded(request, rkforge_bin, tmp_path_factory):
    """A short block forging run with --mcap and the chunk compression of the parameter:
    (history rows, path of the MCAP file, compression, the run's output folder, scene file)."""
    d = tmp_path_factory.mktemp("mcap")
    scene = small_block(d)
    path = d / "run.mcap"
    rows = run_history(rkforge_bin, scene, d / "out", "--mcap", str(path),
                       "--mcap-compression", request.param)
    return rows, path, request.param, d / "out", scene


def metadata(path):
    """The metadata records of an MCAP file: {name: {key: value}}."""
    with open(path, "rb") as f:
        return {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}


def attachments(path):
    """The attachments of an MCAP file: {name: (media type, bytes)}."""
    with open(path, "rb") as f:
        return {a.name: (a.media_type, bytes(a.data)) for a in make_reader(f).iter_attachments()}


def complete_chunks(path):
    """The number of chunks of a file being written that a stream reader reads whole."""
    n = 0
    try:
        with open(path, "rb") as f:
            for r in StreamReader(f, emit_chunks=True).records:
                n += isinstance(r, Chunk)
    except (McapError, EOFError, struct.error, ValueError, OSError):
        pass  # the chunk being written
    return n


def wait_for_chunks(p, path, n, timeout=120):
    """Wait until the file of process `p` holds `n` complete chunks (the process must still
    be running)."""
    t0 = time.monotonic()
    while not path.exists() or complete_chunks(path) < n:
        assert p.poll() is None, f"the run ended before its file had {n} complete chunks"
        assert time.monotonic() - t0 < timeout, f"no {n} complete chunks after {timeout} s"
        time.sleep(0.01)


def decoded(path):
    """Every message decoded by mcap-ros2-support: list of (topic, log_time, message)."""
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [(c.topic, m.log_time, d) for _, c, m, d in reader.iter_decoded_messages()]


def ns(t):
    return round(t * 1e9)


def cloud_xy(cloud):
    """x and y of each point of a PointCloud2 of five float32 fields."""
    step = cloud.point_step
    data = bytes(cloud.data)
    return [struct.unpack_from("<2f", data, k * step) for k in range(cloud.width)]


def check_against_history(msgs, rows, particles=64):
    """The messages of each topic, in order, match the history rows at the same times."""
    by_topic = {}
    for topic, log_time, m in msgs:
        by_topic.setdefault(topic, []).append((log_time, m))
    assert set(by_topic) == set(TOPICS)
    for topic, seq in by_topic.items():
        assert len(seq) == len(rows), topic
        for (log_time, m), row in zip(seq, rows):
            assert log_time == ns(row["time_s"]), topic
            header = getattr(m, "header", None)
            if header is not None:
                assert header.stamp.sec * 10**9 + header.stamp.nanosec == log_time
                assert header.frame_id == "rkforge"
    for (_, js), row in zip(by_topic["/rkforge/tools"], rows):
        assert list(js.name) == ["top", "bottom"]
        for k, tool in enumerate(js.name):
            assert js.position[k] == row[f"{tool}.stroke_m"]
            assert js.velocity[k] == row[f"{tool}.velocity_m_per_s"]
            assert js.effort[k] == row[f"{tool}.force_N"]
    for tool in ["top", "bottom"]:
        for (_, w), row in zip(by_topic[f"/rkforge/{tool}/wrench"], rows):
            assert w.wrench.force.x == row[f"{tool}.force_x_N"]
            assert w.wrench.force.y == row[f"{tool}.force_y_N"]
            assert (w.wrench.torque.x, w.wrench.torque.y, w.wrench.torque.z) == (0, 0, 0)
    for (_, c), row in zip(by_topic["/rkforge/workpiece"], rows):
        assert [f.name for f in c.fields] == ["x", "y", "z", "plastic_strain", "von_mises"]
        assert all(f.datatype == 7 and f.count == 1 for f in c.fields)
        assert (c.height, c.width, c.point_step) == (1, particles, 20)
        xy = cloud_xy(c)
        for k, (col, fn) in enumerate([("x_min_m", min), ("x_max_m", max)]):
            assert fn(p[0] for p in xy) == pytest.approx(row[f"workpiece.{col}"], abs=1e-7)
        for col, fn in [("y_min_m", min), ("y_max_m", max)]:
            assert fn(p[1] for p in xy) == pytest.approx(row[f"workpiece.{col}"], abs=1e-7)
    for (_, m), row in zip(by_topic["/rkforge/tool_markers"], rows):
        assert [mk.text for mk in m.markers] == ["top", "bottom"]
        top = m.markers[0]
        # The top tool starts at y = 0.25 and moves down by its stroke.
        assert top.points[0].y == pytest.approx(0.25 - row["top.stroke_m"], abs=1e-12)
    for (_, e), row in zip(by_topic["/rkforge/energy"], rows):
        for field, column in ENERGY.items():
            assert getattr(e, field) == row[f"energy.{column}"], field
        assert e.initial == 0.0, "the block starts at rest"
    # The register's outputs: every history column under its own name, bit for bit, with
    # its unit beside it, and the figures only the summary and the FMU show.
    for (_, o), row in zip(by_topic["/rkforge/outputs"], rows):
        got = dict(zip(o.names, o.values))
        assert {c: got[c] for c in row} == row
        units = dict(zip(o.names, o.units))
        assert (units["top.force_N"], units["top.pressure_mean_Pa"], units["energy.kinetic_J"],
                units["workpiece.max_plastic_strain"]) == ("N", "Pa", "J", "1")
        assert {"top.peak_force_N", "energy.initial_J"} <= set(got) - set(row)
    for (_, c), row in zip(by_topic["/clock"], rows):
        assert c.clock.sec * 10**9 + c.clock.nanosec == ns(row["time_s"])


def test_mcap_reader_decodes_every_message_and_matches_history(recorded):
    rows, path, compression, _, _ = recorded
    with open(path, "rb") as f:
        reader = make_reader(f)
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        assert summary.statistics.message_count == len(rows) * len(TOPICS)
        assert summary.chunk_indexes, "the file is chunked and indexed"
        expected = {"zstd": "zstd", "none": ""}[compression]
        assert all(ci.compression == expected for ci in summary.chunk_indexes)
        assert {c.topic: summary.schemas[c.schema_id].name
                for c in summary.channels.values()} == TOPICS
        assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
        assert {s.encoding for s in summary.schemas.values()} == {"ros2msg"}
        wrench = next(s for s in summary.schemas.values()
                      if s.name == "geometry_msgs/msg/WrenchStamped").data.decode()
        assert wrench.startswith("# A wrench with reference coordinate frame and timestamp\n")
        assert "\n" + "=" * 80 + "\nMSG: geometry_msgs/Vector3\n" in wrench
    check_against_history(decoded(path), rows)


def test_rosbags_decodes_every_message_and_matches_history(recorded):
    rows, path, _, _, _ = recorded
    msgs = []
    with AnyReader([path]) as reader:
        assert {c.topic: c.msgtype for c in reader.connections} == TOPICS
        for c, log_time, raw in reader.messages():
            msgs.append((c.topic, log_time, reader.deserialize(raw, c.msgtype)))
    msgs.sort(key=lambda m: (m[1], list(TOPICS).index(m[0])))
    check_against_history(msgs, rows)


def test_the_file_holds_the_scene_and_the_summary_of_its_run(recorded):
    rows, path, compression, out, scene = recorded
    meta = metadata(path)
    assert set(meta) == {"rkforge", "rkforge_summary"}
    assert meta["rkforge"] == {
        "scene": "block_forging",
        "scene_file": scene.name,
        "description": meta["rkforge"]["description"],
        "kinematics": "plane_strain",
        "integration": "q2",
        "resolution": "8x8",
        "time": '{"end_s":0.003,"dt_s":1e-6,"dt_safety":0.5}',
        "rkforge_version": "0.1.0",
        "writer": "rkforge run",
        "compression": compression,
    }
    assert meta["rkforge"]["description"].startswith("Plane-strain block forging")
    # The summary record is summary.json, byte for byte.
    assert meta["rkforge_summary"] == {"summary_json": (out / "summary.json").read_text()}
    summary = json.loads(meta["rkforge_summary"]["summary_json"])
    assert summary["end_time_s"] == rows[-1]["time_s"]
    assert attachments(path) == {scene.name: ("application/toml", scene.read_bytes())}
    # The last sample's outputs are the summary's figures of the same names, bit for bit.
    last = [m for topic, _, m in decoded(path) if topic == "/rkforge/outputs"][-1]
    got = dict(zip(last.names, last.values))
    for k, tool in enumerate(summary["tools"]):
        for key in ("stroke_m", "contact_fraction", "pressure_mean_Pa", "peak_force_N"):
            assert got[f"{tool['name']}.{key}"] == tool[key], key
    assert tool["pressure_mean_Pa"] > 0
    for key in ("initial_J", "kinetic_J", "contact_interface_J", "kinetic_to_internal_max"):
        assert got[f"energy.{key}"] == summary["energy"][key], key
    assert got["workpiece.height_m"] == summary["workpiece"]["height_m"]


def test_the_node_records_the_same_bytes_as_rkforge_run(recorded, rkforge_ros_bin, tmp_path):
    rows, path, compression, run_out, _ = recorded
    scene = small_block(tmp_path)
    out = tmp_path / "node.mcap"
    p = start_node(rkforge_ros_bin, scene, 151, "--record", str(out),
                   "--record-compression", compression)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 0, err
    assert f"recorded {out}" in err

    def raw(f):
        with open(f, "rb") as fh:
            return [(c.topic, m.log_time, m.data) for _, c, m in make_reader(fh).iter_messages()]

    assert raw(out) == raw(path)
    meta = metadata(out)
    assert meta["rkforge"]["writer"] == "rkforge-ros"
    assert meta["rkforge"]["compression"] == compression
    summary = json.loads(meta["rkforge_summary"]["summary_json"])
    assert summary["status"] == "ok" and summary["error"] is None
    assert summary["ros"]["samples_published"] == len(rows)
    assert summary["end_time_s"] == rows[-1]["time_s"]
    # The node's summary is the runner's: that of `rkforge run --no-frames` for the same
    # run, but for the wall times and the node's own figures.
    run = json.loads((run_out / "summary.json").read_text())
    volatile = ("wall_s", "stage_seconds", "ros")
    assert {k: v for k, v in summary.items() if k not in volatile} == \
        {k: v for k, v in run.items() if k not in volatile}
    assert attachments(out) == {scene.name: ("application/toml", scene.read_bytes())}


def test_sigint_finishes_the_file_of_rkforge_run(rkforge_bin, tmp_path):
    scene = small_block(tmp_path, end="0.03", particles="[21, 21]")
    path = tmp_path / "int.mcap"
    p = subprocess.Popen([rkforge_bin, "run", str(scene), "--no-frames", "--quiet",
                          "--out", str(tmp_path / "out"), "--mcap", str(path)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    # Interrupt once the run is under way: its first chunk is written.
    wait_for_chunks(p, path, 1)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=30)
    assert p.returncode == 1 and "interrupted by a signal" in err, err
    rows = history(tmp_path / "out" / "history.csv")
    assert 1 < len(rows) < 201, "stopped midway"
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary.statistics.message_count == len(rows) * len(TOPICS)
    with AnyReader([path]) as reader:
        assert sum(1 for _ in reader.messages()) == len(rows) * len(TOPICS)


def test_sigterm_finishes_the_file_of_the_node(rkforge_ros_bin, tmp_path):
    scene = small_block(tmp_path, end="0.015")
    path = tmp_path / "term.mcap"
    # 0.015 s of simulation at 0.003 simulated seconds per second: about 5 s of wall time.
    p = start_node(rkforge_ros_bin, scene, 152, "--record", str(path),
                   "--real-time-factor", "0.003")
    # Wait for the start line (DDS is up, the run begins), then for about 30 samples.
    start = p.stderr.readline()
    assert start.startswith("rkforge-ros: scene"), start
    time.sleep(1.5)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=30)
    err = start + err
    assert p.returncode == 0, err
    assert "stopped by a signal" in err
    msgs = decoded(path)
    clocks = [m for topic, _, m in msgs if topic == "/clock"]
    assert 3 <= len(clocks) < 101
    assert len(msgs) == len(clocks) * len(TOPICS)
    summary = json.loads(metadata(path)["rkforge_summary"]["summary_json"])
    assert summary["status"] == "stopped" and "stopped by a signal" in summary["error"]
    assert summary["ros"]["samples_published"] == len(clocks)


def test_a_killed_process_leaves_a_file_readable_to_its_last_chunk(rkforge_bin, tmp_path):
    scene = small_block(tmp_path, end="0.03", particles="[21, 21]")
    path = tmp_path / "killed.mcap"
    p = subprocess.Popen([rkforge_bin, "run", str(scene), "--no-frames", "--quiet",
                          "--out", str(tmp_path / "out"), "--mcap", str(path)],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    # A chunk is closed after the sample that brings it to 512 KiB (or after 1 s of wall
    # time), so it holds whole samples; the whole run makes about four.
    wait_for_chunks(p, path, 1)
    p.kill()
    p.wait()
    with open(path, "rb") as f:
        with pytest.raises(Exception):
            make_reader(f).get_summary().statistics  # no summary, no footer
    schemas, channels, messages = {}, {}, []
    with open(path, "rb") as f:
        try:
            for r in StreamReader(f, emit_chunks=False).records:
                if isinstance(r, Schema):
                    schemas[r.id] = r
                elif isinstance(r, Channel):
                    channels[r.id] = r
                elif isinstance(r, Message):
                    messages.append(r)
        except (McapError, EOFError, struct.error, ValueError):
            pass  # the unfinished chunk at the end
    assert messages, "no complete chunk"
    factory = DecoderFactory()
    clocks = 0
    for m in messages:
        ch = channels[m.channel_id]
        sc = schemas[ch.schema_id]
        msg = factory.decoder_for(ch.message_encoding, sc)(m.data)
        if ch.topic == "/clock":
            clocks += 1
            assert msg.clock.sec * 10**9 + msg.clock.nanosec == m.log_time
        if ch.topic == "/rkforge/tools":
            assert all(math.isfinite(v) for v in msg.effort)
    # Whole samples only: every topic of every sample up to the last complete chunk.
    assert len(messages) == clocks * len(TOPICS)
    times = [m.log_time for m in messages]
    assert times == sorted(times)


def test_the_die_fill_topic_follows_the_wheels_cavity_corners(rkforge_bin, tmp_path):
    """The wheel forging's die fill read from its recording (both readers' decoder:
    mcap-ros2-support): per tool the contact fraction of history.csv; per fill point the
    filling time, NaN until the sample at which history.csv's `filled` column turns 1, then
    the summary's `filled_s` and `filled_stroke_m`."""
    scene = tmp_path / "wheel.toml"
    scene.write_text((ROOT / "scenes" / "wheel_forging.toml").read_text())
    out, path = tmp_path / "out", tmp_path / "wheel.mcap"
    rows = run_history(rkforge_bin, scene, out, "--mcap", str(path), "--set", "workpiece.particles=[11,11]")
    tools = json.loads((out / "summary.json").read_text())["tools"]
    fill = [(t, m) for topic, t, m in decoded(path) if topic == "/rkforge/die_fill"]
    assert [t for t, _ in fill] == [ns(r["time_s"]) for r in rows]
    points = [f"{t['name']}.{p['name']}" for t in tools for p in t["fill_points"]]
    final = {f"{t['name']}.{p['name']}": p for t in tools for p in t["fill_points"]}
    assert len(points) == 4
    for (_, m), row in zip(fill, rows):
        assert list(m.tools) == ["die", "punch"] and list(m.points) == points
        assert list(m.contact_fraction) == [row["die.contact_fraction"], row["punch.contact_fraction"]]
        for k, name in enumerate(points):
            filled = row[f"{name}.filled"] == 1.0
            assert filled != math.isnan(m.filled_time[k]), (name, row["time_s"])
            if filled:
                assert m.filled_time[k] == final[name]["filled_s"]
                assert m.filled_stroke[k] == final[name]["filled_stroke_m"]
    assert max(r["punch.contact_fraction"] for r in rows) > 0.2


def test_a_hot_scene_records_the_temperature_as_a_point_cloud_field(rkforge_bin, tmp_path):
    """The hot upsetting's recording, read by rosbags: the workpiece's PointCloud2 has a
    sixth float32 field `temperature` (degrees C, 24 bytes a point); at each sample the
    particles' temperatures (smoothed from the points) lie between the dies' 250 C and
    history.csv's largest point temperature, and the die chill shows by the end."""
    scene = tmp_path / "hot.toml"
    scene.write_text((ROOT / "scenes" / "hot_upsetting.toml").read_text())
    out, path = tmp_path / "out", tmp_path / "hot.mcap"
    rows = run_history(rkforge_bin, scene, out, "--mcap", str(path), "--set", "workpiece.particles=[5,13]",
                       "--set", "time.end_s=0.1")
    with AnyReader([path]) as reader:
        conns = [c for c in reader.connections if c.topic == "/rkforge/workpiece"]
        clouds = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(connections=conns)]
    assert len(clouds) == len(rows) > 5
    for cloud, row in zip(clouds, rows):
        assert [f.name for f in cloud.fields] == ["x", "y", "z", "plastic_strain", "von_mises", "temperature"]
        assert cloud.point_step == 24 and cloud.fields[5].offset == 20
        data = bytes(cloud.data)
        temps = [struct.unpack_from("<f", data, k * 24 + 20)[0] for k in range(cloud.width)]
        assert cloud.width == 65
        assert 250.0 < min(temps) and max(temps) <= row["thermal.temperature_max_c"] + 1e-3
    assert min(temps) < 1150.0


def test_the_energy_topic_closes_the_account_of_an_impact(rkforge_bin, tmp_path):
    """The energy account of a coarse Taylor bar (a copper bar at 227 m/s on a rigid wall),
    read from its recording: it starts with the bar's kinetic energy (240 J), which the
    impact turns into plastic work (96 % of it); kinetic + internal - contact work stays at
    the initial energy (measured within 0.01 %); the fixed wall delivers no work and its
    penalty contact only takes energy (4 %); the last figures are the run's summary."""
    scene = tmp_path / "taylor_coarse.toml"
    scene.write_text((ROOT / "scenes" / "taylor_bar.toml").read_text())
    out, path = tmp_path / "out", tmp_path / "taylor.mcap"
    rows = run_history(rkforge_bin, scene, out, "--mcap", str(path),
                       "--set", "workpiece.particles=[6,17]")
    summary = json.loads((out / "summary.json").read_text())["energy"]
    energy = [(t, m) for topic, t, m in decoded(path) if topic == "/rkforge/energy"]
    assert [t for t, _ in energy] == [ns(r["time_s"]) for r in rows]
    initial = summary["initial_J"]
    assert initial > 0
    first, last = energy[0][1], energy[-1][1]
    assert first.kinetic == first.initial == initial
    assert (first.internal, first.contact_work, first.tool_work) == (0.0, 0.0, 0.0)
    for _, e in energy:
        assert e.initial == initial
        assert e.internal == e.elastic + e.plastic
        assert e.kinetic + e.internal - e.contact_work == pytest.approx(initial, rel=1e-3)
        assert e.tool_work == 0.0, "the wall is fixed: it delivers no work"
        # The contact interface only takes energy (here: the penalty's losses).
        assert e.contact_work <= 1e-9 * initial
    plastic = [e.plastic for _, e in energy]
    assert plastic == sorted(plastic), "plastic work is dissipated, never returned"
    assert last.plastic > 0.9 * initial, "the impact turns the kinetic energy into plastic work"
    assert last.kinetic < 0.01 * initial
    # The last sample is the end of the run: the summary's figures, bit for bit.
    assert (last.initial, last.kinetic, last.elastic, last.plastic, last.internal,
            last.contact_work, last.tool_work) == (
        summary["initial_J"], summary["kinetic_J"], summary["elastic_J"], summary["plastic_J"],
        summary["internal_J"], summary["contact_J"], summary["tool_work_J"])


def test_the_foxglove_layout_shows_recorded_topics_and_fields(recorded):
    """The shipped layout's panels read topics and fields that a recording has."""
    _, path, _, _, _ = recorded
    layout = json.loads((ROOT / "ros_node" / "foxglove" / "rkforge_layout.json").read_text())
    panels = layout["configById"]

    def leaves(node):
        return [node] if isinstance(node, str) else leaves(node["first"]) + leaves(node["second"])

    assert sorted(leaves(layout["layout"])) == sorted(panels)
    last = {topic: m for topic, _, m in decoded(path)}
    view = panels["3D!rkforge"]
    assert view["followTf"] == "rkforge" == last["/rkforge/workpiece"].header.frame_id
    assert set(view["topics"]) == {"/rkforge/workpiece", "/rkforge/tool_markers"}
    fields = [f.name for f in last["/rkforge/workpiece"].fields]
    assert view["topics"]["/rkforge/workpiece"]["colorField"] == "plastic_strain" in fields
    plots = [p for name, p in panels.items() if name.startswith("Plot!")]
    paths = [p["value"] for plot in plots for p in plot["paths"]]
    paths += [plot["xAxisPath"]["value"] for plot in plots if plot["xAxisVal"] == "custom"]
    assert "/rkforge/tools.position[0]" in paths
    assert "/rkforge/energy.internal" in paths
    for p in paths:
        topic, field = p.split(".", 1)
        if "[" in field:
            name, index = field.rstrip("]").split("[")
            value = getattr(last[topic], name)[int(index)]
        else:
            value = getattr(last[topic], field)
        assert isinstance(value, float), p


# A 3D scene's topics: a wrench per plane tool, no die fill and no laps (2D only).
TOPICS_3D = {
    "/rkforge/wall/wrench": "geometry_msgs/msg/WrenchStamped",
    "/rkforge/ram/wrench": "geometry_msgs/msg/WrenchStamped",
    "/rkforge/tools": "sensor_msgs/msg/JointState",
    "/rkforge/workpiece": "sensor_msgs/msg/PointCloud2",
    "/rkforge/tool_markers": "visualization_msgs/msg/MarkerArray",
    "/rkforge/energy": "rkforge_msgs/msg/Energy",
    "/rkforge/outputs": "rkforge_msgs/msg/Outputs",
    "/clock": "rosgraph_msgs/msg/Clock",
}


@pytest.fixture(scope="module", params=["zstd", "none"])
def recorded_3d(request, rkforge_bin, tmp_path_factory):
    """A 3D run with --mcap: the coarse quarter bar upset between its wall and a ram
    (ros_peer.upset_bar_3d), in the chunk compression of the parameter: (history rows, MCAP
    file, compression, output folder, scene file)."""
    d = tmp_path_factory.mktemp("mcap3d")
    scene = upset_bar_3d(d)
    path = d / "run3d.mcap"
    rows = run_history(rkforge_bin, scene, d / "out", "--mcap", str(path),
                       "--mcap-compression", request.param)
    return rows, path, request.param, d / "out", scene


def cloud_points(cloud):
    """The float32 fields of each point of a PointCloud2, as tuples in field order."""
    n = len(cloud.fields)
    data = bytes(cloud.data)
    return [struct.unpack_from(f"<{n}f", data, k * cloud.point_step) for k in range(cloud.width)]


def check_3d_against_history(msgs, rows, particles):
    """The messages of a 3D recording match its history rows: the forces in x, y and z, the
    joint states, the particles with three coordinates within the history's bounds, the
    tools' patches, the energy account, and the register's outputs bit for bit."""
    by_topic = {}
    for topic, log_time, m in msgs:
        by_topic.setdefault(topic, []).append((log_time, m))
    assert set(by_topic) == set(TOPICS_3D)
    for topic, seq in by_topic.items():
        assert [t for t, _ in seq] == [ns(r["time_s"]) for r in rows], topic
    for tool in ["wall", "ram"]:
        for (_, w), row in zip(by_topic[f"/rkforge/{tool}/wrench"], rows):
            f = w.wrench.force
            assert (f.x, f.y, f.z) == (row[f"{tool}.force_x_N"], row[f"{tool}.force_y_N"],
                                       row[f"{tool}.force_z_N"])
            assert w.header.frame_id == "rkforge"
    assert max(abs(r["ram.force_z_N"]) for r in rows) > 1e3, "the ram presses"
    for (_, js), row in zip(by_topic["/rkforge/tools"], rows):
        assert list(js.name) == ["wall", "ram"]
        for k, tool in enumerate(js.name):
            assert js.position[k] == row[f"{tool}.stroke_m"]
            assert js.velocity[k] == row[f"{tool}.velocity_m_per_s"]
            assert js.effort[k] == row[f"{tool}.force_N"]
    for (_, c), row in zip(by_topic["/rkforge/workpiece"], rows):
        assert [f.name for f in c.fields] == ["x", "y", "z", "plastic_strain", "von_mises"]
        assert (c.height, c.width, c.point_step) == (1, particles, 20)
        pts = cloud_points(c)
        for k, axis in enumerate("xyz"):
            assert min(p[k] for p in pts) == pytest.approx(row[f"workpiece.{axis}_min_m"], abs=1e-7)
            assert max(p[k] for p in pts) == pytest.approx(row[f"workpiece.{axis}_max_m"], abs=1e-7)
        assert max(p[3] for p in pts) <= row["workpiece.max_plastic_strain"] + 1e-7
    last = cloud_points(by_topic["/rkforge/workpiece"][-1][1])
    assert max(p[3] for p in last) > 0, "the upset bar has yielded"
    for (_, m), row in zip(by_topic["/rkforge/tool_markers"], rows):
        wall, ram = m.markers
        assert (wall.text, ram.text) == ("wall", "ram")
        assert [len(wall.points), len(ram.points)] == [5, 5]
        assert {p.z for p in wall.points} == {0.0}
        for p in ram.points:
            assert p.z == pytest.approx(0.0324 - row["ram.stroke_m"], abs=1e-15)
        assert {round(p.x, 12) for p in ram.points} == {
            round(row["workpiece.x_min_m"], 12), round(row["workpiece.x_max_m"], 12)}
    for (_, e), row in zip(by_topic["/rkforge/energy"], rows):
        for field, column in ENERGY.items():
            assert getattr(e, field) == row[f"energy.{column}"], field
    for (_, o), row in zip(by_topic["/rkforge/outputs"], rows):
        got = dict(zip(o.names, o.values))
        assert {c: got[c] for c in row} == row
        assert dict(zip(o.names, o.units))["ram.force_z_N"] == "N"
        assert "ram.peak_force_N" in set(got) - set(row)
    for (_, c), row in zip(by_topic["/clock"], rows):
        assert c.clock.sec * 10**9 + c.clock.nanosec == ns(row["time_s"])


def test_a_3d_recording_reads_back_with_the_mcap_reader(recorded_3d):
    rows, path, compression, out, _ = recorded_3d
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary.statistics.message_count == len(rows) * len(TOPICS_3D)
    expected = {"zstd": "zstd", "none": ""}[compression]
    assert all(ci.compression == expected for ci in summary.chunk_indexes)
    assert {c.topic: summary.schemas[c.schema_id].name
            for c in summary.channels.values()} == TOPICS_3D
    particles = json.loads((out / "summary.json").read_text())["particles"]
    check_3d_against_history(decoded(path), rows, particles)


def test_a_3d_recording_reads_back_with_rosbags(recorded_3d):
    rows, path, _, out, _ = recorded_3d
    msgs = []
    with AnyReader([path]) as reader:
        assert {c.topic: c.msgtype for c in reader.connections} == TOPICS_3D
        for c, log_time, raw in reader.messages():
            msgs.append((c.topic, log_time, reader.deserialize(raw, c.msgtype)))
    msgs.sort(key=lambda m: (m[1], list(TOPICS_3D).index(m[0])))
    particles = json.loads((out / "summary.json").read_text())["particles"]
    check_3d_against_history(msgs, rows, particles)


def test_a_3d_file_holds_its_scene_and_summary(recorded_3d):
    rows, path, compression, out, scene = recorded_3d
    meta = metadata(path)
    run = meta["rkforge"]
    assert (run["scene"], run["kinematics"], run["integration"]) == ("taylor_bar_3d", "3d", "q2")
    assert (run["resolution"], run["resolution_key"]) == ("2x1x8", "workpiece.cells")
    assert (run["writer"], run["compression"]) == ("rkforge run", compression)
    assert json.loads(run["time"])["end_s"] == 10.0e-6
    assert meta["rkforge_summary"] == {"summary_json": (out / "summary.json").read_text()}
    summary = json.loads(meta["rkforge_summary"]["summary_json"])
    assert summary["status"] == "ok" and summary["kinematics"] == "3d"
    assert summary["end_time_s"] == rows[-1]["time_s"]
    assert attachments(path) == {scene.name: ("application/toml", scene.read_bytes())}
    last = [m for topic, _, m in decoded(path) if topic == "/rkforge/outputs"][-1]
    got = dict(zip(last.names, last.values))
    for tool in summary["tools"]:
        assert got[f"{tool['name']}.peak_force_N"] == tool["peak_force_N"]
    assert got["workpiece.height_m"] == summary["workpiece"]["height_m"]


def test_the_node_records_the_3d_run_as_rkforge_run_does(recorded_3d, rkforge_ros_bin, tmp_path):
    rows, path, compression, run_out, _ = recorded_3d
    scene = upset_bar_3d(tmp_path)
    out = tmp_path / "node3d.mcap"
    p = start_node(rkforge_ros_bin, scene, 153, "--record", str(out),
                   "--record-compression", compression)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 0, err
    assert f"recorded {out}" in err

    def raw(f):
        with open(f, "rb") as fh:
            return [(c.topic, m.log_time, m.data) for _, c, m in make_reader(fh).iter_messages()]

    assert raw(out) == raw(path)
    meta = metadata(out)
    assert (meta["rkforge"]["writer"], meta["rkforge"]["kinematics"]) == ("rkforge-ros", "3d")
    summary = json.loads(meta["rkforge_summary"]["summary_json"])
    assert summary["status"] == "ok" and summary["ros"]["samples_published"] == len(rows)
    run = json.loads((run_out / "summary.json").read_text())
    volatile = ("wall_s", "stage_seconds", "us_per_particle_step", "ros")
    assert {k: v for k, v in summary.items() if k not in volatile} == \
        {k: v for k, v in run.items() if k not in volatile}


def test_a_hot_3d_scene_records_the_temperature(rkforge_bin, tmp_path):
    """The OFHC bar in 3D (adiabatic heating): its cloud has the `temperature` field, the
    particles' temperatures (smoothed from the points) between the start's 22 C and
    history.csv's largest point temperature, warmer at the end than at the start."""
    scene = tmp_path / "ofhc3d.toml"
    scene.write_text(scene_variant("taylor_ofhc_3d.toml", {"cells = [8, 4, 48]": "cells = [2, 1, 8]",
                                                           "end_s = 100.0e-6": "end_s = 10.0e-6"}))
    out, path = tmp_path / "out", tmp_path / "ofhc3d.mcap"
    rows = run_history(rkforge_bin, scene, out, "--mcap", str(path))
    clouds = [m for topic, _, m in decoded(path) if topic == "/rkforge/workpiece"]
    assert len(clouds) == len(rows) == 11
    for cloud, row in zip(clouds, rows):
        assert [f.name for f in cloud.fields][5:] == ["temperature"]
        assert cloud.point_step == 24
        temps = [p[5] for p in cloud_points(cloud)]
        assert 22.0 - 1e-4 <= min(temps) and max(temps) <= row["thermal.temperature_max_c"] + 1e-3
    assert max(temps) > 30.0, "the foot heats"


def test_sigint_finishes_the_file_of_a_3d_run(rkforge_bin, tmp_path):
    scene = small_bar_3d(tmp_path, cells="[4, 2, 24]", end="80.0e-6")
    path = tmp_path / "int3d.mcap"
    p = subprocess.Popen([rkforge_bin, "run", str(scene), "--no-frames", "--quiet",
                          "--out", str(tmp_path / "out"), "--mcap", str(path)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wait_for_chunks(p, path, 1)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=30)
    assert p.returncode == 1 and "interrupted by a signal" in err, err
    rows = history(tmp_path / "out" / "history.csv")
    assert 1 < len(rows) < 81, "stopped midway"
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    assert summary.statistics.message_count == len(rows) * 7
    meta = metadata(path)
    s = json.loads(meta["rkforge_summary"]["summary_json"])
    assert s["status"] == "stopped" and "interrupted by a signal" in s["error"]
    assert s == json.loads((tmp_path / "out" / "summary.json").read_text())


def test_a_3d_forging_run_records_its_forces_and_the_node_records_the_same(
        rkforge_bin, rkforge_ros_bin, tmp_path):
    """The rectangular block forged in 3D at press speed (mass-scaled, 1 mm of stroke):
    `rkforge run --mcap` records the anvil's and the ram's wrenches, the joint states and the
    register's outputs with the bits of history.csv, the ram's patch where its stroke puts
    it, every particle within the history's bounds; `rkforge.read_mcap` gives the history's
    tool columns back; and the node's own recording holds the same messages."""
    import rkforge

    scene = block_3d(tmp_path)
    path = tmp_path / "block3d.mcap"
    rows = run_history(rkforge_bin, scene, tmp_path / "out", "--mcap", str(path))
    assert len(rows) == 6
    particles = json.loads((tmp_path / "out" / "summary.json").read_text())["particles"]
    assert particles == 7 * 5 * 9
    by_topic = {}
    for topic, log_time, m in decoded(path):
        by_topic.setdefault(topic, []).append((log_time, m))
    tools = ["anvil", "ram"]
    assert set(by_topic) == {t.replace("wall", "anvil") for t in TOPICS_3D}
    for tool in tools:
        seq = by_topic[f"/rkforge/{tool}/wrench"]
        assert [t for t, _ in seq] == [ns(r["time_s"]) for r in rows]
        for (_, w), row in zip(seq, rows):
            f = w.wrench.force
            assert (f.x, f.y, f.z) == (row[f"{tool}.force_x_N"], row[f"{tool}.force_y_N"],
                                       row[f"{tool}.force_z_N"])
    for (_, js), row in zip(by_topic["/rkforge/tools"], rows):
        assert list(js.name) == tools
        assert list(js.position) == [row[f"{t}.stroke_m"] for t in tools]
        assert list(js.effort) == [row[f"{t}.force_N"] for t in tools]
    for (_, o), row in zip(by_topic["/rkforge/outputs"], rows):
        got = dict(zip(o.names, o.values))
        assert {c: got[c] for c in row} == row
    for (_, m), row in zip(by_topic["/rkforge/tool_markers"], rows):
        anvil, ram = m.markers
        assert {p.z for p in anvil.points} == {0.0}
        for p in ram.points:
            assert p.z == pytest.approx(0.040 - row["ram.stroke_m"], abs=1e-15)
    for (_, c), row in zip(by_topic["/rkforge/workpiece"], rows):
        assert c.width == particles
        pts = cloud_points(c)
        for k, axis in enumerate("xyz"):
            assert min(p[k] for p in pts) == pytest.approx(row[f"workpiece.{axis}_min_m"], abs=1e-7)
            assert max(p[k] for p in pts) == pytest.approx(row[f"workpiece.{axis}_max_m"], abs=1e-7)
    last = rows[-1]
    assert last["ram.stroke_m"] == pytest.approx(1e-3, rel=1e-9) and last["ram.force_z_N"] > 5e4
    rec = rkforge.read_mcap(path)
    columns = [f"{t}.{c}" for t in tools for c in ("stroke_m", "force_N", "force_z_N")]
    for c in columns:
        assert list(rec.history[c]) == [r[c] for r in rows], c
    node_path = tmp_path / "node.mcap"
    p = start_node(rkforge_ros_bin, scene, 154, "--record", str(node_path))
    _, err = p.communicate(timeout=300)
    assert p.returncode == 0, err

    def raw(f):
        with open(f, "rb") as fh:
            return [(c.topic, m.log_time, m.data) for _, c, m in make_reader(fh).iter_messages()]

    assert raw(node_path) == raw(path)
