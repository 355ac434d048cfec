//! The signed distance of a point to a closed triangle surface (a die read from an STL
//! file, [`crate::stl`]), with its closest point and contact normal, and the bins that
//! make a query far from the surface cost next to nothing.
//!
//! Closest point: on each candidate triangle `(a, b, c)` by its Voronoi regions (Ericson,
//! Real-Time Collision Detection, 2005, section 5.1.5): a vertex, an edge or the face;
//! the nearest over the candidates is the surface's closest point `q` (m).
//!
//! Sign: by the angle-weighted pseudo-normal of the feature `q` lies on (Baerentzen and
//! Aanaes, IEEE TVCG 11(3), 2005): the face's normal `n_f`; on an edge the sum of its two
//! faces' normals; on a vertex `sum_f alpha_f n_f` over its faces, `alpha_f` the face's
//! angle at the vertex (rad). `s = sign((x - q) . N)`: the signed distance `phi = s |x - q|`
//! (m) is negative inside the die and positive outside, exactly, for any closed, oriented
//! surface (what [`crate::stl::TriangleMesh::check`] guarantees). On a face, and on an edge
//! or vertex inside a flat region (whose pseudo-normal is the face's normal: the diagonal
//! of a die's flat face), `phi` is computed as `n_f . (x - a)`, the plane's own formula, so
//! a flat die gives the gap of the analytic plane through it to the bit.
//!
//! Contact normal (out of the die, towards the point): `n_f` on a face, else `s (x - q) /
//! |x - q|` (the pseudo-normal where `x = q`).
//!
//! Bins: a uniform grid over the surface's bounds, each bin listing the triangles whose
//! bounds overlap it; for the empty bins, the Chebyshev count `k` of bins to the nearest
//! occupied one (so no triangle lies within `(k - 1) h` of the bin, `h` the smallest bin
//! side) and whether the bin is inside the die (each face-connected set of empty bins lies
//! on one side of the surface; one exact query per set). A query within reach `r` of a
//! point outside the bounds, or in an empty bin farther than `r` from any occupied one,
//! returns a lower bound on the distance and the side without touching a triangle.
//!
//! Ridges: the die's convex features, which the contact stage's second pass checks against
//! the workpiece's surface between its particles (`solver/solid/ridges.rs`). An edge is a
//! ridge when its two faces' normals `n_1`, `n_2` part by more than [`RIDGE_ANGLE`]
//! (`n_1 . n_2 < cos RIDGE_ANGLE`) and the die is convex across it (the far corner of the
//! second face lies behind the first face's plane). A vertex is a ridge of no length when
//! three or more ridges meet at it (a punch's corner, a pyramid's tip), or when on none its
//! faces' normals part from its pseudo-normal `N_v` by more than [`RIDGE_ANGLE`] and every
//! neighbouring vertex lies behind the plane through it normal to `N_v` (the tip of a
//! finely faceted cone). A flat face's diagonals and a fine faceting
//! of a smooth die (a roll of 36 or more sides) have none.

use crate::math::Real;
use crate::stl::{cross, dot, sub, TriangleMesh};

/// The feature of a triangle a closest point lies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feature {
    /// The face's interior.
    Face,
    /// Edge `k`: 0 from a to b, 1 from b to c, 2 from c to a.
    Edge(u8),
    /// Vertex `k`: 0 a, 1 b, 2 c.
    Vertex(u8),
}

/// Squared distance (m^2) from `p` to the axis-aligned box `[lo, hi]`, 0 inside it: a
/// lower bound on the squared distance from `p` to anything inside the box.
pub fn box_distance2(p: [Real; 3], [lo, hi]: [[Real; 3]; 2]) -> Real {
    (0..3)
        .map(|k| {
            let o = (lo[k] - p[k]).max(p[k] - hi[k]).max(0.0);
            o * o
        })
        .sum()
}

/// The point of the triangle `(a, b, c)` closest to `p` and the feature it lies on
/// (Ericson 2005, section 5.1.5).
pub fn closest_on_triangle(p: [Real; 3], [a, b, c]: [[Real; 3]; 3]) -> ([Real; 3], Feature) {
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::Vertex(0));
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (along(a, ab, v), Feature::Edge(0));
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (along(a, ac, w), Feature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (along(b, sub(c, b), w), Feature::Edge(1));
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (
        std::array::from_fn(|k| a[k] + ab[k] * v + ac[k] * w),
        Feature::Face,
    )
}

/// The part `[t_0, t_1]` of the segment `a + t (b - a)`, `t` in [0, 1], inside the box
/// `lo..hi` (m), by its slabs; `None` when it misses the box.
pub fn clip_to_box(a: [Real; 3], b: [Real; 3], lo: [Real; 3], hi: [Real; 3]) -> Option<[Real; 2]> {
    let (mut t0, mut t1): (Real, Real) = (0.0, 1.0);
    for k in 0..3 {
        let e = b[k] - a[k];
        if e == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (u, v) = ((lo[k] - a[k]) / e, (hi[k] - a[k]) / e);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    (t0 <= t1).then_some([t0, t1])
}

/// `o + t e`.
pub(crate) fn along(o: [Real; 3], e: [Real; 3], t: Real) -> [Real; 3] {
    std::array::from_fn(|k| o[k] + t * e[k])
}

/// `v / |v|`.
fn unit(v: [Real; 3]) -> [Real; 3] {
    let l = dot(v, v).sqrt();
    v.map(|x| x / l)
}

/// The closest point of the surface to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// Signed distance `phi` (m): negative inside the die.
    pub signed: Real,
    /// Unit contact normal, out of the die towards the point.
    pub normal: [Real; 3],
    /// The closest point (m).
    pub point: [Real; 3],
    /// The triangle and the feature of it the closest point lies on.
    pub triangle: u32,
    /// The feature.
    pub feature: Feature,
}

/// Where a query point is with respect to the surface within a reach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Proximity {
    /// Farther than the reach: at least `distance` (m) from the surface, inside the die or
    /// not.
    Far {
        /// A lower bound on the distance to the surface (m).
        distance: Real,
        /// The point is inside the die.
        inside: bool,
    },
    /// Within the reach (or the bins could not rule it out): the exact closest point.
    Near(Closest),
}

/// The smallest angle between the normals of two faces (rad) that makes their convex edge
/// a ridge (20 degrees: the faceting of a smooth die of 18 or more sides stays below it).
pub const RIDGE_ANGLE: Real = 20.0 * std::f64::consts::PI / 180.0;

/// A convex feature of a die: an edge between faces meeting at a convex angle, or a convex
/// vertex on no such edge (then `a = b`), in the die's position at the start (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ridge {
    /// Its ends (m).
    pub a: [Real; 3],
    /// The other end (m).
    pub b: [Real; 3],
    /// Unit pseudo-normal out of the die: the sum of the two faces' normals, or the
    /// vertex's angle-weighted one.
    pub normal: [Real; 3],
}

/// A closed triangle surface with its pseudo-normals and bins.
#[derive(Debug, Clone)]
pub struct TriangleSurface {
    mesh: TriangleMesh,
    /// Unit face normals.
    face_normal: Vec<[Real; 3]>,
    /// Pseudo-normal of each triangle's edges (0: ab, 1: bc, 2: ca): the sum of the two
    /// faces' normals.
    edge_normal: Vec<[[Real; 3]; 3]>,
    /// Angle-weighted pseudo-normal of each vertex.
    vertex_normal: Vec<[Real; 3]>,
    /// The convex ridges and vertices, in the order of the triangles.
    ridges: Vec<Ridge>,
    /// Each triangle's bounding box, `[lo, hi]` (m): a point's squared distance to it
    /// bounds the triangle's from below, so the nearest-triangle search skips the
    /// triangles whose box lies farther than the nearest found.
    boxes: Vec<[[Real; 3]; 2]>,
    bins: Bins,
}

/// The uniform grid of bins over the surface's bounds.
#[derive(Debug, Clone)]
struct Bins {
    lo: [Real; 3],
    hi: [Real; 3],
    size: [Real; 3],
    dims: [usize; 3],
    /// Triangles of bin `b`: `items[offsets[b]..offsets[b + 1]]`.
    offsets: Vec<u32>,
    items: Vec<u32>,
    /// Chebyshev count of bins to the nearest occupied bin (0 for an occupied one).
    ring: Vec<u32>,
    /// An empty bin lies inside the die.
    inside: Vec<bool>,
    /// The absolute rounding margin of a squared distance, `(1e-9 b)^2` with `b` the
    /// smallest bin side (m^2).
    rounding2: Real,
}

/// The most bins along one side of a triangle surface's grid.
const MAX_BINS_PER_SIDE: usize = 256;

/// About the most bins of a triangle surface's grid (some 10 bytes each).
const MAX_BINS: usize = 1 << 21;

impl Bins {
    fn index(&self, i: [usize; 3]) -> usize {
        i[0] + self.dims[0] * (i[1] + self.dims[1] * i[2])
    }
    /// The bin coordinates of `y` clamped to the grid.
    fn cell(&self, y: [Real; 3]) -> [usize; 3] {
        std::array::from_fn(|k| {
            let f = ((y[k] - self.lo[k]) / self.size[k]).floor();
            (f.max(0.0) as usize).min(self.dims[k] - 1)
        })
    }
    /// Distance from `y` to the grid's bounds (m), 0 inside them.
    fn outside_by(&self, y: [Real; 3]) -> Real {
        let d: [Real; 3] =
            std::array::from_fn(|k| (self.lo[k] - y[k]).max(y[k] - self.hi[k]).max(0.0));
        dot(d, d).sqrt()
    }
}

impl TriangleSurface {
    /// The surface of a checked mesh ([`TriangleMesh::check`]) with its normals and bins.
    pub fn new(mesh: TriangleMesh) -> TriangleSurface {
        let nt = mesh.triangles.len();
        let face_normal: Vec<[Real; 3]> = (0..nt)
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                unit(cross(sub(b, a), sub(c, a)))
            })
            .collect();
        let mut vertex_normal = vec![[0.0; 3]; mesh.vertices.len()];
        let mut by_edge: std::collections::HashMap<(u32, u32), [Real; 3]> =
            std::collections::HashMap::new();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let p = mesh.corners(t);
            let n = face_normal[t];
            for k in 0..3 {
                let (e1, e2) = (
                    unit(sub(p[(k + 1) % 3], p[k])),
                    unit(sub(p[(k + 2) % 3], p[k])),
                );
                let angle = dot(e1, e2).clamp(-1.0, 1.0).acos();
                let vn = &mut vertex_normal[tri[k] as usize];
                for (v, nk) in vn.iter_mut().zip(n) {
                    *v += angle * nk;
                }
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let e = by_edge.entry((a.min(b), a.max(b))).or_insert([0.0; 3]);
                for (ek, nk) in e.iter_mut().zip(n) {
                    *ek += nk;
                }
            }
        }
        let edge_normal = mesh
            .triangles
            .iter()
            .map(|tri| {
                std::array::from_fn(|k| {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    by_edge[&(a.min(b), a.max(b))]
                })
            })
            .collect();
        let bins = Bins::new(&mesh);
        let ridges = ridges(&mesh, &face_normal, &vertex_normal);
        let boxes = (0..nt)
            .map(|t| {
                let p = mesh.corners(t);
                [
                    std::array::from_fn(|k| p[0][k].min(p[1][k]).min(p[2][k])),
                    std::array::from_fn(|k| p[0][k].max(p[1][k]).max(p[2][k])),
                ]
            })
            .collect();
        let mut surface = TriangleSurface {
            mesh,
            face_normal,
            edge_normal,
            vertex_normal,
            ridges,
            boxes,
            bins,
        };
        surface.classify_empty_bins();
        surface
    }

    /// The mesh.
    pub fn mesh(&self) -> &TriangleMesh {
        &self.mesh
    }

    /// The die's convex ridges and vertices (see the module doc).
    pub fn ridges(&self) -> &[Ridge] {
        &self.ridges
    }

    /// Triangle `t` cannot be nearer to `y` than the squared distance `e2` (m^2), nor as
    /// near: `y`'s squared distance to its bounding box exceeds `e2` by more than the
    /// rounding of either (a relative 1e-6 and an absolute `(1e-9 b)^2`, `b` the smallest
    /// bin side), so skipping it changes no answer, ties included.
    fn box_beyond(&self, y: [Real; 3], t: usize, e2: Real) -> bool {
        box_distance2(y, self.boxes[t]) > e2 * (1.0 + 1e-6) + self.bins.rounding2
    }

    /// The closest point of triangle `t` to `y` with its squared distance.
    fn on_triangle(&self, y: [Real; 3], t: usize) -> ([Real; 3], Feature, Real) {
        let (q, f) = closest_on_triangle(y, self.mesh.corners(t));
        let d = sub(y, q);
        (q, f, dot(d, d))
    }

    /// The closest point found among `candidates` to `y`, signed ([`Closest`]); `x` and
    /// `shift` the point and the surface's translation whose difference `y` is, so that a
    /// face's distance is `n . (x - a - shift)` as a moved plane's.
    fn signed(&self, x: [Real; 3], shift: [Real; 3], y: [Real; 3], t: usize) -> Closest {
        let (q, feature, _) = self.on_triangle(y, t);
        let tri = self.mesh.triangles[t];
        let n = self.face_normal[t];
        let pseudo = match feature {
            Feature::Edge(k) => self.edge_normal[t][k as usize],
            Feature::Vertex(k) => self.vertex_normal[tri[k as usize] as usize],
            Feature::Face => n,
        };
        // A face, or an edge or vertex inside a flat region (its pseudo-normal the face's):
        // the distance to the plane of the face.
        if feature == Feature::Face || unit(pseudo) == n {
            let a = self.mesh.vertices[tri[0] as usize];
            let rel: [Real; 3] = std::array::from_fn(|k| x[k] - a[k] - shift[k]);
            return Closest {
                signed: dot(n, rel),
                normal: n,
                point: q,
                triangle: t as u32,
                feature,
            };
        }
        let d = sub(y, q);
        let dist = dot(d, d).sqrt();
        let s: Real = if dot(d, pseudo) < 0.0 { -1.0 } else { 1.0 };
        let normal = if dist > 0.0 {
            d.map(|v| s * v / dist)
        } else {
            unit(pseudo)
        };
        Closest {
            signed: s * dist,
            normal,
            point: q,
            triangle: t as u32,
            feature,
        }
    }

    /// The exact closest point to `y = x - shift` (m): the nearest triangle among those
    /// listed in the bins within `r` of `y`, `r` one bin side at first; when the nearest
    /// found lies farther than `r`, the search widens to its distance once more (every
    /// triangle nearer than it lies in those bins), or doubles when none was found. Ties go
    /// to the lowest triangle index, so the answer does not depend on where the search
    /// stopped.
    fn nearest(&self, x: [Real; 3], shift: [Real; 3]) -> Closest {
        let y: [Real; 3] = std::array::from_fn(|k| x[k] - shift[k]);
        let b = &self.bins;
        let mut r = b.size.iter().copied().fold(Real::INFINITY, Real::min);
        loop {
            let lo = b.cell(y.map(|v| v - r));
            let hi = b.cell(std::array::from_fn(|k| y[k] + r));
            let mut best: Option<(Real, u32)> = None;
            for i2 in lo[2]..=hi[2] {
                for i1 in lo[1]..=hi[1] {
                    for i0 in lo[0]..=hi[0] {
                        let bin = b.index([i0, i1, i2]);
                        for &t in &b.items[b.offsets[bin] as usize..b.offsets[bin + 1] as usize] {
                            if best.is_some_and(|(e2, _)| self.box_beyond(y, t as usize, e2)) {
                                continue;
                            }
                            let d2 = self.on_triangle(y, t as usize).2;
                            if best.is_none_or(|(e2, u)| d2 < e2 || (d2 == e2 && t < u)) {
                                best = Some((d2, t));
                            }
                        }
                    }
                }
            }
            let whole = lo == [0; 3] && hi == b.dims.map(|n| n - 1);
            match best {
                Some((d2, t)) if d2 <= r * r || whole => {
                    return self.signed(x, shift, y, t as usize)
                }
                Some((d2, _)) => r = d2.sqrt() * (1.0 + 1e-12),
                None => r *= 2.0,
            }
        }
    }

    /// Where `x` (m) is with the surface translated by `shift` (m): [`Proximity::Far`] with
    /// a lower bound on the distance when the bins show no triangle within `reach` (m),
    /// else the exact closest point.
    pub fn locate(&self, x: [Real; 3], shift: [Real; 3], reach: Real) -> Proximity {
        let y: [Real; 3] = std::array::from_fn(|k| x[k] - shift[k]);
        let b = &self.bins;
        let out = b.outside_by(y);
        if out > reach {
            return Proximity::Far {
                distance: out,
                inside: false,
            };
        }
        if out == 0.0 {
            let i = b.cell(y);
            let bin = b.index(i);
            let ring = b.ring[bin];
            if ring > 0 {
                let smallest = b.size.iter().copied().fold(Real::INFINITY, Real::min);
                let to_side = (0..3)
                    .map(|k| {
                        let lo = b.lo[k] + i[k] as Real * b.size[k];
                        (y[k] - lo).min(lo + b.size[k] - y[k]).max(0.0)
                    })
                    .fold(Real::INFINITY, Real::min);
                let distance = (ring - 1) as Real * smallest + to_side;
                if distance > reach {
                    return Proximity::Far {
                        distance,
                        inside: b.inside[bin],
                    };
                }
            }
        }
        Proximity::Near(self.nearest(x, shift))
    }

    /// The triangles whose centroid lies within `r` (m) of `q` (m, in the surface's own
    /// place, untranslated), ascending. Complete: a centroid lies in its triangle's bounds,
    /// so the bin holding it lists the triangle, and that bin meets the box `q +- r`.
    pub fn triangles_around(&self, q: [Real; 3], r: Real) -> Vec<u32> {
        let b = &self.bins;
        let lo = b.cell(q.map(|v| v - r));
        let hi = b.cell(std::array::from_fn(|k| q[k] + r));
        let mut found = Vec::new();
        for i2 in lo[2]..=hi[2] {
            for i1 in lo[1]..=hi[1] {
                for i0 in lo[0]..=hi[0] {
                    let bin = b.index([i0, i1, i2]);
                    found.extend(
                        b.items[b.offsets[bin] as usize..b.offsets[bin + 1] as usize]
                            .iter()
                            .copied()
                            .filter(|&t| {
                                let [a, bb, c] = self.mesh.corners(t as usize);
                                let d: [Real; 3] =
                                    std::array::from_fn(|k| (a[k] + bb[k] + c[k]) / 3.0 - q[k]);
                                dot(d, d) <= r * r
                            }),
                    );
                }
            }
        }
        found.sort_unstable();
        found.dedup();
        found
    }

    /// The exact signed distance and closest point of `x` (m), the surface translated by
    /// `shift` (m).
    pub fn closest(&self, x: [Real; 3], shift: [Real; 3]) -> Closest {
        self.nearest(x, shift)
    }

    /// Sets which empty bins lie inside the die: each face-connected set of empty bins by
    /// one exact query at one of its bins' centres.
    fn classify_empty_bins(&mut self) {
        let b = &self.bins;
        let n = b.ring.len();
        let mut label = vec![u32::MAX; n];
        let mut inside_of = Vec::new();
        let mut stack = Vec::new();
        for start in 0..n {
            if b.ring[start] == 0 || label[start] != u32::MAX {
                continue;
            }
            let id = inside_of.len() as u32;
            let i = [
                start % b.dims[0],
                (start / b.dims[0]) % b.dims[1],
                start / (b.dims[0] * b.dims[1]),
            ];
            let centre: [Real; 3] =
                std::array::from_fn(|k| b.lo[k] + (i[k] as Real + 0.5) * b.size[k]);
            inside_of.push(self.closest(centre, [0.0; 3]).signed < 0.0);
            label[start] = id;
            stack.push(i);
            while let Some(i) = stack.pop() {
                for k in 0..3 {
                    for step in [-1isize, 1] {
                        let j = i[k] as isize + step;
                        if j < 0 || j >= b.dims[k] as isize {
                            continue;
                        }
                        let mut nb = i;
                        nb[k] = j as usize;
                        let m = b.index(nb);
                        if b.ring[m] > 0 && label[m] == u32::MAX {
                            label[m] = id;
                            stack.push(nb);
                        }
                    }
                }
            }
        }
        self.bins.inside = label
            .iter()
            .map(|&l| l != u32::MAX && inside_of[l as usize])
            .collect();
    }
}

/// The ridges of a closed mesh with its unit face normals and its vertices' (not unit)
/// pseudo-normals (module doc): each convex edge once, from its lower-numbered vertex, in
/// the order of the triangles, then the convex vertices on none in the vertices' order.
fn ridges(
    mesh: &TriangleMesh,
    face_normal: &[[Real; 3]],
    vertex_normal: &[[Real; 3]],
) -> Vec<Ridge> {
    let sharp = RIDGE_ANGLE.cos();
    let mut face_of = std::collections::HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            face_of.insert((tri[k], tri[(k + 1) % 3]), t);
        }
    }
    let mut out = Vec::new();
    let mut on_ridges = vec![0u32; mesh.vertices.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let Some(&u) = face_of.get(&(b, a)).filter(|_| a < b) else {
                continue;
            };
            let (n1, n2) = (face_normal[t], face_normal[u]);
            let far = mesh.triangles[u]
                .into_iter()
                .find(|&v| v != a && v != b)
                .map_or([0.0; 3], |v| mesh.vertices[v as usize]);
            let (pa, pb) = (mesh.vertices[a as usize], mesh.vertices[b as usize]);
            if dot(n1, n2) < sharp && dot(n1, sub(far, pa)) < 0.0 {
                on_ridges[a as usize] += 1;
                on_ridges[b as usize] += 1;
                out.push(Ridge {
                    a: pa,
                    b: pb,
                    normal: unit(std::array::from_fn(|k| n1[k] + n2[k])),
                });
            }
        }
    }
    let mut around: Vec<Vec<u32>> = vec![Vec::new(); mesh.vertices.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &v in tri {
            around[v as usize].push(t as u32);
        }
    }
    for (v, faces) in around.iter().enumerate() {
        if faces.is_empty() || on_ridges[v] == 1 || on_ridges[v] == 2 {
            continue;
        }
        let p = mesh.vertices[v];
        let n = unit(vertex_normal[v]);
        if on_ridges[v] > 2 {
            out.push(Ridge {
                a: p,
                b: p,
                normal: n,
            });
            continue;
        }
        let spread = faces
            .iter()
            .any(|&t| dot(n, face_normal[t as usize]) < sharp);
        let convex = faces.iter().all(|&t| {
            mesh.triangles[t as usize]
                .iter()
                .all(|&w| w as usize == v || dot(n, sub(mesh.vertices[w as usize], p)) < 0.0)
        });
        if spread && convex {
            out.push(Ridge {
                a: p,
                b: p,
                normal: n,
            });
        }
    }
    out
}

impl Bins {
    /// Bins of about the median triangle extent (a die's few large faces, as its flat
    /// back, do not coarsen them), at most [`MAX_BINS_PER_SIDE`] along a side and about
    /// [`MAX_BINS`] in all; the triangles
    /// listed in every bin their bounds overlap; the Chebyshev counts by a breadth-first
    /// sweep from the occupied bins.
    fn new(mesh: &TriangleMesh) -> Bins {
        let bounds = mesh.bounds();
        let extent: [Real; 3] = std::array::from_fn(|k| bounds[k][1] - bounds[k][0]);
        let largest = extent.iter().copied().fold(0.0, Real::max);
        let tri_bounds: Vec<[[Real; 2]; 3]> = (0..mesh.triangles.len())
            .map(|t| {
                let c = mesh.corners(t);
                std::array::from_fn(|k| {
                    [
                        c[0][k].min(c[1][k]).min(c[2][k]),
                        c[0][k].max(c[1][k]).max(c[2][k]),
                    ]
                })
            })
            .collect();
        let mut extents: Vec<Real> = tri_bounds
            .iter()
            .map(|b| (0..3).map(|k| b[k][1] - b[k][0]).fold(0.0, Real::max))
            .collect();
        extents.sort_unstable_by(Real::total_cmp);
        let median = extents[extents.len() / 2];
        let mut h = median.max(largest / MAX_BINS_PER_SIDE as Real);
        let count = |h: Real| extent.map(|e| ((e / h).ceil() as usize).clamp(1, MAX_BINS_PER_SIDE));
        let total = count(h).iter().product::<usize>();
        if total > MAX_BINS {
            h *= (total as Real / MAX_BINS as Real).cbrt();
        }
        let dims = count(h);
        let pad = 1e-9 * largest;
        let lo: [Real; 3] = std::array::from_fn(|k| bounds[k][0] - pad);
        let hi: [Real; 3] = std::array::from_fn(|k| bounds[k][1] + pad);
        let size: [Real; 3] = std::array::from_fn(|k| (hi[k] - lo[k]) / dims[k] as Real);
        let mut bins = Bins {
            lo,
            hi,
            size,
            dims,
            offsets: Vec::new(),
            items: Vec::new(),
            ring: Vec::new(),
            inside: Vec::new(),
            rounding2: {
                let b = size.iter().copied().fold(Real::INFINITY, Real::min);
                (1e-9 * b) * (1e-9 * b)
            },
        };
        let n = dims.iter().product::<usize>();
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (t, tb) in tri_bounds.iter().enumerate() {
            let a = bins.cell(tb.map(|r| r[0]));
            let z = bins.cell(tb.map(|r| r[1]));
            for i2 in a[2]..=z[2] {
                for i1 in a[1]..=z[1] {
                    for i0 in a[0]..=z[0] {
                        lists[bins.index([i0, i1, i2])].push(t as u32);
                    }
                }
            }
        }
        bins.offsets.push(0);
        for l in &lists {
            bins.items.extend_from_slice(l);
            bins.offsets.push(bins.items.len() as u32);
        }
        let mut ring = vec![u32::MAX; n];
        let mut front: Vec<usize> = (0..n).filter(|&b| !lists[b].is_empty()).collect();
        for &b in &front {
            ring[b] = 0;
        }
        let mut level = 0;
        while !front.is_empty() {
            level += 1;
            let mut next = Vec::new();
            for &b in &front {
                let i = [
                    b % dims[0],
                    (b / dims[0]) % dims[1],
                    b / (dims[0] * dims[1]),
                ];
                for d2 in -1isize..=1 {
                    for d1 in -1isize..=1 {
                        for d0 in -1isize..=1 {
                            let j = [i[0] as isize + d0, i[1] as isize + d1, i[2] as isize + d2];
                            if (0..3).any(|k| j[k] < 0 || j[k] >= dims[k] as isize) {
                                continue;
                            }
                            let m = bins.index(j.map(|v| v as usize));
                            if ring[m] == u32::MAX {
                                ring[m] = level;
                                next.push(m);
                            }
                        }
                    }
                }
            }
            front = next;
        }
        bins.ring = ring;
        bins.inside = vec![false; n];
        bins
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stl::tests::box_mesh;

    /// A small deterministic generator of numbers in [0, 1).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> Real {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as Real / (1u64 << 53) as Real
        }
        fn point(&mut self, scale: Real) -> [Real; 3] {
            std::array::from_fn(|_| scale * (2.0 * self.next() - 1.0))
        }
    }

    /// Brute force: the closest of the face's projection (if inside the triangle) and the
    /// closest points of the three edges as segments.
    fn brute(p: [Real; 3], [a, b, c]: [[Real; 3]; 3]) -> Real {
        let seg = |u: [Real; 3], v: [Real; 3]| {
            let e = sub(v, u);
            let t = (dot(sub(p, u), e) / dot(e, e)).clamp(0.0, 1.0);
            let d = sub(p, along(u, e, t));
            dot(d, d).sqrt()
        };
        let mut best = seg(a, b).min(seg(b, c)).min(seg(c, a));
        let n = unit(cross(sub(b, a), sub(c, a)));
        let h = dot(sub(p, a), n);
        let q = along(p, n, -h);
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(u, v)| dot(cross(sub(v, u), sub(q, u)), n) >= 0.0);
        if inside {
            best = best.min(h.abs());
        }
        best
    }

    /// On random triangles and points, the closest point's distance matches brute force,
    /// and the feature it names is where the point lies (a vertex on the vertex, an edge's
    /// point on the segment, a face point strictly inside).
    #[test]
    fn closest_point_per_feature_matches_brute_force() {
        let mut rng = Lcg(7);
        let mut seen = [0usize; 3];
        for _ in 0..20_000 {
            let tri = [rng.point(1.0), rng.point(1.0), rng.point(1.0)];
            let p = rng.point(2.0);
            let (q, f) = closest_on_triangle(p, tri);
            let d = sub(p, q);
            let dist = dot(d, d).sqrt();
            let want = brute(p, tri);
            assert!((dist - want).abs() <= 1e-12 * (1.0 + want), "{dist} {want}");
            match f {
                Feature::Vertex(k) => {
                    seen[0] += 1;
                    assert_eq!(q, tri[k as usize]);
                }
                Feature::Edge(k) => {
                    seen[1] += 1;
                    let (u, v) = (tri[k as usize], tri[(k as usize + 1) % 3]);
                    let c = cross(sub(v, u), sub(q, u));
                    assert!(dot(c, c).sqrt() <= 1e-12, "{c:?}");
                }
                Feature::Face => {
                    seen[2] += 1;
                    let n = cross(sub(tri[1], tri[0]), sub(tri[2], tri[0]));
                    for k in 0..3 {
                        let (u, v) = (tri[k], tri[(k + 1) % 3]);
                        assert!(dot(cross(sub(v, u), sub(q, u)), n) > 0.0);
                    }
                }
            }
        }
        assert!(seen.iter().all(|&n| n > 500), "{seen:?}");
    }

    /// A sphere of radius `r` as a subdivided octahedron projected to it (outward winding).
    fn sphere(r: Real, levels: usize) -> TriangleMesh {
        let mut v: Vec<[Real; 3]> = vec![
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let mut t: Vec<[u32; 3]> = vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        for _ in 0..levels {
            let mut mid = std::collections::HashMap::new();
            let mut m = |a: u32, b: u32, v: &mut Vec<[Real; 3]>| {
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let (p, q) = (v[a as usize], v[b as usize]);
                    v.push(unit(std::array::from_fn(|k| p[k] + q[k])));
                    (v.len() - 1) as u32
                })
            };
            t = t
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = (m(a, b, &mut v), m(b, c, &mut v), m(c, a, &mut v));
                    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
                })
                .collect();
        }
        TriangleMesh {
            vertices: v.iter().map(|p| p.map(|x| r * x)).collect(),
            triangles: t,
        }
    }

    /// On a box and a sphere-ish mesh: the signed distance of random points, through the
    /// bins at any reach, matches brute force over all triangles in size, and its sign is
    /// the analytic inside (negative inside); a point ruled far has no triangle within
    /// its lower bound, on the side it states.
    #[test]
    fn sign_and_distance_on_a_cube_and_a_sphere() {
        let cube = box_mesh([-1.0; 3], [1.0; 3]);
        let ball = sphere(1.0, 3);
        assert!(cube.check().is_ok() && ball.check().is_ok());
        let inside_cube = |p: [Real; 3]| p.iter().all(|x| x.abs() < 1.0);
        // The sphere's mesh lies inside the unit sphere, within 1 - cos of its edge angle.
        let inside_ball = |p: [Real; 3]| dot(p, p).sqrt() < 0.97;
        let outside_ball = |p: [Real; 3]| dot(p, p).sqrt() > 1.0;
        let mut rng = Lcg(11);
        for (mesh, name) in [(&cube, "cube"), (&ball, "ball")] {
            let s = TriangleSurface::new(mesh.clone());
            for _ in 0..4000 {
                let p = rng.point(2.5);
                let brute_d = (0..mesh.triangles.len())
                    .map(|t| brute(p, mesh.corners(t)))
                    .fold(Real::INFINITY, Real::min);
                let c = s.closest(p, [0.0; 3]);
                assert!((c.signed.abs() - brute_d).abs() < 1e-12, "{name} {p:?}");
                let n = dot(c.normal, c.normal);
                assert!((n - 1.0).abs() < 1e-12);
                let want_inside = match name {
                    "cube" => Some(inside_cube(p)),
                    _ if inside_ball(p) => Some(true),
                    _ if outside_ball(p) => Some(false),
                    _ => None,
                };
                if let Some(inside) = want_inside {
                    assert_eq!(c.signed < 0.0, inside, "{name} {p:?} {c:?}");
                }
                for reach in [0.01, 0.1, 0.5] {
                    match s.locate(p, [0.0; 3], reach) {
                        Proximity::Far { distance, inside } => {
                            assert!(distance > reach && distance <= brute_d + 1e-12);
                            assert_eq!(inside, c.signed < 0.0, "{name} {p:?}");
                        }
                        Proximity::Near(n) => assert_eq!(n, c),
                    }
                }
            }
        }
    }

    /// A point far from a die costs no triangle: its bins rule it out, outside the bounds
    /// and at the sphere's centre (the Chebyshev count of bins is a weak bound along the
    /// diagonals: about 0.47 of the radius here).
    #[test]
    fn a_far_query_touches_no_triangle() {
        let s = TriangleSurface::new(sphere(1.0, 4));
        assert!(matches!(
            s.locate([0.0, 0.0, 10.0], [0.0; 3], 0.5),
            Proximity::Far { inside: false, .. }
        ));
        assert!(matches!(
            s.locate([0.0, 0.0, 0.0], [0.0; 3], 0.3),
            Proximity::Far { inside: true, .. }
        ));
    }

    /// The flat face of a box die, moved along an axis, gives the analytic plane's gap
    /// to the bit: `n . (x - a - s axis)` with the plane through the face, on the face's
    /// triangles and on the diagonal between them.
    #[test]
    fn a_flat_face_is_the_analytic_plane_to_the_bit() {
        let top = 0.0324;
        let s = TriangleSurface::new(box_mesh([-0.01, -0.01, top], [0.02, 0.02, top + 0.01]));
        let axis = [0.0, 0.0, -1.0];
        let normal = [0.0, 0.0, -1.0];
        let mut rng = Lcg(3);
        let mut diagonal = 0;
        for i in 0..2000 {
            let stroke = 1e-3 * rng.next();
            let mut x = [
                0.008 * rng.next(),
                0.008 * rng.next(),
                top - 2e-3 + 3e-3 * rng.next(),
            ];
            // Every other point on the face's diagonal, the edge between its triangles.
            if i % 2 == 0 {
                x[1] = x[0];
            }
            let shift = axis.map(|a| stroke * a);
            let plane_depth = {
                let rel: [Real; 3] = std::array::from_fn(|k| x[k] - [0.0, 0.0, top][k] - shift[k]);
                -dot(normal, rel)
            };
            let c = s.closest(x, shift);
            assert!(i % 2 == 0 || c.feature == Feature::Face, "{i}");
            diagonal += usize::from(c.feature != Feature::Face);
            assert_eq!((-c.signed).to_bits(), plane_depth.to_bits(), "{i} {x:?}");
            assert_eq!(c.normal.map(|v| v + 0.0), normal);
        }
        assert!(diagonal > 100, "{diagonal} points on the diagonal's edge");
    }
}
