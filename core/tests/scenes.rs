//! Every shipped scene parses, sets up and runs a few steps with both rules, finite all along.

use rkforge_core::{IntegrationRule, Scene, Simulation};

#[test]
fn every_shipped_scene_runs_a_few_steps() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        for rule in [IntegrationRule::Q4, IntegrationRule::Q2] {
            let scene = Scene::from_file(&path).unwrap().with_integration(rule);
            let mut sim =
                Simulation::new(&scene).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            for _ in 0..20 {
                sim.step(None).unwrap();
                let e = sim.energy();
                assert!(
                    e.kinetic.is_finite() && e.balance_error_rel() < 1e-3,
                    "{}: {e:?}",
                    path.display()
                );
            }
        }
        count += 1;
    }
    assert!(count >= 3, "found {count} scenes");
}
