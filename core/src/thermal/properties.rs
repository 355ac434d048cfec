//! Properties over temperature: a table `[[T (degrees C), value], ...]` read linearly between
//! its points and held beyond them (the form of the scene's `*_by_temperature` keys), and
//! the heat capacity built on one, with its enthalpy `h(T) = int c dT` (J/kg) so that heat
//! is kept exactly however the capacity changes with temperature; and the elasticity over
//! temperature (modulus and thermal stretch).

use crate::math::Real;

/// The value of `table` at `t`: linear between its points, the first and last held beyond
/// them. `table` is non-empty with increasing temperatures.
pub fn interpolate(table: &[[Real; 2]], t: Real) -> Real {
    match table.partition_point(|p| p[0] <= t) {
        0 => table[0][1],
        k if k == table.len() => table[k - 1][1],
        k => {
            let ([t0, v0], [t1, v1]) = (table[k - 1], table[k]);
            v0 + (v1 - v0) * (t - t0) / (t1 - t0)
        }
    }
}

/// The specific heat capacity `c` (J/(kg K)) of the workpiece, a constant or a table over
/// temperature, and the heat it takes to change temperature. With a table the conserved
/// quantity is the specific enthalpy `h(T) = int_{T_1}^T c dT` (J/kg, `T_1` the table's
/// first temperature), piecewise quadratic between the points: heating by `q` (J/kg) takes
/// a temperature `T` to `h^-1(h(T) + q)`, and a field is interpolated in enthalpy, so that
/// `sum m h` is the heat held, exactly.
#[derive(Debug, Clone, PartialEq)]
pub enum HeatCapacity {
    /// The same `c` (J/(kg K)) at every temperature: `h = c T`.
    Constant(Real),
    /// `c` linear between the table's points, held beyond them.
    Table {
        /// `[[T (degrees C), c (J/(kg K))], ...]`, T increasing, c positive.
        points: Vec<[Real; 2]>,
        /// `h` at each point (J/kg), 0 at the first.
        enthalpy: Vec<Real>,
    },
}

impl HeatCapacity {
    /// The constant `c`, or the table `[[T, c], ...]` when it is not empty (J/(kg K)).
    pub fn new(constant: Real, table: &[[Real; 2]]) -> HeatCapacity {
        if table.is_empty() {
            return HeatCapacity::Constant(constant);
        }
        let mut enthalpy = vec![0.0; table.len()];
        for k in 1..table.len() {
            let ([t0, c0], [t1, c1]) = (table[k - 1], table[k]);
            enthalpy[k] = enthalpy[k - 1] + 0.5 * (c0 + c1) * (t1 - t0);
        }
        HeatCapacity::Table {
            points: table.to_vec(),
            enthalpy,
        }
    }

    /// `c(T)` (J/(kg K)).
    pub fn at(&self, t: Real) -> Real {
        match self {
            HeatCapacity::Constant(c) => *c,
            HeatCapacity::Table { points, .. } => interpolate(points, t),
        }
    }

    /// The least `c` at any temperature (J/(kg K)), for the stable heat step.
    pub fn least(&self) -> Real {
        match self {
            HeatCapacity::Constant(c) => *c,
            HeatCapacity::Table { points, .. } => {
                points.iter().map(|p| p[1]).fold(Real::INFINITY, Real::min)
            }
        }
    }

    /// The specific enthalpy `h(T)` (J/kg): `c T`, or the table's integral from its first
    /// point, `H_k + c_k s + (c_{k+1} - c_k) s^2 / (2 (T_{k+1} - T_k))` with `s = T - T_k`
    /// in the interval `[T_k, T_{k+1}]`, linear beyond the ends.
    pub fn enthalpy(&self, t: Real) -> Real {
        match self {
            HeatCapacity::Constant(c) => c * t,
            HeatCapacity::Table { points, enthalpy } => {
                let k = points
                    .partition_point(|p| p[0] <= t)
                    .saturating_sub(1)
                    .min(points.len().saturating_sub(2));
                let [tk, ck] = points[k];
                let s = t - tk;
                if k + 1 < points.len() && s > 0.0 {
                    let [t1, c1] = points[k + 1];
                    let span = t1 - tk;
                    let s = s.min(span);
                    let inside = enthalpy[k] + ck * s + 0.5 * (c1 - ck) / span * s * s;
                    inside + c1 * (t - t1).max(0.0)
                } else {
                    enthalpy[k] + ck * s
                }
            }
        }
    }

    /// The temperature (degrees C) of specific enthalpy `h` (J/kg), the inverse of
    /// [`HeatCapacity::enthalpy`] (c is positive, so `h(T)` increases): in the interval
    /// holding `h`, the root `s = 2 dh / (c_k + sqrt(c_k^2 + 2 a dh))` of
    /// `c_k s + a s^2 / 2 = dh`, `a` the interval's slope of `c`.
    pub fn temperature(&self, h: Real) -> Real {
        match self {
            HeatCapacity::Constant(c) => h / c,
            HeatCapacity::Table { points, enthalpy } => {
                let last = points.len() - 1;
                if h <= 0.0 || last == 0 {
                    return points[0][0] + h / points[0][1];
                }
                if h >= enthalpy[last] {
                    return points[last][0] + (h - enthalpy[last]) / points[last][1];
                }
                let k = enthalpy.partition_point(|&e| e <= h).saturating_sub(1);
                let ([tk, ck], [t1, c1]) = (points[k], points[k + 1]);
                let (dh, a) = (h - enthalpy[k], (c1 - ck) / (t1 - tk));
                let root = (ck * ck + 2.0 * a * dh).max(0.0).sqrt();
                tk + 2.0 * dh / (ck + root)
            }
        }
    }

    /// The temperature (degrees C) a body at `t` reaches when it takes `q` (J/kg):
    /// `t + q / c`, or `h^-1(h(t) + q)`: within the interval of the table holding `t`,
    /// `t + 2 q / (c(t) + sqrt(c(t)^2 + 2 a q))` (`a` the interval's slope of `c`) while that
    /// stays in the interval (a step's heating mostly does), else through the enthalpy.
    #[inline]
    pub fn heat(&self, t: Real, q: Real) -> Real {
        match self {
            HeatCapacity::Constant(c) => t + q / c,
            HeatCapacity::Table { points, .. } => {
                let k = points.partition_point(|p| p[0] <= t);
                if k > 0 && k < points.len() {
                    let ([t0, c0], [t1, c1]) = (points[k - 1], points[k]);
                    let a = (c1 - c0) / (t1 - t0);
                    let c = c0 + a * (t - t0);
                    let root = c * c + 2.0 * a * q;
                    if root >= 0.0 {
                        let next = t + 2.0 * q / (c + root.sqrt());
                        if next >= t0 && next < t1 {
                            return next;
                        }
                    }
                }
                self.temperature(self.enthalpy(t) + q)
            }
        }
    }

    /// The heat (J/kg) it takes to go from `from` to `to` (degrees C): `c (to - from)`, or
    /// `h(to) - h(from)`.
    pub fn heat_between(&self, from: Real, to: Real) -> Real {
        match self {
            HeatCapacity::Constant(c) => c * (to - from),
            HeatCapacity::Table { .. } => self.enthalpy(to) - self.enthalpy(from),
        }
    }

    /// The temperature (degrees C) of a field interpolated from temperatures `t_I` with
    /// weights `n_I` (a partition of unity): `sum n_I t_I`, or `h^-1(sum n_I h(t_I))` (the
    /// heat the weights carry kept).
    pub fn interpolate(&self, row: impl Iterator<Item = (Real, Real)>) -> Real {
        match self {
            HeatCapacity::Constant(_) => row.map(|(n, t)| n * t).sum(),
            HeatCapacity::Table { .. } => {
                self.temperature(row.map(|(n, t)| n * self.enthalpy(t)).sum())
            }
        }
    }
}

/// The elasticity of a thermal scene's material over temperature: Young's modulus scaled by
/// a factor over temperature (Poisson's ratio held, so the bulk and shear moduli scale
/// alike), and the isotropic thermal stretch `lambda_th(T)` that the multiplicative split
/// `F = F_e F_th F_p`, `F_th = lambda_th I`, takes out of the elastic strain: the elastic
/// volumetric log strain is `ln J - ln J_p - 3 ln lambda_th(T)` (`J_p = 1`), the deviatoric
/// part untouched. Both are relative to the initial temperature, where the body is free of
/// stress.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Thermoelastic {
    /// `E(T) / E` as `[[T (degrees C), factor], ...]` (empty: 1).
    pub modulus_factor: Vec<[Real; 2]>,
    /// The thermal stretch.
    pub expansion: Expansion,
}

/// The isotropic thermal stretch of a material, relative to its initial temperature `T_0`.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Expansion {
    /// No thermal strain.
    #[default]
    None,
    /// A constant secant coefficient `alpha` (1/K): `lambda_th = 1 + alpha (T - T_0)`.
    Coefficient {
        /// `alpha` (1/K).
        per_k: Real,
        /// `T_0` (degrees C).
        from_c: Real,
    },
    /// The linear thermal strain `s(T)` (-) over temperature, from any reference, read as
    /// [`interpolate`] reads a table: `lambda_th = (1 + s(T)) / (1 + s(T_0))`.
    Table {
        /// `[[T (degrees C), s], ...]`.
        points: Vec<[Real; 2]>,
        /// `1 + s(T_0)`.
        at_start: Real,
    },
}

impl Thermoelastic {
    /// `E(T) / E` (-).
    pub fn modulus_factor_at(&self, t: Real) -> Real {
        if self.modulus_factor.is_empty() {
            1.0
        } else {
            interpolate(&self.modulus_factor, t)
        }
    }

    /// The largest `E(T) / E` (-), for the stable step.
    pub fn modulus_factor_max(&self) -> Real {
        if self.modulus_factor.is_empty() {
            1.0
        } else {
            self.modulus_factor
                .iter()
                .map(|p| p[1])
                .fold(Real::NEG_INFINITY, Real::max)
        }
    }

    /// The thermal log strain `ln lambda_th(T)` (-).
    pub fn log_strain(&self, t: Real) -> Real {
        match &self.expansion {
            Expansion::None => 0.0,
            Expansion::Coefficient { per_k, from_c } => (per_k * (t - from_c)).ln_1p(),
            Expansion::Table { points, at_start } => {
                ((1.0 + interpolate(points, t)) / at_start).ln()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A capacity rising from 450 to 750 J/(kg K) over 20-720 C, then falling to 600 at
    /// 900 C (the shape of a carbon steel's through its transformation, smoothed).
    fn steel() -> HeatCapacity {
        HeatCapacity::new(0.0, &[[20.0, 450.0], [720.0, 750.0], [900.0, 600.0]])
    }

    #[test]
    fn the_table_is_read_linearly_and_held_beyond() {
        let t = [[0.0, 1.0], [10.0, 3.0]];
        assert_eq!(interpolate(&t, -5.0), 1.0);
        assert_eq!(interpolate(&t, 5.0), 2.0);
        assert_eq!(interpolate(&t, 15.0), 3.0);
    }

    #[test]
    fn enthalpy_is_the_integral_of_the_capacity() {
        let c = steel();
        // Trapezoids are exact for a linear c; a fine midpoint sum checks it.
        for (a, b) in [(20.0, 700.0), (0.0, 1000.0), (500.0, 800.0), (-50.0, 10.0)] {
            let n = 200_000;
            let dt: Real = (b - a) / n as Real;
            let sum: Real = (0..n).map(|i| c.at(a + (i as Real + 0.5) * dt) * dt).sum();
            let exact = c.heat_between(a, b);
            assert!(
                (sum - exact).abs() < 1e-6 * exact.abs(),
                "{a}-{b}: {sum} vs {exact}"
            );
        }
    }

    #[test]
    fn temperature_inverts_enthalpy() {
        let c = steel();
        for t in [
            -100.0, 20.0, 100.0, 719.0, 720.0, 721.0, 850.0, 900.0, 1300.0,
        ] {
            let back = c.temperature(c.enthalpy(t));
            assert!((back - t).abs() < 1e-9, "{t} -> {back}");
        }
        let k = HeatCapacity::new(460.0, &[]);
        assert_eq!(k.heat(100.0, 4600.0), 110.0);
        // Heating within an interval and across intervals agrees with the enthalpy's.
        for (t, q) in [
            (100.0, 50.0),
            (700.0, 5.0e4),
            (719.0, 3.0e3),
            (880.0, -2.0e4),
        ] {
            let exact = c.temperature(c.enthalpy(t) + q);
            assert!((c.heat(t, q) - exact).abs() < 1e-9, "{t} + {q}");
        }
    }

    #[test]
    fn interpolation_in_enthalpy_keeps_the_heat() {
        let c = steel();
        let row = [(0.25, 100.0), (0.5, 700.0), (0.25, 880.0)];
        let t = c.interpolate(row.into_iter());
        let held: Real = row.iter().map(|(n, t)| n * c.enthalpy(*t)).sum();
        assert!((c.enthalpy(t) - held).abs() < 1e-9 * held);
    }
}
