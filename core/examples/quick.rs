//! Development driver: run a scene and print a coarse history (not part of the product).
use rkforge_core::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut scene = Scene::from_file(std::path::Path::new(&args[1])).unwrap();
    if let Some(r) = args.get(2) {
        scene = scene.with_integration(IntegrationRule::parse(r).unwrap());
    }
    let t0 = std::time::Instant::now();
    let mut sim = Simulation::new(&scene).unwrap();
    let end = scene.time.end_s;
    let n = 10;
    for k in 1..=n {
        let res = sim.run_to(end * k as f64 / n as f64, |_| {});
        let e = sim.energy();
        let x = sim.extents();
        let f: Vec<String> = sim
            .tools()
            .iter()
            .map(|t| {
                format!(
                    "{}: s={:.4} F={:.4e}",
                    t.name,
                    t.state.stroke,
                    t.axial_force()
                )
            })
            .collect();
        println!(
            "t={:.3e} x=[{:.4},{:.4}] y=[{:.4},{:.4}] KE={:.3e} el={:.3e} pl={:.3e} W={:.3e} err={:.2e} eps={:.2} {} steps={}",
            sim.time(), x.x[0], x.x[1], x.y[0], x.y[1], e.kinetic, e.elastic, e.plastic, e.contact_work, e.balance_error_rel(), sim.max_plastic_strain(), f.join(" "), sim.steps()
        );
        if let Err(e) = res {
            println!("{e}");
            break;
        }
    }
    println!(
        "intvol={:.3e} vol={:.3e} wall={:.2}s dt0={:.3e} times={:?}",
        sim.integrated_volume() / sim.reference_volume() - 1.0,
        sim.volume() / sim.reference_volume() - 1.0,
        t0.elapsed().as_secs_f64(),
        sim.critical_dt0(),
        sim.times
    );
}
