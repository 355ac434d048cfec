//! The 3D solver against closed-form answers.

mod common;

use common::solid_scenes::{box_scene, ALUMINIUM};
use rkforge_core::scene::solid::BoxFace;
use rkforge_core::scene::{IntegrationRule, SolidScene};
use rkforge_core::solver::SolidSimulation;
use std::f64::consts::PI;

/// A quarter of an elastic steel bar (radius 5 mm, length 100 mm) hitting a rigid wall at
/// 1 m/s, the wall letting it go again.
fn elastic_bar() -> SolidScene {
    SolidScene::from_str_named(&elastic_bar_text(), "elastic_bar.toml").unwrap()
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
    let scene = SolidScene::from_str_named(&text, "square_bar.toml").unwrap();
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
    let scene = SolidScene::from_str_named(&text, "round_bar_scni.toml").unwrap();
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
    SolidScene::from_str_named(&text, "box_impact.toml").unwrap()
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
    let eighth = ["x_min", "y_min", "z_min"];
    let block = box_scene("cube_press", [0.005; 3], [5; 3], &eighth, ALUMINIUM, "q2");
    let text = format!(
        r#"{block}[time]
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
    SolidScene::from_str_named(&text, "cube_press.toml").unwrap()
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

// Heat in 3D: conduction and the heat to the tools and the surroundings, against closed
// forms and the 2D solver on the same problem.

/// Copper-like constants: k 400 W/(m K), rho 8960 kg/m^3, c 385 J/(kg K) (the 2D conduction
/// tests', `core/tests/conduction.rs`).
const K_CU: f64 = 400.0;
const RHO_C_CU: f64 = 8960.0 * 385.0;

/// The `[material]` keys of copper, perfectly plastic at `yield_stress_pa` (Pa): 8960
/// kg/m^3, E 124 GPa, nu 0.34.
fn copper(yield_stress_pa: f64) -> String {
    format!(
        r#"density_kg_per_m3 = 8960.0
youngs_modulus_pa = 124.0e9
poisson_ratio = 0.34
hardening = {{ law = "linear", yield_stress_pa = {yield_stress_pa:e}, modulus_pa = 0.0 }}"#
    )
}

/// A box `size` (m) of `particles` at `t0` (degrees C) with the `rule`, copper-like, its
/// mass scaled by 1e10 so that the mechanical step is not what the run waits on, with
/// `thermal` keys added to `[thermal]` and `extra` scene text after the `[time]` section
/// (the tools); run to `end` (s).
fn copper_box(
    size: [f64; 3],
    particles: [usize; 3],
    t0: f64,
    rule: &str,
    end: f64,
    thermal: &str,
    extra: &str,
) -> SolidScene {
    let block = box_scene("conduction3d", size, particles, &[], &copper(100.0e6), rule);
    let text = format!(
        r#"{block}[thermal]
initial_temperature_c = {t0}
specific_heat_j_per_kg_k = 385.0
conductivity_w_per_m_k = {K_CU}
{thermal}
[time]
end_s = {end}
mass_scaling = {{ factor = 1.0e10 }}
{extra}
"#
    );
    SolidScene::from_str_named(&text, "conduction3d.toml").unwrap()
}

/// `erfc(x)` to 1.2e-7 relative (Numerical Recipes, 2nd ed., section 6.2, `erfcc`).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// The heat balance `(content - made + lost) / scale` of a thermal run (-).
fn heat_balance(values: [f64; 9]) -> f64 {
    values[rkforge_core::THERMAL_MEASURES
        .iter()
        .position(|m| m.0 == "heat_balance_rel")
        .unwrap()]
}

/// Conduction alone: a 10 mm copper bar (a 1 x 1 mm section, insulated all round: no tool,
/// no convection or radiation) starting at `500 + 100 cos(pi x / L)` C decays to its mean as
/// `100 exp(-a (pi / L)^2 t) cos(pi x / L)` (`a = k / (rho c)`, the first Fourier mode
/// between insulated faces; Carslaw and Jaeger 1959, section 3.4). At `t = L^2 / (pi^2 a)`
/// (one e-folding, 0.087 s) the mode's amplitude (the points' temperatures projected on
/// `cos(pi x / L)` with their weights) is within 0.5 % of the closed form's on 0.5 mm
/// spacing (+0.40 %) and within 0.15 % on 0.25 mm (+0.09 %), the error falling more than 3
/// times (4.3: second order), with q4 and q2; with SCNI (the nodal domains) within 0.8 % and
/// 0.25 % (+0.65 %, +0.18 %). `thermal.dt_safety = 0.05` keeps the explicit step's own error
/// (of the other sign, -0.1 % at the default 0.5) below the grid's. The mean stays at 500 C
/// and the heat content at its start to round-off.
#[test]
fn conduction_alone_decays_a_cosine_as_the_closed_form() {
    let l: f64 = 0.01;
    let a = K_CU / RHO_C_CU;
    let end = l * l / (PI * PI * a);
    for rule in ["q4", "q2", "scni"] {
        let mut errors = Vec::new();
        for n in [21, 41] {
            let scene = copper_box(
                [l, 0.001, 0.001],
                [n, 3, 3],
                500.0,
                rule,
                end,
                "dt_safety = 0.05",
                "",
            );
            let mut sim = SolidSimulation::new(&scene).unwrap();
            sim.set_temperature(|x| 500.0 + 100.0 * (PI * x[0] / l).cos())
                .unwrap();
            let start = sim.thermal_values().unwrap();
            sim.run_toward(end, u64::MAX, |_, _| true).unwrap();
            let time = sim.heat_time();
            let (t, w) = (sim.point_temperature().unwrap(), sim.point_weights());
            let (mut proj, mut norm, mut heat, mut vol) = (0.0, 0.0, 0.0, 0.0);
            for (p, x) in sim.point_positions().iter().enumerate() {
                let c = (PI * x[0] / l).cos();
                proj += w[p] * (t[p] - 500.0) * c;
                norm += w[p] * c * c;
                heat += w[p] * t[p];
                vol += w[p];
            }
            let amplitude = proj / norm;
            let exact = 100.0 * (-a * (PI / l).powi(2) * time).exp();
            let error = (amplitude / exact - 1.0).abs();
            errors.push(error);
            assert!(
                (heat / vol - 500.0).abs() < 1e-9,
                "{rule}, {n}: mean {}",
                heat / vol
            );
            let now = sim.thermal_values().unwrap();
            // heat_content_J (index 5) held: nothing crosses the surface.
            assert!(
                (now[5] - start[5]).abs() < 1e-9 * start[5].abs().max(1.0),
                "{rule}, {n}: heat content {} J from {} J",
                now[5],
                start[5]
            );
            println!(
                "{rule}, {n} particles along L: amplitude {amplitude:.4} K against {exact:.4} K ({:+.3} %) at t = {time:.4} s",
                100.0 * (amplitude / exact - 1.0)
            );
        }
        // SCNI integrates over the nodal domains: less accurate, as in 2D.
        let bounds = if rule == "scni" {
            [0.008, 0.0025]
        } else {
            [0.005, 0.0015]
        };
        assert!(
            errors[0] < bounds[0] && errors[1] < bounds[1],
            "{rule}: {errors:?}"
        );
        assert!(errors[0] / errors[1] > 3.0, "{rule}: {errors:?}");
    }
}

/// A 40 mm copper bar (a 1 x 1 mm section on 0.5 mm spacing) at 20 C set on a die at 520 C
/// through h = 5e4 W/(m^2 K), its other faces insulated: the heat moves along z only. The
/// temperature at depth z after time t (0.05 to 0.4 s) against the semi-infinite solution
/// with surface resistance (Carslaw and Jaeger 1959, 2.7(1)),
///
/// `(T - T_i) / (T_d - T_i) = erfc(z / (2 sqrt(a t))) - exp(h z / k + h^2 a t / k^2)
/// erfc(z / (2 sqrt(a t)) + h sqrt(a t) / k)`,
///
/// every point within 0.5 % of the 500 K step (measured: at most 0.27 % with q4, 0.35 %
/// with q2; the 2D test's bound is 2 %, `core/tests/conduction.rs`); the heat the die gave
/// against its integral, `b = h sqrt(a t) / k`,
///
/// `Q / A = (T_d - T_i) k^2 / (h a) (exp(b^2) erfc(b) - 1 + 2 b / sqrt(pi))`,
///
/// within 0.5 % (at most 0.10 %); and against rkforge's 2D plane-strain run of the same bar
/// (the same spacing and rule name), the heat per area within 0.2 % (at most 0.094 %) and the
/// temperatures at the points of the same height within 0.6 % of the step (at most 0.49 %:
/// 3D's q2 is not 2D's). q4 and q2; SCNI within 0.8 % at the points (0.52 %), 0.5 % in the
/// heat (0.16 %), against 2D 0.5 % in the heat (0.15 %) and 1.2 % at the points (0.79 %).
/// The heat balance closes to round-off.
#[test]
fn a_3d_bar_on_a_hot_die_against_the_semi_infinite_solution_and_2d() {
    let (l, h, w) = (0.04, 5e4, 0.001);
    let a = K_CU / RHO_C_CU;
    let die = format!(
        r#"
[[tools]]
name = "bottom"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, 1.0]
motion = {{ kind = "fixed" }}
temperature_c = 520.0
heat_transfer_w_per_m2_k = {h}
"#
    );
    for rule in ["q4", "q2", "scni"] {
        let scene = copper_box([w, w, l], [3, 3, 81], 20.0, rule, 0.4, "", &die);
        let mut sim = SolidSimulation::new(&scene).unwrap();
        let plane = plane_bar(w, l, h, rule);
        let mut flat = rkforge_core::Simulation::new(&plane).unwrap();
        for t in [0.05, 0.1, 0.2, 0.4] {
            sim.run_toward(t, u64::MAX, |_, _| true).unwrap();
            flat.run_to(t, |_| {}).unwrap();
            let time = sim.heat_time();
            let s = (a * time).sqrt();
            let exact = |z: f64| {
                let e = z / (2.0 * s);
                let resistance = (h * z / K_CU + h * h * a * time / (K_CU * K_CU)).exp()
                    * erfc(e + h * s / K_CU);
                20.0 + 500.0 * (erfc(e) - resistance)
            };
            let temps = sim.point_temperature().unwrap();
            let worst = sim
                .point_positions()
                .iter()
                .enumerate()
                .map(|(p, x)| (temps[p] - exact(x[2])).abs() / 500.0)
                .fold(0.0, f64::max);
            let b = h * s / K_CU;
            let q_exact = -500.0 * K_CU * K_CU / (h * a)
                * ((b * b).exp() * erfc(b) - 1.0 + 2.0 * b / PI.sqrt());
            let q = sim.tool_heat(0).unwrap() / (w * w);
            // The 2D bar: the heat per area of its bottom (width w, depth 1 m), the
            // temperatures of its points by height.
            let q_flat = flat.tool_heat(0).unwrap() / (w * plane.model.depth_m);
            let flat_temps = flat.point_temperature().unwrap();
            let mut flat_worst: f64 = 0.0;
            for (p, x) in sim.point_positions().iter().enumerate() {
                for (r, y) in flat.point_positions().iter().enumerate() {
                    if (y[1] - x[2]).abs() < 1e-12 {
                        flat_worst = flat_worst.max((temps[p] - flat_temps[r]).abs() / 500.0);
                    }
                }
            }
            println!(
                "{rule}, t = {time:.3} s: worst point {:.3} % of the step off the closed form, {:.3} % off 2D; heat to the die {:.4e} J/m^2 against {q_exact:.4e} ({:+.3} %), 2D {q_flat:.4e} ({:+.3} %)",
                100.0 * worst,
                100.0 * flat_worst,
                q,
                100.0 * (q / q_exact - 1.0),
                100.0 * (q / q_flat - 1.0)
            );
            // SCNI integrates over the nodal domains: less accurate, as in 2D.
            let [points, heat, heat_2d, points_2d] = if rule == "scni" {
                [0.008, 0.005, 0.005, 0.012]
            } else {
                [0.005, 0.005, 0.002, 0.006]
            };
            assert!(worst < points, "{rule}, t = {time}: {worst}");
            assert!(
                (q / q_exact - 1.0).abs() < heat,
                "{rule}, t = {time}: {q} against {q_exact}"
            );
            assert!(
                (q / q_flat - 1.0).abs() < heat_2d,
                "{rule}, t = {time}: {q} against 2D {q_flat}"
            );
            assert!(
                flat_worst < points_2d,
                "{rule}, t = {time}: 2D {flat_worst}"
            );
            assert!(exact(l) - 20.0 < 0.5, "the far end is still cold");
            assert!(heat_balance(sim.thermal_values().unwrap()).abs() < 1e-9);
        }
    }
}

/// The 2D plane-strain bar of [`a_3d_bar_on_a_hot_die_against_the_semi_infinite_solution_and_2d`]:
/// `w` x `l` (m) on 0.5 mm spacing, on a die at 520 C through `h` (W/(m^2 K)).
fn plane_bar(w: f64, l: f64, h: f64, rule: &str) -> rkforge_core::Scene {
    let text = format!(
        r#"
name = "conduction"
[model]
kinematics = "plane_strain"
[workpiece]
origin_m = [0.0, 0.0]
size_m = [{w}, {l}]
particles = [3, 81]
[material]
density_kg_per_m3 = 8960.0
youngs_modulus_pa = 124.0e9
poisson_ratio = 0.34
hardening = {{ law = "linear", yield_stress_pa = 100.0e6, modulus_pa = 0.0 }}
[discretization]
integration = "{rule}"
[thermal]
initial_temperature_c = 20.0
specific_heat_j_per_kg_k = 385.0
conductivity_w_per_m_k = {K_CU}
[time]
end_s = 0.4
mass_scaling = {{ factor = 1.0e10 }}
[[tools]]
name = "bottom"
points_m = [[{mw}, 0.0], [{w2}, 0.0]]
axis = [0.0, 1.0]
motion = {{ kind = "fixed" }}
temperature_c = 520.0
heat_transfer_w_per_m2_k = {h}
"#,
        w2 = 2.0 * w,
        mw = -w
    );
    rkforge_core::Scene::from_str_named(&text, "conduction.toml").unwrap()
}

/// A hot upset in 3D: a quarter copper cylinder (radius 5 mm, 10 mm long, at 600 C) pressed
/// 2 mm in 20 ms between frictionless dies at 20 C, the ram through a constant 2e4 W/(m^2
/// K), the anvil through a coefficient over the contact pressure ([[0, 5e3], [2e8, 5e4]]),
/// the free surface to air at 20 C (convection 50 W/(m^2 K), emissivity 0.8): the heat
/// held plus what left to the dies and the air equals the plastic work's heat (`beta W_p`)
/// to round-off (`thermal.heat_balance_rel` below 1e-9, measured 7e-15), the heat made
/// matches the energy account's plastic work within 0.1 % (3.6524 J both), heat left through
/// every way (the anvil more than twice
/// what it takes at the table's h(0): the contact pressure is read), and the chilled ends
/// are the coldest. Restored from its state half way, it ends with the same bits.
#[test]
fn a_hot_upset_keeps_its_heat_account() {
    let text = r#"
name = "hot_upset3d"
[model]
kinematics = "3d"
[workpiece]
shape = "cylinder"
radius_m = 0.005
length_m = 0.01
part = "quarter"
cells = [2, 2, 8]
[material]
density_kg_per_m3 = 8960.0
youngs_modulus_pa = 124.0e9
poisson_ratio = 0.34
hardening = { law = "linear", yield_stress_pa = 60.0e6, modulus_pa = 300.0e6 }
[thermal]
initial_temperature_c = 600.0
specific_heat_j_per_kg_k = 385.0
conductivity_w_per_m_k = 400.0
taylor_quinney = 0.9
ambient_temperature_c = 20.0
convection_w_per_m2_k = 50.0
emissivity = 0.8
[time]
end_s = 0.02
mass_scaling = { factor = 1.0e4 }
[[tools]]
name = "anvil"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, -1.0]
motion = { kind = "fixed" }
temperature_c = 20.0
heat_transfer_by_pressure = [[0.0, 5.0e3], [2.0e8, 5.0e4]]
[[tools]]
name = "ram"
point_m = [0.0, 0.0, 0.01]
normal = [0.0, 0.0, -1.0]
axis = [0.0, 0.0, -1.0]
motion = { kind = "constant", velocity_m_per_s = 0.1 }
temperature_c = 20.0
heat_transfer_w_per_m2_k = 2.0e4
"#;
    let read = |text: &str| SolidScene::from_str_named(text, "hot_upset3d.toml").unwrap();
    let scene = read(text);
    // The anvil at the table's h(0) throughout: the contact pressure raised the
    // coefficient, so the anvil takes more heat than at h(0).
    let mut low = SolidSimulation::new(&read(&text.replace(
        "heat_transfer_by_pressure = [[0.0, 5.0e3], [2.0e8, 5.0e4]]",
        "heat_transfer_w_per_m2_k = 5.0e3",
    )))
    .unwrap();
    low.run_toward(scene.time.end_s, u64::MAX, |_, _| true)
        .unwrap();
    let mut sim = SolidSimulation::new(&scene).unwrap();
    sim.run_toward(0.5 * scene.time.end_s, u64::MAX, |_, _| true)
        .unwrap();
    let saved = sim.state().clone();
    sim.run_toward(scene.time.end_s, u64::MAX, |_, _| true)
        .unwrap();
    // A saved state goes on to the same bits, its heat stage's included.
    let mut again = SolidSimulation::new(&scene).unwrap();
    again.restore(saved).unwrap();
    again
        .run_toward(scene.time.end_s, u64::MAX, |_, _| true)
        .unwrap();
    assert_eq!(again.state(), sim.state());
    let v = sim.thermal_values().unwrap();
    let names: Vec<&str> = rkforge_core::THERMAL_MEASURES.iter().map(|m| m.0).collect();
    let at = |name: &str| v[names.iter().position(|n| *n == name).unwrap()];
    let plastic = at("plastic_heat_J");
    let balance = heat_balance(v);
    println!(
        "plastic heat {plastic:.4} J (beta W_p of the energy account {:.4} J), content {:.4} J, to tools {:.4} J ({:?}), to air {:.4} J, balance {balance:.1e}; temperatures {:.1} to {:.1} C",
        0.9 * sim.energy().plastic,
        at("heat_content_J"),
        at("heat_to_tools_J"),
        [sim.tool_heat(0).unwrap(), sim.tool_heat(1).unwrap()],
        at("heat_to_surroundings_J"),
        at("temperature_min_c"),
        at("temperature_max_c"),
    );
    assert!(balance.abs() < 1e-9, "heat balance {balance:e}");
    let work = 0.9 * sim.energy().plastic;
    assert!(
        plastic > 0.0 && (plastic / work - 1.0).abs() < 0.01,
        "{plastic} J against {work} J"
    );
    assert!(sim.tool_heat(0).unwrap() > 0.0 && sim.tool_heat(1).unwrap() > 0.0);
    let at_zero = low.tool_heat(0).unwrap();
    assert!(
        sim.tool_heat(0).unwrap() > 2.0 * at_zero,
        "the anvil took {} J over pressure, {at_zero} J at h(0)",
        sim.tool_heat(0).unwrap()
    );
    assert!(at("heat_to_surroundings_J") > 0.0);
    // The dies chilled the ends: the coldest point lies in a cell at either end.
    let t = sim.point_temperature().unwrap();
    let coldest = (0..t.len()).min_by(|&a, &b| t[a].total_cmp(&t[b])).unwrap();
    let z = sim.point_positions()[coldest][2];
    assert!(
        at("temperature_min_c") < 580.0,
        "{}",
        at("temperature_min_c")
    );
    assert!(
        !(0.00125..=0.00875).contains(&z),
        "the coldest point at z = {z} m"
    );
}

/// A copper cube of 20 mm at 800 C cooling in air at 20 C by convection (20 W/(m^2 K)) and
/// radiation (emissivity 0.8), modelled as an eighth (10 mm, 6 particles per edge, the
/// faces x, y, z = 0 on symmetry planes and so adiabatic): with a Biot number of 5e-4 the
/// body stays uniform and its temperature follows `rho c V dT/dt = -A (h (T - T_a) + eps
/// sigma (T^4 - T_a^4))` (T in kelvin for the radiation), `A` the three free faces (3e-4
/// m^2), integrated in the test by fourth-order Runge-Kutta. After 5 s (a drop of 31.16 K)
/// the mean temperature's drop and the heat to the surroundings are within 0.5 % of it
/// (measured: -0.17 %, the surface a little cooler than the mean; counting the symmetry
/// faces, the heat would double); no heat to tools; the balance to round-off.
#[test]
fn an_eighth_cube_cools_in_air_as_the_lumped_body() {
    let (h, eps, t0, ta, end): (f64, f64, f64, f64, f64) = (20.0, 0.8, 800.0, 20.0, 5.0);
    let scene = copper_box(
        [0.01; 3],
        [6, 6, 6],
        t0,
        "q4",
        end,
        &format!("ambient_temperature_c = {ta}\nconvection_w_per_m2_k = {h}\nemissivity = {eps}"),
        "",
    );
    let mut scene = scene;
    scene.workpiece.symmetry = vec![BoxFace::XMin, BoxFace::YMin, BoxFace::ZMin];
    let mut sim = SolidSimulation::new(&scene).unwrap();
    sim.run_toward(end, u64::MAX, |_, _| true).unwrap();
    let time = sim.heat_time();
    // The lumped body by RK4 in 10,000 steps.
    let (area, cap) = (3.0e-4, RHO_C_CU * 1.0e-6);
    let sigma = 5.670_374_419e-8;
    let rate = |t: f64| {
        let (tk, ak) = (t + 273.15, ta + 273.15);
        -area * (h * (t - ta) + eps * sigma * (tk.powi(4) - ak.powi(4))) / cap
    };
    let mut t = t0;
    let dt = time / 10_000.0;
    for _ in 0..10_000 {
        let k1 = rate(t);
        let k2 = rate(t + 0.5 * dt * k1);
        let k3 = rate(t + 0.5 * dt * k2);
        let k4 = rate(t + dt * k3);
        t += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
    let v = sim.thermal_values().unwrap();
    let names: Vec<&str> = rkforge_core::THERMAL_MEASURES.iter().map(|m| m.0).collect();
    let at = |name: &str| v[names.iter().position(|n| *n == name).unwrap()];
    let drop = t0 - at("temperature_mean_c");
    let to_air = at("heat_to_surroundings_J");
    let exact_heat = cap * (t0 - t);
    println!(
        "t = {time:.3} s: mean drop {drop:.4} K against {:.4} K ({:+.3} %); heat to air {to_air:.4} J against {exact_heat:.4} J ({:+.3} %)",
        t0 - t,
        100.0 * (drop / (t0 - t) - 1.0),
        100.0 * (to_air / exact_heat - 1.0)
    );
    assert!(
        (drop / (t0 - t) - 1.0).abs() < 0.005,
        "{drop} K against {} K",
        t0 - t
    );
    assert!(
        (to_air / exact_heat - 1.0).abs() < 0.005,
        "{to_air} J against {exact_heat} J"
    );
    assert_eq!(at("heat_to_tools_J"), 0.0);
    assert!(heat_balance(v).abs() < 1e-9);
}

/// The 3D scene `name` of a 4 x 4 x 2 mm copper box (5 x 5 x 3 particles, q4, elastic:
/// yield 1 GPa), the face x = 0 held on a symmetry plane, with the `[thermal]` section
/// `thermal` (or none), pressed by a frictionless ram coming down at `ram_speed` (m/s) onto
/// an anvil that slides under it along x at `anvil_speed` (m/s) with the friction `friction`
/// (a scene value), for 10 ms with the mass scaled by 1e4.
fn sliding_scene(
    name: &str,
    thermal: &str,
    anvil_speed: f64,
    friction: &str,
    ram_speed: f64,
) -> SolidScene {
    let block = box_scene(
        name,
        [0.004, 0.004, 0.002],
        [5, 5, 3],
        &["x_min"],
        &copper(1.0e9),
        "q4",
    );
    let text = format!(
        r#"{block}{thermal}[time]
end_s = 0.01
mass_scaling = {{ factor = 1.0e4 }}
[[tools]]
name = "anvil"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [1.0, 0.0, 0.0]
motion = {{ kind = "constant", velocity_m_per_s = {anvil_speed:e} }}
friction = {friction}
[[tools]]
name = "ram"
point_m = [0.0, 0.0, 0.002]
normal = [0.0, 0.0, -1.0]
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "constant", velocity_m_per_s = {ram_speed:e} }}
"#
    );
    SolidScene::from_str_named(&text, &format!("{name}.toml")).unwrap()
}

/// The box of [`sliding_scene`] pressed by the ram coming down at 0.2 mm/s onto the anvil
/// sliding under it at 10 mm/s with Coulomb friction `mu` = 0.2; the face x = 0 held on a
/// symmetry plane, so the box stays and slides on the anvil all the time. `[thermal]` at 20
/// C with the conductivity `k` (W/(m K); 0: the heat stays where friction made it) and
/// `friction_heat_to_workpiece` = 0.5; mass scaled by 1e4 (quasi-static: the box's transit
/// time 5e-5 s against the run's 10 ms).
fn sliding_box(k: f64) -> SolidScene {
    let thermal = format!(
        r#"[thermal]
initial_temperature_c = 20.0
specific_heat_j_per_kg_k = 385.0
conductivity_w_per_m_k = {k}
friction_heat_to_workpiece = 0.5
"#
    );
    sliding_scene("slide3d", &thermal, 0.01, "0.2", 2.0e-4)
}

/// The friction heat made so far (J): what the heat stages took in plus the work booked at
/// the particles since the last one.
fn friction_heat_made(sim: &SolidSimulation) -> f64 {
    let heat = sim.state().heat.as_ref().unwrap();
    heat.friction_heat_j + heat.friction_work.iter().sum::<f64>()
}

/// Friction heat in 3D: the box of [`sliding_box`] slides on the anvil under the ram's
/// load. The heat friction made equals the work of Coulomb friction, `sum mu N (v_anvil -
/// v_x) dt` over the steps (`N` the anvil's normal force, `v_x` the mean x velocity of the
/// particles on the anvil), within 0.2 % (measured -0.02 %: the box's own shear as the
/// load rises); the workpiece holds its share `friction_heat_to_workpiece` = 0.5 of what
/// the heat stages took in (the heat balance to round-off, 2e-14), the tools the rest.
/// Without conduction (`k` = 0, the heat stage still runs for friction, as in 2D) the
/// mechanics and the friction work are the same bits, and the heat stays in the layer that
/// slides: the points of the bottom cells warmer than those of the top ones (+0.089 K
/// against +0.002 K).
#[test]
fn friction_heat_is_the_work_of_coulomb_friction() {
    let mu = 0.2;
    let scene = sliding_box(400.0);
    assert_eq!(scene.validate(), vec![]);
    let mut sim = SolidSimulation::new(&scene).unwrap();
    let bottom: Vec<usize> = (0..sim.particle_count())
        .filter(|&j| sim.reference_positions()[j][2] < 1e-9)
        .collect();
    let mut expected = 0.0;
    while sim.time() < scene.time.end_s * (1.0 - 1e-12) {
        let t0 = sim.time();
        sim.step(Some(scene.time.end_s - t0)).unwrap();
        let dt = sim.time() - t0;
        let v = sim.velocities();
        let vx = bottom.iter().map(|&j| v[j][0]).sum::<f64>() / bottom.len() as f64;
        let anvil = &sim.tools()[0];
        expected += mu * anvil.state.normal_force.abs() * (anvil.state.velocity - vx) * dt;
    }
    let made = friction_heat_made(&sim);
    let v = sim.thermal_values().unwrap();
    let names: Vec<&str> = rkforge_core::THERMAL_MEASURES.iter().map(|m| m.0).collect();
    let at = |name: &str| v[names.iter().position(|n| *n == name).unwrap()];
    let load = sim.tools()[0].state.normal_force.abs();
    println!(
        "friction heat {made:.6e} J against mu N slip {expected:.6e} J ({:+.3} %), load at the end {load:.1} N; taken in {:.6e} J, content {:.6e} J, balance {:.1e}",
        100.0 * (made / expected - 1.0),
        at("friction_heat_J"),
        at("heat_content_J"),
        heat_balance(v)
    );
    assert!(load > 1000.0, "load {load} N");
    assert!(
        (made / expected - 1.0).abs() < 0.002,
        "{made} J against {expected} J"
    );
    assert!(at("friction_heat_J") > 0.5 * made);
    assert!(
        heat_balance(v).abs() < 1e-9,
        "balance {:e}",
        heat_balance(v)
    );
    assert!((at("heat_content_J") / (0.5 * at("friction_heat_J")) - 1.0).abs() < 1e-9);
    assert_eq!(at("heat_to_tools_J"), 0.0);
    // Without conduction.
    let mut still = SolidSimulation::new(&sliding_box(0.0)).unwrap();
    still
        .run_toward(scene.time.end_s, u64::MAX, |_, _| true)
        .unwrap();
    assert_eq!(still.positions(), sim.positions());
    let made_still = friction_heat_made(&still);
    assert!((made_still / made - 1.0).abs() < 1e-12, "{made_still} J");
    let t = still.point_temperature().unwrap();
    let z = still.point_positions();
    let mean = |low: bool| {
        let sel: Vec<f64> = (0..t.len())
            .filter(|&p| (z[p][2] < 0.001) == low)
            .map(|p| t[p])
            .collect();
        sel.iter().sum::<f64>() / sel.len() as f64
    };
    let (low, high) = (mean(true), mean(false));
    println!("without conduction: bottom cells {low:.4} C, top cells {high:.4} C");
    assert!(low - 20.0 > 3.0 * (high - 20.0).abs(), "{low} C, {high} C");
    let w = still.thermal_values().unwrap();
    assert!(heat_balance(w).abs() < 1e-9);
}

/// A 2 x 2 x 5 mm copper box (3 x 3 x 6 particles, q4, elastic: yield 1 GPa), the faces x,
/// y, z = 0 on symmetry planes, at 20 C in air at 120 C (convection 1e5 W/(m^2 K),
/// conductivity 400 W/(m K)), with `thermal` lines added to `[thermal]` and `tools` after
/// `[time]`; run for 0.4 s (14 time constants of the lumped body) with the mass scaled by
/// 1e4 (the period of the box's slowest mode 0.5 ms against the heating's 30 ms). Nothing
/// damps the elastic body: the heat stages' steps leave it ringing about its quasi-static
/// state by about 1 % of the thermal strain along z, so the box is read as the mean over
/// the last 50 ms (some hundred periods), step by step weighted by the step: the particles'
/// extents (m) and the points' Jacobians and Mises stresses (Pa). The 2D tests' block
/// (`core/tests/thermoelastic.rs`) in 3D.
fn heated_box(thermal: &str, tools: &str) -> (SolidSimulation, HeatedBox) {
    let block = box_scene(
        "thermoelastic3d",
        [0.002, 0.002, 0.005],
        [3, 3, 6],
        &["x_min", "y_min", "z_min"],
        &copper(1.0e9),
        "q4",
    );
    let text = format!(
        r#"{block}[thermal]
initial_temperature_c = 20.0
specific_heat_j_per_kg_k = 385.0
conductivity_w_per_m_k = 400.0
ambient_temperature_c = 120.0
convection_w_per_m2_k = 1.0e5
{thermal}
[time]
end_s = 0.4
mass_scaling = {{ factor = 1.0e4 }}
{tools}
"#
    );
    let scene = SolidScene::from_str_named(&text, "thermoelastic3d.toml").unwrap();
    assert_eq!(scene.validate(), vec![]);
    let mut sim = SolidSimulation::new(&scene).unwrap();
    let end = scene.time.end_s;
    sim.run_toward(end - 0.05, u64::MAX, |_, _| true).unwrap();
    let npts = sim.point_count();
    let mut mean = HeatedBox {
        extents: [[0.0; 2]; 3],
        jacobian: vec![0.0; npts],
        von_mises: vec![0.0; npts],
    };
    let mut time = 0.0;
    while sim.time() < end * (1.0 - 1e-12) {
        let t0 = sim.time();
        sim.step(Some(end - t0)).unwrap();
        let dt = sim.time() - t0;
        time += dt;
        let r = sim.readings();
        for (m, e) in mean.extents.iter_mut().zip(r.extents) {
            m[0] += dt * e[0];
            m[1] += dt * e[1];
        }
        for (m, j) in mean.jacobian.iter_mut().zip(sim.point_jacobian()) {
            *m += dt * j;
        }
        for (m, q) in mean.von_mises.iter_mut().zip(sim.point_von_mises()) {
            *m += dt * q;
        }
    }
    mean.extents = mean.extents.map(|e| e.map(|x| x / time));
    mean.jacobian.iter_mut().for_each(|j| *j /= time);
    mean.von_mises.iter_mut().for_each(|q| *q /= time);
    let t = sim.point_temperature().unwrap();
    let (lo, hi) = t
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &t| (a.min(t), b.max(t)));
    assert!(lo > 119.95 && hi < 120.05, "{lo:.3}-{hi:.3} C");
    (sim, mean)
}

/// The means [`heated_box`] reads.
struct HeatedBox {
    /// `[min, max]` of x, y and z over the particles (m).
    extents: [[f64; 2]; 3],
    /// Each point's `J = det F` (-).
    jacobian: Vec<f64>,
    /// Each point's Mises stress (Pa).
    von_mises: Vec<f64>,
}

/// Free thermal expansion in 3D, `alpha` = 1.7e-5 /K from 20 to 120 C: the box grows by
/// `lambda_th - 1`, `lambda_th = 1 + 100 alpha`, along each axis within 0.5 % (measured
/// +0.35, +0.35, +0.12 %), the points' Jacobians are `lambda_th^3` within 1e-6 (1.3e-7);
/// the Mises stress, whose mean over the ringing is its amplitude and not zero, stays
/// below 2 % of the held box's (1.6 %); the same with the thermal strain as a table (`[[0,
/// -3.4e-4], [220, 3.4e-3]]`, 1.7e-5 /K from 20 C): the same extents within 1e-9 of the
/// length. The energy account closes with the elastic energy the heating put in.
#[test]
fn a_free_3d_box_grows_by_the_thermal_stretch() {
    let lambda: f64 = 1.0 + 100.0 * 1.7e-5;
    let held = 0.75 * 124.0e9 * lambda.ln() / (1.0 - 0.34);
    let mut extents = Vec::new();
    for thermal in [
        "expansion_per_k = 1.7e-5",
        "thermal_strain_by_temperature = [[0.0, -3.4e-4], [220.0, 3.4e-3]]",
    ] {
        let (sim, r) = heated_box(thermal, "");
        let grow: Vec<f64> = (0..3)
            .map(|k| (r.extents[k][1] - r.extents[k][0]) / [0.002, 0.002, 0.005][k] - 1.0)
            .collect();
        let worst = r
            .jacobian
            .iter()
            .map(|j| (j / lambda.powi(3) - 1.0).abs())
            .fold(0.0f64, f64::max);
        let largest = r.von_mises.iter().fold(0.0f64, |a, &b| a.max(b));
        let e = sim.energy();
        println!(
            "{thermal}: growth {grow:.6?} against {:.6e}; J worst {worst:.2e}; largest stress {largest:.3e} Pa; energy error {:.2e} J, put in by temperature {:.3e} J",
            lambda - 1.0,
            e.balance_error(),
            e.thermoelastic
        );
        for g in &grow {
            assert!((g / (lambda - 1.0) - 1.0).abs() < 0.005, "growth {g:e}");
        }
        assert!(worst < 1e-6, "J {worst:e} off");
        assert!(largest < 0.02 * held, "stress {largest:.3e} Pa");
        assert!(e.balance_error().abs() < 1e-3 * e.thermoelastic.abs());
        extents.push(r.extents);
    }
    for (a, b) in extents[0].iter().zip(&extents[1]) {
        assert!((a[1] - b[1]).abs() < 1e-9 * 0.005);
    }
}

/// Held at x = 2 mm and y = 2 mm by fixed frictionless planes without separation at 120 C
/// (1e5 W/(m^2 K), as the air; the faces x, y = 0 on symmetry planes), heated from 20 to 120 C with `alpha` 1.7e-5 /K and
/// the modulus halving from 20 to 220 C (`[[20, 1], [220, 0.5]]`, so E(120) = 0.75 E): the
/// Mises stress is the biaxial `|sigma| = E(T) ln(lambda_th) / ((1 - nu) J)` (Cauchy, `J`
/// each point's), as the 2D plane-strain block's (`core/tests/thermoelastic.rs`, held in y
/// and out of plane): its volume mean within 1 % (measured -0.83 %; 2D's within 0.2 %) and
/// every point within 8 % (6.5 %, the points at the held planes' edges: the planes hold by
/// penalty, as the 3D symmetry planes do, where 2D's block has exact constraints); the
/// energy account closes with the elastic energy the heating put in.
#[test]
fn a_held_3d_box_takes_the_thermal_stress_at_its_modulus() {
    let tools = r#"
[[tools]]
name = "wall_x"
point_m = [0.002, 0.0, 0.0]
normal = [-1.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
motion = { kind = "fixed" }
separation = false
temperature_c = 120.0
heat_transfer_w_per_m2_k = 1.0e5
[[tools]]
name = "wall_y"
point_m = [0.0, 0.002, 0.0]
normal = [0.0, -1.0, 0.0]
axis = [0.0, 1.0, 0.0]
motion = { kind = "fixed" }
separation = false
temperature_c = 120.0
heat_transfer_w_per_m2_k = 1.0e5
"#;
    let (sim, r) = heated_box(
        "expansion_per_k = 1.7e-5\nmodulus_factor_by_temperature = [[20.0, 1.0], [220.0, 0.5]]",
        tools,
    );
    let lambda: f64 = 1.0 + 100.0 * 1.7e-5;
    let (q, j, w) = (&r.von_mises, &r.jacobian, sim.point_weights());
    let target = |j: f64| 0.75 * 124.0e9 * lambda.ln() / ((1.0 - 0.34) * j);
    let mut sum = [0.0; 2];
    let mut worst: f64 = 0.0;
    for p in 0..q.len() {
        sum[0] += w[p] * q[p];
        sum[1] += w[p] * target(j[p]);
        worst = worst.max((q[p] / target(j[p]) - 1.0).abs());
    }
    let mean = sum[0] / sum[1] - 1.0;
    let e = sim.energy();
    println!(
        "held: mean Mises {:.5e} Pa against {:.5e} Pa ({:+.3} %), worst point {:.2} %; energy error {:.2e} J of elastic {:.3e} J (put in by temperature {:.3e} J)",
        sum[0] / w.iter().sum::<f64>(),
        sum[1] / w.iter().sum::<f64>(),
        100.0 * mean,
        100.0 * worst,
        e.balance_error(),
        e.elastic,
        e.thermoelastic
    );
    assert!(mean.abs() < 0.01, "mean {mean:e}");
    assert!(worst < 0.08, "worst {worst:e}");
    assert!(
        e.balance_error().abs() < 0.01 * e.elastic,
        "energy error {:e}",
        e.balance_error()
    );
}

/// The scene texts of a copper cylinder (radius 5 mm, length 10 mm, linear hardening from 60
/// MPa by 300 MPa, q4, the mass scaled by 1e4) upset for `end_s` (s) between a fixed anvil and
/// a ram coming down at 0.1 m/s, both with the friction `friction` (a scene value), with the
/// `[thermal]` section `thermal` (or none): the 3D quarter model `{name}3d` on the O-grid
/// `cells` and the axisymmetric scene `{name}2d` on `particles` (r, z).
fn upset_texts(
    name: &str,
    cells: [usize; 3],
    particles: [usize; 2],
    thermal: &str,
    end_s: f64,
    friction: &str,
) -> [String; 2] {
    let common = format!(
        r#"
[material]
density_kg_per_m3 = 8960.0
youngs_modulus_pa = 124.0e9
poisson_ratio = 0.34
hardening = {{ law = "linear", yield_stress_pa = 60.0e6, modulus_pa = 300.0e6 }}
[discretization]
integration = "q4"
{thermal}[time]
end_s = {end_s}
mass_scaling = {{ factor = 1.0e4 }}
"#
    );
    let text3 = format!(
        r#"
name = "{name}3d"
[model]
kinematics = "3d"
[workpiece]
shape = "cylinder"
radius_m = 0.005
length_m = 0.01
part = "quarter"
cells = [{}, {}, {}]
{common}
[[tools]]
name = "anvil"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "fixed" }}
friction = {friction}
[[tools]]
name = "ram"
point_m = [0.0, 0.0, 0.01]
normal = [0.0, 0.0, -1.0]
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "constant", velocity_m_per_s = 0.1 }}
friction = {friction}
"#,
        cells[0], cells[1], cells[2]
    );
    let text2 = format!(
        r#"
name = "{name}2d"
[model]
kinematics = "axisymmetric"
[workpiece]
origin_m = [0.0, 0.0]
size_m = [0.005, 0.01]
particles = [{}, {}]
{common}
[[tools]]
name = "anvil"
points_m = [[-0.002, 0.0], [0.02, 0.0]]
axis = [0.0, -1.0]
motion = {{ kind = "fixed" }}
friction = {friction}
[[tools]]
name = "ram"
points_m = [[0.02, 0.01], [-0.002, 0.01]]
axis = [0.0, -1.0]
motion = {{ kind = "constant", velocity_m_per_s = 0.1 }}
friction = {friction}
"#,
        particles[0], particles[1]
    );
    [text3, text2]
}

/// A copper cylinder (radius 5 mm, length 10 mm, linear hardening from 60 MPa, at 20 C with
/// conductivity 400 W/(m K), no heat to the dies or the air) upset by 2 mm in 20 ms between
/// flat dies with Coulomb friction `mu` = 0.2, the mass scaled by 1e4: as a 3D quarter
/// model on the O-grid `cells` and as the axisymmetric 2D scene on `particles` (r, z);
/// returns the friction heat made and the plastic heat (J) of the whole cylinder of each.
fn frictional_upset(cells: [usize; 3], particles: [usize; 2]) -> [[f64; 2]; 2] {
    let thermal = r#"[thermal]
initial_temperature_c = 20.0
specific_heat_j_per_kg_k = 385.0
conductivity_w_per_m_k = 400.0
taylor_quinney = 0.9
"#;
    let [text3, text2] = upset_texts("friction_upset", cells, particles, thermal, 0.02, "0.2");
    let scene3 = SolidScene::from_str_named(&text3, "friction_upset3d.toml").unwrap();
    let mut sim3 = SolidSimulation::new(&scene3).unwrap();
    sim3.run_toward(0.02, u64::MAX, |_, _| true).unwrap();
    let v3 = sim3.thermal_values().unwrap();
    assert!(
        heat_balance(v3).abs() < 1e-9,
        "3D balance {:e}",
        heat_balance(v3)
    );
    let scene2 = rkforge_core::Scene::from_str_named(&text2, "friction_upset2d.toml").unwrap();
    let mut sim2 = rkforge_core::Simulation::new(&scene2).unwrap();
    sim2.run_to(0.02, |_| {}).unwrap();
    let v2 = sim2.thermal_values().unwrap();
    assert!(
        heat_balance(v2).abs() < 1e-9,
        "2D balance {:e}",
        heat_balance(v2)
    );
    let h2 = sim2.state().heat.as_ref().unwrap();
    let made2 = h2.friction_heat_j + h2.friction_work.iter().sum::<f64>();
    // The quarter's heat four times.
    [
        [4.0 * friction_heat_made(&sim3), 4.0 * v3[3]],
        [made2, v2[3]],
    ]
}

/// Friction heat of a 3D quarter-model upset against the axisymmetric 2D run of the same
/// scene ([`frictional_upset`]), the quarter's four times, on two pairs of grids of about
/// the same spacing along the axis: the 3D O-grid [2, 2, 8] against 2D's 5 x 9 particles
/// (1.25 mm), [6, 4, 24] against 13 x 25 (0.42 mm). Both fall as the grids refine (3D
/// 0.934, 0.748, 0.714, 0.690 J and 2D 1.039, 0.827, 0.762, 0.733 J on [2, 2, 8], [4, 3,
/// 16], [6, 4, 24], [8, 6, 32] against 5 x 9, 9 x 17, 13 x 25, 17 x 33), the 3D run below
/// the 2D one by 10.2, 9.5, 6.4 and 5.9 %: within 11 % on the coarse pair and 7 % on the
/// finer, the gap narrowing. Friction heat is the slip at the die faces times their
/// pressure, which the O-grid's and the lattice's surface particles resolve differently;
/// the plastic heat, a volume figure, agrees within 0.5 % and 0.1 % (-0.43, -0.06 %).
#[test]
fn friction_heat_of_a_3d_upset_against_the_axisymmetric_run() {
    let mut gaps = Vec::new();
    for (cells, particles, tol) in [([2, 2, 8], [5, 9], 0.11), ([6, 4, 24], [13, 25], 0.07)] {
        let [[f3, p3], [f2, p2]] = frictional_upset(cells, particles);
        println!(
            "3D {cells:?} / 2D {particles:?}: friction heat {f3:.5} J against {f2:.5} J ({:+.2} %), plastic heat {p3:.4} J against {p2:.4} J ({:+.2} %)",
            100.0 * (f3 / f2 - 1.0),
            100.0 * (p3 / p2 - 1.0)
        );
        assert!(
            f2 > 0.0 && (f3 / f2 - 1.0).abs() < tol,
            "{f3} J against {f2} J"
        );
        assert!((p3 / p2 - 1.0).abs() < 0.05 * tol, "{p3} J against {p2} J");
        gaps.push((f3 / f2 - 1.0).abs());
    }
    assert!(gaps[1] < gaps[0], "{gaps:?}");
}

/// A modulus that rises as the body cools in 3D (six times stiffer at 20 C than at 500 C,
/// the table `[[20, 6], [500, 1]]`, 2D's `a_body_that_stiffens_as_it_cools_stays_stable`):
/// a 4 x 4 x 4 mm copper box (5 x 5 x 5 particles, q4, elastic) at 500 C held on a die at 20
/// C (1e5 W/(m^2 K), no separation) cools to below 100 C in 0.5 s; the explicit step,
/// measured at 500 C, is `sqrt(f(500) / f_max)` = `1 / sqrt 6` of the step the same box
/// measures without the table's stiffening, so that it holds for the stiffest temperature,
/// and the run ends with its energy account closed.
#[test]
fn a_3d_body_that_stiffens_as_it_cools_stays_stable() {
    let die = r#"
[[tools]]
name = "die"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, 1.0]
motion = { kind = "fixed" }
separation = false
temperature_c = 20.0
heat_transfer_w_per_m2_k = 1.0e5
"#;
    let box_with = |table: &str| {
        let mut scene = copper_box(
            [0.004; 3],
            [5, 5, 5],
            500.0,
            "q4",
            0.5,
            &format!("modulus_factor_by_temperature = {table}\nexpansion_per_k = 1.7e-5"),
            die,
        );
        scene.material.hardening = rkforge_core::material::Hardening::Linear {
            yield_stress_pa: 1.0e9,
            modulus_pa: 0.0,
        };
        scene.time.mass_scaling = Some(rkforge_core::scene::MassScaling {
            factor: Some(1.0e6),
            target_dt_s: None,
            at_rereferences: None,
        });
        scene
    };
    let flat = SolidSimulation::new(&box_with("[[20.0, 1.0], [500.0, 1.0]]")).unwrap();
    let scene = box_with("[[20.0, 6.0], [500.0, 1.0]]");
    let mut sim = SolidSimulation::new(&scene).unwrap();
    let ratio = sim.critical_dt0() / flat.critical_dt0();
    sim.run_toward(scene.time.end_s, u64::MAX, |_, _| true)
        .unwrap();
    let t = sim.point_temperature().unwrap();
    let hottest = t.iter().fold(f64::MIN, |a, &b| a.max(b));
    let e = sim.energy();
    println!(
        "stiffening 3D: critical step {:.4e} s, {ratio:.6} of the unstiffened (1 / sqrt 6 = {:.6}); hottest point {hottest:.1} C; balance {:.2e} of {:.3e} J",
        sim.critical_dt0(),
        1.0 / 6.0f64.sqrt(),
        e.balance_error(),
        e.thermoelastic_abs
    );
    assert!((ratio * 6.0f64.sqrt() - 1.0).abs() < 1e-9, "{ratio}");
    assert!(hottest < 100.0, "{hottest:.1} C");
    assert!(e.balance_error().abs() < 1e-3 * e.thermoelastic_abs);
}

/// The box of [`sliding_box`] without `[thermal]`, the anvil sliding at 100 mm/s with the
/// friction `friction` (a scene value), the ram coming down at 1 mm/s.
fn sliding_box_with(friction: &str) -> SolidScene {
    sliding_scene("slide3d_shear", "", 0.1, friction, 1.0e-3)
}

/// The largest relative departure of the friction stress from `m k` (-) over the second
/// half of the run of [`sliding_box_with`] with `friction`, `k` = 1 GPa / sqrt 3: the
/// anvil's force along its motion over the area of the box's bottom face (the extents of
/// its particles' physical positions), at each step; and the steps read.
fn friction_stress_departure(friction: &str, m: f64) -> (f64, usize) {
    let k = 1.0e9 / 3.0_f64.sqrt();
    let scene = sliding_box_with(friction);
    assert_eq!(scene.validate(), vec![]);
    let mut sim = SolidSimulation::new(&scene).unwrap();
    let bottom: Vec<usize> = (0..sim.particle_count())
        .filter(|&j| sim.reference_positions()[j][2] < 1e-9)
        .collect();
    let (mut worst, mut samples): (f64, usize) = (0.0, 0);
    while sim.time() < scene.time.end_s * (1.0 - 1e-12) {
        let t0 = sim.time();
        sim.step(Some(scene.time.end_s - t0)).unwrap();
        if sim.time() < 0.5 * scene.time.end_s {
            continue;
        }
        let x = sim.positions();
        let extent = |a: usize| {
            let (lo, hi) = bottom.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &j| {
                (lo.min(x[j][a]), hi.max(x[j][a]))
            });
            hi - lo
        };
        let tau = sim.tools()[0].axial_force().abs() / (extent(0) * extent(1));
        worst = worst.max((tau / (m * k) - 1.0).abs());
        samples += 1;
    }
    (worst, samples)
}

/// Shear friction in 3D: the box of [`sliding_box_with`] (elastic, flow stress 1 GPa) held
/// on its symmetry plane x = 0 while the anvil slides under it at 100 mm/s, the ram
/// pressing it to about 600 MPa. Every particle on the anvil slides, so with the shear
/// friction factor m = 0.1 the friction stress is `m k`, `k = sigma_y / sqrt 3` (Wanheim
/// and Bay 1978), within 0.1 % at every step of the second half (measured 5.4e-4 and, capped, 1.5e-4: the
/// particles' slip is not quite along x, the bottom face spreading under the load; the
/// contact areas are the bottom face's quarters, which tile it). The capped law `min(mu p,
/// m k)` with `mu` = 0.5, m = 0.1 is capped there (`mu p` above 150 MPa against `m k` = 58
/// MPa): `m k` within 0.1 % as well; with `mu` = 0.2, m = 0.5 it is Coulomb's (`m k` =
/// 289 MPa above `mu p` throughout): the same bits as `friction = 0.2`. A box lighter
/// loaded (the ram at 0.2 mm/s, 100 MPa) tips under the friction's moment, its trailing
/// edge leaving the anvil, and a slower anvil lets its elastic ringing stick and slip: the
/// friction stress then falls short of `m k` by the area off the anvil.
#[test]
fn a_3d_box_sliding_under_shear_friction_carries_m_k() {
    for (friction, m) in [
        ("{ model = \"shear\", m = 0.1 }", 0.1),
        ("{ model = \"capped\", mu = 0.5, m = 0.1 }", 0.1),
    ] {
        let (worst, samples) = friction_stress_departure(friction, m);
        println!("{friction}: friction stress within {worst:.2e} of m k over {samples} steps");
        assert!(samples > 10 && worst < 1e-3, "{friction}: {worst}");
    }
    let mut capped = SolidSimulation::new(&sliding_box_with(
        "{ model = \"capped\", mu = 0.2, m = 0.5 }",
    ))
    .unwrap();
    let mut coulomb = SolidSimulation::new(&sliding_box_with("0.2")).unwrap();
    for s in [&mut capped, &mut coulomb] {
        s.run_toward(0.01, u64::MAX, |_, _| true).unwrap();
    }
    assert_eq!(capped.positions(), coulomb.positions());
    assert_eq!(
        capped.tools()[0].state.force,
        coulomb.tools()[0].state.force
    );
}

/// The ram's force (N, pressing positive; the 3D quarter's four times) of the copper
/// cylinder of [`frictional_upset`] without `[thermal]` (radius 5 mm, length 10 mm, yield
/// 60 MPa hardening by 300 MPa, q4, mass scaled by 1e4) upset by 4 mm at 0.1 m/s between
/// dies with the friction `friction` (a scene value): the 3D quarter model on the O-grid `cells`
/// and the axisymmetric run on `particles`, each the mean over the steps of each 0.5 mm of
/// stroke (the mass-scaled body rings about its quasi-static answer), eight means.
fn shear_upset(cells: [usize; 3], particles: [usize; 2], friction: &str) -> [Vec<f64>; 2] {
    let [text3, text2] = upset_texts("shear_upset", cells, particles, "", 0.04, friction);
    let windows = 8;
    let window = 0.04 / windows as f64;
    let mean = |sums: &[[f64; 2]]| sums.iter().map(|s| s[0] / s[1]).collect::<Vec<f64>>();
    let scene3 = SolidScene::from_str_named(&text3, "shear_upset3d.toml").unwrap();
    assert_eq!(scene3.validate(), vec![]);
    let mut sim3 = SolidSimulation::new(&scene3).unwrap();
    let mut sums3 = vec![[0.0; 2]; windows];
    while sim3.time() < 0.04 * (1.0 - 1e-12) {
        let t0 = sim3.time();
        sim3.step(Some(0.04 - t0)).unwrap();
        let w = ((t0 / window) as usize).min(windows - 1);
        let dt = sim3.time() - t0;
        sums3[w][0] += -4.0 * sim3.tools()[1].axial_force() * dt;
        sums3[w][1] += dt;
    }
    let scene2 = rkforge_core::Scene::from_str_named(&text2, "shear_upset2d.toml").unwrap();
    let mut sim2 = rkforge_core::Simulation::new(&scene2).unwrap();
    let mut sums2 = vec![[0.0; 2]; windows];
    while sim2.time() < 0.04 * (1.0 - 1e-12) {
        let t0 = sim2.time();
        sim2.step(Some(0.04 - t0)).unwrap();
        let w = ((t0 / window) as usize).min(windows - 1);
        let dt = sim2.time() - t0;
        sums2[w][0] += -sim2.tools()[1].axial_force() * dt;
        sums2[w][1] += dt;
    }
    [mean(&sums3), mean(&sums2)]
}

/// Shear friction of a 3D quarter-model upset against the axisymmetric 2D run of the same
/// scene ([`shear_upset`]) with m = 0.3: the force-stroke, as the mean force over each 0.5
/// mm of the 4 mm stroke, within 3 % in every one (measured -0.38 to -1.07 %, the 3D run
/// below), the O-grid [4, 3, 16] against 2D's 9 x 17 particles (0.625 mm along the axis in
/// both). The friction's share, the rise over the same runs frictionless (the friction
/// hill; 9.0 % of the 2D force at the last 0.5 mm), agrees within 15 % of itself there
/// (measured 2230 N against 2503 N, -10.9 %: the difference of two forces each within
/// 1 %; the friction heat of the Coulomb upset, `friction_heat_of_a_3d_upset_against_the_
/// axisymmetric_run`, falls short of 2D's by as much on the coarse grids).
#[test]
fn a_3d_upset_under_shear_friction_against_the_axisymmetric_run() {
    let shear = "{ model = \"shear\", m = 0.3 }";
    let [f3, f2] = shear_upset([4, 3, 16], [9, 17], shear);
    let mut worst: f64 = 0.0;
    for (w, (a, b)) in f3.iter().zip(&f2).enumerate() {
        println!(
            "stroke {:.1}-{:.1} mm: 3D {a:.1} N, 2D {b:.1} N ({:+.2} %)",
            0.5 * w as f64,
            0.5 * (w + 1) as f64,
            100.0 * (a / b - 1.0)
        );
        worst = worst.max((a / b - 1.0).abs());
    }
    assert!(worst < 0.03, "{worst}");
    let [g3, g2] = shear_upset([4, 3, 16], [9, 17], "0.0");
    let last = f3.len() - 1;
    let (rise3, rise2) = (f3[last] - g3[last], f2[last] - g2[last]);
    println!(
        "friction's share at the end: 3D {rise3:.1} N, 2D {rise2:.1} N ({:+.2} %; {:.1} % of the 2D force)",
        100.0 * (rise3 / rise2 - 1.0),
        100.0 * rise2 / f2[last]
    );
    assert!(rise2 > 0.05 * f2[last], "{rise2} N");
    assert!(
        (rise3 / rise2 - 1.0).abs() < 0.15,
        "{rise3} N against {rise2} N"
    );
}

/// The shipped rectangular block (`scenes/block_upsetting_3d.toml`, 7 x 5 x 9 particles)
/// pressed 10 mm of its 20 mm with `rule`: the saw-tooth of its end face `x = 30 mm`, the
/// alternating part of each column's second difference along z,
/// `|sum_k (-1)^k (x_k - (x_(k-1) + x_(k+1)) / 2)| / (n_z - 2)` in spacings, the largest over
/// the face's columns (a smooth bulge adds next to nothing to it), and the ram's force (N).
fn block_with(rule: IntegrationRule, stabilization: Option<f64>) -> (f64, f64) {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/block_upsetting_3d.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut scene = SolidScene::from_str_named(&text, "block_upsetting_3d.toml").unwrap();
    scene.discretization.integration = rule;
    scene.discretization.scni_stabilization = stabilization;
    scene.time.end_s = 0.5;
    let mut sim = SolidSimulation::new(&scene).unwrap();
    sim.run_toward(0.5, u64::MAX, |_, _| true).unwrap();
    let (nx, ny, nz, h) = (7, 5, 9, 0.005);
    let x = sim.positions();
    let at = |j: usize, k: usize| x[nx - 1 + nx * (j + ny * k)][0];
    let mut saw: f64 = 0.0;
    for j in 0..ny {
        let alternating: f64 = (1..nz - 1)
            .map(|k| {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                sign * (at(j, k) - 0.5 * (at(j, k - 1) + at(j, k + 1)))
            })
            .sum();
        saw = saw.max(alternating.abs() / h / (nz - 2) as f64);
    }
    (saw, -sim.tools()[1].axial_force())
}

/// Plain SCNI on the 3D block lets the free faces take a saw-tooth (the pictures of the
/// whole stroke show it from 5 mm on; the end force is 9 % under q4's); the stabilization
/// over the octants (`discretization.scni_stabilization = 0.03`, as the 2D scenes set)
/// holds them near q4's and the force nearer q4's. Measured at 10 mm: saw-tooth 0.0266
/// (q4), 0.0796 (plain SCNI), 0.0347 (stabilized) spacings; force 356.6, 346.5 (-2.8 %) and
/// 352.8 kN (-1.1 %). Before session 59's landing plan, whose steps are 2 % shorter, plain
/// SCNI's force read 342.4 kN (-4.0 %) and the others as now to 0.1 %: its saw-tooth makes
/// its force depend on the steps.
#[test]
fn stabilized_nodal_integration_holds_the_blocks_free_faces() {
    let (saw_q4, force_q4) = block_with(IntegrationRule::Q4, None);
    let (saw_plain, force_plain) = block_with(IntegrationRule::Scni, None);
    let (saw_held, force_held) = block_with(IntegrationRule::Scni, Some(0.03));
    let report = format!(
        "saw-tooth (spacings) q4 {saw_q4:.4}, scni {saw_plain:.4}, stabilized {saw_held:.4}; \
         force (N) q4 {force_q4:.0}, scni {force_plain:.0}, stabilized {force_held:.0}"
    );
    assert!(saw_plain > 2.5 * saw_q4, "{report}");
    assert!(saw_held < 1.5 * saw_q4, "{report}");
    assert!(
        (force_plain - force_q4).abs() > (force_held - force_q4).abs(),
        "{report}"
    );
    assert!(
        ((force_held - force_q4) / force_q4).abs() < 0.02,
        "{report}"
    );
}

/// Bug: the two tools of a quasi-static upsetting did not balance at the samples. On the
/// shipped hot upsetting in 3D (`scenes/hot_upsetting_3d.toml`, sampled every 10 ms) the
/// ram's and the anvil's forces differed by 1.6 % at every sample, while the die's work
/// and the end state were right: the steps before each sample were cut by up to a half
/// once the natural step had shrunk a little, and the contact force answered that for a
/// few steps, just when the sample was taken. Since session 59 the steps to an instant are
/// planned and kept (`solver/stable_step.rs`, docs/method.md "Steps that land on an
/// instant"): over the first 4 mm (20 samples, from the third on) they balance to 0.01 %
/// (measured); the bound is 0.2 %.
#[test]
fn the_two_tools_of_a_slow_upsetting_balance_at_every_sample() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/hot_upsetting_3d.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let scene = SolidScene::from_str_named(&text, "hot_upsetting_3d.toml").unwrap();
    let every = scene.output.history_interval_s.unwrap();
    assert_eq!(
        (scene.tools[0].name.as_str(), scene.tools[1].name.as_str()),
        ("anvil", "ram")
    );
    let mut sim = SolidSimulation::new(&scene).unwrap();
    let mut worst: f64 = 0.0;
    for k in 1..=20 {
        sim.run_toward(k as f64 * every, u64::MAX, |_, _| true)
            .unwrap();
        let (anvil, ram) = (sim.tools()[0].axial_force(), sim.tools()[1].axial_force());
        if k >= 3 {
            assert!(anvil > 1e3, "sample {k}: the anvil takes {anvil} N");
            worst = worst.max((anvil + ram).abs() / anvil);
        }
    }
    assert!(
        worst < 2e-3,
        "the tools' forces differ by {worst} of the anvil's"
    );
}
