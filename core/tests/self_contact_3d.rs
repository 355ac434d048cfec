//! The 3D workpiece's surface holds against itself, and a fold between surface points that
//! were apart on it is reported as a lap where it forms.

use rkforge_core::scene::solid::{SceneFile, SolidScene};
use rkforge_core::friction::Friction;
use rkforge_core::solver::SolidSimulation;

/// A shipped 3D scene, self-contact on or off.
fn shipped(name: &str, self_contact: bool) -> SolidScene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(name);
    let SceneFile::Solid(mut scene) = SceneFile::from_file(&path).unwrap() else {
        panic!("{name} is not a 3D scene")
    };
    scene.self_contact.enabled = self_contact;
    *scene
}

/// What a run measured at its samples.
#[derive(Debug, Default)]
struct Measured {
    /// Deepest a surface particle lay behind another part of the surface (spacings).
    behind: f64,
    /// Deepest a particle lay inside a tool (spacings).
    in_tool: f64,
    /// Largest relative energy balance error.
    energy: f64,
}

/// Runs `scene` to its end, measuring at `samples` even times.
fn run(scene: &SolidScene, samples: usize) -> (SolidSimulation, Measured) {
    let mut sim = SolidSimulation::new(scene).unwrap();
    let h = sim.h_min();
    let mut m = Measured::default();
    for k in 1..=samples {
        let t = scene.time.end_s * k as f64 / samples as f64;
        sim.run_toward(t, u64::MAX, |_, _| true).unwrap();
        let (behind, j) = sim.self_penetration_now();
        let tools = sim.penetration_now()[0].0;
        m.behind = m.behind.max(behind / h);
        m.in_tool = m.in_tool.max(tools / h);
        m.energy = m.energy.max(sim.energy().balance_error_rel());
        eprintln!(
            "t {t:.4e} s: behind {:.4} spacings (particle {j}), in a tool {:.4}, laps {}, energy {:.2e}",
            behind / h,
            tools / h,
            sim.lap_count(),
            sim.energy().balance_error_rel()
        );
    }
    (sim, m)
}

/// A run without any self-touching gives the same bits with self-contact on and off: no
/// false contact between neighbours or across the body, and the search adds no force.
#[test]
fn a_plain_upset_gives_the_same_bits_with_self_contact_on_and_off() {
    for (name, end) in [
        ("block_upsetting_3d.toml", 0.25),
        ("press_upsetting_3d.toml", 0.0),
    ] {
        let runs = [true, false].map(|on| {
            let mut scene = shipped(name, on);
            if end > 0.0 {
                scene.time.end_s = end;
            }
            let (sim, m) = run(&scene, 4);
            assert_eq!(sim.lap_count(), 0, "{name}");
            (sim, m)
        });
        let [(on, m_on), (off, m_off)] = runs;
        assert_eq!(on.steps(), off.steps(), "{name}");
        assert!(on.state().d == off.state().d, "{name}: displacements differ");
        assert!(on.state().v == off.state().v, "{name}: velocities differ");
        assert_eq!(on.energy(), off.energy(), "{name}");
        assert_eq!(m_on.behind, 0.0, "{name}: {m_on:?}");
        assert_eq!(m_off.behind, 0.0, "{name}: {m_off:?}");
        eprintln!(
            "{name}: {} steps to {} s, same bits on and off, nothing behind the surface",
            on.steps(),
            on.time()
        );
    }
}

/// The shipped pin scene with a coarser mass scaling (16 us, four times the shipped step:
/// the test's runs take a quarter of the steps) and Coulomb friction 0.1 on the dies (no
/// flow stress to smooth at each step), self-contact on.
fn quick_pin() -> SolidScene {
    let mut scene = shipped("lap_around_pin_3d.toml", true);
    scene.time.mass_scaling.as_mut().unwrap().target_dt_s = Some(16e-6);
    for t in &mut scene.tools {
        if t.name != "back" {
            t.friction = Friction::Coulomb { mu: 0.1 };
        }
    }
    scene
}

#[test]
fn the_fronts_that_meet_under_the_pin_form_a_lap_and_stay_apart() {
    let scene = quick_pin();
    let mut on = SolidSimulation::new(&scene).unwrap();
    let h = on.h_min();
    // Before the fronts meet, nothing has passed through, and the run with self-contact
    // off is the same run: it goes on from here.
    let meet = 0.030;
    for k in 1..=10 {
        on.run_toward(meet * k as f64 / 10.0, u64::MAX, |_, _| true).unwrap();
        let (d, j) = on.self_penetration_now();
        eprintln!("t {:.4e} passed {d:.3e} particle {j} ref {:?} at {:?}", on.time(), on.reference_positions()[j], on.positions()[j]);
    }
    assert_eq!(on.self_penetration_now().0, 0.0);
    assert_eq!(on.lap_count(), 0);
    let mut off_scene = scene.clone();
    off_scene.self_contact.enabled = false;
    let mut off = SolidSimulation::new(&off_scene).unwrap();
    off.restore(on.state().clone()).unwrap();
    let (mut deepest_on, mut deepest_off, mut energy) = (0.0f64, 0.0f64, 0.0f64);
    let samples = 16;
    for k in 1..=samples {
        let t = meet + (scene.time.end_s - meet) * k as f64 / samples as f64;
        for sim in [&mut on, &mut off] {
            sim.run_toward(t, u64::MAX, |_, _| true).unwrap();
            energy = energy.max(sim.energy().balance_error_rel());
        }
        let fronts = |sim: &SolidSimulation| {
            let (x, r) = (sim.positions(), sim.reference_positions());
            let (mut left, mut right) = (f64::NEG_INFINITY, f64::INFINITY);
            for j in 0..x.len() {
                if r[j][2] == 0.0 && x[j][2] < -0.0065 {
                    if r[j][0] < 0.0 {
                        left = left.max(x[j][0]);
                    } else if r[j][0] > 0.0 {
                        right = right.min(x[j][0]);
                    }
                }
            }
            [left, right]
        };
        eprintln!("fronts with {:?} without {:?}", fronts(&on), fronts(&off));
        let (a, ja) = on.self_penetration_now();
        let (b, jb) = off.self_penetration_now();
        deepest_on = deepest_on.max(a / h);
        deepest_off = deepest_off.max(b / h);
        eprintln!(
            "t {t:.4e} s: passed through by {:.4} spacings (particle {ja}) with self-contact, {:.4} (particle {jb}) without; laps {}",
            a / h,
            b / h,
            on.lap_count()
        );
    }
    let laps = on.laps();
    eprintln!(
        "deepest {deepest_on:.4} spacings with, {deepest_off:.4} without; energy balance {energy:.2e}; {} steps; {laps:#?}",
        on.steps()
    );
    assert!(deepest_off > 0.2, "without: {deepest_off}");
    assert!(deepest_on < 0.05, "with: {deepest_on}");
    assert!(off.laps().is_empty());
    assert!(energy < 1e-3, "{energy}");
    assert_eq!(laps.len(), 1, "{laps:?}");
    let lap = &laps[0];
    for at in [lap.start_m, lap.end_m] {
        assert!(at[0].abs() < h, "lap off the centre line at {at:?}");
        assert!(at[2] < -0.006 && at[2] > -0.012, "lap not under the pin: {at:?}");
    }
    let punch = on.tool_index("punch").unwrap();
    let stroke = lap.formed_strokes_m[punch];
    assert!(stroke > 0.006 && stroke < 0.0095, "formed at a stroke of {stroke} m");
    let r = on.reference_positions();
    assert!(lap.particles.iter().all(|&j| r[j][2] == 0.0), "{:?}", lap.particles);
    assert!(lap.particles.iter().any(|&j| r[j][0] < 0.0) && lap.particles.iter().any(|&j| r[j][0] > 0.0));
}
