//! Cost of the stress stage per integration point for each rule (issue 35).
//!
//! `cargo bench -p rkforge-core --bench stress`. The Taylor bar of `scenes/taylor_bar.toml`
//! at the paper's grid (21 x 51) and at 81 x 201, run 4 000 steps (20 us) into the impact
//! (the larger grid at a step smaller by the spacing), so the foot has yielded and keeps
//! yielding. Each sample starts from a copy of that state (not timed), takes one step to
//! wake its team, then steps on; what is timed is the stress stage of those steps
//! (deformation gradient, Hencky J2 update, scatter of the internal force: the run's own
//! `times.stress`), so the points yield as in a run. Criterion's throughput is
//! integration points per second: its inverse is the cost per point-step, which is what q2
//! has to match q4 in for its half of the points to halve the stage. Threads: rayon's
//! default (`RAYON_NUM_THREADS=1` for one core).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use rkforge_core::{IntegrationRule, Scene, Simulation};
use std::time::Duration;

/// Particle grids (radial x axial): the paper's and a 16 times larger one.
const GRIDS: [[usize; 2]; 2] = [[21, 51], [81, 201]];

/// The Taylor bar at `grid` with `rule`, 20 us into the impact.
fn taylor(grid: [usize; 2], rule: IntegrationRule) -> Simulation {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/taylor_bar.toml");
    let mut scene = Scene::from_file(std::path::Path::new(path))
        .expect("scenes/taylor_bar.toml")
        .with_integration(rule);
    let refine = grid[0] as f64 / scene.workpiece.particles[0] as f64;
    scene.workpiece.particles = grid;
    scene.time.dt_s = scene.time.dt_s.map(|dt| dt / refine);
    let mut sim = Simulation::new(&scene).expect("Taylor bar setup");
    sim.run_to(20e-6, |_| {}).expect("Taylor bar run");
    sim
}

fn stress_cost(c: &mut Criterion) {
    let mut group = c.benchmark_group("stress_stage");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for grid in GRIDS {
        for rule in [
            IntegrationRule::Q4,
            IntegrationRule::Q2,
            IntegrationRule::Scni,
        ] {
            let sim = taylor(grid, rule);
            let points = sim.point_count();
            eprintln!(
                "{} {}x{}: {} particles, {} integration points, largest plastic strain {:.3}",
                rule.name(),
                grid[0],
                grid[1],
                sim.particle_count(),
                points,
                sim.max_plastic_strain()
            );
            group.throughput(Throughput::Elements(points as u64));
            let id = BenchmarkId::new(rule.name(), format!("{}x{}", grid[0], grid[1]));
            group.bench_function(id, |b| {
                b.iter_custom(|steps| {
                    let mut s = sim.clone();
                    s.step(None).expect("Taylor bar step");
                    let before = s.times.stress;
                    for _ in 0..steps {
                        s.step(None).expect("Taylor bar step");
                    }
                    s.times.stress - before
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, stress_cost);
criterion_main!(benches);
