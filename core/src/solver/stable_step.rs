//! The length of each step (stage 2): the natural step from the critical step
//! (`critical_step.rs`) and the stable estimate on the current deformation, the tools'
//! speed limit, and the equal steps that land on a requested instant.

use crate::error::{Error, Result};
use crate::math::Real;
use crate::scene::TimeSpec;
use crate::tools::Driven;

/// How far below the natural step a landing plan puts its steps (-): the room the natural
/// step has to shrink, as the body deforms, before the plan must change.
pub const LANDING_SLACK: Real = 0.02;

/// Steps before a requested instant within which a plan is kept as long as it is stable: a
/// new plan there would change the step by up to `1 / k`, `k` the steps left.
pub const LANDING_HOLD: Real = 32.0;

/// Length of the next step toward a requested instant `max_dt` (s) ahead (a history sample,
/// a frame, a communication point, the end), the natural step `dt_full` (s), the last step
/// `dt_prev` (s, 0 before the first) and the plan's `slack` (-): [`LANDING_SLACK`] for a
/// natural step, 0 for a fixed `time.dt_s`. The steps to the instant are equal:
/// - with no slack, `dt_full` itself when the time left is an exact multiple of it, else
///   the time left split into `ceil(left / dt_full)` equal steps;
/// - with slack, planned so that the step changes rarely and by little: the last plan is
///   kept while it lands and fits, `left / k` with `k = round(left / dt_prev)` steps,
///   within `slack / 2` of `dt_prev` (across an instant the next interval continues it,
///   stretched or shrunk over the interval) and within `[1 - 2 slack, 1 - slack / 2]` of
///   `dt_full`, in the last [`LANDING_HOLD`] steps from `(1 - 2 slack) dt_full` up to
///   `(1 + slack) dt_full` but never past `ceiling` (s), the longest step the stability
///   and the tools allow (the stable estimate itself, not its `dt_safety` fraction, and
///   the tools' travel limit); otherwise a new plan, the time left in equal steps of at
///   most `(1 - slack) dt_full` (so a step cut short by an instant between two steps is not
///   repeated).
///
/// Up to session 62 the last steps were held to `dt_full` itself: a natural step that
/// shrank by more than the plan's margin through those steps (1.3 % on the conrod at one
/// mass), or fell in a jump of 1-2 % there, put the kept plan a hair above it at the last
/// step, and the new plan at `(1 - slack) dt_full` then needed two steps for the one left,
/// halving it; the contact force answered the halved step and 4 of the 1 mm conrod's 100
/// samples read 22-32 % high (docs/forging.md, "One mass for every grid").
///
/// The plan before session 59 was the no-slack one for every step, made anew at each
/// step: near each instant, once a natural step had shrunk a little, it shortened the last
/// steps by up to a half. The explicit scheme's fastest modes answered with a jump of the
/// contact force of up to 13 % for a few steps, and the history sampled it, its samples
/// being those instants (docs/method.md, "Steps that land on an instant").
pub(super) fn landing_step(
    dt_full: Real,
    max_dt: Option<Real>,
    dt_prev: Real,
    slack: Real,
    ceiling: Real,
) -> Real {
    let Some(left) = max_dt else { return dt_full };
    let tol = 1e-9 * dt_full;
    if slack == 0.0 {
        // Steps still needed, not counting a rounding residue as one more.
        let n = ((left - tol) / dt_full).ceil().max(1.0);
        return match (left - n * dt_full).abs() <= tol {
            true => dt_full,
            false => left / n,
        };
    }
    if dt_prev > 0.0 {
        let k = (left / dt_prev).round().max(1.0);
        let kept = left / k;
        let hi = match k <= LANDING_HOLD {
            true => ((1.0 + slack) * dt_full).min(ceiling.max(dt_full)),
            false => (1.0 - 0.5 * slack) * dt_full,
        };
        if kept <= hi
            && kept >= (1.0 - 2.0 * slack) * dt_full
            && (kept / dt_prev - 1.0).abs() <= 0.5 * slack
        {
            return kept;
        }
    }
    let planned = (1.0 - slack) * dt_full;
    left / ((left - tol) / planned).ceil().max(1.0)
}

/// The landing plan's slack for a scene's `time.dt_s` (s): none for a fixed step, whose
/// length does not drift, [`LANDING_SLACK`] for the natural step.
pub(super) fn landing_slack(fixed: Option<Real>) -> Real {
    match fixed {
        Some(_) => 0.0,
        None => LANDING_SLACK,
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
    for tool in tools.iter().filter(|t| t.is_movable()) {
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

/// The natural step (s): the scene's fixed `time.dt_s`, or `dt_safety` times the stable
/// estimate `stable_dt` (s); the step the next call to `step` takes when neither the tools
/// nor a landing shorten it.
pub(super) fn natural_step(time: &TimeSpec, stable_dt: Real) -> Real {
    time.dt_s.unwrap_or(time.dt_safety * stable_dt)
}

/// What a failed step's diagnosis adds when the step `dt` (s) ran above the stable estimate
/// `stable_dt` (s) of the deformed body (its smallest deformed cell, `stress.rs`): with a
/// fixed step `fixed` (`time.dt_s`, s) above the estimate, that the key holds the step past
/// it and what to do; else the step against the estimate. Empty when the step was within it.
pub(super) fn above_estimate(fixed: Option<Real>, dt: Real, stable_dt: Real) -> String {
    match fixed {
        Some(f) if f > stable_dt => format!(
            "; the fixed step time.dt_s = {f:.3e} s is above the stable estimate {stable_dt:.3e} s of the deformed body (likely an instability): lower time.dt_s, or remove it to step at time.dt_safety of the estimate"
        ),
        _ if dt > stable_dt => format!(
            "; the step {dt:.3e} s was above the stable estimate {stable_dt:.3e} s (likely an instability)"
        ),
        _ => String::new(),
    }
}

/// The step's first check, for both dimensions ([`tool_step_limit`] on the natural step at
/// `stable_dt`, s): the longest step the tools' speeds allow (s), or an error naming the
/// step `step` at time `t` (s) and the tool too fast for it, before anything changes.
pub(super) fn tool_limit<T: Driven>(
    time: &TimeSpec,
    tools: &[T],
    step: u64,
    t: Real,
    stable_dt: Real,
    h_min: Real,
) -> Result<Real> {
    tool_step_limit(tools, t, natural_step(time, stable_dt), h_min)
        .map_err(|what| Error::Request(format!("step {step} (t = {t:.6e} s): {what}")))
}

/// The lengths of one step (s).
#[derive(Debug, Clone, Copy)]
pub(super) struct StepLength {
    /// The step taken, `dt_{n+1}`.
    pub dt: Real,
    /// The natural step (`dt` itself when a landing plan's last step runs over it, so never
    /// less than `dt`): the contact's clearance bound and the 3D penalty's step read it.
    pub full: Real,
    /// `(dt_n + dt_{n+1}) / 2`, the predictor's and corrector's step.
    pub avg: Real,
}

/// Stage 2, the time step, for both dimensions: the natural step (the fixed `time.dt_s`,
/// or `dt_safety` times the stable estimate `stable_dt`, s) within the tools' limit
/// `tool_dt` (s), planned to land on `max_dt` ([`landing_step`], its last steps never past
/// `stable_dt` or `tool_dt`) after a step of `dt_prev` (s); an error when it is not
/// positive. `full` is the natural step, or the step itself when that runs over it.
pub(super) fn length(
    time: &TimeSpec,
    stable_dt: Real,
    dt_prev: Real,
    tool_dt: Real,
    max_dt: Option<Real>,
) -> Result<StepLength> {
    let full = natural_step(time, stable_dt).min(tool_dt);
    let ceiling = stable_dt.min(tool_dt);
    let dt = landing_step(full, max_dt, dt_prev, landing_slack(time.dt_s), ceiling);
    if dt.is_nan() || dt <= 0.0 {
        return Err(Error::Request(format!(
            "step length {dt} s is not positive"
        )));
    }
    Ok(StepLength {
        dt,
        full: full.max(dt),
        avg: 0.5 * (dt + dt_prev),
    })
}

#[cfg(test)]
mod tests {
    use super::{above_estimate, landing_step, LANDING_HOLD};
    use crate::math::Real;

    /// A failed step's diagnosis names a fixed step above the estimate with the key and what
    /// to do, a natural step above it with the two lengths, and nothing within it.
    #[test]
    fn a_step_above_the_estimate_is_named_in_the_diagnosis() {
        let fixed = above_estimate(Some(2.5e-8), 2.5e-8, 1.0e-9);
        assert!(
            fixed.contains("time.dt_s = 2.500e-8 s is above the stable estimate 1.000e-9 s")
                && fixed.contains("lower time.dt_s"),
            "{fixed}"
        );
        let natural = above_estimate(None, 3e-9, 2e-9);
        assert!(
            natural.contains("the step 3.000e-9 s was above the stable estimate 2.000e-9 s"),
            "{natural}"
        );
        assert_eq!(above_estimate(Some(1e-9), 1e-9, 2e-9), "");
        assert_eq!(above_estimate(None, 1e-9, 2e-9), "");
    }

    /// The Taylor bar at a fixed step of 0.95 of its critical step (2.62e-8 s): the foot's
    /// cells shrink the stable estimate below it, and the run stops (an energy balance
    /// error at step 1060) with the diagnosis naming the key.
    #[test]
    fn a_fixed_step_the_deformed_body_outgrew_is_named_when_the_run_stops() {
        let text = include_str!("../../../scenes/taylor_bar.toml")
            .replace("dt_s = 5.0e-9", "dt_s = 2.5e-8");
        let scene = crate::scene::Scene::from_str_named(&text, "t.toml").unwrap();
        let mut sim = crate::Simulation::new(&scene).unwrap();
        let e = sim
            .run_to(scene.time.end_s, |_| {})
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("the fixed step time.dt_s = 2.500e-8 s is above the stable estimate"),
            "{e}"
        );
    }

    #[test]
    fn landing_steps_are_equal_and_never_overshoot() {
        let dt = 2.0;
        assert_eq!(landing_step(dt, None, 0.0, 0.0, 2.0 * dt), dt);
        assert_eq!(landing_step(dt, Some(6.0), dt, 0.0, 2.0 * dt), dt);
        assert_eq!(landing_step(dt, Some(6.0 + 1e-12), dt, 0.0, 2.0 * dt), dt);
        assert_eq!(landing_step(dt, Some(5.0), dt, 0.0, 2.0 * dt), 5.0 / 3.0);
        assert_eq!(landing_step(dt, Some(2.5), dt, 0.0, 2.0 * dt), 1.25);
        assert_eq!(landing_step(dt, Some(0.5), dt, 0.0, 2.0 * dt), 0.5);
        // With slack, a first plan: steps of at most 98 % of the natural step.
        assert_eq!(landing_step(dt, Some(6.0), 0.0, 0.02, 2.0 * dt), 1.5);
        assert_eq!(landing_step(dt, Some(0.5), 0.0, 0.02, 2.0 * dt), 0.5);
        for slack in [0.0, 0.02] {
            for left in [0.1, 1.9, 2.0000001, 3.3, 7.77] {
                for prev in [0.0, 0.3, 1.0, 1.99, 2.5] {
                    let h = landing_step(dt, Some(left), prev, slack, 2.0 * dt);
                    let first = prev == 0.0 || slack == 0.0;
                    assert!(
                        h <= left * (1.0 + 1e-12)
                            && h <= (1.0 + slack) * dt
                            && (h <= dt || left <= LANDING_HOLD * (1.0 + slack) * dt)
                            && (h >= 0.5 * dt || left < dt || !first),
                        "{left}, {prev}, {slack}: {h}"
                    );
                }
            }
        }
    }

    /// The last steps run over the natural step only as far as the ceiling and `1 + slack`:
    /// at `dt_safety` 1 or a tool's travel limit (the ceiling is the natural step itself) a
    /// kept plan a hair above the natural step is made anew within it.
    #[test]
    fn the_last_steps_never_pass_the_ceiling() {
        assert_eq!(landing_step(1.0, Some(2.01), 1.005, 0.02, 2.0), 1.005);
        assert_eq!(landing_step(1.0, Some(2.01), 1.005, 0.02, 1.0), 2.01 / 3.0);
        assert_eq!(landing_step(1.0, Some(2.06), 1.03, 0.02, 2.0), 2.06 / 3.0);
    }

    /// A natural step that falls in jumps (by 1 % every 25 steps, 2 % every 50; the 1 mm
    /// conrod at one mass, session 62: docs/forging.md, "One mass for every grid") with
    /// instants every 97.3 steps: a jump inside the last steps before an instant puts the
    /// kept plan above the natural step, and the new plan at 98 % of it cuts the last step
    /// by a third or a half, unless the last steps may run up to 2 % over the natural step
    /// (never past the stable step, here twice the natural as at `dt_safety` 0.5). No step
    /// changes by more than a fifth.
    #[test]
    fn a_jump_of_the_natural_step_near_an_instant_does_not_halve_the_last_step() {
        for (drop, jump) in [(4e-4, 25usize), (4e-4, 50)] {
            let natural = |i: usize| 1.0 - drop * (jump * (i / jump)) as Real;
            let (every, mut t, mut prev) = (97.3, 0.0, 0.0);
            let mut next = every;
            let mut worst: Real = 1.0;
            for i in 0..2000 {
                let full = natural(i);
                let h = landing_step(full, Some(next - t), prev, 0.02, 2.0 * full);
                assert!(h <= 1.02 * full && h > 0.0, "step {i}: {h} against {full}");
                if prev > 0.0 {
                    worst = worst.min(h / prev);
                }
                t += h;
                prev = h;
                if (next - t).abs() < 1e-9 {
                    t = next;
                    next += every;
                }
            }
            assert!(
                worst >= 0.8,
                "jumps of {} every {jump}: a step fell to {worst} of the one before",
                drop * jump as Real
            );
        }
    }

    /// A run of instants every 37.3 natural steps while the natural step shrinks by 1e-4 a
    /// step (30 % over the run, as a forging's flash thins), then grows back: every step
    /// is stable and lands on each instant, the step never changes by more than 3 % from
    /// one to the next (the plan made anew at each step shortened the last steps before an
    /// instant by up to a third here), and the steps average at least 96 % of the natural.
    #[test]
    fn landing_plans_change_the_step_rarely_and_little() {
        for grow in [false, true] {
            let natural = |i: usize| match grow {
                false => 1.0 - 1e-4 * i as Real,
                true => 0.7 + 1e-4 * i as Real,
            };
            let (every, mut t, mut prev, mut sum) = (37.3, 0.0, 0.0, 0.0);
            let mut worst: Real = 0.0;
            let mut next = every;
            for i in 0..3000 {
                let full = natural(i);
                let h = landing_step(full, Some(next - t), prev, 0.02, 2.0 * full);
                assert!(h <= 1.02 * full && h > 0.0, "step {i}: {h} against {full}");
                if prev > 0.0 {
                    worst = worst.max((h / prev - 1.0).abs());
                }
                sum += h / full;
                t += h;
                prev = h;
                if (next - t).abs() < 1e-9 {
                    t = next;
                    next += every;
                }
                assert!(t <= next + 1e-9, "step {i} passed the instant {next}: {t}");
            }
            assert!(worst <= 0.03, "grow {grow}: the step changed by {worst}");
            assert!(sum / 3000.0 >= 0.96, "grow {grow}: {}", sum / 3000.0);
        }
    }
}
