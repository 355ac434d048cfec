//! The quasi-static watch of the step: a forming run (mass-scaled above all) is
//! quasi-static while the workpiece's kinetic energy stays a small share of its internal
//! energy. From the first touch of a tool (or from t = 0 without tools), once
//! `checks.kinetic_to_internal_from` of the rest of the run has passed, the ratio
//! `E_kin / E_int` is kept at its largest and the run stops past
//! `checks.kinetic_to_internal_max`.

use super::state::State;
use crate::error::Result;
use crate::math::Real;
use crate::scene::Scene;

/// Kinetic-to-internal energy ratio above which a mass-scaled run warns (-): forming is
/// quasi-static while the kinetic energy stays a few per cent of the internal energy.
pub const QUASI_STATIC_WARNING: Real = 0.05;

/// The watch after a step in which a tool touched the workpiece (`touched`) or not, for a
/// scene with no tools (`no_tools`) or some: the ratio once the start-up is over, its
/// largest value kept, and the run stopped past the scene's bound.
pub(super) fn watch(scene: &Scene, no_tools: bool, st: &mut State, touched: bool) -> Result<()> {
    if touched && st.first_contact_s.is_none() {
        st.first_contact_s = Some(st.time);
    }
    let start = if no_tools {
        Some(0.0)
    } else {
        st.first_contact_s
    };
    let (checks, end) = (&scene.checks, scene.time.end_s);
    if start.is_some_and(|t0| st.time >= t0 + checks.kinetic_to_internal_from * (end - t0)) {
        let ratio = st.energy.kinetic_to_internal();
        st.kinetic_to_internal_max = st.kinetic_to_internal_max.max(ratio);
        if let Some(bound) = checks.kinetic_to_internal_max {
            st.energy
                .check_quasi_static(ratio, bound, st.step, st.time)?;
        }
    }
    Ok(())
}
