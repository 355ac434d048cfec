//! Mass scaling: mass added to the particles so that the explicit step grows, for press
//! speeds of mm/s where the wave speed, not the press, would bound the step.
//!
//! The critical step of central differences is `dt_crit = 2 / omega_max`, `omega_max^2` the
//! largest eigenvalue of `M^-1 K`; a factor `f` on every mass gives `sqrt(f)` on the step
//! (uniform scaling, `factor`). Selective scaling (`target_dt_s`, as LS-DYNA's DT2MS) adds
//! mass only where the local step is short: the local step of particle `I` is estimated as
//! `dt_I = c 2 sqrt(m_I / k_I)` (s), with `k_I = M sum_p w_p g_I(p) sum_J g_J(p)` (N/m) a
//! Gershgorin bound on the row sums of the stiffness (`M = K + 4G/3` the P-wave modulus, Pa;
//! `g_I = |grad N_I|` plus `|N_I| / R` in axisymmetry, 1/m), and `c` the calibration that
//! makes the smallest `dt_I` equal the measured (Lanczos) critical step. Particles with
//! `dt_safety dt_I < target` get `m_I (a target / (dt_safety dt_I))^2`, aiming `a` = 2 % above; the critical step is
//! measured again, and the calibration repeated while it falls short (at most
//! [`MAX_ROUNDS`] rounds). Every stage that uses a mass (inertia, the penalty contact of
//! paper eqs. 4-6, the constraint projection, momentum and the energy account) uses the
//! scaled masses.

use super::critical_step::measure_critical_step;
use super::discretization::{Discretization, MassScalingReport};
use super::energy::Energy;
use super::state::State;
use super::update::initial_motion;
use super::workspace::Workspace;
use crate::constraints::Constraints;
use crate::error::Result;
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::scene::{AtRereference, MassScaling, Scene};

/// Most rounds of calibrated selective scaling and measurement of the critical step.
const MAX_ROUNDS: usize = 10;

/// Selective scaling aims this much above its target (-): a particle's added mass also
/// lengthens its neighbours' steps, so the calibrated local estimate undershoots a little
/// from round to round, and an exact aim approaches the target only slowly.
const AIM: Real = 1.02;

/// Upper bounds `k_I = M sum_p w_p g_I(p) sum_J g_J(p)` (N/m) of the stiffness row sums of
/// each of `particles` particles from the point shape table `pt` (weights `w_p`, m^3; `1/R_p`,
/// 1/m, used in axisymmetry), with the P-wave modulus `modulus` (Pa); in `D` dimensions.
pub(super) fn stiffness_bounds<const D: usize>(
    pt: &ShapeTable<D>,
    weights: &[Real],
    inv_radius: &[Real],
    axi: bool,
    modulus: Real,
    particles: usize,
) -> Vec<Real> {
    row_sum_bounds(weights, modulus, particles, |p, g| {
        g.extend(pt.row(p).map(|e| {
            let grad = if D == 2 {
                pt.grad[0][e].hypot(pt.grad[1][e])
            } else {
                pt.grad.iter().map(|g| g[e] * g[e]).sum::<Real>().sqrt()
            };
            let grad = if axi {
                grad + (pt.n[e] * inv_radius[p]).abs()
            } else {
                grad
            };
            (pt.index[e] as usize, grad)
        }))
    })
}

/// The bounds of [`stiffness_bounds`] from any layout of the point shape functions:
/// `row(p, g)` appends point `p`'s pairs `(I, g_I(p))` to `g`.
pub(super) fn row_sum_bounds(
    weights: &[Real],
    modulus: Real,
    particles: usize,
    mut row: impl FnMut(usize, &mut Vec<(usize, Real)>),
) -> Vec<Real> {
    let mut k = vec![0.0; particles];
    let mut g = Vec::new();
    for (p, w) in weights.iter().enumerate() {
        g.clear();
        row(p, &mut g);
        let total: Real = g.iter().map(|(_, gi)| gi).sum();
        for (i, gi) in &g {
            k[*i] += modulus * w * gi * total;
        }
    }
    k
}

/// What selective scaling keeps to act on the shape functions of each kernel re-reference
/// ([`hold`]).
#[derive(Debug, Clone)]
pub(super) struct Target {
    /// The scene's `target_dt_s` (s).
    pub step: Real,
    /// What it does there (`time.mass_scaling.at_rereferences`, not `keep`).
    pub mode: AtRereference,
    /// The P-wave modulus `M` of the stiffness bounds (Pa).
    pub modulus: Real,
    /// The masses before any scaling (kg), what the report measures against.
    pub unscaled: Vec<Real>,
    /// Critical step of the undeformed discretisation without scaling (s).
    pub critical_dt_unscaled: Real,
}

/// How the masses are scaled, from the scene's `[time] mass_scaling`.
pub(super) enum Plan {
    /// Every mass times the factor (-).
    Uniform(Real),
    /// Mass added where the local step is below the target (s), with the stiffness bounds
    /// of [`stiffness_bounds`] (N/m) from the P-wave modulus `modulus` (Pa).
    Selective {
        target: Real,
        modulus: Real,
        stiffness: Vec<Real>,
    },
}

/// Applies mass scaling to the unscaled masses of `disc` (and the critical step measured
/// with them), at setup.
pub(super) fn scale(
    scene: &Scene,
    disc: &mut Discretization,
    st: &mut State,
    ws: &mut Workspace,
    plan: Plan,
) -> Result<()> {
    let unscaled = disc.mass.clone();
    let (report, target) = scaled(
        plan,
        unscaled,
        disc.critical_dt0,
        scene.time.dt_safety,
        |mass| {
            set_masses(scene, disc, st, ws, mass)?;
            measure_critical_step(scene, disc, st, ws)
        },
    )?;
    disc.critical_dt0 = report.critical_dt_s;
    disc.mass_scaling = Some(report);
    disc.scaling_target = target.and_then(|t| t.acting(scene.time.mass_scaling));
    Ok(())
}

/// The scaling of `plan` from the `unscaled` masses (kg) whose critical step is
/// `critical_dt0` (s), with the run's step safety `safety`: `install(masses)` puts masses in
/// the discretisation and returns the critical step measured with them (s). Returns what
/// the masses last installed added and their critical step, and for selective scaling
/// what its re-references need to hold the target (2D and 3D alike).
pub(super) fn scaled(
    plan: Plan,
    unscaled: Vec<Real>,
    critical_dt0: Real,
    safety: Real,
    mut install: impl FnMut(Vec<Real>) -> Result<Real>,
) -> Result<(MassScalingReport, Option<Target>)> {
    match plan {
        Plan::Uniform(f) => {
            let mass: Vec<Real> = unscaled.iter().map(|m| m * f).collect();
            let critical = install(mass.clone())?;
            Ok((report(&unscaled, &mass, critical_dt0, critical), None))
        }
        Plan::Selective {
            target,
            modulus,
            stiffness,
        } => {
            let (mass, critical) = selective(
                target,
                &stiffness,
                unscaled.clone(),
                critical_dt0,
                safety,
                install,
            )?;
            let target = Target {
                step: target,
                mode: AtRereference::Keep,
                modulus,
                unscaled,
                critical_dt_unscaled: critical_dt0,
            };
            Ok((target.report(&mass, critical), Some(target)))
        }
    }
}

/// Selective scaling on the shape functions of a kernel re-reference: mass added to the
/// `current` masses (kg), whose critical step on them is `critical` (s), where the new
/// `stiffness` bounds (N/m, [`row_sum_bounds`]) put a particle's step under the step
/// aimed at: the target (`target`), or `safety` times `before`, the critical step the run
/// followed just before the re-reference (s), if that is shorter (`step`); `install` as
/// for [`scaled`]. The mass is kept at each particle's velocity (the kinetic energy it
/// adds is the re-reference's, `Energy::remap`). Returns the masses installed and what
/// they add to the `unscaled` ones of `target`.
pub(super) fn hold(
    target: &Target,
    before: Real,
    stiffness: &[Real],
    current: Vec<Real>,
    critical: Real,
    safety: Real,
    install: impl FnMut(Vec<Real>) -> Result<Real>,
) -> Result<(Vec<Real>, MassScalingReport)> {
    let aim = match target.mode {
        AtRereference::Step => target.step.min(safety * before),
        AtRereference::Target | AtRereference::Keep => target.step,
    };
    let (mass, critical) = selective(aim, stiffness, current, critical, safety, install)?;
    let report = target.report(&mass, critical);
    Ok((mass, report))
}

/// Calibrated selective scaling (the module doc) of `mass` (kg) with critical step
/// `critical` (s) towards `target` (s): rounds of added mass and measurement until
/// `safety critical >= target`, at most [`MAX_ROUNDS`]. Returns the masses last installed
/// and their critical step (s).
fn selective(
    target: Real,
    stiffness: &[Real],
    mut mass: Vec<Real>,
    mut critical: Real,
    safety: Real,
    mut install: impl FnMut(Vec<Real>) -> Result<Real>,
) -> Result<(Vec<Real>, Real)> {
    for _ in 0..MAX_ROUNDS {
        if safety * critical >= target {
            break;
        }
        let local: Vec<Real> = mass
            .iter()
            .zip(stiffness)
            .map(|(m, k)| 2.0 * (m / k).sqrt())
            .collect();
        let shortest = local.iter().copied().fold(Real::INFINITY, Real::min);
        let calibration = critical / shortest;
        mass = mass
            .iter()
            .zip(&local)
            .map(|(m, dt)| {
                let ratio = AIM * target / (safety * calibration * dt);
                if ratio > 1.0 {
                    m * ratio * ratio
                } else {
                    *m
                }
            })
            .collect();
        critical = install(mass.clone())?;
    }
    Ok((mass, critical))
}

impl Target {
    /// This target with the mode of the scene's `scaling` (`step` when it names none),
    /// `None` where its masses are kept at the re-references.
    pub(super) fn acting(self, scaling: Option<MassScaling>) -> Option<Target> {
        match scaling.and_then(|m| m.at_rereferences) {
            Some(AtRereference::Keep) => None,
            mode => Some(Target {
                mode: mode.unwrap_or(AtRereference::Step),
                ..self
            }),
        }
    }
    /// What the `scaled` masses (kg), whose critical step is `critical` (s), add to the
    /// unscaled ones.
    pub(super) fn report(&self, scaled: &[Real], critical: Real) -> MassScalingReport {
        report(&self.unscaled, scaled, self.critical_dt_unscaled, critical)
    }
}

/// What scaling the `unscaled` masses to `scaled` (kg) added, with the critical steps before
/// and after (s).
fn report(
    unscaled: &[Real],
    scaled: &[Real],
    critical_dt_unscaled_s: Real,
    critical_dt_s: Real,
) -> MassScalingReport {
    let total: Real = unscaled.iter().sum();
    let added: Real = scaled.iter().sum::<Real>() - total;
    let (mut most, mut count) = (0.0, 0);
    for (m, m0) in scaled.iter().zip(unscaled) {
        if m > m0 {
            most = Real::max(most, (m - m0) / m0);
            count += 1;
        }
    }
    MassScalingReport {
        added_mass_rel: added / total,
        max_added_rel: most,
        scaled_particles: count,
        critical_dt_unscaled_s,
        critical_dt_s,
    }
}

/// Replaces the lumped masses (kg) of `disc` and what depends on them: inverse masses, the
/// essential conditions' projection, the initial velocities projected onto them and the
/// initial kinetic energy.
pub(super) fn set_masses(
    scene: &Scene,
    disc: &mut Discretization,
    st: &mut State,
    ws: &mut Workspace,
    mass: Vec<Real>,
) -> Result<()> {
    if let Some(c) = &disc.constraints {
        disc.constraints = Constraints::new(c.rows.clone(), &disc.nodal, &mass)?;
    }
    let v0 = scene.workpiece.initial_velocity_m_per_s;
    let (v, initial) = initial_motion(v0, disc.constraints.as_ref(), &mass);
    disc.inv_mass = mass.iter().map(|m| 1.0 / m).collect();
    disc.mass = mass;
    st.v.clone_from(&v);
    ws.v_prev = v;
    st.energy = Energy::starting(initial);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Uncoupled particles of stiffness `k` (N/m): the critical step is exactly
    /// `min_I 2 sqrt(m_I / k_I)` (s), and the bounds are the stiffnesses.
    fn critical(mass: &[Real], k: &[Real]) -> Real {
        mass.iter()
            .zip(k)
            .map(|(m, k)| 2.0 * (m / k).sqrt())
            .fold(Real::INFINITY, Real::min)
    }

    /// At a re-reference whose new shape functions step shorter than the run did before,
    /// `step` adds mass only to the particles under that step and reaches it, while
    /// `target` reaches the target; `keep`'s masses would not be touched at all (no
    /// [`Target`] for it).
    #[test]
    fn step_restores_the_step_before_and_target_the_target() {
        let (safety, unscaled) = (0.5, vec![1.0; 4]);
        // The particles' own steps on the new shape functions: 2, 1, 0.2 and 0.1 s.
        let k: Vec<Real> = [2.0, 1.0, 0.2, 0.1]
            .map(|dt: Real| 4.0 / (dt * dt))
            .to_vec();
        let target = |mode| Target {
            step: 0.8,
            mode,
            modulus: 1.0,
            unscaled: unscaled.clone(),
            critical_dt_unscaled: 0.1,
        };
        let before = 0.6;
        let run = |mode| {
            hold(
                &target(mode),
                before,
                &k,
                unscaled.clone(),
                critical(&unscaled, &k),
                safety,
                |m| Ok(critical(&m, &k)),
            )
            .unwrap()
        };
        let (step, report) = run(AtRereference::Step);
        assert!(
            safety * report.critical_dt_s >= safety * before,
            "{report:?}"
        );
        assert_eq!(
            &step[..2],
            &unscaled[..2],
            "particles stepping long enough keep their mass"
        );
        assert!(step[2] > 1.0 && step[3] > step[2]);
        let (all, report) = run(AtRereference::Target);
        assert!(safety * report.critical_dt_s >= 0.8, "{report:?}");
        assert!(all[1] > 1.0 && all.iter().zip(&step).all(|(a, s)| a >= s));
    }
}
