//! The contact stage of the 3D solver: the paper's penalty contact (Sidibe et al. 2009,
//! section II-3, eqs. 4-7, the force law [`penalty_force`] shared with 2D) of every
//! particle against the tools and the symmetry planes ([`SolidTool`]: planes, analytic
//! cylinders and closed triangle surfaces from STL files, one law for all).
//!
//! For each particle `J` that may reach a tool, the predicted physical position and
//! velocity are interpolated from the RK coefficients, `x_J = X_J + sum_I N_I(X_J) (d_I +
//! dt v*_I)` (m) and `v_J = sum_I N_I(X_J) v*_I` (m/s); a particle inside a tool by the gap
//! `g` (m: behind a plane, or `-phi` of a cylinder's or a triangle surface's signed
//! distance) gets the penalty force `m_J g / dt^2` along the contact normal `n` (the
//! plane's; the cylinder's nearest feature's; the face's, or from the closest edge or vertex
//! point to `x_J`) plus the friction of eqs. 5-6 (the tool's
//! law, [`crate::friction`]: Coulomb, or the shear friction factor and capped laws with the
//! particle's flow stress and contact area, [`interface`], as in 2D), spread to
//! the coefficients by eq. 7 (`f_I += N_I(X_J) f_J`); the tool takes the reaction. A tool
//! without separation (the FE wall, a symmetry plane) holds a particle once it reached it:
//! its gap is then taken on either side. After the corrector, the friction force the
//! corrector did not realise on the particle is carried to the next step's stick force, as
//! in 2D, in the tangent plane of the normal it was computed with ([`ToolContact::carry`]),
//! and in a scene with `[thermal]` its work against the slip booked at the particle for the
//! heat stage, as in 2D.
//!
//! Skipping: between two stages `x_J` moves at most `S_J M_c` (`S_J = sum_I |N_I(X_J)|`,
//! `M_c` the largest change of `d_I + dt v*_I` over the coefficients near the particle,
//! [`MoveBound`]) and a tool at most its stroke change; a particle whose distance to every
//! tool (its clearance, a triangle surface's lower bound from its bins when no triangle
//! lies within the search depth, [`SolidTool::clearance`]) stays positive after those moves
//! cannot touch one, and is not interpolated.
//!
//! Then the second pass (`ridges.rs`, for the STL dies with `ridges = true`): the tools'
//! convex edges and vertices against the workpiece's surface facets between the particles.

use super::ridges::{ParticlePass, RidgePass};
use super::{Pressed, SolidDisc, SolidState};
use crate::contact::move_bound::MoveBound;
use crate::contact::penalty_feedback::Feedback;
use crate::contact::sidibe2009::{penalty_force, Interface, Slave, SlaveForce};
use crate::contact::{slip_work, Forces};
use crate::math::{dot, Real};
use crate::solid_tool::SolidTool;
use crate::solver::point_outputs::PointOut;
use crate::solver::stable_step::StepLength;
use crate::team::{part, particle_phase, Parts, Team};

/// Particles interpolated by one task of the stage.
const BLOCK: usize = 64;

/// The predicted physical position of particle `j` a step `dt` (s) ahead, `x_J = X_J +
/// sum_I N_I(X_J) (d_I + dt v_I)` (m), from the coefficients `d` (m) and `v` (m/s).
pub(super) fn predicted(
    disc: &SolidDisc,
    d: &[[Real; 3]],
    v: &[[Real; 3]],
    dt: Real,
    j: usize,
) -> [Real; 3] {
    let mut x = disc.ref_pos[j];
    for e in disc.nodal.row(j) {
        let (i, n) = (disc.nodal.index[e] as usize, disc.nodal.n[e]);
        for k in 0..3 {
            x[k] += n * (d[i][k] + dt * v[i][k]);
        }
    }
    x
}

/// What the shear and capped friction laws read of particle `j` on a tool with contact
/// normal `n` ([`Interface`], 2D's `crate::contact::Contact::interface` in 3D): its flow
/// stress `flow` (Pa: the static flow stress `sigma_y(eps_p, T)` of the points smoothed to
/// the particle, the `|N_I(x_p)| w_p`-weighted mean of [`flow_stress`]) and its contact
/// area (m^2): on the body's surface the projection of its quarters on the tool's tangent
/// plane at the predicted positions `position(i)` (m), `A_J = sum |a . n|`
/// ([`super::heat::HeatSurface::contact_area`], the heat stage's contact area); a
/// particle off the surface `V_J^(2/3)` (`V_J` its volume, m^3), as 2D gives one the area
/// of its spacing. The bound is then `m sigma_y A_J / sqrt 3` ([`crate::friction`];
/// Wanheim and Bay 1978).
pub(super) fn interface(
    disc: &SolidDisc,
    j: usize,
    flow: Real,
    n: [Real; 3],
    position: impl Fn(usize) -> [Real; 3],
) -> Interface {
    let area = disc
        .heat_surface
        .contact_area(j, &n, position)
        .unwrap_or_else(|| disc.volumes[j].powf(2.0 / 3.0));
    Interface {
        flow_stress: flow,
        area,
    }
}

/// Particle `j`'s flow stress (Pa): the points' in `out` smoothed to it, the
/// `|N_J(x_p)| w_p`-weighted mean ([`crate::solver::fields::Smoothing`]).
pub(super) fn flow_stress(disc: &SolidDisc, out: &[PointOut], j: usize) -> Real {
    disc.flow_smoothing.at(j, |p| out[p].flow_stress)
}

/// A particle-plane pair with friction in contact at the last stage.
#[derive(Debug, Clone, Copy)]
struct Touched {
    /// Particle `j`.
    j: u32,
    /// Tool or plane `t`.
    t: u32,
    /// The friction force on the particle (N).
    friction: [Real; 3],
    /// The contact normal (out of the tool).
    normal: [Real; 3],
}

/// What the contact stage keeps between steps to skip particles, and its forces.
#[derive(Debug, Clone)]
pub(crate) struct ToolContact {
    /// Contact force on each RK coefficient (N), eq. 7.
    pub force: Forces<3>,
    /// Lower bound on how far each particle must move before a plane can act on it (m).
    clearance: Vec<Real>,
    /// How far each particle's predicted position can have moved since the last stage.
    bound: MoveBound<3>,
    /// `dt V*` of the last two predictors and `dt V` of the last update (m): the global
    /// bound of the ridge pass and the self-contact.
    moves: [Real; 3],
    /// The planes' strokes at the last stage (m).
    strokes: Vec<Real>,
    /// The particles interpolated at this stage, ascending.
    evaluated: Vec<u32>,
    /// Predicted position (m) and velocity (m/s) of each particle evaluated.
    motion: Vec<[[Real; 3]; 2]>,
    /// The penalty feedback of each tool without separation and each symmetry plane over
    /// the particles it holds ([`Feedback`]).
    pub(crate) feedback: Feedback,
    /// The pairs with friction in contact at this stage.
    touched: Vec<Touched>,
    /// The second pass: the tools' ridges against the surface between the particles.
    pub(super) ridges: RidgePass,
    /// Skip the particles with a positive clearance (false only in the test that compares
    /// against evaluating all).
    pub(crate) skip: bool,
}

/// What a contact stage did.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Touch {
    /// Some contact force acts.
    pub any: bool,
    /// A scene's tool (not a symmetry plane) presses the workpiece.
    pub tools: bool,
    /// The work the tools' motion delivered, `sum dt_avg f_J . v_tool` (J).
    pub tool_work: Real,
}

impl ToolContact {
    /// The stage for `particles` particles and `planes` planes: every particle is
    /// evaluated at the first step.
    pub(crate) fn new(particles: usize, planes: usize) -> ToolContact {
        ToolContact {
            force: Forces::new(particles),
            clearance: vec![0.0; particles],
            bound: MoveBound::default(),
            moves: [Real::INFINITY; 3],
            strokes: Vec::with_capacity(planes),
            evaluated: Vec::new(),
            motion: vec![[[0.0; 3]; 2]; particles],
            feedback: Feedback::default(),
            touched: Vec::new(),
            ridges: RidgePass::new(),
            skip: true,
        }
    }

    /// Records the predictor's move bound `dt V*` (m).
    pub(crate) fn predicted_move(&mut self, bound: Real) {
        self.moves = [self.moves[1], bound, self.moves[2]];
    }

    /// Records the update's move bound `dt V` (m).
    pub(crate) fn updated_move(&mut self, bound: Real) {
        self.moves[2] = bound;
    }

    /// Forgets the coefficients' last positions (the shape functions changed): the next
    /// stage evaluates every particle.
    pub(crate) fn forget_moves(&mut self) {
        self.bound.forget();
        self.feedback.forget();
    }

    /// The bound on the change of any coefficient's `d_I + dt v*_I` since the last stage,
    /// `sqrt 3` times the last two predictors' and the last update's move bounds (m): a
    /// particle's predicted position moves at most `S_J` times it.
    pub(crate) fn move_bound(&self) -> Real {
        (3.0 as Real).sqrt() * (self.moves[0] + self.moves[1] + self.moves[2])
    }

    /// The contact of the predicted positions (a natural step `dt = step.full` ahead, s)
    /// with `planes` (paper eqs. 4-7), `dt_avg = step.avg` the corrector's step (s), the
    /// points' flow stresses in `out` for the friction laws that need one ([`interface`]).
    /// Fills [`ToolContact::force`], each plane's force and the held and friction states of
    /// `st`.
    pub(crate) fn stage(
        &mut self,
        team: &Team,
        disc: &SolidDisc,
        planes: &mut [SolidTool],
        st: &mut SolidState,
        out: &[PointOut],
        step: StepLength,
    ) -> Touch {
        let (dt, dt_avg) = (step.full, step.avg);
        for t in planes.iter_mut() {
            t.state.force = [0.0; 3];
            t.state.normal_force = 0.0;
        }
        self.force.clear();
        self.touched.clear();
        st.pressed.clear();
        if planes.is_empty() {
            return Touch::default();
        }
        let np = disc.ref_pos.len();
        let nplanes = planes.len();
        let held = &st.held;
        let measured = self.feedback.update(
            nplanes,
            &disc.nodal,
            &disc.mass,
            |t| !planes[t].separation,
            |t| (0..np).filter(|&j| held[j * nplanes + t]).collect(),
        );
        st.plane_feedback_max = st.plane_feedback_max.max(measured);
        let plane_move = if self.strokes.len() == nplanes {
            planes
                .iter()
                .zip(&self.strokes)
                .fold(0.0, |m: Real, (t, s)| m.max((t.state.stroke - s).abs()))
        } else {
            Real::INFINITY
        };
        self.strokes.clear();
        self.strokes.extend(planes.iter().map(|t| t.state.stroke));
        let du = self.move_bound();
        let margin = 1e-9 * disc.h_min;
        self.evaluated.clear();
        self.bound
            .measure(&disc.nodal, &disc.ref_pos, &st.d, &st.v, dt);
        for (j, (c, s)) in self.clearance.iter_mut().zip(&disc.sum_abs).enumerate() {
            *c -= s * self.bound.near(j) + plane_move;
            if !(self.skip && *c > 0.0) {
                self.evaluated.push(j as u32);
            }
        }
        let planes_now: &[SolidTool] = planes;
        let held_now: &[bool] = &st.held;
        let (d, v) = (&st.d, &st.v);
        let evaluated = &self.evaluated;
        let (motion, clearance) = (
            Parts::new(&mut self.motion),
            Parts::new(&mut self.clearance),
        );
        particle_phase(team, np, evaluated.len().div_ceil(BLOCK), &|b| {
            for &j in &evaluated[part(b, BLOCK, evaluated.len())] {
                let j = j as usize;
                // SAFETY: particle `j` appears once in `evaluated`, in one block.
                let (m, c) = unsafe {
                    (
                        &mut motion.get(j..j + 1)[0],
                        &mut clearance.get(j..j + 1)[0],
                    )
                };
                let x = predicted(disc, d, v, dt, j);
                *m = [x, disc.nodal.interpolate(j, v)];
                *c = planes_now
                    .iter()
                    .enumerate()
                    .map(|(t, plane)| {
                        let front = plane.clearance(x);
                        match held_now[j * nplanes + t] {
                            true => front - plane.depth,
                            false => front,
                        }
                    })
                    .fold(Real::INFINITY, Real::min)
                    - margin;
            }
        });
        let mut touch = Touch::default();
        for &j in &self.evaluated {
            let j = j as usize;
            let stick = &mut st.stick[j * nplanes..(j + 1) * nplanes];
            if self.clearance[j] > 0.0 {
                stick.fill(None);
                continue;
            }
            let [x, vj] = self.motion[j];
            for (t, plane) in planes.iter_mut().enumerate() {
                let held = &mut st.held[j * nplanes + t];
                let below = match (*held, plane.separation) {
                    (true, false) => -plane.depth,
                    _ => 0.0,
                };
                let Some(pen) = plane.gap_above(x, below) else {
                    stick[t] = None;
                    continue;
                };
                if !plane.separation {
                    // A particle held from now on changes the plane's feedback.
                    self.feedback.took_hold(t, *held);
                    *held = true;
                }
                let vt = plane.axis.map(|a| a * plane.state.velocity);
                let slave = Slave {
                    m: disc.mass[j] * self.feedback.scale(t),
                    v_rel: std::array::from_fn(|k| vj[k] - vt[k]),
                    carried: stick[t].unwrap_or([0.0; 3]),
                };
                let at = if plane.friction.needs_flow_stress() {
                    interface(disc, j, flow_stress(disc, out, j), pen.normal, |i| {
                        predicted(disc, d, v, dt, i)
                    })
                } else {
                    Interface::default()
                };
                let SlaveForce { force: f, friction } =
                    penalty_force(slave, pen, &plane.friction, at, dt, dt_avg);
                if plane.friction.is_frictionless() {
                    stick[t] = None;
                } else {
                    self.touched.push(Touched {
                        j: j as u32,
                        t: t as u32,
                        friction,
                        normal: pen.normal,
                    });
                }
                for (a, f) in plane.state.force.iter_mut().zip(f) {
                    *a -= f;
                }
                let normal = dot(&f, &pen.normal);
                plane.state.normal_force += normal;
                if t < disc.scene_tools {
                    st.pressed.push(Pressed {
                        particle: j as u32,
                        tool: t as u32,
                        force_n: normal,
                        normal: pen.normal,
                    });
                }
                // The normal impulse on a scene tool, for a heat transfer over pressure.
                if let Some(i) = st
                    .heat
                    .as_mut()
                    .filter(|_| t < disc.scene_tools)
                    .and_then(|h| h.normal_impulse.get_mut(j))
                {
                    *i += normal.abs() * dt_avg;
                }
                touch.tool_work += dt_avg * dot(&f, &vt);
                self.force.spread(&disc.nodal, j, f);
                touch.any = true;
                touch.tools |= t < disc.scene_tools;
            }
        }
        let ridges = self.ridges.run(
            disc,
            planes,
            st,
            ParticlePass {
                out,
                force: &mut self.force,
                du,
            },
            step,
        );
        if ridges.any {
            touch.any = true;
            touch.tools |= ridges.tools;
            touch.tool_work += ridges.tool_work;
        }
        for t in planes.iter_mut() {
            let f = t.state.force;
            t.state.peak_force = t.state.peak_force.max(dot(&f, &f).sqrt());
        }
        touch
    }

    /// After the corrector: what the friction force `f_T` of each pair in contact did not
    /// realise on its particle, carried to the next step's stick force as `c = f_T + m_J P_T
    /// (v*_J - v_J) / dt_avg` (N), with `v*_J` the predicted velocity the force was computed
    /// from and `v_J = sum_I N_I(X_J) v_I` after the corrector (m/s), `P_T` the projection
    /// on the contact's tangent plane (the 2D law, `crate::contact::Contact::carry`). In a
    /// scene with `[thermal]` each pair's friction work over the step, `max(0, -f_T . P_T
    /// (v_J - v_tool)) dt_avg` (J, [`slip_work`]), is booked at its particle for the heat
    /// stage (`Heat::friction_work`).
    pub(crate) fn carry(
        &self,
        disc: &SolidDisc,
        planes: &[SolidTool],
        st: &mut SolidState,
        dt_avg: Real,
    ) {
        let nplanes = planes.len();
        let mut work = st
            .heat
            .as_mut()
            .map(|h| &mut h.friction_work[..])
            .filter(|w| !w.is_empty());
        for touched in &self.touched {
            let (j, t) = (touched.j as usize, touched.t as usize);
            let vj = disc.nodal.interpolate(j, &st.v);
            let predicted = self.motion[j][1];
            let dv: [Real; 3] = std::array::from_fn(|k| predicted[k] - vj[k]);
            let n = touched.normal;
            let dn = dot(&dv, &n);
            let c = disc.mass[j] / dt_avg;
            let f = touched.friction;
            st.stick[j * nplanes + t] =
                Some(std::array::from_fn(|k| f[k] + c * (dv[k] - dn * n[k])));
            if let Some(work) = work.as_mut() {
                let tool = &planes[t];
                let rel = std::array::from_fn(|k| vj[k] - tool.axis[k] * tool.state.velocity);
                work[j] += slip_work(&f, rel, &n, dt_avg);
            }
        }
    }
}
