//! The 3D solver (`model.kinematics = "3d"`): a running simulation of a [`SolidScene`].
//!
//! One source with 2D: the stages are the 2D solver's, generic over the dimension, called
//! with `D = 3`: the stress stage fused with the scatter of the internal force
//! ([`super::stress::stage`] through [`super::stress::Dim<3>`], the 3D Hencky J2 update),
//! the force gather fused with the predictor, the corrector and the update with the
//! step's energy sums ([`super::update`]), the energy account and its check
//! ([`super::energy`]), the step's length ([`super::stable_step`]) and the Lanczos
//! critical step ([`super::critical_step`]); shape functions, cell rules and lattices are
//! [`crate::rk_shape`] and [`crate::integration`] in three dimensions, and the contact law
//! is [`crate::contact::sidibe2009`]'s. What only 3D has is here: the setup of a box or a
//! cylinder (`setup.rs`), the contact of the tools (planes and triangle surfaces from STL
//! files, [`crate::solid_tool`]) and symmetry planes (`contact.rs`) and the readings of a
//! 3D body.
//!
//! Heat in 3D is 2D's: the stress stage's heating of each point by its plastic work
//! ([`super::heat`]) and its elasticity over temperature (the modulus factor and the
//! thermal strain of `[thermal]`, the shared material update), the friction work the
//! contact stage books at each particle (`contact.rs`, `crate::contact::slip_work`), and
//! when the scene's heat moves or friction makes heat the heat stage
//! ([`super::conduction`], generic over the dimension; the surface of the hexahedral cells
//! in `heat.rs`): conduction, the friction heat's share into the particles, the heat to the
//! tools (planes and triangle surfaces) and the surroundings. Mass
//! scaling, uniform or selective, is 2D's ([`super::mass_scaling`]). SCNI integrates a box
//! over its particles' nodal domains ([`crate::integration::point_shapes`], the 2D code in
//! three dimensions) and a cylinder over the O-grid's
//! ([`crate::cylinder_grid::CylinderGrid::nodal_domains`], smoothed by the same
//! [`crate::integration::smoothed`]). Kernel re-referencing is `rereference.rs` (the
//! temperature field carried as in 2D). Die fill (`fill.rs`: 2D's test on the surface
//! particles) and what the dies feel (`die_contact.rs`: each tool's contact area on the
//! surface patches, its share of the surface, the pressure over an STL die's triangles or
//! a plane's contact patch) are read from the state. Self-contact and its laps are
//! `self_contact.rs` ([`crate::contact::self_contact_3d`] over the cells' outer faces). SCNI's
//! stabilization (`discretization.scni_stabilization`) is 2D's
//! ([`super::nodal_stabilization`]) over the octants of the nodal domains: the box's cut
//! through their centroids ([`crate::integration::orthant_shapes`]), the cylinder's the
//! cells' octants they are made of ([`crate::cylinder_grid::CylinderGrid::octant_domains`]).
//! The tools'
//! convex edges and vertices meet the surface between the particles in the contact
//! stage's second pass (`ridges.rs`), opt-in per die (`ridges = true`).

mod contact;
mod die_contact;
#[cfg(test)]
mod feedback_tests;
mod fill;
mod heat;
mod rereference;
#[cfg(test)]
mod ridge_tests;
mod ridges;
mod self_contact;
mod setup;
#[cfg(test)]
mod tests;
mod volume;

use super::detachment::{Body, Isolation};
use super::discretization::{MassScalingReport, Thermal};
use super::energy::{Energy, StepEnergy};
use super::fields::{smoothed, Smoothing};
use super::heat::Heat;
use super::heat_readings;
use super::layout::Scatter;
use super::mass_scaling::Target;
use super::nodal_stabilization::{self, Forces, Tables};
use super::penetration::CROSSING_TOLERANCE_SPACINGS;
use super::point_outputs::PointOut;
use super::quasi_static;
use super::simulation::{stepping_loop, Ran, StageTimes, Stepping};
use super::stable_step;
use super::state::Filled;
use super::stress::{self, has_avx2, Inputs};
use super::update::{self, Motion, Predictor};
use crate::contact::self_contact_3d::{Crossing, Crossings};
use crate::error::{Error, Result};
use crate::laps::{SolidLap, SolidLapReport};
use crate::material::{HenckyJ2, PointState3};
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::scene::solid::SolidScene;
use crate::solid_tool::{SolidTool, SolidToolState};
use crate::team::Team;
use contact::ToolContact;
pub use die_contact::DiePressure;
pub use rereference::SolidReference;
use self_contact::{SelfStage, SolidSelfContact};
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// The measures of a 3D workpiece from its particles' physical positions
/// ([`SolidSimulation::readings`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyReadings {
    /// The largest distance of a particle from the z axis (m).
    pub radius: Real,
    /// `[min, max]` of x, y and z over the particles (m).
    pub extents: [[Real; 2]; 3],
}

impl BodyReadings {
    /// The readings of particles at `positions` (m).
    pub fn of(positions: &[[Real; 3]]) -> BodyReadings {
        let mut extents = [[Real::INFINITY, Real::NEG_INFINITY]; 3];
        let mut radius: Real = 0.0;
        for p in positions {
            radius = radius.max((p[0] * p[0] + p[1] * p[1]).sqrt());
            for (e, &x) in extents.iter_mut().zip(p) {
                *e = [e[0].min(x), e[1].max(x)];
            }
        }
        BodyReadings { radius, extents }
    }

    /// The length along z, `z_max - z_min` (m).
    pub fn height(&self) -> Real {
        self.extents[2][1] - self.extents[2][0]
    }
}

/// What setup fixes of a 3D simulation; the stages read it.
#[derive(Debug, Clone)]
pub(super) struct SolidDisc {
    material: HenckyJ2,
    /// Reference particle positions `X_I` (m): the start's, or the last kernel
    /// re-reference's.
    ref_pos: Vec<[Real; 3]>,
    /// The particles' positions at the start (m), which a warning names them by.
    original: Vec<[Real; 3]>,
    /// Particle volumes (m^3).
    volumes: Vec<Real>,
    /// Row-sum lumped masses `m_I` (kg) and their inverses.
    mass: Vec<Real>,
    inv_mass: Vec<Real>,
    /// Integration point positions (m) and weights `w_p` (m^3).
    point_positions: Vec<[Real; 3]>,
    weights: Vec<Real>,
    /// What the stress stage reads of 2D bodies, neutral in 3D: `1 / R_p` (zeros) and
    /// `J` at the last re-reference (ones).
    inv_radius: Vec<Real>,
    reference_jacobian: Vec<Real>,
    /// The point shape functions in the stress stage's layout.
    scatter: Scatter<3>,
    /// The octant gradients of the stabilized nodal integration, when the scene asks for
    /// it ([`super::nodal_stabilization`]).
    stabilization: Option<Tables<3>>,
    /// `N_I(X_J)` in row `J` (no gradients).
    nodal: ShapeTable<3>,
    /// Mean number of particles whose shape functions reach a point (-): what a point's
    /// gather and scatter cost.
    neighbours: Real,
    /// `S_J = sum_I |N_I(X_J)|` (-), the contact's move bound.
    sum_abs: Vec<Real>,
    /// Smallest particle spacing (m).
    h_min: Real,
    /// Each particle's distance at the start to the nearest other particle of its row of
    /// `nodal` (m): the scale of the isolation watch ([`crate::solver::detachment`]).
    initial_spacing: Vec<Real>,
    /// Critical step of the undeformed discretisation (s).
    critical_dt0: Real,
    /// Hexahedral cells of 8 particles (for the frames).
    cells: Vec<[u32; 8]>,
    /// The scene's tools come first among the planes, the symmetry planes after them.
    scene_tools: usize,
    /// The heat settings of a scene with `[thermal]` (a transfer when its heat moves).
    thermal: Option<Thermal>,
    /// The surface heat crosses, the friction laws that need a flow stress take their
    /// contact area on and the tools' ridges meet between the particles (empty unless the
    /// scene's heat moves, a tool has such a law or a die has ridges).
    heat_surface: heat::HeatSurface,
    /// The points reaching each particle, for the flow stress at a particle in contact
    /// (empty unless a friction law needs one).
    flow_smoothing: Smoothing,
    /// What mass scaling added, if the scene scales ([`super::mass_scaling`]).
    mass_scaling: Option<MassScalingReport>,
    /// What selective mass scaling holds at each kernel re-reference.
    scaling_target: Option<Target>,
    /// The points are the particles' (SCNI: one per nodal domain, in particle order), not
    /// the cells'.
    nodal_points: bool,
    /// Each particle's cell extents at the start (m): the supports over
    /// `discretization.support`, the cell a re-reference deforms.
    extents: Vec<[Real; 3]>,
    /// The stress stage measures the largest principal stretch (the scene re-references).
    track_stretch: bool,
}

/// Everything that changes during a 3D run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolidState {
    /// Steps taken.
    pub step: u64,
    /// Time (s).
    pub time: Real,
    /// Length of the last step (s), 0 before the first.
    pub dt_prev: Real,
    /// RK coefficients of the displacement `d_I` (m).
    pub d: Vec<[Real; 3]>,
    /// Coefficient velocities at the last half step (m/s).
    pub v: Vec<[Real; 3]>,
    /// Integration point histories.
    pub points: Vec<PointState3>,
    /// The planes' states: the scene's tools, then the symmetry planes.
    pub tools: Vec<SolidToolState>,
    /// Energy account (J).
    pub energy: Energy,
    /// Which particles are held on which plane without separation (`[particle * planes +
    /// plane]`).
    pub held: Vec<bool>,
    /// The friction force carried for each particle on each plane (N), `None` out of
    /// contact.
    pub stick: Vec<Option<[Real; 3]>>,
    /// Deepest a particle's physical position lay inside a tool at a sample (m).
    pub max_penetration: Real,
    /// Deepest a particle's physical position lay beyond a symmetry plane at a sample (m).
    pub max_beyond_plane: Real,
    /// Largest collective feedback of the penalty of a plane or tool without separation
    /// over the particles it held (-; [`crate::contact::penalty_feedback`]).
    #[serde(default)]
    pub plane_feedback_max: Real,
    /// When a scene's tool first pressed the workpiece (s), for the quasi-static watch.
    pub first_contact_s: Option<Real>,
    /// Largest ratio of kinetic to internal energy since the watch began (-).
    pub kinetic_to_internal_max: Real,
    /// Stable step estimate on the deformation (s).
    pub stable_dt: Real,
    /// Time (s) and step count at the last step that was not a full fixed step.
    pub anchor_time: Real,
    /// Step count at `anchor_time`.
    pub anchor_step: u64,
    /// The points' temperatures and plastic work in a scene with `[thermal]`.
    pub heat: Option<Heat>,
    /// Largest principal stretch of a point since the last reference (-), when the scene
    /// re-references.
    #[serde(default)]
    pub max_stretch: Real,
    /// The configuration of the last kernel re-reference, if there was one.
    #[serde(default)]
    pub reference: Option<SolidReference>,
    /// When each fill point of the scene's tools was reached, tool by tool in scene order
    /// (2D's `State::fill`).
    #[serde(default)]
    pub fill: Vec<Option<Filled>>,
    /// The normal contact forces of the last contact stage on the scene tools, one per
    /// particle and tool in contact, in the stage's order (the pressure on the dies).
    #[serde(default)]
    pub pressed: Vec<Pressed>,
    /// Which surface particles were in contact with the surface at the last stage, by slot
    /// ([`crate::contact::self_contact_3d`]; all false when the scene turns it off).
    #[serde(default)]
    pub self_touching: Vec<bool>,
    /// The laps (folds of the surface onto itself) found so far, in the order they formed.
    #[serde(default)]
    pub laps: Vec<SolidLap>,
    /// Most crossings of the surface's faces within the kernel's support of each other at
    /// a sample (0: no fold's root passed through itself;
    /// [`crate::contact::self_contact_3d::Surface::fold_crossings`]).
    #[serde(default)]
    pub max_fold_crossings: u32,
    /// The first sample at which a fold's root passed through itself: its time (s) and its
    /// first crossing.
    #[serde(default)]
    pub first_fold_crossing: Option<(Real, Crossing)>,
    /// The particles' isolation at the samples, and the first that left the body
    /// ([`crate::solver::detachment`]).
    #[serde(default)]
    pub isolation: Isolation,
}

/// The normal contact force of one particle on one scene tool at a contact stage.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pressed {
    /// The particle.
    pub particle: u32,
    /// The scene tool.
    pub tool: u32,
    /// The normal part of the contact force `f_J` on the particle, `f_J . n` (N), positive
    /// pressing (the stage adds it to the tool's `normal_force`).
    pub force_n: Real,
    /// The contact normal, out of the tool towards the particle.
    pub normal: [Real; 3],
}

/// The stages' working arrays.
#[derive(Debug, Clone)]
pub(super) struct SolidWorkspace {
    out: Vec<PointOut>,
    buf: Vec<[Real; 3]>,
    f_int: Vec<[Real; 3]>,
    v_prev: Vec<[Real; 3]>,
    contact: ToolContact,
    self_contact: SolidSelfContact,
    /// The stabilization's octant stresses and force ([`super::nodal_stabilization`]).
    stabilization: Option<Forces<3>>,
    team: Team,
}

/// A running 3D simulation.
#[derive(Debug, Clone)]
pub struct SolidSimulation {
    scene: SolidScene,
    disc: SolidDisc,
    tools: Vec<SolidTool>,
    st: SolidState,
    ws: SolidWorkspace,
    /// Wall time per stage since setup.
    pub times: StageTimes,
}

/// The smallest stable step, as a fraction of the undeformed body's, a 3D run goes on
/// with: below it a cell has been crushed to a thousandth of its height, and the run would
/// crawl on at ever shorter steps instead of stopping with a diagnosis (a quarter Taylor bar
/// at 2000 m/s on cells 4,2,30 took over 7 minutes of steps before it was stopped).
const CRUSHED: Real = 1e-3;

/// Runs `f`, adding its wall time to `into`.
fn timed<T>(into: &mut Duration, f: impl FnOnce() -> T) -> T {
    let t0 = Instant::now();
    let r = f();
    *into += t0.elapsed();
    r
}

/// Stage 1: the stress stage ([`stress::stage`] with `D = 3`) on the points of `disc` with
/// the coefficients of `st`, its buffers in `ws`, heating each point adiabatically in a
/// scene with `[thermal]` (`dT_p = beta dW_p / (rho_0 c)`, [`super::heat::Heating`]) and, with
/// elasticity over temperature, booking the elastic energy its change of temperature put
/// in (`Energy::thermoelastic`, J; the 2D stage's); sets the stable
/// step estimate `dt_crit0 a_min` from the smallest deformed cell altitude `a_min` of a
/// unit cell (-); returns the elastic and plastic energy (J). A point whose update fails
/// stops the run naming it, and the scene's fixed step `fixed` (`time.dt_s`, s) when the
/// last step ran above the estimate ([`stable_step::above_estimate`]).
fn stress_stage(
    disc: &SolidDisc,
    st: &mut SolidState,
    ws: &mut SolidWorkspace,
    fixed: Option<Real>,
) -> Result<(Real, Real)> {
    let input = Inputs {
        d: &st.d,
        material: &disc.material,
        weights: &disc.weights,
        inv_radius: &disc.inv_radius,
        reference_jacobian: &disc.reference_jacobian,
        track_stretch: disc.track_stretch,
        axi: false,
        spacing: [1.0; 3],
        avx2: has_avx2(),
        heating: stress::heating(disc.thermal.as_ref(), st.heat.as_ref(), st.dt_prev),
    };
    let sums = stress::stage(
        &ws.team,
        &disc.scatter,
        &mut ws.buf,
        &input,
        &mut st.points,
        &mut ws.out,
        stress::heat_slices(st.heat.as_mut()),
    )
    .map_err(|(p, m)| Error::Diverged {
        step: st.step,
        time: st.time,
        what: format!(
            "integration point {p} (reference position {:?} m): {m}{}",
            disc.point_positions[p],
            stable_step::above_estimate(fixed, st.dt_prev, st.stable_dt)
        ),
    })?;
    st.stable_dt = disc.critical_dt0 * sums.min_altitude;
    st.max_stretch = sums.max_stretch;
    st.energy.thermoelastic += sums.thermoelastic;
    st.energy.thermoelastic_abs += sums.thermoelastic.abs();
    let stabilization = match (&disc.stabilization, &mut ws.stabilization) {
        (Some(t), Some(s)) => nodal_stabilization::stage(&ws.team, t, s, &st.d, input.avx2),
        _ => 0.0,
    };
    Ok((sums.elastic + stabilization, sums.plastic))
}

/// Stage 3: the force gather into `ws.f_int` (N), fused with the predictor on `st.v` when
/// `step` is given (recording the move bound `dt V*` for the contact stage).
fn gather(
    disc: &SolidDisc,
    st: &mut SolidState,
    ws: &mut SolidWorkspace,
    step: Option<stable_step::StepLength>,
) {
    let predictor = step.map(|s| Predictor {
        dt_avg: s.avg,
        v: &mut st.v,
        v_prev: &mut ws.v_prev,
        inv_mass: &disc.inv_mass,
        track: true,
    });
    let speed = update::gather_forces(
        &ws.team,
        &disc.scatter,
        &ws.buf,
        ws.stabilization.as_ref().map(|s| &s.force[..]),
        &mut ws.f_int,
        predictor,
    );
    if let Some(s) = step {
        ws.contact.predicted_move(s.full * speed);
    }
}

impl Stepping for SolidSimulation {
    fn now(&self) -> Real {
        self.st.time
    }
    fn step_at_most(&mut self, max_dt: Option<Real>) -> Result<()> {
        self.step(max_dt)
    }
}

impl SolidSimulation {
    /// One central-difference step, at most `max_dt` long (s), the 2D step's stages in the
    /// 2D order ([`super::Simulation::step`]): stress, step length, force gather and
    /// predictor, contact (the planes advance, penalty forces), corrector and the friction
    /// carried, update with the energy sums, energy account and clock, and its check; the
    /// heat stage when due.
    ///
    /// # Errors
    ///
    /// A point's update failed, a velocity is not finite, the energy balance does not
    /// close, or a tool is too fast for the step: each named.
    pub fn step(&mut self, max_dt: Option<Real>) -> Result<()> {
        let SolidSimulation {
            scene,
            disc,
            tools,
            st,
            ws,
            times,
        } = self;
        rereference::if_due(scene, disc, st, ws)?;
        let tool_dt = stable_step::tool_limit(
            &scene.time,
            tools,
            st.step,
            st.time,
            st.stable_dt,
            disc.h_min,
        )?;
        let (elastic, plastic) = timed(&mut times.stress, || {
            stress_stage(disc, st, ws, scene.time.dt_s)
        })?;
        if st.stable_dt < CRUSHED * disc.critical_dt0 {
            return Err(Error::Diverged {
                step: st.step,
                time: st.time,
                what: format!(
                    "the stable step fell to {:.3e} s, below {CRUSHED} of the undeformed body's {:.3e} s: a cell is crushed to less than {CRUSHED} of its height, more than this grid and its Lagrangian kernel can follow (an impact too fast, or a grid too coarse for the flow); refine the grid or lower the speed",
                    st.stable_dt, disc.critical_dt0
                ),
            });
        }
        let step = stable_step::length(&scene.time, st.stable_dt, st.dt_prev, tool_dt, max_dt)?;
        let dt = step.dt;
        timed(&mut times.internal_force, || {
            gather(disc, st, ws, Some(step))
        });
        let touch = timed(&mut times.contact, || {
            let t_mid = st.time + 0.5 * dt;
            for t in tools.iter_mut() {
                t.state.velocity = t.velocity_at(t_mid);
                t.state.stroke += dt * t.state.velocity;
            }
            let at_end: Vec<Real> = tools.iter().map(|t| t.state.stroke).collect();
            for t in tools.iter_mut() {
                t.state.stroke += (step.full - dt) * t.state.velocity;
            }
            let mut touch = ws.contact.stage(&ws.team, disc, tools, st, &ws.out, step);
            for t in tools.iter_mut() {
                let f = t.axial_force();
                t.state.account.book(f, t.state.velocity, step.avg);
            }
            let on_itself = SelfStage {
                tools: &tools[..disc.scene_tools],
                out: &ws.out,
                du: ws.contact.move_bound(),
                dt: step.full,
                dt_avg: step.avg,
            };
            touch.any |= ws
                .self_contact
                .stage(disc, st, &mut ws.contact.force, &on_itself);
            for (t, s) in tools.iter_mut().zip(at_end) {
                t.state.stroke = s;
            }
            touch
        });
        timed(&mut times.integration, || -> Result<()> {
            if touch.any {
                update::correct_velocities(&mut st.v, &ws.contact.force, &disc.inv_mass, step.avg);
                ws.contact.carry(disc, tools, st, step.avg);
            }
            let motion = Motion {
                v: &st.v,
                mass: &disc.mass,
                f_int: &ws.f_int,
            };
            let mut u = update::update(&ws.team, &mut st.d, &motion, dt, true);
            if touch.any {
                u.contact_work =
                    update::contact_work(&st.v, &ws.v_prev, &ws.contact.force, step.avg);
            }
            ws.contact.updated_move(dt * u.largest_speed);
            if !u.kinetic.is_finite() {
                let i =
                    st.v.iter()
                        .position(|v| !v.iter().all(|x| x.is_finite()))
                        .unwrap_or(0);
                return Err(Error::Diverged {
                    step: st.step,
                    time: st.time,
                    what: format!(
                        "velocity of particle {i} at {:?} m is not finite{}",
                        disc.ref_pos[i],
                        stable_step::above_estimate(scene.time.dt_s, dt, st.stable_dt)
                    ),
                });
            }
            st.energy.add_step(StepEnergy {
                kinetic: u.kinetic,
                elastic,
                plastic,
                contact_work: u.contact_work,
                tool_work: touch.tool_work,
                internal_half_step: u.half_step,
            });
            st.step += 1;
            match scene.time.dt_s {
                Some(fixed) if dt == fixed => {
                    st.time = st.anchor_time + (st.step - st.anchor_step) as Real * fixed;
                }
                _ => {
                    st.time += dt;
                    st.anchor_time = st.time;
                    st.anchor_step = st.step;
                }
            }
            st.dt_prev = dt;
            for (t, s) in tools.iter().zip(st.tools.iter_mut()) {
                *s = t.state;
            }
            if touch.any {
                fill::check(scene, disc, tools, st);
            }
            st.energy.check(
                scene.checks.energy_balance_tol,
                st.step,
                st.time,
                dt,
                st.stable_dt,
                scene.time.dt_s,
            )?;
            quasi_static::watch(
                &scene.checks,
                scene.time.end_s,
                scene.tools.is_empty(),
                st,
                touch.tools,
            )
        })?;
        timed(&mut times.heat, || {
            heat::stage_if_due(scene, disc, tools, st, &mut ws.out, dt)
        })
    }

    /// Step toward `t_end` (s), the last step shortened to land on it, taking at most
    /// `max_steps` steps; `between(sim, taken)` is called before each step and returns
    /// `false` to stop there (the 2D loop, [`super::Simulation::run_toward`]).
    ///
    /// # Errors
    ///
    /// A step failed (see [`SolidSimulation::step`]).
    pub fn run_toward(
        &mut self,
        t_end: Real,
        max_steps: u64,
        between: impl FnMut(&mut SolidSimulation, u64) -> bool + Send,
    ) -> Result<Ran> {
        stepping_loop(self, t_end, max_steps, between)
    }

    /// The scene being run.
    pub fn scene(&self) -> &SolidScene {
        &self.scene
    }
    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.disc.ref_pos.len()
    }
    /// Number of integration points.
    pub fn point_count(&self) -> usize {
        self.disc.point_positions.len()
    }
    /// Time (s).
    pub fn time(&self) -> Real {
        self.st.time
    }
    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.st.step
    }
    /// The whole changing state.
    pub fn state(&self) -> &SolidState {
        &self.st
    }
    /// Energy account (J).
    pub fn energy(&self) -> Energy {
        self.st.energy
    }
    /// Restore a state saved from a simulation of the same scene ([`SolidSimulation::state`]):
    /// stepping on from it gives the bits the saved run gave.
    ///
    /// # Errors
    ///
    /// The state belongs to another discretisation (its arrays have other lengths).
    pub fn restore(&mut self, st: SolidState) -> Result<()> {
        let same = st.d.len() == self.st.d.len()
            && st.v.len() == self.st.v.len()
            && st.points.len() == self.st.points.len()
            && st.tools.len() == self.st.tools.len()
            && st.held.len() == self.st.held.len()
            && st.stick.len() == self.st.stick.len()
            && st.fill.len() == self.st.fill.len()
            && (st.self_touching.len() == self.st.self_touching.len()
                || st.self_touching.is_empty())
            && st.heat.is_some() == self.st.heat.is_some();
        if !same {
            return Err(Error::State(
                "the saved state belongs to another discretisation".into(),
            ));
        }
        if st.reference != self.st.reference {
            match &st.reference {
                Some(r) => {
                    rereference::install(&self.scene, &mut self.disc, &mut self.st, &mut self.ws, r)
                        .map(|_| ())?
                }
                None => {
                    let fresh = SolidSimulation::new(&self.scene)?;
                    self.disc = fresh.disc;
                    self.ws.buf = fresh.ws.buf;
                }
            }
        }
        for (t, s) in self.tools.iter_mut().zip(&st.tools) {
            t.state = *s;
        }
        self.ws.v_prev.clone_from(&st.v);
        self.ws.contact = ToolContact::new(st.d.len(), self.tools.len());
        self.ws.self_contact.forget();
        // A state saved before self-contact in 3D has no surface contacts: none.
        let mut st = st;
        st.self_touching.resize(self.st.self_touching.len(), false);
        for (p, (out, point)) in self.ws.out.iter_mut().zip(&st.points).enumerate() {
            let temp = st.heat.as_ref().map(|h| h.temperature_c[p]);
            *out = PointOut::at(&self.disc.material, point.eps_p, temp);
        }
        self.st = st;
        Ok(())
    }
    /// Bytes held by the discretisation, the state and the stages' arrays (an estimate from
    /// the lengths of its arrays, as [`super::Simulation::memory_bytes`]).
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        let (d, st, ws) = (&self.disc, &self.st, &self.ws);
        let r3 = size_of::<[Real; 3]>();
        let (np, npts) = (d.ref_pos.len(), d.point_positions.len());
        let nodal = (d.nodal.offsets.len() + d.nodal.index.len()) * 4 + d.nodal.n.len() * 8;
        let heat = st.heat.as_ref().map_or(0, |h| {
            (h.temperature_c.len() + h.plastic_work.len() + h.plastic_rate.len()) * 8
        });
        nodal
            + d.scatter.memory_bytes()
            + ws.buf.len() * r3
            // reference and initial positions, d, v, f_int, v_prev; volumes, masses and
            // their inverses, the move bounds, the initial spacings
            + np * (6 * r3 + 5 * 8)
            // positions, weights, 1/R, J_ref; histories and outputs
            + npts * (r3 + 3 * 8 + size_of::<PointState3>() + size_of::<PointOut>())
            + st.held.len() * size_of::<bool>()
            + st.stick.len() * size_of::<Option<[Real; 3]>>()
            + st.pressed.len() * size_of::<Pressed>()
            + st.fill.len() * size_of::<Option<Filled>>()
            + st.self_touching.len() * size_of::<bool>()
            + d.cells.len() * size_of::<[u32; 8]>()
            + d.stabilization.as_ref().map_or(0, |t| t.memory_bytes())
            + ws.stabilization.as_ref().map_or(0, |s| s.memory_bytes())
            + heat
    }
    /// Mean number of particles whose shape functions reach an integration point (-).
    pub fn neighbours_per_point(&self) -> Real {
        self.disc.neighbours
    }
    /// Smallest particle spacing (m).
    pub fn h_min(&self) -> Real {
        self.disc.h_min
    }
    /// Critical step of the undeformed discretisation (s), with the scaled masses in a
    /// scene with mass scaling.
    pub fn critical_dt0(&self) -> Real {
        self.disc.critical_dt0
    }
    /// What mass scaling added, `None` without it.
    pub fn mass_scaling(&self) -> Option<MassScalingReport> {
        self.disc.mass_scaling
    }

    /// Largest ratio of the workpiece's kinetic to internal energy (-) since the
    /// quasi-static watch began (`checks.kinetic_to_internal_from`); 0 before.
    pub fn kinetic_to_internal_max(&self) -> Real {
        self.st.kinetic_to_internal_max
    }

    /// A warning when a mass-scaled run's inertia was not negligible, as in 2D
    /// ([`quasi_static::warning`]).
    pub fn quasi_static_warning(&self) -> Option<String> {
        quasi_static::warning(
            self.disc.mass_scaling.is_some(),
            self.st.kinetic_to_internal_max,
        )
    }
    /// The smallest factor the contact put on the penalty of a plane or tool without
    /// separation for its collective feedback (-, 1 when none passed the limit;
    /// [`crate::contact::penalty_feedback`]).
    pub fn plane_penalty_scale_min(&self) -> Real {
        crate::contact::penalty_feedback::scale(self.st.plane_feedback_max)
    }
    /// Stable step estimate on the current deformation (s).
    pub fn stable_dt(&self) -> Real {
        self.st.stable_dt
    }
    /// Lumped masses (kg).
    pub fn masses(&self) -> &[Real] {
        &self.disc.mass
    }
    /// Particle volumes (m^3).
    pub fn volumes(&self) -> &[Real] {
        &self.disc.volumes
    }
    /// Particle positions of the undeformed workpiece (m).
    pub fn reference_positions(&self) -> &[[Real; 3]] {
        &self.disc.ref_pos
    }
    /// The hexahedral cells of 8 particles.
    pub fn cells(&self) -> &[[u32; 8]] {
        &self.disc.cells
    }
    /// The scene's tools (the symmetry planes are not among them).
    pub fn tools(&self) -> &[SolidTool] {
        &self.tools[..self.disc.scene_tools]
    }
    /// Index of the scene tool named `name`.
    pub fn tool_index(&self, name: &str) -> Option<usize> {
        self.tools().iter().position(|t| t.name == name)
    }
    /// Set a scene tool's velocity along its axis (m/s) from outside, overriding the scene
    /// motion ([`crate::tools::command_velocity`]).
    ///
    /// # Errors
    ///
    /// No such tool, a fixed tool, or a velocity that is not finite.
    pub fn set_tool_velocity(&mut self, tool: usize, v: Real) -> Result<()> {
        let scene_tools = self.disc.scene_tools;
        crate::tools::command_velocity(&mut self.tools[..scene_tools], tool, v)
    }
    /// The symmetry planes.
    pub fn symmetry_planes(&self) -> &[SolidTool] {
        &self.tools[self.disc.scene_tools..]
    }
    /// Physical particle positions `X_J + sum_I N_I(X_J) d_I` (m).
    pub fn positions(&self) -> Vec<[Real; 3]> {
        (0..self.disc.ref_pos.len())
            .map(|j| {
                let u = self.disc.nodal.interpolate(j, &self.st.d);
                std::array::from_fn(|k| self.disc.ref_pos[j][k] + u[k])
            })
            .collect()
    }
    /// Physical particle velocities `sum_I N_I(X_J) v_I` (m/s) at the last half step.
    pub fn velocities(&self) -> Vec<[Real; 3]> {
        (0..self.disc.ref_pos.len())
            .map(|j| self.disc.nodal.interpolate(j, &self.st.v))
            .collect()
    }
    /// Physical displacements `x_J - X_J = sum_I N_I(X_J) d_I` of the particles (m).
    pub fn displacements(&self) -> Vec<[Real; 3]> {
        (0..self.disc.ref_pos.len())
            .map(|j| self.disc.nodal.interpolate(j, &self.st.d))
            .collect()
    }
    /// The mean over each hexahedral cell of a value per point: over the cell's
    /// integration points (stored cell by cell, [`SolidSimulation::cells`] order), or with
    /// SCNI, whose points are the particles', over its eight corners.
    pub fn cell_means(&self, per_point: &[Real]) -> Vec<Real> {
        if self.disc.nodal_points {
            return self
                .disc
                .cells
                .iter()
                .map(|c| c.iter().map(|&j| per_point[j as usize]).sum::<Real>() / 8.0)
                .collect();
        }
        let per_cell = (per_point.len() / self.disc.cells.len().max(1)).max(1);
        per_point
            .chunks(per_cell)
            .map(|c| c.iter().sum::<Real>() / c.len() as Real)
            .collect()
    }
    /// A value per integration point smoothed to each particle, as the 2D particle fields
    /// are ([`super::Simulation::fields`]): the mean of the values of the points whose
    /// shape functions reach the particle, each weighted by `|N_I(x_p)| w_p` (`w_p` the
    /// point's weight, m^3), so a particle reads the points around it in proportion to how
    /// much of them it carries; 0 at a particle no point reaches. In the unit of the value.
    pub fn particle_means(&self, per_point: &[Real]) -> Vec<Real> {
        smoothed(
            &self.disc.scatter,
            &self.disc.weights,
            self.disc.ref_pos.len(),
            per_point,
        )
    }
    /// Equivalent plastic strain at each integration point (-).
    pub fn point_plastic_strain(&self) -> Vec<Real> {
        self.st.points.iter().map(|p| p.eps_p).collect()
    }
    /// Reference volume weights `w_p` of the integration points (m^3).
    pub fn point_weights(&self) -> &[Real] {
        &self.disc.weights
    }
    /// Integration point positions in the reference configuration (m).
    pub fn point_positions(&self) -> &[[Real; 3]] {
        &self.disc.point_positions
    }
    /// The configuration the kernel was last re-referenced on, if it was
    /// (`discretization.rereference_stretch`).
    pub fn reference(&self) -> Option<&SolidReference> {
        self.st.reference.as_ref()
    }
    /// Re-references the kernel now, on the positions of the current displacement
    /// (`rereference.rs`); a run does it itself when `discretization.rereference_stretch`
    /// is reached.
    ///
    /// # Errors
    ///
    /// The shape functions cannot be formed on the deformed particles.
    pub fn rereference(&mut self) -> Result<()> {
        rereference::now(&self.scene, &mut self.disc, &mut self.st, &mut self.ws)
    }
    /// `J = det F` at each integration point after the last stress stage (-).
    pub fn point_jacobian(&self) -> Vec<Real> {
        self.ws.out.iter().map(|o| o.jacobian).collect()
    }
    /// The largest equivalent plastic strain of the points (-).
    pub fn max_plastic_strain(&self) -> Real {
        self.st.points.iter().map(|p| p.eps_p).fold(0.0, Real::max)
    }
    /// Plastic strain rate of each point at the last stress stage (1/s), `None` for an
    /// isothermal scene.
    pub fn point_plastic_strain_rate(&self) -> Option<&[Real]> {
        self.st.heat.as_ref().map(|h| &h.plastic_rate[..])
    }
    /// The points' temperatures (degrees C), `None` for an isothermal scene.
    pub fn point_temperature(&self) -> Option<&[Real]> {
        self.st.heat.as_ref().map(|h| &h.temperature_c[..])
    }
    /// The thermal measures now, `None` for an isothermal scene, as the 2D run's
    /// ([`super::Simulation::thermal_values`], named by [`crate::THERMAL_MEASURES`]): the
    /// heat to the tools and the surroundings from the heat stage, the friction heat the
    /// heat stage took in (the workpiece's share `thermal.friction_heat_to_workpiece` of it
    /// in the balance, as in 2D).
    pub fn thermal_values(&self) -> Option<[Real; 9]> {
        let (heat, th) = (self.st.heat.as_ref()?, self.disc.thermal.as_ref()?);
        let w = &self.disc.weights;
        Some(heat_readings::measures(
            heat_readings::temperatures(&heat.temperature_c, w),
            heat_readings::plastic_heat(&th.spec, heat, w),
            heat.friction_heat_j,
            th.spec.friction_heat_to_workpiece,
            heat_readings::heat_content(th, heat, w),
            &heat.to_tools_j,
            heat.to_surroundings_j,
        ))
    }
    /// Heat that has flowed into scene tool `k` since the start (J), `None` for an
    /// isothermal scene.
    pub fn tool_heat(&self, k: usize) -> Option<Real> {
        self.st.heat.as_ref().map(|h| h.to_tools_j[k])
    }
    /// Heat flow into each scene tool at the last heat stage (W), `None` for an isothermal
    /// scene.
    pub fn tool_heat_flows(&self) -> Option<&[Real]> {
        self.st.heat.as_ref().map(|h| &h.tool_flow_w[..])
    }
    /// Time of the temperatures' conduction and surface flows (s): the last heat stage's,
    /// up to one heat step before [`SolidSimulation::time`] (plastic heating is up to date).
    pub fn heat_time(&self) -> Real {
        self.st.time - self.st.heat.as_ref().map_or(0.0, |h| h.since_s)
    }
    /// The particles' temperatures (degrees C) the heat stage conducts, `None` unless the
    /// scene's heat moves.
    pub fn particle_temperature(&self) -> Option<&[Real]> {
        self.st
            .heat
            .as_ref()
            .filter(|h| !h.particle_c.is_empty())
            .map(|h| &h.particle_c[..])
    }
    /// Mises stress at each integration point after the last stress stage (Pa).
    pub fn point_von_mises(&self) -> Vec<Real> {
        self.ws.out.iter().map(|o| o.von_mises).collect()
    }

    /// The workpiece's measures from the physical positions of all particles (m), as the
    /// 2D run's `workpiece.*` ([`super::Simulation::extents`]): the largest distance from
    /// the z axis `sqrt(x^2 + y^2)` (a Taylor bar's foot radius) and the bounds of each
    /// coordinate, `[[x_min, x_max], [y_min, y_max], [z_min, z_max]]`; the length along z is
    /// `z_max - z_min` (a bar that has left the wall is measured, not its flight).
    pub fn readings(&self) -> BodyReadings {
        BodyReadings::of(&self.positions())
    }

    /// The deepest physical particle position inside a scene tool and beyond a symmetry
    /// plane now (m), over every particle (the truth the contact's own checks cannot see),
    /// each with the particle and the plane: `[tools, symmetry planes]` as `(depth,
    /// particle, plane)`, depth 0 when none lies inside.
    pub fn penetration_now(&self) -> [(Real, usize, usize); 2] {
        self.penetration_at(&self.positions())
    }

    /// [`SolidSimulation::penetration_now`] with the particles at `positions` (m).
    pub fn penetration_at(&self, positions: &[[Real; 3]]) -> [(Real, usize, usize); 2] {
        let mut worst = [(0.0 as Real, 0usize, 0usize); 2];
        for (j, p) in positions.iter().enumerate() {
            for (t, plane) in self.tools.iter().enumerate() {
                let depth = plane.inside_by(*p);
                let w = &mut worst[plane.symmetry as usize];
                if depth > w.0 {
                    *w = (depth, j, t);
                }
            }
        }
        worst
    }

    /// The laps found so far ([`crate::laps::SolidLap`]), in the order they formed, with
    /// where their material is now.
    pub fn laps(&self) -> Vec<SolidLapReport> {
        if self.st.laps.is_empty() {
            return Vec::new();
        }
        self.ws.self_contact.laps(&self.st, &self.positions())
    }

    /// How many laps formed so far.
    pub fn lap_count(&self) -> usize {
        self.st.laps.len()
    }

    /// The deepest a surface particle's physical position has passed through another part
    /// of the workpiece's surface now, whether the scene's self-contact is on or off
    /// ([`crate::contact::self_contact_3d::Surface::passed_through`]): `(depth (m),
    /// particle)`, depth 0 when none has.
    pub fn self_penetration_now(&self) -> (Real, usize) {
        self.ws.self_contact.passed_through(&self.positions())
    }

    /// The crossings of the workpiece's surface's faces within the kernel's support of
    /// each other (a fold's root, which the self-contact leaves out) at the particles'
    /// physical positions `positions` (m), whether the scene's self-contact is on or off,
    /// with 2D's tolerance ([`CROSSING_TOLERANCE_SPACINGS`] smallest spacings;
    /// [`crate::contact::self_contact_3d::Surface::fold_crossings`]).
    pub fn fold_crossings_at(&self, positions: &[[Real; 3]]) -> Crossings {
        self.ws
            .self_contact
            .fold_crossings(positions, CROSSING_TOLERANCE_SPACINGS * self.disc.h_min)
    }

    /// Most crossings of faces within the support of each other at a sample (0: no fold's
    /// root passed through itself).
    pub fn max_fold_crossings(&self) -> u32 {
        self.st.max_fold_crossings
    }

    /// A warning when a fold's root passed through itself at a sample
    /// ([`SolidSimulation::fold_crossings_at`]), naming when and where it first did, how
    /// far apart those faces started and how long their longest edge is now: the contact
    /// holds nothing there, so the volume, the pictures and the laps are not to be trusted
    /// there.
    pub fn surface_warning(&self) -> Option<String> {
        let (time, c) = self.st.first_fold_crossing?;
        let h = self.disc.h_min;
        Some(format!(
            "the root of a fold passed through itself ({} crossings of faces within the kernel's support of each other at a sample at most; first at t = {time:.4e} s at ({:.3}, {:.3}, {:.3}) mm, between faces whose centres started {:.2} smallest spacings apart, their longest edge now {:.2} spacings): the self-contact leaves out the faces within {} cells of a particle in the undeformed body, so such a fold is neither held nor named a lap (a face stretched over several spacings is also a chord that can cut the surface where the material does not); look at the pictures there, and at a finer grid, on which a fold that outgrows the support is held and named a lap",
            self.st.max_fold_crossings,
            1e3 * c.at[0],
            1e3 * c.at[1],
            1e3 * c.at[2],
            c.apart / h,
            c.longest_edge / h,
            self.ws.self_contact.neighbours(),
        ))
    }

    /// A history sample's measures of the whole body over the particles' physical positions,
    /// formed once: every particle's isolation ([`crate::solver::detachment`]) and
    /// [`SolidSimulation::measure_penetration`], both recorded in the state. Returns the
    /// positions (m) with the depths in the tools and beyond the planes (m).
    ///
    /// # Errors
    ///
    /// The penetration bound is exceeded (the isolation is measured first).
    pub fn measure_sample(&mut self) -> (Vec<[Real; 3]>, Result<(Real, Real)>) {
        let positions = self.positions();
        self.measure_isolation(&positions);
        self.measure_crossings(&positions);
        let depths = self.measure_penetration_at(&positions);
        (positions, depths)
    }

    /// The fold crossings at `positions` (m, now), the most and the first recorded in the
    /// state.
    fn measure_crossings(&mut self, positions: &[[Real; 3]]) {
        let c = self.fold_crossings_at(positions);
        self.st.max_fold_crossings = self.st.max_fold_crossings.max(c.count as u32);
        if self.st.first_fold_crossing.is_none() {
            self.st.first_fold_crossing = c.first.map(|first| (self.st.time, first));
        }
    }

    /// Every particle's isolation with the particles at `positions` (m, now): its nearest
    /// integration point over that distance at the start, recorded in the state.
    fn measure_isolation(&mut self, positions: &[[Real; 3]]) {
        let d = &self.disc;
        let body = Body {
            scatter: &d.scatter,
            points: &d.point_positions,
            d: &self.st.d,
            particles: positions,
            nodal: d.nodal_points,
        };
        let time = self.st.time;
        self.st
            .isolation
            .measure_body(&body, &d.initial_spacing, time);
    }

    /// The warning of a run in which a particle left the body, naming it
    /// ([`crate::solver::detachment`]).
    pub fn detached_warning(&self) -> Option<String> {
        self.st.isolation.warning(&self.disc.original)
    }

    /// [`SolidSimulation::penetration_now`] recorded in the state's maxima; a depth past
    /// `checks.max_penetration_rel` smallest spacings inside a tool or beyond a plane stops
    /// the run naming the particle. Returns the depths in the tools and beyond the planes
    /// (m).
    ///
    /// # Errors
    ///
    /// The penetration bound is exceeded.
    pub fn measure_penetration(&mut self) -> Result<(Real, Real)> {
        self.measure_penetration_at(&self.positions())
    }

    /// [`SolidSimulation::measure_penetration`] with the particles at `positions` (m, now).
    fn measure_penetration_at(&mut self, positions: &[[Real; 3]]) -> Result<(Real, Real)> {
        let worst = self.penetration_at(positions);
        self.st.max_penetration = self.st.max_penetration.max(worst[0].0);
        self.st.max_beyond_plane = self.st.max_beyond_plane.max(worst[1].0);
        let bound = self.scene.checks.max_penetration_rel * self.disc.h_min;
        for (depth, j, t) in worst {
            if depth > bound {
                return Err(Error::Diverged {
                    step: self.st.step,
                    time: self.st.time,
                    what: format!(
                        "particle {j} (reference position {:?} m) lies {depth:.4e} m inside `{}`, more than checks.max_penetration_rel = {} smallest spacings ({bound:.4e} m)",
                        self.disc.ref_pos[j],
                        self.tools[t].name,
                        self.scene.checks.max_penetration_rel
                    ),
                });
            }
        }
        Ok((worst[0].0, worst[1].0))
    }
}
