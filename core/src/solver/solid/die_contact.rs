//! What the dies feel in 3D: the area of the workpiece's surface in contact with each tool,
//! its share of the surface, and the contact pressure on an STL die as a field over its
//! triangles. All three are read from the state alone (the normal forces the last contact
//! stage booked, [`SolidState::pressed`], and the displacements), so a restored state reports
//! them as first computed.
//!
//! Contact area of tool `t` (m^2): `A_t = sum_J sum_q |a_q . n_J|` over the particles `J` the
//! last contact stage pressed on `t`, `q` over the quarters of the surface's faces at `J`
//! (`heat.rs`: the quarter's area vector `a_q` at the particles' physical positions now),
//! `n_J` the contact normal the stage used. The projection on the tool's tangent plane,
//! rather than the quarter's full area `|a_q|`, is what a pressure acts over: a uniform
//! pressure `p` on a patch gives the normal force `p sum |a . n|`, and a particle on the
//! edge of a block's face pressed on a die brings its quarters on the side faces with
//! `a . n = 0` instead of their full area, which would count the free sides as contact. It
//! is the area the heat stage and the friction laws that need one take
//! ([`super::heat::HeatSurface::contact_area`]), here over the particles the stage pressed
//! (each particle's tributary share, half a cell past the last particle in contact, where
//! 2D's contact length stops at that particle). Its share is `A_t / A_s`, `A_s = sum |a_q|`
//! over every quarter: the workpiece's own surface less its faces on symmetry planes.
//!
//! Pressure on an STL die (Pa), per triangle: each pressed particle's normal force
//! `f_J = f . n` (N) goes to the triangle of the die closest to the particle's physical
//! position now (the die where it is now; on a shared edge or vertex the lowest-numbered
//! of the nearest triangles), and `p_k = sum_{J -> k} f_J / A_k`, `A_k` the triangle's area
//! (m^2). So `sum_k p_k A_k = sum_J f_J`, the tool's normal force, to round-off. The field is
//! as fine as the die's triangles: a flat face of two triangles carries its mean pressure.

use super::{SolidSimulation, SolidState};
use crate::math::Real;
use crate::solid_tool::Surface;
use crate::stl::{cross, dot, sub};

/// The contact pressure on an STL die over its triangles, the die where it is now.
#[derive(Debug, Clone, PartialEq)]
pub struct DiePressure {
    /// The die's vertices, moved with it (m).
    pub vertices: Vec<[Real; 3]>,
    /// Its triangles, indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
    /// Each triangle's area (m^2).
    pub areas: Vec<Real>,
    /// The normal contact force on each triangle (N).
    pub forces: Vec<Real>,
    /// The contact pressure on each triangle, its force over its area (Pa).
    pub pressure: Vec<Real>,
}

impl SolidSimulation {
    /// The area of the workpiece's surface now (m^2), `A_s = sum |a_q|` over the quarters of
    /// its faces (the faces on symmetry planes not among them).
    pub fn surface_area(&self) -> Real {
        let x = self.positions();
        self.disc.heat_surface.area(|j| x[j])
    }

    /// The area of the workpiece's surface in contact with scene tool `t` now (m^2), `A_t =
    /// sum |a_q . n_J|` over the particles the last contact stage pressed on it (see the
    /// module doc).
    pub fn contact_area(&self, t: usize) -> Real {
        let x = self.positions();
        pressed_on(&self.st, t)
            .filter_map(|p| {
                self.disc
                    .heat_surface
                    .contact_area(p.particle as usize, &p.normal, |j| x[j])
            })
            .sum()
    }

    /// The contact pressure on scene tool `t`'s triangles (see the module doc), `None` for
    /// a plane tool.
    pub fn die_pressure(&self, t: usize) -> Option<DiePressure> {
        let tool = &self.tools()[t];
        let Surface::Triangles(surface) = &tool.surface else {
            return None;
        };
        let shift: [Real; 3] = tool.axis.map(|a| a * tool.state.stroke);
        let mesh = surface.mesh();
        let areas: Vec<Real> = (0..mesh.triangles.len())
            .map(|k| {
                let [a, b, c] = mesh.corners(k);
                let n = cross(sub(b, a), sub(c, a));
                0.5 * dot(n, n).sqrt()
            })
            .collect();
        let mut forces = vec![0.0; areas.len()];
        let x = self.positions();
        for p in pressed_on(&self.st, t) {
            let k = surface.closest(x[p.particle as usize], shift).triangle as usize;
            forces[k] += p.force_n;
        }
        Some(DiePressure {
            vertices: mesh
                .vertices
                .iter()
                .map(|v| std::array::from_fn(|k| v[k] + shift[k]))
                .collect(),
            triangles: mesh.triangles.clone(),
            pressure: forces.iter().zip(&areas).map(|(f, a)| f / a).collect(),
            areas,
            forces,
        })
    }
}

/// The normal forces of the last contact stage on scene tool `t`.
fn pressed_on(st: &SolidState, t: usize) -> impl Iterator<Item = &super::Pressed> {
    st.pressed.iter().filter(move |p| p.tool as usize == t)
}
