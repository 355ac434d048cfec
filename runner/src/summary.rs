//! The summary of a run (summary.json) and the table of our figures beside the scene's
//! references.
//!
//! The figures of the register ([`rkforge_core::outputs`]) shown in the summary are placed
//! at the path their names give (`workpiece.height_m`, `energy.kinetic_J`,
//! `workpiece.face_y_min.x_max_m`, `thermal.*`; per tool in `tools[k]`, per fill point in
//! its `tools[k].fill_points[i]`). What the summary says of the run as a whole is written
//! here: how it ended, the discretisation, the time step, the bounds as ranges, the
//! largest penetrations, each tool's force vector and fill times, the laps, mass scaling,
//! re-referencing and the stage times; [`solid_summary`] is a 3D run's, with the 3D
//! register's figures placed the same way.

use rkforge_core::outputs::{columns, solid_columns, At, Body, Column, Sample};
use rkforge_core::scene::Reference;
use rkforge_core::solver::{FillPoint, SolidSimulation};
use rkforge_core::{Kinematics, Scene, Simulation};
use serde_json::{json, Value};
use std::fmt::Write as _;

/// How a run ended, as its summary says it (`status` `ok`, `stopped` or `error`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ending<'a> {
    /// It ran to its end time (or to the caller's last order).
    Finished,
    /// A signal or a request stopped it early, for this reason.
    Stopped(&'a str),
    /// It failed with this error.
    Failed(&'a str),
}

/// The summary (summary.json): how the run ended (`status` `ok`, `stopped` or `error`, with
/// the reason or error), scene, discretisation, run, workpiece, energy, tools, contact, and
/// the wall time of each stage (s); `output_s` is the time the caller spent sampling the
/// history and writing files (history.csv, frames, plots, MCAP).
pub fn summary(sim: &Simulation, wall_s: f64, output_s: f64, ending: Ending<'_>) -> Value {
    let (status, error) = match ending {
        Ending::Finished => ("ok", None),
        Ending::Stopped(reason) => ("stopped", Some(reason)),
        Ending::Failed(error) => ("error", Some(error)),
    };
    let sample = Sample::new(sim);
    let x = sample.extents();
    let min_spacing = sample.min_spacing();
    let times = sim.times;
    let scene = sim.scene();
    let mut summary = json!({
        "status": status,
        "error": error,
        "scene": scene.name,
        "kinematics": match scene.model.kinematics { Kinematics::Axisymmetric => "axisymmetric", Kinematics::PlaneStrain => "plane_strain" },
        "integration": scene.discretization.integration.name(),
        "support": scene.discretization.support,
        "particles": sim.particle_count(),
        "grid": [sim.grid().0, sim.grid().1],
        "integration_points": sim.point_count(),
        "steps": sim.steps(),
        "end_time_s": sim.time(),
        "wall_s": wall_s,
        "threads": rayon::current_num_threads(),
        "memory_bytes": sim.memory_bytes(),
        "time_step": {
            "fixed_s": scene.time.dt_s,
            "dt_safety": scene.time.dt_safety,
            "last_s": sim.state().dt_prev,
            "critical_initial_s": sim.critical_dt0(),
            "stable_estimate_now_s": sim.stable_dt(),
        },
        "workpiece": {
            "x_range_m": x.x,
            "y_range_m": x.y,
            "max_isolation_rel": sim.state().isolation.max,
        },
        "mass_scaling": sim.mass_scaling(),
        "warnings": scene.time.unused_safety_warning().into_iter().chain(sim.quasi_static_warning()).chain(sim.surface_warning()).chain(sim.detached_warning()).collect::<Vec<_>>(),
        "tools": (0..sim.tools().len()).map(|k| tool_in(&sample, k)).collect::<Vec<_>>(),
        "contact": {
            "max_penetration_m": sim.max_penetration(),
            "max_penetration_rel": sim.max_penetration() / min_spacing,
            "max_beyond_symmetry_m": sim.max_beyond_symmetry(),
            "max_beyond_symmetry_rel": sim.max_beyond_symmetry() / min_spacing,
            "plane_feedback_max": sim.plane_feedback_max(),
            "plane_penalty_scale_min": sim.plane_penalty_scale_min(),
            "max_inside_itself_m": sim.max_inside_itself(),
            "max_inside_itself_rel": sim.max_inside_itself() / min_spacing,
            "max_boundary_crossings": sim.max_boundary_crossings(),
            "self_contact": scene.self_contact.enabled,
        },
        "laps": laps_json(sim),
        "stage_seconds": {
            "setup": times.setup.as_secs_f64(),
            "shape_functions": times.shape_functions.as_secs_f64(),
            "stress": times.stress.as_secs_f64(),
            "internal_force": times.internal_force.as_secs_f64(),
            "contact": times.contact.as_secs_f64(),
            "integration": times.integration.as_secs_f64(),
            "output": output_s,
        },
    });
    if scene.transfers_heat() {
        summary["stage_seconds"]["heat"] = json!(times.heat.as_secs_f64());
    }
    // The register's figures of the whole workpiece and run (those per tool are in
    // `tools`).
    for c in shown(scene).filter(|c| matches!(c.at, At::Whole | At::Face(_))) {
        *path(&mut summary, &c) = json!(c.value(&sample));
    }
    if let Some(stretch) = scene.discretization.rereference_stretch {
        let last = sim.reference().map(|r| {
            (
                r.count,
                r.time_s,
                r.fit_residual,
                r.short_sites,
                r.flat_sites,
            )
        });
        summary["rereference"] = rereference_entry(stretch, last, sim.energy().remap);
    }
    // Only a run in which a particle left the body has the entry (a study's table gets its
    // columns from such runs alone).
    if let Some(d) = &sim.state().isolation.detached {
        summary["workpiece"]["detached"] = json!(d);
    }
    summary
}

/// The `rereference` entry of a scene that re-references the kernel (only such a scene
/// has it, 2D or 3D): the stretch that triggers one, how many were made and the time of
/// the last with its velocity fit's residual, and the sites whose supports were grown over
/// all of them, too few covering and then too flat a cover (`last`: count, s, -, -, -), and
/// the kinetic energy the remaps changed (J).
fn rereference_entry(stretch: f64, last: Option<(u32, f64, f64, u64, u64)>, remap_j: f64) -> Value {
    json!({
        "stretch": stretch,
        "count": last.map_or(0, |l| l.0),
        "last_s": last.map(|l| l.1),
        "remap_J": remap_j,
        "velocity_fit_residual": last.map(|l| l.2),
        "supports_grown": last.map_or(0, |l| l.3),
        "supports_grown_flat": last.map_or(0, |l| l.4),
    })
}

/// The summary of a 3D run (summary.json) that took `wall_s` (s) of wall time and ended
/// as `ending` says: how it ended, the discretisation and its cost, the bounds as ranges,
/// the largest penetrations, each tool's force vector, the stage times, and the register's
/// figures ([`rkforge_core::outputs::SOLID_REGISTER`]) at the paths their names give;
/// `output_s` is the time the caller spent sampling the history and writing files, as in
/// [`summary`].
pub fn solid_summary(
    sim: &SolidSimulation,
    wall_s: f64,
    output_s: f64,
    ending: Ending<'_>,
) -> Value {
    let (status, error) = match ending {
        Ending::Finished => ("ok", None),
        Ending::Stopped(reason) => ("stopped", Some(reason)),
        Ending::Failed(error) => ("error", Some(error)),
    };
    let scene = sim.scene();
    let sample = Sample::new(sim);
    let b = sample.readings();
    let st = sim.state();
    let particle_steps = sim.particle_count() as f64 * sim.steps() as f64;
    let t = &sim.times;
    let mut summary = json!({
        "status": status,
        "error": error,
        "scene": scene.name,
        "kinematics": "3d",
        "integration": scene.discretization.integration.name(),
        "support": scene.discretization.support,
        "particles": sim.particle_count(),
        "integration_points": sim.point_count(),
        "neighbours_per_point": sim.neighbours_per_point(),
        "memory_bytes": sim.memory_bytes(),
        "steps": sim.steps(),
        "end_time_s": sim.time(),
        "wall_s": wall_s,
        "threads": rayon::current_num_threads(),
        "us_per_particle_step": if particle_steps > 0.0 { 1e6 * wall_s / particle_steps } else { 0.0 },
        "smallest_spacing_m": sim.h_min(),
        "critical_dt_s": sim.critical_dt0(),
        "mass_scaling": sim.mass_scaling(),
        "warnings": scene.time.unused_safety_warning().into_iter().chain(sim.quasi_static_warning()).chain(sim.surface_warning()).chain(sim.detached_warning()).collect::<Vec<_>>(),
        "workpiece": {
            "x_range_m": b.extents[0],
            "y_range_m": b.extents[1],
            "z_range_m": b.extents[2],
            "max_isolation_rel": st.isolation.max,
        },
        "contact": {
            "max_penetration_m": st.max_penetration,
            "max_penetration_rel": st.max_penetration / sim.h_min(),
            "max_beyond_plane_m": st.max_beyond_plane,
            "max_beyond_plane_rel": st.max_beyond_plane / sim.h_min(),
            "plane_feedback_max": st.plane_feedback_max,
            "plane_penalty_scale_min": sim.plane_penalty_scale_min(),
            "max_fold_crossings": sim.max_fold_crossings(),
            "self_contact": scene.self_contact.enabled,
        },
        "tools": sim.tools().iter().enumerate().map(|(k, t)| json!({
            "name": t.name,
            "force_N": t.state.force,
            "axial_force_N": t.axial_force(),
            "fill_points": fill_json(sim.fill_points(), k),
        })).collect::<Vec<_>>(),
        "laps": solid_laps_json(sim),
        "stage_seconds": {
            "setup": t.setup.as_secs_f64(),
            "shape_functions": t.shape_functions.as_secs_f64(),
            "stress": t.stress.as_secs_f64(),
            "internal_force": t.internal_force.as_secs_f64(),
            "contact": t.contact.as_secs_f64(),
            "integration": t.integration.as_secs_f64(),
            "output": output_s,
        },
    });
    if scene.transfers_heat() {
        summary["stage_seconds"]["heat"] = json!(t.heat.as_secs_f64());
    }
    if let Some(stretch) = scene.discretization.rereference_stretch {
        let last = sim.reference().map(|r| {
            (
                r.count,
                r.time_s,
                r.fit_residual,
                r.short_sites,
                r.flat_sites,
            )
        });
        summary["rereference"] = rereference_entry(stretch, last, sim.energy().remap);
    }
    place(&mut summary, &solid_columns(scene), &sample);
    if let Some(d) = &st.isolation.detached {
        summary["workpiece"]["detached"] = json!(d);
    }
    summary
}

/// Each tool's stroke (m) when a lap formed, by the tool's name.
fn strokes_json<'a>(names: impl Iterator<Item = &'a str>, strokes: &[f64]) -> Value {
    let map: serde_json::Map<String, Value> = names
        .zip(strokes)
        .map(|(name, s)| (name.to_owned(), json!(s)))
        .collect();
    Value::Object(map)
}

/// The laps of a 3D run ([`rkforge_core::laps::SolidLap`]), as 2D's ([`laps_json`]) with
/// the lap's extent now (`[min, max]` of x, y and z over its particles) for its length.
pub fn solid_laps_json(sim: &SolidSimulation) -> Vec<Value> {
    sim.laps()
        .into_iter()
        .map(|lap| {
            let strokes = strokes_json(
                sim.tools().iter().map(|t| &t.name[..]),
                &lap.formed_strokes_m,
            );
            json!({
                "formed_s": lap.formed_s,
                "formed_stroke_m": strokes,
                "start_m": lap.start_m,
                "end_m": lap.end_m,
                "extent_m": lap.extent_m,
                "reference_m": lap.reference_m,
                "particles": lap.particles,
            })
        })
        .collect()
}

/// The laps ([`rkforge_core::laps`]): each with when and at which stroke of each tool it
/// formed, where it formed and where its material is now, its length now, where on the
/// undeformed workpiece its first contact came from, and its surface particles.
pub fn laps_json(sim: &Simulation) -> Vec<Value> {
    sim.laps()
        .into_iter()
        .map(|lap| {
            let strokes = strokes_json(
                sim.tools().iter().map(|t| &t.name[..]),
                &lap.formed_strokes_m,
            );
            json!({
                "formed_s": lap.formed_s,
                "formed_stroke_m": strokes,
                "start_m": lap.start_m,
                "end_m": lap.end_m,
                "length_m": lap.length_m,
                "reference_m": lap.reference_m,
                "particles": lap.particles,
            })
        })
        .collect()
}

/// Look up a dotted key such as `workpiece.radius_m` in the summary.
fn lookup(summary: &Value, key: &str) -> Option<f64> {
    key.split('.').try_fold(summary, |v, k| v.get(k))?.as_f64()
}

/// Our figures beside every reference of the scene, one column per referenced key.
pub fn reference_table(scene: &Scene, summary: &Value) -> String {
    references_beside(&scene.name, &scene.reference, summary)
}

/// [`reference_table`] of the scene named `name` with its `references`, for a scene of
/// either kind (2D or 3D).
pub fn references_beside(name: &str, references: &[Reference], summary: &Value) -> String {
    let mut keys: Vec<&String> = Vec::new();
    for r in references {
        for k in r.values.keys() {
            if !keys.contains(&k) {
                keys.push(k);
            }
        }
    }
    let steps = summary["steps"].as_u64().unwrap_or(0);
    let wall = summary["wall_s"].as_f64().unwrap_or(0.0);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{} at t = {:.3e} s: {} rule, {} particles, {} integration points, {} steps, {:.2} s wall",
        name,
        summary["end_time_s"].as_f64().unwrap_or(0.0),
        summary["integration"].as_str().unwrap_or("?"),
        summary["particles"],
        summary["integration_points"],
        steps,
        wall
    );
    if keys.is_empty() {
        return s;
    }
    let unit = |k: &str| {
        if k.ends_with("_m") {
            ("mm", 1e3)
        } else {
            ("", 1.0)
        }
    };
    let ours = format!("rkforge {}", summary["integration"].as_str().unwrap_or("?"));
    // The label column fits the longest source in full (two sources may share a prefix).
    let width = references
        .iter()
        .map(|r| r.source.chars().count())
        .chain([ours.chars().count()])
        .max()
        .unwrap_or(0)
        + 2;
    let _ = write!(s, "{:<width$}", "");
    for k in &keys {
        let (u, _) = unit(k);
        let name = k.rsplit('.').next().unwrap_or(k).trim_end_matches("_m");
        let _ = write!(
            s,
            "{:>16}",
            if u.is_empty() {
                name.to_string()
            } else {
                format!("{name} ({u})")
            }
        );
    }
    s.push('\n');
    let _ = write!(s, "{ours:<width$}");
    for k in &keys {
        let (_, f) = unit(k);
        match lookup(summary, k) {
            Some(v) => {
                let _ = write!(s, "{:>16.3}", v * f);
            }
            None => {
                let _ = write!(s, "{:>16}", "-");
            }
        }
    }
    s.push('\n');
    for r in references {
        let _ = write!(s, "{:<width$}", r.source);
        for k in &keys {
            let (_, f) = unit(k);
            match r.values.get(*k) {
                Some(v) => {
                    let _ = write!(s, "{:>16.3}", v * f);
                }
                None => {
                    let _ = write!(s, "{:>16}", "-");
                }
            }
        }
        s.push('\n');
    }
    s
}

/// The JSON object of one tool in the summary.
pub fn tool_json(sim: &Simulation, k: usize) -> Value {
    tool_in(&Sample::new(sim), k)
}

/// [`tool_json`] of a sample.
fn tool_in(sample: &Sample<'_>, k: usize) -> Value {
    let t = &sample.tools()[k];
    let mut tool = json!({
        "name": t.name,
        "force_N": t.state.force,
        "axial_force_N": t.axial_force(),
        "fill_points": fill_json(sample.fill_points(), k),
    });
    for c in shown(sample.scene()) {
        match c.at {
            At::Tool(j) if j == k => tool[c.output.name] = json!(c.value(sample)),
            At::FillPoint {
                tool: j, within, ..
            } if j == k => {
                tool["fill_points"][within][c.output.name] = json!(c.value(sample));
            }
            _ => {}
        }
    }
    // A thermal scene: every tool's heat flow, heated or not (the history has the heated
    // tools' only).
    if let Some(flows) = sample.tool_heat_flows() {
        tool["heat_flow_W"] = json!(flows[k]);
    }
    tool
}

/// Tool `k`'s fill points among `points` (either dimension's) in the summary: each with
/// where it is now, whether, when and at which stroke the material reached it.
fn fill_json<const D: usize>(points: Vec<FillPoint<D>>, k: usize) -> Vec<Value> {
    points
        .into_iter()
        .filter(|p| p.tool == k)
        .map(|p| {
            json!({
                "name": p.name,
                "at_m": p.at_m.as_slice(),
                "filled": p.filled.is_some(),
                "filled_s": p.filled.map(|f| f.time_s),
                "filled_stroke_m": p.filled.map(|f| f.stroke_m),
            })
        })
        .collect()
}

/// The register's columns of `scene` shown in the summary.
fn shown(scene: &Scene) -> impl Iterator<Item = Column> {
    columns(scene)
        .into_iter()
        .filter(|c| c.output.shown.summary)
}

/// The place of a scalar or per-face column in the summary: the path of its dotted name.
fn path<'v, S: Body>(summary: &'v mut Value, c: &Column<S>) -> &'v mut Value {
    c.name.split('.').fold(summary, |v, key| &mut v[key])
}

/// The values of `columns` shown in the summary, placed in `summary`: a scalar at the path
/// its dotted name gives, a tool's value under its name in `tools[k]` (which must hold an
/// object per tool). What a 3D run's summary takes from its register.
fn place<S: Body>(summary: &mut Value, columns: &[Column<S>], sample: &Sample<'_, S>) {
    for c in columns.iter().filter(|c| c.output.shown.summary) {
        let value = json!(c.value(sample));
        match c.at {
            At::Tool(k) => summary["tools"][k][c.output.name] = value,
            _ => *path(summary, c) = value,
        }
    }
}
