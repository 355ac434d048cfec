//! One run of a 3D scene, as the command line and the Python package both do it (the same
//! bits): [`drive_solid`] steps a [`SolidSimulation`] from mark to mark of the schedule
//! (history rows every `output.history_interval_s`, frame times merged in), recording the
//! 3D register's history ([`History::solid`]), and [`solid_summary`] writes what the run
//! gave, the register's figures placed as the 2D summary places its own.

use crate::summary::{place, Ending};
use crate::{schedule_every, History, Outcome};
use rkforge_core::outputs::{solid_columns, Sample};
use rkforge_core::solver::SolidSimulation;
use serde_json::{json, Value};
use std::time::{Duration, Instant};

/// Run `sim` to its scene's end time with `frames` frames, recording the history;
/// `on_frame` is called at t = 0 and at every frame time when there are frames.
///
/// A failure of the simulation ends the loop and is returned in the [`Outcome`] (with a
/// last history row); an error of `on_frame` is returned at once.
///
/// # Errors
///
/// The schedule is too long, or `on_frame` failed.
pub fn drive_solid(
    sim: &mut SolidSimulation,
    frames: usize,
    mut on_frame: impl FnMut(&SolidSimulation) -> Result<(), String>,
) -> Result<Outcome<SolidSimulation>, String> {
    let scene = sim.scene();
    let interval = scene.history_interval();
    let marks = schedule_every(scene.time.end_s, interval, frames)
        .ok_or_else(|| format!("output.history_interval_s {interval:e} s: too many samples"))?;
    let mut history = History::solid(sim);
    let mut output_time = Duration::ZERO;
    let clock = Instant::now();
    let mut failure = history.record_solid(sim).err().map(|e| e.to_string());
    if frames > 0 {
        on_frame(sim)?;
    }
    output_time += clock.elapsed();
    for mark in &marks {
        if failure.is_some() {
            break;
        }
        if let Err(e) = sim.run_toward(mark.time, u64::MAX, |_, _| true) {
            failure = Some(e.to_string());
            // The run already failed: the row is what matters here, not the bound again.
            let _ = history.record_solid(sim);
            break;
        }
        let clock = Instant::now();
        if mark.sample {
            failure = history.record_solid(sim).err().map(|e| e.to_string());
        }
        if mark.frame {
            on_frame(sim)?;
        }
        output_time += clock.elapsed();
    }
    Ok(Outcome {
        history,
        failure,
        stopped: false,
        output_time,
    })
}

/// The summary of a 3D run (summary.json) that took `wall_s` (s) of wall time and ended
/// as `ending` says: how it ended, the discretisation and its cost, the bounds as ranges,
/// the largest penetrations, each tool's force vector, the stage times, and the register's
/// figures ([`rkforge_core::outputs::SOLID_REGISTER`]) at the paths their names give.
pub fn solid_summary(sim: &SolidSimulation, wall_s: f64, ending: Ending<'_>) -> Value {
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
        "workpiece": {
            "x_range_m": b.extents[0],
            "y_range_m": b.extents[1],
            "z_range_m": b.extents[2],
        },
        "contact": {
            "max_penetration_m": st.max_penetration,
            "max_penetration_rel": st.max_penetration / sim.h_min(),
            "max_beyond_plane_m": st.max_beyond_plane,
            "max_beyond_plane_rel": st.max_beyond_plane / sim.h_min(),
        },
        "tools": sim.tools().iter().map(|t| json!({
            "name": t.name,
            "force_N": t.state.force,
            "axial_force_N": t.axial_force(),
        })).collect::<Vec<_>>(),
        "stage_seconds": {
            "setup": t.setup.as_secs_f64(),
            "shape_functions": t.shape_functions.as_secs_f64(),
            "stress": t.stress.as_secs_f64(),
            "internal_force": t.internal_force.as_secs_f64(),
            "contact": t.contact.as_secs_f64(),
            "integration": t.integration.as_secs_f64(),
        },
    });
    place(&mut summary, &solid_columns(scene), &sample);
    summary
}
