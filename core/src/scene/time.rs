//! The `[time]` section: the time span, the step and mass scaling, with what they must be
//! ([`TimeSpec::check`], [`MassScaling::check`]).

use crate::math::Real;
use crate::validation::{pos, Checks};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Time span and step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// End time (s).
    pub end_s: Real,
    /// Fixed step (s); when absent, `dt_safety` times the stable step, updated every step.
    #[serde(default)]
    pub dt_s: Option<Real>,
    /// Fraction of the stable step used when `dt_s` is absent (-), in (0, 1].
    #[serde(default = "default_safety")]
    pub dt_safety: Real,
    /// Added mass that lengthens the explicit step; none when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass_scaling: Option<MassScaling>,
}

/// Mass scaling: mass added to the particles so that the explicit step, bounded by the
/// wave speed `sqrt((K + 4G/3) / rho)`, grows (the critical step grows with the square root
/// of the mass). For rate-independent forming, where inertia is negligible, a factor `f^2`
/// on the mass has the effect of running the tools `f` times faster; the run watches that
/// inertia stays negligible (`checks.kinetic_to_internal_max`). One of the two keys.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MassScaling {
    /// Uniform: every particle's mass times `factor` (-), at least 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub factor: Option<Real>,
    /// Selective (as LS-DYNA's DT2MS): mass is added only to the particles whose local
    /// step is below what it takes for the run's step, `dt_safety` times the critical
    /// step of the undeformed discretisation, to reach `target_dt_s` (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_dt_s: Option<Real>,
    /// Selective scaling with kernel re-referencing (`discretization.rereference_stretch`):
    /// what the masses do on each re-reference's new shape functions ([`AtRereference`];
    /// `step` when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at_rereferences: Option<AtRereference>,
}

/// What selective mass scaling does at a kernel re-reference, whose new shape functions
/// have a critical step of their own (measured again). What each costs and buys on the
/// conrod is in docs/forging.md, "Mass scaling at the re-references".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum AtRereference {
    /// The masses of the start are kept: the step follows the new shape functions, up or
    /// down.
    Keep,
    /// Mass is added only where the new shape functions would step shorter than the run
    /// stepped just before (their critical step under the one it followed, or under
    /// `target_dt_s / dt_safety` if that is shorter): a re-reference never shortens the
    /// step. The default: a re-reference that steps
    /// longer, as most do, changes no mass and no bit.
    Step,
    /// The target is held again: mass added wherever the deformed body's particles came
    /// close, as at the start.
    Target,
}

fn default_safety() -> Real {
    0.5
}

impl TimeSpec {
    /// The end time, fixed step and step safety factor a run cannot use, under their
    /// dotted keys `time.*`; the mass scaling has its own check ([`MassScaling::check`]),
    /// which the scene's validation runs last.
    pub(crate) fn check(&self, out: &mut Checks) {
        out.check(
            pos(self.end_s),
            "time.end_s",
            format!("must be positive, got {}", self.end_s),
        );
        if let Some(dt) = self.dt_s {
            out.check(pos(dt), "time.dt_s", format!("must be positive, got {dt}"));
            out.check(
                !pos(dt) || !pos(self.end_s) || self.end_s / dt <= 1e9,
                "time.dt_s",
                format!("{dt} s gives more than 1e9 steps"),
            );
        }
        out.check(
            self.dt_safety.is_finite() && self.dt_safety > 0.0 && self.dt_safety <= 1.0,
            "time.dt_safety",
            format!("must lie in (0, 1], got {}", self.dt_safety),
        );
    }
}

impl TimeSpec {
    /// A warning when a fixed step makes `dt_safety` (set to other than its default) do
    /// nothing: it scales only the stable step, and a selective mass scaling's target. A
    /// refusal would refuse `--set time.dt_s=...` on every scene that sets `dt_safety`.
    pub fn unused_safety_warning(&self) -> Option<String> {
        let dt = self.dt_s?;
        let targeted = self.mass_scaling.is_some_and(|m| m.target_dt_s.is_some());
        (self.dt_safety != default_safety() && !targeted).then(|| {
            format!(
                "time.dt_safety = {} is not used: the fixed step time.dt_s = {dt:e} s sets every step (remove one of the two keys)",
                self.dt_safety
            )
        })
    }
}

impl MassScaling {
    /// One of a uniform factor (at least 1) or a target step (positive), under the dotted
    /// keys `time.mass_scaling.*`; a target held at re-references needs the scene to
    /// re-reference its kernel (`rereferenced`).
    pub(crate) fn check(&self, out: &mut Checks, rereferenced: bool) {
        if self.at_rereferences.is_some() {
            out.check(
                self.target_dt_s.is_some() && rereferenced,
                "time.mass_scaling.at_rereferences",
                "acts on a `target_dt_s` at the kernel's re-references: give `target_dt_s` and `discretization.rereference_stretch`".into(),
            );
        }
        match (self.factor, self.target_dt_s) {
            (Some(f), None) => out.check(
                f.is_finite() && f >= 1.0,
                "time.mass_scaling.factor",
                format!("must be at least 1, got {f}"),
            ),
            (None, Some(dt)) => out.check(
                pos(dt),
                "time.mass_scaling.target_dt_s",
                format!("must be positive, got {dt}"),
            ),
            _ => out.check(
                false,
                "time.mass_scaling",
                "give one of `factor` (uniform) or `target_dt_s` (selective)".into(),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(dt_s: Option<Real>, dt_safety: Real, target: Option<Real>) -> TimeSpec {
        TimeSpec {
            end_s: 1e-3,
            dt_s,
            dt_safety,
            mass_scaling: target.map(|t| MassScaling {
                factor: None,
                target_dt_s: Some(t),
                at_rereferences: None,
            }),
        }
    }

    /// A fixed step with a `dt_safety` of its own is named, not refused; the default, no
    /// fixed step, or a selective mass scaling's target (which `dt_safety` scales) is not.
    #[test]
    fn a_safety_a_fixed_step_leaves_unused_is_named() {
        let w = spec(Some(2e-6), 0.9, None).unused_safety_warning().unwrap();
        assert!(
            w.contains("time.dt_safety = 0.9 is not used") && w.contains("time.dt_s = 2e-6 s"),
            "{w}"
        );
        assert_eq!(spec(Some(2e-6), 0.5, None).unused_safety_warning(), None);
        assert_eq!(spec(None, 0.9, None).unused_safety_warning(), None);
        assert_eq!(
            spec(Some(2e-6), 0.9, Some(5e-6)).unused_safety_warning(),
            None
        );
    }
}
