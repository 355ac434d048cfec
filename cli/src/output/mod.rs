//! Files a run writes beyond the history and summary of [`rkforge_runner`]: VTK frames
//! ([`vtu`]) and PNG plots ([`plots`]).

pub mod plots;
pub mod vtu;

use rkforge_core::Simulation;
use rkforge_runner::History;
use std::path::Path;

/// The plots drawn from a run's history.
pub trait HistoryPlots {
    /// Write the history plots into `out`.
    ///
    /// # Errors
    ///
    /// A plot cannot be drawn or written.
    fn plots(&self, sim: &Simulation, out: &Path) -> Result<(), String>;
}

impl HistoryPlots for History {
    /// History plots: lateral size and height over time with the scene's references
    /// (paper Figures 5-6), tool forces over time, force against stroke for the tools that
    /// move, and the energy account.
    fn plots(&self, sim: &Simulation, out: &Path) -> Result<(), String> {
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
        let (lat, _) = sim.extents().lateral(sim.scene().model.kinematics);
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
                    ..plots::Series::default()
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
                ..plots::Series::default()
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
                ..plots::Series::default()
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
            ..plots::Series::default()
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
