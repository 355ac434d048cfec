//! The contact stage of a step: the paper's penalty contact (Sidibe et al. 2009, section
//! II-3, eqs. 4-7; the force laws are in [`crate::tools`]) applied to the predicted
//! boundary particles of the workpiece.
//!
//! For each boundary particle `J` the predicted physical position and velocity are
//! interpolated from the RK coefficients, `x_J = X_J + sum_I N_I(X_J) (d_I + dt v*_I)` (m)
//! and `v_J = sum_I N_I(X_J) v*_I` (m/s); a particle behind a tool segment gets the penalty
//! force of eqs. 4-6 (N), spread to the coefficients with eq. 7, `f_I += N_I(X_J) f_J`, and
//! the tool takes the reaction. Particles that cannot have reached a tool's search box are
//! skipped ([`Contact`]), with the bits of evaluating every one.
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
//! reference position, and the area of its tributary boundary, half of each boundary
//! segment to its ring neighbours at their predicted positions, projected on the tool's
//! tangent (times the depth in plane strain, times `2 pi r` at each half segment's middle in
//! axisymmetry, so a particle on the axis has the disc `pi (l / 2)^2`).

use crate::geometry::{bounds_of, Extents};
use crate::material::{Hardening, PointState};
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::scene::Kinematics;
use crate::team::{part, particle_phase, Parts, Team};
use crate::tools::{penalty_force, Interface, Slave, SlaveForce, Tool};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Boundary particles handled by one task of the contact stage's interpolation.
const BOUNDARY_BLOCK: usize = 32;

/// The workpiece as the contact stage reads it.
pub struct Body<'a> {
    /// Boundary particles, counter-clockwise.
    pub boundary: &'a [u32],
    /// `N_I(X_J)` in row `J` (no gradients needed).
    pub nodal: &'a ShapeTable,
    /// Reference particle positions `X_J` (m).
    pub reference: &'a [[Real; 2]],
    /// Lumped masses `m_J` (kg), the slave masses of eqs. 4 and 6.
    pub mass: &'a [Real],
    /// RK coefficients of the displacement at `t_n` (m).
    pub d: &'a [[Real; 2]],
    /// Predicted coefficient velocities `v*` (m/s).
    pub v: &'a [[Real; 2]],
    /// Particle spacings (m).
    pub spacing: [Real; 2],
    /// Integration point histories (the flow stress of the shear friction factor).
    pub points: &'a [PointState],
    /// The hardening law giving the flow stress.
    pub hardening: &'a Hardening,
    /// Plane strain (areas per `depth_m`) or axisymmetry (areas of whole rings).
    pub kinematics: Kinematics,
    /// Depth of a plane-strain model (m).
    pub depth_m: Real,
}

impl Body<'_> {
    /// Predicted position `x_J = X_J + sum_I N_I(X_J) (d_I + dt v*_I)` (m) and velocity
    /// `v_J = sum_I N_I(X_J) v*_I` (m/s) of particle `j`.
    fn predicted(&self, j: usize, dt: Real) -> [[Real; 2]; 2] {
        let (d, v, nodal) = (self.d, self.v, self.nodal);
        let (mut x, mut vj) = (self.reference[j], [0.0; 2]);
        for e in nodal.row(j) {
            let i = nodal.index[e] as usize;
            let n = nodal.n[e];
            x[0] += n * (d[i][0] + dt * v[i][0]);
            x[1] += n * (d[i][1] + dt * v[i][1]);
            vj[0] += n * v[i][0];
            vj[1] += n * v[i][1];
        }
        [x, vj]
    }
}

/// What the contact stage keeps for each boundary particle `k` on each tool `t` from step to
/// step, at index `k * tools + t` (part of the saved state).
pub struct Pairs<'a> {
    /// Whether the particle is held on the tool (a tool without separation; empty when
    /// every tool separates): a particle that penetrates such a tool is held from then on.
    pub held: &'a mut [bool],
    /// The particle's friction state while it stays in contact with a tool that has
    /// friction.
    pub stick: &'a mut [Option<Stick>],
}

/// A boundary particle's friction on a tool, kept from one step to the next.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stick {
    /// The part of the last step's friction force that the corrector did not realise on
    /// the particle (N; [`Contact::carry`]), added to this step's stick force
    /// ([`crate::tools::penalty_force`]).
    pub carried: [Real; 2],
}

/// A particle-tool pair with friction that was in contact in the last contact stage.
#[derive(Debug, Clone, Copy)]
struct Touched {
    /// Index `k * tools + t` of boundary particle `k` on tool `t`.
    pair: u32,
    /// Contact normal (-).
    normal: [Real; 2],
    /// Friction force on the particle (N).
    friction: [Real; 2],
}

/// The contact forces of the last step, and what the stage keeps from step to step to skip
/// boundary particles that cannot reach a tool. None of the latter is state: dropping it
/// ([`Contact::forget`], as a restore does) only makes the next step evaluate every
/// boundary particle.
#[derive(Debug, Clone, Default)]
pub struct Contact {
    /// Contact force on each RK coefficient (N), eq. 7; zero where no particle touches.
    pub force: Vec<[Real; 2]>,
    /// `dt V*` of the last two predictors (m), `V*` the largest velocity component of a
    /// particle after the predictor and `dt` the step the contact stage interpolates with.
    predicted_moves: [Real; 2],
    /// `dt V` of the last update (m), `V` the largest velocity component at the half step.
    update_move: Real,
    /// `S_J = sum_I |N_I(X_J)|` of each boundary particle. Between two contact stages
    /// `u_I = d_I + dt v*_I` changes by `dt_n v_{n+1/2} + dt_{n+1} v*_{n+1} - dt_n v*_n`,
    /// at most `du = update_move + predicted_moves[0] + predicted_moves[1]` per component,
    /// so `x_J = X_J + sum_I N_I(X_J) u_I` moves at most `S_J du` per component.
    sum_abs: Vec<Real>,
    /// Lower bound on the distance (largest component) from each boundary particle to
    /// every tool's search box (m); positive means the particle cannot be in one.
    pub(crate) clearance: Vec<Real>,
    /// Predicted position (m) and velocity (m/s) of each boundary particle evaluated this
    /// step.
    motion: Vec<[[Real; 2]; 2]>,
    /// The tools' search boxes at the last step.
    boxes: Vec<Extents>,
    /// Skip the particles with a positive clearance (false only in the test that compares
    /// against evaluating all of them).
    pub(crate) skip: bool,
    /// The integration point nearest to each boundary particle's reference position (only
    /// when a tool's friction law needs the flow stress).
    nearest_point: Vec<u32>,
    /// The pairs with friction in contact at this step, for [`Contact::carry`].
    touched: Vec<Touched>,
}

impl Contact {
    /// The stage for a workpiece whose `boundary` particles have the rows of `nodal`, with
    /// reference particle positions `reference` (m) and integration points at `points` (m);
    /// `flow_stress` when a tool's friction law needs it. Every particle is evaluated at the
    /// first step.
    pub fn new(
        boundary: &[u32],
        nodal: &ShapeTable,
        reference: &[[Real; 2]],
        points: &[[Real; 2]],
        flow_stress: bool,
    ) -> Contact {
        let nearest_point = if flow_stress {
            boundary
                .iter()
                .map(|&j| {
                    let x = reference[j as usize];
                    let d2 = |p: &[Real; 2]| (p[0] - x[0]).powi(2) + (p[1] - x[1]).powi(2);
                    (0..points.len())
                        .min_by(|&a, &b| d2(&points[a]).total_cmp(&d2(&points[b])))
                        .unwrap_or(0) as u32
                })
                .collect()
        } else {
            Vec::new()
        };
        let particles = reference.len();
        Contact {
            nearest_point,
            force: vec![[0.0; 2]; particles],
            sum_abs: boundary
                .iter()
                .map(|&j| nodal.row(j as usize).map(|e| nodal.n[e].abs()).sum())
                .collect(),
            clearance: vec![0.0; boundary.len()],
            motion: vec![[[0.0; 2]; 2]; boundary.len()],
            skip: true,
            ..Default::default()
        }
    }

    /// Forgets the clearances and the last step's search boxes, so that the next contact
    /// stage evaluates every boundary particle (after the displacements were set from
    /// outside).
    pub fn forget(&mut self) {
        self.clearance.fill(0.0);
        self.boxes.clear();
        self.update_move = Real::INFINITY;
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

    /// Contact of the predicted boundary positions with `tools` at `t_{n+1}` (paper eqs.
    /// 4-7). The positions are predicted over the solver's natural step `dt` (s; equal to
    /// the actual step except when a step is shortened to land on a requested time), where
    /// the tools must be too, and the penalty stiffness `m_s / dt^2` uses it, so a short step
    /// never turns a residual penetration into a huge impulse; `dt_avg` (s) is the
    /// corrector's step. A boundary particle is interpolated only when it may be in a tool's
    /// search box: its clearance to the boxes, measured when last interpolated, shrinks each
    /// step by `S_J du + box_move` and while it stays positive the particle is skipped.
    /// `pairs` holds what each boundary particle keeps on each tool from step to step.
    /// Fills [`Contact::force`] and each tool's force (N); returns whether any force acts and
    /// the work the tools' motion delivered, `sum dt_avg f_J . v_tool` (J).
    pub fn stage(
        &mut self,
        team: &Team,
        tools: &mut [Tool],
        body: &Body<'_>,
        pairs: Pairs<'_>,
        dt: Real,
        dt_avg: Real,
    ) -> (bool, Real) {
        for t in tools.iter_mut() {
            t.state.force = [0.0; 2];
        }
        if tools.is_empty() {
            return (false, 0.0);
        }
        let mut tool_work = 0.0;
        self.force.iter_mut().for_each(|f| *f = [0.0; 2]);
        let bounds: Vec<Extents> = tools
            .iter()
            .map(|t| bounds_of(&t.vertices(), t.depth))
            .collect();
        // How far any search box moved since the last step (a first step: unbounded).
        let box_move = if self.boxes.len() == bounds.len() {
            bounds
                .iter()
                .zip(&self.boxes)
                .flat_map(|(a, b)| {
                    [
                        a.x[0] - b.x[0],
                        a.x[1] - b.x[1],
                        a.y[0] - b.y[0],
                        a.y[1] - b.y[1],
                    ]
                })
                .fold(0.0, |m: Real, e| m.max(e.abs()))
        } else {
            Real::INFINITY
        };
        // Predicted positions x_J = X_J + sum_I N_I(X_J) u_I, u_I = d_I + dt v*_I, and
        // velocities v_J = sum_I N_I(X_J) v*_I of the boundary particles that may be in a
        // search box: a particle's clearance to the boxes shrinks each step by at most
        // S_J du + box_move, and while it stays positive the particle is skipped (it could
        // not have touched a tool: the bits are those of evaluating every particle).
        let Body {
            boundary,
            nodal,
            reference,
            mass,
            spacing,
            ..
        } = *body;
        let (np, nb) = (reference.len(), boundary.len());
        let du = self.update_move + self.predicted_moves[0] + self.predicted_moves[1];
        let (skip, sum_abs) = (self.skip, &self.sum_abs);
        let margin = 1e-9 * spacing[0].min(spacing[1]);
        let (motion_parts, clearance_parts) = (
            Parts::new(&mut self.motion),
            Parts::new(&mut self.clearance),
        );
        particle_phase(team, np, nb.div_ceil(BOUNDARY_BLOCK), &|b| {
            let range = part(b, BOUNDARY_BLOCK, nb);
            // SAFETY: block `b` alone takes these boundary particles.
            let (out, clear) = unsafe {
                (
                    motion_parts.get(range.clone()),
                    clearance_parts.get(range.clone()),
                )
            };
            for (k, (m, c)) in range.zip(out.iter_mut().zip(clear.iter_mut())) {
                *c -= sum_abs[k] * du + box_move;
                if skip && *c > 0.0 {
                    continue;
                }
                *m = body.predicted(boundary[k] as usize, dt);
                let x = m[0];
                let gap = bounds.iter().fold(Real::INFINITY, |g, b| {
                    let dx = (b.x[0] - x[0]).max(x[0] - b.x[1]);
                    let dy = (b.y[0] - x[1]).max(x[1] - b.y[1]);
                    g.min(dx.max(dy))
                });
                *c = gap - margin;
            }
        });
        let mut any = false;
        let ntools = tools.len();
        let Pairs { held, stick } = pairs;
        self.touched.clear();
        for (k, ((&j, &[x, vj]), &c)) in boundary
            .iter()
            .zip(&self.motion)
            .zip(&self.clearance)
            .enumerate()
        {
            let stick = &mut stick[k * ntools..(k + 1) * ntools];
            if self.skip && c > 0.0 {
                stick.fill(None);
                continue;
            }
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
                    m: mass[j],
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
                tool_work += dt_avg * (f[0] * vt[0] + f[1] * vt[1]);
                for e in nodal.row(j) {
                    let i = nodal.index[e] as usize;
                    let n = nodal.n[e];
                    self.force[i][0] += n * f[0];
                    self.force[i][1] += n * f[1];
                }
                any = true;
            }
        }
        for t in tools.iter_mut() {
            let f = t.state.force;
            t.state.peak_force = t.state.peak_force.max((f[0] * f[0] + f[1] * f[1]).sqrt());
        }
        self.boxes = bounds;
        (any, tool_work)
    }

    /// After the corrector: what the friction force `f_T` of each pair in contact did not
    /// realise on its particle, carried to the next step's stick force
    /// ([`crate::tools::penalty_force`]) as `c = f_T + m_J P_T (v*_J - v_J) / dt_avg` (N),
    /// with `v*_J` the particle's predicted velocity the force was computed from,
    /// `v_J = sum_I N_I(X_J) v_I` its velocity after the corrector and the essential
    /// conditions (m/s; `v` the coefficient velocities), `P_T` the projection on the tool's
    /// tangent and `dt_avg` the corrector's step (s). With interpolating shape functions the
    /// corrector changes `v_J` by `f dt_avg / m_J` and nothing is carried; eq. 7 spreads
    /// `f` over coefficients that other particles share, which realises less on `J`.
    /// `stick` is indexed as [`Pairs::stick`].
    pub fn carry(
        &self,
        boundary: &[u32],
        nodal: &ShapeTable,
        mass: &[Real],
        v: &[[Real; 2]],
        stick: &mut [Option<Stick>],
        dt_avg: Real,
    ) {
        let tools = stick.len() / boundary.len().max(1);
        for touched in &self.touched {
            let k = touched.pair as usize / tools;
            let j = boundary[k] as usize;
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
        }
    }

    /// Flow stress and contact area of boundary particle `k` at its predicted position `x`
    /// (m) on a tool surface with normal `normal` ([`Interface`]; see the module doc).
    fn interface(
        &self,
        body: &Body<'_>,
        k: usize,
        x: [Real; 2],
        normal: [Real; 2],
        dt: Real,
    ) -> Interface {
        let nb = body.boundary.len();
        let tangent = [-normal[1], normal[0]];
        let mut area = 0.0;
        for other in [(k + nb - 1) % nb, (k + 1) % nb] {
            let y = body.predicted(body.boundary[other] as usize, dt)[0];
            let mid = [0.5 * (x[0] + y[0]), 0.5 * (x[1] + y[1])];
            let length = ((mid[0] - x[0]) * tangent[0] + (mid[1] - x[1]) * tangent[1]).abs();
            area += match body.kinematics {
                Kinematics::PlaneStrain => length * body.depth_m,
                Kinematics::Axisymmetric => PI * length * (x[0] + mid[0]).max(0.0),
            };
        }
        let eps_p = body.points[self.nearest_point[k] as usize].eps_p;
        Interface {
            flow_stress: body.hardening.flow_stress(eps_p),
            area,
        }
    }
}
