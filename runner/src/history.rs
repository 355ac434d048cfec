//! The time history of a run: one row per sample, written as history.csv.

use rkforge_core::{Extents, Simulation, THERMAL_MEASURES};
use std::path::Path;

/// Time history: one row per sample.
pub struct History {
    columns: Vec<String>,
    rows: Vec<Vec<f64>>,
}

/// Workpiece measures at one instant.
pub(crate) struct Measures {
    pub(crate) extents: Extents,
    pub(crate) volume_change_rel: f64,
    pub(crate) integrated_volume_change_rel: f64,
}

pub(crate) fn measures(sim: &Simulation) -> Measures {
    Measures {
        extents: sim.extents(),
        volume_change_rel: sim.volume() / sim.reference_volume() - 1.0,
        integrated_volume_change_rel: sim.integrated_volume_change(),
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
                "contact_fraction",
            ] {
                columns.push(format!("{}.{c}", t.name));
            }
        }
        for p in sim.fill_points() {
            columns.push(format!("{}.{}.filled", sim.tools()[p.tool].name, p.name));
        }
        let lat = sim.extents().lateral(sim.scene().model.kinematics).0;
        for c in [
            "x_min_m",
            "x_max_m",
            "y_min_m",
            "y_max_m",
            lat,
            "height_m",
            "volume_change_rel",
            "integrated_volume_change_rel",
            "max_plastic_strain",
            "max_penetration_rel",
            "beyond_symmetry_rel",
            "inside_itself_rel",
            "boundary_crossings",
            "laps",
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
            "kinetic_to_internal",
        ] {
            columns.push(format!("energy.{c}"));
        }
        for (k, _) in thermal_measures(sim) {
            columns.push(format!("thermal.{k}"));
        }
        for t in heated_tools(sim) {
            columns.push(format!("thermal.{}.heat_flow_W", sim.tools()[t].name));
        }
        History {
            columns,
            rows: Vec::new(),
        }
    }

    /// Record the current state. The penetration is measured over every particle against
    /// every tool and symmetry plane, and the boundary against itself (and kept as the run's
    /// largest); a particle deeper than the scene's bound is returned as an error, after the
    /// row is recorded.
    pub fn record(&mut self, sim: &mut Simulation) -> Result<(), rkforge_core::Error> {
        let measured = sim.measure_penetration();
        let depths = match &measured {
            Ok(d) => [
                d.tools.depth,
                d.planes.depth,
                d.itself.depth,
                d.crossings as f64,
            ],
            Err(_) => [
                sim.max_penetration(),
                sim.max_beyond_symmetry(),
                sim.max_inside_itself(),
                sim.max_boundary_crossings() as f64,
            ],
        };
        let m = measures(sim);
        let e = sim.energy();
        let h = min_spacing(sim);
        let mut row = vec![sim.time(), sim.state().dt_prev];
        for (k, t) in sim.tools().iter().enumerate() {
            row.extend([
                t.state.stroke,
                t.state.velocity,
                t.axial_force(),
                t.state.force[0],
                t.state.force[1],
                sim.contact_fraction(k),
            ]);
        }
        row.extend(
            sim.fill_points()
                .iter()
                .map(|p| if p.filled.is_some() { 1.0 } else { 0.0 }),
        );
        let x = m.extents;
        row.extend([
            x.x[0],
            x.x[1],
            x.y[0],
            x.y[1],
            x.lateral(sim.scene().model.kinematics).1,
            x.y[1] - x.y[0],
            m.volume_change_rel,
            m.integrated_volume_change_rel,
            sim.max_plastic_strain(),
            depths[0] / h,
            depths[1] / h,
            depths[2] / h,
            depths[3],
            sim.lap_count() as f64,
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
            e.kinetic_to_internal(),
        ]);
        row.extend(thermal_measures(sim).into_iter().map(|(_, v)| v));
        if let Some(flows) = sim.tool_heat_flows() {
            row.extend(heated_tools(sim).map(|t| flows[t]));
        }
        self.rows.push(row);
        measured.map(|_| ())
    }

    /// The column names: `time_s`, `dt_s`, per tool `<tool>.stroke_m` ..., `workpiece.*`,
    /// `energy.*`.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// The rows, one per sample, in column order.
    pub fn rows(&self) -> &[Vec<f64>] {
        &self.rows
    }

    /// The CSV text: a header line, then one line per row (shortest round-trip numbers).
    pub fn to_csv(&self) -> String {
        let mut s = self.columns.join(",");
        s.push('\n');
        for r in &self.rows {
            let cells: Vec<String> = r.iter().map(|v| format!("{v:e}")).collect();
            s.push_str(&cells.join(","));
            s.push('\n');
        }
        s
    }

    /// Write as CSV with a header line.
    pub fn write(&self, path: &Path) -> Result<(), String> {
        std::fs::write(path, self.to_csv())
            .map_err(|e| format!("cannot write {}: {e}", path.display()))
    }

    /// The values of the column `name`, if there is one.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }
}

/// The temperatures and heat of a scene with `[thermal]`, as (key, value) for the history's
/// `thermal.*` columns and the summary's `thermal` entry; none for an isothermal scene.
pub(crate) fn thermal_measures(sim: &Simulation) -> Vec<(&'static str, f64)> {
    match sim.thermal_values() {
        Some(v) => THERMAL_MEASURES.iter().map(|m| m.0).zip(v).collect(),
        None => Vec::new(),
    }
}

/// The tools that exchange heat with the workpiece (a heat transfer coefficient above 0).
pub(crate) fn heated_tools(sim: &Simulation) -> impl Iterator<Item = usize> + '_ {
    let thermal = sim.scene().thermal.is_some();
    sim.scene()
        .tools
        .iter()
        .enumerate()
        .filter(move |(_, t)| thermal && t.heat_transfer_w_per_m2_k > 0.0)
        .map(|(k, _)| k)
}

/// The bounds of a followed face (`[output] faces`), as history columns and summary keys.
pub(crate) const FACE_KEYS: [&str; 4] = ["x_min_m", "x_max_m", "y_min_m", "y_max_m"];

/// The values of [`FACE_KEYS`] for the particles that started on edge `f` (m).
pub(crate) fn face_values(sim: &Simulation, f: rkforge_core::scene::Edge) -> [f64; 4] {
    let e = sim.face_extents(f);
    [e.x[0], e.x[1], e.y[0], e.y[1]]
}

pub(crate) fn min_spacing(sim: &Simulation) -> f64 {
    let h = sim.spacing();
    h[0].min(h[1])
}
