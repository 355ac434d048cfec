//! Reproducing kernel shape functions with a linear basis (Liu, Jun, Zhang 1995;
//! Chen, Pan, Wu, Liu 1996), paper eqs. (2)-(3):
//!
//! `N_I(x) = H(0)^T M(x)^{-1} H(X_I - x) phi_a(x - X_I) V_I`,
//! `M(x) = sum_I H(X_I - x) H(X_I - x)^T phi_a(x - X_I) V_I`,
//! `H(z) = [1, z_x / a_x, z_y / a_y]` (scaled for conditioning).
//!
//! The approximation reproduces constants and linear fields exactly, with gradients,
//! wherever `M` is invertible. Lagrangian kernel: everything is evaluated once in the
//! reference configuration and stored in compressed rows.

use crate::error::{Error, Result};
use crate::kernel::window;
use crate::math::Real;
use nalgebra::{Matrix3, Vector3};

/// The particles that carry the RK approximation, in the reference configuration.
#[derive(Debug, Clone)]
pub struct KernelCloud {
    /// Reference positions `X_I` (m).
    pub positions: Vec<[Real; 2]>,
    /// Planar particle volumes `V_I` (m^2) used as kernel weights.
    pub volumes: Vec<Real>,
    /// Support radii `(a_x, a_y)` (m), the largest of `supports` where those are given.
    pub support: [Real; 2],
    /// Each particle's own support radii `(a_x, a_y)` (m), or `None` when all share
    /// `support`.
    pub supports: Option<Vec<[Real; 2]>>,
    grid: BinGrid,
}

/// Uniform bins for the neighbour search (bin size = support radius).
#[derive(Debug, Clone)]
struct BinGrid {
    origin: [Real; 2],
    size: [Real; 2],
    dims: [usize; 2],
    offsets: Vec<u32>,
    items: Vec<u32>,
}

impl BinGrid {
    fn new(points: &[[Real; 2]], size: [Real; 2]) -> Self {
        let mut lo = [Real::INFINITY; 2];
        let mut hi = [Real::NEG_INFINITY; 2];
        for p in points {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let dims = [0, 1].map(|k| (((hi[k] - lo[k]) / size[k]).floor() as usize + 1).max(1));
        let mut counts = vec![0u32; dims[0] * dims[1] + 1];
        let bin_of = |p: &[Real; 2]| {
            let i = (((p[0] - lo[0]) / size[0]) as usize).min(dims[0] - 1);
            let j = (((p[1] - lo[1]) / size[1]) as usize).min(dims[1] - 1);
            j * dims[0] + i
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
    fn query(&self, points: &[[Real; 2]], x: [Real; 2], r: [Real; 2], out: &mut Vec<u32>) {
        out.clear();
        let range = |k: usize| {
            let lo = ((x[k] - r[k] - self.origin[k]) / self.size[k]).floor();
            let hi = ((x[k] + r[k] - self.origin[k]) / self.size[k]).floor();
            let lo = lo.max(0.0) as usize;
            let hi = if hi < 0.0 {
                None
            } else {
                Some((hi as usize).min(self.dims[k] - 1))
            };
            (lo, hi)
        };
        let (i0, i1) = range(0);
        let (j0, j1) = range(1);
        let (Some(i1), Some(j1)) = (i1, j1) else {
            return;
        };
        for j in j0..=j1 {
            for i in i0..=i1 {
                let b = j * self.dims[0] + i;
                for &p in &self.items[self.offsets[b] as usize..self.offsets[b + 1] as usize] {
                    let q = points[p as usize];
                    if (x[0] - q[0]).abs() < r[0] && (x[1] - q[1]).abs() < r[1] {
                        out.push(p);
                    }
                }
            }
        }
        out.sort_unstable();
    }
}

/// Shape functions of many evaluation points, compressed by rows: row `p` holds the
/// neighbours `I` of point `p` with `N_I(x_p)` and `grad N_I(x_p)` (1/m).
#[derive(Debug, Clone, Default)]
pub struct ShapeTable {
    /// Row start offsets, `rows + 1` entries.
    pub offsets: Vec<u32>,
    /// Particle index of each entry.
    pub index: Vec<u32>,
    /// `N_I(x_p)`.
    pub n: Vec<Real>,
    /// `dN_I/dX(x_p)`.
    pub dx: Vec<Real>,
    /// `dN_I/dY(x_p)`.
    pub dy: Vec<Real>,
}

impl ShapeTable {
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
    pub fn interpolate(&self, p: usize, d: &[[Real; 2]]) -> [Real; 2] {
        let mut u = [0.0; 2];
        for e in self.row(p) {
            let di = d[self.index[e] as usize];
            u[0] += self.n[e] * di[0];
            u[1] += self.n[e] * di[1];
        }
        u
    }
    /// Total number of stored entries.
    pub fn entries(&self) -> usize {
        self.index.len()
    }
    /// Frees the gradients of a table that is only interpolated: `dx` and `dy` become
    /// empty, `n` and the rows stay.
    pub fn drop_gradients(&mut self) {
        self.dx = Vec::new();
        self.dy = Vec::new();
    }

    /// An empty table with room for `rows` rows.
    fn with_rows(rows: usize) -> ShapeTable {
        let mut offsets = Vec::with_capacity(rows + 1);
        offsets.push(0);
        ShapeTable {
            offsets,
            ..Default::default()
        }
    }

    /// Appends a row: the neighbours `nb` with their `[N, N_x, N_y]`.
    fn push_row(&mut self, nb: &[u32], vals: &[[Real; 3]]) {
        for (&i, v) in nb.iter().zip(vals) {
            self.index.push(i);
            self.n.push(v[0]);
            self.dx.push(v[1]);
            self.dy.push(v[2]);
        }
        self.offsets.push(self.index.len() as u32);
    }
}

impl KernelCloud {
    /// A cloud of particles with planar volumes and per-direction support radii.
    pub fn new(positions: Vec<[Real; 2]>, volumes: Vec<Real>, support: [Real; 2]) -> Self {
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
        positions: Vec<[Real; 2]>,
        volumes: Vec<Real>,
        supports: Vec<[Real; 2]>,
    ) -> Self {
        let largest = supports
            .iter()
            .fold([0.0 as Real; 2], |m, a| [m[0].max(a[0]), m[1].max(a[1])]);
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
        points: &[[Real; 2]],
        label: &dyn Fn(usize) -> String,
    ) -> Result<ShapeTable> {
        let mut t = ShapeTable::with_rows(points.len());
        let (mut nb, mut offsets, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        for (p, &x) in points.iter().enumerate() {
            self.grid.query(&self.positions, x, self.support, &mut nb);
            if let Some(a) = &self.supports {
                nb.retain(|&i| {
                    let (xi, ai) = (self.positions[i as usize], a[i as usize]);
                    (x[0] - xi[0]).abs() < ai[0] && (x[1] - xi[1]).abs() < ai[1]
                });
            }
            offsets.clear();
            offsets.extend(nb.iter().map(|&i| {
                let xi = self.positions[i as usize];
                [x[0] - xi[0], x[1] - xi[1]]
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
                    let n = nb.len().max(1) as Real;
                    let scale = nb.iter().fold([0.0; 2], |s, &i| {
                        let ai = a[i as usize];
                        [s[0] + ai[0] / n, s[1] + ai[1] / n]
                    });
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

/// A point of a [`Lattice`] given by a particle and its offset from it: the position is
/// `X_node + offset` (m). Shape functions at a site depend only on the offsets to the
/// neighbours, which are formed from whole multiples of the spacing, so two sites with
/// the same offset and the same neighbourhood (any two away from the edges) get the same
/// bits wherever they lie: their stored blocks can be shared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Site {
    /// Lattice indices `(i, j)` of the particle.
    pub node: [usize; 2],
    /// Offset from the particle (m).
    pub offset: [Real; 2],
}

/// The particles of a rectangular workpiece: `n[0] x n[1]` particles at
/// `X_ij = origin + (i h_x, j h_y)`, numbered `j n[0] + i`, with volumes `h_x h_y`, halved
/// on each edge (a quarter in the corners), so that they sum to the rectangle's area.
#[derive(Debug, Clone)]
pub struct Lattice {
    cloud: KernelCloud,
    origin: [Real; 2],
    h: [Real; 2],
    n: [usize; 2],
}

impl Lattice {
    /// The lattice with lower-left particle at `origin` (m), spacings `h` (m), `n`
    /// particles per direction and kernel support radii `support` (m).
    pub fn new(origin: [Real; 2], h: [Real; 2], n: [usize; 2], support: [Real; 2]) -> Self {
        let mut positions = Vec::with_capacity(n[0] * n[1]);
        let mut volumes = Vec::with_capacity(n[0] * n[1]);
        for j in 0..n[1] {
            for i in 0..n[0] {
                positions.push([origin[0] + i as Real * h[0], origin[1] + j as Real * h[1]]);
                let fx = if i == 0 || i == n[0] - 1 { 0.5 } else { 1.0 };
                let fy = if j == 0 || j == n[1] - 1 { 0.5 } else { 1.0 };
                volumes.push(h[0] * h[1] * fx * fy);
            }
        }
        Lattice {
            cloud: KernelCloud::new(positions, volumes, support),
            origin,
            h,
            n,
        }
    }

    /// The particles as a general cloud.
    pub fn cloud(&self) -> &KernelCloud {
        &self.cloud
    }

    /// Particle spacings `(h_x, h_y)` (m).
    pub fn spacing(&self) -> [Real; 2] {
        self.h
    }

    /// Particles per direction.
    pub fn dims(&self) -> [usize; 2] {
        self.n
    }

    /// Position of a site (m).
    pub fn position(&self, s: Site) -> [Real; 2] {
        [0, 1].map(|k| self.origin[k] + s.node[k] as Real * self.h[k] + s.offset[k])
    }

    /// Evaluate `N_I` and `grad N_I` at each site, with the neighbour offsets
    /// `x - X_I = (node - I) h + offset` formed from lattice indices; `label` names a site
    /// in errors. Neighbours are the particles with `|x - X_I| < a` per direction, in
    /// ascending index order, as for [`KernelCloud::shape_table`].
    pub fn shape_table(
        &self,
        sites: &[Site],
        label: &dyn Fn(usize) -> String,
    ) -> Result<ShapeTable> {
        let mut t = ShapeTable::with_rows(sites.len());
        let (mut nb, mut offsets, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        let a = self.cloud.support;
        for (p, s) in sites.iter().enumerate() {
            // Index range per direction that can lie within the support.
            let range = |k: usize| {
                let reach = ((a[k] + s.offset[k].abs()) / self.h[k]).ceil() as usize + 1;
                s.node[k].saturating_sub(reach)..(s.node[k] + reach + 1).min(self.n[k])
            };
            let near =
                |k: usize, i: usize| (s.node[k] as Real - i as Real) * self.h[k] + s.offset[k];
            nb.clear();
            offsets.clear();
            let (ri, rj) = (range(0), range(1));
            for j in rj {
                let dy = near(1, j);
                if dy.abs() >= a[1] {
                    continue;
                }
                for i in ri.clone() {
                    let dx = near(0, i);
                    if dx.abs() < a[0] {
                        nb.push((j * self.n[0] + i) as u32);
                        offsets.push([dx, dy]);
                    }
                }
            }
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

/// `[N_I, dN_I/dx, dN_I/dy]` at `x` (m, named in errors) for the neighbours `nb` with
/// offsets `d_I = x - X_I` (m), volumes `volumes[I]` (m^2) and support radii `support(I)`
/// (m), paper eqs. (2)-(3), the basis `H` scaled by `scale` (m).
fn evaluate(
    x: [Real; 2],
    d: &[[Real; 2]],
    nb: &[u32],
    volumes: &[Real],
    scale: [Real; 2],
    support: impl Fn(u32) -> [Real; 2],
    out: &mut Vec<[Real; 3]>,
) -> std::result::Result<(), String> {
    let [ax, ay] = scale;
    out.clear();
    if nb.len() < 3 {
        return Err(format!(
            "only {} particles within the kernel support at ({:.6e}, {:.6e}) m; a linear basis needs 3 (increase the support)",
            nb.len(),
            x[0],
            x[1]
        ));
    }
    let mut m = Matrix3::zeros();
    let mut mx = Matrix3::zeros();
    let mut my = Matrix3::zeros();
    // Derivatives of H(X_I - x) with respect to x.
    let hx = Vector3::new(0.0, -1.0 / ax, 0.0);
    let hy = Vector3::new(0.0, 0.0, -1.0 / ay);
    let basis = |d: [Real; 2]| Vector3::new(1.0, -d[0] / ax, -d[1] / ay);
    for (&i, &di) in nb.iter().zip(d) {
        let v = volumes[i as usize];
        let [wx, wy] = support(i);
        let (phi, gx, gy) = window(di[0], di[1], wx, wy);
        let h = basis(di);
        let hh = h * h.transpose();
        m += hh * (phi * v);
        mx += (hx * h.transpose() + h * hx.transpose()) * (phi * v) + hh * (gx * v);
        my += (hy * h.transpose() + h * hy.transpose()) * (phi * v) + hh * (gy * v);
    }
    // Conditioning check before inversion: a (near-)singular moment matrix means the
    // neighbours are collinear or too few.
    let chol = m.cholesky().ok_or_else(|| {
        format!(
            "moment matrix is singular at ({:.6e}, {:.6e}) m ({} neighbours); increase the support",
            x[0],
            x[1],
            nb.len()
        )
    })?;
    let eig = m.symmetric_eigenvalues();
    let (lmin, lmax) = (eig.min(), eig.max());
    if lmin <= 1e-10 * lmax {
        return Err(format!(
            "moment matrix is ill-conditioned (condition {:.1e}) at ({:.6e}, {:.6e}) m; increase the support",
            lmax / lmin,
            x[0],
            x[1]
        ));
    }
    let b = chol.solve(&Vector3::new(1.0, 0.0, 0.0));
    let bx = -chol.solve(&(mx * b));
    let by = -chol.solve(&(my * b));
    for (&i, &di) in nb.iter().zip(d) {
        let v = volumes[i as usize];
        let [wx, wy] = support(i);
        let (phi, gx, gy) = window(di[0], di[1], wx, wy);
        let h = basis(di);
        let c = b.dot(&h);
        let n = c * phi * v;
        let dnx = (bx.dot(&h) + b.dot(&hx)) * phi * v + c * gx * v;
        let dny = (by.dot(&h) + b.dot(&hy)) * phi * v + c * gy * v;
        out.push([n, dnx, dny]);
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
            t.row(p)
                .find(|&e| t.index[e] == i)
                .map_or([0.0; 3], |e| [t.n[e], t.dx[e] * h[0], t.dy[e] * h[1]])
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
            for v in [&t.n, &t.dx, &t.dy] {
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
                    g0x += t.dx[e];
                    g0y += t.dy[e];
                    gxx += t.dx[e] * xi[0];
                    gxy += t.dy[e] * xi[0];
                    gyx += t.dx[e] * xi[1];
                    gyy += t.dy[e] * xi[1];
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
                gxx += t.dx[e] * xi[0];
                gyy += t.dy[e] * xi[1];
                let dx = (value(p + 1, i) - value(p + 2, i)) / (2.0 * fd);
                let dy = (value(p + 3, i) - value(p + 4, i)) / (2.0 * fd);
                assert!((dx - t.dx[e]).abs() * h[0] < 1e-5, "dN/dx at {:?}", pts[p]);
                assert!((dy - t.dy[e]).abs() * h[1] < 1e-5, "dN/dy at {:?}", pts[p]);
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
            assert!((fdx - t.dx[e]).abs() < 1e-6, "particle {i}");
            assert!((fdy - t.dy[e]).abs() < 1e-6, "particle {i}");
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
}
