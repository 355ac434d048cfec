//! `rkforge`: run RKPM forging and impact scenes from the command line.
//!
//! With no arguments it runs the built-in Taylor bar (the paper's Tables 1-2) with the
//! two-point rule and prints its radius and height beside the paper's Table 3.

/// `println!` that drops what a closed standard output cannot take (`rkforge run ... |
/// head -1`): the run goes on and writes its files, where `println!` panicked.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

mod compare;
mod fmu;
mod output;
mod recording;
mod ring_chart;
mod run;
mod run_solid;
mod ssp;
mod sweep;

use clap::{Parser, Subcommand};
use recording::McapOptions;
use rkforge_core::scene::solid::is_solid;
use rkforge_core::scene::Friction;
use rkforge_core::scene::SolidScene;
use rkforge_core::scene_overrides::{parse_value, split_arg, split_values, Overridable};
use rkforge_core::{IntegrationRule, Scene, SceneSource};
use rkforge_runner::checkpoint::Restart;
use std::path::PathBuf;
use std::process::ExitCode;

/// The built-in default scene.
const DEFAULT_SCENE: &str = include_str!("../../scenes/taylor_bar.toml");

#[derive(Parser)]
#[command(
    name = "rkforge",
    version,
    about = "RKPM simulation of metal forming and impact (2D, explicit, J2 plasticity, penalty contact)"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and write summary.json, history.csv, VTK frames and PNG plots.
    Run(RunArgs),
    /// Run scenes with q4 and q2 and print the paper's Table 5 beside ours.
    Compare(CompareArgs),
    /// Pack a scene as an FMI 2.0 Co-Simulation FMU.
    Fmu(FmuArgs),
    /// Run a grid of resolutions, rules and time-step safety factors; error against wall time.
    Sweep(SweepArgs),
    /// A press plant and the scene's forging as one system (SSP 1.0): both FMUs connected,
    /// velocity to the forging, force, stroke, work and height back to the press
    Ssp(SspArgs),
    /// Friction calibration chart of a ring compression scene: inner diameter decrease
    /// against height reduction per friction law, beside Avitzur's upper bound for each
    /// shear factor m (ring_chart.csv, ring_chart_comparison.csv and ring_chart.png).
    RingChart(RingChartArgs),
}

#[derive(clap::Args)]
struct RingChartArgs {
    /// Ring scene file (TOML), e.g. scenes/ring_compression.toml.
    scene: PathBuf,
    /// Shear friction factors m, one curve each.
    #[arg(long, value_delimiter = ',', default_values_t = [0.0, 0.1, 0.2, 0.4, 0.6, 1.0])]
    m: Vec<f64>,
    /// Coulomb coefficients mu, one curve each.
    #[arg(long, value_delimiter = ',', default_values_t = [0.05, 0.1, 0.2])]
    mu: Vec<f64>,
    /// Output folder (default: out/ring_chart/).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

#[derive(clap::Args)]
struct SweepArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Grids, e.g. 11x26,21x51,41x101 (2D: particles along x and y) or 4x2x30,8x4x60 (3D: a
    /// cylinder's cells, core x ring x axial, or a box's particles along x, y, z); default:
    /// the scene's grid.
    #[arg(long, value_delimiter = ',')]
    resolution: Vec<String>,
    /// Integration rules, e.g. q4,q2,scni (default: q4,q2,scni in 2D, q4,q2 in 3D).
    #[arg(long, value_delimiter = ',')]
    integration: Vec<String>,
    /// Time-step safety factors (the scene's fixed step is replaced by these), e.g. 0.5,0.9.
    #[arg(long, value_delimiter = ',', default_values_t = [0.5])]
    dt_safety: Vec<f64>,
    /// Scene keys to vary, by dotted path, with a list of values (repeatable; the grid of
    /// all combinations), e.g. --set tools.top.friction=0.1,0.2.
    #[arg(long = "set", value_name = "KEY=V1,V2,...")]
    set: Vec<String>,
    /// Output folder (default: out/sweep_<scene name>/).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    #[command(flatten)]
    checkpoints: CheckpointArgs,
}

#[derive(clap::Args)]
struct FmuArgs {
    /// Scene file (TOML): a forging FMU of the scene.
    #[arg(required_unless_present = "press")]
    scene: Option<PathBuf>,
    /// Instead of a scene, a press plant: hydraulic, crank, hammer or screw (FMI 2.0;
    /// examples/presses' equations and defaults).
    #[arg(long, conflicts_with = "scene", value_parser = clap::builder::PossibleValuesParser::new(["hydraulic", "crank", "hammer", "screw"]))]
    press: Option<String>,
    /// The .fmu file to write.
    #[arg(long)]
    out: PathBuf,
    /// FMI version: 2 (FMI 2.0 Co-Simulation) or 3 (FMI 3.0 Co-Simulation).
    #[arg(long, default_value = "2", value_parser = clap::builder::PossibleValuesParser::new(["2", "3"]))]
    fmi: String,
}

#[derive(clap::Args)]
struct SspArgs {
    /// Scene file (TOML) of the forging.
    scene: PathBuf,
    /// The press: hydraulic, crank, hammer or screw.
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(["hydraulic", "crank", "hammer", "screw"]))]
    press: String,
    /// The scene's tool the press drives.
    #[arg(long, default_value = "ram")]
    tool: String,
    /// The .ssp file to write.
    #[arg(long)]
    out: PathBuf,
}

#[derive(clap::Args)]
struct CompareArgs {
    /// Scene files (TOML).
    #[arg(required = true)]
    scenes: Vec<PathBuf>,
    /// Runs per rule and scene (alternating q4 and q2); medians are reported.
    #[arg(long, default_value_t = 1)]
    repeat: usize,
    /// Output folder for the runs and compare.md (default: out/compare/).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

#[derive(clap::Args)]
struct RunArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Integration rule, overriding the scene's.
    #[arg(long, value_parser = ["q2", "q4", "scni"])]
    integration: Option<String>,
    /// Override a scene key by its dotted path (repeatable), e.g.
    /// --set tools.top.friction=0.1 --set time.end_s=2e-3; tools are addressed by name.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Output folder (default: out/<scene name>/).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (default: all cores); results are identical for any count.
    #[arg(long)]
    threads: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Skip VTK frames and PNG plots (summary and history only).
    #[arg(long)]
    no_frames: bool,
    /// Record the ROS 2 topics of `rkforge-ros` (namespace /rkforge) at every history
    /// sample to this MCAP file, without DDS.
    #[arg(long)]
    mcap: Option<PathBuf>,
    /// Chunk compression of the MCAP file: `zstd` or `none`.
    #[arg(long, default_value = "zstd")]
    mcap_compression: rkforge_messages::record::Compression,
    #[command(flatten)]
    checkpoints: CheckpointArgs,
}

/// Checkpoints of long runs, and going on after a kill.
#[derive(clap::Args)]
struct CheckpointArgs {
    /// Write a checkpoint into the output folder (`checkpoint.cbor`; a sweep: into each
    /// run's folder) at the first history sample or frame after every this many seconds of
    /// wall time (0: at every one), so that a killed run can go on with --resume; removed
    /// when the run ends.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    checkpoint_every_s: Option<f64>,
    /// Go on from the checkpoint in the output folder, written by a run of the same scene,
    /// overrides and frames: the same bits as a run that never stopped. A sweep keeps the
    /// runs it finished before (their scene.json the same scene) and goes on from each
    /// run's checkpoint.
    #[arg(long)]
    resume: bool,
}

impl CheckpointArgs {
    /// The checkpoints and resumption `--checkpoint-every-s` and `--resume` ask for.
    fn restart(&self) -> Result<Restart, String> {
        let every = match self.checkpoint_every_s {
            Some(s) if !(s.is_finite() && s >= 0.0) => {
                return Err(format!(
                    "--checkpoint-every-s {s}: give a number of seconds, 0 or more"
                ))
            }
            Some(s) => Some(std::time::Duration::from_secs_f64(s)),
            None => None,
        };
        Ok(Restart {
            every,
            resume: self.resume,
        })
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        None => default_run(),
        Some(Command::Run(a)) => run_command(a),
        Some(Command::Compare(a)) => compare_command(a),
        Some(Command::Sweep(a)) => sweep_command(a),
        Some(Command::Ssp(a)) => ssp::pack(&a.scene, &a.press, &a.tool, &a.out)
            .map(|()| say!("wrote {}", a.out.display())),
        Some(Command::RingChart(a)) => ring_chart_command(a),
        Some(Command::Fmu(a)) => match (&a.scene, &a.press) {
            (Some(scene), _) => fmu::pack(scene, &a.out, fmu::Version::from_arg(&a.fmi)),
            (None, Some(press)) if a.fmi == "2" => fmu::pack_press(press, 1.0, &a.out),
            (None, Some(_)) => Err("--press packs an FMI 2.0 FMU (leave out --fmi 3)".into()),
            (None, None) => Err("give a scene file or --press".into()),
        }
        .map(|id| say!("wrote {} (model identifier {id})", a.out.display())),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn set_threads(n: Option<usize>) -> Result<(), String> {
    rkforge_core::set_threads(n).map_err(|e| e.to_string())
}

/// The scene file with the `--set KEY=VALUE` overrides of `rkforge run` applied.
fn scene_with_overrides(path: &std::path::Path, sets: &[String]) -> Result<Scene, String> {
    with_sets(
        SceneSource::from_file(path).map_err(|e| e.to_string())?,
        sets,
    )
}

/// The scene of `source` (2D or 3D) with the `--set KEY=VALUE` overrides applied.
fn with_sets<S: Overridable + Clone>(
    mut source: SceneSource<S>,
    sets: &[String],
) -> Result<S, String> {
    source.set_args(sets).map_err(|e| e.to_string())?;
    Ok(source.scene().clone())
}

/// A 3D scene file (`model.kinematics = "3d"`) with the `--set KEY=VALUE` overrides
/// applied; `None` when the file is a 2D scene.
fn solid_scene(path: &std::path::Path, sets: &[String]) -> Result<Option<SolidScene>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    if !is_solid(&text) {
        return Ok(None);
    }
    let source = SceneSource::<SolidScene>::of_text(&text, &path.display().to_string(), vec![]);
    with_sets(source.map_err(|e| e.to_string())?, sets).map(Some)
}

/// `rkforge run` of a 3D scene: summary, history, frames and picture, and with `--mcap` the
/// recording of its topics.
fn run_solid_command(a: &RunArgs, mut scene: SolidScene) -> Result<(), String> {
    if let Some(r) = a.integration.as_deref().and_then(IntegrationRule::parse) {
        scene.discretization.integration = r;
        if let Some((key, message)) = scene.validate().into_iter().next() {
            return Err(format!("--integration: `{key}` {message}"));
        }
    }
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    let report = run_solid::run(
        &scene,
        &out,
        !a.no_frames,
        mcap_options(a).as_ref(),
        restart(a)?,
    )?;
    say!(
        "{}",
        rkforge_runner::references_beside(&scene.name, &scene.reference, &report.summary)
    );
    let s = &report.summary;
    print_resumed(s);
    say!(
        "{:.3} us per particle-step; energy balance {:.2e}; deepest in a tool {:.3e} m, beyond a symmetry plane {:.3e} m",
        s["us_per_particle_step"].as_f64().unwrap_or(0.0),
        s["energy"]["balance_error_rel"].as_f64().unwrap_or(0.0),
        s["contact"]["max_penetration_m"].as_f64().unwrap_or(0.0),
        s["contact"]["max_beyond_plane_m"].as_f64().unwrap_or(0.0),
    );
    say!("{}", run::stage_line(s));
    say!("results in {}", out.display());
    match report.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The recording `--mcap` asks for, if it does.
fn mcap_options(a: &RunArgs) -> Option<McapOptions> {
    a.mcap.as_ref().map(|path| McapOptions {
        path: path.clone(),
        scene_file: a.scene.clone(),
        compression: a.mcap_compression,
    })
}

/// Say where a resumed run went on from its checkpoints (summary.json's `resumed_at_s`).
fn print_resumed(summary: &serde_json::Value) {
    if let Some(at) = summary["resumed_at_s"].as_array() {
        let times: Vec<String> = at
            .iter()
            .map(|t| format!("{:.4e} s", t.as_f64().unwrap_or(f64::NAN)))
            .collect();
        say!(
            "resumed from its checkpoint at t = {} (wall and stage times over every process)",
            times.join(", ")
        );
    }
}

/// The checkpoints and resumption of a run, which a recording cannot have.
fn restart(a: &RunArgs) -> Result<Restart, String> {
    let restart = a.checkpoints.restart()?;
    if a.mcap.is_some() && (restart.every.is_some() || restart.resume) {
        return Err(
            "--mcap: a recording cannot be resumed; record without --checkpoint-every-s and \
             --resume, or leave out --mcap"
                .into(),
        );
    }
    Ok(restart)
}

fn run_command(a: RunArgs) -> Result<(), String> {
    set_threads(a.threads)?;
    if let Some(scene) = solid_scene(&a.scene, &a.set)? {
        return run_solid_command(&a, scene);
    }
    let mut scene = scene_with_overrides(&a.scene, &a.set)?;
    if let Some(r) = a.integration.as_deref().and_then(IntegrationRule::parse) {
        scene = scene.with_integration(r);
    }
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    let opts = run::Options {
        out,
        progress: !a.quiet,
        frames: !a.no_frames,
        mcap: mcap_options(&a),
        restart: restart(&a)?,
    };
    let report = run::run(&scene, &opts)?;
    say!("{}", report.table());
    print_resumed(&report.summary);
    say!("{}", run::stage_line(&report.summary));
    for w in report.summary["warnings"].as_array().into_iter().flatten() {
        eprintln!("warning: {}", w.as_str().unwrap_or_default());
    }
    say!("results in {}", opts.out.display());
    Ok(())
}

fn ring_chart_command(a: RingChartArgs) -> Result<(), String> {
    set_threads(a.threads)?;
    let scene = Scene::from_file(&a.scene).map_err(|e| e.to_string())?;
    let laws: Vec<Friction> =
        a.m.iter()
            .map(|&m| Friction::Shear { m })
            .chain(a.mu.iter().map(|&mu| Friction::Coulomb { mu }))
            .collect();
    for (k, law) in laws.iter().enumerate() {
        if let Some((_, message)) = law.validate().into_iter().next() {
            let option = if k < a.m.len() { "--m" } else { "--mu" };
            return Err(format!("{option} {}: {message}", law.coefficient()));
        }
    }
    let out = a
        .out
        .unwrap_or_else(|| PathBuf::from("out").join("ring_chart"));
    match ring_chart::chart(&scene, &laws, &out)? {
        Some(rows) => {
            say!("Decrease of the inner diameter (%), simulated against Avitzur's upper bound:");
            say!(
                "{}",
                ring_chart::comparison_table(&rows).trim_end_matches('\n')
            );
            say!(
                "ring_chart.csv, ring_chart_comparison.csv and ring_chart.png in {}",
                out.display()
            );
        }
        None => {
            say!(
                "no upper-bound reference: the scene is not a half ring mirrored at its y_min edge"
            );
            say!("ring_chart.csv and ring_chart.png in {}", out.display());
        }
    }
    Ok(())
}

fn compare_command(a: CompareArgs) -> Result<(), String> {
    set_threads(a.threads)?;
    if a.repeat == 0 {
        return Err("--repeat must be at least 1".into());
    }
    let out = a
        .out
        .unwrap_or_else(|| PathBuf::from("out").join("compare"));
    let compared = compare::compare(&a.scenes, a.repeat, &out)?;
    say!("{}", compared.table);
    say!("runs and compare.md in {}", out.display());
    match compared.failed {
        0 => Ok(()),
        n => Err(format!(
            "the runs of {n} of {} scenes failed (their rows in compare.md say why)",
            a.scenes.len()
        )),
    }
}

/// The scenes of the `--set KEY=V1,V2` grid (every combination, the first key varying
/// slowest), each built by `build` from its overrides and validated before anything runs.
fn sweep_cases<S>(
    sets: &[String],
    build: impl Fn(&[(String, toml::Value)]) -> Result<S, String>,
) -> Result<Vec<sweep::Case<S>>, String> {
    let mut cases = vec![sweep::Case {
        inputs: Vec::new(),
        scene: build(&[])?,
    }];
    let mut overrides: Vec<Vec<(String, toml::Value)>> = vec![Vec::new()];
    for arg in sets {
        let (key, values) = split_arg(arg).map_err(|e| e.to_string())?;
        let mut next = Vec::new();
        let mut next_overrides = Vec::new();
        for (case, o) in cases.iter().zip(&overrides) {
            for text in split_values(values) {
                let mut o = o.clone();
                o.push((key.to_string(), parse_value(text)));
                let mut inputs = case.inputs.clone();
                inputs.push((key.to_string(), text.trim().to_string()));
                next.push(sweep::Case {
                    inputs,
                    scene: build(&o)?,
                });
                next_overrides.push(o);
            }
        }
        cases = next;
        overrides = next_overrides;
    }
    Ok(cases)
}

fn sweep_command(a: SweepArgs) -> Result<(), String> {
    set_threads(a.threads)?;
    let text = rkforge_core::scene::read_text(&a.scene).map_err(|e| e.to_string())?;
    let file = a.scene.display().to_string();
    if is_solid(&text) {
        return sweep_scenes(&a, &source_cases::<SolidScene>(&text, &file, &a.set)?);
    }
    sweep_scenes(&a, &source_cases::<Scene>(&text, &file, &a.set)?)
}

/// The cases of the `--set` grid of a scene's text (2D or 3D), each validated.
fn source_cases<S: Overridable + Clone>(
    text: &str,
    file: &str,
    sets: &[String],
) -> Result<Vec<sweep::Case<S>>, String> {
    sweep_cases(sets, |o| {
        SceneSource::<S>::of_text(text, file, o.to_vec())
            .map(|built| built.scene().clone())
            .map_err(|e| e.to_string())
    })
}

/// The sweep of `cases` (2D or 3D) with the options of `a`, checked before anything runs.
fn sweep_scenes<S: sweep::Sweepable>(
    a: &SweepArgs,
    cases: &[sweep::Case<S>],
) -> Result<(), String> {
    let scene = &cases[0].scene;
    let mut rules = Vec::new();
    for r in &a.integration {
        rules.push(
            IntegrationRule::parse(r)
                .ok_or_else(|| format!("--integration `{r}`: expected q4, q2 or scni"))?,
        );
    }
    if rules.is_empty() {
        rules = IntegrationRule::ALL.to_vec();
    }
    if let Some(s) = a.dt_safety.iter().find(|s| !(**s > 0.0 && **s <= 1.0)) {
        return Err(format!("--dt-safety {s}: must lie in (0, 1]"));
    }
    let mut grids = Vec::new();
    for r in &a.resolution {
        let parsed: Option<Vec<usize>> = r.split('x').map(|n| n.trim().parse().ok()).collect();
        match parsed {
            Some(g) if g.len() == S::DIMENSIONS && g.iter().all(|&n| n >= S::MIN_COUNT) => {
                scene
                    .variant(rules[0], &g, a.dt_safety.first().copied().unwrap_or(0.5))
                    .map_err(|e| format!("--resolution `{r}`: {e}"))?;
                grids.push(g);
            }
            _ => {
                return Err(format!(
                    "--resolution `{r}`: expected {}",
                    scene.grid_form()
                ))
            }
        }
    }
    if grids.is_empty() {
        grids.push(scene.grid());
    }
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("sweep_{}", scene.name())));
    let restart = a.checkpoints.restart()?;
    let swept = sweep::sweep(cases, &grids, &rules, &a.dt_safety, &out, restart)?;
    say!("{}", swept.table);
    say!("sweep.csv, sweep.md and sweep.png in {}", out.display());
    match swept.failed {
        0 => Ok(()),
        n => Err(format!(
            "{n} of {} runs failed (their rows in sweep.csv and sweep.md say why); the others are in the table",
            swept.runs
        )),
    }
}

fn default_run() -> Result<(), String> {
    let scene = Scene::from_str_named(DEFAULT_SCENE, "scenes/taylor_bar.toml (built in)")
        .map_err(|e| e.to_string())?
        .with_integration(IntegrationRule::Q2);
    let opts = run::Options {
        out: PathBuf::from("out").join(&scene.name),
        progress: true,
        frames: true,
        mcap: None,
        restart: Default::default(),
    };
    say!(
        "rkforge: {} ({}), the paper's Table 3 setting",
        scene.description,
        scene.discretization.integration.name()
    );
    let report = run::run(&scene, &opts)?;
    say!("{}", report.table());
    print_resumed(&report.summary);
    say!("{}", run::stage_line(&report.summary));
    say!(
        "results in {} (summary.json, history.csv, frames/, *.png)",
        opts.out.display()
    );
    say!(
        "run another scene: rkforge run scenes/<name>.toml [--integration q2|q4|scni] [--out DIR]"
    );
    Ok(())
}
