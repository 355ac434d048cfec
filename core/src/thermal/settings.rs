//! The `[thermal]` section of a scene: the workpiece's initial temperature, heat capacity
//! and conductivity, the share of plastic and friction work that becomes heat, the
//! surroundings, elasticity over temperature, the heat stage's accuracy; what each value
//! must be ([`ThermalSpec::check`]), and the properties ([`super::properties`]) it gives.

use super::properties::{interpolate, Expansion, HeatCapacity, Thermoelastic};
use crate::math::Real;
use crate::validation::{above_absolute_zero, increasing_table, pos, Checks};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Temperature and heat in the workpiece (`[thermal]`): its initial temperature, heat
/// capacity and conductivity, and the share of plastic work that becomes heat. Needed by
/// the flow stresses of rate and temperature (`material.hardening.law = "johnson_cook"`,
/// `"hensel_spittel"`, `"table"`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ThermalSpec {
    /// Initial temperature of the workpiece (degrees C).
    pub initial_temperature_c: Real,
    /// Specific heat capacity `c` (J/(kg K)), of the physical density: mass scaling adds
    /// inertia, never heat capacity. 0 (the default) when `specific_heat_by_temperature`
    /// gives it.
    #[serde(default)]
    pub specific_heat_j_per_kg_k: Real,
    /// Specific heat capacity over temperature instead of the constant: `[[T (degrees C), c
    /// (J/(kg K))], ...]`, T increasing, linear between the points and held beyond them.
    /// The heat held is the enthalpy `int c dT`, kept exactly as the capacity changes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub specific_heat_by_temperature: Vec<[Real; 2]>,
    /// Taylor-Quinney coefficient `beta` (-): the fraction of the plastic work that becomes
    /// heat (Taylor and Quinney 1934); 0.9 by default.
    #[serde(default = "taylor_quinney")]
    pub taylor_quinney: Real,
    /// Thermal conductivity `k` (W/(m K)); 0 (the default): no conduction in the workpiece.
    #[serde(default)]
    pub conductivity_w_per_m_k: Real,
    /// Conductivity over temperature instead of the constant: `[[T (degrees C), k
    /// (W/(m K))], ...]`, T increasing, linear between the points and held beyond them; each
    /// integration point conducts at its own temperature.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub conductivity_by_temperature: Vec<[Real; 2]>,
    /// Temperature of the surroundings, for convection and radiation (degrees C); 20 by
    /// default.
    #[serde(default = "ambient")]
    pub ambient_temperature_c: Real,
    /// Convection coefficient from the free surface to the surroundings (W/(m^2 K)); 0 by
    /// default.
    #[serde(default)]
    pub convection_w_per_m2_k: Real,
    /// Emissivity of the free surface for radiation to the surroundings (-), in [0, 1]; 0
    /// by default.
    #[serde(default)]
    pub emissivity: Real,
    /// Fraction of the heat stage's critical step it takes (-), in (0, 1]; 0.5 by default.
    /// The heat stage runs when that much time has passed since its last run (sub-cycled:
    /// the thermal step is far longer than the mechanical one).
    #[serde(default = "half")]
    pub dt_safety: Real,
    /// The largest temperature change of a particle in one heat step (K), the heat stage's
    /// accuracy: the step grows (at most doubling) while the changes stay below it and
    /// shrinks (at most halving) when they pass it, within the stable step. 5 K by default.
    #[serde(default = "five")]
    pub max_change_per_step_k: Real,
    /// The share of the friction work at a tool that heats the workpiece (-), in [0, 1]; the
    /// tool takes the rest. 0.5 by default (equal shares).
    #[serde(default = "half")]
    pub friction_heat_to_workpiece: Real,
    /// Young's modulus over temperature, as a factor on `material.youngs_modulus_pa`:
    /// `[[T (degrees C), E(T) / E], ...]`, T increasing, linear between the points and held
    /// beyond them (Poisson's ratio held). Absent: the modulus of every temperature.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub modulus_factor_by_temperature: Vec<[Real; 2]>,
    /// Thermal expansion, a constant secant coefficient `alpha` (1/K): the thermal stretch
    /// `1 + alpha (T - T_0)` from the initial temperature, where the body is free of stress.
    /// 0 (the default): none.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub expansion_per_k: Real,
    /// Thermal expansion as the linear thermal strain over temperature instead of the
    /// coefficient: `[[T (degrees C), dl/l], ...]` from any reference, T increasing, linear
    /// between the points and held beyond them; the thermal stretch is `(1 + s(T)) / (1 +
    /// s(T_0))`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub thermal_strain_by_temperature: Vec<[Real; 2]>,
}

impl ThermalSpec {
    /// The conductivity at `temp_c` (degrees C): the table's, linear between its points and
    /// held beyond them, or the constant (W/(m K)).
    pub fn conductivity_at(&self, temp_c: Real) -> Real {
        if self.conductivity_by_temperature.is_empty() {
            self.conductivity_w_per_m_k
        } else {
            interpolate(&self.conductivity_by_temperature, temp_c)
        }
    }

    /// The elasticity over temperature the section asks for, `None` when it asks for none
    /// (the modulus and no thermal strain at every temperature).
    pub fn thermoelastic(&self) -> Option<Thermoelastic> {
        let expansion = if !self.thermal_strain_by_temperature.is_empty() {
            let points = self.thermal_strain_by_temperature.clone();
            let at_start = 1.0 + interpolate(&points, self.initial_temperature_c);
            Expansion::Table { points, at_start }
        } else if self.expansion_per_k != 0.0 {
            Expansion::Coefficient {
                per_k: self.expansion_per_k,
                from_c: self.initial_temperature_c,
            }
        } else {
            Expansion::None
        };
        (expansion != Expansion::None || !self.modulus_factor_by_temperature.is_empty()).then(
            || Thermoelastic {
                modulus_factor: self.modulus_factor_by_temperature.clone(),
                expansion,
            },
        )
    }

    /// The specific heat capacity, the constant or the table (J/(kg K)).
    pub fn heat_capacity(&self) -> HeatCapacity {
        HeatCapacity::new(
            self.specific_heat_j_per_kg_k,
            &self.specific_heat_by_temperature,
        )
    }

    /// The largest conductivity the scene can take (W/(m K)), for the stable heat step.
    pub fn conductivity_max(&self) -> Real {
        self.conductivity_by_temperature
            .iter()
            .map(|p| p[1])
            .fold(self.conductivity_w_per_m_k, Real::max)
    }

    /// Every value of the section a run cannot use, under its dotted key `thermal.*`.
    pub(crate) fn check(&self, out: &mut Checks) {
        out.check(
            self.conductivity_w_per_m_k.is_finite() && self.conductivity_w_per_m_k >= 0.0,
            "thermal.conductivity_w_per_m_k",
            format!(
                "must be zero or positive, got {}",
                self.conductivity_w_per_m_k
            ),
        );
        let table = &self.conductivity_by_temperature;
        out.check(
            table.is_empty() || self.conductivity_w_per_m_k == 0.0,
            "thermal.conductivity_by_temperature",
            "give the conductivity as a constant or as a table over temperature, not both".into(),
        );
        out.check(
            increasing_table(table, |k| k >= 0.0),
            "thermal.conductivity_by_temperature",
            format!(
                "must be [[T, k], ...] with T increasing and k zero or positive, got {table:?}"
            ),
        );
        out.check(
            above_absolute_zero(self.ambient_temperature_c),
            "thermal.ambient_temperature_c",
            format!(
                "must be above absolute zero (-273.15), got {}",
                self.ambient_temperature_c
            ),
        );
        out.check(
            self.convection_w_per_m2_k.is_finite() && self.convection_w_per_m2_k >= 0.0,
            "thermal.convection_w_per_m2_k",
            format!(
                "must be zero or positive, got {}",
                self.convection_w_per_m2_k
            ),
        );
        out.check(
            self.emissivity.is_finite() && (0.0..=1.0).contains(&self.emissivity),
            "thermal.emissivity",
            format!("must lie in [0, 1], got {}", self.emissivity),
        );
        out.check(
            pos(self.dt_safety) && self.dt_safety <= 1.0,
            "thermal.dt_safety",
            format!("must lie in (0, 1], got {}", self.dt_safety),
        );
        out.check(
            (0.0..=1.0).contains(&self.friction_heat_to_workpiece),
            "thermal.friction_heat_to_workpiece",
            format!(
                "must lie in [0, 1], got {}",
                self.friction_heat_to_workpiece
            ),
        );
        out.check(
            pos(self.max_change_per_step_k),
            "thermal.max_change_per_step_k",
            format!("must be positive, got {}", self.max_change_per_step_k),
        );
        out.check(
            above_absolute_zero(self.initial_temperature_c),
            "thermal.initial_temperature_c",
            format!(
                "must be above absolute zero (-273.15), got {}",
                self.initial_temperature_c
            ),
        );
        let table = &self.modulus_factor_by_temperature;
        out.check(
            increasing_table(table, pos),
            "thermal.modulus_factor_by_temperature",
            format!("must be [[T, E(T) / E], ...] with T increasing and factors positive, got {table:?}"),
        );
        out.check(
            self.expansion_per_k.is_finite() && self.expansion_per_k.abs() < 1e-3,
            "thermal.expansion_per_k",
            format!(
                "must be a thermal expansion coefficient (1/K) below 1e-3 in size, got {}",
                self.expansion_per_k
            ),
        );
        let table = &self.thermal_strain_by_temperature;
        out.check(
            table.is_empty() || self.expansion_per_k == 0.0,
            "thermal.thermal_strain_by_temperature",
            "give the thermal expansion as a coefficient or as a strain over temperature, not both"
                .into(),
        );
        out.check(
            increasing_table(table, |s| s.abs() < 0.5),
            "thermal.thermal_strain_by_temperature",
            format!(
                "must be [[T, dl/l], ...] with T increasing and strains below 0.5 in size, got \
                 {table:?}"
            ),
        );
        let table = &self.specific_heat_by_temperature;
        if table.is_empty() {
            out.check(
                pos(self.specific_heat_j_per_kg_k),
                "thermal.specific_heat_j_per_kg_k",
                format!(
                    "must be positive (or give specific_heat_by_temperature), got {}",
                    self.specific_heat_j_per_kg_k
                ),
            );
        } else {
            out.check(
                self.specific_heat_j_per_kg_k == 0.0,
                "thermal.specific_heat_by_temperature",
                "give the specific heat as a constant or as a table over temperature, not both"
                    .into(),
            );
            out.check(
                increasing_table(table, pos),
                "thermal.specific_heat_by_temperature",
                format!("must be [[T, c], ...] with T increasing and c positive, got {table:?}"),
            );
        }
        out.check(
            self.taylor_quinney.is_finite() && (0.0..=1.0).contains(&self.taylor_quinney),
            "thermal.taylor_quinney",
            format!("must lie in [0, 1], got {}", self.taylor_quinney),
        );
    }
}

fn taylor_quinney() -> Real {
    0.9
}

fn ambient() -> Real {
    20.0
}

fn half() -> Real {
    0.5
}

fn five() -> Real {
    5.0
}

fn is_zero(x: &Real) -> bool {
    *x == 0.0
}
