//! Stabilization of nodal integration (`discretization.scni_stabilization`): the modified
//! stabilized conforming nodal integration (MSCNI) of Puso, Chen, Zywicz, Elmer (2008),
//! "Meshfree and finite element nodal integration methods", IJNME 74, 416-446, eq. (40), in
//! the total Lagrangian form of this solver.
//!
//! SCNI's smoothed gradient averages the displacement gradient over a particle's whole
//! nodal domain, so a field that alternates from particle to particle along a free surface
//! (a saw-tooth) strains the domains little and costs little energy: under a die's drag the
//! top face of a forging takes it and folds. Each nodal domain `L` is cut into its four
//! quadrants `k`, each with its own smoothed gradient
//! `B^k_I = (1 / A_k) int_{dA_k} N_I n dG` (1/m, [`crate::integration::quadrant_shapes`]);
//! the saw-tooth bends the quadrants' gradients against each other while their mean barely
//! moves. With `T^k = G^k - G_L` the quadrant's displacement gradient
//! `G^k = sum_I d_I (x) B^k_I` (-) less its domain's mean `G_L = sum_k w_k G^k / sum_k w_k`,
//! the stabilization stores the energy
//!
//! `W_s = sum_L sum_k (c mu / 2) w_k |T^k|^2` (J),
//!
//! `w_k` the quadrant's volume weight (m^3), `mu` the shear modulus (Pa), `c` the scene's
//! coefficient (-). Its force on particle `I` is
//! `f_I = dW_s / dd_I = c mu sum_L sum_k w_k T^k B^k_I` (N); the mean's own term vanishes
//! because `sum_k w_k T^k = 0`. A rigid motion and any linear field give `T^k = 0` (each
//! quadrant's smoothed gradient is exact for it), so the patch test and the consistency of
//! SCNI are kept; the energy enters the account as stored (elastic) energy.
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
use crate::team::{part, particle_phase, Parts, Team};

/// Quadrants per nodal domain.
const QUADRANTS: usize = 4;

/// Nodal domains per block of the first phase (fixed, so the bits do not depend on the
/// number of threads).
const DOMAINS: usize = 64;

/// Particles per block of the second phase.
const PARTICLES: usize = 128;

/// The stage's working arrays: the quadrants' stresses and the force.
#[derive(Debug, Clone)]
pub(super) struct Forces {
    /// `c mu w_k T^k` of each domain's quadrants (N m): `[xX, xY]` of quadrants 0..3, then
    /// `[yX, yY]` of quadrants 0..3.
    stress: Vec<[Real; 4 * QUADRANTS]>,
    /// The stabilization's force on each particle (N), added to the internal force.
    pub force: Vec<[Real; 2]>,
}

impl Forces {
    /// Zero arrays for `tables` over `particles` particles.
    pub(super) fn new(tables: &Tables, particles: usize) -> Forces {
        Forces {
            stress: vec![[0.0; 4 * QUADRANTS]; tables.weights.len()],
            force: vec![[0.0; 2]; particles],
        }
    }

    /// Bytes held.
    pub(super) fn memory_bytes(&self) -> usize {
        self.stress.len() * 32 * QUADRANTS + self.force.len() * 16
    }
}

/// What the stage reads, fixed after setup: the coefficient, the weights and both orders of
/// the quadrants' smoothed gradients. A domain's four quadrants share one entry per
/// particle: `[B^0_x, B^0_y, B^1_x, B^1_y, B^2_x, B^2_y, B^3_x, B^3_y]` (1/m), zero for a
/// quadrant that does not involve the particle.
#[derive(Debug, Clone)]
pub(super) struct Tables {
    /// `c mu` (Pa).
    modulus: Real,
    /// `w_k` of quadrant `k` of domain `L` (m^3).
    weights: Vec<[Real; QUADRANTS]>,
    /// Domain `L`'s particles `particles[by_domain[L]..by_domain[L + 1]]` (ascending) and
    /// their gradients in `domain_gradients`.
    by_domain: Vec<u32>,
    particles: Vec<u32>,
    domain_gradients: Vec<[Real; 2 * QUADRANTS]>,
    /// The same entries by particle: the domains `domains[by_particle[I]..by_particle[I +
    /// 1]]` (ascending) whose quadrants involve `I`, with `B^k_I` in `particle_gradients`.
    by_particle: Vec<u32>,
    domains: Vec<u32>,
    particle_gradients: Vec<[Real; 2 * QUADRANTS]>,
}

impl Tables {
    /// The stabilization of `particles` particles with coefficient `c` (-), shear modulus
    /// `mu` (Pa), quadrant gradients `quadrants` (rows `4 L + k`) and weights `weights`
    /// (m^3, the same order).
    pub(super) fn new(
        c: Real,
        mu: Real,
        quadrants: &ShapeTable,
        weights: &[Real],
        particles: usize,
    ) -> Tables {
        let domain_count = quadrants.rows() / QUADRANTS;
        let mut by_domain = vec![0u32];
        let (mut members, mut domain_gradients) = (Vec::new(), Vec::new());
        let mut row: std::collections::BTreeMap<u32, [Real; 2 * QUADRANTS]> = Default::default();
        for l in 0..domain_count {
            row.clear();
            for k in 0..QUADRANTS {
                for e in quadrants.row(QUADRANTS * l + k) {
                    let b = row.entry(quadrants.index[e]).or_default();
                    b[2 * k] = quadrants.grad[0][e];
                    b[2 * k + 1] = quadrants.grad[1][e];
                }
            }
            for (&i, b) in &row {
                members.push(i);
                domain_gradients.push(*b);
            }
            by_domain.push(members.len() as u32);
        }
        let mut count = vec![0u32; particles + 1];
        for &i in &members {
            count[i as usize + 1] += 1;
        }
        for i in 0..particles {
            count[i + 1] += count[i];
        }
        let by_particle = count.clone();
        let (mut domains, mut particle_gradients) = (
            vec![0u32; members.len()],
            vec![[0.0; 2 * QUADRANTS]; members.len()],
        );
        for l in 0..domain_count {
            for e in by_domain[l] as usize..by_domain[l + 1] as usize {
                let i = members[e] as usize;
                let at = count[i] as usize;
                count[i] += 1;
                domains[at] = l as u32;
                particle_gradients[at] = domain_gradients[e];
            }
        }
        Tables {
            modulus: c * mu,
            weights: weights
                .chunks_exact(QUADRANTS)
                .map(|w| [w[0], w[1], w[2], w[3]])
                .collect(),
            by_domain,
            particles: members,
            domain_gradients,
            by_particle,
            domains,
            particle_gradients,
        }
    }

    /// Bytes held.
    pub(super) fn memory_bytes(&self) -> usize {
        let entry = 4 + 16 * QUADRANTS;
        (self.by_domain.len() + self.by_particle.len()) * 4
            + (self.particles.len() + self.domains.len()) * entry
            + self.weights.len() * 8 * QUADRANTS
    }
}

/// The stabilization stage of `t` on the displacement coefficients `d` (m): fills `s.force` (N)
/// and returns the stored energy `W_s` (J). Two parallel phases over fixed blocks: the
/// quadrants' gradients and stresses domain by domain, then each particle's force summed
/// over its domains in ascending order. Every product is a fused multiply-add, so the
/// AVX2 build (`avx2`, where the CPU has it) gives the same bits as the portable one.
pub(super) fn stage(team: &Team, t: &Tables, s: &mut Forces, d: &[[Real; 2]], avx2: bool) -> Real {
    let domains = t.weights.len();
    let blocks = domains.div_ceil(DOMAINS);
    let mut energies = vec![0.0; blocks];
    {
        let (stress, slots) = (Parts::new(&mut s.stress), Parts::new(&mut energies));
        particle_phase(team, d.len(), blocks, &|b| {
            let range = part(b, DOMAINS, domains);
            // SAFETY: block `b` alone takes these domains and its energy slot.
            let (out, energy) = unsafe { (stress.get(range.clone()), &mut slots.get(b..b + 1)[0]) };
            *energy = match avx2 {
                // SAFETY: `avx2` only where the CPU has AVX2 and FMA (the caller checks).
                true => unsafe { domains_avx2(t, d, range, out) },
                false => domain_stresses(t, d, range, out),
            };
        });
    }
    let np = d.len();
    let (force, stress) = (Parts::new(&mut s.force), &s.stress);
    particle_phase(team, np, np.div_ceil(PARTICLES), &|b| {
        let range = part(b, PARTICLES, np);
        // SAFETY: block `b` alone takes these particles.
        let fs = unsafe { force.get(range.clone()) };
        match avx2 {
            // SAFETY: as above.
            true => unsafe { particles_avx2(t, stress, range, fs) },
            false => particle_forces(t, stress, range, fs),
        }
    });
    energies.into_iter().sum()
}

/// The quadrants' gradients `G^k` of the domains in `range`, their stresses `c mu w_k T^k`
/// into `out`, and the domains' stored energy (J). A domain's gradients are summed as two
/// 8-lane vectors, `d_I,x [B^k_x, B^k_y]_k` and `d_I,y [B^k_x, B^k_y]_k`.
#[inline(always)]
fn domain_stresses(
    s: &Tables,
    d: &[[Real; 2]],
    range: std::ops::Range<usize>,
    out: &mut [[Real; 4 * QUADRANTS]],
) -> Real {
    let mut energy = 0.0;
    for (l, out) in range.zip(out.iter_mut()) {
        let (mut gx, mut gy) = ([0.0; 2 * QUADRANTS], [0.0; 2 * QUADRANTS]);
        for e in s.by_domain[l] as usize..s.by_domain[l + 1] as usize {
            let (di, bk) = (d[s.particles[e] as usize], &s.domain_gradients[e]);
            for j in 0..2 * QUADRANTS {
                gx[j] = di[0].mul_add(bk[j], gx[j]);
                gy[j] = di[1].mul_add(bk[j], gy[j]);
            }
        }
        let w = s.weights[l];
        let total = w[0] + w[1] + w[2] + w[3];
        let mut mean = [0.0; 4];
        for (k, wk) in w.iter().enumerate() {
            mean[0] = wk.mul_add(gx[2 * k], mean[0]);
            mean[1] = wk.mul_add(gx[2 * k + 1], mean[1]);
            mean[2] = wk.mul_add(gy[2 * k], mean[2]);
            mean[3] = wk.mul_add(gy[2 * k + 1], mean[3]);
        }
        for m in &mut mean {
            *m /= total;
        }
        for (k, wk) in w.iter().enumerate() {
            let t = [
                gx[2 * k] - mean[0],
                gx[2 * k + 1] - mean[1],
                gy[2 * k] - mean[2],
                gy[2 * k + 1] - mean[3],
            ];
            let scale = s.modulus * wk;
            out[2 * k] = scale * t[0];
            out[2 * k + 1] = scale * t[1];
            out[2 * QUADRANTS + 2 * k] = scale * t[2];
            out[2 * QUADRANTS + 2 * k + 1] = scale * t[3];
            let norm2 = t[0].mul_add(t[0], t[1].mul_add(t[1], t[2].mul_add(t[2], t[3] * t[3])));
            energy = (0.5 * scale).mul_add(norm2, energy);
        }
    }
    energy
}

/// The force on the particles of `range` (N) into `fs`: `f_I = sum_L sum_k (c mu w_k T^k)
/// B^k_I`, each domain's term an 8-lane product summed lane by lane.
#[inline(always)]
fn particle_forces(
    s: &Tables,
    stress: &[[Real; 4 * QUADRANTS]],
    range: std::ops::Range<usize>,
    fs: &mut [[Real; 2]],
) {
    for (i, f) in range.zip(fs.iter_mut()) {
        let (mut ax, mut ay) = ([0.0; 2 * QUADRANTS], [0.0; 2 * QUADRANTS]);
        for e in s.by_particle[i] as usize..s.by_particle[i + 1] as usize {
            let (p, bk) = (&stress[s.domains[e] as usize], &s.particle_gradients[e]);
            for j in 0..2 * QUADRANTS {
                ax[j] = p[j].mul_add(bk[j], ax[j]);
                ay[j] = p[2 * QUADRANTS + j].mul_add(bk[j], ay[j]);
            }
        }
        let lanes = |a: [Real; 2 * QUADRANTS]| {
            ((a[0] + a[1]) + (a[2] + a[3])) + ((a[4] + a[5]) + (a[6] + a[7]))
        };
        *f = [lanes(ax), lanes(ay)];
    }
}

/// [`domain_stresses`] compiled for AVX2 and FMA.
///
/// # Safety
///
/// The CPU must support AVX2 and FMA.
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2,fma"))]
unsafe fn domains_avx2(
    s: &Tables,
    d: &[[Real; 2]],
    range: std::ops::Range<usize>,
    out: &mut [[Real; 4 * QUADRANTS]],
) -> Real {
    domain_stresses(s, d, range, out)
}

/// [`particle_forces`] compiled for AVX2 and FMA.
///
/// # Safety
///
/// The CPU must support AVX2 and FMA.
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2,fma"))]
unsafe fn particles_avx2(
    s: &Tables,
    stress: &[[Real; 4 * QUADRANTS]],
    range: std::ops::Range<usize>,
    fs: &mut [[Real; 2]],
) {
    particle_forces(s, stress, range, fs)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integration::quadrant_shapes;
    use crate::rk_shape::Lattice;

    /// A 9 x 7 lattice of 1 mm spacing with its stabilization (`c mu` = 1 Pa, unit depth).
    fn patch() -> (Lattice, Tables, Forces) {
        let lattice = Lattice::new([0.0, 0.0], [1e-3, 1e-3], [9, 7], [2e-3, 2e-3]);
        let (quadrants, table) = quadrant_shapes(&lattice).unwrap();
        let t = Tables::new(1.0, 1.0, &table, &quadrants.areas, 63);
        let s = Forces::new(&t, 63);
        (lattice, t, s)
    }

    #[test]
    fn each_quadrant_reproduces_a_linear_gradient() {
        let (lattice, _, _) = patch();
        let (quadrants, table) = quadrant_shapes(&lattice).unwrap();
        let x = &lattice.cloud().positions;
        let u = |p: [Real; 2]| [0.3 * p[0] - 0.2 * p[1], 0.1 * p[0] + 0.4 * p[1]];
        for q in 0..quadrants.areas.len() {
            let mut g = [0.0; 4];
            for e in table.row(q) {
                let ui = u(x[table.index[e] as usize]);
                g[0] += ui[0] * table.grad[0][e];
                g[1] += ui[0] * table.grad[1][e];
                g[2] += ui[1] * table.grad[0][e];
                g[3] += ui[1] * table.grad[1][e];
            }
            for (a, b) in g.iter().zip([0.3, -0.2, 0.1, 0.4]) {
                assert!((a - b).abs() < 1e-12, "quadrant {q}: {g:?}");
            }
        }
        let area: Real = quadrants.areas.iter().sum();
        assert!((area - 8e-3 * 6e-3).abs() < 1e-15);
    }

    #[test]
    fn a_linear_field_and_a_rigid_motion_cost_nothing() {
        let (lattice, t, mut s) = patch();
        // The RK coefficients of a linear field are its nodal values (linear basis).
        let d: Vec<[Real; 2]> = lattice
            .cloud()
            .positions
            .iter()
            .map(|p| {
                [
                    1e-4 + 0.01 * p[0] - 0.02 * p[1],
                    -2e-4 + 0.02 * p[0] + 0.005 * p[1],
                ]
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
    fn a_saw_tooth_stores_energy_and_the_force_is_its_gradient() {
        let (_, t, mut s) = patch();
        // The top row alternating up and down.
        let d: Vec<[Real; 2]> = (0..63)
            .map(|i| match i / 9 == 6 {
                true => [0.0, if i % 2 == 0 { 1e-5 } else { -1e-5 }],
                false => [0.0, 0.0],
            })
            .collect();
        let team = Team::default();
        let w = stage(&team, &t, &mut s, &d, false);
        assert!(w > 0.0);
        let force = s.force.clone();
        // W is quadratic in d: W(d) = f . d / 2, and each force component is the central
        // difference of W.
        let work: Real = force
            .iter()
            .zip(&d)
            .map(|(f, d)| f[0] * d[0] + f[1] * d[1])
            .sum();
        assert!((0.5 * work - w).abs() < 1e-9 * w, "{w} vs {}", 0.5 * work);
        let h = 1e-9;
        for i in [58, 60, 31] {
            for c in 0..2 {
                let (mut up, mut down) = (d.clone(), d.clone());
                up[i][c] += h;
                down[i][c] -= h;
                let fd = (stage(&team, &t, &mut s, &up, false)
                    - stage(&team, &t, &mut s, &down, false))
                    / (2.0 * h);
                let tol = 1e-6
                    * force
                        .iter()
                        .flatten()
                        .fold(0.0, |m: Real, x| m.max(x.abs()));
                assert!(
                    (fd - force[i][c]).abs() < tol,
                    "particle {i}.{c}: {fd} vs {}",
                    force[i][c]
                );
            }
        }
        // The AVX2 build gives the same bits.
        if crate::solver::stress::has_avx2() {
            let w2 = stage(&team, &t, &mut s, &d, true);
            assert_eq!(w.to_bits(), w2.to_bits());
            assert_eq!(force, s.force);
        }
    }
}
