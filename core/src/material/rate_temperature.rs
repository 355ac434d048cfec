//! Flow stresses of plastic strain, plastic strain rate and temperature, the laws of hot
//! forging and impact: Johnson-Cook, Hensel-Spittel and a table. Each returns the flow
//! stress with its partial derivatives in strain and rate, which the rate-consistent return
//! map ([`super::HenckyJ2::update_lanes`]) needs for its Newton iteration.

use crate::lanes;
use crate::math::Real;

/// The flow stress `sigma_y` (Pa) at a plastic strain, strain rate and temperature, with
/// `d sigma_y / d eps_p` (Pa) and `d sigma_y / d rate` (Pa s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Flow {
    /// `sigma_y` (Pa).
    pub stress: Real,
    /// `d sigma_y / d eps_p` (Pa); infinite at `eps_p = 0` for a hardening exponent below 1.
    pub d_strain: Real,
    /// `d sigma_y / d rate` (Pa s); 0 where the rate is held at a bound.
    pub d_rate: Real,
}

/// Johnson and Cook (1983), Proc. 7th Int. Symp. Ballistics, eq. 1:
/// `sigma_y = (A + B eps^n) (1 + C ln(rate / rate0)) (1 - T*^m)` (Pa) with
/// `T* = (T - T_ref) / (T_melt - T_ref)`. Below `rate0` the rate term is 1 (no rate
/// effect, as LS-DYNA's `*MAT_JOHNSON_COOK` reads it), and `T*` is held in `[0, 1]`.
/// `law = [A (Pa), B (Pa), n, C, m]`, `temps = [T_ref, T_melt]` (degrees C),
/// `at = [eps_p, rate (1/s), T (degrees C)]`.
pub fn johnson_cook(law: [Real; 5], rate0: Real, temps: [Real; 2], at: [Real; 3]) -> Flow {
    johnson_cook_softening(law[4], temps, at[2]).flow(law, rate0, at[0], at[1])
}

/// The thermal softening `1 - T*^m` of Johnson-Cook at `temp` (degrees C), evaluated once
/// per return map (the temperature is the step's start's).
pub fn johnson_cook_softening(m: Real, temps: [Real; 2], temp: Real) -> Softening {
    let homologous = ((temp - temps[0]) / (temps[1] - temps[0])).clamp(0.0, 1.0);
    Softening(1.0 - homologous.powf(m))
}

/// Johnson-Cook's thermal factor `1 - T*^m` (-) at one temperature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Softening(pub Real);

impl Softening {
    /// Johnson-Cook at this temperature, strain `eps` and rate `rate` (1/s);
    /// `law = [A, B, n, C, m]` as [`johnson_cook`].
    pub fn flow(self, law: [Real; 5], rate0: Real, eps: Real, rate: Real) -> Flow {
        let [a, b, n, c, _] = law;
        let eps = eps.max(0.0);
        let power = if eps > 0.0 {
            lanes::exp(n * lanes::ln(eps))
        } else {
            0.0
        };
        let hard = a + b * power;
        let d_hard = if eps > 0.0 {
            b * n * power / eps
        } else if n < 1.0 {
            Real::INFINITY
        } else if n == 1.0 {
            b
        } else {
            0.0
        };
        let (rate_term, d_rate_term) = if rate > rate0 {
            (1.0 + c * lanes::ln(rate / rate0), c / rate)
        } else {
            (1.0, 0.0)
        };
        let thermal = self.0;
        Flow {
            stress: hard * rate_term * thermal,
            d_strain: d_hard * rate_term * thermal,
            d_rate: hard * d_rate_term * thermal,
        }
    }
}

impl Softening {
    /// Johnson-Cook's plastic work density over a step from `eps` to `eps + dgamma` at the
    /// constant rate `rate` (1/s) and this temperature, exactly: `(A dgamma + B / (n + 1)
    /// ((eps + dgamma)^(n+1) - eps^(n+1))) (1 + C ln(rate / rate0)) (1 - T*^m)` (J/m^3).
    pub fn work(self, law: [Real; 5], rate0: Real, eps: Real, dgamma: Real, rate: Real) -> Real {
        let [a, b, n, c, _] = law;
        let eps = eps.max(0.0);
        let end = eps + dgamma;
        let hard = a * dgamma + b / (n + 1.0) * (end * end.powf(n) - eps * eps.powf(n));
        let rate_term = if rate > rate0 {
            1.0 + c * (rate / rate0).ln()
        } else {
            1.0
        };
        hard * rate_term * self.0
    }
}

/// Hensel and Spittel (1978), Kraft- und Arbeitsbedarf bildsamer Formgebungsverfahren, in
/// the form QForm and FORGE use: `sigma_y = A e^(m1 T) T^m9 eps^m2 e^(m4 / eps)
/// (1 + eps)^(m5 T) e^(m7 eps) rate^(m3 + m8 T)` (Pa), T in degrees C, evaluated as the
/// exponential of its logarithm. Strain, rate and temperature are held inside the fitted
/// `ranges = [strain, rate (1/s), T (degrees C)]`; a held input has no derivative.
/// `m = [m1, m2, m3, m4, m5, m7, m8, m9]`, `at = [eps_p, rate (1/s), T (degrees C)]`.
pub fn hensel_spittel(a: Real, m: [Real; 8], ranges: [[Real; 2]; 3], at: [Real; 3]) -> Flow {
    HenselSpittelAt::new(a, m, ranges, at[2]).flow(at[0], at[1])
}

/// Hensel-Spittel at one temperature: what depends on the temperature alone evaluated once
/// (per return map).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HenselSpittelAt {
    /// `ln A + m1 T + m9 ln T`.
    ln_base: Real,
    /// `m2`, `m4`, `m5 T`, `m7`.
    strain: [Real; 4],
    /// The rate exponent `m3 + m8 T`.
    rate_exponent: Real,
    /// The strain and rate ranges.
    ranges: [[Real; 2]; 2],
}

impl HenselSpittelAt {
    /// The law `(a, m, ranges)` of [`hensel_spittel`] at `temp` (degrees C, held in range).
    pub fn new(a: Real, m: [Real; 8], ranges: [[Real; 2]; 3], temp: Real) -> HenselSpittelAt {
        let [m1, m2, m3, m4, m5, m7, m8, m9] = m;
        let temp = temp.clamp(ranges[2][0], ranges[2][1]);
        let t_power = if m9 == 0.0 { 0.0 } else { m9 * temp.ln() };
        HenselSpittelAt {
            ln_base: a.ln() + m1 * temp + t_power,
            strain: [m2, m4, m5 * temp, m7],
            rate_exponent: m3 + m8 * temp,
            ranges: [ranges[0], ranges[1]],
        }
    }

    /// The flow stress and its derivatives at strain `eps` and rate `rate` (1/s).
    pub fn flow(&self, eps_in: Real, rate_in: Real) -> Flow {
        let [strains, rates] = self.ranges;
        let [m2, m4, m5t, m7] = self.strain;
        let eps = eps_in.clamp(strains[0], strains[1]);
        let rate = rate_in.clamp(rates[0], rates[1]);
        let ln_eps = lanes::ln(eps);
        let ln_stress = self.ln_base
            + m2 * ln_eps
            + m4 / eps
            + m5t * lanes::ln(1.0 + eps)
            + m7 * eps
            + self.rate_exponent * lanes::ln(rate);
        let stress = lanes::exp(ln_stress);
        let inside = |x: Real, r: [Real; 2]| x > r[0] && x < r[1];
        Flow {
            stress,
            d_strain: if inside(eps_in, strains) {
                stress * (m2 / eps - m4 / (eps * eps) + m5t / (1.0 + eps) + m7)
            } else {
                0.0
            },
            d_rate: if inside(rate_in, rates) {
                stress * self.rate_exponent / rate
            } else {
                0.0
            },
        }
    }
}

/// The gas constant `R` (J/(mol K)).
const GAS_CONSTANT: Real = 8.314_462_618;

/// Sellars and McG. Tegart (1966), Mem. Sci. Rev. Met. 63, 731: `sigma_y = asinh((Z /
/// A)^(1/n)) / alpha` (Pa) with `Z = rate exp(Q / (R T))`, T in kelvin; strain
/// independent. `law = [alpha (1/Pa), n, Q (J/mol), A (1/s)]`, `ranges = [rate (1/s), T
/// (degrees C)]` (held inside), `at = [rate (1/s), T (degrees C)]`.
pub fn sellars_tegart(law: [Real; 4], ranges: [[Real; 2]; 2], at: [Real; 2]) -> Flow {
    SellarsTegartAt::new(law, ranges, at[1]).flow(at[0])
}

/// Sellars-Tegart at one temperature: `Q / (R T) - ln A` evaluated once (per return map).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SellarsTegartAt {
    /// `Q / (R T) - ln A`.
    shift: Real,
    /// `alpha` (1/Pa) and `n`.
    alpha_n: [Real; 2],
    /// The rate range (1/s).
    rates: [Real; 2],
}

impl SellarsTegartAt {
    /// The law `(law, ranges)` of [`sellars_tegart`] at `temp` (degrees C, held in range).
    pub fn new(law: [Real; 4], ranges: [[Real; 2]; 2], temp: Real) -> SellarsTegartAt {
        let [alpha, n, q, a] = law;
        let temp_k = temp.clamp(ranges[1][0], ranges[1][1]) + 273.15;
        SellarsTegartAt {
            shift: q / (GAS_CONSTANT * temp_k) - a.ln(),
            alpha_n: [alpha, n],
            rates: ranges[0],
        }
    }

    /// The flow stress and its rate derivative at `rate_in` (1/s); no strain derivative.
    pub fn flow(&self, rate_in: Real) -> Flow {
        let [alpha, n] = self.alpha_n;
        let rate = rate_in.clamp(self.rates[0], self.rates[1]);
        // (Z / A)^(1/n) = exp((ln rate + Q / (R T) - ln A) / n); asinh u = ln(u + sqrt(1 + u^2)).
        let u = lanes::exp((lanes::ln(rate) + self.shift) / n);
        let root = (1.0 + u * u).sqrt();
        let inside = rate_in > self.rates[0] && rate_in < self.rates[1];
        Flow {
            stress: lanes::ln(u + root) / alpha,
            d_strain: 0.0,
            d_rate: if inside {
                u / (n * rate * alpha * root)
            } else {
                0.0
            },
        }
    }
}

/// Where `x` falls among the increasing `values`: the lower index of its interval and the
/// fraction along it, held at the ends (fraction 0 or 1, and `inside` false there).
fn locate(values: &[Real], x: Real) -> (usize, Real, bool) {
    if values.len() < 2 {
        return (0, 0.0, false);
    }
    let last = values.len() - 1;
    if x <= values[0] {
        return (0, 0.0, false);
    }
    if x >= values[last] {
        return (last - 1, 1.0, false);
    }
    let i = values
        .partition_point(|&v| v <= x)
        .saturating_sub(1)
        .min(last - 1);
    (i, (x - values[i]) / (values[i + 1] - values[i]), true)
}

/// A flow stress table over `axes = [strains, rates (1/s), temperatures (degrees C)]`,
/// `stress` entry `(k * rates + j) * strains + i` (Pa): linear in strain, in `ln(rate)`
/// and in temperature between the given values, held at the edges (DEFORM's flow-stress
/// data, Scientific Forming Technologies). `at = [eps_p, rate (1/s), T (degrees C)]`.
pub fn table(axes: [&[Real]; 3], stress: &[Real], at: [Real; 3]) -> Flow {
    let [strains, rates, temps] = axes;
    let (i, fi, in_i) = locate(strains, at[0]);
    // The rate's interval, then its fraction in ln(rate).
    let (j, mut fj, in_j) = locate(rates, at[1]);
    let ln_span = if rates.len() > 1 {
        (rates[j + 1] / rates[j]).ln()
    } else {
        1.0
    };
    if in_j {
        fj = (at[1] / rates[j]).ln() / ln_span;
    }
    let (k, fk, _) = locate(temps, at[2]);
    let (ns, nr) = (strains.len(), rates.len());
    let step = |n: usize, idx: usize| usize::from(n > 1 && idx + 1 < n);
    let (di, dj, dk) = (step(ns, i), step(nr, j), step(temps.len(), k));
    let entry = |a: usize, b: usize, c: usize| stress[(c * nr + b) * ns + a];
    // Bilinear in (strain, ln rate) at temperature row c, with its two slopes.
    let plane = |c: usize| {
        let s00 = entry(i, j, c);
        let s10 = entry(i + di, j, c);
        let s01 = entry(i, j + dj, c);
        let s11 = entry(i + di, j + dj, c);
        let low = s00 + fi * (s10 - s00);
        let high = s01 + fi * (s11 - s01);
        let value = low + fj * (high - low);
        let d_i = (s10 - s00) + fj * ((s11 - s01) - (s10 - s00));
        let d_j = high - low;
        (value, d_i, d_j)
    };
    let (v0, di0, dj0) = plane(k);
    let (v1, di1, dj1) = plane(k + dk);
    let mix = |a: Real, b: Real| a + fk * (b - a);
    let d_strain = if in_i {
        mix(di0, di1) / (strains[i + 1] - strains[i])
    } else {
        0.0
    };
    let d_rate = if in_j {
        mix(dj0, dj1) / ln_span / at[1]
    } else {
        0.0
    };
    Flow {
        stress: mix(v0, v1),
        d_strain,
        d_rate,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// OFHC copper (Johnson and Cook 1983, Table 1): A 90 MPa, B 292 MPa, n 0.31, C 0.025,
    /// m 1.09, T_melt 1356 K, from room temperature (20 degrees C) and 1/s.
    fn copper(at: [Real; 3]) -> Flow {
        johnson_cook(
            [90e6, 292e6, 0.31, 0.025, 1.09],
            1.0,
            [20.0, 1356.0 - 273.15],
            at,
        )
    }

    /// The law's value at hand-computed points, and its derivatives against central
    /// differences.
    #[test]
    fn johnson_cook_values_and_derivatives() {
        // eps 0.5, rate 1000/s, T 300 C.
        let f = copper([0.5, 1000.0, 300.0]);
        let t_star: Real = 280.0 / (1356.0 - 273.15 - 20.0);
        let expect = (90e6 + 292e6 * 0.5f64.powf(0.31))
            * (1.0 + 0.025 * 1000f64.ln())
            * (1.0 - t_star.powf(1.09));
        assert!(
            (f.stress - expect).abs() < 1e-9 * expect,
            "{} {expect}",
            f.stress
        );
        // Below the reference rate, and below the reference temperature: quasi-static, cold.
        let slow = copper([0.5, 0.1, 0.0]);
        assert!((slow.stress - (90e6 + 292e6 * 0.5f64.powf(0.31))).abs() < 1e-6);
        let h = 1e-6;
        let fd = (copper([0.5 + h, 1000.0, 300.0]).stress
            - copper([0.5 - h, 1000.0, 300.0]).stress)
            / (2.0 * h);
        assert!(
            (fd - f.d_strain).abs() < 1e-6 * f.d_strain.abs(),
            "{fd} {}",
            f.d_strain
        );
        let fr = (copper([0.5, 1000.0 + 1e-3, 300.0]).stress
            - copper([0.5, 1000.0 - 1e-3, 300.0]).stress)
            / 2e-3;
        assert!(
            (fr - f.d_rate).abs() < 1e-5 * f.d_rate.abs(),
            "{fr} {}",
            f.d_rate
        );
        assert!(copper([0.0, 1.0, 20.0]).d_strain.is_infinite());
    }

    /// A Hensel-Spittel law against its formula written with `powf`, its derivatives
    /// against central differences inside the ranges, and held inputs outside them.
    #[test]
    fn hensel_spittel_values_derivatives_and_ranges() {
        let m = [-0.0025, 0.2, 0.13, -0.01, -0.0003, 0.0, 0.0001, 0.1];
        let ranges = [[0.03, 1.5], [0.1, 100.0], [900.0, 1250.0]];
        let hs = |at: [Real; 3]| hensel_spittel(1500e6, m, ranges, at);
        let [m1, m2, m3, m4, m5, _, m8, m9] = m;
        let (e, r, t): (Real, Real, Real) = (0.4, 5.0, 1100.0);
        let expect = 1500e6
            * (m1 * t).exp()
            * t.powf(m9)
            * e.powf(m2)
            * (m4 / e).exp()
            * (1.0 + e).powf(m5 * t)
            * r.powf(m3)
            * r.powf(m8 * t);
        let f = hs([e, r, t]);
        assert!(
            (f.stress - expect).abs() < 1e-12 * expect,
            "{} {expect}",
            f.stress
        );
        let h = 1e-6;
        let fd = (hs([e + h, r, t]).stress - hs([e - h, r, t]).stress) / (2.0 * h);
        assert!((fd - f.d_strain).abs() < 1e-6 * f.d_strain.abs());
        let fr = (hs([e, r + 1e-5, t]).stress - hs([e, r - 1e-5, t]).stress) / 2e-5;
        assert!((fr - f.d_rate).abs() < 1e-6 * f.d_rate.abs());
        // Outside the ranges: held at the bound, no derivative along the held input.
        let low = hs([0.0, 0.0, 800.0]);
        assert_eq!(low.stress, hs([0.03, 0.1, 900.0]).stress);
        assert_eq!((low.d_strain, low.d_rate), (0.0, 0.0));
    }

    /// Sellars-Tegart against its formula written with `powf` and `asinh`, its rate derivative
    /// against central differences, and the hold outside the ranges.
    #[test]
    fn sellars_tegart_values_derivative_and_ranges() {
        // AA6082-like constants: alpha 0.045/MPa, n 3.976, Q 153 kJ/mol, A 2.39e8 /s.
        let law = [0.045e-6, 3.976, 153e3, 2.39e8];
        let ranges = [[0.01, 100.0], [350.0, 550.0]];
        let st = |at: [Real; 2]| sellars_tegart(law, ranges, at);
        let (r, t): (Real, Real) = (2.0, 450.0);
        let z: Real = r * (153e3 / (8.314_462_618 * (t + 273.15))).exp();
        let expect = (z / 2.39e8).powf(1.0 / 3.976).asinh() / 0.045e-6;
        let f = st([r, t]);
        assert!(
            (f.stress - expect).abs() < 1e-10 * expect,
            "{} {expect}",
            f.stress
        );
        let fr = (st([r + 1e-6, t]).stress - st([r - 1e-6, t]).stress) / 2e-6;
        assert!(
            (fr - f.d_rate).abs() < 1e-6 * f.d_rate.abs(),
            "{fr} {}",
            f.d_rate
        );
        assert_eq!(f.d_strain, 0.0);
        let held = st([1e-5, 300.0]);
        assert_eq!(held.stress, st([0.01, 350.0]).stress);
        assert_eq!(held.d_rate, 0.0);
    }

    /// A table sampled from a smooth law is that law at its nodes, linear between them in
    /// strain, `ln(rate)` and temperature, held outside; its slopes are the interval's.
    #[test]
    fn table_interpolates_and_holds() {
        let strains = [0.0, 0.5, 1.0];
        let rates = [1.0, 10.0, 100.0];
        let temps = [20.0, 520.0];
        let law = |e: Real, lr: Real, t: Real| 100e6 + 80e6 * e + 10e6 * lr - 0.1e6 * t;
        let mut stress = Vec::new();
        for &t in &temps {
            for &r in &rates {
                for &e in &strains {
                    stress.push(law(e, Real::ln(r), t));
                }
            }
        }
        let axes = [&strains[..], &rates[..], &temps[..]];
        // Trilinear reproduces a law linear in each of (eps, ln rate, T).
        let f = table(axes, &stress, [0.3, 30.0, 100.0]);
        let expect = law(0.3, Real::ln(30.0), 100.0);
        assert!((f.stress - expect).abs() < 1e-6, "{} {expect}", f.stress);
        assert!((f.d_strain - 80e6).abs() < 1e-3);
        assert!((f.d_rate - 10e6 / 30.0).abs() < 1e-6);
        // Held outside.
        let out = table(axes, &stress, [2.0, 1e4, 900.0]);
        assert!((out.stress - law(1.0, Real::ln(100.0), 520.0)).abs() < 1e-6);
        assert_eq!((out.d_strain, out.d_rate), (0.0, 0.0));
    }
}
