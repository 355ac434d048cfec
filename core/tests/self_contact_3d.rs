//! The 3D workpiece's surface holds against itself, and a fold between surface points that
//! were apart on it is reported as a lap where it forms.

use rkforge_core::scene::solid::{SceneFile, SolidScene};
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

#[test]
fn pin_probe() {
    for on in [true, false] {
        let (sim, m) = run(&shipped("lap_around_pin_3d.toml", on), 19);
        eprintln!("self-contact {on}: {m:?} steps {} laps {:#?}", sim.steps(), sim.laps());
    }
}

#[test]
fn step_probe() {
    let scene = shipped("lap_around_pin_3d.toml", true);
    let mut sim = SolidSimulation::new(&scene).unwrap();
    eprintln!("critical {:e} mass scaling {:?}", sim.critical_dt0(), sim.mass_scaling());
    for k in 1..=8 {
        sim.run_toward(0.038 * k as f64 / 8.0, u64::MAX, |_, _| true).unwrap();
        eprintln!("t {:e} steps {} stable {:e} dt_prev {:e}", sim.time(), sim.steps(), sim.stable_dt(), sim.state().dt_prev);
        let (d, j) = sim.self_penetration_now();
        let x = sim.positions();
        eprintln!("  behind {d:e} particle {j} at {:?} ref {:?}", x[j], sim.reference_positions()[j]);
    }
}
