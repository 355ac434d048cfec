//! The penalty feedback of the tools and planes that hold particles (a tool without
//! separation such as the FE wall, the symmetry planes; 2D and 3D): how much of a gap the
//! paper's penalty closes in one step when every particle the tool holds pushes at once,
//! and the scale that keeps the explicit step stable when a kernel raises it.
//!
//! The penalty of eq. 4 (Sidibe et al. 2009; [`super::sidibe2009::penalty_force`]) gives a particle `J` that
//! lies beyond a plane by the gap `g_J` (m, at the predicted position) the force
//! `f_J = m_J g_J / dt^2` (N; `dt dt_avg` for a changing step): alone, it closes its gap in one step. The force reaches the
//! coefficients by eq. 7 (`F_I = sum_J N_I(X_J) f_J`), the corrector moves them by
//! `dt^2 F_I / m_I`, and each particle's position moves by `sum_I N_I(X_J) dt^2 F_I / m_I`:
//! over the particles `S` the plane holds, the gaps left after the corrector are
//! `(I - G) g` with the feedback matrix
//!
//! `G_JK = sum_I N_I(X_J) N_I(X_K) m_K / m_I` (-),
//!
//! similar to the symmetric positive semi-definite `M_S^1/2 N_S M^-1 N_S^T M_S^1/2`, so its
//! eigenvalues `lambda` are real and at least 0. With the predictor
//! `x* = 2 x_n - x_(n-1)` (no stiffness along the mode), a mode's gap follows
//! `x_(n+1) = (1 - lambda) (2 x_n - x_(n-1))`, whose roots
//! `z = mu +- sqrt(mu^2 - mu)`, `mu = 1 - lambda`, lie inside the unit circle for
//! `0 < lambda < 4/3` and pass `z = -1` at `lambda = 4/3`: a feedback above 4/3 makes the
//! gap ring with a growing amplitude (a stiffness along the mode, `omega^2 dt^2 = w`,
//! moves the crossing to `1 + 1 / (3 - w)`, above 4/3 for `0 < w < 3`).
//!
//! An undeformed lattice measures 1.01-1.04 (the shipped 3D scenes); a re-referenced
//! kernel at a flash tip folded onto a plane measured 1.35 (the 0.7 mm conrod at a 3.5 us
//! step, which diverged: docs/forging.md). The contact stages (2D's [`super::Contact`], 3D's
//! `ToolContact`) measure the largest feedback `rho` of each tool without separation and
//! each symmetry plane over the particles it holds ([`Feedback`]), again when it holds a
//! new particle and after a re-reference; one whose `rho` passes [`FEEDBACK_LIMIT`] has its
//! penalty scaled by `1 / rho`, which closes its worst mode's gap exactly and leaves every
//! other mode's between 0 and 1. A tool with separation lets go of a particle whose gap
//! changed sign, so an overshoot cannot ring there. In 2D the corrector also projects the
//! velocities on the essential conditions, an `M`-orthogonal projection that can only
//! lower the feedback: the `rho` measured without it bounds the one the step sees.

use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::solver::largest_eigenvalue;
use std::convert::Infallible;

/// A penalty is scaled when its feedback passes this (-): halfway from the exact closure
/// of an isolated particle (1) to the instability of the step (4/3). There a mode's gap
/// shrinks by at least 0.61 a step (`|z|` above).
pub const FEEDBACK_LIMIT: Real = 7.0 / 6.0;

/// The largest eigenvalue `rho` of the feedback matrix `G` (-, module doc) over the
/// particles `set` (ascending), from the shape functions at the particles `nodal` (row
/// `J`: `N_I(X_J)`) and the lumped masses `mass` (kg), by Lanczos on the symmetric form
/// ([`largest_eigenvalue`]); 0 for an empty set.
pub fn feedback<const D: usize>(nodal: &ShapeTable<D>, mass: &[Real], set: &[usize]) -> Real {
    if set.is_empty() {
        return 0.0;
    }
    let sqrt_m: Vec<Real> = set.iter().map(|&j| mass[j].sqrt()).collect();
    // The coefficients the set's rows reach, each once.
    let mut reached: Vec<usize> = set
        .iter()
        .flat_map(|&j| nodal.row(j).map(|e| nodal.index[e] as usize))
        .collect();
    reached.sort_unstable();
    reached.dedup();
    let mut y = vec![0.0; mass.len()];
    let Ok(rho) = largest_eigenvalue(set.len(), |x: &[[Real; 1]]| {
        // y = M^-1 N_S^T M_S^1/2 x, then M_S^1/2 N_S y.
        for &i in &reached {
            y[i] = 0.0;
        }
        for ((&j, s), x) in set.iter().zip(&sqrt_m).zip(x) {
            for e in nodal.row(j) {
                y[nodal.index[e] as usize] += nodal.n[e] * s * x[0];
            }
        }
        for &i in &reached {
            y[i] /= mass[i];
        }
        Ok::<_, Infallible>(
            set.iter()
                .zip(&sqrt_m)
                .map(|(&j, s)| {
                    [s * nodal
                        .row(j)
                        .map(|e| nodal.n[e] * y[nodal.index[e] as usize])
                        .sum::<Real>()]
                })
                .collect(),
        )
    });
    rho
}

/// Each holding tool's or plane's feedback, kept by a contact stage between steps: measured
/// again when the particles it holds or the kernel changed.
#[derive(Debug, Clone)]
pub struct Feedback {
    /// `rho` of each (-; 0 for a tool with separation).
    rho: Vec<Real>,
    /// The particles it holds changed since `rho` was measured, or the kernel did.
    stale: Vec<bool>,
    /// Scale a penalty whose feedback passes the limit (false only in the tests that show
    /// the instability without it).
    pub bounded: bool,
}

impl Default for Feedback {
    fn default() -> Feedback {
        Feedback {
            rho: Vec::new(),
            stale: Vec::new(),
            bounded: true,
        }
    }
}

impl Feedback {
    /// The kernel or the masses changed: every `rho` is measured again.
    pub fn forget(&mut self) {
        self.stale.fill(true);
    }

    /// Surface `t` took hold of a particle it did not hold (`was_held` false).
    pub fn took_hold(&mut self, t: usize, was_held: bool) {
        self.stale[t] |= !was_held;
    }

    /// Measures `rho` of each of the `surfaces` tools and planes that is stale (or new) and
    /// holds particles (`holds(t)`), over the particles `members(t)` gives, and returns the
    /// largest measured (0 when none was).
    pub fn update<const D: usize>(
        &mut self,
        surfaces: usize,
        nodal: &ShapeTable<D>,
        mass: &[Real],
        holds: impl Fn(usize) -> bool,
        members: impl Fn(usize) -> Vec<usize>,
    ) -> Real {
        if self.rho.len() != surfaces {
            self.rho = vec![0.0; surfaces];
            self.stale = vec![true; surfaces];
        }
        let mut largest: Real = 0.0;
        for t in 0..surfaces {
            if self.stale[t] && self.bounded && holds(t) {
                self.rho[t] = feedback(nodal, mass, &members(t));
                largest = largest.max(self.rho[t]);
            }
            self.stale[t] = false;
        }
        largest
    }

    /// The factor on surface `t`'s penalty mass (-): [`scale`] of its `rho`.
    pub fn scale(&self, t: usize) -> Real {
        scale(self.rho[t])
    }
}

/// The factor on a penalty's mass (-) for the feedback `rho` of its tool or plane:
/// `1 / rho` above [`FEEDBACK_LIMIT`], 1 otherwise.
pub fn scale(rho: Real) -> Real {
    if rho > FEEDBACK_LIMIT {
        1.0 / rho
    } else {
        1.0
    }
}

/// The feedback of [`feedback`] by power iteration (3000 products) on the dense `G` built
/// entry by entry from its definition, for the tests.
#[cfg(test)]
pub(crate) fn dense_feedback<const D: usize>(
    nodal: &ShapeTable<D>,
    mass: &[Real],
    set: &[usize],
) -> Real {
    let n_at = |j: usize, i: usize| {
        nodal
            .row(j)
            .find(|&e| nodal.index[e] as usize == i)
            .map_or(0.0, |e| nodal.n[e])
    };
    let g: Vec<Vec<Real>> = set
        .iter()
        .map(|&j| {
            set.iter()
                .map(|&k| {
                    (0..mass.len())
                        .map(|i| n_at(j, i) * n_at(k, i) * mass[k] / mass[i])
                        .sum()
                })
                .collect()
        })
        .collect();
    let mut x = vec![1.0; set.len()];
    let mut rho = 0.0;
    for _ in 0..3000 {
        let y: Vec<Real> = g
            .iter()
            .map(|r| r.iter().zip(&x).map(|(a, b)| a * b).sum())
            .collect();
        let norm = y.iter().map(|v| v * v).sum::<Real>().sqrt();
        rho = norm / x.iter().map(|v| v * v).sum::<Real>().sqrt();
        x = y.iter().map(|v| v / norm).collect();
    }
    rho
}
