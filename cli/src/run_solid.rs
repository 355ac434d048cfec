//! One run of a 3D scene (`model.kinematics = "3d"`): the time loop over the history's
//! samples and frames, the physical penetration measured at each sample, and the files
//! written: the summary (`summary.json`) and the history (`history.csv`) of the 3D
//! register's figures ([`rkforge_core::outputs::SOLID_REGISTER`], named as the 2D ones, so
//! the scene's references print beside them), and
//! with frames the VTK frames of the body (`frames/frame_NNNN.vtu`, hexahedra with the
//! plastic strain of each cell, and its temperature in a scene with `[thermal]`, and
//! `frames.pvd` for ParaView), each tool's surface where it is with the contact pressure on
//! its triangles (an STL die's, a plane's patch under the workpiece:
//! `frames/die_<tool>_NNNN.vtu`, `pressure_Pa` and `force_N` per triangle,
//! [`SolidSimulation::die_pressure`], and `die_<tool>.pvd`) and `stages.png`: the body at each frame seen from outside,
//! and at the end from the other side, where a half or quarter model shows its sections on
//! the symmetry planes; with `[thermal]`, `temperature.png`: the last frame's temperature
//! from both sides. With `--mcap`, the ROS 2 topics of a 3D scene at every history sample
//! ([`crate::recording`]), SIGINT and SIGTERM stopping the run at the next sample with its
//! files finished. With checkpoints ([`rkforge_runner::checkpoint`]), the frames taken so far
//! are kept in each.

use crate::output::plots::{solid_plot, SolidPanel, View};
use crate::output::vtu::{write_pvd, write_vtu_3d, write_vtu_triangles};
use crate::output::{HistoryPlots, Plotted};
use crate::recording::{Mcap, McapOptions};
use rkforge_core::scene::SolidScene;
use rkforge_core::solver::{DiePressure, SolidSimulation};
use rkforge_runner::checkpoint::{self, Restart};
use rkforge_runner::{solid_summary, Checkpoints, Observer, Run};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::Path;
use std::time::{Duration, Instant};

/// What a finished (or failed) 3D run produced.
pub struct SolidReport {
    /// The summary written to summary.json.
    pub summary: Value,
    /// The failure, if the run stopped with an error.
    pub error: Option<String>,
}

/// Run `scene` to its end time, writing `summary.json` and `history.csv` into `out`, and
/// with `mcap` the recording (its summary record is summary.json's text). A run that fails
/// midway, or that a signal stops while it records, still writes them, the summary with
/// `"status": "error"` (or `"stopped"`) and the reason. `restart` says whether it goes on
/// from its checkpoint in `out` and how often it writes one.
pub fn run(
    scene: &SolidScene,
    out: &Path,
    frames: bool,
    mcap: Option<&McapOptions>,
    restart: Restart,
) -> Result<SolidReport, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let wall = Instant::now();
    let mut sim = SolidSimulation::new(scene).map_err(|e| e.to_string())?;
    let nframes = if frames { scene.output.frames } else { 0 };
    let mut started = checkpoint::start::<_, Vec<Frame>>(&mut sim, nframes, Some(out), restart)?;
    let mut shots = Shots {
        frames: std::mem::take(&mut started.taken),
        mcap: mcap.map(|m| Mcap::start(m, scene)).transpose()?,
        checkpoints: started.checkpoints.take(),
    };
    let outcome = started.go(&mut sim, nframes, &mut shots)?;
    let clock = Instant::now();
    outcome.history.write(&out.join("history.csv"))?;
    // Plots come before the summary so that their time is in it; the summary is written
    // even when a plot fails, and the plot's error is returned after it.
    let plotted = match frames {
        true => outcome
            .history
            .plots(&Plotted::solid(&sim), out)
            .and_then(|()| match shots.frames.is_empty() {
                true => Ok(()),
                false => write_frames(&sim, &shots.frames, out, &scene.name),
            }),
        false => Ok(()),
    };
    let output_time = outcome.output_time + clock.elapsed();
    let mut summary = solid_summary(
        &sim,
        started.wall_s + wall.elapsed().as_secs_f64(),
        started.output_s + output_time.as_secs_f64(),
        outcome.ending(),
    );
    started.mark(&mut summary);
    let text = serde_json::to_string_pretty(&summary).map_err(|e| e.to_string())? + "\n";
    std::fs::write(out.join("summary.json"), &text)
        .map_err(|e| format!("cannot write summary.json: {e}"))?;
    if let Some(m) = shots.mcap {
        m.finish(&text)?;
    }
    plotted?;
    Ok(SolidReport {
        summary,
        error: outcome.failure,
    })
}

/// What a 3D run adds to the bare run: the frames, taken as it goes and written at its end,
/// the MCAP recording of its samples and the checkpoints.
struct Shots {
    frames: Vec<Frame>,
    mcap: Option<Mcap>,
    checkpoints: Option<Checkpoints>,
}

impl Observer<SolidSimulation> for Shots {
    fn sample(&mut self, sim: &SolidSimulation) -> Result<(), String> {
        match &mut self.mcap {
            Some(m) => m.record(sim),
            None => Ok(()),
        }
    }

    fn frame(&mut self, sim: &SolidSimulation) -> Result<(), String> {
        self.frames.push(Frame::of(sim));
        Ok(())
    }

    fn stop(&self, sim: &SolidSimulation) -> Option<String> {
        self.mcap.as_ref().and_then(|m| m.interrupted(sim.time()))
    }

    fn checkpoint(
        &mut self,
        sim: &SolidSimulation,
        run: &Run<SolidSimulation>,
        output: Duration,
    ) -> Result<(), String> {
        checkpoint::keep(self.checkpoints.as_mut(), sim, run, &self.frames, output)
    }
}

/// One frame of the body: time (s); each particle's physical position, displacement (m) and
/// velocity (m/s, at the last half step), as the 2D frames have them; each cell's plastic
/// strain (-), von Mises stress (Pa) and in a scene with `[thermal]` its temperature
/// (degrees C), the means over the cell's integration points.
#[derive(Serialize, Deserialize)]
struct Frame {
    time: f64,
    positions: Vec<[f64; 3]>,
    displacement: Vec<[f64; 3]>,
    velocity: Vec<[f64; 3]>,
    plastic_strain: Vec<f64>,
    von_mises: Vec<f64>,
    temperature: Option<Vec<f64>>,
    /// Each tool's pressure, with its name.
    dies: Vec<(String, DiePressure)>,
}

impl Frame {
    fn of(sim: &SolidSimulation) -> Frame {
        Frame {
            time: sim.time(),
            positions: sim.positions(),
            displacement: sim.displacements(),
            velocity: sim.velocities(),
            plastic_strain: sim.cell_means(&sim.point_plastic_strain()),
            von_mises: sim.cell_means(&sim.point_von_mises()),
            temperature: sim.point_temperature().map(|t| sim.cell_means(t)),
            dies: (0..sim.tools().len())
                .map(|k| (sim.tools()[k].name.clone(), sim.die_pressure(k)))
                .collect(),
        }
    }
}

/// Each tool's frames (`frames/die_<tool>_NNNN.vtu`: its triangles where the tool is, the
/// contact pressure and force on each) and their collection `die_<tool>.pvd`.
fn write_dies(shots: &[Frame], out: &Path) -> Result<(), String> {
    let Some(first) = shots.first() else {
        return Ok(());
    };
    for (d, (name, _)) in first.dies.iter().enumerate() {
        let mut listed = Vec::new();
        for (k, f) in shots.iter().enumerate() {
            let die = &f.dies[d].1;
            let file = format!("die_{name}_{k:04}.vtu");
            write_vtu_triangles(
                &out.join("frames").join(&file),
                &die.vertices,
                &die.triangles,
                &[("pressure_Pa", &die.pressure), ("force_N", &die.forces)],
            )
            .map_err(|e| format!("cannot write {file}: {e}"))?;
            listed.push((f.time, format!("frames/{file}")));
        }
        let pvd = format!("die_{name}.pvd");
        write_pvd(&out.join(&pvd), &listed).map_err(|e| format!("cannot write {pvd}: {e}"))?;
    }
    Ok(())
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
        let mut cell_fields: Vec<(&str, &[f64])> = vec![
            ("plastic_strain", &f.plastic_strain),
            ("von_mises_Pa", &f.von_mises),
        ];
        if let Some(t) = &f.temperature {
            cell_fields.push(("temperature_C", t));
        }
        write_vtu_3d(
            &dir.join(&file),
            &f.positions,
            sim.cells(),
            &[],
            &[
                ("displacement_m", &f.displacement),
                ("velocity_m_per_s", &f.velocity),
            ],
            &cell_fields,
        )
        .map_err(|e| format!("cannot write {file}: {e}"))?;
        listed.push((f.time, format!("frames/{file}")));
    }
    write_pvd(&out.join("frames.pvd"), &listed)
        .map_err(|e| format!("cannot write frames.pvd: {e}"))?;
    write_dies(shots, out)?;
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
