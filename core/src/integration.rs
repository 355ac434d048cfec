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
//!   one point per particle over its domain (the rectangle, in 3D the box, of half spacings
//!   around it, cut at the workpiece's boundary); the gradient is smoothed over the domain,
//!   `B_I = (1 / A_L) int_{dA_L} N_I n dG` (3-point Gauss per edge, 3x3 per face in 3D),
//!   which satisfies the integration constraint exactly (the linear patch test passes to
//!   round-off, also next to the boundary; tested in 3D below). The stabilization of nodal
//!   integration smooths the gradient over each orthant of a domain as well (quadrants in
//!   2D, octants in 3D: [`orthant_shapes`]).

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

/// Edge quadrature points per nodal domain in 2D: 3-point Gauss on each of 4 edges (in
/// 3D, 3x3 Gauss on each of 6 faces: 54).
pub const SCNI_EDGE_POINTS: usize = 12;

/// Nodal domains whose boundary points are evaluated at once ([`smoothed_blocks`]): the
/// points' shape functions of a block are freed before the next (in 3D a domain has 54 of
/// them, its octants 192, each with some 60-90 particles).
const DOMAIN_BLOCK: usize = 64;

/// A face of a box: one corner, the edge vectors from it that span the face (`D - 1` of
/// them) and the outward unit normal; positions relative to the box's particle (m).
struct Face<const D: usize> {
    corner: [Real; D],
    edges: Vec<[Real; D]>,
    normal: [Real; D],
}

/// The faces of the box `[lo, hi]` (offsets from its particle, m). In 2D the four edges
/// counter-clockwise from the bottom one, each traversed counter-clockwise (the order and
/// parametrisation the 2D bits were built with); in other dimensions, per direction `k`
/// the face at `lo_k` then at `hi_k`, spanned from its lowest corner along the other
/// directions in increasing order.
fn box_faces<const D: usize>(lo: [Real; D], hi: [Real; D]) -> Vec<Face<D>> {
    // A corner of the box: bit k of `c` takes `hi_k`, else `lo_k`.
    let corner = |c: usize| -> [Real; D] {
        std::array::from_fn(|k| if (c >> k) & 1 == 1 { hi[k] } else { lo[k] })
    };
    let face = |from: usize, to: &[usize], axis: usize, sign: Real| {
        let a = corner(from);
        Face {
            corner: a,
            edges: to
                .iter()
                .map(|&c| {
                    let b = corner(c);
                    std::array::from_fn(|k| b[k] - a[k])
                })
                .collect(),
            normal: std::array::from_fn(|k| if k == axis { sign } else { 0.0 }),
        }
    };
    if D == 2 {
        return vec![
            face(0b00, &[0b01], 1, -1.0),
            face(0b01, &[0b11], 0, 1.0),
            face(0b11, &[0b10], 1, 1.0),
            face(0b10, &[0b00], 0, -1.0),
        ];
    }
    let mut faces = Vec::with_capacity(2 * D);
    for axis in 0..D {
        for (side, sign) in [(0, -1.0), (1 << axis, 1.0)] {
            let spans: Vec<usize> = (0..D)
                .filter(|&k| k != axis)
                .map(|k| side | 1 << k)
                .collect();
            faces.push(face(side, &spans, axis, sign));
        }
    }
    faces
}

/// Boundary sites of the box `[lo, hi]` (offsets from `node`'s particle, m), face after
/// face ([`box_faces`]), at the tensor-product points of the rule `(t, weight)` on
/// `[0, 1]` (the first edge's parameter running fastest), with the outward normal times
/// the weight and the face's measure (m^(D-1)): `x = corner + sum_m t_m e_m`,
/// `n prod_m w_m prod_m |e_m|`.
fn box_boundary<const D: usize>(
    node: [usize; D],
    lo: [Real; D],
    hi: [Real; D],
    rule: &[(Real, Real)],
    sites: &mut Vec<Site<D>>,
    nw: &mut Vec<[Real; D]>,
) {
    for face in box_faces(lo, hi) {
        let measure = face.edges.iter().fold(1.0, |m, e| {
            m * e.iter().fold(0.0 as Real, |l, &c| l.hypot(c))
        });
        let points = rule.len().pow(face.edges.len() as u32);
        for q in 0..points {
            let (mut offset, mut w, mut digits) = (face.corner, 1.0, q);
            for e in &face.edges {
                let (t, wt) = rule[digits % rule.len()];
                digits /= rule.len();
                for k in 0..D {
                    offset[k] += t * e[k];
                }
                w *= wt;
            }
            sites.push(Site { node, offset });
            nw.push(std::array::from_fn(|k| face.normal[k] * w * measure));
        }
    }
}

/// The nodal domain of each particle of the lattice as `(lo, hi)` relative to the
/// particle (m): half a spacing each way, cut at the workpiece's boundary; in particle
/// order.
fn domain_bounds<const D: usize>(lattice: &Lattice<D>) -> Vec<([usize; D], [Real; D], [Real; D])> {
    let (h, n) = (lattice.spacing(), lattice.dims());
    let mut out = Vec::with_capacity(n.iter().product());
    for_each_index([0; D], n, |node| {
        let lo = std::array::from_fn(|k| if node[k] > 0 { -0.5 * h[k] } else { 0.0 });
        let hi = std::array::from_fn(|k| if node[k] + 1 < n[k] { 0.5 * h[k] } else { 0.0 });
        out.push((node, lo, hi));
    });
    out
}

/// The edge rule of SCNI's nodal domains: 3-point Gauss `(position along the edge,
/// weight)` on `[0, 1]` (tensor product 3x3 on a face in 3D).
fn scni_rule() -> [(Real, Real); 3] {
    let g = (0.6_f64).sqrt() / 2.0;
    [
        (0.5 - g, 5.0 / 18.0),
        (0.5, 8.0 / 18.0),
        (0.5 + g, 5.0 / 18.0),
    ]
}

/// The nodal domains of SCNI: one point per particle at its domain's centroid with the
/// domain's measure (area in 2D, volume in 3D), and for each domain [`scni_rule`] on each
/// edge or face as boundary sites with their outward normal times the quadrature weight
/// (m^(D-1)); [`SCNI_EDGE_POINTS`] per domain in 2D. Everything is formed relative to the
/// domain's particle, so interior domains get the same bits. ([`point_shapes`] forms them a
/// block at a time.)
#[cfg(test)]
fn nodal_domains<const D: usize>(
    lattice: &Lattice<D>,
) -> (PointSet<D>, Vec<Site<D>>, Vec<[Real; D]>) {
    smoothing_cells(
        lattice,
        &domain_bounds(lattice),
        |lo, hi| [(lo, hi)],
        &scni_rule(),
    )
}

/// The `K = 2^D` orthants of the nodal domain `[lo, hi]` (offsets from its particle, m), cut
/// through its centroid: in 2D the quadrants lower-left, lower-right, upper-right,
/// upper-left; in 3D the octants in that order below the centroid, then above it.
fn orthants<const D: usize, const K: usize>(
    lo: [Real; D],
    hi: [Real; D],
) -> [([Real; D], [Real; D]); K] {
    assert_eq!(K, 1 << D, "a nodal domain has 2^D orthants");
    std::array::from_fn(|k| {
        // Counter-clockwise in the first two directions, binary in the others.
        let upper = |axis: usize| match axis {
            0 => matches!(k & 3, 1 | 2),
            1 => k & 2 != 0,
            _ => (k >> axis) & 1 != 0,
        };
        let (mut a, mut b) = (lo, hi);
        for axis in 0..D {
            let centre = 0.5 * (lo[axis] + hi[axis]);
            match upper(axis) {
                true => a[axis] = centre,
                false => b[axis] = centre,
            }
        }
        (a, b)
    })
}

/// The smoothing cells that `split` cuts each nodal domain `[lo, hi]` of `domains` (offsets
/// from its particle, m) into: each cell as a point at its centroid with its measure
/// `prod_k (hi_k - lo_k)` (cell = the domain's particle), domain by domain, and the Gauss
/// points `rule` (position along an edge, weight) on each cell's edges or faces as boundary
/// sites with their outward normal times the weight (m^(D-1)).
#[allow(clippy::type_complexity)]
fn smoothing_cells<const D: usize, const K: usize>(
    lattice: &Lattice<D>,
    domains: &[([usize; D], [Real; D], [Real; D])],
    split: impl Fn([Real; D], [Real; D]) -> [([Real; D], [Real; D]); K],
    rule: &[(Real, Real)],
) -> (PointSet<D>, Vec<Site<D>>, Vec<[Real; D]>) {
    let n = lattice.dims();
    let mut s = PointSet::default();
    let (mut edge_sites, mut edge_nw) = (Vec::new(), Vec::new());
    for &(node, lo, hi) in domains {
        for (a, b) in split(lo, hi) {
            let centre = Site {
                node,
                offset: std::array::from_fn(|k| 0.5 * (a[k] + b[k])),
            };
            let measure = (0..D).fold(1.0, |m, k| m * (b[k] - a[k]));
            s.push(lattice, centre, measure, linear_index(node, n));
            box_boundary(node, a, b, rule, &mut edge_sites, &mut edge_nw);
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
pub fn point_shapes<const D: usize>(
    lattice: &Lattice<D>,
    rule: IntegrationRule,
) -> Result<(PointSet<D>, ShapeTable<D>)> {
    Ok(match rule {
        IntegrationRule::Scni => {
            smoothed_blocks(lattice, |lo, hi| [(lo, hi)], &scni_rule(), true, "")?
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

/// The `K = 2^D` orthants of every nodal domain of the lattice ([`orthants`]), for the
/// stabilization of nodal integration: the orthants as points (centroid, measure; cell =
/// the domain's particle), `K` per domain in particle order, and their smoothed gradients
/// `B^k_I = (1 / A_k) sum_g N_I(x_g) n w_g` (1/m; no values `N_I`) from 2-point Gauss on
/// each orthant's edges (2 x 2 on each face in 3D), a block of domains at a time
/// ([`smoothed_blocks`]).
pub fn orthant_shapes<const D: usize, const K: usize>(
    lattice: &Lattice<D>,
) -> Result<(PointSet<D>, ShapeTable<D>)> {
    let g = 0.5 / 3.0_f64.sqrt();
    let gauss = [(0.5 - g, 0.5), (0.5 + g, 0.5)];
    let name = if D == 2 { "quadrant" } else { "octant" };
    smoothed_blocks(lattice, orthants::<D, K>, &gauss, false, name)
}

/// The smoothing cells `split` cuts the lattice's nodal domains into ([`smoothing_cells`]
/// with the edge rule `rule`) as points, and their smoothed shape table ([`smoothed`]:
/// `N_I` at each cell's centroid when `centre`, and the smoothed gradients), built
/// [`DOMAIN_BLOCK`] domains at a time so that the boundary points' shape functions are
/// never all held at once; each row depends on its own points only, so the table is the
/// one an evaluation of all at once gives. `name` names a cell in errors when a domain has
/// several.
fn smoothed_blocks<const D: usize, const K: usize>(
    lattice: &Lattice<D>,
    split: impl Fn([Real; D], [Real; D]) -> [([Real; D], [Real; D]); K] + Copy,
    rule: &[(Real, Real)],
    centre: bool,
    name: &str,
) -> Result<(PointSet<D>, ShapeTable<D>)> {
    let per_cell = 2 * D * rule.len().pow(D as u32 - 1);
    let mut points = PointSet::default();
    let mut table = ShapeTable {
        offsets: vec![0],
        ..Default::default()
    };
    for (b, block) in domain_bounds(lattice).chunks(DOMAIN_BLOCK).enumerate() {
        let (cells, edges, nw) = smoothing_cells(lattice, block, split, rule);
        let (first_cell, first_edge) = (b * DOMAIN_BLOCK * K, b * DOMAIN_BLOCK * K * per_cell);
        let at_centre = match centre {
            true => Some(lattice.shape_table(&cells.sites, &|p| {
                format!("nodal integration point {}", first_cell + p)
            })?),
            false => None,
        };
        let on_edges = lattice.shape_table(&edges, &|q| {
            let q = first_edge + q;
            let domain = q / (K * per_cell);
            match K {
                1 => format!("boundary point {q} of nodal domain {domain}"),
                _ => format!(
                    "boundary point {q} of {name} {} of nodal domain {domain}",
                    q / per_cell % K
                ),
            }
        })?;
        let boundaries = DomainBoundaries::consecutive(nw, cells.areas.len());
        table.append(smoothed(
            at_centre.as_ref(),
            &on_edges,
            &boundaries,
            &cells.areas,
        ));
        points.sites.extend(cells.sites);
        points.positions.extend(cells.positions);
        points.areas.extend(cells.areas);
        points.cells.extend(cells.cells);
    }
    Ok((points, table))
}

/// The boundary terms of smoothing domains: domain `L`'s terms are
/// `rows[offsets[L]..offsets[L + 1]]` with `nw[..]` alike, each a row of the boundary
/// shape table (a quadrature point on the domain's boundary) and the outward normal times
/// the quadrature weight there (m^(D-1)). A point on a face two domains share is one row
/// that both domains' terms name, with opposite normals.
#[derive(Debug, Clone, Default)]
pub struct DomainBoundaries<const D: usize> {
    /// Start of each domain's terms, and their end.
    pub offsets: Vec<usize>,
    /// The row of each term in the boundary shape table.
    pub rows: Vec<u32>,
    /// Outward normal times weight of each term (m^(D-1)).
    pub nw: Vec<[Real; D]>,
}

impl<const D: usize> DomainBoundaries<D> {
    /// `nw.len() / domains` consecutive rows per domain, in order: each domain's own
    /// boundary points.
    fn consecutive(nw: Vec<[Real; D]>, domains: usize) -> Self {
        let per_domain = nw.len() / domains;
        DomainBoundaries {
            offsets: (0..=domains).map(|l| l * per_domain).collect(),
            rows: (0..nw.len() as u32).collect(),
            nw,
        }
    }
}

/// Smoothed shape table (Chen, Wu, Yoon, You 2001): per domain `L` of measure `A_L`
/// (m^D), `N_I` at its centroid (from `at_centre`, or none) and the smoothed gradient
/// `B_I = (1 / A_L) sum_g N_I(x_g) n w_g` (1/m) over the domain's boundary terms
/// (`boundaries`: the rows of `on_edges` and their outward normal times weight, m^(D-1)).
pub fn smoothed<const D: usize>(
    at_centre: Option<&ShapeTable<D>>,
    on_edges: &ShapeTable<D>,
    boundaries: &DomainBoundaries<D>,
    areas: &[Real],
) -> ShapeTable<D> {
    let mut t = ShapeTable {
        offsets: vec![0],
        ..Default::default()
    };
    let mut row: std::collections::BTreeMap<u32, (Real, [Real; D])> = Default::default();
    for (p, area) in areas.iter().enumerate() {
        row.clear();
        if let Some(c) = at_centre {
            for e in c.row(p) {
                row.entry(c.index[e]).or_insert((0.0, [0.0; D])).0 = c.n[e];
            }
        }
        let terms = boundaries.offsets[p]..boundaries.offsets[p + 1];
        for (&q, w) in boundaries.rows[terms.clone()]
            .iter()
            .zip(&boundaries.nw[terms])
        {
            for e in on_edges.row(q as usize) {
                let (_, g) = row.entry(on_edges.index[e]).or_insert((0.0, [0.0; D]));
                for (gk, &wk) in g.iter_mut().zip(w) {
                    *gk += on_edges.n[e] * wk / area;
                }
            }
        }
        for (&i, (n, g)) in &row {
            t.index.push(i);
            if at_centre.is_some() {
                t.n.push(*n);
            }
            for (column, &gk) in t.grad.iter_mut().zip(g) {
                column.push(gk);
            }
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

    /// The generic cell rules give in 2D the points, order and weights the planar rules
    /// had (counter-clockwise q4 from `(-a, -a)`; q2 on the diagonal), bit for bit.
    #[test]
    fn cell_rules_in_two_dimensions_keep_their_points_and_order() {
        let a = 1.0 / 3.0_f64.sqrt();
        let q4 = [
            ([-a, -a], 1.0),
            ([a, -a], 1.0),
            ([a, a], 1.0),
            ([-a, a], 1.0),
        ];
        assert_eq!(rule_points::<2>(IntegrationRule::Q4), q4);
        assert_eq!(
            rule_points::<2>(IntegrationRule::Q2),
            [([-a, -a], 2.0), ([a, a], 2.0)]
        );
        assert!(rule_points::<2>(IntegrationRule::Scni).is_empty());
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
                        for (aij, grad) in a[i].iter().zip(&t.grad) {
                            let g: Real =
                                t.row(p).map(|e| d[t.index[e] as usize][i] * grad[e]).sum();
                            worst = worst.max((g - aij).abs() / 1e-4);
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
    /// 4 x 5 x 6 particles, supports of 1.5 and 2 spacings) integrated with q4, q2 or SCNI
    /// (smoothed gradients, no stabilization) from the RK gradients has exactly the six
    /// rigid-body zero eigenvalues (below `1e-8` of the largest), and the next one is
    /// clearly positive.
    #[test]
    fn no_spurious_zero_energy_modes_in_three_dimensions() {
        for rule in [
            IntegrationRule::Q4,
            IntegrationRule::Q2,
            IntegrationRule::Scni,
        ] {
            for (n, h) in [([5, 5, 5], [1.0; 3]), ([4, 5, 6], [1.0, 0.8, 1.25])] {
                for s in [1.5, 2.0] {
                    let lattice = Lattice::new([0.0; 3], h, n, h.map(|hk| s * hk));
                    let (points, t) = point_shapes(&lattice, rule).unwrap();
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

    /// 3D nodal domains: their volumes sum to the box's, each has 54 boundary sites (3x3
    /// Gauss on 6 faces) whose `n dA` sum to zero (a closed surface), and interior domains
    /// are cubes of the spacings.
    #[test]
    fn nodal_domains_in_three_dimensions_tile_the_box() {
        let lattice = Lattice::new([0.0; 3], [0.5, 0.25, 0.4], [5, 9, 4], [1.0, 0.5, 0.8]);
        let (s, e, nw) = nodal_domains(&lattice);
        let v: Real = s.areas.iter().sum();
        assert!((v - 2.0 * 2.0 * 1.2).abs() < 1e-12, "{v}");
        assert_eq!(e.len(), 5 * 9 * 4 * 54);
        for d in nw.chunks(54) {
            for k in 0..3 {
                let sum: Real = d.iter().map(|v| v[k]).sum();
                assert!(sum.abs() < 1e-15, "{sum}");
            }
        }
        let interior = 1 + 5 * (1 + 9);
        assert_eq!(s.sites[interior].offset, [0.0; 3]);
        assert!((s.areas[interior] - 0.5 * 0.25 * 0.4).abs() < 1e-16);
    }

    /// SCNI in 3D (Chen, Wu, Yoon, You 2001): the linear patch test passes to round-off,
    /// the smoothed gradient of `u = A X` being `A` in every nodal domain, boundary domains
    /// included, and the integration constraint `sum_L B_I(x_L) V_L = int_G N_I n dG` holds
    /// to round-off for every particle, the boundary integral taken with the same face rule
    /// on the domain faces that lie on the box's surface. The 2x2x2 Gauss cells (q4)
    /// violate the constraint next to the boundary (printed for comparison).
    #[test]
    fn scni_in_three_dimensions_passes_the_linear_patch_test_and_the_integration_constraint() {
        let (n, h) = ([5, 6, 4], [1e-3, 0.7e-3, 1.3e-3]);
        let lattice = Lattice::new([0.0; 3], h, n, h.map(|hk| 2.0 * hk));
        let (points, t) = point_shapes(&lattice, IntegrationRule::Scni).unwrap();
        let a = [
            [1e-4, 2e-4, -3e-4],
            [-0.5e-4, 3e-4, 1e-4],
            [2e-4, -1e-4, 0.7e-4],
        ];
        let x = &lattice.cloud().positions;
        let d: Vec<[Real; 3]> = x
            .iter()
            .map(|&p| std::array::from_fn(|i| (0..3).map(|j| a[i][j] * p[j]).sum()))
            .collect();
        let mut worst: Real = 0.0;
        for (p, &xp) in points.positions.iter().enumerate() {
            let u = t.interpolate(p, &d);
            for i in 0..3 {
                let exact: Real = (0..3).map(|j| a[i][j] * xp[j]).sum();
                worst = worst.max((u[i] - exact).abs() / 1e-3 / 1e-4);
                for (aij, grad) in a[i].iter().zip(&t.grad) {
                    let g: Real = t.row(p).map(|e| d[t.index[e] as usize][i] * grad[e]).sum();
                    worst = worst.max((g - aij).abs() / 1e-4);
                }
            }
        }
        println!("Scni linear patch: largest relative error {worst:.1e}");
        assert!(worst < 1e-10, "{worst}");
        // The boundary integral int_G N_I n dG over the domain faces on the surface.
        let (_, sites, nw) = nodal_domains(&lattice);
        let outer: Vec<(Site<3>, [Real; 3])> = sites
            .into_iter()
            .zip(nw)
            .filter(|(s, w)| {
                (0..3).any(|k| {
                    s.offset[k] == 0.0
                        && ((w[k] < 0.0 && s.node[k] == 0) || (w[k] > 0.0 && s.node[k] == n[k] - 1))
                })
            })
            .collect();
        let area =
            2.0 * (4.0 * 5.0 * h[0] * h[1] + 4.0 * 3.0 * h[0] * h[2] + 5.0 * 3.0 * h[1] * h[2]);
        let total: Real = outer
            .iter()
            .map(|(_, w)| w.iter().map(|c| c.abs()).sum::<Real>())
            .sum();
        assert!((total - area).abs() < 1e-12 * area, "{total} vs {area}");
        let sites: Vec<Site<3>> = outer.iter().map(|&(s, _)| s).collect();
        let on_surface = lattice
            .shape_table(&sites, &|q| format!("surface point {q}"))
            .unwrap();
        let mut boundary = vec![[0.0; 3]; x.len()];
        for (q, (_, w)) in outer.iter().enumerate() {
            for e in on_surface.row(q) {
                for k in 0..3 {
                    boundary[on_surface.index[e] as usize][k] += on_surface.n[e] * w[k];
                }
            }
        }
        let scale = h[0] * h[1];
        let violation = |points: &PointSet<3>, t: &ShapeTable<3>| -> Real {
            let mut sum = vec![[0.0; 3]; x.len()];
            for (p, &v) in points.areas.iter().enumerate() {
                for e in t.row(p) {
                    for (sk, grad) in sum[t.index[e] as usize].iter_mut().zip(&t.grad) {
                        *sk += grad[e] * v;
                    }
                }
            }
            sum.iter()
                .zip(&boundary)
                .flat_map(|(s, b)| (0..3).map(move |k| (s[k] - b[k]).abs() / scale))
                .fold(0.0, Real::max)
        };
        let scni = violation(&points, &t);
        let (q4_points, q4) = point_shapes(&lattice, IntegrationRule::Q4).unwrap();
        let gauss = violation(&q4_points, &q4);
        println!("integration constraint, largest violation / (h_x h_y): scni {scni:.1e}, q4 {gauss:.1e}");
        assert!(scni < 1e-12, "{scni}");
        assert!(gauss > 1e-4, "{gauss}");
    }
}
