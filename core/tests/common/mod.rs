//! Scenes built in code for the physics tests (each test binary uses a subset).
#![allow(dead_code)]

use rkforge_core::material::Hardening;
use rkforge_core::scene::*;
use rkforge_core::Simulation;

pub mod solid_scenes;

/// A free square patch of copper (no tools, no constraints).
pub fn patch(kin: Kinematics, n: usize, rule: IntegrationRule, support: f64) -> Scene {
    Scene {
        name: "patch".into(),
        description: String::new(),
        model: Model {
            kinematics: kin,
            depth_m: 1.0,
        },
        workpiece: Workpiece {
            origin_m: [
                if kin == Kinematics::Axisymmetric {
                    0.01
                } else {
                    0.0
                },
                0.0,
            ],
            size_m: [0.01, 0.01],
            particles: [n, n],
            initial_velocity_m_per_s: [0.0, 0.0],
        },
        material: MaterialSpec {
            density_kg_per_m3: 8930.0,
            youngs_modulus_pa: 117e9,
            poisson_ratio: 0.35,
            hardening: Hardening::Linear {
                yield_stress_pa: 400e6,
                modulus_pa: 100e6,
            },
        },
        thermal: None,
        discretization: Discretization {
            integration: rule,
            support: [support, support],
            rereference_stretch: None,
            scni_stabilization: None,
        },
        time: TimeSpec {
            end_s: 1e-6,
            dt_s: None,
            dt_safety: 0.5,
            mass_scaling: None,
        },
        constraints: vec![],
        self_contact: SelfContactSpec::default(),
        tools: vec![],
        output: OutputSpec::default(),
        checks: Checks::default(),
        reference: vec![],
    }
}

/// The paper's Taylor bar at a chosen resolution and rule.
pub fn taylor(nx: usize, ny: usize, rule: IntegrationRule) -> Scene {
    let text = include_str!("../../../scenes/taylor_bar.toml");
    let mut s = Scene::from_str_named(text, "taylor_bar.toml").expect("shipped scene parses");
    s.workpiece.particles = [nx, ny];
    s.discretization.integration = rule;
    s.time.dt_s = None;
    s
}

/// The shipped block forging with both tools at `speed` (m/s) through the full 300 mm
/// stroke, adaptive steps at `dt_safety` 0.9, on a grid of `n` x `n` particles.
pub fn block_at_press_speed(n: usize, speed: f64) -> Scene {
    let text = include_str!("../../../scenes/block_forging.toml");
    let mut s = Scene::from_str_named(text, "block_forging.toml").expect("shipped scene parses");
    s.workpiece.particles = [n, n];
    for t in &mut s.tools {
        t.motion = Motion::Constant {
            velocity_m_per_s: speed,
        };
    }
    s.time.end_s = 0.15 / speed;
    s.time.dt_s = None;
    s.time.dt_safety = 0.9;
    s
}

/// The worst a run met over its history samples, every particle measured at its physical
/// position: the deepest beyond a symmetry plane or the axis, in a tool and inside another
/// part of the workpiece (in smallest spacings), the most crossings of the boundary at a
/// sample, and the largest difference between the boundary's volume change and the
/// material's own (`integrated_volume_change`).
#[derive(Debug, Default)]
pub struct Worst {
    pub planes: f64,
    pub tools: f64,
    pub itself: f64,
    pub crossings: usize,
    pub volume: f64,
}

/// Runs `scene` to its end, measuring at every history sample ([`Worst`]).
pub fn run_measured(scene: &Scene) -> (Simulation, Worst) {
    let mut sim = Simulation::new(scene).unwrap();
    let h = sim.spacing()[0].min(sim.spacing()[1]);
    let interval = scene.history_interval();
    let samples = (scene.time.end_s / interval).round() as usize;
    let mut w = Worst::default();
    for k in 1..=samples {
        sim.run_to(k as f64 * interval, |_| {}).unwrap();
        let d = sim.measure_penetration().unwrap();
        w.planes = w.planes.max(d.planes.depth / h);
        w.tools = w.tools.max(d.tools.depth / h);
        w.itself = w.itself.max(d.itself.depth / h);
        w.crossings = w.crossings.max(d.crossings);
        let boundary = sim.volume() / sim.reference_volume() - 1.0;
        w.volume = w
            .volume
            .max((boundary - sim.integrated_volume_change()).abs());
    }
    (sim, w)
}
