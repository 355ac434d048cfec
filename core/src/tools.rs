//! Rigid tools: a polyline translating along its axis (fixed, at constant speed, by a
//! velocity table or commanded from outside), with its friction law, fill points and heat
//! transfer, and its geometry as the contact stage reads it: the signed distance of a point
//! to the polyline ([`penetration`], [`gap_within`]) over the candidate segments its bins
//! list. The force law is the paper's ([`crate::contact::sidibe2009`]); the stage that
//! applies it is [`crate::contact`].

use crate::friction::Friction;
use crate::geometry::{closest_on_segment, left_normal};
use crate::math::Real;
use crate::scene::{Motion, ToolSpec};
use crate::segment_bins::SegmentBins;
use serde::{Deserialize, Serialize};

/// A rigid polyline tool translating along its axis.
#[derive(Debug, Clone)]
pub struct Tool {
    /// Name from the scene.
    pub name: String,
    /// Vertices in the initial position (m).
    pub points0: Vec<[Real; 2]>,
    /// Unit axis.
    pub axis: [Real; 2],
    /// Scene motion.
    pub motion: Motion,
    /// Friction law of the interface.
    pub friction: Friction,
    /// Whether particles may leave the tool (false: a particle that reached it stays on it).
    pub separation: bool,
    /// Moving state (saved with the simulation state).
    pub state: ToolState,
    /// Segment bins in the tool's own coordinates.
    pub bins: SegmentBins,
    /// Largest penetration treated as contact (m).
    pub depth: Real,
    /// Indices of the vertices where the tool is convex towards the workpiece (the
    /// polyline turns right, the workpiece lying on its left): the corners that can cut
    /// between two surface particles ([`crate::contact::corners`]).
    pub convex: Vec<u32>,
    /// Number of the tool's named fill points (the die fill needs the whole surface).
    pub fill_points: usize,
}

/// What changes while a tool moves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct ToolState {
    /// Displacement along the axis (m).
    pub stroke: Real,
    /// Velocity along the axis during the last step (m/s).
    pub velocity: Real,
    /// Velocity set from outside, overriding the scene motion (m/s).
    pub command: Option<Real>,
    /// Force of the workpiece on the tool during the last step (N).
    pub force: [Real; 2],
    /// Normal force of the workpiece on the tool during the last step (N): the normal parts
    /// of the contact forces summed, each along its own contact normal (positive pressing,
    /// negative where a tool without separation holds the surface back). On a flat tool it
    /// is the force's component along the tool's normal; on a curved or closed die it is the
    /// integral of the contact pressure, which the force's resultant is not.
    #[serde(default)]
    pub normal_force: Real,
    /// Largest force magnitude so far (N).
    pub peak_force: Real,
    /// What the tool received from the workpiece since the start.
    pub account: Account,
}

/// What a tool received from the workpiece since the start of the run, booked at each
/// contact stage with the step's corrector length `dt_avg` (s), over which the stage's
/// force changes the particles' momentum in the central-difference step (Belytschko, Liu
/// and Moran 2000, sec. 6.2.1): the tool's impulse and the work of its motion.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct Account {
    /// Impulse of the workpiece's force along the axis, `I = sum_n F_n dt_avg,n` (N s),
    /// `F_n` the force along the axis at step `n` (positive pushing the tool along +axis):
    /// the momentum the workpiece gave up to the tool.
    pub impulse: Real,
    /// Work of the tool on the workpiece, `W = -sum_n F_n v_n dt_avg,n` (J), `v_n` the
    /// tool's velocity along its axis over the step: positive while it presses; the sum
    /// over the tools is the energy account's `tool_work`.
    pub work: Real,
}

impl Account {
    /// Book one step: the force along the axis `force` (N), the velocity along the axis
    /// `velocity` (m/s) and the corrector's step `dt_avg` (s).
    pub fn book(&mut self, force: Real, velocity: Real, dt_avg: Real) {
        self.impulse += force * dt_avg;
        self.work -= force * velocity * dt_avg;
    }
}

/// Largest penetration still treated as contact, in particle spacings; deeper points behind
/// a segment belong to the other side of the tool.
pub const SEARCH_DEPTH_SPACINGS: Real = 3.0;

impl Tool {
    /// From its scene description; `depth` (m) is the largest penetration treated as
    /// contact (deeper points behind a segment belong to the other side of the tool).
    pub fn new(spec: &ToolSpec, depth: Real) -> Tool {
        let v0 = match spec.motion {
            Motion::External {
                initial_velocity_m_per_s,
            } => initial_velocity_m_per_s,
            _ => 0.0,
        };
        Tool {
            name: spec.name.clone(),
            points0: spec.points_m.clone(),
            axis: spec.axis,
            motion: spec.motion.clone(),
            friction: spec.friction,
            separation: spec.separation,
            state: ToolState {
                velocity: v0,
                ..Default::default()
            },
            bins: SegmentBins::new(&spec.points_m, depth),
            depth,
            convex: convex_vertices(&spec.points_m),
            fill_points: spec.fill_points.len(),
        }
    }

    /// A lower bound on how far the point `x` (m) must move before the contact search
    /// ([`Tool::gap_above`]) can find it within the search depth (m): its distance to the
    /// polyline prolonged by rays along its end segments (the side the search gives a point
    /// beyond an end is the side of that ray, so a point changes side only by crossing the
    /// prolonged polyline), less the search depth when the point is already inside (or
    /// `held` on a tool without separation, where a gap down to minus the depth counts).
    pub fn clearance(&self, x: [Real; 2], held: bool) -> Real {
        let s = self.state.stroke;
        let local = [x[0] - s * self.axis[0], x[1] - s * self.axis[1]];
        let p = &self.points0;
        let n = p.len();
        let to_segment = |a: [Real; 2], t: [Real; 2], hi: Real| {
            let u = [local[0] - a[0], local[1] - a[1]];
            let s = ((u[0] * t[0] + u[1] * t[1]) / (t[0] * t[0] + t[1] * t[1])).clamp(0.0, hi);
            // `sqrt` of the squares, not `hypot`: within an ulp of it, far inside the
            // stage's margin of 1e-9 spacings, at a fraction of its cost.
            let (a, b) = (u[0] - s * t[0], u[1] - s * t[1]);
            (a * a + b * b).sqrt()
        };
        let mut d = p
            .windows(2)
            .map(|ab| to_segment(ab[0], [ab[1][0] - ab[0][0], ab[1][1] - ab[0][1]], 1.0))
            .fold(Real::INFINITY, Real::min);
        if n >= 2 {
            let first = [p[0][0] - p[1][0], p[0][1] - p[1][1]];
            let last = [p[n - 1][0] - p[n - 2][0], p[n - 1][1] - p[n - 2][1]];
            d = d
                .min(to_segment(p[0], first, Real::INFINITY))
                .min(to_segment(p[n - 1], last, Real::INFINITY));
        }
        if held || self.depth_inside(x).is_some() {
            d - self.depth
        } else {
            d
        }
    }

    /// Whether the point `x` (m) touches the tool in its current position, inside it or
    /// within `within` (m) of its polyline (the heat stage's contact): the unit tangent of
    /// the tool's segment nearest to it when it does.
    pub fn touches(&self, x: [Real; 2], within: Real) -> Option<[Real; 2]> {
        let s = self.state.stroke;
        let local = [x[0] - s * self.axis[0], x[1] - s * self.axis[1]];
        let (distance, tangent) = self
            .points0
            .windows(2)
            .map(|ab| {
                let (a, b) = (ab[0], ab[1]);
                let (t, u) = (
                    [b[0] - a[0], b[1] - a[1]],
                    [local[0] - a[0], local[1] - a[1]],
                );
                let len2 = t[0] * t[0] + t[1] * t[1];
                let f = ((u[0] * t[0] + u[1] * t[1]) / len2).clamp(0.0, 1.0);
                let len = len2.sqrt();
                (
                    (u[0] - f * t[0]).hypot(u[1] - f * t[1]),
                    [t[0] / len, t[1] / len],
                )
            })
            .fold((Real::INFINITY, [0.0; 2]), |best, d| {
                if d.0 < best.0 {
                    d
                } else {
                    best
                }
            });
        (distance <= within || self.depth_inside(x).is_some()).then_some(tangent)
    }

    /// How deep the point `x` (m) lies inside the tool in its current position (m), over
    /// every segment and at any depth: the measure of penetration, where
    /// [`Tool::penetration`] is the contact's search within the search depth.
    pub fn depth_inside(&self, x: [Real; 2]) -> Option<Real> {
        let s = self.state.stroke;
        let local = [x[0] - s * self.axis[0], x[1] - s * self.axis[1]];
        let segments = 0..self.points0.len().saturating_sub(1);
        gap_within(&self.points0, segments, local, 0.0, Real::INFINITY).map(|p| p.gap)
    }

    /// The penetration of the point `x` (m) into the tool in its current position.
    pub fn penetration(&self, x: [Real; 2]) -> Option<Penetration> {
        self.gap_above(x, 0.0)
    }

    /// The signed gap of the point `x` (m) when it lies between `below` (m, exclusive; a
    /// negative value reaches in front of the surface) and the search depth behind it.
    pub fn gap_above(&self, x: [Real; 2], below: Real) -> Option<Penetration> {
        let s = self.state.stroke;
        let local = [x[0] - s * self.axis[0], x[1] - s * self.axis[1]];
        gap_within(
            &self.points0,
            self.bins.candidates(local).iter().map(|&k| k as usize),
            local,
            below,
            self.depth,
        )
    }

    /// Length of the tool's polyline (m).
    pub fn length(&self) -> Real {
        self.points0
            .windows(2)
            .map(|s| (s[1][0] - s[0][0]).hypot(s[1][1] - s[0][1]))
            .sum()
    }

    /// The station (of `stations` equal pieces of the polyline, from its first point) of
    /// the polyline's point closest to `x` (m, physical).
    pub fn station(&self, x: [Real; 2], stations: usize) -> usize {
        let s = self.state.stroke;
        let p = [x[0] - s * self.axis[0], x[1] - s * self.axis[1]];
        let (mut best, mut along, mut walked) = (Real::INFINITY, 0.0, 0.0);
        for seg in self.points0.windows(2) {
            let (a, b) = (seg[0], seg[1]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let len2 = d[0] * d[0] + d[1] * d[1];
            let (t, q, _) = closest_on_segment(a, b, p);
            let dist = (p[0] - q[0]).hypot(p[1] - q[1]);
            if dist < best {
                best = dist;
                along = walked + t * len2.sqrt();
            }
            walked += len2.sqrt();
        }
        ((along / walked * stations as Real) as usize).min(stations - 1)
    }

    /// The area (m^2) of station `k` of `stations`: its length times the depth in plane
    /// strain, times `2 pi r` at its middle (the tool where it is now) in axisymmetry, as
    /// contact forces are for the whole ring there.
    pub fn station_area(&self, k: usize, stations: usize, axisymmetric: bool, depth: Real) -> Real {
        let length = self.length();
        let piece = length / stations as Real;
        if !axisymmetric {
            return piece * depth;
        }
        let mid = (k as Real + 0.5) * piece;
        let mut walked = 0.0;
        let mut r = self.points0[0][0];
        for seg in self.points0.windows(2) {
            let l = (seg[1][0] - seg[0][0]).hypot(seg[1][1] - seg[0][1]);
            if walked + l >= mid && l > 0.0 {
                r = seg[0][0] + (mid - walked) / l * (seg[1][0] - seg[0][0]);
                break;
            }
            walked += l;
        }
        let r = r + self.state.stroke * self.axis[0];
        piece * 2.0 * std::f64::consts::PI * r.abs()
    }

    /// Velocity along the axis (m/s) at time `t` (s): the command if one was given, else
    /// the scene motion (tables interpolate linearly and hold their ends).
    pub fn velocity_at(&self, t: Real) -> Real {
        self.motion.velocity_at(t, self.state.command)
    }

    /// Current vertices (m).
    pub fn vertices(&self) -> Vec<[Real; 2]> {
        let s = self.state.stroke;
        self.points0
            .iter()
            .map(|p| [p[0] + s * self.axis[0], p[1] + s * self.axis[1]])
            .collect()
    }

    /// Force along the axis (N): positive when the workpiece pushes the tool along `+axis`.
    pub fn axial_force(&self) -> Real {
        self.state.force[0] * self.axis[0] + self.state.force[1] * self.axis[1]
    }
}

/// The interior vertices of the polyline `verts` at which it turns right (clockwise): with
/// the workpiece on the left of travel, the tool's convex corners.
fn convex_vertices(verts: &[[Real; 2]]) -> Vec<u32> {
    (1..verts.len().saturating_sub(1))
        .filter(|&k| {
            let (a, b, c) = (verts[k - 1], verts[k], verts[k + 1]);
            (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]) < 0.0
        })
        .map(|k| k as u32)
        .collect()
}

/// A slave point's penetration of a tool: gap (m, > 0 inside) and push direction.
/// A particle held on a tool without separation may have a negative gap: the normal
/// force `m g / dt^2` then pulls it back onto the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Penetration<const D: usize = 2> {
    /// Gap `g` (m): distance from the point to the tool surface, the point being inside.
    pub gap: Real,
    /// Unit direction from the point to the closest surface point (the segment normal on a
    /// face, the direction to the vertex at a corner; the plane's normal in 3D).
    pub normal: [Real; D],
}

/// Signed distance from `x` to the polyline `verts` (workpiece on the left of travel) over
/// the candidate segments; `Some` when `x` is inside the tool by at most `depth`.
///
/// The closest point over all candidates decides: on a segment's interior its normal tells
/// the side; at a vertex, the pseudo-normal (sum of the adjacent segments' normals) does, which
/// is right at convex and concave corners alike. The push direction points from `x` to the
/// closest point, so a particle is carried smoothly round a corner.
pub fn penetration(
    verts: &[[Real; 2]],
    candidates: &[u32],
    x: [Real; 2],
    depth: Real,
) -> Option<Penetration> {
    gap_within(verts, candidates.iter().map(|&k| k as usize), x, 0.0, depth)
}

/// As [`penetration`], for a gap in `(below, depth]` other than zero (`below` < 0 reaches
/// in front of the surface); the push direction still points from the surface's outside
/// into the workpiece (the segment normal on a face).
pub fn gap_within(
    verts: &[[Real; 2]],
    candidates: impl IntoIterator<Item = usize>,
    x: [Real; 2],
    below: Real,
    depth: Real,
) -> Option<Penetration> {
    let normal = |k: usize| left_normal(verts[k], verts[k + 1]);
    // (signed distance, negative inside; closest point; side normal; on a face interior)
    let mut best: Option<(Real, [Real; 2], [Real; 2], bool)> = None;
    for k in candidates {
        let (a, b) = (verts[k], verts[k + 1]);
        let t = [b[0] - a[0], b[1] - a[1]];
        let s = ((x[0] - a[0]) * t[0] + (x[1] - a[1]) * t[1]) / (t[0] * t[0] + t[1] * t[1]);
        let (c, side, face) = if s <= 0.0 {
            let n = normal(k);
            let m = if k > 0 { normal(k - 1) } else { n };
            (a, [n[0] + m[0], n[1] + m[1]], false)
        } else if s >= 1.0 {
            let n = normal(k);
            let m = if k + 2 < verts.len() {
                normal(k + 1)
            } else {
                n
            };
            (b, [n[0] + m[0], n[1] + m[1]], false)
        } else {
            ([a[0] + s * t[0], a[1] + s * t[1]], normal(k), true)
        };
        // On a face, the distance and side come from the face normal itself, free of the
        // rounding of the projected point; at a vertex, from the vertex.
        let signed = if face {
            (x[0] - a[0]) * side[0] + (x[1] - a[1]) * side[1]
        } else {
            let d = (c[0] - x[0]).hypot(c[1] - x[1]);
            if (x[0] - c[0]) * side[0] + (x[1] - c[1]) * side[1] < 0.0 {
                -d
            } else {
                d
            }
        };
        if best.is_none_or(|(d, ..)| signed.abs() < d.abs()) {
            best = Some((signed, c, side, face));
        }
    }
    let (signed, c, side, face) = best?;
    let gap = -signed;
    (gap > below && gap <= depth && gap != 0.0).then(|| Penetration {
        gap,
        normal: if face {
            side
        } else {
            [(c[0] - x[0]) / gap, (c[1] - x[1]) / gap]
        },
    })
}

/// A rigid tool driven along its axis, as the step's speed limit reads it
/// (`solver/stable_step.rs`): its name, motion and the command from outside; the polyline
/// tools of 2D and the plane tools of 3D ([`crate::solid_tool`]) both are.
pub trait Driven {
    /// Name from the scene.
    fn name(&self) -> &str;
    /// The scene's motion.
    fn motion(&self) -> &Motion;
    /// Velocity set from outside (m/s), overriding the motion.
    fn command(&self) -> Option<Real>;
    /// Set the velocity from outside (m/s).
    fn set_command(&mut self, v: Real);
    /// Whether the tool can move (its velocity is an input of the FMU and ROS node): any
    /// motion but `fixed`.
    fn is_movable(&self) -> bool {
        !matches!(self.motion(), Motion::Fixed)
    }
}

/// Command tool `k` of `tools` to move at `v` (m/s, along its axis) from the next step on,
/// overriding the scene's motion (2D tools and 3D plane tools alike).
///
/// # Errors
///
/// No tool `k`, a tool the scene fixes, or a velocity that is not finite.
pub fn command_velocity<T: Driven>(tools: &mut [T], k: usize, v: Real) -> crate::Result<()> {
    let t = tools
        .get_mut(k)
        .ok_or_else(|| crate::Error::Request(format!("no tool with index {k}")))?;
    if !t.is_movable() {
        return Err(crate::Error::Request(format!(
            "tool `{}` is fixed in the scene",
            t.name()
        )));
    }
    if !v.is_finite() {
        return Err(crate::Error::Request(format!(
            "velocity {v} for tool `{}` is not finite",
            t.name()
        )));
    }
    t.set_command(v);
    Ok(())
}

impl Driven for Tool {
    fn name(&self) -> &str {
        &self.name
    }
    fn motion(&self) -> &Motion {
        &self.motion
    }
    fn command(&self) -> Option<Real> {
        self.state.command
    }
    fn set_command(&mut self, v: Real) {
        self.state.command = Some(v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pen(verts: &[[Real; 2]], x: [Real; 2], depth: Real) -> Option<Penetration> {
        let all: Vec<u32> = (0..verts.len() as u32 - 1).collect();
        penetration(verts, &all, x, depth)
    }

    fn close(a: [Real; 2], b: [Real; 2]) -> bool {
        (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12
    }

    #[test]
    fn flat_wall_gap_and_normal() {
        let wall = [[0.0, 0.0], [1.0, 0.0]];
        let p = pen(&wall, [0.5, -0.01], 0.1).unwrap();
        assert!((p.gap - 0.01).abs() < 1e-15 && close(p.normal, [0.0, 1.0]));
        assert!(pen(&wall, [0.5, 0.01], 0.1).is_none());
        assert!(pen(&wall, [0.5, -0.2], 0.1).is_none());
        assert!(
            pen(&wall, [0.5, 0.0], 0.1).is_none(),
            "on the surface is not inside"
        );
    }

    #[test]
    fn faces_at_a_die_corner_take_the_nearest() {
        // A die: floor then a wall going up at x = 1 (workpiece above and left).
        let die = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]];
        let p = pen(&die, [1.01, 0.3], 0.5).unwrap();
        assert!(
            (p.gap - 0.01).abs() < 1e-12 && close(p.normal, [-1.0, 0.0]),
            "{p:?}"
        );
        let q = pen(&die, [0.3, -0.02], 0.5).unwrap();
        assert!(
            (q.gap - 0.02).abs() < 1e-12 && close(q.normal, [0.0, 1.0]),
            "{q:?}"
        );
        // In the die's solid corner, past the ends of both faces: the corner vertex is the
        // nearest surface point.
        let r = pen(&die, [1.01, -0.03], 0.5).unwrap();
        let d = 0.01_f64.hypot(0.03);
        assert!(
            (r.gap - d).abs() < 1e-12 && close(r.normal, [-0.01 / d, 0.03 / d]),
            "{r:?}"
        );
        // Outside the corner (beyond the floor's end, below the wall): free.
        assert!(pen(&die, [0.5, 0.5], 0.5).is_none());
    }

    #[test]
    fn a_point_on_the_extension_of_a_face_past_a_convex_corner_is_free() {
        // The wheel die's hub recess: wall down to z = -5 mm at r = 15 mm, then the floor at
        // z = 0 outward. A particle resting on the floor at r = 19.7 mm lies on the wall's
        // extension; it is outside the tool (this was once taken as 4.7 mm deep).
        let die = [[0.0, -0.005], [0.015, -0.005], [0.015, 0.0], [0.055, 0.0]];
        assert!(pen(&die, [0.0197, 0.0], 0.005).is_none());
        assert!(pen(&die, [0.0197, 1e-6], 0.005).is_none());
        let p = pen(&die, [0.0197, -1e-4], 0.005).unwrap();
        assert!(
            (p.gap - 1e-4).abs() < 1e-12 && close(p.normal, [0.0, 1.0]),
            "{p:?}"
        );
    }

    #[test]
    fn a_point_behind_a_corner_vertex_is_pushed_to_the_vertex() {
        // Workpiece in the quadrant x > 0, y > 0; tool wall x < 0 and floor y < 0.
        let tool = [[0.0, 1.0], [0.0, 0.0], [1.0, 0.0]];
        let p = pen(&tool, [-0.03, -0.04], 0.5).unwrap();
        assert!(
            (p.gap - 0.05).abs() < 1e-12 && close(p.normal, [0.6, 0.8]),
            "{p:?}"
        );
        // A tool corner pointing into the workpiece (tool = quadrant x < 0, y < 0).
        let punch = [[-1.0, 0.0], [0.0, 0.0], [0.0, -1.0]];
        assert!(
            pen(&punch, [0.01, 0.01], 0.5).is_none(),
            "outside a convex corner"
        );
        let q = pen(&punch, [-0.01, -0.02], 0.5).unwrap();
        assert!(
            (q.gap - 0.01).abs() < 1e-12 && close(q.normal, [1.0, 0.0]),
            "{q:?}"
        );
    }

    #[test]
    fn bins_list_every_segment_near_a_point() {
        let verts: Vec<[Real; 2]> = (0..200)
            .map(|k| {
                let a = k as Real * 0.03;
                [a.cos(), a.sin()]
            })
            .collect();
        let depth = 0.05;
        let bins = SegmentBins::new(&verts, depth);
        for k in 0..300 {
            let x = [
                1.3 * (k as Real * 0.7).cos() * (k as Real * 0.011).sin(),
                1.3 * (k as Real * 0.7).sin(),
            ];
            let all: Vec<u32> = (0..199).collect();
            let brute = penetration(&verts, &all, x, depth);
            let binned = penetration(&verts, bins.candidates(x), x, depth);
            assert_eq!(brute, binned, "point {x:?}");
            assert!(
                bins.candidates(x).len() < 20,
                "few candidates: {}",
                bins.candidates(x).len()
            );
        }
    }

    #[test]
    fn a_held_particle_in_front_of_the_wall_is_pulled_back() {
        let wall = [[0.0, 0.0], [1.0, 0.0]];
        let p = gap_within(&wall, [0], [0.5, 0.01], -0.1, 0.1).unwrap();
        assert!(
            (p.gap + 0.01).abs() < 1e-15 && close(p.normal, [0.0, 1.0]),
            "{p:?}"
        );
        assert!(gap_within(&wall, [0], [0.5, 0.2], -0.1, 0.1).is_none());
        assert!(gap_within(&wall, [0], [0.5, 0.0], -0.1, 0.1).is_none());
    }

    #[test]
    fn velocity_table_interpolates_and_holds() {
        let spec = ToolSpec {
            name: "p".into(),
            points_m: vec![[0.0, 0.0], [1.0, 0.0]],
            axis: [0.0, -1.0],
            motion: Motion::Table {
                points: vec![[0.0, 0.0], [1.0, 10.0], [2.0, -10.0]],
            },
            friction: Friction::default(),
            separation: true,
            fill_points: Vec::new(),
            temperature_c: None,
            heat_transfer_w_per_m2_k: 0.0,
            heat_transfer_by_pressure: Vec::new(),
        };
        let mut t = Tool::new(&spec, 0.1);
        assert_eq!(t.velocity_at(-1.0), 0.0);
        assert_eq!(t.velocity_at(0.5), 5.0);
        assert_eq!(t.velocity_at(1.5), 0.0);
        assert_eq!(t.velocity_at(9.0), -10.0);
        t.state.command = Some(3.0);
        assert_eq!(t.velocity_at(0.5), 3.0);
    }
}
