//! The particles of a cylinder: an O-grid that follows its round surface (a square core
//! and a ring of cells from the core's edges to the circle), extruded along the axis, with
//! each particle's volume from the mapping. A Cartesian lattice clipped by a circle would
//! leave a staircase surface, wrong for contact and for the measured radius.
//!
//! Cross-section of radius `R` (m): the core is the square `[-a, a]^2`, `a = c R`, with `n`
//! cells per side (`n` even, so that lines of particles lie on the planes `x = 0` and
//! `y = 0`). Its boundary, walked counter-clockwise from the corner `(a, -a)`, is `4 n`
//! points `s_p` at angles `theta_p = -pi/4 + (pi/2) p / n`; the ring's layer `k = 0..m` has
//! the points `x_kp = (1 - t_k) s_p + t_k R (cos theta_p, sin theta_p)`, `t_k = k / m`, so its
//! last layer lies on the circle. Between nodes the map is the same formula with `p` and
//! `t` continuous (the ring) or bilinear (the core), so the cells' outer faces are the arc
//! itself, not its chords: cell volumes `int |det dx/dxi| dxi` by Gauss quadrature of the
//! map add up to `pi R^2 L` to round-off. Along the axis, `l` cells of equal length.
//!
//! A half (`x >= 0`) or quarter (`x, y >= 0`) cross-section keeps the cells on that side of
//! the symmetry planes; the particles on a plane lie on it exactly.

use crate::integration::rule_points;
use crate::integration::DomainBoundaries;
use crate::math::Real;
use crate::scene::IntegrationRule;
use std::collections::HashMap;
use std::f64::consts::FRAC_PI_2;

/// Which part of the cross-section is modelled, the rest by symmetry planes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sector {
    /// The whole circle.
    Full,
    /// `x >= 0`: the plane `x = 0` is a symmetry plane.
    Half,
    /// `x >= 0`, `y >= 0`: the planes `x = 0` and `y = 0` are symmetry planes.
    Quarter,
}

/// A cell of the cross-section: the core's cell `(i, j)` or the ring's cell between layers
/// `k` and `k + 1` (its `xi`) and boundary points `p` and `p + 1` (its `eta`).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Section {
    Core { i: usize, j: usize },
    Ring { k: usize, p: usize },
}

/// The particles and hexahedral cells of an O-grid cylinder.
#[derive(Debug, Clone)]
pub struct CylinderGrid {
    /// Particle positions (m).
    pub positions: Vec<[Real; 3]>,
    /// Particle volumes (m^3): `int N_a |det J| dxi` over the cells around each particle,
    /// `N_a` the trilinear function of its corner of the cell.
    pub volumes: Vec<Real>,
    /// Each cell's 8 particles: `(xi, eta, zeta)` corners `(-,-,-), (+,-,-), (+,+,-),
    /// (-,+,-)`, then the same at `zeta = +1`.
    pub cells: Vec<[u32; 8]>,
    radius: Real,
    core: Real,
    n: usize,
    m: usize,
    length: Real,
    layers: usize,
    sections: Vec<Section>,
}

/// Gauss-Legendre points and weights on `[-1, 1]`, 3 points.
const GAUSS3: [(Real, Real); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// The nodal domains of the O-grid ([`CylinderGrid::nodal_domains`]).
#[derive(Debug, Clone)]
pub struct NodalDomains {
    /// Each particle's domain's centroid (m).
    pub centroids: Vec<[Real; 3]>,
    /// Each particle's domain's volume (m^3).
    pub volumes: Vec<Real>,
    /// The boundary quadrature points (m).
    pub sites: Vec<[Real; 3]>,
    /// Each domain's boundary terms, rows of `sites`.
    pub boundaries: DomainBoundaries<3>,
}

/// Most octants a particle's nodal domain is made of ([`CylinderGrid::particle_octants`]).
pub const MAX_OCTANTS: usize = 8;

/// The octants of a block of nodal domains ([`CylinderGrid::octant_domains`]),
/// [`MAX_OCTANTS`] slots per domain.
#[derive(Debug, Clone)]
pub struct OctantDomains {
    /// Each octant's volume (m^3), 0 for an empty slot.
    pub volumes: Vec<Real>,
    /// The boundary quadrature points (m).
    pub sites: Vec<[Real; 3]>,
    /// Each octant's boundary terms, rows of `sites`.
    pub boundaries: DomainBoundaries<3>,
}

/// The signs `(xi, eta, zeta)` of a cell's corner `a` in the order of
/// [`CylinderGrid::cells`].
fn corner_signs(a: usize) -> [Real; 3] {
    let xi = if a % 4 == 1 || a % 4 == 2 { 1.0 } else { -1.0 };
    let eta = if a % 4 >= 2 { 1.0 } else { -1.0 };
    let zeta = if a >= 4 { 1.0 } else { -1.0 };
    [xi, eta, zeta]
}

/// The corner of a cell with the signs `s` ([`corner_signs`]).
fn corner_of(s: [Real; 3]) -> usize {
    (0..8)
        .find(|&a| corner_signs(a) == s)
        .unwrap_or_else(|| unreachable!("signs are +-1"))
}

/// The sorted particles of a cell's face `xi_k = side`: the same key from both cells that
/// share it.
fn face_key(cell: &[u32; 8], k: usize, side: Real) -> [u32; 4] {
    let mut key = [0; 4];
    let mut n = 0;
    for (a, &particle) in cell.iter().enumerate() {
        if corner_signs(a)[k] == side {
            key[n] = particle;
            n += 1;
        }
    }
    key.sort_unstable();
    key
}

/// `a x b`.
fn cross(a: [Real; 3], b: [Real; 3]) -> [Real; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Gauss-Legendre points and weights on `[-1, 1]`, 4 points: exact for the map's
/// polynomial part, and to round-off on cells of a few degrees of arc.
const GAUSS4: [(Real, Real); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_85),
    (-0.339_981_043_584_856_25, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_25, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_85),
];

impl CylinderGrid {
    /// The cylinder of radius `radius` and length `length` (m) along `z` from `z = 0`, with
    /// `n` core cells per side (even, at least 2), `m` ring layers (at least 1), `layers`
    /// cells along the axis, the core's half side `core_ratio R` (`0 < core_ratio < 1/sqrt 2`)
    /// and the part `sector`.
    ///
    /// # Errors
    ///
    /// A count or ratio out of range, named.
    pub fn new(
        radius: Real,
        length: Real,
        [n, m, layers]: [usize; 3],
        core_ratio: Real,
        sector: Sector,
    ) -> Result<CylinderGrid, String> {
        if n < 2 || n % 2 != 0 {
            return Err(format!(
                "core cells per side must be even and at least 2, not {n}"
            ));
        }
        if m < 1 || layers < 1 {
            return Err(format!(
                "ring layers ({m}) and axial cells ({layers}) must be at least 1"
            ));
        }
        if !(core_ratio > 0.0 && core_ratio < std::f64::consts::FRAC_1_SQRT_2) {
            return Err(format!(
                "the core's half side must be between 0 and R / sqrt 2, not {core_ratio} R"
            ));
        }
        if !(radius > 0.0 && length > 0.0) {
            return Err(format!(
                "radius ({radius} m) and length ({length} m) must be positive"
            ));
        }
        let mut grid = CylinderGrid {
            positions: Vec::new(),
            volumes: Vec::new(),
            cells: Vec::new(),
            radius,
            core: core_ratio * radius,
            n,
            m,
            length,
            layers,
            sections: Vec::new(),
        };
        grid.build(sector);
        Ok(grid)
    }

    /// Particles, cells and volumes of the cells of `sector`.
    fn build(&mut self, sector: Sector) {
        let (n, m) = (self.n, self.m);
        let keep = |x: [Real; 2]| match sector {
            Sector::Full => true,
            Sector::Half => x[0] > 0.0,
            Sector::Quarter => x[0] > 0.0 && x[1] > 0.0,
        };
        let mut sections = Vec::new();
        for j in 0..n {
            for i in 0..n {
                sections.push(Section::Core { i, j });
            }
        }
        for k in 0..m {
            for p in 0..4 * n {
                sections.push(Section::Ring { k, p });
            }
        }
        sections.retain(|&s| keep(self.section_point(s, [0.0, 0.0]).0));
        // The cross-section's nodes, numbered as the kept cells first reach them.
        let mut number = std::collections::HashMap::new();
        let mut nodes: Vec<[Real; 2]> = Vec::new();
        let corners: Vec<[u32; 4]> = sections
            .iter()
            .map(|&s| {
                self.section_nodes(s).map(|key| {
                    *number.entry(key).or_insert_with(|| {
                        nodes.push(self.node(key));
                        (nodes.len() - 1) as u32
                    })
                })
            })
            .collect();
        let per_layer = nodes.len() as u32;
        let hz = self.length / self.layers as Real;
        for l in 0..=self.layers {
            let z = l as Real * hz;
            self.positions.extend(nodes.iter().map(|x| [x[0], x[1], z]));
        }
        self.volumes = vec![0.0; self.positions.len()];
        for l in 0..self.layers as u32 {
            for (c, &q) in corners.iter().enumerate() {
                let below = q.map(|v| v + l * per_layer);
                let above = q.map(|v| v + (l + 1) * per_layer);
                let cell = [
                    below[0], below[1], below[2], below[3], above[0], above[1], above[2], above[3],
                ];
                // int N_a |det J| over the cell: the section's 2D weights times hz / 2 per
                // half of the trilinear function along the axis.
                let weights = self.section_weights(sections[c]);
                for (a, &v) in cell.iter().enumerate() {
                    self.volumes[v as usize] += weights[a % 4] * 0.5 * hz;
                }
                self.cells.push(cell);
            }
        }
        self.sections = sections;
    }

    /// The four nodes of a section cell, counter-clockwise from `(xi, eta) = (-1, -1)`, as
    /// keys: `(layer, boundary point)` in the ring (layer 0 is the core's boundary) and
    /// `(i, j)` of the core offset past the ring's keys.
    fn section_nodes(&self, s: Section) -> [(usize, usize); 4] {
        let n = self.n;
        let core = |i: usize, j: usize| match self.boundary_index(i, j) {
            Some(p) => (0, p),
            None => (self.m + 1 + j, i),
        };
        match s {
            Section::Core { i, j } => [
                core(i, j),
                core(i + 1, j),
                core(i + 1, j + 1),
                core(i, j + 1),
            ],
            Section::Ring { k, p } => {
                // xi outward, eta counter-clockwise: a positive Jacobian.
                let q = (p + 1) % (4 * n);
                [(k, p), (k + 1, p), (k + 1, q), (k, q)]
            }
        }
    }

    /// The boundary point `p` of the core's node `(i, j)`, if it lies on the boundary
    /// (counter-clockwise from the corner `(a, -a)`).
    fn boundary_index(&self, i: usize, j: usize) -> Option<usize> {
        let n = self.n;
        match (i, j) {
            (_, 0) => Some((3 * n + i) % (4 * n)),
            (i, j) if i == n => Some(j),
            (i, j) if j == n => Some(2 * n - i),
            (0, j) => Some(3 * n - j),
            _ => None,
        }
    }

    /// The position of a node key (m).
    fn node(&self, (k, p): (usize, usize)) -> [Real; 2] {
        let x = if k <= self.m {
            self.ring_point(p as Real, k as Real / self.m as Real).0
        } else {
            let (i, j) = (p, k - self.m - 1);
            let h = 2.0 * self.core / self.n as Real;
            [-self.core + i as Real * h, -self.core + j as Real * h]
        };
        // Nodes on the planes x = 0 and y = 0 lie on them exactly.
        x.map(|c| {
            if c.abs() < 1e-12 * self.radius {
                0.0
            } else {
                c
            }
        })
    }

    /// The ring's map at boundary parameter `p` (continuous, `0..4n`) and layer fraction
    /// `t` (`0..1`): the point (m) and its derivatives with respect to `p` and `t` (m).
    fn ring_point(&self, p: Real, t: Real) -> ([Real; 2], [Real; 2], [Real; 2]) {
        let (n, a, r) = (self.n as Real, self.core, self.radius);
        let side = (p / n).floor().clamp(0.0, 3.0);
        let u = p - side * n;
        // The core's boundary: side 0 east (y up), 1 north (x down), 2 west (y down), 3
        // south (x up), each from its corner, 2a / n per unit of p.
        let h = 2.0 * a / n;
        let (s, ds) = match side as usize {
            0 => ([a, -a + u * h], [0.0, h]),
            1 => ([a - u * h, a], [-h, 0.0]),
            2 => ([-a, a - u * h], [0.0, -h]),
            _ => ([-a + u * h, -a], [h, 0.0]),
        };
        let theta = -std::f64::consts::FRAC_PI_4 + FRAC_PI_2 * p / n;
        let dtheta = FRAC_PI_2 / n;
        let (sin, cos) = theta.sin_cos();
        let arc = [r * cos, r * sin];
        let darc = [-r * sin * dtheta, r * cos * dtheta];
        (
            [0, 1].map(|c| (1.0 - t) * s[c] + t * arc[c]),
            [0, 1].map(|c| (1.0 - t) * ds[c] + t * darc[c]),
            [0, 1].map(|c| arc[c] - s[c]),
        )
    }

    /// A section cell's map at `(xi, eta)` in `[-1, 1]^2`: the point (m) and `det dx/dxi`
    /// (m^2).
    fn section_point(&self, s: Section, [xi, eta]: [Real; 2]) -> ([Real; 2], Real) {
        match s {
            Section::Core { i, j } => {
                let h = 2.0 * self.core / self.n as Real;
                let x = [
                    -self.core + (i as Real + 0.5 * (1.0 + xi)) * h,
                    -self.core + (j as Real + 0.5 * (1.0 + eta)) * h,
                ];
                (x, 0.25 * h * h)
            }
            Section::Ring { k, p } => {
                let m = self.m as Real;
                let t = (k as Real + 0.5 * (1.0 + xi)) / m;
                let pc = p as Real + 0.5 * (1.0 + eta);
                let (x, dp, dt) = self.ring_point(pc, t);
                // d/dxi = dt / (2 m), d/deta = dp / 2.
                let det = (dt[0] * dp[1] - dt[1] * dp[0]) * 0.25 / m;
                (x, det)
            }
        }
    }

    /// `int N_a |det J| dxi deta` over a section cell for its four corners (m^2), `N_a` the
    /// bilinear functions, by 4 x 4 Gauss points.
    fn section_weights(&self, s: Section) -> [Real; 4] {
        let mut w = [0.0; 4];
        for &(xi, wx) in &GAUSS4 {
            for &(eta, wy) in &GAUSS4 {
                let det = self.section_point(s, [xi, eta]).1 * wx * wy;
                let n = [
                    0.25 * (1.0 - xi) * (1.0 - eta),
                    0.25 * (1.0 + xi) * (1.0 - eta),
                    0.25 * (1.0 + xi) * (1.0 + eta),
                    0.25 * (1.0 - xi) * (1.0 + eta),
                ];
                for (wa, na) in w.iter_mut().zip(n) {
                    *wa += na * det;
                }
            }
        }
        w
    }

    /// Cell `c`'s map at `xi` in `[-1, 1]^3`: the point (m) and `det dx/dxi` (m^3), the
    /// section's map times the axial half length. An integration rule on the reference cube
    /// places its points and weights with it.
    pub fn cell_point(&self, c: usize, xi: [Real; 3]) -> ([Real; 3], Real) {
        let per_layer = self.sections.len();
        let (l, s) = (c / per_layer, self.sections[c % per_layer]);
        let hz = self.length / self.layers as Real;
        let (x, det) = self.section_point(s, [xi[0], xi[1]]);
        let z = (l as Real + 0.5 * (1.0 + xi[2])) * hz;
        ([x[0], x[1], z], det * 0.5 * hz)
    }

    /// Cell `c`'s map at `xi` in `[-1, 1]^3`: the point (m) and the columns
    /// `dx/dxi_k` (m) of its Jacobian, as [`CylinderGrid::cell_point`] maps.
    pub fn cell_frame(&self, c: usize, xi: [Real; 3]) -> ([Real; 3], [[Real; 3]; 3]) {
        let per_layer = self.sections.len();
        let (l, s) = (c / per_layer, self.sections[c % per_layer]);
        let hz = self.length / self.layers as Real;
        let z = (l as Real + 0.5 * (1.0 + xi[2])) * hz;
        let axial = [0.0, 0.0, 0.5 * hz];
        match s {
            Section::Core { .. } => {
                let h = 2.0 * self.core / self.n as Real;
                let x = self.section_point(s, [xi[0], xi[1]]).0;
                (
                    [x[0], x[1], z],
                    [[0.5 * h, 0.0, 0.0], [0.0, 0.5 * h, 0.0], axial],
                )
            }
            Section::Ring { k, p } => {
                let m = self.m as Real;
                let t = (k as Real + 0.5 * (1.0 + xi[0])) / m;
                let (x, dp, dt) = self.ring_point(p as Real + 0.5 * (1.0 + xi[1]), t);
                (
                    [x[0], x[1], z],
                    [
                        [0.5 * dt[0] / m, 0.5 * dt[1] / m, 0.0],
                        [0.5 * dp[0], 0.5 * dp[1], 0.0],
                        axial,
                    ],
                )
            }
        }
    }

    /// The nodal domains of SCNI on the O-grid ([`crate::integration`]): particle `I`'s
    /// domain is the union of the octants at its corner of the cells around it, each octant
    /// the image under the cell's map of the reference octant between the corner and the
    /// cell's centre (`xi_k` between 0 and the corner's sign), so the domains tile the
    /// cylinder and follow its round surface. Per particle: the domain's volume
    /// `V_I = sum int |det J| dxi` (m^3, 4 x 4 x 4 Gauss points per octant) and centroid (m),
    /// and its boundary: the quarter faces `xi_k = 0` inside each cell, which two domains
    /// share, and the quarter faces of the cells' faces on the body's surface or a symmetry
    /// plane, at 3 x 3 Gauss points each, with the outward normal times the weight
    /// `(dx/dxi_u x dx/dxi_v) w_u w_v` (m^2; `(u, v, k)` cyclic). Returned as the centroids,
    /// the volumes, the boundary points (m) and the terms that name them
    /// ([`DomainBoundaries`]).
    pub fn nodal_domains(&self) -> NodalDomains {
        let np = self.positions.len();
        let mut volumes = vec![0.0; np];
        let mut moments = vec![[0.0; 3]; np];
        let mut terms: Vec<Vec<(u32, [Real; 3])>> = vec![Vec::new(); np];
        let mut sites = Vec::new();
        // Each face of every cell, by its sorted particles: one cell's face is the surface.
        let mut faces: HashMap<[u32; 4], u32> = HashMap::new();
        for cell in &self.cells {
            for k in 0..3 {
                for side in [-1.0, 1.0] {
                    *faces.entry(face_key(cell, k, side)).or_default() += 1;
                }
            }
        }
        for (c, cell) in self.cells.iter().enumerate() {
            for (a, &particle) in cell.iter().enumerate() {
                let sign = corner_signs(a);
                for &(g0, w0) in &GAUSS4 {
                    for &(g1, w1) in &GAUSS4 {
                        for &(g2, w2) in &GAUSS4 {
                            let g = [g0, g1, g2];
                            let xi = std::array::from_fn(|d| 0.5 * sign[d] * (1.0 + g[d]));
                            let (x, det) = self.cell_point(c, xi);
                            let dv = det * w0 * w1 * w2 / 8.0;
                            volumes[particle as usize] += dv;
                            for (m, xk) in moments[particle as usize].iter_mut().zip(x) {
                                *m += dv * xk;
                            }
                        }
                    }
                }
            }
            for k in 0..3 {
                let (u, v) = ((k + 1) % 3, (k + 2) % 3);
                for su in [-1.0, 1.0] {
                    for sv in [-1.0, 1.0] {
                        // The quarter face xi_k = 0 between the octants below and above it.
                        let octant = |sk: Real| {
                            let mut s = [0.0; 3];
                            (s[k], s[u], s[v]) = (sk, su, sv);
                            cell[corner_of(s)]
                        };
                        let (below, above) = (octant(-1.0), octant(1.0));
                        self.quarter_face(c, k, 0.0, [su, sv], &mut sites, |q, nw| {
                            terms[below as usize].push((q, nw));
                            terms[above as usize].push((q, nw.map(|x| -x)));
                        });
                    }
                }
                for side in [-1.0, 1.0] {
                    if faces[&face_key(cell, k, side)] > 1 {
                        continue;
                    }
                    for su in [-1.0, 1.0] {
                        for sv in [-1.0, 1.0] {
                            let mut s = [0.0; 3];
                            (s[k], s[u], s[v]) = (side, su, sv);
                            let owner = cell[corner_of(s)];
                            self.quarter_face(c, k, side, [su, sv], &mut sites, |q, nw| {
                                terms[owner as usize].push((q, nw.map(|x| side * x)));
                            });
                        }
                    }
                }
            }
        }
        let mut boundaries = DomainBoundaries {
            offsets: vec![0],
            ..Default::default()
        };
        for t in terms {
            for (q, nw) in t {
                boundaries.rows.push(q);
                boundaries.nw.push(nw);
            }
            boundaries.offsets.push(boundaries.rows.len());
        }
        NodalDomains {
            centroids: moments
                .iter()
                .zip(&volumes)
                .map(|(m, v)| m.map(|mk| mk / v))
                .collect(),
            volumes,
            sites,
            boundaries,
        }
    }

    /// Each particle's octants for the stabilization of nodal integration: the cells'
    /// octants at its corner whose union is its nodal domain ([`CylinderGrid::nodal_domains`]),
    /// as `(cell, corner)` in ascending cell order; at most [`MAX_OCTANTS`] (a particle at a
    /// corner of the core's square lies in 3 cells of a section, 6 octants).
    pub fn particle_octants(&self) -> Vec<Vec<(u32, u8)>> {
        let mut octants = vec![Vec::new(); self.positions.len()];
        for (c, cell) in self.cells.iter().enumerate() {
            for (a, &particle) in cell.iter().enumerate() {
                octants[particle as usize].push((c as u32, a as u8));
            }
        }
        debug_assert!(octants.iter().all(|o| o.len() <= MAX_OCTANTS));
        octants
    }

    /// The octants of the particles `octants` lists ([`CylinderGrid::particle_octants`],
    /// a block of them), each a smoothing cell of its own, [`MAX_OCTANTS`] slots per
    /// particle (a particle with fewer has empty slots after its own: volume 0, no
    /// boundary). Per octant, the image of the reference octant between its corner and the
    /// cell's centre: its volume `int |det J| dxi` (m^3, 4 x 4 x 4 Gauss points) and its six
    /// quarter faces at 3 x 3 Gauss points each (`xi_k = 0` and `xi_k = s_k`, `s` the
    /// corner's signs), with the outward normal times the weight (m^2).
    pub fn octant_domains(&self, octants: &[Vec<(u32, u8)>]) -> OctantDomains {
        let mut volumes = Vec::with_capacity(MAX_OCTANTS * octants.len());
        let mut sites = Vec::new();
        let mut boundaries = DomainBoundaries {
            offsets: vec![0],
            ..Default::default()
        };
        for own in octants {
            for slot in 0..MAX_OCTANTS {
                let Some(&(c, a)) = own.get(slot) else {
                    volumes.push(0.0);
                    boundaries.offsets.push(boundaries.rows.len());
                    continue;
                };
                let (c, sign) = (c as usize, corner_signs(a as usize));
                let mut volume = 0.0;
                for &(g0, w0) in &GAUSS4 {
                    for &(g1, w1) in &GAUSS4 {
                        for &(g2, w2) in &GAUSS4 {
                            let g = [g0, g1, g2];
                            let xi = std::array::from_fn(|d| 0.5 * sign[d] * (1.0 + g[d]));
                            volume += self.cell_point(c, xi).1 * w0 * w1 * w2 / 8.0;
                        }
                    }
                }
                volumes.push(volume);
                for k in 0..3 {
                    let quarter = [sign[(k + 1) % 3], sign[(k + 2) % 3]];
                    for (at, outward) in [(0.0, -sign[k]), (sign[k], sign[k])] {
                        self.quarter_face(c, k, at, quarter, &mut sites, |q, nw| {
                            boundaries.rows.push(q);
                            boundaries.nw.push(nw.map(|x| outward * x));
                        });
                    }
                }
                boundaries.offsets.push(boundaries.rows.len());
            }
        }
        OctantDomains {
            volumes,
            sites,
            boundaries,
        }
    }

    /// The 3 x 3 Gauss points of cell `c`'s quarter face `xi_k = at` with `xi_u` between 0
    /// and `signs[0]`, `xi_v` between 0 and `signs[1]` (`(u, v, k)` cyclic): each point is
    /// pushed to `sites` (m) and `term(row, nw)` told its row and `(dx/dxi_u x dx/dxi_v)
    /// w_u w_v` (m^2), the area vector along increasing `xi_k`.
    fn quarter_face(
        &self,
        c: usize,
        k: usize,
        at: Real,
        signs: [Real; 2],
        sites: &mut Vec<[Real; 3]>,
        mut term: impl FnMut(u32, [Real; 3]),
    ) {
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        for &(gu, wu) in &GAUSS3 {
            for &(gv, wv) in &GAUSS3 {
                let mut xi = [0.0; 3];
                xi[k] = at;
                xi[u] = 0.5 * signs[0] * (1.0 + gu);
                xi[v] = 0.5 * signs[1] * (1.0 + gv);
                let (x, j) = self.cell_frame(c, xi);
                let w = 0.25 * wu * wv;
                let normal = cross(j[u], j[v]).map(|n| n * w);
                term(sites.len() as u32, normal);
                sites.push(x);
            }
        }
    }

    /// Radius of the cylinder (m).
    pub fn radius(&self) -> Real {
        self.radius
    }

    /// The integration points of a cell rule ([`rule_points`]) placed in every cell by the
    /// map: positions (m) and weights `w_g det J` (m^3), cell by cell.
    pub fn points(&self, rule: IntegrationRule) -> (Vec<[Real; 3]>, Vec<Real>) {
        let rule = rule_points::<3>(rule);
        (0..self.cells.len())
            .flat_map(|c| {
                rule.iter().map(move |&(xi, w)| {
                    let (x, det) = self.cell_point(c, xi);
                    (x, w * det)
                })
            })
            .unzip()
    }

    /// Each particle's kernel support radii (m): `scale` times its largest distance to a
    /// particle of a cell it belongs to, per direction, so a particle of the small cells at
    /// the core's corners has a small support and one of the large ring cells a large one
    /// (the variable-support RK approximation, [`crate::rk_shape::KernelCloud::with_supports`]).
    pub fn supports(&self, scale: Real) -> Vec<[Real; 3]> {
        let mut reach = vec![[0.0 as Real; 3]; self.positions.len()];
        for cell in &self.cells {
            for &a in cell {
                for &b in cell {
                    let (xa, xb) = (self.positions[a as usize], self.positions[b as usize]);
                    for k in 0..3 {
                        let r = &mut reach[a as usize][k];
                        *r = r.max((xa[k] - xb[k]).abs());
                    }
                }
            }
        }
        reach.into_iter().map(|r| r.map(|rk| scale * rk)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rk_shape::ShapeTable;
    use std::f64::consts::PI;

    fn grid(sector: Sector) -> CylinderGrid {
        CylinderGrid::new(3.2e-3, 32.4e-3, [8, 4, 20], 0.55, sector).unwrap()
    }

    /// The particles' volumes and the cells' mapped volumes add up to the cylinder's (the
    /// outer faces are the arc, not chords), for the whole, half and quarter.
    #[test]
    fn volumes_add_up_to_the_cylinder() {
        let (r, l) = (3.2e-3, 32.4e-3);
        for (sector, part) in [
            (Sector::Full, 1.0),
            (Sector::Half, 0.5),
            (Sector::Quarter, 0.25),
        ] {
            let g = grid(sector);
            let exact = part * PI * r * r * l;
            let particles: Real = g.volumes.iter().sum();
            assert!(
                ((particles - exact) / exact).abs() < 1e-12,
                "{sector:?}: {particles} against {exact}"
            );
            let mut cells = 0.0;
            for c in 0..g.cells.len() {
                for &(a, wa) in &GAUSS4 {
                    for &(b, wb) in &GAUSS4 {
                        for &(e, we) in &GAUSS4 {
                            cells += g.cell_point(c, [a, b, e]).1 * wa * wb * we;
                        }
                    }
                }
            }
            assert!(
                ((cells - exact) / exact).abs() < 1e-12,
                "{sector:?}: {cells}"
            );
        }
    }

    /// The outer layer lies on the circle, the particles of a symmetry plane on it exactly,
    /// none beyond, and each cell's map keeps a positive Jacobian.
    #[test]
    fn surface_on_the_circle_and_planes_exact() {
        let g = grid(Sector::Quarter);
        let r = g.radius();
        let on_circle = g
            .positions
            .iter()
            .filter(|x| ((x[0].hypot(x[1]) - r) / r).abs() < 1e-14)
            .count();
        // The quarter arc has n + 1 particles per layer (a quarter of the ring's 4n).
        assert_eq!(on_circle, (8 + 1) * 21);
        assert!(g.positions.iter().all(|x| x[0] >= 0.0 && x[1] >= 0.0));
        let on_x0 = g.positions.iter().filter(|x| x[0] == 0.0).count();
        let on_y0 = g.positions.iter().filter(|x| x[1] == 0.0).count();
        // n / 2 core particles, m ring particles and the axis on each plane, per layer.
        assert_eq!(on_x0, (8 / 2 + 4 + 1) * 21);
        assert_eq!(on_y0, on_x0);
        for c in 0..g.cells.len() {
            for xi in [
                [-1.0, -1.0, -1.0],
                [1.0, 1.0, 1.0],
                [1.0, -1.0, 0.0],
                [-1.0, 1.0, 0.0],
            ] {
                assert!(g.cell_point(c, xi).1 > 0.0, "cell {c} at {xi:?}");
            }
        }
    }

    /// Each cell's corners are its particles: the map at the reference corners gives their
    /// positions.
    #[test]
    fn cells_map_their_corners_to_their_particles() {
        let g = grid(Sector::Half);
        let corners = [
            [-1.0, -1.0, -1.0],
            [1.0, -1.0, -1.0],
            [1.0, 1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
            [1.0, -1.0, 1.0],
            [1.0, 1.0, 1.0],
            [-1.0, 1.0, 1.0],
        ];
        for (c, cell) in g.cells.iter().enumerate() {
            for (xi, &v) in corners.iter().zip(cell) {
                let (x, _) = g.cell_point(c, *xi);
                let p = g.positions[v as usize];
                for k in 0..3 {
                    assert!((x[k] - p[k]).abs() < 1e-15, "cell {c} corner {xi:?}");
                }
            }
        }
    }

    /// The cells of a layer stay within a factor 4 of each other in volume (the ring's
    /// cells at the core's corners are the smallest) from coarse to fine grids.
    #[test]
    fn cells_stay_within_a_factor_four_in_volume() {
        for (n, m) in [(8, 4), (16, 8), (32, 14)] {
            let g = CylinderGrid::new(3.2e-3, 1e-3, [n, m, 1], 0.55, Sector::Quarter).unwrap();
            let v: Vec<Real> = (0..g.cells.len())
                .map(|c| g.cell_point(c, [0.0; 3]).1)
                .collect();
            let (lo, hi) = v
                .iter()
                .fold((Real::INFINITY, 0.0), |(a, b): (Real, Real), &x| {
                    (a.min(x), b.max(x))
                });
            assert!(hi / lo < 4.0, "n {n} m {m}: {}", hi / lo);
        }
    }

    /// The RK shape functions on the O-grid (variable supports) reproduce linear fields
    /// and their gradients at every integration point of the mapped q4 and q2 rules, and
    /// the points' weights add up to the cylinder's volume to the rules' accuracy on the
    /// arc: the particles are usable by the RKPM as they stand.
    #[test]
    fn rk_shape_functions_on_the_grid_reproduce_linear_fields_at_the_mapped_points() {
        use crate::rk_shape::KernelCloud;
        let g = CylinderGrid::new(3.2e-3, 3.0e-3, [8, 4, 6], 0.55, Sector::Quarter).unwrap();
        let cloud =
            KernelCloud::with_supports(g.positions.clone(), g.volumes.clone(), g.supports(1.5));
        let exact = 0.25 * PI * 3.2e-3 * 3.2e-3 * 3.0e-3;
        for rule in [IntegrationRule::Q4, IntegrationRule::Q2] {
            let (x, w) = g.points(rule);
            // The rule integrates the core's cells exactly and the ring's map (linear
            // outward, trigonometric along the arc) to O(dtheta^4): 8.7e-7 with cells of
            // 11 degrees.
            let total: Real = w.iter().sum();
            let error = (total - exact) / exact;
            assert!(error.abs() < 2e-6, "{rule:?}: {error:e}");
            let t = cloud.shape_table(&x, &|p| format!("point {p}")).unwrap();
            for (p, xp) in x.iter().enumerate() {
                let (mut sum, mut first, mut grad) = (0.0, [0.0; 3], [[0.0; 3]; 3]);
                for e in t.row(p) {
                    let xi = g.positions[t.index[e] as usize];
                    sum += t.n[e];
                    for k in 0..3 {
                        first[k] += t.n[e] * xi[k];
                        for (j, gj) in grad[k].iter_mut().enumerate() {
                            *gj += t.grad[j][e] * xi[k];
                        }
                    }
                }
                assert!((sum - 1.0).abs() < 1e-12, "{rule:?} point {p}: sum {sum}");
                for k in 0..3 {
                    assert!((first[k] - xp[k]).abs() < 1e-15, "{rule:?} point {p}");
                    for (j, gj) in grad[k].iter().enumerate() {
                        let id = if j == k { 1.0 } else { 0.0 };
                        assert!((gj - id).abs() < 1e-10, "{rule:?} point {p}");
                    }
                }
            }
        }
    }

    /// The nodal domains tile the cylinder: their volumes add up to its volume, each is
    /// closed (its boundary's area vectors add up to zero) and satisfies the divergence
    /// theorem for a linear field (`sum x n w = V I`), to the face rule's accuracy on the
    /// arc; and SCNI's smoothed gradients of the RK shape functions reproduce a linear
    /// field's gradient in every domain, at the surface and on the symmetry planes too:
    /// the linear patch test of SCNI on the O-grid.
    /// The largest error of row `p`'s smoothed gradient of the position field, `|sum_I
    /// x_I,k B_I,j - delta_kj|`: a linear field's gradient, which a smoothed gradient
    /// passing the patch test reproduces.
    fn position_gradient_error(t: &ShapeTable<3>, p: usize, positions: &[[Real; 3]]) -> Real {
        let mut g = [[0.0; 3]; 3];
        for e in t.row(p) {
            for (gk, xk) in g.iter_mut().zip(positions[t.index[e] as usize]) {
                for (gkj, column) in gk.iter_mut().zip(&t.grad) {
                    *gkj += column[e] * xk;
                }
            }
        }
        let mut worst: Real = 0.0;
        for (k, gk) in g.iter().enumerate() {
            for (j, gkj) in gk.iter().enumerate() {
                let id = if j == k { 1.0 } else { 0.0 };
                worst = worst.max((gkj - id).abs());
            }
        }
        worst
    }

    /// The octants of the nodal domains (the stabilization's smoothing cells) tile each
    /// domain, are closed, and their smoothed gradients reproduce a linear field.
    #[test]
    fn octants_tile_the_nodal_domains_and_pass_the_linear_patch_test() {
        use crate::integration::smoothed;
        use crate::rk_shape::KernelCloud;
        let (r, l) = (3.2e-3, 3.0e-3);
        for sector in [Sector::Full, Sector::Quarter] {
            let g = CylinderGrid::new(r, l, [4, 2, 3], 0.55, sector).unwrap();
            let domains = g.nodal_domains();
            let own = g.particle_octants();
            assert!(own.iter().all(|o| !o.is_empty() && o.len() <= MAX_OCTANTS));
            let d = g.octant_domains(&own);
            assert_eq!(d.volumes.len(), MAX_OCTANTS * own.len());
            for (i, v) in domains.volumes.iter().enumerate() {
                let sum: Real = d.volumes[MAX_OCTANTS * i..MAX_OCTANTS * (i + 1)]
                    .iter()
                    .sum();
                assert!(
                    ((sum - v) / v).abs() < 1e-12,
                    "{sector:?} domain {i}: {sum} vs {v}"
                );
            }
            let b = &d.boundaries;
            let cloud =
                KernelCloud::with_supports(g.positions.clone(), g.volumes.clone(), g.supports(1.5));
            let on_faces = cloud.shape_table(&d.sites, &|q| format!("{q}")).unwrap();
            let t = smoothed(None, &on_faces, b, &d.volumes);
            let mut worst: [Real; 2] = [0.0; 2];
            for (o, v) in d.volumes.iter().enumerate() {
                if *v == 0.0 {
                    assert_eq!(b.offsets[o], b.offsets[o + 1]);
                    assert!(t.row(o).is_empty());
                    continue;
                }
                let mut closure = [0.0; 3];
                for term in b.offsets[o]..b.offsets[o + 1] {
                    for (c, nw) in closure.iter_mut().zip(b.nw[term]) {
                        *c += nw;
                    }
                }
                let area = v.powf(2.0 / 3.0);
                for c in closure {
                    worst[0] = worst[0].max(c.abs() / area);
                }
                worst[1] = worst[1].max(position_gradient_error(&t, o, &g.positions));
            }
            // The domains' face rule on quarter faces: measured 1.4e-11 (closure, relative
            // to the octant's face area) and 6.1e-9 (the gradient) on the ring's cells of
            // 22.5 degrees of arc.
            assert!(worst[0] < 1e-10 && worst[1] < 2e-8, "{sector:?}: {worst:?}");
        }
    }

    #[test]
    fn nodal_domains_tile_the_cylinder_and_pass_the_linear_patch_test() {
        use crate::integration::smoothed;
        use crate::rk_shape::KernelCloud;
        let (r, l) = (3.2e-3, 3.0e-3);
        for (sector, part) in [(Sector::Full, 1.0), (Sector::Quarter, 0.25)] {
            let g = CylinderGrid::new(r, l, [4, 2, 3], 0.55, sector).unwrap();
            let d = g.nodal_domains();
            let exact = part * PI * r * r * l;
            let total: Real = d.volumes.iter().sum();
            assert!(
                ((total - exact) / exact).abs() < 1e-12,
                "{sector:?}: {total}"
            );
            let b = &d.boundaries;
            let mut worst: [Real; 2] = [0.0; 2];
            for (i, v) in d.volumes.iter().enumerate() {
                assert!(*v > 0.0, "{sector:?} domain {i}");
                let (mut closure, mut divergence) = ([0.0; 3], [[0.0; 3]; 3]);
                for t in b.offsets[i]..b.offsets[i + 1] {
                    let (x, nw) = (d.sites[b.rows[t] as usize], b.nw[t]);
                    for k in 0..3 {
                        closure[k] += nw[k];
                        for j in 0..3 {
                            divergence[k][j] += x[k] * nw[j];
                        }
                    }
                }
                let area = v.powf(2.0 / 3.0);
                for (k, (c, row)) in closure.iter().zip(&divergence).enumerate() {
                    worst[0] = worst[0].max(c.abs() / area);
                    for (j, dkj) in row.iter().enumerate() {
                        let id = if j == k { *v } else { 0.0 };
                        worst[1] = worst[1].max((dkj - id).abs() / v);
                    }
                }
            }
            // The 3-point face rule on the ring's cells of 22.5 degrees of arc (the
            // coarsest grid): the trigonometric map integrated to O(dtheta^6), measured
            // 2.2e-11 (closure) and 6.0e-9 (divergence); the core's faces are exact.
            assert!(worst[0] < 1e-10 && worst[1] < 1e-8, "{sector:?}: {worst:?}");
            let cloud =
                KernelCloud::with_supports(g.positions.clone(), g.volumes.clone(), g.supports(1.5));
            let at_centre = cloud
                .shape_table(&d.centroids, &|p| format!("{p}"))
                .unwrap();
            let on_faces = cloud.shape_table(&d.sites, &|q| format!("{q}")).unwrap();
            let t = smoothed(Some(&at_centre), &on_faces, b, &d.volumes);
            // Measured: a gradient error up to about 6e-9 (domain 0 of the full grid: 7e-10),
            // the divergence's error over the domain.
            for p in 0..d.volumes.len() {
                let error = position_gradient_error(&t, p, &g.positions);
                assert!(error < 2e-8, "{sector:?} domain {p}: {error}");
            }
        }
    }

    #[test]
    fn bad_counts_are_named() {
        let e = CylinderGrid::new(1.0, 1.0, [3, 2, 2], 0.5, Sector::Full).unwrap_err();
        assert!(e.contains("even"), "{e}");
        let e = CylinderGrid::new(1.0, 1.0, [4, 2, 2], 0.8, Sector::Full).unwrap_err();
        assert!(e.contains("half side"), "{e}");
    }
}
