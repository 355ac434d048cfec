//! The ROS 2 messages of an rkforge run and their recording, without DDS: which topics a
//! run publishes and subscribes to, with their standard message types, under a namespace
//! validated by the ROS 2 naming rules. Used by the ROS 2 node (`rkforge-ros`) and by
//! `rkforge run --mcap`, for scenes of both kinds: a 2D [`Scene`] (plane strain,
//! axisymmetric) run by a [`Simulation`](rkforge_core::Simulation) and a 3D [`SolidScene`]
//! run by a [`SolidSimulation`](rkforge_core::solver::SolidSimulation), through the traits
//! [`PublishedScene`] and [`frame::Published`].
//!
//! - [`msgs`]: the standard messages, generated from the `.msg` files in `messages/msg`, and
//!   their CDR encoding;
//! - [`frame`]: the messages of one sample of a simulation of either kind;
//! - [`record`]: the MCAP recorder (used by `rkforge-ros --record` and `rkforge run --mcap`);
//! - [`signals`]: SIGINT and SIGTERM as a flag, so that a run stops and finishes its files.
//!
//! Feature `dds`: the messages also implement `ros2_client::Message`, for the node.

pub mod frame;
pub mod msgs;
pub mod record;
pub mod signals;

use msgs::RosMessage;
use rkforge_core::scene::solid::ShapeKind;
use rkforge_core::scene::{Kinematics, Motion, Scene, SolidScene, TimeSpec};

/// What the topics and the recording's metadata read of a scene of either kind: a 2D
/// [`Scene`] or a 3D [`SolidScene`].
pub trait PublishedScene: std::fmt::Debug {
    /// The scene's short name.
    fn scene_name(&self) -> &str;
    /// The scene's free-text description.
    fn scene_description(&self) -> &str;
    /// `model.kinematics` as the scene file writes it: `plane_strain`, `axisymmetric` or
    /// `3d`.
    fn kinematics_name(&self) -> &'static str;
    /// The integration rule's name (`q4`, `q2`, `scni`).
    fn integration_name(&self) -> &'static str;
    /// The scene's `[time]` table.
    fn time_spec(&self) -> &TimeSpec;
    /// The grid as the recording's metadata gives it: `resolution`, the particle counts of
    /// a 2D scene (`21x21`), or the grid key of a 3D one (a cylinder's `workpiece.cells`, a
    /// box's `workpiece.particles`, `4x2x24`) with `resolution_key` naming that key.
    fn grid(&self) -> Vec<(&'static str, String)>;
    /// Each tool in scene order: its name and whether it moves (a tool whose motion is not
    /// `fixed` takes velocity commands).
    fn tool_list(&self) -> Vec<(&str, bool)>;
    /// Whether the scene publishes the topics only 2D has: the die fill (fill points and
    /// contact fractions of polyline tools) and the laps (a 2D boundary folding onto
    /// itself). A 3D scene has neither and leaves both topics out.
    fn has_die_fill_and_laps(&self) -> bool;
}

impl PublishedScene for Scene {
    fn scene_name(&self) -> &str {
        &self.name
    }
    fn scene_description(&self) -> &str {
        &self.description
    }
    fn kinematics_name(&self) -> &'static str {
        match self.model.kinematics {
            Kinematics::PlaneStrain => "plane_strain",
            Kinematics::Axisymmetric => "axisymmetric",
        }
    }
    fn integration_name(&self) -> &'static str {
        self.discretization.integration.name()
    }
    fn time_spec(&self) -> &TimeSpec {
        &self.time
    }
    fn grid(&self) -> Vec<(&'static str, String)> {
        let [nx, ny] = self.workpiece.particles;
        vec![("resolution", format!("{nx}x{ny}"))]
    }
    fn tool_list(&self) -> Vec<(&str, bool)> {
        self.tools
            .iter()
            .map(|t| (t.name.as_str(), !matches!(t.motion, Motion::Fixed)))
            .collect()
    }
    fn has_die_fill_and_laps(&self) -> bool {
        true
    }
}

impl PublishedScene for SolidScene {
    fn scene_name(&self) -> &str {
        &self.name
    }
    fn scene_description(&self) -> &str {
        &self.description
    }
    fn kinematics_name(&self) -> &'static str {
        "3d"
    }
    fn integration_name(&self) -> &'static str {
        self.discretization.integration.name()
    }
    fn time_spec(&self) -> &TimeSpec {
        &self.time
    }
    fn grid(&self) -> Vec<(&'static str, String)> {
        let w = &self.workpiece;
        let (key, grid) = match w.shape {
            ShapeKind::Cylinder => ("workpiece.cells", w.cells),
            ShapeKind::Box => ("workpiece.particles", w.particles),
        };
        let text = grid.map_or_else(String::new, |g| g.map(|n| n.to_string()).join("x"));
        vec![("resolution", text), ("resolution_key", key.to_owned())]
    }
    fn tool_list(&self) -> Vec<(&str, bool)> {
        self.tools
            .iter()
            .map(|t| (t.name.as_str(), !matches!(t.motion, Motion::Fixed)))
            .collect()
    }
    fn has_die_fill_and_laps(&self) -> bool {
        false
    }
}

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

/// The topics of a scene of either kind under namespace `ns`: first the published ones in
/// the order of the messages of a [`frame::Sample`] (one wrench per tool in scene order,
/// `tools`, `workpiece`, `tool_markers`, `die_fill` and `laps` (2D scenes only, see
/// [`PublishedScene::has_die_fill_and_laps`]), `energy`, `outputs`, `/clock`), then one
/// `velocity_cmd` subscription per movable tool.
///
/// # Errors
///
/// The namespace breaks the ROS 2 naming rules, or a tool name is not a valid topic token.
pub fn topics<S: PublishedScene + ?Sized>(scene: &S, ns: &str) -> Result<Vec<Topic>, String> {
    validate_namespace(ns)?;
    let base = ns.trim_end_matches('/');
    let tools = scene.tool_list();
    for (name, _) in &tools {
        validate_namespace(&format!("/{name}"))
            .map_err(|e| format!("tool `{name}` cannot name a ROS 2 topic: {e}"))?;
    }
    let mut t = Vec::new();
    for (name, _) in &tools {
        t.push(Topic {
            name: format!("{base}/{name}/wrench"),
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
    if scene.has_die_fill_and_laps() {
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
    }
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
    for (name, _) in tools.iter().filter(|(_, moves)| *moves) {
        t.push(Topic {
            name: format!("{base}/{name}/velocity_cmd"),
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

    /// A 3D scene publishes the topics of 2D but the die fill and the laps, and a command
    /// topic for a tool that moves.
    #[test]
    fn a_3d_scene_has_no_die_fill_or_laps_topics() {
        let text = include_str!("../../scenes/taylor_bar_3d.toml");
        let scene = SolidScene::from_str_named(text, "t").unwrap();
        let t = topics(&scene, "/rkforge").unwrap();
        let names: Vec<&str> = t.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "/rkforge/wall/wrench",
                "/rkforge/tools",
                "/rkforge/workpiece",
                "/rkforge/tool_markers",
                "/rkforge/energy",
                "/rkforge/outputs",
                "/clock"
            ]
        );
        assert!(t.iter().all(|t| t.publish));
        let moving = text.replace(
            r#"motion = { kind = "fixed" }"#,
            r#"motion = { kind = "external" }"#,
        );
        let scene = SolidScene::from_str_named(&moving, "t").unwrap();
        let t = topics(&scene, "/rkforge").unwrap();
        let last = t.last().unwrap();
        assert_eq!(last.name, "/rkforge/wall/velocity_cmd");
        assert!(!last.publish && last.message == "std_msgs/msg/Float64");
    }
}
