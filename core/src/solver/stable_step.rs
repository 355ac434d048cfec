//! The length of each step: the critical step of central differences measured once on the
//! undeformed discretisation, the tools' speed limit, and the equal steps that land on a
//! requested instant.

use super::discretization::Discretization;
use super::state::State;
use super::workspace::Workspace;
use super::{stress, update};
use crate::error::{Error, Result};
use crate::math::Real;
use crate::scene::Scene;
use crate::tools::Tool;

/// Most Lanczos products for the critical step.
const LANCZOS_MAX: usize = 300;

/// Critical step of central differences with lumped masses on the undeformed
/// discretisation, `dt_crit = 2 / omega_max` (s), with `omega_max^2` the largest
/// eigenvalue of `M^{-1} K`, found by Lanczos iteration on the symmetric
/// `A = M^{-1/2} K M^{-1/2}` (Golub & Van Loan, Matrix Computations, sec. 10.1): the
/// largest eigenvalue of the tridiagonal `T_k` converges to it from below in a few tens
/// of products, where power iteration needs hundreds on large models. `K x` is the
/// internal force (N) that `internal_force` returns for a displacement `x` (m) scaled to
/// `amplitude` (m; small enough to stay linear elastic); `inv_sqrt_m` is `1 / sqrt(m_I)`
/// (kg^-1/2). The estimate depends on the support, the integration rule and the mass
/// lumping, which `h / c` ignores.
pub(super) fn critical_step(
    inv_sqrt_m: &[Real],
    amplitude: Real,
    mut internal_force: impl FnMut(Vec<[Real; 2]>) -> Result<Vec<[Real; 2]>>,
) -> Result<Real> {
    let np = inv_sqrt_m.len();
    // Deterministic pseudo-random start (xorshift), so no mode is missed by symmetry.
    let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as Real / (1u64 << 53) as Real - 0.5
    };
    let mut v: Vec<[Real; 2]> = (0..np).map(|_| [rnd(), rnd()]).collect();
    let norm = |x: &[[Real; 2]]| {
        x.iter()
            .map(|a| a[0] * a[0] + a[1] * a[1])
            .sum::<Real>()
            .sqrt()
    };
    let n0 = norm(&v);
    v.iter_mut().for_each(|a| *a = [a[0] / n0, a[1] / n0]);
    let mut v_prev = vec![[0.0; 2]; np];
    let (mut alpha, mut beta) = (Vec::new(), Vec::new());
    let mut lambda = 0.0;
    for it in 0..LANCZOS_MAX {
        // w = A v: K applied to the displacement M^{-1/2} v, scaled to `amplitude`.
        let xmax = v
            .iter()
            .zip(inv_sqrt_m)
            .map(|(a, s)| (a[0].abs().max(a[1].abs())) * s)
            .fold(0.0, Real::max);
        let scale = amplitude / xmax;
        let f_int = internal_force(
            v.iter()
                .zip(inv_sqrt_m)
                .map(|(a, s)| [a[0] * s * scale, a[1] * s * scale])
                .collect(),
        )?;
        let b_prev = beta.last().copied().unwrap_or(0.0);
        let mut w: Vec<[Real; 2]> = f_int
            .iter()
            .zip(inv_sqrt_m)
            .zip(&v_prev)
            .map(|((f, s), vp)| {
                [
                    f[0] * s / scale - b_prev * vp[0],
                    f[1] * s / scale - b_prev * vp[1],
                ]
            })
            .collect();
        let a: Real = w
            .iter()
            .zip(&v)
            .map(|(x, y)| x[0] * y[0] + x[1] * y[1])
            .sum();
        w.iter_mut().zip(&v).for_each(|(x, y)| {
            x[0] -= a * y[0];
            x[1] -= a * y[1];
        });
        alpha.push(a);
        let next = tridiagonal_max_eigenvalue(&alpha, &beta);
        let b = norm(&w);
        let converged = it >= 10 && (next - lambda).abs() <= 1e-6 * next;
        lambda = next;
        if converged || b <= 1e-12 * next.abs() {
            break;
        }
        beta.push(b);
        w.iter_mut().for_each(|x| *x = [x[0] / b, x[1] / b]);
        v_prev = std::mem::replace(&mut v, w);
    }
    if !(lambda > 0.0 && lambda.is_finite()) {
        return Err(Error::ShapeFunctions(format!(
            "the stiffness has no positive eigenvalue ({lambda:.3e})"
        )));
    }
    Ok(2.0 / lambda.sqrt())
}

/// Largest eigenvalue of the symmetric tridiagonal matrix with diagonal `a` and
/// off-diagonal `b` (`b.len() + 1 == a.len()`), by Sturm-sequence bisection between the
/// Gershgorin bounds: the count of eigenvalues below `x` is the number of negative pivots
/// of `T - x I` (Golub & Van Loan, sec. 8.4).
fn tridiagonal_max_eigenvalue(a: &[Real], b: &[Real]) -> Real {
    let radius =
        |i: usize| (if i > 0 { b[i - 1].abs() } else { 0.0 }) + b.get(i).map_or(0.0, |x| x.abs());
    let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
    for (i, &ai) in a.iter().enumerate() {
        lo = lo.min(ai - radius(i));
        hi = hi.max(ai + radius(i));
    }
    let below = |x: Real| {
        let mut count = 0;
        let mut q = 1.0;
        for (i, &ai) in a.iter().enumerate() {
            let off = if i > 0 { b[i - 1] * b[i - 1] } else { 0.0 };
            q = ai - x - if i > 0 { off / q } else { 0.0 };
            if q == 0.0 {
                q = -Real::EPSILON * (x.abs() + 1.0);
            }
            if q < 0.0 {
                count += 1;
            }
        }
        count
    };
    let n = a.len();
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if below(mid) < n {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

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
pub(super) fn tool_step_limit(
    tools: &[Tool],
    t: Real,
    dt: Real,
    h: Real,
) -> std::result::Result<Real, String> {
    let travel = TOOL_TRAVEL_SPACINGS * h;
    let mut limited = Real::INFINITY;
    for tool in tools.iter().filter(|t| t.is_movable()) {
        let speed = tool
            .velocity_at(t)
            .abs()
            .max(tool.velocity_at(t + dt).abs());
        if speed * dt <= travel {
            continue;
        }
        let short = travel / speed;
        if short < TOOL_STEP_FRACTION * dt {
            let source = match tool.state.command {
                Some(_) => "commanded",
                None => "in the scene",
            };
            return Err(format!(
                "tool `{}`: velocity {speed:.4e} m/s ({source}) would move it {:.4e} m in one step of {dt:.4e} s, more than {TOOL_TRAVEL_SPACINGS} particle spacing ({travel:.4e} m), and the step would have to shorten below {TOOL_STEP_FRACTION} of its length; lower the tool's velocity",
                tool.name,
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

/// The critical step on the undeformed discretisation ([`critical_step`]), with `K x` the
/// internal force of a displacement of 1e-7 of the spacing; the state is left undeformed.
/// With a modulus over temperature the points answer at their temperatures now: the step
/// is scaled by `sqrt(f_now / f_max)`, `f_now` the largest modulus factor of the points'
/// temperatures and `f_max` the table's largest, so that it holds when a die chills the
/// body stiffer.
pub(super) fn measure_critical_step(
    scene: &Scene,
    disc: &Discretization,
    st: &mut State,
    ws: &mut Workspace,
) -> Result<Real> {
    let stiffening = match (&disc.material.thermoelastic, &st.heat) {
        (Some(te), Some(h)) if !te.modulus_factor.is_empty() => {
            let now = h
                .temperature_c
                .iter()
                .map(|&t| te.modulus_factor_at(t))
                .fold(Real::NEG_INFINITY, Real::max);
            (now / te.modulus_factor_max()).sqrt()
        }
        _ => 1.0,
    };
    let saved_points = st.points.clone();
    // The stress stage also heats the points and books the energy: neither is the run's.
    let (saved_heat, saved_energy) = (st.heat.clone(), st.energy);
    let amplitude = 1e-7 * disc.h_min();
    let inv_sqrt_m: Vec<Real> = disc.mass.iter().map(|m| 1.0 / m.sqrt()).collect();
    let dt = critical_step(&inv_sqrt_m, amplitude, |d| {
        st.d = d;
        stress::run(scene, disc, st, ws)?;
        update::forces(disc, &[], st, ws, None);
        Ok(ws.f_int.clone())
    });
    st.d = vec![[0.0; 2]; disc.ref_pos.len()];
    st.points = saved_points;
    st.heat = saved_heat;
    st.energy = saved_energy;
    dt.map(|dt| dt * stiffening)
}

#[cfg(test)]
mod tests {
    use super::{landing_step, tridiagonal_max_eigenvalue};

    #[test]
    fn tridiagonal_largest_eigenvalue() {
        // Second-difference matrix: eigenvalues 2 - 2 cos(k pi / (n + 1)).
        for n in [1, 2, 5, 40] {
            let a = vec![2.0; n];
            let b = vec![-1.0; n - 1];
            let exact = 2.0 - 2.0 * (n as f64 * std::f64::consts::PI / (n as f64 + 1.0)).cos();
            let got = tridiagonal_max_eigenvalue(&a, &b);
            assert!(
                (got - exact).abs() <= 1e-12 * exact,
                "n {n}: {got} vs {exact}"
            );
        }
        assert_eq!(tridiagonal_max_eigenvalue(&[3.0, -1.0], &[0.0]), 3.0);
    }

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
