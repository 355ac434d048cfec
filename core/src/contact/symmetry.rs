//! Symmetry planes and the axis of an axisymmetric body as frictionless walls that hold
//! every particle reaching them, not only the particles that started on them.
//!
//! A `[[constraints]]` entry that holds an edge's normal component (`x_min` or `x_max` with
//! `fix = ["x"]`, `y_min` or `y_max` with `fix = ["y"]`) is a symmetry plane: the edge's
//! own particles are held on it exactly by the essential conditions
//! ([`crate::constraints`]). Material that reaches the plane later, flowing round a corner
//! or folding (a flash tip made of particles that started on the block's side face), is not
//! among them: here every other particle is held by the plane as by a tool without
//! separation (paper eqs. 4 and 7, no friction): once its physical position
//! `x_J = X_J + sum_I N_I(X_J) d_I` (m) lies beyond the plane by `g > 0`, the normal force
//! `f = m_J g / (dt dt_avg)` (N) pushes it back, and from then on the same force, of either
//! sign, keeps it on the plane (a mirror never lets go: the material's mirror image lies
//! across it). The axis `r = 0` of an axisymmetric body is such a plane whether or not the
//! workpiece starts on it.

use crate::math::Real;
use crate::scene::{Component, Edge, Kinematics, Scene};

/// A symmetry plane `x_c = at` with the material on one side.
#[derive(Debug, Clone, PartialEq)]
pub struct SymmetryPlane {
    /// The edge it was declared on (`x_min`, ...), or `axis` for the axis of an
    /// axisymmetric body.
    pub name: String,
    /// The coordinate it holds (0: x or r, 1: y or z).
    pub component: usize,
    /// Where it lies (m).
    pub at: Real,
    /// `+1` when the material lies at larger coordinates than the plane, `-1` otherwise.
    pub side: Real,
    /// The particles the essential conditions hold on it exactly (by particle index).
    pub exact: Vec<bool>,
}

impl SymmetryPlane {
    /// How far the point `x` (m) lies beyond the plane (m): `side (at - x_c)`, positive on
    /// the far side from the material.
    pub fn beyond(&self, x: [Real; 2]) -> Real {
        self.side * (self.at - x[self.component])
    }

    /// The unit direction from the plane into the material (the push on a particle beyond
    /// it).
    pub fn normal(&self) -> [Real; 2] {
        let mut n = [0.0; 2];
        n[self.component] = self.side;
        n
    }

    /// The plane as a diagnosis names it: "the symmetry plane `y_min` (y = 0 m)" or "the
    /// axis (r = 0)".
    pub fn describe(&self, kinematics: Kinematics) -> String {
        if self.name == "axis" {
            return "the axis (r = 0)".into();
        }
        let coordinate = match (kinematics, self.component) {
            (Kinematics::Axisymmetric, 0) => "r",
            (Kinematics::Axisymmetric, _) => "z",
            (Kinematics::PlaneStrain, 0) => "x",
            (Kinematics::PlaneStrain, _) => "y",
        };
        format!(
            "the symmetry plane `{}` ({coordinate} = {} m)",
            self.name, self.at
        )
    }
}

/// The symmetry planes of a scene whose lattice has its particles at `lattice` (m, row by
/// row): each constrained edge whose normal component is held, where the edge's particles
/// lie, and the axis of an axisymmetric body (held exactly on the particles of the `x_min`
/// edge when the workpiece starts on it). Planes at the same place are one plane.
pub fn planes(scene: &Scene, lattice: &[[Real; 2]]) -> Vec<SymmetryPlane> {
    let [nx, ny] = scene.workpiece.particles;
    let o = scene.workpiece.origin_m;
    let mut planes: Vec<SymmetryPlane> = Vec::new();
    let mut add = |name: &str, component: usize, at: Real, side: Real, exact: &[u32]| {
        let plane = match planes
            .iter_mut()
            .find(|p| p.component == component && p.at == at && p.side == side)
        {
            Some(p) => p,
            None => {
                planes.push(SymmetryPlane {
                    name: name.into(),
                    component,
                    at,
                    side,
                    exact: vec![false; nx * ny],
                });
                planes.last_mut().expect("just pushed")
            }
        };
        for &j in exact {
            plane.exact[j as usize] = true;
        }
    };
    if scene.model.kinematics == Kinematics::Axisymmetric {
        let on_axis = match o[0] == 0.0 {
            true => Edge::XMin.particles(nx, ny),
            false => Vec::new(),
        };
        add("axis", 0, 0.0, 1.0, &on_axis);
    }
    for c in &scene.constraints {
        let (x, y) = (c.fix.contains(&Component::X), c.fix.contains(&Component::Y));
        let (component, side) = match (c.edge, x, y) {
            (Edge::XMin, true, _) => (0, 1.0),
            (Edge::XMax, true, _) => (0, -1.0),
            (Edge::YMin, _, true) => (1, 1.0),
            (Edge::YMax, _, true) => (1, -1.0),
            _ => continue,
        };
        let edge = c.edge.particles(nx, ny);
        let at = lattice[edge[0] as usize][component];
        add(c.edge.name(), component, at, side, &edge);
    }
    planes
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(kinematics: &str, origin: [Real; 2], constraints: &str) -> Scene {
        let text = format!(
            "name = \"s\"\n[model]\nkinematics = \"{kinematics}\"\n[workpiece]\norigin_m = [{}, {}]\nsize_m = [0.004, 0.002]\nparticles = [5, 3]\n[material]\ndensity_kg_per_m3 = 1.0\nyoungs_modulus_pa = 1.0e9\npoisson_ratio = 0.3\nhardening = {{ law = \"linear\", yield_stress_pa = 1.0e6, modulus_pa = 0.0 }}\n[time]\nend_s = 1.0\n{constraints}",
            origin[0], origin[1]
        );
        Scene::from_str_named(&text, "s").unwrap()
    }

    fn lattice(s: &Scene) -> Vec<[Real; 2]> {
        let [nx, ny] = s.workpiece.particles;
        let (o, size) = (s.workpiece.origin_m, s.workpiece.size_m);
        (0..ny)
            .flat_map(|j| {
                (0..nx).map(move |i| {
                    [
                        o[0] + size[0] * i as Real / (nx - 1) as Real,
                        o[1] + size[1] * j as Real / (ny - 1) as Real,
                    ]
                })
            })
            .collect()
    }

    #[test]
    fn a_held_normal_makes_a_plane_and_a_held_tangent_does_not() {
        let s = scene(
            "plane_strain",
            [0.001, -0.002],
            "[[constraints]]\nedge = \"y_min\"\nfix = [\"y\"]\n[[constraints]]\nedge = \"x_max\"\nfix = [\"x\"]\n[[constraints]]\nedge = \"y_max\"\nfix = [\"x\"]\n",
        );
        let p = planes(&s, &lattice(&s));
        assert_eq!(p.len(), 2, "{p:?}");
        let (y_min, x_max) = (&p[0], &p[1]);
        assert_eq!((y_min.name.as_str(), y_min.component), ("y_min", 1));
        assert_eq!((y_min.at, y_min.side), (-0.002, 1.0));
        assert_eq!((x_max.name.as_str(), x_max.component), ("x_max", 0));
        assert!((x_max.at - 0.005).abs() < 1e-15 && x_max.side == -1.0);
        // Beyond: below the mid-plane, right of the x_max plane; the push is back into the
        // material; the edge's own particles are the essential conditions'.
        assert!((y_min.beyond([0.0, -0.003]) - 0.001).abs() < 1e-15);
        assert!(y_min.beyond([0.0, -0.001]) < 0.0);
        assert_eq!(y_min.normal(), [0.0, 1.0]);
        assert_eq!(x_max.normal(), [-1.0, 0.0]);
        assert!((x_max.beyond([0.006, 0.0]) - 0.001).abs() < 1e-12);
        let exact: Vec<usize> = (0..15).filter(|&j| y_min.exact[j]).collect();
        assert_eq!(exact, vec![0, 1, 2, 3, 4]);
        assert_eq!(
            y_min.describe(Kinematics::PlaneStrain),
            "the symmetry plane `y_min` (y = -0.002 m)"
        );
    }

    #[test]
    fn the_axis_is_a_plane_held_exactly_only_where_the_body_starts_on_it() {
        let on = scene("axisymmetric", [0.0, 0.0], "");
        let p = planes(&on, &lattice(&on));
        assert_eq!(p.len(), 1);
        assert_eq!(
            (p[0].name.as_str(), p[0].component, p[0].at),
            ("axis", 0, 0.0)
        );
        let exact: Vec<usize> = (0..15).filter(|&j| p[0].exact[j]).collect();
        assert_eq!(exact, vec![0, 5, 10]);
        assert_eq!(p[0].describe(Kinematics::Axisymmetric), "the axis (r = 0)");
        // A ring off the axis: the axis still holds anything that reaches it.
        let ring = scene("axisymmetric", [0.001, 0.0], "");
        let p = planes(&ring, &lattice(&ring));
        assert_eq!(p.len(), 1);
        assert!(p[0].exact.iter().all(|e| !e));
        // A declared x_min constraint on the axis is the same plane, not a second one.
        let both = scene(
            "axisymmetric",
            [0.0, 0.0],
            "[[constraints]]\nedge = \"x_min\"\nfix = [\"x\"]\n",
        );
        assert_eq!(planes(&both, &lattice(&both)).len(), 1);
    }
}
