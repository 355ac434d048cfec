//! The instance's simulation, of either kind ([`Forging`]: the 2D [`Simulation`], the 3D
//! [`SolidSimulation`]), on the run layer: a communication step is a
//! [`rkforge_runner::Run`] advanced to one mark, the communication point, as the command
//! line, the Python package and the ROS node step theirs (the last solver step shortened to
//! land on it). Between solver steps, the hook ends the step early at an armed event (FMI
//! 3.0 early return) and reports the step to the host (FMI 3.0 intermediate update).

use crate::instance::Snapshot;
use rkforge_core::scene::SolidScene;
use rkforge_core::scene_overrides::Overridable;
use rkforge_core::solver::{SolidSimulation, SolidState};
use rkforge_core::{Result, Scene, Simulation, State};
use rkforge_model_description::FmuScene;
use rkforge_runner::{Mark, Run, Runnable, Until};

/// A simulation an FMU steps: what the instance reads, commands and saves of either kind.
pub(crate) trait Forging:
    Runnable<Scene: FmuScene<Body = Self> + Overridable + Clone>
{
    /// Set up the simulation of `scene`.
    fn build(scene: &Self::Scene) -> Result<Self>;
    /// Whether tool `k` touches the workpiece.
    fn touches(&self, k: usize) -> bool;
    /// Tool `k`'s force along its axis (N).
    fn axial_force(&self, k: usize) -> f64;
    /// Tool `k`'s velocity along its axis at time `t` (s): its command, else its motion's.
    fn velocity_at(&self, k: usize, t: f64) -> f64;
    /// Command tool `k`'s velocity (m/s).
    fn command(&mut self, k: usize, v: f64) -> Result<()>;
    /// Whether `state` has this simulation's discretisation.
    fn fits(&self, state: &Self::State) -> bool;
    /// The contact pressure at tool `k`'s stations (Pa); none in 3D.
    fn pressure(&self, k: usize) -> Vec<f64>;
    /// Keep `state` in a snapshot.
    fn put(state: &Self::State, snapshot: &mut Snapshot);
    /// The state a snapshot keeps of this kind.
    fn take(snapshot: &Snapshot) -> Option<&Self::State>;
}

/// The methods of [`Forging`] that both simulations answer with their own inherent methods
/// of the same names.
macro_rules! shared {
    () => {
        fn axial_force(&self, k: usize) -> f64 {
            self.tools()[k].axial_force()
        }
        fn velocity_at(&self, k: usize, t: f64) -> f64 {
            self.tools()[k].velocity_at(t)
        }
        fn command(&mut self, k: usize, v: f64) -> Result<()> {
            self.set_tool_velocity(k, v)
        }
        fn fits(&self, state: &Self::State) -> bool {
            self.state().d.len() == state.d.len()
        }
    };
}

impl Forging for Simulation {
    fn build(scene: &Scene) -> Result<Simulation> {
        Simulation::new(scene)
    }
    shared!();
    fn touches(&self, k: usize) -> bool {
        self.contact_fraction(k) > 0.0
    }
    fn pressure(&self, k: usize) -> Vec<f64> {
        self.contact_pressure(k)
    }
    fn put(state: &State, snapshot: &mut Snapshot) {
        snapshot.state = Some(state.clone());
    }
    fn take(snapshot: &Snapshot) -> Option<&State> {
        snapshot.state.as_ref()
    }
}

impl Forging for SolidSimulation {
    fn build(scene: &SolidScene) -> Result<SolidSimulation> {
        SolidSimulation::new(scene)
    }
    shared!();
    /// A plane tool touches when the workpiece presses on it.
    fn touches(&self, k: usize) -> bool {
        self.tools()[k].state.normal_force != 0.0
    }
    fn pressure(&self, _k: usize) -> Vec<f64> {
        Vec::new()
    }
    fn put(state: &SolidState, snapshot: &mut Snapshot) {
        snapshot.solid = Some(Box::new(state.clone()));
    }
    fn take(snapshot: &Snapshot) -> Option<&SolidState> {
        snapshot.solid.as_deref()
    }
}

/// The early-return events of one tool (FMI 3.0 `fmi3DoStep`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct EarlyReturn {
    /// When the tool comes to touch the workpiece (each rise).
    pub(crate) contact: bool,
    /// When the force magnitude rises to `level` (each rise).
    pub(crate) force: bool,
    /// Force level (N).
    pub(crate) level: f64,
}

impl EarlyReturn {
    /// These events, armed only when the step may return early.
    pub(crate) fn armed(self, early: bool) -> EarlyReturn {
        EarlyReturn {
            contact: self.contact && early,
            force: self.force && early,
            level: self.level,
        }
    }
}

/// Whether tool `k` touches the workpiece, and whether its force magnitude has reached its
/// early-return level: the states whose rise ends a step early.
fn event_states<S: Forging>(sim: &S, early: &[EarlyReturn]) -> Vec<(bool, bool)> {
    early
        .iter()
        .enumerate()
        .map(|(k, e)| (sim.touches(k), sim.axial_force(k).abs() >= e.level))
        .collect()
}

/// What a step reports after each solver step (FMI 3.0 intermediate update): the time (s)
/// and the Float64 outputs by value reference; it returns true to ask the step to return
/// early there.
pub type Observer<'a> = &'a mut (dyn FnMut(f64, &[(u32, f64)]) -> bool + Send);

/// A report to the host after a solver step: called with the simulation, it returns true
/// when the host asks the step to return there.
pub(crate) type Report<'a, S> = &'a mut (dyn FnMut(&S) -> bool + Send);

/// A simulation and the run that steps it.
pub(crate) struct Stepper<S: Forging> {
    sim: S,
    run: Run<S>,
}

impl<S: Forging> Stepper<S> {
    /// `sim` on a run with no mark yet: each step names its own.
    pub(crate) fn new(sim: S) -> Stepper<S> {
        let run = Run::new(&sim, Vec::new());
        Stepper { sim, run }
    }

    /// The simulation.
    pub(crate) fn sim(&self) -> &S {
        &self.sim
    }

    /// The simulation, to command or restore.
    pub(crate) fn sim_mut(&mut self) -> &mut S {
        &mut self.sim
    }

    /// Step to `target` (s, the simulation's own time). Before each solver step after the
    /// first, what the last one did: an armed event of `events` that happened ends the step
    /// there; so does `report`'s request when `early`. `report` is called once more at the
    /// target when the step reached it. Returns whether the step ended early.
    ///
    /// # Errors
    ///
    /// A solver step failed; the simulation holds the state reached.
    pub(crate) fn step_to(
        &mut self,
        target: f64,
        events: &[EarlyReturn],
        early: bool,
        mut report: Option<Report<'_, S>>,
    ) -> Result<bool> {
        let any_armed = events.iter().any(|e| e.contact || e.force);
        let mut before = if any_armed {
            event_states(&self.sim, events)
        } else {
            Vec::new()
        };
        self.run.aim(Mark {
            time: target,
            sample: false,
            frame: false,
        });
        let advanced = self
            .run
            .advance(&mut self.sim, Until::NextMark, |sim, taken| {
                if taken == 0 {
                    return true;
                }
                if any_armed {
                    let now = event_states(&*sim, events);
                    let fired = events
                        .iter()
                        .zip(before.iter().zip(&now))
                        .any(|(e, (b, n))| (e.contact && !b.0 && n.0) || (e.force && !b.1 && n.1));
                    before = now;
                    if fired {
                        return false;
                    }
                }
                match report.as_mut() {
                    Some(r) => !(r(sim) && early),
                    None => true,
                }
            })?;
        if let (Some(_), Some(r)) = (advanced.mark, report) {
            if advanced.steps > 0 {
                r(&self.sim);
            }
        }
        Ok(advanced.interrupted)
    }
}
