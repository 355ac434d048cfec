//! The time history of a run: one row per sample, written as history.csv. Its columns are
//! the register's ([`rkforge_core::outputs`]) that are shown in the history, in register
//! order: the 2D register's for a [`Simulation`], the 3D one's for a [`SolidSimulation`].

use rkforge_core::outputs::{columns, solid_columns, At, Body, Column, Penetration, Sample, Since};
use rkforge_core::solver::SolidSimulation;
use rkforge_core::Simulation;
use std::path::Path;

/// Time history: one row per sample.
pub struct History<S: Body = Simulation> {
    columns: Vec<Column<S>>,
    names: Vec<String>,
    rows: Vec<Vec<f64>>,
    /// The last row's time and impulses, where the next row's interval means start.
    since: Option<Since>,
}

impl History {
    /// The columns of the simulation's scene.
    pub fn new(sim: &Simulation) -> Self {
        History::of(columns(sim.scene()))
    }

    /// Record the current state. Every particle's isolation is measured (a particle that
    /// left the body is kept for the summary's warning, `rkforge_core::solver::detachment`).
    /// The penetration is measured over every particle against
    /// every tool and symmetry plane, and the boundary against itself (and kept as the run's
    /// largest); a particle deeper than the scene's bound is returned as an error, after the
    /// row is recorded (with the run's largest depths).
    pub fn record(&mut self, sim: &mut Simulation) -> Result<(), rkforge_core::Error> {
        let (positions, measured) = sim.measure_sample();
        let depths = match &measured {
            Ok(d) => Penetration::of(d),
            Err(_) => Penetration::largest(sim),
        };
        let sample = Sample::<Simulation>::measured(sim, positions, depths);
        self.push(sample);
        measured.map(|_| ())
    }
}

impl History<SolidSimulation> {
    /// The columns of a 3D simulation's scene.
    pub fn solid(sim: &SolidSimulation) -> Self {
        History::of(solid_columns(sim.scene()))
    }

    /// Record the current state of a 3D run, every particle's isolation measured (as in 2D)
    /// and the penetration measured over every particle
    /// against every tool and symmetry plane ([`SolidSimulation::measure_sample`]); a
    /// particle deeper than the scene's bound is returned as an error, after the row is
    /// recorded (with the run's largest depths).
    pub fn record_solid(&mut self, sim: &mut SolidSimulation) -> Result<(), rkforge_core::Error> {
        let (positions, measured) = sim.measure_sample();
        let depths = match &measured {
            Ok((tools, planes)) => [*tools, *planes],
            Err(_) => [sim.state().max_penetration, sim.state().max_beyond_plane],
        };
        let sample = Sample::<SolidSimulation>::measured(sim, positions, depths);
        self.push(sample);
        measured.map(|_| ())
    }
}

impl<S: Body> History<S> {
    /// The history of the columns among `columns` shown in it.
    pub fn of(columns: Vec<Column<S>>) -> Self {
        let columns: Vec<Column<S>> = columns
            .into_iter()
            .filter(|c| c.output.shown.history)
            .collect();
        History {
            names: columns.iter().map(|c| c.name.clone()).collect(),
            columns,
            rows: Vec::new(),
            since: None,
        }
    }

    /// The same history, its next row's interval means taken since `since` (none: since
    /// the start): a history that goes on from another's last row.
    pub fn since(mut self, since: Option<Since>) -> Self {
        self.since = since;
        self
    }

    /// Where the next row's interval means start: the last row (none before the first and
    /// without [`History::since`]).
    pub fn next_since(&self) -> Option<&Since> {
        self.since.as_ref()
    }

    /// `history` (empty) with the `rows` of a checkpoint.
    ///
    /// # Errors
    ///
    /// A row has another number of columns than the history.
    pub fn with_rows(mut history: Self, rows: Vec<Vec<f64>>) -> Result<Self, String> {
        if let Some(r) = rows.iter().find(|r| r.len() != history.names.len()) {
            return Err(format!(
                "a history row has {} columns, the scene's history {}",
                r.len(),
                history.names.len()
            ));
        }
        history.since = rows.last().map(|row| history.since_row(row));
        history.rows = rows;
        Ok(history)
    }

    /// Where the interval means of the row after `row` start: its time and its tools'
    /// impulses.
    fn since_row(&self, row: &[f64]) -> Since {
        let of = |name: &str| self.columns.iter().position(|c| c.output.name == name);
        let mut impulse = Vec::new();
        for (c, v) in self.columns.iter().zip(row) {
            if let (At::Tool(k), "impulse_N_s") = (c.at, c.output.name) {
                impulse.resize(k + 1, 0.0);
                impulse[k] = *v;
            }
        }
        Since {
            time: of("time_s").map_or(0.0, |k| row[k]),
            impulse,
        }
    }

    /// Record a row of `sample`, its interval means since the last row (the start for the
    /// first).
    pub fn push(&mut self, sample: Sample<'_, S>) {
        let sample = sample.since(self.since.as_ref());
        self.rows
            .push(self.columns.iter().map(|c| c.value(&sample)).collect());
        self.since = Some(Since::of(&*sample));
    }

    /// The column names: `time_s`, `dt_s`, per tool `<tool>.stroke_m` ..., `workpiece.*`,
    /// `energy.*`.
    pub fn columns(&self) -> &[String] {
        &self.names
    }

    /// The rows, one per sample, in column order.
    pub fn rows(&self) -> &[Vec<f64>] {
        &self.rows
    }

    /// The CSV text: a header line, then one line per row (shortest round-trip numbers).
    pub fn to_csv(&self) -> String {
        let mut s = self.names.join(",");
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
        let k = self.names.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }
}
