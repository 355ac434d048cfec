"""`rkforge-ros` seen by an independent ROS 2 peer: Cyclone DDS (PyPI `cyclonedds`, the DDS
under rmw_cyclonedds_cpp) with the standard DDS type names, on 2D and 3D scenes. Each test uses
its own ROS domain."""
import json
import math
import struct
import subprocess
import time

import pytest

from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from ros_peer import (Clock, DescribeParametersReply, DescribeParametersRequest, Energy,
                      Float64, GetParametersReply, GetParametersRequest,
                      GetSimulationStateReply, GetSimulationStateRequest, JointState,
                      SetSimulationStateReply, SetSimulationStateRequest, SimulationState,
                      ListParametersReply, ListParametersRequest, Outputs, Parameter, Peer,
                      PointCloud2,
                      ServiceClient, SetParametersReply, SetParametersRequest, SimulateSteps,
                      Simulator, WrenchStamped,
                      block_3d, parameter_value, qos, quit_node, run_history, running_node,
                      small_block,
                      stamp_ns, start_node, take, upset_bar_3d, wait_matched,
                      wait_readers_matched, wait_until)

NS = "/rkforge"


class LockstepController:
    """Answers each new joint state (by stamp) once with the velocities `command(k, js)` for
    the `commanded` tools (the block's top and bottom), reads the wrenches of the `tools`,
    and keeps what it read."""

    def __init__(self, domain, command, tools=("top", "bottom"), commanded=("top", "bottom")):
        self.peer = Peer(domain)
        # Transient local, as the node offers them: samples published before a reader
        # matched still reach it.
        self.tools = self.peer.reader(f"{NS}/tools", JointState, latched=True)
        self.wrenches = {n: self.peer.reader(f"{NS}/{n}/wrench", WrenchStamped, latched=True)
                         for n in tools}
        self.clock = self.peer.reader("/clock", Clock, latched=True)
        self.energy = self.peer.reader(f"{NS}/energy", Energy, latched=True)
        self.outputs = self.peer.reader(f"{NS}/outputs", Outputs, latched=True)
        self.cloud = self.peer.reader(f"{NS}/workpiece", PointCloud2, reliable=False)
        self.commanded = list(commanded)
        self.cmd = {n: self.peer.writer(f"{NS}/{n}/velocity_cmd", Float64) for n in commanded}
        self.command = command
        self.states = {}
        self.wrench = {n: {} for n in tools}
        self.clouds = {}
        self.clocks = set()
        self.energies = {}
        self.register = {}

    def serve(self, node, timeout=120):
        t0 = time.monotonic()
        # Before its first answer the controller waits until every reader found the node
        # (the node holds the first sample until then): nothing published is missed.
        wait_readers_matched([self.tools, self.clock, self.energy, self.outputs,
                              *self.wrenches.values()])
        while node.poll() is None:
            assert time.monotonic() - t0 < timeout, "the lockstep run did not finish"
            for js in take(self.tools, 50):
                s = stamp_ns(js.header)
                if s in self.states:
                    continue  # republished while the node waits
                self.states[s] = js
                for name, v in zip(self.commanded, self.command(len(self.states) - 1, js)):
                    wait_matched(self.cmd[name])
                    self.cmd[name].write(Float64(v))
            for n, r in self.wrenches.items():
                for w in take(r, 50):
                    self.wrench[n][stamp_ns(w.header)] = w
            for c in take(self.cloud, 50):
                self.clouds[stamp_ns(c.header)] = c
            for c in take(self.clock, 50):
                self.clocks.add(c.clock.sec * 10**9 + c.clock.nanosec)
            for e in take(self.energy, 50):
                self.energies[stamp_ns(e.header)] = e
            for o in take(self.outputs, 50):
                self.register[stamp_ns(o.header)] = o
            time.sleep(0.001)
        return node.communicate(timeout=10)


def test_a_cyclone_dds_peer_reads_the_topics_with_history_values(rkforge_bin, rkforge_ros_bin,
                                                                  tmp_path):
    scene = small_block(tmp_path)
    rows = run_history(rkforge_bin, scene, tmp_path / "out")
    # Commanding the scene's own velocity (10 m/s) in lockstep must reproduce the run exactly.
    ctl = LockstepController(161, lambda k, js: (10.0, 10.0))
    node = start_node(rkforge_ros_bin, scene, 161, "--lockstep")
    _, err = ctl.serve(node)
    assert node.returncode == 0, err
    stamps = sorted(ctl.states)
    assert stamps == [round(r["time_s"] * 1e9) for r in rows]
    for s, row in zip(stamps, rows):
        js = ctl.states[s]
        assert list(js.name) == ["top", "bottom"]
        assert js.header.frame_id == "rkforge"
        for k, tool in enumerate(js.name):
            assert js.position[k] == row[f"{tool}.stroke_m"]
            assert js.velocity[k] == row[f"{tool}.velocity_m_per_s"]
            assert js.effort[k] == row[f"{tool}.force_N"]
    for tool, got in ctl.wrench.items():
        assert set(got) == set(stamps), f"{tool}: reliable wrenches are all delivered"
        for s, row in zip(stamps, rows):
            assert got[s].wrench.force.x == row[f"{tool}.force_x_N"]
            assert got[s].wrench.force.y == row[f"{tool}.force_y_N"]
    assert ctl.clocks == set(stamps)
    assert set(ctl.energies) == set(stamps), "reliable energy accounts are all delivered"
    for s, row in zip(stamps, rows):
        e = ctl.energies[s]
        assert e.header.frame_id == "rkforge"
        assert (e.kinetic, e.elastic, e.plastic, e.internal, e.contact_work, e.tool_work) == (
            row["energy.kinetic_J"], row["energy.elastic_J"], row["energy.plastic_J"],
            row["energy.internal_J"], row["energy.contact_J"], row["energy.tool_work_J"])
    # The register's outputs: every history column under its own name, the same bits,
    # with its unit beside it.
    assert set(ctl.register) == set(stamps), "reliable outputs are all delivered"
    for s, row in zip(stamps, rows):
        o = ctl.register[s]
        got = dict(zip(o.names, o.values))
        assert {c: got[c] for c in row} == row
        assert dict(zip(o.names, o.units))["top.pressure_mean_Pa"] == "Pa"
    assert ctl.clouds, "no point cloud arrived"
    by_stamp = dict(zip(stamps, rows))
    for s, c in ctl.clouds.items():
        row = by_stamp[s]
        assert [f.name for f in c.fields] == ["x", "y", "z", "plastic_strain", "von_mises"]
        assert (c.width, c.point_step) == (64, 20)
        data = bytes(c.data)
        pts = [struct.unpack_from("<5f", data, 20 * k) for k in range(c.width)]
        assert min(p[1] for p in pts) == pytest.approx(row["workpiece.y_min_m"], abs=1e-7)
        assert max(p[1] for p in pts) == pytest.approx(row["workpiece.y_max_m"], abs=1e-7)
        assert max(p[3] for p in pts) >= 0.0


def test_a_late_reader_gets_the_samples_published_before_it_joined(rkforge_ros_bin, tmp_path):
    """Wrenches, joint states, markers and /clock are transient local (keep last 10): a
    reader that matches after samples were published still receives them, whereas a volatile
    reader created at the same moment only gets later ones."""
    scene = small_block(tmp_path)
    # 20 samples 0.5 s of wall time apart: readers created after the second sample match
    # long before the first one leaves the publisher's last 10.
    node = start_node(rkforge_ros_bin, scene, 169, "--real-time-factor", "0.0003")
    try:
        peer = Peer(169)
        first = peer.reader("/clock", Clock)
        seen = []
        wait_until(lambda: seen.extend(c.clock.nanosec for c in take(first)) or
                   any(n >= 150_000 for n in seen) or node.poll() is not None, 60,
                   "the second sample")
        assert node.poll() is None, "the run ended before the late readers joined"
        known = max(seen)
        latched = peer.reader(f"{NS}/top/wrench", WrenchStamped, latched=True)
        volatile = peer.reader(f"{NS}/top/wrench", WrenchStamped)
        wait_readers_matched([latched, volatile])
        got = {"latched": [], "volatile": []}
        wait_until(lambda: got["latched"].extend(stamp_ns(w.header) for w in take(latched)) or
                   got["volatile"].extend(stamp_ns(w.header) for w in take(volatile)) or
                   (got["latched"] and got["volatile"]) or node.poll() is not None, 60,
                   "wrenches on both readers")
        assert node.poll() is None, "the run ended before the late readers got a sample"
        assert min(got["latched"]) == 0, "the latched reader got the first sample"
        assert known in got["latched"]
        assert min(got["volatile"]) > known, "a volatile reader only gets later samples"
    finally:
        node.terminate()
        node.communicate(timeout=30)


def test_parameters_are_listed_read_set_and_refused_with_a_reason(rkforge_ros_bin, tmp_path):
    """The run-time settings through the standard rcl_interfaces services, called as an
    rmw_cyclonedds_cpp client calls them: a lockstep run waits (nobody commands) until the
    peer switches lockstep off, then runs to its end."""
    scene = small_block(tmp_path)
    with running_node(rkforge_ros_bin, scene, 170, "--lockstep") as node:
        peer = Peer(170)
        base = "/rkforge/rkforge"
        list_ = ServiceClient(peer, f"{base}/list_parameters", ListParametersRequest,
                              ListParametersReply)
        get = ServiceClient(peer, f"{base}/get_parameters", GetParametersRequest,
                            GetParametersReply)
        set_ = ServiceClient(peer, f"{base}/set_parameters", SetParametersRequest,
                             SetParametersReply)
        describe = ServiceClient(peer, f"{base}/describe_parameters", DescribeParametersRequest,
                                 DescribeParametersReply)
        names = ["lockstep", "publish_rate", "real_time_factor"]
        assert list(list_.call([], 0).names) == names

        def values():
            got = get.call(names + ["no_such"]).values
            assert [v.type for v in got] == [1, 3, 3, 0]
            return got[0].bool_value, got[1].double_value, got[2].double_value

        # One sample per history interval (0.15 ms) of the scene; 0 = as fast as possible.
        assert values() == (True, pytest.approx(1 / 0.15e-3), 0.0)
        d = {x.name: x for x in describe.call(names).descriptors}
        assert d["publish_rate"].read_only and not d["lockstep"].read_only
        assert d["real_time_factor"].type == 3
        refused = set_.call([Parameter("real_time_factor", parameter_value(-1.0)),
                             Parameter("publish_rate", parameter_value(100.0)),
                             Parameter("lockstep", parameter_value(2.0)),
                             Parameter("speed", parameter_value(1.0))]).results
        assert [r.successful for r in refused] == [False] * 4
        assert "real_time_factor -1: must be finite and >= 0" in refused[0].reason
        assert "publish_rate is read only" in refused[1].reason
        assert "lockstep is a bool" in refused[2].reason
        assert "no parameter `speed`" in refused[3].reason
        assert node.poll() is None, "the node lives on"
        assert values() == (True, pytest.approx(1 / 0.15e-3), 0.0)
        ok = set_.call([Parameter("real_time_factor", parameter_value(0.5))]).results
        assert [(r.successful, r.reason) for r in ok] == [(True, "")]
        assert values()[2] == 0.5
        assert node.poll() is None, "lockstep holds the run: nobody commands"
        ok = set_.call([Parameter("real_time_factor", parameter_value(0.0)),
                        Parameter("lockstep", parameter_value(False))]).results
        assert [r.successful for r in ok] == [True, True]
        _, err = node.communicate(timeout=120)
        assert node.returncode == 0, err
        assert "published 21 samples" in err


def call_with_a_late_reply_reader(peer, service, request, reply, *fields):
    """Call `service` as a client whose reply reader matches only after the node has taken
    the request and had a second to answer; the reply."""
    writer = DataWriter(peer.dp, Topic(peer.dp, f"rq{service}Request", request), qos=qos(True))
    wait_matched(writer)
    writer.write(request(ServiceClient.GUID, 1, *fields))
    assert writer.wait_for_acks(duration(seconds=60)), "the node never took the request"
    time.sleep(1.0)
    reader = DataReader(peer.dp, Topic(peer.dp, f"rr{service}Reply", reply), qos=qos(True))
    got = []
    wait_until(lambda: got.extend(r for r in take(reader) if r.seq == 1) or got, 60,
               f"the reply of {service} to a client whose reply reader matched late")
    return got[0]


def test_a_reply_reaches_a_client_whose_reply_reader_matches_after_its_request(
        rkforge_ros_bin, tmp_path):
    """A client knows the service is there when its own endpoints have matched the node's
    (rclcpp's wait_for_service); on a loaded machine the node's reply writer can match the
    client's reply reader only later, and a volatile writer never delivers what it wrote
    before. The node holds the reply until the reader matches, also the last one (quitting)
    before it ends."""
    scene = small_block(tmp_path)
    with running_node(rkforge_ros_bin, scene, 175, "--lockstep") as node:
        peer = Peer(175)
        r = call_with_a_late_reply_reader(peer, f"{NS}/get_simulation_state",
                                          GetSimulationStateRequest, GetSimulationStateReply, 0)
        assert (r.state.state, r.result.result) == (Simulator.PLAYING, 1)
        assert node.poll() is None
        r = call_with_a_late_reply_reader(peer, f"{NS}/set_simulation_state",
                                          SetSimulationStateRequest, SetSimulationStateReply,
                                          SimulationState(Simulator.QUITTING))
        assert (r.result.result, r.result.error_message) == (1, "")
        _, err = node.communicate(timeout=60)
        assert node.returncode == 0, err
        assert "has not matched" not in err


def test_simulation_interfaces_pause_step_and_refuse_with_standard_codes(rkforge_ros_bin,
                                                                          tmp_path):
    """The peer calls the simulation_interfaces services with their standard types. The
    block forging has a fixed step of 1 us, so N steps from a sample move the time by N us;
    in lockstep with nobody commanding, playing holds the first sample (no race)."""
    scene = small_block(tmp_path)
    with running_node(rkforge_ros_bin, scene, 171, "--lockstep", "--hold-at-end") as node:
        peer = Peer(171)
        sim = Simulator(peer)
        features = sim.features.call(0).features
        # Reset, state getting, setting and pausing, single and multiple steps, the
        # SimulateSteps action.
        assert sorted(features.features) == [20, 24, 25, 26, 31, 32, 33]
        assert sim.state() == sim.PLAYING
        assert sim.set(sim.PAUSED) == (1, "")
        assert sim.state() == sim.PAUSED
        # A late joiner sees the held time on /clock (transient local).
        clock = peer.reader("/clock", Clock, latched=True)
        tools = peer.reader(f"{NS}/tools", JointState, latched=True)
        clocks = []
        wait_until(lambda: clocks.extend(stamp_ns(c) for c in take(clock)) or clocks, 60,
                   "/clock while paused")
        assert set(clocks) == {0}
        stamps = []

        def stamp_seen(ns):
            wait_until(lambda: stamps.extend(stamp_ns(js.header) for js in take(tools)) or
                       ns in stamps, 60, f"a joint state at {ns} ns")

        assert sim.step(10) == (1, "")
        stamp_seen(10_000)
        # Across the sample time 150 us: 145 steps more end at 155 us.
        assert sim.step(145) == (1, "")
        stamp_seen(155_000)
        assert stamps[-1] == 155_000 and sim.state() == sim.PAUSED
        # Refused with the standard codes, and the node lives on.
        assert sim.step(0)[0] == 4  # RESULT_OPERATION_FAILED
        assert sim.set(9) == (4, "unknown simulation state 9")
        assert sim.set(4)[0] == 0  # STATE_NO_WORLD: RESULT_FEATURE_UNSUPPORTED
        assert sim.set(sim.PAUSED)[0] == 101  # ALREADY_IN_TARGET_STATE
        assert sim.reset(1)[0] == 0  # SCOPE_TIME alone: RESULT_FEATURE_UNSUPPORTED
        assert sim.set(sim.PLAYING) == (1, "")
        code, message = sim.step(1)
        assert (code, message) == (4, "StepSimulation needs the simulation paused")
        assert node.poll() is None
        # Stopped: back to the initial state, held.
        assert sim.set(sim.STOPPED) == (1, "")
        assert sim.state() == sim.STOPPED
        stamp_seen(0)
        assert stamps[-1] == 0
        quit_node(sim, node)


class StampWatch:
    """The joint-state stamps a latched reader has seen, to wait for one."""

    def __init__(self, peer):
        self.reader = peer.reader(f"{NS}/tools", JointState, latched=True)
        self.stamps = []

    def wait_for(self, ns):
        wait_until(lambda: self.stamps.extend(stamp_ns(js.header) for js in take(self.reader))
                   or ns in self.stamps, 60, f"a joint state at {ns} ns")
        return self.stamps[-1]


def feedback_of(action, goal, seen, steps):
    """Wait for the feedback of `goal` that reports `steps` steps completed (kept in `seen`,
    with the feedback of other goals); the feedback of `goal` so far."""
    def mine():
        return [f.feedback for f in seen if bytes(f.goal_id.uuid) == goal]

    wait_until(lambda: seen.extend(take(action.feedback)) or
               any(f.completed_steps == steps for f in mine()), 60,
               f"feedback of {steps} steps")
    return mine()


def test_simulate_steps_takes_exactly_n_steps_with_feedback(rkforge_ros_bin, tmp_path):
    """The SimulateSteps action, called as rclcpp's action client calls it over
    rmw_cyclonedds_cpp. The block forging has a fixed step of 1 us: a goal of N steps while
    paused ends SUCCEEDED with the time N us later, its feedback counting the steps. Goals it
    cannot carry out are accepted, then aborted with RESULT_OPERATION_FAILED and the reason,
    as StepSimulation refuses them; the node goes on."""
    scene = small_block(tmp_path)
    with running_node(rkforge_ros_bin, scene, 173, "--lockstep", "--hold-at-end") as node:
        peer = Peer(173)
        sim = Simulator(peer)
        action = SimulateSteps(peer)
        watch = StampWatch(peer)
        action.wait_ready()
        wait_readers_matched([watch.reader, action.status])
        assert 33 in sim.features.call(0).features.features  # STEP_SIMULATION_ACTION
        # Playing (lockstep holds the first sample: nobody commands).
        goal, accepted = action.send(10)
        assert accepted
        assert action.result(goal) == (action.ABORTED, 4,
                                       "SimulateSteps needs the simulation paused")
        assert sim.set(sim.PAUSED) == (1, "")
        goal, accepted = action.send(0)
        assert accepted
        assert action.result(goal) == (action.ABORTED, 4, "SimulateSteps needs at least one step")
        assert watch.wait_for(0) == 0
        seen = []
        # Across the sample time 150 us: 155 steps end at 155 us.
        goal, accepted = action.send(155)
        assert accepted
        assert action.result(goal) == (action.SUCCEEDED, 1, "")
        assert watch.wait_for(155_000) == 155_000
        fb = feedback_of(action, goal, seen, 155)
        assert fb[-1].remaining_steps == 0
        assert all(f.completed_steps + f.remaining_steps == 155 for f in fb)
        assert [f.completed_steps for f in fb] == sorted(f.completed_steps for f in fb)
        # The latched status topic has the goal's end.
        statuses = {}

        def status_seen():
            for array in take(action.status):
                statuses.update((bytes(s.goal_info.goal_id.uuid), s.status)
                                for s in array.status_list)
            return statuses.get(goal) == action.SUCCEEDED

        wait_until(status_seen, 60, "the goal's status SUCCEEDED")
        # A goal beyond the end time stops there: 2845 steps from 155 us to 3 ms.
        goal, _ = action.send(10**6)
        assert action.result(goal) == (
            action.ABORTED, 4, "stopped at the end time after 2845 of 1000000 steps")
        assert watch.wait_for(3_000_000) == 3_000_000
        assert feedback_of(action, goal, seen, 2845)[-1].remaining_steps == 10**6 - 2845
        goal, _ = action.send(1)
        assert action.result(goal) == (action.ABORTED, 4,
                                       "the run is at its end time: reset it before stepping")
        # A result request for a goal the node never had: STATUS_UNKNOWN.
        assert action.result(bytes(16))[0] == action.UNKNOWN
        assert sim.state() == sim.PAUSED and node.poll() is None
        quit_node(sim, node)


def test_a_simulate_steps_goal_is_canceled_after_the_step_under_way(rkforge_ros_bin, tmp_path):
    """A goal of a million steps is canceled once its feedback shows it under way: it ends
    CANCELED after k steps, the time k us later (fixed step of 1 us) and the last feedback
    at k; canceling it again answers ERROR_GOAL_TERMINATED, an unknown goal
    ERROR_UNKNOWN_GOAL_ID, and a further goal steps on from there."""
    # 2 s of press time at 10 mm/s per tool: a million steps deform the block little.
    scene = small_block(tmp_path, end="2.0")
    slow = ["--set", "tools.top.motion.velocity_m_per_s=0.01",
            "--set", "tools.bottom.motion.velocity_m_per_s=0.01"]
    with running_node(rkforge_ros_bin, scene, 174, "--lockstep", "--hold-at-end",
                      *slow) as node:
        peer = Peer(174)
        sim = Simulator(peer)
        action = SimulateSteps(peer)
        watch = StampWatch(peer)
        action.wait_ready()
        wait_readers_matched([watch.reader])
        assert sim.set(sim.PAUSED) == (1, "")
        assert watch.wait_for(0) == 0
        steps = 10**6
        goal, accepted = action.send(steps)
        assert accepted
        seen = []
        wait_until(lambda: seen.extend(take(action.feedback)) or seen, 60,
                   "feedback of the goal under way")
        assert bytes(seen[0].goal_id.uuid) == goal
        assert 0 < seen[0].feedback.completed_steps < steps
        assert action.cancel(goal) == (0, [goal])  # ERROR_NONE: the goal is canceling
        status, code, message = action.result(goal)
        assert (status, code) == (action.CANCELED, 4)
        assert message.startswith("canceled after ") and message.endswith(f" of {steps} steps")
        k = int(message.split()[2])
        assert seen[0].feedback.completed_steps <= k < steps
        fb = feedback_of(action, goal, seen, k)
        assert fb[-1].remaining_steps == steps - k
        assert watch.wait_for(k * 1000) == k * 1000
        assert action.cancel(goal) == (3, [])  # ERROR_GOAL_TERMINATED
        assert action.cancel(bytes(range(16))) == (2, [])  # ERROR_UNKNOWN_GOAL_ID
        goal, _ = action.send(10)
        assert action.result(goal) == (action.SUCCEEDED, 1, "")
        assert watch.wait_for((k + 10) * 1000) == (k + 10) * 1000
        assert node.poll() is None
        quit_node(sim, node)


def test_reset_gives_bit_identical_episodes(rkforge_bin, rkforge_ros_bin, tmp_path):
    """Two episodes after ResetSimulation (one reset at the end time, one in the middle of an
    episode) publish the same joint states, bit for bit, as a fresh `rkforge run`, paced
    from t = 0 again."""
    scene = small_block(tmp_path)
    rows = run_history(rkforge_bin, scene, tmp_path / "out")
    expected = [(round(r["time_s"] * 1e9), [r["top.stroke_m"], r["bottom.stroke_m"]],
                 [r["top.force_N"], r["bottom.force_N"]]) for r in rows]
    # 3 ms of simulation at 0.003 simulated seconds per second: 1 s per episode.
    with running_node(rkforge_ros_bin, scene, 172, "--hold-at-end",
                      "--real-time-factor", "0.003") as node:
        peer = Peer(172)
        sim = Simulator(peer)
        tools = peer.reader(f"{NS}/tools", JointState, latched=True)
        wait_readers_matched([tools])

        def play_to_end():
            got = []
            wait_until(lambda: got.extend(take(tools)) or sim.state() == sim.PAUSED, 120,
                       "the end of the episode")
            got.extend(take(tools))
            return got

        def states(got):
            return [(stamp_ns(js.header), list(js.position), list(js.effort)) for js in got]

        play_to_end()  # the first episode, from start-up: its beginning may precede the peer
        # A reset at the end time, while paused, then played.
        assert sim.reset() == (1, "")
        assert sim.state() == sim.PAUSED, "a reset keeps the state"
        assert sim.set(sim.PLAYING) == (1, "")
        first = states(play_to_end())
        # A reset in the middle of an episode, while playing: it plays on from t = 0.
        assert sim.reset() == (1, "")
        assert sim.set(sim.PLAYING) == (1, "")
        before = []
        wait_until(lambda: before.extend(take(tools)) or
                   any(stamp_ns(js.header) >= 1_500_000 for js in before), 60, "t = 1.5 ms")
        t0 = time.monotonic()
        assert sim.reset() == (1, "")
        assert sim.state() == sim.PLAYING
        got = before + play_to_end()
        # Paced from t = 0 again: 3 ms at 0.003 take 1 s of wall time (0.5 s if the pacing
        # went on from the time before the reset).
        assert time.monotonic() - t0 > 0.9
        restart = max(k for k, js in enumerate(got) if stamp_ns(js.header) == 0)
        second = states(got[restart:])
        assert first == expected
        assert second == expected
        assert sim.set(sim.PLAYING)[0] == 102  # at the end time: STATE_TRANSITION_ERROR
        quit_node(sim, node)


def test_the_stroke_follows_velocity_commands(rkforge_ros_bin, tmp_path):
    scene = small_block(tmp_path)

    def command(k, js):
        v = 4.0 if k < 10 else 1.5
        return v, 2.0 * v

    ctl = LockstepController(162, command)
    node = start_node(rkforge_ros_bin, scene, 162, "--lockstep")
    _, err = ctl.serve(node)
    assert node.returncode == 0, err
    states = [ctl.states[s] for s in sorted(ctl.states)]
    assert len(states) == 21
    dt = 0.15e-3
    for k in range(1, len(states)):
        v = 4.0 if k - 1 < 10 else 1.5
        top = states[k].position[0] - states[k - 1].position[0]
        bottom = states[k].position[1] - states[k - 1].position[1]
        assert top == pytest.approx(v * dt, rel=1e-9), k
        assert bottom == pytest.approx(2.0 * v * dt, rel=1e-9), k
        assert states[k].velocity[0] == v


def test_lockstep_runs_are_reproducible(rkforge_ros_bin, tmp_path):
    scene = small_block(tmp_path)

    def command(k, js):
        # A proportional force loop: the answer depends on the state read.
        f = -js.effort[0]
        return max(0.0, min(10.0, 10.0 * (2.6e8 - f) / 2.6e8 + 5.0)), 10.0

    runs = []
    for domain in [163, 164]:
        ctl = LockstepController(domain, command)
        node = start_node(rkforge_ros_bin, scene, domain, "--lockstep")
        _, err = ctl.serve(node)
        assert node.returncode == 0, err
        runs.append([(s, list(js.position), list(js.effort))
                     for s, js in sorted(ctl.states.items())])
    assert runs[0] == runs[1]
    assert len({round(p[0], 12) for _, p, _ in runs[0]}) > 10


def test_bad_commands_are_ignored_and_a_burst_does_not_stall(rkforge_ros_bin, tmp_path):
    scene = small_block(tmp_path, end="0.006")
    peer = Peer(165)
    tools = peer.reader(f"{NS}/tools", JointState)
    cmd = peer.writer(f"{NS}/top/velocity_cmd", Float64)
    # 0.006 s at 0.003 simulated s per wall s: about 2 s.
    node = start_node(rkforge_ros_bin, scene, 165, "--real-time-factor", "0.003")
    t0 = time.monotonic()
    wait_until(lambda: take(tools, 10) or node.poll() is not None, 20, "a joint state")
    assert node.poll() is None, "the run ended before the peer could join"
    wait_matched(cmd)
    for _ in range(2000):
        cmd.write(Float64(3.0))
    # Last, so that they are among the samples a reliable writer keeps (keep last 10).
    for v in [math.nan, math.inf, -math.inf]:
        cmd.write(Float64(v))
    # The peer goes away in the middle of the run.
    del cmd, tools, peer
    _, err = node.communicate(timeout=30)
    wall = time.monotonic() - t0
    assert node.returncode == 0, err
    assert "ignoring velocity command NaN m/s on /rkforge/top/velocity_cmd: not finite" in err
    assert "ignoring velocity command inf m/s" in err
    assert "ignoring velocity command -inf m/s" in err
    assert wall < 10, f"the run took {wall:.1f} s of wall time for about 2 s of pacing"


def test_the_stroke_of_a_paced_run_follows_a_command(rkforge_ros_bin, tmp_path):
    scene = small_block(tmp_path, end="0.006")
    peer = Peer(166)
    tools = peer.reader(f"{NS}/tools", JointState)
    cmd = peer.writer(f"{NS}/top/velocity_cmd", Float64)
    node = start_node(rkforge_ros_bin, scene, 166, "--real-time-factor", "0.003")
    got = []
    wait_until(lambda: got.extend(take(tools, 10)) or got or node.poll() is not None, 20,
               "a joint state")
    wait_matched(cmd)
    cmd.write(Float64(2.5))
    while node.poll() is None:
        got.extend(take(tools, 10))
        time.sleep(0.002)
    got.extend(take(tools, 10))
    _, err = node.communicate(timeout=10)
    assert node.returncode == 0, err
    late = [js for js in got if js.velocity[0] == 2.5]
    assert len(late) >= 3, "the command did not take over"
    assert got[-1].velocity[1] == 10.0, "the other tool keeps its scene velocity"
    for a, b in zip(late, late[1:]):
        dt = (stamp_ns(b.header) - stamp_ns(a.header)) * 1e-9
        assert b.position[0] - a.position[0] == pytest.approx(2.5 * dt, rel=1e-6)


def test_the_example_controller_holds_a_force(rkforge_ros_bin, force_controller_bin, tmp_path):
    scene = small_block(tmp_path, end="0.009")
    env_domain = 167
    node = start_node(rkforge_ros_bin, scene, env_domain, "--lockstep")
    ctl = subprocess.Popen([force_controller_bin, "--tool", "top", "--other", "bottom",
                            "--force", "2.6e8", "--kp", "2", "--idle-timeout", "2"],
                           env={"ROS_DOMAIN_ID": str(env_domain)}, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)
    _, err = node.communicate(timeout=60)
    out, cerr = ctl.communicate(timeout=30)
    assert node.returncode == 0, err
    assert ctl.returncode == 0, cerr
    forces = [float(line.split()[7]) for line in out.splitlines() if line.startswith("t ")]
    assert len(forces) == 61
    late = forces[30:]
    assert sum(late) / len(late) == pytest.approx(2.6e8, rel=0.1)


@pytest.mark.parametrize("value", ["abc", "233", "-1"])
def test_a_bad_domain_id_is_named(rkforge_ros_bin, tmp_path, value):
    scene = small_block(tmp_path)
    p = subprocess.run([rkforge_ros_bin, str(scene)], env={"ROS_DOMAIN_ID": value},
                       capture_output=True, text=True, timeout=30)
    assert p.returncode == 1
    assert f"ROS_DOMAIN_ID `{value}` is not an integer in 0..=232" in p.stderr


@pytest.mark.parametrize("args,message", [
    (["--namespace", "rkforge"], "namespace `rkforge` must start with `/`"),
    (["--namespace", "/1press"], "namespace token `1press` starts with a digit"),
    (["--publish-rate", "0"], "--publish-rate 0: must be positive and finite"),
    (["--real-time-factor", "nan"], "--real-time-factor NaN: must be positive and finite"),
])
def test_bad_arguments_are_named(rkforge_ros_bin, tmp_path, args, message):
    scene = small_block(tmp_path)
    p = subprocess.run([rkforge_ros_bin, str(scene), *args], env={"ROS_DOMAIN_ID": "168"},
                       capture_output=True, text=True, timeout=30)
    assert p.returncode == 1
    assert message in p.stderr


@pytest.mark.parametrize("make, tools, speed, domain", [
    (upset_bar_3d, ("wall", "ram"), 20.0, 176),
    (block_3d, ("anvil", "ram"), 0.020, 178),
], ids=["upset_bar", "forging_block"])
def test_a_3d_scene_over_dds_gives_its_history(rkforge_bin, rkforge_ros_bin, tmp_path, make, tools,
                                               speed, domain):
    """A 3D scene over DDS, the coarse quarter bar upset between its wall and a ram, and the
    3D forging of the rectangular block at press speed (mass-scaled, 1 mm of stroke): in
    lockstep, commanding the ram's own speed reproduces `rkforge run` bit for bit: the joint
    states, the wrenches with their z parts, the energy account and the register's outputs
    at history.csv's times; the point cloud has every particle with three coordinates."""
    scene = make(tmp_path)
    rows = run_history(rkforge_bin, scene, tmp_path / "out")
    particles = json.loads((tmp_path / "out" / "summary.json").read_text())["particles"]
    ctl = LockstepController(domain, lambda k, js: (speed,), tools=tools, commanded=("ram",))
    node = start_node(rkforge_ros_bin, scene, domain, "--lockstep")
    _, err = ctl.serve(node)
    assert node.returncode == 0, err
    stamps = sorted(ctl.states)
    assert stamps == [round(r["time_s"] * 1e9) for r in rows]
    for s, row in zip(stamps, rows):
        js = ctl.states[s]
        assert list(js.name) == list(tools)
        for k, tool in enumerate(js.name):
            assert js.position[k] == row[f"{tool}.stroke_m"]
            assert js.velocity[k] == row[f"{tool}.velocity_m_per_s"]
            assert js.effort[k] == row[f"{tool}.force_N"]
    for tool, got in ctl.wrench.items():
        assert set(got) == set(stamps), f"{tool}: reliable wrenches are all delivered"
        for s, row in zip(stamps, rows):
            f = got[s].wrench.force
            assert (f.x, f.y, f.z) == (row[f"{tool}.force_x_N"], row[f"{tool}.force_y_N"],
                                       row[f"{tool}.force_z_N"])
    assert rows[-1]["ram.stroke_m"] == pytest.approx(speed * rows[-1]["time_s"], rel=1e-9)
    assert abs(rows[-1]["ram.force_z_N"]) > 1e3
    assert set(ctl.energies) == set(stamps)
    for s, row in zip(stamps, rows):
        e = ctl.energies[s]
        assert (e.kinetic, e.plastic, e.tool_work) == (
            row["energy.kinetic_J"], row["energy.plastic_J"], row["energy.tool_work_J"])
    assert set(ctl.register) == set(stamps), "reliable outputs are all delivered"
    for s, row in zip(stamps, rows):
        got = dict(zip(ctl.register[s].names, ctl.register[s].values))
        assert {c: got[c] for c in row} == row
    assert ctl.clouds, "no point cloud arrived"
    by_stamp = dict(zip(stamps, rows))
    for s, c in ctl.clouds.items():
        row = by_stamp[s]
        assert (c.width, c.point_step) == (particles, 20)
        data = bytes(c.data)
        pts = [struct.unpack_from("<5f", data, 20 * k) for k in range(c.width)]
        for k, axis in enumerate("xyz"):
            assert min(p[k] for p in pts) == pytest.approx(row[f"workpiece.{axis}_min_m"], abs=1e-7)
            assert max(p[k] for p in pts) == pytest.approx(row[f"workpiece.{axis}_max_m"], abs=1e-7)


def test_a_3d_node_pauses_steps_resets_and_quits(rkforge_ros_bin, tmp_path):
    """The simulation_interfaces services and SimulateSteps on a 3D scene (the coarse quarter
    bar upset by a ram, its step set by the stable step; in lockstep with nobody commanding,
    playing holds the first sample): paused, N steps move the time on, by the service and by
    the action; a reset brings back t = 0."""
    scene = upset_bar_3d(tmp_path)
    with running_node(rkforge_ros_bin, scene, 177, "--lockstep", "--hold-at-end") as node:
        peer = Peer(177)
        sim = Simulator(peer)
        assert sim.set(sim.PAUSED) == (1, "")
        watch = StampWatch(peer)
        assert watch.wait_for(0) == 0
        assert sim.step(3) == (1, "")
        t3 = wait_for_new_stamp(watch, 0)
        assert 0 < t3 < 1000, "3 steps of about 170 ns"
        action = SimulateSteps(peer)
        action.wait_ready()
        goal, accepted = action.send(5)
        assert accepted
        assert action.result(goal)[:2] == (action.SUCCEEDED, 1)
        t8 = wait_for_new_stamp(watch, t3)
        assert t8 > t3
        assert sim.reset() == (1, "")
        assert wait_for_new_stamp(watch, t8) == 0
        assert sim.state() == sim.PAUSED
        quit_node(sim, node)


def wait_for_new_stamp(watch, previous):
    """The first joint-state stamp other than `previous` that `watch` sees."""
    seen = len(watch.stamps)
    wait_until(lambda: watch.stamps.extend(stamp_ns(js.header) for js in take(watch.reader))
               or any(s != previous for s in watch.stamps[seen:]), 60,
               f"a joint state after {previous} ns")
    return next(s for s in watch.stamps[seen:] if s != previous)
