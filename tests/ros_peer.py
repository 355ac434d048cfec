"""An independent ROS 2 peer for the tests: the standard messages as Cyclone DDS IDL types with
the DDS type names ROS 2 uses (`pkg::msg::dds_::Type_`), QoS as rclcpp's defaults, and helpers
to read history.csv and to derive small scenes."""
import csv
import os
import subprocess
import time
from contextlib import contextmanager
from dataclasses import dataclass

import cyclonedds.idl.types as t
from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.internal import InvalidSample
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

from conftest import ROOT, scene_variant


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: t.int32
    nanosec: t.uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: t.float64
    y: t.float64
    z: t.float64


@dataclass
class Wrench(IdlStruct, typename="geometry_msgs::msg::dds_::Wrench_"):
    force: Vector3
    torque: Vector3


@dataclass
class WrenchStamped(IdlStruct, typename="geometry_msgs::msg::dds_::WrenchStamped_"):
    header: Header
    wrench: Wrench


@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    header: Header
    name: t.sequence[str]
    position: t.sequence[t.float64]
    velocity: t.sequence[t.float64]
    effort: t.sequence[t.float64]


@dataclass
class PointField(IdlStruct, typename="sensor_msgs::msg::dds_::PointField_"):
    name: str
    offset: t.uint32
    datatype: t.uint8
    count: t.uint32


@dataclass
class PointCloud2(IdlStruct, typename="sensor_msgs::msg::dds_::PointCloud2_"):
    header: Header
    height: t.uint32
    width: t.uint32
    fields: t.sequence[PointField]
    is_bigendian: bool
    point_step: t.uint32
    row_step: t.uint32
    data: t.sequence[t.uint8]
    is_dense: bool


@dataclass
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    clock: Time


@dataclass
class Float64(IdlStruct, typename="std_msgs::msg::dds_::Float64_"):
    data: t.float64


@dataclass
class ParameterValue(IdlStruct, typename="rcl_interfaces::msg::dds_::ParameterValue_"):
    type: t.uint8
    bool_value: bool
    integer_value: t.int64
    double_value: t.float64
    string_value: str
    byte_array_value: t.sequence[t.uint8]
    bool_array_value: t.sequence[bool]
    integer_array_value: t.sequence[t.int64]
    double_array_value: t.sequence[t.float64]
    string_array_value: t.sequence[str]


def parameter_value(v):
    """A ParameterValue of a bool (type 1) or a float (type 3)."""
    kind = 1 if isinstance(v, bool) else 3
    return ParameterValue(kind, v if kind == 1 else False, 0, v if kind == 3 else 0.0, "",
                          [], [], [], [], [])


@dataclass
class Parameter(IdlStruct, typename="rcl_interfaces::msg::dds_::Parameter_"):
    name: str
    value: ParameterValue


@dataclass
class SetParametersResult(IdlStruct, typename="rcl_interfaces::msg::dds_::SetParametersResult_"):
    successful: bool
    reason: str


@dataclass
class FloatingPointRange(IdlStruct, typename="rcl_interfaces::msg::dds_::FloatingPointRange_"):
    from_value: t.float64
    to_value: t.float64
    step: t.float64


@dataclass
class IntegerRange(IdlStruct, typename="rcl_interfaces::msg::dds_::IntegerRange_"):
    from_value: t.int64
    to_value: t.int64
    step: t.uint64


@dataclass
class ParameterDescriptor(IdlStruct, typename="rcl_interfaces::msg::dds_::ParameterDescriptor_"):
    name: str
    type: t.uint8
    description: str
    additional_constraints: str
    read_only: bool
    dynamic_typing: bool
    floating_point_range: t.sequence[FloatingPointRange, 1]
    integer_range: t.sequence[IntegerRange, 1]


# Requests and replies as rmw_cyclonedds_cpp puts them on the wire: a header of the client's
# GUID (its last 8 bytes) and a 64-bit sequence number, then the standard request or reply.
@dataclass
class ListParametersRequest(IdlStruct,
                            typename="rcl_interfaces::srv::dds_::ListParameters_Request_"):
    guid: t.uint64
    seq: t.int64
    prefixes: t.sequence[str]
    depth: t.uint64


@dataclass
class ListParametersReply(IdlStruct,
                          typename="rcl_interfaces::srv::dds_::ListParameters_Response_"):
    guid: t.uint64
    seq: t.int64
    names: t.sequence[str]
    prefixes: t.sequence[str]


@dataclass
class GetParametersRequest(IdlStruct, typename="rcl_interfaces::srv::dds_::GetParameters_Request_"):
    guid: t.uint64
    seq: t.int64
    names: t.sequence[str]


@dataclass
class GetParametersReply(IdlStruct, typename="rcl_interfaces::srv::dds_::GetParameters_Response_"):
    guid: t.uint64
    seq: t.int64
    values: t.sequence[ParameterValue]


@dataclass
class SetParametersRequest(IdlStruct, typename="rcl_interfaces::srv::dds_::SetParameters_Request_"):
    guid: t.uint64
    seq: t.int64
    parameters: t.sequence[Parameter]


@dataclass
class SetParametersReply(IdlStruct, typename="rcl_interfaces::srv::dds_::SetParameters_Response_"):
    guid: t.uint64
    seq: t.int64
    results: t.sequence[SetParametersResult]


@dataclass
class DescribeParametersRequest(IdlStruct,
                                typename="rcl_interfaces::srv::dds_::DescribeParameters_Request_"):
    guid: t.uint64
    seq: t.int64
    names: t.sequence[str]


@dataclass
class DescribeParametersReply(IdlStruct,
                              typename="rcl_interfaces::srv::dds_::DescribeParameters_Response_"):
    guid: t.uint64
    seq: t.int64
    descriptors: t.sequence[ParameterDescriptor]


@dataclass
class SimResult(IdlStruct, typename="simulation_interfaces::msg::dds_::Result_"):
    result: t.uint8
    error_message: str


@dataclass
class SimulationState(IdlStruct, typename="simulation_interfaces::msg::dds_::SimulationState_"):
    state: t.uint8


@dataclass
class SimulatorFeatures(IdlStruct,
                        typename="simulation_interfaces::msg::dds_::SimulatorFeatures_"):
    features: t.sequence[t.uint16]
    spawn_formats: t.sequence[str]
    custom_info: str


# Requests without fields carry the one byte ROS 2's IDL gives an empty structure.
@dataclass
class GetSimulatorFeaturesRequest(
        IdlStruct, typename="simulation_interfaces::srv::dds_::GetSimulatorFeatures_Request_"):
    guid: t.uint64
    seq: t.int64
    structure_needs_at_least_one_member: t.uint8


@dataclass
class GetSimulatorFeaturesReply(
        IdlStruct, typename="simulation_interfaces::srv::dds_::GetSimulatorFeatures_Response_"):
    guid: t.uint64
    seq: t.int64
    features: SimulatorFeatures


@dataclass
class GetSimulationStateRequest(
        IdlStruct, typename="simulation_interfaces::srv::dds_::GetSimulationState_Request_"):
    guid: t.uint64
    seq: t.int64
    structure_needs_at_least_one_member: t.uint8


@dataclass
class GetSimulationStateReply(
        IdlStruct, typename="simulation_interfaces::srv::dds_::GetSimulationState_Response_"):
    guid: t.uint64
    seq: t.int64
    state: SimulationState
    result: SimResult


@dataclass
class SetSimulationStateRequest(
        IdlStruct, typename="simulation_interfaces::srv::dds_::SetSimulationState_Request_"):
    guid: t.uint64
    seq: t.int64
    state: SimulationState


@dataclass
class SetSimulationStateReply(
        IdlStruct, typename="simulation_interfaces::srv::dds_::SetSimulationState_Response_"):
    guid: t.uint64
    seq: t.int64
    result: SimResult


@dataclass
class ResetSimulationRequest(
        IdlStruct, typename="simulation_interfaces::srv::dds_::ResetSimulation_Request_"):
    guid: t.uint64
    seq: t.int64
    scope: t.uint8


@dataclass
class ResetSimulationReply(
        IdlStruct, typename="simulation_interfaces::srv::dds_::ResetSimulation_Response_"):
    guid: t.uint64
    seq: t.int64
    result: SimResult


@dataclass
class StepSimulationRequest(
        IdlStruct, typename="simulation_interfaces::srv::dds_::StepSimulation_Request_"):
    guid: t.uint64
    seq: t.int64
    steps: t.uint64


@dataclass
class StepSimulationReply(
        IdlStruct, typename="simulation_interfaces::srv::dds_::StepSimulation_Response_"):
    guid: t.uint64
    seq: t.int64
    result: SimResult


@dataclass
class Energy(IdlStruct, typename="rkforge_msgs::msg::dds_::Energy_"):
    header: Header
    initial: t.float64
    kinetic: t.float64
    elastic: t.float64
    plastic: t.float64
    internal: t.float64
    contact_work: t.float64
    tool_work: t.float64


@dataclass
class Outputs(IdlStruct, typename="rkforge_msgs::msg::dds_::Outputs_"):
    header: Header
    names: t.sequence[str]
    units: t.sequence[str]
    values: t.sequence[t.float64]


# The SimulateSteps action as rcl_action puts it on DDS: services `<action>/_action/send_goal`,
# `get_result`, `cancel_goal` (requests and replies with rmw_cyclonedds_cpp's header, as
# above), topics `<action>/_action/feedback` and `status`.
@dataclass
class UUID(IdlStruct, typename="unique_identifier_msgs::msg::dds_::UUID_"):
    uuid: t.array[t.uint8, 16]


@dataclass
class GoalInfo(IdlStruct, typename="action_msgs::msg::dds_::GoalInfo_"):
    goal_id: UUID
    stamp: Time


@dataclass
class GoalStatus(IdlStruct, typename="action_msgs::msg::dds_::GoalStatus_"):
    goal_info: GoalInfo
    status: t.int8


@dataclass
class GoalStatusArray(IdlStruct, typename="action_msgs::msg::dds_::GoalStatusArray_"):
    status_list: t.sequence[GoalStatus]


@dataclass
class SimulateStepsGoal(IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_Goal_"):
    steps: t.uint64


@dataclass
class SimulateStepsResult(IdlStruct,
                          typename="simulation_interfaces::action::dds_::SimulateSteps_Result_"):
    result: SimResult


@dataclass
class SimulateStepsFeedback(
        IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_Feedback_"):
    completed_steps: t.uint64
    remaining_steps: t.uint64


@dataclass
class SimulateStepsFeedbackMessage(
        IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_FeedbackMessage_"):
    goal_id: UUID
    feedback: SimulateStepsFeedback


@dataclass
class SendGoalRequest(
        IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_SendGoal_Request_"):
    guid: t.uint64
    seq: t.int64
    goal_id: UUID
    goal: SimulateStepsGoal


@dataclass
class SendGoalReply(
        IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_SendGoal_Response_"):
    guid: t.uint64
    seq: t.int64
    accepted: bool
    stamp: Time


@dataclass
class GetResultRequest(
        IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_GetResult_Request_"):
    guid: t.uint64
    seq: t.int64
    goal_id: UUID


@dataclass
class GetResultReply(
        IdlStruct, typename="simulation_interfaces::action::dds_::SimulateSteps_GetResult_Response_"):
    guid: t.uint64
    seq: t.int64
    status: t.int8
    result: SimulateStepsResult


@dataclass
class CancelGoalRequest(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Request_"):
    guid: t.uint64
    seq: t.int64
    goal_info: GoalInfo


@dataclass
class CancelGoalReply(IdlStruct, typename="action_msgs::srv::dds_::CancelGoal_Response_"):
    guid: t.uint64
    seq: t.int64
    return_code: t.int8
    goals_canceling: t.sequence[GoalInfo]


def qos(reliable=True, latched=False):
    """rclcpp's default (reliable, keep last 10, volatile) or best effort; transient local
    when `latched` (a reader that matches late still gets the samples the writer holds); plain
    CDR (XCDR1) as rmw_cyclonedds_cpp writes it."""
    r = (Policy.Reliability.Reliable(max_blocking_time=1_000_000_000) if reliable
         else Policy.Reliability.BestEffort)
    d = Policy.Durability.TransientLocal if latched else Policy.Durability.Volatile
    return Qos(r, Policy.History.KeepLast(10), d,
               Policy.DataRepresentation(use_cdrv0_representation=True))


class Peer:
    """A DDS participant on `domain` with readers and writers on ROS 2 topics (`rt/...`)."""

    def __init__(self, domain):
        self.dp = DomainParticipant(domain)

    def reader(self, topic, cls, reliable=True, latched=False):
        return DataReader(self.dp, Topic(self.dp, "rt" + topic, cls),
                          qos=qos(reliable, latched))

    def writer(self, topic, cls):
        return DataWriter(self.dp, Topic(self.dp, "rt" + topic, cls), qos=qos(True))


class ServiceClient:
    """Calls service `name` (e.g. `/rkforge/rkforge/get_parameters`) of a ROS 2 node as an
    rmw_cyclonedds_cpp client does: requests on `rq<name>Request`, replies on
    `rr<name>Reply`, matched by sequence number."""

    GUID = 0x0123456789ABCDEF

    def __init__(self, peer, name, request, reply):
        self.request = request
        self.writer = DataWriter(peer.dp, Topic(peer.dp, f"rq{name}Request", request),
                                 qos=qos(True))
        self.reader = DataReader(peer.dp, Topic(peer.dp, f"rr{name}Reply", reply), qos=qos(True))
        self.seq = 0

    def call(self, *fields, timeout=60):
        """Send a request with `fields` after the header; the reply to it."""
        wait_matched(self.writer, timeout)
        wait_until(lambda: self.reader.get_matched_publications(), timeout, "the reply writer")
        self.seq += 1
        self.writer.write(self.request(self.GUID, self.seq, *fields))
        got = []
        wait_until(lambda: got.extend(r for r in take(self.reader) if r.seq == self.seq) or got,
                   timeout, f"the reply to request {self.seq}")
        return got[0]


class Simulator:
    """A client of the node's simulation_interfaces services under namespace `ns`."""

    PLAYING, PAUSED, STOPPED, QUITTING = 1, 2, 0, 3

    def __init__(self, peer, ns="/rkforge"):
        def client(service, request, reply):
            return ServiceClient(peer, f"{ns}/{service}", request, reply)

        self.features = client("get_simulator_features", GetSimulatorFeaturesRequest,
                               GetSimulatorFeaturesReply)
        self.get_state = client("get_simulation_state", GetSimulationStateRequest,
                                GetSimulationStateReply)
        self.set_state = client("set_simulation_state", SetSimulationStateRequest,
                                SetSimulationStateReply)
        self.reset_ = client("reset_simulation", ResetSimulationRequest, ResetSimulationReply)
        self.step_ = client("step_simulation", StepSimulationRequest, StepSimulationReply)

    def state(self):
        return self.get_state.call(0).state.state

    def set(self, state):
        """SetSimulationState: (result code, error message)."""
        r = self.set_state.call(SimulationState(state)).result
        return r.result, r.error_message

    def reset(self, scope=0):
        r = self.reset_.call(scope).result
        return r.result, r.error_message

    def step(self, steps):
        r = self.step_.call(steps).result
        return r.result, r.error_message


class SimulateSteps:
    """A client of the node's SimulateSteps action under namespace `ns`, as rclcpp's action
    client talks to it: goals with a random id, the result by id, cancel by id; the feedback
    and status topics are read with rcl_action's QoS (status: transient local)."""

    # action_msgs/msg/GoalStatus
    UNKNOWN, ACCEPTED, EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = range(7)

    def __init__(self, peer, ns="/rkforge"):
        base = f"{ns}/simulate_steps/_action"
        self.send_goal = ServiceClient(peer, f"{base}/send_goal", SendGoalRequest, SendGoalReply)
        self.get_result = ServiceClient(peer, f"{base}/get_result", GetResultRequest,
                                        GetResultReply)
        self.cancel_goal = ServiceClient(peer, f"{base}/cancel_goal", CancelGoalRequest,
                                         CancelGoalReply)
        self.feedback = DataReader(
            peer.dp, Topic(peer.dp, f"rt{base}/feedback", SimulateStepsFeedbackMessage),
            qos=qos(True))
        self.status = DataReader(
            peer.dp, Topic(peer.dp, f"rt{base}/status", GoalStatusArray),
            qos=Qos(Policy.Reliability.Reliable(max_blocking_time=1_000_000_000),
                    Policy.History.KeepLast(1), Policy.Durability.TransientLocal,
                    Policy.DataRepresentation(use_cdrv0_representation=True)))

    def wait_ready(self, timeout=60):
        """Wait until the three services and the feedback topic have found the node's
        endpoints (feedback is volatile: what is published before that is lost)."""
        for client in [self.send_goal, self.get_result, self.cancel_goal]:
            wait_matched(client.writer, timeout)
            wait_readers_matched([client.reader], timeout)
        wait_readers_matched([self.feedback], timeout)

    def send(self, steps):
        """Send a goal of `steps` steps: (goal id as bytes, accepted)."""
        goal_id = os.urandom(16)
        reply = self.send_goal.call(UUID(list(goal_id)), SimulateStepsGoal(steps))
        return goal_id, reply.accepted

    def result(self, goal_id, timeout=120):
        """The goal's status and result: (status, result code, error message); waits until
        the goal has ended."""
        r = self.get_result.call(UUID(list(goal_id)), timeout=timeout)
        return r.status, r.result.result.result, r.result.result.error_message

    def cancel(self, goal_id):
        """Cancel a goal by id: (return code, ids of the goals canceling)."""
        r = self.cancel_goal.call(GoalInfo(UUID(list(goal_id)), Time(0, 0)))
        return r.return_code, [bytes(g.goal_id.uuid) for g in r.goals_canceling]


def take(reader, n=50):
    """Valid samples only: Cyclone also hands over "invalid samples" that carry no data, only
    an instance state change (e.g. when the writer of the node goes away)."""
    return [s for s in reader.take(N=n) if not isinstance(s, InvalidSample)]


def wait_matched(writer, timeout=60):
    """Wait until the writer has found the node's reader: the command topics are volatile, so
    what is written before that is lost."""
    wait_until(lambda: writer.get_matched_subscriptions(), timeout, "the node's command reader")


def wait_readers_matched(readers, timeout=60):
    """Wait until each reader has found the node's writer (discovery can take seconds on a
    busy machine)."""
    for r in readers:
        wait_until(lambda: r.get_matched_publications(), timeout, "the node's publisher")


def stamp_ns(header):
    """A Header's stamp, or a Clock's time, in nanoseconds."""
    t = getattr(header, "stamp", None) or header.clock
    return t.sec * 1_000_000_000 + t.nanosec


def history(path):
    """history.csv as a list of dicts of floats."""
    with open(path) as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def small_block(tmp_path, end="0.003", particles="[8, 8]", name="block_small.toml"):
    """The block forging scene, coarse and short."""
    p = tmp_path / name
    p.write_text(scene_variant("block_forging.toml", {
        "particles = [21, 21]": f"particles = {particles}",
        "end_s = 0.015": f"end_s = {end}",
    }))
    return p


def small_bar_3d(tmp_path, cells="[2, 1, 8]", end="10.0e-6", name="bar3d_small.toml"):
    """The quarter Taylor bar in 3D (scenes/taylor_bar_3d.toml: a fixed wall, no command
    topic), coarse and short."""
    p = tmp_path / name
    p.write_text(scene_variant("taylor_bar_3d.toml", {
        "cells = [8, 4, 60]": f"cells = {cells}",
        "end_s = 80.0e-6": f"end_s = {end}",
    }))
    return p


def upset_bar_3d(tmp_path, cells="[2, 1, 8]", end="10.0e-6", name="upset3d.toml"):
    """The quarter bar of scenes/taylor_bar_3d.toml at rest on its wall, coarse and short,
    upset by a second plane tool, `ram`, on its top face moving down at a constant 20 m/s
    (a tool that takes velocity commands)."""
    p = tmp_path / name
    p.write_text(scene_variant("taylor_bar_3d.toml", {
        "cells = [8, 4, 60]": f"cells = {cells}",
        "end_s = 80.0e-6": f"end_s = {end}",
        "initial_velocity_m_per_s = [0.0, 0.0, -227.0]": "initial_velocity_m_per_s = [0.0, 0.0, 0.0]",
        "[output]": """[[tools]]
name = "ram"
point_m = [0.0, 0.0, 0.0324]
normal = [0.0, 0.0, -1.0]
axis = [0.0, 0.0, -1.0]
motion = { kind = "constant", velocity_m_per_s = 20.0 }

[output]""",
    }))
    return p


def block_3d(tmp_path, end="0.05", name="block3d.toml"):
    """The rectangular block of scenes/block_upsetting_3d.toml (a 3D forging: the quarter
    7 x 5 x 9 particles between an anvil and a ram at 20 mm/s, mass-scaled), `end` s long
    (0.05 s: 1 mm of stroke, history rows every 10 ms)."""
    p = tmp_path / name
    p.write_text(scene_variant("block_upsetting_3d.toml", {"end_s = 1.0 ": f"end_s = {end} "}))
    return p


def run_history(rkforge_bin, scene, out, *extra):
    """`rkforge run SCENE --no-frames` and its history rows."""
    subprocess.run([rkforge_bin, "run", str(scene), "--no-frames", "--quiet", "--out", str(out),
                    *extra], check=True, capture_output=True, text=True)
    return history(out / "history.csv")


def start_node(rkforge_ros_bin, scene, domain, *args):
    """Start `rkforge-ros` on `domain`; stdout and stderr are captured as text."""
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain)}
    return subprocess.Popen([rkforge_ros_bin, str(scene), *args], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@contextmanager
def running_node(rkforge_ros_bin, scene, domain, *args):
    """`start_node` for a `with` block: the node is killed if the block leaves it running."""
    node = start_node(rkforge_ros_bin, scene, domain, *args)
    try:
        yield node
    finally:
        if node.poll() is None:
            node.kill()
            node.communicate()


def quit_node(sim, node):
    """End the node with SetSimulationState(STATE_QUITTING); it exits with status 0."""
    assert sim.set(sim.QUITTING) == (1, "")
    _, err = node.communicate(timeout=60)
    assert node.returncode == 0, err


def wait_until(cond, timeout, what):
    t0 = time.monotonic()
    while not cond():
        if time.monotonic() - t0 > timeout:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        time.sleep(0.002)


__all__ = ["ROOT"]
