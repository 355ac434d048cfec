//! What the stages write and read back within a step, and keep between steps only to save
//! work: none of it is part of the [`super::State`] a snapshot saves (a restore rebuilds it
//! from the state).

use super::nodal_stabilization::Forces;
use super::point_outputs::PointOut;
use crate::contact::Contact;
use crate::math::Real;
use crate::team::Team;

/// The stages' working arrays and the threads they run on.
#[derive(Debug, Clone)]
pub(super) struct Workspace {
    /// Per-point outputs of the last stress stage.
    pub out: Vec<PointOut>,
    /// The stress stage's chunk buffers of point forces (N), summed by the force gather
    /// ([`super::layout::Scatter`]).
    pub buf: Vec<[Real; 2]>,
    /// Internal forces `f_I` of the last force gather (N).
    pub f_int: Vec<[Real; 2]>,
    /// Coefficient velocities `v_{n-1/2}` before the last predictor (m/s).
    pub v_prev: Vec<[Real; 2]>,
    /// The stabilization's quadrant stresses and force, when the scene stabilizes nodal
    /// integration (`nodal_stabilization.rs`).
    pub stabilization: Option<Forces<2>>,
    /// The contact stage: contact forces, its candidates and bins, and what it carries
    /// between steps.
    pub contact: Contact,
    /// The threads of the parallel phases.
    pub team: Team,
    /// Use the AVX2 build of the stress stage where the CPU has it (same bits either way;
    /// false only in the test that compares the two).
    pub simd: bool,
}
