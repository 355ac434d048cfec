//! The workpiece as the contact stage reads it ([`Body`]) and what the stage keeps for each
//! candidate particle from step to step ([`Pairs`]).

use crate::material::{Hardening, PointState};
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::scene::Kinematics;
use serde::{Deserialize, Serialize};

/// The workpiece as the contact stage reads it.
pub struct Body<'a> {
    /// Boundary particles, counter-clockwise.
    pub boundary: &'a [u32],
    /// `N_I(X_J)` in row `J` (no gradients needed).
    pub nodal: &'a ShapeTable,
    /// Reference particle positions `X_J` (m).
    pub reference: &'a [[Real; 2]],
    /// Lumped masses `m_J` (kg), the slave masses of eqs. 4 and 6.
    pub mass: &'a [Real],
    /// RK coefficients of the displacement at `t_n` (m).
    pub d: &'a [[Real; 2]],
    /// Predicted coefficient velocities `v*` (m/s).
    pub v: &'a [[Real; 2]],
    /// Particle spacings (m).
    pub spacing: [Real; 2],
    /// Integration point histories (the flow stress of the shear friction factor).
    pub points: &'a [PointState],
    /// The hardening law giving the flow stress.
    pub hardening: &'a Hardening,
    /// The points' temperatures (degrees C) in a thermal scene, where the flow stress
    /// depends on them.
    pub temperature: Option<&'a [Real]>,
    /// Plane strain (areas per `depth_m`) or axisymmetry (areas of whole rings).
    pub kinematics: Kinematics,
    /// Depth of a plane-strain model (m).
    pub depth_m: Real,
}

impl Body<'_> {
    /// Predicted position `x_J = X_J + sum_I N_I(X_J) (d_I + dt v*_I)` (m) and velocity
    /// `v_J = sum_I N_I(X_J) v*_I` (m/s) of particle `j`.
    pub(crate) fn predicted(&self, j: usize, dt: Real) -> [[Real; 2]; 2] {
        let (d, v, nodal) = (self.d, self.v, self.nodal);
        let (mut x, mut vj) = (self.reference[j], [0.0; 2]);
        for e in nodal.row(j) {
            let i = nodal.index[e] as usize;
            let n = nodal.n[e];
            x[0] += n * (d[i][0] + dt * v[i][0]);
            x[1] += n * (d[i][1] + dt * v[i][1]);
            vj[0] += n * v[i][0];
            vj[1] += n * v[i][1];
        }
        [x, vj]
    }
}

/// What the contact stage keeps for each candidate `k` (boundary ring first, then the
/// inside particles; the candidates of [`crate::contact::Contact`]) on each tool `t` from step to step, at index
/// `k * tools + t` (part of the saved state).
pub struct Pairs<'a> {
    /// Whether the particle is held on the tool (a tool without separation; empty when
    /// every tool separates): a particle that penetrates such a tool is held from then on.
    pub held: &'a mut [bool],
    /// Whether the particle is held on each symmetry plane, at `k * planes + p` (empty
    /// without planes): a particle that reached a plane stays on it.
    pub plane_held: &'a mut [bool],
    /// Whether each boundary ring particle (the first candidates) is in contact with the
    /// workpiece's own surface (empty without self-contact; [`crate::contact::self_contact`]).
    pub self_touching: &'a mut [bool],
    /// The particle's friction state while it stays in contact with a tool that has
    /// friction.
    pub stick: &'a mut [Option<Stick>],
    /// Normal force (N) on each tool's pressure stations, tool by tool, `stations` per tool
    /// (empty without stations); filled by the stage.
    pub pressure: &'a mut [Real],
    /// Pressure stations per tool (0: none).
    pub stations: usize,
    /// Normal impulse of the contact forces on each particle, `sum |f_n| dt_avg` (N s),
    /// added to by the stage (empty: not booked); the heat stage takes it for the contact
    /// pressure of a heat transfer coefficient over pressure.
    pub impulse: &'a mut [Real],
}

/// A particle's friction on a tool, kept from one step to the next.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stick {
    /// The part of the last step's friction force that the corrector did not realise on
    /// the particle (N; [`crate::contact::Contact::carry`]), added to this step's stick force
    /// ([`crate::contact::sidibe2009::penalty_force`]).
    pub carried: [Real; 2],
}
