//! Isotropic hardening laws: the flow stress as a function of the equivalent plastic
//! strain (linear, power), or of plastic strain, plastic strain rate and temperature
//! (Johnson-Cook, Hensel-Spittel, a table: [`super::rate_temperature`]).

use super::rate_temperature::{self, Flow, HenselSpittelAt, SellarsTegartAt, Softening};
use crate::lanes;
use crate::math::Real;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Flow stress `sigma_y(eps_p)` (Pa) as a function of equivalent plastic strain (-), or
/// `sigma_y(eps_p, rate, T)` of strain, plastic strain rate (1/s) and temperature (degrees C)
/// for the laws of hot forging and impact, which need the scene's `[thermal]` section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "law", rename_all = "snake_case", deny_unknown_fields)]
pub enum Hardening {
    /// Linear: `sigma_y = sigma_y0 + H eps_p` (paper Table 2: 400 MPa, H = 100 MPa).
    Linear {
        /// Initial yield stress `sigma_y0` (Pa).
        yield_stress_pa: Real,
        /// Plastic hardening modulus `H` (Pa).
        modulus_pa: Real,
    },
    /// Power law (Swift): `sigma_y = K (eps0 + eps_p)^n`
    /// (paper Table 4: K = 576.79 MPa, eps0 = 0.01658, n = 0.3593).
    Power {
        /// Strength coefficient `K` (Pa).
        k_pa: Real,
        /// Pre-strain `eps0` (-), > 0 so that the initial yield `K eps0^n` is finite and positive.
        eps0: Real,
        /// Hardening exponent `n` (-).
        n: Real,
    },
    /// Johnson and Cook (1983): `sigma_y = (A + B eps^n) (1 + C ln(rate / rate0))
    /// (1 - T*^m)`, `T* = (T - T_ref) / (T_melt - T_ref)`; no rate effect below `rate0`
    /// (`rate / rate0` held at 1) and `T*` held in `[0, 1]`.
    JohnsonCook {
        /// Yield stress `A` (Pa).
        a_pa: Real,
        /// Hardening coefficient `B` (Pa).
        b_pa: Real,
        /// Hardening exponent `n` (-).
        n: Real,
        /// Strain-rate coefficient `C` (-).
        c: Real,
        /// Reference plastic strain rate `rate0` (1/s).
        reference_strain_rate_per_s: Real,
        /// Thermal-softening exponent `m` (-).
        m: Real,
        /// Temperature `T_ref` at which `A`, `B`, `n` were measured (degrees C).
        reference_temperature_c: Real,
        /// Melting temperature `T_melt` (degrees C).
        melting_temperature_c: Real,
    },
    /// Hensel and Spittel (1978), as QForm and FORGE write it: `sigma_y = A e^(m1 T) T^m9
    /// eps^m2 e^(m4 / eps) (1 + eps)^(m5 T) e^(m7 eps) rate^(m3 + m8 T)`, T in degrees C;
    /// strain, rate and temperature held inside the ranges the parameters were fitted on.
    HenselSpittel {
        /// `A` (Pa).
        a_pa: Real,
        /// `m1` (1/degree C).
        m1: Real,
        /// `m2` (-), the strain exponent.
        m2: Real,
        /// `m3` (-), the strain-rate exponent.
        m3: Real,
        /// `m4` (-), in `e^(m4 / eps)`.
        #[serde(default)]
        m4: Real,
        /// `m5` (1/degree C), in `(1 + eps)^(m5 T)`.
        #[serde(default)]
        m5: Real,
        /// `m7` (-), in `e^(m7 eps)`.
        #[serde(default)]
        m7: Real,
        /// `m8` (1/degree C), in `rate^(m8 T)`.
        #[serde(default)]
        m8: Real,
        /// `m9` (-), in `T^m9`.
        #[serde(default)]
        m9: Real,
        /// Strains the parameters were fitted on, `[least, largest]` (-); the least > 0.
        strain_range: [Real; 2],
        /// Strain rates the parameters were fitted on, `[least, largest]` (1/s).
        strain_rate_range_per_s: [Real; 2],
        /// Temperatures the parameters were fitted on, `[least, largest]` (degrees C).
        temperature_range_c: [Real; 2],
    },
    /// Sellars and McG. Tegart (1966), the hyperbolic-sine law of hot working, strain
    /// independent (the steady flow of aluminium alloys at extrusion and forging heat):
    /// `sigma_y = asinh((Z / A)^(1/n)) / alpha` with the Zener-Hollomon parameter
    /// `Z = rate exp(Q / (R T))`, T in kelvin; rate and temperature held inside the fitted
    /// ranges.
    SellarsTegart {
        /// `alpha` (1/Pa).
        alpha_per_pa: Real,
        /// The stress exponent `n` (-).
        n: Real,
        /// The activation energy `Q` (J/mol).
        activation_energy_j_per_mol: Real,
        /// `A` (1/s).
        a_per_s: Real,
        /// Strain rates the constants were fitted on, `[least, largest]` (1/s).
        strain_rate_range_per_s: [Real; 2],
        /// Temperatures the constants were fitted on, `[least, largest]` (degrees C).
        temperature_range_c: [Real; 2],
    },
    /// A table over strain, strain rate and temperature (as DEFORM reads flow curves):
    /// linear in strain, in `ln(rate)` and in temperature between the given values, held
    /// at the table's edges.
    Table {
        /// Plastic strains, increasing (-).
        strains: Vec<Real>,
        /// Plastic strain rates, increasing, positive (1/s).
        strain_rates_per_s: Vec<Real>,
        /// Temperatures, increasing (degrees C).
        temperatures_c: Vec<Real>,
        /// Flow stresses (Pa), temperature by temperature, within one temperature rate by
        /// rate, within one rate strain by strain: entry `(k * rates + j) * strains + i`.
        flow_stress_pa: Vec<Real>,
    },
}

impl Hardening {
    /// Flow stress `sigma_y(eps_p)` (Pa). The power law is `K exp(n ln(eps0 + eps_p))`
    /// with [`lanes::ln`] and [`lanes::exp`], written exactly as the return map in lanes
    /// writes it, so the flow stress it leaves in a lane has these bits.
    /// The laws of rate and temperature give their flow stress at their least rate and
    /// `T = 0` degrees C here; the solver evaluates them with [`Hardening::flow`].
    #[inline(always)]
    pub fn flow_stress(&self, eps_p: Real) -> Real {
        match *self {
            Hardening::Linear {
                yield_stress_pa,
                modulus_pa,
            } => yield_stress_pa + modulus_pa * eps_p,
            Hardening::Power { k_pa, eps0, n } => k_pa * lanes::exp(n * lanes::ln(eps0 + eps_p)),
            _ => self.flow(eps_p, 0.0, 0.0).stress,
        }
    }

    /// Whether the flow stress depends on strain rate and temperature (the law needs the
    /// scene's `[thermal]` section and the solver's rate-consistent return map).
    pub fn is_thermal(&self) -> bool {
        !matches!(self, Hardening::Linear { .. } | Hardening::Power { .. })
    }

    /// Flow stress and its partial derivatives at plastic strain `eps_p` (-), plastic strain
    /// rate `rate` (1/s; held at the law's least rate below it) and temperature `temp_c`
    /// (degrees C). Linear and power laws ignore rate and temperature.
    pub fn flow(&self, eps_p: Real, rate: Real, temp_c: Real) -> Flow {
        self.isotherm(temp_c).flow(eps_p, rate)
    }

    /// The law at one temperature (degrees C), with what depends on the temperature alone
    /// evaluated once (Johnson-Cook's softening `1 - T*^m`): the return map iterates on it.
    pub fn isotherm(&self, temp_c: Real) -> Isotherm<'_> {
        match *self {
            Hardening::JohnsonCook {
                a_pa,
                b_pa,
                n,
                c,
                reference_strain_rate_per_s,
                m,
                reference_temperature_c,
                melting_temperature_c,
            } => Isotherm::JohnsonCook {
                law: [a_pa, b_pa, n, c, m],
                rate0: reference_strain_rate_per_s,
                softening: rate_temperature::johnson_cook_softening(
                    m,
                    [reference_temperature_c, melting_temperature_c],
                    temp_c,
                ),
            },
            Hardening::HenselSpittel {
                a_pa,
                m1,
                m2,
                m3,
                m4,
                m5,
                m7,
                m8,
                m9,
                strain_range,
                strain_rate_range_per_s,
                temperature_range_c,
            } => Isotherm::HenselSpittel(HenselSpittelAt::new(
                a_pa,
                [m1, m2, m3, m4, m5, m7, m8, m9],
                [strain_range, strain_rate_range_per_s, temperature_range_c],
                temp_c,
            )),
            Hardening::SellarsTegart {
                alpha_per_pa,
                n,
                activation_energy_j_per_mol,
                a_per_s,
                strain_rate_range_per_s,
                temperature_range_c,
            } => Isotherm::SellarsTegart(SellarsTegartAt::new(
                [alpha_per_pa, n, activation_energy_j_per_mol, a_per_s],
                [strain_rate_range_per_s, temperature_range_c],
                temp_c,
            )),
            _ => Isotherm::Any { law: self, temp_c },
        }
    }

    /// [`Hardening::flow`] for the laws that [`Isotherm`] does not specialise (linear, power,
    /// table).
    fn flow_any(&self, eps_p: Real, rate: Real, temp_c: Real) -> Flow {
        match self {
            Hardening::Linear { .. } | Hardening::Power { .. } => {
                let stress = self.flow_stress(eps_p);
                Flow {
                    stress,
                    d_strain: self.slope_at(eps_p, stress),
                    d_rate: 0.0,
                }
            }
            // Specialised in `isotherm`, which never hands them here.
            Hardening::JohnsonCook { .. }
            | Hardening::HenselSpittel { .. }
            | Hardening::SellarsTegart { .. } => self.isotherm(temp_c).flow(eps_p, rate),
            Hardening::Table {
                strains,
                strain_rates_per_s,
                temperatures_c,
                flow_stress_pa,
            } => rate_temperature::table(
                [strains, strain_rates_per_s, temperatures_c],
                flow_stress_pa,
                [eps_p, rate, temp_c],
            ),
        }
    }

    /// Hardening slope `d sigma_y / d eps_p` (Pa) given the flow stress `flow` at `eps_p`:
    /// `H`, or `n sigma_y / (eps0 + eps_p)` for the power law.
    #[inline(always)]
    pub fn slope_at(&self, eps_p: Real, flow: Real) -> Real {
        match *self {
            Hardening::Linear { modulus_pa, .. } => modulus_pa,
            Hardening::Power { eps0, n, .. } => n * flow / (eps0 + eps_p),
            _ => self.flow(eps_p, 0.0, 0.0).d_strain,
        }
    }

    /// Initial yield stress `sigma_y(0)` (Pa).
    pub fn initial_yield(&self) -> Real {
        self.flow_stress(0.0)
    }

    /// Plastic work density `int_0^eps_p sigma_y de` (J/m^3), exact for the linear and power
    /// laws (NaN for the laws of rate and temperature, whose work depends on the path).
    pub fn plastic_work(&self, eps_p: Real) -> Real {
        self.plastic_work_at(eps_p, self.flow_stress(eps_p), self.initial_yield())
    }

    /// Plastic work density (J/m^3) given the flow stresses `flow` at `eps_p` and
    /// `initial` at 0 (Pa): for the power law `K / (n + 1) ((eps0 + eps_p)^(n+1) -
    /// eps0^(n+1)) = ((eps0 + eps_p) sigma_y(eps_p) - eps0 sigma_y(0)) / (n + 1)`, so no
    /// power is evaluated.
    #[inline]
    pub fn plastic_work_at(&self, eps_p: Real, flow: Real, initial: Real) -> Real {
        match *self {
            Hardening::Linear {
                yield_stress_pa,
                modulus_pa,
            } => yield_stress_pa * eps_p + 0.5 * modulus_pa * eps_p * eps_p,
            Hardening::Power { eps0, n, .. } => {
                ((eps0 + eps_p) * flow - eps0 * initial) / (n + 1.0)
            }
            // Rate and temperature laws: the solver sums sigma_y d eps_p step by step.
            _ => Real::NAN,
        }
    }
}

/// A hardening law at one temperature ([`Hardening::isotherm`]).
#[derive(Debug, Clone, Copy)]
pub enum Isotherm<'a> {
    /// Johnson-Cook with its softening factor evaluated.
    JohnsonCook {
        /// `[A (Pa), B (Pa), n, C, m]`.
        law: [Real; 5],
        /// Reference rate (1/s).
        rate0: Real,
        /// `1 - T*^m` at the temperature.
        softening: Softening,
    },
    /// Hensel-Spittel with its temperature terms evaluated.
    HenselSpittel(HenselSpittelAt),
    /// Sellars-Tegart with its temperature term evaluated.
    SellarsTegart(SellarsTegartAt),
    /// Any other law, evaluated whole at `temp_c` (degrees C).
    Any {
        /// The law.
        law: &'a Hardening,
        /// Temperature (degrees C).
        temp_c: Real,
    },
}

impl Isotherm<'_> {
    /// Flow stress and its derivatives at plastic strain `eps_p` and rate `rate` (1/s).
    #[inline]
    pub fn flow(&self, eps_p: Real, rate: Real) -> Flow {
        match *self {
            Isotherm::JohnsonCook {
                law,
                rate0,
                softening,
            } => softening.flow(law, rate0, eps_p, rate),
            Isotherm::HenselSpittel(at) => at.flow(eps_p, rate),
            Isotherm::SellarsTegart(at) => at.flow(rate),
            Isotherm::Any { law, temp_c } => law.flow_any(eps_p, rate, temp_c),
        }
    }

    /// Plastic work density `int sigma_y d eps` (J/m^3) over a step from `eps_p` to
    /// `eps_p + dgamma` at the constant rate `rate` (1/s), `end` the flow stress at its end
    /// (Pa): exact for Johnson-Cook and Sellars-Tegart, Simpson's rule for the other laws
    /// (whose strain terms have no closed-form integral worth its cost).
    #[inline]
    pub fn work(&self, eps_p: Real, dgamma: Real, rate: Real, end: Real) -> Real {
        match *self {
            Isotherm::JohnsonCook {
                law,
                rate0,
                softening,
            } => softening.work(law, rate0, eps_p, dgamma, rate),
            // Strain independent: the flow stress is constant over the step.
            Isotherm::SellarsTegart(_) => end * dgamma,
            Isotherm::HenselSpittel(_) | Isotherm::Any { .. } => {
                let start = self.flow(eps_p, rate).stress;
                let mid = self.flow(eps_p + 0.5 * dgamma, rate).stress;
                (start + 4.0 * mid + end) * dgamma / 6.0
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_table_4_initial_yield_is_132_mpa() {
        let h = Hardening::Power {
            k_pa: 576.79e6,
            eps0: 0.01658,
            n: 0.3593,
        };
        assert!(
            (h.initial_yield() / 1e6 - 132.2).abs() < 0.1,
            "{}",
            h.initial_yield()
        );
    }

    /// The power law through the lanes' `exp` and `ln`, and its work through the flow
    /// stress, agree with `powf` of the C library to round-off (the work relative to the
    /// `eps0 sigma_y(0)` that both forms subtract).
    #[test]
    fn power_law_matches_powf() {
        let (k, eps0, n) = (576.79e6, 0.01658, 0.3593);
        let h = Hardening::Power { k_pa: k, eps0, n };
        for &e in &[0.0, 1e-9, 1e-4, 0.01, 0.3, 1.0, 2.5, 10.0] {
            let flow: Real = k * (eps0 + e).powf(n);
            let work: Real = k / (n + 1.0) * ((eps0 + e).powf(n + 1.0) - eps0.powf(n + 1.0));
            assert!(
                (h.flow_stress(e) - flow).abs() <= 4e-16 * flow,
                "{e}: {} {flow}",
                h.flow_stress(e)
            );
            // Both forms subtract eps0 sigma_y(0) (J/m^3): round-off relative to that.
            let scale = work + eps0 * h.initial_yield();
            assert!((h.plastic_work(e) - work).abs() <= 2e-15 * scale, "{e}");
        }
    }

    #[test]
    fn slope_and_work_are_consistent_with_flow_stress() {
        let laws = [
            Hardening::Linear {
                yield_stress_pa: 400e6,
                modulus_pa: 100e6,
            },
            Hardening::Power {
                k_pa: 576.79e6,
                eps0: 0.01658,
                n: 0.3593,
            },
        ];
        for h in laws {
            for &e in &[0.0, 0.1, 1.0, 2.5] {
                let d = 1e-7;
                let fd = (h.flow_stress(e + d) - h.flow_stress((e - d).max(0.0)))
                    / (e + d - (e - d).max(0.0));
                let slope = h.slope_at(e, h.flow_stress(e));
                assert!(
                    (fd - slope).abs() < 1e-4 * slope.abs().max(1.0),
                    "{h:?} {e}"
                );
                let fw = (h.plastic_work(e + d) - h.plastic_work((e - d).max(0.0)))
                    / (e + d - (e - d).max(0.0));
                assert!(
                    (fw - h.flow_stress(e)).abs() < 1e-5 * h.flow_stress(e),
                    "{h:?} {e}"
                );
            }
        }
    }
}
