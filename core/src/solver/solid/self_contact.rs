//! The 3D workpiece's contact with itself in the contact stage
//! ([`crate::contact::self_contact_3d`]: the surface, the search and the force law) and its
//! laps ([`crate::laps::grow_solid`]).
//!
//! The surface is the heat stage's ([`super::heat::HeatSurface`]: the cells' faces that
//! belong to one cell and lie on no symmetry plane) over the reference configuration of
//! setup. At a stage whose search is due, each surface particle's position and velocity are
//! predicted a natural step `dt` ahead as the tool contact predicts them, `x_J = X_J + sum_I
//! N_I(X_J) (d_I + dt v*_I)` (m), `v_J = sum_I N_I(X_J) v*_I` (m/s); each pair's force on
//! its slave and the reactions on its master face's four particles are spread to the RK
//! coefficients with eq. 7 (`f_I += N_I(X_J) f_J`) into the stage's contact forces, which
//! the corrector applies and the energy account books with the tools' (their work is that
//! of contact, none of a tool's). Between two stages two surface points move at most `2 S
//! du` relative to each other (`S` the largest `sum_I |N_I(X_J)|` of the surface, `du` the
//! tool contact's bound on the change of `d_I + dt v*_I`), which decides whether the search
//! is due.

use super::contact::{flow_stress, interface, predicted};
use super::heat::HeatSurface;
use super::{SolidDisc, SolidState};
use crate::contact::self_contact_3d::{Crossings, SelfContact3, Surface};
use crate::contact::sidibe2009::Interface;
use crate::contact::Forces;
use crate::laps::{self, SolidLap, SolidLapReport};
use crate::math::Real;
use crate::scene::solid::SolidScene;
use crate::solid_tool::SolidTool;
use crate::solver::point_outputs::PointOut;

/// The self-contact of a 3D run and its stage's arrays.
#[derive(Debug, Clone)]
pub(crate) struct SolidSelfContact {
    /// The surface and its search (built also when the scene turns self-contact off, to
    /// measure how far the surface passes through itself).
    search: SelfContact3,
    /// The scene's `self_contact.enabled`.
    enabled: bool,
    /// The symmetry planes `(axis, coordinate)` the body is mirrored on.
    mirrors: Vec<(usize, Real)>,
    /// The surface's predicted positions (m) and velocities (m/s) of the last search.
    x: Vec<[Real; 3]>,
    v: Vec<[Real; 3]>,
}

/// What the 3D self-contact reads of a stage.
pub(super) struct SelfStage<'a> {
    /// The scene's tools (their strokes a natural step ahead, for the laps).
    pub tools: &'a [SolidTool],
    /// The points' outputs (flow stresses for the friction laws that need one).
    pub out: &'a [PointOut],
    /// The tool contact's bound on the change of `d_I + dt v*_I` since the last stage (m).
    pub du: Real,
    /// The natural step and the corrector's (s).
    pub dt: Real,
    pub dt_avg: Real,
}

impl SolidSelfContact {
    /// The self-contact of `scene` on the cells `cells` over the reference positions
    /// `positions` (m) with each particle's cell extents `extents` (m), the symmetry
    /// planes `planes` and the smallest spacing `h_min` (m).
    pub(super) fn new(
        scene: &SolidScene,
        cells: &[[u32; 8]],
        positions: &[[Real; 3]],
        extents: &[[Real; 3]],
        planes: &[(usize, Real)],
        h_min: Real,
    ) -> SolidSelfContact {
        let faces = HeatSurface::new(cells, positions, planes, h_min);
        let (particles, quads) = faces.parts();
        let reference = particles.iter().map(|&j| positions[j as usize]).collect();
        let extents = particles.iter().map(|&j| extents[j as usize]).collect();
        let surface = Surface::new(particles.to_vec(), quads.to_vec(), reference, extents);
        let n = surface.len();
        let search = SelfContact3::new(
            scene.self_contact.friction,
            surface,
            h_min,
            scene.discretization.support,
        );
        SolidSelfContact {
            search,
            enabled: scene.self_contact.enabled,
            mirrors: planes.to_vec(),
            x: vec![[0.0; 3]; n],
            v: vec![[0.0; 3]; n],
        }
    }

    /// Number of surface particles (the length of [`SolidState::self_touching`], whether
    /// the scene's self-contact is on or off: a state saved from either restores on the
    /// other).
    pub(super) fn slots(&self) -> usize {
        self.search.surface.len()
    }

    /// Forgets the last search, so that the next stage searches.
    pub(super) fn forget(&mut self) {
        self.search.forget();
    }

    /// The stage (module doc): the search when due, the pairs' forces into `force` (N),
    /// the laps grown in `st`; whether any force acts. Nothing when the scene turns
    /// self-contact off.
    pub(super) fn stage(
        &mut self,
        disc: &SolidDisc,
        st: &mut SolidState,
        force: &mut Forces<3>,
        at: &SelfStage<'_>,
    ) -> bool {
        if !self.enabled {
            return false;
        }
        let largest = self
            .search
            .surface
            .particles
            .iter()
            .fold(0.0, |m: Real, &j| m.max(disc.sum_abs[j as usize]));
        if !self.search.due(2.0 * largest * at.du) {
            self.search.clear();
            if st.self_touching.contains(&true) {
                st.self_touching.fill(false);
            }
            return false;
        }
        let (d, v, dt) = (&st.d, &st.v, at.dt);
        for (s, &j) in self.search.surface.particles.iter().enumerate() {
            let j = j as usize;
            self.x[s] = predicted(disc, d, v, dt, j);
            self.v[s] = disc.nodal.interpolate(j, v);
        }
        self.search
            .search(&self.x, &self.v, dt, &mut st.self_touching);
        let search = &self.search;
        let pairs = search.pairs();
        if pairs.is_empty() {
            return false;
        }
        let particles = &search.surface.particles;
        let own_law = search.friction.needs_flow_stress();
        for pair in pairs {
            let j = particles[pair.slave as usize] as usize;
            let law = match own_law {
                true => interface(disc, j, flow_stress(disc, at.out, j), pair.normal, |i| {
                    predicted(disc, d, v, dt, i)
                }),
                false => Interface::default(),
            };
            let mass = |s: usize| disc.mass[particles[s] as usize];
            let f = search.pair_force(pair, &self.v, mass, law, dt, at.dt_avg);
            force.spread(&disc.nodal, j, f);
            let face = search.surface.faces[pair.face as usize];
            for (&s, w) in face.iter().zip(pair.weights) {
                force.spread(
                    &disc.nodal,
                    particles[s as usize] as usize,
                    f.map(|c| -w * c),
                );
            }
        }
        let stage = laps::SolidStage {
            surface: &search.surface,
            neighbours: search.neighbours,
            x: &self.x,
            time: st.time + dt,
            strokes: at.tools.iter().map(|t| t.state.stroke).collect(),
        };
        laps::grow_solid(&mut st.laps, pairs, &stage);
        true
    }

    /// The laps of `st` as reported at the particles' positions now `positions` (m).
    pub(super) fn laps(&self, st: &SolidState, positions: &[[Real; 3]]) -> Vec<SolidLapReport> {
        let (surface, x) = (&self.search.surface, self.by_slot(positions));
        st.laps
            .iter()
            .map(|lap: &SolidLap| laps::solid_report(lap, surface, &x))
            .collect()
    }

    /// The deepest a surface particle has passed through another part of the surface at
    /// the particles' positions `positions` (m): `(depth (m), particle)`
    /// ([`Surface::passed_through`]).
    pub(super) fn passed_through(&self, positions: &[[Real; 3]]) -> (Real, usize) {
        let (surface, x) = (&self.search.surface, self.by_slot(positions));
        let (depth, s) = surface.passed_through(&x, &self.mirrors, self.search.neighbours);
        (depth, surface.particles.get(s).map_or(0, |&j| j as usize))
    }

    /// The crossings of the surface's faces within the kernel's support of each other at
    /// the particles' positions `positions` (m), corners within `tolerance` (m) of the other
    /// face let through ([`Surface::fold_crossings`]).
    pub(super) fn fold_crossings(&self, positions: &[[Real; 3]], tolerance: Real) -> Crossings {
        self.search.surface.fold_crossings(
            &self.by_slot(positions),
            tolerance,
            self.search.neighbours,
        )
    }

    /// The surface particles' positions (m) by slot, from every particle's `positions`.
    fn by_slot(&self, positions: &[[Real; 3]]) -> Vec<[Real; 3]> {
        self.search
            .surface
            .particles
            .iter()
            .map(|&j| positions[j as usize])
            .collect()
    }

    /// The cells on either side of a surface particle whose faces its contact leaves out.
    pub(super) fn neighbours(&self) -> usize {
        self.search.neighbours
    }
}
