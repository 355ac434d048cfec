//! Math aliases used across the solver: one scalar type and the small fixed-size
//! vectors and matrices of 2D continuum mechanics.

/// The scalar type of every physical quantity (SI units).
pub type Real = f64;
/// A 2-vector: a position (m), displacement (m), velocity (m/s) or force (N).
pub type Vec2 = nalgebra::Vector2<Real>;
/// A 2x2 matrix: the in-plane block of a deformation gradient or stress.
pub type Mat2 = nalgebra::Matrix2<Real>;

/// Eigen-decomposition of a symmetric 2x2 matrix `[[a, b], [b, c]]`.
///
/// Returns the eigenvalues `(l1, l2)` with `l1 >= l2` and the unit eigenvector of `l1`
/// as `(cos t, sin t)`; the other is `(-sin t, cos t)`. Closed form, exact for repeated
/// eigenvalues (the angle is then 0).
#[inline]
pub fn sym_eigen2(a: Real, b: Real, c: Real) -> (Real, Real, Real, Real) {
    let m = 0.5 * (a + c);
    let h = 0.5 * (a - c);
    let r = (h * h + b * b).sqrt();
    let (l1, l2) = (m + r, m - r);
    if r == 0.0 {
        return (l1, l2, 1.0, 0.0);
    }
    // Half-angle formulas avoid atan2/sin/cos: 2t = atan2(b, h).
    let cos2 = h / r;
    let sin2 = b / r;
    let (ct, st) = if cos2 >= 0.0 {
        let ct = (0.5 * (1.0 + cos2)).sqrt();
        (ct, sin2 / (2.0 * ct))
    } else {
        let st = (0.5 * (1.0 - cos2)).sqrt().copysign(sin2);
        let st = if st == 0.0 { 1.0 } else { st };
        (sin2 / (2.0 * st), st)
    };
    (l1, l2, ct, st)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigen2_reconstructs_matrix() {
        for &(a, b, c) in &[
            (2.0, 0.5, -1.0),
            (1.0, 0.0, 1.0),
            (1.0, 0.0, 3.0),
            (-4.0, 1e-9, -4.0),
            (0.3, -2.0, 0.1),
            (5.0, 0.0, -5.0),
        ] {
            let (l1, l2, ct, st) = sym_eigen2(a, b, c);
            assert!(l1 >= l2);
            let n1 = Vec2::new(ct, st);
            let n2 = Vec2::new(-st, ct);
            let m = n1 * n1.transpose() * l1 + n2 * n2.transpose() * l2;
            assert!((m[(0, 0)] - a).abs() < 1e-12, "{a} {b} {c}: {m}");
            assert!((m[(0, 1)] - b).abs() < 1e-12, "{a} {b} {c}: {m}");
            assert!((m[(1, 1)] - c).abs() < 1e-12, "{a} {b} {c}: {m}");
            assert!((n1.norm() - 1.0).abs() < 1e-14);
        }
    }
}
