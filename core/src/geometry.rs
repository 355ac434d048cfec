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
