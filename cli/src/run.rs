//! One run of a scene: the time loop, samples, frames and the files written.

use crate::output::{plots, vtu, HistoryPlots, Plotted};
use crate::recording::{Mcap, McapOptions};
use indicatif::{ProgressBar, ProgressStyle};
use rkforge_core::{Kinematics, Scene, Simulation};
use rkforge_runner::checkpoint::{self, Restart};
use rkforge_runner::{Checkpoints, Observer, Run};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// A frame's shape for the plots.
#[derive(Serialize, Deserialize)]
struct Shape {
    /// Time (s).
    time: f64,
    /// Particle positions (m).
    positions: Vec<[f64; 2]>,
    /// Equivalent plastic strain per particle.
    plastic_strain: Vec<f64>,
    /// Tool polylines (m).
    tools: Vec<Vec<[f64; 2]>>,
    /// The tools' fill points (m) with whether each is filled.
    marks: Vec<([f64; 2], bool)>,
    /// The laps: each one's label and its surface particles' positions (m).
    laps: Vec<plots::Lap>,
    /// In a scene with temperature, the particles' temperatures (degrees C).
    temperature: Option<Vec<f64>>,
}

/// How to run.
pub struct Options {
    /// Output folder.
    pub out: PathBuf,
    /// Show a progress bar.
    pub progress: bool,
    /// Write VTK frames and PNG plots.
    pub frames: bool,
    /// Record the ROS 2 topics of `rkforge-ros` (namespace `/rkforge`) at every history
    /// sample to an MCAP file; SIGINT and SIGTERM then stop the run and finish the files.
    pub mcap: Option<McapOptions>,
    /// Checkpoints written, and whether the run goes on from its checkpoint in `out`.
    pub restart: Restart,
}

/// What a finished run produced.
pub struct Report {
    /// The summary written to summary.json.
    pub summary: Value,
    scene: Scene,
}

impl Report {
    /// Our figures beside the scene's references, as a text table.
    pub fn table(&self) -> String {
        rkforge_runner::reference_table(&self.scene, &self.summary)
    }
}

/// Where the wall time of a run went, from its summary (2D or 3D): each stage of
/// `stage_seconds` with its share of the run.
pub fn stage_line(summary: &Value) -> String {
    let t = &summary["stage_seconds"];
    let get = |k: &str| t[k].as_f64().unwrap_or(0.0);
    let wall = summary["wall_s"].as_f64().unwrap_or(0.0);
    let share = |x: f64| if wall > 0.0 { 100.0 * x / wall } else { 0.0 };
    let stages = [
        ("stress", "strain and stress"),
        ("internal_force", "internal force"),
        ("contact", "contact"),
        ("integration", "integration"),
        ("output", "output"),
    ];
    let mut line = format!(
        "stages: setup {:.2} s (shape functions {:.2} s)",
        get("setup"),
        get("shape_functions")
    );
    let mut counted = get("setup");
    // The heat stage, in a scene whose heat moves.
    let heat = t.get("heat").map(|_| ("heat", "heat"));
    for (key, name) in stages.into_iter().chain(heat) {
        counted += get(key);
        line += &format!(", {name} {:.2} s ({:.0} %)", get(key), share(get(key)));
    }
    line + &format!(
        ", other {:.2} s of {wall:.2} s wall",
        (wall - counted).max(0.0)
    )
}

/// Run `scene` to its end time, writing results into `opts.out`. A run that fails midway
/// still writes its history and a summary with `"status": "error"` before returning the error.
pub fn run(scene: &Scene, opts: &Options) -> Result<Report, String> {
    std::fs::create_dir_all(&opts.out)
        .map_err(|e| format!("cannot create {}: {e}", opts.out.display()))?;
    let wall = Instant::now();
    let mut sim = Simulation::new(scene).map_err(|e| e.to_string())?;
    let end = scene.time.end_s;
    let frames = if opts.frames { scene.output.frames } else { 0 };
    let mut started =
        checkpoint::start::<_, Taken>(&mut sim, frames, Some(&opts.out), opts.restart)?;
    let mut outputs = Outputs {
        opts,
        bar: progress_bar(opts.progress, end),
        mcap: match &opts.mcap {
            Some(m) => Some(Mcap::start(m, scene)?),
            None => None,
        },
        taken: std::mem::take(&mut started.taken),
        checkpoints: started.checkpoints.take(),
    };
    let outcome = started.go(&mut sim, frames, &mut outputs)?;
    outputs.bar.finish_and_clear();
    let clock = Instant::now();
    outcome.history.write(&opts.out.join("history.csv"))?;
    if frames > 0 {
        vtu::write_pvd(&opts.out.join("frames.pvd"), &outputs.taken.frames)
            .map_err(|e| e.to_string())?;
    }
    // Plots come before the summary so that their time is in it; the summary is written
    // even when a plot fails, and the plot's error is returned after it.
    let plotted = if opts.frames {
        outcome
            .history
            .plots(&Plotted::plane(&sim), &opts.out)
            .and_then(|()| write_stages(&sim, opts, &outputs.taken.shapes))
    } else {
        Ok(())
    };
    let output_time = outcome.output_time + clock.elapsed();
    let mut summary = rkforge_runner::summary(
        &sim,
        started.wall_s + wall.elapsed().as_secs_f64(),
        started.output_s + output_time.as_secs_f64(),
        outcome.ending(),
    );
    started.mark(&mut summary);
    let text = serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?;
    std::fs::write(opts.out.join("summary.json"), &text)
        .map_err(|e| format!("cannot write summary.json: {e}"))?;
    if let Some(m) = outputs.mcap.take() {
        m.finish(&text)?;
    }
    plotted?;
    match outcome.failure {
        Some(e) => Err(format!(
            "{e}\n(history and summary up to the failure are in {})",
            opts.out.display()
        )),
        None => Ok(Report {
            summary,
            scene: scene.clone(),
        }),
    }
}

/// What `rkforge run` adds to the bare run: frames and the shapes of the stage plot, the
/// MCAP recording, the progress bar and the checkpoints.
struct Outputs<'a> {
    opts: &'a Options,
    bar: ProgressBar,
    mcap: Option<Mcap>,
    taken: Taken,
    checkpoints: Option<Checkpoints>,
}

/// The frames taken so far: what a checkpoint keeps of them.
#[derive(Default, Serialize, Deserialize)]
struct Taken {
    /// Time and file of each VTK frame, for frames.pvd.
    frames: Vec<(f64, String)>,
    /// Each frame's shape, for the stage plot.
    shapes: Vec<Shape>,
}

impl Observer for Outputs<'_> {
    fn sample(&mut self, sim: &Simulation) -> Result<(), String> {
        match &mut self.mcap {
            Some(m) => m.record(sim),
            None => Ok(()),
        }
    }

    fn frame(&mut self, sim: &Simulation) -> Result<(), String> {
        write_frame(sim, self.opts, &mut self.taken)
    }

    fn stop(&self, sim: &Simulation) -> Option<String> {
        self.mcap.as_ref().and_then(|m| m.interrupted(sim.time()))
    }

    fn progress(&mut self, sim: &Simulation) {
        let end = sim.scene().time.end_s;
        self.bar.set_position((sim.time() / end * 1000.0) as u64);
    }

    fn checkpoint(&mut self, sim: &Simulation, run: &Run, output: Duration) -> Result<(), String> {
        checkpoint::keep(self.checkpoints.as_mut(), sim, run, &self.taken, output)
    }
}

fn progress_bar(show: bool, end: f64) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(1000);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% of {msg} (eta {eta})",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(format!("{:.3e} s", end));
    bar
}

/// Grid cells as quads of particle indices.
pub fn quads(sim: &Simulation) -> Vec<[u32; 4]> {
    let (nx, ny) = sim.grid();
    let id = |i: usize, j: usize| (j * nx + i) as u32;
    let mut q = Vec::with_capacity((nx - 1) * (ny - 1));
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            q.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    q
}

fn axis_labels(sim: &Simulation) -> (&'static str, &'static str) {
    match sim.scene().model.kinematics {
        Kinematics::Axisymmetric => ("r (mm)", "z (mm)"),
        Kinematics::PlaneStrain => ("x (mm)", "y (mm)"),
    }
}

/// A VTK frame and the shape kept for the stage plot.
fn write_frame(sim: &Simulation, opts: &Options, taken: &mut Taken) -> Result<(), String> {
    let dir = opts.out.join("frames");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let f = sim.fields();
    let name = format!("frame_{:04}.vtu", taken.frames.len());
    let mut scalars: Vec<(&str, &[f64])> = vec![
        ("plastic_strain", &f.plastic_strain),
        ("von_mises_Pa", &f.von_mises),
    ];
    if let Some(t) = &f.temperature {
        scalars.push(("temperature_C", t));
    }
    scalars.push(("lap", &f.lap));
    vtu::write_vtu(
        &dir.join(&name),
        &f.positions,
        &quads(sim),
        &scalars,
        &[
            ("displacement_m", &f.displacement),
            ("velocity_m_per_s", &f.velocity),
        ],
    )
    .map_err(|e| format!("cannot write {name}: {e}"))?;
    taken.frames.push((sim.time(), format!("frames/{name}")));
    let tools = sim.tools().iter().map(|t| t.vertices()).collect();
    let marks = sim
        .fill_points()
        .iter()
        .map(|p| (p.at_m, p.filled.is_some()))
        .collect();
    let laps = sim
        .laps()
        .iter()
        .enumerate()
        .map(|(k, lap)| plots::Lap {
            label: format!("lap {}", k + 1),
            points: lap.particles.iter().map(|&j| f.positions[j]).collect(),
        })
        .collect();
    taken.shapes.push(Shape {
        time: sim.time(),
        positions: f.positions,
        plastic_strain: f.plastic_strain,
        tools,
        marks,
        laps,
        temperature: f.temperature,
    });
    Ok(())
}

/// The final deformed shape and the stages side by side, coloured by plastic strain.
fn write_stages(sim: &Simulation, opts: &Options, shapes: &[Shape]) -> Result<(), String> {
    let Some(last) = shapes.last() else {
        return Ok(());
    };
    let q = quads(sim);
    let name = &sim.scene().name;
    fn panel<'a>(last: &'a Shape, values: &'a [f64]) -> plots::Stage<'a> {
        plots::Stage {
            title: String::new(),
            positions: &last.positions,
            values,
            tools: last.tools.clone(),
            marks: last.marks.clone(),
            laps: last.laps.clone(),
        }
    }
    plots::shape_plot(
        &opts.out.join("shape.png"),
        &format!("{name}: plastic strain at t = {:.3e} s", last.time),
        &q,
        panel(last, &last.plastic_strain),
        "equivalent plastic strain",
        axis_labels(sim),
        1e3,
    )?;
    if let Some(temperature) = &last.temperature {
        plots::shape_plot(
            &opts.out.join("temperature.png"),
            &format!("{name}: temperature at t = {:.3e} s", last.time),
            &q,
            panel(last, temperature),
            "temperature (C)",
            axis_labels(sim),
            1e3,
        )?;
    }
    let stages: Vec<plots::Stage> = shapes
        .iter()
        .map(|s| plots::Stage {
            title: format!("t = {:.3e} s", s.time),
            positions: &s.positions,
            values: &s.plastic_strain,
            tools: s.tools.clone(),
            marks: s.marks.clone(),
            laps: s.laps.clone(),
        })
        .collect();
    plots::stages_plot(
        &opts.out.join("stages.png"),
        &format!(
            "{name}: deformation stages ({})",
            sim.scene().discretization.integration.name()
        ),
        &q,
        &stages,
        "equivalent plastic strain",
        axis_labels(sim),
        1e3,
    )
}
