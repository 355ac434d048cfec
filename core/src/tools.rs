//! Rigid tools and the paper's penalty particle-to-segment contact (Sidibe et al. 2009,
//! section II-3, eqs. 4-7).
//!
//! Slaves are the workpiece boundary particles, masters the tool segments. For a slave `J`
//! whose predicted physical position lies behind a segment by the gap `g_J > 0`:
//! - normal force (eq. 4): `f_n = m_s g / dt^2` along the segment normal `n` (N);
//! - stick force (eq. 6): `f_st = -m_s v_TR / dt`, `v_TR` the tangential relative velocity,
//!   plus what the last step's friction left unrealised (see [`penalty_force`]);
//! - friction (eq. 5): `f_f = min(b, |f_st|) f_st / |f_st|` with the bound `b` of the
//!   tool's law ([`Friction`]): `mu f_n` (Coulomb, the paper's), `m k A` (shear friction
//!   factor) or `min(mu f_n, m k A)`;
//! - the particle force is spread to the RK coefficients (eq. 7): `f_I += f_J N_I(X_J)`.
//!
//! The force on the tool is the reaction: minus the sum of the slave forces.

use crate::friction::Friction;
use crate::math::Real;
use crate::scene::{Motion, ToolSpec};
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
    /// between two surface particles ([`crate::corners`]).
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
    /// Largest force magnitude so far (N).
    pub peak_force: Real,
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
            (u[0] - s * t[0]).hypot(u[1] - s * t[1])
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
            let t = if len2 > 0.0 {
                (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let q = [a[0] + t * d[0], a[1] + t * d[1]];
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

    /// Whether the tool can move (its velocity is an input of the FMU and ROS node).
    pub fn is_movable(&self) -> bool {
        !matches!(self.motion, Motion::Fixed)
    }

    /// Velocity along the axis (m/s) at time `t` (s): the command if one was given, else
    /// the scene motion (tables interpolate linearly and hold their ends).
    pub fn velocity_at(&self, t: Real) -> Real {
        if let Some(c) = self.state.command {
            return c;
        }
        match &self.motion {
            Motion::Fixed => 0.0,
            Motion::Constant { velocity_m_per_s } => *velocity_m_per_s,
            Motion::External {
                initial_velocity_m_per_s,
            } => *initial_velocity_m_per_s,
            Motion::Table { points } => {
                let k = points.partition_point(|p| p[0] <= t);
                if k == 0 {
                    points[0][1]
                } else if k == points.len() {
                    points[k - 1][1]
                } else {
                    let (a, b) = (points[k - 1], points[k]);
                    a[1] + (b[1] - a[1]) * (t - a[0]) / (b[0] - a[0])
                }
            }
        }
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
pub struct Penetration {
    /// Gap `g` (m): distance from the point to the tool surface, the point being inside.
    pub gap: Real,
    /// Unit direction from the point to the closest surface point (the segment normal on a
    /// face, the direction to the vertex at a corner).
    pub normal: [Real; 2],
}

/// Uniform bins over segments: a tool's polyline in the tool's own (initial) coordinates,
/// built once as a tool only translates, or the workpiece's boundary ring, built again at
/// each self-contact search ([`crate::self_contact`]). Each segment is listed in every bin
/// that its bounding box, grown by the search depth, overlaps.
#[derive(Debug, Clone, Default)]
pub struct SegmentBins {
    origin: [Real; 2],
    size: Real,
    dims: [usize; 2],
    offsets: Vec<u32>,
    items: Vec<u32>,
    /// Where the next item of each bin goes while filling.
    cursor: Vec<u32>,
}

impl SegmentBins {
    /// Bins of size `depth` (m) over the segments of `verts`.
    pub fn new(verts: &[[Real; 2]], depth: Real) -> SegmentBins {
        let mut lo = [Real::INFINITY; 2];
        let mut hi = [Real::NEG_INFINITY; 2];
        for v in verts {
            for k in 0..2 {
                lo[k] = lo[k].min(v[k] - depth);
                hi[k] = hi[k].max(v[k] + depth);
            }
        }
        // At most about 4096 bins per direction.
        let size = depth.max((hi[0] - lo[0]).max(hi[1] - lo[1]) / 4096.0);
        let mut bins = SegmentBins::default();
        bins.fill(
            verts.windows(2).map(|s| [s[0], s[1]]),
            [lo, hi],
            depth,
            size,
        );
        bins
    }

    /// Bins of `size` (m) over `bounds` (`[lo, hi]`, m) listing each of `segments` in every
    /// bin its bounding box grown by `depth` (m) overlaps, in segment order, reusing the
    /// buffers (a counting sort: no list per bin).
    pub fn fill(
        &mut self,
        segments: impl Iterator<Item = [[Real; 2]; 2]> + Clone,
        bounds: [[Real; 2]; 2],
        depth: Real,
        size: Real,
    ) {
        let [lo, hi] = bounds;
        self.origin = lo;
        self.size = size;
        self.dims = [0, 1].map(|k| ((hi[k] - lo[k]) / size).ceil().max(1.0) as usize);
        let dims = self.dims;
        let range = |s: &[[Real; 2]; 2], c: usize| {
            let a = ((s[0][c].min(s[1][c]) - depth - lo[c]) / size)
                .floor()
                .max(0.0) as usize;
            let b = ((s[0][c].max(s[1][c]) + depth - lo[c]) / size).floor() as usize;
            a..=b.min(dims[c] - 1)
        };
        self.offsets.clear();
        self.offsets.resize(dims[0] * dims[1] + 1, 0);
        for s in segments.clone() {
            for j in range(&s, 1) {
                for i in range(&s, 0) {
                    self.offsets[j * dims[0] + i + 1] += 1;
                }
            }
        }
        for b in 0..dims[0] * dims[1] {
            self.offsets[b + 1] += self.offsets[b];
        }
        self.items.clear();
        self.items
            .resize(self.offsets[dims[0] * dims[1]] as usize, 0);
        self.cursor.clear();
        self.cursor
            .extend_from_slice(&self.offsets[..dims[0] * dims[1]]);
        for (k, s) in segments.enumerate() {
            for j in range(&s, 1) {
                for i in range(&s, 0) {
                    let b = j * dims[0] + i;
                    self.items[self.cursor[b] as usize] = k as u32;
                    self.cursor[b] += 1;
                }
            }
        }
    }

    /// Segments that may lie within the search depth of the point `x` (tool coordinates).
    pub fn candidates(&self, x: [Real; 2]) -> &[u32] {
        let i = ((x[0] - self.origin[0]) / self.size).floor();
        let j = ((x[1] - self.origin[1]) / self.size).floor();
        if i < 0.0 || j < 0.0 || i >= self.dims[0] as Real || j >= self.dims[1] as Real {
            return &[];
        }
        let b = j as usize * self.dims[0] + i as usize;
        &self.items[self.offsets[b] as usize..self.offsets[b + 1] as usize]
    }
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
    let normal = |k: usize| {
        let (a, b) = (verts[k], verts[k + 1]);
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        [-(b[1] - a[1]) / len, (b[0] - a[0]) / len]
    };
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

/// What the shear friction factor needs of a slave particle: its flow stress and contact
/// area.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Interface {
    /// Current flow stress `sigma_y` of the particle's material (Pa).
    pub flow_stress: Real,
    /// Contact area `A` of the particle (m^2): its tributary length along the tool times
    /// the depth in plane strain, times `2 pi r` in axisymmetry.
    pub area: Real,
}

/// The force on one slave particle, with its friction part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlaveForce {
    /// Contact force on the slave (N): normal penalty plus friction.
    pub force: [Real; 2],
    /// Its tangential part, the friction force (N): the stick force while sticking, the
    /// law's bound while sliding.
    pub friction: [Real; 2],
}

/// A slave particle as the contact force sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slave {
    /// Mass `m` (kg).
    pub m: Real,
    /// Velocity relative to the tool (m/s).
    pub v_rel: [Real; 2],
    /// The friction force the last step left unrealised (N; zero on a new contact).
    pub carried: [Real; 2],
}

/// Paper eqs. 4-6: contact force on a `slave` of mass `m` (kg) with gap `g` (m) along the
/// normal `n`, velocity relative to the tool `v_rel` (m/s), the friction force `carried`
/// (N) that the last step's friction left unrealised, the tool's `law` with the
/// particle's flow stress and area `at`, the natural step `dt_step` and the corrector's
/// step `dt_avg` (s):
/// - normal (eq. 4): `f_n = m g / (dt_step dt_avg)` (`m g / dt^2` at constant step);
/// - stick (eq. 6): `f_st = c_T - m v_TR / dt_avg`, the paper's force that stops the
///   tangential relative velocity `v_TR` in one step plus the tangential part `c_T` of the
///   carried force. For interpolating shape functions `c` is zero and this is the paper's
///   law. RK shape functions do not interpolate: eq. 7 spreads the force over coefficients
///   that move other particles too, so it changes the particle's velocity by less than
///   `f dt_avg / m`, and what it did not realise is carried to the next step
///   ([`crate::contact::Contact::carry`]). A sticking particle's force thus builds up until
///   its slip stops, instead of leaving it slipping at a speed set by the step and the mass
///   (which made the friction depend on the step, the mass scaling and the tool speed);
/// - friction (eq. 5): `f_f = min(b, |f_st|) f_st / |f_st|` with the law's bound `b`: the
///   particle sticks below the bound and slides at it (the return mapping of elasto-plastic
///   friction, Wriggers 2006, *Computational Contact Mechanics*, section 5.2), so the
///   tangential force never exceeds `b`.
pub fn penalty_force(
    slave: Slave,
    pen: Penetration,
    law: &Friction,
    at: Interface,
    dt_step: Real,
    dt_avg: Real,
) -> SlaveForce {
    let Slave { m, v_rel, carried } = slave;
    let n = pen.normal;
    let fn_ = m * pen.gap / (dt_step * dt_avg);
    let mut force = [fn_ * n[0], fn_ * n[1]];
    let mut friction = [0.0; 2];
    if !law.is_frictionless() {
        let tangential = |a: [Real; 2]| {
            let an = a[0] * n[0] + a[1] * n[1];
            [a[0] - an * n[0], a[1] - an * n[1]]
        };
        let (vt, ct) = (tangential(v_rel), tangential(carried));
        let st = [ct[0] - m * vt[0] / dt_avg, ct[1] - m * vt[1] / dt_avg];
        let stick = (st[0] * st[0] + st[1] * st[1]).sqrt();
        if stick > 0.0 {
            let ff = law.bound(fn_, at.flow_stress, at.area).min(stick);
            friction = [ff * st[0] / stick, ff * st[1] / stick];
            force[0] += friction[0];
            force[1] += friction[1];
        }
    }
    SlaveForce { force, friction }
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

    /// A slave of mass `m` moving at `v` relative to the tool with `carried` force.
    fn slave(m: Real, v: [Real; 2], carried: [Real; 2]) -> Slave {
        Slave {
            m,
            v_rel: v,
            carried,
        }
    }

    #[test]
    fn friction_is_bounded_by_coulomb_and_by_the_stick_force() {
        let pen = Penetration {
            gap: 1e-3,
            normal: [0.0, 1.0],
        };
        let (m, dt) = (2.0, 1e-3);
        let fn_ = m * 1e-3 / (dt * dt);
        // Fast sliding: Coulomb bound.
        let c = Friction::Coulomb { mu: 0.3 };
        let at = Interface::default();
        let f = penalty_force(slave(m, [5.0, 0.0], [0.0; 2]), pen, &c, at, dt, dt).force;
        assert!(
            (f[1] - fn_).abs() < 1e-9 && (f[0] + 0.3 * fn_).abs() < 1e-9,
            "{f:?}"
        );
        // Slow sliding: the stick force m v / dt is smaller and wins.
        let slow = penalty_force(slave(m, [1e-4, 0.0], [0.0; 2]), pen, &c, at, dt, dt);
        assert!((slow.force[0] + m * 1e-4 / dt).abs() < 1e-12, "{slow:?}");
        assert_eq!(slow.friction, [slow.force[0], 0.0]);
        // A carried force adds to the stick force (its normal part is dropped); the sum is
        // still capped at the bound.
        let carried = [-50.0, 1e9];
        let held = penalty_force(slave(m, [1e-4, 0.0], carried), pen, &c, at, dt, dt);
        assert!(
            (held.friction[0] + 50.0 + m * 1e-4 / dt).abs() < 1e-9,
            "{held:?}"
        );
        assert_eq!(held.friction[1], 0.0);
        let capped = penalty_force(slave(m, [1e-4, 0.0], [-1e9, 0.0]), pen, &c, at, dt, dt);
        assert!((capped.friction[0] + 0.3 * fn_).abs() < 1e-9, "{capped:?}");
        // Frictionless: no tangential force, whatever is carried.
        let none = Friction::Coulomb { mu: 0.0 };
        let free = penalty_force(slave(m, [5.0, 0.0], carried), pen, &none, at, dt, dt);
        assert_eq!((free.force[0], free.friction), (0.0, [0.0; 2]));
    }

    #[test]
    fn shear_and_capped_friction_slide_at_their_bound_and_stick_below_it() {
        // A 1 mm^2 contact area on a material flowing at 300 MPa: k A = 173.2 N.
        let pen = Penetration {
            gap: 1e-6,
            normal: [0.0, 1.0],
        };
        let (m, dt): (Real, Real) = (1e-3, 1e-6);
        let fn_ = m * 1e-6 / (dt * dt);
        let at = Interface {
            flow_stress: 300e6,
            area: 1e-6,
        };
        let ka: Real = 300e6 / 3.0_f64.sqrt() * 1e-6;
        let laws = [
            (Friction::Shear { m: 0.4 }, 0.4 * ka),
            (
                Friction::Capped { mu: 0.1, m: 0.4 },
                (0.1 * fn_).min(0.4 * ka),
            ),
            (
                Friction::Capped { mu: 0.5, m: 0.4 },
                (0.5 * fn_).min(0.4 * ka),
            ),
        ];
        for (law, bound) in laws {
            for v in [
                [5.0, 0.0],
                [-3.0, 2.0],
                [0.0, -1e3],
                [1e-6, 0.0],
                [-2e-7, 7.0],
            ] {
                let SlaveForce { force: f, friction } =
                    penalty_force(slave(m, v, [0.0; 2]), pen, &law, at, dt, dt);
                assert_eq!(friction, [f[0], 0.0], "{law:?}: the tangential part");
                let vt = v[0];
                // Never above the bound nor the stick force; never along the sliding (no
                // energy created: f_t v_t <= 0).
                let stick = m * vt.abs() / dt;
                assert!(
                    f[0].abs() <= bound.min(stick) * (1.0 + 1e-15),
                    "{law:?} {v:?} {f:?}"
                );
                assert!(f[0] * vt <= 0.0, "{law:?} {v:?} {f:?}");
                // The normal force is untouched by friction.
                assert_eq!(f[1], fn_);
                if stick > bound {
                    assert!(
                        (f[0].abs() - bound).abs() <= 1e-12 * bound,
                        "{law:?} slides at its bound"
                    );
                } else {
                    // Sticking: the force stops the sliding in this step, m v + f dt = 0.
                    assert!(
                        (m * vt + f[0] * dt).abs() <= 1e-15 * m * vt.abs().max(1.0),
                        "{law:?} sticks"
                    );
                }
            }
        }
        // m = 0 and a bonded particle under tension (negative gap) carry no Coulomb friction.
        let fast = slave(m, [5.0, 0.0], [0.0; 2]);
        let none = penalty_force(fast, pen, &Friction::Shear { m: 0.0 }, at, dt, dt);
        assert_eq!(none.force[0], 0.0);
        let pull = Penetration {
            gap: -1e-7,
            normal: [0.0, 1.0],
        };
        let f = penalty_force(fast, pull, &Friction::Coulomb { mu: 0.3 }, at, dt, dt).force;
        assert!(f[1] < 0.0 && f[0] == 0.0, "{f:?}");
        let f = penalty_force(fast, pull, &Friction::Shear { m: 0.3 }, at, dt, dt).force;
        assert!(
            (f[0] + 0.3 * ka).abs() < 1e-12 * ka,
            "shear friction needs no pressure: {f:?}"
        );
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
