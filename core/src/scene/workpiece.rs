//! The `[workpiece]` section: a rectangle filled with a regular grid of particles, and its
//! initial velocity, with what they must be ([`Workpiece::check`]; what an axisymmetric
//! model asks of it is checked across the sections, `across_sections.rs`).

use crate::math::Real;
use crate::validation::{pos, Checks};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A rectangular workpiece filled with a regular grid of particles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Workpiece {
    /// Lower-left corner (m).
    pub origin_m: [Real; 2],
    /// Width and height (m).
    pub size_m: [Real; 2],
    /// Particles along x and y (each at least 2).
    pub particles: [usize; 2],
    /// Uniform initial velocity (m/s).
    #[serde(default)]
    pub initial_velocity_m_per_s: [Real; 2],
}

impl Workpiece {
    /// Every value of the section a run cannot use, under its dotted key `workpiece.*`:
    /// placement, size, particles and initial velocity.
    pub(crate) fn check(&self, out: &mut Checks) {
        for k in 0..2 {
            out.check(
                self.origin_m[k].is_finite(),
                "workpiece.origin_m",
                format!("must be finite, got {:?}", self.origin_m),
            );
            out.check(
                pos(self.size_m[k]),
                "workpiece.size_m",
                format!("both sizes must be positive, got {:?}", self.size_m),
            );
            out.check(
                self.particles[k] >= 2,
                "workpiece.particles",
                format!(
                    "need at least 2 particles in each direction, got {:?}",
                    self.particles
                ),
            );
            out.check(
                self.initial_velocity_m_per_s[k].is_finite(),
                "workpiece.initial_velocity_m_per_s",
                format!("must be finite, got {:?}", self.initial_velocity_m_per_s),
            );
        }
        out.check(
            self.particles[0].saturating_mul(self.particles[1]) <= 4_000_000,
            "workpiece.particles",
            format!("{:?} is more than 4 million particles", self.particles),
        );
    }
}
