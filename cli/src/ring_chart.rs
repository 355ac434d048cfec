//! `rkforge ring-chart`: the friction calibration chart of the ring compression test
//! (Male and Cockcroft 1964-65): the decrease of the ring's smallest inner diameter against
//! the height reduction, one curve per friction law of the pressing tool, beside the
//! upper-bound curve of Avitzur's analysis for every shear friction factor m (the theory
//! behind Male and DePierre's 1970 m-chart, [`upper_bound`]). Writes `ring_chart.csv`,
//! `ring_chart_comparison.csv` and `ring_chart.png`.

mod upper_bound;

use crate::output::plots::{line_plot, Colour, Series};
use rkforge_core::scene::{Component, Edge, Friction};
use rkforge_core::{sample_times, Kinematics, Scene, Simulation};
use std::fmt::Write as _;
use std::path::Path;
pub use upper_bound::Ring;

/// Height reductions (%) of the comparison table.
pub const TABLE_REDUCTIONS_PCT: [f64; 5] = [10.0, 20.0, 30.0, 40.0, 50.0];

/// How far (percentage points of height reduction) a run is read beyond its last sample, along
/// its last segment: the contact leaves the measured end of the stroke a fraction of a
/// micrometre short (49.9997 % for the shipped ring's 50 %).
const END_TOLERANCE_PCT: f64 = 0.01;

/// Spacing (%) of the height reductions at which the upper-bound curves are drawn.
const REFERENCE_SPACING_PCT: f64 = 0.5;

/// Where a curve comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// A run of the scene.
    Simulation,
    /// Avitzur's upper-bound analysis ([`upper_bound`]), for a shear friction factor.
    UpperBound,
}

impl Source {
    /// The name in the CSV's `source` column.
    fn name(self) -> &'static str {
        match self {
            Source::Simulation => "simulation",
            Source::UpperBound => "upper_bound",
        }
    }
}

/// One curve: the law and its (height reduction %, inner diameter decrease %) points.
pub struct Curve {
    /// A run or the upper bound.
    pub source: Source,
    /// The tool's friction law.
    pub friction: Friction,
    /// Height reduction `1 - h / h0` (%).
    pub reduction_pct: Vec<f64>,
    /// Decrease of the smallest inner diameter, `1 - D_i / D_i0` (%; negative when the
    /// hole grows).
    pub decrease_pct: Vec<f64>,
}

impl Curve {
    /// The decrease (%) at height reduction `r` (%), linear between samples, and along the
    /// last segment up to [`END_TOLERANCE_PCT`] beyond the last sample; `None` outside.
    fn decrease_at(&self, r: f64) -> Option<f64> {
        let (x, y) = (&self.reduction_pct, &self.decrease_pct);
        let last = x.len().checked_sub(2)?;
        let k = x
            .windows(2)
            .position(|w| w[0] <= r && r <= w[1])
            .or_else(|| {
                (r > x[last + 1] && r <= x[last + 1] + END_TOLERANCE_PCT).then_some(last)
            })?;
        let t = if x[k + 1] > x[k] {
            (r - x[k]) / (x[k + 1] - x[k])
        } else {
            0.0
        };
        Some(y[k] + t * (y[k + 1] - y[k]))
    }
}

/// The legend label of a law.
fn label(f: &Friction) -> String {
    match *f {
        Friction::Coulomb { mu } => format!("mu = {mu}"),
        Friction::Shear { m } => format!("m = {m}"),
        Friction::Capped { mu, m } => format!("mu = {mu}, m <= {m}"),
    }
}

/// The ring whose upper bound goes beside the runs of `scene`: inner radius
/// `workpiece.origin_m[0]`, outer `origin_m[0] + size_m[0]`, and full height twice the
/// modelled `size_m[1]`, the scene being the upper half of the ring mirrored at its y_min edge
/// (y held there), so that both faces see the tool's law as in the analysis. `None` for any
/// other scene (the chart then has no upper bound).
pub fn mirrored_ring(scene: &Scene) -> Option<Ring> {
    let mirrored = scene
        .constraints
        .iter()
        .any(|c| c.edge == Edge::YMin && c.fix.contains(&Component::Y));
    let w = &scene.workpiece;
    mirrored.then_some(Ring {
        inner: w.origin_m[0],
        outer: w.origin_m[0] + w.size_m[0],
        thickness: 2.0 * w.size_m[1],
    })
}

/// Runs the ring `scene` once per law in `laws`, the law set on every movable tool, and
/// samples the inner diameter at the scene's history interval.
///
/// # Errors
///
/// A scene that is not an axisymmetric ring (inner radius above zero) or has no moving
/// tool, or a run that fails.
pub fn curves(scene: &Scene, laws: &[Friction]) -> Result<Vec<Curve>, String> {
    let w = &scene.workpiece;
    if scene.model.kinematics != Kinematics::Axisymmetric || w.origin_m[0] <= 0.0 {
        return Err(format!(
            "scene `{}`: a ring is axisymmetric with its inner radius (workpiece.origin_m[0]) above zero",
            scene.name
        ));
    }
    if !scene
        .tools
        .iter()
        .any(|t| !matches!(t.motion, rkforge_core::scene::Motion::Fixed))
    {
        return Err(format!("scene `{}` has no moving tool", scene.name));
    }
    let end = scene.time.end_s;
    let interval = scene.history_interval();
    let times = sample_times(end, interval)
        .ok_or_else(|| format!("output.history_interval_s {interval} gives too many samples"))?;
    let (d0, h0) = (2.0 * w.origin_m[0], w.size_m[1]);
    let mut out = Vec::new();
    for law in laws {
        let mut s = scene.clone();
        for t in s.tools.iter_mut() {
            if !matches!(t.motion, rkforge_core::scene::Motion::Fixed) {
                t.friction = *law;
            }
        }
        let mut sim = Simulation::new(&s).map_err(|e| e.to_string())?;
        let mut curve = Curve {
            source: Source::Simulation,
            friction: *law,
            reduction_pct: vec![0.0],
            decrease_pct: vec![0.0],
        };
        for &t in &times {
            sim.run_to(t, |_| {})
                .map_err(|e| format!("{}: {e}", label(law)))?;
            let e = sim.extents();
            let inner = 2.0 * sim.face_extents(Edge::XMin).x[0];
            curve
                .reduction_pct
                .push(100.0 * (1.0 - (e.y[1] - e.y[0]) / h0));
            curve.decrease_pct.push(100.0 * (1.0 - inner / d0));
        }
        out.push(curve);
    }
    Ok(out)
}

/// The upper-bound curve of `ring` beside each simulated shear-friction curve of `runs`,
/// with the same m, every [`REFERENCE_SPACING_PCT`] of height reduction up to the run's
/// largest.
pub fn upper_bound_curves(ring: &Ring, runs: &[Curve]) -> Vec<Curve> {
    runs.iter()
        .filter_map(|c| match c.friction {
            Friction::Shear { m } if c.source == Source::Simulation => Some((m, c)),
            _ => None,
        })
        .map(|(m, c)| {
            let last = c.reduction_pct.iter().copied().fold(0.0, f64::max);
            let n = (last / REFERENCE_SPACING_PCT).floor() as usize;
            let mut reduction_pct: Vec<f64> =
                (0..=n).map(|k| k as f64 * REFERENCE_SPACING_PCT).collect();
            if last > n as f64 * REFERENCE_SPACING_PCT {
                reduction_pct.push(last);
            }
            Curve {
                source: Source::UpperBound,
                friction: Friction::Shear { m },
                decrease_pct: ring.inner_diameter_decrease_pct(m, &reduction_pct),
                reduction_pct,
            }
        })
        .collect()
}

/// The chart's CSV:
/// `source,law,mu,m,height_reduction_pct,inner_diameter_decrease_pct`, `source` being
/// `simulation` or `upper_bound`.
pub fn csv(curves: &[Curve]) -> String {
    let mut s = String::from("source,law,mu,m,height_reduction_pct,inner_diameter_decrease_pct\n");
    for c in curves {
        let (law, mu, m) = match c.friction {
            Friction::Coulomb { mu } => ("coulomb", mu, f64::NAN),
            Friction::Shear { m } => ("shear", f64::NAN, m),
            Friction::Capped { mu, m } => ("capped", mu, m),
        };
        for (r, d) in c.reduction_pct.iter().zip(&c.decrease_pct) {
            let source = c.source.name();
            let _ = writeln!(s, "{source},{law},{mu},{m},{r:.4},{d:.4}");
        }
    }
    s
}

/// One shear friction factor of the comparison table.
pub struct Comparison {
    /// The friction factor m.
    pub m: f64,
    /// Simulated inner diameter decrease (%) at each of [`TABLE_REDUCTIONS_PCT`]; `None`
    /// beyond the run's stroke.
    pub simulated: Vec<Option<f64>>,
    /// Upper-bound inner diameter decrease (%) at each of [`TABLE_REDUCTIONS_PCT`].
    pub upper_bound: Vec<f64>,
}

/// Simulated against upper bound at [`TABLE_REDUCTIONS_PCT`] for every shear-friction run.
pub fn comparison(ring: &Ring, runs: &[Curve]) -> Vec<Comparison> {
    runs.iter()
        .filter_map(|c| match c.friction {
            Friction::Shear { m } if c.source == Source::Simulation => Some(Comparison {
                m,
                simulated: TABLE_REDUCTIONS_PCT.map(|r| c.decrease_at(r)).to_vec(),
                upper_bound: ring.inner_diameter_decrease_pct(m, &TABLE_REDUCTIONS_PCT),
            }),
            _ => None,
        })
        .collect()
}

/// A signed percentage with one decimal, or `-` without a value.
fn pct(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:+.1}"))
}

/// The comparison as a Markdown table: per m the simulated and the upper-bound decrease of
/// the inner diameter (%) and their difference (simulated minus upper bound, percentage
/// points) at each height reduction.
pub fn comparison_table(rows: &[Comparison]) -> String {
    let mut s = String::from("| m | |");
    for r in TABLE_REDUCTIONS_PCT {
        let _ = write!(s, " {r} % |");
    }
    s.push_str("\n|---|---|");
    s.push_str(&"---|".repeat(TABLE_REDUCTIONS_PCT.len()));
    s.push('\n');
    for c in rows {
        let lines: [(String, &str, Vec<Option<f64>>); 3] = [
            (c.m.to_string(), "simulated", c.simulated.clone()),
            (
                String::new(),
                "upper bound",
                c.upper_bound.iter().map(|&u| Some(u)).collect(),
            ),
            (
                String::new(),
                "difference",
                c.simulated
                    .iter()
                    .zip(&c.upper_bound)
                    .map(|(s, u)| s.map(|s| s - u))
                    .collect(),
            ),
        ];
        for (m, what, values) in lines {
            let _ = write!(s, "| {m} | {what} |");
            for v in values {
                let _ = write!(s, " {} |", pct(v));
            }
            s.push('\n');
        }
    }
    s
}

/// The comparison as CSV:
/// `m,height_reduction_pct,simulated_pct,upper_bound_pct,difference_pct` (empty simulated
/// and difference beyond the run's stroke).
pub fn comparison_csv(rows: &[Comparison]) -> String {
    let mut s =
        String::from("m,height_reduction_pct,simulated_pct,upper_bound_pct,difference_pct\n");
    for c in rows {
        for ((r, sim), ub) in TABLE_REDUCTIONS_PCT
            .iter()
            .zip(&c.simulated)
            .zip(&c.upper_bound)
        {
            let (sim, diff) = sim.map_or((String::new(), String::new()), |v| {
                (format!("{v:.4}"), format!("{:.4}", v - ub))
            });
            let _ = writeln!(s, "{},{r},{sim},{ub:.4},{diff}", c.m);
        }
    }
    s
}

/// Runs the chart and writes `ring_chart.csv`, `ring_chart.png` and, for a mirrored half
/// ring ([`mirrored_ring`]), `ring_chart_comparison.csv` into `out`. Returns the comparison
/// with the upper bound per shear friction factor, `None` without a mirrored half ring.
///
/// # Errors
///
/// As [`curves`], or a file that cannot be written.
pub fn chart(
    scene: &Scene,
    laws: &[Friction],
    out: &Path,
) -> Result<Option<Vec<Comparison>>, String> {
    let mut curves = curves(scene, laws)?;
    let ring = mirrored_ring(scene);
    let comparison = ring.map(|ring| {
        curves.extend(upper_bound_curves(&ring, &curves));
        comparison(&ring, &curves)
    });
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let write = |name: &str, text: String| {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
    };
    write("ring_chart.csv", csv(&curves))?;
    if let Some(rows) = &comparison {
        write("ring_chart_comparison.csv", comparison_csv(rows))?;
    }
    let runs = curves.iter().filter(|c| c.source == Source::Simulation);
    let mut series: Vec<Series> = runs
        .clone()
        .map(|c| Series {
            label: label(&c.friction),
            x: c.reduction_pct.clone(),
            y: c.decrease_pct.clone(),
            ..Series::default()
        })
        .collect();
    for reference in curves.iter().filter(|c| c.source == Source::UpperBound) {
        if let Some(k) = runs.clone().position(|c| c.friction == reference.friction) {
            series.push(Series {
                x: reference.reduction_pct.clone(),
                y: reference.decrease_pct.clone(),
                colour: Colour::Palette(k),
                dashed: true,
                ..Series::default()
            });
        }
    }
    let title = match comparison {
        Some(_) => format!("Ring calibration ({}), dashed: upper bound", scene.name),
        None => format!("Ring compression calibration ({})", scene.name),
    };
    line_plot(
        &out.join("ring_chart.png"),
        &title,
        "height reduction (%)",
        "decrease of inner diameter (%)",
        &series,
        &[],
    )?;
    Ok(comparison)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring_scene() -> Scene {
        let text = include_str!("../../scenes/ring_compression.toml");
        Scene::from_str_named(text, "ring_compression.toml").unwrap()
    }

    fn run(m: f64, reduction_pct: Vec<f64>, decrease_pct: Vec<f64>) -> Curve {
        Curve {
            source: Source::Simulation,
            friction: Friction::Shear { m },
            reduction_pct,
            decrease_pct,
        }
    }

    #[test]
    fn a_bar_on_the_axis_is_not_a_ring() {
        let s = Scene::from_str_named(crate::DEFAULT_SCENE, "taylor_bar.toml").unwrap();
        let e = curves(&s, &[Friction::Shear { m: 0.1 }]).err().unwrap();
        assert!(e.contains("inner radius"), "{e}");
    }

    #[test]
    fn the_shipped_half_ring_is_the_full_6_3_2_ring() {
        let mut scene = ring_scene();
        let ring = mirrored_ring(&scene).expect("mirrored at y_min");
        assert_eq!(ring.inner, 0.015);
        assert_eq!(ring.outer, 0.030);
        assert_eq!(ring.thickness, 0.020);
        scene.constraints.clear();
        assert!(mirrored_ring(&scene).is_none());
    }

    #[test]
    fn csv_has_one_row_per_sample_and_names_the_source_and_law() {
        let c = Curve {
            source: Source::Simulation,
            friction: Friction::Capped { mu: 0.1, m: 0.4 },
            reduction_pct: vec![0.0, 10.0],
            decrease_pct: vec![0.0, 2.5],
        };
        let text = csv(&[c]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[2], "simulation,capped,0.1,0.4,10.0000,2.5000");
    }

    #[test]
    fn upper_bounds_follow_the_shear_runs_to_their_last_reduction() {
        let ring = mirrored_ring(&ring_scene()).unwrap();
        let coulomb = Curve {
            friction: Friction::Coulomb { mu: 0.1 },
            ..run(0.0, vec![0.0, 30.0], vec![0.0, 1.0])
        };
        let runs = [run(0.0, vec![0.0, 20.2], vec![0.0, -12.0]), coulomb];
        let refs = upper_bound_curves(&ring, &runs);
        assert_eq!(refs.len(), 1);
        let r = &refs[0];
        assert_eq!(r.source, Source::UpperBound);
        assert_eq!(r.reduction_pct.len(), 42);
        assert_eq!(r.reduction_pct[40], 20.0);
        assert_eq!(r.reduction_pct[41], 20.2);
        // m = 0: Ri sqrt(T0 / T).
        let homogeneous = 100.0 * (1.0 - 1.0 / (1.0_f64 - 0.202).sqrt());
        assert!((r.decrease_pct[41] - homogeneous).abs() < 1e-9);
        let text = csv(&refs);
        assert!(text
            .lines()
            .nth(1)
            .unwrap()
            .starts_with("upper_bound,shear,NaN,0,"));
    }

    #[test]
    fn comparison_interpolates_the_run_and_stops_at_its_stroke() {
        let ring = mirrored_ring(&ring_scene()).unwrap();
        let runs = [run(0.4, vec![0.0, 20.0, 39.995], vec![0.0, 4.0, 8.0])];
        let rows = comparison(&ring, &runs);
        assert_eq!(rows.len(), 1);
        let c = &rows[0];
        let sim: Vec<String> = c.simulated.iter().map(|&v| pct(v)).collect();
        assert_eq!(sim, ["+2.0", "+4.0", "+6.0", "+8.0", "-"]);
        // 40 % is 0.005 beyond the last sample: read along the last segment.
        assert!((c.simulated[3].unwrap() - (8.0 + 0.005 * 4.0 / 19.995)).abs() < 1e-12);
        assert_eq!(
            c.upper_bound,
            ring.inner_diameter_decrease_pct(0.4, &TABLE_REDUCTIONS_PCT)
        );
        let table = comparison_table(&rows);
        let lines: Vec<&str> = table.lines().collect();
        assert_eq!(lines.len(), 5);
        assert_eq!(lines[0], "| m | | 10 % | 20 % | 30 % | 40 % | 50 % |");
        assert_eq!(
            lines[2],
            "| 0.4 | simulated | +2.0 | +4.0 | +6.0 | +8.0 | - |"
        );
        let diff = format!("{:+.1}", 2.0 - c.upper_bound[0]);
        assert!(
            lines[4].starts_with(&format!("|  | difference | {diff} |")),
            "{table}"
        );
        let text = comparison_csv(&rows);
        assert_eq!(text.lines().count(), 6);
        assert!(
            text.lines().nth(5).unwrap().starts_with("0.4,50,,"),
            "{text}"
        );
    }
}
