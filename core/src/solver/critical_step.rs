//! The critical step of central differences with lumped masses, measured on the undeformed
//! discretisation at setup (again at a kernel re-reference, and after each round of mass
//! scaling): Lanczos on `M^-1/2 K M^-1/2` with `K x` the internal force of the stress
//! stage itself, so the support, the rule and the lumping all enter.

use super::discretization::Discretization;
use super::heat::Heat;
use super::state::State;
use super::workspace::Workspace;
use super::{stress, update};
use crate::error::{Error, Result};
use crate::material::HenckyJ2;
use crate::math::{dot, Real};
use crate::scene::Scene;

/// Most Lanczos products of [`largest_eigenvalue`].
const LANCZOS_MAX: usize = 300;

/// Critical step of central differences with lumped masses on the undeformed
/// discretisation, `dt_crit = 2 / omega_max` (s), with `omega_max^2` the largest
/// eigenvalue of `M^{-1} K`, found by Lanczos iteration ([`largest_eigenvalue`]) on the
/// symmetric `A = M^{-1/2} K M^{-1/2}`. `K x` is the internal force (N) that
/// `internal_force` returns for a displacement `x` (m) scaled to `amplitude` (m; small
/// enough to stay linear elastic); `inv_sqrt_m` is `1 / sqrt(m_I)` (kg^-1/2);
/// displacements and forces have `D` components. The estimate depends on the support, the
/// integration rule and the mass lumping, which `h / c` ignores.
pub(super) fn critical_step<const D: usize>(
    inv_sqrt_m: &[Real],
    amplitude: Real,
    mut internal_force: impl FnMut(Vec<[Real; D]>) -> Result<Vec<[Real; D]>>,
) -> Result<Real> {
    let lambda = largest_eigenvalue(inv_sqrt_m.len(), |v: &[[Real; D]]| {
        // A v: K applied to the displacement M^{-1/2} v, scaled to `amplitude`.
        let xmax = v
            .iter()
            .zip(inv_sqrt_m)
            .map(|(a, s)| a[1..].iter().fold(a[0].abs(), |m, x| m.max(x.abs())) * s)
            .fold(0.0, Real::max);
        let scale = amplitude / xmax;
        let f_int = internal_force(
            v.iter()
                .zip(inv_sqrt_m)
                .map(|(a, s)| a.map(|x| x * s * scale))
                .collect(),
        )?;
        Ok(f_int
            .iter()
            .zip(inv_sqrt_m)
            .map(|(f, s)| f.map(|f| f * s / scale))
            .collect())
    })?;
    if !(lambda > 0.0 && lambda.is_finite()) {
        return Err(Error::ShapeFunctions(format!(
            "the stiffness has no positive eigenvalue ({lambda:.3e})"
        )));
    }
    Ok(2.0 / lambda.sqrt())
}

/// The largest eigenvalue of a symmetric operator `A` on vectors of `n` entries of `D`
/// components, `apply(v) = A v`, by Lanczos iteration (Golub & Van Loan, Matrix
/// Computations, sec. 10.1): the largest eigenvalue of the tridiagonal `T_k` converges to
/// it from below in a few tens of products, where power iteration needs hundreds on large
/// models. The start vector is a fixed pseudo-random one, the dot products are summed from
/// the first component on ([`dot`]), so the answer has the same bits on every run; the
/// iteration stops when the estimate changes by at most 1e-6 relative (after 10 products)
/// or after [`LANCZOS_MAX`].
pub(crate) fn largest_eigenvalue<const D: usize, E>(
    n: usize,
    mut apply: impl FnMut(&[[Real; D]]) -> std::result::Result<Vec<[Real; D]>, E>,
) -> std::result::Result<Real, E> {
    // Deterministic pseudo-random start (xorshift), so no mode is missed by symmetry.
    let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as Real / (1u64 << 53) as Real - 0.5
    };
    // The components of each entry drawn in order (`from_fn` calls in index order).
    let mut v: Vec<[Real; D]> = (0..n).map(|_| std::array::from_fn(|_| rnd())).collect();
    let norm = |x: &[[Real; D]]| x.iter().map(|a| dot(a, a)).sum::<Real>().sqrt();
    let n0 = norm(&v);
    v.iter_mut().for_each(|a| *a = a.map(|x| x / n0));
    let mut v_prev = vec![[0.0; D]; n];
    let (mut alpha, mut beta) = (Vec::new(), Vec::new());
    let mut lambda = 0.0;
    for it in 0..LANCZOS_MAX {
        let b_prev = beta.last().copied().unwrap_or(0.0);
        let mut w = apply(&v)?;
        w.iter_mut().zip(&v_prev).for_each(|(x, vp)| {
            for (x, vp) in x.iter_mut().zip(vp) {
                *x -= b_prev * vp;
            }
        });
        let a: Real = w.iter().zip(&v).map(|(x, y)| dot(x, y)).sum();
        w.iter_mut().zip(&v).for_each(|(x, y)| {
            for (x, y) in x.iter_mut().zip(y) {
                *x -= a * y;
            }
        });
        alpha.push(a);
        let next = tridiagonal_max_eigenvalue(&alpha, &beta);
        let b = norm(&w);
        let converged = it >= 10 && (next - lambda).abs() <= 1e-6 * next;
        lambda = next;
        if converged || b <= 1e-12 * next.abs() {
            break;
        }
        beta.push(b);
        w.iter_mut().for_each(|x| *x = x.map(|c| c / b));
        v_prev = std::mem::replace(&mut v, w);
    }
    Ok(lambda)
}

/// Largest eigenvalue of the symmetric tridiagonal matrix with diagonal `a` and
/// off-diagonal `b` (`b.len() + 1 == a.len()`), by Sturm-sequence bisection between the
/// Gershgorin bounds: the count of eigenvalues below `x` is the number of negative pivots
/// of `T - x I` (Golub & Van Loan, sec. 8.4).
fn tridiagonal_max_eigenvalue(a: &[Real], b: &[Real]) -> Real {
    let radius =
        |i: usize| (if i > 0 { b[i - 1].abs() } else { 0.0 }) + b.get(i).map_or(0.0, |x| x.abs());
    let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
    for (i, &ai) in a.iter().enumerate() {
        lo = lo.min(ai - radius(i));
        hi = hi.max(ai + radius(i));
    }
    let below = |x: Real| {
        let mut count = 0;
        let mut q = 1.0;
        for (i, &ai) in a.iter().enumerate() {
            let off = if i > 0 { b[i - 1] * b[i - 1] } else { 0.0 };
            q = ai - x - if i > 0 { off / q } else { 0.0 };
            if q == 0.0 {
                q = -Real::EPSILON * (x.abs() + 1.0);
            }
            if q < 0.0 {
                count += 1;
            }
        }
        count
    };
    let n = a.len();
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if below(mid) < n {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// The critical step on the undeformed discretisation ([`critical_step`]), with `K x` the
/// internal force of a displacement of 1e-7 of the spacing; the state is left undeformed.
/// With a modulus over temperature the points answer at their temperatures now: the step
/// is scaled by `sqrt(f_now / f_max)`, `f_now` the largest modulus factor of the points'
/// temperatures and `f_max` the table's largest, so that it holds when a die chills the
/// body stiffer.
pub(super) fn measure_critical_step(
    scene: &Scene,
    disc: &Discretization,
    st: &mut State,
    ws: &mut Workspace,
) -> Result<Real> {
    let stiffening = stiffening(&disc.material, st.heat.as_ref());
    let saved_points = st.points.clone();
    // The stress stage also heats the points and books the energy: neither is the run's.
    let (saved_heat, saved_energy) = (st.heat.clone(), st.energy);
    let amplitude = 1e-7 * disc.h_min();
    let inv_sqrt_m: Vec<Real> = disc.mass.iter().map(|m| 1.0 / m.sqrt()).collect();
    let dt = critical_step(&inv_sqrt_m, amplitude, |d| {
        st.d = d;
        stress::run(scene, disc, st, ws)?;
        update::forces(disc, &[], st, ws, None);
        Ok(ws.f_int.clone())
    });
    st.d = vec![[0.0; 2]; disc.ref_pos.len()];
    st.points = saved_points;
    st.heat = saved_heat;
    st.energy = saved_energy;
    dt.map(|dt| dt * stiffening)
}

/// The factor `sqrt(f_now / f_max)` (-) on a critical step measured with the points at their
/// temperatures now (2D and 3D): `f_now` the largest modulus factor `E(T_p) / E` of the
/// points' temperatures, `f_max` the largest of the scene's table
/// (`thermal.modulus_factor_by_temperature`), so that the step holds when the body cools
/// stiffer (the critical step scales as `1 / sqrt(E)`); 1 without a modulus over
/// temperature.
pub(super) fn stiffening(material: &HenckyJ2, heat: Option<&Heat>) -> Real {
    match (&material.thermoelastic, heat) {
        (Some(te), Some(h)) if !te.modulus_factor.is_empty() => {
            let now = h
                .temperature_c
                .iter()
                .map(|&t| te.modulus_factor_at(t))
                .fold(Real::NEG_INFINITY, Real::max);
            (now / te.modulus_factor_max()).sqrt()
        }
        _ => 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::{critical_step, tridiagonal_max_eigenvalue};
    use crate::math::Real;
    use std::f64::consts::PI;

    /// The critical step of a 3D lattice of `n_0 x n_1 x n_2` equal masses `m` (kg) with
    /// springs between nearest neighbours, free at every face: along axis `a` the spring
    /// resists the relative displacement in component `c` with stiffness `k[a][c]` (N/m), so
    /// component `c` is the product of three free chains, whose largest eigenvalue is
    /// `omega_c^2 = sum_a k[a][c] (2 - 2 cos((n_a - 1) pi / n_a)) / m`, and `dt_crit = 2 /
    /// max_c omega_c` to 1e-6.
    #[test]
    fn critical_step_of_a_3d_spring_lattice() {
        let n = [4, 5, 6];
        let k = [
            [3.0e6, 1.0e6, 2.0e6],
            [1.5e6, 2.5e6, 0.5e6],
            [2.0e6, 1.0e6, 3.0e6],
        ];
        let m = 0.02;
        let np = n[0] * n[1] * n[2];
        let index = |i: [usize; 3]| i[0] + n[0] * (i[1] + n[1] * i[2]);
        let force = |x: Vec<[Real; 3]>| -> crate::error::Result<Vec<[Real; 3]>> {
            let mut f = vec![[0.0; 3]; np];
            for p in 0..np {
                let i = [p % n[0], p / n[0] % n[1], p / (n[0] * n[1])];
                for a in 0..3 {
                    if i[a] + 1 < n[a] {
                        let mut j = i;
                        j[a] += 1;
                        let q = index(j);
                        for c in 0..3 {
                            let t = k[a][c] * (x[p][c] - x[q][c]);
                            f[p][c] += t;
                            f[q][c] -= t;
                        }
                    }
                }
            }
            Ok(f)
        };
        let chain = |a: usize| 2.0 - 2.0 * ((n[a] - 1) as Real * PI / n[a] as Real).cos();
        let omega2 = (0..3)
            .map(|c| (0..3).map(|a| k[a][c] * chain(a)).sum::<Real>() / m)
            .fold(0.0, Real::max);
        let exact = 2.0 / omega2.sqrt();
        let inv_sqrt_m = vec![1.0 / m.sqrt(); np];
        let dt = critical_step(&inv_sqrt_m, 1e-9, force).unwrap();
        assert!((dt - exact).abs() <= 1e-6 * exact, "{dt} vs {exact}");
    }

    #[test]
    fn tridiagonal_largest_eigenvalue() {
        // Second-difference matrix: eigenvalues 2 - 2 cos(k pi / (n + 1)).
        for n in [1, 2, 5, 40] {
            let a = vec![2.0; n];
            let b = vec![-1.0; n - 1];
            let exact = 2.0 - 2.0 * (n as f64 * std::f64::consts::PI / (n as f64 + 1.0)).cos();
            let got = tridiagonal_max_eigenvalue(&a, &b);
            assert!(
                (got - exact).abs() <= 1e-12 * exact,
                "n {n}: {got} vs {exact}"
            );
        }
        assert_eq!(tridiagonal_max_eigenvalue(&[3.0, -1.0], &[0.0]), 3.0);
    }
}
