//! Contact pressure along a tool (`output.pressure_stations`): frictionless plane-strain
//! upsetting of the block between flat tools. The stations' normal forces add up to the
//! tool's force, the stations beyond the block carry none, and the mean pressure under the
//! block is the plane-strain flow stress `2 sigma_y / sqrt 3` of homogeneous compression
//! (the equivalent strain `(2 / sqrt 3) ln(h0 / h)`, linear hardening).

use rkforge_core::{SceneSource, Simulation};

#[test]
fn frictionless_upsetting_presses_at_the_plane_strain_flow_stress() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/block_forging.toml");
    let mut source = SceneSource::from_file(std::path::Path::new(path)).unwrap();
    for arg in [
        "workpiece.particles=[15,15]",
        "tools.top.friction=0.0",
        "tools.bottom.friction=0.0",
        "output.pressure_stations=40",
        "time.end_s=5.0e-3",
    ] {
        source.set_arg(arg).unwrap();
    }
    let scene = source.scene().clone();
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
