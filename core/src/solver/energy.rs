//! The energy account of a run (J): what each step adds to it, and the two checks that stop
//! a run whose account does not close (a discretisation error or an instability) or whose
//! contact interface generates energy.

use super::stable_step::above_estimate;
use crate::error::{Error, Result};
use crate::math::{dot, Real};
use serde::{Deserialize, Serialize};

/// Energy account (J), whole ring in axisymmetry, per depth in plane strain.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct Energy {
    /// Kinetic energy at the start.
    pub initial: Real,
    /// Kinetic energy `sum m_I |v_I|^2 / 2` at the last half step.
    pub kinetic: Real,
    /// Stored elastic energy `sum_p W(eps_e) w_p`.
    pub elastic: Real,
    /// Plastic dissipation `sum_p w_p int sigma_y d eps_p`.
    pub plastic: Real,
    /// Work done by the tools' contact forces on the workpiece.
    pub contact_work: Real,
    /// Sum of the magnitudes of the contact work increments (scale for the balance).
    pub contact_work_abs: Real,
    /// Work delivered by the tools' motion, `sum dt_avg f_J . v_tool` (J): what a press
    /// would measure. It differs from `contact_work` by what the penalty interface takes.
    pub tool_work: Real,
    /// Sum of the magnitudes of the tool work increments (J).
    pub tool_work_abs: Real,
    /// Internal work over the half step from `d_n` to `d_{n+1/2}`, `dt f_int . v_{n+1/2} / 2`,
    /// which puts the internal energy at the time of the kinetic energy.
    pub internal_half_step: Real,
    /// Kinetic energy changed by the velocity transfers of kernel re-referencing
    /// (`rereference.rs`; J), 0 without re-referencing.
    #[serde(default)]
    pub remap: Real,
    /// Elastic energy that changes of temperature put into the elastic state, through the
    /// modulus and the thermal strain over temperature (J; `stress.rs`), 0 without them: no
    /// force did that work.
    #[serde(default)]
    pub thermoelastic: Real,
    /// Sum of the magnitudes of the thermoelastic increments (J), part of the balance's
    /// reference: a body that the dies chill at rest exchanges no work but that.
    #[serde(default)]
    pub thermoelastic_abs: Real,
}

/// Kinetic energy `sum m_I |v_I|^2 / 2` (J) of coefficient velocities `v` (m/s) with the
/// lumped masses `mass` (kg), `|v_I|^2` summed from its first component on ([`dot`]).
pub(super) fn kinetic_energy<const D: usize>(mass: &[Real], v: &[[Real; D]]) -> Real {
    0.5 * mass.iter().zip(v).map(|(m, v)| m * dot(v, v)).sum::<Real>()
}

impl Energy {
    /// The account at the start of a run: the body's kinetic energy `initial` (J), nothing
    /// exchanged yet.
    pub fn starting(initial: Real) -> Energy {
        Energy {
            initial,
            kinetic: initial,
            ..Default::default()
        }
    }

    /// Internal energy: stored elastic plus plastic dissipation.
    pub fn internal(&self) -> Real {
        self.elastic + self.plastic
    }
    /// `kinetic + internal - contact_work - initial` (J), all at the half step: zero for an
    /// exact account. Kinetic energy and contact work obey the exact discrete identity
    /// `dKE = dt_avg f . (v_new + v_old) / 2`; the internal energy is the constitutive one at
    /// `d_n` plus the half-step work, which equals the internal force work exactly for a
    /// linear elastic body, so what remains measures the time discretisation of plasticity.
    pub fn balance_error(&self) -> Real {
        self.kinetic + self.internal() + self.internal_half_step
            - self.contact_work
            - self.initial
            - self.remap
            - self.thermoelastic
    }
    /// The energy against which the balance error is measured: the largest of the initial
    /// energy, the total contact work and tool work exchanged, and the elastic energy
    /// changes of temperature moved in and out.
    pub fn reference(&self) -> Real {
        self.initial
            .max(self.contact_work_abs)
            .max(self.tool_work_abs)
            .max(self.thermoelastic_abs)
    }
    /// Energy gained by the penalty interface, `contact_work - tool_work` (J): negative or
    /// near zero (the paper's penalty stops particles at a tool, which dissipates); a clear
    /// gain means the contact produced energy.
    pub fn interface_gain(&self) -> Real {
        self.contact_work - self.tool_work
    }
    /// Balance error relative to the reference energy (0 when nothing happened yet).
    pub fn balance_error_rel(&self) -> Real {
        let r = self.reference();
        if r > 0.0 {
            self.balance_error().abs() / r
        } else {
            0.0
        }
    }

    /// Kinetic over internal energy (-): infinite while the workpiece moves without
    /// internal energy, 0 at rest.
    pub fn kinetic_to_internal(&self) -> Real {
        let internal = self.internal();
        if internal > 0.0 {
            self.kinetic / internal
        } else if self.kinetic > 0.0 {
            Real::INFINITY
        } else {
            0.0
        }
    }

    /// Stops a run whose kinetic-to-internal ratio `ratio` exceeds the scene's `bound`
    /// (`step` ending at `time`, s): inertia is no longer negligible, so the quasi-static
    /// assumption behind mass scaling fails.
    pub(super) fn check_quasi_static(
        &self,
        ratio: Real,
        bound: Real,
        step: u64,
        time: Real,
    ) -> Result<()> {
        if ratio > bound {
            return Err(Error::QuasiStatic {
                step,
                time,
                ratio,
                bound,
                detail: format!(
                    "kinetic {:.4e} J, internal {:.4e} J (elastic {:.4e} J + plastic {:.4e} J); lower the mass scaling or the tool speed",
                    self.kinetic,
                    self.internal(),
                    self.elastic,
                    self.plastic
                ),
            });
        }
        Ok(())
    }

    /// Adds one step's figures (J): the kinetic energy at the new half step, the elastic and
    /// plastic energy of the stress stage, the contact work and the work the tools delivered
    /// over the step, and the internal half-step work.
    pub(super) fn add_step(&mut self, step: StepEnergy) {
        self.kinetic = step.kinetic;
        self.elastic = step.elastic;
        self.plastic = step.plastic;
        self.contact_work += step.contact_work;
        self.contact_work_abs += step.contact_work.abs();
        self.tool_work += step.tool_work;
        self.tool_work_abs += step.tool_work.abs();
        self.internal_half_step = step.internal_half_step;
    }

    /// Stops a run whose balance error exceeds `tol` of the reference energy, or whose
    /// contact interface generated more than `tol` of it, with a diagnosis naming the step
    /// (`step` ending at `time`, s, of length `dt` against the stable estimate `stable_dt`, s).
    pub(super) fn check(
        &self,
        tol: Real,
        step: u64,
        time: Real,
        dt: Real,
        stable_dt: Real,
        fixed: Option<Real>,
    ) -> Result<()> {
        let e = self;
        let rel = e.balance_error_rel();
        if rel > tol {
            return Err(Error::EnergyBalance {
                step,
                time,
                error_rel: rel,
                bound: tol,
                detail: format!(
                    "kinetic {:.4e} J + elastic {:.4e} J + plastic {:.4e} J - contact work {:.4e} J{} vs initial {:.4e} J; step {:.3e} s, stable estimate {:.3e} s{}",
                    e.kinetic,
                    e.elastic,
                    e.plastic,
                    e.contact_work,
                    if e.thermoelastic_abs > 0.0 {
                        format!(" - put in by temperature {:.4e} J", e.thermoelastic)
                    } else {
                        String::new()
                    },
                    e.initial,
                    dt,
                    stable_dt,
                    above_estimate(fixed, dt, stable_dt)
                ),
            });
        }
        let gain = e.interface_gain();
        if gain > tol * e.reference() {
            return Err(Error::EnergyBalance {
                step,
                time,
                error_rel: gain / e.reference(),
                bound: tol,
                detail: format!(
                    "the contact interface generated {gain:.4e} J: the contact forces did {:.4e} J of work on the workpiece while the tools delivered {:.4e} J{}",
                    e.contact_work, e.tool_work, above_estimate(fixed, dt, stable_dt)
                ),
            });
        }
        Ok(())
    }
}

/// What one step adds to the account (J).
pub(super) struct StepEnergy {
    /// Kinetic energy at the new half step.
    pub kinetic: Real,
    /// Stored elastic energy from the stress stage.
    pub elastic: Real,
    /// Plastic dissipation from the stress stage.
    pub plastic: Real,
    /// Work of the contact forces on the workpiece over the step.
    pub contact_work: Real,
    /// Work delivered by the tools' motion over the step.
    pub tool_work: Real,
    /// Internal work over the half step.
    pub internal_half_step: Real,
}
