//! What the outputs read of a thermal scene's heat now: the temperatures of the points
//! and the workpiece's least, largest and mean, the heat plastic work and friction made,
//! the heat held and what flowed to the tools and the surroundings, as the register of
//! outputs names them ([`crate::outputs::THERMAL_MEASURES`]).

use super::discretization::Thermal;
use super::heat::{Heat, Temperatures};
use super::simulation::Simulation;
use crate::math::Real;
use crate::scene::ThermalSpec;

impl Simulation {
    /// The thermal measures now, `None` for an isothermal scene: least, largest and mean
    /// temperature (degrees C), the heat made by plastic work and by friction, the heat
    /// content, the heat to the tools and to the surroundings (J), and the heat balance (-),
    /// as [`crate::outputs::REGISTER`] names them (`thermal.*`).
    pub fn thermal_values(&self) -> Option<[Real; 9]> {
        let t = self.temperatures()?;
        let heat = self.st.heat.as_ref()?;
        let share = self.scene.thermal.as_ref()?.friction_heat_to_workpiece;
        Some(measures(
            t,
            self.plastic_heat()?,
            heat.friction_heat_j,
            share,
            self.heat_content()?,
            &heat.to_tools_j,
            heat.to_surroundings_j,
        ))
    }

    /// The points' temperatures (degrees C), `None` for an isothermal scene.
    pub fn point_temperature(&self) -> Option<&[Real]> {
        self.st.heat.as_ref().map(|h| &h.temperature_c[..])
    }

    /// Plastic strain rate of each point at the last stress stage, `dgamma / dt` (1/s), the
    /// rate its flow stress was evaluated at; `None` for an isothermal scene.
    pub fn point_plastic_strain_rate(&self) -> Option<&[Real]> {
        self.st.heat.as_ref().map(|h| &h.plastic_rate[..])
    }

    /// Heat that has flowed into tool `k` since the start (J), `None` for an isothermal scene.
    pub fn tool_heat(&self, k: usize) -> Option<Real> {
        self.st.heat.as_ref().map(|h| h.to_tools_j[k])
    }

    /// Heat flow into each tool at the last heat stage (W), `None` for an isothermal scene.
    pub fn tool_heat_flows(&self) -> Option<&[Real]> {
        self.st.heat.as_ref().map(|h| &h.tool_flow_w[..])
    }

    /// Time of the temperatures' conduction and surface flows (s): the last heat stage's,
    /// up to one heat step before [`Simulation::time`] (plastic heating is up to date).
    pub fn heat_time(&self) -> Real {
        self.st.time - self.st.heat.as_ref().map_or(0.0, |h| h.since_s)
    }

    /// Least, largest and mean temperature of the workpiece, `None` for an isothermal scene.
    pub fn temperatures(&self) -> Option<Temperatures> {
        Some(temperatures(self.point_temperature()?, &self.disc.weights))
    }

    /// Heat the plastic work released into the workpiece so far, `beta sum_p W_p w_p` (J);
    /// `None` for an isothermal scene.
    pub fn plastic_heat(&self) -> Option<Real> {
        let (h, spec) = (self.st.heat.as_ref()?, self.scene.thermal.as_ref()?);
        Some(plastic_heat(spec, h, &self.disc.weights))
    }

    /// Heat held in the workpiece above its initial temperature, `sum_p rho_0 w_p (h(T_p) -
    /// h(T_0))` (J, `h` the specific enthalpy, `c (T_p - T_0)` for a constant capacity);
    /// `None` for an isothermal scene. Equal to [`Simulation::plastic_heat`] while no heat
    /// crosses the surface.
    pub fn heat_content(&self) -> Option<Real> {
        let (h, th) = (self.st.heat.as_ref()?, self.disc.thermal.as_ref()?);
        Some(heat_content(th, h, &self.disc.weights))
    }
}

/// The thermal measures in the order of [`crate::outputs::THERMAL_MEASURES`] (2D and 3D):
/// the temperatures `t`, the heat made by plastic work and by friction (J, the workpiece
/// taking `share` of the friction heat), the heat content, the heat to each tool and to the
/// surroundings (J), and the heat balance `(content - made + lost) / scale` (-), `scale`
/// the sum of the magnitudes of what was made and of each flow.
pub(super) fn measures(
    t: Temperatures,
    plastic: Real,
    friction: Real,
    share: Real,
    content: Real,
    to_each_tool: &[Real],
    to_surroundings: Real,
) -> [Real; 9] {
    let made = plastic + share * friction;
    let to_tools: Real = to_each_tool.iter().sum();
    let lost = to_tools + to_surroundings;
    let scale =
        made.abs() + to_each_tool.iter().map(|q| q.abs()).sum::<Real>() + to_surroundings.abs();
    let balance = if scale > 0.0 {
        (content - made + lost) / scale
    } else {
        0.0
    };
    [
        t.min_c,
        t.max_c,
        t.mean_c,
        plastic,
        friction,
        content,
        to_tools,
        to_surroundings,
        balance,
    ]
}

/// Least, largest and volume-weighted mean of the point temperatures `t` (degrees C) with
/// the points' weights `w_p` (m^3).
pub(super) fn temperatures(t: &[Real], weights: &[Real]) -> Temperatures {
    let (mut min_c, mut max_c) = (Real::INFINITY, Real::NEG_INFINITY);
    let (mut sum, mut wsum) = (0.0, 0.0);
    for (&t, &w) in t.iter().zip(weights) {
        min_c = min_c.min(t);
        max_c = max_c.max(t);
        sum += w * t;
        wsum += w;
    }
    Temperatures {
        min_c,
        max_c,
        mean_c: sum / wsum,
    }
}

/// Heat the plastic work released, `beta sum_p W_p w_p` (J), with the points' weights
/// `w_p` (m^3).
pub(super) fn plastic_heat(spec: &ThermalSpec, heat: &Heat, weights: &[Real]) -> Real {
    spec.taylor_quinney
        * heat
            .plastic_work
            .iter()
            .zip(weights)
            .map(|(w, v)| w * v)
            .sum::<Real>()
}

/// Heat held above the initial temperature, `sum_p rho_0 w_p (h(T_p) - h(T_0))` (J), with
/// the points' weights `w_p` (m^3).
pub(super) fn heat_content(thermal: &Thermal, heat: &Heat, weights: &[Real]) -> Real {
    let t0 = thermal.spec.initial_temperature_c;
    thermal.density
        * heat
            .temperature_c
            .iter()
            .zip(weights)
            .map(|(&t, w)| w * thermal.capacity.heat_between(t0, t))
            .sum::<Real>()
}
