//! The 3D solver against closed-form answers.

use rkforge_core::scene::{SceneFile, SolidScene};
use rkforge_core::solver::SolidSimulation;
use std::f64::consts::PI;

/// A quarter of an elastic steel bar (radius 5 mm, length 100 mm) hitting a rigid wall at
/// 1 m/s, the wall letting it go again.
fn elastic_bar() -> SolidScene {
    let text = r#"
name = "elastic_bar"
[model]
kinematics = "3d"
[workpiece]
shape = "cylinder"
radius_m = 0.005
length_m = 0.1
part = "quarter"
cells = [4, 2, 40]
initial_velocity_m_per_s = [0.0, 0.0, -1.0]
[material]
density_kg_per_m3 = 7800.0
youngs_modulus_pa = 200e9
poisson_ratio = 0.3
hardening = { law = "linear", yield_stress_pa = 1e12, modulus_pa = 0.0 }
[time]
end_s = 60e-6
[[tools]]
name = "wall"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, -1.0]
motion = { kind = "fixed" }
"#;
    match SceneFile::from_str_named(text, "elastic_bar.toml").unwrap() {
        SceneFile::Solid(s) => *s,
        SceneFile::Plane(_) => panic!("read as 2D"),
    }
}

/// 1D wave theory (a long bar, Graff 1975, Wave Motion in Elastic Solids, section 2.1): the
/// bar stays on the wall for `2 L / c0`, `c0 = sqrt(E / rho)`, pressing it with `rho c0 v0
/// A` (a quarter of it on the quarter model). The contact ends within 3 % of `2 L / c0` and
/// the force over the middle 80 % of that time averages within 3 % of the plateau; the
/// energy account closes and no particle enters the wall or crosses a symmetry plane by
/// more than 1e-3 of a spacing.
#[test]
fn an_elastic_bar_impact_follows_1d_wave_theory() {
    let (e, rho, v0, r, l): (f64, f64, f64, f64, f64) = (200e9, 7800.0, 1.0, 0.005, 0.1);
    let c0: f64 = (e / rho).sqrt();
    let (t_c, plateau) = (2.0 * l / c0, rho * c0 * v0 * PI * r * r / 4.0);
    let mut sim = SolidSimulation::new(&elastic_bar()).unwrap();
    let dt = 0.25e-6;
    let mut samples = Vec::new();
    for k in 1..=240 {
        sim.run_toward(k as f64 * dt, u64::MAX, |_, _| true)
            .unwrap();
        sim.measure_penetration().unwrap();
        samples.push((sim.time(), sim.tools()[0].axial_force()));
    }
    let end = samples
        .iter()
        .find(|&&(t, f)| t > 0.5 * t_c && f == 0.0)
        .map(|&(t, _)| t)
        .expect("the bar leaves the wall");
    // The force falls to zero between the last sample with a force and this one.
    let left = end - 0.5 * dt;
    assert!(
        (left / t_c - 1.0).abs() < 0.03,
        "contact {left:e} s against 2 L / c0 = {t_c:e} s"
    );
    let middle: Vec<f64> = samples
        .iter()
        .filter(|&&(t, _)| t > 0.1 * t_c && t < 0.9 * t_c)
        .map(|&(_, f)| f)
        .collect();
    let mean = middle.iter().sum::<f64>() / middle.len() as f64;
    assert!(
        (mean / plateau - 1.0).abs() < 0.03,
        "mean force {mean} N against rho c0 v0 A / 4 = {plateau} N"
    );
    let energy = sim.energy();
    assert!(energy.balance_error_rel() < 1e-3, "{energy:?}");
    let st = sim.state();
    let h = sim.h_min();
    assert!(
        st.max_penetration < 1e-3 * h && st.max_beyond_plane < 1e-3 * h,
        "in the wall {:e} m, beyond a plane {:e} m, spacing {h:e} m",
        st.max_penetration,
        st.max_beyond_plane
    );
    eprintln!(
        "contact {:.3} us (2L/c0 {:.3} us), mean force {mean:.1} N (plateau {plateau:.1} N)",
        left * 1e6,
        t_c * 1e6
    );
}
