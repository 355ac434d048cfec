//! What the dies feel in 3D: the area of the workpiece's surface in contact with each tool,
//! its share of the surface, and the contact pressure on the tool as a field over
//! triangles (an STL die's own, a plane's or a cylinder's contact patch). All three are read from the state alone (the normal forces the last contact
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
//! Pressure on a tool (Pa), per triangle. On an STL die, over the die's own triangles: each
//! pressed particle's normal force `f_J = f . n` (N) is spread over the triangles whose
//! centroids lie within `r_J = sqrt(A_J / pi)` of its closest point on the die (the die
//! where it is now; `A_J` its contact area, below), each taking `f_J A_k / sum A_k` by its
//! area `A_k` (m^2), so that a die finer than the particles carries `f_J / A_J` over the
//! particle's own patch rather than all of `f_J` on one small triangle; a pressed particle
//! with no contact area of its own (its surface quarters all edge-on to the die, or a
//! particle off the surface pressed in the flash) takes the mean patch of the tool's other
//! pressed particles, `A_J = A_t / n_t` (`n_t` those with an area), rather than loading one
//! triangle with its whole force; where no centroid lies that near (a die coarser than the
//! particles), the closest point's triangle takes it all. Then `p_k = f_k / A_k`. The field
//! is as fine as the die's triangles: a flat face exported as two triangles carries its mean
//! pressure. On a plane or a cylinder, over the
//! contact patch itself: each pressed particle's surface quarters, each corner moved to its
//! nearest point of the tool's surface ([`crate::solid_tool::SolidTool::nearest_on_surface`]:
//! on a plane its projection, on a cylinder's mantle the radial one), two triangles each,
//! quarter `q` carrying `f_J |a_q . n_J| / A_J` of the particle's force (`n_J` the particle's
//! contact normal, `A_J = sum_q |a_q . n_J|`, its share of the contact area) split over its
//! two triangles by their areas: the particle's pressure `p_J = f_J / A_J` on a flat
//! quarter. On a cylinder the triangles are chords of its curved surface, their area short
//! of the arc's by `(w / R)^2 / 24` for a triangle `w` wide (a fraction of a percent at a
//! spacing under a fifth of the radius). Either way `sum_k p_k A_k = sum_J f_J`, the tool's
//! normal force, to round-off (less the force of a pressed particle with no area on it: one
//! whose quarters all stand edge-on to its normal, which a die pressing a face does not
//! have).

use super::{SolidSimulation, SolidState};
use crate::math::Real;
use crate::solid_tool::Surface;
use crate::stl::{cross, dot, sub};
use std::f64::consts::PI;

/// The contact pressure on a tool over triangles (an STL die's own, or a plane's contact
/// patch), where the tool is now.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DiePressure {
    /// The triangles' vertices (m).
    pub vertices: Vec<[Real; 3]>,
    /// The triangles, indices into `vertices`, wound with their normal out of the tool.
    pub triangles: Vec<[u32; 3]>,
    /// Each triangle's area (m^2).
    pub areas: Vec<Real>,
    /// The normal contact force on each triangle (N).
    pub forces: Vec<Real>,
    /// The contact pressure on each triangle, its force over its area (Pa).
    pub pressure: Vec<Real>,
}

impl DiePressure {
    /// The triangles with no force on them yet.
    fn unloaded(vertices: Vec<[Real; 3]>, triangles: Vec<[u32; 3]>) -> DiePressure {
        let areas: Vec<Real> = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| vertices[v as usize]);
                let n = cross(sub(b, a), sub(c, a));
                0.5 * dot(n, n).sqrt()
            })
            .collect();
        DiePressure {
            vertices,
            triangles,
            forces: vec![0.0; areas.len()],
            pressure: Vec::new(),
            areas,
        }
    }

    /// The pressures from the forces, 0 on a triangle of no area (a quarter edge-on to a
    /// plane).
    fn loaded(mut self) -> DiePressure {
        self.pressure = self
            .forces
            .iter()
            .zip(&self.areas)
            .map(|(f, &a)| if a > 0.0 { f / a } else { 0.0 })
            .collect();
        self
    }
}

impl SolidSimulation {
    /// The area of the workpiece's surface now (m^2), `A_s = sum |a_q|` over the quarters of
    /// its faces (the faces on symmetry planes not among them).
    pub fn surface_area(&self) -> Real {
        self.surface_area_at(&self.positions())
    }

    /// [`SolidSimulation::surface_area`] with the particles at `x` (m, now).
    pub fn surface_area_at(&self, x: &[[Real; 3]]) -> Real {
        self.disc.heat_surface.area(|j| x[j])
    }

    /// The area of the workpiece's surface in contact with scene tool `t` now (m^2), `A_t =
    /// sum |a_q . n_J|` over the particles the last contact stage pressed on it (see the
    /// module doc).
    pub fn contact_area(&self, t: usize) -> Real {
        self.contact_area_at(t, &self.positions())
    }

    /// [`SolidSimulation::contact_area`] with the particles at `x` (m, now).
    pub fn contact_area_at(&self, t: usize, x: &[[Real; 3]]) -> Real {
        pressed_on(&self.st, t)
            .filter_map(|p| {
                self.disc
                    .heat_surface
                    .contact_area(p.particle as usize, &p.normal, |j| x[j])
            })
            .sum()
    }

    /// The contact pressure on scene tool `t` over triangles, an STL die's own or a plane's
    /// or a cylinder's contact patch (see the module doc).
    pub fn die_pressure(&self, t: usize) -> DiePressure {
        let tool = &self.tools()[t];
        let shift: [Real; 3] = tool.axis.map(|a| a * tool.state.stroke);
        let x = self.positions();
        match &tool.surface {
            Surface::Triangles(surface) => {
                let mesh = surface.mesh();
                let vertices = mesh
                    .vertices
                    .iter()
                    .map(|v| std::array::from_fn(|k| v[k] + shift[k]))
                    .collect();
                let mut die = DiePressure::unloaded(vertices, mesh.triangles.clone());
                let patches = &self.disc.heat_surface;
                let areas: Vec<Real> = pressed_on(&self.st, t)
                    .map(|p| {
                        let j = p.particle as usize;
                        patches.contact_area(j, &p.normal, |i| x[i]).unwrap_or(0.0)
                    })
                    .collect();
                let with_area = areas.iter().filter(|&&a| a > 0.0).count();
                let mean_patch = areas.iter().sum::<Real>() / with_area.max(1) as Real;
                for (p, &own) in pressed_on(&self.st, t).zip(&areas) {
                    let j = p.particle as usize;
                    let closest = surface.closest(x[j], shift);
                    let area = if own > 0.0 { own } else { mean_patch };
                    let around = surface.triangles_around(closest.point, (area / PI).sqrt());
                    let total: Real = around.iter().map(|&k| die.areas[k as usize]).sum();
                    if total > 0.0 {
                        for &k in &around {
                            die.forces[k as usize] += p.force_n * die.areas[k as usize] / total;
                        }
                    } else {
                        die.forces[closest.triangle as usize] += p.force_n;
                    }
                }
                die.loaded()
            }
            Surface::Plane { .. } | Surface::Cylinder(_) => {
                // The analytic surface where the tool is now, each corner to its nearest
                // point on it.
                let on_tool = |y: [Real; 3]| tool.nearest_on_surface(y).unwrap_or(y);
                let (mut vertices, mut triangles, mut shares) =
                    (Vec::new(), Vec::new(), Vec::new());
                let surface = &self.disc.heat_surface;
                for p in pressed_on(&self.st, t) {
                    let normal = &p.normal;
                    let quads = surface.quarters_at(p.particle as usize, |i| x[i]);
                    // Each quarter's projected area `|a . n|`, `a = (c - x_0) x (m_next -
                    // m_prev) / 2`, and the particle's, their sum.
                    let projected: Vec<Real> = quads
                        .iter()
                        .map(|q| 0.5 * dot(cross(sub(q[2], q[0]), sub(q[1], q[3])), *normal).abs())
                        .collect();
                    let area: Real = projected.iter().sum();
                    if area <= 0.0 {
                        continue;
                    }
                    for (quad, a) in quads.iter().zip(projected) {
                        let c = quad.map(on_tool);
                        let first = vertices.len() as u32;
                        // Wound with the normal out of the tool.
                        let out = dot(cross(sub(c[1], c[0]), sub(c[2], c[0])), *normal) >= 0.0;
                        let order: [u32; 4] = if out { [0, 1, 2, 3] } else { [0, 3, 2, 1] };
                        vertices.extend(c);
                        triangles.push([order[0], order[1], order[2]].map(|v| first + v));
                        triangles.push([order[0], order[2], order[3]].map(|v| first + v));
                        shares.push(p.force_n * a / area);
                    }
                }
                let mut die = DiePressure::unloaded(vertices, triangles);
                // A quarter's force over its two triangles by their areas.
                for (q, f) in shares.iter().enumerate() {
                    let (a1, a2) = (die.areas[2 * q], die.areas[2 * q + 1]);
                    if a1 + a2 > 0.0 {
                        die.forces[2 * q] = f * a1 / (a1 + a2);
                        die.forces[2 * q + 1] = f * a2 / (a1 + a2);
                    }
                }
                die.loaded()
            }
        }
    }
}

/// The normal forces of the last contact stage on scene tool `t`.
fn pressed_on(st: &SolidState, t: usize) -> impl Iterator<Item = &super::Pressed> {
    st.pressed.iter().filter(move |p| p.tool as usize == t)
}
