//! Background-cell integration over the cells of the particle lattice: quadrilaterals in
//! 2D, hexahedra in 3D (the cell rules are generic over the dimension `D`).
//!
//! - `q4`: the 2x2 Gauss rule, points at `(+-1/sqrt3, +-1/sqrt3)`, weight 1 each; in 3D the
//!   2x2x2 Gauss rule, points at `(+-1/sqrt3, +-1/sqrt3, +-1/sqrt3)`, weight 1 each.
//! - `q2`: the paper's two-point rule (Sidibe et al. 2009, Figure 1-c; Sidibe, Li, Ouane,
//!   Sanogo 2009). The figure is not in the text; we read it as the two points on one cell
//!   diagonal at `+-(1/sqrt3, 1/sqrt3)` with weight 2 each, which integrates `1, xi, eta, xi^2,
//!   eta^2` exactly (the bilinear `xi eta` term is not: it is the price of the rule). Because
//!   RK shape functions span several cells, the assembled stiffness keeps full rank; the
//!   spurious-mode test in `tests/` checks that. In 3D the same choice, the Gauss points
//!   with an even number of negative coordinates, is the alternate half of the 2x2x2 rule:
//!   `(a, a, a)`, `(a, -a, -a)`, `(-a, a, -a)`, `(-a, -a, a)`, `a = 1/sqrt3`, weight 2 each.
//!   It integrates every monomial of degree <= 2 exactly (`xi eta` too, unlike in 2D) and of
//!   degree 3 misses only `xi eta zeta`; the stiffness of a free 3D patch keeps only the six
//!   rigid-body zero modes (tested below).
//! - `scni`: stabilized conforming nodal integration (Chen, Wu, Yoon, You 2001, IJNME 50):
//!   one point per particle over its domain (the rectangle of half spacings around it, cut at
//!   the workpiece edges); the gradient is smoothed over the domain,
//!   `B_I = (1 / A_L) int_{dA_L} N_I n dG`, which satisfies the integration constraint exactly
//!   (the linear patch test passes to round-off, also next to the boundary).

use crate::error::Result;
use crate::math::Real;
use crate::rk_shape::{for_each_index, linear_index, Lattice, ShapeTable, Site};
use crate::scene::IntegrationRule;

/// Integration points: reference positions and cell-local data.
#[derive(Debug, Clone)]
pub struct PointSet<const D: usize = 2> {
    /// Each point as a particle of the lattice and the offset from it.
    pub sites: Vec<Site<D>>,
    /// Reference positions (m).
    pub positions: Vec<[Real; D]>,
    /// Weights (m^D; planar areas in 2D): Gauss weight times the cell Jacobian.
    pub areas: Vec<Real>,
    /// Cell index `i_0 + (n_0 - 1) (i_1 + (n_1 - 1) i_2)` of each point (the lattice has
    /// `n_k` particles per direction).
    pub cells: Vec<u32>,
}

impl<const D: usize> Default for PointSet<D> {
    fn default() -> Self {
        PointSet {
            sites: Vec::new(),
            positions: Vec::new(),
            areas: Vec::new(),
            cells: Vec::new(),
        }
    }
}

impl<const D: usize> PointSet<D> {
    fn push(&mut self, lattice: &Lattice<D>, site: Site<D>, area: Real, cell: usize) {
        self.sites.push(site);
        self.positions.push(lattice.position(site));
        self.areas.push(area);
        self.cells.push(cell as u32);
    }
}

/// Gauss points `(xi, weight)` of a cell rule on the reference cube `[-1, 1]^D` (none for
/// the nodal rule). `q4` takes every point of the 2^D Gauss rule, counter-clockwise in
/// `(xi, eta)`, layer after layer in `zeta` in 3D; `q2` the ones among them with an even
/// number of negative coordinates, in the same order, with weight 2.
pub fn rule_points<const D: usize>(rule: IntegrationRule) -> Vec<([Real; D], Real)> {
    let a = 1.0 / 3.0_f64.sqrt();
    let gauss = (0..1usize << D).map(|m| {
        let negative: [bool; D] = std::array::from_fn(|k| match k {
            0 => m & 1 == (m >> 1) & 1,
            k => (m >> k) & 1 == 0,
        });
        let xi = negative.map(|neg| if neg { -a } else { a });
        (xi, negative.iter().filter(|&&neg| neg).count())
    });
    match rule {
        IntegrationRule::Q4 => gauss.map(|(xi, _)| (xi, 1.0)).collect(),
        IntegrationRule::Q2 => gauss
            .filter(|&(_, negatives)| negatives % 2 == 0)
            .map(|(xi, _)| (xi, 2.0))
            .collect(),
        IntegrationRule::Scni => vec![],
    }
}

/// Edge quadrature points per nodal domain: 3-point Gauss on each of 4 edges.
pub const SCNI_EDGE_POINTS: usize = 12;

/// Edge quadrature points per quadrant of a nodal domain: 2-point Gauss on each of its 4
/// edges (the stabilization's smoothed gradients, [`nodal_quadrants`]).
pub const QUADRANT_EDGE_POINTS: usize = 8;

/// Boundary sites of the rectangle `[x0, x1] x [y0, y1]` (offsets from `node`'s particle),
/// counter-clockwise from the bottom edge, at the points `(t, weight)` of an edge rule on
/// `[0, 1]`, with the outward normal times the weight and the edge's length (m).
fn rectangle_boundary(
    node: [usize; 2],
    [x0, x1, y0, y1]: [Real; 4],
    rule: &[(Real, Real)],
    sites: &mut Vec<Site>,
    nw: &mut Vec<[Real; 2]>,
) {
    let edges = [
        ([x0, y0], [x1, y0], [0.0, -1.0]),
        ([x1, y0], [x1, y1], [1.0, 0.0]),
        ([x1, y1], [x0, y1], [0.0, 1.0]),
        ([x0, y1], [x0, y0], [-1.0, 0.0]),
    ];
    for (a, b, n) in edges {
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        for &(t, w) in rule {
            sites.push(Site {
                node,
                offset: [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])],
            });
            nw.push([n[0] * w * len, n[1] * w * len]);
        }
    }
}

/// The nodal domain of each particle of the lattice as `[x0, x1, y0, y1]` relative to the
/// particle (m): half a spacing each way, cut at the workpiece's edges; row by row.
fn domain_bounds(lattice: &Lattice) -> impl Iterator<Item = ([usize; 2], [Real; 4])> {
    let (h, [nx, ny]) = (lattice.spacing(), lattice.dims());
    let lo = move |k: usize, i: usize| if i > 0 { -0.5 * h[k] } else { 0.0 };
    let hi = move |k: usize, i: usize, n: usize| if i + 1 < n { 0.5 * h[k] } else { 0.0 };
    (0..ny).flat_map(move |j| {
        (0..nx).map(move |i| ([i, j], [lo(0, i), hi(0, i, nx), lo(1, j), hi(1, j, ny)]))
    })
}

/// The nodal domains of SCNI: one point per particle at its domain's centroid with the
/// domain's area, and for each domain [`SCNI_EDGE_POINTS`] boundary sites with their
/// outward normal times the quadrature weight (m). Everything is formed relative to the
/// domain's particle, so interior domains get the same bits.
pub fn nodal_domains(lattice: &Lattice) -> (PointSet, Vec<Site>, Vec<[Real; 2]>) {
    let g = (0.6_f64).sqrt() / 2.0;
    let gauss = [
        (0.5 - g, 5.0 / 18.0),
        (0.5, 8.0 / 18.0),
        (0.5 + g, 5.0 / 18.0),
    ];
    smoothing_cells(lattice, |b| [b], &gauss)
}

/// The four quadrants of every nodal domain (cut through the domain's centroid), for the
/// stabilization of nodal integration: the quadrants as points (centroid, area; cell = the
/// domain's particle), domain by domain in the order lower-left, lower-right, upper-right,
/// upper-left, and [`QUADRANT_EDGE_POINTS`] boundary sites per quadrant with their outward
/// normal times the quadrature weight (m).
pub fn nodal_quadrants(lattice: &Lattice) -> (PointSet, Vec<Site>, Vec<[Real; 2]>) {
    let g = 0.5 / 3.0_f64.sqrt();
    let gauss = [(0.5 - g, 0.5), (0.5 + g, 0.5)];
    smoothing_cells(
        lattice,
        |[x0, x1, y0, y1]| {
            let (xc, yc) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
            [
                [x0, xc, y0, yc],
                [xc, x1, y0, yc],
                [xc, x1, yc, y1],
                [x0, xc, yc, y1],
            ]
        },
        &gauss,
    )
}

/// The smoothing cells that `split` cuts each nodal domain `[x0, x1, y0, y1]` (offsets
/// from its particle, m) into: each cell as a point at its centroid with its area (cell =
/// the domain's particle), domain by domain, and the Gauss points `rule` (position along
/// an edge, weight) on each cell's edges as boundary sites with their outward normal times
/// the weight (m).
fn smoothing_cells<const K: usize>(
    lattice: &Lattice,
    split: impl Fn([Real; 4]) -> [[Real; 4]; K],
    rule: &[(Real, Real)],
) -> (PointSet, Vec<Site>, Vec<[Real; 2]>) {
    let nx = lattice.dims()[0];
    let mut s = PointSet::default();
    let (mut edge_sites, mut edge_nw) = (Vec::new(), Vec::new());
    for (node, domain) in domain_bounds(lattice) {
        for b @ [a0, a1, b0, b1] in split(domain) {
            let centre = Site {
                node,
                offset: [0.5 * (a0 + a1), 0.5 * (b0 + b1)],
            };
            s.push(
                lattice,
                centre,
                (a1 - a0) * (b1 - b0),
                node[1] * nx + node[0],
            );
            rectangle_boundary(node, b, rule, &mut edge_sites, &mut edge_nw);
        }
    }
    (s, edge_sites, edge_nw)
}

/// Points of `rule` in every cell of the lattice, as offsets from the cell's lowest
/// particle, with weight `w prod_k (h_k / 2)` (m^D).
pub fn grid_points<const D: usize>(rule: IntegrationRule, lattice: &Lattice<D>) -> PointSet<D> {
    let (h, n) = (lattice.spacing(), lattice.dims());
    let jacobian = (0.5 as Real).powi(D as i32);
    let local: Vec<([Real; D], Real)> = rule_points::<D>(rule)
        .into_iter()
        .map(|(xi, w)| {
            let mut weight = w * jacobian;
            for hk in h {
                weight *= hk;
            }
            (std::array::from_fn(|k| (0.5 + 0.5 * xi[k]) * h[k]), weight)
        })
        .collect();
    let cells = n.map(|nk| nk - 1);
    let mut s = PointSet::default();
    for_each_index([0; D], cells, |node| {
        for &(offset, area) in &local {
            s.push(
                lattice,
                Site { node, offset },
                area,
                linear_index(node, cells),
            );
        }
    });
    s
}

/// The integration points of `rule` on the lattice and their shape functions.
pub fn point_shapes(lattice: &Lattice, rule: IntegrationRule) -> Result<(PointSet, ShapeTable)> {
    Ok(match rule {
        IntegrationRule::Scni => {
            let (points, edges, nw) = nodal_domains(lattice);
            let at_centre =
                lattice.shape_table(&points.sites, &|p| format!("nodal integration point {p}"))?;
            let on_edges = lattice.shape_table(&edges, &|q| {
                format!(
                    "boundary point {q} of nodal domain {}",
                    q / SCNI_EDGE_POINTS
                )
            })?;
            let pt = smoothed(Some(&at_centre), &on_edges, &nw, &points.areas);
            (points, pt)
        }
        rule => {
            let points = grid_points(rule, lattice);
            let pt = lattice.shape_table(&points.sites, &|p| {
                format!("integration point {p} (cell {})", points.cells[p])
            })?;
            (points, pt)
        }
    })
}

/// The quadrants of the nodal domains ([`nodal_quadrants`]) with their smoothed gradients
/// `B^k_I = (1 / A_k) sum_edges N_I(x_g) n w_g` (1/m; no values `N_I`).
pub fn quadrant_shapes(lattice: &Lattice) -> Result<(PointSet, ShapeTable)> {
    let (quadrants, edges, nw) = nodal_quadrants(lattice);
    let on_edges = lattice.shape_table(&edges, &|q| {
        format!(
            "boundary point {q} of quadrant {} of nodal domain {}",
            q / QUADRANT_EDGE_POINTS % 4,
            q / (4 * QUADRANT_EDGE_POINTS)
        )
    })?;
    let table = smoothed(None, &on_edges, &nw, &quadrants.areas);
    Ok((quadrants, table))
}

/// Smoothed shape table (Chen, Wu, Yoon, You 2001): per domain `L` of area `A_L`, `N_I` at
/// its centroid (from `at_centre`, or none) and the smoothed gradient
/// `B_I = (1 / A_L) sum_edges N_I(x_g) n w_g` from the domain's boundary sites (`on_edges`,
/// `nw.len() / areas.len()` consecutive rows per domain, `nw` their outward normal times
/// weight).
fn smoothed(
    at_centre: Option<&ShapeTable>,
    on_edges: &ShapeTable,
    nw: &[[Real; 2]],
    areas: &[Real],
) -> ShapeTable {
    let per_domain = nw.len() / areas.len();
    let mut t = ShapeTable {
        offsets: vec![0],
        ..Default::default()
    };
    let mut row: std::collections::BTreeMap<u32, [Real; 3]> = Default::default();
    for (p, area) in areas.iter().enumerate() {
        row.clear();
        if let Some(c) = at_centre {
            for e in c.row(p) {
                row.entry(c.index[e]).or_default()[0] = c.n[e];
            }
        }
        let first = p * per_domain;
        for (q, w) in nw.iter().enumerate().skip(first).take(per_domain) {
            for e in on_edges.row(q) {
                let v = row.entry(on_edges.index[e]).or_default();
                v[1] += on_edges.n[e] * w[0] / area;
                v[2] += on_edges.n[e] * w[1] / area;
            }
        }
        for (&i, v) in &row {
            t.index.push(i);
            if at_centre.is_some() {
                t.n.push(v[0]);
            }
            t.grad[0].push(v[1]);
            t.grad[1].push(v[2]);
        }
        t.offsets.push(t.index.len() as u32);
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Integrate a monomial over [-1,1]^2 with a rule.
    fn integrate(rule: IntegrationRule, f: impl Fn(Real, Real) -> Real) -> Real {
        rule_points(rule)
            .iter()
            .map(|&([x, y], w)| w * f(x, y))
            .sum()
    }

    #[test]
    fn q4_is_exact_for_bicubics_and_q2_for_complete_quadratics_but_xy() {
        let exact2 = |p: i32| {
            if p % 2 == 1 {
                0.0
            } else {
                2.0 / (p as Real + 1.0)
            }
        };
        for px in 0..=3 {
            for py in 0..=3 {
                let e = exact2(px) * exact2(py);
                let q4 = integrate(IntegrationRule::Q4, |x, y| x.powi(px) * y.powi(py));
                assert!((q4 - e).abs() < 1e-14, "q4 x^{px} y^{py}");
                if px + py <= 2 && !(px == 1 && py == 1) {
                    let q2 = integrate(IntegrationRule::Q2, |x, y| x.powi(px) * y.powi(py));
                    assert!((q2 - e).abs() < 1e-14, "q2 x^{px} y^{py}");
                }
            }
        }
        assert!((integrate(IntegrationRule::Q2, |x, y| x * y) - 4.0 / 3.0).abs() < 1e-14);
    }

    #[test]
    fn weights_sum_to_the_area() {
        let lattice = Lattice::new([0.0, 0.0], [0.5, 0.25], [5, 9], [1.0, 0.5]);
        for rule in [IntegrationRule::Q4, IntegrationRule::Q2] {
            let s = grid_points(rule, &lattice);
            let a: Real = s.areas.iter().sum();
            assert!((a - 2.0 * 2.0).abs() < 1e-12);
        }
        let (s, e, nw) = nodal_domains(&lattice);
        let a: Real = s.areas.iter().sum();
        assert!((a - 2.0 * 2.0).abs() < 1e-12);
        assert_eq!(e.len(), 45 * SCNI_EDGE_POINTS);
        // Each closed domain boundary: sum of n dG vanishes.
        for d in nw.chunks(SCNI_EDGE_POINTS) {
            let sx: Real = d.iter().map(|v| v[0]).sum();
            let sy: Real = d.iter().map(|v| v[1]).sum();
            assert!(sx.abs() < 1e-15 && sy.abs() < 1e-15);
        }
    }

    /// `(monomial exponents, q4 result, q2 result, exact)` for every `xi^p eta^q zeta^r`
    /// with `p, q, r <= 3` on `[-1, 1]^3`.
    fn monomials3() -> Vec<([i32; 3], Real, Real, Real)> {
        let exact1 = |p: i32| {
            if p % 2 == 1 {
                0.0
            } else {
                2.0 / (p as Real + 1.0)
            }
        };
        let integrate = |rule, e: [i32; 3]| -> Real {
            rule_points::<3>(rule)
                .iter()
                .map(|&(x, w)| w * (0..3).map(|k| x[k].powi(e[k])).product::<Real>())
                .sum()
        };
        let mut out = Vec::new();
        for p in 0..=3 {
            for q in 0..=3 {
                for r in 0..=3 {
                    let e = [p, q, r];
                    let exact = e.iter().map(|&k| exact1(k)).product();
                    out.push((
                        e,
                        integrate(IntegrationRule::Q4, e),
                        integrate(IntegrationRule::Q2, e),
                        exact,
                    ));
                }
            }
        }
        out
    }

    /// 3D cell rules on the reference cube: q4 (2x2x2 Gauss, 8 points) integrates every
    /// `xi^p eta^q zeta^r` with `p, q, r <= 3` exactly; q2 (the alternate four, weight 2)
    /// every monomial of degree <= 2 and, of degree 3, all but `xi eta zeta` (which it
    /// integrates to `8 / 3^(3/2)` instead of 0).
    #[test]
    fn q4_and_q2_in_three_dimensions_integrate_the_monomials_they_should() {
        assert_eq!(rule_points::<3>(IntegrationRule::Q4).len(), 8);
        let q2 = rule_points::<3>(IntegrationRule::Q2);
        let a = 1.0 / 3.0_f64.sqrt();
        let expected = [[a, -a, -a], [-a, a, -a], [-a, -a, a], [a, a, a]];
        assert_eq!(q2.iter().map(|&(x, _)| x).collect::<Vec<_>>(), expected);
        assert!(q2.iter().all(|&(_, w)| w == 2.0));
        let mut missed = Vec::new();
        for (e, q4, q2, exact) in monomials3() {
            assert!((q4 - exact).abs() < 1e-14, "q4 {e:?}");
            let degree: i32 = e.iter().sum();
            if (q2 - exact).abs() > 1e-14 {
                assert!(degree > 2, "q2 misses {e:?} of degree {degree}");
                if degree == 3 {
                    missed.push(e);
                }
            }
        }
        assert_eq!(missed, [[1, 1, 1]], "the degree-3 monomials q2 misses");
        let (_, _, xyz, _) = monomials3().into_iter().find(|m| m.0 == [1, 1, 1]).unwrap();
        assert!((xyz - 8.0 / 27.0_f64.sqrt()).abs() < 1e-14, "{xyz}");
    }

    #[test]
    fn weights_sum_to_the_volume_in_three_dimensions() {
        let lattice = Lattice::new([0.0; 3], [0.5, 0.25, 0.4], [5, 9, 4], [1.0, 0.5, 0.8]);
        let cells = 4 * 8 * 3;
        let volumes: Real = lattice.cloud().volumes.iter().sum();
        assert!((volumes - 2.0 * 2.0 * 1.2).abs() < 1e-12, "{volumes}");
        for (rule, per_cell) in [(IntegrationRule::Q4, 8), (IntegrationRule::Q2, 4)] {
            let s = grid_points(rule, &lattice);
            assert_eq!(s.areas.len(), cells * per_cell);
            let v: Real = s.areas.iter().sum();
            assert!((v - 2.0 * 2.0 * 1.2).abs() < 1e-12, "{rule:?}: {v}");
            assert_eq!(*s.cells.last().unwrap() as usize, cells - 1);
        }
    }

    /// A box lattice of `n` particles with spacings `h` and supports of `s` spacings, its
    /// points of `rule` and their shape functions.
    fn patch3(
        n: [usize; 3],
        h: [Real; 3],
        s: Real,
        rule: IntegrationRule,
    ) -> (Lattice<3>, PointSet<3>, ShapeTable<3>) {
        let lattice = Lattice::new([0.0; 3], h, n, h.map(|hk| s * hk));
        let points = grid_points(rule, &lattice);
        let table = lattice
            .shape_table(&points.sites, &|p| format!("point {p}"))
            .unwrap();
        (lattice, points, table)
    }

    /// 3D linear patch test: the displacement `u = A X` (any `A`) gives at every point of
    /// each rule `u(x) = A x` and the gradient `sum_I u_I (x) grad N_I = A`, so
    /// `F = I + A` everywhere, to round-off, on a box with anisotropic spacings.
    #[test]
    fn linear_patch_in_three_dimensions_gives_the_field_and_its_gradient_at_every_point() {
        let a = [
            [1e-4, 2e-4, -3e-4],
            [-0.5e-4, 3e-4, 1e-4],
            [2e-4, -1e-4, 0.7e-4],
        ];
        let displacement = |x: [Real; 3]| -> [Real; 3] {
            std::array::from_fn(|i| (0..3).map(|j| a[i][j] * x[j]).sum())
        };
        for rule in [IntegrationRule::Q4, IntegrationRule::Q2] {
            for s in [1.5, 2.0] {
                let (lattice, points, t) = patch3([5, 6, 4], [1e-3, 0.7e-3, 1.3e-3], s, rule);
                let d: Vec<[Real; 3]> = lattice
                    .cloud()
                    .positions
                    .iter()
                    .map(|&x| displacement(x))
                    .collect();
                let mut worst: Real = 0.0;
                for (p, &x) in points.positions.iter().enumerate() {
                    let u = t.interpolate(p, &d);
                    let exact = displacement(x);
                    for i in 0..3 {
                        worst = worst.max((u[i] - exact[i]).abs() / 1e-3 / 1e-4);
                        for j in 0..3 {
                            let g: Real = t
                                .row(p)
                                .map(|e| d[t.index[e] as usize][i] * t.grad[j][e])
                                .sum();
                            worst = worst.max((g - a[i][j]).abs() / 1e-4);
                        }
                    }
                }
                println!("{rule:?}, support {s}: largest relative error {worst:.1e}");
                assert!(worst < 1e-10, "{rule:?}, support {s}: {worst}");
            }
        }
    }

    /// Small-strain stiffness (Pa m, with `E` in Pa and lengths in m) of a free patch,
    /// isotropic linear elasticity `sigma = lambda tr(eps) I + 2 mu eps`:
    /// `K_{Ia,Jb} = sum_p w_p (lambda N_{I,a} N_{J,b} + mu (N_{I,b} N_{J,a} +
    /// delta_ab grad N_I . grad N_J))`, dofs `3 I + a`.
    fn stiffness3(
        points: &PointSet<3>,
        t: &ShapeTable<3>,
        particles: usize,
    ) -> nalgebra::DMatrix<Real> {
        let (e, nu) = (1.0, 0.3);
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        let mut k = nalgebra::DMatrix::zeros(3 * particles, 3 * particles);
        for (p, &w) in points.areas.iter().enumerate() {
            for e1 in t.row(p) {
                let (i, gi) = (t.index[e1] as usize, [0, 1, 2].map(|c| t.grad[c][e1]));
                for e2 in t.row(p) {
                    let (j, gj) = (t.index[e2] as usize, [0, 1, 2].map(|c| t.grad[c][e2]));
                    let dot = gi[0] * gj[0] + gi[1] * gj[1] + gi[2] * gj[2];
                    for a in 0..3 {
                        for b in 0..3 {
                            let diagonal = if a == b { dot } else { 0.0 };
                            k[(3 * i + a, 3 * j + b)] +=
                                w * (lambda * gi[a] * gj[b] + mu * (gi[b] * gj[a] + diagonal));
                        }
                    }
                }
            }
        }
        k
    }

    /// Spurious modes in 3D: the small-strain stiffness of a free box patch (5 x 5 x 5 and
    /// 4 x 5 x 6 particles, supports of 1.5 and 2 spacings) integrated with q4 or q2 from
    /// the RK gradients has exactly the six rigid-body zero eigenvalues (below `1e-8` of
    /// the largest), and the next one is clearly positive.
    #[test]
    fn no_spurious_zero_energy_modes_in_three_dimensions() {
        for rule in [IntegrationRule::Q4, IntegrationRule::Q2] {
            for (n, h) in [([5, 5, 5], [1.0; 3]), ([4, 5, 6], [1.0, 0.8, 1.25])] {
                for s in [1.5, 2.0] {
                    let (lattice, points, t) = patch3(n, h, s, rule);
                    let k = stiffness3(&points, &t, lattice.cloud().positions.len());
                    let mut ev: Vec<Real> = k.symmetric_eigenvalues().iter().copied().collect();
                    ev.sort_by(Real::total_cmp);
                    let max = ev[ev.len() - 1];
                    let zeros = ev.iter().filter(|e| e.abs() < 1e-8 * max).count();
                    let first = ev[6] / max;
                    println!("{rule:?} {n:?} support {s}: {zeros} zero eigenvalues, smallest deformation mode {first:.3e} of the largest");
                    assert_eq!(zeros, 6, "{rule:?} {n:?} support {s}: {:?}", &ev[..8]);
                    assert!(
                        first > 1e-4,
                        "{rule:?} {n:?} support {s}: near-zero mode {first:e}"
                    );
                    assert!(ev[0] > -1e-8 * max, "negative eigenvalue {}", ev[0]);
                }
            }
        }
    }
}
