//! The shipped hot upsetting (`scenes/hot_upsetting.toml`): mass scaling adds inertia, never
//! heat capacity or time, so a scaled run at press speed follows the unscaled one.

use rkforge_core::scene::Motion;
use rkforge_core::{Scene, Simulation, THERMAL_MEASURES};

/// At the end of `scene`: the ram's force along its axis (N), the workpiece's least
/// temperature (degrees C), the heat made by plastic work and the heat lost to the tools (J),
/// and the steps taken.
fn end_of(scene: &Scene) -> (f64, f64, f64, f64, u64) {
    let mut sim = Simulation::new(scene).unwrap();
    sim.run_to(scene.time.end_s, |_| {}).unwrap();
    let ram = sim.tool_index("ram").unwrap();
    let t = sim.temperatures().unwrap();
    let to_tools: f64 = (0..sim.tools().len())
        .map(|k| sim.tool_heat(k).unwrap())
        .sum();
    (
        -sim.tools()[ram].axial_force(),
        t.min_c,
        sim.plastic_heat().unwrap(),
        to_tools,
        sim.steps(),
    )
}

/// The shipped hot upsetting on a coarse grid (6 x 16 particles).
fn coarse() -> Scene {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/hot_upsetting.toml");
    let mut scene = Scene::from_file(&path).unwrap();
    scene.workpiece.particles = [6, 16];
    scene
}

/// The shipped scene on a coarse grid (6 x 16) at 0.2 m/s for 15 mm (a screw press's speed,
/// so that the unscaled run is short): with the scene's selective mass scaling (a 20 us
/// step) and without (the wave speed's step): the ram force at the end within 2 %, the least
/// temperature (the die chill) within 1 % of its fall from 1150 C, the heat made by plastic
/// work and the heat lost to the dies within 1 % (measured with the scene's properties over
/// temperature: 0.03 %, 0.97 %, 0.10 %, 0.80 %).
#[test]
fn mass_scaled_hot_upsetting_follows_the_unscaled_run() {
    let mut scene = coarse();
    let speed = 0.2;
    for tool in &mut scene.tools {
        if let Motion::Constant { velocity_m_per_s } = &mut tool.motion {
            *velocity_m_per_s = speed;
        }
    }
    scene.time.end_s = 0.015 / speed;
    let scaled = end_of(&scene);
    scene.time.mass_scaling = None;
    let unscaled = end_of(&scene);
    let t0 = scene.thermal.as_ref().unwrap().initial_temperature_c;
    eprintln!(
        "scaled / unscaled: ram force {:.5e} / {:.5e} N, least temperature {:.2} / {:.2} C, \
         plastic heat {:.5e} / {:.5e} J, heat to the dies {:.5e} / {:.5e} J, steps {} / {}",
        scaled.0,
        unscaled.0,
        scaled.1,
        unscaled.1,
        scaled.2,
        unscaled.2,
        scaled.3,
        unscaled.3,
        scaled.4,
        unscaled.4
    );
    assert!(
        scaled.4 * 10 < unscaled.4,
        "{} against {} steps",
        scaled.4,
        unscaled.4
    );
    assert!(
        (scaled.0 / unscaled.0 - 1.0).abs() < 0.02,
        "ram force {:.4e} N scaled against {:.4e} N",
        scaled.0,
        unscaled.0
    );
    assert!(
        (scaled.1 - unscaled.1).abs() < 0.01 * (t0 - unscaled.1),
        "least temperature {:.2} C scaled against {:.2} C",
        scaled.1,
        unscaled.1
    );
    for (name, s, u) in [
        ("plastic", scaled.2, unscaled.2),
        ("die", scaled.3, unscaled.3),
    ] {
        assert!(
            (s / u - 1.0).abs() < 0.01,
            "{name} heat {s:.4e} J scaled against {u:.4e} J"
        );
    }
}

/// Friction heat: the shipped hot upsetting made adiabatic but for friction (no conduction,
/// no heat to the dies or the air), coarse (6 x 16), 10 mm at 0.2 m/s: the heat friction made
/// is most of the work the interface took from the tools' work, `tool_work - contact_work`
/// of the energy account (72 %: the rest is what the normal penalty took, its springs'
/// energy and the particles' normal velocity it stops), never more; the workpiece holds its
/// share (0.5) of it and the plastic heat, the account closing to round-off. (The friction
/// work is booked against the slip the corrector realised: against the predicted slip it
/// was five times larger without mass scaling than with it, the elastic ringing's.)
#[test]
fn friction_heats_the_workpiece_by_its_share_of_the_interface_work() {
    let mut scene = coarse();
    let thermal = scene.thermal.as_mut().unwrap();
    thermal.conductivity_w_per_m_k = 0.0;
    thermal.convection_w_per_m2_k = 0.0;
    thermal.emissivity = 0.0;
    for tool in &mut scene.tools {
        tool.heat_transfer_w_per_m2_k = 0.0;
        if let Motion::Constant { velocity_m_per_s } = &mut tool.motion {
            *velocity_m_per_s = 0.2;
        }
    }
    scene.time.end_s = 0.05;
    let mut sim = Simulation::new(&scene).unwrap();
    sim.run_to(scene.time.end_s, |_| {}).unwrap();
    let values = sim.thermal_values().unwrap();
    let get = |name: &str| values[THERMAL_MEASURES.iter().position(|m| m.0 == name).unwrap()];
    let e = sim.energy();
    let interface = e.tool_work - e.contact_work;
    let friction = get("friction_heat_J");
    assert!(
        friction > 0.6 * interface && friction <= interface,
        "friction heat {friction:.4e} J against the interface's {interface:.4e} J"
    );
    let content = get("heat_content_J");
    let made = get("plastic_heat_J") + 0.5 * friction;
    assert!(
        (content / made - 1.0).abs() < 1e-9,
        "{content} J held against {made} J made"
    );
    assert!(get("heat_balance_rel").abs() < 1e-9);
}

/// The shipped hot upsetting (coarse, 6 x 16, its thermal strain over temperature) resting
/// on the dies at 250 C with the ram still for 0.3 s: the dies chill the billet's faces, the
/// thermal contraction strains it (and at 1150 C, with a flow stress of tens of MPa, flows it
/// plastically) with no work done by a tool. The energy account, with the elastic energy the
/// changes of temperature put in, closes to 1e-4 of that energy (the run's energy check would
/// stop it at 5 % of it), and the billet is strained: that energy and the plastic work are
/// more than 0.1 J.
#[test]
fn a_billet_chilled_at_rest_keeps_its_energy_account() {
    let mut scene = coarse();
    for tool in &mut scene.tools {
        if let Motion::Constant { velocity_m_per_s } = &mut tool.motion {
            *velocity_m_per_s = 0.0;
        }
    }
    scene.time.end_s = 0.3;
    let mut sim = Simulation::new(&scene).unwrap();
    sim.run_to(scene.time.end_s, |_| {}).unwrap();
    let e = sim.energy();
    eprintln!(
        "at rest: put in by temperature {:.4e} J, plastic {:.4e} J, balance error {:.3e} J",
        e.thermoelastic,
        e.plastic,
        e.balance_error()
    );
    assert!(e.thermoelastic > 0.1 && e.plastic > 0.1);
    assert!(e.balance_error().abs() < 1e-4 * e.thermoelastic);
}
