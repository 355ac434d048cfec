//! Contact pressure along a tool (`output.pressure_stations`): frictionless plane-strain
//! upsetting of the block between flat tools. The stations' normal forces add up to the
//! tool's force, the stations beyond the block carry none, and the mean pressure under the
//! block is the plane-strain flow stress `2 sigma_y / sqrt 3` of homogeneous compression
//! (the equivalent strain `(2 / sqrt 3) ln(h0 / h)`, linear hardening). The mean contact
//! pressure of the register (`<tool>.pressure_mean_Pa`) against the same flow stress, and
//! against the uniaxial flow stress in frictionless axisymmetric upsetting.

use rkforge_core::{Scene, SceneSource, Simulation};

/// The shipped scene `name` with the overrides `args` (`key=value`).
fn shipped(name: &str, args: &[&str]) -> Scene {
    let path = format!("{}/../scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let mut source = SceneSource::from_file(std::path::Path::new(&path)).unwrap();
    source.set_args(args).unwrap();
    source.scene().clone()
}

#[test]
fn frictionless_upsetting_presses_at_the_plane_strain_flow_stress() {
    let scene = shipped(
        "block_forging",
        &[
            "workpiece.particles=[15,15]",
            "tools.top.friction=0.0",
            "tools.bottom.friction=0.0",
            "output.pressure_stations=40",
            "time.end_s=5.0e-3",
        ],
    );
    let mut sim = Simulation::new(&scene).unwrap();
    assert_eq!(sim.contact_pressure(0), vec![0.0; 40]);
    sim.run_to(scene.time.end_s, |_| {}).unwrap();
    let top = &sim.tools()[0];
    let p = sim.contact_pressure(0);
    assert_eq!(p.len(), 40);
    // 2 m of tool in 40 stations of 5 cm, the block 0.5 m wide (wider now) in the middle.
    let area = 0.05 * scene.model.depth_m;
    let total: f64 = p.iter().map(|x| x * area).sum();
    let force = top.state.force[1].abs();
    assert!((total / force - 1.0).abs() < 1e-9, "{total} vs {force} N");
    let e = sim.extents();
    let width = e.x[1] - e.x[0];
    for (k, x) in p.iter().enumerate() {
        // Station k spans x from 1 - 0.05 k down to 1 - 0.05 (k + 1) (the top tool runs
        // from x = 1 to x = -1).
        let (hi, lo) = (1.0 - 0.05 * k as f64, 1.0 - 0.05 * (k + 1) as f64);
        if lo > e.x[1] || hi < e.x[0] {
            assert_eq!(*x, 0.0, "station {k} beyond the block");
        }
    }
    let height = e.y[1] - e.y[0];
    let eps = 2.0 / 3f64.sqrt() * (0.5 / height).ln();
    let flow = 400.0e6 + 100.0e6 * eps;
    let expected = 2.0 / 3f64.sqrt() * flow;
    let mean = force / (width * scene.model.depth_m);
    // The stations wholly under the block: their mean pressure, a particle or two each.
    let under: Vec<f64> = (0..40)
        .filter(|&k| 1.0 - 0.05 * k as f64 <= e.x[1] && 1.0 - 0.05 * (k + 1) as f64 >= e.x[0])
        .map(|k| p[k])
        .collect();
    let under_mean = under.iter().sum::<f64>() / under.len() as f64;
    println!(
        "stations under the block: {} of mean {under_mean:.4e} Pa",
        under.len()
    );
    assert!(under.len() >= 10 && (under_mean / expected - 1.0).abs() < 0.1);
    println!(
        "mean pressure {mean:.4e} Pa, 2 sigma_y / sqrt 3 = {expected:.4e} Pa, width {width} m"
    );
    assert!((mean / expected - 1.0).abs() < 0.05, "{mean} vs {expected}");
}

/// The register's `<tool>.pressure_mean_Pa` of `sim` now (Pa).
fn mean_pressure(sim: &Simulation, tool: &str) -> f64 {
    let name = format!("{tool}.pressure_mean_Pa");
    let column = rkforge_core::outputs::columns(sim.scene())
        .into_iter()
        .find(|c| c.name == name)
        .unwrap();
    assert_eq!(column.unit(), "Pa");
    column.value(&rkforge_core::outputs::Sample::new(sim))
}

/// The block of the test above through the register's mean contact pressure: the normal
/// force over the contact length times the depth gives the plane-strain flow stress of
/// homogeneous compression at the strain reached, `(2 / sqrt 3) sigma_y((2 / sqrt 3) ln(h0 /
/// h))`, and the contact length is the block's width.
#[test]
fn the_mean_pressure_of_frictionless_plane_strain_upsetting_is_the_flow_stress() {
    let scene = shipped(
        "block_forging",
        &[
            "workpiece.particles=[15,15]",
            "tools.top.friction=0.0",
            "tools.bottom.friction=0.0",
            "time.end_s=5.0e-3",
        ],
    );
    let mut sim = Simulation::new(&scene).unwrap();
    assert_eq!(mean_pressure(&sim, "top"), 0.0, "no contact, no pressure");
    sim.run_to(scene.time.end_s, |_| {}).unwrap();
    let e = sim.extents();
    let (width, height) = (e.x[1] - e.x[0], e.y[1] - e.y[0]);
    let eps = 2.0 / 3f64.sqrt() * (0.5 / height).ln();
    let expected = 2.0 / 3f64.sqrt() * (400.0e6 + 100.0e6 * eps);
    for tool in ["top", "bottom"] {
        let k = sim.tool_index(tool).unwrap();
        let t = &sim.tools()[k];
        // A flat frictionless tool: the normal force is the force along its normal.
        let normal = t.state.normal_force;
        assert!(
            (normal / t.axial_force().abs() - 1.0).abs() < 1e-9,
            "{normal}"
        );
        let length = sim.contact_length(k);
        let h = sim.spacing()[0];
        assert!((length - width).abs() < 0.2 * h, "{length} vs {width} m");
        let p = mean_pressure(&sim, tool);
        println!(
            "{tool}: mean pressure {p:.4e} Pa, (2 / sqrt 3) sigma_y = {expected:.4e} Pa ({:+.2} %), \
             contact {length:.4} m of the width {width:.4} m, height {height:.4} m",
            100.0 * (p / expected - 1.0)
        );
        assert!((p / expected - 1.0).abs() < 0.01, "{p} vs {expected}");
    }
}

/// Frictionless axisymmetric upsetting of the press scene's aluminium billet (40 x 60 mm,
/// power-law hardening) by 20 %: the mean pressure on each die is the flow stress of
/// homogeneous compression, `sigma_y = K (eps0 + ln(h0 / h))^n`, and the contact area, the
/// bands the top face's segments sweep about the axis, is the disc `pi R^2` of the current
/// radius.
#[test]
fn the_mean_pressure_of_frictionless_axisymmetric_upsetting_is_the_flow_stress() {
    let scene = shipped(
        "press_upsetting",
        &[
            "tools.anvil.friction=0.0",
            "tools.ram.friction=0.0",
            "time.end_s=0.6",
        ],
    );
    let mut sim = Simulation::new(&scene).unwrap();
    sim.run_to(scene.time.end_s, |_| {}).unwrap();
    let e = sim.extents();
    let (radius, height) = (e.x[1], e.y[1] - e.y[0]);
    let eps = (0.060 / height).ln();
    let expected = 576.79e6 * (0.01658 + eps).powf(0.3593);
    for tool in ["anvil", "ram"] {
        let k = sim.tool_index(tool).unwrap();
        let t = &sim.tools()[k];
        let normal = t.state.normal_force;
        assert!(
            (normal / t.axial_force().abs() - 1.0).abs() < 1e-9,
            "{normal}"
        );
        let area = rkforge_core::outputs::contact_area(&sim, k);
        let disc = std::f64::consts::PI * radius * radius;
        let p = mean_pressure(&sim, tool);
        println!(
            "{tool}: mean pressure {p:.4e} Pa, sigma_y = {expected:.4e} Pa ({:+.2} %), \
             area {area:.4e} m^2 = {:.4} pi R^2, R {radius:.5} m, height {height:.5} m",
            100.0 * (p / expected - 1.0),
            area / disc
        );
        assert!((area / disc - 1.0).abs() < 0.01, "{area} vs {disc}");
        assert!((p / expected - 1.0).abs() < 0.01, "{p} vs {expected}");
    }
}
