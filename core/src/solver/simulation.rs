//! A running simulation of one scene: the scene, its [`Discretization`] (fixed after setup),
//! its tools, the [`State`] a snapshot saves and the stages' [`Workspace`], apart; the step
//! as the list of its stages ([`Simulation::step`]) and the stepping loop of every front end
//! ([`Simulation::run_toward`]).

use super::contact_stage;
use super::detachment::Body;
use super::discretization::{Discretization, MassScalingReport};
use super::energy::{Energy, StepEnergy};
use super::point_outputs::PointOut;
use super::quasi_static;
use super::state::{Reference, State};
use super::workspace::Workspace;
use super::{conduction, fill, penetration, rereference, stable_step, stress, update};
use crate::contact::self_contact::neighbours;
use crate::contact::symmetry::SymmetryPlane;
use crate::error::{Error, Result};
use crate::laps;
use crate::material::{HenckyJ2, PointState};
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::scene::IntegrationRule;
use crate::scene::Scene;
use crate::tools::Tool;
use std::time::{Duration, Instant};

/// Wall time spent in each stage.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
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
    /// Time integration, constraints, energy and the checks.
    pub integration: Duration,
    /// The heat stage (conduction and surface flows), when the scene's heat moves.
    pub heat: Duration,
}

impl std::ops::AddAssign for StageTimes {
    /// Add another process's times of the same run, stage by stage (a resumed run's times
    /// cover every process that ran it, each one's setup included).
    fn add_assign(&mut self, o: StageTimes) {
        self.setup += o.setup;
        self.shape_functions += o.shape_functions;
        self.stress += o.stress;
        self.internal_force += o.internal_force;
        self.contact += o.contact;
        self.integration += o.integration;
        self.heat += o.heat;
    }
}

/// Runs `f`, adding its wall time to `into`.
fn timed<T>(into: &mut Duration, f: impl FnOnce() -> T) -> T {
    let t0 = Instant::now();
    let r = f();
    *into += t0.elapsed();
    r
}

/// A running simulation of one scene.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// The scene being run.
    pub(super) scene: Scene,
    /// What setup fixed: particles, points, shape functions, masses, boundary, planes.
    pub(super) disc: Discretization,
    /// The rigid tools: their geometry, motion and state now (copied into the state after
    /// each step).
    pub(super) tools: Vec<Tool>,
    /// The whole changing state.
    pub(super) st: State,
    /// The stages' working arrays.
    pub(super) ws: Workspace,
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

/// A simulation the stepping loop drives: the 2D [`Simulation`] and the 3D
/// [`super::SolidSimulation`].
pub(super) trait Stepping: Send {
    /// Time (s).
    fn now(&self) -> Real;
    /// One step of at most `max_dt` (s).
    fn step_at_most(&mut self, max_dt: Option<Real>) -> Result<()>;
}

impl Stepping for Simulation {
    fn now(&self) -> Real {
        self.st.time
    }
    fn step_at_most(&mut self, max_dt: Option<Real>) -> Result<()> {
        self.step(max_dt)
    }
}

/// The one stepping loop of every front end, 2D and 3D: steps `sim` toward `t_end` (s),
/// the last step shortened to land on it, taking at most `max_steps` steps;
/// `between(sim, taken)` is called before each step and returns `false` to stop there. The
/// loop runs on a worker of the current rayon pool, so the parallel stages of each step
/// start without a thread hand-off.
pub(super) fn stepping_loop<S: Stepping>(
    sim: &mut S,
    t_end: Real,
    max_steps: u64,
    mut between: impl FnMut(&mut S, u64) -> bool + Send,
) -> Result<Ran> {
    let mut run = move || -> Result<Ran> {
        let mut ran = Ran {
            steps: 0,
            reached: false,
            interrupted: false,
        };
        loop {
            if sim.now() >= t_end - 1e-12 * t_end.abs() {
                ran.reached = true;
                return Ok(ran);
            }
            if ran.steps >= max_steps {
                return Ok(ran);
            }
            if !between(sim, ran.steps) {
                ran.interrupted = true;
                return Ok(ran);
            }
            let left = t_end - sim.now();
            sim.step_at_most(Some(left))?;
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

impl Simulation {
    /// One central-difference step, at most `max_dt` long (s). The stages, in order (the
    /// module doc of [`crate::solver`] gives each one's formula and file):
    /// 0. kernel re-reference when due (`rereference.rs`), the tools' speed limit on the step
    ///    (`stable_step.rs`);
    /// 1. stress, fused with the scatter of the internal force (`stress.rs`), and the
    ///    stabilization of nodal integration (`nodal_stabilization.rs`);
    /// 2. time step (`stable_step.rs`);
    /// 3. force gather and predictor (`update.rs`);
    /// 4. contact: tools advance, penalty forces, laps (`contact_stage.rs`);
    /// 5. corrector, essential conditions and the friction carried (`update.rs`);
    /// 6. update of the coefficients, with the step's energy sums (`update.rs`);
    /// 7. energy account and clock (`energy.rs`, `state.rs`);
    /// 8. checks: penetration (`penetration.rs`), die fill (`fill.rs`), energy balance
    ///    (`energy.rs`), the quasi-static watch (`quasi_static.rs`);
    /// 9. the heat stage when due (`conduction.rs`).
    pub fn step(&mut self, max_dt: Option<Real>) -> Result<()> {
        let Simulation {
            scene,
            disc,
            tools,
            st,
            ws,
            times,
        } = self;
        rereference::if_due(scene, disc, tools, st, ws)?;
        let tool_dt = stable_step::tool_limit(
            &scene.time,
            tools,
            st.step,
            st.time,
            st.stable_dt,
            disc.h_min(),
        )?;
        let (elastic, plastic) = timed(&mut times.stress, || stress::run(scene, disc, st, ws))?;
        let dt = timed(&mut times.integration, || {
            stable_step::length(&scene.time, st.stable_dt, st.dt_prev, tool_dt, max_dt)
        })?;
        timed(&mut times.internal_force, || {
            update::forces(disc, tools, st, ws, Some(dt))
        });
        let touch = timed(&mut times.contact, || {
            contact_stage::run(scene, disc, tools, st, ws, dt)
        });
        timed(&mut times.integration, || -> Result<()> {
            update::correct(disc, tools, st, ws, touch.any, dt.avg);
            let u = update::advance(disc, tools, st, ws, touch.any, dt, scene.time.dt_s)?;
            st.energy.add_step(StepEnergy {
                kinetic: u.kinetic,
                elastic,
                plastic,
                contact_work: u.contact_work,
                tool_work: touch.tool_work,
                internal_half_step: u.half_step,
            });
            st.advance_clock(scene.time.dt_s, dt.dt, tools);
            if touch.any {
                penetration::check(scene, disc, tools, st, ws)?;
                fill::check(scene, disc, tools, st, ws);
            }
            let tol = scene.checks.energy_balance_tol;
            st.energy
                .check(tol, st.step, st.time, dt.dt, st.stable_dt, scene.time.dt_s)?;
            quasi_static::watch(
                &scene.checks,
                scene.time.end_s,
                tools.is_empty(),
                st,
                touch.tools,
            )
        })?;
        timed(&mut times.heat, || {
            conduction::stage_if_due(scene, disc, tools, st, &mut ws.out, dt.dt)
        })
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
        between: impl FnMut(&mut Simulation, u64) -> bool + Send,
    ) -> Result<Ran> {
        stepping_loop(self, t_end, max_steps, between)
    }

    /// The scene being run.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.disc.ref_pos.len()
    }
    /// Number of integration points.
    pub fn point_count(&self) -> usize {
        self.disc.points.positions.len()
    }
    /// Grid size `(nx, ny)`.
    pub fn grid(&self) -> (usize, usize) {
        (self.disc.nx, self.disc.ny)
    }
    /// Particle spacings (m).
    pub fn spacing(&self) -> [Real; 2] {
        self.disc.spacing
    }
    /// Particle positions of the undeformed workpiece (m).
    pub fn reference_positions(&self) -> &[[Real; 2]] {
        &self.disc.original
    }
    /// The configuration the kernel was last re-referenced on, if it was
    /// (`discretization.rereference_stretch`).
    pub fn reference(&self) -> Option<&Reference> {
        self.st.reference.as_ref()
    }
    /// Lumped masses (kg).
    pub fn masses(&self) -> &[Real] {
        &self.disc.mass
    }
    /// Boundary particles, counter-clockwise.
    pub fn boundary(&self) -> &[u32] {
        &self.disc.boundary
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
        stable_step::natural_step(&self.scene.time, self.st.stable_dt)
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
    /// Set a tool's velocity along its axis (m/s) from outside, overriding the scene motion
    /// ([`crate::tools::command_velocity`]).
    ///
    /// # Errors
    ///
    /// No such tool, a fixed tool, or a velocity that is not finite.
    pub fn set_tool_velocity(&mut self, tool: usize, v: Real) -> Result<()> {
        crate::tools::command_velocity(&mut self.tools, tool, v)
    }
    /// Total mass of the workpiece (kg; whole ring or per depth).
    pub fn total_mass(&self) -> Real {
        self.disc.mass.iter().sum()
    }
    /// Momentum `sum m_I v_I` (kg m/s) at the last half step.
    pub fn momentum(&self) -> [Real; 2] {
        self.st
            .v
            .iter()
            .zip(&self.disc.mass)
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
    /// Largest collective feedback of the penalty of a tool without separation or a
    /// symmetry plane over the particles it held (-; [`crate::contact::penalty_feedback`]).
    pub fn plane_feedback_max(&self) -> Real {
        self.st.plane_feedback_max
    }
    /// The smallest factor the contact put on such a penalty for its feedback (-, 1 when
    /// none passed the limit).
    pub fn plane_penalty_scale_min(&self) -> Real {
        crate::contact::penalty_feedback::scale(self.st.plane_feedback_max)
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
        &self.disc.planes
    }
    /// The laps found so far ([`crate::laps`]), in the order they formed, with their
    /// positions and lengths now.
    pub fn laps(&self) -> Vec<laps::LapReport> {
        if self.st.laps.is_empty() {
            return Vec::new();
        }
        let x = self.disc.ring(&self.st.d);
        self.st
            .laps
            .iter()
            .map(|lap| {
                let s = neighbours(self.scene.discretization.support);
                laps::report(lap, &self.disc.boundary, &x, &self.disc.original, s)
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
        if !self.st.same_shape(&st) {
            return Err(Error::State(
                "the saved state belongs to another discretisation".into(),
            ));
        }
        if st.reference != self.st.reference {
            match &st.reference {
                Some(r) => rereference::install(
                    &self.scene,
                    &mut self.disc,
                    &self.tools,
                    &mut self.st,
                    &mut self.ws,
                    r,
                )
                .map(|_| ())?,
                None => {
                    let fresh = Simulation::new(&self.scene)?;
                    self.disc = fresh.disc;
                    self.ws.contact = fresh.ws.contact;
                    self.ws.buf = fresh.ws.buf;
                }
            }
        }
        for (t, s) in self.tools.iter_mut().zip(&st.tools) {
            t.state = *s;
        }
        self.ws.v_prev.clone_from(&st.v);
        self.ws.contact.forget();
        for (p, (out, point)) in self.ws.out.iter_mut().zip(&st.points).enumerate() {
            let temp = st.heat.as_ref().map(|h| h.temperature_c[p]);
            *out = PointOut::at(&self.disc.material, point.eps_p, temp);
        }
        self.st = st;
        Ok(())
    }

    /// Bytes held by the discretisation and the state (an estimate from the lengths of its
    /// arrays).
    pub fn memory_bytes(&self) -> usize {
        let table = |t: &ShapeTable| {
            t.offsets.len() * 4
                + t.index.len() * 4
                + (t.n.len() + t.grad.iter().map(Vec::len).sum::<usize>()) * 8
        };
        let r2 = std::mem::size_of::<[Real; 2]>();
        let d = &self.disc;
        let np = d.ref_pos.len();
        let npts = d.points.positions.len();
        table(&d.nodal)
            + d.scatter.memory_bytes()
            + self.ws.buf.len() * r2
            + np * (5 * r2 + 3 * 8)
            + npts
                * (r2 + 3 * 8 + std::mem::size_of::<PointState>() + std::mem::size_of::<PointOut>())
            + d.boundary.len() * 4
            + d.outline.memory_bytes()
            + d.stabilization.as_ref().map_or(0, |s| s.memory_bytes())
            + self
                .ws
                .stabilization
                .as_ref()
                .map_or(0, |s| s.memory_bytes())
    }

    /// Critical step measured on the undeformed discretisation (s).
    pub fn critical_dt0(&self) -> Real {
        self.disc.critical_dt0
    }

    /// Internal force on each coefficient from the current stresses (N); for tests.
    pub fn internal_forces(&mut self) -> Result<Vec<[Real; 2]>> {
        let Simulation {
            scene,
            disc,
            tools,
            st,
            ws,
            ..
        } = self;
        stress::run(scene, disc, st, ws)?;
        update::forces(disc, tools, st, ws, None);
        Ok(self.ws.f_int.clone())
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
        self.ws.contact.forget();
        Ok(())
    }
    /// The material model.
    pub fn material(&self) -> &HenckyJ2 {
        &self.disc.material
    }
    /// Largest physical velocity of a constrained component (m/s): zero up to round-off.
    pub fn constraint_residual(&self) -> Real {
        self.disc
            .constraints
            .as_ref()
            .map_or(0.0, |c| c.residual(&self.st.v))
    }

    /// What mass scaling added, if the scene scales (`[time] mass_scaling`).
    pub fn mass_scaling(&self) -> Option<MassScalingReport> {
        self.disc.mass_scaling
    }

    /// Largest ratio of the workpiece's kinetic to internal energy (-) since the
    /// quasi-static watch began (`checks.kinetic_to_internal_from`); 0 before.
    pub fn kinetic_to_internal_max(&self) -> Real {
        self.st.kinetic_to_internal_max
    }

    /// A warning when a mass-scaled run's inertia was not negligible
    /// ([`quasi_static::warning`]).
    pub fn quasi_static_warning(&self) -> Option<String> {
        quasi_static::warning(
            self.disc.mass_scaling.is_some(),
            self.st.kinetic_to_internal_max,
        )
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
                self.st.max_inside_itself / self.disc.h_min()
            )
        })
    }

    /// Re-references the kernel now, on the positions of the current displacement
    /// (`rereference.rs`); a run does it itself when `discretization.rereference_stretch`
    /// is reached.
    pub fn rereference(&mut self) -> Result<()> {
        rereference::now(
            &self.scene,
            &mut self.disc,
            &self.tools,
            &mut self.st,
            &mut self.ws,
        )
    }

    /// A history sample's measures of the whole body over the particles' physical positions,
    /// formed once: every particle's isolation (its nearest integration point over that
    /// distance at the start, `detachment.rs`), and every particle against every tool at
    /// any depth and every symmetry plane and the boundary ring against itself
    /// (`penetration.rs`), both recorded in the state (the run's largest). Returns the
    /// positions (m) with the depths.
    ///
    /// # Errors
    ///
    /// A particle lies past the scene's bound in a tool or beyond a plane: the error names
    /// it, where it lies and the depth (the isolation is measured first).
    pub fn measure_sample(&mut self) -> (Vec<[Real; 2]>, Result<penetration::Depths>) {
        let positions = self.positions();
        self.measure_isolation(&positions);
        let depths = self.measure_penetration_at(&positions);
        (positions, depths)
    }

    /// Every particle's isolation with the particles at `positions` (m, now): its nearest
    /// integration point over that distance at the start, recorded in the state.
    fn measure_isolation(&mut self, positions: &[[Real; 2]]) {
        let d = &self.disc;
        let body = Body {
            scatter: &d.scatter,
            points: &d.points.positions,
            d: &self.st.d,
            particles: positions,
            nodal: self.scene.discretization.integration == IntegrationRule::Scni,
        };
        let time = self.st.time;
        self.st
            .isolation
            .measure_body(&body, &d.initial_spacing, time);
    }

    /// Every particle against every tool at any depth and every symmetry plane, and the
    /// boundary ring against itself, now (`penetration.rs`); also kept as the run's
    /// largest; past the scene's bound in a tool or beyond a plane an error naming the
    /// particle, where it lies and the depth.
    ///
    /// # Errors
    ///
    /// The penetration bound is exceeded.
    pub fn measure_penetration(&mut self) -> Result<penetration::Depths> {
        self.measure_penetration_at(&self.positions())
    }

    /// [`Simulation::measure_penetration`] with the particles at `positions` (m, now).
    fn measure_penetration_at(&mut self, positions: &[[Real; 2]]) -> Result<penetration::Depths> {
        penetration::measure(
            &self.scene,
            &self.disc,
            &self.tools,
            &mut self.st,
            positions,
        )
    }

    /// The warning of a run in which a particle left the body, naming it (`detachment.rs`).
    pub fn detached_warning(&self) -> Option<String> {
        self.st.isolation.warning(&self.disc.original)
    }

    /// Every particle against every tool at any depth and every symmetry plane, and the
    /// boundary ring against itself, now (zero depths when nothing lies inside), without
    /// keeping it (`penetration.rs`).
    pub fn penetration(&self) -> penetration::Depths {
        self.penetration_at(&self.positions())
    }

    /// [`Simulation::penetration`] with the particles at `positions` (m, now).
    pub fn penetration_at(&self, positions: &[[Real; 2]]) -> penetration::Depths {
        penetration::depths(&self.disc, &self.tools, positions)
    }
}
