//! Isotropic hardening laws: flow stress as a function of the equivalent plastic strain.

use crate::lanes;
use crate::math::Real;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Flow stress `sigma_y(eps_p)` (Pa) as a function of equivalent plastic strain (-).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
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
}

impl Hardening {
    /// Flow stress `sigma_y(eps_p)` (Pa). The power law is `K exp(n ln(eps0 + eps_p))`
    /// with [`lanes::ln`] and [`lanes::exp`], written exactly as the return map in lanes
    /// writes it, so the flow stress it leaves in a lane has these bits.
    #[inline(always)]
    pub fn flow_stress(&self, eps_p: Real) -> Real {
        match *self {
            Hardening::Linear {
                yield_stress_pa,
                modulus_pa,
            } => yield_stress_pa + modulus_pa * eps_p,
            Hardening::Power { k_pa, eps0, n } => k_pa * lanes::exp(n * lanes::ln(eps0 + eps_p)),
        }
    }

    /// Hardening slope `d sigma_y / d eps_p` (Pa) given the flow stress `flow` at `eps_p`:
    /// `H`, or `n sigma_y / (eps0 + eps_p)` for the power law.
    #[inline(always)]
    pub fn slope_at(&self, eps_p: Real, flow: Real) -> Real {
        match *self {
            Hardening::Linear { modulus_pa, .. } => modulus_pa,
            Hardening::Power { eps0, n, .. } => n * flow / (eps0 + eps_p),
        }
    }

    /// Initial yield stress `sigma_y(0)` (Pa).
    pub fn initial_yield(&self) -> Real {
        self.flow_stress(0.0)
    }

    /// Plastic work density `int_0^eps_p sigma_y de` (J/m^3), exact for both laws.
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
