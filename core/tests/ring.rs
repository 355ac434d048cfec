//! The shipped ring compression scene (issue 17): the frictionless ring upsets
//! homogeneously, every radius growing as `sqrt(h0 / h)`.

use rkforge_core::scene::{Edge, Friction, Motion};
use rkforge_core::{Scene, Simulation};

/// Frictionless platen, 50 % height reduction: the inner and outer radii within 1 % of the
/// homogeneous solution `R sqrt(h0 / h)`. The press is quasi-static: `rho v^2` is below a
/// thousandth of the flow stress (checked here on the scene). A coarser grid than shipped
/// keeps the test short.
#[test]
fn frictionless_ring_upsets_homogeneously() {
    let text = include_str!("../../scenes/ring_compression.toml");
    let mut s = Scene::from_str_named(text, "ring_compression.toml").unwrap();
    s.workpiece.particles = [16, 11];
    s.tools[0].friction = Friction::Coulomb { mu: 0.0 };
    let Motion::Table { points } = &s.tools[0].motion else {
        panic!("the platen follows a velocity table");
    };
    let v = points.iter().fold(0.0_f64, |a, p| a.max(p[1].abs()));
    let rho = s.material.density_kg_per_m3;
    let flow = s.material.hardening.initial_yield();
    assert!(rho * v * v < 1e-3 * flow, "rho v^2 = {} Pa", rho * v * v);
    let mut sim = Simulation::new(&s).unwrap();
    sim.run_to(s.time.end_s, |_| {}).unwrap();
    let (h0, r0) = (s.workpiece.size_m[1], s.workpiece.origin_m[0]);
    let e = sim.extents();
    let h = e.y[1] - e.y[0];
    assert!(
        (1.0 - h / h0 - 0.5).abs() < 0.005,
        "height reduction {}",
        1.0 - h / h0
    );
    let stretch = (h0 / h).sqrt();
    let inner = sim.face_extents(Edge::XMin);
    let outer = sim.face_extents(Edge::XMax);
    for (name, got, want) in [
        ("inner, smallest", inner.x[0], r0 * stretch),
        ("inner, largest", inner.x[1], r0 * stretch),
        (
            "outer, smallest",
            outer.x[0],
            (r0 + s.workpiece.size_m[0]) * stretch,
        ),
        (
            "outer, largest",
            outer.x[1],
            (r0 + s.workpiece.size_m[0]) * stretch,
        ),
    ] {
        assert!(
            (got / want - 1.0).abs() < 0.01,
            "{name} radius {got} m against {want} m ({:+.2} %)",
            100.0 * (got / want - 1.0)
        );
    }
}

/// Bug (issue 17): the shear law created energy when the platen met the ring at a press
/// speed without a ramp. With the stick force taken from the one-step slip, many particles
/// reached the stick cap together at first contact, and their corrections, spread through
/// shared coefficients, overshot: the interface gave the ring 5 % more work than the platen
/// delivered and the energy check stopped the run at 73 us. With the unrealised part of the
/// stick force carried to the next step instead, the force builds up over several steps and
/// the interface gives back at most what its penalty stores:
/// over the elastic start (200 us at 10 mm/s, every contact sticking) the work it created is
/// below 0.5 % of the platen's at every step for m = 0.2 and m = 1 (0.14 % measured), and
/// below 0.1 % for the frictionless platen (0.03 %): the penalty's discrete error in the
/// energy its springs store.
#[test]
fn shear_friction_creates_no_energy_at_a_slow_start() {
    let text = include_str!("../../scenes/ring_compression.toml");
    let mut s = Scene::from_str_named(text, "ring_compression.toml").unwrap();
    s.workpiece.particles = [21, 14];
    s.time.end_s = 2e-4;
    s.time.dt_safety = 0.9;
    s.tools[0].motion = Motion::Constant {
        velocity_m_per_s: 0.01,
    };
    for (law, bound) in [
        (Friction::Coulomb { mu: 0.0 }, 1e-3),
        (Friction::Shear { m: 0.2 }, 5e-3),
        (Friction::Shear { m: 1.0 }, 5e-3),
    ] {
        s.tools[0].friction = law;
        let mut sim = Simulation::new(&s).unwrap();
        let mut worst: f64 = 0.0;
        sim.run_to(s.time.end_s, |sim| {
            let e = sim.energy();
            if e.tool_work > 0.0 {
                worst = worst.max(e.interface_gain() / e.tool_work_abs);
            }
        })
        .unwrap();
        assert!(
            worst < bound,
            "{law:?}: the interface created {worst:.2e} of the platen's work"
        );
        assert!(sim.energy().tool_work > 0.0);
        println!("{law:?}: largest interface gain {worst:.2e} of the platen's work");
    }
}
