//! The explicit RKPM solver (total Lagrangian, Lagrangian kernel unless the scene
//! re-references it, `rereference.rs`): a [`Simulation`] of one scene, set up once in the
//! reference configuration and advanced step by step.
//!
//! Setup ([`Simulation::new`], `setup.rs`): particle lattice and planar volumes; integration points of
//! the chosen rule and their RK shape functions ([`crate::integration`],
//! [`crate::rk_shape`]); the point groups, shared shape-function blocks and chunk buffers
//! (`layout.rs`); row-sum lumped masses `m_I = sum_p rho N_I(X_p) w_p` (kg); essential
//! conditions ([`crate::constraints`]); the critical step (`stable_step.rs`).
//!
//! One step `n -> n+1` of the central-difference scheme (Belytschko, Liu, Moran 2000,
//! Box 6.1) with the paper's predictor-corrector contact (section II-3), as
//! [`Simulation::step`] calls the stages:
//! 0. when the scene sets `discretization.rereference_stretch` and the last stress stage
//!    reached it, the kernel re-reference (`rereference.rs`); then a tool commanded too far
//!    for the step stops the run (`stable_step.rs`);
//! 1. stress (`stress.rs`): `F = I + sum_I d_I (x) grad N_I` at each point (plus
//!    `F_33 = 1 + u_r / R` in axisymmetry), Hencky J2 update, first Piola-Kirchhoff stress
//!    `P`, fused with the scatter of `w_p (P grad N_I + e_r P_33 N_I / R)` into chunk
//!    buffers; with scni and `discretization.scni_stabilization`, the stabilization's
//!    force on the quadrants of the nodal domains (`nodal_stabilization.rs`);
//! 2. time step (`stable_step.rs`): fixed, or `dt_safety * dt_crit`, with
//!    `dt_crit = dt_crit0 h_min / h_min0` from the smallest altitude of the deformed cells;
//! 3. force gather and predictor (`update.rs`): `f_I` summed in a fixed order,
//!    `v* = v_{n-1/2} - dt_avg f_int / m`;
//! 4. contact ([`crate::contact`]): the tools advance; penetration of the predicted boundary
//!    particles at `t_{n+1}`, paper eqs. 4-7 (on a step shortened to land on a requested
//!    time, positions and tools a natural step ahead);
//! 5. corrector (`update.rs`): `v_{n+1/2} = v* + dt_avg f_c / m`, then the projection onto the
//!    essential conditions, and the friction the corrector did not realise carried to the
//!    next step ([`crate::contact::Contact::carry`]);
//! 6. update (`update.rs`): `d_{n+1} = d_n + dt v_{n+1/2}` with the step's energy sums;
//! 7. energy account and its checks (`energy.rs`).
//!
//! The parallel phases (1; on large models also 3, the contact interpolation and 6) run on
//! a [`Team`] over fixed chunks, so the bits do not depend on the number of threads. What
//! the outputs read is in `fields.rs`; the whole changing state is [`State`].

mod conduction;
mod energy;
mod fields;
mod fill;
mod heat;
mod layout;
mod mass_scaling;
mod nodal_stabilization;
mod outline;
mod penetration;
mod rereference;
mod setup;
mod stable_step;
mod state;
mod stress;
#[cfg(test)]
mod tests;
mod update;

pub use energy::Energy;
pub use fields::Fields;
pub use fill::FillPoint;
pub use heat::{Heat, Temperatures};
pub use mass_scaling::MassScalingReport;
pub use penetration::{Depths, Penetrated, Within};
pub use state::Reference;
pub use state::{Filled, State};

use crate::constraints::Constraints;
use crate::contact::self_contact::neighbours;
use crate::contact::symmetry::SymmetryPlane;
use crate::contact::{Body, Contact, Pairs, Slip};
use crate::error::{Error, Result};
use crate::integration::PointSet;
use crate::laps;
use crate::material::{HeatCapacity, HenckyJ2, PointState};
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::scene::{Kinematics, Scene};
use crate::team::Team;
use crate::tools::Tool;
use energy::StepEnergy;
use layout::{Scatter, MAX_GROUP};
use setup::initial_motion;
use stable_step::{landing_step, tool_step_limit};
use std::time::{Duration, Instant};
use stress::{has_avx2, PointOut};
use update::{Motion, Predictor};

/// Wall time spent in each stage.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Whole setup: particles, shape functions, masses, constraints, critical step.
    pub setup: Duration,
    /// Part of `setup`: neighbour search and RK shape functions (and SCNI smoothing).
    pub shape_functions: Duration,
    /// Deformation gradient and stress update at the points.
    pub stress: Duration,
    /// Internal force gather, fused with the predictor.
    pub internal_force: Duration,
    /// Contact search and forces.
    pub contact: Duration,
    /// Time integration, constraints and energy.
    pub integration: Duration,
    /// The heat stage (conduction and surface flows), when the scene's heat moves.
    pub heat: Duration,
}

/// A running simulation of one scene.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// The scene being run.
    scene: Scene,
    /// The workpiece's material.
    material: HenckyJ2,
    /// Particles along x (r).
    nx: usize,
    /// Particles along y (z).
    ny: usize,
    /// Particle spacings (m).
    spacing: [Real; 2],
    /// Reference particle positions `X_I` (m), row by row: the lattice's, or the positions
    /// at the last kernel re-reference (`rereference.rs`).
    ref_pos: Vec<[Real; 2]>,
    /// The lattice's particle positions (m), the undeformed workpiece.
    original: Vec<[Real; 2]>,
    /// The lattice's planar kernel volumes (m^2), for the first re-reference.
    lattice_volumes: Vec<Real>,
    /// `J = det F` of each point at the last re-reference (-), 1 before one.
    reference_jacobian: Vec<Real>,
    /// Row-sum lumped masses `m_I` (kg; whole ring in axisymmetry, per depth in plane
    /// strain).
    mass: Vec<Real>,
    /// `1 / m_I` (1/kg): the predictor and corrector multiply by it (two divisions per
    /// particle and step were a quarter of the serial stages' time).
    inv_mass: Vec<Real>,
    /// The integration points of the scene's rule.
    points: PointSet,
    /// Reference volume weights `w_p` of the points (m^3; 2 pi R included).
    weights: Vec<Real>,
    /// `1 / R_p` of each integration point (1/m) in axisymmetry, 1 in plane strain.
    inv_radius: Vec<Real>,
    /// The point shape functions live only in the scatter's shared blocks
    /// ([`Scatter::point_row`]); the point-major table is dropped after setup.
    scatter: Scatter,
    /// The stabilization of nodal integration, when the scene asks for it
    /// (`nodal_stabilization.rs`).
    stabilization: Option<nodal_stabilization::NodalStabilization>,
    /// `N_I(X_J)` in row `J`, for positions and contact; its gradients are freed after
    /// setup (nothing reads them).
    nodal: ShapeTable,
    /// Boundary particles, counter-clockwise (the contact slaves).
    boundary: Vec<u32>,
    /// The workpiece's outline: the boundary of the body the RK approximation describes
    /// (`outline.rs`), whose enclosed volume is the workpiece's.
    outline: outline::Outline,
    /// Essential conditions, if the scene has any.
    constraints: Option<Constraints>,
    /// The rigid tools.
    tools: Vec<Tool>,
    /// The symmetry planes and the axis, holding every particle that reaches them.
    planes: Vec<SymmetryPlane>,
    /// The whole changing state.
    st: State,
    /// Per-point outputs of the last stress stage.
    out: Vec<PointOut>,
    /// Internal forces `f_I` of the last force gather (N).
    f_int: Vec<[Real; 2]>,
    /// Coefficient velocities `v_{n-1/2}` before the last predictor (m/s).
    v_prev: Vec<[Real; 2]>,
    /// Critical step of the undeformed discretisation (s).
    critical_dt0: Real,
    /// What mass scaling added, if the scene scales.
    mass_scaling: Option<MassScalingReport>,
    /// The contact stage: contact forces and what it carries between steps.
    contact: Contact,
    /// The threads of the parallel phases.
    team: Team,
    /// Use the AVX2 build of the stress stage where the CPU has it (same bits either way;
    /// false only in the test that compares the two).
    simd: bool,
    /// Whether the scene's heat moves (conduction, surface flows): the heat stage runs.
    transfers_heat: bool,
    /// Particles on a constrained edge, adiabatic in the heat stage (empty unless heat
    /// moves).
    adiabatic_edge: Vec<bool>,
    /// Conduction's largest eigenvalue `lambda_max(C^-1 K)` on the undeformed body (1/s), 0
    /// without conduction (`conduction.rs`).
    conduction_lambda0: Real,
    /// The workpiece's specific heat capacity in a thermal scene.
    heat_capacity: Option<HeatCapacity>,
    /// Wall time per stage since setup.
    pub times: StageTimes,
}

/// How far [`Simulation::run_toward`] went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ran {
    /// Steps taken.
    pub steps: u64,
    /// The time reached the target.
    pub reached: bool,
    /// The caller's `between` stopped it before the target.
    pub interrupted: bool,
}

impl Simulation {
    /// The scene being run.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.ref_pos.len()
    }
    /// Number of integration points.
    pub fn point_count(&self) -> usize {
        self.points.positions.len()
    }
    /// Grid size `(nx, ny)`.
    pub fn grid(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }
    /// Particle spacings (m).
    pub fn spacing(&self) -> [Real; 2] {
        self.spacing
    }
    /// Particle positions of the undeformed workpiece (m).
    pub fn reference_positions(&self) -> &[[Real; 2]] {
        &self.original
    }
    /// The configuration the kernel was last re-referenced on, if it was
    /// (`discretization.rereference_stretch`).
    pub fn reference(&self) -> Option<&Reference> {
        self.st.reference.as_ref()
    }
    /// Lumped masses (kg).
    pub fn masses(&self) -> &[Real] {
        &self.mass
    }
    /// Boundary particles, counter-clockwise.
    pub fn boundary(&self) -> &[u32] {
        &self.boundary
    }
    /// Time (s).
    pub fn time(&self) -> Real {
        self.st.time
    }
    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.st.step
    }
    /// Stable step estimate `h_min / c` on the current deformation (s).
    pub fn stable_dt(&self) -> Real {
        self.st.stable_dt
    }
    /// The step the next call to `step` will take when not limited (s).
    pub fn next_dt(&self) -> Real {
        self.scene
            .time
            .dt_s
            .unwrap_or(self.scene.time.dt_safety * self.st.stable_dt)
    }
    /// Energy account.
    pub fn energy(&self) -> Energy {
        self.st.energy
    }
    /// Tools.
    pub fn tools(&self) -> &[Tool] {
        &self.tools
    }
    /// Index of the tool named `name`.
    pub fn tool_index(&self, name: &str) -> Option<usize> {
        self.tools.iter().position(|t| t.name == name)
    }
    /// Set a tool's velocity along its axis (m/s) from outside, overriding the scene motion.
    pub fn set_tool_velocity(&mut self, tool: usize, v: Real) -> Result<()> {
        let t = self
            .tools
            .get_mut(tool)
            .ok_or_else(|| Error::Request(format!("no tool with index {tool}")))?;
        if !t.is_movable() {
            return Err(Error::Request(format!(
                "tool `{}` is fixed in the scene",
                t.name
            )));
        }
        if !v.is_finite() {
            return Err(Error::Request(format!(
                "velocity {v} for tool `{}` is not finite",
                t.name
            )));
        }
        t.state.command = Some(v);
        Ok(())
    }
    /// Total mass of the workpiece (kg; whole ring or per depth).
    pub fn total_mass(&self) -> Real {
        self.mass.iter().sum()
    }
    /// Momentum `sum m_I v_I` (kg m/s) at the last half step.
    pub fn momentum(&self) -> [Real; 2] {
        self.st
            .v
            .iter()
            .zip(&self.mass)
            .fold([0.0; 2], |a, (v, m)| [a[0] + m * v[0], a[1] + m * v[1]])
    }
    /// Largest equivalent plastic strain over the integration points.
    pub fn max_plastic_strain(&self) -> Real {
        self.st.points.iter().map(|s| s.eps_p).fold(0.0, Real::max)
    }
    /// Deepest a particle's physical position lay inside a tool (m), over the steps'
    /// checks and the samples.
    pub fn max_penetration(&self) -> Real {
        self.st.max_penetration
    }
    /// Deepest a particle's physical position lay beyond a symmetry plane or the axis (m).
    pub fn max_beyond_symmetry(&self) -> Real {
        self.st.max_beyond_plane
    }
    /// Deepest a surface particle lay inside another part of the workpiece (m).
    pub fn max_inside_itself(&self) -> Real {
        self.st.max_inside_itself
    }
    /// Most crossings of the boundary ring's segments at a sample (0: the surface never
    /// passed through itself).
    pub fn max_boundary_crossings(&self) -> u32 {
        self.st.max_crossings
    }
    /// The symmetry planes (and the axis) that hold the workpiece.
    pub fn symmetry_planes(&self) -> &[SymmetryPlane] {
        &self.planes
    }
    /// The laps found so far ([`crate::laps`]), in the order they formed, with their
    /// positions and lengths now.
    pub fn laps(&self) -> Vec<laps::LapReport> {
        if self.st.laps.is_empty() {
            return Vec::new();
        }
        let x: Vec<[Real; 2]> = self
            .boundary
            .iter()
            .map(|&j| self.position(j as usize))
            .collect();
        self.st
            .laps
            .iter()
            .map(|lap| {
                let s = neighbours(self.scene.discretization.support);
                laps::report(lap, &self.boundary, &x, &self.original, s)
            })
            .collect()
    }
    /// How many laps formed so far.
    pub fn lap_count(&self) -> usize {
        self.st.laps.len()
    }
    /// The whole changing state.
    pub fn state(&self) -> &State {
        &self.st
    }
    /// Restore a state saved from a simulation of the same scene.
    pub fn restore(&mut self, st: State) -> Result<()> {
        if st.d.len() != self.st.d.len()
            || st.v.len() != self.st.v.len()
            || st.points.len() != self.st.points.len()
            || st.tools.len() != self.st.tools.len()
            || st.held.len() != self.st.held.len()
            || st.plane_held.len() != self.st.plane_held.len()
            || st.self_touching.len() != self.st.self_touching.len()
            || st.stick.len() != self.st.stick.len()
            || st.fill.len() != self.st.fill.len()
        {
            return Err(Error::State(
                "the saved state belongs to another discretisation".into(),
            ));
        }
        if st.reference != self.st.reference {
            match &st.reference {
                Some(r) => self.install(r)?,
                None => self.take_discretization(Simulation::new(&self.scene)?),
            }
        }
        for (t, s) in self.tools.iter_mut().zip(&st.tools) {
            t.state = *s;
        }
        self.v_prev.clone_from(&st.v);
        self.contact.forget();
        for (p, (out, point)) in self.out.iter_mut().zip(&st.points).enumerate() {
            let temp = st.heat.as_ref().map(|h| h.temperature_c[p]);
            *out = PointOut::at(&self.material, point.eps_p, temp);
        }
        self.st = st;
        Ok(())
    }

    /// One central-difference step, at most `max_dt` long (s): the stages of the module
    /// doc, in order.
    pub fn step(&mut self, max_dt: Option<Real>) -> Result<()> {
        // 0a. Kernel re-reference, when the scene asks for it and the deformation reached it.
        self.rereference_if_due()
            .map_err(|e| rereference::failed(self.st.step, self.st.time, e))?;
        // 0b. A tool too fast for the step stops the run before anything changes.
        let h_min = self.spacing[0].min(self.spacing[1]);
        let tool_dt =
            tool_step_limit(&self.tools, self.st.time, self.next_dt(), h_min).map_err(|what| {
                Error::Request(format!(
                    "step {} (t = {:.6e} s): {what}",
                    self.st.step, self.st.time
                ))
            })?;
        // 1. Stress, fused with the scatter of the internal force.
        let (elastic, plastic) = self.stress_stage()?;
        // 2. Time step.
        let t1 = Instant::now();
        let dt_full = self.next_dt().min(tool_dt);
        let dt = landing_step(dt_full, max_dt);
        if dt.is_nan() || dt <= 0.0 {
            return Err(Error::Request(format!(
                "step length {dt} s is not positive"
            )));
        }
        let dt_avg = 0.5 * (dt + self.st.dt_prev);
        let t2 = Instant::now();
        // 3. Force gather and predictor.
        self.force_stage(Some((dt_avg, dt_full)));
        let t3 = Instant::now();
        // 4. Contact: the tools advance over the step at their mid-step velocity. The
        // predicted positions are a natural step ahead; on a step shortened to land on a
        // requested time the tools meet them there too, a further `dt_full - dt` ahead, and
        // go back to the end of the step after the stage.
        let t_mid = self.st.time + 0.5 * dt;
        for t in self.tools.iter_mut() {
            t.state.velocity = t.velocity_at(t_mid);
            t.state.stroke += dt * t.state.velocity;
        }
        let strokes = (dt < dt_full).then(|| {
            let at_end: Vec<Real> = self.tools.iter().map(|t| t.state.stroke).collect();
            for t in self.tools.iter_mut() {
                t.state.stroke += (dt_full - dt) * t.state.velocity;
            }
            at_end
        });
        let (temperature, impulse) = match &mut self.st.heat {
            Some(h) => (Some(&h.temperature_c[..]), &mut h.normal_impulse[..]),
            None => (None, &mut [][..]),
        };
        let body = Body {
            boundary: &self.boundary,
            nodal: &self.nodal,
            reference: &self.ref_pos,
            mass: &self.mass,
            d: &self.st.d,
            v: &self.st.v,
            spacing: self.spacing,
            points: &self.st.points,
            hardening: &self.material.hardening,
            temperature,
            kinematics: self.scene.model.kinematics,
            depth_m: self.scene.model.depth_m,
        };
        let touch = self.contact.stage(
            &self.team,
            &mut self.tools,
            &self.planes,
            &body,
            Pairs {
                held: &mut self.st.held,
                plane_held: &mut self.st.plane_held,
                self_touching: &mut self.st.self_touching,
                stick: &mut self.st.stick,
                pressure: &mut self.st.pressure,
                stations: self.scene.output.pressure_stations.unwrap_or(0),
                impulse,
            },
            dt_full,
            dt_avg,
        );
        if let Some(strokes) = strokes {
            for (t, stroke) in self.tools.iter_mut().zip(strokes) {
                t.state.stroke = stroke;
            }
        }
        let (contact, tool_work) = (touch.any, touch.tool_work);
        self.grow_laps(self.st.time + dt);
        let t4 = Instant::now();
        // 5. Corrector and essential conditions.
        if contact {
            update::correct(&mut self.st.v, &self.contact.force, &self.inv_mass, dt_avg);
        }
        if let Some(c) = &self.constraints {
            c.project(&mut self.st.v, &self.mass);
        }
        if contact {
            let slip = match &mut self.st.heat {
                Some(h) if !h.friction_work.is_empty() => Some(Slip {
                    tools: &self.tools,
                    work: &mut h.friction_work,
                }),
                _ => None,
            };
            self.contact.carry(
                &self.nodal,
                &self.mass,
                &self.st.v,
                &mut self.st.stick,
                dt_avg,
                slip,
            );
        }
        // 6. Update, with the energy sums.
        let motion = Motion {
            v: &self.st.v,
            v_prev: &self.v_prev,
            mass: &self.mass,
            f_int: &self.f_int,
            f_con: &self.contact.force,
        };
        let track = self.contacts_anything();
        let u = update::update(
            &self.team,
            &mut self.st.d,
            &motion,
            dt,
            dt_avg,
            contact,
            track,
        );
        self.contact.updated_move(dt * u.largest_speed);
        if !u.kinetic.is_finite() {
            let i = self
                .st
                .v
                .iter()
                .position(|v| !(v[0].is_finite() && v[1].is_finite()))
                .unwrap_or(0);
            return Err(Error::Diverged {
                step: self.st.step,
                time: self.st.time,
                what: format!(
                    "velocity of particle {i} at {:?} m is not finite",
                    self.original[i]
                ),
            });
        }
        // 7. Energy account; time advances; the checks.
        self.st.energy.add_step(StepEnergy {
            kinetic: u.kinetic,
            elastic,
            plastic,
            contact_work: u.contact_work,
            tool_work,
            internal_half_step: u.half_step,
        });
        self.st.step += 1;
        match self.scene.time.dt_s {
            Some(fixed) if dt == fixed => {
                self.st.time =
                    self.st.anchor_time + (self.st.step - self.st.anchor_step) as Real * fixed;
            }
            _ => {
                self.st.time += dt;
                self.st.anchor_time = self.st.time;
                self.st.anchor_step = self.st.step;
            }
        }
        self.st.dt_prev = dt;
        for (t, s) in self.tools.iter().zip(self.st.tools.iter_mut()) {
            *s = t.state;
        }
        if contact {
            self.check_penetration()?;
            self.check_fill();
        }
        let checks = &self.scene.checks;
        self.st.energy.check(
            checks.energy_balance_tol,
            self.st.step,
            self.st.time,
            dt,
            self.st.stable_dt,
        )?;
        // 8. The quasi-static watch, from the first touch of a tool.
        self.watch_quasi_static(touch.tools)?;
        // 9. The heat stage, when it is due (`conduction.rs`).
        let t6 = Instant::now();
        self.heat_stage_if_due(dt)?;
        self.times.heat += t6.elapsed();
        let t5 = Instant::now();
        self.times.contact += t4 - t3;
        self.times.integration += (t2 - t1) + (t5 - t4);
        Ok(())
    }

    /// Step until `time` reaches `t_end` (s), the last step shortened to land on it, calling
    /// `on_step` after each step.
    ///
    /// # Errors
    ///
    /// A step failed (see [`Simulation::step`]).
    pub fn run_to(
        &mut self,
        t_end: Real,
        mut on_step: impl FnMut(&Simulation) + Send,
    ) -> Result<()> {
        let ran = self.run_toward(t_end, u64::MAX, |sim, taken| {
            if taken > 0 {
                on_step(sim);
            }
            true
        })?;
        if ran.steps > 0 {
            on_step(self);
        }
        Ok(())
    }

    /// Step toward `t_end` (s), the last step shortened to land on it, taking at most
    /// `max_steps` steps. `between(sim, taken)` is called before each step with the steps
    /// taken so far; it may change the simulation (a tool's velocity command) and returns
    /// `false` to stop there. The one stepping loop of every front end.
    ///
    /// The loop runs on a worker of the current rayon pool, so the parallel stages of each
    /// step start without a thread hand-off.
    ///
    /// # Errors
    ///
    /// A step failed (see [`Simulation::step`]).
    pub fn run_toward(
        &mut self,
        t_end: Real,
        max_steps: u64,
        mut between: impl FnMut(&mut Simulation, u64) -> bool + Send,
    ) -> Result<Ran> {
        let this = &mut *self;
        let mut run = move || -> Result<Ran> {
            let mut ran = Ran {
                steps: 0,
                reached: false,
                interrupted: false,
            };
            loop {
                if this.st.time >= t_end - 1e-12 * t_end.abs() {
                    ran.reached = true;
                    return Ok(ran);
                }
                if ran.steps >= max_steps {
                    return Ok(ran);
                }
                if !between(this, ran.steps) {
                    ran.interrupted = true;
                    return Ok(ran);
                }
                this.step(Some(t_end - this.st.time))?;
                ran.steps += 1;
            }
        };
        if rayon::current_thread_index().is_some() {
            run()
        } else {
            // `scope` runs its body on a worker of the global pool.
            rayon::scope(|_| run())
        }
    }

    /// Whether the contact stage has anything to do: tools, symmetry planes or the surface
    /// against itself (the update then bounds how far the particles move, for its skips).
    fn contacts_anything(&self) -> bool {
        !self.tools.is_empty() || !self.planes.is_empty() || self.contact.self_contact().is_some()
    }

    /// Grows the laps by the last contact stage's self-contacts, predicted for `time` (s)
    /// ([`crate::laps`]).
    fn grow_laps(&mut self, time: Real) {
        let (pairs, x) = self.contact.self_pairs();
        if pairs.is_empty() {
            return;
        }
        let stage = laps::Stage {
            neighbours: neighbours(self.scene.discretization.support),
            x,
            time,
            strokes: self.tools.iter().map(|t| t.state.stroke).collect(),
        };
        laps::grow(&mut self.st.laps, pairs, &stage);
    }

    /// The stress stage (`stress.rs`) on this simulation's points, timed; a point whose
    /// update fails stops the run with a diagnosis naming it. Sets the stable step estimate
    /// from the smallest deformed altitude. Returns (elastic, plastic) energy (J).
    fn stress_stage(&mut self) -> Result<(Real, Real)> {
        let t0 = Instant::now();
        let input = stress::Inputs {
            d: &self.st.d,
            material: &self.material,
            weights: &self.weights,
            inv_radius: &self.inv_radius,
            reference_jacobian: &self.reference_jacobian,
            track_stretch: self.scene.discretization.rereference_stretch.is_some(),
            axi: self.scene.model.kinematics == Kinematics::Axisymmetric,
            spacing: self.spacing,
            avx2: self.simd && has_avx2(),
            heating: self
                .scene
                .thermal
                .as_ref()
                .zip(self.heat_capacity.as_ref())
                .map(|(spec, capacity)| {
                    let mut h = heat::Heating::new(
                        spec,
                        capacity,
                        self.scene.material.density_kg_per_m3,
                        self.st.dt_prev,
                    );
                    if let Some(heat) = &self.st.heat {
                        h.ramp = if heat.step_s > 0.0 {
                            (1.0 - heat.since_s / heat.step_s).clamp(0.0, 1.0)
                        } else {
                            0.0
                        };
                    }
                    h
                }),
        };
        let sums = stress::stage(
            &self.team,
            &mut self.scatter,
            &input,
            &mut self.st.points,
            &mut self.out,
            self.st.heat.as_mut().map(|h| {
                (
                    &mut h.temperature_c[..],
                    &mut h.plastic_work[..],
                    &mut h.plastic_rate[..],
                    (!h.elastic_state.is_empty())
                        .then_some((&mut h.elastic_state[..], &h.stage_change_k[..])),
                )
            }),
        )
        .map_err(|(p, m)| Error::Diverged {
            step: self.st.step,
            time: self.st.time,
            what: format!(
                "integration point {p} (reference position {:?} m): {m}",
                self.points.positions[p]
            ),
        })?;
        self.st.stable_dt =
            self.critical_dt0 * sums.min_altitude / self.spacing[0].min(self.spacing[1]);
        if self.scene.discretization.rereference_stretch.is_some() {
            self.st.max_stretch = sums.max_stretch;
        }
        self.st.energy.thermoelastic += sums.thermoelastic;
        self.st.energy.thermoelastic_abs += sums.thermoelastic.abs();
        let stabilization = match &mut self.stabilization {
            Some(s) => {
                nodal_stabilization::stage(&self.team, s, &self.st.d, self.simd && has_avx2())
            }
            None => 0.0,
        };
        self.times.stress += t0.elapsed();
        Ok((sums.elastic + stabilization, sums.plastic))
    }

    /// The internal force gather (`update.rs`), timed; with
    /// `predict = Some((dt_avg, dt))` (s) fused with the predictor, recording the move bound
    /// `dt V*` for the contact stage.
    fn force_stage(&mut self, predict: Option<(Real, Real)>) {
        let t0 = Instant::now();
        let track = self.contacts_anything();
        let predictor = predict.map(|(dt_avg, _)| Predictor {
            dt_avg,
            v: &mut self.st.v,
            v_prev: &mut self.v_prev,
            inv_mass: &self.inv_mass,
            track,
        });
        let extra = self.stabilization.as_ref().map(|s| &s.force[..]);
        let speed =
            update::gather_forces(&self.team, &self.scatter, extra, &mut self.f_int, predictor);
        if let Some((_, dt)) = predict {
            self.contact.predicted_move(dt * speed);
        }
        self.times.internal_force += t0.elapsed();
    }

    /// The critical step on the undeformed discretisation (`stable_step.rs`),
    /// with `K x` the internal force of a displacement of 1e-7 of the spacing; the state is
    /// left undeformed. With a modulus over temperature the points answer at their
    /// temperatures now: the step is scaled by `sqrt(f_now / f_max)`, `f_now` the largest
    /// modulus factor of the points' temperatures and `f_max` the table's largest, so that
    /// it holds when a die chills the body stiffer.
    fn measure_critical_step(&mut self) -> Result<Real> {
        let stiffening = match (&self.material.thermoelastic, &self.st.heat) {
            (Some(te), Some(h)) if !te.modulus_factor.is_empty() => {
                let now = h
                    .temperature_c
                    .iter()
                    .map(|&t| te.modulus_factor_at(t))
                    .fold(Real::NEG_INFINITY, Real::max);
                (now / te.modulus_factor_max()).sqrt()
            }
            _ => 1.0,
        };
        self.measure_critical_step_now().map(|dt| dt * stiffening)
    }

    /// The critical step the points answer with at their temperatures now (see
    /// [`Simulation::measure_critical_step`]).
    fn measure_critical_step_now(&mut self) -> Result<Real> {
        let saved_points = self.st.points.clone();
        // The stress stage also heats the points and books the energy: neither is the run's.
        let (saved_heat, saved_energy) = (self.st.heat.clone(), self.st.energy);
        let amplitude = 1e-7 * self.spacing[0].min(self.spacing[1]);
        let inv_sqrt_m: Vec<Real> = self.mass.iter().map(|m| 1.0 / m.sqrt()).collect();
        let dt = stable_step::critical_step(&inv_sqrt_m, amplitude, |d| {
            self.st.d = d;
            self.stress_stage()?;
            self.force_stage(None);
            Ok(self.f_int.clone())
        });
        self.st.d = vec![[0.0; 2]; self.ref_pos.len()];
        self.st.points = saved_points;
        self.st.heat = saved_heat;
        self.st.energy = saved_energy;
        dt
    }

    /// of its arrays).
    pub fn memory_bytes(&self) -> usize {
        let table = |t: &ShapeTable| {
            t.offsets.len() * 4 + t.index.len() * 4 + (t.n.len() + t.dx.len() + t.dy.len()) * 8
        };
        let r2 = std::mem::size_of::<[Real; 2]>();
        let np = self.ref_pos.len();
        let npts = self.points.positions.len();
        table(&self.nodal)
            + self.scatter.memory_bytes()
            + np * (5 * r2 + 2 * 8)
            + npts
                * (r2 + 3 * 8 + std::mem::size_of::<PointState>() + std::mem::size_of::<PointOut>())
            + self.boundary.len() * 4
            + self.outline.memory_bytes()
            + self.stabilization.as_ref().map_or(0, |s| s.memory_bytes())
    }

    /// Critical step measured on the undeformed discretisation (s).
    pub fn critical_dt0(&self) -> Real {
        self.critical_dt0
    }

    /// Internal force on each coefficient from the current stresses (N); for tests.
    pub fn internal_forces(&mut self) -> Result<Vec<[Real; 2]>> {
        self.stress_stage()?;
        self.force_stage(None);
        Ok(self.f_int.clone())
    }

    /// Set the displacement coefficients directly (m); for tests and restarts.
    pub fn set_displacement(&mut self, d: Vec<[Real; 2]>) -> Result<()> {
        if d.len() != self.st.d.len() {
            return Err(Error::State(format!(
                "expected {} coefficients, got {}",
                self.st.d.len(),
                d.len()
            )));
        }
        self.st.d = d;
        self.contact.forget();
        Ok(())
    }
    /// The material model.
    pub fn material(&self) -> &HenckyJ2 {
        &self.material
    }
    /// Largest physical velocity of a constrained component (m/s): zero up to round-off.
    pub fn constraint_residual(&self) -> Real {
        self.constraints
            .as_ref()
            .map_or(0.0, |c| c.residual(&self.st.v))
    }

    /// What mass scaling added, if the scene scales (`[time] mass_scaling`).
    pub fn mass_scaling(&self) -> Option<MassScalingReport> {
        self.mass_scaling
    }

    /// Largest ratio of the workpiece's kinetic to internal energy (-) since the
    /// quasi-static watch began (`checks.kinetic_to_internal_from`); 0 before.
    pub fn kinetic_to_internal_max(&self) -> Real {
        self.st.kinetic_to_internal_max
    }

    /// A warning when a mass-scaled run's kinetic energy exceeded
    /// [`QUASI_STATIC_WARNING`] of its internal energy after the start-up: the inertia that
    /// mass scaling adds is no longer negligible, and forces and shapes carry it.
    pub fn quasi_static_warning(&self) -> Option<String> {
        let ratio = self.st.kinetic_to_internal_max;
        (self.mass_scaling.is_some() && ratio > QUASI_STATIC_WARNING).then(|| {
            format!(
                "the kinetic energy reached {:.1} % of the internal energy (above {:.0} %): the added mass is not negligible; scale less or set checks.kinetic_to_internal_max to stop such runs",
                100.0 * ratio,
                100.0 * QUASI_STATIC_WARNING
            )
        })
    }

    /// A warning when the boundary ring crossed itself at a sample: the surface passed
    /// through itself (the self-contact is off, or the fold was shorter than the kernel's
    /// support, which contact cannot hold), so the boundary's volume and the pictures are
    /// not to be trusted there.
    pub fn surface_warning(&self) -> Option<String> {
        let n = self.st.max_crossings;
        (n > 0).then(|| {
            let why = match self.scene.self_contact.enabled {
                true => "a fold shorter than the kernel's support passed through itself (two surface particles swapping places on a coarse grid, or the saw-tooth plain nodal integration leaves on a free surface: discretization.scni_stabilization holds it), which contact does not hold",
                false => "[self_contact] enabled = false lets it pass through itself",
            };
            format!(
                "the boundary crossed itself ({n} crossings of its segments at a sample; deepest particle {:.3} spacings inside the workpiece's own surface): {why}",
                self.st.max_inside_itself / self.spacing[0].min(self.spacing[1])
            )
        })
    }

    /// Replaces the lumped masses (kg) and what depends on them: inverse masses, the
    /// essential conditions' projection, the initial velocities projected onto them and
    /// the initial kinetic energy.
    fn set_masses(&mut self, mass: Vec<Real>) -> Result<()> {
        if let Some(c) = &self.constraints {
            self.constraints = Constraints::new(c.rows.clone(), &self.nodal, &mass)?;
        }
        let v0 = self.scene.workpiece.initial_velocity_m_per_s;
        let (v, initial) = initial_motion(v0, self.constraints.as_ref(), &mass);
        self.inv_mass = mass.iter().map(|m| 1.0 / m).collect();
        self.mass = mass;
        self.st.v.clone_from(&v);
        self.v_prev = v;
        self.st.energy = Energy {
            initial,
            kinetic: initial,
            ..Default::default()
        };
        Ok(())
    }
}

/// Kinetic-to-internal energy ratio above which a mass-scaled run warns (-): forming is
/// quasi-static while the kinetic energy stays a few per cent of the internal energy.
pub const QUASI_STATIC_WARNING: Real = 0.05;
