//! Essential conditions on the physical displacement (symmetry axis, symmetry planes).
//!
//! RK shape functions do not interpolate, so holding a coefficient does not hold the
//! particle. The condition `u_c(X_J) = sum_I N_I(X_J) d_Ic = 0` for each constrained particle
//! `J` and component `c` is the linear constraint `L d = 0`, enforced with Lagrange
//! multipliers inside the central-difference update (Belytschko, Liu, Moran 2000, sec. 6.3):
//! `v <- v - M^{-1} L^T (L M^{-1} L^T)^{-1} L v`. The reaction `L^T lambda` does no work
//! because both half-step velocities satisfy `L v = 0`, so the energy account is unchanged.

use crate::error::{Error, Result};
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

/// Rows of `L` and the factorised `L M^{-1} L^T`.
#[derive(Debug, Clone)]
pub struct Constraints {
    /// (particle J, component c) of each row.
    pub rows: Vec<(u32, usize)>,
    /// Row entries `(I, N_I(X_J))`.
    entries: Vec<Vec<(u32, Real)>>,
    chol: Cholesky<Real, Dyn>,
}

/// Largest number of constrained (particle, component) pairs for the dense factorisation.
pub const MAX_ROWS: usize = 8000;

impl Constraints {
    /// Build from the constrained (particle, component) pairs, the particle-row shape table
    /// `nodal` (`N_I(X_J)`) and the lumped masses.
    pub fn new(
        mut rows: Vec<(u32, usize)>,
        nodal: &ShapeTable,
        mass: &[Real],
    ) -> Result<Option<Self>> {
        rows.sort_unstable();
        rows.dedup();
        if rows.is_empty() {
            return Ok(None);
        }
        if rows.len() > MAX_ROWS {
            return Err(Error::Request(format!(
                "{} constrained particle components exceed the limit of {MAX_ROWS}",
                rows.len()
            )));
        }
        let entries: Vec<Vec<(u32, Real)>> = rows
            .iter()
            .map(|&(j, _)| {
                nodal
                    .row(j as usize)
                    .map(|e| (nodal.index[e], nodal.n[e]))
                    .collect()
            })
            .collect();
        let n = rows.len();
        // S = L M^{-1} L^T, assembled through the particles each row touches.
        let mut touching: std::collections::BTreeMap<(u32, usize), Vec<(usize, Real)>> =
            Default::default();
        for (r, row) in entries.iter().enumerate() {
            for &(i, v) in row {
                touching.entry((i, rows[r].1)).or_default().push((r, v));
            }
        }
        let mut s = DMatrix::zeros(n, n);
        for ((i, _), list) in &touching {
            let minv = 1.0 / mass[*i as usize];
            for &(r, a) in list {
                for &(q, b) in list {
                    s[(r, q)] += a * b * minv;
                }
            }
        }
        let chol = Cholesky::new(s).ok_or_else(|| {
            Error::ShapeFunctions(
                "the essential conditions are linearly dependent (L M^-1 L^T is singular)".into(),
            )
        })?;
        Ok(Some(Constraints {
            rows,
            entries,
            chol,
        }))
    }

    /// Remove the constrained components from a coefficient velocity field `v` (m/s).
    pub fn project(&self, v: &mut [[Real; 2]], mass: &[Real]) {
        let y = DVector::from_iterator(
            self.rows.len(),
            self.rows
                .iter()
                .zip(&self.entries)
                .map(|(&(_, c), row)| row.iter().map(|&(i, n)| n * v[i as usize][c]).sum::<Real>()),
        );
        let lambda = self.chol.solve(&y);
        for (r, (&(_, c), row)) in self.rows.iter().zip(&self.entries).enumerate() {
            for &(i, n) in row {
                v[i as usize][c] -= n * lambda[r] / mass[i as usize];
            }
        }
    }

    /// Largest `|L v|` over the rows: the physical constrained velocity (m/s).
    pub fn residual(&self, v: &[[Real; 2]]) -> Real {
        self.rows
            .iter()
            .zip(&self.entries)
            .map(|(&(_, c), row)| {
                row.iter()
                    .map(|&(i, n)| n * v[i as usize][c])
                    .sum::<Real>()
                    .abs()
            })
            .fold(0.0, Real::max)
    }
}
