//! What the stress stage leaves at each integration point besides its history: the Mises
//! stress and `J` for the outputs, and the hardening law cached at the point's plastic
//! strain for the next yield test.

use crate::material::HenckyJ2;
use crate::math::Real;

/// Per-point results of the last stress update, and the hardening law evaluated at the
/// point's `eps_p` (cached: recomputed only when the point yields).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct PointOut {
    pub(super) von_mises: Real,
    pub(super) jacobian: Real,
    /// `sigma_y(eps_p)` (Pa).
    pub(super) flow_stress: Real,
    /// `int_0^eps_p sigma_y de` (J/m^3).
    pub(super) plastic_work: Real,
}

impl PointOut {
    pub(super) fn initial(material: &HenckyJ2) -> PointOut {
        PointOut {
            flow_stress: material.hardening.initial_yield(),
            ..Default::default()
        }
    }

    /// The cached outputs of a point with plastic strain `eps_p` at temperature `temp_c`
    /// (degrees C; `None` in an isothermal scene): the yield test's flow stress (the law at
    /// the point's plastic strain, its least rate and temperature), and the closed-form
    /// plastic work of the linear and power laws.
    pub(super) fn at(material: &HenckyJ2, eps_p: Real, temp_c: Option<Real>) -> PointOut {
        let mut out = PointOut::initial(material);
        let flow = match temp_c {
            Some(t) if material.hardening.is_thermal() => {
                material.hardening.flow(eps_p, 0.0, t).stress
            }
            _ => material.hardening.flow_stress(eps_p),
        };
        out.set_plastic_strain(material, eps_p, flow, material.hardening.initial_yield());
        out
    }

    /// Caches the hardening law at `eps_p`, where the flow stress is `flow` and the
    /// initial yield stress `initial` (Pa).
    pub(super) fn set_plastic_strain(
        &mut self,
        material: &HenckyJ2,
        eps_p: Real,
        flow: Real,
        initial: Real,
    ) {
        self.flow_stress = flow;
        self.plastic_work = material.hardening.plastic_work_at(eps_p, flow, initial);
    }
}
