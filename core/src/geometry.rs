//! Plane geometry of particle sets: axis-aligned bounds and the volume a closed boundary
//! encloses in plane strain or axisymmetry.

use crate::math::Real;
use crate::scene::Kinematics;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Axis-aligned bounds of a point set, e.g. the deformed workpiece (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Extents {
    /// Smallest and largest x (r).
    pub x: [Real; 2],
    /// Smallest and largest y (z).
    pub y: [Real; 2],
}

impl Extents {
    /// The workpiece's lateral size (m) with its summary key: the largest r in axisymmetry
    /// (`radius_m`), the x extent in plane strain (`width_m`).
    pub fn lateral(&self, kinematics: Kinematics) -> (&'static str, Real) {
        match kinematics {
            Kinematics::Axisymmetric => ("radius_m", self.x[1]),
            Kinematics::PlaneStrain => ("width_m", self.x[1] - self.x[0]),
        }
    }
}

/// Bounds of a point set (m).
pub fn bounds(p: &[[Real; 2]]) -> Extents {
    bounds_of(p, 0.0)
}

/// Bounds of a point set, grown by `pad` (m).
pub fn bounds_of(p: &[[Real; 2]], pad: Real) -> Extents {
    let mut e = Extents {
        x: [Real::INFINITY, Real::NEG_INFINITY],
        y: [Real::INFINITY, Real::NEG_INFINITY],
    };
    for q in p {
        e.x = [e.x[0].min(q[0]), e.x[1].max(q[0])];
        e.y = [e.y[0].min(q[1]), e.y[1].max(q[1])];
    }
    e.x = [e.x[0] - pad, e.x[1] + pad];
    e.y = [e.y[0] - pad, e.y[1] + pad];
    e
}

/// Volume enclosed by the closed polygon `ring` (m^3), counter-clockwise: Pappus' theorem
/// `2 pi r_c A` about the y axis in axisymmetry (x is the radius), `A depth` in plane strain,
/// with the area `A = sum (x_k y_k+1 - x_k+1 y_k) / 2` and `r_c A = sum (x_k + x_k+1)
/// (x_k y_k+1 - x_k+1 y_k) / 6` (shoelace formulas).
pub fn enclosed_volume(ring: &[[Real; 2]], kinematics: Kinematics, depth: Real) -> Real {
    let (mut a, mut ax) = (0.0, 0.0);
    for k in 0..ring.len() {
        let (p, q) = (ring[k], ring[(k + 1) % ring.len()]);
        let c = p[0] * q[1] - q[0] * p[1];
        a += 0.5 * c;
        ax += (p[0] + q[0]) * c / 6.0;
    }
    match kinematics {
        Kinematics::Axisymmetric => 2.0 * PI * ax,
        Kinematics::PlaneStrain => a * depth,
    }
}

/// Winding number of the closed polygon `ring` around the point `p` (-): +1 inside a
/// counter-clockwise simple polygon, 0 outside, 2 where the polygon overlaps itself (a
/// surface folded through itself covers the overlap twice). Counts the signed crossings of
/// the ray from `p` towards +x (Sunday 2001's crossing rule, half-open in y).
pub fn winding(ring: &[[Real; 2]], p: [Real; 2]) -> i32 {
    let n = ring.len();
    let mut w = 0;
    for k in 0..n {
        let (a, b) = (ring[k], ring[(k + 1) % n]);
        let left = (b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1]);
        if a[1] <= p[1] {
            if b[1] > p[1] && left > 0.0 {
                w += 1;
            }
        } else if b[1] <= p[1] && left < 0.0 {
            w -= 1;
        }
    }
    w
}

/// The unit normal of segment `(a, b)` turned +90 degrees from its direction: into the
/// material of a counter-clockwise ring.
pub fn left_normal(a: [Real; 2], b: [Real; 2]) -> [Real; 2] {
    let len = (b[0] - a[0]).hypot(b[1] - a[1]);
    [-(b[1] - a[1]) / len, (b[0] - a[0]) / len]
}

/// The inward unit normal of the counter-clockwise closed polygon `ring` at vertex `k`: the
/// sum of its two segments' normals, normalised (`None` where they cancel, a surface turned
/// back on itself).
pub fn vertex_normal(ring: &[[Real; 2]], k: usize) -> Option<[Real; 2]> {
    let n = ring.len();
    let (p, x, q) = (ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]);
    let (u, v) = (left_normal(p, x), left_normal(x, q));
    let s = [u[0] + v[0], u[1] + v[1]];
    let len = s[0].hypot(s[1]);
    (len > 1e-12).then(|| [s[0] / len, s[1] / len])
}

/// The closest point of segment `(a, b)` to `x`: its parameter `t` in [0, 1] from `a`, the
/// point and its squared distance (m^2; the searches compare squares and take one root).
pub fn closest_on_segment(a: [Real; 2], b: [Real; 2], x: [Real; 2]) -> (Real, [Real; 2], Real) {
    let t = [b[0] - a[0], b[1] - a[1]];
    let len2 = t[0] * t[0] + t[1] * t[1];
    let s = if len2 > 0.0 {
        (((x[0] - a[0]) * t[0] + (x[1] - a[1]) * t[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let c = [a[0] + s * t[0], a[1] + s * t[1]];
    let e = [x[0] - c[0], x[1] - c[1]];
    (s, c, e[0] * e[0] + e[1] * e[1])
}

/// How many pairs of segments of the closed polygon `ring` that share no vertex cross each
/// other with every end of either farther than `tolerance` (m) from the other: 0 for a
/// boundary that has not passed through itself. The tolerance lets through the crossings of a
/// contact a penalty holds: a vertex pressed a little behind a segment makes its two segments
/// cross that one by its gap.
pub fn crossings(ring: &[[Real; 2]], tolerance: Real) -> usize {
    let n = ring.len();
    let side = |a: [Real; 2], b: [Real; 2], c: [Real; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let boxes: Vec<Extents> = (0..n)
        .map(|k| bounds(&[ring[k], ring[(k + 1) % n]]))
        .collect();
    let mut count = 0;
    for a in 0..n {
        for b in a + 2..n {
            if a == 0 && b == n - 1 {
                continue;
            }
            let (p, q) = (&boxes[a], &boxes[b]);
            if p.x[1] < q.x[0] || q.x[1] < p.x[0] || p.y[1] < q.y[0] || q.y[1] < p.y[0] {
                continue;
            }
            let (p1, p2) = (ring[a], ring[(a + 1) % n]);
            let (q1, q2) = (ring[b], ring[(b + 1) % n]);
            let (d1, d2) = (side(q1, q2, p1), side(q1, q2, p2));
            let (d3, d4) = (side(p1, p2, q1), side(p1, p2, q2));
            if (d1 > 0.0) != (d2 > 0.0) && (d3 > 0.0) != (d4 > 0.0) {
                let clear = |p: [Real; 2], a: [Real; 2], b: [Real; 2]| {
                    closest_on_segment(a, b, p).2 > tolerance * tolerance
                };
                if clear(p1, q1, q2) && clear(p2, q1, q2) && clear(q1, p1, p2) && clear(q2, p1, p2)
                {
                    count += 1;
                }
            }
        }
    }
    count
}
