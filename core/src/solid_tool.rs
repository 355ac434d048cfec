//! Rigid tools of 3D scenes and the symmetry planes of a half, quarter or eighth model: a
//! plane (a wall, a flat die: the half-space behind it) or a closed triangle surface read
//! from an STL file (a die from CAD: the solid it encloses, [`TriangleSurface`]),
//! translating along an axis as the 2D tools do ([`crate::scene::Motion`]), with the signed
//! gap of a point and the contact normal that the contact stage of the 3D solver reads.
//!
//! A symmetry plane is a fixed, frictionless plane without separation that holds from the
//! start every particle lying on it: the same penalty law as the tools (Sidibe et al. 2009,
//! eqs. 4-7), so material that reaches the plane later is held as well.

use crate::friction::Friction;
use crate::math::{dot, Real};
use crate::scene::solid::SolidToolSpec;
use crate::scene::Motion;
use crate::stl::TriangleMesh;
use crate::tools::{Driven, Penetration};
use crate::triangle_surface::{clip_to_box, Proximity, Ridge, TriangleSurface};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// What changes while a tool moves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct SolidToolState {
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

/// The surface of a rigid tool at the start of its motion.
#[derive(Debug, Clone)]
pub enum Surface {
    /// A plane; the tool fills the half-space behind it.
    Plane {
        /// A point of the plane (m).
        point0: [Real; 3],
        /// Unit normal out of the tool, towards the workpiece.
        normal: [Real; 3],
    },
    /// A closed triangle surface; the tool is the solid it encloses (shared by the clones
    /// of a simulation).
    Triangles(Arc<TriangleSurface>),
}

/// A rigid tool translating along its axis.
#[derive(Debug, Clone)]
pub struct SolidTool {
    /// Name from the scene (`symmetry_x` etc. for a symmetry plane).
    pub name: String,
    /// Its surface at the start.
    pub surface: Surface,
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
    /// Whether the contact's second pass holds its ridges ([`SolidToolSpec::ridges`]).
    pub ridge_pass: bool,
    /// Moving state.
    pub state: SolidToolState,
}

impl SolidTool {
    /// From its scene description, its triangles given for an STL tool (read and checked
    /// by the scene, [`crate::scene::SolidScene::tool_mesh`]); `depth` (m) is the largest
    /// penetration treated as contact.
    pub fn new(spec: &SolidToolSpec, mesh: Option<TriangleMesh>, depth: Real) -> SolidTool {
        let v0 = match spec.motion {
            Motion::External {
                initial_velocity_m_per_s,
            } => initial_velocity_m_per_s,
            _ => 0.0,
        };
        let surface = match mesh {
            Some(mesh) => Surface::Triangles(Arc::new(TriangleSurface::new(mesh))),
            None => Surface::Plane {
                point0: spec.point_m.unwrap_or_default(),
                normal: spec.normal.unwrap_or_default(),
            },
        };
        SolidTool {
            name: spec.name.clone(),
            surface,
            axis: spec.axis,
            motion: spec.motion.clone(),
            friction: spec.friction,
            separation: spec.separation,
            symmetry: false,
            depth,
            ridge_pass: spec.ridges,
            state: SolidToolState {
                velocity: v0,
                ..Default::default()
            },
        }
    }

    /// The symmetry plane `x_axis = at` (m) with the body on its positive side.
    pub fn symmetry(axis: usize, at: Real, depth: Real) -> SolidTool {
        let mut normal = [0.0; 3];
        normal[axis] = 1.0;
        let mut point0 = [0.0; 3];
        point0[axis] = at;
        SolidTool {
            name: format!("symmetry_{}", ["x", "y", "z"][axis]),
            surface: Surface::Plane { point0, normal },
            axis: normal,
            motion: Motion::Fixed,
            friction: Friction::Coulomb { mu: 0.0 },
            separation: false,
            symmetry: true,
            depth,
            ridge_pass: false,
            state: SolidToolState::default(),
        }
    }

    /// The translation of the tool from its start, `s a` (m).
    fn shift(&self) -> [Real; 3] {
        let s = self.state.stroke;
        self.axis.map(|a| s * a)
    }

    /// Signed depth of the point `x` (m) inside the tool in its current position (m),
    /// positive inside: a plane's `g = -n . (x - p0 - s a)`; a triangle surface's `-phi`,
    /// its signed distance ([`TriangleSurface::closest`]), exact at any depth.
    pub fn depth_of(&self, x: [Real; 3]) -> Real {
        match &self.surface {
            Surface::Plane { point0, normal } => {
                let s = self.state.stroke;
                let rel: [Real; 3] = std::array::from_fn(|k| x[k] - point0[k] - s * self.axis[k]);
                -dot(normal, &rel)
            }
            Surface::Triangles(t) => -t.closest(x, self.shift()).signed,
        }
    }

    /// A lower bound on how far `x` (m) lies in front of the tool (m), its distance for a
    /// plane; negative inside. A triangle surface answers from its bins alone (the bound
    /// of [`TriangleSurface::locate`]) unless the point's own bin holds a triangle.
    pub fn clearance(&self, x: [Real; 3]) -> Real {
        match &self.surface {
            Surface::Plane { .. } => -self.depth_of(x),
            Surface::Triangles(t) => match t.locate(x, self.shift(), 0.0) {
                Proximity::Far { distance, inside } => match inside {
                    true => -distance,
                    false => distance,
                },
                Proximity::Near(c) => c.signed,
            },
        }
    }

    /// The deepest `x` (m) lies inside the tool, or any value not above 0 when it lies
    /// outside (m): the depth, found from the bins alone for a point far outside a
    /// triangle surface.
    pub fn inside_by(&self, x: [Real; 3]) -> Real {
        match &self.surface {
            Surface::Plane { .. } => self.depth_of(x),
            Surface::Triangles(t) => match t.locate(x, self.shift(), 0.0) {
                Proximity::Far { inside: false, .. } => 0.0,
                Proximity::Far { inside: true, .. } => -t.closest(x, self.shift()).signed,
                Proximity::Near(c) => -c.signed,
            },
        }
    }

    /// The penetration of `x` (m) when its signed depth lies between `below` (m, exclusive;
    /// a negative value reaches in front of the tool for a held particle) and the search
    /// depth, with the contact normal: a plane's normal; on a triangle surface the face's
    /// normal, or at an edge or vertex the direction from the closest point to `x` out of
    /// the die ([`crate::triangle_surface`]).
    pub fn gap_above(&self, x: [Real; 3], below: Real) -> Option<Penetration<3>> {
        let (gap, normal) = match &self.surface {
            Surface::Plane { normal, .. } => (self.depth_of(x), *normal),
            Surface::Triangles(t) => match t.locate(x, self.shift(), (-below).max(0.0)) {
                Proximity::Far {
                    inside: true,
                    distance,
                } if distance <= self.depth => {
                    let c = t.closest(x, self.shift());
                    (-c.signed, c.normal)
                }
                Proximity::Far { .. } => return None,
                Proximity::Near(c) => (-c.signed, c.normal),
            },
        };
        (gap > below && gap <= self.depth).then_some(Penetration { gap, normal })
    }

    /// The contact normal at `x` (m) when it lies within `within` (m) in front of the tool
    /// or inside it: a plane's normal, a triangle surface's at the closest point.
    pub fn touching(&self, x: [Real; 3], within: Real) -> Option<[Real; 3]> {
        match &self.surface {
            Surface::Plane { normal, .. } => (self.depth_of(x) >= -within).then_some(*normal),
            Surface::Triangles(t) => match t.locate(x, self.shift(), within) {
                Proximity::Far { inside: false, .. } => None,
                Proximity::Far { inside: true, .. } => Some(t.closest(x, self.shift()).normal),
                Proximity::Near(c) => (c.signed <= within).then_some(c.normal),
            },
        }
    }

    /// Whether the tool has ridges ([`TriangleSurface::ridges`]) and the scene turns the
    /// contact stage's second pass on for it ([`SolidToolSpec::ridges`]): the pass checks
    /// them against the workpiece's surface.
    pub fn has_ridges(&self) -> bool {
        self.ridge_pass && matches!(&self.surface, Surface::Triangles(t) if !t.ridges().is_empty())
    }

    /// The tool's ridges in its current position (m) that reach into the box `lo..hi` (m),
    /// whole (not clipped: the second pass samples each at fixed points along it), in their
    /// order; none for a plane or a cylinder.
    pub fn ridges_in(&self, lo: [Real; 3], hi: [Real; 3]) -> Vec<Ridge> {
        let Surface::Triangles(t) = &self.surface else {
            return Vec::new();
        };
        let shift = self.shift();
        t.ridges()
            .iter()
            .filter_map(|r| {
                let a: [Real; 3] = std::array::from_fn(|k| r.a[k] + shift[k]);
                let b: [Real; 3] = std::array::from_fn(|k| r.b[k] + shift[k]);
                clip_to_box(a, b, lo, hi)?;
                Some(Ridge {
                    a,
                    b,
                    normal: r.normal,
                })
            })
            .collect()
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

impl Driven for SolidTool {
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
    use crate::scene::solid::ToolShape;

    /// A wall under z = 0 moving down: the depth is measured from the plane where it is
    /// now, within the search depth and, for a held particle, in front of it.
    #[test]
    fn depth_follows_the_moving_plane() {
        let spec = SolidToolSpec {
            name: "die".into(),
            shape: ToolShape::Plane,
            point_m: Some([0.0, 0.0, 1.0]),
            normal: Some([0.0, 0.0, -1.0]),
            file: None,
            unit: None,
            axis: [0.0, 0.0, -1.0],
            motion: Motion::Constant {
                velocity_m_per_s: 2.0,
            },
            friction: Friction::default(),
            separation: true,
            temperature_c: None,
            heat_transfer_w_per_m2_k: 0.0,
            heat_transfer_by_pressure: Vec::new(),
            fill_points: Vec::new(),
            ridges: false,
        };
        let mut t = SolidTool::new(&spec, None, 0.5);
        assert_eq!(t.depth_of([3.0, -2.0, 0.75]), -0.25);
        t.state.stroke = 0.5;
        assert_eq!(t.depth_of([3.0, -2.0, 0.75]), 0.25);
        assert_eq!(t.gap_above([0.0, 0.0, 0.75], 0.0).unwrap().gap, 0.25);
        assert!(t.gap_above([0.0, 0.0, 0.5 + 0.6], 0.0).is_none());
        assert!(t.gap_above([0.0, 0.0, 0.25], 0.0).is_none());
        assert_eq!(t.gap_above([0.0, 0.0, 0.25], -0.5).unwrap().gap, -0.25);
        assert_eq!(t.velocity_at(1.0), 2.0);
        let s = SolidTool::symmetry(1, 0.0, 0.1);
        assert_eq!(s.depth_of([5.0, -0.01, 7.0]), 0.01);
        assert!(!s.separation && s.friction.is_frictionless());
    }
}
