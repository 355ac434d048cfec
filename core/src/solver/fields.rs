//! What the outputs read from a running simulation: physical positions, bounds and volumes
//! of the workpiece, tool penetration, particle fields smoothed from the integration points,
//! and the points' own data.

use super::layout::Scatter;
use super::simulation::Simulation;
use crate::geometry::{bounds, enclosed_volume, Extents};
use crate::math::Real;
use crate::scene::Edge;

/// Particle fields for output frames.
#[derive(Debug, Clone, Default)]
pub struct Fields {
    /// Physical positions `X_J + u(X_J)` (m).
    pub positions: Vec<[Real; 2]>,
    /// Physical displacements `x_J - X_J` from the undeformed workpiece (m).
    pub displacement: Vec<[Real; 2]>,
    /// Physical velocities (m/s).
    pub velocity: Vec<[Real; 2]>,
    /// Equivalent plastic strain smoothed to particles (-).
    pub plastic_strain: Vec<Real>,
    /// Von Mises stress smoothed to particles (Pa).
    pub von_mises: Vec<Real>,
    /// Temperature smoothed to particles (degrees C), in a scene with `[thermal]`.
    pub temperature: Option<Vec<Real>>,
    /// The lap each particle took part in, numbered from 1 in the order they formed, 0 for
    /// none ([`crate::laps`]).
    pub lap: Vec<Real>,
}

/// Values per integration point smoothed to the `particles` particles, in 2D and 3D: at
/// particle `I` the mean of the values of the points its shape function reaches, each
/// weighted by `|N_I(x_p)| w_p` (the point's weight `w_p` in m^D, `N_I` from the points'
/// shape functions in `scatter`); 0 at a particle no point reaches.
pub(super) fn smoothed<const D: usize>(
    scatter: &Scatter<D>,
    weights: &[Real],
    particles: usize,
    values: &[Real],
) -> Vec<Real> {
    let (mut wsum, mut sum) = (vec![0.0; particles], vec![0.0; particles]);
    for (p, (&weight, &value)) in weights.iter().zip(values).enumerate() {
        for (i, n) in scatter.point_values(p) {
            let w = (n * weight).abs();
            wsum[i] += w;
            sum[i] += w * value;
        }
    }
    sum.iter()
        .zip(&wsum)
        .map(|(&s, &w)| s * if w > 0.0 { 1.0 / w } else { 0.0 })
        .collect()
}

impl Simulation {
    /// Physical positions `X_J + sum_I N_I(X_J) d_I` of all particles (m).
    pub fn positions(&self) -> Vec<[Real; 2]> {
        self.disc.positions(&self.st.d)
    }

    /// Bounds of the deformed workpiece over all particles (m).
    pub fn extents(&self) -> Extents {
        bounds(&self.positions())
    }

    /// Volume of the workpiece now (m^3): enclosed by its outline (`outline.rs`), the
    /// image of the reference boundary sampled between the boundary particles.
    pub fn volume(&self) -> Real {
        let model = &self.scene.model;
        enclosed_volume(&self.outline(), model.kinematics, model.depth_m)
    }

    /// The workpiece's outline now (m): the image of the reference boundary, sampled at
    /// `outline::POINTS_PER_SEGMENT` points along each boundary segment from its first
    /// particle on, counter-clockwise.
    pub fn outline(&self) -> Vec<[Real; 2]> {
        self.disc.outline.positions(&self.st.d)
    }

    /// Current volume as the integration rule sees it, `sum_p J_p w_p` (m^3), at the last
    /// stress stage.
    pub fn integrated_volume(&self) -> Real {
        self.ws
            .out
            .iter()
            .zip(&self.disc.weights)
            .map(|(o, w)| o.jacobian * w)
            .sum()
    }

    /// Relative change of the material's own volume, `sum_p J_p w_p / sum_p w_p - 1` (-)
    /// with `w_p` the points' initial volumes: elastic only, as plastic flow is isochoric
    /// (`det F_p = 1`, Simo 1992). Beside the boundary's [`Simulation::volume`], the
    /// difference between the two is volume the discretisation gains or loses (a fold of
    /// the boundary, material inside a tool), not compression.
    pub fn integrated_volume_change(&self) -> Real {
        self.integrated_volume() / self.disc.weights.iter().sum::<Real>() - 1.0
    }

    /// Volume of the undeformed workpiece (m^3): its rectangle, by Pappus' theorem
    /// `2 pi r_c A` in axisymmetry, `A depth` in plane strain.
    pub fn reference_volume(&self) -> Real {
        let ring: Vec<[Real; 2]> = self
            .disc
            .boundary
            .iter()
            .map(|&j| self.disc.original[j as usize])
            .collect();
        let model = &self.scene.model;
        enclosed_volume(&ring, model.kinematics, model.depth_m)
    }

    /// Bounds of the physical positions of the particles that started on `edge` (m): for
    /// the Taylor bar, `YMin`'s largest x is the impact-face radius and `YMax`'s largest y
    /// the free-face length.
    pub fn face_extents(&self, edge: Edge) -> Extents {
        let x: Vec<[Real; 2]> = edge
            .particles(self.disc.nx, self.disc.ny)
            .into_iter()
            .map(|j| self.disc.position(&self.st.d, j as usize))
            .collect();
        bounds(&x)
    }

    /// Particle fields for output: physical positions, displacements and velocities;
    /// plastic strain, von Mises stress and temperature smoothed from the points with
    /// weights `|N_I| w_p`.
    pub fn fields(&self) -> Fields {
        let np = self.disc.ref_pos.len();
        let smooth = |values: &[Real]| smoothed(&self.disc.scatter, &self.disc.weights, np, values);
        let mut f = Fields {
            positions: self.positions(),
            plastic_strain: smooth(&self.point_plastic_strain()),
            von_mises: smooth(&self.point_von_mises()),
            temperature: self.point_temperature().map(smooth),
            ..Default::default()
        };
        for j in 0..np {
            f.displacement.push(match self.st.reference {
                None => self.disc.nodal.interpolate(j, &self.st.d),
                Some(_) => {
                    let (x, x0) = (f.positions[j], self.disc.original[j]);
                    [x[0] - x0[0], x[1] - x0[1]]
                }
            });
            f.velocity.push(self.disc.nodal.interpolate(j, &self.st.v));
        }
        f.lap = vec![0.0; np];
        for (l, lap) in self.st.laps.iter().enumerate() {
            for &k in &lap.ring {
                f.lap[self.disc.boundary[k as usize] as usize] = (l + 1) as Real;
            }
        }
        f
    }

    /// Shape functions at integration point `p`: each particle `I` of its group's list
    /// with `[N_I, dN_I/dX, dN_I/dY]` (1, 1/m), including zeros where `I` is outside the
    /// point's own support.
    pub fn point_shapes(&self, p: usize) -> impl Iterator<Item = (usize, [Real; 3])> + '_ {
        self.disc.scatter.point_row(p)
    }
    /// Reference volume weights of the integration points (m^3; 2 pi R included).
    pub fn point_weights(&self) -> &[Real] {
        &self.disc.weights
    }
    /// Reference positions of the integration points (m).
    pub fn point_positions(&self) -> &[[Real; 2]] {
        &self.disc.points.positions
    }
    /// Mises equivalent of the Cauchy stress at each integration point (Pa), at the last
    /// stress stage.
    pub fn point_von_mises(&self) -> Vec<Real> {
        self.ws.out.iter().map(|o| o.von_mises).collect()
    }
    /// `J = det F` of each integration point at the last stress stage (-): the Mises
    /// Kirchhoff stress the yield condition holds is `J` times [`Simulation::point_von_mises`].
    pub fn point_jacobian(&self) -> Vec<Real> {
        self.ws.out.iter().map(|o| o.jacobian).collect()
    }
    /// Equivalent plastic strain at each integration point.
    pub fn point_plastic_strain(&self) -> Vec<Real> {
        self.st.points.iter().map(|s| s.eps_p).collect()
    }
}
