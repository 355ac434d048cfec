//! Rigid tools and the paper's penalty particle-to-segment contact (Sidibe et al. 2009,
//! section II-3, eqs. 4-7).
//!
//! Slaves are the workpiece boundary particles, masters the tool segments. For a slave `J`
//! whose predicted physical position lies behind a segment by the gap `g_J > 0`:
//! - normal force (eq. 4): `f_n = m_s g / dt^2` along the segment normal `n` (N);
//! - stick force (eq. 6): `f_st = -m_s v_TR / dt`, `v_TR` the tangential relative velocity;
//! - Coulomb friction (eq. 5): `f_f = -min(mu f_n, |f_st|) v_TR / |v_TR|`;
//! - the particle force is spread to the RK coefficients (eq. 7): `f_I += f_J N_I(X_J)`.
//!
//! The force on the tool is the reaction: minus the sum of the slave forces.

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
    /// Coulomb coefficient.
    pub friction: Real,
    /// Moving state (saved with the simulation state).
    pub state: ToolState,
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
    /// From its scene description.
    pub fn new(spec: &ToolSpec) -> Tool {
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
            state: ToolState {
                velocity: v0,
                ..Default::default()
            },
        }
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

/// A slave point's penetration of a tool: gap (m, > 0 inside) and outward unit normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Penetration {
    /// Gap `g` (m), positive when the point is behind the tool surface.
    pub gap: Real,
    /// Unit normal of the master segment, pointing to the workpiece side.
    pub normal: [Real; 2],
}

/// The penetration of point `x` into the polyline `verts` (workpiece on the left), or none.
/// Among the segments whose extent contains the projection of `x` and behind which `x`
/// lies by at most `depth`, the one with the smallest gap wins; a point behind both lines
/// at a left-turning vertex but beyond both segments' ends takes the nearer line.
pub fn penetration(verts: &[[Real; 2]], x: [Real; 2], depth: Real) -> Option<Penetration> {
    fn better(
        best: Option<Penetration>,
        gap: Real,
        normal: [Real; 2],
        depth: Real,
    ) -> Option<Penetration> {
        if gap > 0.0 && gap <= depth && best.is_none_or(|b| gap < b.gap) {
            Some(Penetration { gap, normal })
        } else {
            best
        }
    }
    let mut best: Option<Penetration> = None;
    let nseg = verts.len() - 1;
    let mut gaps = Vec::with_capacity(nseg);
    for k in 0..nseg {
        let (a, b) = (verts[k], verts[k + 1]);
        let (tx, ty) = (b[0] - a[0], b[1] - a[1]);
        let len = (tx * tx + ty * ty).sqrt();
        let (tx, ty) = (tx / len, ty / len);
        let n = [-ty, tx];
        let (rx, ry) = (x[0] - a[0], x[1] - a[1]);
        let s = (rx * tx + ry * ty) / len;
        let gap = -(rx * n[0] + ry * n[1]);
        gaps.push((gap, n, s));
        if (0.0..=1.0).contains(&s) {
            best = better(best, gap, n, depth);
        }
    }
    if best.is_none() {
        // Behind a left-turning vertex (a corner the workpiece fills), beyond the end of one
        // segment and before the start of the next: no segment's extent holds the point.
        for k in 1..nseg {
            let (g0, n0, s0) = gaps[k - 1];
            let (g1, n1, s1) = gaps[k];
            let turn = n0[0] * n1[1] - n0[1] * n1[0];
            if turn > 0.0 && s0 > 1.0 && s1 < 0.0 && g0 > 0.0 && g1 > 0.0 {
                best = if g0 < g1 {
                    better(best, g0, n0, depth)
                } else {
                    better(best, g1, n1, depth)
                };
            }
        }
    }
    best
}

/// Paper eqs. 4-6: contact force on a slave of mass `m` (kg) with gap `g` (m) along the
/// normal `n`, tangential relative velocity taken from `v_rel` (m/s), friction `mu`, and
/// the step factor `dt2 = dt * dt_avg` (s^2; `dt^2` at constant step) and `dt_avg` (s).
pub fn penalty_force(
    m: Real,
    pen: Penetration,
    v_rel: [Real; 2],
    mu: Real,
    dt_step: Real,
    dt_avg: Real,
) -> [Real; 2] {
    let n = pen.normal;
    let fn_ = m * pen.gap / (dt_step * dt_avg);
    let mut f = [fn_ * n[0], fn_ * n[1]];
    if mu > 0.0 {
        let vn = v_rel[0] * n[0] + v_rel[1] * n[1];
        let vt = [v_rel[0] - vn * n[0], v_rel[1] - vn * n[1]];
        let vt_norm = (vt[0] * vt[0] + vt[1] * vt[1]).sqrt();
        if vt_norm > 0.0 {
            let stick = m * vt_norm / dt_avg;
            let ff = (mu * fn_).min(stick);
            f[0] -= ff * vt[0] / vt_norm;
            f[1] -= ff * vt[1] / vt_norm;
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_wall_gap_and_normal() {
        let wall = [[0.0, 0.0], [1.0, 0.0]];
        let p = penetration(&wall, [0.5, -0.01], 0.1).unwrap();
        assert!((p.gap - 0.01).abs() < 1e-15 && p.normal == [0.0, 1.0]);
        assert!(penetration(&wall, [0.5, 0.01], 0.1).is_none());
        assert!(penetration(&wall, [0.5, -0.2], 0.1).is_none());
        assert!(penetration(&wall, [1.5, -0.01], 0.1).is_none());
    }

    #[test]
    fn corner_takes_the_smaller_gap() {
        // A die: floor then a wall going up at x = 1 (workpiece above and left).
        let die = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]];
        let p = penetration(&die, [1.01, 0.3], 0.5).unwrap();
        assert!(
            (p.gap - 0.01).abs() < 1e-12 && p.normal == [-1.0, 0.0],
            "{p:?}"
        );
        let q = penetration(&die, [0.3, -0.02], 0.5).unwrap();
        assert!(
            (q.gap - 0.02).abs() < 1e-12 && q.normal == [-0.0, 1.0],
            "{q:?}"
        );
        // Obtuse corner where both segments claim the point: smaller gap wins.
        let v = [[0.0, 0.0], [1.0, 0.0], [2.0, 1.0]];
        let r = penetration(&v, [0.95, -0.01], 0.5).unwrap();
        assert!((r.gap - 0.01).abs() < 1e-12, "{r:?}");
    }

    #[test]
    fn point_behind_a_filled_corner_vertex_is_caught() {
        // Workpiece in the quadrant x > 0, y > 0; tool wall x < 0 then floor y < 0.
        let tool = [[0.0, 1.0], [0.0, 0.0], [1.0, 0.0]];
        let p = penetration(&tool, [-0.01, -0.02], 0.5).unwrap();
        assert!(
            (p.gap - 0.01).abs() < 1e-12 && p.normal == [1.0, 0.0],
            "{p:?}"
        );
        let q = penetration(&tool, [-0.02, -0.01], 0.5).unwrap();
        assert!(
            (q.gap - 0.01).abs() < 1e-12 && q.normal == [-0.0, 1.0],
            "{q:?}"
        );
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
        let f = penalty_force(m, pen, [5.0, 0.0], 0.3, dt, dt);
        assert!(
            (f[1] - fn_).abs() < 1e-9 && (f[0] + 0.3 * fn_).abs() < 1e-9,
            "{f:?}"
        );
        // Slow sliding: the stick force m v / dt is smaller and wins.
        let f = penalty_force(m, pen, [1e-4, 0.0], 0.3, dt, dt);
        assert!((f[0] + m * 1e-4 / dt).abs() < 1e-12, "{f:?}");
        // Frictionless: no tangential force.
        assert_eq!(penalty_force(m, pen, [5.0, 0.0], 0.0, dt, dt)[0], 0.0);
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
            friction: 0.0,
        };
        let mut t = Tool::new(&spec);
        assert_eq!(t.velocity_at(-1.0), 0.0);
        assert_eq!(t.velocity_at(0.5), 5.0);
        assert_eq!(t.velocity_at(1.5), 0.0);
        assert_eq!(t.velocity_at(9.0), -10.0);
        t.state.command = Some(3.0);
        assert_eq!(t.velocity_at(0.5), 3.0);
    }
}
