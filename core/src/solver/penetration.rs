//! How deep particles lie inside the tools, measured on their physical positions
//! `x_J = X_J + sum_I N_I(X_J) d_I` (m) against each tool's polyline in its position at the
//! same time, and the scene's bound on it (`checks.max_penetration_rel`).
//!
//! Two measures, neither limited to the particles the contact stage treats as slaves:
//! - at every step with a contact force, the particles that took one
//!   ([`crate::contact::Contact::near`]: every particle the stage found inside a tool at its
//!   predicted position) and whose predicted gap reached half the bound (the corrector only
//!   pushes a particle in contact out of its tool), against that tool within its search
//!   depth; past the bound the run stops with the step, time, particle, tool and depth;
//! - at each output sample ([`Simulation::measure_penetration`]), every particle against
//!   every segment of every tool at any depth.

use super::Simulation;
use crate::error::{Error, Result};
use crate::math::Real;

/// The deepest particle inside a tool.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Penetrated {
    /// Depth inside the tool (m).
    pub depth: Real,
    /// The particle.
    pub particle: usize,
    /// The tool's index.
    pub tool: usize,
}

impl Simulation {
    /// The physical position `X_j + sum_I N_I(X_j) d_I` of particle `j` now (m).
    pub(super) fn position(&self, j: usize) -> [Real; 2] {
        let u = self.nodal.interpolate(j, &self.st.d);
        [self.ref_pos[j][0] + u[0], self.ref_pos[j][1] + u[1]]
    }

    /// The step's check: the deepest of the particles in contact whose predicted gap reached
    /// half the bound, within the search depth (m); kept as the run's largest and stopped at
    /// the scene's bound.
    pub(super) fn check_penetration(&mut self) -> Result<()> {
        let mut worst = Penetrated::default();
        let h = self.spacing[0].min(self.spacing[1]);
        let watch = 0.5 * self.scene.checks.max_penetration_rel * h;
        let deep: Vec<(usize, usize)> = self
            .contact
            .near()
            .filter(|n| n.3 >= watch)
            .map(|n| (n.0, n.1))
            .collect();
        for (j, t) in deep {
            if let Some(p) = self.tools[t].penetration(self.position(j)) {
                if p.gap > worst.depth {
                    worst = Penetrated {
                        depth: p.gap,
                        particle: j,
                        tool: t,
                    };
                }
            }
        }
        self.record_penetration(worst)
    }

    /// Every particle against every tool at any depth, now: the deepest (a zero depth when
    /// none is inside), also kept as the run's largest; past the scene's bound an error
    /// naming the particle, tool and depth.
    pub fn measure_penetration(&mut self) -> Result<Penetrated> {
        let mut worst = Penetrated::default();
        for j in 0..self.ref_pos.len() {
            let x = self.position(j);
            for (t, tool) in self.tools.iter().enumerate() {
                if let Some(depth) = tool.depth_inside(x) {
                    if depth > worst.depth {
                        worst = Penetrated {
                            depth,
                            particle: j,
                            tool: t,
                        };
                    }
                }
            }
        }
        self.record_penetration(worst)?;
        Ok(worst)
    }

    /// Keeps `worst` if it is the run's deepest, and stops the run past the bound.
    fn record_penetration(&mut self, worst: Penetrated) -> Result<()> {
        if worst.depth > self.st.max_penetration {
            self.st.max_penetration = worst.depth;
        }
        let h = self.spacing[0].min(self.spacing[1]);
        let bound = self.scene.checks.max_penetration_rel;
        if worst.depth > bound * h {
            return Err(Error::Penetration {
                step: self.st.step,
                time: self.st.time,
                particle: worst.particle,
                reference: self.original[worst.particle],
                tool: self.tools[worst.tool].name.clone(),
                depth: worst.depth,
                depth_rel: worst.depth / h,
                bound,
            });
        }
        Ok(())
    }
}
