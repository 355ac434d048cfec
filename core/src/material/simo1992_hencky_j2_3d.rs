//! The 3D kinematics of the Hencky J2 update (Simo 1992, CMAME 99, Box 1; the model and its
//! steps in [`super::simo1992_hencky_j2`]): a full deformation gradient `F` (9 components)
//! and a full symmetric `C_p^{-1}` (6), where the 2D update has an in-plane block and an
//! out-of-plane stretch. The principal-axes steps (logarithmic strains, trial Kirchhoff
//! stress, radial return with the same return maps, energy, thermoelastic terms) are
//! `HenckyJ2::update_batch`, shared with 2D; only these differ:
//!
//! - step 1: `b_e = F C_p^{-1} F^T` (-), symmetric, its principal values `lambda_i^2` and
//!   directions `n_i` by [`crate::math::sym_spectral3`] (cyclic Jacobi: exact for a
//!   diagonal `b_e`, as at the undeformed state or along the axes of a uniaxial state, and
//!   accurate for nearly repeated `lambda_i`);
//! - step 5: after the return, `b_e = sum exp(2 eps_i) n_i n_i^T` and
//!   `C_p^{-1} = F^{-1} b_e F^{-T}` (-), `F^{-1} = adj F / det F`;
//! - step 6: Kirchhoff `tau = sum tau_i n_i n_i^T` (Pa) and first Piola-Kirchhoff
//!   `P = tau F^{-T}` (Pa), the Mises stress of the Cauchy stress `q / J` (Pa), `J = det F`.
//!
//! Symmetric tensors are stored as `[11, 22, 33, 12, 23, 13]`, full ones row-major
//! `[11, 12, 13, 21, 22, 23, 31, 32, 33]` (`P_iJ`: `i` the spatial, `J` the material index).

use super::simo1992_hencky_j2::{HenckyJ2, Kinematics, Plastic, Principal};
use crate::lanes::{Lanes, LANES};
use crate::math::{sym_spectral3_lanes, Real};
use serde::{Deserialize, Serialize};

/// Trial elastic left Cauchy-Green tensor `b_e = F C_p^{-1} F^T` (-) as `[11, 22, 33, 12,
/// 23, 13]`, for `f` row-major and `cp_inv = C_p^{-1}` as `[11, 22, 33, 12, 23, 13]`.
#[inline(always)]
pub fn elastic_left_cauchy_green3(f: [Real; 9], cp_inv: [Real; 6]) -> [Real; 6] {
    let [c11, c22, c33, c12, c23, c13] = cp_inv;
    let c = [[c11, c12, c13], [c12, c22, c23], [c13, c23, c33]];
    let fc: [[Real; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            f[3 * i] * c[0][j] + f[3 * i + 1] * c[1][j] + f[3 * i + 2] * c[2][j]
        })
    });
    let b = |i: usize, j: usize| {
        fc[i][0] * f[3 * j] + fc[i][1] * f[3 * j + 1] + fc[i][2] * f[3 * j + 2]
    };
    [b(0, 0), b(1, 1), b(2, 2), b(0, 1), b(1, 2), b(0, 2)]
}

/// `sum_k w_k v_ik v_jk` as `[11, 22, 33, 12, 23, 13]`: the symmetric tensor of principal
/// values `w` on the directions `v` (columns).
#[inline(always)]
fn from_principal(w: [Real; 3], v: &[[Real; 3]; 3]) -> [Real; 6] {
    let s = |i: usize, j: usize| {
        w[0] * v[i][0] * v[j][0] + w[1] * v[i][1] * v[j][1] + w[2] * v[i][2] * v[j][2]
    };
    [s(0, 0), s(1, 1), s(2, 2), s(0, 1), s(1, 2), s(0, 2)]
}

/// `[11, 22, 33, 12, 23, 13]` as a full 3x3 matrix.
#[inline(always)]
fn full(s: [Real; 6]) -> [[Real; 3]; 3] {
    let [s11, s22, s33, s12, s23, s13] = s;
    [[s11, s12, s13], [s12, s22, s23], [s13, s23, s33]]
}

/// History variables of one 3D integration point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PointState3 {
    /// `C_p^{-1}` components `[11, 22, 33, 12, 23, 13]` (-), identity at the start.
    pub cp_inv: [Real; 6],
    /// Equivalent plastic strain (-).
    pub eps_p: Real,
}

impl Default for PointState3 {
    fn default() -> Self {
        PointState3 {
            cp_inv: [1.0, 1.0, 1.0, 0.0, 0.0, 0.0],
            eps_p: 0.0,
        }
    }
}

/// What the 3D stress update returns for one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StressUpdate3 {
    /// First Piola-Kirchhoff stress, row-major `[P_xX, P_xY, P_xZ, P_yX, .., P_zZ]` (Pa).
    pub piola: [Real; 9],
    /// Kirchhoff stress `[tau_xx, tau_yy, tau_zz, tau_xy, tau_yz, tau_xz]` (Pa).
    pub kirchhoff: [Real; 6],
    /// Jacobian `J = det F` (-).
    pub jacobian: Real,
    /// Mises equivalent of the Cauchy stress `q / J` (Pa).
    pub von_mises: Real,
    /// Stored elastic energy per reference volume `K theta^2 / 2 + G |e|^2` (J/m^3).
    pub elastic_energy: Real,
}

/// Inputs and history of [`LANES`] 3D points, component-major (`f[c][lane]`); the fields
/// other than `f` and `cp_inv` are those of [`super::PointLanes`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLanes3 {
    /// `F` row-major `[F_xX, F_xY, F_xZ, F_yX, .., F_zZ]` (-).
    pub f: [Lanes; 9],
    /// `C_p^{-1}` components `[11, 22, 33, 12, 23, 13]` (-).
    pub cp_inv: [Lanes; 6],
    /// Equivalent plastic strain (-).
    pub eps_p: Lanes,
    /// Flow stress `sigma_y(eps_p)` (Pa): the yield test's, at the law's least rate.
    pub flow_stress: Lanes,
    /// Temperature (degrees C), as [`super::PointLanes::temperature`].
    pub temperature: Lanes,
    /// The last update's `[E(T) / E, ln lambda_th(T), ln J, |e|^2]` (-), as
    /// [`super::PointLanes::elastic_prev`].
    pub elastic_prev: [Lanes; 4],
    /// `1 / dt` (1/s) of the step, as [`super::PointLanes::inv_dt`].
    pub inv_dt: Real,
    /// A first guess of each lane's `dgamma` (-), as [`super::PointLanes::guess`].
    pub guess: Lanes,
    /// Plastic work density of the last update (J/m^3), as
    /// [`super::PointLanes::plastic_work`].
    pub plastic_work: Lanes,
}

impl PointLanes3 {
    /// Every lane undeformed and unable to yield: the filling of unused lanes.
    pub fn unstressed() -> Self {
        let one = [1.0; LANES];
        let zero = [0.0; LANES];
        PointLanes3 {
            f: [one, zero, zero, zero, one, zero, zero, zero, one],
            cp_inv: [one, one, one, zero, zero, zero],
            eps_p: zero,
            flow_stress: [Real::INFINITY; LANES],
            temperature: zero,
            elastic_prev: [one, zero, zero, zero],
            inv_dt: 0.0,
            guess: zero,
            plastic_work: zero,
        }
    }

    /// Loads one point into lane `l`: `f` row-major, its history and flow stress (Pa).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // one index into several component-major arrays
    pub fn set(&mut self, l: usize, f: [Real; 9], state: &PointState3, flow: Real) {
        for c in 0..9 {
            self.f[c][l] = f[c];
        }
        self.set_history(l, state, flow);
    }

    /// Loads the history of one point into lane `l`.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // one index into several component-major arrays
    pub fn set_history(&mut self, l: usize, state: &PointState3, flow: Real) {
        for c in 0..6 {
            self.cp_inv[c][l] = state.cp_inv[c];
        }
        self.eps_p[l] = state.eps_p;
        self.flow_stress[l] = flow;
    }

    /// The history of lane `l`.
    #[inline(always)]
    pub fn state(&self, l: usize) -> PointState3 {
        PointState3 {
            cp_inv: std::array::from_fn(|c| self.cp_inv[c][l]),
            eps_p: self.eps_p[l],
        }
    }
}

/// What [`HenckyJ2::update_lanes3`] returns, one [`StressUpdate3`] per lane,
/// component-major; the fields other than `piola` and `kirchhoff` are those of
/// [`super::StressLanes`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StressLanes3 {
    /// First Piola-Kirchhoff stress, row-major (Pa).
    pub piola: [Lanes; 9],
    /// Kirchhoff stress `[tau_xx, tau_yy, tau_zz, tau_xy, tau_yz, tau_xz]` (Pa).
    pub kirchhoff: [Lanes; 6],
    /// Jacobian `J = det F` (-).
    pub jacobian: Lanes,
    /// Mises equivalent of the Cauchy stress `q / J` (Pa).
    pub von_mises: Lanes,
    /// Stored elastic energy per reference volume (J/m^3).
    pub elastic_energy: Lanes,
    /// Elastic energy per reference volume that the change of temperature put in (J/m^3),
    /// as [`super::StressLanes::thermoelastic`].
    pub thermoelastic: Lanes,
    /// `[E(T) / E, ln lambda_th(T), ln J, |e|^2]` (-) of this update, for the next one's
    /// [`PointLanes3::elastic_prev`] (set with elasticity over temperature only).
    pub elastic_now: [Lanes; 4],
}

/// What the 3D kinematics keep of each lane from the trial to the stress.
#[derive(Default)]
pub(super) struct SolidTrial {
    /// `det F`.
    jac: Lanes,
    /// Principal values of `b_e`.
    b: [Lanes; 3],
    /// `1 / det F`.
    inv_det: Lanes,
    /// `F^{-1}` row-major.
    inv: [Lanes; 9],
    /// Principal directions of `b_e`, row-major, column `k` the direction `n_k`.
    dir: [Lanes; 9],
}

/// The 3D stress tensors of a batch.
#[derive(Default)]
pub(super) struct SolidStress {
    piola: [Lanes; 9],
    kirchhoff: [Lanes; 6],
}

impl SolidTrial {
    /// `F^{-1}` of lane `l`, by rows.
    #[inline(always)]
    fn inv(&self, l: usize) -> [[Real; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| self.inv[3 * i + j][l]))
    }

    /// The principal directions of lane `l`, column `k` the direction `n_k`.
    #[inline(always)]
    fn dir(&self, l: usize) -> [[Real; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| self.dir[3 * i + j][l]))
    }
}

#[allow(clippy::needless_range_loop)] // component loops index several component-major arrays
impl Kinematics for PointLanes3 {
    type Trial = SolidTrial;
    type Stress = SolidStress;

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

    /// `b_e` by [`elastic_left_cauchy_green3`] and `F^{-1} = adj F / det F` (`det F` by the
    /// first row's cofactors) lane by lane, then the principal values and directions of
    /// every lane's `b_e` at once by [`sym_spectral3_lanes`].
    #[inline(always)]
    fn prepare(&self, t: &mut SolidTrial) {
        let mut be = [[0.0; LANES]; 6];
        for l in 0..LANES {
            let f: [Real; 9] = std::array::from_fn(|c| self.f[c][l]);
            let cp: [Real; 6] = std::array::from_fn(|c| self.cp_inv[c][l]);
            // adj F, row-major: (adj F)_ij is the cofactor of F_ji.
            let adj = [
                f[4] * f[8] - f[5] * f[7],
                f[2] * f[7] - f[1] * f[8],
                f[1] * f[5] - f[2] * f[4],
                f[5] * f[6] - f[3] * f[8],
                f[0] * f[8] - f[2] * f[6],
                f[2] * f[3] - f[0] * f[5],
                f[3] * f[7] - f[4] * f[6],
                f[1] * f[6] - f[0] * f[7],
                f[0] * f[4] - f[1] * f[3],
            ];
            let jac = f[0] * adj[0] + f[1] * adj[3] + f[2] * adj[6];
            let inv_det = 1.0 / jac;
            t.jac[l] = jac;
            t.inv_det[l] = inv_det;
            for c in 0..9 {
                t.inv[c][l] = adj[c] * inv_det;
            }
            for (c, b) in elastic_left_cauchy_green3(f, cp).into_iter().enumerate() {
                be[c][l] = b;
            }
        }
        let (b, dir) = sym_spectral3_lanes(be);
        t.b = b;
        for c in 0..9 {
            t.dir[c] = dir[c / 3][c % 3];
        }
    }

    /// Lane `l` of what [`Kinematics::prepare`] found: `b_e`'s principal values, `det F`,
    /// and whether both are admissible.
    #[inline(always)]
    fn trial(&self, l: usize, t: &mut SolidTrial) -> Principal {
        let (b, jac) = ([t.b[0][l], t.b[1][l], t.b[2][l]], t.jac[l]);
        let positive = |x: Real| x >= Real::MIN_POSITIVE && x.is_finite();
        Principal {
            b,
            jac,
            ok: jac > 0.0 && jac.is_finite() && positive(b[0]) && positive(b[1]) && positive(b[2]),
        }
    }

    fn inverted(&self, l: usize, jac: Real) -> Option<String> {
        let f: [Real; 9] = std::array::from_fn(|c| self.f[c][l]);
        (!(jac > 0.0 && jac.is_finite())).then(|| {
            format!("deformation gradient inverted or non-finite (det F = {jac:.3e}, F = {f:?})")
        })
    }

    #[inline(always)]
    fn flow(&mut self, l: usize, t: &SolidTrial, be: [Real; 3], yields: bool) {
        let n = full(from_principal(be, &t.dir(l)));
        let inv = t.inv(l);
        // A = F^{-1} b_e, C_p^{-1} = A F^{-T}.
        let a: [[Real; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| inv[i][0] * n[0][j] + inv[i][1] * n[1][j] + inv[i][2] * n[2][j])
        });
        let cp =
            |i: usize, j: usize| a[i][0] * inv[j][0] + a[i][1] * inv[j][1] + a[i][2] * inv[j][2];
        let cp = [cp(0, 0), cp(1, 1), cp(2, 2), cp(0, 1), cp(1, 2), cp(0, 2)];
        for c in 0..6 {
            self.cp_inv[c][l] = if yields { cp[c] } else { self.cp_inv[c][l] };
        }
    }

    #[inline(always)]
    fn stress(t: &SolidTrial, l: usize, tau: [Real; 3], out: &mut SolidStress) {
        let kirchhoff = from_principal(tau, &t.dir(l));
        let s = full(kirchhoff);
        let inv = t.inv(l);
        // P_iJ = tau_ik (F^{-T})_kJ = tau_ik (F^{-1})_Jk.
        for i in 0..3 {
            for j in 0..3 {
                out.piola[3 * i + j][l] =
                    s[i][0] * inv[j][0] + s[i][1] * inv[j][1] + s[i][2] * inv[j][2];
            }
        }
        for c in 0..6 {
            out.kirchhoff[c][l] = kirchhoff[c];
        }
    }

    #[inline(always)]
    fn per_volume(t: &SolidTrial, l: usize, x: Real) -> Real {
        x * t.inv_det[l]
    }
}

impl HenckyJ2 {
    /// Stress update for the 3D deformation gradient `f` (row-major). Updates `state` in
    /// place; an inverted or non-finite deformation is an error with a short reason. The
    /// point goes through [`HenckyJ2::update_lanes3`] in lane 0.
    pub fn update3(&self, f: [Real; 9], state: &mut PointState3) -> Result<StressUpdate3, String> {
        let mut lanes = PointLanes3::unstressed();
        lanes.set(0, f, state, self.hardening.flow_stress(state.eps_p));
        let u = self.update_lanes3(&mut lanes).map_err(|(_, m)| m)?;
        *state = lanes.state(0);
        Ok(StressUpdate3 {
            piola: u.piola.map(|x| x[0]),
            kirchhoff: u.kirchhoff.map(|x| x[0]),
            jacobian: u.jacobian[0],
            von_mises: u.von_mises[0],
            elastic_energy: u.elastic_energy[0],
        })
    }

    /// The 3D update of [`LANES`] points at once, one per lane: what
    /// [`HenckyJ2::update_lanes`] does in 2D, with the 3D kinematics of the module doc.
    /// Updates `p.cp_inv`, `p.eps_p`, `p.flow_stress` (and `p.plastic_work` for the laws of
    /// rate and temperature); on an inverted or non-finite deformation returns the first
    /// failing lane and the reason, with `p` unchanged.
    #[inline(always)]
    pub fn update_lanes3(&self, p: &mut PointLanes3) -> Result<StressLanes3, (usize, String)> {
        let u = self.update_batch(p)?;
        Ok(StressLanes3 {
            piola: u.stress.piola,
            kirchhoff: u.stress.kirchhoff,
            jacobian: u.jacobian,
            von_mises: u.von_mises,
            elastic_energy: u.elastic_energy,
            thermoelastic: u.thermoelastic,
            elastic_now: u.elastic_now,
        })
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // lane and component loops index several arrays
mod tests {
    use super::*;
    use crate::material::simo1992_hencky_j2::tests::{aluminium, copper, hot_copper};
    use crate::material::{PointLanes, PointState};

    /// `[F_xX, F_xY, F_yX, F_yY]` and `F_33` as a 3D `F`, row-major.
    fn embed(f: [Real; 4], f33: Real) -> [Real; 9] {
        [f[0], f[1], 0.0, f[2], f[3], 0.0, 0.0, 0.0, f33]
    }

    /// `a b`, 3x3 row-major.
    fn mul(a: [Real; 9], b: [Real; 9]) -> [Real; 9] {
        std::array::from_fn(|c| {
            let (i, j) = (c / 3, c % 3);
            (0..3).map(|k| a[3 * i + k] * b[3 * k + j]).sum()
        })
    }

    fn transpose(a: [Real; 9]) -> [Real; 9] {
        std::array::from_fn(|c| a[3 * (c % 3) + c / 3])
    }

    fn det(a: [Real; 9]) -> Real {
        a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6])
            + a[2] * (a[3] * a[7] - a[4] * a[6])
    }

    /// A rotation from a quaternion `(w, x, y, z)`, row-major.
    fn rotation(q: [Real; 4]) -> [Real; 9] {
        crate::math::rotation(q)
            .as_flattened()
            .try_into()
            .expect("3 x 3")
    }

    /// Mises stress `sqrt(3/2 s:s)` (Pa) of a Kirchhoff stress `[11, 22, 33, 12, 23, 13]`.
    fn mises(t: [Real; 6]) -> Real {
        let m = (t[0] + t[1] + t[2]) / 3.0;
        let s2 = (t[0] - m).powi(2)
            + (t[1] - m).powi(2)
            + (t[2] - m).powi(2)
            + 2.0 * (t[3] * t[3] + t[4] * t[4] + t[5] * t[5]);
        (1.5 * s2).sqrt()
    }

    /// The largest relative differences between the 2D and the 3D update of the same plane
    /// or axisymmetric state, per quantity.
    #[derive(Default, Debug)]
    struct Agreement {
        stress: Real,
        cp_inv: Real,
        jacobian: Real,
        eps_p: Real,
        energy: Real,
        thermal: Real,
        /// The Kirchhoff stress's difference as a strain, `|d tau| / 2G`, in ulps of 1:
        /// the principal stretches' round-off, which the relative differences above
        /// divide by the elastic strain (1e-4 to 1e-2 here).
        strain_ulps: Real,
    }

    /// `|a - b| / scale`, kept as the worst in `worst`.
    fn differ(worst: &mut Real, a: Real, b: Real, scale: Real) {
        *worst = worst.max((a - b).abs() / scale);
    }

    /// Eight lanes, four in plane strain (`F_33 = 1`) and four axisymmetric (`F_33` a hoop
    /// stretch), each a rotation of a stretch and in-plane shear, loaded over eight steps
    /// (elastic, then yielding) and unloaded over two, through the 2D and the 3D update
    /// from the same history; the laws of rate and temperature at rising temperatures with
    /// elasticity over temperature.
    fn agreement(m: &HenckyJ2) -> Agreement {
        let mut worst = Agreement::default();
        let mut p2 = PointLanes::unstressed();
        let mut p3 = PointLanes3::unstressed();
        for l in 0..LANES {
            let flow = m.hardening.flow_stress(0.0);
            p2.set_history(l, &PointState::default(), flow);
            p3.set_history(l, &PointState3::default(), flow);
        }
        p2.inv_dt = 1e4;
        p3.inv_dt = 1e4;
        let (mut elastic, mut plastic) = (0, 0);
        for s in [0.05, 0.1, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 2.95, 2.9] {
            for l in 0..LANES {
                let a = 0.01 * s * (l as Real + 1.0) / LANES as Real;
                let (c, sn) = ((0.4 * l as Real).cos(), (0.4 * l as Real).sin());
                let u = [1.0 - 0.7 * a, 0.3 * a, -0.2 * a, 1.0 + a];
                let f = [
                    c * u[0] - sn * u[2],
                    c * u[1] - sn * u[3],
                    sn * u[0] + c * u[2],
                    sn * u[1] + c * u[3],
                ];
                let f33 = if l < 4 { 1.0 } else { 1.0 - 0.5 * a };
                for k in 0..4 {
                    p2.f[k][l] = f[k];
                }
                p2.f33[l] = f33;
                let f3 = embed(f, f33);
                for k in 0..9 {
                    p3.f[k][l] = f3[k];
                }
                p2.temperature[l] = 20.0 + 40.0 * s + 10.0 * l as Real;
                p3.temperature[l] = p2.temperature[l];
            }
            let before = p2.eps_p;
            let u2 = m.update_lanes(&mut p2).unwrap();
            let u3 = m.update_lanes3(&mut p3).unwrap();
            for l in 0..LANES {
                if p2.eps_p[l] > before[l] {
                    plastic += 1;
                } else {
                    elastic += 1;
                }
                let tau = u2
                    .kirchhoff
                    .iter()
                    .fold(0.0, |x: Real, t| x.max(t[l].abs()));
                for (c2, c3) in [(0, 0), (1, 1), (2, 3), (3, 4), (4, 8)] {
                    differ(&mut worst.stress, u2.piola[c2][l], u3.piola[c3][l], tau);
                }
                for c3 in [2, 5, 6, 7] {
                    assert_eq!(u3.piola[c3][l], 0.0, "P[{c3}] lane {l}");
                }
                for (c2, c3) in [(0, 0), (1, 3), (2, 1), (3, 2)] {
                    let (t2, t3) = (u2.kirchhoff[c2][l], u3.kirchhoff[c3][l]);
                    differ(&mut worst.stress, t2, t3, tau);
                    differ(
                        &mut worst.strain_ulps,
                        t2,
                        t3,
                        2.0 * m.shear * Real::EPSILON,
                    );
                    differ(&mut worst.cp_inv, p2.cp_inv[c2][l], p3.cp_inv[c3][l], 1.0);
                }
                assert_eq!([u3.kirchhoff[4][l], u3.kirchhoff[5][l]], [0.0; 2]);
                assert_eq!([p3.cp_inv[4][l], p3.cp_inv[5][l]], [0.0; 2]);
                differ(&mut worst.stress, u2.von_mises[l], u3.von_mises[l], tau);
                differ(&mut worst.stress, p2.flow_stress[l], p3.flow_stress[l], tau);
                let eps = p2.eps_p[l].max(1e-3);
                differ(&mut worst.eps_p, p2.eps_p[l], p3.eps_p[l], eps);
                differ(&mut worst.jacobian, u2.jacobian[l], u3.jacobian[l], 1.0);
                let w = u2.elastic_energy[l];
                differ(&mut worst.energy, w, u3.elastic_energy[l], w);
                // The energy the change of temperature put in, on the elastic energy's
                // scale; the plastic work; the factor and thermal strain of the next
                // update, its ln J on the elastic strain's scale and its |e|^2.
                let (t2, t3) = (u2.thermoelastic[l], u3.thermoelastic[l]);
                differ(&mut worst.thermal, t2, t3, w.max(1e-300));
                let (a, b) = (p2.plastic_work[l], p3.plastic_work[l]);
                differ(&mut worst.thermal, a, b, a.abs().max(1e-300));
                let [n2, n3] = [u2.elastic_now, u3.elastic_now].map(|n| n.map(|c| c[l]));
                let strain = n2[2].abs() + n2[3].sqrt();
                for (c, scale) in [(0, 1.0), (1, 1.0), (2, strain), (3, n2[3])] {
                    differ(&mut worst.thermal, n2[c], n3[c], scale.max(1e-300));
                }
            }
            p2.elastic_prev = u2.elastic_now;
            p3.elastic_prev = u3.elastic_now;
            for l in 0..LANES {
                p2.guess[l] = 0.5 * p2.eps_p[l].min(1e-3);
                p3.guess[l] = p2.guess[l];
            }
        }
        assert!(
            elastic > 0 && plastic > 0,
            "{elastic} elastic, {plastic} plastic"
        );
        worst
    }

    /// Plane-strain and axisymmetric states through the 3D update agree with the 2D update
    /// to round-off in stress, `C_p^{-1}`, `J`, `eps_p` and energy over
    /// elastic and plastic steps and a history, for the linear, power and Johnson-Cook laws
    /// (the last with elasticity over temperature and the rate-consistent return map).
    #[test]
    fn plane_and_axisymmetric_states_agree_with_2d() {
        for m in [copper(), aluminium(), hot_copper()] {
            let w = agreement(&m);
            for x in [w.stress, w.cp_inv, w.jacobian, w.eps_p, w.energy, w.thermal] {
                assert!(x < 1e-12, "{:?}: {w:?}", m.hardening);
            }
            assert!(w.strain_ulps < 16.0, "{:?}: {w:?}", m.hardening);
        }
    }

    /// A history in 3D (a path of shear, stretch and rotation), then one step with `F` and
    /// with `R F` for arbitrary rotations `R`: `C_p^{-1}`, `eps_p`, energy and `q / J`
    /// unchanged, `P` rotated to `R P`, `tau` to `R tau R^T`.
    #[test]
    fn superposed_rotation_rotates_the_stress_only() {
        for m in [copper(), aluminium()] {
            let mut st = PointState3::default();
            for s in 1..=5 {
                let a = 0.01 * s as Real;
                let f = [
                    1.0 + a,
                    0.5 * a,
                    -0.3 * a,
                    0.2 * a,
                    1.0 - 0.4 * a,
                    0.6 * a,
                    -0.1 * a,
                    0.4 * a,
                    1.0 - 0.2 * a,
                ];
                m.update3(mul(rotation([1.0, 0.1 * a, -0.2, 0.3]), f), &mut st)
                    .unwrap();
            }
            assert!(st.eps_p > 0.0);
            let f = [1.08, 0.05, -0.02, 0.03, 0.97, 0.06, -0.04, 0.02, 0.99];
            let mut s1 = st;
            let u1 = m.update3(f, &mut s1).unwrap();
            assert!(s1.eps_p > st.eps_p, "the step yields");
            for q in [
                [0.3, 0.5, -0.7, 0.2],
                [-0.9, 0.1, 0.3, 0.8],
                [0.0, 0.0, 0.0, 1.0],
            ] {
                let r = rotation(q);
                let mut s2 = st;
                let u2 = m.update3(mul(r, f), &mut s2).unwrap();
                for c in 0..6 {
                    assert!((s1.cp_inv[c] - s2.cp_inv[c]).abs() < 1e-14, "{s1:?} {s2:?}");
                }
                assert!((s1.eps_p - s2.eps_p).abs() < 1e-12 * s1.eps_p);
                let w = u1.elastic_energy;
                assert!((w - u2.elastic_energy).abs() < 1e-12 * w);
                assert!((u1.von_mises - u2.von_mises).abs() < 1e-12 * u1.von_mises);
                let rp = mul(r, u1.piola);
                let top = u1.piola.iter().fold(0.0, |x: Real, y| x.max(y.abs()));
                for c in 0..9 {
                    assert!(
                        (rp[c] - u2.piola[c]).abs() < 1e-12 * top,
                        "{rp:?} {:?}",
                        u2.piola
                    );
                }
                let t: [Real; 9] = full(u1.kirchhoff).concat().try_into().unwrap();
                let rtr = mul(mul(r, t), transpose(r));
                let want = [rtr[0], rtr[4], rtr[8], rtr[1], rtr[5], rtr[2]];
                for c in 0..6 {
                    assert!((want[c] - u2.kirchhoff[c]).abs() < 1e-12 * top);
                }
            }
        }
    }

    /// Simple shear in the xz plane with a stretch along y, `F = I + gamma e_x e_z^T + (lambda
    /// - 1) e_y e_y^T`, to `gamma = 1.5`, `lambda = 1.2` in 600 increments: plastic flow
    /// isochoric (`det C_p^{-1} = 1` to round-off), the Mises stress of `tau` after each
    /// plastic step the flow stress at the new `eps_p`, `q / J` as the update reports it,
    /// and `ln J` the volumetric strain `tr tau / (3 K)` (plastic flow keeps the volume).
    #[test]
    fn three_d_plastic_flow_is_isochoric_and_on_the_yield_surface() {
        for m in [copper(), aluminium()] {
            let mut st = PointState3::default();
            let (mut worst_det, mut worst_q): (Real, Real) = (0.0, 0.0);
            let steps = 600;
            for s in 1..=steps {
                let x = s as Real / steps as Real;
                let f = [1.0, 0.0, 1.5 * x, 0.0, 1.0 + 0.2 * x, 0.0, 0.0, 0.0, 1.0];
                let before = st.eps_p;
                let u = m.update3(f, &mut st).unwrap();
                worst_det =
                    worst_det.max((det(full(st.cp_inv).concat().try_into().unwrap()) - 1.0).abs());
                let q = mises(u.kirchhoff);
                assert!((q - u.von_mises * u.jacobian).abs() < 1e-12 * q);
                let theta = (u.kirchhoff[0] + u.kirchhoff[1] + u.kirchhoff[2]) / (3.0 * m.bulk);
                assert!(
                    (u.jacobian.ln() - theta).abs() < 1e-12,
                    "J = {}",
                    u.jacobian
                );
                if st.eps_p > before {
                    let flow = m.hardening.flow_stress(st.eps_p);
                    worst_q = worst_q.max((q - flow).abs() / flow);
                }
            }
            assert!(st.eps_p > 0.8, "eps_p = {}", st.eps_p);
            assert!(worst_det < 1e-13, "det C_p^-1 - 1: {worst_det:e}");
            // The return maps stop at a residual of 1e-12 q_trial, q_trial up to about twice
            // sigma_y in these increments.
            assert!(worst_q < 3e-12, "q / sigma_y - 1: {worst_q:e}");
        }
    }

    /// A lane's results do not depend on what the other lanes hold: each of a set of 3D
    /// points, yielding or not, gets the same bits alone in lane 0 among unstressed lanes
    /// (through `update3`) and in every lane of batches filled with the other points.
    #[test]
    fn lanes_are_independent_3d() {
        for m in [copper(), aluminium()] {
            let plastic = PointState3 {
                cp_inv: [0.9, 1.1, 1.0 / 0.99, 0.05, -0.02, 0.03],
                eps_p: 0.3,
            };
            let cases: [([Real; 9], PointState3); 5] = [
                (
                    [
                        1.0001, 0.00002, 0.0, -0.00001, 0.9998, 0.00003, 0.0, 0.0, 1.00005,
                    ],
                    PointState3::default(),
                ),
                (
                    [1.2, 0.1, 0.05, -0.05, 0.8, 0.1, 0.02, -0.1, 1.1],
                    PointState3::default(),
                ),
                ([0.95, -0.3, 0.1, 0.2, 1.3, 0.0, -0.1, 0.05, 0.97], plastic),
                ([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], plastic),
                (
                    [0.7, 0.0, 0.3, 0.0, 1.6, 0.0, 0.0, 0.0, 0.9],
                    PointState3::default(),
                ),
            ];
            let alone: Vec<_> = cases
                .iter()
                .map(|&(f, st)| {
                    let mut st = st;
                    let u = m.update3(f, &mut st).unwrap();
                    (u, st)
                })
                .collect();
            assert!(
                alone.iter().any(|(_, st)| st.eps_p > 0.3),
                "some case yields"
            );
            assert_eq!(alone[0].1, PointState3::default(), "an elastic step");
            for shift in 0..cases.len() {
                let mut p = PointLanes3::unstressed();
                for l in 0..LANES {
                    let (f, st) = cases[(shift + l) % cases.len()];
                    p.set(l, f, &st, m.hardening.flow_stress(st.eps_p));
                }
                let u = m.update_lanes3(&mut p).unwrap();
                for l in 0..LANES {
                    let (want, want_st) = &alone[(shift + l) % cases.len()];
                    assert_eq!(p.state(l), *want_st, "lane {l}, shift {shift}");
                    let flow = m.hardening.flow_stress(want_st.eps_p);
                    assert_eq!(p.flow_stress[l].to_bits(), flow.to_bits(), "lane {l}");
                    for c in 0..9 {
                        assert_eq!(u.piola[c][l].to_bits(), want.piola[c].to_bits());
                    }
                    for c in 0..6 {
                        assert_eq!(u.kirchhoff[c][l].to_bits(), want.kirchhoff[c].to_bits());
                    }
                    assert_eq!(u.von_mises[l].to_bits(), want.von_mises.to_bits());
                    assert_eq!(u.elastic_energy[l].to_bits(), want.elastic_energy.to_bits());
                }
            }
        }
    }

    /// An inverted or non-finite `F`, or a `C_p^{-1}` that is not positive, is an error
    /// naming the lane and the reason, with the batch's history left as it was.
    #[test]
    fn inverted_deformation_is_an_error_3d() {
        let m = copper();
        let mut st = PointState3::default();
        let mirror = [-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        assert!(m.update3(mirror, &mut st).unwrap_err().contains("inverted"));
        let mut nan = embed([1.0, 0.0, 0.0, 1.0], 1.0);
        nan[5] = Real::NAN;
        assert!(m.update3(nan, &mut st).unwrap_err().contains("non-finite"));
        assert_eq!(st, PointState3::default());
        let mut p = PointLanes3::unstressed();
        p.set(2, [1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0], &st, 400e6);
        let before = p;
        let (lane, reason) = m.update_lanes3(&mut p).unwrap_err();
        assert_eq!(lane, 2);
        assert!(reason.contains("inverted"), "{reason}");
        assert_eq!(p, before);
        let mut p = PointLanes3::unstressed();
        let bad = PointState3 {
            cp_inv: [1.0, 1.0, -1.0, 0.0, 0.0, 0.0],
            eps_p: 0.0,
        };
        p.set(5, embed([1.0, 0.0, 0.0, 1.0], 1.0), &bad, 400e6);
        let before = p;
        let (lane, reason) = m.update_lanes3(&mut p).unwrap_err();
        assert_eq!(lane, 5);
        assert!(reason.contains("elastic stretch not positive"), "{reason}");
        assert_eq!(p, before);
    }

    /// Repeated principal stretches: `F = I` gives exactly no stress, energy or flow (and
    /// keeps a plastic history exactly); `F = diag(a, a, b)` from the undeformed state,
    /// elastic or yielding, gives the bits of the 2D update of the same axisymmetric state
    /// in the Kirchhoff stress, `eps_p` and energy, and `P`, `C_p^{-1}` and `q / J` within
    /// two ulps (2D forms `F^{-1}` its own way); along a path of such states, exactly equal
    /// lateral components and exactly zero shears.
    #[test]
    fn repeated_principal_stretches_are_exact() {
        for m in [copper(), aluminium()] {
            let plastic = PointState3 {
                cp_inv: [1.002, 1.002, 1.0 / (1.002 * 1.002), 0.0, 0.0, 0.0],
                eps_p: 0.1,
            };
            for st in [PointState3::default(), plastic] {
                let mut s = st;
                let u = m.update3(embed([1.0, 0.0, 0.0, 1.0], 1.0), &mut s).unwrap();
                assert_eq!(s, st);
                let elastic = PointState3::default() == st;
                if elastic {
                    assert_eq!(u.piola, [0.0; 9]);
                    assert_eq!(u.kirchhoff, [0.0; 6]);
                    assert_eq!(u.elastic_energy, 0.0);
                }
                assert_eq!(u.jacobian, 1.0);
            }
            // From the undeformed state: the same bits as 2D, elastic or yielding.
            for (a, b) in [(0.999, 1.002), (0.99, 1.02), (0.98, 1.045)] {
                let (mut s2, mut s3) = (PointState::default(), PointState3::default());
                let u3 = m.update3(embed([a, 0.0, 0.0, a], b), &mut s3).unwrap();
                let u2 = m.update([a, 0.0, 0.0, a], b, &mut s2).unwrap();
                for (c2, c3) in [(0, 0), (1, 3), (2, 1), (3, 2)] {
                    assert_eq!(u2.kirchhoff[c2].to_bits(), u3.kirchhoff[c3].to_bits());
                    let (x, y) = (s2.cp_inv[c2], s3.cp_inv[c3]);
                    assert!((x - y).abs() <= 2.0 * Real::EPSILON * x.abs(), "{x} {y}");
                }
                assert_eq!(s2.eps_p.to_bits(), s3.eps_p.to_bits());
                assert_eq!(u2.elastic_energy.to_bits(), u3.elastic_energy.to_bits());
                for (c2, c3) in [(0, 0), (3, 4), (4, 8)] {
                    let (x, y) = (u2.piola[c2], u3.piola[c3]);
                    assert!((x - y).abs() <= 2.0 * Real::EPSILON * x.abs(), "{x} {y}");
                }
                let (x, y) = (u2.von_mises, u3.von_mises);
                assert!((x - y).abs() <= 2.0 * Real::EPSILON * x, "{x} {y}");
            }
            // Along a path (the histories of 2D and 3D an ulp apart after the first
            // return, since each forms F^{-1} its own way): the lateral components equal
            // and the shears zero, exactly.
            let mut s3 = PointState3::default();
            for (a, b) in [(0.999, 1.002), (0.99, 1.02), (0.98, 1.045), (0.985, 1.04)] {
                let u3 = m.update3(embed([a, 0.0, 0.0, a], b), &mut s3).unwrap();
                assert_eq!(u3.kirchhoff[0].to_bits(), u3.kirchhoff[1].to_bits());
                assert_eq!(s3.cp_inv[0].to_bits(), s3.cp_inv[1].to_bits());
                assert_eq!(u3.piola[0].to_bits(), u3.piola[4].to_bits());
                assert_eq!(
                    [u3.kirchhoff[3], u3.kirchhoff[4], u3.kirchhoff[5]],
                    [0.0; 3]
                );
                assert_eq!([s3.cp_inv[3], s3.cp_inv[4], s3.cp_inv[5]], [0.0; 3]);
                for c in [1, 2, 3, 5, 6, 7] {
                    assert_eq!(u3.piola[c], 0.0);
                }
            }
            assert!(s3.eps_p > 0.0, "the path yields");
        }
    }
}
