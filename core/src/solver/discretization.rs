//! What setup fixes of a simulation (`setup.rs`) and only a kernel re-reference rebuilds
//! (`rereference.rs`): the particles, the integration points with their shape functions
//! and weights, the masses, the boundary and its outline, the essential conditions, the
//! symmetry planes, the critical step and, in a thermal scene, the heat settings. The
//! stages read it; none writes it.

use super::layout::Scatter;
use super::mass_scaling::Target;
use super::nodal_stabilization::Tables;
use super::outline::Outline;
use crate::constraints::Constraints;
use crate::contact::symmetry::SymmetryPlane;
use crate::integration::PointSet;
use crate::material::{HeatCapacity, HenckyJ2};
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::scene::ThermalSpec;
use serde::{Deserialize, Serialize};

/// The discretization of one scene.
#[derive(Debug, Clone)]
pub(super) struct Discretization {
    /// The workpiece's material.
    pub material: HenckyJ2,
    /// Particles along x (r).
    pub nx: usize,
    /// Particles along y (z).
    pub ny: usize,
    /// Particle spacings (m).
    pub spacing: [Real; 2],
    /// Reference particle positions `X_I` (m), row by row: the lattice's, or the positions
    /// at the last kernel re-reference (`rereference.rs`).
    pub ref_pos: Vec<[Real; 2]>,
    /// The lattice's particle positions (m), the undeformed workpiece.
    pub original: Vec<[Real; 2]>,
    /// The lattice's planar kernel volumes (m^2), for the first re-reference.
    pub lattice_volumes: Vec<Real>,
    /// `J = det F` of each point at the last re-reference (-), 1 before one.
    pub reference_jacobian: Vec<Real>,
    /// Row-sum lumped masses `m_I` (kg; whole ring in axisymmetry, per depth in plane
    /// strain).
    pub mass: Vec<Real>,
    /// `1 / m_I` (1/kg): the predictor and corrector multiply by it (two divisions per
    /// particle and step were a quarter of the serial stages' time).
    pub inv_mass: Vec<Real>,
    /// The integration points of the scene's rule.
    pub points: PointSet,
    /// Reference volume weights `w_p` of the points (m^3; 2 pi R included).
    pub weights: Vec<Real>,
    /// `1 / R_p` of each integration point (1/m) in axisymmetry, 1 in plane strain.
    pub inv_radius: Vec<Real>,
    /// The point shape functions, in the scatter's shared blocks ([`Scatter::point_row`]);
    /// the point-major table is dropped after setup.
    pub scatter: Scatter,
    /// The quadrant gradients of the stabilized nodal integration, when the scene asks for
    /// it (`nodal_stabilization.rs`).
    pub stabilization: Option<Tables<2>>,
    /// `N_I(X_J)` in row `J`, for positions and contact; its gradients are freed after
    /// setup (nothing reads them).
    pub nodal: ShapeTable,
    /// Each particle's distance at the start to the nearest other particle of its row of
    /// `nodal` (m): the scale of the isolation watch (`detachment.rs`).
    pub initial_spacing: Vec<Real>,
    /// Boundary particles, counter-clockwise (the contact slaves).
    pub boundary: Vec<u32>,
    /// The workpiece's outline: the boundary of the body the RK approximation describes
    /// (`outline.rs`), whose enclosed volume is the workpiece's.
    pub outline: Outline,
    /// Essential conditions, if the scene has any.
    pub constraints: Option<Constraints>,
    /// The symmetry planes and the axis, holding every particle that reaches them.
    pub planes: Vec<SymmetryPlane>,
    /// Critical step of the undeformed discretisation (s).
    pub critical_dt0: Real,
    /// What mass scaling added, if the scene scales.
    pub mass_scaling: Option<MassScalingReport>,
    /// What selective mass scaling holds at each kernel re-reference.
    pub scaling_target: Option<Target>,
    /// The heat settings of a scene with `[thermal]`.
    pub thermal: Option<Thermal>,
}

/// The heat settings of a thermal scene, fixed at setup: what the stress stage's adiabatic
/// heating (`heat.rs`) and the heat stage (`conduction.rs`) read.
#[derive(Debug, Clone)]
pub(super) struct Thermal {
    /// The scene's `[thermal]` section.
    pub spec: ThermalSpec,
    /// The workpiece's specific heat capacity.
    pub capacity: HeatCapacity,
    /// The physical density `rho_0` (kg/m^3; mass scaling never enters).
    pub density: Real,
    /// What the heat stage needs when the scene's heat moves (conduction, surface flows);
    /// `None` when it does not and the stage never runs.
    pub transfer: Option<Transfer>,
}

/// The heat stage's fixed inputs of a scene whose heat moves.
#[derive(Debug, Clone)]
pub(super) struct Transfer {
    /// 2D: particles on a constrained edge, adiabatic in the heat stage (empty in 3D, whose
    /// surface leaves out the faces on the symmetry planes).
    pub adiabatic_edge: Vec<bool>,
    /// Conduction's largest eigenvalue `lambda_max(C^-1 K)` on the undeformed body (1/s), 0
    /// without conduction (`conduction.rs`).
    pub lambda0: Real,
}

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
    /// Critical step with the scaled masses (s): the start's, or the last kernel
    /// re-reference's where the masses act there (`time.mass_scaling.at_rereferences` not
    /// `keep`).
    pub critical_dt_s: Real,
}

impl Discretization {
    /// The smaller particle spacing (m).
    pub fn h_min(&self) -> Real {
        self.spacing[0].min(self.spacing[1])
    }

    /// The physical position `X_j + sum_I N_I(X_j) d_I` of particle `j` (m) for the
    /// displacement coefficients `d` (m).
    pub fn position(&self, d: &[[Real; 2]], j: usize) -> [Real; 2] {
        let u = self.nodal.interpolate(j, d);
        [self.ref_pos[j][0] + u[0], self.ref_pos[j][1] + u[1]]
    }

    /// The physical positions of every particle (m), for the displacement coefficients `d`
    /// (m).
    pub fn positions(&self, d: &[[Real; 2]]) -> Vec<[Real; 2]> {
        (0..self.ref_pos.len())
            .map(|j| self.position(d, j))
            .collect()
    }

    /// The physical positions of the boundary ring's particles (m), in ring order.
    pub fn ring(&self, d: &[[Real; 2]]) -> Vec<[Real; 2]> {
        self.boundary
            .iter()
            .map(|&j| self.position(d, j as usize))
            .collect()
    }
}
