//! Rigid plane tools of 3D scenes (a wall, a flat die) and the symmetry planes of a half,
//! quarter or eighth model: the half-space behind a plane, translating along an axis as
//! the 2D tools do ([`crate::scene::Motion`]), with the signed gap of a point that the
//! contact stage of the 3D solver reads.
//!
//! A symmetry plane is a fixed, frictionless plane without separation that holds from the
//! start every particle lying on it: the same penalty law as the tools (Sidibe et al. 2009,
//! eqs. 4-7), so material that reaches the plane later is held as well.

use crate::friction::Friction;
use crate::math::{dot, Real};
use crate::scene::solid::PlaneToolSpec;
use crate::scene::Motion;
use crate::tools::{Driven, Penetration};
use serde::{Deserialize, Serialize};

/// What changes while a plane tool moves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct PlaneToolState {
    /// Displacement along the axis (m).
    pub stroke: Real,
    /// Velocity along the axis during the last step (m/s).
    pub velocity: Real,
    /// Velocity set from outside, overriding the scene motion (m/s).
    pub command: Option<Real>,
    /// Force of the workpiece on the tool during the last step (N).
    pub force: [Real; 3],
    /// Normal force of the workpiece on the tool during the last step (N), positive pressing.
    pub normal_force: Real,
    /// Largest force magnitude so far (N).
    pub peak_force: Real,
}

/// A rigid plane translating along its axis; the tool fills the half-space behind it.
#[derive(Debug, Clone)]
pub struct PlaneTool {
    /// Name from the scene (`symmetry_x` etc. for a symmetry plane).
    pub name: String,
    /// A point of the plane at the start (m).
    pub point0: [Real; 3],
    /// Unit normal out of the tool, towards the workpiece.
    pub normal: [Real; 3],
    /// Unit axis of the motion.
    pub axis: [Real; 3],
    /// Scene motion.
    pub motion: Motion,
    /// Friction law of the interface.
    pub friction: Friction,
    /// Whether particles may leave the tool (false: a particle that reached it stays on it).
    pub separation: bool,
    /// A symmetry plane rather than a tool (not reported among the tools).
    pub symmetry: bool,
    /// Largest penetration treated as contact (m).
    pub depth: Real,
    /// Moving state.
    pub state: PlaneToolState,
}

impl PlaneTool {
    /// From its scene description; `depth` (m) is the largest penetration treated as
    /// contact.
    pub fn new(spec: &PlaneToolSpec, depth: Real) -> PlaneTool {
        let v0 = match spec.motion {
            Motion::External {
                initial_velocity_m_per_s,
            } => initial_velocity_m_per_s,
            _ => 0.0,
        };
        PlaneTool {
            name: spec.name.clone(),
            point0: spec.point_m,
            normal: spec.normal,
            axis: spec.axis,
            motion: spec.motion.clone(),
            friction: spec.friction,
            separation: spec.separation,
            symmetry: false,
            depth,
            state: PlaneToolState {
                velocity: v0,
                ..Default::default()
            },
        }
    }

    /// The symmetry plane `x_axis = at` (m) with the body on its positive side.
    pub fn symmetry(axis: usize, at: Real, depth: Real) -> PlaneTool {
        let mut normal = [0.0; 3];
        normal[axis] = 1.0;
        let mut point0 = [0.0; 3];
        point0[axis] = at;
        PlaneTool {
            name: format!("symmetry_{}", ["x", "y", "z"][axis]),
            point0,
            normal,
            axis: normal,
            motion: Motion::Fixed,
            friction: Friction::Coulomb { mu: 0.0 },
            separation: false,
            symmetry: true,
            depth,
            state: PlaneToolState::default(),
        }
    }

    /// Signed depth of the point `x` (m) behind the plane in its current position (m):
    /// `g = -n . (x - p0 - s a)`, positive inside the tool.
    pub fn depth_of(&self, x: [Real; 3]) -> Real {
        let s = self.state.stroke;
        let rel: [Real; 3] = std::array::from_fn(|k| x[k] - self.point0[k] - s * self.axis[k]);
        -dot(&self.normal, &rel)
    }

    /// The penetration of `x` (m) when its signed depth lies between `below` (m, exclusive;
    /// a negative value reaches in front of the plane for a held particle) and the search
    /// depth.
    pub fn gap_above(&self, x: [Real; 3], below: Real) -> Option<Penetration<3>> {
        let gap = self.depth_of(x);
        (gap > below && gap <= self.depth).then_some(Penetration {
            gap,
            normal: self.normal,
        })
    }

    /// Velocity along the axis (m/s) at time `t` (s): the command, else the motion's.
    pub fn velocity_at(&self, t: Real) -> Real {
        self.motion.velocity_at(t, self.state.command)
    }

    /// The force on the tool along its axis (N).
    pub fn axial_force(&self) -> Real {
        dot(&self.state.force, &self.axis)
    }
}

impl Driven for PlaneTool {
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

    /// A wall under z = 0 moving down: the depth is measured from the plane where it is
    /// now, within the search depth and, for a held particle, in front of it.
    #[test]
    fn depth_follows_the_moving_plane() {
        let spec = PlaneToolSpec {
            name: "die".into(),
            point_m: [0.0, 0.0, 1.0],
            normal: [0.0, 0.0, -1.0],
            axis: [0.0, 0.0, -1.0],
            motion: Motion::Constant {
                velocity_m_per_s: 2.0,
            },
            friction: Friction::default(),
            separation: true,
            temperature_c: None,
            heat_transfer_w_per_m2_k: 0.0,
            heat_transfer_by_pressure: Vec::new(),
        };
        let mut t = PlaneTool::new(&spec, 0.5);
        assert_eq!(t.depth_of([3.0, -2.0, 0.75]), -0.25);
        t.state.stroke = 0.5;
        assert_eq!(t.depth_of([3.0, -2.0, 0.75]), 0.25);
        assert_eq!(t.gap_above([0.0, 0.0, 0.75], 0.0).unwrap().gap, 0.25);
        assert!(t.gap_above([0.0, 0.0, 0.5 + 0.6], 0.0).is_none());
        assert!(t.gap_above([0.0, 0.0, 0.25], 0.0).is_none());
        assert_eq!(t.gap_above([0.0, 0.0, 0.25], -0.5).unwrap().gap, -0.25);
        assert_eq!(t.velocity_at(1.0), 2.0);
        let s = PlaneTool::symmetry(1, 0.0, 0.1);
        assert_eq!(s.depth_of([5.0, -0.01, 7.0]), 0.01);
        assert!(!s.separation && s.friction.is_frictionless());
    }
}
