//! `rkforge ring-chart`: the friction calibration chart of the ring compression test
//! (Male and Cockcroft 1964-65): the decrease of the ring's smallest inner diameter against
//! the height reduction, one curve per friction law of the pressing tool. Writes
//! `ring_chart.csv` and `ring_chart.png`.

use crate::output::plots::{line_plot, Series};
use rkforge_core::scene::{Edge, Friction};
use rkforge_core::{sample_times, Kinematics, Scene, Simulation};
use std::fmt::Write as _;
use std::path::Path;

/// One curve: the law and its (height reduction %, inner diameter decrease %) points.
pub struct Curve {
    /// The tool's friction law.
    pub friction: Friction,
    /// Height reduction `1 - h / h0` (%).
    pub reduction_pct: Vec<f64>,
    /// Decrease of the smallest inner diameter, `1 - D_i / D_i0` (%; negative when the
    /// hole grows).
    pub decrease_pct: Vec<f64>,
}

/// The legend label of a law.
fn label(f: &Friction) -> String {
    match *f {
        Friction::Coulomb { mu } => format!("mu = {mu}"),
        Friction::Shear { m } => format!("m = {m}"),
        Friction::Capped { mu, m } => format!("mu = {mu}, m <= {m}"),
    }
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
    let interval = scene.output.history_interval_s.unwrap_or(end / 200.0);
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

/// The chart's CSV: `law,m,mu,height_reduction_pct,inner_diameter_decrease_pct`.
pub fn csv(curves: &[Curve]) -> String {
    let mut s = String::from("law,mu,m,height_reduction_pct,inner_diameter_decrease_pct\n");
    for c in curves {
        let (law, mu, m) = match c.friction {
            Friction::Coulomb { mu } => ("coulomb", mu, f64::NAN),
            Friction::Shear { m } => ("shear", f64::NAN, m),
            Friction::Capped { mu, m } => ("capped", mu, m),
        };
        for (r, d) in c.reduction_pct.iter().zip(&c.decrease_pct) {
            let _ = writeln!(s, "{law},{mu},{m},{r:.4},{d:.4}");
        }
    }
    s
}

/// Runs the chart and writes `ring_chart.csv` and `ring_chart.png` into `out`.
///
/// # Errors
///
/// As [`curves`], or a file that cannot be written.
pub fn chart(scene: &Scene, laws: &[Friction], out: &Path) -> Result<Vec<Curve>, String> {
    let curves = curves(scene, laws)?;
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let path = out.join("ring_chart.csv");
    std::fs::write(&path, csv(&curves))
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    let series: Vec<Series> = curves
        .iter()
        .map(|c| Series {
            label: label(&c.friction),
            x: c.reduction_pct.clone(),
            y: c.decrease_pct.clone(),
        })
        .collect();
    line_plot(
        &out.join("ring_chart.png"),
        &format!("Ring compression calibration ({})", scene.name),
        "height reduction (%)",
        "decrease of inner diameter (%)",
        &series,
        &[],
    )?;
    Ok(curves)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bar_on_the_axis_is_not_a_ring() {
        let s = Scene::from_str_named(crate::DEFAULT_SCENE, "taylor_bar.toml").unwrap();
        let e = curves(&s, &[Friction::Shear { m: 0.1 }]).err().unwrap();
        assert!(e.contains("inner radius"), "{e}");
    }

    #[test]
    fn csv_has_one_row_per_sample_and_names_the_law() {
        let c = Curve {
            friction: Friction::Capped { mu: 0.1, m: 0.4 },
            reduction_pct: vec![0.0, 10.0],
            decrease_pct: vec![0.0, 2.5],
        };
        let text = csv(&[c]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 3);
        assert_eq!(lines[2], "capped,0.1,0.4,10.0000,2.5000");
    }
}
