//! The simulations the run layer steps: [`Runnable`], implemented by the 2D
//! [`Simulation`] and the 3D [`SolidSimulation`], so that one [`Run`](crate::Run) and one
//! [`drive`](crate::drive) serve both kinds.

use crate::History;
use rkforge_core::outputs::Body;
use rkforge_core::scene::SolidScene;
use rkforge_core::solver::{SolidSimulation, SolidState};
use rkforge_core::{Error, Ran, Scene, Simulation, StageTimes, State};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// A simulation a [`Run`](crate::Run) steps and records.
pub trait Runnable: Body + Send {
    /// Its scene.
    type Scene: Serialize;
    /// Everything that changes during a run: what a checkpoint and an FMU state save.
    type State: Clone + Serialize + DeserializeOwned;
    /// The scene it runs, every override applied.
    fn scene(&self) -> &Self::Scene;
    /// The state.
    fn saved(&self) -> &Self::State;
    /// Go on from `state`, saved from a simulation of the same scene: stepping on gives the
    /// bits the saved run gave.
    ///
    /// # Errors
    ///
    /// The state belongs to another discretisation.
    fn restore_state(&mut self, state: Self::State) -> Result<(), Error>;
    /// The wall time spent in each stage so far.
    fn stage_times(&self) -> StageTimes;
    /// The same, to add to (a resumed run adds the times of the processes before).
    fn stage_times_mut(&mut self) -> &mut StageTimes;
    /// The scene's end time (s).
    fn end_time(&self) -> f64;
    /// The interval between history rows (s), `output.history_interval_s` or its default.
    fn history_interval(&self) -> f64;
    /// An empty history of the scene's columns.
    fn new_history(&self) -> History<Self>;
    /// Record a row of the current state in `history`, the penetration measured over every
    /// particle; a particle deeper than the scene's bound is returned as an error, after the
    /// row is recorded.
    ///
    /// # Errors
    ///
    /// The penetration bound is exceeded.
    fn record_in(&mut self, history: &mut History<Self>) -> Result<(), Error>;
    /// Step toward `t_end` (s), at most `max_steps` steps, the last one shortened to land on
    /// it; `between(sim, taken)` before each step returns `false` to stop there (the
    /// simulation's own `run_toward`).
    ///
    /// # Errors
    ///
    /// A step failed; the simulation holds the state reached.
    fn step_toward(
        &mut self,
        t_end: f64,
        max_steps: u64,
        between: impl FnMut(&mut Self, u64) -> bool + Send,
    ) -> Result<Ran, Error>;
}

/// The methods of [`Runnable`] that both simulations answer with their own inherent methods
/// of the same names.
macro_rules! shared {
    ($sim:ty) => {
        fn scene(&self) -> &Self::Scene {
            <$sim>::scene(self)
        }
        fn saved(&self) -> &Self::State {
            self.state()
        }
        fn restore_state(&mut self, state: Self::State) -> Result<(), Error> {
            self.restore(state)
        }
        fn stage_times(&self) -> StageTimes {
            self.times
        }
        fn stage_times_mut(&mut self) -> &mut StageTimes {
            &mut self.times
        }
        fn end_time(&self) -> f64 {
            <$sim>::scene(self).time.end_s
        }
        fn history_interval(&self) -> f64 {
            <$sim>::scene(self).history_interval()
        }
        fn step_toward(
            &mut self,
            t_end: f64,
            max_steps: u64,
            between: impl FnMut(&mut Self, u64) -> bool + Send,
        ) -> Result<Ran, Error> {
            self.run_toward(t_end, max_steps, between)
        }
    };
}

impl Runnable for Simulation {
    type Scene = Scene;
    type State = State;
    shared!(Simulation);
    fn new_history(&self) -> History<Self> {
        History::new(self)
    }
    fn record_in(&mut self, history: &mut History<Self>) -> Result<(), Error> {
        history.record(self)
    }
}

impl Runnable for SolidSimulation {
    type Scene = SolidScene;
    type State = SolidState;
    shared!(SolidSimulation);
    fn new_history(&self) -> History<Self> {
        History::solid(self)
    }
    fn record_in(&mut self, history: &mut History<Self>) -> Result<(), Error> {
        history.record_solid(self)
    }
}
