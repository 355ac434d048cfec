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

/// [`smoothed`] particle by particle: for each particle the points its shape function
/// reaches, ascending, with the weights `|N_I(x_p) w_p|` (m^D), so that one particle's
/// smoothed value costs its own points instead of a pass over every point. A stage that
/// needs a point value at a few particles (the flow stress of the particles in contact,
/// for the shear and capped friction laws) reads it here; the bits are [`smoothed`]'s (the
/// same sums in the same order, the zero weights left out).
#[derive(Debug, Clone, Default)]
pub(super) struct Smoothing {
    /// Start of each particle's entries, `particles + 1` of them.
    offsets: Vec<u32>,
    /// The points, ascending within a particle.
    points: Vec<u32>,
    /// `|N_I(x_p) w_p|` of each entry (m^D).
    weights: Vec<Real>,
}

impl Smoothing {
    /// The points of `scatter` with weights `weights` (m^D) reaching each of `particles`.
    pub(super) fn new<const D: usize>(
        scatter: &Scatter<D>,
        weights: &[Real],
        particles: usize,
    ) -> Smoothing {
        let entries = |p: usize| {
            let weight = weights[p];
            scatter
                .point_values(p)
                .map(move |(i, n)| (i, (n * weight).abs()))
                .filter(|&(_, w)| w != 0.0)
        };
        let mut offsets = vec![0u32; particles + 1];
        for p in 0..weights.len() {
            for (i, _) in entries(p) {
                offsets[i + 1] += 1;
            }
        }
        for i in 0..particles {
            offsets[i + 1] += offsets[i];
        }
        let total = offsets[particles] as usize;
        let (mut points, mut w) = (vec![0u32; total], vec![0.0; total]);
        let mut next = offsets.clone();
        for p in 0..weights.len() {
            for (i, wi) in entries(p) {
                let e = next[i] as usize;
                (points[e], w[e]) = (p as u32, wi);
                next[i] += 1;
            }
        }
        Smoothing {
            offsets,
            points,
            weights: w,
        }
    }

    /// No particle has points (the table was not needed).
    pub(super) fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Particle `j`'s value: the mean of `value(p)` over the points reaching it, weighted by
    /// `|N_J(x_p) w_p|`; 0 if none does.
    pub(super) fn at(&self, j: usize, value: impl Fn(usize) -> Real) -> Real {
        let e = self.offsets[j] as usize..self.offsets[j + 1] as usize;
        let (mut wsum, mut sum) = (0.0, 0.0);
        for (&p, &w) in self.points[e.clone()].iter().zip(&self.weights[e]) {
            wsum += w;
            sum += w * value(p as usize);
        }
        sum * if wsum > 0.0 { 1.0 / wsum } else { 0.0 }
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integration::point_shapes;
    use crate::rk_shape::Lattice;
    use crate::scene::IntegrationRule;
    use crate::solver::layout::MAX_GROUP_3D;

    #[test]
    fn one_particle_smoothed_gives_the_bits_of_the_whole_field() {
        let h = [1.0e-3, 1.2e-3, 0.9e-3];
        let lattice = Lattice::new([0.0; 3], h, [7, 6, 5], h.map(|h| 2.0 * h));
        let particles = lattice.cloud().positions.len();
        for rule in [IntegrationRule::Q2, IntegrationRule::Q4] {
            let (points, pt) = point_shapes(&lattice, rule).unwrap();
            let scatter = Scatter::new(&pt, particles, 96, MAX_GROUP_3D);
            // A value varying from point to point, negative at some.
            let values: Vec<Real> = (0..points.areas.len())
                .map(|p| ((p * 7919) % 113) as Real * 1.37e6 - 2.0e7)
                .collect();
            let field = smoothed(&scatter, &points.areas, particles, &values);
            let smoothing = Smoothing::new(&scatter, &points.areas, particles);
            for (j, &f) in field.iter().enumerate() {
                assert_eq!(smoothing.at(j, |p| values[p]).to_bits(), f.to_bits(), "{j}");
            }
        }
    }
}
