//! The quasi-static watch of the step: a forming run (mass-scaled above all) is
//! quasi-static while the workpiece's kinetic energy stays a small share of its internal
//! energy. From the first touch of a tool (or from t = 0 without tools), once
//! `checks.kinetic_to_internal_from` of the rest of the run has passed, the ratio
//! `E_kin / E_int` is kept at its largest and the run stops past
//! `checks.kinetic_to_internal_max`.

use super::energy::Energy;
use super::solid::SolidState;
use super::state::State;
use crate::error::Result;
use crate::math::Real;
use crate::scene::Checks;

/// Kinetic-to-internal energy ratio above which a mass-scaled run warns (-): forming is
/// quasi-static while the kinetic energy stays a few per cent of the internal energy.
pub const QUASI_STATIC_WARNING: Real = 0.05;

/// What the watch reads and keeps in a run's state, 2D or 3D.
pub(super) trait Watched {
    /// The energy account, the step count and the time (s).
    fn account(&self) -> (&Energy, u64, Real);
    /// When a tool first touched (s), and the largest ratio so far (-).
    fn kept(&mut self) -> (&mut Option<Real>, &mut Real);
}

impl Watched for State {
    fn account(&self) -> (&Energy, u64, Real) {
        (&self.energy, self.step, self.time)
    }
    fn kept(&mut self) -> (&mut Option<Real>, &mut Real) {
        (&mut self.first_contact_s, &mut self.kinetic_to_internal_max)
    }
}

impl Watched for SolidState {
    fn account(&self) -> (&Energy, u64, Real) {
        (&self.energy, self.step, self.time)
    }
    fn kept(&mut self) -> (&mut Option<Real>, &mut Real) {
        (&mut self.first_contact_s, &mut self.kinetic_to_internal_max)
    }
}

/// The watch after a step in which a tool touched the workpiece (`touched`) or not, for a
/// scene with no tools (`no_tools`) or some, `checks` and the run's end `end_s` (s): the
/// ratio once the start-up is over, its largest value kept, and the run stopped past the
/// scene's bound.
pub(super) fn watch(
    checks: &Checks,
    end_s: Real,
    no_tools: bool,
    st: &mut impl Watched,
    touched: bool,
) -> Result<()> {
    let (energy, step, time) = st.account();
    let ratio = energy.kinetic_to_internal();
    let (first_contact_s, ratio_max) = st.kept();
    if touched && first_contact_s.is_none() {
        *first_contact_s = Some(time);
    }
    let start = if no_tools {
        Some(0.0)
    } else {
        *first_contact_s
    };
    if start.is_some_and(|t0| time >= t0 + checks.kinetic_to_internal_from * (end_s - t0)) {
        *ratio_max = ratio_max.max(ratio);
        if let Some(bound) = checks.kinetic_to_internal_max {
            st.account()
                .0
                .check_quasi_static(ratio, bound, step, time)?;
        }
    }
    Ok(())
}

/// A warning when a mass-scaled run's (`mass_scaled`) kinetic energy exceeded
/// [`QUASI_STATIC_WARNING`] of its internal energy after the start-up (`ratio_max`, -): the
/// inertia that mass scaling adds is no longer negligible, and forces and shapes carry it.
pub(super) fn warning(mass_scaled: bool, ratio_max: Real) -> Option<String> {
    (mass_scaled && ratio_max > QUASI_STATIC_WARNING).then(|| {
        format!(
            "the kinetic energy reached {:.1} % of the internal energy (above {:.0} %): the added mass is not negligible; scale less or set checks.kinetic_to_internal_max to stop such runs",
            100.0 * ratio_max,
            100.0 * QUASI_STATIC_WARNING
        )
    })
}
