//! The ROS 2 interface of an rkforge scene: which topics a run publishes and subscribes to,
//! with their standard message types, under a namespace validated by the ROS 2 naming rules;
//! [`msgs`] holds the standard message definitions (schema texts) and their CDR encoding.

pub mod msgs;

use rkforge_core::scene::{Motion, Scene};

/// A topic with its ROS 2 message type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Topic {
    /// Fully qualified name.
    pub name: String,
    /// Message type, e.g. `geometry_msgs/msg/WrenchStamped`.
    pub message: &'static str,
    /// Whether the node publishes (true) or subscribes (false).
    pub publish: bool,
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

/// The topics of a scene under namespace `ns`.
pub fn topics(scene: &Scene, ns: &str) -> Result<Vec<Topic>, String> {
    validate_namespace(ns)?;
    let base = ns.trim_end_matches('/');
    let mut t = Vec::new();
    for tool in &scene.tools {
        t.push(Topic {
            name: format!("{base}/{}/wrench", tool.name),
            message: "geometry_msgs/msg/WrenchStamped",
            publish: true,
        });
    }
    t.push(Topic {
        name: format!("{base}/tools"),
        message: "sensor_msgs/msg/JointState",
        publish: true,
    });
    t.push(Topic {
        name: format!("{base}/workpiece"),
        message: "sensor_msgs/msg/PointCloud2",
        publish: true,
    });
    t.push(Topic {
        name: format!("{base}/tool_markers"),
        message: "visualization_msgs/msg/MarkerArray",
        publish: true,
    });
    t.push(Topic {
        name: "/clock".into(),
        message: "rosgraph_msgs/msg/Clock",
        publish: true,
    });
    for tool in scene
        .tools
        .iter()
        .filter(|t| !matches!(t.motion, Motion::Fixed))
    {
        t.push(Topic {
            name: format!("{base}/{}/velocity_cmd", tool.name),
            message: "std_msgs/msg/Float64",
            publish: false,
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
