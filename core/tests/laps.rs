//! The workpiece's surface holds against itself, and a fold between surface points that were
//! apart along it is reported as a lap where it forms.
//!
//! `scenes/lap_around_pin.toml`: a billet pressed down a closed die past a round pin; the
//! metal parts over the pin and the two fronts meet on the centre line under it. Without
//! self-contact the fronts passed through each other and nothing was reported.

mod common;

use common::run_measured;
use rkforge_core::Scene;

/// The shipped pin scene on a coarse grid (21 x 11, 1 mm), self-contact on or off.
fn pin(self_contact: bool) -> Scene {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/lap_around_pin.toml");
    let mut scene = Scene::from_file(&path).unwrap();
    scene.workpiece.particles = [21, 11];
    scene.self_contact.enabled = self_contact;
    scene
}

#[test]
fn the_fronts_that_meet_under_the_pin_form_a_lap_on_the_centre_line() {
    let (sim, w) = run_measured(&pin(true));
    let (crossings, inside, volume) = (w.crossings, w.itself, w.volume);
    let h = sim.spacing()[0];
    assert_eq!(crossings, 0, "the boundary crossed itself");
    assert!(
        inside < 0.05,
        "a particle {inside:.3} spacings inside the other front"
    );
    assert!(volume < 0.01, "volumes {volume:.4} apart");
    let laps = sim.laps();
    assert_eq!(laps.len(), 1, "{laps:?}");
    let lap = &laps[0];
    // Where: on the centre line, below the pin's bottom (y = -6 mm), above the floor.
    for at in [lap.start_m, lap.end_m] {
        assert!(at[0].abs() < h, "lap off the centre line at {at:?}");
        assert!(
            at[1] < -0.006 && at[1] > -0.012,
            "lap not under the pin: {at:?}"
        );
    }
    // When: after the fronts passed the pin (its diameter, 6 mm of stroke, is the least the
    // metal must travel down its sides) and before the end.
    let punch = sim.tool_index("punch").unwrap();
    let stroke = lap.formed_strokes_m[punch];
    assert!(
        stroke > 0.006 && stroke < 0.0095,
        "formed at a stroke of {stroke} m"
    );
    // Its surface particles came from the billet's bottom face, on either side of the pin.
    let bottom = |j: usize| sim.reference_positions()[j][1] == 0.0;
    assert!(
        lap.particles.iter().all(|&j| bottom(j)),
        "{:?}",
        lap.particles
    );
    let x: Vec<f64> = lap
        .particles
        .iter()
        .map(|&j| sim.reference_positions()[j][0])
        .collect();
    assert!(
        x.iter().any(|&x| x < -0.003) && x.iter().any(|&x| x > 0.003),
        "{x:?}"
    );
    assert!(lap.length_m > h, "length {}", lap.length_m);
}

#[test]
fn without_self_contact_the_fronts_pass_through_each_other() {
    let (sim, w) = run_measured(&pin(false));
    let (crossings, inside) = (w.crossings, w.itself);
    assert!(crossings > 0, "the boundary never crossed itself");
    assert!(inside > 0.1, "deepest {inside:.3} spacings inside");
    assert!(sim.laps().is_empty());
    assert!(sim
        .surface_warning()
        .is_some_and(|w| w.contains("enabled = false")));
}
