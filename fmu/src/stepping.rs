//! The instance's simulation on the run layer: a communication step is a
//! [`rkforge_runner::Run`] advanced to one mark, the communication point, as the command
//! line, the Python package and the ROS node step theirs (the last solver step shortened to
//! land on it). Between solver steps, the hook ends the step early at an armed event (FMI
//! 3.0 early return) and reports the step to the host (FMI 3.0 intermediate update).

use rkforge_core::{Result, Simulation};
use rkforge_runner::{Mark, Run, Until};

/// The early-return events of one tool (FMI 3.0 `fmi3DoStep`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct EarlyReturn {
    /// At the first touch of the workpiece.
    pub(crate) contact: bool,
    /// When the force magnitude first reaches `level`.
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
fn event_states(sim: &Simulation, early: &[EarlyReturn]) -> Vec<(bool, bool)> {
    early
        .iter()
        .enumerate()
        .map(|(k, e)| {
            (
                sim.contact_fraction(k) > 0.0,
                sim.tools()[k].axial_force().abs() >= e.level,
            )
        })
        .collect()
}

/// What a step reports after each solver step (FMI 3.0 intermediate update): the time (s)
/// and the Float64 outputs by value reference; it returns true to ask the step to return
/// early there.
pub type Observer<'a> = &'a mut (dyn FnMut(f64, &[(u32, f64)]) -> bool + Send);

/// A report to the host after a solver step: called with the simulation, it returns true
/// when the host asks the step to return there.
pub(crate) type Report<'a> = &'a mut (dyn FnMut(&Simulation) -> bool + Send);

/// A simulation and the run that steps it.
pub(crate) struct Stepper {
    sim: Simulation,
    run: Run,
}

impl Stepper {
    /// `sim` on a run with no mark yet: each step names its own.
    pub(crate) fn new(sim: Simulation) -> Stepper {
        let run = Run::new(&sim, Vec::new());
        Stepper { sim, run }
    }

    /// The simulation.
    pub(crate) fn sim(&self) -> &Simulation {
        &self.sim
    }

    /// The simulation, to command or restore.
    pub(crate) fn sim_mut(&mut self) -> &mut Simulation {
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
        mut report: Option<Report<'_>>,
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
                    let now = event_states(sim, events);
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
