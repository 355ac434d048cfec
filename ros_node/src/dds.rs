//! The ROS 2 node over DDS (`ros2-client`, RustDDS): publishers for the topics of
//! [`topics`](crate::topics) with their standard DDS type names
//! (`geometry_msgs::msg::dds_::WrenchStamped_`, ...) and QoS, a `std_msgs/msg/Float64`
//! subscription per movable tool for velocity commands, the parameter and
//! `simulation_interfaces` services and the `SimulateSteps` action. The state topics a
//! controller needs from the start (wrenches, joint states, markers, energy, outputs,
//! `/clock`) are transient local: a reader that matches after a sample was published still
//! receives it.
//!
//! The messages are those of a [`Sample`], already CDR-encoded by [`msgs`](crate::msgs); they
//! are handed to DDS as they are (see [`Payload`]), so the wire bytes equal the MCAP bytes.

use crate::action::StepsAction;
use crate::control::{Request, Services};
use crate::frame::Sample;
use crate::msgs::Float64;
use crate::msgs::ResultMsg;
use crate::params::{Parameters, Settings};
use crate::service::ReplyReaders;
use crate::{PublishedScene, Topic};
use ros2_client::dds::rustdds::Topic as DdsTopic;
use ros2_client::dds::{Context, ContextOptions, Node as RosNode, Publisher, Subscription};
use ros2_client::qos::{Durability, History, Reliability, WhenFull};
use ros2_client::{MessageTypeName, Name, NodeName, NodeOptions, QosProfile};
use serde::ser::SerializeTuple;
use serde::{Serialize, Serializer};
use std::sync::Arc;

/// Largest `ROS_DOMAIN_ID` (the ROS 2 documentation's limit for the default port mapping).
pub const MAX_DOMAIN_ID: u16 = 232;

/// History depth of every publisher and subscription.
const DEPTH: usize = 10;

/// Warnings about bad commands printed per topic before they are only counted.
const MAX_WARNINGS: u64 = 10;

/// The domain id from the value of `ROS_DOMAIN_ID`: unset or empty gives 0.
///
/// # Errors
///
/// The value is not an integer in `0..=232`.
pub fn parse_domain_id(value: Option<&str>) -> Result<u16, String> {
    let Some(v) = value.map(str::trim).filter(|v| !v.is_empty()) else {
        return Ok(0);
    };
    match v.parse::<u16>() {
        Ok(id) if id <= MAX_DOMAIN_ID => Ok(id),
        _ => Err(format!(
            "ROS_DOMAIN_ID `{v}` is not an integer in 0..={MAX_DOMAIN_ID}"
        )),
    }
}

/// The domain id from the environment variable `ROS_DOMAIN_ID` (see [`parse_domain_id`]).
///
/// # Errors
///
/// The variable is set to something other than an integer in `0..=232`, or is not Unicode.
pub fn domain_id_from_env() -> Result<u16, String> {
    match std::env::var("ROS_DOMAIN_ID") {
        Ok(v) => parse_domain_id(Some(&v)),
        Err(std::env::VarError::NotPresent) => Ok(0),
        Err(std::env::VarError::NotUnicode(v)) => Err(format!(
            "ROS_DOMAIN_ID {v:?} is not an integer in 0..={MAX_DOMAIN_ID}"
        )),
    }
}

/// An already serialized CDR message (encapsulation header included), written to DDS as it
/// is: the payload after the 4-byte header goes out as a tuple of bytes, which the CDR
/// serializer copies without length prefix or padding, behind its own (identical)
/// little-endian header.
#[derive(Debug, Clone)]
pub struct Payload(pub Vec<u8>);

impl Serialize for Payload {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let body = self.0.get(4..).unwrap_or_default();
        let mut t = s.serialize_tuple(body.len())?;
        for b in body {
            t.serialize_element(b)?;
        }
        t.end()
    }
}

/// A velocity command for a tool.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command {
    /// Index of the tool in the scene.
    pub tool: usize,
    /// Velocity along the tool's axis (m/s), finite.
    pub velocity: f64,
}

/// A tool's command subscription.
struct CommandInput {
    tool: usize,
    topic: String,
    sub: Subscription<Float64>,
    rejected: u64,
}

/// The rkforge node: publishers and command subscriptions on one DDS domain.
pub struct Node {
    publishers: Vec<(String, Publisher<Payload>)>,
    parameters: Parameters,
    services: Services,
    action: StepsAction,
    inputs: Vec<CommandInput>,
    dropped: u64,
    // Declared last: dropped after the publishers and subscriptions that belong to it.
    _node: RosNode,
    _context: Context,
}

/// The `MessageTypeName` of a type written `pkg/msg/Type`.
fn type_name(message: &str) -> Result<MessageTypeName, String> {
    match message.split('/').collect::<Vec<_>>()[..] {
        [pkg, "msg", ty] => Ok(MessageTypeName::new(pkg, ty)),
        _ => Err(format!(
            "message type `{message}` is not of the form pkg/msg/Type"
        )),
    }
}

/// The QoS of a topic: reliable (a full send window drops the sample rather than waiting) or
/// best effort; transient local (the samples held are sent to readers that match later) or
/// volatile; keep last [`DEPTH`].
fn qos(t: &Topic) -> QosProfile {
    qos_of(t.reliable, t.latched)
}

/// The QoS of [`qos`] from the two choices.
fn qos_of(reliable: bool, latched: bool) -> QosProfile {
    let reliability = if reliable {
        Reliability::Reliable {
            when_full: WhenFull::Fail,
        }
    } else {
        Reliability::BestEffort
    };
    let durability = if latched {
        Durability::TransientLocal
    } else {
        Durability::Volatile
    };
    QosProfile {
        reliability,
        durability,
        history: History::KeepLast { depth: DEPTH },
        ..QosProfile::publisher_default()
    }
}

impl Node {
    /// Join DDS domain `domain_id` as node `rkforge` in namespace `ns`, with a publisher for
    /// every published topic of `scene` (2D or 3D) and a subscription for every command
    /// topic.
    ///
    /// # Errors
    ///
    /// A bad namespace or tool name, or DDS could not start (e.g. no network interface).
    pub fn new(domain_id: u16, ns: &str, scene: &dyn PublishedScene) -> Result<Node, String> {
        let topics = crate::topics(scene, ns)?;
        let context = Context::with_options(ContextOptions::new().domain_id(domain_id))
            .map_err(|e| format!("cannot join DDS domain {domain_id}: {e:?}"))?;
        let name = NodeName::new(ns, "rkforge")
            .map_err(|e| format!("node name `rkforge` in namespace `{ns}`: {e:?}"))?;
        let mut node = context
            .new_node(
                name,
                NodeOptions::new()
                    .enable_rosout(false)
                    // Served below in the request/reply mapping of rmw_cyclonedds_cpp.
                    .start_parameter_services(false),
            )
            .map_err(|e| format!("cannot create the ROS 2 node: {e:?}"))?;
        let mut publishers = Vec::new();
        let mut inputs = Vec::new();
        for t in &topics {
            let topic = create_topic(&node, t)?;
            if t.publish {
                let p = node
                    .create_publisher::<Payload>(&topic, Some(qos(t)))
                    .map_err(|e| format!("cannot publish {}: {e:?}", t.name))?;
                publishers.push((t.name.clone(), p));
            } else {
                let tool = scene
                    .tool_list()
                    .iter()
                    .position(|(name, _)| t.name.ends_with(&format!("/{name}/velocity_cmd")))
                    .ok_or_else(|| format!("no tool for command topic {}", t.name))?;
                let sub = node
                    .create_subscription::<Float64>(&topic, Some(qos(t)))
                    .map_err(|e| format!("cannot subscribe to {}: {e:?}", t.name))?;
                inputs.push(CommandInput {
                    tool,
                    topic: t.name.clone(),
                    sub,
                    rejected: 0,
                });
            }
        }
        // Services: reliable and volatile, as rmw's default for services.
        let readers = Arc::new(ReplyReaders::watch(context.domain_participant())?);
        let parameters = Parameters::new(&mut node, &readers, ns, "rkforge", &qos_of(true, false))?;
        let services = Services::new(&mut node, &readers, ns, &qos_of(true, false))?;
        // The action's status: reliable, transient local, keep last 1 (rcl_action's default).
        let status = QosProfile {
            history: History::KeepLast { depth: 1 },
            ..qos_of(true, true)
        };
        let reliable = qos_of(true, false);
        let action = StepsAction::new(&mut node, &readers, ns, &reliable, &reliable, &status)?;
        Ok(Node {
            publishers,
            parameters,
            services,
            action,
            inputs,
            dropped: 0,
            _node: node,
            _context: context,
        })
    }

    /// Publish the messages of `sample`, one per publisher. A message that DDS cannot take now
    /// (a reliable reader's window is full) is dropped and counted, never waited for.
    ///
    /// # Errors
    ///
    /// The sample does not have one message per publisher.
    pub fn publish(&mut self, sample: &Sample) -> Result<(), String> {
        if sample.messages.len() != self.publishers.len() {
            return Err(format!(
                "a sample of {} messages for {} publishers",
                sample.messages.len(),
                self.publishers.len()
            ));
        }
        for ((_, p), m) in self.publishers.iter().zip(&sample.messages) {
            if p.publish(Payload(m.clone())).is_err() {
                self.dropped += 1;
            }
        }
        Ok(())
    }

    /// Answer the parameter requests received since the last call (see
    /// [`params`](crate::params)); true if a setting changed.
    pub fn serve_parameters(&mut self, settings: &mut Settings) -> bool {
        self.parameters.serve(settings)
    }

    /// Answer the simulator feature and state queries (the simulation is in `state`, a
    /// `SimulationState` value) and return the other `simulation_interfaces` requests
    /// received since the last call (see [`control`](crate::control)).
    pub fn poll_services(&mut self, state: u8) -> Vec<Request> {
        self.services.poll(state)
    }

    /// Answer a request returned by [`Node::poll_services`].
    pub fn answer(&mut self, request: Request, result: ResultMsg) {
        self.services.answer(request, result);
    }

    /// Write the replies held for clients whose reply readers have now matched (see
    /// [`service`](crate::service)); true if replies still wait (for at most
    /// [`HOLD`](crate::service::HOLD)).
    pub fn flush_replies(&mut self) -> bool {
        let waiting = [
            self.parameters.flush(),
            self.services.flush(),
            self.action.flush(),
        ];
        waiting.contains(&true)
    }

    /// The `SimulateSteps` action server (see [`action`](crate::action)).
    pub fn steps_action(&mut self) -> &mut StepsAction {
        &mut self.action
    }

    /// Messages not published because DDS could not take them.
    #[must_use]
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Indices of the tools that take commands.
    #[must_use]
    pub fn commanded_tools(&self) -> Vec<usize> {
        self.inputs.iter().map(|i| i.tool).collect()
    }

    /// Every command received since the last call, oldest first. NaN and infinite values are
    /// dropped with a warning on stderr (the first [`MAX_WARNINGS`] per topic, then counted).
    pub fn take_commands(&mut self) -> Vec<Command> {
        let mut out = Vec::new();
        for input in &mut self.inputs {
            loop {
                match input.sub.take() {
                    Ok(Some((m, _))) if m.data.is_finite() => out.push(Command {
                        tool: input.tool,
                        velocity: m.data,
                    }),
                    Ok(Some((m, _))) => {
                        input.rejected += 1;
                        if input.rejected <= MAX_WARNINGS {
                            eprintln!(
                                "warning: ignoring velocity command {} m/s on {}: not finite{}",
                                m.data,
                                input.topic,
                                if input.rejected == MAX_WARNINGS {
                                    " (further warnings on this topic are only counted)"
                                } else {
                                    ""
                                }
                            );
                        }
                    }
                    Ok(None) => break,
                    Err(e) => {
                        input.rejected += 1;
                        if input.rejected <= MAX_WARNINGS {
                            eprintln!(
                                "warning: ignoring an unreadable message on {}: {e:?}",
                                input.topic
                            );
                        }
                    }
                }
            }
        }
        out
    }

    /// Commands rejected so far (not finite or unreadable), per command topic.
    #[must_use]
    pub fn rejected(&self) -> Vec<(String, u64)> {
        self.inputs
            .iter()
            .map(|i| (i.topic.clone(), i.rejected))
            .collect()
    }
}

/// The DDS topic (`rt/...`) of `t` with its standard type name.
fn create_topic(node: &RosNode, t: &Topic) -> Result<DdsTopic, String> {
    let name = Name::parse(&t.name).map_err(|e| format!("topic name {}: {e:?}", t.name))?;
    node.create_topic(&name, type_name(t.message)?, &qos(t))
        .map_err(|e| format!("cannot create topic {}: {e:?}", t.name))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::{
        Clock, DieFill, Energy, JointState, Laps, MarkerArray, Outputs, PointCloud2, RosMessage,
        WrenchStamped,
    };

    #[test]
    fn domain_ids_follow_ros2() {
        assert_eq!(parse_domain_id(None), Ok(0));
        assert_eq!(parse_domain_id(Some("")), Ok(0));
        assert_eq!(parse_domain_id(Some("42")), Ok(42));
        assert_eq!(parse_domain_id(Some("232")), Ok(232));
        for bad in ["233", "-1", "x", "1.5"] {
            let e = parse_domain_id(Some(bad)).unwrap_err();
            assert!(e.contains(&format!("`{bad}`")), "{e}");
        }
    }

    #[test]
    fn type_names_split_into_package_and_type() {
        let t = type_name("geometry_msgs/msg/WrenchStamped").unwrap();
        assert_eq!(t.dds_msg_type(), "geometry_msgs::msg::dds_::WrenchStamped_");
        // ros2-client derives the DDS name the build script gives each message.
        for (name, dds) in [
            (WrenchStamped::TYPE_NAME, WrenchStamped::DDS_TYPE_NAME),
            (JointState::TYPE_NAME, JointState::DDS_TYPE_NAME),
            (PointCloud2::TYPE_NAME, PointCloud2::DDS_TYPE_NAME),
            (MarkerArray::TYPE_NAME, MarkerArray::DDS_TYPE_NAME),
            (Clock::TYPE_NAME, Clock::DDS_TYPE_NAME),
            (Float64::TYPE_NAME, Float64::DDS_TYPE_NAME),
            (Energy::TYPE_NAME, Energy::DDS_TYPE_NAME),
            (DieFill::TYPE_NAME, DieFill::DDS_TYPE_NAME),
            (Laps::TYPE_NAME, Laps::DDS_TYPE_NAME),
            (Outputs::TYPE_NAME, Outputs::DDS_TYPE_NAME),
        ] {
            assert_eq!(type_name(name).unwrap().dds_msg_type(), dds);
        }
        assert!(type_name("WrenchStamped").is_err());
    }
}
