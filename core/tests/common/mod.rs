//! Scenes built in code for the physics tests (each test binary uses a subset).
#![allow(dead_code)]

use rkforge_core::material::Hardening;
use rkforge_core::scene::*;

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
