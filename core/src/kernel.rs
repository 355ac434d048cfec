//! Cubic B-spline kernel, tensor product per direction (Liu, Jun, Zhang 1995, eq. 3's
//! window function `Phi_a`).
//!
//! `w(z) = 2/3 - 4 z^2 + 4 z^3` for `z <= 1/2`, `4/3 (1 - z)^3` for `1/2 < z <= 1`,
//! `0` beyond, with `z = |x| / a` and `a` the support radius (m) of that direction.
//! The 2D window is `phi(x, y) = w(|x|/a_x) w(|y|/a_y)`; its normalisation cancels in the RK
//! correction, so none is applied.

use crate::math::Real;

/// 1D cubic B-spline value and derivative with respect to `z = |x|/a`.
#[inline]
pub fn cubic_spline(z: Real) -> (Real, Real) {
    if z <= 0.5 {
        (
            2.0 / 3.0 - 4.0 * z * z + 4.0 * z * z * z,
            -8.0 * z + 12.0 * z * z,
        )
    } else if z < 1.0 {
        let t = 1.0 - z;
        (4.0 / 3.0 * t * t * t, -4.0 * t * t)
    } else {
        (0.0, 0.0)
    }
}

/// Tensor-product window `phi(dx, dy)` and its gradient with respect to the evaluation
/// point, for the offset `(dx, dy) = x - X_I` and support radii `(ax, ay)`.
#[inline]
pub fn window(dx: Real, dy: Real, ax: Real, ay: Real) -> (Real, Real, Real) {
    let (wx, dwx) = cubic_spline(dx.abs() / ax);
    let (wy, dwy) = cubic_spline(dy.abs() / ay);
    let gx = dwx * dx.signum() / ax * wy;
    let gy = wx * dwy * dy.signum() / ay;
    (wx * wy, gx, gy)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spline_is_c2_at_the_joints_and_vanishes_at_support() {
        let e = 1e-9;
        let (a, da) = cubic_spline(0.5 - e);
        let (b, db) = cubic_spline(0.5 + e);
        assert!((a - b).abs() < 1e-8 && (da - db).abs() < 1e-7);
        let (c, dc) = cubic_spline(1.0 - e);
        assert!(c.abs() < 1e-12 && dc.abs() < 1e-8);
        assert_eq!(cubic_spline(1.0), (0.0, 0.0));
        assert_eq!(cubic_spline(0.0).1, 0.0);
    }

    #[test]
    fn derivative_matches_finite_difference() {
        for &z in &[0.1, 0.3, 0.49, 0.51, 0.7, 0.95] {
            let h = 1e-6;
            let fd = (cubic_spline(z + h).0 - cubic_spline(z - h).0) / (2.0 * h);
            assert!((fd - cubic_spline(z).1).abs() < 1e-6, "z = {z}");
        }
    }
}
