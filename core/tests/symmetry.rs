//! Symmetry planes hold every particle that reaches them, and the boundary does not pass
//! through itself, measured on the particles' physical positions.
//!
//! The bug: a symmetry constraint held only the particles that started on its edge. In the
//! plane-strain closed-die quarter model `scenes/flash_quarter.toml` the flash's tip, made of
//! particles that started on the block's side face, curled down through the mid-plane: 0.25
//! spacings deep on the 21 x 13 grid and 7 spacings on the 41 x 25 grid at the end of the
//! stroke (the rounded land entry on 41 x 25: 7.5), while the run said "ok".

mod common;

use common::run_measured;
use rkforge_core::{IntegrationRule, Scene};

/// The shipped flash scene on the coarse grid, with the die's sharp land entry or a 2 mm
/// radius there (six segments), with `rule`.
fn flash(rounded: bool, rule: IntegrationRule) -> Scene {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/flash_quarter.toml");
    let mut scene = Scene::from_file(&path).unwrap().with_integration(rule);
    scene.workpiece.particles = [21, 13];
    if rounded {
        let (w, r, land) = (0.016, 0.002, 0.012);
        let mut points = vec![[0.090, land]];
        points.extend((0..=6).map(|i| {
            let t = std::f64::consts::FRAC_PI_2 * i as f64 / 6.0;
            [w + r - r * t.sin(), land + r - r * t.cos()]
        }));
        points.extend([[w, 0.023], [-0.002, 0.023]]);
        scene.tools[0].points_m = points;
    }
    scene
}

/// With every rule the flash stays above the mid-plane and out of the die, the boundary
/// never crosses itself and encloses the material's own volume within 1 %. SCNI runs with
/// the scene's `discretization.scni_stabilization`: plain SCNI's top face under the die's
/// ceiling takes a saw-tooth (a boundary oscillation of nodal integration) and the ring
/// crosses itself once in the last tenth of the stroke, with the outline's volume 5 points
/// from the points' own ([`plain_scni_folds_where_the_stabilized_one_holds`]).
#[test]
fn the_flash_stays_on_its_side_of_the_mid_plane_with_any_rule() {
    for rounded in [false, true] {
        for rule in [
            IntegrationRule::Q2,
            IntegrationRule::Q4,
            IntegrationRule::Scni,
        ] {
            let scene = flash(rounded, rule);
            assert!(scene.discretization.scni_stabilization.is_some());
            let (_, w) = run_measured(&scene);
            let (plane, tool, crossings, volume) = (w.planes, w.tools, w.crossings, w.volume);
            let case = format!("rounded {rounded}, {rule:?}");
            assert!(
                plane < 0.05,
                "{case}: {plane:.4} spacings beyond the mid-plane"
            );
            assert!(tool < 0.05, "{case}: {tool:.4} spacings inside the die");
            assert_eq!(crossings, 0, "{case}: the boundary crossed itself");
            assert!(volume < 0.01, "{case}: volumes {volume:.4} apart");
        }
    }
}

/// What the stabilization buys: without it, SCNI's saw-tooth folds the sharp-cornered
/// flash's boundary through itself.
#[test]
fn plain_scni_folds_where_the_stabilized_one_holds() {
    let mut scene = flash(false, IntegrationRule::Scni);
    scene.discretization.scni_stabilization = None;
    let (_, w) = run_measured(&scene);
    assert!(w.crossings > 0, "plain SCNI: {} crossings", w.crossings);
}
