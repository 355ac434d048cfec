//! Files a run writes beyond the history and summary of [`rkforge_runner`]: VTK frames
//! ([`vtu`]) and PNG plots ([`plots`]).

pub mod plots;
pub mod vtu;

use rkforge_core::outputs::Body;
use rkforge_core::scene::solid::ShapeKind;
use rkforge_core::scene::Reference;
use rkforge_core::solver::SolidSimulation;
use rkforge_core::tools::Driven;
use rkforge_core::Simulation;
use rkforge_runner::History;
use std::path::Path;

/// What the history plots read of a run besides its history, in 2D or 3D.
pub struct Plotted<'a> {
    /// The scene's name, in each title.
    pub name: &'a str,
    /// The integration rule's name, in each title.
    pub rule: &'static str,
    /// The end time (s), which picks the time axis' unit and places the references.
    pub end_s: f64,
    /// The history key of the lateral size (`radius_m`, `width_m`) after `workpiece.`; none
    /// for a 3D box, which has no one lateral size (its extents are in the history).
    pub lateral: Option<&'static str>,
    /// The tools' names, each with whether it moves (then it has a force-stroke curve).
    pub tools: Vec<(&'a str, bool)>,
    /// The scene's published values, drawn at the end time.
    pub references: &'a [Reference],
}

impl<'a> Plotted<'a> {
    /// The tools' names of `tools`, each with whether it moves.
    fn tools<T: Driven>(tools: &'a [T]) -> Vec<(&'a str, bool)> {
        tools.iter().map(|t| (t.name(), t.is_movable())).collect()
    }

    /// A 2D run's: the lateral size is the axisymmetric radius or the plane-strain width.
    pub fn plane(sim: &'a Simulation) -> Self {
        let scene = sim.scene();
        Plotted {
            name: &scene.name,
            rule: scene.discretization.integration.name(),
            end_s: scene.time.end_s,
            lateral: Some(sim.extents().lateral(scene.model.kinematics).0),
            tools: Self::tools(sim.tools()),
            references: &scene.reference,
        }
    }

    /// A 3D run's: a cylinder's lateral size is the largest distance of a particle from the
    /// z axis (its radius); a box has none.
    pub fn solid(sim: &'a SolidSimulation) -> Self {
        let scene = sim.scene();
        Plotted {
            name: &scene.name,
            rule: scene.discretization.integration.name(),
            end_s: scene.time.end_s,
            lateral: match scene.workpiece.shape {
                ShapeKind::Cylinder => Some("radius_m"),
                ShapeKind::Box => None,
            },
            tools: Self::tools(sim.tools()),
            references: &scene.reference,
        }
    }
}

/// The plots drawn from a run's history.
pub trait HistoryPlots {
    /// Write the history plots of the run `what` describes into `out`.
    ///
    /// # Errors
    ///
    /// A plot cannot be drawn or written.
    fn plots(&self, what: &Plotted, out: &Path) -> Result<(), String>;
}

impl<S: Body> HistoryPlots for History<S> {
    /// History plots: lateral size and height over time with the scene's references
    /// (paper Figures 5-6), tool forces over time (each tool's sampled force and its mean
    /// over each sampling interval, `force_mean_N`, drawn dashed as a staircase over the
    /// interval it averages), force against stroke for the tools that move, and the energy
    /// account.
    fn plots(&self, what: &Plotted, out: &Path) -> Result<(), String> {
        let Plotted {
            name,
            rule,
            end_s: end,
            lateral: lat,
            ..
        } = *what;
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
        let lateral = lat.map(|key| (key, key.trim_end_matches("_m")));
        for (key, label) in lateral.into_iter().chain([("height_m", "height")]) {
            let y: Vec<f64> = self
                .column(&format!("workpiece.{key}"))
                .unwrap_or_default()
                .iter()
                .map(|v| v * 1e3)
                .collect();
            let markers: Vec<plots::Marker> = what
                .references
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
        let mut over_time = Vec::new();
        for (k, &(tool, _)) in what.tools.iter().enumerate() {
            over_time.push(plots::Series {
                label: format!("{tool}, sampled"),
                x: t.clone(),
                y: force(tool),
                colour: plots::Colour::Palette(k),
                dashed: false,
            });
            let (x, y) = staircase(
                &t,
                &self
                    .column(&format!("{tool}.force_mean_N"))
                    .unwrap_or_default(),
            );
            over_time.push(plots::Series {
                label: format!("{tool}, mean over each interval"),
                x,
                y,
                colour: plots::Colour::Palette(k),
                dashed: true,
            });
        }
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
        let strokes: Vec<plots::Series> = what
            .tools
            .iter()
            .filter(|(_, moves)| *moves)
            .map(|&(tool, _)| plots::Series {
                label: tool.to_string(),
                x: self
                    .column(&format!("{tool}.stroke_m"))
                    .unwrap_or_default()
                    .iter()
                    .map(|s| s * 1e3)
                    .collect(),
                y: force(tool).iter().map(|f| -f).collect(),
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
        let energy_of = |c: &str| self.column(&format!("energy.{c}")).unwrap_or_default();
        let mut energy: Vec<plots::Series> = [
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
            y: energy_of(c),
            ..plots::Series::default()
        })
        .collect();
        // What the tools put in and the contact did not pass on: friction heat and penalty
        // losses (summary.json's `contact_interface_J`), so that the curves add up.
        energy.push(plots::Series {
            label: "contact interface (tool work - contact)".into(),
            x: t.clone(),
            y: energy_of("tool_work_J")
                .iter()
                .zip(energy_of("contact_J"))
                .map(|(w, c)| w - c)
                .collect(),
            ..plots::Series::default()
        });
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

/// The staircase of interval means `mean` (each row's value the mean over the interval
/// since the row before, as `<tool>.force_mean_N`) at the sample times `t`: each mean held
/// flat from the sample before to its own; the first row, an interval of no length, draws
/// nothing.
fn staircase(t: &[f64], mean: &[f64]) -> (Vec<f64>, Vec<f64>) {
    t.windows(2)
        .zip(mean.iter().skip(1))
        .flat_map(|(w, &m)| [(w[0], m), (w[1], m)])
        .unzip()
}

#[cfg(test)]
mod tests {
    use super::staircase;

    #[test]
    fn each_mean_is_held_over_the_interval_it_averages() {
        let (x, y) = staircase(&[0.0, 1.0, 3.0], &[0.0, 5.0, 7.0]);
        assert_eq!(x, [0.0, 1.0, 1.0, 3.0]);
        assert_eq!(y, [5.0, 5.0, 7.0, 7.0]);
        assert_eq!(staircase(&[0.0], &[0.0]), (vec![], vec![]));
    }
}
