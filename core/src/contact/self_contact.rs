//! Contact of the workpiece with itself: the paper's particle-to-segment algorithm
//! (Sidibe et al. 2009, section II-3, eqs. 4-7) with the workpiece's own current surface as
//! the master, so that two parts of the surface that meet press on each other instead of
//! passing through (a fold, or a lap when it closes).
//!
//! The surface is the boundary ring: the particles that started on the lattice's edge,
//! counter-clockwise (in a Lagrangian description the material's surface is the image of
//! its reference boundary), joined by straight segments at their predicted positions
//! (the paper's master particles "connected into piecewise linear segments"). Every ring
//! particle `k` is a slave of every ring segment `(a, a + 1)` except those that touch a
//! ring particle sharing its RK coefficients ([`neighbours`]); the segments near it are
//! found in uniform bins over the ring ([`crate::segment_bins::SegmentBins`]), not by an all-pairs
//! search.
//!
//! A slave is in contact when the closest point `c` of its candidate segments lies behind
//! the surface there (`(x_k - c) . n > 0`, `n` the segment's inward normal on its interior,
//! the vertex's pseudo-normal, the sum of its two segments' normals, at a vertex) within the
//! search depth `D`, and either it was in contact at the last stage or its gap is within
//! twice its displacement relative to the master point over the step,
//! `g <= 2 dt |v_k - v_c|` (m): a surface that folds onto itself crosses itself by no more
//! than that in the step it crosses (the penalty then holds it near a thousandth of a
//! spacing), while a particle behind a surface by more has always been there: the two
//! faces of a thin flash lie behind each other by its thickness, and a particle next to a
//! convex corner of the surface lies behind the far face's line by a spacing. The penalty
//! closes a gap in one step, so a contact's first push changes the relative velocity by
//! `g / dt`, at most twice what it was. Which slaves are in contact is state
//! ([`crate::solver::State`]), so a restored run continues with the same contacts.

//! The force on the slave is eq. 4's normal penalty with the pair's reduced mass, as the
//! master is not rigid: `f_n = mu g / (dt dt_avg)`, `mu = m_k m_c / (m_k + m_c)` (kg) with
//! `m_c = (1 - t) m_a + t m_b` the master point's interpolated mass (kg) and `t` its
//! parameter on the segment, along the push direction `(c - x_k) / g`; friction as for tools
//! (eqs. 5-6, [`crate::contact::sidibe2009::penalty_force`]) with the scene's law and the velocity
//! relative to the master point `v_k - (1 - t) v_a - t v_b` (m/s). Every ring particle is a
//! slave and every segment a master (a symmetric two-pass treatment, Hallquist, Goudreau
//! and Benson 1985): where two faces meet, both see the other, so each pass carries half of
//! the penalty (`mu / 2`), and the gap of two faces closes in one step as a tool's does. The
//! force is spread to the coefficients with eq. 7 at the slave, and its reaction at the
//! master point, shared `(1 - t)` and `t` by the segment's two particles, each spread with
//! eq. 7; both are internal to the workpiece, so the force does no work of a tool and the
//! energy account books its work with the other contact forces.
//!
//! The search runs only where a contact could exist ([`SelfContact`]: candidate lists from
//! a full search, kept while the surface moves less than the search depth relative to
//! itself, and only the slaves near another part checked against them). Skipping gives the
//! bits of searching.

use crate::contact::sidibe2009::{penalty_force, Interface, Slave};
use crate::friction::Friction;
use crate::geometry::{closest_on_segment, left_normal, vertex_normal};
use crate::math::Real;
use crate::scene::SelfContactSpec;
use crate::segment_bins::{padded_bounds, SegmentBins};
use crate::tools::Penetration;

/// Largest gap of a self-contact that goes on, in smallest particle spacings: a penalty
/// contact holds a gap near a thousandth of a spacing, so a deeper slave has passed
/// through.
pub const SEARCH_DEPTH_SPACINGS: Real = 1.0;

/// How many ring particles on either side of a slave share its RK coefficients: those
/// within the kernel's support, `ceil(max(a_x, a_y))` for a support of `a` spacings (at
/// least one). A slave is never tested against a segment touching them: a force between
/// particles whose kernels overlap largely moves them together (eq. 7 spreads both onto the
/// same coefficients), so a fold shorter than the support cannot be held, only resolved by
/// a finer grid.
pub fn neighbours(support: [Real; 2]) -> usize {
    (support[0].max(support[1]).ceil() as usize).max(1)
}

/// Whether segment `(a, a + 1)` of a ring of `n` particles touches a particle within
/// `neighbours` ring steps of particle `k`.
pub fn is_neighbour_segment(a: usize, k: usize, n: usize, neighbours: usize) -> bool {
    let near = |i: usize| {
        let d = i.abs_diff(k);
        d.min(n - d) <= neighbours
    };
    near(a) || near((a + 1) % n)
}

/// One slave in contact with a master segment in the last search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pair {
    /// The slave's index in the ring.
    pub slave: u32,
    /// The master segment `(a, a + 1)` by its first particle's index in the ring.
    pub segment: u32,
    /// Where on the segment the closest point lies, `t` in [0, 1] from `a`.
    pub along: Real,
    /// The gap `g` (m), positive.
    pub gap: Real,
    /// Unit push direction on the slave, from it to the closest point.
    pub normal: [Real; 2],
}

/// What a stage's self-contact has to do ([`SelfContact::due`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Due {
    /// No slave can be within the search depth of a segment: nothing.
    Nothing,
    /// The slaves near another part of the surface, against the segments listed for them
    /// at the last full search ([`SelfContact::local_search`]).
    Local,
    /// A full search over the whole ring ([`SelfContact::full_search`]).
    Full,
}

/// The self-contact search and what it keeps from step to step (none of it state: dropping
/// it, [`SelfContact::forget`], only makes the next step search the whole ring).
///
/// A full search bins the ring's segments and lists, for each slave, the candidate segments
/// within twice the search depth `D` of it, with the distance to the nearest (Verlet lists).
/// Until the surface has moved `D` relative to itself since, no other segment can come
/// within `D` of the slave, and a slave whose nearest listed segment lay farther than `D`
/// plus that motion cannot touch: each later stage checks only the slaves near another
/// part, against their lists, interpolating just those particles.
#[derive(Debug, Clone)]
pub struct SelfContact {
    /// Friction law between the surface's parts.
    pub friction: Friction,
    /// Search depth `D` (m).
    depth: Real,
    /// Ring particles on either side of a slave whose segments it is not tested against
    /// ([`neighbours`]).
    neighbours: usize,
    /// Whether the lists are good (a full search since the last [`SelfContact::forget`]).
    listed: bool,
    /// Bound on how far the surface moved relative to itself since the last full search (m).
    moved: Real,
    /// Each slave's listed segments: `list[start[k]..start[k + 1]]`, in bin order.
    start: Vec<u32>,
    list: Vec<u32>,
    /// Each slave's distance to its nearest listed segment at the last full search, less
    /// `D` (m); `D` when it lists none.
    clear: Vec<Real>,
    /// The least of `clear`.
    least_clear: Real,
    /// Bins over the ring's segments, rebuilt at each full search.
    bins: SegmentBins,
    /// The contacts of the last search.
    pairs: Vec<Pair>,
    /// Which ring particles a local search has interpolated at this stage.
    fresh: Vec<bool>,
}

impl SelfContact {
    /// The search of a scene's `[self_contact]` on a lattice of `spacing` (m) with a kernel
    /// support of `support` spacings; `None` when the scene turns it off.
    pub fn new(
        spec: &SelfContactSpec,
        spacing: [Real; 2],
        support: [Real; 2],
    ) -> Option<SelfContact> {
        spec.enabled.then(|| SelfContact {
            friction: spec.friction,
            depth: SEARCH_DEPTH_SPACINGS * spacing[0].min(spacing[1]),
            neighbours: neighbours(support),
            listed: false,
            moved: 0.0,
            start: Vec::new(),
            list: Vec::new(),
            clear: Vec::new(),
            least_clear: Real::NEG_INFINITY,
            bins: SegmentBins::default(),
            pairs: Vec::new(),
            fresh: Vec::new(),
        })
    }

    /// Adds `moved` (m), a bound on how far any two surface points moved relative to each
    /// other since the last stage, to the motion since the last full search; what this
    /// stage has to do.
    pub fn due(&mut self, moved: Real) -> Due {
        self.moved += moved;
        if !self.listed || !self.moved.is_finite() || self.moved >= self.depth {
            Due::Full
        } else if self.least_clear - self.moved <= 0.0 {
            Due::Local
        } else {
            Due::Nothing
        }
    }

    /// Forgets the lists, so that the next stage searches the whole ring.
    pub fn forget(&mut self) {
        self.listed = false;
        self.pairs.clear();
    }

    /// The contacts of the last search.
    pub fn pairs(&self) -> &[Pair] {
        &self.pairs
    }

    /// Drops the last search's contacts (a stage without a search).
    pub fn clear(&mut self) {
        self.pairs.clear();
    }

    /// The full search on the ring's predicted positions `x` (m, counter-clockwise, by ring
    /// index) and velocities `v` (m/s) over the natural step `dt` (s), with `touching` the
    /// slaves in contact at the last stage (by ring index), updated to this stage's: fills
    /// [`SelfContact::pairs`] (in ring order) and the lists (type doc).
    pub fn full_search(
        &mut self,
        x: &[[Real; 2]],
        v: &[[Real; 2]],
        dt: Real,
        touching: &mut [bool],
    ) {
        self.pairs.clear();
        let n = x.len();
        let (depth, reach) = (self.depth, 2.0 * self.depth);
        self.listed = true;
        self.moved = 0.0;
        self.start.clear();
        self.list.clear();
        self.clear.clear();
        self.start.push(0);
        if n < 2 * self.neighbours + 4 {
            self.clear.resize(n, depth);
            self.start.resize(n + 1, 0);
            self.least_clear = depth;
            touching.fill(false);
            return;
        }
        let [lo, hi] = padded_bounds(x, reach);
        // Bins of the reach, but no more than about one per segment.
        let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        let size = reach.max((area / n as Real).sqrt());
        let segments = (0..n).map(|a| [x[a], x[(a + 1) % n]]);
        self.bins.fill(segments, [lo, hi], reach, size);
        for (k, touch) in touching.iter_mut().enumerate() {
            let first = self.list.len();
            for &a in self.bins.candidates(x[k]) {
                let a = a as usize;
                if !is_neighbour_segment(a, k, n, self.neighbours)
                    && closest_on_segment(x[a], x[(a + 1) % n], x[k]).2 <= reach * reach
                {
                    self.list.push(a as u32);
                }
            }
            self.start.push(self.list.len() as u32);
            let listed = &self.list[first..];
            let pair = slave_contact(k, listed, x, v, dt, depth, *touch);
            let nearest = match pair.near {
                Some(d) => d,
                None => reach,
            };
            self.clear.push(nearest - depth);
            *touch = pair.contact.is_some();
            self.pairs.extend(pair.contact);
        }
        self.least_clear = self.clear.iter().copied().fold(Real::INFINITY, Real::min);
    }

    /// The search between full ones (type doc): each slave whose nearest listed segment may
    /// now lie within the search depth, against its lists, at the ring's predicted positions
    /// and velocities `at(k)` (m, m/s; read once per particle into `x`, `v`) over the
    /// natural step `dt` (s); `touching` as for [`SelfContact::full_search`]. Finds what a
    /// full search would.
    pub fn local_search(
        &mut self,
        mut at: impl FnMut(usize) -> [[Real; 2]; 2],
        x: &mut [[Real; 2]],
        v: &mut [[Real; 2]],
        dt: Real,
        touching: &mut [bool],
    ) {
        self.pairs.clear();
        let n = x.len();
        self.fresh.clear();
        self.fresh.resize(n, false);
        for (k, touch) in touching.iter_mut().enumerate() {
            if self.clear[k] - self.moved > 0.0 {
                *touch = false;
                continue;
            }
            let listed = &self.list[self.start[k] as usize..self.start[k + 1] as usize];
            // The slave, each listed segment's ends and their neighbours (the pseudo-normal
            // at a vertex reads both segments beside it).
            for i in std::iter::once(k).chain(listed.iter().flat_map(|&a| {
                let a = a as usize;
                [(a + n - 1) % n, a, (a + 1) % n, (a + 2) % n]
            })) {
                if !self.fresh[i] {
                    [x[i], v[i]] = at(i);
                    self.fresh[i] = true;
                }
            }
            let pair = slave_contact(k, listed, x, v, dt, self.depth, *touch);
            *touch = pair.contact.is_some();
            self.pairs.extend(pair.contact);
        }
    }
}

/// What [`slave_contact`] found of one slave.
struct SlaveContact {
    /// The distance to its nearest listed segment (m), if it lists any.
    near: Option<Real>,
    /// Its contact, if it has one.
    contact: Option<Pair>,
}

/// Slave `k` against its `listed` segments (ring indices of their first particles), the
/// ring at predicted positions `x` (m) and velocities `v` (m/s) over the natural step `dt`
/// (s), with search depth `depth` (m), `was` in contact at the last stage (module doc).
fn slave_contact(
    k: usize,
    listed: &[u32],
    x: &[[Real; 2]],
    v: &[[Real; 2]],
    dt: Real,
    depth: Real,
    was: bool,
) -> SlaveContact {
    let n = x.len();
    let xk = x[k];
    // The closest candidate: (squared distance, segment, parameter, point).
    let mut best: Option<(Real, usize, Real, [Real; 2])> = None;
    for &a in listed {
        let a = a as usize;
        let (t, c, d2) = closest_on_segment(x[a], x[(a + 1) % n], xk);
        if best.is_none_or(|b| d2 < b.0) {
            best = Some((d2, a, t, c));
        }
    }
    let near = best.map(|b| b.0.sqrt());
    let none = SlaveContact {
        near,
        contact: None,
    };
    let (Some(d), Some((_, a, t, c))) = (near, best) else {
        return none;
    };
    if d > depth || d <= 0.0 {
        return none;
    }
    let b = (a + 1) % n;
    if !was {
        let rel = [
            v[k][0] - (1.0 - t) * v[a][0] - t * v[b][0],
            v[k][1] - (1.0 - t) * v[a][1] - t * v[b][1],
        ];
        if d * d > 4.0 * dt * dt * (rel[0] * rel[0] + rel[1] * rel[1]) {
            return none;
        }
    }
    // The side: the segment's normal on its interior, the pseudo-normal at a vertex.
    let side = if t <= 0.0 || t >= 1.0 {
        let vertex = if t <= 0.0 { a } else { b };
        match vertex_normal(x, vertex) {
            Some(s) => s,
            None => return none,
        }
    } else {
        left_normal(x[a], x[b])
    };
    if (xk[0] - c[0]) * side[0] + (xk[1] - c[1]) * side[1] <= 0.0 {
        return none;
    }
    SlaveContact {
        near,
        contact: Some(Pair {
            slave: k as u32,
            segment: a as u32,
            along: t,
            gap: d,
            normal: [(c[0] - xk[0]) / d, (c[1] - xk[1]) / d],
        }),
    }
}

/// The surface of the workpiece as a self-contact force reads it, by ring index.
pub struct Ring<'a> {
    /// Predicted positions (m).
    pub x: &'a [[Real; 2]],
    /// Predicted velocities (m/s).
    pub v: &'a [[Real; 2]],
    /// The ring's particles.
    pub particles: &'a [u32],
    /// Lumped masses of all particles (kg).
    pub mass: &'a [Real],
}

/// The force on the slave of `pair` (N; the module doc): eq. 4 with half the pair's reduced
/// mass, friction by `law` (eqs. 5-6) with the slave's flow stress and area `at` and the
/// velocity relative to the master point, over the natural step `dt` and the corrector's
/// step `dt_avg` (s). The master point takes its reaction.
pub fn pair_force(
    pair: &Pair,
    ring: &Ring<'_>,
    law: &Friction,
    at: Interface,
    dt: Real,
    dt_avg: Real,
) -> [Real; 2] {
    let n = ring.x.len();
    let (k, a, t) = (pair.slave as usize, pair.segment as usize, pair.along);
    let b = (a + 1) % n;
    let mass = |i: usize| ring.mass[ring.particles[i] as usize];
    let m_c = (1.0 - t) * mass(a) + t * mass(b);
    let m_k = mass(k);
    let reduced = m_k * m_c / (m_k + m_c);
    let v_c = [
        (1.0 - t) * ring.v[a][0] + t * ring.v[b][0],
        (1.0 - t) * ring.v[a][1] + t * ring.v[b][1],
    ];
    let slave = Slave {
        m: 0.5 * reduced,
        v_rel: [ring.v[k][0] - v_c[0], ring.v[k][1] - v_c[1]],
        carried: [0.0; 2],
    };
    let pen = Penetration {
        gap: pair.gap,
        normal: pair.normal,
    };
    penalty_force(slave, pen, law, at, dt, dt_avg).force
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The search over one step of length 1 on a grid of spacing 1, the first half of the
    /// ring's particles moving up at `speed / 2`, the second half down.
    fn search(x: &[[Real; 2]], speed: Real, touching: &mut [bool]) -> Vec<Pair> {
        let half = x.len() / 2;
        let v: Vec<[Real; 2]> = (0..x.len())
            .map(|k| [0.0, if k < half { 0.5 * speed } else { -0.5 * speed }])
            .collect();
        let spec = SelfContactSpec {
            enabled: true,
            friction: Friction::default(),
        };
        let mut s = SelfContact::new(&spec, [1.0; 2], [1.0; 2]).expect("enabled");
        s.full_search(x, &v, 1.0, touching);
        s.pairs
    }

    /// A counter-clockwise rectangle ring of `nx` x `ny` particles at spacing `h`.
    fn rectangle(nx: usize, ny: usize, h: Real) -> Vec<[Real; 2]> {
        let mut r = Vec::new();
        r.extend((0..nx).map(|i| [i as Real * h, 0.0]));
        r.extend((1..ny).map(|j| [(nx - 1) as Real * h, j as Real * h]));
        r.extend(
            (0..nx - 1)
                .rev()
                .map(|i| [i as Real * h, (ny - 1) as Real * h]),
        );
        r.extend((1..ny - 1).rev().map(|j| [0.0, j as Real * h]));
        r
    }

    #[test]
    fn a_plain_body_and_a_thin_strip_touch_nothing() {
        assert!(search(&rectangle(6, 5, 1.0), 1.0, &mut [false; 18]).is_empty());
        // A strip half a spacing thick: each face lies behind the other within the search
        // depth, by more than the faces moved towards each other.
        let mut strip = rectangle(8, 2, 1.0);
        for p in &mut strip {
            p[1] *= 0.5;
        }
        assert!(search(&strip, 0.2, &mut [false; 16]).is_empty());
    }

    /// A body folded over itself (a hairpin opening to the right, material on the left of
    /// travel): the lower arm's top face at y = 1, the upper arm's bottom face at
    /// `y = 1 - overlap`, so the two arms overlap over x in [1, 4].
    fn hairpin(overlap: Real) -> Vec<[Real; 2]> {
        let y = 1.0 - overlap;
        vec![
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [3.0, 0.0],
            [4.0, 0.0],
            [4.0, 1.0],
            [3.0, 1.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, y],
            [2.0, y],
            [3.0, y],
            [4.0, y],
            [4.0, 2.0],
            [0.0, 2.0],
            [0.0, 1.0],
        ]
    }

    #[test]
    fn a_fold_pressed_through_the_opposite_face_is_found_from_both_sides() {
        let pairs = search(&hairpin(0.05), 0.05, &mut [false; 16]);
        let slaves: Vec<u32> = pairs.iter().map(|p| p.slave).collect();
        // The lower arm's top face particles (6, 7) lie 0.05 inside the upper arm, and the
        // upper arm's bottom face particles (10, 11) 0.05 inside the lower arm.
        assert!(slaves.contains(&6) && slaves.contains(&7), "{pairs:?}");
        assert!(slaves.contains(&10) && slaves.contains(&11), "{pairs:?}");
        for p in &pairs {
            assert!((p.gap - 0.05).abs() < 1e-12, "{p:?}");
            // Pushed out of the other arm: the lower arm's particles down, the upper's up.
            let down = p.slave < 9;
            assert_eq!(p.normal[1] < 0.0, down, "{p:?}");
        }
    }

    #[test]
    fn a_contact_begins_shallow_and_goes_on_deeper() {
        // Overlapping by 0.3 spacings, the arms closing by 0.05 in the step: no contact
        // begins so deep (a thin part's two faces lie behind each other by its thickness),
        // but one that began goes on.
        assert!(search(&hairpin(0.3), 0.05, &mut [false; 16]).is_empty());
        let mut touching = vec![false; 16];
        touching[6] = true;
        let pairs = search(&hairpin(0.3), 0.05, &mut touching);
        assert_eq!(pairs.len(), 1, "{pairs:?}");
        assert_eq!(pairs[0].slave, 6);
        assert!(touching[6] && touching.iter().filter(|&&t| t).count() == 1);
    }
}
