//! Temperature and heat of a scene with a `[thermal]` section: the temperature of each
//! integration point, raised in the stress stage by its share of the plastic work,
//! `dT_p = beta sigma_y dgamma / (rho_0 c)` (K), with `sigma_y` the flow stress of the
//! rate-consistent return and `rho_0` the physical density (mass scaling never enters), so
//! that `rho_0 c (T_p - T_0) = beta W_p` point by point (adiabatic heating, Taylor and
//! Quinney 1934); with a capacity over temperature the enthalpy takes it, `rho_0 (h(T_p) -
//! h(T_0)) = beta W_p`, `h = int c dT`. The plastic work density `W_p = sum sigma_y dgamma`
//! (J/m^3) is summed step by step, as a flow stress of rate and temperature has no
//! closed-form work (the linear and power laws add the difference of theirs).

use crate::material::HeatCapacity;
use crate::math::Real;
use crate::scene::ThermalSpec;
use serde::{Deserialize, Serialize};

/// The changing thermal state of the workpiece (part of [`super::State`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Heat {
    /// Temperature of each integration point (degrees C).
    pub temperature_c: Vec<Real>,
    /// Plastic work density of each point since the start, `sum sigma_y dgamma` (J/m^3,
    /// per reference volume).
    pub plastic_work: Vec<Real>,
    /// Plastic strain rate of each point at the last stress stage, `dgamma / dt` (1/s; 0
    /// where it stayed elastic): the rate its flow stress was evaluated at.
    pub plastic_rate: Vec<Real>,
    /// Temperature of each particle (degrees C), the field the heat stage conducts, when the
    /// scene's heat moves (empty otherwise); the points hold `sum_I N_I T_I` after each heat
    /// stage plus what plastic work added since.
    pub particle_c: Vec<Real>,
    /// Time since the heat stage last ran (s).
    pub since_s: Real,
    /// The heat step the last heat stage found stable (s); 0 before the first, which runs
    /// after the first mechanical step.
    pub step_s: Real,
    /// Heat that has flowed into each tool since the start (J).
    pub to_tools_j: Vec<Real>,
    /// Heat flow into each tool at the last heat stage (W).
    pub tool_flow_w: Vec<Real>,
    /// Heat that has flowed into the surroundings since the start (J).
    pub to_surroundings_j: Real,
    /// Friction work at the tool interfaces of each particle since the last heat stage (J;
    /// empty when no tool has friction).
    pub friction_work: Vec<Real>,
    /// Heat friction made at the tool interfaces since the start (J), all of it: the
    /// workpiece takes `thermal.friction_heat_to_workpiece` of it, the tools the rest.
    pub friction_heat_j: Real,
    /// Normal impulse of the contact forces on each particle since the last heat stage (N s;
    /// empty unless a tool's heat transfer depends on the contact pressure).
    #[serde(default)]
    pub normal_impulse: Vec<Real>,
    /// Each point's elastic state at its last stress update (-; empty without elasticity
    /// over temperature; [`crate::material::PointLanes::elastic_prev`]): the energy account
    /// books the elastic energy a change of temperature puts in.
    #[serde(default)]
    pub elastic_state: Vec<[Real; 4]>,
    /// The change of each point's temperature in the last heat stage (K; empty without
    /// elasticity over temperature), which the elasticity takes in over the heat step that
    /// follows ([`Heating::ramp`]).
    #[serde(default)]
    pub stage_change_k: Vec<Real>,
}

impl Heat {
    /// Every point at the scene's initial temperature, no plastic work.
    pub(super) fn initial(
        spec: &ThermalSpec,
        points: usize,
        tools: usize,
        particles: usize,
        friction: bool,
        pressure: bool,
        thermoelastic: Option<[Real; 4]>,
    ) -> Heat {
        Heat {
            temperature_c: vec![spec.initial_temperature_c; points],
            particle_c: vec![spec.initial_temperature_c; particles],
            plastic_work: vec![0.0; points],
            plastic_rate: vec![0.0; points],
            since_s: 0.0,
            step_s: 0.0,
            to_tools_j: vec![0.0; tools],
            tool_flow_w: vec![0.0; tools],
            to_surroundings_j: 0.0,
            friction_work: vec![0.0; if friction { particles } else { 0 }],
            friction_heat_j: 0.0,
            normal_impulse: vec![0.0; if pressure { particles } else { 0 }],
            elastic_state: thermoelastic.map_or(Vec::new(), |s| vec![s; points]),
            stage_change_k: vec![0.0; if thermoelastic.is_some() { points } else { 0 }],
        }
    }
}

/// What the stress stage needs to heat the points: `beta / rho_0` (m^3/kg), the heat
/// capacity, and `1/dt` (1/s) of the step the strain increment was taken over (0 before the
/// first step). A point's plastic work `dW` (J/m^3) takes it from `T` to
/// `T + beta dW / (rho_0 c)`, or `h^-1(h(T) + beta dW / rho_0)` with a capacity over
/// temperature.
#[derive(Debug, Clone, Copy)]
pub(super) struct Heating<'a> {
    pub(super) beta_over_rho: Real,
    pub(super) capacity: &'a HeatCapacity,
    pub(super) inv_dt: Real,
    /// The share of the last heat stage's change (`Heat::stage_change_k`) that the
    /// elasticity over temperature does not see yet, `1 - t_since / dt_heat` in [0, 1]: the
    /// stage's change ramps in over the heat step that follows it, so that the thermal
    /// strain and modulus change smoothly (a sub-cycled stage's jump of a few kelvin in the
    /// thermal strain would set the elastic body ringing).
    pub(super) ramp: Real,
}

impl<'a> Heating<'a> {
    /// From the scene's thermal section, heat capacity and physical density `rho_0`
    /// (kg/m^3).
    pub(super) fn new(
        spec: &ThermalSpec,
        capacity: &'a HeatCapacity,
        density: Real,
        dt_prev: Real,
    ) -> Heating<'a> {
        Heating {
            beta_over_rho: spec.taylor_quinney / density,
            capacity,
            inv_dt: if dt_prev > 0.0 { 1.0 / dt_prev } else { 0.0 },
            ramp: 0.0,
        }
    }

    /// The temperature (degrees C) of a point at `t` after plastic work `dw` (J/m^3).
    #[inline]
    pub(super) fn heated(&self, t: Real, dw: Real) -> Real {
        self.capacity.heat(t, self.beta_over_rho * dw)
    }
}

/// The workpiece's temperatures over its integration points: least, largest and the mean
/// weighted by the points' masses `rho_0 w_p` (degrees C).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Temperatures {
    /// Least point temperature (degrees C).
    pub min_c: Real,
    /// Largest point temperature (degrees C).
    pub max_c: Real,
    /// Mass-weighted mean, `sum_p w_p T_p / sum_p w_p` (degrees C).
    pub mean_c: Real,
}
