//! Files a run writes: the time history (CSV), the summary (JSON), the reference table,
//! VTK frames ([`vtu`]) and PNG plots ([`plots`]).

pub mod plots;
pub mod vtu;

use rkforge_core::{Kinematics, Scene, Simulation};
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::path::Path;

/// Time history: one row per sample.
pub struct History {
    columns: Vec<String>,
    rows: Vec<Vec<f64>>,
}

/// Workpiece measures at one instant.
struct Measures {
    extents: rkforge_core::Extents,
    volume_change_rel: f64,
}

fn measures(sim: &Simulation) -> Measures {
    let x = sim.positions();
    let v0 = sim.reference_volume();
    Measures {
        extents: rkforge_core::geometry::bounds(&x),
        volume_change_rel: sim.volume_of(&x) / v0 - 1.0,
    }
}

/// `radius_m` (axisymmetric: largest r) or `width_m` (plane strain: x extent).
fn lateral(sim: &Simulation, e: &rkforge_core::Extents) -> (&'static str, f64) {
    match sim.scene().model.kinematics {
        Kinematics::Axisymmetric => ("radius_m", e.x[1]),
        Kinematics::PlaneStrain => ("width_m", e.x[1] - e.x[0]),
    }
}

impl History {
    /// Columns for the scene's tools.
    pub fn new(sim: &Simulation) -> Self {
        let mut columns = vec!["time_s".to_string(), "dt_s".to_string()];
        for t in sim.tools() {
            for c in [
                "stroke_m",
                "velocity_m_per_s",
                "force_N",
                "force_x_N",
                "force_y_N",
            ] {
                columns.push(format!("{}.{c}", t.name));
            }
        }
        let lat = lateral(sim, &sim.extents()).0;
        for c in [
            "x_min_m",
            "x_max_m",
            "y_min_m",
            "y_max_m",
            lat,
            "height_m",
            "volume_change_rel",
            "max_plastic_strain",
            "max_penetration_rel",
        ] {
            columns.push(format!("workpiece.{c}"));
        }
        for f in &sim.scene().output.faces {
            for c in FACE_KEYS {
                columns.push(format!("workpiece.face_{}.{c}", f.name()));
            }
        }
        for c in [
            "kinetic_J",
            "elastic_J",
            "plastic_J",
            "internal_J",
            "contact_J",
            "tool_work_J",
            "balance_error_rel",
        ] {
            columns.push(format!("energy.{c}"));
        }
        History {
            columns,
            rows: Vec::new(),
        }
    }

    /// Record the current state (also updates the run's largest penetration).
    pub fn record(&mut self, sim: &mut Simulation) {
        let pen = sim.measure_penetration();
        let m = measures(sim);
        let e = sim.energy();
        let h = min_spacing(sim);
        let mut row = vec![sim.time(), sim.state().dt_prev];
        for t in sim.tools() {
            row.extend([
                t.state.stroke,
                t.state.velocity,
                t.axial_force(),
                t.state.force[0],
                t.state.force[1],
            ]);
        }
        let x = m.extents;
        row.extend([
            x.x[0],
            x.x[1],
            x.y[0],
            x.y[1],
            lateral(sim, &x).1,
            x.y[1] - x.y[0],
            m.volume_change_rel,
            sim.max_plastic_strain(),
            pen / h,
        ]);
        for &f in &sim.scene().output.faces {
            row.extend(face_values(sim, f));
        }
        row.extend([
            e.kinetic,
            e.elastic,
            e.plastic,
            e.internal(),
            e.contact_work,
            e.tool_work,
            e.balance_error_rel(),
        ]);
        self.rows.push(row);
    }

    /// Write as CSV with a header line.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        let mut s = self.columns.join(",");
        s.push('\n');
        for r in &self.rows {
            let cells: Vec<String> = r.iter().map(|v| format!("{v:e}")).collect();
            s.push_str(&cells.join(","));
            s.push('\n');
        }
        std::fs::write(path, s).map_err(|e| format!("cannot write {}: {e}", path.display()))
    }

    fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }

    /// History plots: lateral size and height over time with the scene's references
    /// (paper Figures 5-6), tool forces over time, force against stroke for the tools that
    /// move, and the energy account.
    pub fn plots(&self, sim: &Simulation, out: &Path) -> Result<(), String> {
        let name = &sim.scene().name;
        let rule = sim.scene().discretization.integration.name();
        let end = sim.scene().time.end_s;
        let (tscale, tlabel) = if end < 1e-3 {
            (1e6, "time (us)")
        } else {
            (1e3, "time (ms)")
        };
        let t: Vec<f64> = self
            .column("time_s")
            .unwrap_or_default()
            .iter()
            .map(|v| v * tscale)
            .collect();
        let (lat, _) = lateral(sim, &sim.extents());
        let lat_label = lat.trim_end_matches("_m");
        for (key, label) in [(lat, lat_label), ("height_m", "height")] {
            let y: Vec<f64> = self
                .column(&format!("workpiece.{key}"))
                .unwrap_or_default()
                .iter()
                .map(|v| v * 1e3)
                .collect();
            let markers: Vec<plots::Marker> = sim
                .scene()
                .reference
                .iter()
                .filter_map(|r| {
                    r.values
                        .get(&format!("workpiece.{key}"))
                        .map(|v| plots::Marker {
                            label: r.source.clone(),
                            x: end * tscale,
                            y: v * 1e3,
                        })
                })
                .collect();
            plots::line_plot(
                &out.join(format!("{label}_history.png")),
                &format!("{name}: {label} ({rule})"),
                tlabel,
                &format!("{label} (mm)"),
                &[plots::Series {
                    label: format!("rkforge {rule}"),
                    x: t.clone(),
                    y,
                }],
                &markers,
            )?;
        }
        let force = |tool: &str| self.column(&format!("{tool}.force_N")).unwrap_or_default();
        let over_time: Vec<plots::Series> = sim
            .tools()
            .iter()
            .map(|tool| plots::Series {
                label: tool.name.clone(),
                x: t.clone(),
                y: force(&tool.name),
            })
            .collect();
        if !over_time.is_empty() {
            plots::line_plot(
                &out.join("forces.png"),
                &format!("{name}: tool forces along their axes ({rule})"),
                tlabel,
                "force on the tool along its axis (N)",
                &over_time,
                &[],
            )?;
        }
        let strokes: Vec<plots::Series> = sim
            .tools()
            .iter()
            .filter(|tool| tool.is_movable())
            .map(|tool| plots::Series {
                label: tool.name.clone(),
                x: self
                    .column(&format!("{}.stroke_m", tool.name))
                    .unwrap_or_default()
                    .iter()
                    .map(|s| s * 1e3)
                    .collect(),
                y: force(&tool.name).iter().map(|f| -f).collect(),
            })
            .collect();
        if !strokes.is_empty() {
            plots::line_plot(
                &out.join("force_stroke.png"),
                &format!("{name}: force against stroke ({rule})"),
                "stroke along the tool axis (mm)",
                "force resisting the stroke (N)",
                &strokes,
                &[],
            )?;
        }
        let energy: Vec<plots::Series> = [
            "kinetic_J",
            "elastic_J",
            "plastic_J",
            "contact_J",
            "tool_work_J",
        ]
        .iter()
        .map(|c| plots::Series {
            label: c.trim_end_matches("_J").replace('_', " "),
            x: t.clone(),
            y: self.column(&format!("energy.{c}")).unwrap_or_default(),
        })
        .collect();
        plots::line_plot(
            &out.join("energy.png"),
            &format!("{name}: energy account ({rule})"),
            tlabel,
            "energy (J)",
            &energy,
            &[],
        )
    }
}

/// The bounds of a followed face (`[output] faces`), as history columns and summary keys.
const FACE_KEYS: [&str; 4] = ["x_min_m", "x_max_m", "y_min_m", "y_max_m"];

/// The values of [`FACE_KEYS`] for the particles that started on edge `f`.
fn face_values(sim: &Simulation, f: rkforge_core::scene::Edge) -> [f64; 4] {
    let e = sim.face_extents(f);
    [e.x[0], e.x[1], e.y[0], e.y[1]]
}

fn min_spacing(sim: &Simulation) -> f64 {
    let h = sim.spacing();
    h[0].min(h[1])
}

/// The summary (summary.json): scene, discretisation, run, workpiece, energy, tools, contact,
/// and the wall time of each stage (s); `output_s` is the time the caller spent sampling the
/// history and writing files (history.csv, frames, plots, MCAP).
pub fn summary(sim: &Simulation, wall_s: f64, output_s: f64, error: Option<&str>) -> Value {
    let m = measures(sim);
    let e = sim.energy();
    let x = m.extents;
    let (lat, lat_v) = lateral(sim, &x);
    let mut workpiece = json!({
        "height_m": x.y[1] - x.y[0],
        "x_range_m": x.x,
        "y_range_m": x.y,
        "volume_change_rel": m.volume_change_rel,
        "max_plastic_strain": sim.max_plastic_strain(),
    });
    workpiece[lat] = json!(lat_v);
    for &f in &sim.scene().output.faces {
        let keys = FACE_KEYS.iter().map(|k| k.to_string());
        let face: serde_json::Map<String, Value> =
            keys.zip(face_values(sim, f).map(|v| json!(v))).collect();
        workpiece[format!("face_{}", f.name())] = Value::Object(face);
    }
    let times = sim.times;
    let scene = sim.scene();
    json!({
        "status": if error.is_some() { "error" } else { "ok" },
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
        "workpiece": workpiece,
        "energy": {
            "initial_J": e.initial,
            "kinetic_J": e.kinetic,
            "elastic_J": e.elastic,
            "internal_J": e.internal(),
            "plastic_J": e.plastic,
            "contact_J": e.contact_work,
            "tool_work_J": e.tool_work,
            "contact_interface_J": e.interface_gain(),
            "balance_error_rel": e.balance_error_rel(),
        },
        "tools": (0..sim.tools().len()).map(|k| crate::run::tool_json(sim, k)).collect::<Vec<_>>(),
        "contact": {
            "max_penetration_m": sim.max_penetration(),
            "max_penetration_rel": sim.max_penetration() / min_spacing(sim),
        },
        "stage_seconds": {
            "setup": times.setup.as_secs_f64(),
            "shape_functions": times.shape_functions.as_secs_f64(),
            "stress": times.stress.as_secs_f64(),
            "internal_force": times.internal_force.as_secs_f64(),
            "contact": times.contact.as_secs_f64(),
            "integration": times.integration.as_secs_f64(),
            "output": output_s,
        },
    })
}

/// Look up a dotted key such as `workpiece.radius_m` in the summary.
fn lookup(summary: &Value, key: &str) -> Option<f64> {
    key.split('.').try_fold(summary, |v, k| v.get(k))?.as_f64()
}

/// Our figures beside every reference of the scene, one column per referenced key.
pub fn reference_table(scene: &Scene, summary: &Value) -> String {
    let mut keys: Vec<&String> = Vec::new();
    for r in &scene.reference {
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
        scene.name,
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
    let _ = write!(s, "{:<40}", "");
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
    let ours = format!("rkforge {}", summary["integration"].as_str().unwrap_or("?"));
    let _ = write!(s, "{ours:<40}");
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
    for r in &scene.reference {
        let _ = write!(s, "{:<40}", r.source.chars().take(39).collect::<String>());
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
