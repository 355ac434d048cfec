//! Essential conditions on the physical displacement (symmetry axis, symmetry planes).
//!
//! RK shape functions do not interpolate, so holding a coefficient does not hold the
//! particle. The condition `u_c(X_J) = sum_I N_I(X_J) d_Ic = 0` for each constrained particle
//! `J` and component `c` is the linear constraint `L d = 0`, enforced with Lagrange
//! multipliers inside the central-difference update (Belytschko, Liu, Moran 2000, sec. 6.3):
//! `v <- v - M^{-1} L^T (L M^{-1} L^T)^{-1} L v`. The reaction `L^T lambda` does no work
//! because both half-step velocities satisfy `L v = 0`, so the energy account is unchanged.
//!
//! `L M^{-1} L^T` couples two rows only where their particles share a neighbour, so its
//! Cholesky factor is zero outside a narrow profile; the projection's two triangular solves
//! run over that profile ([`Profile`]), with the arithmetic of nalgebra's dense solves (the
//! same bits: the entries left out are zeros).

use crate::error::{Error, Result};
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use nalgebra::{Cholesky, DMatrix, Dyn};

/// Rows of `L` and the factorised `L M^{-1} L^T`.
#[derive(Debug, Clone)]
pub struct Constraints {
    /// (particle J, component c) of each row.
    pub rows: Vec<(u32, usize)>,
    /// Row entries `(I, N_I(X_J))`.
    entries: Vec<Vec<(u32, Real)>>,
    /// The Cholesky factor `G` of `L M^{-1} L^T = G G^T` within its profile.
    factor: Profile,
}

/// The Cholesky factorisation of `S = L M^{-1} L^T` for the rows `rows` of `L` with their
/// entries `entries` and the lumped masses `mass` (kg), assembled through the particles each
/// row touches.
fn factorise(
    rows: &[(u32, usize)],
    entries: &[Vec<(u32, Real)>],
    mass: &[Real],
) -> Result<Cholesky<Real, Dyn>> {
    let n = rows.len();
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
    Cholesky::new(s).ok_or_else(|| {
        Error::ShapeFunctions(
            "the essential conditions are linearly dependent (L M^-1 L^T is singular)".into(),
        )
    })
}

/// A lower-triangular matrix `G` (the Cholesky factor) by columns, each from the diagonal
/// down to its last nonzero entry: below it the column holds only zeros.
#[derive(Debug, Clone)]
struct Profile {
    /// `G_ii`.
    diag: Vec<Real>,
    /// Column `i`'s entries `G_{i+1, i}, G_{i+2, i}, ...` up to its last nonzero:
    /// `below[start[i]..start[i + 1]]`.
    below: Vec<Real>,
    start: Vec<usize>,
}

impl Profile {
    /// The profile of the factor of `chol`.
    fn new(chol: &Cholesky<Real, Dyn>) -> Profile {
        let g = chol.l_dirty();
        let n = g.nrows();
        let (mut below, mut start) = (Vec::new(), vec![0]);
        for i in 0..n {
            let last = (i + 1..n).rev().find(|&r| g[(r, i)] != 0.0).unwrap_or(i);
            below.extend((i + 1..=last).map(|r| g[(r, i)]));
            start.push(below.len());
        }
        Profile {
            diag: (0..n).map(|i| g[(i, i)]).collect(),
            below,
            start,
        }
    }

    /// Solves `G G^T x = y` in place: `G z = y` forward, then `G^T x = z` backward. Each
    /// operation is nalgebra's (`Cholesky::solve`: an axpy per column forward, a dot product
    /// with eight running sums backward) on the column's profile; the entries below it are
    /// zeros, whose terms leave every sum's bits as they are.
    fn solve(&self, y: &mut [Real]) {
        let n = y.len();
        for i in 0..n {
            let coeff = y[i] / self.diag[i];
            y[i] = coeff;
            for (yr, &g) in y[i + 1..].iter_mut().zip(self.column(i)) {
                *yr += -coeff * g;
            }
        }
        for i in (0..n).rev() {
            let (col, rest) = (self.column(i), &y[i + 1..]);
            // nalgebra's dot product: terms j < 8 floor(m / 8) into running sum j mod 8, the
            // sums added in pairs (0, 4), (1, 5), (2, 6), (3, 7), then the rest in turn.
            let unrolled = rest.len() / 8 * 8;
            let mut acc = [0.0; 8];
            for (j, (&g, &z)) in col.iter().zip(rest).take(unrolled).enumerate() {
                acc[j % 8] += g * z;
            }
            let mut dot = 0.0;
            for k in 0..4 {
                dot += acc[k] + acc[k + 4];
            }
            for (&g, &z) in col.iter().zip(rest).skip(unrolled) {
                dot += g * z;
            }
            y[i] = (y[i] - dot) / self.diag[i];
        }
    }

    /// Column `i` below the diagonal, to its last nonzero.
    fn column(&self, i: usize) -> &[Real] {
        &self.below[self.start[i]..self.start[i + 1]]
    }
}

/// Largest number of constrained (particle, component) pairs for the dense factorisation.
pub const MAX_ROWS: usize = 8000;

impl Constraints {
    /// Build from the constrained (particle, component) pairs, the particle-row shape table
    /// `nodal` (`N_I(X_J)`, in `D` dimensions; components `c < D`) and the lumped masses.
    pub fn new<const D: usize>(
        mut rows: Vec<(u32, usize)>,
        nodal: &ShapeTable<D>,
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
        let chol = factorise(&rows, &entries, mass)?;
        Ok(Some(Constraints {
            rows,
            entries,
            factor: Profile::new(&chol),
        }))
    }

    /// Remove the constrained components from a coefficient velocity field `v` (m/s) of
    /// `D` components (the rows' components `c < D`) with the lumped masses `mass` (kg).
    pub fn project<const D: usize>(&self, v: &mut [[Real; D]], mass: &[Real]) {
        let mut lambda: Vec<Real> = self
            .rows
            .iter()
            .zip(&self.entries)
            .map(|(&(_, c), row)| row.iter().map(|&(i, n)| n * v[i as usize][c]).sum::<Real>())
            .collect();
        self.factor.solve(&mut lambda);
        for (r, (&(_, c), row)) in self.rows.iter().zip(&self.entries).enumerate() {
            for &(i, n) in row {
                v[i as usize][c] -= n * lambda[r] / mass[i as usize];
            }
        }
    }

    /// Largest `|L v|` over the rows: the physical constrained velocity (m/s).
    pub fn residual<const D: usize>(&self, v: &[[Real; D]]) -> Real {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rk_shape::{Lattice, Site};

    /// In 3D: conditions on the planes x = 0, y = 0 and z = 0 of a lattice (component `c`
    /// of the particles with lattice index 0 along `c`, so the edges and the corner carry
    /// two and three rows), shape functions at the particles' own sites, masses from the
    /// volumes. After the projection `L v = 0` to round-off; projecting again changes
    /// nothing beyond round-off; the projection does not raise the kinetic energy (it is
    /// the M-orthogonal one); coefficients out of every row's reach keep their bits.
    #[test]
    fn projection_holds_the_symmetry_planes_of_a_3d_lattice() {
        let (n, h) = ([5, 6, 7], [1e-3, 1.2e-3, 0.9e-3]);
        let lattice = Lattice::new([0.0; 3], h, n, h.map(|h| 2.0 * h));
        let sites: Vec<Site<3>> = (0..n[0] * n[1] * n[2])
            .map(|p| Site {
                node: [p % n[0], p / n[0] % n[1], p / (n[0] * n[1])],
                offset: [0.0; 3],
            })
            .collect();
        let nodal = lattice.shape_table(&sites, &|p| format!("{p}")).unwrap();
        let mass: Vec<Real> = lattice.cloud().volumes.iter().map(|v| 7800.0 * v).collect();
        let rows: Vec<(u32, usize)> = sites
            .iter()
            .enumerate()
            .flat_map(|(p, s)| {
                (0..3)
                    .filter(|&c| s.node[c] == 0)
                    .map(move |c| (p as u32, c))
            })
            .collect();
        assert_eq!(rows.len(), n[1] * n[2] + n[0] * n[2] + n[0] * n[1]);
        let c = Constraints::new(rows, &nodal, &mass).unwrap().unwrap();
        let v0: Vec<[Real; 3]> = (0..sites.len())
            .map(|p| std::array::from_fn(|k| 3.0 + (0.71 * (3 * p + k) as Real).sin()))
            .collect();
        let mut v = v0.clone();
        assert!(c.residual(&v) > 1.0);
        c.project(&mut v, &mass);
        assert!(c.residual(&v) <= 1e-13, "{}", c.residual(&v));
        let mut again = v.clone();
        c.project(&mut again, &mass);
        for (a, b) in again.iter().flatten().zip(v.iter().flatten()) {
            assert!((a - b).abs() <= 1e-13, "{a} {b}");
        }
        let ke = |v: &[[Real; 3]]| -> Real {
            v.iter()
                .zip(&mass)
                .map(|(v, m)| m * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]))
                .sum()
        };
        assert!(ke(&v) < ke(&v0));
        for (s, (a, b)) in sites.iter().zip(v.iter().zip(&v0)) {
            if s.node.iter().all(|&i| i >= 2) {
                assert_eq!(a, b, "{:?}", s.node);
            }
        }
    }

    /// The profile solve gives the bits of nalgebra's dense `Cholesky::solve` for the
    /// conditions of an axis (or plane) at x = 0 and a plane at y = 0 on a lattice,
    /// over right-hand sides of mixed signs and scales.
    #[test]
    fn profile_solve_gives_the_bits_of_the_dense_solve() {
        for (n, h) in [([21, 51], [0.16e-3, 0.648e-3]), ([9, 30], [1e-3, 1e-3])] {
            let lattice = Lattice::new([0.0; 2], h, n, [2.0 * h[0], 2.0 * h[1]]);
            let sites: Vec<Site> = (0..n[0] * n[1])
                .map(|p| Site {
                    node: [p % n[0], p / n[0]],
                    offset: [0.0; 2],
                })
                .collect();
            let nodal = lattice.shape_table(&sites, &|p| format!("{p}")).unwrap();
            let mass: Vec<Real> = lattice.cloud().volumes.iter().map(|v| 8930.0 * v).collect();
            let mut rows: Vec<(u32, usize)> = (0..n[1]).map(|j| ((j * n[0]) as u32, 0)).collect();
            rows.extend((0..n[0]).map(|i| (i as u32, 1)));
            rows.sort_unstable();
            let entries: Vec<Vec<(u32, Real)>> = rows
                .iter()
                .map(|&(j, _)| {
                    let row = nodal.row(j as usize);
                    row.map(|e| (nodal.index[e], nodal.n[e])).collect()
                })
                .collect();
            let chol = factorise(&rows, &entries, &mass).unwrap();
            let profile = Profile::new(&chol);
            assert!(profile.below.len() < rows.len() * rows.len() / 4);
            for seed in 0..20u64 {
                let y: Vec<Real> = (0..rows.len() as u64)
                    .map(|r| {
                        let k = (r * 2654435761 + seed * 40503) % 1000;
                        (k as Real - 500.0) * 10f64.powi((k % 7) as i32 - 3)
                    })
                    .collect();
                let dense = chol.solve(&nalgebra::DVector::from_vec(y.clone()));
                let mut x = y;
                profile.solve(&mut x);
                for (a, b) in x.iter().zip(dense.iter()) {
                    assert_eq!(a.to_bits(), b.to_bits(), "{a} {b}");
                }
            }
        }
    }
}
