//! Cubic B-spline kernel, tensor product per direction (Liu, Jun, Zhang 1995, eq. 3's
//! window function `Phi_a`).
//!
//! `w(z) = 2/3 - 4 z^2 + 4 z^3` for `z <= 1/2`, `4/3 (1 - z)^3` for `1/2 < z <= 1`,
//! `0` beyond, with `z = |x| / a` and `a` the support radius (m) of that direction.
//! The window in `D` dimensions is the product `phi(x) = prod_k w(|x_k|/a_k)` (2D:
//! `w(|x|/a_x) w(|y|/a_y)`, 3D: times `w(|z|/a_z)`); its normalisation cancels in the RK
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

/// Tensor-product window `phi(d) = prod_k w(|d_k|/a_k)` and its gradient with respect to
/// the evaluation point, `dphi/dx_k = prod_{j<k} w_j * w'_k sign(d_k) / a_k * prod_{j>k} w_j`
/// (1/m), for the offset `d = x - X_I` (m) and support radii `a` (m), in `D` dimensions.
///
/// The products are formed left to right in this order, so that 2D gives the bits of
/// `phi = w_x w_y`, `dphi/dx = w'_x sign / a_x * w_y`, `dphi/dy = w_x w'_y sign / a_y`.
#[inline]
pub fn window<const D: usize>(d: [Real; D], a: [Real; D]) -> (Real, [Real; D]) {
    let w: [(Real, Real); D] = std::array::from_fn(|k| cubic_spline(d[k].abs() / a[k]));
    let grad = std::array::from_fn(|k| {
        let mut g = 1.0;
        for &(wj, _) in &w[..k] {
            g *= wj;
        }
        g = g * w[k].1 * d[k].signum() / a[k];
        for &(wj, _) in &w[k + 1..] {
            g *= wj;
        }
        g
    });
    let phi = w.iter().fold(1.0, |p, &(wj, _)| p * wj);
    (phi, grad)
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

    /// The 3D window is the 2D window times the third direction's spline, and its gradient
    /// matches finite differences in every direction.
    #[test]
    fn window_in_three_dimensions_is_the_product_with_its_gradient() {
        let a = [0.4, 0.7, 1.1];
        for d in [[0.1, -0.3, 0.5], [-0.25, 0.6, -0.05], [0.39, 0.0, -1.0]] {
            let (phi, g) = window(d, a);
            let (phi2, _) = window([d[0], d[1]], [a[0], a[1]]);
            let (w3, _) = cubic_spline(d[2].abs() / a[2]);
            assert!((phi - phi2 * w3).abs() < 1e-15, "{d:?}");
            let h = 1e-7;
            for k in 0..3 {
                let (mut p, mut m) = (d, d);
                p[k] += h;
                m[k] -= h;
                let fd = (window(p, a).0 - window(m, a).0) / (2.0 * h);
                assert!((fd - g[k]).abs() < 1e-7, "{d:?}, direction {k}");
            }
        }
    }

    /// In 2D the generic window gives the bits of the planar formula it replaced:
    /// `phi = w_x w_y`, `dphi/dx = w'_x sign(dx) / a_x * w_y`,
    /// `dphi/dy = w_x w'_y sign(dy) / a_y`, evaluated left to right.
    #[test]
    fn window_in_two_dimensions_keeps_the_bits_of_the_planar_formula() {
        let (ax, ay) = (0.32e-3, 1.296e-3);
        for i in -40..=40 {
            for j in -40..=40 {
                let (dx, dy) = (i as Real * 0.0091e-3, j as Real * 0.0333e-3);
                let (wx, dwx) = cubic_spline(dx.abs() / ax);
                let (wy, dwy) = cubic_spline(dy.abs() / ay);
                let planar = [
                    wx * wy,
                    dwx * dx.signum() / ax * wy,
                    wx * dwy * dy.signum() / ay,
                ];
                let (phi, [gx, gy]) = window([dx, dy], [ax, ay]);
                assert_eq!(
                    [phi, gx, gy].map(Real::to_bits),
                    planar.map(Real::to_bits),
                    "({dx}, {dy})"
                );
            }
        }
    }
}
