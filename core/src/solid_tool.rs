//! Rigid tools of 3D scenes and the symmetry planes of a half, quarter or eighth model: a
//! plane (a wall, a flat die: the half-space behind it), a solid circular cylinder (a pin,
//! a punch, a roll or a mandrel: [`Cylinder`], unbounded or with flat end caps) or a closed
//! triangle surface read from an STL file (a die from CAD: the solid it encloses,
//! [`TriangleSurface`]),
//! translating along an axis as the 2D tools do ([`crate::scene::Motion`]), with the signed
//! gap of a point and the contact normal that the contact stage of the 3D solver reads.
//!
//! A symmetry plane is a fixed, frictionless plane without separation that holds from the
//! start every particle lying on it: the same penalty law as the tools (Sidibe et al. 2009,
//! eqs. 4-7), so material that reaches the plane later is held as well.

use crate::friction::Friction;
use crate::math::{dot, Real};
use crate::scene::solid::{SolidToolSpec, ToolShape};
use crate::scene::Motion;
use crate::stl::TriangleMesh;
use crate::tools::{Account, Driven, Penetration};
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
    /// What the tool received from the workpiece since the start.
    pub account: Account,
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
    /// A solid circular cylinder, unbounded or with flat end caps.
    Cylinder(Cylinder),
    /// A closed triangle surface; the tool is the solid it encloses (shared by the clones
    /// of a simulation).
    Triangles(Arc<TriangleSurface>),
}

/// The solid circular cylinder of radius `R` about the line through `centre` along the unit
/// `direction`: unbounded along it, or capped by the flat ends `a = +-H` (`a` the coordinate
/// along the axis from the centre, `H` half the length). Its exact signed distance and
/// outward normal are [`Cylinder::signed`]; no tessellation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    /// The point of the axis at the middle of the length (any point of it when unbounded; m).
    pub centre: [Real; 3],
    /// Unit direction of the axis.
    pub direction: [Real; 3],
    /// Radius `R` (m).
    pub radius: Real,
    /// Half the length `H` (m); `None`: unbounded along the axis.
    pub half_length: Option<Real>,
}

impl Cylinder {
    /// The signed distance `phi` (m, positive outside) of the point `x` (m) from the
    /// cylinder's surface and the outward unit normal of the surface's feature nearest to it,
    /// `n = grad phi`. With `r = x - c`, `a = r . d` the coordinate along the axis, `q = r - a
    /// d` the radial part, `rho = |q|`, `e = q / rho`, and the distances past the mantle and
    /// past the nearer cap `u = rho - R`, `w = |a| - H` (m):
    ///
    /// - unbounded: `phi = u`, `n = e`;
    /// - outside beside the mantle (`u > 0`, `w <= 0`): `phi = u`, `n = e`;
    /// - outside beyond a cap (`w > 0`, `u <= 0`): `phi = w`, `n = sign(a) d`;
    /// - outside beyond the cap's rim (`u, w > 0`): `phi = sqrt(u^2 + w^2)`, `n = (u e + w
    ///   sign(a) d) / phi`, from the rim's nearest point;
    /// - inside (`u, w <= 0`): `phi = max(u, w)` (the nearer of the mantle and the cap),
    ///   `n` that feature's normal (the mantle's on a tie).
    ///
    /// The nearest point of the surface is `x - phi n` in every case. On the axis (`rho =
    /// 0`) `e` is any unit vector normal to `d` ([`normal_to`]).
    pub fn signed(&self, x: [Real; 3]) -> (Real, [Real; 3]) {
        let d = self.direction;
        let r: [Real; 3] = std::array::from_fn(|k| x[k] - self.centre[k]);
        let a = dot(&r, &d);
        let q: [Real; 3] = std::array::from_fn(|k| r[k] - a * d[k]);
        let rho = dot(&q, &q).sqrt();
        let e = match rho > 0.0 {
            true => q.map(|c| c / rho),
            false => normal_to(d),
        };
        let u = rho - self.radius;
        let Some(h) = self.half_length else {
            return (u, e);
        };
        let w = a.abs() - h;
        let cap = match a < 0.0 {
            true => d.map(|c| -c),
            false => d,
        };
        if u > 0.0 && w > 0.0 {
            let phi = (u * u + w * w).sqrt();
            (phi, std::array::from_fn(|k| (u * e[k] + w * cap[k]) / phi))
        } else if u >= w {
            (u, e)
        } else {
            (w, cap)
        }
    }
}

/// A unit vector normal to the unit vector `d`: `d` crossed with the coordinate axis least
/// aligned with it, normalised.
pub fn normal_to(d: [Real; 3]) -> [Real; 3] {
    let k = (0..3)
        .min_by(|&i, &j| d[i].abs().total_cmp(&d[j].abs()))
        .unwrap_or(0);
    let mut e = [0.0; 3];
    e[k] = 1.0;
    let c = [
        d[1] * e[2] - d[2] * e[1],
        d[2] * e[0] - d[0] * e[2],
        d[0] * e[1] - d[1] * e[0],
    ];
    let n = dot(&c, &c).sqrt();
    c.map(|x| x / n)
}

/// What a tool's surface answers about a point ([`SolidTool::at`]).
enum Local<'a> {
    /// A plane's or a cylinder's signed depth (m, positive inside) and outward normal.
    Analytic(Real, [Real; 3]),
    /// A triangle surface, to be searched.
    Triangles(&'a TriangleSurface),
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
    /// penetration treated as contact. A cylinder's axis direction is normalised (the
    /// scene checks it is a unit vector within 1e-9).
    pub fn new(spec: &SolidToolSpec, mesh: Option<TriangleMesh>, depth: Real) -> SolidTool {
        let v0 = match spec.motion {
            Motion::External {
                initial_velocity_m_per_s,
            } => initial_velocity_m_per_s,
            _ => 0.0,
        };
        let surface = match (mesh, spec.shape) {
            (Some(mesh), _) => Surface::Triangles(Arc::new(TriangleSurface::new(mesh))),
            (None, ToolShape::Cylinder) => {
                let d = spec.axis_direction.unwrap_or([0.0, 0.0, 1.0]);
                let n = dot(&d, &d).sqrt();
                Surface::Cylinder(Cylinder {
                    centre: spec.center_m.unwrap_or_default(),
                    direction: d.map(|c| c / n),
                    radius: spec.radius_m.unwrap_or_default(),
                    half_length: spec.length_m.map(|l| 0.5 * l),
                })
            }
            (None, _) => Surface::Plane {
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

    /// What the tool's surface answers about the point `x` (m) where the tool is now: an
    /// analytic surface its signed depth (m, positive inside) and outward contact normal, a
    /// plane's `g = -n . (x - p0 - s a)` and its normal `n`, a cylinder's `-phi` of its
    /// signed distance and the normal of its nearest feature ([`Cylinder::signed`], at `x -
    /// s a`), both exact at any depth, so the clearance, the depth and the gap below are
    /// this one value; a triangle surface itself, to be searched.
    fn at(&self, x: [Real; 3]) -> Local<'_> {
        let s = self.state.stroke;
        match &self.surface {
            Surface::Plane { point0, normal } => {
                let rel: [Real; 3] = std::array::from_fn(|k| x[k] - point0[k] - s * self.axis[k]);
                Local::Analytic(-dot(normal, &rel), *normal)
            }
            Surface::Cylinder(c) => {
                let (phi, n) = c.signed(std::array::from_fn(|k| x[k] - s * self.axis[k]));
                Local::Analytic(-phi, n)
            }
            Surface::Triangles(t) => Local::Triangles(t),
        }
    }

    /// Signed depth of the point `x` (m) inside the tool in its current position (m),
    /// positive inside: a plane's or a cylinder's ([`SolidTool::at`]); a triangle surface's
    /// `-phi`, its signed distance ([`TriangleSurface::closest`]), exact at any depth.
    pub fn depth_of(&self, x: [Real; 3]) -> Real {
        match self.at(x) {
            Local::Analytic(depth, _) => depth,
            Local::Triangles(t) => -t.closest(x, self.shift()).signed,
        }
    }

    /// A lower bound on how far `x` (m) lies in front of the tool (m), its distance for a
    /// plane or a cylinder; negative inside. A triangle surface answers from its bins alone
    /// (the bound of [`TriangleSurface::locate`]) unless the point's own bin holds a
    /// triangle.
    pub fn clearance(&self, x: [Real; 3]) -> Real {
        match self.at(x) {
            Local::Analytic(depth, _) => -depth,
            Local::Triangles(t) => match t.locate(x, self.shift(), 0.0) {
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
        match self.at(x) {
            Local::Analytic(depth, _) => depth,
            Local::Triangles(t) => match t.locate(x, self.shift(), 0.0) {
                Proximity::Far { inside: false, .. } => 0.0,
                Proximity::Far { inside: true, .. } => -t.closest(x, self.shift()).signed,
                Proximity::Near(c) => -c.signed,
            },
        }
    }

    /// The penetration of `x` (m) when its signed depth lies between `below` (m, exclusive;
    /// a negative value reaches in front of the tool for a held particle) and the search
    /// depth, with the contact normal: a plane's normal, a cylinder's at its nearest feature
    /// (the mantle's radial direction, a cap's axis direction, or from the cap's rim to `x`);
    /// on a triangle surface the face's normal, or at an edge or vertex the direction from
    /// the closest point to `x` out of the die ([`crate::triangle_surface`]).
    pub fn gap_above(&self, x: [Real; 3], below: Real) -> Option<Penetration<3>> {
        let (gap, normal) = match self.at(x) {
            Local::Analytic(depth, normal) => (depth, normal),
            Local::Triangles(t) => match t.locate(x, self.shift(), (-below).max(0.0)) {
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
    /// or inside it: a plane's normal, a cylinder's or a triangle surface's at the closest
    /// point.
    pub fn touching(&self, x: [Real; 3], within: Real) -> Option<[Real; 3]> {
        match self.at(x) {
            Local::Analytic(depth, normal) => (depth >= -within).then_some(normal),
            Local::Triangles(t) => match t.locate(x, self.shift(), within) {
                Proximity::Far { inside: false, .. } => None,
                Proximity::Far { inside: true, .. } => Some(t.closest(x, self.shift()).normal),
                Proximity::Near(c) => (c.signed <= within).then_some(c.normal),
            },
        }
    }

    /// The point of an analytic tool's surface (a plane's or a cylinder's) nearest to `x`
    /// (m), where the tool is now: `x + g n` with the depth `g` and the normal `n` of
    /// [`SolidTool::at`]; `None` for a triangle surface.
    pub fn nearest_on_surface(&self, x: [Real; 3]) -> Option<[Real; 3]> {
        match self.at(x) {
            Local::Analytic(g, n) => Some(std::array::from_fn(|k| x[k] + g * n[k])),
            Local::Triangles(_) => None,
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

    /// A plane tool `die` filling z > 1 (its face z = 1 looking down), moving down at 2 m/s.
    fn plane_spec() -> SolidToolSpec {
        SolidToolSpec {
            name: "die".into(),
            shape: ToolShape::Plane,
            point_m: Some([0.0, 0.0, 1.0]),
            normal: Some([0.0, 0.0, -1.0]),
            center_m: None,
            axis_direction: None,
            radius_m: None,
            length_m: None,
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
        }
    }

    /// A wall under z = 0 moving down: the depth is measured from the plane where it is
    /// now, within the search depth and, for a held particle, in front of it.
    #[test]
    fn depth_follows_the_moving_plane() {
        let spec = plane_spec();
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

    /// The distance (m) and normal of a capped cylinder on a tilted axis against hand
    /// computed points. With `d = (0, 0.6, 0.8)`, `e1 = (1, 0, 0)`, `e2 = d x e1 = (0, 0.8,
    /// -0.6)`, `R = 0.5`, `H = 1` and a point `c + a d + rho e`: beside the mantle (`a =
    /// 0.3`, `rho = 0.8` along `e1`) `phi = 0.3`, `n = e1`; inside near the mantle (`a =
    /// 0.2`, `rho = 0.4` along `e2`) `-0.1`, `e2`; inside near a cap (`a = 0.9`, `rho =
    /// 0.1`) `-0.1`, `d`; beyond the other cap (`a = -1.25`, `rho = 0.3`) `0.25`, `-d`;
    /// beyond the rim (`a = 1.3`, `rho = 0.9` along `e2`: 0.4 past the mantle, 0.3 past the
    /// cap) `0.5`, `(0.8 e2 + 0.6 d)`; at the centre `-0.5` (the mantle nearer than the caps)
    /// with a unit normal across the axis; unbounded, far along the axis (`a = 5`, `rho =
    /// 0.8`) `0.3`, `e1`. The nearest point `x - phi n` lies on the surface.
    #[test]
    fn a_cylinders_distance_and_normal_are_the_hand_computed_ones() {
        let (c, d) = ([1.0, 2.0, 3.0], [0.0, 0.6, 0.8]);
        let (e1, e2) = ([1.0, 0.0, 0.0], [0.0, 0.8, -0.6]);
        let capped = Cylinder {
            centre: c,
            direction: d,
            radius: 0.5,
            half_length: Some(1.0),
        };
        let at = |a: Real, rho: Real, e: [Real; 3]| -> [Real; 3] {
            std::array::from_fn(|k| c[k] + a * d[k] + rho * e[k])
        };
        let comb = |p: Real, u: [Real; 3], q: Real, v: [Real; 3]| -> [Real; 3] {
            std::array::from_fn(|k| p * u[k] + q * v[k])
        };
        let cases = [
            (at(0.3, 0.8, e1), 0.3, e1),
            (at(0.2, 0.4, e2), -0.1, e2),
            (at(0.9, 0.1, e1), -0.1, d),
            (at(-1.25, 0.3, e1), 0.25, d.map(|x| -x)),
            (at(1.3, 0.9, e2), 0.5, comb(0.8, e2, 0.6, d)),
        ];
        for (x, phi, n) in cases {
            let (p, m) = capped.signed(x);
            assert!((p - phi).abs() < 1e-12, "{x:?}: {p} against {phi}");
            assert!((0..3).all(|k| (m[k] - n[k]).abs() < 1e-12), "{x:?}: {m:?}");
            let on: [Real; 3] = std::array::from_fn(|k| x[k] - p * m[k]);
            assert!(capped.signed(on).0.abs() < 1e-12, "{x:?}");
        }
        let (p, m) = capped.signed(c);
        assert!((p + 0.5).abs() < 1e-12 && dot(&m, &d).abs() < 1e-12);
        assert!((dot(&m, &m) - 1.0).abs() < 1e-12);
        let unbounded = Cylinder {
            half_length: None,
            ..capped
        };
        let (p, m) = unbounded.signed(at(5.0, 0.8, e1));
        assert!((p - 0.3).abs() < 1e-12 && (0..3).all(|k| (m[k] - e1[k]).abs() < 1e-12));
    }

    /// A cylinder tool moving down its motion axis: the depth, the gap, the clearance and
    /// the touch follow it as they do a plane.
    #[test]
    fn a_cylinder_tool_moves_with_its_stroke() {
        let spec = SolidToolSpec {
            name: "pin".into(),
            shape: ToolShape::Cylinder,
            point_m: None,
            normal: None,
            center_m: Some([0.0, 0.0, 2.0]),
            axis_direction: Some([1.0, 0.0, 0.0]),
            radius_m: Some(1.0),
            motion: Motion::Constant {
                velocity_m_per_s: 1.0,
            },
            ..plane_spec()
        };
        let mut t = SolidTool::new(&spec, None, 0.5);
        // The lowest line of the mantle is z = 1: a point at z = 0.75 under it is 0.25 clear.
        assert!((t.depth_of([7.0, 0.0, 0.75]) + 0.25).abs() < 1e-15);
        assert!((t.clearance([7.0, 0.0, 0.75]) - 0.25).abs() < 1e-15);
        assert!(t.gap_above([7.0, 0.0, 0.75], 0.0).is_none());
        assert_eq!(t.touching([7.0, 0.0, 0.75], 0.3), Some([0.0, 0.0, -1.0]));
        t.state.stroke = 0.5;
        let pen = t.gap_above([7.0, 0.0, 0.75], 0.0).unwrap();
        assert!((pen.gap - 0.25).abs() < 1e-15 && pen.normal == [0.0, 0.0, -1.0]);
        assert_eq!(t.inside_by([7.0, 0.0, 0.75]), t.depth_of([7.0, 0.0, 0.75]));
        let on = t.nearest_on_surface([7.0, 0.0, 0.75]).unwrap();
        assert!((on[2] - 0.5).abs() < 1e-15 && on[0] == 7.0);
    }
}
