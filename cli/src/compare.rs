//! `rkforge compare`: each scene with q4 and q2, the paper's Table 5 beside ours.

use crate::run;
use rkforge_core::{IntegrationRule, Scene};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What one run of one rule gave.
struct Outcome {
    wall: Vec<f64>,
    /// Stress stage wall time per integration point and step (ns), one per run.
    per_point: Vec<f64>,
    /// Wall time of the per-particle stages (force gather and predictor, contact,
    /// integration, output) per particle and step (ns), one per run.
    per_particle: Vec<f64>,
    lateral: f64,
    height: f64,
    peak_force: f64,
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

fn reference_wall(scene: &Scene, rule: IntegrationRule) -> Option<f64> {
    scene
        .reference
        .iter()
        .filter(|r| r.integration == Some(rule))
        .find_map(|r| r.values.get("wall_s").copied())
}

fn outcome(summary: &Value) -> Outcome {
    let w = &summary["workpiece"];
    let lateral = w
        .get("radius_m")
        .or_else(|| w.get("width_m"))
        .and_then(Value::as_f64)
        .unwrap_or(f64::NAN);
    let peak_force = summary["tools"]
        .as_array()
        .map(|t| {
            t.iter()
                .filter_map(|t| t["peak_force_N"].as_f64())
                .fold(0.0, f64::max)
        })
        .unwrap_or(0.0);
    let number = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
    let stage = |k: &str| number(&summary["stage_seconds"][k]);
    let steps = number(&summary["steps"]);
    let per_step = |seconds: f64, count: &str| seconds * 1e9 / (steps * number(&summary[count]));
    let particle_stages = ["internal_force", "contact", "integration", "output"]
        .map(stage)
        .iter()
        .sum();
    Outcome {
        wall: vec![number(&summary["wall_s"])],
        per_point: vec![per_step(stage("stress"), "integration_points")],
        per_particle: vec![per_step(particle_stages, "particles")],
        lateral,
        height: w["height_m"].as_f64().unwrap_or(f64::NAN),
        peak_force,
    }
}

/// What a comparison wrote: the table (compare.md's text) and the scenes whose runs failed.
pub struct Compared {
    /// compare.md's text.
    pub table: String,
    /// Scenes with a failed run (each a row of the table, its reason under the table).
    pub failed: usize,
}

/// Run every scene `repeat` times with each rule (alternating), write `compare.md` into
/// `out`, and return the table: wall times and their ratio beside the paper's Table 5, the
/// stress stage's cost per integration point and step and the per-particle stages' cost
/// per particle and step (medians, ns), and how far the two rules' results differ. A scene
/// whose run fails is a row saying so, its reason under the table, and the others go on.
pub fn compare(scenes: &[PathBuf], repeat: usize, out: &Path) -> Result<Compared, String> {
    let mut table = String::new();
    let _ = writeln!(
        table,
        "| scene | q4 wall (s) | q2 wall (s) | q2 / q4 | paper q4 | paper q2 | paper q2 / q4 | q4 ns / point-step | q2 ns / point-step | q4 ns / particle-step | q2 ns / particle-step | lateral q2 - q4 | height q2 - q4 | peak force q2 / q4 - 1 |"
    );
    let _ = writeln!(
        table,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    let mut failures = Vec::new();
    for path in scenes {
        let scene = Scene::from_file(path).map_err(|e| e.to_string())?;
        let mut results: Vec<Option<Outcome>> = vec![None, None];
        let mut failure = None;
        'runs: for _ in 0..repeat {
            for (k, rule) in [IntegrationRule::Q4, IntegrationRule::Q2]
                .into_iter()
                .enumerate()
            {
                let s = scene.clone().with_integration(rule);
                let opts = run::Options {
                    out: out.join(&scene.name).join(rule.name()),
                    progress: false,
                    frames: false,
                    mcap: None,
                    restart: Default::default(),
                };
                let report = match run::run(&s, &opts) {
                    Ok(report) => report,
                    Err(e) => {
                        failure = Some(format!("{} ({}): {e}", scene.name, rule.name()));
                        break 'runs;
                    }
                };
                let o = outcome(&report.summary);
                match &mut results[k] {
                    Some(prev) => {
                        prev.wall.extend(o.wall);
                        prev.per_point.extend(o.per_point);
                        prev.per_particle.extend(o.per_particle);
                    }
                    slot => *slot = Some(o),
                }
            }
        }
        if let Some(why) = failure {
            eprintln!("{why}");
            let _ = writeln!(
                table,
                "| {} | failed: see below |{}",
                scene.name,
                " |".repeat(13)
            );
            failures.push(why);
            continue;
        }
        let (Some(q4), Some(q2)) = (&results[0], &results[1]) else {
            continue;
        };
        let (w4, w2) = (median(&q4.wall), median(&q2.wall));
        let paper = |r| reference_wall(&scene, r).map_or("-".to_string(), |v| format!("{v:.0}"));
        let paper_ratio = match (
            reference_wall(&scene, IntegrationRule::Q4),
            reference_wall(&scene, IntegrationRule::Q2),
        ) {
            (Some(a), Some(b)) => format!("{:.3}", b / a),
            _ => "-".into(),
        };
        let _ = writeln!(
            table,
            "| {} | {w4:.3} | {w2:.3} | {:.3} | {} | {} | {paper_ratio} | {:.1} | {:.1} | {:.1} | {:.1} | {:+.3} mm | {:+.3} mm | {:+.2} % |",
            scene.name,
            w2 / w4,
            paper(IntegrationRule::Q4),
            paper(IntegrationRule::Q2),
            median(&q4.per_point),
            median(&q2.per_point),
            median(&q4.per_particle),
            median(&q2.per_particle),
            (q2.lateral - q4.lateral) * 1e3,
            (q2.height - q4.height) * 1e3,
            (q2.peak_force / q4.peak_force - 1.0) * 100.0,
        );
    }
    let note = format!(
        "\nWall times are medians of {repeat} run(s) per rule on {} thread(s); the paper's are CPU times on a Pentium 4 (3.2 GHz). \
         Per point-step: the stress stage (deformation gradient, material update, scatter of the internal force) over integration points x steps; \
         per particle-step: the force gather and predictor, contact, integration and output stages over particles x steps (wall time, ns).\n",
        rayon::current_num_threads()
    );
    table.push_str(&note);
    for why in &failures {
        let _ = writeln!(table, "\n- failed: {why}");
    }
    std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
    std::fs::write(out.join("compare.md"), &table)
        .map_err(|e| format!("cannot write compare.md: {e}"))?;
    Ok(Compared {
        table,
        failed: failures.len(),
    })
}
