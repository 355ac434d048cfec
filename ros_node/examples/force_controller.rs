//! A ROS 2 force controller for an rkforge press: it subscribes to `NS/tools`
//! (`sensor_msgs/msg/JointState`) and publishes `NS/<tool>/velocity_cmd` (`std_msgs/msg/Float64`)
//! so that the force resisting the tool's stroke holds a set point.
//!
//! The force resisting the stroke is minus the effort (the effort is the force of the
//! workpiece along the tool's axis, negative while the tool presses). The command is a PI law
//! on the relative force error, clamped to `[0, max velocity]`:
//! `v = v_max * clamp(kp * e + ki * integral(e dt), 0, 1)` with `e = (F_set - F) / F_set`,
//! the integral frozen while the output is at a limit.
//! It answers each joint state (each stamp) once, so it works with `rkforge-ros --lockstep`;
//! a sample the node republishes (no answer came within 250 ms) gets the same answer again.
//!
//! ```text
//! ROS_DOMAIN_ID=7 rkforge-ros scenes/block_forging.toml --lockstep &
//! ROS_DOMAIN_ID=7 cargo run --release -p rkforge-ros --example force_controller -- \
//!     --tool top --force 2.0e8 --max-velocity 10 --other bottom
//! ```

use clap::Parser;
use rkforge_ros::dds::domain_id_from_env;
use rkforge_ros::msgs::{Float64, JointState, Time};
use ros2_client::dds::{Context, Publisher};
use ros2_client::qos::{Durability, History, Reliability, WhenFull};
use ros2_client::{ContextOptions, MessageTypeName, Name, NodeName, NodeOptions, QosProfile};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(about = "Hold a press force set point by commanding a tool's velocity over ROS 2")]
struct Args {
    /// Namespace of the rkforge node.
    #[arg(long, default_value = "/rkforge")]
    namespace: String,
    /// Tool to control.
    #[arg(long)]
    tool: String,
    /// Force set point, resisting the stroke (N).
    #[arg(long)]
    force: f64,
    /// Largest velocity command (m/s).
    #[arg(long, default_value_t = 10.0)]
    max_velocity: f64,
    /// Proportional gain on the relative force error.
    #[arg(long, default_value_t = 1.0)]
    kp: f64,
    /// Integral gain on the relative force error (1/s).
    #[arg(long, default_value_t = 0.0)]
    ki: f64,
    /// Other movable tools, commanded with the same velocity (e.g. the lower die).
    #[arg(long, value_delimiter = ',')]
    other: Vec<String>,
    /// Stop after this long without a new joint state (s), once one was seen.
    #[arg(long, default_value_t = 3.0)]
    idle_timeout: f64,
}

/// Publish velocity `v` (m/s) on every command topic.
fn send(commands: &[Publisher<Float64>], v: f64) {
    for p in commands {
        if p.publish(Float64 { data: v }).is_err() {
            eprintln!("warning: command {v} m/s not sent (send window full)");
        }
    }
}

fn main() -> Result<(), String> {
    let a = Args::parse();
    if !(a.force.is_finite() && a.force > 0.0) {
        return Err(format!("--force {}: must be positive", a.force));
    }
    let stop = rkforge_ros::signals::stop_flag()?;
    let domain = domain_id_from_env()?;
    let ctx = Context::with_options(ContextOptions::new().domain_id(domain))
        .map_err(|e| format!("DDS domain {domain}: {e:?}"))?;
    let mut node = ctx
        .new_node(
            NodeName::new(&a.namespace, "force_controller").map_err(|e| format!("{e:?}"))?,
            NodeOptions::new().enable_rosout(false),
        )
        .map_err(|e| format!("{e:?}"))?;
    let qos = QosProfile {
        reliability: Reliability::Reliable {
            when_full: WhenFull::Fail,
        },
        durability: Durability::Volatile,
        history: History::KeepLast { depth: 10 },
        ..QosProfile::publisher_default()
    };
    let name = |base: &str| {
        Name::parse(&format!("{}/{base}", a.namespace.trim_end_matches('/')))
            .map_err(|e| format!("{base}: {e:?}"))
    };
    let tools_topic = node
        .create_topic(
            &name("tools")?,
            MessageTypeName::new("sensor_msgs", "JointState"),
            &qos,
        )
        .map_err(|e| format!("{e:?}"))?;
    let states = node
        .create_subscription::<JointState>(&tools_topic, Some(qos.clone()))
        .map_err(|e| format!("{e:?}"))?;
    let mut commands = Vec::new();
    for tool in std::iter::once(&a.tool).chain(&a.other) {
        let topic = node
            .create_topic(
                &name(&format!("{tool}/velocity_cmd"))?,
                MessageTypeName::new("std_msgs", "Float64"),
                &qos,
            )
            .map_err(|e| format!("{e:?}"))?;
        commands.push(
            node.create_publisher::<Float64>(&topic, Some(qos.clone()))
                .map_err(|e| format!("{e:?}"))?,
        );
    }
    eprintln!(
        "force_controller: holding {} N on {}/{} (domain {domain})",
        a.force, a.namespace, a.tool
    );
    let mut last: Option<(Time, f64, f64)> = None;
    let mut integral = 0.0;
    let mut seen = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        let Ok(Some((js, _))) = states.take() else {
            if last.is_some() && seen.elapsed().as_secs_f64() > a.idle_timeout {
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
            continue;
        };
        seen = Instant::now();
        let stamp = js.header.stamp;
        if let Some((s, _, v)) = last {
            if s == stamp {
                // The node republishes a sample only when no answer came within 250 ms: the
                // answer was lost (e.g. sent before discovery finished). Send it again; the
                // law's state does not advance.
                send(&commands, v);
                continue;
            }
        }
        let Some(k) = js.name.iter().position(|n| *n == a.tool) else {
            return Err(format!("no tool `{}` in {}/tools", a.tool, a.namespace));
        };
        let (Some(effort), Some(stroke)) = (js.effort.get(k), js.position.get(k)) else {
            return Err(format!("joint state without effort for `{}`", a.tool));
        };
        let t = f64::from(stamp.sec) + 1e-9 * f64::from(stamp.nanosec);
        let dt = last.map_or(0.0, |(_, t0, _)| t - t0);
        let error = (a.force + effort) / a.force;
        // Conditional integration (anti-windup): integrate only while the output is not
        // held at a limit.
        let trial = a.kp * error + a.ki * (integral + error * dt);
        if (0.0..=1.0).contains(&trial) {
            integral += error * dt;
        }
        let v = a.max_velocity * (a.kp * error + a.ki * integral).clamp(0.0, 1.0);
        send(&commands, v);
        println!(
            "t {t:e} s stroke {stroke:e} m force {:e} N -> {v:e} m/s",
            -effort
        );
        last = Some((stamp, t, v));
    }
    Ok(())
}
