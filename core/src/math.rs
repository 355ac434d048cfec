//! Math aliases used across the solver: one scalar type and the small fixed-size
//! vectors and matrices of 2D continuum mechanics.

/// The scalar type of every physical quantity (SI units).
pub type Real = f64;
/// A 2-vector: a position (m), displacement (m), velocity (m/s) or force (N).
pub type Vec2 = nalgebra::Vector2<Real>;
/// A 2x2 matrix: the in-plane block of a deformation gradient or stress.
pub type Mat2 = nalgebra::Matrix2<Real>;

/// Spectral decomposition of a symmetric 2x2 matrix `[[a, b], [b, c]] = l1 P + l2 (I - P)`.
///
/// Returns the eigenvalues `(l1, l2)` with `l1 >= l2` and the eigenprojector of `l1`,
/// `P = n1 n1^T = [p11, p12, p22]` with `p11 = (1 + cos 2t) / 2`, `p12 = sin 2t / 2`,
/// `p22 = 1 - p11`, where `2t = atan2(b, (a - c) / 2)`. No angle, square root of an angle
/// or second division is needed: an isotropic function of the matrix only uses `P`.
/// Exact for repeated eigenvalues (then `P = [1, 0, 0]`).
#[inline]
pub fn sym_spectral2(a: Real, b: Real, c: Real) -> (Real, Real, [Real; 3]) {
    let m = 0.5 * (a + c);
    let h = 0.5 * (a - c);
    let r = (h * h + b * b).sqrt();
    let (l1, l2) = (m + r, m - r);
    if r == 0.0 {
        return (l1, l2, [1.0, 0.0, 0.0]);
    }
    let half_inv_r = 0.5 / r;
    let p11 = 0.5 + h * half_inv_r;
    (l1, l2, [p11, b * half_inv_r, 1.0 - p11])
}

/// Cyclic Jacobi sweeps of [`sym_spectral3`]: its off-diagonal falls quadratically, below
/// `1e-25` of the matrix's norm after four sweeps over the matrices its test draws
/// (random rotations of spread, nearly repeated and repeated eigenvalues); the fifth is margin.
pub const JACOBI_SWEEPS: usize = 5;

/// Spectral decomposition of a symmetric 3x3 matrix `a = [a11, a22, a33, a12, a23, a13]`
/// by cyclic Jacobi rotations (Golub and Van Loan 2013, Matrix Computations, section 8.5;
/// the update of Press et al. 2007, Numerical Recipes, section 11.1): `a = V diag(l) V^T`.
///
/// Returns the eigenvalues `l` (unordered) and `V` row-major, column `k` the eigenvector of
/// `l[k]`. Each rotation in the plane `(p, q)` takes `t = tan phi = 2 a_pq sgn(d) / (|d| +
/// sqrt(d^2 + 4 a_pq^2))`, `d = a_qq - a_pp` (the smaller root, `|phi| <= pi/4`; `t = 0`
/// where `a_pq = d = 0`), `c = 1 / sqrt(1 + t^2)`, `s = t c`, and zeroes `a_pq`;
/// [`JACOBI_SWEEPS`] sweeps over `(1, 2), (1, 3), (2, 3)`, a fixed count, so the function
/// is branch-free (selects only) and written with `+ - * /` and `sqrt` alone, as the lanes
/// ask ([`crate::lanes`]). Jacobi's method keeps `V` orthogonal to round-off and resolves
/// repeated and nearly repeated eigenvalues as well as spread ones; a rotation whose `a_pq`
/// is zero is the identity, so a diagonal matrix is returned exactly, with `V = I`.
/// Entries beyond `1e150` in magnitude (squares overflowing) are not supported.
#[inline(always)]
pub fn sym_spectral3(a: [Real; 6]) -> ([Real; 3], [[Real; 3]; 3]) {
    let (l, v) = sym_spectral3_lanes(a.map(|x| [x]));
    (l.map(|x| x[0]), v.map(|row| row.map(|x| x[0])))
}

/// [`sym_spectral3`] of `L` matrices at once, one per lane (`a[c][l]`), eigenvalues
/// `l[k][lane]` and vectors `V[i][k][lane]`: every operation runs over the lanes in an
/// inner loop the compiler turns into vector instructions (the square roots and divisions
/// of the rotations are most of the 3D stress update's time), each lane with the bits of
/// the one-matrix function.
#[inline(always)]
#[allow(clippy::type_complexity)] // lanes of the eigenvalues and of the eigenvector matrix
pub fn sym_spectral3_lanes<const L: usize>(
    a: [[Real; L]; 6],
) -> ([[Real; L]; 3], [[[Real; L]; 3]; 3]) {
    let [a11, a22, a33, a12, a23, a13] = a;
    let mut m = [[a11, a12, a13], [a12, a22, a23], [a13, a23, a33]];
    let (zero, one) = ([0.0; L], [1.0; L]);
    let mut v = [[one, zero, zero], [zero, one, zero], [zero, zero, one]];
    for _ in 0..JACOBI_SWEEPS {
        jacobi_rotation::<L, 0, 1, 2>(&mut m, &mut v);
        jacobi_rotation::<L, 0, 2, 1>(&mut m, &mut v);
        jacobi_rotation::<L, 1, 2, 0>(&mut m, &mut v);
    }
    ([m[0][0], m[1][1], m[2][2]], v)
}

/// One Jacobi rotation of [`sym_spectral3_lanes`] in the plane `(P, Q)` (`R` the third
/// axis) on every lane of `m`, accumulated into `v`: the angle's `s = sin phi`, `tau = s /
/// (1 + cos phi)` and `h = tan phi a_pq` lane by lane, then each entry's update over the
/// lanes, so that every loop is one vector operation per quantity (the indices are
/// constants).
#[inline(always)]
fn jacobi_rotation<const L: usize, const P: usize, const Q: usize, const R: usize>(
    m: &mut [[[Real; L]; 3]; 3],
    v: &mut [[[Real; L]; 3]; 3],
) {
    let (mut s, mut tau, mut h) = ([0.0; L], [0.0; L], [0.0; L]);
    for l in 0..L {
        let apq = m[P][Q][l];
        let d = m[Q][Q][l] - m[P][P][l];
        let den = d.abs() + (d * d + 4.0 * apq * apq).sqrt();
        let t = if den > 0.0 { 2.0 * apq / den } else { 0.0 };
        let t = if d < 0.0 { -t } else { t };
        let c = 1.0 / (t * t + 1.0).sqrt();
        s[l] = t * c;
        tau[l] = s[l] / (1.0 + c);
        h[l] = t * apq;
    }
    for l in 0..L {
        m[P][P][l] -= h[l];
        m[Q][Q][l] += h[l];
        m[P][Q][l] = 0.0;
        m[Q][P][l] = 0.0;
        let (arp, arq) = (m[R][P][l], m[R][Q][l]);
        m[R][P][l] = arp - s[l] * (arq + tau[l] * arp);
        m[P][R][l] = m[R][P][l];
        m[R][Q][l] = arq + s[l] * (arp - tau[l] * arq);
        m[Q][R][l] = m[R][Q][l];
    }
    for row in v.iter_mut() {
        for l in 0..L {
            let (vp, vq) = (row[P][l], row[Q][l]);
            row[P][l] = vp - s[l] * (vq + tau[l] * vp);
            row[Q][l] = vq + s[l] * (vp - tau[l] * vq);
        }
    }
}

/// `sum_k term(k)` over the `D >= 1` components, summed from the first term on:
/// `term(0) + term(1) + ... + term(D - 1)`, the order of the 2D expressions written out
/// (`a[0] * b[0] + a[1] * b[1]`), so that a sum generic over the dimension keeps their bits
/// at `D = 2` (a sum started from `0.0` would not: `0.0 + (-0.0)` is `+0.0`).
#[inline(always)]
pub fn component_sum<const D: usize>(term: impl Fn(usize) -> Real) -> Real {
    let mut sum = term(0);
    for k in 1..D {
        sum += term(k);
    }
    sum
}

/// Dot product `a . b = a_0 b_0 + a_1 b_1 + ...` of two `D`-vectors, summed from the first
/// term on ([`component_sum`]).
#[inline(always)]
pub fn dot<const D: usize>(a: &[Real; D], b: &[Real; D]) -> Real {
    component_sum::<D>(|k| a[k] * b[k])
}

/// A rotation from a quaternion `(w, x, y, z)` (normalised here), by rows; for the tests
/// of the symmetric decompositions and the 3D material.
#[cfg(test)]
pub(crate) fn rotation(q: [Real; 4]) -> [[Real; 3]; 3] {
    let n = q.iter().map(|x| x * x).sum::<Real>().sqrt();
    let [w, x, y, z] = q.map(|c| c / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - z * w),
            2.0 * (x * z + y * w),
        ],
        [
            2.0 * (x * y + z * w),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - x * w),
        ],
        [
            2.0 * (x * z - y * w),
            2.0 * (y * z + x * w),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spectral2_reconstructs_matrix() {
        for &(a, b, c) in &[
            (2.0, 0.5, -1.0),
            (1.0, 0.0, 1.0),
            (1.0, 0.0, 3.0),
            (-4.0, 1e-9, -4.0),
            (0.3, -2.0, 0.1),
            (5.0, 0.0, -5.0),
        ] {
            let (l1, l2, [p11, p12, p22]) = sym_spectral2(a, b, c);
            assert!(l1 >= l2);
            let p = Mat2::new(p11, p12, p12, p22);
            // A projector of rank one: P P = P, trace 1.
            assert!((p * p - p).norm() < 1e-14, "{a} {b} {c}: {p}");
            assert!((p11 + p22 - 1.0).abs() < 1e-15);
            let m = p * l1 + (Mat2::identity() - p) * l2;
            assert!((m[(0, 0)] - a).abs() < 1e-12, "{a} {b} {c}: {m}");
            assert!((m[(0, 1)] - b).abs() < 1e-12, "{a} {b} {c}: {m}");
            assert!((m[(1, 1)] - c).abs() < 1e-12, "{a} {b} {c}: {m}");
        }
    }

    /// Random rotations of eigenvalues spread, nearly repeated (relative gaps 1e-8 and
    /// 1e-14), repeated and all near 1 (the elastic stretches of metals): `V` orthogonal
    /// and `V diag(l) V^T` the matrix to a few ulps of its norm, each eigenvalue to a few
    /// ulps of the largest.
    #[test]
    fn spectral3_reconstructs_matrix() {
        let mut s: u64 = 0x2545_F491_4F6C_DD1D;
        let mut uniform = move |lo: Real, hi: Real| {
            s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            lo + (hi - lo) * ((s >> 11) as Real / (1u64 << 53) as Real)
        };
        let (mut worst_a, mut worst_l, mut worst_o): (Real, Real, Real) = (0.0, 0.0, 0.0);
        for case in 0..20_000 {
            let a = uniform(-1.0, 1.0).exp();
            let l: [Real; 3] = match case % 5 {
                0 => [a, uniform(-1.0, 1.0).exp(), uniform(-1.0, 1.0).exp()],
                1 => [
                    a,
                    a * (1.0 + 1e-8 * uniform(-1.0, 1.0)),
                    uniform(-1.0, 1.0).exp(),
                ],
                2 => [a, a * (1.0 + 1e-14 * uniform(-1.0, 1.0)), a * 1.001],
                3 => [a, a, a * uniform(0.5, 2.0)],
                _ => [0.0; 3].map(|_| 1.0 + 1e-3 * uniform(-1.0, 1.0)),
            };
            let r = rotation([0; 4].map(|_| uniform(-1.0, 1.0)));
            let m = |i: usize, j: usize| (0..3).map(|k| r[i][k] * l[k] * r[j][k]).sum::<Real>();
            let (got, v) = sym_spectral3([m(0, 0), m(1, 1), m(2, 2), m(0, 1), m(1, 2), m(0, 2)]);
            let top = l.iter().fold(0.0, |x: Real, &y| x.max(y));
            for i in 0..3 {
                for j in 0..3 {
                    let back = (0..3).map(|k| v[i][k] * got[k] * v[j][k]).sum::<Real>();
                    worst_a = worst_a.max((back - m(i, j)).abs() / top);
                    let vtv = (0..3).map(|k| v[k][i] * v[k][j]).sum::<Real>();
                    worst_o = worst_o.max((vtv - if i == j { 1.0 } else { 0.0 }).abs());
                }
            }
            let mut want = l;
            let mut have = got;
            want.sort_by(Real::total_cmp);
            have.sort_by(Real::total_cmp);
            for k in 0..3 {
                worst_l = worst_l.max((have[k] - want[k]).abs() / top);
            }
        }
        assert!(worst_a < 4e-15, "reconstruction {worst_a:e}");
        assert!(worst_l < 4e-15, "eigenvalues {worst_l:e}");
        assert!(worst_o < 4e-15, "orthogonality {worst_o:e}");
    }

    /// A diagonal matrix, repeated eigenvalues or not, comes back exactly with `V = I`.
    #[test]
    fn spectral3_of_a_diagonal_is_exact() {
        let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        for d in [
            [1.0, 1.0, 1.0],
            [1.3, 1.3, 0.7],
            [0.7, 1.3, 1.3],
            [2.0, 0.5, 1.1],
        ] {
            let (l, v) = sym_spectral3([d[0], d[1], d[2], 0.0, 0.0, 0.0]);
            assert_eq!(l, d);
            assert_eq!(v, identity);
        }
    }
}
