//! One sample of a running simulation as the CDR-encoded messages of every published topic.
//!
//! A sample is taken at one instant of simulation time and holds, in the order of the published
//! topics of [`topics`](crate::topics):
//!
//! - per tool, `geometry_msgs/msg/WrenchStamped`: the force of the workpiece on the tool (N;
//!   history.csv's `force_x_N`, `force_y_N`), zero torque;
//! - `sensor_msgs/msg/JointState`, one entry per tool in scene order: position = stroke (m),
//!   velocity (m/s) and effort = force along the tool's axis (N), as history.csv's `stroke_m`,
//!   `velocity_m_per_s` and `force_N`;
//! - `sensor_msgs/msg/PointCloud2` of the particles: `x`, `y`, `z` (m; the 2D model's plane is
//!   z = 0, axisymmetric scenes put r on x and z on y), `plastic_strain`, `von_mises` (Pa) and,
//!   in a scene with temperature, `temperature` (degrees C), all `float32`, from
//!   [`Simulation::fields`];
//! - `visualization_msgs/msg/MarkerArray`: one line strip per tool through its current vertices;
//! - `rkforge_msgs/msg/DieFill`: each tool's contact fraction and each fill point's filling
//!   time and stroke (NaN while empty), history.csv's `contact_fraction` and `filled` columns;
//! - `rkforge_msgs/msg/Laps`: the laps so far, when and at which strokes each formed, where it
//!   formed and is now, and its length (summary.json's `laps`, history.csv's
//!   `workpiece.laps`);
//! - `rkforge_msgs/msg/Energy`: the energy account (J), history.csv's energy columns;
//! - `rkforge_msgs/msg/Outputs`: every column of the register of outputs
//!   ([`rkforge_core::outputs`]) with its unit and value, history.csv's columns bit for bit
//!   and the figures only the summary and the FMU show (an output added to the register
//!   appears here);
//! - `rosgraph_msgs/msg/Clock`: the simulation time.
//!
//! Every header stamp is the simulation time rounded to the nearest nanosecond, in frame
//! [`FRAME_ID`]. Forces are per metre of depth in plane strain and for the whole ring in
//! axisymmetry, as in history.csv.

use crate::msgs::{
    point_cloud_xyz_fields, Clock, ColorRGBA, DieFill, Energy, Header, JointState, Laps, Marker,
    MarkerArray, Outputs, Point, RosMessage, StrainPoint, Time, Vector3, Wrench, WrenchStamped,
};
use rkforge_core::outputs;
use rkforge_core::Simulation;

/// The coordinate frame of every message: the scene's plane, SI units.
pub const FRAME_ID: &str = "rkforge";

/// Width of the tool outlines (m), as a fraction of the workpiece's larger size.
const LINE_WIDTH_REL: f64 = 0.01;

/// The messages of one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// Simulation time (s).
    pub time: f64,
    /// Simulation time in whole nanoseconds: the header stamps and the MCAP log time.
    pub nanos: u64,
    /// Serialized messages (CDR with encapsulation header), one per published topic in the
    /// order of [`topics`](crate::topics).
    pub messages: Vec<Vec<u8>>,
}

/// Simulation time `t` (s) in whole nanoseconds, rounded to the nearest; negative and NaN
/// times give zero.
#[must_use]
pub fn nanos(t: f64) -> u64 {
    let n = (t * 1e9).round();
    if n.is_nan() || n <= 0.0 {
        0
    } else {
        // Saturating float-to-int cast: times beyond 584 years are clamped.
        n as u64
    }
}

/// `builtin_interfaces/Time` of `nanos` nanoseconds, saturating at `i32::MAX` seconds.
#[must_use]
pub fn stamp(nanos: u64) -> Time {
    let sec = nanos / 1_000_000_000;
    match i32::try_from(sec) {
        Ok(sec) => Time {
            sec,
            nanosec: (nanos % 1_000_000_000) as u32,
        },
        Err(_) => Time {
            sec: i32::MAX,
            nanosec: 999_999_999,
        },
    }
}

/// The messages of the current state of `sim`.
#[must_use]
pub fn sample(sim: &Simulation) -> Sample {
    let time = sim.time();
    let n = nanos(time);
    let header = Header {
        stamp: stamp(n),
        frame_id: FRAME_ID.to_owned(),
    };
    let tools = sim.tools();
    let now = outputs::Sample::new(sim);
    let mut messages = Vec::with_capacity(tools.len() + 8);
    for t in tools {
        let f = t.state.force;
        messages.push(
            WrenchStamped {
                header: header.clone(),
                wrench: Wrench {
                    force: Vector3 {
                        x: f[0],
                        y: f[1],
                        z: 0.0,
                    },
                    torque: Vector3::default(),
                },
            }
            .to_cdr(),
        );
    }
    messages.push(
        JointState {
            header: header.clone(),
            name: tools.iter().map(|t| t.name.clone()).collect(),
            position: tools.iter().map(|t| t.state.stroke).collect(),
            velocity: tools.iter().map(|t| t.state.velocity).collect(),
            effort: tools.iter().map(|t| t.axial_force()).collect(),
        }
        .to_cdr(),
    );
    let fields = now.particle_fields();
    let points: Vec<StrainPoint> = fields
        .positions
        .iter()
        .zip(&fields.plastic_strain)
        .zip(&fields.von_mises)
        .enumerate()
        .map(|(j, ((p, &e), &s))| StrainPoint {
            x: p[0] as f32,
            y: p[1] as f32,
            z: 0.0,
            plastic_strain: e as f32,
            von_mises: s as f32,
            temperature: fields.temperature.as_ref().map_or(0.0, |t| t[j] as f32),
        })
        .collect();
    let hot = fields.temperature.is_some();
    messages.push(point_cloud_xyz_fields(header.clone(), &points, hot).to_cdr());
    messages.push(tool_markers(sim, &header).to_cdr());
    let fill = sim.fill_points();
    messages.push(
        DieFill {
            header: header.clone(),
            tools: tools.iter().map(|t| t.name.clone()).collect(),
            contact_fraction: (0..tools.len()).map(|k| sim.contact_fraction(k)).collect(),
            points: fill
                .iter()
                .map(|p| format!("{}.{}", tools[p.tool].name, p.name))
                .collect(),
            filled_time: fill
                .iter()
                .map(|p| p.filled.map_or(f64::NAN, |f| f.time_s))
                .collect(),
            filled_stroke: fill
                .iter()
                .map(|p| p.filled.map_or(f64::NAN, |f| f.stroke_m))
                .collect(),
        }
        .to_cdr(),
    );
    let laps = sim.laps();
    messages.push(
        Laps {
            header: header.clone(),
            tools: tools.iter().map(|t| t.name.clone()).collect(),
            formed_time: laps.iter().map(|l| l.formed_s).collect(),
            formed_stroke: laps
                .iter()
                .flat_map(|l| l.formed_strokes_m.iter().copied())
                .collect(),
            start_x: laps.iter().map(|l| l.start_m[0]).collect(),
            start_y: laps.iter().map(|l| l.start_m[1]).collect(),
            end_x: laps.iter().map(|l| l.end_m[0]).collect(),
            end_y: laps.iter().map(|l| l.end_m[1]).collect(),
            length: laps.iter().map(|l| l.length_m).collect(),
        }
        .to_cdr(),
    );
    let e = sim.energy();
    messages.push(
        Energy {
            header: header.clone(),
            initial: e.initial,
            kinetic: e.kinetic,
            elastic: e.elastic,
            plastic: e.plastic,
            internal: e.internal(),
            contact_work: e.contact_work,
            tool_work: e.tool_work,
        }
        .to_cdr(),
    );
    let register = outputs::columns(sim.scene());
    messages.push(
        Outputs {
            header: header.clone(),
            names: register.iter().map(|c| c.name.clone()).collect(),
            units: register.iter().map(|c| c.unit().to_owned()).collect(),
            values: register.iter().map(|c| c.value(&now)).collect(),
        }
        .to_cdr(),
    );
    messages.push(
        Clock {
            clock: header.stamp,
        }
        .to_cdr(),
    );
    Sample {
        time,
        nanos: n,
        messages,
    }
}

/// One line strip per tool (namespace `tools`, id = tool index) through its current vertices.
fn tool_markers(sim: &Simulation, header: &Header) -> MarkerArray {
    let size = sim.scene().workpiece.size_m;
    let width = LINE_WIDTH_REL * size[0].max(size[1]);
    let palette = [
        [0.85, 0.33, 0.10],
        [0.00, 0.45, 0.74],
        [0.47, 0.67, 0.19],
        [0.49, 0.18, 0.56],
    ];
    let markers = sim
        .tools()
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let [r, g, b] = palette[k % palette.len()];
            Marker {
                header: header.clone(),
                ns: "tools".to_owned(),
                id: i32::try_from(k).unwrap_or(i32::MAX),
                r#type: Marker::LINE_STRIP,
                action: Marker::ADD,
                scale: Vector3 {
                    x: width,
                    ..Vector3::default()
                },
                color: ColorRGBA { r, g, b, a: 1.0 },
                points: t
                    .vertices()
                    .iter()
                    .map(|v| Point {
                        x: v[0],
                        y: v[1],
                        z: 0.0,
                    })
                    .collect(),
                text: t.name.clone(),
                ..Marker::default()
            }
        })
        .collect();
    MarkerArray { markers }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::{Clock, Energy, JointState, Outputs, RosMessage, WrenchStamped};
    use rkforge_core::Scene;

    fn block() -> Simulation {
        let text = include_str!("../../scenes/block_forging.toml")
            .replace("particles = [21, 21]", "particles = [6, 6]");
        Simulation::new(&Scene::from_str_named(&text, "block").unwrap()).unwrap()
    }

    #[test]
    fn nanoseconds_round_to_nearest() {
        assert_eq!(nanos(0.5e-6 * 7.0), 3500);
        assert_eq!(nanos(-1.0), 0);
        assert_eq!(nanos(f64::NAN), 0);
        let t = stamp(3_000_000_123);
        assert_eq!((t.sec, t.nanosec), (3, 123));
        assert_eq!(stamp(u64::MAX).sec, i32::MAX);
    }

    #[test]
    fn a_sample_holds_the_tool_state_in_topic_order() {
        let mut sim = block();
        for _ in 0..20 {
            sim.step(None).unwrap();
        }
        let s = sample(&sim);
        let topics = crate::topics(sim.scene(), "/rkforge").unwrap();
        let published = topics.iter().filter(|t| t.publish).count();
        assert_eq!(s.messages.len(), published);
        let w = WrenchStamped::from_cdr(&s.messages[0]).unwrap();
        assert_eq!(w.header.stamp, stamp(nanos(sim.time())));
        assert_eq!(w.wrench.force.x, sim.tools()[0].state.force[0]);
        assert_eq!(w.wrench.force.y, sim.tools()[0].state.force[1]);
        let j = JointState::from_cdr(&s.messages[2]).unwrap();
        assert_eq!(j.name, ["top", "bottom"]);
        assert_eq!(j.position[1], sim.tools()[1].state.stroke);
        assert_eq!(j.velocity[0], 10.0);
        assert_eq!(j.effort[0], sim.tools()[0].axial_force());
        let e = Energy::from_cdr(&s.messages[published - 3]).unwrap();
        assert_eq!(e.header, w.header);
        let account = sim.energy();
        assert_eq!((e.kinetic, e.plastic), (account.kinetic, account.plastic));
        assert_eq!(e.internal, account.elastic + account.plastic);
        assert_eq!(e.tool_work, account.tool_work);
        assert!(
            e.tool_work > 0.0 && e.internal > 0.0,
            "the tools are forging"
        );
        let o = Outputs::from_cdr(&s.messages[published - 2]).unwrap();
        assert_eq!(o.header, w.header);
        assert_eq!(o.names.len(), o.values.len());
        assert_eq!(o.units.len(), o.values.len());
        let value = |name: &str| o.values[o.names.iter().position(|n| n == name).unwrap()];
        assert_eq!(value("top.force_N"), sim.tools()[0].axial_force());
        assert_eq!(value("energy.plastic_J"), account.plastic);
        let p = value("top.pressure_mean_Pa");
        assert!(p > 0.0, "{p}");
        assert_eq!(
            o.units[o.names.iter().position(|n| n == "top.force_N").unwrap()],
            "N"
        );
        let c = Clock::from_cdr(s.messages.last().unwrap()).unwrap();
        assert_eq!(c.clock, w.header.stamp);
        // 36 particles of 20 bytes at the end of the cloud, before is_dense.
        assert!(s.messages[3].len() > 36 * 20);
    }
}
