//! The node's publishers and subscriptions seen by a second ROS 2 node (ros2-client) in the
//! same process, over loopback DDS on a domain of its own.
#![cfg(feature = "dds")]

use rkforge_core::{Scene, Simulation};
use rkforge_ros::dds::Node;
use rkforge_ros::frame::sample;
use rkforge_ros::msgs::{
    Float64, JointState as JointStateMsg, RosMessage, WrenchStamped as WrenchMsg,
};
use ros2_client::dds::Context;
use ros2_client::qos::{Durability, History, Reliability, WhenFull};
use ros2_client::{ContextOptions, MessageTypeName, Name, NodeName, NodeOptions, QosProfile};
use serde::Deserialize;
use std::time::{Duration, Instant};

/// Domain of this test only.
const DOMAIN: u16 = 141;

#[derive(Deserialize, Debug, PartialEq)]
struct Time {
    sec: i32,
    nanosec: u32,
}

#[derive(Deserialize, Debug, PartialEq)]
struct Header {
    stamp: Time,
    frame_id: String,
}

#[derive(Deserialize, Debug)]
struct JointState {
    header: Header,
    name: Vec<String>,
    position: Vec<f64>,
    velocity: Vec<f64>,
    effort: Vec<f64>,
}

#[derive(Deserialize, Debug)]
struct Vector3 {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Deserialize, Debug)]
struct Wrench {
    force: Vector3,
    torque: Vector3,
}

#[derive(Deserialize, Debug)]
struct WrenchStamped {
    header: Header,
    wrench: Wrench,
}

fn qos() -> QosProfile {
    QosProfile {
        reliability: Reliability::Reliable {
            when_full: WhenFull::Fail,
        },
        durability: Durability::Volatile,
        history: History::KeepLast { depth: 10 },
        ..QosProfile::publisher_default()
    }
}

#[test]
fn a_second_node_reads_the_state_and_commands_a_tool() {
    let text = include_str!("../../scenes/block_forging.toml")
        .replace("particles = [21, 21]", "particles = [6, 6]");
    let scene = Scene::from_str_named(&text, "block").unwrap();
    let mut sim = Simulation::new(&scene).unwrap();
    let mut node = Node::new(DOMAIN, "/loop", &scene).unwrap();
    assert_eq!(node.commanded_tools(), [0, 1]);

    let ctx = Context::with_options(ContextOptions::new().domain_id(DOMAIN)).unwrap();
    let mut peer = ctx
        .new_node(
            NodeName::new("/", "peer").unwrap(),
            NodeOptions::new().enable_rosout(false),
        )
        .unwrap();
    let topic = |name: &str, pkg: &str, ty: &str| {
        peer.create_topic(
            &Name::parse(name).unwrap(),
            MessageTypeName::new(pkg, ty),
            &qos(),
        )
        .unwrap()
    };
    let tools_topic = topic("/loop/tools", "sensor_msgs", "JointState");
    let wrench_topic = topic("/loop/top/wrench", "geometry_msgs", "WrenchStamped");
    let cmd_topic = topic("/loop/bottom/velocity_cmd", "std_msgs", "Float64");
    let states = peer
        .create_subscription::<JointState>(&tools_topic, Some(qos()))
        .unwrap();
    let wrenches = peer
        .create_subscription::<WrenchStamped>(&wrench_topic, Some(qos()))
        .unwrap();
    let commands = peer
        .create_publisher::<Float64>(&cmd_topic, Some(qos()))
        .unwrap();

    for _ in 0..30 {
        sim.step(None).unwrap();
    }
    let s = sample(&sim, None);
    let sent_state = JointStateMsg::from_cdr(&s.messages[2]).unwrap();
    let sent_wrench = WrenchMsg::from_cdr(&s.messages[0]).unwrap();
    let start = Instant::now();
    let (mut state, mut wrench, mut received) = (None, None, Vec::new());
    while state.is_none() || wrench.is_none() || received.len() < 2 {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "loopback exchange incomplete: state {} wrench {} commands {received:?}",
            state.is_some(),
            wrench.is_some()
        );
        // Publish until discovery has matched the peer (volatile: earlier samples are lost).
        node.publish(&s).unwrap();
        if let Ok(Some((m, _))) = states.take() {
            state = Some(m);
        }
        if let Ok(Some((m, _))) = wrenches.take() {
            wrench = Some(m);
        }
        for v in [f64::NAN, -1.25] {
            let _ = commands.publish(Float64 { data: v });
        }
        received.extend(node.take_commands());
        std::thread::sleep(Duration::from_millis(20));
    }
    let state = state.unwrap();
    assert_eq!(state.name, sent_state.name);
    assert_eq!(state.position, sent_state.position);
    assert_eq!(state.velocity, sent_state.velocity);
    assert_eq!(state.effort, sent_state.effort);
    assert_eq!(state.header.frame_id, "rkforge");
    assert_eq!(state.header.stamp.nanosec, sent_state.header.stamp.nanosec);
    let wrench = wrench.unwrap();
    assert_eq!(wrench.wrench.force.x, sent_wrench.wrench.force.x);
    assert_eq!(wrench.wrench.force.y, sent_wrench.wrench.force.y);
    assert_eq!((wrench.wrench.force.z, wrench.wrench.torque.x), (0.0, 0.0));
    assert_eq!((wrench.wrench.torque.y, wrench.wrench.torque.z), (0.0, 0.0));
    assert_eq!(wrench.header, state.header);
    // Only the finite commands come through, for the bottom tool (index 1).
    assert!(received.iter().all(|c| c.tool == 1 && c.velocity == -1.25));
    let rejected = node.rejected();
    assert_eq!(rejected[1].0, "/loop/bottom/velocity_cmd");
    assert!(rejected[1].1 >= 1, "the NaN commands are counted");
    assert_eq!(rejected[0].1, 0);
}
