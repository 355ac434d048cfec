//! Stabilization of nodal integration (`discretization.scni_stabilization`): the modified
//! stabilized conforming nodal integration (MSCNI) of Puso, Chen, Zywicz, Elmer (2008),
//! "Meshfree and finite element nodal integration methods", IJNME 74, 416-446, eq. (40), in
//! the total Lagrangian form of this solver, in two and three dimensions.
//!
//! SCNI's smoothed gradient averages the displacement gradient over a particle's whole
//! nodal domain, so a field that alternates from particle to particle along a free surface
//! (a saw-tooth) strains the domains little and costs little energy: under a die's drag the
//! top face of a forging takes it and folds. Each nodal domain `L` is cut into its `K`
//! orthants `k` (four quadrants in 2D, eight octants in 3D), each with its own smoothed
//! gradient `B^k_I = (1 / A_k) int_{dA_k} N_I n dG` (1/m,
//! [`crate::integration::orthant_shapes`] on a lattice,
//! [`crate::cylinder_grid::CylinderGrid::octant_domains`] on a cylinder); the saw-tooth
//! bends the orthants' gradients against each other while their mean barely moves. With
//! `T^k = G^k - G_L` the orthant's displacement gradient `G^k = sum_I d_I (x) B^k_I` (-)
//! less its domain's mean `G_L = sum_k w_k G^k / sum_k w_k`, the stabilization stores the
//! energy
//!
//! `W_s = sum_L sum_k (c mu / 2) w_k |T^k|^2` (J),
//!
//! `w_k` the orthant's volume weight (m^3), `mu` the shear modulus (Pa), `c` the scene's
//! coefficient (-). Its force on particle `I` is
//! `f_I = dW_s / dd_I = c mu sum_L sum_k w_k T^k B^k_I` (N); the mean's own term vanishes
//! because `sum_k w_k T^k = 0`. A rigid motion and any linear field give `T^k = 0` (each
//! orthant's smoothed gradient is exact for it), so the patch test and the consistency of
//! SCNI are kept; the energy enters the account as stored (elastic) energy. The gradients
//! are the reference configuration's, so `W_s` is a fixed quadratic form in the
//! coefficients: the stage applies its Hessian ([`Tables`]), assembled once at setup,
//! instead of forming the `K D^2` gradients of every domain at every step (in 3D a tenth
//! of the arithmetic).
//!
//! The energy is elastic in the whole gradient since the start, also where the metal flows:
//! a real flow that varies the gradient over half a spacing is resisted as well, in
//! proportion to `c`. Measured in `docs/forging.md` (the flash quarter model and the
//! paper's scenes), which is why the coefficient is the scene's choice and absent by
//! default. A form capped at a fraction of the flow stress (a Huber potential) was tried
//! and held the flash's top face only at `c = 1`, with the outline's volume 3-4 points
//! from the points' own.

use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::team::{part, Parts, Team};
use rayon::prelude::*;

/// Particles per block of the stage and of the setup (fixed, so the bits do not depend on
/// the number of threads).
const PARTICLES: usize = 128;

/// Running sums per row of the stage: entry `e` of a row goes to sum `e mod SUMS`, and the
/// sums are added pairwise at the end (a fixed order; four chains keep the fused
/// multiply-adds from waiting on each other).
const SUMS: usize = 4;

/// The stage's working arrays: the force and the energy of each block.
#[derive(Debug, Clone)]
pub(crate) struct Forces<const D: usize> {
    /// The stabilization's force on each particle (N), added to the internal force.
    pub force: Vec<[Real; D]>,
    /// `f_I . d_I` summed over each block of particles (J).
    work: Vec<Real>,
}

impl<const D: usize> Forces<D> {
    /// Zero arrays over `particles` particles.
    pub(crate) fn new(particles: usize) -> Forces<D> {
        Forces {
            force: vec![[0.0; D]; particles],
            work: vec![0.0; particles.div_ceil(PARTICLES)],
        }
    }

    /// Bytes held.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.force.len() * std::mem::size_of::<[Real; D]>() + self.work.len() * 8
    }
}

/// What the stage reads, fixed after setup: the stabilization's stiffness. `W_s` is a
/// quadratic form in the coefficients whose directions do not mix (`T^k_ij` takes
/// component `i` of the `d_I` only), so its Hessian is a scalar matrix per pair of
/// particles:
///
/// `W_s = 1/2 sum_i sum_I sum_J k_IJ d_I,i d_J,i`, `k_IJ = c mu sum_L sum_k w_k C^k_I . C^k_J`
/// (N/m),
///
/// `C^k_I = B^k_I - sum_m w_m B^m_I / sum_m w_m` (1/m) the orthant's gradient less the
/// domain's mean, and the force `f_I = sum_J k_IJ d_J` (N). The stage is then one sparse
/// product: two particles are coupled when a domain reaches both (81 per particle inside
/// a lattice in 2D, 729 in 3D).
#[derive(Debug, Clone)]
pub(crate) struct Tables<const D: usize> {
    /// Row `I`'s entries `rows[I]..rows[I + 1]`.
    rows: Vec<u32>,
    /// Each entry's particle `J`, ascending within a row.
    columns: Vec<u32>,
    /// Each entry's `k_IJ` (N/m).
    stiffness: Vec<Real>,
}

impl<const D: usize> Tables<D> {
    /// The stabilization of `particles` particles with coefficient `c` (-), shear modulus
    /// `mu` (Pa), orthant gradients `orthants` (rows `K L + k`, [`crate::integration::orthant_shapes`]) and weights
    /// `weights` (m^3, the same order; a domain of fewer than `K` orthants has empty rows of
    /// weight 0 after its own).
    pub(crate) fn new<const K: usize>(
        c: Real,
        mu: Real,
        orthants: &ShapeTable<D>,
        weights: &[Real],
        particles: usize,
    ) -> Tables<D> {
        let domains = orthants.rows() / K;
        // Each domain's particles (ascending) with `C^k_I`.
        let mut by_domain = vec![0u32];
        let (mut members, mut centred) = (Vec::new(), Vec::new());
        let mut row: std::collections::BTreeMap<u32, [[Real; D]; K]> = Default::default();
        for l in 0..domains {
            row.clear();
            for k in 0..K {
                for e in orthants.row(K * l + k) {
                    let b = row.entry(orthants.index[e]).or_insert([[0.0; D]; K]);
                    for (j, column) in orthants.grad.iter().enumerate() {
                        b[k][j] = column[e];
                    }
                }
            }
            let w = &weights[K * l..K * (l + 1)];
            let total: Real = w.iter().sum();
            for (&i, b) in &row {
                let mean: [Real; D] =
                    std::array::from_fn(|j| (0..K).map(|k| w[k] * b[k][j]).sum::<Real>() / total);
                let centred_i: [[Real; D]; K] =
                    std::array::from_fn(|k| std::array::from_fn(|j| b[k][j] - mean[j]));
                members.push(i);
                centred.push(centred_i);
            }
            by_domain.push(members.len() as u32);
        }
        // The domains reaching each particle, ascending, with the particle's entry in each.
        let mut reach = vec![Vec::new(); particles];
        for l in 0..domains {
            for e in by_domain[l] as usize..by_domain[l + 1] as usize {
                reach[members[e] as usize].push((l, e));
            }
        }
        // Row I: the domains reaching I in ascending order, each one's particles J in
        // ascending order, k_IJ += sum_k sum_j (c mu w_k C^k_I,j) C^k_J,j.
        let blocks: Vec<(Vec<u32>, Vec<u32>, Vec<Real>)> = (0..particles.div_ceil(PARTICLES))
            .into_par_iter()
            .map(|b| {
                let (mut rows, mut columns, mut stiffness) = (Vec::new(), Vec::new(), Vec::new());
                let (mut acc, mut mark) = (vec![0.0; particles], vec![usize::MAX; particles]);
                let mut touched = Vec::new();
                for i in part(b, PARTICLES, particles) {
                    for &(l, at) in &reach[i] {
                        let w = &weights[K * l..K * (l + 1)];
                        let ci: [[Real; D]; K] =
                            std::array::from_fn(|k| centred[at][k].map(|x| c * mu * w[k] * x));
                        for e in by_domain[l] as usize..by_domain[l + 1] as usize {
                            // sum_k sum_j in four running sums (the K D products come in
                            // fours: D K = 8 in 2D, 24 in 3D).
                            let mut sums = [0.0; 4];
                            let lanes = ci.as_flattened().chunks_exact(4);
                            for (a, b) in lanes.zip(centred[e].as_flattened().chunks_exact(4)) {
                                for ((s, x), y) in sums.iter_mut().zip(a).zip(b) {
                                    *s += x * y;
                                }
                            }
                            let s = (sums[0] + sums[1]) + (sums[2] + sums[3]);
                            let j = members[e] as usize;
                            if mark[j] != i {
                                mark[j] = i;
                                touched.push(j as u32);
                            }
                            acc[j] += s;
                        }
                    }
                    touched.sort_unstable();
                    rows.push(touched.len() as u32);
                    for &j in &touched {
                        columns.push(j);
                        stiffness.push(acc[j as usize]);
                        acc[j as usize] = 0.0;
                    }
                    touched.clear();
                }
                (rows, columns, stiffness)
            })
            .collect();
        let mut t = Tables {
            rows: vec![0],
            columns: Vec::new(),
            stiffness: Vec::new(),
        };
        for (lengths, columns, stiffness) in blocks {
            for n in lengths {
                let last = *t.rows.last().unwrap_or(&0);
                t.rows.push(last + n);
            }
            t.columns.extend(columns);
            t.stiffness.extend(stiffness);
        }
        t
    }

    /// Bytes held.
    pub(crate) fn memory_bytes(&self) -> usize {
        (self.rows.len() + self.columns.len()) * 4 + self.stiffness.len() * 8
    }
}

/// The stabilization stage of `t` on the displacement coefficients `d` (m): fills `s.force`
/// (N) with `f_I = sum_J k_IJ d_J` and returns the stored energy `W_s = 1/2 sum_I f_I . d_I`
/// (J). One parallel phase over fixed blocks of particles, the blocks' work added in block
/// order. Every product is a fused multiply-add, so the AVX2 build (`avx2`, where the CPU
/// has it) gives the same bits as the portable one.
pub(crate) fn stage<const D: usize>(
    team: &Team,
    t: &Tables<D>,
    s: &mut Forces<D>,
    d: &[[Real; D]],
    avx2: bool,
) -> Real {
    let np = d.len();
    {
        let (force, work) = (Parts::new(&mut s.force), Parts::new(&mut s.work));
        // On the team at every size: a row costs 81 (2D) to 729 (3D) products a component,
        // far more than the particle phases that stay on one thread below
        // `PARALLEL_PARTICLES`.
        team.for_each(np.div_ceil(PARTICLES), &|b| {
            let range = part(b, PARTICLES, np);
            // SAFETY: block `b` alone takes these particles and its work slot.
            let (fs, w) = unsafe { (force.get(range.clone()), &mut work.get(b..b + 1)[0]) };
            *w = match avx2 {
                // SAFETY: `avx2` only where the CPU has AVX2 and FMA (the caller checks).
                true => unsafe { rows_avx2(t, d, range, fs) },
                false => rows(t, d, range, fs),
            };
        });
    }
    0.5 * s.work.iter().sum::<Real>()
}

/// The force `f_I = sum_J k_IJ d_J` (N) on the particles of `range` into `fs`, and `sum_I
/// f_I . d_I` over them (J).
#[inline(always)]
fn rows<const D: usize>(
    t: &Tables<D>,
    d: &[[Real; D]],
    range: std::ops::Range<usize>,
    fs: &mut [[Real; D]],
) -> Real {
    let mut work = 0.0;
    for (i, f) in range.zip(fs.iter_mut()) {
        let entries = t.rows[i] as usize..t.rows[i + 1] as usize;
        let mut sums = [[0.0; D]; SUMS];
        let add = |sum: &mut [Real; D], j: u32, k: Real| {
            for (s, x) in sum.iter_mut().zip(d[j as usize]) {
                *s = k.mul_add(x, *s);
            }
        };
        let (columns, stiffness) = (&t.columns[entries.clone()], &t.stiffness[entries]);
        let (full, rest) = (columns.chunks_exact(SUMS), stiffness.chunks_exact(SUMS));
        let (tail_columns, tail_stiffness) = (full.remainder(), rest.remainder());
        for (js, ks) in full.zip(rest) {
            for ((sum, &j), &k) in sums.iter_mut().zip(js).zip(ks) {
                add(sum, j, k);
            }
        }
        for ((sum, &j), &k) in sums.iter_mut().zip(tail_columns).zip(tail_stiffness) {
            add(sum, j, k);
        }
        *f = std::array::from_fn(|c| (sums[0][c] + sums[1][c]) + (sums[2][c] + sums[3][c]));
        for (fc, dc) in f.iter().zip(&d[i]) {
            work = fc.mul_add(*dc, work);
        }
    }
    work
}

/// [`rows`] compiled for AVX2 and FMA.
///
/// # Safety
///
/// The CPU must support AVX2 and FMA.
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2,fma"))]
unsafe fn rows_avx2<const D: usize>(
    t: &Tables<D>,
    d: &[[Real; D]],
    range: std::ops::Range<usize>,
    fs: &mut [[Real; D]],
) -> Real {
    rows(t, d, range, fs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integration::orthant_shapes;
    use crate::rk_shape::{Lattice, ShapeTable};

    /// A lattice of spacing `h` with `n` particles per direction, its orthants (gradients
    /// and weights) and their stabilization (`c mu` = 1 Pa).
    #[allow(clippy::type_complexity)]
    fn patch<const D: usize, const K: usize>(
        n: [usize; D],
        h: [Real; D],
    ) -> (Lattice<D>, ShapeTable<D>, Vec<Real>, Tables<D>, Forces<D>) {
        let lattice = Lattice::new([0.0; D], h, n, h.map(|hk| 2.0 * hk));
        let (orthants, table) = orthant_shapes::<D, K>(&lattice).unwrap();
        let np = n.iter().product();
        let t = Tables::new::<K>(1.0, 1.0, &table, &orthants.areas, np);
        (lattice, table, orthants.areas, t, Forces::new(np))
    }

    /// The energy of the definition, `W_s = sum_L sum_k (c mu / 2) w_k |G^k - G_L|^2` with
    /// `G^k = sum_I d_I (x) B^k_I` and `G_L` the weighted mean (J; `c mu` = 1 Pa), straight
    /// from the orthants' gradients: the reference the stiffness is checked against.
    fn energy_by_definition<const D: usize, const K: usize>(
        table: &ShapeTable<D>,
        weights: &[Real],
        d: &[[Real; D]],
    ) -> Real {
        let mut energy = 0.0;
        for l in 0..table.rows() / K {
            let g: Vec<[[Real; D]; D]> = (0..K)
                .map(|k| {
                    let mut g = [[0.0; D]; D];
                    for e in table.row(K * l + k) {
                        for (i, gi) in g.iter_mut().enumerate() {
                            for (j, gij) in gi.iter_mut().enumerate() {
                                *gij += d[table.index[e] as usize][i] * table.grad[j][e];
                            }
                        }
                    }
                    g
                })
                .collect();
            let w = &weights[K * l..K * (l + 1)];
            let total: Real = w.iter().sum();
            for (wk, gk) in w.iter().zip(&g) {
                for (i, gki) in gk.iter().enumerate() {
                    for (j, gkij) in gki.iter().enumerate() {
                        let mean: Real =
                            w.iter().zip(&g).map(|(wm, gm)| wm * gm[i][j]).sum::<Real>() / total;
                        energy += 0.5 * wk * (gkij - mean).powi(2);
                    }
                }
            }
        }
        energy
    }

    /// Every orthant's smoothed gradient reproduces a linear field's gradient, and the
    /// orthants tile the body.
    fn each_orthant_reproduces_a_linear_gradient<const D: usize, const K: usize>(n: [usize; D]) {
        let (lattice, table, weights, _, _) = patch::<D, K>(n, [1e-3; D]);
        let x = &lattice.cloud().positions;
        let grad = |i: usize, j: usize| 0.1 * (1 + i) as Real - 0.07 * (j * j) as Real;
        let u = |p: [Real; D]| -> [Real; D] {
            std::array::from_fn(|i| (0..D).map(|j| grad(i, j) * p[j]).sum())
        };
        for q in 0..table.rows() {
            let mut g = [[0.0; D]; D];
            for e in table.row(q) {
                let ui = u(x[table.index[e] as usize]);
                for (gi, uik) in g.iter_mut().zip(ui) {
                    for (gij, column) in gi.iter_mut().zip(&table.grad) {
                        *gij += uik * column[e];
                    }
                }
            }
            for (i, gi) in g.iter().enumerate() {
                for (j, gij) in gi.iter().enumerate() {
                    assert!((gij - grad(i, j)).abs() < 1e-12, "orthant {q}: {g:?}");
                }
            }
        }
        let volume: Real = weights.iter().sum();
        let exact: Real = n.iter().map(|&nk| (nk - 1) as Real * 1e-3).product();
        assert!(
            (volume - exact).abs() < 1e-12 * exact,
            "{volume} vs {exact}"
        );
    }

    #[test]
    fn each_quadrant_reproduces_a_linear_gradient() {
        each_orthant_reproduces_a_linear_gradient::<2, 4>([9, 7]);
    }

    #[test]
    fn each_octant_reproduces_a_linear_gradient() {
        each_orthant_reproduces_a_linear_gradient::<3, 8>([5, 4, 6]);
    }

    /// A linear field and a rigid motion (the RK coefficients of a linear field are its
    /// nodal values, linear basis) store no energy and feel no force.
    fn linear_fields_cost_nothing<const D: usize, const K: usize>(n: [usize; D]) {
        let (lattice, _, _, t, mut s) = patch::<D, K>(n, [1e-3; D]);
        let d: Vec<[Real; D]> = lattice
            .cloud()
            .positions
            .iter()
            .map(|p| {
                std::array::from_fn(|i| {
                    (1.0 - 3.0 * i as Real) * 1e-4
                        + (0..D)
                            .map(|j| (0.01 + 0.005 * i as Real - 0.02 * j as Real) * p[j])
                            .sum::<Real>()
                })
            })
            .collect();
        for avx2 in [false, crate::solver::stress::has_avx2()] {
            let w = stage(&Team::default(), &t, &mut s, &d, avx2);
            assert!(w.abs() < 1e-20, "energy {w}");
            let f = s
                .force
                .iter()
                .flatten()
                .fold(0.0, |m: Real, x| m.max(x.abs()));
            assert!(f < 1e-15, "force {f}");
        }
    }

    #[test]
    fn a_linear_field_and_a_rigid_motion_cost_nothing() {
        linear_fields_cost_nothing::<2, 4>([9, 7]);
    }

    #[test]
    fn a_linear_field_costs_nothing_in_three_dimensions() {
        linear_fields_cost_nothing::<3, 8>([5, 4, 6]);
    }

    /// A scattered field and a saw-tooth of the top layer (particles alternating up and
    /// down) on an unequal lattice: the stage's energy is the definition's, and its force
    /// the definition's gradient (central differences); the saw-tooth stores energy; the
    /// AVX2 build gives the same bits.
    fn the_stiffness_is_the_energys_hessian<const D: usize, const K: usize>(
        n: [usize; D],
        probe: [usize; 3],
    ) {
        let h: [Real; D] = std::array::from_fn(|k| 1e-3 * (1.0 + 0.3 * k as Real));
        let (_, table, weights, t, mut s) = patch::<D, K>(n, h);
        let np: usize = n.iter().product();
        let top = np - np / n[D - 1];
        let scattered: Vec<[Real; D]> = (0..np as u64)
            .map(|i| {
                std::array::from_fn(|c| {
                    ((i * 2654435761 + 40503 * c as u64) % 1000) as Real * 1e-8 - 5e-6
                })
            })
            .collect();
        let saw: Vec<[Real; D]> = (0..np)
            .map(|i| {
                let mut di = [0.0; D];
                if i >= top {
                    di[D - 1] = if i % 2 == 0 { 1e-5 } else { -1e-5 };
                }
                di
            })
            .collect();
        let team = Team::default();
        for d in [scattered, saw] {
            let w = stage(&team, &t, &mut s, &d, false);
            let reference = energy_by_definition::<D, K>(&table, &weights, &d);
            assert!(w > 0.0);
            assert!(
                (w - reference).abs() < 1e-10 * reference,
                "{w} vs {reference}"
            );
            let force = s.force.clone();
            let largest = force
                .iter()
                .flatten()
                .fold(0.0, |m: Real, x| m.max(x.abs()));
            let step = 1e-9;
            for i in probe {
                for c in 0..D {
                    let (mut up, mut down) = (d.clone(), d.clone());
                    up[i][c] += step;
                    down[i][c] -= step;
                    let fd = (energy_by_definition::<D, K>(&table, &weights, &up)
                        - energy_by_definition::<D, K>(&table, &weights, &down))
                        / (2.0 * step);
                    assert!(
                        (fd - force[i][c]).abs() < 1e-6 * largest,
                        "particle {i}.{c}: {fd} vs {}",
                        force[i][c]
                    );
                }
            }
            if crate::solver::stress::has_avx2() {
                let w2 = stage(&team, &t, &mut s, &d, true);
                assert_eq!(w.to_bits(), w2.to_bits());
                assert_eq!(force, s.force);
            }
        }
    }

    #[test]
    fn the_plane_stiffness_is_the_energys_hessian() {
        the_stiffness_is_the_energys_hessian::<2, 4>([9, 7], [58, 60, 31]);
    }

    #[test]
    fn the_solid_stiffness_is_the_energys_hessian() {
        the_stiffness_is_the_energys_hessian::<3, 8>([5, 4, 6], [100, 117, 47]);
    }
}
