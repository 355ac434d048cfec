//! The finite-element benchmark's wall (issue 17): a tool without separation holds every
//! particle that reached it, on the particles' physical positions.

use rkforge_core::scene::Edge;
use rkforge_core::{IntegrationRule, Scene, Simulation};

/// The Taylor bar (11 x 26, SCNI, adaptive step) with the wall's `separation` set.
fn taylor(separation: bool) -> Scene {
    let text = include_str!("../../scenes/taylor_bar.toml");
    let mut s = Scene::from_str_named(text, "taylor_bar.toml").unwrap();
    s.workpiece.particles = [11, 26];
    s.time.dt_s = None;
    s.tools[0].separation = separation;
    s.with_integration(IntegrationRule::Scni)
}

/// Largest distance of an impact-face particle from the wall (m).
fn off_wall(sim: &Simulation) -> f64 {
    let e = sim.face_extents(Edge::YMin);
    e.y[0].abs().max(e.y[1].abs())
}

/// With lift-off allowed the impact face's rim curls off the frictionless wall by tens of
/// micrometres; without separation every impact-face particle stays on it (within 1 um,
/// 0.3 % of the radial spacing: the penalty's residual) for the whole impact, and the bar
/// ends narrower.
#[test]
fn a_wall_without_separation_holds_the_impact_face() {
    let mut free = Simulation::new(&taylor(true)).unwrap();
    free.run_to(80e-6, |_| {}).unwrap();
    assert!(off_wall(&free) > 10e-6, "lift-off {} m", off_wall(&free));
    let mut held = Simulation::new(&taylor(false)).unwrap();
    let mut worst: f64 = 0.0;
    for k in 1..=16 {
        held.run_to(k as f64 * 5e-6, |_| {}).unwrap();
        worst = worst.max(off_wall(&held));
    }
    assert!(
        worst < 1e-6,
        "an impact-face particle {worst} m off the wall"
    );
    let (r_free, r_held) = (
        free.face_extents(Edge::YMin).x[1],
        held.face_extents(Edge::YMin).x[1],
    );
    assert!(r_held < r_free, "held {r_held} m, free {r_free} m");
    assert!(held.energy().balance_error_rel().abs() < 1e-3);
}

/// The held particles are part of the state: a restored run continues bit for bit.
#[test]
fn held_particles_survive_a_restore() {
    let scene = taylor(false);
    let mut a = Simulation::new(&scene).unwrap();
    a.run_to(20e-6, |_| {}).unwrap();
    let saved = a.state().clone();
    assert!(saved.held.iter().any(|&h| h));
    a.run_to(40e-6, |_| {}).unwrap();
    let mut b = Simulation::new(&scene).unwrap();
    let mut no_held = saved.clone();
    no_held.held.clear();
    assert!(
        b.restore(no_held).is_err(),
        "a state without the held set is refused"
    );
    b.restore(saved).unwrap();
    b.run_to(40e-6, |_| {}).unwrap();
    assert_eq!(a.state(), b.state());
}
