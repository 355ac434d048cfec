//! Cost of one solver step against particle count and integration rule (issue 6).
//!
//! `cargo bench -p rkforge-core --bench step` (or `scripts/bench_scaling.sh`, which also
//! prints the table of docs/performance.md). Each case is the Taylor bar of
//! `scenes/taylor_bar.toml` (axisymmetric, wall contact, plastic foot) at a resolution
//! from 21 x 51 (1 071 particles) to 201 x 501 (100 701), advanced 20 steps into the impact
//! before timing, so contact and plasticity are active. Criterion's throughput is particles
//! per second: its inverse is the time per particle-step. Setup cost and memory per
//! particle are printed to stderr.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use rkforge_core::{IntegrationRule, Scene, Simulation};
use std::time::{Duration, Instant};

/// Particle grids (radial x axial), about 1 k, 4 k, 16 k, 64 k and 100 k particles.
const GRIDS: [[usize; 2]; 5] = [[21, 51], [41, 101], [81, 201], [161, 401], [201, 501]];

/// The Taylor bar at `grid` with `rule`, adaptive step, 20 steps into the impact.
fn taylor(grid: [usize; 2], rule: IntegrationRule) -> Simulation {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/taylor_bar.toml");
    let mut scene = Scene::from_file(std::path::Path::new(path))
        .expect("scenes/taylor_bar.toml")
        .with_integration(rule);
    scene.workpiece.particles = grid;
    scene.time.dt_s = None;
    let t0 = Instant::now();
    let mut sim = Simulation::new(&scene).expect("Taylor bar setup");
    let setup = t0.elapsed();
    for _ in 0..20 {
        sim.step(None).expect("Taylor bar step");
    }
    eprintln!(
        "{} {}x{}: {} particles, {} integration points, setup {:.3} s, memory {:.1} MB = {:.0} B/particle",
        rule.name(),
        grid[0],
        grid[1],
        sim.particle_count(),
        sim.point_count(),
        setup.as_secs_f64(),
        sim.memory_bytes() as f64 / 1e6,
        sim.memory_bytes() as f64 / sim.particle_count() as f64
    );
    sim
}

fn step_cost(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for rule in [
        IntegrationRule::Q4,
        IntegrationRule::Q2,
        IntegrationRule::Scni,
    ] {
        for grid in GRIDS {
            let mut sim = taylor(grid, rule);
            let particles = sim.particle_count();
            group.throughput(Throughput::Elements(particles as u64));
            group.bench_function(BenchmarkId::new(rule.name(), particles), |b| {
                b.iter(|| sim.step(None).expect("Taylor bar step"))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, step_cost);
criterion_main!(benches);
