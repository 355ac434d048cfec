use rkforge_core::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut scene = Scene::from_file(std::path::Path::new(&args[1])).unwrap();
    if let Some(r) = args.get(2) {
        scene = scene.with_integration(IntegrationRule::parse(r).unwrap());
    }
    if let Some(s) = args.get(3) {
        let s: f64 = s.parse().unwrap();
        scene.discretization.support = [s, s];
    }
    let t0 = std::time::Instant::now();
    let mut sim = Simulation::new(&scene).unwrap();
    let end = scene.time.end_s;
    let mut next = 0.0;
    let res = sim.run_to(end, |s| {
        if s.time() >= next {
            next += 10e-6;
            let e = s.energy(); let x = s.extents();
            println!("t={:.1}us r={:.3}mm h={:.3}mm KE={:.2} el={:.2} pl={:.2} W={:.2} err={:.2e} eps={:.2}", s.time()*1e6, x.x[1]*1e3, (x.y[1]-x.y[0])*1e3, e.kinetic, e.elastic, e.plastic, e.contact_work, e.balance_error_rel(), s.max_plastic_strain());
        }
    });
    println!(
        "{:?} dt0={:.4e} h/c={:.4e}",
        res,
        sim.critical_dt0(),
        0.16e-3 / 4586.0
    );
    let x = sim.extents();
    let v0 = 3.14159265 * 0.0032f64.powi(2) * 0.0324;
    println!("final r={:.4}mm h={:.4}mm vol={:.4e} rel={:.3e} eps_max={:.3} wall={:.2}s times={:?} pts={} entries={}", x.x[1]*1e3, (x.y[1]-x.y[0])*1e3, sim.volume(), sim.volume()/v0-1.0, sim.max_plastic_strain(), t0.elapsed().as_secs_f64(), sim.times, sim.point_count(), sim.point_shapes().entries());
}
