//! The length of each step (stage 2): the natural step from the critical step
//! (`critical_step.rs`) and the stable estimate on the current deformation, the tools'
//! speed limit, and the equal steps that land on a requested instant.

use super::state::State;
use crate::error::{Error, Result};
use crate::math::Real;
use crate::scene::Motion;
use crate::scene::Scene;
use crate::tools::{Driven, Tool};

/// Length of the next step: the full step `dt_full`, or, when `max_dt` (the time left to a
/// requested instant) is not a whole number of full steps, that time split into equal steps,
/// so that no step is shorter than half a full one. An exact multiple keeps `dt_full` itself.
pub(super) fn landing_step(dt_full: Real, max_dt: Option<Real>) -> Real {
    let Some(left) = max_dt else { return dt_full };
    let tol = 1e-9 * dt_full;
    // Steps still needed, not counting a rounding residue as one more.
    let n = ((left - tol) / dt_full).ceil().max(1.0);
    if (left - n * dt_full).abs() <= tol {
        dt_full
    } else {
        left / n
    }
}

/// Farthest a tool may move in one step, in smallest particle spacings: the penalty contact
/// sees a particle only once it is behind a segment, so a tool that moved past a spacing in
/// one step could pass particles it never saw (a velocity input of 1e300 m/s took a tool
/// through the block with no force).
pub const TOOL_TRAVEL_SPACINGS: Real = 0.5;

/// Shortest a tool's speed may make a step, as a fraction of the natural step: below it the
/// run stops and names the tool, instead of crawling.
pub const TOOL_STEP_FRACTION: Real = 0.01;

/// The longest step (s) in which no tool moves more than [`TOOL_TRAVEL_SPACINGS`] smallest
/// spacings `h` (m), `0.5 h / |v|` with `|v|` the larger of each tool's speeds at `t` and
/// `t + dt` (m/s), `dt` the natural step (infinite when no tool is that fast). A tool that
/// would shorten the step below [`TOOL_STEP_FRACTION`] of `dt` is an error naming it and its
/// speed.
pub(super) fn tool_step_limit<T: Driven>(
    tools: &[T],
    t: Real,
    dt: Real,
    h: Real,
) -> std::result::Result<Real, String> {
    let travel = TOOL_TRAVEL_SPACINGS * h;
    let mut limited = Real::INFINITY;
    for tool in tools
        .iter()
        .filter(|t| !matches!(t.motion(), Motion::Fixed))
    {
        let velocity = |t: Real| tool.motion().velocity_at(t, tool.command());
        let speed = velocity(t).abs().max(velocity(t + dt).abs());
        if speed * dt <= travel {
            continue;
        }
        let short = travel / speed;
        if short < TOOL_STEP_FRACTION * dt {
            let source = match tool.command() {
                Some(_) => "commanded",
                None => "in the scene",
            };
            return Err(format!(
                "tool `{}`: velocity {speed:.4e} m/s ({source}) would move it {:.4e} m in one step of {dt:.4e} s, more than {TOOL_TRAVEL_SPACINGS} particle spacing ({travel:.4e} m), and the step would have to shorten below {TOOL_STEP_FRACTION} of its length; lower the tool's velocity",
                tool.name(),
                speed * dt,
            ));
        }
        limited = limited.min(short);
    }
    Ok(limited)
}

/// The step the next call to `step` takes when not limited (s): the scene's fixed
/// `time.dt_s`, or `dt_safety` times the stable estimate.
pub(super) fn next_dt(scene: &Scene, st: &State) -> Real {
    scene
        .time
        .dt_s
        .unwrap_or(scene.time.dt_safety * st.stable_dt)
}

/// The step's first check ([`tool_step_limit`] on the natural step): the longest step the
/// tools' speeds allow (s), or an error naming the step, the time and the tool too fast
/// for it, before anything changes.
pub(super) fn tool_limit(scene: &Scene, tools: &[Tool], st: &State, h_min: Real) -> Result<Real> {
    tool_step_limit(tools, st.time, next_dt(scene, st), h_min)
        .map_err(|what| Error::Request(format!("step {} (t = {:.6e} s): {what}", st.step, st.time)))
}

/// The lengths of one step (s).
#[derive(Debug, Clone, Copy)]
pub(super) struct StepLength {
    /// The step taken, `dt_{n+1}`.
    pub dt: Real,
    /// The natural step it was shortened from to land on a requested time (`dt` itself
    /// otherwise).
    pub full: Real,
    /// `(dt_n + dt_{n+1}) / 2`, the predictor's and corrector's step.
    pub avg: Real,
}

/// Stage 2, the time step: the natural step ([`next_dt`]) within the tools' limit
/// `tool_dt` (s), shortened to land on `max_dt` ([`landing_step`]); an error when it is not
/// positive.
pub(super) fn length(
    scene: &Scene,
    st: &State,
    tool_dt: Real,
    max_dt: Option<Real>,
) -> Result<StepLength> {
    let full = next_dt(scene, st).min(tool_dt);
    let dt = landing_step(full, max_dt);
    if dt.is_nan() || dt <= 0.0 {
        return Err(Error::Request(format!(
            "step length {dt} s is not positive"
        )));
    }
    Ok(StepLength {
        dt,
        full,
        avg: 0.5 * (dt + st.dt_prev),
    })
}

#[cfg(test)]
mod tests {
    use super::landing_step;

    #[test]
    fn landing_steps_are_equal_and_never_overshoot() {
        let dt = 2.0;
        assert_eq!(landing_step(dt, None), dt);
        assert_eq!(landing_step(dt, Some(6.0)), dt);
        assert_eq!(landing_step(dt, Some(6.0 + 1e-12)), dt);
        assert_eq!(landing_step(dt, Some(5.0)), 5.0 / 3.0);
        assert_eq!(landing_step(dt, Some(2.5)), 1.25);
        assert_eq!(landing_step(dt, Some(0.5)), 0.5);
        for left in [0.1, 1.9, 2.0000001, 3.3, 7.77] {
            let h = landing_step(dt, Some(left));
            assert!(
                h <= left * (1.0 + 1e-12) && h <= dt && (h >= 0.5 * dt || left < dt),
                "{left}: {h}"
            );
        }
    }
}
