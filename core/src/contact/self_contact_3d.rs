//! Contact of a 3D workpiece with itself: the paper's particle-to-segment algorithm
//! (Sidibe et al. 2009, section II-3, eqs. 4-7) with the workpiece's own current surface as
//! the master, as [`crate::contact::self_contact`] does in 2D, so that two parts of the
//! surface that meet press on each other instead of passing through (a fold, or a lap when
//! it closes).
//!
//! The surface is the faces of the background hexahedral cells that belong to one cell only
//! and do not lie on a symmetry plane (the heat stage's surface), through the particles'
//! predicted positions. Each quadrilateral face is split into four triangles through its
//! centre `c = (x_0 + x_1 + x_2 + x_3) / 4` (m), so that the facet is continuous and a point
//! on it has the weights `w_a` on the face's four particles with `sum w_a = 1` and
//! `sum w_a x_a` the point: `lambda_0`, `lambda_1` on the triangle's two corners plus a
//! quarter of the centre's `lambda_c` on each of the four (bilinear at the corners and along
//! the edges). Every surface particle `k` is a slave of every face except those with a corner
//! within `s` cells of it in the reference configuration along every axis (`s` the
//! particles on either side that share its RK coefficients, [`neighbours`], the 2D rule
//! over the ring in three dimensions); the faces near it are found in uniform bins
//! ([`Bins`]), not by an all-pairs search.
//!
//! A slave is in contact when the closest point `q` of its candidate faces lies behind the
//! surface there (`(x_k - q) . N < 0`, `N` the outward angle-weighted pseudo-normal of the
//! feature `q` lies on: the triangle's normal on its interior, the sum of the two
//! triangles' normals on an edge, `sum alpha_t n_t` over the triangles at a vertex,
//! `alpha_t` the triangle's angle there; Baerentzen and Aanaes 2005, as
//! [`crate::triangle_surface`] signs a die's distance; the faces left out as the slave's
//! neighbours' count in the pseudo-normals, as 2D's vertex normals count both segments)
//! within the search depth `D` (one smallest spacing, [`SEARCH_DEPTH_SPACINGS`]), and
//! either it was in contact at the last stage or its gap is within twice its displacement
//! relative to the master point over the step, `g <= 2 dt |v_k - v_q|` (m): 2D's rule,
//! which keeps the two faces of a thin part and a particle next to a convex edge (behind a
//! far face by a spacing) out of contact.
//!
//! The force on the slave is 2D's: eq. 4's normal penalty with half the pair's reduced mass
//! (a symmetric two-pass treatment, each face a slave of the other), `f_n = mu g / (2 dt
//! dt_avg)`, `mu = m_k m_q / (m_k + m_q)` (kg), `m_q = sum w_a m_a` the master point's
//! interpolated mass, along the push direction `(q - x_k) / g`; friction as for tools
//! (eqs. 5-6, [`penalty_force`]) with the scene's `self_contact.friction` and the velocity
//! relative to the master point `v_k - sum w_a v_a` (m/s). The reaction `-f` acts at the
//! master point, shared `w_a` by the face's four particles: the forces sum to zero and,
//! as `sum w_a x_a = q`, their moment is that of `-f` at `q`. Both are internal to the
//! workpiece: the energy account books their work with the other contact forces.
//!
//! The search runs only where a contact could exist ([`SelfContact3::due`]): a full search
//! notes each slave's distance to its nearest candidate face; until the surface has moved
//! relative to itself by more than the least of those distances less `D`, no contact can
//! begin and nothing is searched.

use crate::contact::self_contact::{neighbours, SEARCH_DEPTH_SPACINGS};
use crate::contact::sidibe2009::{penalty_force, Interface, Slave};
use crate::friction::Friction;
use crate::math::Real;
use crate::segment_bins::{padded_bounds, Bins};
use crate::stl::{cross, dot, sub};
use crate::tools::Penetration;
use crate::triangle_surface::{box_distance2, closest_on_triangle, Feature};
use std::collections::HashMap;

mod crossings;
pub use crossings::{Crossing, Crossings};

/// The winding number above which a surface particle has passed through another part of
/// the surface ([`Surface::passed_through`]): halfway between a surface point's 1/2 and a
/// passed-through point's 3/2, with room for a bent neighbourhood.
pub const PASSED: Real = 1.0;

/// No face across an edge (an edge on a symmetry plane).
const NONE: u32 = u32::MAX;

/// The workpiece's surface in 3D: quadrilateral faces over surface particles ("slots"),
/// with what the search reads of their reference configuration.
#[derive(Debug, Clone, Default)]
pub struct Surface {
    /// The particles on the surface, ascending.
    pub particles: Vec<u32>,
    /// Each face's corners in order around it (outward by the right-hand rule), as slots.
    pub faces: Vec<[u32; 4]>,
    /// Each slot's reference position (m).
    reference: Vec<[Real; 3]>,
    /// Each slot's cell extents (m), the spacing its neighbourhood is counted in.
    extents: Vec<[Real; 3]>,
    /// For each face and each edge `q` (corners `q`, `q + 1`), the face across it.
    across: Vec<[u32; 4]>,
    /// The (face, corner) at each slot: those of slot `s` from `first[s]` to `first[s + 1]`.
    first: Vec<u32>,
    at: Vec<(u32, u8)>,
}

impl Surface {
    /// The surface of `faces` (corners as slots into `particles`), with each slot's
    /// reference position `reference` (m) and cell extents `extents` (m).
    pub fn new(
        particles: Vec<u32>,
        faces: Vec<[u32; 4]>,
        reference: Vec<[Real; 3]>,
        extents: Vec<[Real; 3]>,
    ) -> Surface {
        let mut edges: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        for (f, c) in faces.iter().enumerate() {
            for q in 0..4 {
                let (a, b) = (c[q], c[(q + 1) % 4]);
                edges
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push(f as u32);
            }
        }
        let across = faces
            .iter()
            .enumerate()
            .map(|(f, c)| {
                std::array::from_fn(|q| {
                    let (a, b) = (c[q], c[(q + 1) % 4]);
                    edges[&(a.min(b), a.max(b))]
                        .iter()
                        .copied()
                        .find(|&g| g != f as u32)
                        .unwrap_or(NONE)
                })
            })
            .collect();
        let mut at: Vec<Vec<(u32, u8)>> = vec![Vec::new(); particles.len()];
        for (f, c) in faces.iter().enumerate() {
            for (q, &s) in c.iter().enumerate() {
                at[s as usize].push((f as u32, q as u8));
            }
        }
        let mut first = vec![0];
        for a in &at {
            first.push(first[first.len() - 1] + a.len() as u32);
        }
        Surface {
            particles,
            faces,
            reference,
            extents,
            across,
            first,
            at: at.concat(),
        }
    }

    /// Number of surface particles.
    pub fn len(&self) -> usize {
        self.particles.len()
    }

    /// Whether the surface has no particle.
    pub fn is_empty(&self) -> bool {
        self.particles.is_empty()
    }

    /// Slot `s`'s position in the undeformed workpiece (m).
    pub fn reference(&self, s: usize) -> [Real; 3] {
        self.reference[s]
    }

    /// Whether slots `a` and `b` lie within `s` cells of each other along every axis in the
    /// reference configuration (cells of the larger of their extents).
    pub fn near(&self, a: usize, b: usize, s: usize) -> bool {
        let (xa, xb) = (self.reference[a], self.reference[b]);
        (0..3).all(|c| {
            let cell = self.extents[a][c].max(self.extents[b][c]);
            (xa[c] - xb[c]).abs() <= s as Real * cell * (1.0 + 1e-9)
        })
    }

    /// Whether the reference point `r` (m) lies within `s` cells of slot `k` along every
    /// axis (cells of the slot's extents).
    fn near_point(&self, k: usize, r: [Real; 3], s: usize) -> bool {
        let xk = self.reference[k];
        (0..3).all(|c| (xk[c] - r[c]).abs() <= s as Real * self.extents[k][c] * (1.0 + 1e-9))
    }

    /// Whether face `f` has a corner within `s` cells of slot `k` ([`Surface::near`]).
    fn excluded(&self, k: usize, f: usize, s: usize) -> bool {
        self.faces[f].iter().any(|&a| self.near(k, a as usize, s))
    }

    /// The centres and the triangles' unit normals of every face at the positions `x` (m,
    /// by slot).
    fn geometry(&self, x: &[[Real; 3]], geo: &mut Geometry) {
        geo.centre.clear();
        geo.normal.clear();
        geo.boxes.clear();
        for c in &self.faces {
            let p = c.map(|s| x[s as usize]);
            geo.boxes.push([
                std::array::from_fn(|k| p.iter().fold(Real::INFINITY, |m, q| m.min(q[k]))),
                std::array::from_fn(|k| p.iter().fold(Real::NEG_INFINITY, |m, q| m.max(q[k]))),
            ]);
            let m: [Real; 3] =
                std::array::from_fn(|k| 0.25 * (p[0][k] + p[1][k] + p[2][k] + p[3][k]));
            geo.centre.push(m);
            geo.normal.push(std::array::from_fn(|q| {
                unit(cross(sub(p[(q + 1) % 4], p[q]), sub(m, p[q])))
            }));
        }
    }

    /// Triangle `q` of face `f`: its corners `q`, `q + 1` and the centre.
    fn triangle(&self, x: &[[Real; 3]], geo: &Geometry, f: usize, q: usize) -> [[Real; 3]; 3] {
        let c = self.faces[f];
        [x[c[q] as usize], x[c[(q + 1) % 4] as usize], geo.centre[f]]
    }

    /// Bins of the faces at the positions `x` (m), each listed where it lies within `reach`
    /// (m).
    fn bin(&self, x: &[[Real; 3]], geo: &Geometry, reach: Real, bins: &mut Bins<3>) {
        let [lo, hi] = padded_bounds(x, reach);
        // Bins of the reach, but no more than about one per face.
        let volume = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
        let size = reach.max((volume / self.faces.len().max(1) as Real).cbrt());
        bins.fill_boxes(geo.boxes.iter().copied(), [lo, hi], reach, size);
    }

    /// The closest point to slot `k` of the faces binned near it that are not its
    /// neighbours' (`s` cells), at the positions `x` (m).
    fn closest(
        &self,
        k: usize,
        x: &[[Real; 3]],
        geo: &Geometry,
        bins: &Bins<3>,
        s: usize,
    ) -> Option<Nearest> {
        let xk = x[k];
        let mut best: Option<Nearest> = None;
        for &f in bins.candidates(xk) {
            let f = f as usize;
            // A face whose box lies beyond the nearest found by more than the rounding
            // (a relative 1e-6, an absolute 1e-9 of the face's size) cannot be nearer.
            if best.is_some_and(|b| {
                let [lo, hi] = geo.boxes[f];
                let size2 = dot(sub(hi, lo), sub(hi, lo));
                box_distance2(xk, [lo, hi]) > b.d2 * (1.0 + 1e-6) + 1e-18 * size2
            }) {
                continue;
            }
            if self.excluded(k, f, s) {
                continue;
            }
            for q in 0..4 {
                let (point, feature) = closest_on_triangle(xk, self.triangle(x, geo, f, q));
                let d = sub(xk, point);
                let d2 = dot(d, d);
                if best.is_none_or(|b| d2 < b.d2) {
                    best = Some(Nearest {
                        d2,
                        face: f,
                        triangle: q,
                        point,
                        feature,
                    });
                }
            }
        }
        best
    }

    /// The outward pseudo-normal (not of unit length) of the feature `b` lies on (module
    /// doc).
    fn pseudo_normal(&self, x: &[[Real; 3]], geo: &Geometry, b: &Nearest) -> [Real; 3] {
        let (f, q) = (b.face, b.triangle);
        let n = &geo.normal;
        let add = |a: [Real; 3], c: [Real; 3]| std::array::from_fn(|i| a[i] + c[i]);
        match b.feature {
            Feature::Face => n[f][q],
            // The face's own edge: shared with the face across it.
            Feature::Edge(0) => match self.across[f][q] {
                NONE => n[f][q],
                g => {
                    let g = g as usize;
                    let (a, c) = (self.faces[f][q], self.faces[f][(q + 1) % 4]);
                    let r = (0..4)
                        .find(|&r| {
                            let e = [self.faces[g][r], self.faces[g][(r + 1) % 4]];
                            e == [c, a] || e == [a, c]
                        })
                        .unwrap_or(0);
                    add(n[f][q], n[g][r])
                }
            },
            // The edges to the centre, shared with the face's next and last triangles.
            Feature::Edge(1) => add(n[f][q], n[f][(q + 1) % 4]),
            Feature::Edge(_) => add(n[f][q], n[f][(q + 3) % 4]),
            Feature::Vertex(2) => (0..4).fold([0.0; 3], |acc, r| {
                let t = self.triangle(x, geo, f, r);
                add(acc, n[f][r].map(|v| v * angle(t[2], t[0], t[1])))
            }),
            Feature::Vertex(v) => {
                let slot = self.faces[f][(q + v as usize) % 4] as usize;
                let at = &self.at[self.first[slot] as usize..self.first[slot + 1] as usize];
                at.iter().fold([0.0; 3], |acc, &(g, r)| {
                    let (g, r) = (g as usize, r as usize);
                    // The triangles r (the slot its first corner) and r - 1 (its second).
                    let t = self.triangle(x, geo, g, r);
                    let u = self.triangle(x, geo, g, (r + 3) % 4);
                    let a = n[g][r].map(|v| v * angle(t[0], t[1], t[2]));
                    let b = n[g][(r + 3) % 4].map(|v| v * angle(u[1], u[2], u[0]));
                    add(acc, add(a, b))
                })
            }
        }
    }

    /// The weights on face `f`'s four corners of a point `p` of its triangle `q` at the
    /// positions `x` (m): the triangle's barycentric coordinates, the centre's shared a
    /// quarter to each corner (module doc).
    fn weights(
        &self,
        x: &[[Real; 3]],
        geo: &Geometry,
        f: usize,
        q: usize,
        p: [Real; 3],
    ) -> [Real; 4] {
        let [a, b, c] = self.triangle(x, geo, f, q);
        let (v0, v1, v2) = (sub(b, a), sub(c, a), sub(p, a));
        let (d00, d01, d11) = (dot(v0, v0), dot(v0, v1), dot(v1, v1));
        let (d20, d21) = (dot(v2, v0), dot(v2, v1));
        let den = d00 * d11 - d01 * d01;
        let (l1, l2) = if den > 0.0 {
            ((d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den)
        } else {
            (0.0, 0.0)
        };
        let l0 = 1.0 - l1 - l2;
        let mut w = [0.25 * l2; 4];
        w[q] += l0;
        w[(q + 1) % 4] += l1;
        w
    }

    /// The deepest a surface particle has passed through another part of the surface, at
    /// the positions `x` (m, by slot), the body mirrored on its symmetry planes `mirrors`
    /// (`(axis, coordinate)`): `(depth (m), slot)`, depth 0 when none has. The measure the
    /// contact's own checks cannot see. A particle has passed through when the winding
    /// number at it of the surface (the faces and their mirror images) less its neighbours'
    /// faces (`s` cells) exceeds [`PASSED`], `w = sum_t Omega_t / (4 pi)` over the faces'
    /// triangles, `Omega_t` the signed solid angle of triangle `t` (sr; Van Oosterom and
    /// Strackee 1983): a point on the closed surface has `w` in [0, 1] (1/2 on a smooth
    /// part, less at a convex edge, more at a concave one), a point on one part's surface
    /// and inside another `3/2`; leaving out the neighbours' faces (which pass near the point
    /// or through it) changes that by their solid angle, zero for a flat neighbourhood, and
    /// leaves out a fold shorter than the support (which the contact does not hold either).
    /// Its depth is then its distance to the nearest face not its neighbours'.
    pub fn passed_through(
        &self,
        x: &[[Real; 3]],
        mirrors: &[(usize, Real)],
        s: usize,
    ) -> (Real, usize) {
        let mut geo = Geometry::default();
        self.geometry(x, &mut geo);
        let mut worst = (0.0, 0);
        for (k, &p) in x.iter().enumerate().take(self.len()) {
            if self.at[self.first[k] as usize..self.first[k + 1] as usize].is_empty() {
                continue;
            }
            let mut w = 0.0;
            // A particle held on a symmetry plane (within a hundredth of its cell: the plane's
            // penalty holds it a small fraction of a spacing beyond) is read on the plane, so
            // that its own faces' mirror images pass through it as its own faces do.
            let cell = self.extents[k]
                .iter()
                .copied()
                .fold(Real::INFINITY, Real::min);
            let mut p = p;
            for &(axis, at) in mirrors {
                if (p[axis] - at).abs() <= 0.01 * cell {
                    p[axis] = at;
                }
            }
            // A mirror image of a face, turned outward again, subtends at `p` the face's
            // solid angle at the mirror image of `p`.
            for mask in 0..1usize << mirrors.len() {
                let mut m = p;
                for (i, &(axis, at)) in mirrors.iter().enumerate() {
                    if mask >> i & 1 == 1 {
                        m[axis] = 2.0 * at - m[axis];
                    }
                }
                // The copy's faces within `s` cells of the slave in the reference
                // configuration are its neighbours': left out.
                let mirrored = |a: u32| {
                    let mut r = self.reference[a as usize];
                    for (i, &(axis, at)) in mirrors.iter().enumerate() {
                        if mask >> i & 1 == 1 {
                            r[axis] = 2.0 * at - r[axis];
                        }
                    }
                    r
                };
                for (f, c) in self.faces.iter().enumerate() {
                    if c.iter().any(|&a| self.near_point(k, mirrored(a), s)) {
                        continue;
                    }
                    for q in 0..4 {
                        w += solid_angle(m, self.triangle(x, &geo, f, q));
                    }
                }
            }
            w /= 4.0 * std::f64::consts::PI;
            if w <= PASSED {
                continue;
            }
            let depth = (0..self.faces.len())
                .filter(|&f| !self.excluded(k, f, s))
                .flat_map(|f| (0..4).map(move |q| (f, q)))
                .map(|(f, q)| {
                    let d = sub(p, closest_on_triangle(p, self.triangle(x, &geo, f, q)).0);
                    dot(d, d)
                })
                .fold(Real::INFINITY, Real::min)
                .sqrt();
            if depth.is_finite() && depth > worst.0 {
                worst = (depth, k);
            }
        }
        worst
    }
}

/// The signed solid angle of the triangle `t` seen from `p` (sr), positive when `p` lies
/// behind it (on the side its normal points away from): Van Oosterom and Strackee, IEEE
/// Trans. Biomed. Eng. 30(2), 1983, `tan(Omega / 2) = a . (b x c) / d` with
/// `d = |a||b||c| + (a . b)|c| + (a . c)|b| + (b . c)|a|`, `a`, `b`, `c` the corners
/// relative to `p`. Zero when `p` is a corner.
fn solid_angle(p: [Real; 3], t: [[Real; 3]; 3]) -> Real {
    let [a, b, c] = t.map(|v| sub(v, p));
    let (la, lb, lc) = (dot(a, a).sqrt(), dot(b, b).sqrt(), dot(c, c).sqrt());
    let num = dot(a, cross(b, c));
    let den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    2.0 * num.atan2(den)
}

/// `v / |v|`, zero for a zero vector.
fn unit(v: [Real; 3]) -> [Real; 3] {
    let l = dot(v, v).sqrt();
    if l > 0.0 {
        v.map(|x| x / l)
    } else {
        [0.0; 3]
    }
}

/// The angle at `p` of the triangle `(p, a, b)` (rad).
fn angle(p: [Real; 3], a: [Real; 3], b: [Real; 3]) -> Real {
    let (u, w) = (sub(a, p), sub(b, p));
    let c = cross(u, w);
    dot(c, c).sqrt().atan2(dot(u, w))
}

/// The faces' centres and their triangles' unit normals at one configuration.
#[derive(Debug, Clone, Default)]
struct Geometry {
    centre: Vec<[Real; 3]>,
    normal: Vec<[[Real; 3]; 4]>,
    /// Each face's bounding box `[lo, hi]` (m).
    boxes: Vec<[[Real; 3]; 2]>,
}

/// The closest point of a slave's candidate faces.
#[derive(Debug, Clone, Copy)]
struct Nearest {
    /// Squared distance (m^2).
    d2: Real,
    /// The face and its triangle.
    face: usize,
    triangle: usize,
    /// The point (m).
    point: [Real; 3],
    /// The triangle's feature it lies on.
    feature: Feature,
}

/// One slave in contact with a master face in the last search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pair3 {
    /// The slave's slot.
    pub slave: u32,
    /// The master face.
    pub face: u32,
    /// The master point's weights on the face's four corners.
    pub weights: [Real; 4],
    /// The gap `g` (m), positive.
    pub gap: Real,
    /// Unit push direction on the slave, from it to the master point.
    pub normal: [Real; 3],
}

/// The 3D self-contact search and what it keeps between stages (none of it state:
/// [`SelfContact3::forget`] only makes the next stage search).
#[derive(Debug, Clone)]
pub struct SelfContact3 {
    /// Friction law between the surface's parts.
    pub friction: Friction,
    /// The surface.
    pub surface: Surface,
    /// Search depth `D` (m).
    depth: Real,
    /// Cells on either side of a slave whose faces it is not tested against.
    pub neighbours: usize,
    /// Whether a search has run since the last [`SelfContact3::forget`].
    searched: bool,
    /// Bound on how far the surface moved relative to itself since the last search (m).
    moved: Real,
    /// The least over the slaves of the distance to the nearest candidate face at the last
    /// search, less `D` (m).
    least_clear: Real,
    geo: Geometry,
    bins: Bins<3>,
    /// The contacts of the last search.
    pairs: Vec<Pair3>,
}

impl SelfContact3 {
    /// The search over `surface` with the friction law `friction` (`self_contact.friction`),
    /// smallest spacing `h_min` (m) and kernel support `support` cells.
    pub fn new(friction: Friction, surface: Surface, h_min: Real, support: Real) -> SelfContact3 {
        SelfContact3 {
            friction,
            surface,
            depth: SEARCH_DEPTH_SPACINGS * h_min,
            neighbours: neighbours([support; 2]),
            searched: false,
            moved: 0.0,
            least_clear: Real::NEG_INFINITY,
            geo: Geometry::default(),
            bins: Bins::default(),
            pairs: Vec::new(),
        }
    }

    /// Adds `moved` (m), a bound on how far any two surface points moved relative to each
    /// other since the last stage; whether this stage must search (module doc).
    pub fn due(&mut self, moved: Real) -> bool {
        self.moved += moved;
        !self.searched || !self.moved.is_finite() || self.least_clear - self.moved <= 0.0
    }

    /// Forgets the last search, so that the next stage searches.
    pub fn forget(&mut self) {
        self.searched = false;
        self.pairs.clear();
    }

    /// The contacts of the last search (empty at a stage that did not search).
    pub fn pairs(&self) -> &[Pair3] {
        &self.pairs
    }

    /// Drops the last search's contacts (a stage without a search).
    pub fn clear(&mut self) {
        self.pairs.clear();
    }

    /// The search on the surface's predicted positions `x` (m, by slot) and velocities `v`
    /// (m/s) over the natural step `dt` (s), with `touching` the slots in contact at the
    /// last stage, updated to this stage's: fills [`SelfContact3::pairs`] in slot order.
    pub fn search(&mut self, x: &[[Real; 3]], v: &[[Real; 3]], dt: Real, touching: &mut [bool]) {
        self.pairs.clear();
        self.searched = true;
        self.moved = 0.0;
        let (depth, reach, s) = (self.depth, 2.0 * self.depth, self.neighbours);
        let surface = &self.surface;
        surface.geometry(x, &mut self.geo);
        surface.bin(x, &self.geo, reach, &mut self.bins);
        let mut least = depth;
        for (k, touch) in touching.iter_mut().enumerate() {
            let was = std::mem::replace(touch, false);
            let Some(b) = surface.closest(k, x, &self.geo, &self.bins, s) else {
                continue;
            };
            let d = b.d2.sqrt();
            least = least.min(d.min(reach) - depth);
            if d > depth || d <= 0.0 {
                continue;
            }
            let (f, q) = (b.face, b.triangle);
            let w = surface.weights(x, &self.geo, f, q, b.point);
            if !was {
                let corners = surface.faces[f];
                let rel: [Real; 3] = std::array::from_fn(|i| {
                    v[k][i]
                        - (0..4)
                            .map(|a| w[a] * v[corners[a] as usize][i])
                            .sum::<Real>()
                });
                if d * d > 4.0 * dt * dt * dot(rel, rel) {
                    continue;
                }
            }
            if dot(sub(x[k], b.point), surface.pseudo_normal(x, &self.geo, &b)) >= 0.0 {
                continue;
            }
            *touch = true;
            self.pairs.push(Pair3 {
                slave: k as u32,
                face: f as u32,
                weights: w,
                gap: d,
                normal: sub(b.point, x[k]).map(|c| c / d),
            });
        }
        self.least_clear = least;
    }

    /// The force on the slave of `pair` (N; the module doc): eq. 4 with half the pair's
    /// reduced mass, the slots' masses `mass(slot)` (kg) and predicted velocities `v` (m/s,
    /// by slot), friction by the scene's law (eqs. 5-6) with the slave's flow stress and
    /// area `at`, over the natural step `dt` and the corrector's step `dt_avg` (s). The
    /// master point takes its reaction.
    pub fn pair_force(
        &self,
        pair: &Pair3,
        v: &[[Real; 3]],
        mass: impl Fn(usize) -> Real,
        at: Interface,
        dt: Real,
        dt_avg: Real,
    ) -> [Real; 3] {
        let k = pair.slave as usize;
        let corners = self.surface.faces[pair.face as usize].map(|a| a as usize);
        let w = pair.weights;
        let m_c: Real = (0..4).map(|a| w[a] * mass(corners[a])).sum();
        let m_k = mass(k);
        let reduced = m_k * m_c / (m_k + m_c);
        let v_rel = std::array::from_fn(|i| {
            v[k][i] - (0..4).map(|a| w[a] * v[corners[a]][i]).sum::<Real>()
        });
        let slave = Slave {
            m: 0.5 * reduced,
            v_rel,
            carried: [0.0; 3],
        };
        let pen = Penetration {
            gap: pair.gap,
            normal: pair.normal,
        };
        penalty_force(slave, pen, &self.friction, at, dt, dt_avg).force
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The outer faces of a box of `n` particles per axis at spacing 1 (all six sides),
    /// corners outward, over slots numbered as the lattice.
    pub(crate) fn lattice_box(n: [usize; 3]) -> (Vec<[Real; 3]>, Surface) {
        let id = |i: usize, j: usize, k: usize| (i + n[0] * (j + n[1] * k)) as u32;
        let x: Vec<[Real; 3]> = (0..n[2])
            .flat_map(|k| {
                (0..n[1])
                    .flat_map(move |j| (0..n[0]).map(move |i| [i as Real, j as Real, k as Real]))
            })
            .collect();
        let mut faces = Vec::new();
        for k in 0..n[2] - 1 {
            for j in 0..n[1] - 1 {
                for i in 0..n[0] - 1 {
                    let c = [
                        id(i, j, k),
                        id(i + 1, j, k),
                        id(i + 1, j + 1, k),
                        id(i, j + 1, k),
                        id(i, j, k + 1),
                        id(i + 1, j, k + 1),
                        id(i + 1, j + 1, k + 1),
                        id(i, j + 1, k + 1),
                    ];
                    let sides = [
                        (k == 0, [0, 3, 2, 1]),
                        (k == n[2] - 2, [4, 5, 6, 7]),
                        (j == 0, [0, 1, 5, 4]),
                        (i == n[0] - 2, [1, 2, 6, 5]),
                        (j == n[1] - 2, [2, 3, 7, 6]),
                        (i == 0, [3, 0, 4, 7]),
                    ];
                    for (outer, f) in sides {
                        if outer {
                            faces.push(f.map(|a: usize| c[a]));
                        }
                    }
                }
            }
        }
        // Every particle a slot (inner ones on no face).
        let particles = (0..x.len() as u32).collect();
        let surface = Surface::new(particles, faces, x.clone(), vec![[1.0; 3]; x.len()]);
        (x, surface)
    }

    /// A strip of 13 x 3 x 2 particles whose right part (x > 6.5) is folded over onto the
    /// left part, turned half round the line x = 6.5, z = 0.975 (along y): its former top
    /// face lies at z = 0.95, 0.05 inside the left part's top face (z = 1). The two parts
    /// close at 0.1 per unit time. Positions, velocities and the surface.
    pub(crate) fn folded_strip() -> (Vec<[Real; 3]>, Vec<[Real; 3]>, Surface) {
        let (mut x, surface) = lattice_box([13, 3, 2]);
        let mut v = vec![[0.0, 0.0, 0.05]; x.len()];
        for (p, w) in x.iter_mut().zip(&mut v) {
            if p[0] > 6.5 {
                *p = [13.0 - p[0], p[1], 1.95 - p[2]];
                *w = [0.0, 0.0, -0.05];
            }
        }
        (x, v, surface)
    }

    pub(crate) fn search(
        x: &[[Real; 3]],
        surface: &Surface,
        v: &[[Real; 3]],
        touching: &mut [bool],
    ) -> Vec<Pair3> {
        let mut s = SelfContact3::new(Friction::default(), surface.clone(), 1.0, 2.0);
        s.search(x, v, 1.0, touching);
        s.pairs
    }

    #[test]
    fn a_box_and_a_thin_plate_touch_nothing() {
        let (x, surface) = lattice_box([6, 5, 7]);
        let v = vec![[0.0, 0.0, 1.0]; x.len()];
        assert!(search(&x, &surface, &v, &mut vec![false; x.len()]).is_empty());
        assert_eq!(surface.passed_through(&x, &[], 2), (0.0, 0));
        // A plate one spacing thick, pressed to half of it: its faces are neighbours.
        let (mut x, surface) = lattice_box([8, 6, 2]);
        for p in &mut x {
            p[2] *= 0.5;
        }
        assert!(search(&x, &surface, &v, &mut vec![false; x.len()]).is_empty());
    }

    #[test]
    fn a_half_box_mirrored_on_its_symmetry_plane_has_passed_nowhere() {
        let (x, surface) = lattice_box([5, 3, 4]);
        let keep: Vec<[u32; 4]> = surface
            .faces
            .iter()
            .copied()
            .filter(|f| !f.iter().all(|&a| x[a as usize][1] == 0.0))
            .collect();
        let half = Surface::new(
            surface.particles.clone(),
            keep,
            surface.reference.clone(),
            surface.extents.clone(),
        );
        let mut moved = x.clone();
        for p in &mut moved {
            if p[1] == 0.0 {
                p[1] = -1e-7;
            }
        }
        assert_eq!(half.passed_through(&moved, &[(1, 0.0)], 2), (0.0, 0));
    }

    #[test]
    fn a_strip_folded_through_itself_is_pushed_back_from_both_sides() {
        let (x, v, surface) = folded_strip();
        let pairs = search(&x, &surface, &v, &mut vec![false; x.len()]);
        assert!(!pairs.is_empty());
        let (mut up, mut down) = (0, 0);
        for p in &pairs {
            assert!((p.gap - 0.05).abs() < 1e-12, "{p:?}");
            assert!((p.weights.iter().sum::<Real>() - 1.0).abs() < 1e-12);
            // The master point is the weighted corners.
            let c = surface.faces[p.face as usize];
            let q: [Real; 3] = std::array::from_fn(|i| {
                (0..4)
                    .map(|a| p.weights[a] * x[c[a] as usize][i])
                    .sum::<Real>()
            });
            let k = p.slave as usize;
            assert!((0..3).all(|i| (x[k][i] + p.gap * p.normal[i] - q[i]).abs() < 1e-12));
            if p.normal[2] > 0.0 {
                up += 1;
            } else {
                down += 1;
            }
        }
        assert!(up > 0 && down > 0, "{pairs:?}");
        let (deep, _) = surface.passed_through(&x, &[], 2);
        assert!((deep - 0.05).abs() < 1e-12, "{deep}");
        // The same strip as the half y >= 1 of itself, mirrored on the plane y = 1.
        let keep: Vec<usize> = (0..surface.faces.len())
            .filter(|&f| surface.faces[f].iter().all(|&a| x[a as usize][1] >= 1.0))
            .collect();
        let half = Surface::new(
            surface.particles.clone(),
            keep.iter().map(|&f| surface.faces[f]).collect(),
            surface.reference.clone(),
            surface.extents.clone(),
        );
        let on_half: Vec<[Real; 3]> = x.iter().map(|p| [p[0], p[1].max(1.0), p[2]]).collect();
        let (deep, _) = half.passed_through(&on_half, &[(1, 1.0)], 2);
        assert!((deep - 0.05).abs() < 1e-12, "{deep}");
        // A contact does not begin so deep when the faces close slowly, but goes on.
        let slow: Vec<[Real; 3]> = v.iter().map(|w| w.map(|c| c * 0.1)).collect();
        assert!(search(&x, &surface, &slow, &mut vec![false; x.len()]).is_empty());
        let k = pairs[0].slave as usize;
        let mut touching = vec![false; x.len()];
        touching[k] = true;
        let on = search(&x, &surface, &slow, &mut touching);
        assert_eq!(on.len(), 1);
        assert_eq!(on[0].slave as usize, k);
    }
}
