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
}
