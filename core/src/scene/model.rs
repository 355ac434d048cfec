//! The `[model]` section: plane strain or axisymmetric kinematics and the out-of-plane
//! depth, with what they must be ([`Model::check`]).

use crate::math::Real;
use crate::validation::{pos, Checks};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Plane strain (x, y) or axisymmetric (r, z) kinematics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Kinematics {
    /// Plane strain in (x, y); forces per `depth_m` of depth.
    PlaneStrain,
    /// Axisymmetric about x = r = 0 in (r, z); forces are for the whole ring.
    Axisymmetric,
}

/// The kinematic model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Model {
    /// `plane_strain` or `axisymmetric`.
    pub kinematics: Kinematics,
    /// Out-of-plane depth (m) for plane strain; forces and masses are per this depth.
    #[serde(default = "one")]
    pub depth_m: Real,
}

fn one() -> Real {
    1.0
}

impl Model {
    /// Every value of the section a run cannot use, under its dotted key `model.*`.
    pub(crate) fn check(&self, out: &mut Checks) {
        out.check(
            pos(self.depth_m),
            "model.depth_m",
            format!("must be positive, got {}", self.depth_m),
        );
    }
}
