//! rkforge-runner: one run of a scene as the command line and the Python package both do
//! it, so that their results are the same bits.
//!
//! A [`Run`] steps a simulation of either kind ([`Runnable`]: the 2D [`Simulation`], the 3D
//! `SolidSimulation`) from mark to mark of its [`schedule`] (history rows every
//! `output.history_interval_s`, frame times merged in), or by a number of steps, with a
//! hook between steps (commands, cancels), and records the [`History`]; the run ends with
//! the [`summary()`] ([`solid_summary`] in 3D). [`drive`] runs a scene to its end through one,
//! for the command line and the Python package, with what a caller adds at the samples and
//! frames (files, plots, MCAP, a progress bar) through an [`Observer`]; the ROS node and
//! the FMU step their own [`Run`] as their services and communication points order.

pub mod checkpoint;
pub mod history;
pub mod runnable;
pub mod summary;

pub use checkpoint::{Checkpoints, Resumed};
pub use history::History;
pub use runnable::Runnable;
pub use summary::{
    laps_json, reference_table, references_beside, solid_laps_json, solid_summary, summary,
    tool_json, Ending,
};

impl<S: Body> Outcome<S> {
    /// How the run ended, for [`summary()`].
    pub fn ending(&self) -> Ending<'_> {
        match (&self.failure, self.stopped) {
            (None, _) => Ending::Finished,
            (Some(reason), true) => Ending::Stopped(reason),
            (Some(error), false) => Ending::Failed(error),
        }
    }
}

use rkforge_core::outputs::Body;
use rkforge_core::Simulation;
use std::time::{Duration, Instant};

/// One instant of the schedule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mark {
    /// Time (s).
    pub time: f64,
    /// A history row is due.
    pub sample: bool,
    /// A frame is due.
    pub frame: bool,
}

/// The instants a run of `sim` stops at: the history's sample times up to the scene's end,
/// and `frames` frame times `k * end / frames`, merged in order.
///
/// # Errors
///
/// The scene's history interval gives more than [`rkforge_core::MAX_SAMPLES`] samples.
pub fn schedule<S: Runnable>(sim: &S, frames: usize) -> Result<Vec<Mark>, String> {
    let interval = sim.history_interval();
    schedule_every(sim.end_time(), interval, frames)
        .ok_or_else(|| format!("output.history_interval_s {interval:e} s: too many samples"))
}

/// [`schedule`] with samples every `interval` (s) up to `end` (s); `None` if that gives
/// more than [`rkforge_core::MAX_SAMPLES`] samples.
pub fn schedule_every(end: f64, interval: f64, frames: usize) -> Option<Vec<Mark>> {
    let mut marks: Vec<Mark> = rkforge_core::sample_times(end, interval)?
        .into_iter()
        .map(|time| Mark {
            time,
            sample: true,
            frame: false,
        })
        .collect();
    marks.extend((1..=frames).map(|k| Mark {
        time: end * k as f64 / frames as f64,
        sample: false,
        frame: true,
    }));
    marks.sort_by(|a, b| a.time.total_cmp(&b.time));
    Some(marks)
}

/// A run under way: the marks of its schedule still ahead and its history so far.
pub struct Run<S: Runnable = Simulation> {
    marks: Vec<Mark>,
    next: usize,
    history: History<S>,
}

/// How far [`Run::advance`] goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Until {
    /// To the next mark of the schedule.
    NextMark,
    /// This many steps, each landing on the marks it crosses (fewer at the end).
    Steps(u64),
}

/// What [`Run::advance`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Advance {
    /// Steps taken.
    pub steps: u64,
    /// The mark reached, for [`Until::NextMark`].
    pub mark: Option<Mark>,
    /// The hook between steps stopped it.
    pub interrupted: bool,
}

impl<S: Runnable> Run<S> {
    /// A run of `sim` from its current time over `marks` (from [`schedule`]).
    pub fn new(sim: &S, marks: Vec<Mark>) -> Run<S> {
        Run {
            marks,
            next: 0,
            history: sim.new_history(),
        }
    }

    /// A run resumed at mark `next` of `marks` with its `history` so far
    /// ([`checkpoint::resume`]).
    pub fn at(marks: Vec<Mark>, next: usize, history: History<S>) -> Run<S> {
        Run {
            marks,
            next,
            history,
        }
    }

    /// The next mark's place in the schedule.
    pub fn next(&self) -> usize {
        self.next
    }

    /// The number of frames in the schedule.
    pub fn frames(&self) -> usize {
        self.marks.iter().filter(|m| m.frame).count()
    }

    /// Back to the first mark with an empty history, for a simulation rebuilt at t = 0.
    pub fn restart(&mut self, sim: &S) {
        self.next = 0;
        self.history = sim.new_history();
    }

    /// Make `mark` the one mark ahead, for a caller that learns its marks one at a time: the
    /// FMU, whose `doStep` names the next communication point (an early return leaves a mark
    /// unreached, which the next step's replaces).
    pub fn aim(&mut self, mark: Mark) {
        self.marks.clear();
        self.marks.push(mark);
        self.next = 0;
    }

    /// Every mark is behind: the run is at its end.
    pub fn finished(&self) -> bool {
        self.next >= self.marks.len()
    }

    /// Record a history row of the current state ([`Runnable::record_in`]).
    ///
    /// # Errors
    ///
    /// A particle is deeper in a tool than the scene's bound (the row is recorded).
    pub fn record(&mut self, sim: &mut S) -> Result<(), rkforge_core::Error> {
        sim.record_in(&mut self.history)
    }

    /// The history so far.
    pub fn history(&self) -> &History<S> {
        &self.history
    }

    /// The history, at the end of the run.
    pub fn into_history(self) -> History<S> {
        self.history
    }

    /// Step on as `until` says, each step shortened to land on the next mark
    /// ([`Runnable::step_toward`]). `between(sim, taken)` is called before each step
    /// with the steps taken so far in this call: it may change the simulation (a velocity
    /// command) and returns `false` to stop there.
    ///
    /// # Errors
    ///
    /// A step failed; the simulation holds the state reached.
    pub fn advance(
        &mut self,
        sim: &mut S,
        until: Until,
        mut between: impl FnMut(&mut S, u64) -> bool + Send,
    ) -> Result<Advance, rkforge_core::Error> {
        let mut steps = 0;
        while let Some(&mark) = self.marks.get(self.next) {
            let limit = match until {
                Until::NextMark => u64::MAX,
                Until::Steps(n) => n - steps,
            };
            let ran = sim.step_toward(mark.time, limit, |s, k| between(s, steps + k))?;
            steps += ran.steps;
            if !ran.reached {
                return Ok(Advance {
                    steps,
                    mark: None,
                    interrupted: ran.interrupted,
                });
            }
            self.next += 1;
            if until == Until::NextMark {
                return Ok(Advance {
                    steps,
                    mark: Some(mark),
                    interrupted: false,
                });
            }
        }
        Ok(Advance {
            steps,
            mark: None,
            interrupted: false,
        })
    }
}

/// What a caller does at the instants of a run of an `S`. Every method has a default that
/// does nothing.
pub trait Observer<S = Simulation> {
    /// After each history row: at t = 0, at every sample, and once more after a failure.
    ///
    /// # Errors
    ///
    /// An output error, which ends the run at once.
    fn sample(&mut self, _sim: &S) -> Result<(), String> {
        Ok(())
    }
    /// At t = 0 and at every frame time, when the run has frames.
    ///
    /// # Errors
    ///
    /// An output error, which ends the run at once.
    fn frame(&mut self, _sim: &S) -> Result<(), String> {
        Ok(())
    }
    /// Asked before each stretch of steps: a reason to stop the run there (a signal).
    fn stop(&self, _sim: &S) -> Option<String> {
        None
    }
    /// After each instant of the schedule.
    fn progress(&mut self, _sim: &S) {}
    /// After each instant's outputs, with the run and the output time (s) spent so far in
    /// this process: where a caller writes a [`checkpoint`] when one is due (its writing
    /// is output time too).
    ///
    /// # Errors
    ///
    /// The checkpoint cannot be written, which ends the run at once.
    fn checkpoint(&mut self, _sim: &S, _run: &Run<S>, _output: Duration) -> Result<(), String>
    where
        S: Runnable,
    {
        Ok(())
    }
}

/// An observer that does nothing: the bare run.
pub struct Quiet;

impl<S> Observer<S> for Quiet {}

/// What a run produced (of a 2D simulation, or `Outcome<SolidSimulation>` of a 3D one).
pub struct Outcome<S: Body = Simulation> {
    /// One row per sample (and a last one after a failure).
    pub history: History<S>,
    /// Why the run stopped before its end (divergence, a signal), if it did.
    pub failure: Option<String>,
    /// The observer stopped it ([`Observer::stop`]): `failure` is the reason.
    pub stopped: bool,
    /// Wall time spent recording samples and in the observer's `sample` and `frame`.
    pub output_time: Duration,
}

/// Run `sim` to its scene's end time with `frames` frames, recording the history.
///
/// A failure of the simulation ends the loop and is returned in the [`Outcome`] (with a
/// last history row); an error of the observer is returned at once.
///
/// # Errors
///
/// The schedule is too long, or the observer failed.
pub fn drive<S: Runnable>(
    sim: &mut S,
    frames: usize,
    observer: &mut impl Observer<S>,
) -> Result<Outcome<S>, String> {
    let mut run = Run::new(sim, schedule(sim, frames)?);
    let clock = Instant::now();
    let failure = run.record(sim).err().map(|e| e.to_string());
    observer.sample(sim)?;
    if frames > 0 {
        observer.frame(sim)?;
    }
    drive_on(sim, run, failure, clock.elapsed(), observer)
}

/// Go on with `run` of `sim` to its end, as [`drive`] does after the start: a run resumed
/// from a [`checkpoint`] ([`checkpoint::resume`]).
///
/// # Errors
///
/// The observer failed.
pub fn resume<S: Runnable>(
    sim: &mut S,
    run: Run<S>,
    observer: &mut impl Observer<S>,
) -> Result<Outcome<S>, String> {
    drive_on(sim, run, None, Duration::ZERO, observer)
}

/// The loop of [`drive`] and [`resume`]: from `run`'s next mark to its end, `failure` a
/// failure already met and `output_time` the output time spent so far.
fn drive_on<S: Runnable>(
    sim: &mut S,
    mut run: Run<S>,
    mut failure: Option<String>,
    mut output_time: Duration,
    observer: &mut impl Observer<S>,
) -> Result<Outcome<S>, String> {
    let mut recorded = true;
    let mut stopped = false;
    while failure.is_none() && !run.finished() {
        if let Some(e) = observer.stop(sim) {
            failure = Some(e);
            stopped = true;
            break;
        }
        let mark = match run.advance(sim, Until::NextMark, |_, _| true) {
            Ok(Advance {
                mark: Some(mark), ..
            }) => mark,
            Ok(_) => break,
            Err(e) => {
                failure = Some(e.to_string());
                recorded = false;
                break;
            }
        };
        let clock = Instant::now();
        if mark.sample {
            failure = run.record(sim).err().map(|e| e.to_string());
            observer.sample(sim)?;
        }
        if mark.frame {
            observer.frame(sim)?;
        }
        observer.progress(sim);
        if failure.is_none() {
            observer.checkpoint(sim, &run, clock.elapsed() + output_time)?;
        }
        output_time += clock.elapsed();
    }
    if failure.is_some() && !recorded {
        let clock = Instant::now();
        // The run already failed: the row is what matters here, not the bound again.
        let _ = run.record(sim);
        observer.sample(sim)?;
        output_time += clock.elapsed();
    }
    Ok(Outcome {
        history: run.into_history(),
        failure,
        stopped,
        output_time,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rkforge_core::Scene;

    fn block(end: &str) -> Scene {
        let text = include_str!("../../scenes/block_forging.toml")
            .replace("particles = [21, 21]", "particles = [7, 7]")
            .replace("end_s = 0.015", &format!("end_s = {end}"));
        Scene::from_str_named(&text, "block").unwrap()
    }

    #[test]
    fn schedule_merges_frames_into_the_samples() {
        let sim = Simulation::new(&block("0.0015")).unwrap();
        let marks = schedule(&sim, 3).unwrap();
        // history_interval_s = 0.15e-3: ten samples; three frames, the last on the end.
        assert_eq!(marks.iter().filter(|m| m.sample).count(), 10);
        assert_eq!(marks.iter().filter(|m| m.frame).count(), 3);
        assert!(marks.windows(2).all(|w| w[0].time <= w[1].time));
        // The last sample and the last frame fall on the end, up to rounding.
        for last in [
            marks.iter().rfind(|m| m.sample),
            marks.iter().rfind(|m| m.frame),
        ] {
            let t = last.map_or(0.0, |m| m.time);
            assert!((t - 0.0015).abs() < 1e-15, "{t}");
        }
    }

    #[test]
    fn a_run_records_every_sample_and_ends_on_time() {
        let scene = block("0.0006");
        let mut sim = Simulation::new(&scene).unwrap();
        let outcome = drive(&mut sim, 0, &mut Quiet).unwrap();
        assert!(outcome.failure.is_none());
        let rows = outcome.history.rows();
        assert_eq!(rows.len(), 5);
        assert_eq!(rows.last().map(|r| r[0]), Some(0.0006));
        assert_eq!(outcome.history.column("time_s").unwrap().len(), 5);
        let csv = outcome.history.to_csv();
        assert!(csv.starts_with("time_s,dt_s,top.stroke_m,"), "{csv}");
        let s = summary(&sim, 1.0, 0.0, outcome.ending());
        assert_eq!(s["status"], "ok");
        // The material's own volume: compressed elastically under the tools, a little.
        let v = s["workpiece"]["integrated_volume_change_rel"]
            .as_f64()
            .unwrap();
        assert!(v < 0.0 && v > -1e-2, "{v}");
        assert_eq!(s["end_time_s"], 0.0006);
    }

    /// A 3D run goes through the same loop: a row at t = 0 and at every sample, the last on
    /// the end time, and the 3D register's columns.
    #[test]
    fn a_3d_run_records_every_sample() {
        let text = include_str!("../../scenes/taylor_bar_3d.toml")
            .replace("cells = [8, 4, 60]", "cells = [2, 1, 8]")
            .replace("end_s = 80.0e-6", "end_s = 4.0e-6");
        let scene = rkforge_core::scene::SolidScene::from_str_named(&text, "bar").unwrap();
        let mut sim = rkforge_core::solver::SolidSimulation::new(&scene).unwrap();
        let outcome = drive(&mut sim, 2, &mut Quiet).unwrap();
        assert!(outcome.failure.is_none());
        let time = outcome.history.column("time_s").unwrap();
        assert_eq!(time.len(), 5);
        assert_eq!(time.last(), Some(&4.0e-6));
        assert!(outcome.history.column("wall.force_z_N").is_some());
        let s = solid_summary(&sim, 1.0, 0.0, outcome.ending());
        assert_eq!(s["status"], "ok");
        assert_eq!(s["end_time_s"], 4.0e-6);
    }
}
