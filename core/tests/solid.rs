//! The 3D solver against closed-form answers.

use rkforge_core::scene::{SceneFile, SolidScene};
use rkforge_core::solver::SolidSimulation;
use std::f64::consts::PI;

/// A quarter of an elastic steel bar (radius 5 mm, length 100 mm) hitting a rigid wall at
/// 1 m/s, the wall letting it go again.
fn elastic_bar() -> SolidScene {
    match SceneFile::from_str_named(&elastic_bar_text(), "elastic_bar.toml").unwrap() {
        SceneFile::Solid(s) => *s,
        SceneFile::Plane(_) => panic!("read as 2D"),
    }
}

/// The scene text of [`elastic_bar`].
fn elastic_bar_text() -> String {
    r#"
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
"#
    .to_string()
}

/// 1D wave theory (a long bar, Graff 1975, Wave Motion in Elastic Solids, section 2.1): the
/// bar stays on the wall for `2 L / c0`, `c0 = sqrt(E / rho)`, pressing it with `rho c0 v0
/// A` (a quarter of it on the quarter model). The contact ends within 3 % of `2 L / c0` and
/// the force over the middle 80 % of that time averages within 3 % of the plateau; the
/// energy account closes and no particle enters the wall or crosses a symmetry plane by
/// more than 1e-3 of a spacing. The round bar on its O-grid with q2 (the scene's default).
#[test]
fn an_elastic_bar_impact_follows_1d_wave_theory() {
    let r: f64 = 0.005;
    follows_wave_theory(elastic_bar(), PI * r * r / 4.0);
}

/// The same impact of a square bar (10 x 10 mm, a quarter modelled, on a lattice of 6 x 6 x
/// 81 particles) integrated with SCNI over the particles' nodal domains: contact 40.4 us
/// against 39.5 us (+2.2 %, as the round bar's q2), mean force 986.3 N against 987.4 N.
#[test]
fn a_square_bar_with_scni_follows_1d_wave_theory() {
    let text = elastic_bar_text()
        .replace(
            "shape = \"cylinder\"\nradius_m = 0.005\nlength_m = 0.1\npart = \"quarter\"\ncells = [4, 2, 40]",
            "shape = \"box\"\norigin_m = [0.0, 0.0, 0.0]\nsize_m = [0.005, 0.005, 0.1]\nparticles = [6, 6, 81]\nsymmetry = [\"x_min\", \"y_min\"]",
        )
        .replace("[time]", "[discretization]\nintegration = \"scni\"\n[time]");
    let scene = match SceneFile::from_str_named(&text, "square_bar.toml").unwrap() {
        SceneFile::Solid(s) => *s,
        SceneFile::Plane(_) => panic!("read as 2D"),
    };
    assert_eq!(
        scene.discretization.integration,
        rkforge_core::IntegrationRule::Scni
    );
    let sim = SolidSimulation::new(&scene).unwrap();
    assert_eq!(sim.point_count(), sim.particle_count());
    follows_wave_theory(scene, 0.005 * 0.005);
}

/// The round bar's impact integrated with SCNI over the O-grid's nodal domains (the
/// octants of the cells around each particle, following the round surface): contact
/// 40.6 us against 39.5 us (+2.9 %; q2 on the same grid +2.2 %, and the samples are
/// 0.25 us apart), mean force 773.4 N against 775.5 N.
#[test]
fn a_round_bar_with_scni_follows_1d_wave_theory() {
    let text =
        elastic_bar_text().replace("[time]", "[discretization]\nintegration = \"scni\"\n[time]");
    let scene = match SceneFile::from_str_named(&text, "round_bar_scni.toml").unwrap() {
        SceneFile::Solid(s) => *s,
        SceneFile::Plane(_) => panic!("read as 2D"),
    };
    let sim = SolidSimulation::new(&scene).unwrap();
    assert_eq!(sim.point_count(), sim.particle_count());
    let r: f64 = 0.005;
    follows_wave_theory(scene, PI * r * r / 4.0);
}

/// The checks of the bar impact on `scene`, whose modelled cross-section is `area` (m^2).
fn follows_wave_theory(scene: SolidScene, area: f64) {
    let (e, rho, v0, l): (f64, f64, f64, f64) = (200e9, 7800.0, 1.0, 0.1);
    let c0: f64 = (e / rho).sqrt();
    let (t_c, plateau) = (2.0 * l / c0, rho * c0 * v0 * area);
    let mut sim = SolidSimulation::new(&scene).unwrap();
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
        "mean force {mean} N against rho c0 v0 A = {plateau} N"
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

/// A steel box (`origin`, `size`, `particles`, symmetry faces) at 100 m/s onto the FE wall.
fn box_impact(
    origin: [f64; 3],
    size: [f64; 3],
    particles: [usize; 3],
    symmetry: &str,
) -> SolidScene {
    let text = format!(
        r#"
name = "box_impact"
[model]
kinematics = "3d"
[workpiece]
shape = "box"
origin_m = {origin:?}
size_m = {size:?}
particles = {particles:?}
symmetry = {symmetry}
initial_velocity_m_per_s = [0.0, 0.0, -100.0]
[material]
density_kg_per_m3 = 7800.0
youngs_modulus_pa = 200e9
poisson_ratio = 0.3
hardening = {{ law = "linear", yield_stress_pa = 300e6, modulus_pa = 1e9 }}
[discretization]
integration = "q4"
[time]
end_s = 8e-6
[[tools]]
name = "wall"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "fixed" }}
separation = false
"#
    );
    match SceneFile::from_str_named(&text, "box_impact.toml").unwrap() {
        SceneFile::Solid(s) => *s,
        SceneFile::Plane(_) => panic!("read as 2D"),
    }
}

/// The symmetry planes hold a quarter model as the whole body's symmetry does: a quarter
/// of a square box on the planes x = 0 and y = 0 against the whole box on the same lattice
/// (the quarter's particles are the whole's with x, y >= 0). The two differ only near the
/// planes, where the quarter's kernels are cut off (no particles beyond) and the whole's are
/// not, a difference that falls with the spacing: after 8 us, with 5 x 5 x 11 particles
/// in the quarter, its plastic work and kinetic energy are 1.0 % below a quarter of the
/// whole's and its impact face spreads 1.5 % further; with 9 x 9 x 21, 0.3 %, 0.4 % and
/// 0.6 %. Here (the coarse pair): plastic work and kinetic energy within 2 %, the impact
/// face's spread within 3 %, and no particle beyond a plane by more than 1e-3 of a spacing.
#[test]
fn symmetry_planes_hold_a_quarter_as_the_whole_body_does() {
    let (a, l, n, m) = (4e-3, 10e-3, 5, 11);
    let run = |scene: SolidScene| {
        let mut sim = SolidSimulation::new(&scene).unwrap();
        sim.run_toward(8e-6, u64::MAX, |_, _| true).unwrap();
        sim.measure_penetration().unwrap();
        let x = sim.positions();
        let foot = sim
            .reference_positions()
            .iter()
            .zip(&x)
            .filter(|(r, _)| r[2] == 0.0)
            .map(|(_, p)| p[0])
            .fold(f64::NEG_INFINITY, f64::max);
        let e = sim.energy();
        (
            foot,
            e.plastic,
            e.kinetic,
            sim.state().max_beyond_plane,
            sim.h_min(),
        )
    };
    let (q_foot, q_plastic, q_kinetic, beyond, h) = run(box_impact(
        [0.0; 3],
        [a, a, l],
        [n, n, m],
        "[\"x_min\", \"y_min\"]",
    ));
    let (w_foot, w_plastic, w_kinetic, _, _) = run(box_impact(
        [-a, -a, 0.0],
        [2.0 * a, 2.0 * a, l],
        [2 * n - 1, 2 * n - 1, m],
        "[]",
    ));
    assert!(q_foot > a * 1.02, "the foot spreads: {q_foot:e} m");
    assert!(
        ((q_foot - a) / (w_foot - a) - 1.0).abs() < 0.03,
        "foot {q_foot:e} against {w_foot:e} m"
    );
    assert!(
        (4.0 * q_plastic / w_plastic - 1.0).abs() < 0.02,
        "plastic work {q_plastic} J against a quarter of {w_plastic} J"
    );
    assert!(
        (4.0 * q_kinetic / w_kinetic - 1.0).abs() < 0.02,
        "kinetic energy {q_kinetic} J against a quarter of {w_kinetic} J"
    );
    assert!(
        beyond < 1e-3 * h,
        "beyond a plane {beyond:e} m, spacing {h:e} m"
    );
}

/// An eighth of an aluminium cube (the planes x = 0, y = 0 and z = 0 its symmetry planes)
/// pressed by a frictionless plane from above to 10 % of its height, the press's speed
/// ramped up to `speed` (m/s) over 50 us (a press does not start at full speed, and a sudden
/// start would set the scaled body ringing), with `[time] mass_scaling` given as `scaling`
/// (TOML, or empty).
fn cube_press(speed: f64, scaling: &str) -> SolidScene {
    let text = format!(
        r#"
name = "cube_press"
[model]
kinematics = "3d"
[workpiece]
shape = "box"
origin_m = [0.0, 0.0, 0.0]
size_m = [0.005, 0.005, 0.005]
particles = [5, 5, 5]
symmetry = ["x_min", "y_min", "z_min"]
initial_velocity_m_per_s = [0.0, 0.0, 0.0]
[material]
density_kg_per_m3 = 2700.0
youngs_modulus_pa = 70e9
poisson_ratio = 0.33
hardening = {{ law = "linear", yield_stress_pa = 100e6, modulus_pa = 500e6 }}
[discretization]
integration = "q2"
[time]
end_s = {end}
{scaling}
[[tools]]
name = "top"
point_m = [0.0, 0.0, 0.005]
normal = [0.0, 0.0, -1.0]
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "table", points = [[0.0, 0.0], [50e-6, {speed}]] }}
[output]
history_interval_s = {end}
"#,
        end = 0.5e-3 / speed + 25e-6
    );
    match SceneFile::from_str_named(&text, "cube_press.toml").unwrap() {
        SceneFile::Solid(s) => *s,
        SceneFile::Plane(_) => panic!("read as 2D"),
    }
}

/// Mass scaling in 3D buys steps and keeps a slow press's answer: an eighth of a cube pressed
/// frictionless to 10 % at 2 m/s (the elastic wave crosses it some 300 times over the
/// stroke, some 30 times with the masses scaled by 100: quasi-static) gives the force of homogeneous compression, `F = (sigma_0 + H eps) A_0 h_0
/// / h` with `eps = ln(h_0 / h)` (plastic flow keeps the volume): 4209.2 N against 4241.1 N
/// in 2521 steps; uniform scaling by 100 takes a tenth of the steps (`sqrt(100)` on the
/// critical step), 254, and gives 4195.6 N, within 1 % of the unscaled force (0.32 %); and
/// selective scaling to a target step reaches it.
#[test]
fn mass_scaling_keeps_a_slow_press_answer_in_fewer_steps() {
    let run = |scene: SolidScene| {
        let mut sim = SolidSimulation::new(&scene).unwrap();
        sim.run_toward(scene.time.end_s, u64::MAX, |_, _| true)
            .unwrap();
        sim.measure_penetration().unwrap();
        let e = sim.energy();
        assert!(e.balance_error_rel() < 1e-2, "{e:?}");
        // The cube pushes the tool up, against its axis (down).
        (
            -sim.tools()[0].axial_force(),
            sim.steps(),
            sim.mass_scaling(),
        )
    };
    let (plain, steps, none) = run(cube_press(2.0, ""));
    assert!(none.is_none());
    let (h0, h): (f64, f64) = (5e-3, 4.5e-3);
    let eps = (h0 / h).ln();
    let exact = (100e6 + 500e6 * eps) * 25e-6 * h0 / h;
    assert!(
        (plain / exact - 1.0).abs() < 0.02,
        "force {plain} N against homogeneous compression {exact} N"
    );
    let (uniform, steps_uniform, report) =
        run(cube_press(2.0, "mass_scaling = { factor = 100.0 }"));
    let report = report.unwrap();
    assert!((report.added_mass_rel - 99.0).abs() < 1e-9, "{report:?}");
    assert!(
        (report.critical_dt_s / report.critical_dt_unscaled_s - 10.0).abs() < 0.05,
        "{report:?}"
    );
    let ratio = steps as f64 / steps_uniform as f64;
    assert!(
        (9.0..11.0).contains(&ratio),
        "{steps} against {steps_uniform} steps"
    );
    assert!(
        (uniform / plain - 1.0).abs() < 0.01,
        "scaled {uniform} N against {plain} N"
    );
    eprintln!(
        "unscaled {plain:.1} N in {steps} steps, scaled by 100 {uniform:.1} N in {steps_uniform} steps, homogeneous compression {exact:.1} N"
    );
    let target = 5.0 * report.critical_dt_unscaled_s * 0.5;
    let (_, _, selective) = run(cube_press(
        2.0,
        &format!("mass_scaling = {{ target_dt_s = {target:e} }}"),
    ));
    let selective = selective.unwrap();
    assert!(
        0.5 * selective.critical_dt_s >= target * 0.999,
        "{selective:?} against the target {target:e} s"
    );
}
