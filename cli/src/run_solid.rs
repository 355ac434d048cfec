//! One run of a 3D scene (`model.kinematics = "3d"`): the time loop over the history's
//! samples and frames, the physical penetration measured at each sample, and the files
//! written: the summary (`summary.json`) and the history (`history.csv`) of the 3D
//! register's figures ([`rkforge_core::outputs::SOLID_REGISTER`], named as the 2D ones, so
//! the scene's references print beside them), and
//! with frames the VTK frames of the body (`frames/frame_NNNN.vtu`, hexahedra with the
//! plastic strain of each cell, and its temperature in a scene with `[thermal]`, and
//! `frames.pvd` for ParaView) and `stages.png`: the body at each frame seen from outside,
//! and at the end from the other side, where a half or quarter model shows its sections on
//! the symmetry planes; with `[thermal]`, `temperature.png`: the last frame's temperature
//! from both sides.

use crate::output::plots::{solid_plot, SolidPanel, View};
use crate::output::vtu::{write_pvd, write_vtu_3d};
use rkforge_core::outputs::{solid_columns, Sample};
use rkforge_core::scene::SolidScene;
use rkforge_core::solver::SolidSimulation;
use rkforge_runner::{place, History};
use serde_json::{json, Value};
use std::path::Path;
use std::time::Instant;

/// What a finished (or failed) 3D run produced.
pub struct SolidReport {
    /// The summary written to summary.json.
    pub summary: Value,
    /// The failure, if the run stopped with an error.
    pub error: Option<String>,
}

/// Run `scene` to its end time, writing `summary.json` and `history.csv` into `out`. A run
/// that fails midway still writes both, the summary with `"status": "error"` and the
/// error.
pub fn run(scene: &SolidScene, out: &Path, frames: bool) -> Result<SolidReport, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let wall = Instant::now();
    let mut sim = SolidSimulation::new(scene).map_err(|e| e.to_string())?;
    let end = scene.time.end_s;
    let nframes = if frames { scene.output.frames } else { 0 };
    let marks = rkforge_runner::schedule_every(end, scene.history_interval(), nframes).ok_or_else(
        || {
            format!(
                "output.history_interval_s {:e} s: too many samples",
                scene.history_interval()
            )
        },
    )?;
    let mut history = History::solid(&sim);
    let mut row = |sim: &mut SolidSimulation| history.record_solid(sim).map_err(|e| e.to_string());
    let mut error = row(&mut sim).err();
    let mut shots = Vec::new();
    if nframes > 0 {
        shots.push(Frame::of(&sim));
    }
    for mark in &marks {
        if error.is_some() {
            break;
        }
        if let Err(e) = sim.run_toward(mark.time, u64::MAX, |_, _| true) {
            error = Some(e.to_string());
            break;
        }
        if mark.sample {
            error = row(&mut sim).err();
        }
        if mark.frame {
            shots.push(Frame::of(&sim));
        }
    }
    if !shots.is_empty() {
        write_frames(&sim, &shots, out, &scene.name)?;
    }
    let wall_s = wall.elapsed().as_secs_f64();
    history.write(&out.join("history.csv"))?;
    let summary = summary(scene, &sim, wall_s, error.as_deref());
    let text = serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())?;
    std::fs::write(out.join("summary.json"), text + "\n")
        .map_err(|e| format!("cannot write summary.json: {e}"))?;
    Ok(SolidReport { summary, error })
}

/// The summary of a 3D run that took `wall_s` (s) of wall time, ended by `error` if any:
/// how it ended, the discretisation and its cost, the bounds as ranges, the largest
/// penetrations, each tool's force vector, the stage times, and the register's figures
/// ([`rkforge_core::outputs::SOLID_REGISTER`]) at the paths their names give, as the 2D
/// summary places them.
fn summary(scene: &SolidScene, sim: &SolidSimulation, wall_s: f64, error: Option<&str>) -> Value {
    let sample = Sample::new(sim);
    let b = sample.readings();
    let st = sim.state();
    let particle_steps = sim.particle_count() as f64 * sim.steps() as f64;
    let t = &sim.times;
    let mut summary = json!({
        "status": if error.is_some() { "error" } else { "ok" },
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

/// One frame of the body: time (s), particle positions (m), each cell's plastic strain
/// (-) and in a scene with `[thermal]` its temperature (degrees C), the means over the
/// cell's integration points.
struct Frame {
    time: f64,
    positions: Vec<[f64; 3]>,
    plastic_strain: Vec<f64>,
    temperature: Option<Vec<f64>>,
}

impl Frame {
    fn of(sim: &SolidSimulation) -> Frame {
        let eps = sim.point_plastic_strain();
        let per_cell = (eps.len() / sim.cells().len().max(1)).max(1);
        let cell_means = |v: &[f64]| -> Vec<f64> {
            v.chunks(per_cell)
                .map(|c| c.iter().sum::<f64>() / c.len() as f64)
                .collect()
        };
        Frame {
            time: sim.time(),
            positions: sim.positions(),
            plastic_strain: cell_means(&eps),
            temperature: sim.point_temperature().map(cell_means),
        }
    }
}

/// The VTK frames with their collection and the picture of the frames.
fn write_frames(
    sim: &SolidSimulation,
    shots: &[Frame],
    out: &Path,
    name: &str,
) -> Result<(), String> {
    let dir = out.join("frames");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let mut listed = Vec::new();
    for (k, f) in shots.iter().enumerate() {
        let file = format!("frame_{k:04}.vtu");
        let mut cell_fields: Vec<(&str, &[f64])> = vec![("plastic_strain", &f.plastic_strain)];
        if let Some(t) = &f.temperature {
            cell_fields.push(("temperature_C", t));
        }
        write_vtu_3d(
            &dir.join(&file),
            &f.positions,
            sim.cells(),
            &[],
            &[],
            &cell_fields,
        )
        .map_err(|e| format!("cannot write {file}: {e}"))?;
        listed.push((f.time, format!("frames/{file}")));
    }
    write_pvd(&out.join("frames.pvd"), &listed)
        .map_err(|e| format!("cannot write frames.pvd: {e}"))?;
    let panel = |f: &Frame, values: &[f64], label: &str, view: View| SolidPanel {
        time: f.time,
        positions: f.positions.clone(),
        hexes: sim.cells().to_vec(),
        cell_values: values.to_vec(),
        label: label.into(),
        view,
    };
    let sections = !sim.symmetry_planes().is_empty();
    let mut panels: Vec<SolidPanel> = shots
        .iter()
        .map(|f| panel(f, &f.plastic_strain, "plastic strain", View::OUTSIDE))
        .collect();
    if let (true, Some(last)) = (sections, shots.last()) {
        panels.push(panel(
            last,
            &last.plastic_strain,
            "plastic strain",
            View::SECTIONS,
        ));
    }
    solid_plot(&out.join("stages.png"), name, &panels)?;
    // The last frame's temperature, from outside and on the symmetry planes' sections.
    let Some((last, temperature)) = shots
        .last()
        .and_then(|f| f.temperature.as_ref().map(|t| (f, t)))
    else {
        return Ok(());
    };
    let mut panels = vec![panel(last, temperature, "temperature (C)", View::OUTSIDE)];
    if sections {
        panels.push(panel(last, temperature, "temperature (C)", View::SECTIONS));
    }
    solid_plot(
        &out.join("temperature.png"),
        &format!("{name}: temperature"),
        &panels,
    )
}
