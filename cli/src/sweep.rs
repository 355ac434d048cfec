//! `rkforge sweep`: the speed/accuracy trade of a scene over a grid of resolutions,
//! integration rules and time-step safety factors.
//!
//! Error is measured against a converged reference: for each rule, the two or three finest
//! resolutions (at the smallest safety factor) are extrapolated (Richardson, with the order
//! estimated from three grids when they converge monotonically, else order 1); the reference
//! is the mean over the rules, its uncertainty the larger of their spread and the distance of
//! the finest run from its extrapolation.

use crate::output::plots;
use crate::run;
use rkforge_core::{IntegrationRule, Scene};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

/// One run of the grid.
struct Row {
    rule: IntegrationRule,
    grid: [usize; 2],
    safety: f64,
    steps: u64,
    wall: f64,
    memory: f64,
    values: Vec<f64>,
}

/// The quantities compared: the lateral size, the height, and the peak force of moving tools.
fn quantities(summary: &Value) -> (Vec<&'static str>, Vec<f64>) {
    let w = &summary["workpiece"];
    let (name, lateral) = match w.get("radius_m") {
        Some(r) => ("radius_m", r.as_f64().unwrap_or(f64::NAN)),
        None => ("width_m", w["width_m"].as_f64().unwrap_or(f64::NAN)),
    };
    let mut names = vec![name, "height_m"];
    let mut values = vec![lateral, w["height_m"].as_f64().unwrap_or(f64::NAN)];
    // Peak force of the tools that move (a press's design figure); a fixed wall's peak is the
    // impact spike at first contact, which does not converge with resolution.
    let peak = summary["tools"]
        .as_array()
        .map(|t| {
            t.iter()
                .filter(|t| t["stroke_m"].as_f64().unwrap_or(0.0) != 0.0)
                .filter_map(|t| t["peak_force_N"].as_f64())
                .fold(0.0, f64::max)
        })
        .unwrap_or(0.0);
    if peak > 0.0 {
        names.push("peak_force_N");
        values.push(peak);
    }
    (names, values)
}

/// Richardson extrapolation of values on grids of spacing ratio `r` (coarse to fine):
/// returns (extrapolated value, order used).
fn extrapolate(v: &[f64], r: f64) -> (f64, f64) {
    let n = v.len();
    if n == 1 {
        return (v[0], 0.0);
    }
    let (c, f) = (v[n - 2], v[n - 1]);
    let mut p = 1.0;
    if n >= 3 {
        let (d1, d2) = (v[n - 2] - v[n - 3], v[n - 1] - v[n - 2]);
        if d1 * d2 > 0.0 && d2.abs() < d1.abs() {
            p = ((d1 / d2).ln() / r.ln()).clamp(0.5, 4.0);
        }
    }
    (f + (f - c) / (r.powf(p) - 1.0), p)
}

/// Run the grid, write sweep.csv, sweep.md and sweep.png into `out`, return the table.
pub fn sweep(
    scene: &Scene,
    grids: &[[usize; 2]],
    rules: &[IntegrationRule],
    safeties: &[f64],
    out: &Path,
) -> Result<String, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let mut grids = grids.to_vec();
    grids.sort_by_key(|g| g[0] * g[1]);
    let mut rows = Vec::new();
    let mut names = Vec::new();
    for &rule in rules {
        for &grid in &grids {
            for &safety in safeties {
                let mut s = scene.clone().with_integration(rule);
                s.workpiece.particles = grid;
                s.time.dt_s = None;
                s.time.dt_safety = safety;
                let label = format!("{}_{}x{}_{}", rule.name(), grid[0], grid[1], safety);
                let opts = run::Options {
                    out: out.join(&label),
                    progress: false,
                    frames: false,
                    mcap: None,
                };
                let report = run::run(&s, &opts).map_err(|e| format!("{label}: {e}"))?;
                let (n, values) = quantities(&report.summary);
                names = n;
                rows.push(Row {
                    rule,
                    grid,
                    safety,
                    steps: report.summary["steps"].as_u64().unwrap_or(0),
                    wall: report.summary["wall_s"].as_f64().unwrap_or(f64::NAN),
                    memory: report.summary["memory_bytes"].as_f64().unwrap_or(f64::NAN) / 1e6,
                    values,
                });
            }
        }
    }
    // Reference: per rule, extrapolate the finest grids at the smallest safety factor.
    let smin = safeties.iter().copied().fold(f64::INFINITY, f64::min);
    let ratio = if grids.len() >= 2 {
        let (a, b) = (grids[grids.len() - 2], grids[grids.len() - 1]);
        ((b[0] - 1) as f64 / (a[0] - 1) as f64).max(1.0 + 1e-9)
    } else {
        2.0
    };
    let mut reference = Vec::new();
    let mut uncertainty = Vec::new();
    let mut orders = String::new();
    for (q, name) in names.iter().enumerate() {
        let mut per_rule = Vec::new();
        let mut distance: f64 = 0.0;
        for &rule in rules {
            let series: Vec<f64> = rows
                .iter()
                .filter(|r| r.rule == rule && r.safety == smin)
                .map(|r| r.values[q])
                .collect();
            let (x, p) = extrapolate(&series, ratio);
            distance = distance.max((x - series[series.len() - 1]).abs());
            let _ = write!(orders, "{} {name} order {p:.2}; ", rule.name());
            per_rule.push(x);
        }
        let mean = per_rule.iter().sum::<f64>() / per_rule.len() as f64;
        let spread = per_rule
            .iter()
            .map(|x| (x - mean).abs())
            .fold(0.0, f64::max);
        reference.push(mean);
        uncertainty.push(spread.max(distance));
    }
    let error = |r: &Row| {
        r.values
            .iter()
            .zip(&reference)
            .map(|(v, x)| ((v - x) / x).abs())
            .fold(0.0, f64::max)
    };
    // Pareto front: no other run is both faster and more accurate.
    let pareto: Vec<bool> = rows
        .iter()
        .map(|a| !rows.iter().any(|b| b.wall < a.wall && error(b) < error(a)))
        .collect();
    let mut csv = String::from("integration,nx,ny,dt_safety,steps,wall_s,memory_MB");
    for n in &names {
        let _ = write!(csv, ",{n}");
    }
    csv.push_str(",error_rel,pareto\n");
    let mut md = format!(
        "# Sweep of {}\n\nReference (extrapolated, +- uncertainty): {}\n\nRichardson orders: {orders}\n\n",
        scene.name,
        names
            .iter()
            .zip(reference.iter().zip(&uncertainty))
            .map(|(n, (x, u))| format!("{n} = {x:.6e} +- {u:.1e}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    md.push_str("| rule | grid | dt_safety | steps | wall (s) | memory (MB) | error | Pareto |\n|---|---|---|---|---|---|---|---|\n");
    for (r, p) in rows.iter().zip(&pareto) {
        let _ = write!(
            csv,
            "{},{},{},{},{},{:.6},{:.3}",
            r.rule.name(),
            r.grid[0],
            r.grid[1],
            r.safety,
            r.steps,
            r.wall,
            r.memory
        );
        for v in &r.values {
            let _ = write!(csv, ",{v:e}");
        }
        let _ = writeln!(csv, ",{:e},{}", error(r), p);
        let _ = writeln!(
            md,
            "| {} | {}x{} | {} | {} | {:.2} | {:.1} | {:.2e} | {} |",
            r.rule.name(),
            r.grid[0],
            r.grid[1],
            r.safety,
            r.steps,
            r.wall,
            r.memory,
            error(r),
            if *p { "yes" } else { "" }
        );
    }
    std::fs::write(out.join("sweep.csv"), &csv)
        .map_err(|e| format!("cannot write sweep.csv: {e}"))?;
    std::fs::write(out.join("sweep.md"), &md).map_err(|e| format!("cannot write sweep.md: {e}"))?;
    let series: Vec<plots::Series> = rules
        .iter()
        .map(|&rule| {
            let pts: Vec<&Row> = rows.iter().filter(|r| r.rule == rule).collect();
            plots::Series {
                label: rule.name().to_string(),
                x: pts.iter().map(|r| r.wall.log10()).collect(),
                y: pts.iter().map(|r| error(r).max(1e-12).log10()).collect(),
            }
        })
        .collect();
    plots::line_plot(
        &out.join("sweep.png"),
        &format!("{}: error against wall time", scene.name),
        "log10 wall time (s)",
        "log10 relative error",
        &series,
        &[],
    )?;
    Ok(md)
}
