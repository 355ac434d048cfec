//! Particles that have left the body: a particle whose physical position `x_I = X_I + sum_J
//! N_J(X_I) d_J` lies far from all the material its kernel reaches is a lone point, no
//! longer part of a resolved continuum (a corner squeezed out of the body: the 1 mm conrod
//! with a longer bar, q2 with the kernel re-referenced, threw the bar's top corner 34 mm
//! out along the parting plane; docs/forging.md). Nothing else watches for it: the particle
//! lies outside the tools and on or inside the planes, and it moves the fill points,
//! extents, volume and laps it reaches, so a run reports it.
//!
//! The material is the integration points: at each output sample, every particle's
//! isolation is its distance to the nearest point whose shape functions it reaches
//! (`N_I(x_p) != 0`, the points at their physical positions; SCNI's own point left out),
//! over its distance to the nearest other particle of its kernel neighbourhood at the start,
//! `h_I` (-). A stretched body keeps its points between its particles: the flash pressed
//! out 55 mm under its land from a 4 mm side (`scenes/flash_quarter.toml`) reached 3.7, the
//! other shipped scenes less (docs/method.md). The run keeps the largest, and the first
//! particle past [`DETACHED_REL`].

use super::layout::Scatter;
use crate::math::Real;
use crate::rk_shape::ShapeTable;
use serde::{Deserialize, Serialize};

/// Isolation (initial nearest-neighbour spacings, -) from which a particle counts as having
/// left the body (the stretched flash of the module doc reached 3.7).
pub const DETACHED_REL: Real = 5.0;

/// Each particle's distance (m) to the nearest integration point whose shape functions it
/// reaches: `pairs` yields `(point, particle)` for each particle with `N_I(x_p) != 0` (a
/// nodal rule leaves out each particle's own point); a particle in no pair (its kernel
/// reaches no point), to the nearest point of all.
pub fn nearest_points<const D: usize>(
    particles: &[[Real; D]],
    points: &[[Real; D]],
    pairs: impl Iterator<Item = (usize, usize)>,
) -> Vec<Real> {
    let mut nearest = vec![Real::INFINITY; particles.len()];
    for (p, i) in pairs {
        nearest[i] = nearest[i].min(squared_distance(&points[p], &particles[i]));
    }
    finish_nearest(&mut nearest, particles, points);
    nearest
}

/// `|a - b|^2` (m^2).
fn squared_distance<const D: usize>(a: &[Real; D], b: &[Real; D]) -> Real {
    (0..D).map(|k| (a[k] - b[k]).powi(2)).sum::<Real>()
}

/// The squared distances `nearest` (m^2) of [`nearest_points`] made distances (m), a
/// particle in no pair given its distance to the nearest point of all.
fn finish_nearest<const D: usize>(
    nearest: &mut [Real],
    particles: &[[Real; D]],
    points: &[[Real; D]],
) {
    for (i, d) in nearest.iter_mut().enumerate() {
        if d.is_infinite() {
            *d = points
                .iter()
                .map(|x| squared_distance(x, &particles[i]))
                .fold(Real::INFINITY, Real::min);
        }
        *d = d.sqrt();
    }
}

/// Each particle's distance (m) to the nearest other particle of its row in `table` (one
/// row per particle, `N_J(X_I)`), at `positions`.
pub fn nearest_in_rows<const D: usize>(
    table: &ShapeTable<D>,
    positions: &[[Real; D]],
) -> Vec<Real> {
    (0..positions.len())
        .map(|i| {
            let x = positions[i];
            table
                .row(i)
                .map(|e| table.index[e] as usize)
                .filter(|&j| j != i)
                .map(|j| {
                    (0..D)
                        .map(|k| (positions[j][k] - x[k]).powi(2))
                        .sum::<Real>()
                })
                .fold(Real::INFINITY, Real::min)
                .sqrt()
        })
        .collect()
}

/// A body at an output sample, as the isolation watch reads it.
pub(super) struct Body<'a, const D: usize> {
    /// The point shape functions.
    pub scatter: &'a Scatter<D>,
    /// The points' reference positions `X_p` (m).
    pub points: &'a [[Real; D]],
    /// The displacement coefficients `d_I` (m).
    pub d: &'a [[Real; D]],
    /// The particles' physical positions (m).
    pub particles: &'a [[Real; D]],
    /// The points are the particles' own (SCNI), each left out of its particle's search.
    pub nodal: bool,
}

/// [`nearest_points`] of the body's particles among its integration points at their
/// physical positions `x_p = X_p + sum_I N_I(x_p) d_I`, group by group of the scatter
/// ([`Scatter::groups`]): each group's points formed over its list, then its pairs
/// measured (each point's sum in its list's order, as a one-point loop forms it).
pub(super) fn point_distances<const D: usize>(body: &Body<'_, D>) -> Vec<Real> {
    let Body {
        scatter,
        points: reference,
        d,
        particles,
        nodal,
    } = *body;
    let mut points = reference.to_vec();
    let mut nearest = vec![Real::INFINITY; particles.len()];
    for group in scatter.groups() {
        let x = &mut points[group.first..group.first + group.size];
        for k in 0..group.len() {
            let (n, i) = group.values::<D>(k);
            for (q, (x, n)) in x.iter_mut().zip(n).enumerate() {
                let d = &d[i + group.shift(q)];
                for c in 0..D {
                    x[c] += n * d[c];
                }
            }
        }
        for k in 0..group.len() {
            let (n, i) = group.values::<D>(k);
            for (q, (x, &n)) in x.iter().zip(n).enumerate() {
                let i = i + group.shift(q);
                if n != 0.0 && !(nodal && i == group.first + q) {
                    nearest[i] = nearest[i].min(squared_distance(x, &particles[i]));
                }
            }
        }
    }
    finish_nearest(&mut nearest, particles, &points);
    nearest
}

/// A particle that left the body: the first sample at which one passed [`DETACHED_REL`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Detached {
    /// The particle.
    pub particle: u32,
    /// The sample's time (s).
    pub time_s: Real,
    /// Its physical position then (m).
    pub position_m: Vec<Real>,
    /// Its isolation then (-).
    pub isolation: Real,
}

/// The isolation watch of a run (module doc).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Isolation {
    /// Largest isolation at a sample so far (-).
    pub max: Real,
    /// The first particle that left the body, if one did.
    pub detached: Option<Detached>,
}

impl Isolation {
    /// Measures the isolation of every particle of `body` against the initial nearest
    /// distances `initial` (m) at time `time_s`, recorded in the watch.
    pub(super) fn measure_body<const D: usize>(
        &mut self,
        body: &Body<'_, D>,
        initial: &[Real],
        time_s: Real,
    ) {
        self.measure(body.particles, &point_distances(body), initial, time_s);
    }

    /// Measures the isolation of every particle at `positions` (m) against the initial
    /// nearest distances `initial` (m) at time `time_s`; returns the largest now (-).
    pub fn measure<const D: usize>(
        &mut self,
        positions: &[[Real; D]],
        nearest: &[Real],
        initial: &[Real],
        time_s: Real,
    ) -> Real {
        let (mut worst, mut at) = (0.0 as Real, 0);
        for (i, (d, h)) in nearest.iter().zip(initial).enumerate() {
            let r = d / h;
            if r > worst {
                (worst, at) = (r, i);
            }
        }
        self.max = self.max.max(worst);
        if worst >= DETACHED_REL && self.detached.is_none() {
            self.detached = Some(Detached {
                particle: at as u32,
                time_s,
                position_m: positions[at].to_vec(),
                isolation: worst,
            });
        }
        worst
    }

    /// The run's warning when a particle left the body, naming it with its position at the
    /// start (`initial`: every particle's, m).
    pub fn warning<const D: usize>(&self, initial: &[[Real; D]]) -> Option<String> {
        let d = self.detached.as_ref()?;
        let initial = initial[d.particle as usize];
        Some(format!(
            "particle {} (at {:?} m at the start) left the body at t = {:.4e} s: at {:?} m the nearest integration point it reaches lay {:.1} of its initial spacings away (from {DETACHED_REL} on a particle counts as detached; the largest over the run was {:.1}). The material there is not resolved (a corner or fin squeezed out as a lone particle); the fill points, extents, volume and laps it reaches may be wrong",
            d.particle, initial, d.time_s, d.position_m, d.isolation, self.max
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stretched_body_is_not_detached_and_a_lone_particle_is() {
        // Six particles 1 m apart on a line, a point halfway between each pair reaching the
        // two particles beside it.
        let particles: Vec<[Real; 2]> = (0..6).map(|i| [i as Real, 0.0]).collect();
        let points = |x: &[[Real; 2]]| -> Vec<[Real; 2]> {
            (0..5)
                .map(|p| [(x[p][0] + x[p + 1][0]) / 2.0, (x[p][1] + x[p + 1][1]) / 2.0])
                .collect()
        };
        let pairs = || (0..5).flat_map(|p| [(p, p), (p, p + 1)]);
        let h = nearest_points(&particles, &points(&particles), pairs());
        assert!(h.iter().all(|&d| (d - 0.5).abs() < 1e-15));
        let mut watch = Isolation::default();
        // Stretched 3 times along the line, the points with it: isolation 3, not detached.
        let stretched: Vec<[Real; 2]> = particles.iter().map(|x| [3.0 * x[0], 0.0]).collect();
        let near = nearest_points(&stretched, &points(&stretched), pairs());
        assert!((watch.measure(&stretched, &near, &h, 1.0) - 3.0).abs() < 1e-12);
        assert!(watch.detached.is_none() && watch.warning(&particles).is_none());
        // The last particle thrown 5 m off sideways while the material's points stay (a
        // particle the points do not follow): it is named, with the time.
        let mut thrown = particles.clone();
        thrown[5] = [5.0, 5.0];
        let near = nearest_points(&thrown, &points(&particles), pairs());
        let r = watch.measure(&thrown, &near, &h, 2.0);
        assert!(
            (r - 2.0 * (0.25 as Real + 25.0).sqrt()).abs() < 1e-12,
            "{r}"
        );
        let d = watch.detached.clone().expect("detached");
        assert_eq!((d.particle, d.time_s), (5, 2.0));
        let w = watch.warning(&particles).expect("warning");
        assert!(
            w.contains("particle 5") && w.contains("left the body"),
            "{w}"
        );
        // Later samples keep the first; the largest grows.
        thrown[0] = [0.0, -9.0];
        let near = nearest_points(&thrown, &points(&particles), pairs());
        watch.measure(&thrown, &near, &h, 3.0);
        assert_eq!(watch.detached.as_ref().map(|d| d.particle), Some(5));
        assert!(watch.max > 17.0, "{}", watch.max);
    }
}
