//! The `[checks]` section: the limits at which a run stops (energy balance, kinetic to
//! internal energy, penetration into a tool), with what they must be ([`Checks::check`]).

use crate::math::Real;
use crate::validation::{self, pos};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Run-time checks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Checks {
    /// Largest energy balance error, relative to the reference energy, before the run stops.
    #[serde(default = "default_energy_tol")]
    pub energy_balance_tol: Real,
    /// Largest ratio of the workpiece's kinetic to internal energy (-) after the start-up
    /// (`kinetic_to_internal_from`) before the run stops: the quasi-static assumption
    /// that mass scaling rests on. Absent: the ratio is reported (and a mass-scaled run
    /// warns above 5 %) but never stops the run.
    #[serde(default)]
    pub kinetic_to_internal_max: Option<Real>,
    /// Start of the kinetic-to-internal watch (-), in [0, 1): this fraction of the time from
    /// the first contact (t = 0 for a workpiece without tools) to `time.end_s`. The first
    /// contact accelerates the touched layer to the tool speed while the internal energy is
    /// still small (the ratio is 0.26 at 1 % of the shipped block forging's stroke and below
    /// 0.02 from 10 % on).
    #[serde(default = "default_watch_from")]
    pub kinetic_to_internal_from: Real,
    /// Deepest a particle may lie inside a tool, in smallest particle spacings (-), before
    /// the run stops with the step, time, particle, tool and depth named. The penalty's own
    /// penetration under forging pressures is a few thousandths of a spacing
    /// (`g = p h dt^2 / (m_J / h)`, about `0.8 h p / (K + 4G/3)`), so 0.1 only trips when
    /// the contact lets material through.
    #[serde(default = "default_max_penetration")]
    pub max_penetration_rel: Real,
}

fn default_max_penetration() -> Real {
    0.1
}

fn default_watch_from() -> Real {
    0.1
}

fn default_energy_tol() -> Real {
    0.05
}

impl Default for Checks {
    fn default() -> Self {
        Checks {
            energy_balance_tol: default_energy_tol(),
            kinetic_to_internal_max: None,
            kinetic_to_internal_from: default_watch_from(),
            max_penetration_rel: default_max_penetration(),
        }
    }
}

impl Checks {
    /// Every value of the section a run cannot use, under its dotted key `checks.*`.
    pub(crate) fn check(&self, out: &mut validation::Checks) {
        out.check(
            self.energy_balance_tol.is_finite() && self.energy_balance_tol > 0.0,
            "checks.energy_balance_tol",
            format!("must be positive, got {}", self.energy_balance_tol),
        );
        if let Some(r) = self.kinetic_to_internal_max {
            out.check(
                pos(r),
                "checks.kinetic_to_internal_max",
                format!("must be positive, got {r}"),
            );
        }
        out.check(
            pos(self.max_penetration_rel),
            "checks.max_penetration_rel",
            format!("must be positive, got {}", self.max_penetration_rel),
        );
        out.check(
            (0.0..1.0).contains(&self.kinetic_to_internal_from),
            "checks.kinetic_to_internal_from",
            format!("must lie in [0, 1), got {}", self.kinetic_to_internal_from),
        );
    }
}
