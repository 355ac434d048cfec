//! J2 elasto-plasticity at finite strain: hyperelastic Hencky model with multiplicative
//! split `F = F_e F_p` and exponential return mapping in principal logarithmic strains
//! (Simo 1992, CMAME 99, Box 1; Eterovic & Bathe 1990).
//!
//! Why this model rather than a hypoelastic objective rate: the stored energy is a true
//! potential, so the energy account is exact state by state; plastic flow is exactly
//! isochoric (`det F_p = 1`), so volume is conserved under plasticity by construction; it is
//! objective without any incremental rotation, and the return mapping is exactly the
//! small-strain radial return written in logarithmic strains, exact for proportional paths.
//!
//! Per integration point, with `C_p^{-1}` the stored inverse plastic right Cauchy-Green tensor:
//! 1. trial elastic left Cauchy-Green `b_e = F C_p^{-1} F^T`, principal values `lambda_i^2`;
//! 2. logarithmic elastic strains `eps_i = ln lambda_i`, volumetric `theta = sum eps_i`,
//!    deviatoric `e_i = eps_i - theta/3`;
//! 3. trial Kirchhoff stress `tau_i = K theta + 2 G e_i`, Mises `q = sqrt(6) G |e|`;
//! 4. if `q > sigma_y(eps_p)`: solve `q - 3 G dgamma - sigma_y(eps_p + dgamma) = 0`
//!    and scale `e_i *= 1 - 3 G dgamma / q` (radial return);
//! 5. update `b_e = sum exp(2 eps_i) n_i n_i^T` and `C_p^{-1} = F^{-1} b_e F^{-T}`;
//! 6. first Piola-Kirchhoff stress `P = tau F^{-T}` (Pa), Cauchy `sigma = tau / J`.
//!
//! Kinematics are 2D with an out-of-plane stretch `F_33`: 1 in plane strain, the hoop
//! stretch `r / R` in axisymmetry; `b_e` stays block diagonal (in-plane 2x2 and `33`).
//! The 3D kinematics (a full `F`) are [`super::simo1992_hencky_j2_3d`]. Only steps 1, 5
//! and 6 depend on the dimension (`Kinematics`); steps 2-4, the energy and the
//! thermoelastic terms are `HenckyJ2::update_batch`, one source for both.

use super::hardening::Isotherm;
use super::Hardening;
use crate::lanes::{self, Lanes, LANES};
use crate::math::{sym_spectral2, Real};
use crate::thermal::properties::Thermoelastic;
use serde::{Deserialize, Serialize};

/// Trial elastic left Cauchy-Green tensor `b_e = F C_p^{-1} F^T` (step 1 of the module doc)
/// as `[b_11, b_12, b_22, b_33]` (-), for `f = [F_xX, F_xY, F_yX, F_yY]`, the out-of-plane
/// stretch `f33` and `cp_inv = [C_p^{-1}_11, _12, _22, _33]`.
#[inline(always)]
pub fn elastic_left_cauchy_green(f: [Real; 4], f33: Real, cp_inv: [Real; 4]) -> [Real; 4] {
    let [c11, c12, c22, c33] = cp_inv;
    let fc11 = f[0] * c11 + f[1] * c12;
    let fc12 = f[0] * c12 + f[1] * c22;
    let fc21 = f[2] * c11 + f[3] * c12;
    let fc22 = f[2] * c12 + f[3] * c22;
    [
        fc11 * f[0] + fc12 * f[1],
        fc11 * f[2] + fc12 * f[3],
        fc21 * f[2] + fc22 * f[3],
        f33 * f33 * c33,
    ]
}

/// `sqrt(6)`: the Mises stress of a deviatoric logarithmic strain `e` is `sqrt(6) G |e|`.
const SQRT_6: Real = 2.449_489_742_783_178;

/// Elastic constants and hardening law of a Hencky J2 material.
#[derive(Debug, Clone, PartialEq)]
pub struct HenckyJ2 {
    /// Bulk modulus `K = E / (3 (1 - 2 nu))` (Pa).
    pub bulk: Real,
    /// Shear modulus `G = E / (2 (1 + nu))` (Pa).
    pub shear: Real,
    /// Isotropic hardening law.
    pub hardening: Hardening,
    /// The modulus and thermal stretch over temperature of a thermal scene that asks for
    /// them (`None`: the constants above at every temperature, no thermal strain).
    pub thermoelastic: Option<Thermoelastic>,
}

/// History variables of one integration point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PointState {
    /// `C_p^{-1}` components `[11, 12, 22, 33]` (-), identity at the start.
    pub cp_inv: [Real; 4],
    /// Equivalent plastic strain (-).
    pub eps_p: Real,
}

impl Default for PointState {
    fn default() -> Self {
        PointState {
            cp_inv: [1.0, 0.0, 1.0, 1.0],
            eps_p: 0.0,
        }
    }
}

/// What the stress update returns for one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StressUpdate {
    /// First Piola-Kirchhoff stress `[P_xX, P_xY, P_yX, P_yY, P_33]` (Pa).
    pub piola: [Real; 5],
    /// Kirchhoff stress `[tau_xx, tau_xy, tau_yy, tau_33]` (Pa).
    pub kirchhoff: [Real; 4],
    /// Jacobian `J = det F` (-).
    pub jacobian: Real,
    /// Mises equivalent of the Cauchy stress `q / J` (Pa).
    pub von_mises: Real,
    /// Stored elastic energy per reference volume `K theta^2 / 2 + G |e|^2` (J/m^3).
    pub elastic_energy: Real,
}

/// Inputs and history of [`LANES`] points, component-major (`f[c][lane]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLanes {
    /// `[F_xX, F_xY, F_yX, F_yY]` (-).
    pub f: [Lanes; 4],
    /// Out-of-plane stretch `F_33` (-).
    pub f33: Lanes,
    /// `C_p^{-1}` components `[11, 12, 22, 33]` (-).
    pub cp_inv: [Lanes; 4],
    /// Equivalent plastic strain (-).
    pub eps_p: Lanes,
    /// Flow stress `sigma_y(eps_p)` (Pa): the yield test's, at the law's least rate.
    pub flow_stress: Lanes,
    /// Temperature (degrees C), read by the laws of rate and temperature and the
    /// elasticity over temperature only.
    pub temperature: Lanes,
    /// The last update's `[E(T) / E, ln lambda_th(T), ln J, |e|^2]` (-: the modulus factor
    /// and thermal log strain of its temperature, its volumetric log strain and its elastic
    /// deviator's square after the return), read by the elasticity over temperature only:
    /// the energy the change of temperature put into the elastic state.
    pub elastic_prev: [Lanes; 4],
    /// `1 / dt` (1/s) of the step the strain increment was taken over: the plastic strain
    /// rate of a return is `dgamma / dt`; 0 before the first step (the least rate).
    pub inv_dt: Real,
    /// A first guess of each lane's `dgamma` for the laws of rate and temperature (the last
    /// step's plastic strain rate times this step's length; 0: none).
    pub guess: Lanes,
    /// Plastic work density of the last update (J/m^3), `int sigma_y d eps` over the step's
    /// strain at its rate and temperature ([`super::hardening::Isotherm::work`]), for the
    /// laws of rate and temperature (0 where a lane stayed elastic; not set for the
    /// linear and power laws, whose work has a closed form).
    pub plastic_work: Lanes,
}

impl PointLanes {
    /// Every lane undeformed and unable to yield: the filling of unused lanes.
    pub fn unstressed() -> Self {
        let one = [1.0; LANES];
        let zero = [0.0; LANES];
        PointLanes {
            f: [one, zero, zero, one],
            f33: one,
            cp_inv: [one, zero, one, one],
            eps_p: zero,
            flow_stress: [Real::INFINITY; LANES],
            temperature: zero,
            elastic_prev: [one, zero, zero, zero],
            inv_dt: 0.0,
            guess: zero,
            plastic_work: zero,
        }
    }

    /// Loads one point into lane `l`.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // one index into several component-major arrays
    pub fn set(&mut self, l: usize, f: [Real; 4], f33: Real, state: &PointState, flow: Real) {
        for c in 0..4 {
            self.f[c][l] = f[c];
        }
        self.f33[l] = f33;
        self.set_history(l, state, flow);
    }

    /// Loads the history of one point into lane `l`.
    #[inline(always)]
    pub fn set_history(&mut self, l: usize, state: &PointState, flow: Real) {
        self.cp_inv[0][l] = state.cp_inv[0];
        self.cp_inv[1][l] = state.cp_inv[1];
        self.cp_inv[2][l] = state.cp_inv[2];
        self.cp_inv[3][l] = state.cp_inv[3];
        self.eps_p[l] = state.eps_p;
        self.flow_stress[l] = flow;
    }

    /// The history of lane `l`.
    #[inline(always)]
    pub fn state(&self, l: usize) -> PointState {
        PointState {
            cp_inv: [
                self.cp_inv[0][l],
                self.cp_inv[1][l],
                self.cp_inv[2][l],
                self.cp_inv[3][l],
            ],
            eps_p: self.eps_p[l],
        }
    }
}

/// What [`HenckyJ2::update_lanes`] returns, one [`StressUpdate`] per lane, component-major.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StressLanes {
    /// First Piola-Kirchhoff stress `[P_xX, P_xY, P_yX, P_yY, P_33]` (Pa).
    pub piola: [Lanes; 5],
    /// Kirchhoff stress `[tau_xx, tau_xy, tau_yy, tau_33]` (Pa).
    pub kirchhoff: [Lanes; 4],
    /// Jacobian `J = det F` (-).
    pub jacobian: Lanes,
    /// Mises equivalent of the Cauchy stress `q / J` (Pa).
    pub von_mises: Lanes,
    /// Stored elastic energy per reference volume (J/m^3).
    pub elastic_energy: Lanes,
    /// Elastic energy per reference volume that the change of temperature since the last
    /// update put in, at this update's trial strain (J/m^3): `W(eps, T) - W(eps, T_prev)`
    /// with the thermal strain of each; 0 without elasticity over temperature.
    pub thermoelastic: Lanes,
    /// `[E(T) / E, ln lambda_th(T)]` (-) of this update, for the next one's
    /// [`PointLanes::elastic_prev`] (set with elasticity over temperature only).
    pub elastic_now: [Lanes; 4],
}

/// The fields of a batch that do not depend on the dimension (those of [`PointLanes`]
/// bar the kinematics), borrowed for the steps the 2D and the 3D update share.
pub(super) struct Plastic<'a> {
    /// Equivalent plastic strain (-).
    pub eps_p: &'a mut Lanes,
    /// Flow stress `sigma_y(eps_p)` (Pa).
    pub flow_stress: &'a mut Lanes,
    /// Temperature (degrees C).
    pub temperature: &'a Lanes,
    /// The last update's `[E(T) / E, ln lambda_th(T), ln J, |e|^2]` (-).
    pub elastic_prev: &'a [Lanes; 4],
    /// `1 / dt` (1/s).
    pub inv_dt: Real,
    /// A first guess of each lane's `dgamma` (-).
    pub guess: &'a Lanes,
    /// Plastic work density of the update (J/m^3).
    pub plastic_work: &'a mut Lanes,
}

/// What the principal-axes steps of a lane need from its kinematics (step 1).
pub(super) struct Principal {
    /// The principal values `lambda_i^2` of the trial `b_e` (-).
    pub b: [Real; 3],
    /// `J = det F` (-).
    pub jac: Real,
    /// Whether the deformation is admissible: `F` finite and not inverted, every `lambda_i^2`
    /// positive and normal, finite.
    pub ok: bool,
}

/// The kinematics of a batch of points, all that differs between the 2D update
/// ([`PointLanes`]) and the 3D one ([`super::simo1992_hencky_j2_3d::PointLanes3`]): the trial
/// `b_e` and its principal values (step 1), and back from principal values to tensors:
/// `C_p^{-1}` (step 5), `P` and `tau` (step 6). [`HenckyJ2::update_batch`] does the rest,
/// once for both.
pub(super) trait Kinematics {
    /// What the kinematics keep of each lane from the trial to the stress, component-major.
    type Trial: Default;
    /// The stress tensors of a batch, `P` and `tau`, component-major.
    type Stress: Default;
    /// The fields that do not depend on the dimension.
    fn plastic(&mut self) -> Plastic<'_>;
    /// Step 1 for all lanes at once, before [`Kinematics::trial`] reads each lane: what is
    /// cheaper computed over the lanes together (3D: the spectral decomposition of `b_e`,
    /// whose square roots and divisions vectorise over the lanes); nothing by default.
    #[inline(always)]
    fn prepare(&self, _t: &mut Self::Trial) {}
    /// Step 1 for lane `l`: the principal values of the trial `b_e`; keeps in `t` what the
    /// other steps need.
    fn trial(&self, l: usize, t: &mut Self::Trial) -> Principal;
    /// Why lane `l`'s deformation gradient, of determinant `jac`, is not admissible
    /// (inverted or non-finite), if it is not: the message of its error.
    fn inverted(&self, l: usize, jac: Real) -> Option<String>;
    /// Step 5 for lane `l`: `C_p^{-1} = F^{-1} b_e F^{-T}` with `b_e = sum be_i n_i n_i^T`,
    /// stored if the lane `yields` (else the history is kept).
    fn flow(&mut self, l: usize, t: &Self::Trial, be: [Real; 3], yields: bool);
    /// Step 6 for lane `l`: `tau = sum tau_i n_i n_i^T` and `P = tau F^{-T}` from the
    /// principal Kirchhoff stresses `tau_i` (Pa).
    fn stress(t: &Self::Trial, l: usize, tau: [Real; 3], out: &mut Self::Stress);
    /// `x / J` for lane `l`.
    fn per_volume(t: &Self::Trial, l: usize, x: Real) -> Real;
}

/// What [`HenckyJ2::update_batch`] returns: the stress tensors of the kinematics and the
/// values that do not depend on the dimension, as [`StressLanes`] documents them.
#[derive(Default)]
pub(super) struct Update<S> {
    pub stress: S,
    pub jacobian: Lanes,
    pub von_mises: Lanes,
    pub elastic_energy: Lanes,
    pub thermoelastic: Lanes,
    pub elastic_now: [Lanes; 4],
}

/// Trial state of each lane (steps 1-3), kept for the return mapping and the stress.
#[derive(Default)]
struct Trial<K> {
    ok: [bool; LANES],
    jac: Lanes,
    /// What the kinematics keep.
    kin: K,
    /// Deviatoric logarithmic strains.
    e: [Lanes; 3],
    mean: Lanes,
    theta: Lanes,
    q_trial: Lanes,
    /// Eigenvalues of `b_e` (for the error message).
    b: [[Real; 3]; LANES],
}

/// What the 2D kinematics keep of each lane from the trial to the stress.
#[derive(Default)]
pub(super) struct PlaneTrial {
    inv_det2: Lanes,
    inv33: Lanes,
    /// `F^{-1}` as `[11, 12, 21, 22]`.
    inv: [Lanes; 4],
    /// Eigenprojector of the larger in-plane eigenvalue of `b_e`, `[11, 12, 22]`.
    proj: [Lanes; 3],
}

/// The 2D stress tensors of a batch.
#[derive(Default)]
pub(super) struct PlaneStress {
    piola: [Lanes; 5],
    kirchhoff: [Lanes; 4],
}

#[allow(clippy::needless_range_loop)] // component loops index several component-major arrays
impl Kinematics for PointLanes {
    type Trial = PlaneTrial;
    type Stress = PlaneStress;

    #[inline(always)]
    fn plastic(&mut self) -> Plastic<'_> {
        Plastic {
            eps_p: &mut self.eps_p,
            flow_stress: &mut self.flow_stress,
            temperature: &self.temperature,
            elastic_prev: &self.elastic_prev,
            inv_dt: self.inv_dt,
            guess: &self.guess,
            plastic_work: &mut self.plastic_work,
        }
    }

    /// `b_e` block diagonal: its in-plane block by [`sym_spectral2`], `b_33 = F_33^2 C_p^{-1}_33`.
    #[inline(always)]
    fn trial(&self, l: usize, t: &mut PlaneTrial) -> Principal {
        let f = [self.f[0][l], self.f[1][l], self.f[2][l], self.f[3][l]];
        let f33 = self.f33[l];
        let det2 = f[0] * f[3] - f[1] * f[2];
        let inv_det2 = 1.0 / det2;
        let inv33 = 1.0 / f33;
        // F^{-1} = [[F22, -F12], [-F21, F11]] / det2.
        let inv = [
            f[3] * inv_det2,
            -f[1] * inv_det2,
            -f[2] * inv_det2,
            f[0] * inv_det2,
        ];
        let [c11, c12, c22, c33] = [
            self.cp_inv[0][l],
            self.cp_inv[1][l],
            self.cp_inv[2][l],
            self.cp_inv[3][l],
        ];
        let [b11, b12, b22, b33] = elastic_left_cauchy_green(f, f33, [c11, c12, c22, c33]);
        let (l1, l2, proj) = sym_spectral2(b11, b12, b22);
        let jac = det2 * f33;
        t.inv_det2[l] = inv_det2;
        t.inv33[l] = inv33;
        for c in 0..4 {
            t.inv[c][l] = inv[c];
        }
        for c in 0..3 {
            t.proj[c][l] = proj[c];
        }
        Principal {
            b: [l1, l2, b33],
            jac,
            ok: jac > 0.0
                && f33 > 0.0
                && jac.is_finite()
                && l2 >= Real::MIN_POSITIVE
                && b33 >= Real::MIN_POSITIVE
                && b33.is_finite(),
        }
    }

    fn inverted(&self, l: usize, jac: Real) -> Option<String> {
        let f = [self.f[0][l], self.f[1][l], self.f[2][l], self.f[3][l]];
        let f33 = self.f33[l];
        (!(jac > 0.0 && f33 > 0.0 && jac.is_finite())).then(|| {
            format!("deformation gradient inverted or non-finite (det F = {jac:.3e}, F33 = {f33:.3e}, F = {f:?})")
        })
    }

    #[inline(always)]
    fn flow(&mut self, l: usize, t: &PlaneTrial, be: [Real; 3], yields: bool) {
        let [p11, p12, p22] = [t.proj[0][l], t.proj[1][l], t.proj[2][l]];
        let [i11, i12, i21, i22] = [t.inv[0][l], t.inv[1][l], t.inv[2][l], t.inv[3][l]];
        let n11 = be[0] * p11 + be[1] * p22;
        let n12 = (be[0] - be[1]) * p12;
        let n22 = be[0] * p22 + be[1] * p11;
        let a11 = i11 * n11 + i12 * n12;
        let a12 = i11 * n12 + i12 * n22;
        let a21 = i21 * n11 + i22 * n12;
        let a22 = i21 * n12 + i22 * n22;
        let cp = [
            a11 * i11 + a12 * i12,
            a11 * i21 + a12 * i22,
            a21 * i21 + a22 * i22,
            be[2] * t.inv33[l] * t.inv33[l],
        ];
        for c in 0..4 {
            self.cp_inv[c][l] = if yields { cp[c] } else { self.cp_inv[c][l] };
        }
    }

    #[inline(always)]
    fn stress(t: &PlaneTrial, l: usize, tau: [Real; 3], out: &mut PlaneStress) {
        let [tau1, tau2, tau33] = tau;
        let [p11, p12, p22] = [t.proj[0][l], t.proj[1][l], t.proj[2][l]];
        let [i11, i12, i21, i22] = [t.inv[0][l], t.inv[1][l], t.inv[2][l], t.inv[3][l]];
        let t11 = tau1 * p11 + tau2 * p22;
        let t12 = (tau1 - tau2) * p12;
        let t22 = tau1 * p22 + tau2 * p11;
        // P = tau F^{-T}, F^{-T} = (F^{-1})^T.
        let piola = [
            t11 * i11 + t12 * i12,
            t11 * i21 + t12 * i22,
            t12 * i11 + t22 * i12,
            t12 * i21 + t22 * i22,
            tau33 * t.inv33[l],
        ];
        for c in 0..5 {
            out.piola[c][l] = piola[c];
        }
        for (c, v) in [t11, t12, t22, tau33].into_iter().enumerate() {
            out.kirchhoff[c][l] = v;
        }
    }

    /// `x / det_2 / F_33`, as the reciprocals multiply.
    #[inline(always)]
    fn per_volume(t: &PlaneTrial, l: usize, x: Real) -> Real {
        x * t.inv_det2[l] * t.inv33[l]
    }
}

impl HenckyJ2 {
    /// From Young's modulus `E` (Pa) and Poisson's ratio `nu` (-).
    pub fn new(youngs: Real, poisson: Real, hardening: Hardening) -> Self {
        HenckyJ2 {
            bulk: youngs / (3.0 * (1.0 - 2.0 * poisson)),
            shear: youngs / (2.0 * (1.0 + poisson)),
            hardening,
            thermoelastic: None,
        }
    }

    /// Dilatational wave speed `c = sqrt((K + 4 G / 3) / rho)` (m/s), at the stiffest
    /// temperature of a modulus over temperature.
    pub fn wave_speed(&self, density: Real) -> Real {
        let factor = self
            .thermoelastic
            .as_ref()
            .map_or(1.0, Thermoelastic::modulus_factor_max);
        (factor * (self.bulk + 4.0 / 3.0 * self.shear) / density).sqrt()
    }

    /// `[E(T) / E, ln lambda_th(T)]` (-) of each lane at its temperature `temps` (degrees
    /// C): 1 and 0 without elasticity over temperature.
    #[inline(always)]
    fn elastic_lanes(&self, temps: &Lanes) -> [Lanes; 2] {
        match &self.thermoelastic {
            None => [[1.0; LANES], [0.0; LANES]],
            Some(te) => [
                temps.map(|t| te.modulus_factor_at(t)),
                temps.map(|t| te.log_strain(t)),
            ],
        }
    }

    /// Stress update for the deformation gradient `f = [F_xX, F_xY, F_yX, F_yY]` and the
    /// out-of-plane stretch `f33`. Updates `state` in place; an inverted or non-finite
    /// deformation is an error with a short reason. The point goes through
    /// [`HenckyJ2::update_lanes`] in lane 0, so it gets the bits of the solver's batches.
    pub fn update(
        &self,
        f: [Real; 4],
        f33: Real,
        state: &mut PointState,
    ) -> Result<StressUpdate, String> {
        let mut lanes = PointLanes::unstressed();
        lanes.set(0, f, f33, state, self.hardening.flow_stress(state.eps_p));
        let u = self.update_lanes(&mut lanes).map_err(|(_, m)| m)?;
        state.cp_inv = std::array::from_fn(|c| lanes.cp_inv[c][0]);
        state.eps_p = lanes.eps_p[0];
        Ok(StressUpdate {
            piola: u.piola.map(|x| x[0]),
            kirchhoff: u.kirchhoff.map(|x| x[0]),
            jacobian: u.jacobian[0],
            von_mises: u.von_mises[0],
            elastic_energy: u.elastic_energy[0],
        })
    }

    /// The update of [`LANES`] points at once, one per lane, with the current flow stress
    /// `sigma_y(eps_p)` (Pa) of each supplied by the caller (who caches it, so an elastic
    /// step never evaluates the hardening law). Branch-free per lane up to the return
    /// mapping, so the compiler can use SIMD; a lane's bits do not depend on the other lanes.
    /// Updates `p.cp_inv`, `p.eps_p` and `p.flow_stress` (the bits of
    /// `Hardening::flow_stress` at the new `eps_p`); on an inverted or non-finite deformation returns the
    /// first failing lane and the reason, with `p` unchanged.
    #[inline(always)]
    pub fn update_lanes(&self, p: &mut PointLanes) -> Result<StressLanes, (usize, String)> {
        let u = self.update_batch(p)?;
        Ok(StressLanes {
            piola: u.stress.piola,
            kirchhoff: u.stress.kirchhoff,
            jacobian: u.jacobian,
            von_mises: u.von_mises,
            elastic_energy: u.elastic_energy,
            thermoelastic: u.thermoelastic,
            elastic_now: u.elastic_now,
        })
    }

    /// Steps 1-6 of the module doc for a batch of either dimension: the kinematics `B` give
    /// the principal values of the trial `b_e` and turn principal values back into tensors;
    /// the logarithmic strains, the trial stress, the return map, the energy and the
    /// thermoelastic terms are the same in 2D and 3D. What [`HenckyJ2::update_lanes`]
    /// documents, for `B`'s tensors.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // lane loops index several component-major arrays
    pub(super) fn update_batch<B: Kinematics>(
        &self,
        p: &mut B,
    ) -> Result<Update<B::Stress>, (usize, String)> {
        let [factor, th] = self.elastic_lanes(p.plastic().temperature);
        let (k, g) = (
            factor.map(|f| f * self.bulk),
            factor.map(|f| f * self.shear),
        );
        let mut t = Trial::<B::Trial>::default();
        p.prepare(&mut t.kin);
        for l in 0..LANES {
            let Principal { b, jac, ok } = p.trial(l, &mut t.kin);
            let eps = [
                0.5 * lanes::ln(b[0]),
                0.5 * lanes::ln(b[1]),
                0.5 * lanes::ln(b[2]),
            ];
            let theta = eps[0] + eps[1] + eps[2];
            let mean = theta * (1.0 / 3.0);
            let e = [eps[0] - mean, eps[1] - mean, eps[2] - mean];
            let e2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
            t.ok[l] = ok;
            t.jac[l] = jac;
            for c in 0..3 {
                t.e[c][l] = e[c];
            }
            t.mean[l] = mean;
            // The elastic volumetric strain: the thermal stretch taken out.
            t.theta[l] = theta - 3.0 * th[l];
            t.q_trial[l] = SQRT_6 * g[l] * e2.sqrt();
            t.b[l] = b;
        }
        if let Some(l) = t.ok.iter().position(|ok| !ok) {
            let reason = p.inverted(l, t.jac[l]).unwrap_or_else(|| {
                let [l1, l2, l3] = t.b[l];
                format!(
                    "elastic stretch not positive (b_e eigenvalues {l1:.3e}, {l2:.3e}, {l3:.3e})"
                )
            });
            return Err((l, reason));
        }
        // Radial return (step 4), lanes that yield only.
        let mut scale = [1.0; LANES];
        let mut yields = [false; LANES];
        let mut plastic = p.plastic();
        for l in 0..LANES {
            yields[l] = t.q_trial[l] > plastic.flow_stress[l];
        }
        let thermal = self.hardening.is_thermal();
        if thermal {
            *plastic.plastic_work = [0.0; LANES];
        }
        if yields.iter().any(|&y| y) {
            let (dgamma, flow) = if thermal {
                self.return_map_rate(&t.q_trial, &g, &mut plastic, &yields)?
            } else {
                self.return_map(&t.q_trial, &g, plastic.eps_p, plastic.flow_stress, &yields)?
            };
            for l in 0..LANES {
                if yields[l] {
                    scale[l] = 1.0 - 3.0 * g[l] * dgamma[l] / t.q_trial[l];
                }
            }
            for l in 0..LANES {
                plastic.eps_p[l] += dgamma[l];
            }
            *plastic.flow_stress = flow;
            // b_e = sum exp(2 eps_i) n_i n_i^T, then C_p^{-1} = F^{-1} b_e F^{-T}.
            for l in 0..LANES {
                let (mean, sc) = (t.mean[l], scale[l]);
                let be = [
                    lanes::exp(2.0 * (mean + t.e[0][l] * sc)),
                    lanes::exp(2.0 * (mean + t.e[1][l] * sc)),
                    lanes::exp(2.0 * (mean + t.e[2][l] * sc)),
                ];
                p.flow(l, &t.kin, be, yields[l]);
            }
        }
        let mut out = Update::<B::Stress>::default();
        for l in 0..LANES {
            let e = [
                t.e[0][l] * scale[l],
                t.e[1][l] * scale[l],
                t.e[2][l] * scale[l],
            ];
            let (k, g) = (k[l], g[l]);
            let kt = k * t.theta[l];
            let tau = [
                kt + 2.0 * g * e[0],
                kt + 2.0 * g * e[1],
                kt + 2.0 * g * e[2],
            ];
            B::stress(&t.kin, l, tau, &mut out.stress);
            out.jacobian[l] = t.jac[l];
            out.von_mises[l] = B::per_volume(&t.kin, l, t.q_trial[l] * scale[l]);
            out.elastic_energy[l] =
                0.5 * kt * t.theta[l] + g * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        }
        if self.thermoelastic.is_some() {
            // int dW/dT dT over the step by the trapezoid rule in the strain: `W(eps, T) -
            // W(eps, T_prev)` at the last update's strain and at this one's trial strain,
            // averaged (second order: a first-order booking at the trial strain alone missed
            // a fifth of the energy of a die's first chill), with the modulus and the
            // thermal strain of each temperature.
            let [fp, thp, jp, e2p] = *p.plastic().elastic_prev;
            let w = |f: Real, th: Real, ln_j: Real, e2: Real| {
                let theta = ln_j - 3.0 * th;
                f * (0.5 * self.bulk * theta * theta + self.shear * e2)
            };
            let mut now = [[0.0; LANES]; 4];
            for l in 0..LANES {
                let e2 = t.e[0][l] * t.e[0][l] + t.e[1][l] * t.e[1][l] + t.e[2][l] * t.e[2][l];
                let ln_j = t.theta[l] + 3.0 * th[l];
                let at_trial = w(factor[l], th[l], ln_j, e2) - w(fp[l], thp[l], ln_j, e2);
                let at_last = w(factor[l], th[l], jp[l], e2p[l]) - w(fp[l], thp[l], jp[l], e2p[l]);
                out.thermoelastic[l] = 0.5 * (at_trial + at_last);
                now[0][l] = factor[l];
                now[1][l] = th[l];
                now[2][l] = ln_j;
                now[3][l] = e2 * scale[l] * scale[l];
            }
            out.elastic_now = now;
        }
        Ok(out)
    }

    /// Plastic multipliers `dgamma >= 0` of the lanes that yield, from
    /// `q_trial - 3 G dgamma - sigma_y(eps_p + dgamma) = 0` (0 in the other lanes), and the
    /// flow stress `sigma_y(eps_p + dgamma)` (Pa) in every lane: closed form for linear
    /// hardening; for the power law `sigma_y = K (eps0 + eps_p)^n`, Newton's method
    /// safeguarded by bisection in `[0, q_trial / 3G]`, all lanes iterating together and
    /// each frozen once its residual is below `1e-12 q_trial` (so a lane's result does not
    /// depend on the others), evaluating [`Hardening::flow_stress`] (one `ln` and one
    /// `exp` from [`lanes`]) and [`Hardening::slope_at`] per iterate, so the flow stress
    /// returned has the bits that function gives at the new `eps_p`. `sy` is the flow
    /// stress at `eps_p` (Pa). An error names the lane that did not converge in 50
    /// iterations.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // lane loops index several arrays
    fn return_map(
        &self,
        q_trial: &Lanes,
        shear: &Lanes,
        eps_p: &Lanes,
        sy: &Lanes,
        yields: &[bool; LANES],
    ) -> Result<(Lanes, Lanes), (usize, String)> {
        let g3 = shear.map(|g| 3.0 * g);
        let mut x = [0.0; LANES];
        let mut flow_at = *sy;
        match self.hardening {
            Hardening::Linear {
                yield_stress_pa,
                modulus_pa,
            } => {
                for l in 0..LANES {
                    if yields[l] {
                        x[l] = (q_trial[l] - sy[l]) / (g3[l] + modulus_pa);
                        flow_at[l] = yield_stress_pa + modulus_pa * (eps_p[l] + x[l]);
                    }
                }
                Ok((x, flow_at))
            }
            Hardening::Power { k_pa, eps0, n } => {
                // The residual is decreasing and concave in dgamma; Newton from below
                // converges monotonically. Bracket [0, q_trial / 3G] for safety. The law and
                // its slope written out as `Hardening::flow_stress` and `slope_at` write them
                // (the same bits), so the lane loop holds no call into the other laws.
                let flow_stress = |e: Real| k_pa * lanes::exp(n * lanes::ln(eps0 + e));
                let slope_at = |e: Real, flow: Real| n * flow / (eps0 + e);
                let (mut lo, mut hi) = ([0.0; LANES], [0.0; LANES]);
                let mut done = [true; LANES];
                for l in 0..LANES {
                    let slope = slope_at(eps_p[l], sy[l]);
                    hi[l] = q_trial[l] / g3[l];
                    // Lanes that do not yield keep x = 0 and never iterate.
                    if yields[l] {
                        x[l] = (q_trial[l] - sy[l]) / (g3[l] + slope);
                    }
                    done[l] = !yields[l];
                }
                for _ in 0..50 {
                    if done.iter().all(|&d| d) {
                        break;
                    }
                    for l in 0..LANES {
                        let eps = eps_p[l] + x[l];
                        let flow = flow_stress(eps);
                        let slope = slope_at(eps, flow);
                        let r = q_trial[l] - g3[l] * x[l] - flow;
                        let (lo_new, hi_new) = if r > 0.0 {
                            (x[l], hi[l])
                        } else {
                            (lo[l], x[l])
                        };
                        let next = x[l] - r / (-g3[l] - slope);
                        let x_new = if next > lo_new && next < hi_new {
                            next
                        } else {
                            0.5 * (lo_new + hi_new)
                        };
                        if !done[l] {
                            if r.abs() <= 1e-12 * q_trial[l] {
                                done[l] = true;
                                flow_at[l] = flow;
                            } else {
                                (lo[l], hi[l], x[l]) = (lo_new, hi_new, x_new);
                            }
                        }
                    }
                }
                match done.iter().position(|&d| !d) {
                    None => Ok((x, flow_at)),
                    Some(l) => Err((
                        l,
                        format!(
                            "return mapping did not converge (q_trial = {:.6e} Pa, eps_p = {:.6e})",
                            q_trial[l], eps_p[l]
                        ),
                    )),
                }
            }
            _ => Err((
                0,
                "a flow stress of rate and temperature takes the rate-consistent return map".into(),
            )),
        }
    }

    /// The rate-consistent return map of the laws of rate and temperature: in each lane
    /// that yields, `dgamma >= 0` with `q_trial - 3 G dgamma - sigma_y(eps_p + dgamma,
    /// dgamma / dt, T) = 0`, the flow stress at the plastic strain rate of the step itself
    /// (`dt` the step the strain increment was taken over, `p.inv_dt`; the temperature the
    /// lane's at the step's start), and that flow stress (Pa), by [`rate_consistent_root`],
    /// each lane alone (the laws call `powf`, `ln` and `exp` of the C library), from the
    /// lane's last increment. Sets each yielding lane's plastic work of the step,
    /// `p.plastic_work`, over the step's strain at its rate and temperature.
    /// An error names a lane that did not converge in 200 iterations.
    #[allow(clippy::needless_range_loop)] // lane loops index several arrays
    fn return_map_rate(
        &self,
        q_trial: &Lanes,
        shear: &Lanes,
        p: &mut Plastic<'_>,
        yields: &[bool; LANES],
    ) -> Result<(Lanes, Lanes), (usize, String)> {
        let mut x = [0.0; LANES];
        let mut flow_at = *p.flow_stress;
        for l in 0..LANES {
            if !yields[l] {
                continue;
            }
            let g3 = 3.0 * shear[l];
            let (q, eps, temp) = (q_trial[l], p.eps_p[l], p.temperature[l]);
            let law = self.hardening.isotherm(temp);
            // The last step's plastic strain over this step (the rate changes little from
            // step to step), else the perfectly plastic estimate, above the root for a
            // hardening material.
            let start = if p.guess[l] > 0.0 && p.guess[l] < q / g3 {
                p.guess[l]
            } else {
                (q - p.flow_stress[l]) / g3
            };
            let Some((xl, flow)) = rate_consistent_root(&law, q, g3, eps, p.inv_dt, start) else {
                return Err((
                    l,
                    format!(
                        "rate-consistent return mapping did not converge (q_trial = {q:.6e} Pa, \
                         eps_p = {eps:.6e}, T = {temp:.1} C)"
                    ),
                ));
            };
            flow_at[l] = flow;
            x[l] = xl;
            p.plastic_work[l] = law.work(eps, xl, xl * p.inv_dt, flow_at[l]);
        }
        Ok((x, flow_at))
    }
}

/// The plastic strain increment `dgamma` (in `[0, q / 3G]`) of the rate-consistent return
/// map, `q - 3 G dgamma - sigma_y(eps_p + dgamma, dgamma / dt) = 0` (`g3 = 3 G`, Pa;
/// `inv_dt = 1 / dt`, 1/s), and the flow stress there (Pa), from `start`; `None` after 200
/// iterations. Newton's method on `ln(dgamma)`, `ln sigma_y - ln(q - 3 G dgamma) = 0`,
/// nearly linear where the flow stress goes as a power of the rate (a plain Newton step
/// from a rate of almost nothing overshoots by orders of magnitude), kept inside the
/// bracket `[lo, hi]` the residual's signs give (positive at 0, `-sigma_y <= 0` at the top)
/// and replaced by a bisection of it (geometric once `lo > 0`) when it would leave the
/// bracket or when it is not half the step before the last (`rtsafe`'s rule, Press et al.,
/// *Numerical Recipes*, section 9.4): a law clamped to its rate range has a kink at the
/// range's end, across which Newton's steps ping-pong while the bracket shrinks by a percent
/// a pair (the hot hub with q4 at 0.115 s: 200 iterations did not converge). Converged at
/// `|r| <= 1e-12 q` or a bracket `hi - lo <= 1e-15 hi`.
fn rate_consistent_root(
    law: &Isotherm<'_>,
    q: Real,
    g3: Real,
    eps: Real,
    inv_dt: Real,
    start: Real,
) -> Option<(Real, Real)> {
    let (mut lo, mut hi) = (0.0, q / g3);
    let mut xl = start;
    let mut steps = [Real::INFINITY; 2];
    for _ in 0..200 {
        let f = law.flow(eps + xl, xl * inv_dt);
        let r = q - g3 * xl - f.stress;
        if r.abs() <= 1e-12 * q || hi - lo <= 1e-15 * hi {
            return Some((xl, f.stress));
        }
        if r > 0.0 {
            lo = xl;
        } else {
            hi = xl;
        }
        let slope = f.d_strain + f.d_rate * inv_dt;
        let room = q - g3 * xl;
        let next = if f.stress > 0.0 && room > 0.0 && xl > 0.0 {
            let g = lanes::ln(f.stress / room);
            let dg = xl * (slope / f.stress + g3 / room);
            xl * lanes::exp(-g / dg)
        } else {
            xl + r / (g3 + slope)
        };
        let next = if next > lo && next < hi && (next - xl).abs() <= 0.5 * steps[0] {
            next
        } else if lo > 0.0 {
            (lo * hi).sqrt()
        } else {
            0.5 * (lo + hi)
        };
        steps = [steps[1], (next - xl).abs()];
        xl = next;
    }
    None
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::thermal::properties::Expansion;

    pub(crate) fn copper() -> HenckyJ2 {
        HenckyJ2::new(
            117e9,
            0.35,
            Hardening::Linear {
                yield_stress_pa: 400e6,
                modulus_pa: 100e6,
            },
        )
    }

    pub(crate) fn aluminium() -> HenckyJ2 {
        HenckyJ2::new(
            71e9,
            0.3,
            Hardening::Power {
                k_pa: 576.79e6,
                eps0: 0.01658,
                n: 0.3593,
            },
        )
    }

    /// Drive uniaxial stress along y (axisymmetric: r and theta lateral, equal) to a
    /// logarithmic strain of 1.0 in many small increments, finding the lateral stretch so
    /// that the lateral stress vanishes, and compare with the analytic curve
    /// `tau = sigma_y(eps - tau / E)` (elastic: `tau = E eps`).
    fn uniaxial(m: HenckyJ2, youngs: Real) {
        let mut st = PointState::default();
        let mut lat = 1.0;
        let steps = 2000;
        let mut max_err: Real = 0.0;
        for s in 1..=steps {
            let eps = 1.0 * s as Real / steps as Real;
            let ly = eps.exp();
            // Secant iteration on the lateral stretch, each trial from the same old state.
            let eval = |lat: Real| {
                let mut trial = st;
                let u = m.update([lat, 0.0, 0.0, ly], lat, &mut trial).unwrap();
                (u.kirchhoff[0], u, trial)
            };
            let (mut x0, mut x1) = (lat, lat * (1.0 - 1e-6));
            let (mut r0, _, _) = eval(x0);
            for _ in 0..60 {
                let (r1, _, _) = eval(x1);
                if r1.abs() < 1e-3 || r1 == r0 {
                    break;
                }
                let x2 = x1 - r1 * (x1 - x0) / (r1 - r0);
                x0 = x1;
                r0 = r1;
                x1 = x2;
            }
            lat = x1;
            let (rlat, u, trial) = eval(lat);
            assert!(rlat.abs() < 1.0, "lateral stress {rlat}");
            st = trial;
            let tau = u.kirchhoff[2];
            // Analytic: elastic branch or tau = sigma_y(eps - tau/E), solved by bisection.
            let expected = if youngs * eps <= m.hardening.initial_yield() {
                youngs * eps
            } else {
                let (mut a, mut b) = (0.0, youngs * eps);
                for _ in 0..200 {
                    let c = 0.5 * (a + b);
                    if c - m.hardening.flow_stress(eps - c / youngs) > 0.0 {
                        b = c;
                    } else {
                        a = c;
                    }
                }
                0.5 * (a + b)
            };
            max_err = max_err.max((tau - expected).abs() / expected.abs());
            // Volume: J = exp(theta) with theta = tau_m / K; plastic flow isochoric.
            let theta = (tau / 3.0) / m.bulk;
            assert!((u.jacobian.ln() - theta).abs() < 1e-9, "J = {}", u.jacobian);
        }
        assert!(max_err < 1e-6, "max relative error {max_err}");
        assert!(
            (st.eps_p - (1.0 - 0.0)).abs() < 0.02,
            "eps_p = {}",
            st.eps_p
        );
    }

    #[test]
    fn uniaxial_curve_linear_hardening() {
        uniaxial(copper(), 117e9);
    }

    #[test]
    fn uniaxial_curve_power_law() {
        uniaxial(aluminium(), 71e9);
    }

    #[test]
    fn rigid_rotation_gives_no_stress() {
        let m = copper();
        let mut st = PointState::default();
        let a: Real = 0.7;
        let u = m
            .update([a.cos(), -a.sin(), a.sin(), a.cos()], 1.0, &mut st)
            .unwrap();
        for p in u.piola {
            assert!(p.abs() < 1e-3, "{:?}", u.piola);
        }
        assert_eq!(st, PointState::default());
    }

    #[test]
    fn stress_is_objective_under_superposed_rotation() {
        let m = copper();
        let f = [1.3, 0.2, -0.1, 0.8];
        let (mut s1, mut s2) = (PointState::default(), PointState::default());
        let u1 = m.update(f, 1.05, &mut s1).unwrap();
        let a: Real = 1.1;
        let (c, s) = (a.cos(), a.sin());
        let rf = [
            c * f[0] - s * f[2],
            c * f[1] - s * f[3],
            s * f[0] + c * f[2],
            s * f[1] + c * f[3],
        ];
        let u2 = m.update(rf, 1.05, &mut s2).unwrap();
        assert!((u1.von_mises - u2.von_mises).abs() < 1e-6 * u1.von_mises);
        assert!((s1.eps_p - s2.eps_p).abs() < 1e-12);
        // C_p^{-1} lives in the reference configuration: unchanged by the rotation.
        for k in 0..4 {
            assert!(
                (s1.cp_inv[k] - s2.cp_inv[k]).abs() < 1e-12,
                "{:?} {:?}",
                s1.cp_inv,
                s2.cp_inv
            );
        }
    }

    /// A lane's results do not depend on what the other lanes hold: each of a set of
    /// points, yielding or not, gets the same bits alone in lane 0 (through `update`) and
    /// in every lane of batches filled with the other points.
    #[test]
    fn lanes_are_independent() {
        // Linear hardening (closed-form return map) and the power law (Newton in lanes).
        lanes_are_independent_for(copper());
        lanes_are_independent_for(aluminium());
    }

    fn lanes_are_independent_for(m: HenckyJ2) {
        let plastic = PointState {
            cp_inv: [0.9, 0.05, 1.1, 1.02],
            eps_p: 0.3,
        };
        let cases: [([Real; 4], Real, PointState); 5] = [
            (
                [1.0001, 0.00002, -0.00001, 0.9998],
                1.00005,
                PointState::default(),
            ),
            ([1.2, 0.1, -0.05, 0.8], 1.1, PointState::default()),
            ([0.95, -0.3, 0.2, 1.3], 0.97, plastic),
            ([1.0, 0.0, 0.0, 1.0], 1.0, plastic),
            ([0.7, 0.0, 0.0, 1.6], 0.9, PointState::default()),
        ];
        let alone: Vec<_> = cases
            .iter()
            .map(|&(f, f33, st)| {
                let mut st = st;
                let u = m.update(f, f33, &mut st).unwrap();
                (u, st)
            })
            .collect();
        assert!(
            alone.iter().any(|(_, st)| st.eps_p > 0.3),
            "some case yields"
        );
        // An elastic step leaves the plastic strain exactly as it was.
        assert_eq!(alone[0].1.eps_p, 0.0);
        assert!(
            alone
                .iter()
                .any(|(u, _)| u.von_mises < m.hardening.initial_yield()),
            "some case is elastic"
        );
        for shift in 0..cases.len() {
            let mut p = PointLanes::unstressed();
            for l in 0..LANES {
                let (f, f33, st) = cases[(shift + l) % cases.len()];
                p.set(l, f, f33, &st, m.hardening.flow_stress(st.eps_p));
            }
            let u = m.update_lanes(&mut p).unwrap();
            for l in 0..LANES {
                let (want, want_st) = &alone[(shift + l) % cases.len()];
                assert_eq!(p.state(l), *want_st, "lane {l}, shift {shift}");
                let flow = m.hardening.flow_stress(want_st.eps_p);
                assert_eq!(p.flow_stress[l].to_bits(), flow.to_bits(), "lane {l}");
                for c in 0..5 {
                    assert_eq!(u.piola[c][l].to_bits(), want.piola[c].to_bits());
                }
                assert_eq!(u.von_mises[l].to_bits(), want.von_mises.to_bits());
                assert_eq!(u.elastic_energy[l].to_bits(), want.elastic_energy.to_bits());
            }
        }
    }

    /// A Johnson-Cook law (OFHC copper, Johnson and Cook 1983, Table 1) with a modulus and
    /// a thermal expansion over temperature: the rate-consistent return map and the
    /// thermoelastic terms.
    pub(crate) fn hot_copper() -> HenckyJ2 {
        let mut m = HenckyJ2::new(
            117e9,
            0.35,
            Hardening::JohnsonCook {
                a_pa: 90e6,
                b_pa: 292e6,
                n: 0.31,
                c: 0.025,
                reference_strain_rate_per_s: 1.0,
                m: 1.09,
                reference_temperature_c: 20.0,
                melting_temperature_c: 1356.0 - 273.15,
            },
        );
        m.thermoelastic = Some(Thermoelastic {
            modulus_factor: vec![[20.0, 1.0], [800.0, 0.6]],
            expansion: Expansion::Coefficient {
                per_k: 17e-6,
                from_c: 20.0,
            },
        });
        m
    }

    /// A digest (FNV-1a over the bits) of every output and history of batches of the 2D
    /// update: eight points, yielding and elastic, over six steps of a history (loading, unloading), for the
    /// linear, power and Johnson-Cook laws (the last with elasticity over temperature).
    #[allow(clippy::needless_range_loop)] // lane loops index several component-major arrays
    fn plane_digest() -> u64 {
        let mut h: u64 = 0xCBF2_9CE4_8422_2325;
        let mut eat = |x: Real| {
            for b in x.to_bits().to_le_bytes() {
                h = (h ^ b as u64).wrapping_mul(0x0100_0000_01B3);
            }
        };
        for m in [copper(), aluminium(), hot_copper()] {
            let (mut elastic, mut plastic, mut heated) = (0, 0, 0);
            let mut p = PointLanes::unstressed();
            for l in 0..LANES {
                p.set_history(l, &PointState::default(), m.hardening.flow_stress(0.0));
                p.temperature[l] = 20.0 + 60.0 * l as Real;
                p.elastic_prev[1][l] = 1e-4 * l as Real;
            }
            p.inv_dt = 1e5;
            // Loading, then unloading a little (elastic steps for every law).
            for s in [0.1, 1.0, 2.0, 3.0, 2.95, 2.9] {
                for l in 0..LANES {
                    let a = 0.01 * s * (l as Real + 1.0) / LANES as Real;
                    let (c, sn) = ((0.3 * l as Real).cos(), (0.3 * l as Real).sin());
                    let u = [1.0 + a, 0.4 * a, -0.1 * a, 1.0 - 0.6 * a];
                    // F = R U: a rotation of each lane times a stretch and shear.
                    p.f[0][l] = c * u[0] - sn * u[2];
                    p.f[1][l] = c * u[1] - sn * u[3];
                    p.f[2][l] = sn * u[0] + c * u[2];
                    p.f[3][l] = sn * u[1] + c * u[3];
                    p.f33[l] = 1.0 + 0.3 * a;
                    p.temperature[l] += 5.0;
                }
                let before = p.eps_p;
                let u = m.update_lanes(&mut p).unwrap();
                p.elastic_prev = u.elastic_now;
                for l in 0..LANES {
                    if p.eps_p[l] > before[l] {
                        plastic += 1;
                    } else {
                        elastic += 1;
                    }
                    heated += (u.thermoelastic[l] != 0.0) as usize;
                    p.guess[l] = 0.5 * p.eps_p[l].min(1e-3);
                    for c in 0..5 {
                        eat(u.piola[c][l]);
                    }
                    for c in 0..4 {
                        eat(u.kirchhoff[c][l]);
                        eat(u.elastic_now[c][l]);
                        eat(p.cp_inv[c][l]);
                    }
                    eat(u.jacobian[l]);
                    eat(u.von_mises[l]);
                    eat(u.elastic_energy[l]);
                    eat(u.thermoelastic[l]);
                    eat(p.eps_p[l]);
                    eat(p.flow_stress[l]);
                    eat(p.plastic_work[l]);
                }
            }
            assert!(
                elastic > 0 && plastic > 0,
                "{elastic} elastic, {plastic} plastic"
            );
            assert_eq!(heated > 0, m.thermoelastic.is_some());
        }
        h
    }

    /// The 2D update gives the bits it gave before the 3D update shared its steps (the
    /// digest of commit d62fe70's code, 7_139_988_511_618_323_398, until session 56's
    /// safeguard in [`rate_consistent_root`] changed the rate laws' iterates at round-off).
    #[test]
    fn plane_update_keeps_its_bits() {
        assert_eq!(plane_digest(), 6_639_902_864_249_278_799);
    }

    /// The hot hub's AA6063 (Sellars-Tegart held below 0.01/s) at 481 C, a point whose
    /// trial stress lies 745 Pa over the held flow stress at a step of 0.34 us: the root sits
    /// just past the rate range's end, a kink across which Newton's steps ping-ponged for
    /// 200 iterations (q4's hot hub stopped at 0.115 s). It converges now, to the root.
    #[test]
    fn the_rate_consistent_root_crosses_a_held_rate_range() {
        let aa6063 = Hardening::SellarsTegart {
            alpha_per_pa: 0.040e-6,
            n: 5.385,
            activation_energy_j_per_mol: 141.55e3,
            a_per_s: 5.91e9,
            strain_rate_range_per_s: [0.01, 100.0],
            temperature_range_c: [350.0, 550.0],
        };
        let law = aa6063.isotherm(481.22043492661476);
        let (q, g3, eps, inv_dt) = (
            1.0458261990420613e7,
            5.6390977443609024e10,
            1.2797753036483048e-2,
            2.946464533610687e6,
        );
        let (x, flow) = rate_consistent_root(&law, q, g3, eps, inv_dt, 1.4848010789630763e-9)
            .expect("converges");
        assert!(x * inv_dt > 0.01, "past the range's end: {}", x * inv_dt);
        assert!((q - g3 * x - flow).abs() <= 1e-9 * q, "{x:e} {flow:e}");
        assert_eq!(flow, law.flow(eps + x, x * inv_dt).stress);
    }

    #[test]
    fn inverted_element_is_an_error() {
        let m = copper();
        let mut st = PointState::default();
        assert!(m.update([-1.0, 0.0, 0.0, 1.0], 1.0, &mut st).is_err());
        assert!(m.update([f64::NAN, 0.0, 0.0, 1.0], 1.0, &mut st).is_err());
        // A failing lane is named and the batch's history is left as it was.
        let mut p = PointLanes::unstressed();
        p.set(2, [1.0, 2.0, 2.0, 1.0], 1.0, &st, 400e6);
        let before = p;
        let (lane, reason) = m.update_lanes(&mut p).unwrap_err();
        assert_eq!(lane, 2);
        assert!(reason.contains("inverted"), "{reason}");
        assert_eq!(p, before);
    }
}
