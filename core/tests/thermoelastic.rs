//! Elasticity over temperature: a Young's modulus that falls with temperature
//! (`thermal.modulus_factor_by_temperature`) and thermal expansion (`thermal.expansion_per_k`,
//! `thermal.thermal_strain_by_temperature`), against the closed forms of a block heated to a
//! uniform temperature: free, it grows by the thermal stretch and stays free of stress; held
//! between two planes, it takes the biaxial stress `sigma = -E(T) ln(lambda_th) / (1 - nu)`.
//! The block is heated through its free sides by convection from air at the target
//! temperature, with a conductivity high enough that it heats nearly uniformly; its
//! constrained edges are adiabatic (symmetry planes).

use rkforge_core::{Scene, Simulation};

/// A copper block 4 x 10 mm (9 x 21 particles, q4, elastic: yield 1 GPa) at 20 C in air at
/// 120 C (convection 1e5 W/(m^2 K), conductivity 400 W/(m K)), its bottom edge held in y;
/// when `held`, its top edge too and in plane strain, else a free cylinder of radius 4 mm
/// (axisymmetric); `thermal` lines added to its `[thermal]` section; run for 0.8 s with the
/// mass scaled by 1e4 (the mechanical transit time 0.1 ms against a thermal one of 0.07 s:
/// quasi-static, the ringing of the sudden heating below 0.5 %).
fn block(thermal: &str, held: bool) -> Scene {
    let kinematics = if held { "plane_strain" } else { "axisymmetric" };
    let top = if held {
        "[[constraints]]\nedge = \"y_max\"\nfix = [\"y\"]\n"
    } else {
        ""
    };
    let text = format!(
        r#"
name = "thermoelastic"
[model]
kinematics = "{kinematics}"
[workpiece]
origin_m = [0.0, 0.0]
size_m = [0.004, 0.01]
particles = [9, 21]
[material]
density_kg_per_m3 = 8960.0
youngs_modulus_pa = 124.0e9
poisson_ratio = 0.34
hardening = {{ law = "linear", yield_stress_pa = 1.0e9, modulus_pa = 0.0 }}
[discretization]
integration = "q4"
[thermal]
initial_temperature_c = 20.0
specific_heat_j_per_kg_k = 385.0
conductivity_w_per_m_k = 400.0
ambient_temperature_c = 120.0
convection_w_per_m2_k = 1.0e5
{thermal}
[time]
end_s = 0.8
mass_scaling = {{ factor = 1.0e4 }}
[[constraints]]
edge = "y_min"
fix = ["y"]
{top}
"#
    );
    Scene::from_str_named(&text, "thermoelastic.toml").unwrap()
}

/// Runs `scene` to its end; returns the simulation, checking that the block reached 120 C
/// within 0.05 K everywhere and that the energy account closes with the elastic energy the
/// heating put in (`Energy::thermoelastic`): its error below 1 % of the stored elastic energy
/// (when any is stored) and of the kinetic energy's scale.
fn heated(scene: &Scene) -> Simulation {
    let mut sim = Simulation::new(scene).unwrap();
    sim.run_to(scene.time.end_s, |_| {}).unwrap();
    let t = sim.temperatures().unwrap();
    assert!(
        t.min_c > 119.95 && t.max_c < 120.05,
        "{:.3}-{:.3} C",
        t.min_c,
        t.max_c
    );
    sim
}

/// Free expansion with a constant coefficient, alpha = 1.7e-5 /K: the cylinder's top and
/// side move out by `lambda_th - 1`, `lambda_th = 1 + 100 alpha`, of its height and radius
/// within 0.5 %, the points' Jacobians are `lambda_th^3` within 1e-5, and the stress stays
/// below 0.5 % of the held block's.
#[test]
fn a_free_block_grows_by_the_thermal_stretch() {
    let scene = block("expansion_per_k = 1.7e-5", false);
    let sim = heated(&scene);
    let lambda: f64 = 1.0 + 100.0 * 1.7e-5;
    // The particles' physical positions: the cylinder's top and side.
    let x = sim.positions();
    let (top, side) = (
        x.iter().map(|p| p[1]).fold(f64::MIN, f64::max),
        x.iter().map(|p| p[0]).fold(f64::MIN, f64::max),
    );
    let (rise, widen) = (top / 0.01 - 1.0, side / 0.004 - 1.0);
    eprintln!(
        "free: rise {rise:.6e}, widening {widen:.6e}, against {:.6e}",
        lambda - 1.0
    );
    assert!((rise / (lambda - 1.0) - 1.0).abs() < 0.005, "rise {rise:e}");
    assert!(
        (widen / (lambda - 1.0) - 1.0).abs() < 0.005,
        "widening {widen:e}"
    );
    let j = sim.point_jacobian();
    let worst = j
        .iter()
        .map(|j| (j / lambda.powi(3) - 1.0).abs())
        .fold(0.0f64, f64::max);
    eprintln!("free: J worst {worst:.2e}");
    assert!(worst < 1e-5, "J {worst:e} off");
    let held = 0.75 * 124.0e9 * lambda.ln() / (1.0 - 0.34);
    let q = sim.point_von_mises();
    let largest = q.iter().fold(0.0f64, |a, &b| a.max(b));
    eprintln!("free: largest stress {largest:.3e} Pa");
    assert!(largest < 0.005 * held, "stress {largest:.3e} Pa");
}

/// Held between two planes (y and the plane-strain thickness), heated from 20 to 120 C with
/// `alpha` 1.7e-5 /K and the modulus halving from 20 to 220 C (the table `[[20, 1], [220,
/// 0.5]]`, so E(120) = 0.75 E): the Mises stress is the biaxial `|sigma| = E(T)
/// ln(lambda_th) / ((1 - nu) J)` (Cauchy; `J` the free width's stretch), its volume mean
/// within 0.2 % and every point within 1 % (q4 does not pass the patch test exactly: the
/// points by the held edges' corners deviate most), and
/// the energy account, with the elastic energy the heating put in, closes to 1e-5 of the
/// elastic energy stored. The same with the thermal strain as a table (`[[0, -3.4e-4], [220,
/// 3.4e-3]]`, 1.7e-5 /K from 20 C): the same stresses within 1e-9.
#[test]
fn a_held_block_takes_the_thermal_stress_at_its_modulus() {
    let factor = "modulus_factor_by_temperature = [[20.0, 1.0], [220.0, 0.5]]";
    let scene = block(&format!("expansion_per_k = 1.7e-5\n{factor}"), true);
    let sim = heated(&scene);
    let (e, nu) = (0.75 * 124.0e9, 0.34);
    let ln_l = (1.0f64 + 100.0 * 1.7e-5).ln();
    // The free width: sigma_xx = 0 with eps_yy = eps_zz = 0 gives eps_xx = ln_l (1 + nu) /
    // (1 - nu) (Lame: (3 lam + 2 mu) / (lam + 2 mu)).
    let j = (ln_l * (1.0 + nu) / (1.0 - nu)).exp();
    let expected = e * ln_l / ((1.0 - nu) * j);
    let q = sim.point_von_mises();
    let worst = q
        .iter()
        .map(|&q| (q / expected - 1.0).abs())
        .fold(0.0f64, f64::max);
    let w = sim.point_weights();
    let mean = q.iter().zip(w).map(|(q, w)| q * w).sum::<f64>() / w.iter().sum::<f64>();
    eprintln!(
        "held: mean stress {mean:.4e} Pa against {expected:.4e} ({:.2e}), worst point {worst:.2e}",
        mean / expected - 1.0
    );
    assert!((mean / expected - 1.0).abs() < 0.002, "mean {mean:.4e} Pa");
    assert!(worst < 0.01, "worst point {:.3} % off", 100.0 * worst);
    let energy = sim.energy();
    eprintln!(
        "held: elastic {:.4e} J, thermoelastic {:.4e} J, balance error {:.3e} J",
        energy.elastic,
        energy.thermoelastic,
        energy.balance_error()
    );
    assert!(energy.balance_error().abs() < 1e-5 * energy.elastic);
    let table = block(
        &format!("thermal_strain_by_temperature = [[0.0, -3.4e-4], [220.0, 3.4e-3]]\n{factor}"),
        true,
    );
    let q_table = heated(&table).point_von_mises();
    for (a, b) in q.iter().zip(&q_table) {
        assert!((a / b - 1.0).abs() < 1e-9, "{a} against {b}");
    }
}

/// A modulus that rises as the body cools (six times stiffer at 20 C than at 500 C, the
/// table `[[20, 6], [500, 1]]`): the block at 500 C on a die at 20 C (1e5 W/(m^2 K)) cools
/// to below 100 C in 0.5 s, and the explicit step, measured at 500 C, is scaled by
/// `sqrt(f(500) / f_max)` so that it holds for the stiffest temperature: the run ends with its
/// energy account closed (at the measured step alone the cold body is unstable at the
/// default `dt_safety` 0.5, as `1 / sqrt(6)` is below it).
#[test]
fn a_body_that_stiffens_as_it_cools_stays_stable() {
    let text = r#"
name = "stiffening"
[model]
kinematics = "plane_strain"
[workpiece]
origin_m = [0.0, 0.0]
size_m = [0.004, 0.004]
particles = [9, 9]
[material]
density_kg_per_m3 = 8960.0
youngs_modulus_pa = 124.0e9
poisson_ratio = 0.34
hardening = { law = "linear", yield_stress_pa = 1.0e9, modulus_pa = 0.0 }
[discretization]
integration = "q4"
[thermal]
initial_temperature_c = 500.0
specific_heat_j_per_kg_k = 385.0
conductivity_w_per_m_k = 400.0
modulus_factor_by_temperature = [[20.0, 6.0], [500.0, 1.0]]
expansion_per_k = 1.7e-5
[time]
end_s = 0.5
mass_scaling = { factor = 1.0e6 }
[[tools]]
name = "die"
points_m = [[-0.004, 0.0], [0.008, 0.0]]
axis = [0.0, 1.0]
motion = { kind = "fixed" }
separation = false
temperature_c = 20.0
heat_transfer_w_per_m2_k = 1.0e5
"#;
    let scene = Scene::from_str_named(text, "stiffening.toml").unwrap();
    let mut sim = Simulation::new(&scene).unwrap();
    let measured = sim.critical_dt0();
    sim.run_to(scene.time.end_s, |_| {}).unwrap();
    let t = sim.temperatures().unwrap();
    let e = sim.energy();
    eprintln!(
        "stiffening: critical step {measured:.3e} s, {:.1}-{:.1} C at the end, balance {:.2e} of {:.3e} J",
        t.min_c,
        t.max_c,
        e.balance_error(),
        e.thermoelastic_abs
    );
    assert!(t.max_c < 100.0, "{:.1} C", t.max_c);
    assert!(e.balance_error().abs() < 1e-3 * e.thermoelastic_abs);
}
