//! Background-cell integration over the quadrilaterals of the particle grid.
//!
//! - `q4`: the 2x2 Gauss rule, points at `(+-1/sqrt3, +-1/sqrt3)`, weight 1 each.
//! - `q2`: the paper's two-point rule (Sidibe et al. 2009, Figure 1-c; Sidibe, Li, Ouane,
//!   Sanogo 2009). The figure is not in the text; we read it as the two points on one cell
//!   diagonal at `+-(1/sqrt3, 1/sqrt3)` with weight 2 each, which integrates `1, xi, eta, xi^2,
//!   eta^2` exactly (the bilinear `xi eta` term is not: it is the price of the rule). Because
//!   RK shape functions span several cells, the assembled stiffness keeps full rank; the
//!   spurious-mode test in `tests/` checks that.

use crate::math::Real;
use crate::scene::IntegrationRule;

/// Integration points: reference positions and cell-local data.
#[derive(Debug, Clone, Default)]
pub struct PointSet {
    /// Reference positions (m).
    pub positions: Vec<[Real; 2]>,
    /// Planar area weights (m^2): Gauss weight times the cell Jacobian.
    pub areas: Vec<Real>,
    /// Cell index `j * (nx - 1) + i` of each point.
    pub cells: Vec<u32>,
}

/// Gauss points `(xi, eta, weight)` of a rule on the reference square `[-1, 1]^2`.
pub fn rule_points(rule: IntegrationRule) -> Vec<(Real, Real, Real)> {
    let a = 1.0 / 3.0_f64.sqrt();
    match rule {
        IntegrationRule::Q4 => vec![(-a, -a, 1.0), (a, -a, 1.0), (a, a, 1.0), (-a, a, 1.0)],
        IntegrationRule::Q2 => vec![(-a, -a, 2.0), (a, a, 2.0)],
    }
}

/// Points of `rule` in every cell of the `nx x ny` grid with lower-left `origin` and
/// spacings `h`.
pub fn grid_points(
    rule: IntegrationRule,
    origin: [Real; 2],
    h: [Real; 2],
    nx: usize,
    ny: usize,
) -> PointSet {
    let local = rule_points(rule);
    let mut s = PointSet::default();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let xc = origin[0] + (i as Real + 0.5) * h[0];
            let yc = origin[1] + (j as Real + 0.5) * h[1];
            for &(xi, eta, w) in &local {
                s.positions
                    .push([xc + 0.5 * xi * h[0], yc + 0.5 * eta * h[1]]);
                s.areas.push(w * 0.25 * h[0] * h[1]);
                s.cells.push((j * (nx - 1) + i) as u32);
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Integrate a monomial over [-1,1]^2 with a rule.
    fn integrate(rule: IntegrationRule, f: impl Fn(Real, Real) -> Real) -> Real {
        rule_points(rule).iter().map(|&(x, y, w)| w * f(x, y)).sum()
    }

    #[test]
    fn q4_is_exact_for_bicubics_and_q2_for_complete_quadratics_but_xy() {
        let exact2 = |p: i32| {
            if p % 2 == 1 {
                0.0
            } else {
                2.0 / (p as Real + 1.0)
            }
        };
        for px in 0..=3 {
            for py in 0..=3 {
                let e = exact2(px) * exact2(py);
                let q4 = integrate(IntegrationRule::Q4, |x, y| x.powi(px) * y.powi(py));
                assert!((q4 - e).abs() < 1e-14, "q4 x^{px} y^{py}");
                if px + py <= 2 && !(px == 1 && py == 1) {
                    let q2 = integrate(IntegrationRule::Q2, |x, y| x.powi(px) * y.powi(py));
                    assert!((q2 - e).abs() < 1e-14, "q2 x^{px} y^{py}");
                }
            }
        }
        assert!((integrate(IntegrationRule::Q2, |x, y| x * y) - 4.0 / 3.0).abs() < 1e-14);
    }

    #[test]
    fn weights_sum_to_the_area() {
        for rule in [IntegrationRule::Q4, IntegrationRule::Q2] {
            let s = grid_points(rule, [0.0, 0.0], [0.5, 0.25], 5, 9);
            let a: Real = s.areas.iter().sum();
            assert!((a - 2.0 * 2.0).abs() < 1e-12);
        }
    }
}
