//! One sample of a running simulation as the CDR-encoded messages of every published topic,
//! for a 2D [`Simulation`] and a 3D [`SolidSimulation`] alike ([`Published`]).
//!
//! A sample is taken at one instant of simulation time and holds, in the order of the published
//! topics of [`topics`](crate::topics):
//!
//! - per tool, `geometry_msgs/msg/WrenchStamped`: the force of the workpiece on the tool (N;
//!   history.csv's `force_x_N`, `force_y_N`, and in 3D `force_z_N`; z is 0 in 2D), zero
//!   torque;
//! - `sensor_msgs/msg/JointState`, one entry per tool in scene order: position = stroke (m),
//!   velocity (m/s) and effort = force along the tool's axis (N), as history.csv's `stroke_m`,
//!   `velocity_m_per_s` and `force_N`;
//! - `sensor_msgs/msg/PointCloud2` of the particles: `x`, `y`, `z` (m; the 2D model's plane is
//!   z = 0, axisymmetric scenes put r on x and z on y, a 3D scene gives its own x, y, z),
//!   `plastic_strain`, `von_mises` (Pa) and, in a scene with temperature, `temperature`
//!   (degrees C), all `float32`: the points' values smoothed to the particles with weights
//!   `|N_I| w_p` ([`Simulation::fields`], [`SolidSimulation::particle_means`]);
//! - `visualization_msgs/msg/MarkerArray`: one line strip per tool, through its current
//!   vertices in 2D; in 3D a closed loop round the patch of the tool's plane (in its current
//!   position) that the workpiece's bounding box covers, projected onto the plane;
//! - 2D only: `rkforge_msgs/msg/DieFill`, each tool's contact fraction and each fill point's
//!   filling time and stroke (NaN while empty), history.csv's `contact_fraction` and
//!   `filled` columns; and `rkforge_msgs/msg/Laps`, the laps so far, when and at which
//!   strokes each formed, where it formed and is now, and its length (summary.json's `laps`,
//!   history.csv's `workpiece.laps`). A 3D scene has no fill points and no laps, and its
//!   sample leaves both messages out (as its topics do) rather than publishing them empty;
//! - `rkforge_msgs/msg/Energy`: the energy account (J), history.csv's energy columns;
//! - `rkforge_msgs/msg/Outputs`: every column of the scene's register of outputs
//!   ([`rkforge_core::outputs`]: [`outputs::columns`] in 2D, [`outputs::solid_columns`] in
//!   3D) with its unit and value, history.csv's columns bit for bit and the figures only the
//!   summary and the FMU show (an output added to the register appears here);
//! - `rosgraph_msgs/msg/Clock`: the simulation time.
//!
//! Every header stamp is the simulation time rounded to the nearest nanosecond, in frame
//! [`FRAME_ID`]. Forces are per metre of depth in plane strain, for the whole ring in
//! axisymmetry and for the modelled part (a half or a quarter) in 3D, as in history.csv.

use crate::msgs::{
    point_cloud_xyz_fields, Clock, ColorRGBA, DieFill, Energy, Header, JointState, Laps, Marker,
    MarkerArray, Outputs, Point, RosMessage, StrainPoint, Time, Vector3, Wrench, WrenchStamped,
};
use crate::PublishedScene;
use rkforge_core::math::{dot, Real};
use rkforge_core::outputs::{self, Body, Column, Since};
use rkforge_core::solid_tool::{normal_to, Cylinder, Surface};
use rkforge_core::solver::SolidSimulation;
use rkforge_core::Simulation;

/// The coordinate frame of every message: the scene's plane, or its space in 3D, SI units.
pub const FRAME_ID: &str = "rkforge";

/// Width of the tool outlines (m), as a fraction of the workpiece's larger size.
const LINE_WIDTH_REL: f64 = 0.01;

/// The colours of the tools' markers (red, green, blue), tool by tool in scene order.
const PALETTE: [[f32; 3]; 4] = [
    [0.85, 0.33, 0.10],
    [0.00, 0.45, 0.74],
    [0.47, 0.67, 0.19],
    [0.49, 0.18, 0.56],
];

/// What a sample reads of a tool.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolReading {
    /// The tool's name.
    pub name: String,
    /// Force of the workpiece on the tool (N), x, y, z (z = 0 in 2D).
    pub force: [f64; 3],
    /// Displacement along the tool's axis (m).
    pub stroke: f64,
    /// Velocity along the axis during the last step (m/s).
    pub velocity: f64,
    /// Force along the axis (N), positive pushing the tool along +axis.
    pub axial_force: f64,
}

/// A simulation whose state the messages publish: the 2D [`Simulation`] and the 3D
/// [`SolidSimulation`]. Each reading is taken through an [`outputs::Sample`] of it (which
/// dereferences to the simulation), so the measures the outputs share are taken once.
pub trait Published: Body {
    /// The kind of scene the simulation runs.
    type Scene: PublishedScene;
    /// Each tool of the scene, in scene order.
    fn tool_readings(now: &outputs::Sample<'_, Self>) -> Vec<ToolReading>;
    /// The particles of the point cloud, and whether the cloud has the `temperature` field.
    fn cloud(now: &outputs::Sample<'_, Self>) -> (Vec<StrainPoint>, bool);
    /// Each tool's marker points (m), tool by tool, and the outlines' width (m).
    fn marker_lines(now: &outputs::Sample<'_, Self>) -> (Vec<Vec<Point>>, f64);
    /// The messages between the markers and the energy account that only some scenes have
    /// (2D: the die fill and the laps; none in 3D), CDR-encoded.
    fn extra_messages(now: &outputs::Sample<'_, Self>, header: &Header) -> Vec<Vec<u8>>;
    /// Every column of the scene's register of outputs.
    fn register_columns(&self) -> Vec<Column<Self>>;
}

impl Published for Simulation {
    type Scene = rkforge_core::Scene;
    fn tool_readings(now: &outputs::Sample<'_, Self>) -> Vec<ToolReading> {
        now.tools()
            .iter()
            .map(|t| ToolReading {
                name: t.name.clone(),
                force: [t.state.force[0], t.state.force[1], 0.0],
                stroke: t.state.stroke,
                velocity: t.state.velocity,
                axial_force: t.axial_force(),
            })
            .collect()
    }
    fn cloud(now: &outputs::Sample<'_, Self>) -> (Vec<StrainPoint>, bool) {
        let fields = now.particle_fields();
        let points = fields
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
        (points, fields.temperature.is_some())
    }
    fn marker_lines(now: &outputs::Sample<'_, Self>) -> (Vec<Vec<Point>>, f64) {
        let size = now.scene().workpiece.size_m;
        let lines = now
            .tools()
            .iter()
            .map(|t| {
                t.vertices()
                    .iter()
                    .map(|v| Point {
                        x: v[0],
                        y: v[1],
                        z: 0.0,
                    })
                    .collect()
            })
            .collect();
        (lines, LINE_WIDTH_REL * size[0].max(size[1]))
    }
    fn extra_messages(now: &outputs::Sample<'_, Self>, header: &Header) -> Vec<Vec<u8>> {
        let tools = now.tools();
        let fill = now.fill_points();
        let die_fill = DieFill {
            header: header.clone(),
            tools: tools.iter().map(|t| t.name.clone()).collect(),
            contact_fraction: (0..tools.len()).map(|k| now.contact_fraction(k)).collect(),
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
        };
        let laps = now.laps();
        let laps = Laps {
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
        };
        vec![die_fill.to_cdr(), laps.to_cdr()]
    }
    fn register_columns(&self) -> Vec<Column<Self>> {
        outputs::columns(self.scene())
    }
}

impl Published for SolidSimulation {
    type Scene = rkforge_core::scene::SolidScene;
    fn tool_readings(now: &outputs::Sample<'_, Self>) -> Vec<ToolReading> {
        now.tools()
            .iter()
            .map(|t| ToolReading {
                name: t.name.clone(),
                force: t.state.force,
                stroke: t.state.stroke,
                velocity: t.state.velocity,
                axial_force: t.axial_force(),
            })
            .collect()
    }
    fn cloud(now: &outputs::Sample<'_, Self>) -> (Vec<StrainPoint>, bool) {
        let plastic_strain = now.particle_means(&now.point_plastic_strain());
        let von_mises = now.particle_means(&now.point_von_mises());
        let temperature = now.point_temperature().map(|t| now.particle_means(t));
        let points = now
            .positions()
            .iter()
            .enumerate()
            .map(|(j, p)| StrainPoint {
                x: p[0] as f32,
                y: p[1] as f32,
                z: p[2] as f32,
                plastic_strain: plastic_strain[j] as f32,
                von_mises: von_mises[j] as f32,
                temperature: temperature.as_ref().map_or(0.0, |t| t[j] as f32),
            })
            .collect();
        (points, temperature.is_some())
    }
    fn marker_lines(now: &outputs::Sample<'_, Self>) -> (Vec<Vec<Point>>, f64) {
        let bounds = now.readings().extents;
        let lines = now
            .tools()
            .iter()
            .map(|t| {
                let s = t.state.stroke;
                let line: Vec<[Real; 3]> = match &t.surface {
                    Surface::Plane { point0, normal } => {
                        let origin: [Real; 3] = std::array::from_fn(|k| point0[k] + s * t.axis[k]);
                        plane_patch(origin, *normal, bounds).to_vec()
                    }
                    Surface::Cylinder(c) => cylinder_outline(c, t.axis.map(|a| s * a), bounds),
                    Surface::Triangles(tri) => {
                        let b = tri.mesh().bounds();
                        box_outline(std::array::from_fn(|k| b[k].map(|x| x + s * t.axis[k])))
                            .to_vec()
                    }
                };
                line.iter()
                    .map(|p| Point {
                        x: p[0],
                        y: p[1],
                        z: p[2],
                    })
                    .collect()
            })
            .collect();
        let largest = bounds.iter().map(|b| b[1] - b[0]).fold(0.0, Real::max);
        (lines, LINE_WIDTH_REL * largest)
    }
    fn extra_messages(_: &outputs::Sample<'_, Self>, _: &Header) -> Vec<Vec<u8>> {
        Vec::new()
    }
    fn register_columns(&self) -> Vec<Column<Self>> {
        outputs::solid_columns(self.scene())
    }
}

/// A line through the box `bounds` (`[min, max]` of x, y, z; m) drawing its bottom and
/// top loops and one upright edge: an STL tool's place, the bounds of its triangles.
fn box_outline(bounds: [[Real; 2]; 3]) -> [[Real; 3]; 10] {
    let c = |i: usize, z: usize| [bounds[0][i & 1], bounds[1][i >> 1], bounds[2][z]];
    [
        c(0, 0),
        c(1, 0),
        c(3, 0),
        c(2, 0),
        c(0, 0),
        c(0, 1),
        c(1, 1),
        c(3, 1),
        c(2, 1),
        c(0, 1),
    ]
}

/// Points round a cylinder tool shifted by `shift` (m): a loop of 16 chords round its end
/// `a = -H` (`a` along its axis from its centre, `H` half its length), along the mantle to
/// the end `a = +H` and a loop round it. An unbounded cylinder is drawn over the reach of
/// the box `bounds` (`[min, max]` of x, y, z; m) along its axis, about the point of the axis
/// nearest to the box's centre.
fn cylinder_outline(c: &Cylinder, shift: [Real; 3], bounds: [[Real; 2]; 3]) -> Vec<[Real; 3]> {
    const CHORDS: usize = 16;
    let d = c.direction;
    let mut centre: [Real; 3] = std::array::from_fn(|k| c.centre[k] + shift[k]);
    let h = c.half_length.unwrap_or_else(|| {
        let middle: [Real; 3] = std::array::from_fn(|k| 0.5 * (bounds[k][0] + bounds[k][1]));
        let along = dot(&d, &std::array::from_fn(|k| middle[k] - centre[k]));
        centre = std::array::from_fn(|k| centre[k] + along * d[k]);
        (0..3)
            .map(|k| 0.5 * (bounds[k][1] - bounds[k][0]) * d[k].abs())
            .sum()
    });
    let u = normal_to(d);
    let v = cross(&d, &u);
    let mut line = Vec::with_capacity(2 * (CHORDS + 1));
    for end in [-h, h] {
        for i in 0..=CHORDS {
            let (sin, cos) = (i as Real * std::f64::consts::TAU / CHORDS as Real).sin_cos();
            line.push(std::array::from_fn(|k| {
                centre[k] + end * d[k] + c.radius * (cos * u[k] + sin * v[k])
            }));
        }
    }
    line
}

/// The closed loop (five corners, the first repeated; m) round the patch of the plane
/// through `origin` (m) with unit normal `normal` that the box `bounds` (`[min, max]` of x,
/// y, z; m) covers when projected onto it along the normal: centred on the projection of
/// the box's centre, its sides along two unit vectors of the plane (the first normal to the
/// coordinate axis least aligned with the normal), each as long as the box's projection
/// on it.
fn plane_patch(origin: [Real; 3], normal: [Real; 3], bounds: [[Real; 2]; 3]) -> [[Real; 3]; 5] {
    let centre: [Real; 3] = std::array::from_fn(|k| 0.5 * (bounds[k][0] + bounds[k][1]));
    let off: [Real; 3] = std::array::from_fn(|k| centre[k] - origin[k]);
    let h = dot(&normal, &off);
    let c: [Real; 3] = std::array::from_fn(|k| centre[k] - h * normal[k]);
    let least = (0..3)
        .min_by(|&a, &b| normal[a].abs().total_cmp(&normal[b].abs()))
        .unwrap_or(0);
    let mut e = [0.0; 3];
    e[least] = 1.0;
    let u = cross(&e, &normal);
    let norm = dot(&u, &u).sqrt();
    let u: [Real; 3] = u.map(|x| x / norm);
    let v = cross(&normal, &u);
    // Half the box's projection on each side: the half-diagonal's largest reach along it.
    let half = |d: &[Real; 3]| -> Real {
        (0..3)
            .map(|k| 0.5 * (bounds[k][1] - bounds[k][0]) * d[k].abs())
            .sum()
    };
    let (a, b) = (half(&u), half(&v));
    let corner = |su: Real, sv: Real| -> [Real; 3] {
        std::array::from_fn(|k| c[k] + su * a * u[k] + sv * b * v[k])
    };
    let first = corner(1.0, 1.0);
    [
        first,
        corner(-1.0, 1.0),
        corner(-1.0, -1.0),
        corner(1.0, -1.0),
        first,
    ]
}

/// The cross product `a x b`.
fn cross(a: &[Real; 3], b: &[Real; 3]) -> [Real; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

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

/// Successive samples of one run, each one's interval means
/// ([`outputs::force_mean`]) since the sample before (the first's since the start).
#[derive(Debug, Default)]
pub struct Sampler {
    since: Option<Since>,
}

impl Sampler {
    /// The messages of `sim` now ([`sample`]); the next sample's interval means start here.
    pub fn sample<S: Published>(&mut self, sim: &S) -> Sample {
        let s = sample(sim, self.since.as_ref());
        self.since = Some(Since::of(sim));
        s
    }

    /// Where the next sample's interval means start (none: at the start of the run).
    pub fn since(&self) -> Option<&Since> {
        self.since.as_ref()
    }
}

/// The messages of the current state of `sim`, a 2D or a 3D simulation, the interval means
/// of its outputs since `since` (none: since the start; [`Sampler`] keeps it).
#[must_use]
pub fn sample<S: Published>(sim: &S, since: Option<&Since>) -> Sample {
    let time = sim.time_now();
    let n = nanos(time);
    let header = Header {
        stamp: stamp(n),
        frame_id: FRAME_ID.to_owned(),
    };
    let now = outputs::Sample::new(sim).since(since);
    let tools = S::tool_readings(&now);
    let mut messages = Vec::with_capacity(tools.len() + 8);
    for t in &tools {
        let [x, y, z] = t.force;
        messages.push(
            WrenchStamped {
                header: header.clone(),
                wrench: Wrench {
                    force: Vector3 { x, y, z },
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
            position: tools.iter().map(|t| t.stroke).collect(),
            velocity: tools.iter().map(|t| t.velocity).collect(),
            effort: tools.iter().map(|t| t.axial_force).collect(),
        }
        .to_cdr(),
    );
    let (points, hot) = S::cloud(&now);
    messages.push(point_cloud_xyz_fields(header.clone(), &points, hot).to_cdr());
    messages.push(tool_markers(&now, &tools, &header).to_cdr());
    messages.extend(S::extra_messages(&now, &header));
    let e = sim.energy_now();
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
    let register = sim.register_columns();
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

/// One line strip per tool (namespace `tools`, id = tool index, text = its name) through
/// the points [`Published::marker_lines`] gives.
fn tool_markers<S: Published>(
    now: &outputs::Sample<'_, S>,
    tools: &[ToolReading],
    header: &Header,
) -> MarkerArray {
    let (lines, width) = S::marker_lines(now);
    let markers = lines
        .into_iter()
        .zip(tools)
        .enumerate()
        .map(|(k, (points, t))| {
            let [r, g, b] = PALETTE[k % PALETTE.len()];
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
                points,
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
    use crate::msgs::{Clock, Energy, JointState, Outputs, PointCloud2, RosMessage, WrenchStamped};
    use rkforge_core::scene::SolidScene;
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
        let s = sample(&sim, None);
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

    /// The coarse OFHC bar in 3D during its impact, held by the wall (the FE benchmark's
    /// wall: the coarse bar would leave a wall it may leave).
    fn ofhc_3d() -> SolidSimulation {
        let text = include_str!("../../scenes/taylor_ofhc_3d.toml")
            .replace("cells = [8, 4, 48]", "cells = [4, 2, 8]")
            .replace(
                r#"motion = { kind = "fixed" }"#,
                "motion = { kind = \"fixed\" }\nseparation = false",
            );
        let scene = SolidScene::from_str_named(&text, "ofhc").unwrap();
        let mut sim = SolidSimulation::new(&scene).unwrap();
        sim.run_toward(2e-6, u64::MAX, |_, _| true).unwrap();
        sim
    }

    /// A 3D sample: the wall's 3D force, the particles in space with their smoothed fields
    /// and temperature, the wall's patch under the bar, the register's values bit for bit,
    /// no die fill and no laps.
    #[test]
    fn a_3d_sample_holds_the_body_in_space() {
        let sim = ofhc_3d();
        let s = sample(&sim, None);
        let topics = crate::topics(sim.scene(), "/rkforge").unwrap();
        assert_eq!(s.messages.len(), topics.len());
        assert_eq!(s.messages.len(), 7);
        let w = WrenchStamped::from_cdr(&s.messages[0]).unwrap();
        let wall = &sim.tools()[0];
        let f = w.wrench.force;
        assert_eq!([f.x, f.y, f.z], wall.state.force);
        assert!(f.z != 0.0, "the bar is on the wall: {f:?}");
        let j = JointState::from_cdr(&s.messages[1]).unwrap();
        assert_eq!(j.name, ["wall"]);
        assert_eq!(j.effort, [wall.axial_force()]);
        assert_eq!(j.effort, [-f.z], "along the wall's axis, -z");
        let cloud = PointCloud2::from_cdr(&s.messages[2]).unwrap();
        assert_eq!(cloud.width as usize, sim.particle_count());
        assert_eq!(cloud.point_step, 24);
        assert_eq!(cloud.fields[5].name, "temperature");
        let positions = sim.positions();
        let strain = sim.particle_means(&sim.point_plastic_strain());
        let temperature = sim.particle_means(sim.point_temperature().unwrap());
        let float = |k: usize, at: usize| {
            let o = 24 * k + 4 * at;
            f32::from_le_bytes(cloud.data[o..o + 4].try_into().unwrap())
        };
        for (k, p) in positions.iter().enumerate() {
            assert_eq!([float(k, 0), float(k, 1), float(k, 2)], p.map(|x| x as f32));
            assert_eq!(float(k, 3), strain[k] as f32);
            assert_eq!(float(k, 5), temperature[k] as f32);
            assert!(float(k, 5) >= 22.0);
        }
        assert!(strain.iter().any(|&e| e > 0.01), "the foot has yielded");
        let markers = MarkerArray::from_cdr(&s.messages[3]).unwrap();
        let [m] = &markers.markers[..] else {
            panic!("one marker for the one tool")
        };
        assert_eq!((m.text.as_str(), m.r#type), ("wall", Marker::LINE_STRIP));
        let e = sim.readings().extents;
        let corners: Vec<[f64; 3]> = m.points.iter().map(|p| [p.x, p.y, p.z]).collect();
        assert_eq!(corners.len(), 5);
        assert_eq!(corners[0], corners[4]);
        for c in &corners {
            assert_eq!(c[2], 0.0, "on the wall");
            for k in 0..2 {
                let off = (c[k] - e[k][0]).abs().min((c[k] - e[k][1]).abs());
                assert!(off < 1e-15, "{c:?} at the bounds {e:?}");
            }
        }
        let energy = Energy::from_cdr(&s.messages[4]).unwrap();
        assert_eq!(energy.plastic, sim.energy().plastic);
        let o = Outputs::from_cdr(&s.messages[5]).unwrap();
        let now = outputs::Sample::new(&sim);
        let register = outputs::solid_columns(sim.scene());
        assert_eq!(o.names.len(), register.len());
        for (k, c) in register.iter().enumerate() {
            assert_eq!(
                (o.names[k].as_str(), o.units[k].as_str()),
                (c.name.as_str(), c.unit())
            );
            assert_eq!(o.values[k].to_bits(), c.value(&now).to_bits(), "{}", c.name);
        }
        assert!(o.names.iter().any(|n| n == "wall.force_z_N"));
        let c = Clock::from_cdr(&s.messages[6]).unwrap();
        assert_eq!(c.clock, stamp(nanos(sim.time())));
    }

    /// A cylinder's outline lies on its mantle at its two ends, shifted with the tool; an
    /// unbounded one spans the box's reach along its axis about the box's centre.
    #[test]
    fn a_cylinder_outline_lies_on_its_ends() {
        let capped = Cylinder {
            centre: [1.0, 2.0, 3.0],
            direction: [0.0, 0.6, 0.8],
            radius: 0.5,
            half_length: Some(1.0),
        };
        let shift = [0.0, 0.0, -0.25];
        let line = cylinder_outline(&capped, shift, [[0.0, 1.0]; 3]);
        assert_eq!(line.len(), 34);
        let moved = Cylinder {
            centre: [1.0, 2.0, 2.75],
            ..capped
        };
        for p in &line {
            let (phi, _) = moved.signed(*p);
            let rel: [f64; 3] = std::array::from_fn(|k| p[k] - moved.centre[k]);
            assert!(phi.abs() < 1e-12 && (dot(&rel, &capped.direction).abs() - 1.0).abs() < 1e-12);
        }
        let bar = Cylinder {
            centre: [0.0, 0.0, 7.0],
            direction: [0.0, 1.0, 0.0],
            radius: 2.0,
            half_length: None,
        };
        let line = cylinder_outline(&bar, [0.0; 3], [[0.0, 5.0], [0.0, 2.0], [0.0, 5.0]]);
        let ys: Vec<f64> = line.iter().map(|p| p[1]).collect();
        assert!(ys[..17].iter().all(|&y| (y - 0.0).abs() < 1e-12), "{ys:?}");
        assert!(ys[17..].iter().all(|&y| (y - 2.0).abs() < 1e-12), "{ys:?}");
    }

    /// The patch of an inclined plane lies on the plane, its sides as long as the box's
    /// projection on them; a plane normal to z shows the box's x and y bounds.
    #[test]
    fn a_plane_patch_covers_the_box_on_the_plane() {
        let bounds = [[0.0, 2.0], [-1.0, 1.0], [3.0, 7.0]];
        let flat = plane_patch([5.0, 5.0, 1.5], [0.0, 0.0, 1.0], bounds);
        let xy: Vec<[f64; 3]> = flat.to_vec();
        assert_eq!(
            xy,
            [
                [2.0, -1.0, 1.5],
                [2.0, 1.0, 1.5],
                [0.0, 1.0, 1.5],
                [0.0, -1.0, 1.5],
                [2.0, -1.0, 1.5]
            ]
        );
        let s = 0.5f64.sqrt();
        let normal = [s, 0.0, s];
        let origin = [1.0, 0.0, 1.0];
        let patch = plane_patch(origin, normal, bounds);
        for c in patch {
            let rel = [c[0] - origin[0], c[1] - origin[1], c[2] - origin[2]];
            assert!(dot(&normal, &rel).abs() < 1e-12, "{c:?}");
        }
        let side = |a: [f64; 3], b: [f64; 3]| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        };
        // Along y: the box's 2; across it, in the plane: its 2 x 4 section seen at 45 deg.
        let (a, b) = (side(patch[0], patch[1]), side(patch[1], patch[2]));
        let mut sides = [a, b];
        sides.sort_by(f64::total_cmp);
        assert!((sides[0] - 2.0).abs() < 1e-12, "{sides:?}");
        assert!((sides[1] - 6.0 * s).abs() < 1e-12, "{sides:?}");
    }
}
