//! The 3D solver on small scenes.

use super::*;
use crate::scene::SceneFile;

/// A coarse quarter Taylor bar (the paper's copper at 227 m/s on the FE wall).
pub(crate) fn quarter_bar(cells: [usize; 3], rule: &str, end_s: Real) -> SolidScene {
    let text = format!(
        r#"
name = "bar3d"
[model]
kinematics = "3d"
[workpiece]
shape = "cylinder"
radius_m = 0.0032
length_m = 0.0324
part = "quarter"
cells = {cells:?}
initial_velocity_m_per_s = [0.0, 0.0, -227.0]
[material]
density_kg_per_m3 = 8930.0
youngs_modulus_pa = 117e9
poisson_ratio = 0.35
hardening = {{ law = "linear", yield_stress_pa = 400e6, modulus_pa = 100e6 }}
[discretization]
integration = "{rule}"
[time]
end_s = {end_s:e}
dt_s = 5e-9
[[tools]]
name = "wall"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, -1.0]
motion = {{ kind = "fixed" }}
separation = false
"#
    );
    match SceneFile::from_str_named(&text, "bar3d.toml").unwrap() {
        SceneFile::Solid(s) => *s,
        SceneFile::Plane(_) => panic!("not 3D"),
    }
}

/// The coarse bar runs 2 us: the energy account closes, the impact face spreads, and no
/// particle lies inside the wall or beyond a symmetry plane by more than a tenth of a
/// spacing.
#[test]
fn a_coarse_quarter_bar_runs() {
    let scene = quarter_bar([4, 2, 16], "q2", 2e-6);
    let mut sim = SolidSimulation::new(&scene).unwrap();
    let b0 = sim.readings();
    let (r0, l0) = (b0.radius, b0.height());
    assert!(
        (r0 - 3.2e-3).abs() < 1e-12 && (l0 - 32.4e-3).abs() < 1e-12,
        "{r0} {l0}"
    );
    sim.run_toward(2e-6, u64::MAX, |_, _| true).unwrap();
    let b = sim.readings();
    let (r, l) = (b.radius, b.height());
    let (pen, beyond) = sim.measure_penetration().unwrap();
    let e = sim.energy();
    eprintln!(
        "r {r} l {l} pen {pen:e} beyond {beyond:e} balance {:e} dt0 {:e}",
        e.balance_error_rel(),
        sim.critical_dt0()
    );
    assert!(r > r0 && l < l0, "{r} {l}");
    assert!(e.balance_error_rel() < 0.01, "{e:?}");
}

/// The bits do not depend on the number of threads: the stress stage's chunks, the
/// particle phases' blocks and the contact stage's order are fixed.
#[test]
fn the_bits_do_not_depend_on_the_threads() {
    let scene = quarter_bar([4, 2, 16], "q4", 1e-6);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut sim = SolidSimulation::new(&scene).unwrap();
            sim.run_toward(1e-6, u64::MAX, |_, _| true).unwrap();
            sim.state().clone()
        })
    };
    let (one, two) = (run(1), run(2));
    assert!(one.step > 100);
    assert_eq!(one, two);
}

/// The points of an O-grid cell, each with its own particle list (the particles' supports
/// differ), are gathered as one group over the union of their lists.
#[test]
fn a_cells_points_are_one_group() {
    let scene = quarter_bar([8, 4, 20], "q2", 1e-7);
    let sim = SolidSimulation::new(&scene).unwrap();
    let groups = &sim.disc.scatter.group;
    let firsts = groups.iter().filter(|&&g| g > 0).count();
    assert_eq!(
        groups.iter().map(|&g| g as usize).sum::<usize>(),
        groups.len()
    );
    assert_eq!(
        firsts,
        groups.len() / 8,
        "{firsts} groups of {} points",
        groups.len()
    );
}

/// The particle means of point values: a uniform value reads back at every particle (each
/// particle is reached by points, the weights are a mean's) for the cell rules and SCNI's
/// nodal points; a value growing along z gives particle means growing along z, the highest
/// particles' above the lowest's.
#[test]
fn particle_means_are_weighted_means_of_the_points_around() {
    for rule in ["q2", "q4", "scni"] {
        let scene = quarter_bar([4, 2, 8], rule, 1e-7);
        let sim = SolidSimulation::new(&scene).unwrap();
        let uniform = sim.particle_means(&vec![2.5; sim.point_count()]);
        assert_eq!(uniform.len(), sim.particle_count());
        for (j, m) in uniform.iter().enumerate() {
            assert!((m - 2.5).abs() < 1e-12, "{rule}: particle {j}: {m}");
        }
        let z: Vec<Real> = sim.point_positions().iter().map(|p| p[2]).collect();
        let means = sim.particle_means(&z);
        let x = sim.reference_positions();
        let (low, high): (Vec<usize>, Vec<usize>) = (0..x.len())
            .filter(|&j| x[j][2] < 1e-9 || x[j][2] > 0.0324 - 1e-9)
            .partition(|&j| x[j][2] < 1e-9);
        let top = high
            .iter()
            .map(|&j| means[j])
            .fold(Real::INFINITY, Real::min);
        let bottom = low.iter().map(|&j| means[j]).fold(0.0, Real::max);
        assert!(
            bottom > 0.0 && top > bottom && top < 0.0324,
            "{rule}: {bottom} {top}"
        );
    }
}
