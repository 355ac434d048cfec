//! How far each particle's predicted position can have moved since the last contact stage,
//! region by region: the bound that lets the contact stage skip a particle whose clearance
//! to every tool has not run out.
//!
//! The stage interpolates `x_J = X_J + sum_I N_I(X_J) u_I` (m) with `u_I = d_I + dt v*_I`
//! (m, `dt` the step the stage looks ahead by, s). Between two stages `x_J` moves by
//! `sum_I N_I(X_J) du_I`, at most `S_J max_{I in row J} |du_I|` (`S_J = sum_I |N_I(X_J)|`,
//! `|.|` the Euclidean norm). The coefficients are binned in cells of the reference
//! configuration at least as wide, per direction, as the farthest reach of a row, so
//! every coefficient of row `J` lies in particle `J`'s cell or one of its neighbours; the
//! bound is then `S_J M_c`, `M_c` the largest `|du_I|` (measured exactly from the `u_I` of
//! the last stage) over the coefficients of cell `c = cell(J)` and its neighbours.
//!
//! A global bound (the fastest coefficient anywhere, as 2D uses) makes every particle near a
//! tool wait on the surface coefficients that ring under the penalty contact: on the 3D
//! block they move some twenty times faster than the material. By region, a particle's
//! clearance runs out at the pace of its own neighbourhood. The 3D stage uses it, where a
//! particle's evaluation costs a row of about a hundred coefficients and a search of the
//! tools' triangles; 2D keeps the global bound, as this pass over every coefficient cost
//! more than it saved there (the Taylor bar with SCNI took 1.21 times as long).

use crate::math::Real;
use crate::rk_shape::ShapeTable;

/// The cells and the last stage's `u_I` the bound is measured from; empty until the first
/// stage and after [`MoveBound::forget`], when every particle's bound is infinite.
#[derive(Debug, Clone)]
pub struct MoveBound<const D: usize> {
    /// The cell of each coefficient (and of the particle at its reference position).
    cell_of: Vec<u32>,
    /// Cells per direction.
    dims: [usize; D],
    /// `u_I` at the last stage (m).
    last: Vec<[Real; D]>,
    /// Largest `|du_I|^2` of each cell's coefficients since the last stage (m^2); the
    /// neighbour pass's scratch after it.
    cell_move: Vec<Real>,
    /// `M_c`: the largest over the cell and its neighbours (m).
    near_move: Vec<Real>,
}

impl<const D: usize> Default for MoveBound<D> {
    fn default() -> Self {
        MoveBound {
            cell_of: Vec::new(),
            dims: [0; D],
            last: Vec::new(),
            cell_move: Vec::new(),
            near_move: Vec::new(),
        }
    }
}

/// `a` if it is not below `b` or not a number, else `b`: a maximum that keeps a NaN, so
/// that a coefficient gone bad makes its neighbours' particles evaluated.
fn max_keep_nan(a: Real, b: Real) -> Real {
    if a >= b || a.is_nan() {
        a
    } else {
        b
    }
}

impl<const D: usize> MoveBound<D> {
    /// Drops the cells and the last `u_I` (a re-reference changed the shape functions, a
    /// restore the state): the next stage's bound is infinite everywhere.
    pub fn forget(&mut self) {
        self.cell_of.clear();
        self.last.clear();
    }

    /// Bins the coefficients at `reference` (m) in cells at least as wide as the reach of
    /// `nodal`'s rows per direction.
    fn bin(&mut self, nodal: &ShapeTable<D>, reference: &[[Real; D]]) {
        let mut reach = [0.0 as Real; D];
        for (j, xj) in reference.iter().enumerate() {
            for e in nodal.row(j) {
                let xi = reference[nodal.index[e] as usize];
                for k in 0..D {
                    reach[k] = reach[k].max((xi[k] - xj[k]).abs());
                }
            }
        }
        let lo: [Real; D] =
            std::array::from_fn(|k| reference.iter().fold(Real::INFINITY, |m, x| m.min(x[k])));
        let hi: [Real; D] = std::array::from_fn(|k| {
            reference
                .iter()
                .fold(Real::NEG_INFINITY, |m, x| m.max(x[k]))
        });
        // Wider than the reach by a relative 1e-6, so that rounding in the cell index
        // cannot put two coefficients of one row two cells apart; a body one particle
        // thick gets one cell across.
        let size: [Real; D] = std::array::from_fn(|k| {
            let s = reach[k] * (1.0 + 1e-6);
            if s > 0.0 {
                s
            } else {
                (hi[k] - lo[k]).max(1.0)
            }
        });
        self.dims = std::array::from_fn(|k| ((hi[k] - lo[k]) / size[k]) as usize + 1);
        let index = |x: &[Real; D]| {
            (0..D).rev().fold(0usize, |c, k| {
                let i = (((x[k] - lo[k]) / size[k]) as usize).min(self.dims[k] - 1);
                c * self.dims[k] + i
            })
        };
        self.cell_of = reference.iter().map(|x| index(x) as u32).collect();
        let cells = self.dims.iter().product();
        self.cell_move = vec![0.0; cells];
        self.near_move = vec![0.0; cells];
    }

    /// Measures each coefficient's `|du_I|` from the last stage's `u_I` to `u_I = d_I + dt
    /// v_I` (`d` m, `v` m/s, `dt` s), keeps the new `u_I` and returns each particle's
    /// bound's factor `M_c` (m) by cell, read with [`MoveBound::near`]: a particle's
    /// predicted position has moved at most `S_J M_{cell(J)}` since the last stage.
    pub fn measure(
        &mut self,
        nodal: &ShapeTable<D>,
        reference: &[[Real; D]],
        d: &[[Real; D]],
        v: &[[Real; D]],
        dt: Real,
    ) {
        if self.cell_of.len() != d.len() {
            self.bin(nodal, reference);
        }
        let first = self.last.len() != d.len();
        if first {
            self.last = vec![[0.0; D]; d.len()];
        }
        self.cell_move.fill(0.0);
        for (i, ((u, di), vi)) in self.last.iter_mut().zip(d).zip(v).enumerate() {
            let now: [Real; D] = std::array::from_fn(|k| di[k] + dt * vi[k]);
            // The squared move: the square root is taken once per cell.
            let moved = if first {
                Real::INFINITY
            } else {
                (0..D).map(|k| (now[k] - u[k]) * (now[k] - u[k])).sum()
            };
            *u = now;
            let c = &mut self.cell_move[self.cell_of[i] as usize];
            *c = max_keep_nan(moved, *c);
        }
        self.spread();
    }

    /// `near_move` from `cell_move` (squared): the largest over each cell's neighbours, one
    /// direction at a time, then its square root.
    fn spread(&mut self) {
        let mut stride = 1;
        for k in 0..D {
            let n = self.dims[k];
            let (from, to) = match k % 2 {
                0 => (&self.cell_move, &mut self.near_move),
                _ => (&self.near_move, &mut self.cell_move),
            };
            for (c, m) in to.iter_mut().enumerate() {
                let i = (c / stride) % n;
                *m = from[c];
                if i > 0 {
                    *m = max_keep_nan(from[c - stride], *m);
                }
                if i + 1 < n {
                    *m = max_keep_nan(from[c + stride], *m);
                }
            }
            stride *= n;
        }
        if D % 2 == 0 {
            std::mem::swap(&mut self.cell_move, &mut self.near_move);
        }
        for m in &mut self.near_move {
            *m = m.sqrt();
        }
    }

    /// `M_c` of particle `j`'s cell (m): the largest `|du_I|` of the coefficients its row
    /// can hold.
    pub fn near(&self, j: usize) -> Real {
        self.near_move[self.cell_of[j] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Real;

    /// A lattice of `n x n x n` particles 1 apart, each row reaching `r` lattice steps.
    fn lattice(n: usize, r: i64) -> (ShapeTable<3>, Vec<[Real; 3]>) {
        let at = |i: usize| [(i % n) as Real, ((i / n) % n) as Real, (i / n / n) as Real];
        let x: Vec<[Real; 3]> = (0..n * n * n).map(at).collect();
        let mut table = ShapeTable::<3> {
            offsets: vec![0],
            ..Default::default()
        };
        for xj in &x {
            let row: Vec<u32> = (0..x.len() as u32)
                .filter(|&i| (0..3).all(|k| (x[i as usize][k] - xj[k]).abs() <= r as Real))
                .collect();
            table.n.extend(row.iter().map(|_| 1.0 / row.len() as Real));
            table.index.extend(row);
            table.offsets.push(table.index.len() as u32);
        }
        (table, x)
    }

    #[test]
    fn a_particle_is_bounded_by_every_coefficient_its_row_holds() {
        let (table, x) = lattice(7, 2);
        let mut bound = MoveBound::<3>::default();
        let zero = vec![[0.0; 3]; x.len()];
        bound.measure(&table, &x, &zero, &zero, 1.0);
        assert!((0..x.len()).all(|j| bound.near(j) == Real::INFINITY));
        // One coefficient in a corner moves; every particle whose row holds it must see
        // its move, and the far corner must not.
        let mut v = zero.clone();
        v[0] = [3.0, 4.0, 0.0];
        bound.measure(&table, &x, &zero, &v, 1.0);
        for j in 0..x.len() {
            if table.row(j).any(|e| table.index[e] == 0) {
                assert_eq!(bound.near(j), 5.0, "particle {j}");
            }
        }
        assert_eq!(bound.near(x.len() - 1), 0.0);
        // Measured from the last stage, not from zero: no further move, no bound.
        bound.measure(&table, &x, &zero, &v, 1.0);
        assert!((0..x.len()).all(|j| bound.near(j) == 0.0));
        bound.forget();
        bound.measure(&table, &x, &zero, &v, 1.0);
        assert!((0..x.len()).all(|j| bound.near(j) == Real::INFINITY));
    }

    #[test]
    fn a_coefficient_gone_bad_is_not_hidden() {
        let (table, x) = lattice(9, 1);
        let mut bound = MoveBound::<3>::default();
        let zero = vec![[0.0; 3]; x.len()];
        bound.measure(&table, &x, &zero, &zero, 1.0);
        let mut v = zero.clone();
        // The centre (4, 4, 4): its cell is the fourth of eight per direction, two cells
        // from the corner's neighbourhood.
        v[364] = [Real::NAN, 0.0, 0.0];
        bound.measure(&table, &x, &zero, &v, 1.0);
        for j in 0..x.len() {
            if table.row(j).any(|e| table.index[e] == 364) {
                assert!(bound.near(j).is_nan(), "particle {j}");
            }
        }
        assert_eq!(bound.near(0), 0.0);
    }
}
