//! The ROS 2 messages of an rkforge run and their recording, without DDS: which topics a
//! run publishes and subscribes to, with their standard message types, under a namespace
//! validated by the ROS 2 naming rules. Used by the ROS 2 node (`rkforge-ros`) and by
//! `rkforge run --mcap`.
//!
//! - [`msgs`]: the standard messages, generated from the `.msg` files in `messages/msg`, and
//!   their CDR encoding;
//! - [`frame`]: the messages of one sample of a [`Simulation`](rkforge_core::Simulation);
//! - [`record`]: the MCAP recorder (used by `rkforge-ros --record` and `rkforge run --mcap`);
//! - [`signals`]: SIGINT and SIGTERM as a flag, so that a run stops and finishes its files.
//!
//! Feature `dds`: the messages also implement `ros2_client::Message`, for the node.

pub mod frame;
pub mod msgs;
pub mod record;
pub mod signals;

use msgs::RosMessage;
use rkforge_core::scene::{Motion, Scene};

/// A topic with its ROS 2 message type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Topic {
    /// Fully qualified name.
    pub name: String,
    /// Message type, e.g. `geometry_msgs/msg/WrenchStamped`.
    pub message: &'static str,
    /// The `ros2msg` definition of the message type, as rosbag2 writes it in MCAP.
    pub schema: &'static str,
    /// Whether the node publishes (true) or subscribes (false).
    pub publish: bool,
    /// Reliable (true) or best-effort (false) quality of service.
    pub reliable: bool,
    /// Transient-local durability (latched): a reader that matches late still receives the
    /// last samples the publisher holds (keep last 10). Volatile when false.
    pub latched: bool,
}

/// Check a namespace against the ROS 2 rules: absolute, tokens of letters, digits and
/// underscores, not starting with a digit, no empty tokens, no trailing slash.
pub fn validate_namespace(ns: &str) -> Result<(), String> {
    if !ns.starts_with('/') {
        return Err(format!("namespace `{ns}` must start with `/`"));
    }
    if ns == "/" {
        return Ok(());
    }
    for token in ns[1..].split('/') {
        if token.is_empty() {
            return Err(format!(
                "namespace `{ns}` has an empty token (`//` or a trailing `/`)"
            ));
        }
        if token.starts_with(|c: char| c.is_ascii_digit()) {
            return Err(format!("namespace token `{token}` starts with a digit"));
        }
        if !token.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(format!(
                "namespace token `{token}` may only use letters, digits and `_`"
            ));
        }
    }
    Ok(())
}

/// The topics of a scene under namespace `ns`: first the published ones in the order of the
/// messages of a [`frame::Sample`] (one wrench per tool in scene order, `tools`, `workpiece`,
/// `tool_markers`, `die_fill`, `laps`, `energy`, `outputs`, `/clock`), then one `velocity_cmd`
/// subscription per movable tool.
///
/// # Errors
///
/// The namespace breaks the ROS 2 naming rules, or a tool name is not a valid topic token.
pub fn topics(scene: &Scene, ns: &str) -> Result<Vec<Topic>, String> {
    validate_namespace(ns)?;
    let base = ns.trim_end_matches('/');
    for tool in &scene.tools {
        validate_namespace(&format!("/{}", tool.name))
            .map_err(|e| format!("tool `{}` cannot name a ROS 2 topic: {e}", tool.name))?;
    }
    let mut t = Vec::new();
    for tool in &scene.tools {
        t.push(Topic {
            name: format!("{base}/{}/wrench", tool.name),
            message: msgs::WrenchStamped::TYPE_NAME,
            schema: msgs::WrenchStamped::SCHEMA,
            publish: true,
            reliable: true,
            latched: true,
        });
    }
    t.push(Topic {
        name: format!("{base}/tools"),
        message: msgs::JointState::TYPE_NAME,
        schema: msgs::JointState::SCHEMA,
        publish: true,
        reliable: true,
        latched: true,
    });
    t.push(Topic {
        name: format!("{base}/workpiece"),
        message: msgs::PointCloud2::TYPE_NAME,
        schema: msgs::PointCloud2::SCHEMA,
        publish: true,
        reliable: false,
        latched: false,
    });
    t.push(Topic {
        name: format!("{base}/tool_markers"),
        message: msgs::MarkerArray::TYPE_NAME,
        schema: msgs::MarkerArray::SCHEMA,
        publish: true,
        reliable: true,
        latched: true,
    });
    t.push(Topic {
        name: format!("{base}/die_fill"),
        message: msgs::DieFill::TYPE_NAME,
        schema: msgs::DieFill::SCHEMA,
        publish: true,
        reliable: true,
        latched: true,
    });
    t.push(Topic {
        name: format!("{base}/laps"),
        message: msgs::Laps::TYPE_NAME,
        schema: msgs::Laps::SCHEMA,
        publish: true,
        reliable: true,
        latched: true,
    });
    t.push(Topic {
        name: format!("{base}/energy"),
        message: msgs::Energy::TYPE_NAME,
        schema: msgs::Energy::SCHEMA,
        publish: true,
        reliable: true,
        latched: true,
    });
    t.push(Topic {
        name: format!("{base}/outputs"),
        message: msgs::Outputs::TYPE_NAME,
        schema: msgs::Outputs::SCHEMA,
        publish: true,
        reliable: true,
        latched: true,
    });
    t.push(Topic {
        name: "/clock".into(),
        message: msgs::Clock::TYPE_NAME,
        schema: msgs::Clock::SCHEMA,
        publish: true,
        reliable: true,
        latched: true,
    });
    for tool in scene
        .tools
        .iter()
        .filter(|t| !matches!(t.motion, Motion::Fixed))
    {
        t.push(Topic {
            name: format!("{base}/{}/velocity_cmd", tool.name),
            message: msgs::Float64::TYPE_NAME,
            schema: msgs::Float64::SCHEMA,
            publish: false,
            reliable: true,
            latched: false,
        });
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn namespaces_follow_ros2_rules() {
        assert!(validate_namespace("/rkforge").is_ok());
        assert!(validate_namespace("/press_1/forge").is_ok());
        for bad in ["rkforge", "/rk forge", "/1press", "/a//b", "/a/"] {
            assert!(validate_namespace(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_fixed_tool_has_no_command_topic() {
        let scene =
            Scene::from_str_named(include_str!("../../scenes/taylor_bar.toml"), "t").unwrap();
        let t = topics(&scene, "/rkforge").unwrap();
        assert!(t
            .iter()
            .any(|t| t.name == "/rkforge/wall/wrench" && t.publish));
        assert!(!t.iter().any(|t| t.name.ends_with("velocity_cmd")));
        assert!(t.iter().any(|t| t.name == "/clock"));
    }
}
