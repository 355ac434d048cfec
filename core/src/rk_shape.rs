//! Reproducing kernel shape functions with a linear basis (Liu, Jun, Zhang 1995;
//! Chen, Pan, Wu, Liu 1996), paper eqs. (2)-(3), in `D` = 2 or 3 dimensions:
//!
//! `N_I(x) = H(0)^T M(x)^{-1} H(X_I - x) phi_a(x - X_I) V_I`,
//! `M(x) = sum_I H(X_I - x) H(X_I - x)^T phi_a(x - X_I) V_I`,
//! `H(z) = [1, z_1 / a_1, ..., z_D / a_D]` (scaled for conditioning), so `M` is
//! `(D + 1) x (D + 1)`.
//!
//! The approximation reproduces constants and linear fields exactly, with gradients,
//! wherever `M` is invertible. Lagrangian kernel: everything is evaluated once in the
//! reference configuration and stored in compressed rows. One source serves both
//! dimensions through the const parameter `D` (default 2, so 2D code names the types
//! without it); the 2D results are the bits of the former 2D-only code.

use crate::error::{Error, Result};
use crate::kernel::window;
use crate::math::Real;
use nalgebra::{SMatrix, SVector};

/// The particles that carry the RK approximation, in the reference configuration.
#[derive(Debug, Clone)]
pub struct KernelCloud<const D: usize = 2> {
    /// Reference positions `X_I` (m).
    pub positions: Vec<[Real; D]>,
    /// Particle volumes `V_I` (m^D: planar areas in 2D) used as kernel weights.
    pub volumes: Vec<Real>,
    /// Support radius per direction `a_k` (m), the largest of `supports` where those are
    /// given.
    pub support: [Real; D],
    /// Each particle's own support radii (m), or `None` when all share `support`.
    pub supports: Option<Vec<[Real; D]>>,
    grid: BinGrid<D>,
}

/// Uniform bins for the neighbour search (bin size = support radius).
#[derive(Debug, Clone)]
struct BinGrid<const D: usize> {
    origin: [Real; D],
    size: [Real; D],
    dims: [usize; D],
    offsets: Vec<u32>,
    items: Vec<u32>,
}

/// Calls `f` with every multi-index of the box `lo[k] <= i_k < hi[k]`, the first index
/// running fastest (the order of particles numbered `i_0 + n_0 (i_1 + n_1 i_2)`).
pub(crate) fn for_each_index<const D: usize>(
    lo: [usize; D],
    hi: [usize; D],
    mut f: impl FnMut([usize; D]),
) {
    if (0..D).any(|k| lo[k] >= hi[k]) {
        return;
    }
    let mut i = lo;
    loop {
        f(i);
        let mut k = 0;
        loop {
            i[k] += 1;
            if i[k] < hi[k] {
                break;
            }
            i[k] = lo[k];
            k += 1;
            if k == D {
                return;
            }
        }
    }
}

/// The linear number `i_0 + n_0 (i_1 + n_1 (i_2 + ...))` of the multi-index `i` in a box
/// of `n` per direction.
#[inline]
pub(crate) fn linear_index<const D: usize>(i: [usize; D], n: [usize; D]) -> usize {
    (0..D).rev().fold(0, |b, k| b * n[k] + i[k])
}

/// `(x_1, ..., x_D)` with six significant digits, for messages.
fn coordinates<const D: usize>(x: [Real; D]) -> String {
    let parts: Vec<String> = x.iter().map(|c| format!("{c:.6e}")).collect();
    format!("({})", parts.join(", "))
}

impl<const D: usize> BinGrid<D> {
    fn new(points: &[[Real; D]], size: [Real; D]) -> Self {
        let mut lo = [Real::INFINITY; D];
        let mut hi = [Real::NEG_INFINITY; D];
        for p in points {
            for k in 0..D {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let dims: [usize; D] =
            std::array::from_fn(|k| (((hi[k] - lo[k]) / size[k]).floor() as usize + 1).max(1));
        let mut counts = vec![0u32; dims.iter().product::<usize>() + 1];
        let bin_of = |p: &[Real; D]| {
            let i = std::array::from_fn(|k| (((p[k] - lo[k]) / size[k]) as usize).min(dims[k] - 1));
            linear_index(i, dims)
        };
        for p in points {
            counts[bin_of(p) + 1] += 1;
        }
        for b in 1..counts.len() {
            counts[b] += counts[b - 1];
        }
        let mut fill = counts.clone();
        let mut items = vec![0u32; points.len()];
        for (i, p) in points.iter().enumerate() {
            let b = bin_of(p);
            items[fill[b] as usize] = i as u32;
            fill[b] += 1;
        }
        BinGrid {
            origin: lo,
            size,
            dims,
            offsets: counts,
            items,
        }
    }

    /// Indices of points strictly inside the open box `|x - p| < r` per direction, in
    /// ascending index order (deterministic).
    fn query(&self, points: &[[Real; D]], x: [Real; D], r: [Real; D], out: &mut Vec<u32>) {
        out.clear();
        let (mut lo, mut hi) = ([0; D], [0; D]);
        for k in 0..D {
            let first = ((x[k] - r[k] - self.origin[k]) / self.size[k]).floor();
            let last = ((x[k] + r[k] - self.origin[k]) / self.size[k]).floor();
            if last < 0.0 {
                return;
            }
            lo[k] = first.max(0.0) as usize;
            hi[k] = (last as usize).min(self.dims[k] - 1) + 1;
        }
        for_each_index(lo, hi, |i| {
            let b = linear_index(i, self.dims);
            for &p in &self.items[self.offsets[b] as usize..self.offsets[b + 1] as usize] {
                let q = points[p as usize];
                if (0..D).all(|k| (x[k] - q[k]).abs() < r[k]) {
                    out.push(p);
                }
            }
        });
        out.sort_unstable();
    }
}

/// Shape functions of many evaluation points, compressed by rows: row `p` holds the
/// neighbours `I` of point `p` with `N_I(x_p)` and `grad N_I(x_p)` (1/m).
#[derive(Debug, Clone)]
pub struct ShapeTable<const D: usize = 2> {
    /// Row start offsets, `rows + 1` entries.
    pub offsets: Vec<u32>,
    /// Particle index of each entry.
    pub index: Vec<u32>,
    /// `N_I(x_p)`.
    pub n: Vec<Real>,
    /// `dN_I/dX_k(x_p)` for each direction `k` (1/m).
    pub grad: [Vec<Real>; D],
}

impl<const D: usize> Default for ShapeTable<D> {
    fn default() -> Self {
        ShapeTable {
            offsets: Vec::new(),
            index: Vec::new(),
            n: Vec::new(),
            grad: std::array::from_fn(|_| Vec::new()),
        }
    }
}

impl<const D: usize> ShapeTable<D> {
    /// Number of rows (evaluation points).
    pub fn rows(&self) -> usize {
        self.offsets.len() - 1
    }
    /// Entry range of row `p`.
    #[inline]
    pub fn row(&self, p: usize) -> std::ops::Range<usize> {
        self.offsets[p] as usize..self.offsets[p + 1] as usize
    }
    /// `u(x_p) = sum_I N_I(x_p) d_I`: interpolate a nodal vector field at row `p`.
    #[inline]
    pub fn interpolate(&self, p: usize, d: &[[Real; D]]) -> [Real; D] {
        let mut u = [0.0; D];
        for e in self.row(p) {
            let di = d[self.index[e] as usize];
            for k in 0..D {
                u[k] += self.n[e] * di[k];
            }
        }
        u
    }
    /// Total number of stored entries.
    pub fn entries(&self) -> usize {
        self.index.len()
    }
    /// Appends the rows of `other` after this table's.
    pub fn append(&mut self, other: ShapeTable<D>) {
        let base = self.index.len() as u32;
        self.offsets
            .extend(other.offsets[1..].iter().map(|&o| base + o));
        self.index.extend(other.index);
        self.n.extend(other.n);
        for (column, more) in self.grad.iter_mut().zip(other.grad) {
            column.extend(more);
        }
    }
    /// Frees the gradients of a table that is only interpolated: `grad` becomes empty,
    /// `n` and the rows stay.
    pub fn drop_gradients(&mut self) {
        self.grad = std::array::from_fn(|_| Vec::new());
    }

    /// An empty table with room for `rows` rows.
    fn with_rows(rows: usize) -> ShapeTable<D> {
        let mut offsets = Vec::with_capacity(rows + 1);
        offsets.push(0);
        ShapeTable {
            offsets,
            ..Default::default()
        }
    }

    /// Appends a row: the neighbours `nb` with their `(N, grad N)`.
    fn push_row(&mut self, nb: &[u32], vals: &[(Real, [Real; D])]) {
        for (&i, (n, g)) in nb.iter().zip(vals) {
            self.index.push(i);
            self.n.push(*n);
            for (column, &gk) in self.grad.iter_mut().zip(g) {
                column.push(gk);
            }
        }
        self.offsets.push(self.index.len() as u32);
    }
}

impl<const D: usize> KernelCloud<D> {
    /// A cloud of particles with volumes (m^D) and per-direction support radii (m).
    pub fn new(positions: Vec<[Real; D]>, volumes: Vec<Real>, support: [Real; D]) -> Self {
        let grid = BinGrid::new(&positions, support);
        KernelCloud {
            positions,
            volumes,
            support,
            supports: None,
            grid,
        }
    }

    /// A cloud whose particles each have their own support radii `supports` (m): the
    /// window of particle `I` is `phi_{a_I}(x - X_I)`, and `x` has the neighbours whose own
    /// support covers it (the variable-support RK approximation of Chen, Pan, Wu, Liu 1996;
    /// the reproducing conditions hold for any supports that leave `M(x)` invertible).
    pub fn with_supports(
        positions: Vec<[Real; D]>,
        volumes: Vec<Real>,
        supports: Vec<[Real; D]>,
    ) -> Self {
        let largest = supports.iter().fold([0.0 as Real; D], |m, a| {
            std::array::from_fn(|k| m[k].max(a[k]))
        });
        let grid = BinGrid::new(&positions, largest);
        KernelCloud {
            positions,
            volumes,
            support: largest,
            supports: Some(supports),
            grid,
        }
    }

    /// Evaluate `N_I` and `grad N_I` at each of `points`; `label` names a point in errors.
    pub fn shape_table(
        &self,
        points: &[[Real; D]],
        label: &dyn Fn(usize) -> String,
    ) -> Result<ShapeTable<D>> {
        let mut t = ShapeTable::with_rows(points.len());
        let (mut nb, mut offsets, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        for (p, &x) in points.iter().enumerate() {
            self.grid.query(&self.positions, x, self.support, &mut nb);
            if let Some(a) = &self.supports {
                nb.retain(|&i| covers(x, self.positions[i as usize], a[i as usize]));
            }
            offsets.clear();
            offsets.extend(nb.iter().map(|&i| {
                let xi = self.positions[i as usize];
                std::array::from_fn(|k| x[k] - xi[k])
            }));
            let result = match &self.supports {
                None => evaluate(
                    x,
                    &offsets,
                    &nb,
                    &self.volumes,
                    self.support,
                    |_| self.support,
                    &mut vals,
                ),
                Some(a) => {
                    // The basis is scaled by the neighbours' mean support (conditioning only).
                    let scale = mean_support(&nb, a);
                    evaluate(
                        x,
                        &offsets,
                        &nb,
                        &self.volumes,
                        scale,
                        |i| a[i as usize],
                        &mut vals,
                    )
                }
            };
            result.map_err(|m| Error::ShapeFunctions(format!("{}: {m}", label(p))))?;
            t.push_row(&nb, &vals);
        }
        Ok(t)
    }
}

/// Whether `x` (m) lies strictly inside the support `a` (m, per direction) of the particle
/// at `xi` (m): `|x_k - X_k| < a_k` in every direction, where the window of
/// [`crate::kernel`] (a cubic B-spline per direction) is nonzero.
#[inline]
fn covers<const D: usize>(x: [Real; D], xi: [Real; D], a: [Real; D]) -> bool {
    (0..D).all(|k| (x[k] - xi[k]).abs() < a[k])
}

/// Grows the per-particle support radii `supports` (m) of the particles at `positions` (m)
/// so that each of `sites` (m) lies strictly inside the supports of at least `min`
/// particles. At a site with fewer, its `min` nearest particles (Euclidean distance, ties
/// by index) take `a_k = max(a_k, s |x_k - X_k|)` in each direction `k`, `s` the scene's
/// support in spacings: the site becomes to them what a lattice neighbour is at a distance
/// of one spacing. Sites are visited in order, so the result is deterministic. Returns how
/// many sites were short.
///
/// A re-referenced kernel sizes each support from the particle's deformed cell
/// (`solver::rereference`); where the material thins to a sheet or a particle runs out
/// ahead of its neighbours (a flash's tip), that cell can miss the neighbours, and `M(x)`
/// would be singular. `min = 2^D`, the coverage of a corner particle of the starting
/// lattice, is the floor the callers use.
pub fn cover_sites<const D: usize>(
    positions: &[[Real; D]],
    supports: &mut [[Real; D]],
    sites: &[[Real; D]],
    min: usize,
    s: [Real; D],
) -> usize {
    if positions.len() < min {
        return 0;
    }
    let mut largest = supports.iter().fold([0.0 as Real; D], |m, a| {
        std::array::from_fn(|k| m[k].max(a[k]))
    });
    let grid = BinGrid::new(positions, largest);
    let (mut short, mut nb) = (0, Vec::new());
    for &x in sites {
        grid.query(positions, x, largest, &mut nb);
        let covering = nb
            .iter()
            .filter(|&&i| covers(x, positions[i as usize], supports[i as usize]))
            .count();
        if covering >= min {
            continue;
        }
        short += 1;
        // The nearest `min`: a box query of half-width `r` holds every particle nearer
        // than `min_k r_k` (Euclidean), so a `min`-th nearest inside that distance has no
        // nearer or tied particle left out.
        let mut r = largest;
        let nearest = loop {
            grid.query(positions, x, r, &mut nb);
            let mut by_distance: Vec<(Real, u32)> = nb
                .iter()
                .map(|&i| {
                    let xi = positions[i as usize];
                    ((0..D).map(|k| (x[k] - xi[k]).powi(2)).sum::<Real>(), i)
                })
                .collect();
            by_distance.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let reach = r.iter().copied().fold(Real::INFINITY, Real::min);
            if by_distance.len() >= min && by_distance[min - 1].0 < reach * reach {
                break by_distance;
            }
            r = r.map(|v| 2.0 * v);
        };
        for &(_, i) in &nearest[..min] {
            let (xi, a) = (positions[i as usize], &mut supports[i as usize]);
            for k in 0..D {
                a[k] = a[k].max(s[k] * (x[k] - xi[k]).abs());
                largest[k] = largest[k].max(a[k]);
            }
        }
    }
    short
}

/// The largest condition `lambda_max / lambda_min` (-) of the moment matrix `M(x)` that
/// [`condition_sites`] leaves at a re-referenced kernel's sites. A site of a box lattice
/// measures 9-23 (supports of 1.5-2 spacings); where it passes 1e3 the covering particles
/// lie nearly on a plane (a line in 2D) and the shape functions' gradients across it grow as
/// the condition does. The conrod's 0.5 mm grid measured 17-85 at its steepest sites through
/// its fourteenth re-reference, up to 620 at the fifteenth and 1.7e3-1.7e4 at the sixteenth,
/// with `sum_I |N_I|` up to 18 and `sum_I |grad N_I|` 90 times the median site's.
pub const MAX_CONDITION: Real = 1e3;

/// How many times [`condition_sites`] visits the sites at most.
const CONDITION_PASSES: usize = 4;

/// Grows the per-particle support radii `supports` (m) of the particles at `positions` (m,
/// volumes `volumes`, m^D) until the moment matrix at each of `sites` (m) has a condition of
/// at most `limit`: at a site above it, the particles whose supports do not yet cover it take
/// `a_k = max(a_k, s |x_k - X_k|)` one at a time, nearest first (Euclidean, ties by index),
/// until the condition is met or no particle within the largest support (in any direction)
/// is left. A support grown for one site also reaches others and changes their basis scale,
/// so the sites are visited again, in order, until none is above (at most
/// [`CONDITION_PASSES`] times); the result is deterministic. Returns how many sites were
/// above.
///
/// Each covering particle adds a positive semi-definite term to `M` (paper eq. 3), but it
/// also moves the basis scale and `lambda_max`, so a site met once is checked again. A
/// re-referenced kernel sizes each support along the axes from the particle's deformed cell
/// (`solver::rereference`); where the material is sheared into a thin sheet that is not
/// along an axis, the neighbours across it can lie outside those axis-aligned supports while
/// enough particles along it still cover the site ([`cover_sites`] counts them), and `M(x)`
/// is then nearly singular across the sheet.
pub fn condition_sites<const D: usize>(
    positions: &[[Real; D]],
    volumes: &[Real],
    supports: &mut [[Real; D]],
    sites: &[[Real; D]],
    limit: Real,
    s: [Real; D],
) -> usize {
    let mut largest = supports.iter().fold([0.0 as Real; D], |m, a| {
        std::array::from_fn(|k| m[k].max(a[k]))
    });
    let grid = BinGrid::new(positions, largest);
    let (mut above, mut nb) = (vec![false; sites.len()], Vec::new());
    for _ in 0..CONDITION_PASSES {
        let mut any = false;
        for (site, &x) in sites.iter().enumerate() {
            grid.query(positions, x, largest, &mut nb);
            nb.retain(|&i| covers(x, positions[i as usize], supports[i as usize]));
            let mut covering = nb.clone();
            let condition_now = |covering: &[u32], supports: &[[Real; D]]| {
                condition(x, covering, positions, volumes, supports)
            };
            if condition_now(&covering, supports) <= limit {
                continue;
            }
            (above[site], any) = (true, true);
            // The particles that could reach `x`: within the largest support in any direction
            // (the one missing may be the direction whose supports are short).
            let reach = largest.iter().copied().fold(0.0, Real::max);
            grid.query(positions, x, [reach; D], &mut nb);
            let mut rest: Vec<u32> = nb
                .iter()
                .copied()
                .filter(|&i| !covers(x, positions[i as usize], supports[i as usize]))
                .collect();
            let distance = |i: u32| {
                let xi = positions[i as usize];
                (0..D).map(|k| (x[k] - xi[k]).powi(2)).sum::<Real>()
            };
            rest.sort_by(|&a, &b| distance(a).total_cmp(&distance(b)).then(a.cmp(&b)));
            for i in rest {
                let (xi, a) = (positions[i as usize], &mut supports[i as usize]);
                for k in 0..D {
                    a[k] = a[k].max(s[k] * (x[k] - xi[k]).abs());
                    largest[k] = largest[k].max(a[k]);
                }
                covering.push(i);
                covering.sort_unstable();
                if condition_now(&covering, supports) <= limit {
                    break;
                }
            }
        }
        if !any {
            break;
        }
    }
    above.iter().filter(|&&a| a).count()
}

/// The condition `lambda_max / lambda_min` (-) of the moment matrix `M(x)` at `x` (m) of the
/// neighbours `nb`, built as [`KernelCloud::shape_table`] builds it (the basis scaled by the
/// neighbours' mean support); infinite where `M` is singular or there are too few neighbours.
fn condition<const D: usize>(
    x: [Real; D],
    nb: &[u32],
    positions: &[[Real; D]],
    volumes: &[Real],
    supports: &[[Real; D]],
) -> Real {
    let scale = mean_support(nb, supports);
    let terms = nb.iter().map(|&i| {
        let xi = positions[i as usize];
        let d: [Real; D] = std::array::from_fn(|k| x[k] - xi[k]);
        let (phi, _) = window(d, supports[i as usize]);
        (d, phi * volumes[i as usize])
    });
    let extremes = match D {
        2 => {
            let eig = moment_matrix::<D, 3>(terms, scale).symmetric_eigenvalues();
            (eig.min(), eig.max())
        }
        3 => {
            let eig = moment_matrix::<D, 4>(terms, scale).symmetric_eigenvalues();
            (eig.min(), eig.max())
        }
        _ => (0.0, 1.0),
    };
    match extremes {
        (lo, hi) if nb.len() > D && lo > 0.0 => hi / lo,
        _ => Real::INFINITY,
    }
}

/// The moment matrix `M = sum_I H_I H_I^T w_I` over `terms` `(x - X_I, phi_I V_I)`,
/// `H_I = [1, -(x - X_I)_k / scale_k]`, `N = D + 1`.
fn moment_matrix<const D: usize, const N: usize>(
    terms: impl Iterator<Item = ([Real; D], Real)>,
    scale: [Real; D],
) -> SMatrix<Real, N, N> {
    let mut m = SMatrix::<Real, N, N>::zeros();
    for (d, w) in terms {
        let h = basis::<D, N>(d, scale);
        m += h * h.transpose() * w;
    }
    m
}

/// The linear basis `H(X_I - x) = [1, -(x - X_I)_k / scale_k]` (-) at the offset
/// `d = x - X_I` (m), scaled by `scale` (m) for conditioning, `N = D + 1`.
fn basis<const D: usize, const N: usize>(d: [Real; D], scale: [Real; D]) -> SVector<Real, N> {
    SVector::from_fn(|r, _| {
        if r == 0 {
            1.0
        } else {
            -d[r - 1] / scale[r - 1]
        }
    })
}

/// The mean of the support radii `supports` (m) of the neighbours `nb`, per direction: the
/// scale of a variable-support cloud's basis.
fn mean_support<const D: usize>(nb: &[u32], supports: &[[Real; D]]) -> [Real; D] {
    let n = nb.len().max(1) as Real;
    nb.iter().fold([0.0; D], |s, &i| {
        let ai = supports[i as usize];
        std::array::from_fn(|k| s[k] + ai[k] / n)
    })
}

/// A point of a [`Lattice`] given by a particle and its offset from it: the position is
/// `X_node + offset` (m). Shape functions at a site depend only on the offsets to the
/// neighbours, which are formed from whole multiples of the spacing, so two sites with
/// the same offset and the same neighbourhood (any two away from the boundary) get the
/// same bits wherever they lie: their stored blocks can be shared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Site<const D: usize = 2> {
    /// Lattice indices `(i, j[, k])` of the particle.
    pub node: [usize; D],
    /// Offset from the particle (m).
    pub offset: [Real; D],
}

/// The particles of a box workpiece: `n[0] x n[1] (x n[2])` particles at
/// `X_i = origin + (i_0 h_0, i_1 h_1, ...)`, numbered `i_0 + n_0 (i_1 + n_1 i_2)`, with
/// volumes `prod_k h_k` (m^D), halved once per direction in which the particle lies on
/// the boundary (on a face, edge, corner), so that they sum to the box's measure.
#[derive(Debug, Clone)]
pub struct Lattice<const D: usize = 2> {
    cloud: KernelCloud<D>,
    origin: [Real; D],
    h: [Real; D],
    n: [usize; D],
}

impl<const D: usize> Lattice<D> {
    /// The lattice with lowest particle at `origin` (m), spacings `h` (m), `n` particles
    /// per direction and kernel support radii `support` (m).
    pub fn new(origin: [Real; D], h: [Real; D], n: [usize; D], support: [Real; D]) -> Self {
        let count = n.iter().product();
        let mut positions = Vec::with_capacity(count);
        let mut volumes = Vec::with_capacity(count);
        for_each_index([0; D], n, |i| {
            positions.push(std::array::from_fn(|k| origin[k] + i[k] as Real * h[k]));
            let mut v = h[0];
            for &hk in &h[1..] {
                v *= hk;
            }
            for k in 0..D {
                v *= if i[k] == 0 || i[k] == n[k] - 1 {
                    0.5
                } else {
                    1.0
                };
            }
            volumes.push(v);
        });
        Lattice {
            cloud: KernelCloud::new(positions, volumes, support),
            origin,
            h,
            n,
        }
    }

    /// The particles as a general cloud.
    pub fn cloud(&self) -> &KernelCloud<D> {
        &self.cloud
    }

    /// Particle spacings `h_k` (m).
    pub fn spacing(&self) -> [Real; D] {
        self.h
    }

    /// Particles per direction.
    pub fn dims(&self) -> [usize; D] {
        self.n
    }

    /// Position of a site (m).
    pub fn position(&self, s: Site<D>) -> [Real; D] {
        std::array::from_fn(|k| self.origin[k] + s.node[k] as Real * self.h[k] + s.offset[k])
    }

    /// Evaluate `N_I` and `grad N_I` at each site, with the neighbour offsets
    /// `x - X_I = (node - I) h + offset` formed from lattice indices; `label` names a site
    /// in errors. Neighbours are the particles with `|x - X_I| < a` per direction, in
    /// ascending index order, as for [`KernelCloud::shape_table`].
    pub fn shape_table(
        &self,
        sites: &[Site<D>],
        label: &dyn Fn(usize) -> String,
    ) -> Result<ShapeTable<D>> {
        let mut t = ShapeTable::with_rows(sites.len());
        let (mut nb, mut offsets, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        let a = self.cloud.support;
        for (p, s) in sites.iter().enumerate() {
            // Index range per direction that can lie within the support.
            let (mut lo, mut hi) = ([0; D], [0; D]);
            for k in 0..D {
                let reach = ((a[k] + s.offset[k].abs()) / self.h[k]).ceil() as usize + 1;
                lo[k] = s.node[k].saturating_sub(reach);
                hi[k] = (s.node[k] + reach + 1).min(self.n[k]);
            }
            nb.clear();
            offsets.clear();
            for_each_index(lo, hi, |i| {
                let d: [Real; D] = std::array::from_fn(|k| {
                    (s.node[k] as Real - i[k] as Real) * self.h[k] + s.offset[k]
                });
                if (0..D).all(|k| d[k].abs() < a[k]) {
                    nb.push(linear_index(i, self.n) as u32);
                    offsets.push(d);
                }
            });
            evaluate(
                self.position(*s),
                &offsets,
                &nb,
                &self.cloud.volumes,
                a,
                |_| a,
                &mut vals,
            )
            .map_err(|m| Error::ShapeFunctions(format!("{}: {m}", label(p))))?;
            t.push_row(&nb, &vals);
        }
        Ok(t)
    }
}

/// `(N_I, grad N_I)` (-, 1/m) at `x` (m, named in errors) for the neighbours `nb` with
/// offsets `d_I = x - X_I` (m), volumes `volumes[I]` (m^D) and support radii `support(I)`
/// (m), paper eqs. (2)-(3), the basis `H` scaled by `scale` (m).
///
/// Stable Rust cannot name the basis size `D + 1` from `D` in a generic context, so this
/// dispatches once to [`moments`] with it; the conditioning check takes the eigenvalues of
/// the `3 x 3` (2D) or `4 x 4` (3D) moment matrix with nalgebra's
/// `symmetric_eigenvalues`.
fn evaluate<const D: usize>(
    x: [Real; D],
    d: &[[Real; D]],
    nb: &[u32],
    volumes: &[Real],
    scale: [Real; D],
    support: impl Fn(u32) -> [Real; D],
    out: &mut Vec<(Real, [Real; D])>,
) -> std::result::Result<(), String> {
    match D {
        2 => moments::<D, 3>(x, d, nb, volumes, scale, support, out, |m| {
            let eig = m.symmetric_eigenvalues();
            (eig.min(), eig.max())
        }),
        3 => moments::<D, 4>(x, d, nb, volumes, scale, support, out, |m| {
            let eig = m.symmetric_eigenvalues();
            (eig.min(), eig.max())
        }),
        _ => Err(format!(
            "RK shape functions are built for 2 or 3 dimensions, not {D}"
        )),
    }
}

/// [`evaluate`] with the basis size `N = D + 1`: the moment matrix `M` and its
/// derivatives `dM/dx_k` summed over the neighbours, `M` factored (Cholesky) after the
/// conditioning check `lambda_min > 1e-10 lambda_max` on the eigenvalue extremes that
/// `eigen_extremes` returns, then `b = M^{-1} H(0)`, `db/dx_k = -M^{-1} (dM/dx_k) b` and
/// `N_I = b . H_I phi_I V_I`, `dN_I/dx_k = (db/dx_k . H_I + b . dH_I/dx_k) phi_I V_I +
/// b . H_I dphi_I/dx_k V_I`.
#[allow(clippy::too_many_arguments)]
fn moments<const D: usize, const N: usize>(
    x: [Real; D],
    d: &[[Real; D]],
    nb: &[u32],
    volumes: &[Real],
    scale: [Real; D],
    support: impl Fn(u32) -> [Real; D],
    out: &mut Vec<(Real, [Real; D])>,
    eigen_extremes: impl Fn(&SMatrix<Real, N, N>) -> (Real, Real),
) -> std::result::Result<(), String> {
    assert_eq!(N, D + 1, "the linear basis has D + 1 terms");
    out.clear();
    if nb.len() < N {
        return Err(format!(
            "only {} particles within the kernel support at {} m; a linear basis needs {N} (increase the support)",
            nb.len(),
            coordinates(x),
        ));
    }
    let mut m = SMatrix::<Real, N, N>::zeros();
    let mut mg = [SMatrix::<Real, N, N>::zeros(); D];
    // Derivatives of H(X_I - x) with respect to x_k.
    let hg: [SVector<Real, N>; D] = std::array::from_fn(|k| {
        let mut v = SVector::zeros();
        v[k + 1] = -1.0 / scale[k];
        v
    });
    let basis = |d: [Real; D]| basis::<D, N>(d, scale);
    for (&i, &di) in nb.iter().zip(d) {
        let v = volumes[i as usize];
        let (phi, g) = window(di, support(i));
        let h = basis(di);
        let hh = h * h.transpose();
        m += hh * (phi * v);
        for k in 0..D {
            mg[k] += (hg[k] * h.transpose() + h * hg[k].transpose()) * (phi * v) + hh * (g[k] * v);
        }
    }
    // Conditioning check before inversion: a (near-)singular moment matrix means the
    // neighbours are collinear (in 3D coplanar) or too few.
    let chol = m.cholesky().ok_or_else(|| {
        format!(
            "moment matrix is singular at {} m ({} neighbours); increase the support",
            coordinates(x),
            nb.len()
        )
    })?;
    let (lmin, lmax) = eigen_extremes(&m);
    if lmin <= 1e-10 * lmax {
        return Err(format!(
            "moment matrix is ill-conditioned (condition {:.1e}) at {} m; increase the support",
            lmax / lmin,
            coordinates(x),
        ));
    }
    let mut e0 = SVector::<Real, N>::zeros();
    e0[0] = 1.0;
    let b = chol.solve(&e0);
    let bg: [SVector<Real, N>; D] = std::array::from_fn(|k| -chol.solve(&(mg[k] * b)));
    for (&i, &di) in nb.iter().zip(d) {
        let v = volumes[i as usize];
        let (phi, g) = window(di, support(i));
        let h = basis(di);
        let c = b.dot(&h);
        let n = c * phi * v;
        let dn = std::array::from_fn(|k| (bg[k].dot(&h) + b.dot(&hg[k])) * phi * v + c * g[k] * v);
        out.push((n, dn));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid with halved volumes on the edges, to exercise the correction there.
    fn cloud(nx: usize, ny: usize, hx: Real, hy: Real, s: Real) -> KernelCloud {
        Lattice::new([0.0, 0.0], [hx, hy], [nx, ny], [s * hx, s * hy])
            .cloud()
            .clone()
    }

    /// The lattice path finds the cloud's neighbours and values (to round-off), and two
    /// interior sites with the same offset get the same bits wherever they lie.
    #[test]
    fn lattice_sites_match_the_cloud_and_repeat_their_bits_inside() {
        let h = [0.16e-3, 0.648e-3];
        let l = Lattice::new([1.3e-3, -0.7e-3], h, [15, 17], [2.0 * h[0], 2.0 * h[1]]);
        let offsets = [
            [0.0, 0.0],
            [0.3e-4, 0.2e-3],
            [-0.08e-3, 0.324e-3],
            [0.1e-3, -0.5e-3],
        ];
        let nodes = [[0, 0], [7, 8], [10, 11], [14, 16], [3, 12]];
        let sites: Vec<Site> = nodes
            .iter()
            .flat_map(|&node| offsets.iter().map(move |&offset| Site { node, offset }))
            .collect();
        let t = l.shape_table(&sites, &|p| format!("site {p}")).unwrap();
        let x: Vec<[Real; 2]> = sites.iter().map(|&s| l.position(s)).collect();
        let c = l
            .cloud()
            .shape_table(&x, &|p| format!("point {p}"))
            .unwrap();
        // A particle exactly one support radius away has a zero window: the lattice
        // leaves it out, the cloud may keep it from rounding in the absolute offsets.
        let value = |t: &ShapeTable, p: usize, i: u32| {
            t.row(p).find(|&e| t.index[e] == i).map_or([0.0; 3], |e| {
                [t.n[e], t.grad[0][e] * h[0], t.grad[1][e] * h[1]]
            })
        };
        for p in 0..sites.len() {
            for &i in &c.index[c.row(p)] {
                let (a, b) = (value(&t, p, i), value(&c, p, i));
                assert!(
                    (0..3).all(|k| (a[k] - b[k]).abs() < 1e-12),
                    "site {p}, particle {i}"
                );
            }
            assert!(t.row(p).all(|e| c.index[c.row(p)].contains(&t.index[e])));
        }
        // Sites 4..8 sit at node (7, 8), sites 8..12 at node (10, 11).
        for k in 0..offsets.len() {
            let (a, b) = (t.row(4 + k), t.row(8 + k));
            for v in [&t.n, &t.grad[0], &t.grad[1]] {
                let bits = |r: std::ops::Range<usize>| -> Vec<u64> {
                    v[r].iter().map(|x| x.to_bits()).collect()
                };
                assert_eq!(bits(a.clone()), bits(b.clone()), "offset {k}");
            }
        }
    }

    #[test]
    fn reproduces_constant_and_linear_fields_with_gradients_everywhere() {
        for &s in &[1.5, 2.0, 2.5] {
            let (nx, ny, hx, hy) = (7, 9, 0.16e-3, 0.648e-3);
            let c = cloud(nx, ny, hx, hy, s);
            // Sample points over the whole domain including edges and corners.
            let mut pts = Vec::new();
            for j in 0..=24 {
                for i in 0..=18 {
                    pts.push([
                        i as Real / 18.0 * (nx - 1) as Real * hx,
                        j as Real / 24.0 * (ny - 1) as Real * hy,
                    ]);
                }
            }
            let t = c.shape_table(&pts, &|p| format!("sample {p}")).unwrap();
            for (p, x) in pts.iter().enumerate() {
                let (mut s0, mut sx, mut sy) = (0.0, 0.0, 0.0);
                let (mut g0x, mut g0y) = (0.0, 0.0);
                let (mut gxx, mut gxy, mut gyx, mut gyy) = (0.0, 0.0, 0.0, 0.0);
                for e in t.row(p) {
                    let xi = c.positions[t.index[e] as usize];
                    s0 += t.n[e];
                    sx += t.n[e] * xi[0];
                    sy += t.n[e] * xi[1];
                    g0x += t.grad[0][e];
                    g0y += t.grad[1][e];
                    gxx += t.grad[0][e] * xi[0];
                    gxy += t.grad[1][e] * xi[0];
                    gyx += t.grad[0][e] * xi[1];
                    gyy += t.grad[1][e] * xi[1];
                }
                let scale = 1e-3; // lengths relative to 1 mm
                assert!(
                    (s0 - 1.0).abs() < 1e-10,
                    "partition of unity at {x:?}: {s0}"
                );
                assert!((sx - x[0]).abs() < 1e-10 * scale, "x at {x:?}");
                assert!((sy - x[1]).abs() < 1e-10 * scale, "y at {x:?}");
                // Gradients in 1/m: compare against 1/h.
                assert!(
                    g0x.abs() * hx < 1e-10 && g0y.abs() * hy < 1e-10,
                    "grad 1 at {x:?}"
                );
                assert!(
                    (gxx - 1.0).abs() < 1e-10 && (gyy - 1.0).abs() < 1e-10,
                    "grad x at {x:?}"
                );
                assert!(
                    gxy.abs() < 1e-10 && gyx.abs() < 1e-10,
                    "cross grad at {x:?}"
                );
            }
        }
    }

    /// A 4 x 4 x 4 lattice of spacing 1 with supports of 2, and a particle run out 3.5
    /// spacings ahead of one face (a flash's tip): only its own support covers it, so its
    /// shape functions cannot be built. `cover_sites` grows the supports of its 8 nearest
    /// particles (itself among them, already covering it) and no others, after which it and
    /// every particle reproduce a linear field; where every site is covered, nothing
    /// changes.
    #[test]
    fn cover_sites_reaches_a_particle_run_out_of_its_neighbours_supports() {
        let mut positions: Vec<[Real; 3]> = Vec::new();
        for k in 0..4 {
            for j in 0..4 {
                for i in 0..4 {
                    positions.push([i as Real, j as Real, k as Real]);
                }
            }
        }
        let lattice = positions.len();
        let mut supports = vec![[2.0; 3]; lattice];
        let unchanged = supports.clone();
        assert_eq!(
            cover_sites(&positions, &mut supports, &positions, 8, [2.0; 3]),
            0
        );
        assert_eq!(supports, unchanged);
        positions.push([6.5, 1.5, 1.2]);
        supports.push([2.0; 3]);
        let volumes = vec![1.0; positions.len()];
        let short =
            KernelCloud::with_supports(positions.clone(), volumes.clone(), supports.clone())
                .shape_table(&positions, &|p| format!("particle {p}"));
        assert!(short.is_err());
        assert_eq!(
            cover_sites(&positions, &mut supports, &positions, 8, [2.0; 3]),
            1
        );
        // Its 8 nearest are itself and 7 on the face x = 3: (y, z) = (1, 1), (2, 1),
        // (1, 2), (2, 2), (1, 0), (2, 0), and of the tie (0, 1) / (3, 1) the lower index.
        let grown: Vec<usize> = (0..lattice).filter(|&i| supports[i] != [2.0; 3]).collect();
        assert_eq!(grown, [7, 11, 19, 23, 27, 39, 43]);
        for &i in &grown {
            assert_eq!(positions[i][0], 3.0);
            assert_eq!(supports[i][0], 2.0 * 3.5);
        }
        let t = KernelCloud::with_supports(positions.clone(), volumes, supports)
            .shape_table(&positions, &|p| format!("particle {p}"))
            .unwrap();
        for (p, x) in positions.iter().enumerate() {
            let mut sum = [0.0; 4];
            for e in t.row(p) {
                let xi = positions[t.index[e] as usize];
                sum[0] += t.n[e];
                for k in 0..3 {
                    sum[k + 1] += t.n[e] * xi[k];
                }
            }
            assert!((sum[0] - 1.0).abs() < 1e-10, "partition of unity at {x:?}");
            for k in 0..3 {
                assert!((sum[k + 1] - x[k]).abs() < 1e-9, "linear field at {x:?}");
            }
        }
    }

    /// Two sheets of particles one spacing apart, each support reaching 0.9 spacings across:
    /// every site on the lower sheet is covered by at least 9 particles, all on its own
    /// sheet, so [`cover_sites`] finds nothing short while `M` is singular across the sheet
    /// (the 0.5 mm conrod's sheared flash, along the axes). [`condition_sites`] grows the
    /// supports of the upper sheet's nearest particles until every condition is within
    /// [`MAX_CONDITION`]; the shape functions then reproduce linear fields with their
    /// gradients. On a lattice with supports of two spacings it changes nothing.
    #[test]
    fn condition_sites_reaches_across_a_sheet_the_supports_miss() {
        let lattice: Vec<[Real; 3]> = (0..64)
            .map(|i| [(i % 4) as Real, ((i / 4) % 4) as Real, (i / 16) as Real])
            .collect();
        let mut supports = vec![[2.0; 3]; lattice.len()];
        let volumes = vec![1.0; lattice.len()];
        assert_eq!(
            condition_sites(
                &lattice,
                &volumes,
                &mut supports,
                &lattice,
                MAX_CONDITION,
                [2.0; 3]
            ),
            0
        );
        assert_eq!(supports, vec![[2.0; 3]; lattice.len()]);

        let positions: Vec<[Real; 3]> = (0..72)
            .map(|i| [(i % 6) as Real, ((i / 6) % 6) as Real, (i / 36) as Real])
            .collect();
        let mut supports = vec![[2.5, 2.5, 0.9]; positions.len()];
        let volumes = vec![1.0; positions.len()];
        let lower: Vec<[Real; 3]> = positions[..36].to_vec();
        assert_eq!(
            cover_sites(&positions, &mut supports, &positions, 8, [2.0; 3]),
            0
        );
        let before =
            KernelCloud::with_supports(positions.clone(), volumes.clone(), supports.clone())
                .shape_table(&lower, &|p| format!("particle {p}"));
        assert!(before.is_err(), "M is singular on a sheet");
        let above = condition_sites(
            &positions,
            &volumes,
            &mut supports,
            &positions,
            MAX_CONDITION,
            [2.0; 3],
        );
        // The first site of each sheet is above; supports grown for it reach later sites.
        assert!(above > 0 && above < positions.len(), "{above} sites above");
        assert!(
            supports[36..].iter().any(|a| a[2] > 0.9),
            "the upper sheet reaches down"
        );
        let cloud = KernelCloud::with_supports(positions.clone(), volumes, supports);
        for (p, &x) in positions.iter().enumerate() {
            let covering: Vec<u32> = (0..positions.len() as u32)
                .filter(|&i| {
                    covers(
                        x,
                        positions[i as usize],
                        cloud.supports.as_ref().unwrap()[i as usize],
                    )
                })
                .collect();
            let c = condition(
                x,
                &covering,
                &positions,
                &cloud.volumes,
                cloud.supports.as_ref().unwrap(),
            );
            assert!(c <= MAX_CONDITION, "condition {c:.1e} at particle {p}");
        }
        let t = cloud
            .shape_table(&positions, &|p| format!("particle {p}"))
            .unwrap();
        let field = |x: [Real; 3]| 0.3 + 1.1 * x[0] - 0.7 * x[1] + 2.3 * x[2];
        for (p, x) in positions.iter().enumerate() {
            let (mut u, mut g) = (0.0, [0.0 as Real; 3]);
            for e in t.row(p) {
                let f = field(positions[t.index[e] as usize]);
                u += t.n[e] * f;
                for (gk, grad) in g.iter_mut().zip(&t.grad) {
                    *gk += grad[e] * f;
                }
            }
            assert!((u - field(*x)).abs() < 1e-9, "value at {x:?}");
            for (k, gk) in [1.1, -0.7, 2.3].iter().enumerate() {
                assert!((g[k] - gk).abs() < 1e-8, "gradient {k} at {x:?}: {}", g[k]);
            }
        }
    }

    /// Particles with their own supports (as after a re-reference): linear fields and
    /// their gradients are still reproduced, and the gradients are the derivatives of the
    /// values.
    #[test]
    fn variable_supports_reproduce_linear_fields_with_consistent_gradients() {
        let (nx, ny, h) = (9, 7, [0.2e-3, 0.5e-3]);
        let base = cloud(nx, ny, h[0], h[1], 2.0);
        // Stretch the lattice along x by up to 2.5 and give each particle a support that
        // follows its local spacing.
        let stretch = |x: Real| x * (1.0 + 1.5 * x / ((nx - 1) as Real * h[0]));
        let positions: Vec<[Real; 2]> = base
            .positions
            .iter()
            .map(|p| [stretch(p[0]), p[1]])
            .collect();
        let supports: Vec<[Real; 2]> = base
            .positions
            .iter()
            .map(|p| {
                let local = (stretch(p[0] + 1e-9) - stretch(p[0])) / 1e-9;
                [2.0 * h[0] * local, 2.0 * h[1]]
            })
            .collect();
        let c = KernelCloud::with_supports(positions.clone(), base.volumes.clone(), supports);
        let (x_max, y_max) = (stretch((nx - 1) as Real * h[0]), (ny - 1) as Real * h[1]);
        let fd = 1e-9;
        let mut pts = Vec::new();
        for j in 0..=10 {
            for i in 0..=10 {
                let x = [i as Real / 10.0 * x_max, j as Real / 10.0 * y_max];
                pts.extend([
                    x,
                    [x[0] + fd, x[1]],
                    [x[0] - fd, x[1]],
                    [x[0], x[1] + fd],
                    [x[0], x[1] - fd],
                ]);
            }
        }
        let t = c.shape_table(&pts, &|p| format!("sample {p}")).unwrap();
        let value = |p: usize, i: u32| t.row(p).find(|&e| t.index[e] == i).map_or(0.0, |e| t.n[e]);
        for p in (0..pts.len()).step_by(5) {
            let (mut s0, mut sx, mut sy, mut gxx, mut gyy) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for e in t.row(p) {
                let (i, xi) = (t.index[e], positions[t.index[e] as usize]);
                s0 += t.n[e];
                sx += t.n[e] * xi[0];
                sy += t.n[e] * xi[1];
                gxx += t.grad[0][e] * xi[0];
                gyy += t.grad[1][e] * xi[1];
                let dx = (value(p + 1, i) - value(p + 2, i)) / (2.0 * fd);
                let dy = (value(p + 3, i) - value(p + 4, i)) / (2.0 * fd);
                assert!(
                    (dx - t.grad[0][e]).abs() * h[0] < 1e-5,
                    "dN/dx at {:?}",
                    pts[p]
                );
                assert!(
                    (dy - t.grad[1][e]).abs() * h[1] < 1e-5,
                    "dN/dy at {:?}",
                    pts[p]
                );
            }
            assert!(
                (s0 - 1.0).abs() < 1e-10,
                "partition of unity at {:?}",
                pts[p]
            );
            assert!((sx - pts[p][0]).abs() < 1e-13 && (sy - pts[p][1]).abs() < 1e-13);
            assert!((gxx - 1.0).abs() < 1e-9 && (gyy - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn gradients_match_finite_differences() {
        let c = cloud(6, 6, 1.0, 1.0, 2.0);
        let x0 = [2.3, 1.7];
        let h = 1e-6;
        let pts = vec![
            x0,
            [x0[0] + h, x0[1]],
            [x0[0] - h, x0[1]],
            [x0[0], x0[1] + h],
            [x0[0], x0[1] - h],
        ];
        let t = c.shape_table(&pts, &|p| p.to_string()).unwrap();
        let value = |p: usize, i: u32| {
            t.row(p)
                .find(|&e| t.index[e] == i)
                .map(|e| t.n[e])
                .unwrap_or(0.0)
        };
        for e in t.row(0) {
            let i = t.index[e];
            let fdx = (value(1, i) - value(2, i)) / (2.0 * h);
            let fdy = (value(3, i) - value(4, i)) / (2.0 * h);
            assert!((fdx - t.grad[0][e]).abs() < 1e-6, "particle {i}");
            assert!((fdy - t.grad[1][e]).abs() < 1e-6, "particle {i}");
        }
    }

    #[test]
    fn too_small_support_is_an_error_not_a_panic() {
        let c = cloud(4, 4, 1.0, 1.0, 0.6);
        let err = c
            .shape_table(&[[1.0, 1.0]], &|_| "point 0".into())
            .unwrap_err();
        assert!(err.to_string().contains("point 0"), "{err}");
    }

    /// A box lattice with anisotropic spacings for the 3D tests: 6 x 7 x 5 particles.
    const H3: [Real; 3] = [0.16e-3, 0.648e-3, 0.3e-3];
    const N3: [usize; 3] = [6, 7, 5];

    fn lattice3(s: Real) -> Lattice<3> {
        Lattice::new([1.3e-3, -0.7e-3, 0.2e-3], H3, N3, H3.map(|h| s * h))
    }

    /// Sites of the 3D box: per direction, the first and last particle with no offset (on
    /// the boundary) and five points inside, so that the product has interior, face, edge
    /// and corner points; with the number of directions in which each lies on the boundary.
    fn sites3() -> Vec<(Site<3>, usize)> {
        let along = |k: usize| {
            let (n, h) = (N3[k], H3[k]);
            [
                (0, 0.0),
                (0, 0.3 * h),
                (1, 0.5 * h),
                (n / 2, -0.21 * h),
                (n / 2, 0.0),
                (n - 2, 0.7 * h),
                (n - 1, 0.0),
            ]
        };
        let mut sites = Vec::new();
        for (k, &z) in along(2).iter().enumerate() {
            for (j, &y) in along(1).iter().enumerate() {
                for (i, &x) in along(0).iter().enumerate() {
                    let on_boundary = [i, j, k].iter().filter(|&&c| c == 0 || c == 6).count();
                    let site = Site {
                        node: [x.0, y.0, z.0],
                        offset: [x.1, y.1, z.1],
                    };
                    sites.push((site, on_boundary));
                }
            }
        }
        sites
    }

    /// 3D reproducing conditions (Liu, Jun, Zhang 1995; Chen, Pan, Wu, Liu 1996) at
    /// interior, face, edge and corner points of a box with anisotropic spacings, for
    /// supports of 1.5, 2 and 2.5 spacings: `sum N_I = 1`, `sum N_I X_I = x`,
    /// `sum grad N_I = 0`, `sum grad N_I (x) X_I = I`, to round-off (lengths against 1 mm,
    /// gradients against `1 / h_k`).
    #[test]
    fn reproduces_linear_fields_with_gradients_in_three_dimensions() {
        let sites = sites3();
        let mut kinds = [0; 4];
        for &(_, b) in &sites {
            kinds[b] += 1;
        }
        assert_eq!(
            kinds,
            [125, 150, 60, 8],
            "interior, face, edge, corner points"
        );
        for s in [1.5, 2.0, 2.5] {
            let l = lattice3(s);
            let only: Vec<Site<3>> = sites.iter().map(|&(site, _)| site).collect();
            let t = l.shape_table(&only, &|p| format!("site {p}")).unwrap();
            let (mut worst_x, mut worst_g): (Real, Real) = (0.0, 0.0);
            for (p, &(site, b)) in sites.iter().enumerate() {
                let x = l.position(site);
                let (mut s0, mut sx, mut g0, mut gx) = (0.0, [0.0; 3], [0.0; 3], [[0.0; 3]; 3]);
                for e in t.row(p) {
                    let xi = l.cloud().positions[t.index[e] as usize];
                    s0 += t.n[e];
                    for a in 0..3 {
                        sx[a] += t.n[e] * xi[a];
                        g0[a] += t.grad[a][e];
                        for c in 0..3 {
                            gx[c][a] += t.grad[a][e] * xi[c];
                        }
                    }
                }
                assert!(
                    (s0 - 1.0).abs() < 1e-10,
                    "s {s}, kind {b}, {x:?}: sum N = {s0}"
                );
                for a in 0..3 {
                    worst_x = worst_x.max((sx[a] - x[a]).abs() / 1e-3);
                    worst_g = worst_g.max(g0[a].abs() * H3[a]);
                    for (c, row) in gx.iter().enumerate() {
                        let i = if a == c { 1.0 } else { 0.0 };
                        worst_g = worst_g.max((row[a] - i).abs());
                    }
                }
            }
            println!("support {s}: linear field {worst_x:.1e}, gradients {worst_g:.1e}");
            assert!(worst_x < 1e-10 && worst_g < 1e-10, "support {s}");
        }
    }

    /// In 3D the lattice path finds the cloud's neighbours and values (to round-off), and
    /// two interior sites with the same offset get the same bits wherever they lie.
    #[test]
    fn lattice_sites_match_the_cloud_and_repeat_their_bits_inside_in_three_dimensions() {
        let l = Lattice::new([0.0; 3], H3, [9, 9, 9], H3.map(|h| 2.0 * h));
        let offset = [0.3e-4, -0.2e-3, 0.1e-3];
        let sites: Vec<Site<3>> = [[0, 0, 0], [4, 4, 4], [5, 4, 4], [4, 5, 3], [8, 2, 8]]
            .map(|node| Site { node, offset })
            .to_vec();
        let t = l.shape_table(&sites, &|p| format!("site {p}")).unwrap();
        let x: Vec<[Real; 3]> = sites.iter().map(|&s| l.position(s)).collect();
        let c = l
            .cloud()
            .shape_table(&x, &|p| format!("point {p}"))
            .unwrap();
        let value = |t: &ShapeTable<3>, p: usize, i: u32| {
            t.row(p).find(|&e| t.index[e] == i).map_or([0.0; 4], |e| {
                [
                    t.n[e],
                    t.grad[0][e] * H3[0],
                    t.grad[1][e] * H3[1],
                    t.grad[2][e] * H3[2],
                ]
            })
        };
        for p in 0..sites.len() {
            for &i in &c.index[c.row(p)] {
                let (a, b) = (value(&t, p, i), value(&c, p, i));
                assert!(
                    (0..4).all(|k| (a[k] - b[k]).abs() < 1e-12),
                    "site {p}, particle {i}"
                );
            }
            assert!(t.row(p).all(|e| c.index[c.row(p)].contains(&t.index[e])));
        }
        let bits = |v: &[Real], r: std::ops::Range<usize>| -> Vec<u64> {
            v[r].iter().map(|x| x.to_bits()).collect()
        };
        for q in 2..4 {
            for v in [&t.n, &t.grad[0], &t.grad[1], &t.grad[2]] {
                assert_eq!(bits(v, t.row(1)), bits(v, t.row(q)), "site {q}");
            }
        }
    }

    /// 3D gradients are the derivatives of the values: central differences at interior,
    /// face, edge and corner sites.
    #[test]
    fn gradients_match_finite_differences_in_three_dimensions() {
        let l = lattice3(2.0);
        let fd = 1e-9;
        let mut pts = Vec::new();
        for &(site, _) in sites3().iter().step_by(7) {
            let x = l.position(site);
            pts.push(x);
            for k in 0..3 {
                let (mut p, mut m) = (x, x);
                p[k] += fd;
                m[k] -= fd;
                pts.extend([p, m]);
            }
        }
        let t = l
            .cloud()
            .shape_table(&pts, &|p| format!("point {p}"))
            .unwrap();
        let value = |p: usize, i: u32| t.row(p).find(|&e| t.index[e] == i).map_or(0.0, |e| t.n[e]);
        let mut worst: Real = 0.0;
        for p in (0..pts.len()).step_by(7) {
            for e in t.row(p) {
                let i = t.index[e];
                for (k, hk) in H3.iter().enumerate() {
                    let d = (value(p + 1 + 2 * k, i) - value(p + 2 + 2 * k, i)) / (2.0 * fd);
                    worst = worst.max((d - t.grad[k][e]).abs() * hk);
                }
            }
        }
        println!("largest |finite difference - dN/dx_k| h_k: {worst:.1e}");
        assert!(worst < 1e-5, "{worst}");
    }

    /// In 3D too, a support too small for the linear basis is an error naming the point:
    /// a particle alone in its support, and a site whose neighbours all lie in one plane.
    #[test]
    fn too_small_support_in_three_dimensions_is_an_error_not_a_panic() {
        let l = Lattice::new([0.0; 3], [1.0; 3], [4, 4, 4], [0.6; 3]);
        let alone = Site {
            node: [1, 1, 1],
            offset: [0.0; 3],
        };
        let flat = Site {
            node: [1, 1, 1],
            offset: [0.5, 0.5, 0.0],
        };
        for (site, why) in [(alone, "only 1 particles"), (flat, "moment matrix")] {
            let err = l.shape_table(&[site], &|_| "site 0".into()).unwrap_err();
            let text = err.to_string();
            assert!(text.contains("site 0") && text.contains(why), "{text}");
        }
    }
}
