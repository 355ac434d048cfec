//! The contact stage of a step: the paper's penalty contact (Sidibe et al. 2009, section
//! II-3, eqs. 4-7; the force law is [`sidibe2009`]) applied to every particle of the
//! workpiece that can reach a tool or a symmetry plane ([`crate::contact::symmetry`]), then the
//! tools' convex corners against the workpiece's surface ([`crate::contact::corners`], the second
//! pass of a two-pass node-to-segment method), then the workpiece's surface against itself
//! ([`crate::contact::self_contact`]).
//!
//! Every particle is a contact candidate, not only those that started on the boundary:
//! material that flows around a die corner brings particles from the inside to the surface
//! (and a Lagrangian kernel stretches the boundary ring open there). Candidates are ordered
//! boundary ring first (counter-clockwise), then the inside particles by index.
//!
//! For each candidate `J` the predicted physical position and velocity are interpolated
//! from the RK coefficients, `x_J = X_J + sum_I N_I(X_J) (d_I + dt v*_I)` (m) and
//! `v_J = sum_I N_I(X_J) v*_I` (m/s); a particle behind a tool segment gets the penalty
//! force of eqs. 4-6 (N), spread to the coefficients with eq. 7, `f_I += N_I(X_J) f_J`, and
//! the tool takes the reaction. The boundary ring is interpolated at every step when a tool
//! has convex corners or fill points (the corner pass and the die fill need the whole
//! surface) and when the self-contact search is due; any other particle only while it may
//! reach a tool or a symmetry plane: its clearance ([`Contact`]) bounds its distance to
//! every tool's polyline and every plane, so skipping it gives the bits of evaluating it.
//!
//! A tool without separation holds every particle that has penetrated it: from then on the
//! particle's signed gap is taken on either side of the surface, so the normal force pulls a
//! particle that moved off back onto it. Like the paper's push, the pull acts on the
//! particle's physical position `x_J` (RK shape functions do not interpolate: the
//! coefficients `d_I` alone say nothing about where the particle is) and is spread with
//! eq. 7.
//!
//! The shear friction factor needs each slave's flow stress and contact area
//! ([`Interface`]): the flow stress of the integration point nearest to the particle's
//! reference position, and the area of its tributary boundary: for a boundary ring particle
//! half of each boundary segment to its ring neighbours at their predicted positions,
//! projected on the tool's tangent; for an inside particle that reached a tool, one
//! reference spacing `sqrt(h_x h_y)`; times the depth in plane strain, times `2 pi r` in
//! axisymmetry (at each half segment's middle for a ring particle, so a particle on the
//! axis has the disc `pi (l / 2)^2`).

pub mod corners;
pub(crate) mod move_bound;
pub(crate) mod penalty_feedback;
pub mod self_contact;
pub mod self_contact_3d;
pub mod sidibe2009;
pub mod symmetry;
pub mod workpiece;

pub use workpiece::{Body, Pairs, Stick};

use crate::contact::penalty_feedback::Feedback;
use crate::contact::self_contact::{pair_force, Due, Pair, Ring, SelfContact};
use crate::contact::sidibe2009::{penalty_force, Interface, Slave, SlaveForce};
use crate::contact::symmetry::SymmetryPlane;
use crate::friction::Friction;
use crate::geometry::{bounds_of, Extents};
use crate::math::{dot, Real};
use crate::rk_shape::ShapeTable;
use crate::scene::Kinematics;
use crate::team::{part, particle_phase, Parts, Team};
use crate::tools::{Penetration, Tool, SEARCH_DEPTH_SPACINGS};
use std::f64::consts::PI;

/// Candidates handled by one task of the contact stage's interpolation.
const CANDIDATE_BLOCK: usize = 32;

/// What [`Contact::carry`] needs to book the friction work of a thermal scene.
pub struct Slip<'a> {
    /// The tools, at their velocity over the step.
    pub tools: &'a [Tool],
    /// Friction work of each particle since the heat stage last took it (J).
    pub work: &'a mut [Real],
}

/// The friction work of a particle-tool pair over a step (J): the friction force `f_T` (N)
/// on the particle against the slip the corrector realised, `W = max(0, -f_T . P_T v_rel)
/// dt_avg`, with `v_rel = v_J - v_tool` the particle's velocity relative to the tool after
/// the corrector (m/s), `P_T = I - n n` the projection on the tool's tangent (`normal` `n`)
/// and `dt_avg` the corrector's step (s); none while the particle sticks. Coulomb friction
/// `|f_T| = mu f_N` sliding at `s` books `mu f_N s dt_avg` (the friction law: Sidibe et al.
/// 2009, eqs. 5-6). One source for the 2D tools and the 3D planes (`D` = 2, 3); summed from the first
/// component on ([`dot`]), so 2D keeps its bits.
pub(crate) fn slip_work<const D: usize>(
    friction: &[Real; D],
    v_rel: [Real; D],
    normal: &[Real; D],
    dt_avg: Real,
) -> Real {
    let rn = dot(&v_rel, normal);
    let slide: [Real; D] = std::array::from_fn(|k| v_rel[k] - rn * normal[k]);
    (-dot(friction, &slide)).max(0.0) * dt_avg
}

/// A particle-tool pair with friction that was in contact in the last contact stage.
#[derive(Debug, Clone, Copy)]
struct Touched {
    /// Index `k * tools + t` of candidate `k` on tool `t`.
    pair: u32,
    /// Contact normal (-).
    normal: [Real; 2],
    /// Friction force on the particle (N).
    friction: [Real; 2],
}

/// The contact forces of the last step, and what the stage keeps from step to step to skip
/// particles that cannot reach a tool or a symmetry plane and self-contact searches that
/// cannot find anything. None of the latter is state: dropping it ([`Contact::forget`], as
/// a restore does) only makes the next step evaluate every particle and search.
#[derive(Debug, Clone, Default)]
pub struct Contact {
    /// Contact force on each RK coefficient (N), eq. 7, with the list of the coefficients
    /// it reached: zero elsewhere.
    pub force: Forces,
    /// The contact candidates: the boundary ring (counter-clockwise), then every other
    /// particle by index.
    candidates: Vec<u32>,
    /// Length of the boundary ring, the first candidates.
    ring: usize,
    /// `dt V*` of the last two predictors (m), `V*` the largest velocity component of a
    /// particle after the predictor and `dt` the step the contact stage interpolates with.
    predicted_moves: [Real; 2],
    /// `dt V` of the last update (m), `V` the largest velocity component at the half step.
    update_move: Real,
    /// `S_J = sum_I |N_I(X_J)|` of each candidate. Between two contact stages
    /// `u_I = d_I + dt v*_I` changes by `dt_n v_{n+1/2} + dt_{n+1} v*_{n+1} - dt_n v*_n`,
    /// at most `du = update_move + predicted_moves[0] + predicted_moves[1]` per component,
    /// so `x_J = X_J + sum_I N_I(X_J) u_I` moves at most `S_J du` per component (and
    /// `sqrt 2 S_J du` in distance).
    sum_abs: Vec<Real>,
    /// Lower bound on how far each candidate must move before a tool's contact search can
    /// find it ([`Tool::clearance`]) or a symmetry plane can act on it (m): positive means
    /// no contact force can act on it. A ring particle evaluated with the whole ring has
    /// none (minus infinity), so it is evaluated again when the ring is not.
    pub(crate) clearance: Vec<Real>,
    /// Predicted position (m) and velocity (m/s) of each candidate evaluated this step.
    motion: Vec<[[Real; 2]; 2]>,
    /// The tools' strokes at the last step (m).
    strokes: Vec<Real>,
    /// Skip the inside particles with a positive clearance (false only in the test that
    /// compares against evaluating all of them).
    pub(crate) skip: bool,
    /// The penalty feedback of each tool without separation and each symmetry plane (after
    /// the tools) over the particles it holds ([`Feedback`]).
    pub(crate) feedback: Feedback,
    /// The integration point nearest to each candidate's reference position (only when a
    /// tool's friction law needs the flow stress).
    nearest_point: Vec<u32>,
    /// The pairs with friction in contact at this step, for [`Contact::carry`].
    touched: Vec<Touched>,
    /// The candidates this stage interpolated, ascending: the ring when it is needed
    /// whole, and every other candidate whose clearance ran out.
    evaluated: Vec<u32>,
    /// The candidates the last stage found within reach of a tool or a plane, ascending:
    /// the only ones that can hold a friction state ([`Stick`]).
    in_reach: Vec<u32>,
    /// The pairs with a contact force this step ([`Contact::near`]).
    near: Vec<Near>,
    /// The workpiece's surface against itself, unless the scene turns it off.
    self_contact: Option<SelfContact>,
    /// Whether the last stage searched for self-contact.
    searched: bool,
    /// The largest `S_J` of the ring's particles: between two stages two points of the
    /// ring's segments move at most `2 S du` relative to each other.
    ring_sum_abs: Real,
    /// The ring's predicted positions (m) and velocities (m/s) the last self-contact search
    /// read: all of them after a full search, those it needed after a local one.
    ring_positions: Vec<[Real; 2]>,
    ring_velocities: Vec<[Real; 2]>,
}

/// What a particle touched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Surface {
    /// The tool with this index.
    Tool(usize),
    /// The symmetry plane with this index.
    Plane(usize),
}

/// A candidate that took a contact force from a tool or a symmetry plane in the last stage.
#[derive(Debug, Clone, Copy)]
struct Near {
    /// The candidate.
    k: u32,
    /// What it touched.
    surface: Surface,
    /// Its predicted gap (m).
    gap: Real,
}

/// What a contact stage did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Touch {
    /// Some contact force acts (tools, symmetry planes or the surface on itself).
    pub any: bool,
    /// A tool touches the workpiece.
    pub tools: bool,
    /// The work the tools' motion delivered, `sum dt_avg f_J . v_tool` (J).
    pub tool_work: Real,
    /// The largest penalty feedback of a holding tool or plane this stage measured (-, 0
    /// when it measured none; [`penalty_feedback`]).
    pub feedback: Real,
}

/// The frictionless law of the symmetry planes.
const FRICTIONLESS: Friction = Friction::Coulomb { mu: 0.0 };

impl Contact {
    /// The stage for a workpiece whose particles have the rows of `nodal`, with the
    /// counter-clockwise `boundary` ring, reference particle positions `reference` (m) and
    /// integration points at `points` (m); `flow_stress` when a friction law needs it; the
    /// self-contact search unless the scene turns it off. Every particle is evaluated and
    /// the self-contact searched at the first step.
    pub fn new(
        boundary: &[u32],
        nodal: &ShapeTable,
        reference: &[[Real; 2]],
        points: &[[Real; 2]],
        flow_stress: bool,
        self_contact: Option<SelfContact>,
    ) -> Contact {
        let particles = reference.len();
        let mut on_ring = vec![false; particles];
        for &j in boundary {
            on_ring[j as usize] = true;
        }
        let candidates: Vec<u32> = boundary
            .iter()
            .copied()
            .chain((0..particles as u32).filter(|&j| !on_ring[j as usize]))
            .collect();
        let nearest_point = if flow_stress {
            nearest_points(&candidates, reference, points)
        } else {
            Vec::new()
        };
        let sum_abs: Vec<Real> = candidates
            .iter()
            .map(|&j| nodal.row(j as usize).map(|e| nodal.n[e].abs()).sum())
            .collect();
        Contact {
            nearest_point,
            force: Forces::new(particles),
            ring_sum_abs: sum_abs[..boundary.len()]
                .iter()
                .copied()
                .fold(0.0, Real::max),
            sum_abs,
            self_contact,
            clearance: vec![0.0; candidates.len()],
            motion: vec![[[0.0; 2]; 2]; candidates.len()],
            ring: boundary.len(),
            candidates,
            skip: true,
            ..Default::default()
        }
    }

    /// Number of contact candidates (every particle): the pairs of [`Pairs`] are
    /// `candidates * tools`.
    pub fn candidate_count(&self) -> usize {
        self.candidates.len()
    }

    /// Every particle that took a contact force from a tool or a symmetry plane in the last
    /// stage, with what it touched, its predicted position (m) and its predicted gap (m).
    pub fn near(&self) -> impl Iterator<Item = (usize, Surface, [Real; 2], Real)> + '_ {
        self.near.iter().map(|n| {
            let k = n.k as usize;
            let x = self.motion[k][0];
            (self.candidates[k] as usize, n.surface, x, n.gap)
        })
    }

    /// The self-contacts of the last stage (empty when it did not search), and the ring's
    /// predicted positions they refer to (m, by ring index; those of the pairs' particles are
    /// this stage's).
    pub fn self_pairs(&self) -> (&[Pair], &[[Real; 2]]) {
        match (&self.self_contact, self.searched) {
            (Some(s), true) => (s.pairs(), &self.ring_positions),
            _ => (&[], &[]),
        }
    }

    /// The workpiece's surface against itself, unless the scene turns it off.
    pub fn self_contact(&self) -> Option<&SelfContact> {
        self.self_contact.as_ref()
    }

    /// The boundary ring's particles with their positions as the last stage predicted them
    /// (m; a natural step ahead of the step's start): all fresh when a tool has fill points
    /// or convex corners, which is when the stage interpolates the whole ring.
    pub fn ring_predicted(&self) -> impl Iterator<Item = (usize, [Real; 2])> + '_ {
        self.candidates[..self.ring]
            .iter()
            .zip(&self.motion)
            .map(|(&j, m)| (j as usize, m[0]))
    }

    /// Forgets the clearances and the last step's strokes, so that the next contact stage
    /// evaluates every particle (after the displacements were set from outside).
    pub fn forget(&mut self) {
        self.clearance.fill(0.0);
        self.feedback.forget();
        self.strokes.clear();
        self.update_move = Real::INFINITY;
        if let Some(s) = &mut self.self_contact {
            s.forget();
        }
    }

    /// Records the predictor's move bound `dt V*` (m): `dt` the natural step, `V*` the
    /// largest predicted velocity component.
    pub fn predicted_move(&mut self, bound: Real) {
        self.predicted_moves = [self.predicted_moves[1], bound];
    }

    /// Records the update's move bound `dt V` (m): `V` the largest velocity component at
    /// the half step.
    pub fn updated_move(&mut self, bound: Real) {
        self.update_move = bound;
    }

    /// Contact of the predicted particle positions with `tools` and the symmetry `planes` at
    /// `t_{n+1}` (paper eqs. 4-7), then of the tools' convex corners with the predicted
    /// surface ([`crate::contact::corners`]), then of the surface with itself
    /// ([`crate::contact::self_contact`]). The positions are predicted over the solver's natural
    /// step `dt` (s; equal to the actual step except when a step is shortened to land on a
    /// requested time), where the tools must be too, and the penalty stiffness `m_s / dt^2`
    /// uses it, so a short step never turns a residual penetration into a huge impulse;
    /// `dt_avg` (s) is the corrector's step. The boundary ring is interpolated at every step
    /// when a tool has convex corners or fill points, and when the self-contact search is
    /// due; any other particle only when it may reach a tool or a plane: its clearance,
    /// measured when last interpolated, shrinks each step by `sqrt 2 S_J du + tool_move`
    /// and while it stays positive the particle is skipped: a skipped particle costs that
    /// subtraction, as the stage lists the candidates it interpolates and walks only those
    /// (and the last stage's in reach, to drop their friction states). `pairs` holds what each
    /// candidate keeps on each tool and plane from step to step. Fills [`Contact::force`]
    /// and each tool's force (N).
    #[allow(clippy::too_many_arguments)]
    pub fn stage(
        &mut self,
        team: &Team,
        tools: &mut [Tool],
        planes: &[SymmetryPlane],
        body: &Body<'_>,
        pairs: Pairs<'_>,
        dt: Real,
        dt_avg: Real,
    ) -> Touch {
        for t in tools.iter_mut() {
            t.state.force = [0.0; 2];
            t.state.normal_force = 0.0;
        }
        self.near.clear();
        self.searched = false;
        if let Some(s) = &mut self.self_contact {
            s.clear();
        }
        if tools.is_empty() && planes.is_empty() && self.self_contact.is_none() {
            return Touch::default();
        }
        let mut touch = Touch::default();
        self.force.clear();
        let bounds: Vec<Extents> = tools
            .iter()
            .map(|t| bounds_of(&t.vertices(), t.depth))
            .collect();
        // How far any tool moved since the last step (a first step: unbounded).
        let tool_move = if self.strokes.len() == tools.len() {
            tools
                .iter()
                .zip(&self.strokes)
                .fold(0.0, |m: Real, (t, s)| m.max((t.state.stroke - s).abs()))
        } else {
            Real::INFINITY
        };
        // Predicted positions x_J = X_J + sum_I N_I(X_J) u_I, u_I = d_I + dt v*_I, and
        // velocities v_J = sum_I N_I(X_J) v*_I of the ring and of the inside particles that
        // may be within the search depth of a tool or reach a plane: a particle's clearance
        // shrinks each step by at most sqrt 2 S_J du + tool_move, and while it stays
        // positive the particle is skipped (it could not have touched anything: the bits
        // are those of evaluating every particle).
        let Body {
            nodal,
            reference,
            mass,
            spacing,
            ..
        } = *body;
        let (np, ring) = (reference.len(), self.ring);
        let du = std::f64::consts::SQRT_2
            * (self.update_move + self.predicted_moves[0] + self.predicted_moves[1]);
        // What the self-contact has to do: two points of the surface move at most 2 S du
        // relative to each other between stages.
        let moved = 2.0 * self.ring_sum_abs * du;
        let due = match &mut self.self_contact {
            Some(s) => s.due(moved),
            None => Due::Nothing,
        };
        let search = due == Due::Full;
        // The whole ring is needed at every step when a tool has convex corners (the corner
        // pass) or fill points ([`Contact::ring_predicted`]), and for a self-contact
        // search; otherwise it is skipped like the inside particles.
        let whole_ring = search
            || tools
                .iter()
                .any(|t| !t.convex.is_empty() || t.fill_points > 0);
        let always = if whole_ring { ring } else { 0 };
        let (skip, sum_abs, candidates) = (self.skip, &self.sum_abs, &self.candidates);
        let margin = 1e-9 * spacing[0].min(spacing[1]);
        let plane_depth = SEARCH_DEPTH_SPACINGS * spacing[0].max(spacing[1]);
        let tools_now: &[Tool] = tools;
        let (ntools, nplanes) = (tools.len(), planes.len());
        let held_now: &[bool] = pairs.held;
        let plane_held_now: &[bool] = pairs.plane_held;
        // The clearances shrink by the move bound; the ring when needed whole and every
        // particle whose clearance ran out are evaluated (ascending).
        self.evaluated.clear();
        self.evaluated.extend(0..always as u32);
        for (k, (c, s)) in self.clearance[always..]
            .iter_mut()
            .zip(&sum_abs[always..])
            .enumerate()
        {
            *c -= s * du + tool_move;
            if !(skip && *c > 0.0) {
                self.evaluated.push((always + k) as u32);
            }
        }
        let evaluated = &self.evaluated;
        let (motion_parts, clearance_parts) = (
            Parts::new(&mut self.motion),
            Parts::new(&mut self.clearance),
        );
        particle_phase(team, np, evaluated.len().div_ceil(CANDIDATE_BLOCK), &|b| {
            for &k in &evaluated[part(b, CANDIDATE_BLOCK, evaluated.len())] {
                let k = k as usize;
                // SAFETY: candidate `k` appears once in `evaluated`, in one block.
                let (m, c) = unsafe {
                    (
                        &mut motion_parts.get(k..k + 1)[0],
                        &mut clearance_parts.get(k..k + 1)[0],
                    )
                };
                *m = body.predicted(candidates[k] as usize, dt);
                if k < always {
                    *c = Real::NEG_INFINITY;
                    continue;
                }
                let x = m[0];
                let j = candidates[k] as usize;
                let to_tools = tools_now
                    .iter()
                    .enumerate()
                    .map(|(t, tool)| {
                        let held = held_now.get(k * ntools + t).copied().unwrap_or(false);
                        tool.clearance(x, held)
                    })
                    .fold(Real::INFINITY, Real::min);
                let to_planes = planes
                    .iter()
                    .enumerate()
                    .filter(|(_, plane)| !plane.exact[j])
                    .map(|(p, plane)| match plane_held_now[k * nplanes + p] {
                        true => -plane.beyond(x) - plane_depth,
                        false => -plane.beyond(x),
                    })
                    .fold(Real::INFINITY, Real::min);
                *c = to_tools.min(to_planes) - margin;
            }
        });
        let Pairs {
            held,
            plane_held,
            self_touching,
            stick,
            pressure,
            stations,
            impulse,
        } = pairs;
        let candidates = &self.candidates;
        let holding = |flags: &[bool], count: usize, t: usize| -> Vec<usize> {
            let mut set: Vec<usize> = (0..candidates.len())
                .filter(|&k| flags.get(k * count + t).copied().unwrap_or(false))
                .map(|k| candidates[k] as usize)
                .collect();
            set.sort_unstable();
            set
        };
        let measured = self.feedback.update(
            ntools + nplanes,
            nodal,
            mass,
            |t| t >= ntools || !tools[t].separation,
            |t| match t < ntools {
                true => holding(held, ntools, t),
                false => holding(plane_held, nplanes, t - ntools),
            },
        );
        touch.feedback = measured;
        pressure.fill(0.0);
        self.touched.clear();
        // Friction states live only on the candidates the last stage kept in reach: those
        // out of reach now drop theirs (written only when there is one to drop).
        let drop_stick = |stick: &mut [Option<Stick>], k: usize| {
            let stick = &mut stick[k * ntools..(k + 1) * ntools];
            if stick.iter().any(Option::is_some) {
                stick.fill(None);
            }
        };
        let in_reach = |k: usize| {
            let c = self.clearance[k];
            k < always || !self.skip || c <= 0.0 || c.is_nan()
        };
        let mut now = self.evaluated.iter().map(|&k| k as usize).peekable();
        for &k in &self.in_reach {
            let k = k as usize;
            while now.next_if(|&e| e < k).is_some() {}
            if now.peek() != Some(&k) {
                drop_stick(stick, k);
            }
        }
        let mut kept = std::mem::take(&mut self.in_reach);
        kept.clear();
        for &k in &self.evaluated {
            let k = k as usize;
            if !in_reach(k) {
                drop_stick(stick, k);
                continue;
            }
            kept.push(k as u32);
            let (j, [x, vj]) = (self.candidates[k], self.motion[k]);
            let stick = &mut stick[k * ntools..(k + 1) * ntools];
            let j = j as usize;
            for (t, tool) in tools.iter_mut().enumerate() {
                let b = &bounds[t];
                if x[0] < b.x[0] || x[0] > b.x[1] || x[1] < b.y[0] || x[1] > b.y[1] {
                    stick[t] = None;
                    continue;
                }
                let hold = (!tool.separation).then(|| &mut held[k * ntools + t]);
                let below = match &hold {
                    Some(h) if **h => -tool.depth,
                    _ => 0.0,
                };
                let Some(pen) = tool.gap_above(x, below) else {
                    stick[t] = None;
                    continue;
                };
                if let Some(h) = hold {
                    self.feedback.took_hold(t, *h);
                    *h = true;
                }
                let vt = [
                    tool.axis[0] * tool.state.velocity,
                    tool.axis[1] * tool.state.velocity,
                ];
                let at = if tool.friction.needs_flow_stress() {
                    self.interface(body, k, x, pen.normal, dt)
                } else {
                    Interface::default()
                };
                let carried = match stick[t] {
                    Some(Stick { carried }) => carried,
                    None => [0.0; 2],
                };
                let slave = Slave {
                    m: mass[j] * self.feedback.scale(t),
                    v_rel: [vj[0] - vt[0], vj[1] - vt[1]],
                    carried,
                };
                let SlaveForce { force: f, friction } =
                    penalty_force(slave, pen, &tool.friction, at, dt, dt_avg);
                if tool.friction.is_frictionless() {
                    stick[t] = None;
                } else {
                    self.touched.push(Touched {
                        pair: (k * ntools + t) as u32,
                        normal: pen.normal,
                        friction,
                    });
                }
                tool.state.force[0] -= f[0];
                tool.state.force[1] -= f[1];
                let normal = f[0] * pen.normal[0] + f[1] * pen.normal[1];
                tool.state.normal_force += normal;
                if stations > 0 {
                    // The normal part of the penalty force, at the station of the closest
                    // point of the tool's polyline.
                    let s = tool.station(x, stations);
                    pressure[t * stations + s] += normal;
                }
                if let Some(i) = impulse.get_mut(j) {
                    *i += normal.abs() * dt_avg;
                }
                touch.tool_work += dt_avg * (f[0] * vt[0] + f[1] * vt[1]);
                self.force.spread(nodal, j, f);
                self.near.push(Near {
                    k: k as u32,
                    surface: Surface::Tool(t),
                    gap: pen.gap,
                });
                touch.tools = true;
            }
            // The symmetry planes: frictionless, holding a particle once it reached one
            // (`crate::contact::symmetry`); the particles the essential conditions hold are theirs.
            for (p, plane) in planes.iter().enumerate() {
                if plane.exact[j] {
                    continue;
                }
                let hold = &mut plane_held[k * nplanes + p];
                let gap = plane.beyond(x);
                let below = if *hold { -plane_depth } else { 0.0 };
                if gap <= below || gap == 0.0 {
                    continue;
                }
                self.feedback.took_hold(ntools + p, *hold);
                *hold = true;
                let slave = Slave {
                    m: mass[j] * self.feedback.scale(ntools + p),
                    v_rel: vj,
                    carried: [0.0; 2],
                };
                let pen = Penetration {
                    gap,
                    normal: plane.normal(),
                };
                let f = penalty_force(slave, pen, &FRICTIONLESS, Interface::default(), dt, dt_avg)
                    .force;
                self.force.spread(nodal, j, f);
                self.near.push(Near {
                    k: k as u32,
                    surface: Surface::Plane(p),
                    gap,
                });
                touch.any = true;
            }
        }
        self.in_reach = kept;
        touch.any |= touch.tools;
        let corners = tools.iter().any(|t| !t.convex.is_empty());
        // The ring as the particle pass leaves it: each predicted position moved by the
        // corrector's displacement of the forces so far, `dt dt_avg sum_I N_I(X_J) f_I / m_I`
        // (m), so that a corner over a particle the particle pass already pushes out of the
        // tool is not pushed against a second time (which would overshoot: the interface
        // would generate energy).
        let positions: Vec<[Real; 2]> = match corners {
            true => self.motion[..ring]
                .iter()
                .zip(&self.candidates[..ring])
                .map(|(m, &j)| {
                    let mut x = m[0];
                    for e in nodal.row(j as usize) {
                        let i = nodal.index[e] as usize;
                        let w = nodal.n[e] * dt * dt_avg / mass[i];
                        x[0] += w * self.force.at[i][0];
                        x[1] += w * self.force.at[i][1];
                    }
                    x
                })
                .collect(),
            false => Vec::new(),
        };
        let surface = corners::Surface {
            ring: &self.candidates[..ring],
            positions: &positions,
            mass,
        };
        for tool in tools.iter_mut().filter(|_| corners) {
            for corner in corners::inside(tool, &surface) {
                let f = corners::penalty(&corner, &surface, dt, dt_avg);
                let vt = [
                    tool.axis[0] * tool.state.velocity,
                    tool.axis[1] * tool.state.velocity,
                ];
                for (k, w) in [
                    (corner.segment, 1.0 - corner.along),
                    ((corner.segment + 1) % ring, corner.along),
                ] {
                    let fk = [w * f[0], w * f[1]];
                    let j = self.candidates[k] as usize;
                    self.force.spread(nodal, j, fk);
                    if let Some(i) = impulse.get_mut(j) {
                        *i += w * f[0].hypot(f[1]) * dt_avg;
                    }
                    touch.tool_work += dt_avg * (fk[0] * vt[0] + fk[1] * vt[1]);
                }
                tool.state.force[0] -= f[0];
                tool.state.force[1] -= f[1];
                // The corner pass is frictionless: its force lies along the surface's normal.
                tool.state.normal_force += f[0].hypot(f[1]);
                touch.tools = true;
                touch.any = true;
            }
        }
        match due {
            Due::Full | Due::Local => {
                touch.any |= self.self_stage(due, whole_ring, body, self_touching, dt, dt_avg);
            }
            Due::Nothing => {
                if self_touching.contains(&true) {
                    // No slave within the search depth of a candidate: no contact goes on.
                    self_touching.fill(false);
                }
            }
        }
        for t in tools.iter_mut() {
            let f = t.state.force;
            t.state.peak_force = t.state.peak_force.max((f[0] * f[0] + f[1] * f[1]).sqrt());
        }
        self.strokes.clear();
        self.strokes.extend(tools.iter().map(|t| t.state.stroke));
        self.force.reached.sort_unstable();
        touch
    }

    /// The self-contact search on the predicted ring, `due` full or local, and its forces
    /// ([`crate::contact::self_contact`]), `touching` the ring particles in contact at the last stage,
    /// updated: each pair's force on its slave, its reaction on the master point shared by
    /// the segment's two particles, each spread with eq. 7; whether any acts. A full search
    /// reads the ring the stage interpolated whole; a local one reads it too when the stage
    /// interpolated it (`whole_ring`), else interpolates the particles it reads.
    fn self_stage(
        &mut self,
        due: Due,
        whole_ring: bool,
        body: &Body<'_>,
        touching: &mut [bool],
        dt: Real,
        dt_avg: Real,
    ) -> bool {
        let ring = self.ring;
        let Some(mut search) = self.self_contact.take() else {
            return false;
        };
        self.searched = true;
        self.ring_positions.resize(ring, [0.0; 2]);
        self.ring_velocities.resize(ring, [0.0; 2]);
        if due == Due::Full {
            for (k, m) in self.motion[..ring].iter().enumerate() {
                [self.ring_positions[k], self.ring_velocities[k]] = *m;
            }
            search.full_search(&self.ring_positions, &self.ring_velocities, dt, touching);
        } else {
            let (particles, motion) = (&self.candidates[..ring], &self.motion[..ring]);
            search.local_search(
                |k| match whole_ring {
                    true => motion[k],
                    false => body.predicted(particles[k] as usize, dt),
                },
                &mut self.ring_positions,
                &mut self.ring_velocities,
                dt,
                touching,
            );
        }
        let velocities = std::mem::take(&mut self.ring_velocities);
        let any = self.self_forces(&search, &velocities, body, dt, dt_avg);
        self.ring_velocities = velocities;
        self.self_contact = Some(search);
        any
    }

    /// The forces of the self-contact pairs `search` found, at the ring's predicted
    /// velocities `velocities` (m/s); whether any acts.
    fn self_forces(
        &mut self,
        search: &SelfContact,
        velocities: &[[Real; 2]],
        body: &Body<'_>,
        dt: Real,
        dt_avg: Real,
    ) -> bool {
        let ring = self.ring;
        let (pairs, law) = (search.pairs(), search.friction);
        if pairs.is_empty() {
            return false;
        }
        let particles = &self.candidates[..ring];
        let surface = Ring {
            x: &self.ring_positions,
            v: velocities,
            particles,
            mass: body.mass,
        };
        let forces: Vec<(usize, [Real; 2])> = pairs
            .iter()
            .map(|pair| {
                let k = pair.slave as usize;
                let at = if law.needs_flow_stress() {
                    self.interface(body, k, self.ring_positions[k], pair.normal, dt)
                } else {
                    Interface::default()
                };
                (k, pair_force(pair, &surface, &law, at, dt, dt_avg))
            })
            .collect();
        for (pair, (k, f)) in pairs.iter().zip(forces) {
            let (a, t) = (pair.segment as usize, pair.along);
            let b = (a + 1) % ring;
            self.force.spread(body.nodal, particles[k] as usize, f);
            for (i, w) in [(a, 1.0 - t), (b, t)] {
                self.force
                    .spread(body.nodal, particles[i] as usize, [-w * f[0], -w * f[1]]);
            }
        }
        true
    }

    /// After the corrector: what the friction force `f_T` of each pair in contact did not
    /// realise on its particle, carried to the next step's stick force
    /// ([`crate::contact::sidibe2009::penalty_force`]) as `c = f_T + m_J P_T (v*_J - v_J) / dt_avg` (N),
    /// with `v*_J` the particle's predicted velocity the force was computed from,
    /// `v_J = sum_I N_I(X_J) v_I` its velocity after the corrector and the essential
    /// conditions (m/s; `v` the coefficient velocities), `P_T` the projection on the tool's
    /// tangent and `dt_avg` the corrector's step (s). With interpolating shape functions the
    /// corrector changes `v_J` by `f dt_avg / m_J` and nothing is carried; eq. 7 spreads
    /// `f` over coefficients that other particles share, which realises less on `J`.
    /// `stick` is indexed as [`Pairs::stick`].
    pub fn carry(
        &self,
        nodal: &ShapeTable,
        mass: &[Real],
        v: &[[Real; 2]],
        stick: &mut [Option<Stick>],
        dt_avg: Real,
        mut slip: Option<Slip<'_>>,
    ) {
        let tools = stick.len() / self.candidates.len().max(1);
        for touched in &self.touched {
            let k = touched.pair as usize / tools;
            let j = self.candidates[k] as usize;
            let mut vj = [0.0; 2];
            for e in nodal.row(j) {
                let i = nodal.index[e] as usize;
                vj[0] += nodal.n[e] * v[i][0];
                vj[1] += nodal.n[e] * v[i][1];
            }
            let predicted = self.motion[k][1];
            let dv = [predicted[0] - vj[0], predicted[1] - vj[1]];
            let n = touched.normal;
            let dn = dv[0] * n[0] + dv[1] * n[1];
            let c = mass[j] / dt_avg;
            let f = touched.friction;
            stick[touched.pair as usize] = Some(Stick {
                carried: [
                    f[0] + c * (dv[0] - dn * n[0]),
                    f[1] + c * (dv[1] - dn * n[1]),
                ],
            });
            if let Some(slip) = slip.as_mut() {
                let tool = &slip.tools[touched.pair as usize % tools];
                let vt = [
                    tool.axis[0] * tool.state.velocity,
                    tool.axis[1] * tool.state.velocity,
                ];
                let rel = [vj[0] - vt[0], vj[1] - vt[1]];
                slip.work[j] += slip_work(&f, rel, &n, dt_avg);
            }
        }
    }

    /// Flow stress and contact area of candidate `k` at its predicted position `x` (m) on a
    /// tool surface with normal `normal` ([`Interface`]; see the module doc).
    fn interface(
        &self,
        body: &Body<'_>,
        k: usize,
        x: [Real; 2],
        normal: [Real; 2],
        dt: Real,
    ) -> Interface {
        let nb = self.ring;
        let tangent = [-normal[1], normal[0]];
        let mut area = 0.0;
        if k < nb {
            for other in [(k + nb - 1) % nb, (k + 1) % nb] {
                let y = body.predicted(self.candidates[other] as usize, dt)[0];
                let mid = [0.5 * (x[0] + y[0]), 0.5 * (x[1] + y[1])];
                let length = ((mid[0] - x[0]) * tangent[0] + (mid[1] - x[1]) * tangent[1]).abs();
                area += match body.kinematics {
                    Kinematics::PlaneStrain => length * body.depth_m,
                    Kinematics::Axisymmetric => PI * length * (x[0] + mid[0]).max(0.0),
                };
            }
        } else {
            let length = (body.spacing[0] * body.spacing[1]).sqrt();
            area = match body.kinematics {
                Kinematics::PlaneStrain => length * body.depth_m,
                Kinematics::Axisymmetric => 2.0 * PI * length * x[0].max(0.0),
            };
        }
        let p = self.nearest_point[k] as usize;
        let eps_p = body.points[p].eps_p;
        let flow_stress = match body.temperature {
            Some(t) if body.hardening.is_thermal() => body.hardening.flow(eps_p, 0.0, t[p]).stress,
            _ => body.hardening.flow_stress(eps_p),
        };
        Interface { flow_stress, area }
    }
}

/// The contact forces on the RK coefficients (N), eq. 7, of `D` components (2 by default),
/// and the coefficients they reached: a stage clears and corrects only those, not every
/// particle.
#[derive(Debug, Clone, Default)]
pub struct Forces<const D: usize = 2> {
    /// Contact force on each coefficient (N); zero where no particle's force reached it.
    pub at: Vec<[Real; D]>,
    /// The coefficients a force reached in the last stage, ascending once it ended.
    reached: Vec<u32>,
    /// Whether each coefficient is in `reached`.
    marked: Vec<bool>,
}

impl<const D: usize> Forces<D> {
    /// No force on any of `particles` coefficients.
    pub(crate) fn new(particles: usize) -> Forces<D> {
        Forces {
            at: vec![[0.0; D]; particles],
            reached: Vec::new(),
            marked: vec![false; particles],
        }
    }

    /// Zero again the coefficients the last stage reached.
    pub(crate) fn clear(&mut self) {
        for &i in &self.reached {
            self.at[i as usize] = [0.0; D];
            self.marked[i as usize] = false;
        }
        self.reached.clear();
    }

    /// Eq. 7: spreads particle `j`'s contact force `f` (N) to the coefficients,
    /// `f_I += N_I(X_J) f_J` over `j`'s row of `nodal`.
    pub(crate) fn spread(&mut self, nodal: &ShapeTable<D>, j: usize, f: [Real; D]) {
        for e in nodal.row(j) {
            let i = nodal.index[e] as usize;
            let n = nodal.n[e];
            for (a, f) in self.at[i].iter_mut().zip(f) {
                *a += n * f;
            }
            if !self.marked[i] {
                self.marked[i] = true;
                self.reached.push(i as u32);
            }
        }
    }

    /// The coefficients a contact force reached in the last stage, ascending: every other
    /// coefficient's force is zero.
    pub fn reached(&self) -> &[u32] {
        &self.reached
    }
}

/// The integration point nearest to each particle of `particles` (reference positions
/// `reference`, m) among the points at `points` (m), the first of equals by index; points
/// are binned at the largest spacing of their cloud, so each particle looks at a few bins.
fn nearest_points(particles: &[u32], reference: &[[Real; 2]], points: &[[Real; 2]]) -> Vec<u32> {
    let b = bounds_of(points, 0.0);
    let span = [b.x[1] - b.x[0], b.y[1] - b.y[0]];
    let size =
        (span[0].max(span[1]) / (points.len() as Real).sqrt().max(1.0)).max(Real::MIN_POSITIVE);
    let dims = [0, 1].map(|c| (span[c] / size).floor() as usize + 1);
    let cell = |x: [Real; 2]| {
        [
            ((x[0] - b.x[0]) / size)
                .floor()
                .clamp(0.0, (dims[0] - 1) as Real) as usize,
            ((x[1] - b.y[0]) / size)
                .floor()
                .clamp(0.0, (dims[1] - 1) as Real) as usize,
        ]
    };
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); dims[0] * dims[1]];
    for (p, x) in points.iter().enumerate() {
        let [i, j] = cell(*x);
        bins[j * dims[0] + i].push(p as u32);
    }
    particles
        .iter()
        .map(|&j| {
            let x = reference[j as usize];
            let d2 = |p: u32| {
                let q = points[p as usize];
                (q[0] - x[0]).powi(2) + (q[1] - x[1]).powi(2)
            };
            let [ci, cj] = cell(x);
            // Widen the ring of bins until it holds a point and every bin that could hold
            // a nearer one has been seen.
            let mut best: Option<(Real, u32)> = None;
            for r in 0..dims[0].max(dims[1]) {
                for bj in cj.saturating_sub(r)..=(cj + r).min(dims[1] - 1) {
                    for bi in ci.saturating_sub(r)..=(ci + r).min(dims[0] - 1) {
                        if bi.abs_diff(ci).max(bj.abs_diff(cj)) != r {
                            continue;
                        }
                        for &p in &bins[bj * dims[0] + bi] {
                            let d = d2(p);
                            if best.is_none_or(|(bd, bp)| d < bd || (d == bd && p < bp)) {
                                best = Some((d, p));
                            }
                        }
                    }
                }
                if let Some((d, _)) = best {
                    if d.sqrt() <= r as Real * size {
                        break;
                    }
                }
            }
            best.map_or(0, |(_, p)| p)
        })
        .collect()
}
