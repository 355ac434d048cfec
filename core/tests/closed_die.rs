//! Closed-die forging: no particle enters a die, wherever the material flows. Before the
//! contact took every particle as a candidate and checked the tools' convex corners against
//! the surface, the shipped wheel forging ended with 25 particles up to 1.25 spacings deep
//! inside punch and die at the hub recess corners, and reported a penetration of 0.0016
//! spacings measured over the initial boundary alone. Here the depth is measured on every
//! particle's physical position against every tool, at every history sample.

use rkforge_core::{IntegrationRule, Scene, Simulation};

/// The shipped wheel forging on a coarse grid, full stroke.
fn wheel(rule: IntegrationRule, particles: [usize; 2]) -> Scene {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/wheel_forging.toml");
    let mut scene = Scene::from_file(&path).unwrap().with_integration(rule);
    scene.workpiece.particles = particles;
    scene
}

/// Runs `scene` to its end, sampling every `output.history_interval_s`; returns the deepest
/// particle inside a tool over the samples, in smallest spacings, and the largest volume
/// change over the samples up to 90 % of the stroke (from there on the dies lock and the
/// mean pressure, about 1 GPa at the end, compresses the aluminium elastically by 1.5 %:
/// `sum_p (J_p - 1) w_p`, the integration points' own volume change, says so).
fn deepest(scene: &Scene) -> (f64, f64) {
    let mut sim = Simulation::new(scene).unwrap();
    let h = sim.spacing()[0].min(sim.spacing()[1]);
    let interval = scene.output.history_interval_s.unwrap();
    let samples = (scene.time.end_s / interval).round() as usize;
    let (mut worst, mut volume): (f64, f64) = (0.0, 0.0);
    for k in 1..=samples {
        let t = k as f64 * interval;
        sim.run_to(t, |_| {}).unwrap();
        let p = sim.measure_penetration().unwrap();
        worst = worst.max(p.depth / h);
        if t <= 0.9 * scene.time.end_s {
            let change = sim.volume() / sim.reference_volume() - 1.0;
            volume = if change.abs() > volume.abs() {
                change
            } else {
                volume
            };
        }
    }
    (worst, volume)
}

/// The shipped wheel's cavity corners (its `fill_points`): the hub recesses' outer corners
/// fill near the end of the stroke, the rim's outer corners stay empty (the scene's
/// underfill: no flash land); the workpiece touches a part of each tool. (On the 15 x 15
/// grid no particle comes within half a spacing of the hub corners.)
#[test]
fn the_wheel_fills_its_hub_corners_and_not_its_rim_corners() {
    let scene = wheel(IntegrationRule::Q2, [30, 30]);
    let mut sim = Simulation::new(&scene).unwrap();
    sim.run_to(0.5 * scene.time.end_s, |_| {}).unwrap();
    assert!(sim.fill_points().iter().all(|p| p.filled.is_none()));
    sim.run_to(scene.time.end_s, |_| {}).unwrap();
    for p in sim.fill_points() {
        let tool = &sim.tools()[p.tool].name;
        let expected = p.name == "hub_corner";
        assert_eq!(p.filled.is_some(), expected, "{tool}.{}: {:?}", p.name, p.filled);
    }
    for t in 0..sim.tools().len() {
        let f = sim.contact_fraction(t);
        assert!(f > 0.2 && f < 1.0, "tool {t}: contact fraction {f}");
    }
}

#[test]
fn no_particle_enters_the_wheel_dies_with_any_rule() {
    for rule in [
        IntegrationRule::Q2,
        IntegrationRule::Q4,
        IntegrationRule::Scni,
    ] {
        let (depth, volume) = deepest(&wheel(rule, [15, 15]));
        assert!(
            depth < 0.05,
            "{rule:?}: a particle {depth:.4} spacings inside a tool"
        );
        assert!(volume.abs() < 0.01, "{rule:?}: volume change {volume:.4}");
    }
}
