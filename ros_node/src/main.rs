//! `rkforge-ros`: run a scene as a ROS 2 node, a 2D or a 3D one (`model.kinematics =
//! "3d"`, [`NodeSim`]). See the README's ROS 2 section.
//!
//! Two threads: the simulation steps on a rayon worker and hands a [`Sample`] over at every
//! publish instant; the main thread publishes it over DDS, records it to MCAP, paces the run,
//! forwards velocity commands, which the simulation applies before its next step, and serves
//! the parameters, the `simulation_interfaces` services and the `SimulateSteps` action.

use clap::Parser;
use rkforge_core::scene::solid::is_solid;
use rkforge_core::scene::SolidScene;
use rkforge_core::scene_overrides::Overridable;
use rkforge_core::solver::SolidSimulation;
use rkforge_core::{Scene, SceneSource, Simulation, MAX_SAMPLES};
use rkforge_ros::action::{GoalId, GoalStatusEnum};
use rkforge_ros::control::{self, check_reset, check_step, transition, Request, Transition};
use rkforge_ros::dds::{domain_id_from_env, Command, Node};
use rkforge_ros::frame::{Published, Sample, Sampler};
use rkforge_ros::msgs::{ResultMsg, SimulationState};
use rkforge_ros::params::Settings;
use rkforge_ros::record::{Compression, Provenance, Recorder};
use rkforge_ros::PublishedScene;
use rkforge_runner::{Ending, Mark, Run, Runnable, Until};
use serde_json::{json, Value};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

/// How often the main thread looks for commands and signals while it waits.
const POLL: Duration = Duration::from_millis(1);

/// How long the node stays up after its last sample, so that DDS can deliver (and repeat, for
/// reliable readers) the last messages before the participant goes away.
const LINGER: Duration = Duration::from_millis(300);

/// In lockstep, how often the current sample is published again while the node waits for
/// commands (a controller that joined late then still sees it; controllers answer each
/// stamp once).
const REPUBLISH: Duration = Duration::from_millis(250);

/// The feedback of a `SimulateSteps` goal is published at most this often while it executes,
/// and once after its last step.
const FEEDBACK: Duration = Duration::from_millis(10);

#[derive(Parser)]
#[command(
    name = "rkforge-ros",
    version,
    about = "Run an rkforge scene as a ROS 2 node: tool wrenches, joint states, the workpiece as a point cloud, tool markers and /clock; velocity commands per movable tool"
)]
struct Args {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Override a scene key by its dotted path, e.g. `--set time.mass_scaling.factor=1e4`
    /// or `--set tools.top.friction=0.1` (repeatable; as `rkforge run --set`).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Namespace of the topics.
    #[arg(long, default_value = "/rkforge")]
    namespace: String,
    /// Also record every published message to this MCAP file.
    #[arg(long)]
    record: Option<PathBuf>,
    /// Chunk compression of the MCAP file: `zstd` or `none`.
    #[arg(long, default_value = "zstd")]
    record_compression: Compression,
    /// Pace the run: simulated seconds per wall-clock second (default: as fast as possible).
    #[arg(long)]
    real_time_factor: Option<f64>,
    /// Samples per second of simulation time (default: one per history interval of the
    /// scene, so the samples fall at history.csv's times).
    #[arg(long)]
    publish_rate: Option<f64>,
    /// Wait at every sample until each movable tool has received a command, then apply it:
    /// closed loops are reproducible.
    #[arg(long)]
    lockstep: bool,
    /// Worker threads (default: all cores); results are identical for any count.
    #[arg(long)]
    threads: Option<usize>,
    /// At the end time, pause and keep serving (for ResetSimulation and further episodes)
    /// instead of ending the node.
    #[arg(long)]
    hold_at_end: bool,
}

/// From the main thread to the simulation.
enum ToSim {
    /// Apply a velocity command before the next step.
    Command(Command),
    /// Go on to the next sample.
    Continue,
    /// Take this many solver steps (fewer if the end time comes first), then a sample.
    Step(u64),
    /// Stop the steps of [`ToSim::Step`] after the one under way (ignored if they are done).
    Cancel,
    /// Back to the scene's initial state, then a sample.
    Reset,
    /// Stop now (a signal arrived).
    Stop,
}

/// From the simulation to the main thread.
enum FromSim {
    /// The state after an order (at a sample time for [`ToSim::Continue`]): whether it is
    /// the end time, and the solver steps the order took. The simulation waits for the next
    /// order.
    Sample(Sample, bool, u64),
    /// The step failed; the last sample is the state reached.
    Failed(String, Box<Sample>),
}

fn main() -> ExitCode {
    match run(&Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Check that an optional rate is positive and finite.
fn positive(name: &str, v: Option<f64>) -> Result<(), String> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => {
            Err(format!("{name} {x}: must be positive and finite"))
        }
        _ => Ok(()),
    }
}

/// A simulation the node runs: the 2D [`Simulation`] and the 3D [`SolidSimulation`].
trait NodeSim: Runnable + Published<Scene: Overridable + Clone + Sync> {
    /// A new simulation of `scene` at t = 0.
    ///
    /// # Errors
    ///
    /// The setup failed (the solver's reason).
    fn start(scene: &<Self as Published>::Scene) -> Result<Self, String>;
    /// The end time of `scene` and the interval between its history rows (s).
    fn sampling(scene: &<Self as Published>::Scene) -> (f64, f64);
    /// Set tool `tool`'s velocity along its axis (m/s), overriding the scene's motion.
    ///
    /// # Errors
    ///
    /// No such tool, a fixed tool, or a velocity that is not finite.
    fn command_velocity(&mut self, tool: usize, velocity: f64) -> Result<(), String>;
    /// The summary as `rkforge run` writes it (summary.json) after `wall_s` (s) of wall time.
    fn run_summary(&self, wall_s: f64, ending: Ending<'_>) -> Value;
}

impl NodeSim for Simulation {
    fn start(scene: &Scene) -> Result<Self, String> {
        Simulation::new(scene).map_err(|e| e.to_string())
    }
    fn sampling(scene: &Scene) -> (f64, f64) {
        (scene.time.end_s, scene.history_interval())
    }
    fn command_velocity(&mut self, tool: usize, velocity: f64) -> Result<(), String> {
        self.set_tool_velocity(tool, velocity)
            .map_err(|e| e.to_string())
    }
    fn run_summary(&self, wall_s: f64, ending: Ending<'_>) -> Value {
        rkforge_runner::summary(self, wall_s, 0.0, ending)
    }
}

impl NodeSim for SolidSimulation {
    fn start(scene: &SolidScene) -> Result<Self, String> {
        SolidSimulation::new(scene).map_err(|e| e.to_string())
    }
    fn sampling(scene: &SolidScene) -> (f64, f64) {
        (scene.time.end_s, scene.history_interval())
    }
    fn command_velocity(&mut self, tool: usize, velocity: f64) -> Result<(), String> {
        self.set_tool_velocity(tool, velocity)
            .map_err(|e| e.to_string())
    }
    fn run_summary(&self, wall_s: f64, ending: Ending<'_>) -> Value {
        rkforge_runner::solid_summary(self, wall_s, 0.0, ending)
    }
}

fn run(a: &Args) -> Result<(), String> {
    positive("--real-time-factor", a.real_time_factor)?;
    positive("--publish-rate", a.publish_rate)?;
    rkforge_core::set_threads(a.threads).map_err(|e| e.to_string())?;
    let text = std::fs::read_to_string(&a.scene)
        .map_err(|e| format!("{}: cannot read: {e}", a.scene.display()))?;
    if is_solid(&text) {
        run_scene::<SolidSimulation>(a, &text)
    } else {
        run_scene::<Simulation>(a, &text)
    }
}

/// Run the scene `text` (of the file `a.scene`) as a simulation of kind `S`.
fn run_scene<S: NodeSim>(a: &Args, text: &str) -> Result<(), String> {
    let file = a.scene.display().to_string();
    let mut source = SceneSource::<<S as Published>::Scene>::of_text(text, &file, Vec::new())
        .map_err(|e| e.to_string())?;
    source.set_args(&a.set).map_err(|e| e.to_string())?;
    let scene = source.scene().clone();
    let topics = rkforge_ros::topics(&scene, &a.namespace)?;
    let domain = domain_id_from_env()?;
    let (end, history_interval) = S::sampling(&scene);
    let interval = a.publish_rate.map_or(history_interval, |r| 1.0 / r);
    let schedule = schedule(end, interval)?;
    let samples = schedule.len();
    // Wall time from scene setup on, as `rkforge run` counts it in summary.json.
    let wall = Instant::now();
    let mut sim = S::start(&scene)?;
    let mut node = Node::new(domain, &a.namespace, &scene)?;
    let mut recorder = match &a.record {
        Some(p) => Some(Recorder::create(
            p,
            &topics,
            &Provenance {
                scene: &scene,
                scene_file: &a.scene,
                writer: "rkforge-ros",
            },
            a.record_compression,
        )?),
        None => None,
    };
    let stop = rkforge_ros::signals::stop_flag()?;
    if a.lockstep && node.commanded_tools().is_empty() {
        eprintln!("warning: --lockstep has no effect: every tool of the scene is fixed");
    }
    eprintln!(
        "rkforge-ros: scene {} on ROS domain {domain}, namespace {}, {} samples every {interval:e} s of simulation time{}",
        scene.scene_name(),
        a.namespace,
        samples + 1,
        if a.lockstep { ", lockstep" } else { "" }
    );
    let (to_sim, sim_rx) = mpsc::channel();
    let (sim_tx, from_sim) = mpsc::channel();
    let progress = AtomicU64::new(0);
    let outcome = std::thread::scope(|s| {
        let sim = &mut sim;
        let scene = &scene;
        let progress = &progress;
        let mut sim_rx = sim_rx;
        s.spawn(move || {
            rayon::scope(move |_| simulate(sim, scene, schedule, &mut sim_rx, &sim_tx, progress));
        });
        let mut main = MainLoop {
            node: &mut node,
            recorder: recorder.as_mut(),
            to_sim: &to_sim,
            stop: &stop,
            settings: Settings {
                real_time_factor: a.real_time_factor,
                lockstep: a.lockstep,
                publish_rate: 1.0 / interval,
            },
            pace: (Instant::now(), 0.0),
            time: 0.0,
            state: SimulationState::STATE_PLAYING,
            hold_at_end: a.hold_at_end,
            current: None,
            progress,
            executing: None,
        };
        let r = main.serve(&from_sim);
        // Unblock the simulation whatever happened (it may be gone already).
        let _ = to_sim.send(ToSim::Stop);
        r
    });
    let loop_wall = wall.elapsed().as_secs_f64();
    // The last replies (e.g. to STATE_QUITTING) reach their clients before the node ends.
    while node.flush_replies() {
        std::thread::sleep(POLL);
    }
    std::thread::sleep(LINGER);
    let stopped = stop.load(Ordering::SeqCst);
    let figures = summary(&sim, &outcome, stopped, node.dropped(), loop_wall);
    let finished = match recorder.map(|r| r.finish(&figures)).transpose() {
        Ok(p) => p,
        Err(e) => return Err(outcome.err().map_or(e.clone(), |o| format!("{o}; {e}"))),
    };
    let published = outcome?;
    let dropped = node.dropped();
    eprintln!(
        "rkforge-ros: published {published} samples up to t = {:e} s in {:.3} s wall{}{}",
        sim.time_now(),
        loop_wall,
        if dropped > 0 {
            format!(", {dropped} messages dropped (send window full)")
        } else {
            String::new()
        },
        finished.map_or(String::new(), |p| format!(", recorded {}", p.display()))
    );
    for (topic, n) in node.rejected() {
        if n > 0 {
            eprintln!("rkforge-ros: {n} commands ignored on {topic}");
        }
    }
    if stopped {
        eprintln!("rkforge-ros: stopped by a signal");
    }
    Ok(())
}

/// The run's summary for the recording: the runner's (`summary.json` of `rkforge run`:
/// status `ok`, `stopped` by a signal or `error`), with the node's own figures under `ros`:
/// samples published, messages dropped and the loop's wall time (s).
fn summary<S: NodeSim>(
    sim: &S,
    outcome: &Result<u64, String>,
    stopped: bool,
    dropped: u64,
    loop_wall: f64,
) -> String {
    let reason = format!("stopped by a signal at t = {:e} s", sim.time_now());
    let ending = match (outcome, stopped) {
        (Err(e), _) => Ending::Failed(e),
        (Ok(_), true) => Ending::Stopped(&reason),
        (Ok(_), false) => Ending::Finished,
    };
    let mut figures = sim.run_summary(loop_wall, ending);
    figures["ros"] = json!({
        "samples_published": outcome.as_ref().ok(),
        "messages_dropped": dropped,
        "loop_wall_s": loop_wall,
    });
    serde_json::to_string_pretty(&figures).unwrap_or_else(|e| e.to_string())
}

/// The sample marks after t = 0 every `interval` (s), as `rkforge run` samples its history
/// ([`rkforge_runner::schedule_every`]).
fn schedule(end: f64, interval: f64) -> Result<Vec<Mark>, String> {
    rkforge_runner::schedule_every(end, interval, 0).ok_or_else(|| {
        format!(
            "--publish-rate {:e} Hz gives {:e} samples over {end:e} s; at most {:e}",
            1.0 / interval,
            (end / interval).floor(),
            MAX_SAMPLES as f64
        )
    })
}

/// The simulation thread: a sample at t = 0, then one after each order of the main thread,
/// stepped through the runner's [`Run`] over `schedule`: [`ToSim::Continue`] steps to the
/// next mark (the last step of each interval shortened to land on it, as `rkforge run`),
/// [`ToSim::Step`] takes N of those steps (fewer on [`ToSim::Cancel`] or at the end),
/// [`ToSim::Reset`] rebuilds the simulation from `scene` (the same bits as at start).
/// Commands apply between steps as they come; `progress` counts the steps of the order
/// under way. Each sample records the runner's history row (penetration of every particle
/// against its bound), as `rkforge run` does.
fn simulate<S: NodeSim>(
    sim: &mut S,
    scene: &<S as Published>::Scene,
    schedule: Vec<Mark>,
    rx: &mut Receiver<ToSim>,
    tx: &Sender<FromSim>,
    progress: &AtomicU64,
) {
    let mut run = Run::new(sim, schedule);
    let mut sampler = Sampler::default();
    let mut steps = 0;
    loop {
        if let Err(e) = run.record(sim) {
            let _ = tx.send(FromSim::Failed(
                e.to_string(),
                Box::new(sampler.sample(sim)),
            ));
            return;
        }
        if tx
            .send(FromSim::Sample(sampler.sample(sim), run.finished(), steps))
            .is_err()
        {
            return;
        }
        let order = loop {
            match rx.recv() {
                Ok(ToSim::Command(c)) => command(sim, c),
                // A cancel that came after the steps it was meant to stop.
                Ok(ToSim::Cancel) => {}
                Ok(order) => break order,
                Err(_) => return,
            }
        };
        let until = match order {
            ToSim::Continue => Until::NextMark,
            ToSim::Step(n) => Until::Steps(n),
            ToSim::Reset => {
                match S::start(scene) {
                    Ok(s) => {
                        *sim = s;
                        run.restart(sim);
                        sampler = Sampler::default();
                    }
                    Err(e) => {
                        let _ = tx.send(FromSim::Failed(e, Box::new(sampler.sample(sim))));
                        return;
                    }
                }
                steps = 0;
                continue;
            }
            ToSim::Command(_) | ToSim::Cancel | ToSim::Stop => return,
        };
        // Between steps: the commands received apply; a cancel ends the order, a stop the
        // thread.
        let mut quit = false;
        let (orders, quitting) = (&mut *rx, &mut quit);
        let between = move |sim: &mut S, taken: u64| {
            progress.store(taken, Ordering::Relaxed);
            while let Ok(msg) = orders.try_recv() {
                match msg {
                    ToSim::Command(c) => command(sim, c),
                    ToSim::Cancel => return false,
                    _ => {
                        *quitting = true;
                        return false;
                    }
                }
            }
            true
        };
        match run.advance(sim, until, between) {
            Ok(advance) => steps = advance.steps,
            Err(e) => {
                let _ = tx.send(FromSim::Failed(
                    e.to_string(),
                    Box::new(sampler.sample(sim)),
                ));
                return;
            }
        }
        progress.store(steps, Ordering::Relaxed);
        if quit {
            return;
        }
    }
}

/// Apply a velocity command (a bad one is reported and ignored).
fn command<S: NodeSim>(sim: &mut S, c: Command) {
    if let Err(e) = sim.command_velocity(c.tool, c.velocity) {
        eprintln!("warning: command ignored: {e}");
    }
}

/// The main thread's side: DDS, MCAP, pacing, commands, parameters and the simulation
/// services.
struct MainLoop<'a> {
    node: &'a mut Node,
    recorder: Option<&'a mut Recorder>,
    to_sim: &'a Sender<ToSim>,
    stop: &'a AtomicBool,
    /// Lockstep, pacing and rate, changed at run time through the parameter services.
    settings: Settings,
    /// Pacing starts from this wall instant at this simulation time (s); set again when a
    /// setting changes or the simulation resumes.
    pace: (Instant, f64),
    /// Time of the last sample (s).
    time: f64,
    /// The `SimulationState`: playing, paused or stopped.
    state: u8,
    /// At the end time, pause instead of ending.
    hold_at_end: bool,
    /// The last sample published.
    current: Option<Sample>,
    /// Steps of the simulation's order under way (for the feedback of `SimulateSteps`).
    progress: &'a AtomicU64,
    /// The `SimulateSteps` goal executing.
    executing: Option<Executing>,
}

/// A `SimulateSteps` goal while its steps run.
struct Executing {
    id: GoalId,
    /// Steps the goal asks for.
    steps: u64,
    /// Steps completed in the last feedback, and when it was published.
    reported: (u64, Instant),
    /// Whether the simulation was told to stop early.
    cancel_sent: bool,
}

/// How a wait for the go-ahead ended.
#[derive(PartialEq)]
enum Go {
    /// Step on to the next sample.
    On,
    /// The state changed (paused, stopped, reset or stepped): decide again.
    Again,
    /// End the node (a signal or `STATE_QUITTING`).
    Quit,
}

impl MainLoop<'_> {
    /// Serve samples until the end (or a signal, or `STATE_QUITTING`); the number of
    /// samples published.
    fn serve(&mut self, from_sim: &Receiver<FromSim>) -> Result<u64, String> {
        let mut published = 0;
        let Some((mut at_end, _)) = self.receive(from_sim, &mut published)? else {
            return Ok(published);
        };
        loop {
            match self.go(from_sim, &mut published, &mut at_end)? {
                Go::Quit => return Ok(published),
                Go::Again => continue,
                Go::On => {}
            }
            if at_end {
                if !self.hold_at_end {
                    self.forward_commands()?;
                    return Ok(published);
                }
                self.state = SimulationState::STATE_PAUSED;
                continue;
            }
            self.send(ToSim::Continue)?;
            match self.receive(from_sim, &mut published)? {
                Some((end, _)) => at_end = end,
                None => return Ok(published),
            }
        }
    }

    /// Wait for the next sample (forwarding commands unless in lockstep), publish and record
    /// it: whether it is the end time, and the steps it took; `None` if a signal came first.
    fn receive(
        &mut self,
        from_sim: &Receiver<FromSim>,
        published: &mut u64,
    ) -> Result<Option<(bool, u64)>, String> {
        loop {
            match from_sim.recv_timeout(POLL) {
                Ok(FromSim::Sample(s, at_end, steps)) => {
                    self.time = s.time;
                    self.emit(&s)?;
                    *published += 1;
                    self.current = Some(s);
                    return Ok(Some((at_end, steps)));
                }
                Ok(FromSim::Failed(e, s)) => {
                    self.emit(&s)?;
                    return Err(format!("the simulation failed: {e}"));
                }
                Err(RecvTimeoutError::Timeout) => {
                    if self.stop.load(Ordering::SeqCst) {
                        return Ok(None);
                    }
                    if !self.settings.lockstep {
                        self.forward_commands()?;
                    }
                    self.tend_goal()?;
                }
                Err(RecvTimeoutError::Disconnected) => {
                    return Err("the simulation thread ended unexpectedly".into())
                }
            }
        }
    }
    fn send(&self, m: ToSim) -> Result<(), String> {
        self.to_sim
            .send(m)
            .map_err(|_| "the simulation thread ended unexpectedly".to_string())
    }

    fn emit(&mut self, s: &Sample) -> Result<(), String> {
        self.node.publish(s)?;
        if let Some(r) = self.recorder.as_deref_mut() {
            r.write(s)?;
        }
        Ok(())
    }

    /// Answer parameter requests; pacing restarts from now when a setting changed.
    fn poll_parameters(&mut self) {
        if self.node.serve_parameters(&mut self.settings) {
            self.pace = (Instant::now(), self.time);
        }
    }

    fn forward_commands(&mut self) -> Result<(), String> {
        for c in self.node.take_commands() {
            self.send(ToSim::Command(c))?;
        }
        Ok(())
    }

    /// After a sample: answer parameter and simulation requests; while playing, keep to the
    /// real-time factor and in lockstep wait for a command for every movable tool (the last
    /// one of each tool applies); while paused or stopped, hold the time.
    fn go(
        &mut self,
        from_sim: &Receiver<FromSim>,
        published: &mut u64,
        at_end: &mut bool,
    ) -> Result<Go, String> {
        let tools = self.node.commanded_tools();
        let mut latest: Vec<Option<f64>> = vec![None; tools.len()];
        let mut last_publish = Instant::now();
        loop {
            if self.stop.load(Ordering::SeqCst) {
                return Ok(Go::Quit);
            }
            self.poll_parameters();
            if let Some(go) = self.requests(from_sim, published, at_end)? {
                return Ok(go);
            }
            if let Some(go) = self.goals(from_sim, published, at_end)? {
                return Ok(go);
            }
            if self.state != SimulationState::STATE_PLAYING {
                if !self.settings.lockstep {
                    self.forward_commands()?;
                }
                std::thread::sleep(POLL);
                continue;
            }
            if let Some(r) = self.settings.real_time_factor {
                let (wall, sim) = self.pace;
                let due = wall + Duration::from_secs_f64(((self.time - sim) / r).max(0.0));
                if Instant::now() < due {
                    if !self.settings.lockstep {
                        self.forward_commands()?;
                    }
                    std::thread::sleep(POLL.min(due.saturating_duration_since(Instant::now())));
                    continue;
                }
            }
            // After the last sample there is no period left to command.
            if !self.settings.lockstep || *at_end {
                self.forward_commands()?;
                return Ok(Go::On);
            }
            for c in self.node.take_commands() {
                if let Some(k) = tools.iter().position(|&t| t == c.tool) {
                    latest[k] = Some(c.velocity);
                }
            }
            if latest.iter().all(Option::is_some) {
                for (&tool, v) in tools.iter().zip(&latest) {
                    if let Some(velocity) = *v {
                        self.send(ToSim::Command(Command { tool, velocity }))?;
                    }
                }
                return Ok(Go::On);
            }
            if last_publish.elapsed() >= REPUBLISH {
                if let Some(s) = &self.current {
                    self.node.publish(s)?;
                }
                last_publish = Instant::now();
            }
            std::thread::sleep(POLL);
        }
    }

    /// Carry out and answer the `simulation_interfaces` requests received; what the caller
    /// does next if one changed the state or the sample.
    fn requests(
        &mut self,
        from_sim: &Receiver<FromSim>,
        published: &mut u64,
        at_end: &mut bool,
    ) -> Result<Option<Go>, String> {
        let mut next = None;
        for r in self.node.poll_services(self.state) {
            let outcome = match r {
                Request::SetState(_, target) => {
                    transition(self.state, target, *at_end).map(|t| match t {
                        Transition::Play => {
                            self.state = SimulationState::STATE_PLAYING;
                            self.pace = (Instant::now(), self.time);
                            Go::Again
                        }
                        Transition::Pause => {
                            self.state = SimulationState::STATE_PAUSED;
                            Go::Again
                        }
                        Transition::Stop => {
                            self.state = SimulationState::STATE_STOPPED;
                            Go::Again
                        }
                        Transition::Quit => Go::Quit,
                    })
                }
                Request::Reset(_, scope) => check_reset(scope).map(|()| Go::Again),
                Request::Step(_, n) => {
                    check_step("StepSimulation", self.state, n, *at_end).map(|()| Go::Again)
                }
            };
            let result = match outcome {
                Err(refused) => refused,
                Ok(go) => {
                    let stop = matches!(r, Request::SetState(_, SimulationState::STATE_STOPPED));
                    let mut result = control::result(ResultMsg::RESULT_OK, "");
                    let order = match r {
                        Request::Step(_, n) => Some(ToSim::Step(n)),
                        Request::Reset(..) => Some(ToSim::Reset),
                        Request::SetState(..) if stop => Some(ToSim::Reset),
                        Request::SetState(..) => None,
                    };
                    let mut taken = 0;
                    if let Some(order) = order {
                        self.send(order)?;
                        let Some((end, steps)) = self.receive(from_sim, published)? else {
                            return Ok(Some(Go::Quit));
                        };
                        *at_end = end;
                        taken = steps;
                        // Pacing goes on from the new time (after a reset: from t = 0).
                        self.pace = (Instant::now(), self.time);
                    }
                    if let Request::Step(_, n) = r {
                        let steps = taken;
                        if steps < n {
                            result = control::result(
                                ResultMsg::RESULT_OPERATION_FAILED,
                                &format!("stopped at the end time after {steps} of {n} steps"),
                            );
                        }
                    }
                    next = Some(if next == Some(Go::Quit) { Go::Quit } else { go });
                    result
                }
            };
            self.node.answer(r, result);
        }
        Ok(next)
    }

    /// Carry out the `SimulateSteps` goals received, one after the other; what the caller
    /// does next if one of them stepped.
    fn goals(
        &mut self,
        from_sim: &Receiver<FromSim>,
        published: &mut u64,
        at_end: &mut bool,
    ) -> Result<Option<Go>, String> {
        let mut next = None;
        for (id, steps) in self.node.steps_action().poll() {
            match self.simulate_steps(id, steps, from_sim, published, at_end)? {
                Some(Go::Quit) => return Ok(Some(Go::Quit)),
                Some(go) => next = Some(go),
                None => {}
            }
        }
        Ok(next)
    }

    /// Carry out goal `id` of `steps` steps and end it: succeeded after all of them; aborted
    /// with `RESULT_OPERATION_FAILED` if refused as `StepSimulation` would refuse it, stopped
    /// at the end time, or stopped by a signal or a failure; canceled if asked to stop before
    /// its last step. What the caller does next if it stepped (`None` if refused).
    fn simulate_steps(
        &mut self,
        id: GoalId,
        steps: u64,
        from_sim: &Receiver<FromSim>,
        published: &mut u64,
        at_end: &mut bool,
    ) -> Result<Option<Go>, String> {
        let failed = |m: &str| control::result(ResultMsg::RESULT_OPERATION_FAILED, m);
        if let Err(refused) = check_step("SimulateSteps", self.state, steps, *at_end) {
            let action = self.node.steps_action();
            action.finish(id, GoalStatusEnum::Aborted, refused);
            return Ok(None);
        }
        if self.node.steps_action().canceling(id) {
            let result = failed(&format!("canceled before it started: 0 of {steps} steps"));
            let action = self.node.steps_action();
            action.finish(id, GoalStatusEnum::Canceled, result);
            return Ok(None);
        }
        self.node.steps_action().execute(id);
        self.progress.store(0, Ordering::Relaxed);
        self.executing = Some(Executing {
            id,
            steps,
            reported: (0, Instant::now()),
            cancel_sent: false,
        });
        self.send(ToSim::Step(steps))?;
        let received = self.receive(from_sim, published);
        let cancel_sent = self.executing.take().is_some_and(|g| g.cancel_sent);
        let (status, result, go) = match &received {
            Err(e) => (GoalStatusEnum::Aborted, failed(e), None),
            Ok(None) => {
                let done = self.progress.load(Ordering::Relaxed);
                let message =
                    format!("the node is stopping (a signal) after {done} of {steps} steps");
                (GoalStatusEnum::Aborted, failed(&message), Some(Go::Quit))
            }
            Ok(Some((end, done))) => {
                let done = *done;
                *at_end = *end;
                self.pace = (Instant::now(), self.time);
                self.node.steps_action().feedback(id, done, steps - done);
                let (status, result) = if done == steps {
                    (
                        GoalStatusEnum::Succeeded,
                        control::result(ResultMsg::RESULT_OK, ""),
                    )
                } else if cancel_sent {
                    let message = format!("canceled after {done} of {steps} steps");
                    (GoalStatusEnum::Canceled, failed(&message))
                } else {
                    let message = format!("stopped at the end time after {done} of {steps} steps");
                    (GoalStatusEnum::Aborted, failed(&message))
                };
                (status, result, Some(Go::Again))
            }
        };
        self.node.steps_action().finish(id, status, result);
        received.map(|_| go)
    }

    /// While a `SimulateSteps` goal executes: answer the action's requests (a goal that
    /// arrives now is aborted: one goal at a time), stop the steps when the goal is canceled
    /// and publish its feedback at most every [`FEEDBACK`].
    fn tend_goal(&mut self) -> Result<(), String> {
        let Some(goal) = self.executing.as_mut() else {
            return Ok(());
        };
        let action = self.node.steps_action();
        for (other, _) in action.poll() {
            let result = control::result(
                ResultMsg::RESULT_OPERATION_FAILED,
                "another SimulateSteps goal is executing (one at a time)",
            );
            action.finish(other, GoalStatusEnum::Aborted, result);
        }
        if !goal.cancel_sent && action.canceling(goal.id) {
            self.to_sim
                .send(ToSim::Cancel)
                .map_err(|_| "the simulation thread ended unexpectedly".to_string())?;
            goal.cancel_sent = true;
        }
        let done = self.progress.load(Ordering::Relaxed);
        if done > goal.reported.0 && goal.reported.1.elapsed() >= FEEDBACK {
            action.feedback(goal.id, done, goal.steps.saturating_sub(done));
            goal.reported = (done, Instant::now());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::schedule;

    #[test]
    fn samples_fall_on_history_rows_and_reach_the_end() {
        let times = |end, interval| -> Result<Vec<f64>, String> {
            Ok(schedule(end, interval)?.iter().map(|m| m.time).collect())
        };
        let s = times(0.003, 0.15e-3).unwrap();
        assert_eq!(s.len(), 20);
        assert_eq!(s[0], 0.15e-3);
        // 20 * 0.15e-3 as history.csv's last row has it, one rounding below 0.003.
        assert_eq!(*s.last().unwrap(), 20.0 * 0.15e-3);
        assert!(0.003 - s.last().unwrap() < 1e-18);
        assert_eq!(times(1.0, 0.4).unwrap(), [0.4, 0.8, 1.0]);
        assert_eq!(times(1.0, 2.0).unwrap(), [1.0]);
        let e = times(1.0, 1e-9).unwrap_err();
        assert!(e.contains("at most 1e7"), "{e}");
    }
}
