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

use super::Simulation;
use crate::error::Result;
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use serde::{Deserialize, Serialize};

/// Most rounds of calibrated selective scaling and measurement of the critical step.
const MAX_ROUNDS: usize = 10;

/// Selective scaling aims this much above its target (-): a particle's added mass also
/// lengthens its neighbours' steps, so the calibrated local estimate undershoots a little
/// from round to round, and an exact aim approaches the target only slowly.
const AIM: Real = 1.02;

/// What mass scaling added, for the summary.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MassScalingReport {
    /// Mass added relative to the workpiece's mass, `(sum m'_I - sum m_I) / sum m_I` (-).
    pub added_mass_rel: Real,
    /// Largest mass added to one particle relative to its own mass, `max (m'_I - m_I) / m_I`.
    pub max_added_rel: Real,
    /// Particles that got mass.
    pub scaled_particles: usize,
    /// Critical step of the undeformed discretisation without scaling (s).
    pub critical_dt_unscaled_s: Real,
    /// Critical step with the scaled masses (s).
    pub critical_dt_s: Real,
}

/// Upper bounds `k_I = M sum_p w_p g_I(p) sum_J g_J(p)` (N/m) of the stiffness row sums of
/// each of `particles` particles from the point shape table `pt` (weights `w_p`, m^3; `1/R_p`,
/// 1/m, used in axisymmetry), with the P-wave modulus `modulus` (Pa).
pub(super) fn stiffness_bounds(
    pt: &ShapeTable,
    weights: &[Real],
    inv_radius: &[Real],
    axi: bool,
    modulus: Real,
    particles: usize,
) -> Vec<Real> {
    let mut k = vec![0.0; particles];
    let mut g = Vec::new();
    for (p, w) in weights.iter().enumerate() {
        g.clear();
        g.extend(pt.row(p).map(|e| {
            let grad = pt.dx[e].hypot(pt.dy[e]);
            if axi {
                grad + (pt.n[e] * inv_radius[p]).abs()
            } else {
                grad
            }
        }));
        let total: Real = g.iter().sum();
        for (e, gi) in pt.row(p).zip(&g) {
            k[pt.index[e] as usize] += modulus * w * gi * total;
        }
    }
    k
}

/// How the masses are scaled, from the scene's `[time] mass_scaling`.
pub(super) enum Plan {
    /// Every mass times the factor (-).
    Uniform(Real),
    /// Mass added where the local step is below the target (s), with the stiffness bounds
    /// of [`stiffness_bounds`] (N/m).
    Selective { target: Real, stiffness: Vec<Real> },
}

impl Simulation {
    /// The quasi-static watch after a step in which `contact` forces acted or not: the
    /// kinetic-to-internal energy ratio once the start-up is over (`kinetic_to_internal_from`
    /// of the time from the first contact, or from t = 0 without tools, to the end), its
    /// largest value kept, and the run stopped past `checks.kinetic_to_internal_max`.
    pub(super) fn watch_quasi_static(&mut self, contact: bool) -> Result<()> {
        let st = &mut self.st;
        if contact && st.first_contact_s.is_none() {
            st.first_contact_s = Some(st.time);
        }
        let start = if self.tools.is_empty() {
            Some(0.0)
        } else {
            st.first_contact_s
        };
        let (checks, end) = (&self.scene.checks, self.scene.time.end_s);
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

    /// Applies mass scaling to the unscaled masses (and the critical step measured with
    /// them).
    pub(super) fn scale_masses(&mut self, plan: Plan) -> Result<()> {
        let unscaled = self.mass.clone();
        let critical_dt_unscaled_s = self.critical_dt0;
        match plan {
            Plan::Uniform(f) => {
                let scaled = unscaled.iter().map(|m| m * f).collect();
                self.set_masses(scaled)?;
                self.critical_dt0 = self.measure_critical_step()?;
            }
            Plan::Selective { target, stiffness } => {
                let safety = self.scene.time.dt_safety;
                for _ in 0..MAX_ROUNDS {
                    if safety * self.critical_dt0 >= target {
                        break;
                    }
                    let local: Vec<Real> = self
                        .mass
                        .iter()
                        .zip(&stiffness)
                        .map(|(m, k)| 2.0 * (m / k).sqrt())
                        .collect();
                    let shortest = local.iter().copied().fold(Real::INFINITY, Real::min);
                    let calibration = self.critical_dt0 / shortest;
                    let scaled = self
                        .mass
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
                    self.set_masses(scaled)?;
                    self.critical_dt0 = self.measure_critical_step()?;
                }
            }
        }
        let total: Real = unscaled.iter().sum();
        let added: Real = self.mass.iter().sum::<Real>() - total;
        let (mut most, mut count) = (0.0, 0);
        for (m, m0) in self.mass.iter().zip(&unscaled) {
            if m > m0 {
                most = Real::max(most, (m - m0) / m0);
                count += 1;
            }
        }
        self.mass_scaling = Some(MassScalingReport {
            added_mass_rel: added / total,
            max_added_rel: most,
            scaled_particles: count,
            critical_dt_unscaled_s,
            critical_dt_s: self.critical_dt0,
        });
        Ok(())
    }
}
