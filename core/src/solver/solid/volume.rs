//! The volume of a 3D body, two ways, as the 2D register reads it: the volume of its cells
//! through the particles' physical positions (what the workpiece occupies), and the
//! integration points' own `sum_p J_p w_p` (what the material holds). Plastic flow keeps
//! volume (`det F_p = 1`, Simo 1992), so the first differs from the material's own only by
//! its small elastic change, unless material is lost inside a tool, folded or torn.

use super::SolidSimulation;
use crate::math::Real;

/// The reference cube's corners of a hexahedral cell's 8 particles, in the cells' order
/// (VTK_HEXAHEDRON: the bottom face counter-clockwise, then the top).
const CORNERS: [[Real; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// The volume of the trilinear hexahedron through the corners `x` (m^3), in the cells'
/// order: `V = int_{[-1,1]^3} det (dx/dxi) dxi`. `det (dx/dxi)` of the trilinear map is of
/// degree two in each reference coordinate, so the 2 x 2 x 2 Gauss rule (weights 1) gives
/// it exactly. Negative for a cell turned inside out.
pub(crate) fn hexahedron_volume(x: &[[Real; 3]; 8]) -> Real {
    let g = 1.0 / Real::sqrt(3.0);
    let mut volume = 0.0;
    for p in CORNERS {
        let xi = p.map(|c| c * g);
        // dx/dxi_k = sum_a x_a dN_a/dxi_k, N_a = prod_k (1 + c_ak xi_k) / 8.
        let mut jac = [[0.0; 3]; 3];
        for (xa, c) in x.iter().zip(CORNERS) {
            let n = [1.0 + c[0] * xi[0], 1.0 + c[1] * xi[1], 1.0 + c[2] * xi[2]];
            let dn = [
                c[0] * n[1] * n[2] / 8.0,
                c[1] * n[0] * n[2] / 8.0,
                c[2] * n[0] * n[1] / 8.0,
            ];
            for (row, xc) in jac.iter_mut().zip(xa) {
                for (j, d) in row.iter_mut().zip(dn) {
                    *j += xc * d;
                }
            }
        }
        volume += jac[0][0] * (jac[1][1] * jac[2][2] - jac[1][2] * jac[2][1])
            - jac[0][1] * (jac[1][0] * jac[2][2] - jac[1][2] * jac[2][0])
            + jac[0][2] * (jac[1][0] * jac[2][1] - jac[1][1] * jac[2][0]);
    }
    volume
}

/// The summed volume of `cells` through the positions `x` (m^3).
fn cells_volume(cells: &[[u32; 8]], x: &[[Real; 3]]) -> Real {
    cells
        .iter()
        .map(|c| hexahedron_volume(&c.map(|j| x[j as usize])))
        .sum()
}

impl SolidSimulation {
    /// The workpiece's volume now (m^3): its hexahedral cells through the particles'
    /// physical positions `x_J = X_J + sum_I N_I(X_J) d_I`, each cell trilinear between
    /// its 8 particles ([`hexahedron_volume`]).
    pub fn volume(&self) -> Real {
        self.volume_at(&self.positions())
    }

    /// [`SolidSimulation::volume`] with the particles at `positions` (m).
    pub fn volume_at(&self, positions: &[[Real; 3]]) -> Real {
        cells_volume(&self.disc.cells, positions)
    }

    /// The same cells' volume at the start (m^3), through the particles' reference
    /// positions (a cylinder's chords, not its arcs: the ratio of the two volumes is what
    /// the register reads, so the chords' deficit cancels).
    pub fn reference_volume(&self) -> Real {
        cells_volume(&self.disc.cells, &self.disc.ref_pos)
    }

    /// Relative change of the material's own volume, `sum_p J_p w_p / sum_p w_p - 1` (-),
    /// `w_p` the points' initial volumes, `J_p` at the last stress stage: elastic only.
    pub fn integrated_volume_change(&self) -> Real {
        let now: Real = self
            .ws
            .out
            .iter()
            .zip(&self.disc.weights)
            .map(|(o, w)| o.jacobian * w)
            .sum();
        now / self.disc.weights.iter().sum::<Real>() - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box's corners in the cells' order, `[0, a] x [0, b] x [0, c]` (m).
    fn brick(a: Real, b: Real, c: Real) -> [[Real; 3]; 8] {
        CORNERS.map(|p| {
            [
                a * (p[0] + 1.0) / 2.0,
                b * (p[1] + 1.0) / 2.0,
                c * (p[2] + 1.0) / 2.0,
            ]
        })
    }

    #[test]
    fn a_brick_a_shear_and_a_rotation_keep_their_volumes() {
        let v = hexahedron_volume(&brick(2.0, 3.0, 5.0));
        assert!((v - 30.0).abs() < 1e-13, "{v}");
        // A simple shear and a rotation keep the volume.
        let (s, c) = (0.6, 0.8);
        let moved = brick(2.0, 3.0, 5.0).map(|x| {
            let x = [x[0] + 0.7 * x[2], x[1], x[2]];
            [c * x[0] - s * x[1], s * x[0] + c * x[1], x[2]]
        });
        let w = hexahedron_volume(&moved);
        assert!((w - 30.0).abs() < 1e-12, "{w}");
        // Turned inside out (two faces swapped): the volume changes sign.
        let b = brick(2.0, 3.0, 5.0);
        let flipped = [b[4], b[5], b[6], b[7], b[0], b[1], b[2], b[3]];
        assert!((hexahedron_volume(&flipped) + 30.0).abs() < 1e-13);
    }

    #[test]
    fn a_warped_cell_has_its_trilinear_volume() {
        // Lift the unit cube's corner (1, 1, 1) by h: the bilinear top face is
        // z = 1 + h x y, so the volume is 1 + h int x y dx dy = 1 + h / 4.
        let mut x = brick(1.0, 1.0, 1.0);
        x[6][2] += 0.4;
        let v = hexahedron_volume(&x);
        assert!((v - (1.0 + 0.4 / 4.0)).abs() < 1e-13, "{v}");
    }
}
