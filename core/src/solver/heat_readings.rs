//! What the outputs read of a thermal scene's heat now: the temperatures of the points
//! and the workpiece's least, largest and mean, the heat plastic work and friction made,
//! the heat held and what flowed to the tools and the surroundings, as the register of
//! outputs names them ([`crate::outputs::THERMAL_MEASURES`]).

use super::heat::Temperatures;
use super::simulation::Simulation;
use crate::math::Real;

impl Simulation {
    /// The thermal measures now, `None` for an isothermal scene: least, largest and mean
    /// temperature (degrees C), the heat made by plastic work and by friction, the heat
    /// content, the heat to the tools and to the surroundings (J), and the heat balance (-),
    /// as [`crate::outputs::REGISTER`] names them (`thermal.*`).
    pub fn thermal_values(&self) -> Option<[Real; 9]> {
        let t = self.temperatures()?;
        let heat = self.st.heat.as_ref()?;
        let share = self.scene.thermal.as_ref()?.friction_heat_to_workpiece;
        let plastic = self.plastic_heat()?;
        let (made, content) = (plastic + share * heat.friction_heat_j, self.heat_content()?);
        let to_tools: Real = heat.to_tools_j.iter().sum();
        let lost = to_tools + heat.to_surroundings_j;
        let scale = made.abs()
            + heat.to_tools_j.iter().map(|q| q.abs()).sum::<Real>()
            + heat.to_surroundings_j.abs();
        let balance = if scale > 0.0 {
            (content - made + lost) / scale
        } else {
            0.0
        };
        Some([
            t.min_c,
            t.max_c,
            t.mean_c,
            plastic,
            heat.friction_heat_j,
            content,
            to_tools,
            heat.to_surroundings_j,
            balance,
        ])
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
        let t = self.point_temperature()?;
        let (mut min_c, mut max_c) = (Real::INFINITY, Real::NEG_INFINITY);
        let (mut sum, mut wsum) = (0.0, 0.0);
        for (&t, &w) in t.iter().zip(&self.disc.weights) {
            min_c = min_c.min(t);
            max_c = max_c.max(t);
            sum += w * t;
            wsum += w;
        }
        Some(Temperatures {
            min_c,
            max_c,
            mean_c: sum / wsum,
        })
    }

    /// Heat the plastic work released into the workpiece so far, `beta sum_p W_p w_p` (J);
    /// `None` for an isothermal scene.
    pub fn plastic_heat(&self) -> Option<Real> {
        let (h, spec) = (self.st.heat.as_ref()?, self.scene.thermal.as_ref()?);
        Some(
            spec.taylor_quinney
                * h.plastic_work
                    .iter()
                    .zip(&self.disc.weights)
                    .map(|(w, v)| w * v)
                    .sum::<Real>(),
        )
    }

    /// Heat held in the workpiece above its initial temperature, `sum_p rho_0 w_p (h(T_p) -
    /// h(T_0))` (J, `h` the specific enthalpy, `c (T_p - T_0)` for a constant capacity);
    /// `None` for an isothermal scene. Equal to [`Simulation::plastic_heat`] while no heat
    /// crosses the surface.
    pub fn heat_content(&self) -> Option<Real> {
        let (h, spec) = (self.st.heat.as_ref()?, self.scene.thermal.as_ref()?);
        let capacity = &self.disc.thermal.as_ref()?.capacity;
        let t0 = spec.initial_temperature_c;
        Some(
            self.scene.material.density_kg_per_m3
                * h.temperature_c
                    .iter()
                    .zip(&self.disc.weights)
                    .map(|(&t, w)| w * capacity.heat_between(t0, t))
                    .sum::<Real>(),
        )
    }
}
