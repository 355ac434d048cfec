//! Checkpoints of a run: everything a run needs to go on after its process is killed (a
//! session's end, a cluster's pre-emption, a power cut) with the same bits as if it had
//! never stopped.
//!
//! A [`Checkpoint`] holds the scene as it was run, the schedule's place (the next mark and the
//! number of frames), the history's rows so far, the simulation's whole changing state
//! ([`Runnable::saved`], what an FMU state saves) and what the caller took of the frames so
//! far, with the wall time spent, in all and per stage. It is written as CBOR (RFC 8949, `ciborium`: every float
//! its 8 bytes, so the state comes back to the bit) to a temporary file that is then renamed
//! over the last one, so a process killed while it writes leaves the previous checkpoint
//! whole. [`Checkpoints`] writes one at the first instant of the schedule after each
//! interval of wall time; a run that reaches its end removes its checkpoint.

use crate::{History, Run, Runnable};
use rkforge_core::StageTimes;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The format of the checkpoint files this build writes and reads: 3 since each tool's state
/// carries its impulse and work ([`rkforge_core::tools::Account`]; 2: a 3D run's frames carry
/// the particles' displacements and velocities and the cells' von Mises stress).
pub const FORMAT: u32 = 3;

/// The one field every checkpoint format has, read before the rest.
#[derive(Deserialize)]
struct Format {
    format: u32,
}

/// The checkpoint file in a run's output folder.
pub const FILE: &str = "checkpoint.cbor";

/// One checkpoint: `Sc` the scene, `St` the simulation's state, `Fr` what the caller took of
/// the frames so far (written from references, read as owned values).
#[derive(Debug, Serialize, Deserialize)]
pub struct Checkpoint<Sc, St, Fr> {
    /// [`FORMAT`] when written.
    pub format: u32,
    /// The scene as run, every override applied.
    pub scene: Sc,
    /// The number of frames of the run's schedule.
    pub frames: usize,
    /// The schedule's next mark.
    pub next: usize,
    /// The history's rows so far.
    pub rows: Vec<Vec<f64>>,
    /// The simulation's changing state.
    pub state: St,
    /// What the caller took of the frames so far.
    pub taken: Fr,
    /// Wall time spent on the run up to the checkpoint, over every resumption (s).
    pub wall_s: f64,
    /// Of it, the time spent on outputs (s).
    pub output_s: f64,
    /// Of it, the time spent in each stage of the simulation (a checkpoint written before
    /// they were kept reads as zeros).
    #[serde(default)]
    pub stage_times: StageTimes,
    /// The simulated times at which the run was resumed before (s).
    pub resumed_at_s: Vec<f64>,
}

/// A run resumed from a checkpoint: the run at its next mark, the frames the caller took
/// before it, and the wall time spent before.
pub struct Resumed<S: Runnable, Fr> {
    /// The run, at the checkpoint's next mark with its history.
    pub run: Run<S>,
    /// What the caller took of the frames before the checkpoint.
    pub taken: Fr,
    /// Wall time spent before the checkpoint (s).
    pub wall_s: f64,
    /// Of it, the time spent on outputs (s).
    pub output_s: f64,
    /// The simulated times at which the run was resumed (s), this time last.
    pub resumed_at_s: Vec<f64>,
}

/// Writes a run's checkpoints into one file, at the first instant of the schedule after
/// each `every` of wall time.
pub struct Checkpoints {
    path: PathBuf,
    every: Duration,
    last: Instant,
    /// Wall time spent on the run before this process took it up (s).
    before_s: f64,
    /// Of it, the time spent on outputs (s).
    before_output_s: f64,
    /// The simulated times at which the run was resumed (s).
    resumed_at_s: Vec<f64>,
    started: Instant,
}

impl Checkpoints {
    /// Checkpoints into `path` every `every` of wall time, of a run started in this process.
    pub fn new(path: &Path, every: Duration) -> Self {
        let now = Instant::now();
        Checkpoints {
            path: path.to_path_buf(),
            every,
            last: now,
            before_s: 0.0,
            before_output_s: 0.0,
            resumed_at_s: Vec::new(),
            started: now,
        }
    }

    /// Checkpoints into `path` every `every` of wall time, of a run `resumed` in this
    /// process.
    pub fn after<S: Runnable, Fr>(path: &Path, every: Duration, resumed: &Resumed<S, Fr>) -> Self {
        Checkpoints {
            before_s: resumed.wall_s,
            before_output_s: resumed.output_s,
            resumed_at_s: resumed.resumed_at_s.clone(),
            ..Checkpoints::new(path, every)
        }
    }

    /// The same checkpoints counting `setup`, the wall time this process spent setting the
    /// simulation up before they were, in the run's wall time (a resumed run's `wall_s`
    /// then covers each process's setup, as its stage times do).
    pub fn counting_setup(self, setup: Duration) -> Self {
        Checkpoints {
            started: self.started.checked_sub(setup).unwrap_or(self.started),
            ..self
        }
    }

    /// The checkpoint file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whether a checkpoint is due (the interval has passed since the last one).
    pub fn due(&self) -> bool {
        self.last.elapsed() >= self.every
    }

    /// Write a checkpoint of `sim` in `run`, with the caller's `taken` frames and `output_s`
    /// (s) of output time in this process, over the last one.
    ///
    /// # Errors
    ///
    /// The file cannot be written (the last checkpoint is then left as it was).
    pub fn write<S: Runnable, Fr: Serialize>(
        &mut self,
        sim: &S,
        run: &Run<S>,
        taken: &Fr,
        output_s: f64,
    ) -> Result<(), String> {
        let checkpoint = Checkpoint {
            format: FORMAT,
            scene: sim.scene(),
            frames: run.frames(),
            next: run.next(),
            rows: run.history().rows().to_vec(),
            state: sim.saved(),
            taken,
            wall_s: self.before_s + self.started.elapsed().as_secs_f64(),
            output_s: self.before_output_s + output_s,
            stage_times: sim.stage_times(),
            resumed_at_s: self.resumed_at_s.clone(),
        };
        let partial = self.path.with_extension("cbor.partial");
        let written = std::fs::File::create(&partial)
            .map_err(|e| e.to_string())
            .and_then(|file| {
                let mut w = std::io::BufWriter::new(file);
                ciborium::into_writer(&checkpoint, &mut w).map_err(|e| e.to_string())?;
                std::io::Write::flush(&mut w).map_err(|e| e.to_string())?;
                w.get_ref().sync_all().map_err(|e| e.to_string())
            })
            .and_then(|()| std::fs::rename(&partial, &self.path).map_err(|e| e.to_string()));
        self.last = Instant::now();
        written.map_err(|e| format!("cannot write the checkpoint {}: {e}", self.path.display()))
    }

    /// [`Checkpoints::write`] when one is [`due`](Checkpoints::due).
    ///
    /// # Errors
    ///
    /// The file cannot be written.
    pub fn write_if_due<S: Runnable, Fr: Serialize>(
        &mut self,
        sim: &S,
        run: &Run<S>,
        taken: &Fr,
        output: Duration,
    ) -> Result<(), String> {
        if self.due() {
            self.write(sim, run, taken, output.as_secs_f64())
        } else {
            Ok(())
        }
    }
}

/// [`Checkpoints::write_if_due`] for an observer that may keep none: what every observer's
/// [`crate::Observer::checkpoint`] does with its checkpoints.
///
/// # Errors
///
/// The file cannot be written.
pub fn keep<S: Runnable, Fr: Serialize>(
    checkpoints: Option<&mut Checkpoints>,
    sim: &S,
    run: &Run<S>,
    taken: &Fr,
    output: Duration,
) -> Result<(), String> {
    match checkpoints {
        Some(c) => c.write_if_due(sim, run, taken, output),
        None => Ok(()),
    }
}

/// How a run starts and keeps checkpoints: from its checkpoint (`resume`) or afresh, and
/// writing one every `every` of wall time, or none.
#[derive(Debug, Clone, Copy, Default)]
pub struct Restart {
    /// Write a checkpoint after each interval of wall time.
    pub every: Option<Duration>,
    /// Go on from the checkpoint in the output folder.
    pub resume: bool,
}

/// A run set up as a [`Restart`] asks: `run` the resumed run (`None`: start afresh with
/// [`crate::drive`]), the frames taken before, the checkpoints to write, and the wall time
/// and resumptions before this process.
pub struct Started<S: Runnable, Fr> {
    /// The resumed run, or `None` for a fresh start.
    pub run: Option<Run<S>>,
    /// What the caller took of the frames before.
    pub taken: Fr,
    /// Where and how often checkpoints are written, if they are.
    pub checkpoints: Option<Checkpoints>,
    /// Wall time spent before this process (s).
    pub wall_s: f64,
    /// Of it, the time spent on outputs (s).
    pub output_s: f64,
    /// The simulated times at which the run was resumed (s); empty for a fresh start.
    pub resumed_at_s: Vec<f64>,
    /// The checkpoint file of the run's folder, if it has one.
    file: Option<PathBuf>,
}

impl<S: Runnable, Fr> Started<S, Fr> {
    /// Run `sim` to its end from where it starts, with `frames` frames ([`crate::drive`],
    /// [`crate::resume`]). A run that ends (finished or failed, not stopped by the
    /// observer) removes the checkpoint from its folder: the folder now holds the run's end.
    ///
    /// # Errors
    ///
    /// The schedule is too long, the observer failed, or the checkpoint cannot be removed.
    pub fn go(
        &mut self,
        sim: &mut S,
        frames: usize,
        observer: &mut impl crate::Observer<S>,
    ) -> Result<crate::Outcome<S>, String> {
        let outcome = match self.run.take() {
            Some(run) => crate::resume(sim, run, observer)?,
            None => crate::drive(sim, frames, observer)?,
        };
        if let (false, Some(path)) = (outcome.stopped, &self.file) {
            if let Err(e) = std::fs::remove_file(path) {
                if e.kind() != std::io::ErrorKind::NotFound {
                    return Err(format!(
                        "cannot remove the checkpoint {}: {e}",
                        path.display()
                    ));
                }
            }
        }
        Ok(outcome)
    }

    /// Mark a summary (summary.json) of a resumed run: the simulated times it was resumed
    /// at, `resumed_at_s` (its `wall_s` and stage times count every process).
    pub fn mark(&self, summary: &mut serde_json::Value) {
        if !self.resumed_at_s.is_empty() {
            summary["resumed_at_s"] = serde_json::json!(self.resumed_at_s);
        }
    }
}

/// Set up a run of `sim` with `frames` frames and its checkpoint file in `folder`, as `how`
/// asks; without a folder, a fresh run without checkpoints.
///
/// # Errors
///
/// `how.resume` and the checkpoint cannot be read or does not fit ([`resume`]).
pub fn start<S: Runnable, Fr: Default + DeserializeOwned>(
    sim: &mut S,
    frames: usize,
    folder: Option<&Path>,
    how: Restart,
) -> Result<Started<S, Fr>, String> {
    let file = folder.map(|f| f.join(FILE));
    let setup = sim.stage_times().setup;
    let Some(path) = file.as_deref().filter(|_| how.resume) else {
        return Ok(Started {
            run: None,
            taken: Fr::default(),
            checkpoints: file
                .as_deref()
                .zip(how.every)
                .map(|(path, every)| Checkpoints::new(path, every).counting_setup(setup)),
            wall_s: 0.0,
            output_s: 0.0,
            resumed_at_s: Vec::new(),
            file,
        });
    };
    let resumed: Resumed<S, Fr> = resume(path, sim, frames)?;
    Ok(Started {
        checkpoints: how
            .every
            .map(|every| Checkpoints::after(path, every, &resumed).counting_setup(setup)),
        run: Some(resumed.run),
        taken: resumed.taken,
        wall_s: resumed.wall_s,
        output_s: resumed.output_s,
        resumed_at_s: resumed.resumed_at_s,
        file: file.clone(),
    })
}

/// Read the checkpoint at `path` and put `sim` (built anew from the same scene) in its state,
/// for a run of `frames` frames.
///
/// # Errors
///
/// The file cannot be read or is not a checkpoint of this format; it was taken of another
/// scene (the first key that differs is named), with another number of frames, or of
/// another discretisation.
pub fn resume<S: Runnable, Fr: DeserializeOwned>(
    path: &Path,
    sim: &mut S,
    frames: usize,
) -> Result<Resumed<S, Fr>, String> {
    let at = |e: String| format!("checkpoint {}: {e}", path.display());
    let file = std::fs::File::open(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => format!(
            "no checkpoint to resume: {} is not there (a run writes it with \
             --checkpoint-every-s, and removes it when it ends)",
            path.display()
        ),
        _ => at(format!("cannot read: {e}")),
    })?;
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(&mut std::io::BufReader::new(file), &mut bytes)
        .map_err(|e| at(format!("cannot read: {e}")))?;
    let not_one = |e: ciborium::de::Error<std::io::Error>| {
        at(format!(
            "not a checkpoint of this build (format {FORMAT}): {e}"
        ))
    };
    // The format first, so that a checkpoint of another build is named as such, not by the
    // first field its state lacks.
    let header: Format = ciborium::from_reader(&bytes[..]).map_err(not_one)?;
    if header.format != FORMAT {
        return Err(at(format!(
            "format {} (this build reads {FORMAT})",
            header.format
        )));
    }
    let saved: Checkpoint<serde_json::Value, S::State, Fr> =
        ciborium::from_reader(&bytes[..]).map_err(not_one)?;
    let scene = serde_json::to_value(sim.scene()).map_err(|e| at(e.to_string()))?;
    if let Some(key) = first_difference(&scene, &saved.scene, "") {
        return Err(at(format!(
            "taken of another scene: `{key}` differs (resume with the scene file and --set \
             overrides of the run that wrote it)"
        )));
    }
    if saved.frames != frames {
        return Err(at(format!(
            "taken of a run with {} frames, this one has {frames} (resume with the frames, \
             and --no-frames or not, of the run that wrote it)",
            saved.frames
        )));
    }
    sim.restore_state(saved.state)
        .map_err(|e| at(e.to_string()))?;
    *sim.stage_times_mut() += saved.stage_times;
    let marks = crate::schedule(sim, frames)?;
    if saved.next > marks.len() {
        return Err(at(format!(
            "its next mark {} lies beyond the schedule's {}",
            saved.next,
            marks.len()
        )));
    }
    let history = History::with_rows(sim.new_history(), saved.rows).map_err(at)?;
    let mut resumed_at_s = saved.resumed_at_s;
    resumed_at_s.push(sim.time_now());
    Ok(Resumed {
        run: Run::at(marks, saved.next, history),
        taken: saved.taken,
        wall_s: saved.wall_s,
        output_s: saved.output_s,
        resumed_at_s,
    })
}

/// The dotted path of the first key where `a` and `b` differ, if they do (`at` the path
/// of both, "" at the top): how a scene that does not fit a saved run is named.
pub fn first_difference(a: &serde_json::Value, b: &serde_json::Value, at: &str) -> Option<String> {
    use serde_json::Value;
    let name = |k: &str| {
        if at.is_empty() {
            k.to_string()
        } else {
            format!("{at}.{k}")
        }
    };
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => x
            .iter()
            .find_map(|(k, v)| match y.get(k) {
                Some(w) => first_difference(v, w, &name(k)),
                None => Some(name(k)),
            })
            .or_else(|| y.keys().find(|k| !x.contains_key(*k)).map(|k| name(k))),
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .find_map(|(i, (v, w))| first_difference(v, w, &format!("{at}[{i}]"))),
        _ if a == b => None,
        _ => Some(if at.is_empty() {
            "the scene".into()
        } else {
            at.into()
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{drive, Observer};
    use rkforge_core::scene::SolidScene;
    use rkforge_core::solver::SolidSimulation;
    use rkforge_core::{Scene, Simulation};
    use serde_json::json;

    /// Writes one checkpoint, at mark `at`, with the number of frames taken as `taken`, and
    /// keeps the stage times it wrote.
    struct OneCheckpoint {
        at: usize,
        frames: usize,
        checkpoints: Checkpoints,
        times: StageTimes,
    }

    impl<S: Runnable> Observer<S> for OneCheckpoint {
        fn frame(&mut self, _sim: &S) -> Result<(), String> {
            self.frames += 1;
            Ok(())
        }
        fn checkpoint(&mut self, sim: &S, run: &Run<S>, output: Duration) -> Result<(), String> {
            if run.next() == self.at {
                self.checkpoints
                    .write(sim, run, &self.frames, output.as_secs_f64())?;
                self.times = sim.stage_times();
            }
            Ok(())
        }
    }

    /// A run resumed from a checkpoint at `at` in a new simulation gives the history's rows
    /// to the bit of the run that never stopped, and its frames.
    fn resumed_gives_the_same_bits<S: Runnable>(fresh: impl Fn() -> S, frames: usize, at: usize) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(FILE);
        let mut observer = OneCheckpoint {
            at,
            frames: 0,
            checkpoints: Checkpoints::new(&path, Duration::ZERO),
            times: StageTimes::default(),
        };
        let mut sim = fresh();
        let whole = drive(&mut sim, frames, &mut observer).unwrap();
        assert!(whole.failure.is_none(), "{:?}", whole.failure);
        let mut again = fresh();
        let own = again.stage_times();
        let resumed: Resumed<S, usize> = resume(&path, &mut again, frames).unwrap();
        // The stage times go on from the checkpoint's, this process's setup added.
        let (saved, now) = (observer.times, again.stage_times());
        assert!(saved.stress > Duration::ZERO && saved.contact > Duration::ZERO);
        assert_eq!(now.stress, saved.stress);
        assert_eq!(now.contact, saved.contact);
        assert_eq!(now.setup, saved.setup + own.setup);
        let rows = resumed.run.history().rows().len();
        assert!(rows > 1 && rows < whole.history.rows().len(), "{rows}");
        let time = *resumed.resumed_at_s.last().unwrap();
        assert!(time > 0.0 && time < again.end_time(), "{time}");
        let mut counted = OneCheckpoint {
            at: usize::MAX,
            frames: resumed.taken,
            checkpoints: Checkpoints::new(&path, Duration::ZERO),
            times: StageTimes::default(),
        };
        let rest = crate::resume(&mut again, resumed.run, &mut counted).unwrap();
        assert!(rest.failure.is_none());
        let bits = |rows: &[Vec<f64>]| -> Vec<Vec<u64>> {
            rows.iter()
                .map(|r| r.iter().map(|v| v.to_bits()).collect())
                .collect()
        };
        assert_eq!(bits(rest.history.rows()), bits(whole.history.rows()));
        assert_eq!(counted.frames, frames + 1);
        // Another number of frames is refused, naming both.
        let mut other = fresh();
        let refused = resume::<S, usize>(&path, &mut other, frames + 1)
            .err()
            .unwrap();
        assert!(refused.contains(&format!("{frames} frames")), "{refused}");
    }

    /// A shipped scene's text with `edits` (each `(from, to)` must match).
    fn shipped(text: &str, edits: &[(&str, &str)]) -> String {
        edits.iter().fold(text.to_string(), |t, (from, to)| {
            assert!(t.contains(from), "{from}");
            t.replace(from, to)
        })
    }

    #[test]
    fn a_2d_run_resumed_gives_the_same_bits() {
        let text = shipped(
            include_str!("../../scenes/block_forging.toml"),
            &[
                ("particles = [21, 21]", "particles = [9, 9]"),
                ("end_s = 0.015", "end_s = 0.003"),
            ],
        );
        let scene = Scene::from_str_named(&text, "block").unwrap();
        resumed_gives_the_same_bits(|| Simulation::new(&scene).unwrap(), 4, 9);
    }

    #[test]
    fn a_3d_run_resumed_gives_the_same_bits() {
        let text = shipped(
            include_str!("../../scenes/taylor_bar_3d.toml"),
            &[
                ("cells = [8, 4, 60]", "cells = [2, 1, 8]"),
                ("end_s = 80.0e-6", "end_s = 8.0e-6"),
            ],
        );
        let scene = SolidScene::from_str_named(&text, "bar").unwrap();
        resumed_gives_the_same_bits(|| SolidSimulation::new(&scene).unwrap(), 2, 6);
    }

    #[test]
    fn a_checkpoint_of_another_scene_is_refused() {
        let text = shipped(
            include_str!("../../scenes/block_forging.toml"),
            &[
                ("particles = [21, 21]", "particles = [7, 7]"),
                ("end_s = 0.015", "end_s = 0.0006"),
            ],
        );
        let scene = Scene::from_str_named(&text, "block").unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(FILE);
        let mut observer = OneCheckpoint {
            at: 2,
            frames: 0,
            checkpoints: Checkpoints::new(&path, Duration::ZERO),
            times: StageTimes::default(),
        };
        drive(&mut Simulation::new(&scene).unwrap(), 0, &mut observer).unwrap();
        let changed = Scene::from_str_named(&text.replace("0.0006", "0.0007"), "block").unwrap();
        let mut sim = Simulation::new(&changed).unwrap();
        let refused = resume::<_, usize>(&path, &mut sim, 0).err().unwrap();
        assert!(refused.contains("`time.end_s` differs"), "{refused}");
        let missing = resume::<_, usize>(&dir.path().join("none.cbor"), &mut sim, 0)
            .err()
            .unwrap();
        assert!(missing.contains("no checkpoint to resume"), "{missing}");
        // A checkpoint of an older format, whose state lacks what this build's has, is named
        // by its format, not by the first field it lacks.
        let older = dir.path().join("older.cbor");
        let file = std::fs::File::create(&older).unwrap();
        ciborium::into_writer(&json!({"format": FORMAT - 1, "state": {}}), file).unwrap();
        let refused = resume::<_, usize>(&older, &mut sim, 0).err().unwrap();
        assert!(
            refused.ends_with(&format!(
                "format {} (this build reads {FORMAT})",
                FORMAT - 1
            )),
            "{refused}"
        );
    }

    #[test]
    fn the_first_differing_key_is_named() {
        let a = json!({"time": {"end_s": 1.0, "dt_s": 2.0}, "tools": [{"v": 1.0}, {"v": 2.0}]});
        let b = json!({"time": {"end_s": 1.0, "dt_s": 2.0}, "tools": [{"v": 1.0}, {"v": 3.0}]});
        assert_eq!(first_difference(&a, &a, ""), None);
        assert_eq!(first_difference(&a, &b, "").as_deref(), Some("tools[1].v"));
        let c = json!({"time": {"end_s": 1.0}, "tools": []});
        assert_eq!(first_difference(&a, &c, "").as_deref(), Some("time.dt_s"));
    }
}
