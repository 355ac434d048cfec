//! The `[material]` section: density, elastic constants and the hardening law, with what
//! they must be ([`MaterialSpec::check`]; that a law of rate and temperature needs
//! `[thermal]` is checked across the sections, `across_sections.rs`).

use crate::material::Hardening;
use crate::math::Real;
use crate::validation::{above_absolute_zero, pos, Checks};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Material constants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Mass density (kg/m^3).
    pub density_kg_per_m3: Real,
    /// Young's modulus (Pa).
    pub youngs_modulus_pa: Real,
    /// Poisson's ratio (-), in (-1, 0.5).
    pub poisson_ratio: Real,
    /// Isotropic hardening law (`law = "linear"`, `"power"`; with `[thermal]` also
    /// `"johnson_cook"`, `"hensel_spittel"`, `"sellars_tegart"`, `"table"`).
    pub hardening: Hardening,
}

impl MaterialSpec {
    /// Every value of the section a run cannot use, under its dotted key `material.*`:
    /// density, elastic constants and the hardening law.
    pub(crate) fn check(&self, out: &mut Checks) {
        out.check(
            pos(self.density_kg_per_m3),
            "material.density_kg_per_m3",
            format!("must be positive, got {}", self.density_kg_per_m3),
        );
        out.check(
            pos(self.youngs_modulus_pa),
            "material.youngs_modulus_pa",
            format!("must be positive, got {}", self.youngs_modulus_pa),
        );
        out.check(
            self.poisson_ratio.is_finite() && self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5,
            "material.poisson_ratio",
            format!("must lie in (-1, 0.5), got {}", self.poisson_ratio),
        );
        match self.hardening {
            Hardening::Linear {
                yield_stress_pa,
                modulus_pa,
            } => {
                out.check(
                    pos(yield_stress_pa),
                    "material.hardening.yield_stress_pa",
                    format!("must be positive, got {yield_stress_pa}"),
                );
                out.check(
                    modulus_pa.is_finite() && modulus_pa >= 0.0,
                    "material.hardening.modulus_pa",
                    format!("must be zero or positive, got {modulus_pa}"),
                );
            }
            Hardening::JohnsonCook { .. }
            | Hardening::HenselSpittel { .. }
            | Hardening::SellarsTegart { .. }
            | Hardening::Table { .. } => check_rate_temperature_law(&self.hardening, out),
            Hardening::Power { k_pa, eps0, n } => {
                out.check(
                    pos(k_pa),
                    "material.hardening.k_pa",
                    format!("must be positive, got {k_pa}"),
                );
                out.check(
                    pos(eps0),
                    "material.hardening.eps0",
                    format!("must be positive, got {eps0}"),
                );
                out.check(
                    n.is_finite() && (0.0..1.0).contains(&n),
                    "material.hardening.n",
                    format!("must lie in [0, 1), got {n}"),
                );
            }
        }
    }
}

/// A law of rate and temperature: finite constants in their ranges, increasing table axes.
fn check_rate_temperature_law(law: &Hardening, out: &mut Checks) {
    let key = |k: &str| format!("material.hardening.{k}");
    let increasing =
        |v: &[Real]| v.windows(2).all(|w| w[0] < w[1]) && v.iter().all(|x| x.is_finite());
    // A fitted range of a positive quantity (strain, strain rate).
    let positive_range = |out: &mut Checks, name: &str, range: &[Real; 2]| {
        out.check(
            pos(range[0]) && increasing(range),
            &key(name),
            format!("must be [least, largest] with 0 < least < largest, got {range:?}"),
        );
    };
    match law {
        Hardening::JohnsonCook {
            a_pa,
            b_pa,
            n,
            c,
            reference_strain_rate_per_s,
            m,
            reference_temperature_c,
            melting_temperature_c,
        } => {
            for (name, v) in [("a_pa", a_pa), ("b_pa", b_pa), ("n", n), ("c", c)] {
                out.check(
                    v.is_finite() && *v >= 0.0,
                    &key(name),
                    format!("must be zero or positive, got {v}"),
                );
            }
            out.check(
                pos(*a_pa + *b_pa),
                &key("a_pa"),
                "A + B must be positive".into(),
            );
            out.check(
                pos(*reference_strain_rate_per_s),
                &key("reference_strain_rate_per_s"),
                format!("must be positive, got {reference_strain_rate_per_s}"),
            );
            out.check(pos(*m), &key("m"), format!("must be positive, got {m}"));
            out.check(
                reference_temperature_c.is_finite()
                    && melting_temperature_c.is_finite()
                    && melting_temperature_c > reference_temperature_c,
                &key("melting_temperature_c"),
                format!(
                    "must be above reference_temperature_c ({reference_temperature_c}), got {melting_temperature_c}"
                ),
            );
        }
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
        } => {
            out.check(
                pos(*a_pa),
                &key("a_pa"),
                format!("must be positive, got {a_pa}"),
            );
            for (name, v) in [
                ("m1", m1),
                ("m2", m2),
                ("m3", m3),
                ("m4", m4),
                ("m5", m5),
                ("m7", m7),
                ("m8", m8),
                ("m9", m9),
            ] {
                out.check(
                    v.is_finite(),
                    &key(name),
                    format!("must be finite, got {v}"),
                );
            }
            positive_range(out, "strain_range", strain_range);
            positive_range(out, "strain_rate_range_per_s", strain_rate_range_per_s);
            out.check(
                increasing(temperature_range_c) && (*m9 == 0.0 || temperature_range_c[0] > 0.0),
                &key("temperature_range_c"),
                format!(
                    "must be [least, largest] with least < largest (and least > 0 with m9 set), got {temperature_range_c:?}"
                ),
            );
        }
        Hardening::SellarsTegart {
            alpha_per_pa,
            n,
            activation_energy_j_per_mol,
            a_per_s,
            strain_rate_range_per_s,
            temperature_range_c,
        } => {
            for (name, v) in [
                ("alpha_per_pa", alpha_per_pa),
                ("n", n),
                ("activation_energy_j_per_mol", activation_energy_j_per_mol),
                ("a_per_s", a_per_s),
            ] {
                out.check(pos(*v), &key(name), format!("must be positive, got {v}"));
            }
            positive_range(out, "strain_rate_range_per_s", strain_rate_range_per_s);
            out.check(
                increasing(temperature_range_c) && above_absolute_zero(temperature_range_c[0]),
                &key("temperature_range_c"),
                format!(
                    "must be [least, largest] above absolute zero with least < largest, got {temperature_range_c:?}"
                ),
            );
        }
        Hardening::Table {
            strains,
            strain_rates_per_s,
            temperatures_c,
            flow_stress_pa,
        } => {
            for (name, axis) in [
                ("strains", strains),
                ("strain_rates_per_s", strain_rates_per_s),
                ("temperatures_c", temperatures_c),
            ] {
                out.check(
                    !axis.is_empty() && increasing(axis),
                    &key(name),
                    format!("must be one or more increasing values, got {axis:?}"),
                );
            }
            out.check(
                strain_rates_per_s.iter().all(|&r| pos(r)),
                &key("strain_rates_per_s"),
                "every rate must be positive".into(),
            );
            let cells = strains.len() * strain_rates_per_s.len() * temperatures_c.len();
            out.check(
                flow_stress_pa.len() == cells,
                &key("flow_stress_pa"),
                format!(
                    "needs {} x {} x {} = {cells} values (strains x rates x temperatures), got {}",
                    strains.len(),
                    strain_rates_per_s.len(),
                    temperatures_c.len(),
                    flow_stress_pa.len()
                ),
            );
            if let Some(i) = flow_stress_pa.iter().position(|&s| !pos(s)) {
                out.check(
                    false,
                    &key("flow_stress_pa"),
                    format!("entry {i} must be positive, got {}", flow_stress_pa[i]),
                );
            }
        }
        Hardening::Linear { .. } | Hardening::Power { .. } => {}
    }
}
