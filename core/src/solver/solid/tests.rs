//! The 3D solver on small scenes.

use super::*;
use crate::scene::solid::SolidScene;
use crate::scene::AtRereference;

/// A coarse quarter Taylor bar (the paper's copper at 227 m/s on the FE wall).
pub(crate) fn quarter_bar(cells: [usize; 3], rule: &str, end_s: Real) -> SolidScene {
    let text = format!(
        r#"
name = "bar3d"
[model]
kinematics = "3d"
[workpiece]
shape = "cylinder"
radius_m = 0.0032
length_m = 0.0324
part = "quarter"
cells = {cells:?}
initial_velocity_m_per_s = [0.0, 0.0, -227.0]
[material]
density_kg_per_m3 = 8930.0
youngs_modulus_pa = 117e9
poisson_ratio = 0.35
hardening = {{ law = "linear", yield_stress_pa = 400e6, modulus_pa = 100e6 }}
[discretization]
integration = "{rule}"
[time]
end_s = {end_s:e}
dt_s = 5e-9
[[tools]]
name = "wall"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "fixed" }}
separation = false
"#
    );
    SolidScene::from_str_named(&text, "bar3d.toml").unwrap()
}

/// The coarse bar runs 2 us: the energy account closes, the impact face spreads, and no
/// particle lies inside the wall or beyond a symmetry plane by more than a tenth of a
/// spacing.
#[test]
fn a_coarse_quarter_bar_runs() {
    let scene = quarter_bar([4, 2, 16], "q2", 2e-6);
    let mut sim = SolidSimulation::new(&scene).unwrap();
    let b0 = sim.readings();
    let (r0, l0) = (b0.radius, b0.height());
    assert!(
        (r0 - 3.2e-3).abs() < 1e-12 && (l0 - 32.4e-3).abs() < 1e-12,
        "{r0} {l0}"
    );
    sim.run_toward(2e-6, u64::MAX, |_, _| true).unwrap();
    let b = sim.readings();
    let (r, l) = (b.radius, b.height());
    let (pen, beyond) = sim.measure_penetration().unwrap();
    let e = sim.energy();
    eprintln!(
        "r {r} l {l} pen {pen:e} beyond {beyond:e} balance {:e} dt0 {:e}",
        e.balance_error_rel(),
        sim.critical_dt0()
    );
    assert!(r > r0 && l < l0, "{r} {l}");
    assert!(e.balance_error_rel() < 0.01, "{e:?}");
}

/// The bits do not depend on the number of threads: the stress stage's chunks, the
/// particle phases' blocks and the contact stage's order are fixed.
#[test]
fn the_bits_do_not_depend_on_the_threads() {
    let scene = quarter_bar([4, 2, 16], "q4", 1e-6);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut sim = SolidSimulation::new(&scene).unwrap();
            sim.run_toward(1e-6, u64::MAX, |_, _| true).unwrap();
            sim.state().clone()
        })
    };
    let (one, two) = (run(1), run(2));
    assert!(one.step > 100);
    assert_eq!(one, two);
}

/// The points of an O-grid cell, each with its own particle list (the particles' supports
/// differ), are gathered as one group over the union of their lists.
#[test]
fn a_cells_points_are_one_group() {
    let scene = quarter_bar([8, 4, 20], "q2", 1e-7);
    let sim = SolidSimulation::new(&scene).unwrap();
    let groups = &sim.disc.scatter.group;
    let firsts = groups.iter().filter(|&&g| g > 0).count();
    assert_eq!(
        groups.iter().map(|&g| g as usize).sum::<usize>(),
        groups.len()
    );
    assert_eq!(
        firsts,
        groups.len() / 8,
        "{firsts} groups of {} points",
        groups.len()
    );
}

/// The particle means of point values: a uniform value reads back at every particle (each
/// particle is reached by points, the weights are a mean's) for the cell rules and SCNI's
/// nodal points; a value growing along z gives particle means growing along z, the highest
/// particles' above the lowest's.
#[test]
fn particle_means_are_weighted_means_of_the_points_around() {
    for rule in ["q2", "q4", "scni"] {
        let scene = quarter_bar([4, 2, 8], rule, 1e-7);
        let sim = SolidSimulation::new(&scene).unwrap();
        let uniform = sim.particle_means(&vec![2.5; sim.point_count()]);
        assert_eq!(uniform.len(), sim.particle_count());
        for (j, m) in uniform.iter().enumerate() {
            assert!((m - 2.5).abs() < 1e-12, "{rule}: particle {j}: {m}");
        }
        let z: Vec<Real> = sim.point_positions().iter().map(|p| p[2]).collect();
        let means = sim.particle_means(&z);
        let x = sim.reference_positions();
        let (low, high): (Vec<usize>, Vec<usize>) = (0..x.len())
            .filter(|&j| x[j][2] < 1e-9 || x[j][2] > 0.0324 - 1e-9)
            .partition(|&j| x[j][2] < 1e-9);
        let top = high
            .iter()
            .map(|&j| means[j])
            .fold(Real::INFINITY, Real::min);
        let bottom = low.iter().map(|&j| means[j]).fold(0.0, Real::max);
        assert!(
            bottom > 0.0 && top > bottom && top < 0.0324,
            "{rule}: {bottom} {top}"
        );
    }
}

/// A kernel re-reference of the coarse bar mid-impact keeps the body where it is and as
/// it moves: the particles' physical positions to round-off, their velocities to the fit's
/// residual, the displacement zeroed; and it keeps the stress: one step on from the new
/// reference gives each point's Mises stress within 1e-3 of the step on from the old.
#[test]
fn a_rereference_keeps_positions_velocities_and_stresses() {
    let scene = quarter_bar([4, 2, 16], "q2", 10e-6);
    let mut sim = SolidSimulation::new(&scene).unwrap();
    sim.run_toward(10e-6, u64::MAX, |_, _| true).unwrap();
    let (x0, v0) = (sim.positions(), sim.velocities());
    let mut on = sim.clone();
    on.step(None).unwrap();
    sim.rereference().unwrap();
    let r = sim.reference().unwrap();
    assert_eq!(r.count, 1);
    assert!(r.fit_residual < 1e-6, "{}", r.fit_residual);
    assert!(sim.state().d.iter().all(|d| *d == [0.0; 3]));
    let (x1, v1) = (sim.positions(), sim.velocities());
    let speed = v0.iter().flatten().fold(0.0 as Real, |m, v| m.max(v.abs()));
    let mut slip: Real = 0.0;
    for j in 0..x0.len() {
        assert_eq!(x1[j], x0[j], "particle {j}");
        for k in 0..3 {
            slip = slip.max((v1[j][k] - v0[j][k]).abs() / speed);
        }
    }
    eprintln!(
        "velocities within {slip:e} of the largest speed, fit {:e}",
        r.fit_residual
    );
    assert!(slip < 1e-6, "{slip:e}");
    sim.step(None).unwrap();
    let (a, b) = (on.point_von_mises(), sim.point_von_mises());
    let largest = a.iter().fold(0.0 as Real, |m, s| m.max(*s));
    let worst = a
        .iter()
        .zip(&b)
        .fold(0.0 as Real, |m, (a, b)| m.max((a - b).abs() / largest));
    eprintln!("Mises within {worst:e} of the largest");
    assert!(worst < 1e-3, "{worst:e}");
    assert!(
        sim.energy().balance_error_rel() < 1e-3,
        "{:?}",
        sim.energy()
    );
}

/// The coarse bar re-referenced whenever a point stretches by 1.5 since the last
/// reference runs its 80 us through three re-references with the energy account closed
/// (the kinetic energy the velocity transfers change, booked as remap, is 0.02 J of the
/// quarter bar's 60 J) and no particle deeper than a tenth of a spacing in the wall or
/// beyond a plane. On this grid (4,2,16) the foot comes out 4.1 % narrower than the
/// Lagrangian kernel's (6.494 against 6.769 mm) and the length 0.2 % shorter: the
/// re-referenced supports on the crushed foot are another approximation, as in 2D
/// (`docs/forging.md`: 9.5 % in the closed-die end force on its coarse grid).
#[test]
fn the_bar_runs_through_its_rereferences_with_the_energy_closed() {
    let lagrangian = quarter_bar([4, 2, 16], "q2", 80e-6);
    let mut scene = lagrangian.clone();
    scene.discretization.rereference_stretch = Some(1.5);
    let mut a = SolidSimulation::new(&lagrangian).unwrap();
    let mut b = SolidSimulation::new(&scene).unwrap();
    a.run_toward(80e-6, u64::MAX, |_, _| true).unwrap();
    b.run_toward(80e-6, u64::MAX, |_, _| true).unwrap();
    let (ra, rb) = (a.readings(), b.readings());
    let count = b.reference().map_or(0, |r| r.count);
    let e = b.energy();
    eprintln!(
        "re-references {count}: radius {:.4} / {:.4} mm, length {:.4} / {:.4} mm, remap {:e} J, balance {:e}",
        ra.radius * 1e3,
        rb.radius * 1e3,
        ra.height() * 1e3,
        rb.height() * 1e3,
        e.remap,
        e.balance_error_rel()
    );
    assert!(count >= 2, "{count}");
    assert!(e.balance_error_rel() < 1e-3, "{e:?}");
    assert!(e.remap.abs() < 1e-3 * 60.0, "{e:?}");
    let (pen, beyond) = b.measure_penetration().unwrap();
    assert!(
        pen < 0.1 * b.h_min() && beyond < 0.1 * b.h_min(),
        "{pen:e} {beyond:e}"
    );
    assert!((rb.radius / ra.radius - 1.0).abs() < 0.05);
    assert!((rb.height() / ra.height() - 1.0).abs() < 0.01);
}

/// A rollback across re-references repeats the bits, in the same simulation and in a
/// fresh one (an FMU's get and set state): a saved state carries its reference, and
/// restoring it rebuilds the shape functions on it.
#[test]
fn a_rollback_across_a_rereference_repeats_its_bits() {
    let mut scene = quarter_bar([4, 2, 16], "q2", 20e-6);
    scene.discretization.rereference_stretch = Some(1.2);
    let mut sim = SolidSimulation::new(&scene).unwrap();
    sim.run_toward(5e-6, u64::MAX, |_, _| true).unwrap();
    let saved = sim.state().clone();
    let before = saved.reference.as_ref().map_or(0, |r| r.count);
    sim.run_toward(20e-6, u64::MAX, |_, _| true).unwrap();
    let first = (sim.positions(), sim.state().clone());
    assert!(first.1.reference.as_ref().map_or(0, |r| r.count) > before);
    sim.restore(saved.clone()).unwrap();
    sim.run_toward(20e-6, u64::MAX, |_, _| true).unwrap();
    assert_eq!(sim.positions(), first.0);
    assert_eq!(*sim.state(), first.1);
    let mut fresh = SolidSimulation::new(&scene).unwrap();
    fresh.restore(first.1.clone()).unwrap();
    assert_eq!(fresh.positions(), first.0);
    sim.step(None).unwrap();
    fresh.step(None).unwrap();
    assert_eq!(fresh.state(), sim.state());
}

/// A quarter copper cylinder (radius 5 mm, length 10 mm, cells [2, 2, 8], q2) upset 3 mm
/// at 1 m/s between frictionless flat dies, the step held at 0.5 us by selective mass
/// scaling (some 25 times the wave's step) and the kernel re-referenced at a stretch of
/// 1.1.
fn scaled_rereferenced_upset() -> SolidScene {
    let mut text = HOT_REREFERENCED_UPSET.to_string();
    let thermal = text.find("[thermal]").unwrap();
    let time = text.find("[time]").unwrap();
    text.replace_range(thermal..time, "");
    for (from, to) in [
        ("hot_reref3d", "scaled_reref3d"),
        ("\"q4\"", "\"q2\""),
        (
            "end_s = 0.02\nmass_scaling = { factor = 1.0e4 }",
            "end_s = 3.0e-3\nmass_scaling = { target_dt_s = 0.5e-6, at_rereferences = \"target\" }",
        ),
        (
            "friction = 0.2\ntemperature_c = 20.0\nheat_transfer_w_per_m2_k = 2.0e4\n",
            "",
        ),
        ("velocity_m_per_s = 0.1", "velocity_m_per_s = 1.0"),
    ] {
        assert!(text.contains(from), "{from}");
        text = text.replace(from, to);
    }
    SolidScene::from_str_named(&text, "scaled_reref3d.toml").unwrap()
}

/// Selective mass scaling holds its target at every re-reference: the new shape functions
/// on the crushed body would step shorter, so mass is added there as at the start (the
/// critical step with it at least the target over `dt_safety`, no particle lighter than
/// before, the kinetic energy it adds booked so the account closes); a rollback across the
/// re-references restores the masses with the shape functions, in the same simulation and
/// a fresh one.
#[test]
fn a_rereference_holds_the_mass_scaling_target() {
    let scene = scaled_rereferenced_upset();
    let target = scene.time.mass_scaling.and_then(|m| m.target_dt_s).unwrap();
    let mut sim = SolidSimulation::new(&scene).unwrap();
    let start = (sim.masses().to_vec(), sim.mass_scaling().unwrap());
    sim.run_toward(1.5e-3, u64::MAX, |_, _| true).unwrap();
    let saved = sim.state().clone();
    let count = |s: &SolidSimulation| s.reference().map_or(0, |r| r.count);
    let at_save = count(&sim);
    sim.run_toward(3.0e-3, u64::MAX, |_, _| true).unwrap();
    let end = sim.mass_scaling().unwrap();
    eprintln!(
        "re-references {} ({at_save} at the save): added mass {:.3} -> {:.3}, critical step {:e} -> {:e} s, remap {:e} J, balance {:e}",
        count(&sim),
        start.1.added_mass_rel,
        end.added_mass_rel,
        start.1.critical_dt_s,
        end.critical_dt_s,
        sim.energy().remap,
        sim.energy().balance_error_rel()
    );
    assert!(at_save >= 1 && count(&sim) > at_save, "{at_save}");
    assert!(
        scene.time.dt_safety * end.critical_dt_s >= target,
        "{end:?}"
    );
    assert!(end.added_mass_rel > start.1.added_mass_rel, "{end:?}");
    assert!(sim.masses().iter().zip(&start.0).all(|(m, m0)| m >= m0));
    let held = sim.reference().and_then(|r| r.masses.clone());
    assert_eq!(held.as_deref(), Some(sim.masses()));
    assert!(
        sim.energy().balance_error_rel() < 1e-3,
        "{:?}",
        sim.energy()
    );
    let first = (sim.positions(), sim.state().clone(), sim.masses().to_vec());
    sim.restore(saved).unwrap();
    sim.run_toward(3.0e-3, u64::MAX, |_, _| true).unwrap();
    assert_eq!(sim.positions(), first.0);
    assert_eq!(*sim.state(), first.1);
    let mut fresh = SolidSimulation::new(&scene).unwrap();
    fresh.restore(first.1.clone()).unwrap();
    assert_eq!(fresh.masses(), &first.2[..]);
    assert_eq!(fresh.mass_scaling(), sim.mass_scaling());
    sim.step(None).unwrap();
    fresh.step(None).unwrap();
    assert_eq!(fresh.state(), sim.state());
}

/// Mass scaling at the re-references of the upset, `keep`, `step` and `target`: where no
/// re-reference shortens the step (each new critical step at least the one the run
/// followed), `step` adds nothing and runs the bits of `keep`; `target` adds mass.
/// (`mass_scaling`'s unit test has `step` acting.)
#[test]
fn at_rereferences_step_adds_no_mass_where_the_step_does_not_fall() {
    let runs = [AtRereference::Keep, AtRereference::Step, AtRereference::Target].map(|mode| {
        let mut scene = scaled_rereferenced_upset();
        scene.time.mass_scaling.as_mut().unwrap().at_rereferences = Some(mode);
        let mut sim = SolidSimulation::new(&scene).unwrap();
        let mut steps = Vec::new();
        while sim.time() < 3.0e-3 {
            let before = (sim.stable_dt(), sim.reference().map_or(0, |r| r.count));
            sim.step(None).unwrap();
            if sim.reference().map_or(0, |r| r.count) > before.1 {
                steps.push((before.0, sim.mass_scaling().unwrap().critical_dt_s));
            }
        }
        let added = sim.mass_scaling().unwrap().added_mass_rel;
        eprintln!("{mode:?}: critical step before / after each re-reference {steps:?}, added mass {added:.3}");
        (steps, added, sim.positions())
    });
    let [keep, step, target] = &runs;
    assert!(step.0.len() >= 2);
    assert!(step.0.iter().all(|(before, after)| after > before));
    assert_eq!(step.1, keep.1);
    assert_eq!(step.2, keep.2);
    assert!(target.1 > keep.1 * 1.2, "{} {}", target.1, keep.1);
}

/// Re-referencing is refused by its key with SCNI (no nodal domains on the deformed
/// particles), and taken on a body whose heat moves (its particles' temperatures carried).
#[test]
fn rereferencing_refuses_scni_and_takes_a_body_whose_heat_moves() {
    let refused = |scene: &SolidScene, why: &str| {
        scene
            .validate()
            .iter()
            .any(|(k, m)| k == "discretization.rereference_stretch" && m.contains(why))
    };
    let mut scni = quarter_bar([4, 2, 16], "scni", 1e-6);
    scni.discretization.rereference_stretch = Some(1.5);
    assert!(refused(&scni, "scni"));
    let text = include_str!("../../../../scenes/hot_upsetting_3d.toml");
    let mut hot = SolidScene::from_str_named(text, "hot.toml").unwrap();
    assert!(hot.validate().is_empty());
    hot.discretization.rereference_stretch = Some(1.5);
    assert_eq!(hot.validate(), vec![]);
}

/// A hot quarter copper cylinder (radius 5 mm, length 10 mm, cells [2, 2, 8], q4) at 600 C
/// upset 2 mm in 20 ms between dies at 20 C (2e4 W/(m^2 K)) with Coulomb friction 0.2,
/// conduction and air at 20 C: a body whose heat moves, re-referenced at a stretch of 1.1.
fn hot_rereferenced_upset() -> SolidScene {
    SolidScene::from_str_named(HOT_REREFERENCED_UPSET, "hot_reref3d.toml").unwrap()
}

/// The scene of [`hot_rereferenced_upset`].
const HOT_REREFERENCED_UPSET: &str = r#"
name = "hot_reref3d"
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
[discretization]
integration = "q4"
rereference_stretch = 1.1
[thermal]
initial_temperature_c = 600.0
specific_heat_j_per_kg_k = 385.0
conductivity_w_per_m_k = 400.0
ambient_temperature_c = 20.0
convection_w_per_m2_k = 50.0
[time]
end_s = 0.02
mass_scaling = { factor = 1.0e4 }
[[tools]]
name = "anvil"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, -1.0]
motion = { kind = "fixed" }
friction = 0.2
temperature_c = 20.0
heat_transfer_w_per_m2_k = 2.0e4
[[tools]]
name = "ram"
point_m = [0.0, 0.0, 0.01]
normal = [0.0, 0.0, -1.0]
axis = [0.0, 0.0, -1.0]
motion = { kind = "constant", velocity_m_per_s = 0.1 }
friction = 0.2
temperature_c = 20.0
heat_transfer_w_per_m2_k = 2.0e4
"#;

/// The temperature field at the particles, `sum_I N_I(X_J) T_I` (degrees C).
fn field_at_particles(sim: &SolidSimulation) -> Vec<Real> {
    let t = sim.particle_temperature().unwrap();
    let nodal = &sim.disc.nodal;
    (0..sim.particle_count())
        .map(|j| {
            nodal
                .row(j)
                .map(|e| nodal.n[e] * t[nodal.index[e] as usize])
                .sum()
        })
        .collect()
}

/// Re-referencing a 3D body whose heat moves ([`hot_rereferenced_upset`]) carries its
/// temperature field: at a re-reference the field at the particles is the same within 1e-9
/// K (measured 4e-10 K, the fit's residual 1e-12), the points keep their temperatures to
/// the bit and the heat account is unchanged; through the run's re-references the heat
/// balance closes to 1e-9 (8e-15); against the Lagrangian kernel's run the mechanics agree
/// within 1 % (radius +0.02 %, ram force +0.8 %, plastic heat +0.03 %) and every point's
/// temperature within 2 K (1.4 K), the heat to the dies within 10 % (+7.0 %) and the
/// friction heat within 15 % (+10 %); likely (not isolated) because the surface flows read
/// the particles' temperature coefficients `T_I`, which the fit changes where the chill is
/// steep (the field they interpolate it keeps), and the friction work the slip at the
/// faces. A rollback across re-references repeats the bits.
#[test]
fn a_rereference_carries_the_temperature_field() {
    let scene = hot_rereferenced_upset();
    assert_eq!(scene.validate(), vec![]);
    let mut sim = SolidSimulation::new(&scene).unwrap();
    sim.run_toward(0.005, u64::MAX, |_, _| true).unwrap();
    let (field, points, values) = (
        field_at_particles(&sim),
        sim.point_temperature().unwrap().to_vec(),
        sim.thermal_values().unwrap(),
    );
    let count = sim.reference().map_or(0, |r| r.count);
    sim.rereference().unwrap();
    assert_eq!(sim.reference().unwrap().count, count + 1);
    let moved = field_at_particles(&sim)
        .iter()
        .zip(&field)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, Real::max);
    eprintln!(
        "at re-reference {}: the field at the particles moved {moved:.2e} K, fit residual {:.1e}",
        count + 1,
        sim.reference().unwrap().fit_residual
    );
    assert!(moved < 1e-9, "{moved} K");
    assert_eq!(sim.point_temperature().unwrap(), &points[..]);
    assert_eq!(sim.thermal_values().unwrap(), values);
    let saved = sim.state().clone();
    sim.run_toward(0.02, u64::MAX, |_, _| true).unwrap();
    let count = sim.reference().map_or(0, |r| r.count);
    let v = sim.thermal_values().unwrap();
    let balance = v[8];
    let mut lagrangian = scene.clone();
    lagrangian.discretization.rereference_stretch = None;
    let mut lag = SolidSimulation::new(&lagrangian).unwrap();
    lag.run_toward(0.02, u64::MAX, |_, _| true).unwrap();
    let w = lag.thermal_values().unwrap();
    let apart = sim
        .point_temperature()
        .unwrap()
        .iter()
        .zip(lag.point_temperature().unwrap())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, Real::max);
    eprintln!(
        "{count} re-references: balance {balance:.1e}; to the dies {:.4} J against {:.4} J, friction heat {:.4} J against {:.4} J, plastic heat {:.4} J against {:.4} J (Lagrangian), points within {apart:.3} K; radius {:.4} / {:.4} mm, ram force {:.1} / {:.1} N",
        v[6],
        w[6],
        v[4],
        w[4],
        v[3],
        w[3],
        1e3 * sim.readings().radius,
        1e3 * lag.readings().radius,
        sim.tools()[1].state.normal_force,
        lag.tools()[1].state.normal_force,
    );
    assert!(count >= 2, "{count}");
    assert!(balance.abs() < 1e-9, "{balance:e}");
    assert!((sim.readings().radius / lag.readings().radius - 1.0).abs() < 0.01);
    assert!((v[3] / w[3] - 1.0).abs() < 0.01);
    assert!((v[6] / w[6] - 1.0).abs() < 0.1);
    assert!(w[4] > 0.0 && (v[4] / w[4] - 1.0).abs() < 0.15);
    assert!(apart < 2.0, "{apart} K");
    let mut fresh = SolidSimulation::new(&scene).unwrap();
    fresh.restore(saved).unwrap();
    fresh.run_toward(0.02, u64::MAX, |_, _| true).unwrap();
    assert_eq!(fresh.state(), sim.state());
}

/// The cells' volume through the particles: at the start the quarter bar's cells fill the
/// prism on its rim's chords, `sin(a) / a` of the cylinder's volume with the rim's four
/// cells of `a = 22.5` degrees (the inner cells' chords are shared), and after 2 us of impact the relative change of the
/// cells' volume follows the points' own `sum J_p w_p` (plastic flow keeps volume), both
/// small.
#[test]
fn the_cells_volume_follows_the_material_s_own() {
    let scene = quarter_bar([4, 2, 16], "q2", 2e-6);
    let mut sim = SolidSimulation::new(&scene).unwrap();
    let exact = std::f64::consts::PI * 3.2e-3 * 3.2e-3 * 32.4e-3 / 4.0;
    let v0 = sim.reference_volume();
    assert!((sim.volume() - v0).abs() < 1e-15 * v0);
    let a = std::f64::consts::PI / 8.0;
    assert!(
        (v0 / (exact * a.sin() / a) - 1.0).abs() < 1e-12,
        "{v0} {exact}"
    );
    sim.run_toward(2e-6, u64::MAX, |_, _| true).unwrap();
    let cells = sim.volume() / v0 - 1.0;
    let points = sim.integrated_volume_change();
    eprintln!("cells {cells:e} points {points:e}");
    assert!(
        cells.abs() < 0.02 && points.abs() < 0.02,
        "{cells} {points}"
    );
    assert!((cells - points).abs() < 0.01, "{cells} {points}");
}

/// A tool's impulse is the momentum the body gave up to it, in 3D as in 2D: the quarter
/// bar's axial momentum `sum_I M_I v_I` changes by minus the wall's impulse along its axis
/// (the symmetry planes push along x and y only), to round-off.
#[test]
fn a_tools_impulse_is_the_momentum_the_body_gave_up() {
    let mut sim = SolidSimulation::new(&quarter_bar([4, 2, 16], "q2", 4e-6)).unwrap();
    let momentum = |sim: &SolidSimulation| -> Real {
        sim.disc
            .mass
            .iter()
            .zip(&sim.st.v)
            .map(|(m, v)| m * v[2])
            .sum()
    };
    let p0 = momentum(&sim);
    sim.run_toward(4e-6, u64::MAX, |_, _| true).unwrap();
    let wall = &sim.tools()[0];
    let (axis, account) = (wall.axis[2], wall.state.account);
    let lost = (p0 - momentum(&sim)) * axis;
    assert!(account.impulse > 0.05 * p0.abs(), "{account:?} of {p0} N s");
    assert!(
        (lost - account.impulse).abs() < 1e-9 * p0.abs(),
        "momentum lost {lost} N s, impulse {} N s",
        account.impulse
    );
    assert_eq!(account.work, 0.0);
}
