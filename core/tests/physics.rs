//! Physics validation of the solver against references: patch test, spurious modes,
//! the axis condition, a coarse Taylor bar against the paper's Table 3, bitwise restore
//! and thread-count independence.

mod common;

use rkforge_core::rk_shape::Lattice;
use rkforge_core::{IntegrationRule, Kinematics, Simulation};

const RULES: [IntegrationRule; 3] = [
    IntegrationRule::Q4,
    IntegrationRule::Q2,
    IntegrationRule::Scni,
];

/// Linear displacement `u = A X` on a free plane-strain patch (9 x 9 particles).
fn linear_patch(rule: IntegrationRule) -> (Simulation, [[f64; 2]; 2], Vec<[f64; 2]>) {
    let scene = common::patch(Kinematics::PlaneStrain, 9, rule, 2.0);
    let mut sim = Simulation::new(&scene).unwrap();
    let a = [[1e-4, 2e-4], [-0.5e-4, 3e-4]];
    let d = sim
        .reference_positions()
        .iter()
        .map(|x| {
            [
                a[0][0] * x[0] + a[0][1] * x[1],
                a[1][0] * x[0] + a[1][1] * x[1],
            ]
        })
        .collect();
    sim.set_displacement(d).unwrap();
    let f = sim.internal_forces().unwrap();
    (sim, a, f)
}

/// Patch test. RK shape functions reproduce the linear field exactly, so every point sees
/// the same F = I + A (checked through the physical displacement of every particle) and
/// the internal forces balance exactly: globally (sum and moment), and on every particle
/// whose support does not reach the boundary. Near the boundary, Gauss-integrated RKPM
/// violates the integration constraint `sum_p grad N_I w_p = int_G N_I n dG` (Chen et al.
/// 2001): the residual against the consistent traction load is measured and bounded (it
/// is what SCNI removes).
#[test]
fn patch_test_linear_field_constant_strain_and_balance() {
    for rule in RULES {
        let (sim, a, f) = linear_patch(rule);
        // Physical displacement reproduces A X at every particle.
        let x = sim.positions();
        for (xi, x0) in x.iter().zip(sim.reference_positions()) {
            let ux = a[0][0] * x0[0] + a[0][1] * x0[1];
            let uy = a[1][0] * x0[0] + a[1][1] * x0[1];
            assert!((xi[0] - x0[0] - ux).abs() < 1e-16 && (xi[1] - x0[1] - uy).abs() < 1e-16);
        }
        let fmax = f.iter().map(|v| v[0].hypot(v[1])).fold(0.0, f64::max);
        assert!(fmax > 1e4, "the patch is loaded: {fmax}");
        // Global balance: sum of forces and moment vanish.
        let (mut sx, mut sy, mut m) = (0.0, 0.0, 0.0);
        for (fi, xi) in f.iter().zip(&x) {
            sx += fi[0];
            sy += fi[1];
            m += xi[0] * fi[1] - xi[1] * fi[0];
        }
        assert!(
            sx.abs() < 1e-12 * fmax * 81.0 && sy.abs() < 1e-12 * fmax * 81.0,
            "{rule:?}: sum {sx} {sy}"
        );
        assert!(m.abs() < 1e-10 * fmax * 0.01 * 81.0, "{rule:?}: moment {m}");
        // Interior particles (support clear of the boundary): exact balance.
        let (nx, ny) = sim.grid();
        for (i, fi) in f.iter().enumerate() {
            let (ix, iy) = (i % nx, i / nx);
            if ix.min(iy).min(nx - 1 - ix).min(ny - 1 - iy) >= 4 {
                assert!(
                    fi[0].hypot(fi[1]) < 1e-10 * fmax,
                    "{rule:?}: particle {i}: {fi:?}"
                );
            }
        }
        // Residual against the consistent boundary load int_G N_I (sigma n) dG, with the
        // Cauchy stress of the (uniform) deformation recovered from one point's forces.
        // Measured: q4 1.35 %, q2 9.2 % (the diagonal rule's xi*eta error is systematic),
        // scni 0.04 %.
        let residual = boundary_residual(&sim, &f);
        println!(
            "{rule:?}: largest out-of-balance near the boundary {:.2} % of the largest nodal force",
            residual / fmax * 100.0
        );
        let bound = match rule {
            IntegrationRule::Q4 => 0.02,
            IntegrationRule::Q2 => 0.10,
            // SCNI satisfies the integration constraint with its own boundary quadrature
            // (interior edges cancel exactly); what remains, measured 0.04 %, is the gap
            // between its 3-point edge rule and this test's 8-point boundary integral.
            IntegrationRule::Scni => 0.002,
        };
        assert!(residual < bound * fmax, "{rule:?}: {residual} vs {fmax}");
    }
}

/// Largest `|f_int_I - f_ext_I|` with `f_ext_I = int_G N_I P N dG` (first Piola-Kirchhoff
/// traction on the reference boundary), 1D Gauss with 8 points per particle spacing.
fn boundary_residual(sim: &Simulation, f: &[[f64; 2]]) -> f64 {
    let h = sim.spacing();
    let (nx, ny) = sim.grid();
    let x0 = sim.reference_positions();
    let s = sim.scene().discretization.support;
    let lattice = Lattice::new(x0[0], h, [nx, ny], [s[0] * h[0], s[1] * h[1]]);
    let cloud = lattice.cloud();
    // Uniform P from the material at F = I + A (plane strain).
    let p = {
        let mut g = [1.0, 0.0, 0.0, 1.0];
        for (i, [_, dx, dy]) in sim.point_shapes(0) {
            let di = sim.state().d[i];
            g[0] += di[0] * dx;
            g[1] += di[0] * dy;
            g[2] += di[1] * dx;
            g[3] += di[1] * dy;
        }
        let mut st = rkforge_core::material::PointState::default();
        sim.material().update(g, 1.0, &mut st).unwrap().piola
    };
    let (gx, gw) = gauss8();
    let (lo, hi) = (x0[0], x0[x0.len() - 1]);
    let mut fext = vec![[0.0; 2]; x0.len()];
    // Edges: (start, end, outward normal N).
    let edges = [
        ([lo[0], lo[1]], [hi[0], lo[1]], [0.0, -1.0]),
        ([hi[0], lo[1]], [hi[0], hi[1]], [1.0, 0.0]),
        ([hi[0], hi[1]], [lo[0], hi[1]], [0.0, 1.0]),
        ([lo[0], hi[1]], [lo[0], lo[1]], [-1.0, 0.0]),
    ];
    for (a, b, n) in edges {
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        let segs = ((len / h[0].min(h[1])).round() as usize).max(1);
        let mut pts = Vec::new();
        let mut wts = Vec::new();
        for k in 0..segs {
            for (xi, w) in gx.iter().zip(&gw) {
                let t = (k as f64 + 0.5 * (xi + 1.0)) / segs as f64;
                pts.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
                wts.push(w * 0.5 * len / segs as f64);
            }
        }
        let table = cloud
            .shape_table(&pts, &|q| format!("boundary point {q}"))
            .unwrap();
        let t = [p[0] * n[0] + p[1] * n[1], p[2] * n[0] + p[3] * n[1]];
        for (q, w) in wts.iter().enumerate() {
            for e in table.row(q) {
                let i = table.index[e] as usize;
                fext[i][0] += table.n[e] * t[0] * w;
                fext[i][1] += table.n[e] * t[1] * w;
            }
        }
    }
    f.iter()
        .zip(&fext)
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .fold(0.0, f64::max)
}

fn gauss8() -> ([f64; 8], [f64; 8]) {
    (
        [
            -0.9602898564975363,
            -0.7966664774136267,
            -0.525_532_409_916_329,
            -0.1834346424956498,
            0.1834346424956498,
            0.525_532_409_916_329,
            0.7966664774136267,
            0.9602898564975363,
        ],
        [
            0.1012285362903763,
            0.2223810344533745,
            0.3137066458778873,
            0.362_683_783_378_362,
            0.362_683_783_378_362,
            0.3137066458778873,
            0.2223810344533745,
            0.1012285362903763,
        ],
    )
}

/// Small-strain stiffness of a free patch by central differences of the internal force
/// (amplitude small enough to stay linear elastic), symmetrised.
fn stiffness(sim: &mut Simulation) -> nalgebra::DMatrix<f64> {
    let n = 2 * sim.particle_count();
    let h = sim.spacing()[0];
    let eps = 1e-7 * h;
    let mut k = nalgebra::DMatrix::zeros(n, n);
    for c in 0..n {
        let mut col = [vec![[0.0; 2]; n / 2], vec![[0.0; 2]; n / 2]];
        for (s, sign) in [(0, 1.0), (1, -1.0)] {
            let mut d = vec![[0.0; 2]; n / 2];
            d[c / 2][c % 2] = sign * eps;
            sim.set_displacement(d).unwrap();
            col[s] = sim.internal_forces().unwrap();
        }
        for r in 0..n {
            k[(r, c)] = (col[0][r / 2][r % 2] - col[1][r / 2][r % 2]) / (2.0 * eps);
        }
    }
    (&k + k.transpose()) * 0.5
}

/// Spurious modes: the small-strain stiffness of a free patch has exactly the rigid-body
/// zero eigenvalues (3 in plane strain, 1 in axisymmetry: axial translation) with both
/// rules, and the next eigenvalue is clearly positive.
#[test]
fn no_spurious_zero_energy_modes() {
    for (kin, rigid) in [(Kinematics::PlaneStrain, 3), (Kinematics::Axisymmetric, 1)] {
        for rule in RULES {
            for n in [5, 7] {
                let mut sim = Simulation::new(&common::patch(kin, n, rule, 2.0)).unwrap();
                let mut ev: Vec<f64> = stiffness(&mut sim)
                    .symmetric_eigenvalues()
                    .iter()
                    .copied()
                    .collect();
                ev.sort_by(f64::total_cmp);
                let max = ev[ev.len() - 1];
                let zeros = ev.iter().filter(|e| e.abs() < 1e-8 * max).count();
                let first = ev[rigid] / max;
                println!("{kin:?} {rule:?} {n}x{n}: {zeros} zero eigenvalues, smallest deformation mode {first:.3e} of the largest");
                assert_eq!(
                    zeros,
                    rigid,
                    "{kin:?} {rule:?} {n}x{n}: eigenvalues {:?}",
                    &ev[..rigid + 2]
                );
                assert!(
                    first > 1e-4,
                    "{kin:?} {rule:?} {n}x{n}: near-zero mode {first:e}"
                );
                assert!(ev[0] > -1e-8 * max, "negative eigenvalue {}", ev[0]);
            }
        }
    }
}

/// Axis condition: the physical radial displacement (and velocity) of the particles on the
/// axis stays zero at every step of an impact, although their RK coefficients move.
#[test]
fn axis_particles_keep_zero_radial_displacement() {
    let mut scene = common::taylor(7, 15, IntegrationRule::Q2);
    scene.time.end_s = 10e-6;
    let mut sim = Simulation::new(&scene).unwrap();
    let (nx, ny) = sim.grid();
    let h = sim.spacing()[0];
    let mut coefficient_moved = 0.0_f64;
    for _ in 0..400 {
        sim.step(None).unwrap();
        let x = sim.positions();
        for j in 0..ny {
            let p = j * nx;
            assert!(
                x[p][0].abs() < 1e-12 * h,
                "axis particle {p}: r = {}",
                x[p][0]
            );
            coefficient_moved = coefficient_moved.max(sim.state().d[p][0].abs());
        }
        assert!(
            sim.constraint_residual() < 1e-9,
            "radial velocity {}",
            sim.constraint_residual()
        );
    }
    assert!(
        coefficient_moved > 1e-6 * h,
        "coefficients did move: the condition is on the physical field"
    );
}

/// A coarse Taylor bar (11 x 26 particles, adaptive step) against the paper's Table 3 and
/// the published spread, with volume and energy checks.
#[test]
fn coarse_taylor_bar_against_table_3() {
    for rule in RULES {
        let scene = common::taylor(11, 26, rule);
        let mut sim = Simulation::new(&scene).unwrap();
        let e0 = sim.energy().initial;
        assert!((e0 - 239.8).abs() < 0.2, "initial kinetic energy {e0}");
        sim.run_to(scene.time.end_s, |s| {
            assert!(s.energy().kinetic.is_finite());
        })
        .unwrap();
        let x = sim.extents();
        let (r, h) = (x.x[1] * 1e3, (x.y[1] - x.y[0]) * 1e3);
        let vol = sim.volume() / sim.reference_volume() - 1.0;
        let e = sim.energy();
        println!("{rule:?} 11x26: radius {r:.3} mm, height {h:.3} mm, volume {vol:.2e}, balance {:.2e}, eps_p max {:.2}", e.balance_error_rel(), sim.max_plastic_strain());
        // Coarse: a wider band than the 21 x 51 acceptance (7.00-7.25 / 21.35-21.70).
        assert!((6.8..7.5).contains(&r), "{rule:?}: radius {r}");
        assert!((21.2..21.9).contains(&h), "{rule:?}: height {h}");
        assert!(vol.abs() < 0.01, "volume change {vol}");
        assert!(
            e.balance_error_rel() < 0.01,
            "energy balance {}",
            e.balance_error_rel()
        );
        assert!(
            sim.max_plastic_strain() > 1.5,
            "foot strain {}",
            sim.max_plastic_strain()
        );
        assert!(
            e.kinetic < 0.02 * e0,
            "the bar has nearly stopped: {}",
            e.kinetic
        );
    }
}

/// Restoring a saved state continues bit for bit: the Taylor bar (linear hardening) and
/// the wheel forging (power law, whose cached flow stress the restore recomputes).
#[test]
fn restored_state_continues_bit_for_bit() {
    let mut taylor = common::taylor(7, 15, IntegrationRule::Q4);
    taylor.time.end_s = 20e-6;
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/wheel_forging.toml");
    let mut wheel = rkforge_core::Scene::from_file(std::path::Path::new(path)).unwrap();
    wheel.workpiece.particles = [12, 12];
    for (scene, steps) in [(taylor, 150), (wheel, 1500)] {
        let mut a = Simulation::new(&scene).unwrap();
        for _ in 0..steps {
            a.step(None).unwrap();
        }
        let saved = a.state().clone();
        assert!(
            saved.points.iter().any(|p| p.eps_p > 0.0),
            "{}: the saved state is plastic",
            scene.name
        );
        let mut b = Simulation::new(&scene).unwrap();
        b.restore(saved).unwrap();
        for _ in 0..steps {
            a.step(None).unwrap();
            b.step(None).unwrap();
        }
        assert_eq!(a.state(), b.state(), "{}", scene.name);
    }
}

/// Two simulations stepping at once in one 2-thread pool (each on a worker, each with its
/// own team, their helpers competing for the same workers) finish and give the bits of
/// one run alone; so does a simulation stepped from a thread outside any pool.
#[test]
fn simulations_sharing_a_pool_or_outside_it_give_the_bits_of_one_run() {
    let mut scene = common::taylor(41, 101, IntegrationRule::Q2);
    scene.time.end_s = 0.2e-6;
    let run = |scene: &rkforge_core::Scene| {
        let mut s = Simulation::new(scene).unwrap();
        s.run_to(scene.time.end_s, |_| {}).unwrap();
        s.state().clone()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let alone = pool.install(|| run(&scene));
    let (a, b) = pool.install(|| rayon::join(|| run(&scene), || run(&scene)));
    assert!(alone.step > 10, "{} steps", alone.step);
    assert_eq!(a, alone);
    assert_eq!(b, alone);
    let outside = std::thread::spawn(move || {
        let mut s = Simulation::new(&scene).unwrap();
        while s.time() < scene.time.end_s - 1e-18 {
            s.step(Some(scene.time.end_s - s.time())).unwrap();
        }
        s.state().clone()
    })
    .join()
    .unwrap();
    assert_eq!(outside, alone);
}

/// The same run on 1, 2 and 3 threads gives the same bits, with every rule: on the paper's
/// grid (1071 particles: stress phase on the team, particle phases on one thread) and on
/// 41 x 101 (4141 particles, above the 4096 where the force gather and predictor, contact
/// interpolation and update phases run on the team too).
#[test]
fn thread_count_does_not_change_the_bits() {
    for (nx, ny, end_s) in [(21, 51, 2e-6), (41, 101, 0.3e-6)] {
        for rule in [
            IntegrationRule::Q4,
            IntegrationRule::Q2,
            IntegrationRule::Scni,
        ] {
            let mut scene = common::taylor(nx, ny, rule);
            scene.time.end_s = end_s;
            let run = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                pool.install(|| {
                    let mut s = Simulation::new(&scene).unwrap();
                    s.run_to(scene.time.end_s, |_| {}).unwrap();
                    s.state().clone()
                })
            };
            let one = run(1);
            assert!(one.step > 20, "{nx}x{ny} {rule:?}: {} steps", one.step);
            assert_eq!(one, run(2), "{nx}x{ny} {rule:?}: 1 vs 2 threads");
            assert_eq!(one, run(3), "{nx}x{ny} {rule:?}: 1 vs 3 threads");
        }
    }
}
