//! The heat that moves in a 3D workpiece: the 2D heat stage ([`crate::solver::conduction`],
//! generic over the dimension) on the 3D body, when the scene's heat moves
//! ([`SolidScene::transfers_heat`]): lumped thermal masses, total-Lagrangian conduction
//! with the mechanics' shape functions at the integration points, the surface flows to the
//! tools and to the surroundings, sub-cycled explicit steps within the
//! power-iteration stable step, the enthalpy form. What is 3D's is the surface, here.
//!
//! The surface is the faces of the hexahedral cells that belong to one cell only and do
//! not lie on a symmetry plane (a face on one is adiabatic: the mirror image beyond it has
//! the same temperatures). A particle's share of it, in the current configuration, is the
//! quarter of each such face at the particle: the part of the bilinear face between the
//! particle `x_0`, the midpoints `m_1`, `m_2` of its two edges there and the face's centre
//! `c`, with the area vector `a = (c - x_0) x (m_2 - m_1) / 2` (half the cross product of
//! the quarter's diagonals: the vector area of the bilinear patch, its area `|a|` for a
//! flat face and the projected area of a warped one). A particle touches a tool when it
//! lies within [`TOUCH_SPACINGS`] smallest spacings in front of it or behind it (2D's
//! distance; a plane's distance or a triangle surface's signed distance,
//! [`SolidTool::touching`]); its contact area is then `sum |a . n|` over its quarters, `n`
//! the contact normal (a plane's; a triangle surface's at the closest point), the quarters
//! on faces across the tool, such as the sides of a billet on a die, having none; the rest
//! of its share is free surface to the surroundings. The contact stage reads the same
//! contact area for the friction laws that need one ([`HeatSurface::contact_area`]).
use super::{SolidDisc, SolidSimulation, SolidState};
use crate::error::{Error, Result};
use crate::math::{dot, Real};
use crate::scene::solid::{SolidScene, SolidToolSpec};
use crate::solid_tool::SolidTool;
use crate::solver::conduction::{self, Body, Patch, Stage, TOUCH_SPACINGS};
use crate::solver::discretization::Thermal;
use crate::solver::point_outputs::PointOut;
use std::collections::HashMap;

/// The faces of a hexahedral cell (corners 0-3 around the bottom, 4-7 above them), each
/// with its corners in order around it.
const FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

/// The surface heat crosses, fixed at setup (see the module doc); the contact stage reads
/// a particle's contact area on it for the friction laws that need one
/// ([`HeatSurface::contact_area`]).
#[derive(Debug, Clone, Default)]
pub(super) struct HeatSurface {
    /// The particles on its faces, ascending.
    particles: Vec<u32>,
    /// Each face's corners in order around it, as indices into `particles`.
    faces: Vec<[u32; 4]>,
    /// Each particle's index into `particles`, [`OFF_SURFACE`] for a particle not on it.
    slot: Vec<u32>,
    /// The quarters at each surface particle, as (face, corner), those of `particles[s]`
    /// from `first[s]` to `first[s + 1]`.
    quarters: Vec<(u32, u8)>,
    first: Vec<u32>,
}

/// [`HeatSurface::slot`] of a particle not on the surface.
const OFF_SURFACE: u32 = u32::MAX;

/// The area vector of the quarter at corner `q` of the face with corners `c` in order
/// around it (m, m^2): `a = (m - x_q) x (x_{q+1} - x_{q-1}) / 4`, `m` the face's centre
/// (see the module doc).
fn quarter(c: &[[Real; 3]; 4], q: usize) -> [Real; 3] {
    let (x0, next, prev) = (c[q], c[(q + 1) % 4], c[(q + 3) % 4]);
    let centre: [Real; 3] = std::array::from_fn(|k| 0.25 * (c[0][k] + c[1][k] + c[2][k] + c[3][k]));
    // The quarter's diagonals: x_0 to the centre, and m_prev to m_next.
    let diagonal: [Real; 3] = std::array::from_fn(|k| centre[k] - x0[k]);
    let across: [Real; 3] = std::array::from_fn(|k| 0.5 * (next[k] - prev[k]));
    cross(diagonal, across).map(|v| 0.5 * v)
}

impl HeatSurface {
    /// The faces of `cells` over the particles at `positions` (m) that belong to one cell
    /// only and do not lie on a symmetry plane `(axis, coordinate)` of `planes` (every corner
    /// within `1e-9 h_min` of it, `h_min` the smallest spacing, m), in cell order.
    pub(super) fn new(
        cells: &[[u32; 8]],
        positions: &[[Real; 3]],
        planes: &[(usize, Real)],
        h_min: Real,
    ) -> HeatSurface {
        let key = |f: [u32; 4]| {
            let mut k = f;
            k.sort_unstable();
            k
        };
        let faces = || {
            cells
                .iter()
                .flat_map(|c| FACES.iter().map(move |f| f.map(|a| c[a])))
        };
        let mut count: HashMap<[u32; 4], u32> = HashMap::new();
        for f in faces() {
            *count.entry(key(f)).or_default() += 1;
        }
        let on_plane = |f: &[u32; 4]| {
            planes.iter().any(|&(axis, at)| {
                f.iter()
                    .all(|&j| (positions[j as usize][axis] - at).abs() <= 1e-9 * h_min)
            })
        };
        let outer: Vec<[u32; 4]> = faces()
            .filter(|f| count[&key(*f)] == 1 && !on_plane(f))
            .collect();
        let mut particles: Vec<u32> = outer.iter().flatten().copied().collect();
        particles.sort_unstable();
        particles.dedup();
        let slot: HashMap<u32, u32> = particles
            .iter()
            .enumerate()
            .map(|(s, &j)| (j, s as u32))
            .collect();
        let faces: Vec<[u32; 4]> = outer.iter().map(|f| f.map(|j| slot[&j])).collect();
        let mut at: Vec<Vec<(u32, u8)>> = vec![Vec::new(); particles.len()];
        for (f, face) in faces.iter().enumerate() {
            for (q, &s) in face.iter().enumerate() {
                at[s as usize].push((f as u32, q as u8));
            }
        }
        let mut first = vec![0];
        for quarters in &at {
            first.push(first[first.len() - 1] + quarters.len() as u32);
        }
        let mut by_particle = vec![OFF_SURFACE; positions.len()];
        for (s, &j) in particles.iter().enumerate() {
            by_particle[j as usize] = s as u32;
        }
        HeatSurface {
            faces,
            particles,
            slot: by_particle,
            quarters: at.concat(),
            first,
        }
    }

    /// The particles on the surface, ascending.
    pub(super) fn particles(&self) -> &[u32] {
        &self.particles
    }

    /// The quarters at particle `j`, each as its corners `x_0, m_next, c, m_prev` in order
    /// around it (the particle, the middle of the next edge, the face's centre, the middle
    /// of the previous edge; m), the particles at `position(particle)` (m); none off the
    /// surface.
    pub(super) fn quarters_at(
        &self,
        j: usize,
        position: impl Fn(usize) -> [Real; 3],
    ) -> Vec<[[Real; 3]; 4]> {
        let Some(&s) = self.slot.get(j).filter(|&&s| s != OFF_SURFACE) else {
            return Vec::new();
        };
        let s = s as usize;
        self.quarters[self.first[s] as usize..self.first[s + 1] as usize]
            .iter()
            .map(|&(f, q)| {
                let c =
                    self.faces[f as usize].map(|s| position(self.particles[s as usize] as usize));
                let q = q as usize;
                let mid = |a: [Real; 3], b: [Real; 3]| std::array::from_fn(|k| 0.5 * (a[k] + b[k]));
                let centre =
                    std::array::from_fn(|k| 0.25 * (c[0][k] + c[1][k] + c[2][k] + c[3][k]));
                [
                    c[q],
                    mid(c[q], c[(q + 1) % 4]),
                    centre,
                    mid(c[q], c[(q + 3) % 4]),
                ]
            })
            .collect()
    }

    /// The surface's area (m^2), `sum |a|` over every quarter, the corners at
    /// `position(particle)` (m).
    pub(super) fn area(&self, position: impl Fn(usize) -> [Real; 3]) -> Real {
        self.faces
            .iter()
            .map(|face| {
                let c = face.map(|s| position(self.particles[s as usize] as usize));
                (0..4)
                    .map(|q| {
                        let a = quarter(&c, q);
                        dot(&a, &a).sqrt()
                    })
                    .sum::<Real>()
            })
            .sum()
    }

    /// The particles on its faces (ascending) and each face's corners in order around it,
    /// outward by the right-hand rule, as indices into the particles.
    pub(super) fn parts(&self) -> (&[u32], &[[u32; 4]]) {
        (&self.particles, &self.faces)
    }

    /// The contact area (m^2) of particle `j` on a tool surface with unit normal `n`, the
    /// corners at `position(particle)` (m): `A_J = sum |a . n|` over its quarters (the
    /// area of its share of the surface projected on the tool's tangent plane, as the
    /// heat stage's contact area), `None` for a particle not on the surface.
    pub(super) fn contact_area(
        &self,
        j: usize,
        n: &[Real; 3],
        position: impl Fn(usize) -> [Real; 3],
    ) -> Option<Real> {
        let s = *self.slot.get(j).filter(|&&s| s != OFF_SURFACE)? as usize;
        let quarters = &self.quarters[self.first[s] as usize..self.first[s + 1] as usize];
        Some(quarters.iter().fold(0.0, |area, &(f, q)| {
            let c = self.faces[f as usize].map(|s| position(self.particles[s as usize] as usize));
            area + dot(&quarter(&c, q as usize), n).abs()
        }))
    }

    /// Each surface particle's [`Patch`] at the displacement coefficients `d` (m): its
    /// quarters' areas (m^2), the scene tool among `tools` it touches and its contact area
    /// on it (m^2).
    fn patches(&self, disc: &SolidDisc, tools: &[SolidTool], d: &[[Real; 3]]) -> Vec<Patch> {
        let touch = TOUCH_SPACINGS * disc.h_min;
        let x: Vec<[Real; 3]> = self
            .particles
            .iter()
            .map(|&j| {
                let j = j as usize;
                let u = disc.nodal.interpolate(j, d);
                std::array::from_fn(|k| disc.ref_pos[j][k] + u[k])
            })
            .collect();
        let touched: Vec<Option<(usize, [Real; 3])>> = x
            .iter()
            .map(|&x| {
                tools
                    .iter()
                    .enumerate()
                    .find_map(|(t, tool)| tool.touching(x, touch).map(|n| (t, n)))
            })
            .collect();
        let (mut area, mut contact) = (vec![0.0; x.len()], vec![0.0; x.len()]);
        for face in &self.faces {
            let c = face.map(|s| x[s as usize]);
            for (q, &s) in face.iter().enumerate() {
                let a = quarter(&c, q);
                let s = s as usize;
                area[s] += dot(&a, &a).sqrt();
                if let Some((_, n)) = touched[s] {
                    contact[s] += dot(&a, &n).abs();
                }
            }
        }
        (0..x.len())
            .map(|s| Patch {
                j: self.particles[s] as usize,
                area: area[s],
                contact: contact[s],
                tool: touched[s].map(|(t, _)| t),
            })
            .collect()
    }
}

/// `a x b`.
fn cross(a: [Real; 3], b: [Real; 3]) -> [Real; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// A two-colouring of the particles of `cells` (`np` particles) along the cells' edges
/// (the checkerboard of a lattice; the O-grid's quadrilateral sections colour alike), by
/// breadth-first search from the lowest particle of each connected part: the start of
/// conduction's power iteration, the shortest wave the grid carries.
pub(super) fn checkerboard(cells: &[[u32; 8]], np: usize) -> Vec<bool> {
    let mut next: Vec<Vec<u32>> = vec![Vec::new(); np];
    for c in cells {
        for (a, b) in super::setup::HEX_EDGES {
            next[c[a] as usize].push(c[b]);
            next[c[b] as usize].push(c[a]);
        }
    }
    let mut colour: Vec<Option<bool>> = vec![None; np];
    let mut queue = std::collections::VecDeque::new();
    for start in 0..np {
        if colour[start].is_some() {
            continue;
        }
        colour[start] = Some(true);
        queue.push_back(start);
        while let Some(j) = queue.pop_front() {
            let here = colour[j] == Some(true);
            for &k in &next[j] {
                if colour[k as usize].is_none() {
                    colour[k as usize] = Some(!here);
                    queue.push_back(k as usize);
                }
            }
        }
    }
    colour.into_iter().map(|c| c == Some(true)).collect()
}

impl SolidDisc {
    /// What the heat stage reads of the 3D body.
    pub(super) fn heat_body(&self) -> Body<'_, 3> {
        Body {
            weights: &self.weights,
            reference_jacobian: &self.reference_jacobian,
            hoop: None,
            scatter: &self.scatter,
            nodal: &self.nodal,
            particles: &self.ref_pos,
            point_positions: &self.point_positions,
            critical_dt0: self.critical_dt0,
            hardening: &self.material.hardening,
        }
    }
}

/// Conduction's largest eigenvalue on the undeformed body (1/s,
/// [`conduction::eigenvalue`] from the cells' [`checkerboard`]), stored in the heat
/// settings of a scene whose heat moves.
pub(super) fn update_eigenvalue(disc: &mut SolidDisc) -> Result<()> {
    let lambda = match disc.thermal.as_ref() {
        Some(
            th @ Thermal {
                transfer: Some(_), ..
            },
        ) => {
            let colour = checkerboard(&disc.cells, disc.ref_pos.len());
            conduction::eigenvalue(&disc.heat_body(), th, |j| colour[j], 0, 0.0)?
        }
        _ => return Ok(()),
    };
    if let Some(transfer) = disc.thermal.as_mut().and_then(|th| th.transfer.as_mut()) {
        transfer.lambda0 = lambda;
    }
    Ok(())
}

/// The heat stage of the 3D step after a step of `dt` (s), when due
/// ([`conduction::due`]): the 2D stage's ([`Stage::run`]) on the 3D body with its
/// surface's patches, against the scene tools of `planes` (the symmetry planes follow
/// them), updating the points' flow stresses in `out`.
pub(super) fn stage_if_due(
    scene: &SolidScene,
    disc: &SolidDisc,
    planes: &[SolidTool],
    st: &mut SolidState,
    out: &mut [PointOut],
    dt: Real,
) -> Result<()> {
    let (Some(thermal), Some(heat)) = (&disc.thermal, &mut st.heat) else {
        return Ok(());
    };
    let Some(transfer) = &thermal.transfer else {
        return Ok(());
    };
    let Some(elapsed) = conduction::due(heat, dt) else {
        return Ok(());
    };
    let d = &st.d;
    let tools = &planes[..disc.scene_tools];
    let stage = Stage {
        body: disc.heat_body(),
        thermal,
        tools: scene
            .tools
            .iter()
            .map(SolidToolSpec::heat_contact)
            .collect(),
        surface: || disc.heat_surface.patches(disc, tools, d),
        lambda0: transfer.lambda0,
        d,
        points: &st.points,
        step: st.step,
        time: st.time,
        stable_dt: st.stable_dt,
    };
    stage.run(heat, out, elapsed)
}

impl SolidSimulation {
    /// Sets the temperature field of a scene whose heat moves before its first step, in
    /// place of the scene's uniform `thermal.initial_temperature_c`: each particle at
    /// `field(X_I)` (degrees C, `X_I` its reference position, m) and each point at the field
    /// the particles give it, `sum_I N_I(X_p) T_I` (in enthalpy with a capacity table), as
    /// after a heat stage. The heat content and its balance stay measured from
    /// `thermal.initial_temperature_c`, so they then hold the field's initial heat too.
    ///
    /// # Errors
    ///
    /// The scene's heat does not move (no particle temperatures), or steps were taken.
    pub fn set_temperature(&mut self, field: impl Fn([Real; 3]) -> Real) -> Result<()> {
        let (disc, st) = (&self.disc, &mut self.st);
        let (Some(th), Some(heat)) = (disc.thermal.as_ref(), st.heat.as_mut()) else {
            return Err(Error::Request(
                "a temperature field needs a scene with [thermal]".into(),
            ));
        };
        if heat.particle_c.is_empty() || st.step > 0 {
            return Err(Error::Request(
                "a temperature field is set before the first step of a scene whose heat moves (thermal conductivity, convection, emissivity or a tool's heat transfer)".into(),
            ));
        }
        heat.particle_c = disc.ref_pos.iter().map(|&x| field(x)).collect();
        heat.temperature_c =
            conduction::at_points(&disc.heat_body(), &th.capacity, &heat.particle_c);
        for (p, (out, point)) in self.ws.out.iter_mut().zip(&st.points).enumerate() {
            *out = PointOut::at(&disc.material, point.eps_p, Some(heat.temperature_c[p]));
        }
        Ok(())
    }
}
