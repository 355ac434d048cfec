//! The 3D stress stage ([`Dim<3>`]) on a lattice patch, through the generic [`stage`]: a
//! linear displacement `d_I = A X_I` is reproduced as `F = I + A` at every point, and the
//! homogeneous stress it gives has the internal forces of a constant `P`: zero on the
//! interior particles, zero in sum, the traction `P n A` on each half of the patch; the
//! stored energy is `W(F) V`. The bits do not depend on the threads, on AVX2, nor on the
//! grouping of the points. On this patch (11 x 10 x 9 particles, unequal spacings,
//! support 2 h) q4 (5760 points), q2 (2880) and SCNI (990) all meet these to round-off:
//! interior forces at most 2e-12 |P| h_x h_y, tractions and energy within 5e-13.

use super::*;
use crate::integration::point_shapes;
use crate::material::simo1992_hencky_j2::tests::copper;
use crate::rk_shape::Lattice;
use crate::scene::IntegrationRule;

/// Particles per direction, spacings (m) and kernel support in spacings of the patch.
const N: [usize; 3] = [11, 10, 9];
const H: [Real; 3] = [1.0e-3, 1.2e-3, 0.9e-3];
const SUPPORT: Real = 2.0;

/// The displacement gradient `A` (row-major): small, so the response is elastic.
const A: [Real; 9] = [
    2.0e-4, -1.0e-4, 0.5e-4, 0.7e-4, -1.5e-4, 1.2e-4, -0.3e-4, 0.9e-4, 1.0e-4,
];

/// A patch's points of `rule`, its layout (chunks of 96 points) and `d_I = A X_I`.
struct Patch {
    lattice: Lattice<3>,
    weights: Vec<Real>,
    scatter: Scatter<3>,
    /// The same chunks with every point its own group.
    single: Scatter<3>,
    d: Vec<[Real; 3]>,
}

fn patch(rule: IntegrationRule) -> Patch {
    let lattice = Lattice::new([0.0; 3], H, N, H.map(|h| SUPPORT * h));
    let (points, pt) = point_shapes(&lattice, rule).unwrap();
    let particles = lattice.cloud().positions.len();
    let scatter = Scatter::new(&pt, particles, 96, MAX_GROUP_3D);
    let single = Scatter::new(&pt, particles, 96, 1);
    let d = (0..lattice.cloud().positions.len())
        .map(|i| {
            let x = lattice.cloud().positions[i];
            std::array::from_fn(|r| (0..3).map(|c| A[3 * r + c] * x[c]).sum())
        })
        .collect();
    Patch {
        lattice,
        weights: points.areas,
        scatter,
        single,
        d,
    }
}

/// What a run of the stage gives: the sums and the chunk buffers.
struct Run {
    sums: Sums,
    states: Vec<PointState3>,
    buf: Vec<[Real; 3]>,
    outs: Vec<PointOut>,
}

fn run(p: &Patch, sc: &Scatter<3>, material: &HenckyJ2, threads: usize, avx2: bool) -> Run {
    let points = p.weights.len();
    let (inv_radius, reference_jacobian) = (vec![0.0; points], vec![1.0; points]);
    let input = Inputs {
        d: &p.d,
        material,
        weights: &p.weights,
        inv_radius: &inv_radius,
        reference_jacobian: &reference_jacobian,
        track_stretch: true,
        axi: false,
        spacing: H,
        avx2: avx2 && has_avx2(),
        heating: None,
    };
    let mut states = vec![PointState3::default(); points];
    let mut outs = vec![PointOut::initial(material); points];
    let mut buf = sc.buffers();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let sums = pool
        .install(|| {
            stage(
                &Team::default(),
                sc,
                &mut buf,
                &input,
                &mut states,
                &mut outs,
                None,
            )
        })
        .unwrap();
    Run {
        sums,
        states,
        buf,
        outs,
    }
}

/// The particle forces (N): the chunk buffers summed per particle in chunk order.
fn forces(sc: &Scatter<3>, buf: &[[Real; 3]], particles: usize) -> Vec<[Real; 3]> {
    let mut f = vec![[0.0; 3]; particles];
    for c in 0..sc.lo.len() {
        let slice = &buf[sc.offsets[c]..sc.offsets[c + 1]];
        for (k, b) in slice.iter().enumerate() {
            let fi = &mut f[sc.lo[c] as usize + k];
            for r in 0..3 {
                fi[r] += b[r];
            }
        }
    }
    f
}

/// `F = I + A` at every point, to round-off: each group gathered as the stage gathers it.
#[test]
fn linear_displacements_give_their_gradient_at_every_point() {
    for rule in [
        IntegrationRule::Q4,
        IntegrationRule::Q2,
        IntegrationRule::Scni,
    ] {
        let p = patch(rule);
        let material = copper();
        let (inv_radius, reference_jacobian) = (vec![0.0; 0], vec![0.0; 0]);
        let input = Inputs {
            d: &p.d,
            material: &material,
            weights: &p.weights,
            inv_radius: &inv_radius,
            reference_jacobian: &reference_jacobian,
            track_stretch: false,
            axi: false,
            spacing: H,
            avx2: false,
            heating: None,
        };
        let cx = StressContext::new(&p.scatter, &input);
        let sc = &p.scatter;
        // Points per group size: a q4 cell's 8, two q2 cells' 4 each over the union of
        // their lists; SCNI points merged over the union of their lists.
        let mut sizes = [0usize; MAX_GROUP_3D + 1];
        for &g in &sc.group {
            sizes[g as usize] += g as usize;
        }
        eprintln!("{rule:?}: points in groups of 1..=8: {:?}", &sizes[1..]);
        match rule {
            IntegrationRule::Q4 => assert_eq!(sizes[8], sc.group.len()),
            IntegrationRule::Q2 => assert_eq!(sizes[8], sc.group.len()),
            _ => assert!(sizes[8] > sc.group.len() / 2, "{rule:?}: {sizes:?}"),
        }
        let (mut lanes, mut buf) = (Dim::<3>::batch(), sc.buffers());
        let mut worst: Real = 0.0;
        for first in (0..sc.group.len()).filter(|&q| sc.group[q] > 0) {
            let g = sc.group[first] as usize;
            let lo = sc.lo[first / sc.chunk] as usize;
            Dim::<3>::group::<false, false>(&cx, g, first, 0, &mut lanes, &mut buf, lo);
            for l in 0..g {
                for (c, (fc, a)) in lanes.f.iter().zip(A).enumerate() {
                    let exact = a + if c % 4 == 0 { 1.0 } else { 0.0 };
                    worst = worst.max((fc[l] - exact).abs());
                }
            }
        }
        assert!(worst < 1e-13, "{rule:?}: |F - (I + A)| = {worst:e}");
    }
}

/// The homogeneous stress of `F = I + A` through the whole stage: forces vanish on the
/// interior particles and in sum, each half of the patch carries the traction `P n A` of its
/// outer face, the energy is `W(F) V`; the bits do not depend on the threads nor on AVX2.
#[test]
fn homogeneous_stress_gives_the_forces_and_energy_of_a_constant_stress() {
    let material = copper();
    let f: [Real; 9] = std::array::from_fn(|c| A[c] + if c % 4 == 0 { 1.0 } else { 0.0 });
    let exact = material.update3(f, &mut PointState3::default()).unwrap();
    let piola = exact.piola;
    let scale = piola.iter().fold(0.0 as Real, |m, x| m.max(x.abs()));
    let extent: [Real; 3] = std::array::from_fn(|k| (N[k] - 1) as Real * H[k]);
    let volume = extent[0] * extent[1] * extent[2];
    for rule in [
        IntegrationRule::Q4,
        IntegrationRule::Q2,
        IntegrationRule::Scni,
    ] {
        let p = patch(rule);
        let r = run(&p, &p.scatter, &material, 1, true);
        let np = p.lattice.cloud().positions.len();
        let forces = forces(&p.scatter, &r.buf, np);
        // Bits: 2 threads, the generic build, every point its own group.
        for (threads, avx2, single) in [(2, true, false), (1, false, false), (1, true, true)] {
            let sc = if single { &p.single } else { &p.scatter };
            let other = run(&p, sc, &material, threads, avx2);
            let what = format!("{rule:?}: {threads} threads, AVX2 {avx2}, single {single}");
            assert_eq!(other.buf, r.buf, "{what}");
            assert_eq!(other.sums.elastic, r.sums.elastic, "{what}");
        }
        let force_scale = scale * H[0] * H[1];
        let node = |i: usize| [i % N[0], i / N[0] % N[1], i / (N[0] * N[1])];
        // Interior: each neighbour's neighbourhood is complete (2 supports from the faces).
        let reach = (2.0 * SUPPORT).ceil() as usize;
        let inner = |i: usize| {
            let n = node(i);
            (0..3).all(|k| n[k] >= reach && n[k] + reach < N[k])
        };
        let interior: Vec<usize> = (0..np).filter(|&i| inner(i)).collect();
        assert!(!interior.is_empty());
        let worst_interior = interior
            .iter()
            .flat_map(|&i| forces[i])
            .fold(0.0 as Real, |m, x| m.max(x.abs()));
        assert!(
            worst_interior < 1e-10 * force_scale,
            "{rule:?}: interior force {worst_interior:e} N"
        );
        let total: [Real; 3] = std::array::from_fn(|r| forces.iter().map(|f| f[r]).sum());
        for t in total {
            assert!(t.abs() < 1e-10 * force_scale, "{rule:?}: sum {total:?} N");
        }
        // The particles beyond the middle plane normal to e_k, on the side `sign`.
        let mut worst_traction: Real = 0.0;
        for k in 0..3 {
            let area = extent[(k + 1) % 3] * extent[(k + 2) % 3];
            for sign in [-1.0, 1.0] {
                let side = |i: usize| {
                    let twice = 2 * node(i)[k];
                    if sign > 0.0 {
                        twice > N[k] - 1
                    } else {
                        twice < N[k] - 1
                    }
                };
                let sum: [Real; 3] = std::array::from_fn(|r| {
                    (0..np).filter(|&i| side(i)).map(|i| forces[i][r]).sum()
                });
                for r in 0..3 {
                    let traction = sign * piola[3 * r + k] * area;
                    worst_traction = worst_traction.max((sum[r] - traction).abs() / (scale * area));
                }
            }
        }
        assert!(
            worst_traction < 1e-11,
            "{rule:?}: traction error {worst_traction:e} of |P| A"
        );
        let energy = exact.elastic_energy * volume;
        let energy_error = (r.sums.elastic - energy).abs() / energy;
        assert!(
            energy_error < 1e-12,
            "{rule:?}: energy {} J, W V {energy} J",
            r.sums.elastic
        );
        assert_eq!(r.sums.plastic, 0.0);
        // Every cell deformed alike: J, the smallest altitude of the parallelepiped of the
        // edges F h_k e_k (its volume over each face's area) and the largest stretch of F,
        // the square root of C = F^T F's largest eigenvalue.
        for out in &r.outs {
            assert!((out.jacobian - exact.jacobian).abs() < 1e-13);
        }
        let edge = |k: usize| -> [Real; 3] { std::array::from_fn(|r| f[3 * r + k] * H[k]) };
        let cross = |a: [Real; 3], b: [Real; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let norm = |a: [Real; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        let cell = exact.jacobian * H[0] * H[1] * H[2];
        let altitude = (0..3)
            .map(|k| cell / norm(cross(edge((k + 1) % 3), edge((k + 2) % 3))))
            .fold(Real::INFINITY, Real::min);
        assert!((r.sums.min_altitude - altitude).abs() < 1e-12 * altitude);
        // Largest eigenvalue of C in closed form (Smith 1961): q + 2 p cos(phi) with q =
        // tr C / 3, p^2 = |C - q I|^2 / 6, cos(3 phi) = det((C - q I) / p) / 2.
        let c = |a: usize, b: usize| (0..3).map(|r| f[3 * r + a] * f[3 * r + b]).sum::<Real>();
        let q = (c(0, 0) + c(1, 1) + c(2, 2)) / 3.0;
        let m = |a: usize, b: usize| c(a, b) - if a == b { q } else { 0.0 };
        let p2 = (0..9).map(|k| m(k / 3, k % 3).powi(2)).sum::<Real>() / 6.0;
        let det = m(0, 0) * (m(1, 1) * m(2, 2) - m(1, 2) * m(2, 1))
            - m(0, 1) * (m(1, 0) * m(2, 2) - m(1, 2) * m(2, 0))
            + m(0, 2) * (m(1, 0) * m(2, 1) - m(1, 1) * m(2, 0));
        let phi = (det / (2.0 * p2 * p2.sqrt())).clamp(-1.0, 1.0).acos() / 3.0;
        let stretch = (q + 2.0 * p2.sqrt() * phi.cos()).sqrt();
        assert!(
            (r.sums.max_stretch - stretch).abs() < 1e-12,
            "{} {stretch}",
            r.sums.max_stretch
        );
        eprintln!(
            "{rule:?}: {} points, largest interior force {:.1e} of |P| h^2, traction error \
             {worst_traction:.1e} of |P| A, energy error {energy_error:.1e}, smallest \
             altitude {:.6e} m, largest stretch {:.12}",
            p.weights.len(),
            worst_interior / force_scale,
            r.sums.min_altitude,
            r.sums.max_stretch
        );
    }
}

/// Plastic flow through the 3D stage under a deformation that varies from point to point
/// (`d_I = 40 A X_I` plus a wobble of 2 % of a spacing): every point its own group, 2
/// threads and the generic build give the bits of the grouped AVX2 stage.
#[test]
fn plastic_flow_keeps_the_bits_of_single_points_threads_and_builds() {
    let material = copper();
    for rule in [
        IntegrationRule::Q4,
        IntegrationRule::Q2,
        IntegrationRule::Scni,
    ] {
        let mut p = patch(rule);
        for (i, d) in p.d.iter_mut().enumerate() {
            for (r, dr) in d.iter_mut().enumerate() {
                let wobble = 0.02 * H[r] * ((i * (r + 3)) as Real * 0.7).sin();
                *dr = 40.0 * *dr + wobble;
            }
        }
        let r = run(&p, &p.scatter, &material, 1, true);
        assert!(r.sums.plastic > 0.0, "{rule:?}: plastic flow");
        let yielded = r.states.iter().filter(|s| s.eps_p > 0.0).count();
        assert!(
            yielded * 2 > r.states.len(),
            "{rule:?}: {yielded} points yielded"
        );
        for (threads, avx2, single) in [(1, true, true), (2, true, false), (1, false, true)] {
            let sc = if single { &p.single } else { &p.scatter };
            let other = run(&p, sc, &material, threads, avx2);
            let what = format!("{rule:?}: {threads} threads, AVX2 {avx2}, single {single}");
            assert_eq!(other.buf, r.buf, "{what}");
            assert_eq!(other.states, r.states, "{what}");
            assert_eq!(other.sums.elastic, r.sums.elastic, "{what}");
            assert_eq!(other.sums.plastic, r.sums.plastic, "{what}");
            assert_eq!(other.sums.min_altitude, r.sums.min_altitude, "{what}");
            assert_eq!(other.sums.max_stretch, r.sums.max_stretch, "{what}");
        }
    }
}
