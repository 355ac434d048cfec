//! Every shipped scene parses, sets up and runs a few steps with both rules, finite all along.
//!
//! The energy balance stays within 1e-3 over the first steps, except while a mass-scaled
//! press strikes its resting billet in the first steps of the impression die: the explicit
//! scheme's start-up error of a tool meeting the billet at a long (mass-scaled) step is then
//! 1.5e-2 of the energy exchanged at step 3 (6.3e-3 with the contact before the corner pass,
//! which missed the punch's recess edge pressing into the billet), 1.2e-3 at step 60 and
//! 3e-6 at the end of the stroke; in the hot impression die, whose flow stress is 20 times
//! lower, 4.3e-2 of the 0.02 J exchanged in its first 20 steps (5e-6 at the end); in 3D, the
//! connecting rod's STL die on its bar, 2.6e-3 after 10 steps (1.1e-4 after 1 ms, 6.8e-7 at
//! the end). A mass-scaled scene, 2D or 3D, is held in its first steps to the runs' own
//! default bound, `checks.energy_balance_tol` = 0.05.

use rkforge_core::scene::SceneFile;
use rkforge_core::solver::SolidSimulation;
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
        if let SceneFile::Solid(scene) = SceneFile::from_file(&path).unwrap() {
            for rule in [IntegrationRule::Q4, IntegrationRule::Q2] {
                let mut scene = (*scene).clone();
                scene.discretization.integration = rule;
                let mut sim = SolidSimulation::new(&scene)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                let bound = match scene.time.mass_scaling {
                    Some(_) => 5e-2,
                    None => 1e-3,
                };
                for _ in 0..20 {
                    sim.step(None).unwrap();
                    let e = sim.energy();
                    assert!(
                        e.kinetic.is_finite() && e.balance_error_rel() < bound,
                        "{}: {e:?}",
                        path.display()
                    );
                }
            }
            count += 1;
            continue;
        }
        for rule in [IntegrationRule::Q4, IntegrationRule::Q2] {
            let scene = Scene::from_file(&path).unwrap().with_integration(rule);
            let mut sim =
                Simulation::new(&scene).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            for _ in 0..20 {
                sim.step(None).unwrap();
                let e = sim.energy();
                let bound = match scene.time.mass_scaling {
                    Some(_) => 5e-2,
                    None => 1e-3,
                };
                assert!(
                    e.kinetic.is_finite() && e.balance_error_rel() < bound,
                    "{}: {e:?}",
                    path.display()
                );
            }
        }
        count += 1;
    }
    assert!(count >= 3, "found {count} scenes");
}
