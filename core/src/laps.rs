//! Laps (folds) as results: where and when the free surface folded onto itself.
//!
//! A lap is a self-contact ([`crate::contact::self_contact`]) between surface points that were
//! apart along the surface: the slave and the nearer particle of its master segment more
//! than twice `s` particles apart along the boundary ring, `s` the ring particles that
//! share a particle's RK coefficients ([`crate::contact::self_contact::neighbours`], two for the
//! usual support of two spacings): a fold whose two faces are each longer than the kernel's
//! support (closer contacts are a fold's own root, or a kink at the scale of the
//! particles). The lap pairs of a stage are joined into laps: pairs whose particles lie
//! within `s` ring steps of each other belong to one lap, and a group that touches a lap
//! already found grows it (two laps that grow together become one, the older). A lap is kept once formed, whether its faces stay
//! pressed together or open again: it is a defect of the part either way, as forging codes
//! trace a lap through later blows.
//!
//! Each lap keeps the time and the tools' strokes when it formed, the point where its first
//! contact was (the midpoint of the slave and its master point) and that contact's material
//! point, followed to its position now, and every surface particle that took part in it.

use crate::contact::self_contact::Pair;
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// A lap as the state keeps it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Lap {
    /// When it formed (s).
    pub formed_s: Real,
    /// Each tool's stroke then (m), in scene order.
    pub formed_strokes_m: Vec<Real>,
    /// Where it formed: the midpoint of its first contact's slave and master point (m).
    pub start_m: [Real; 2],
    /// Its first contact: the slave's and the master segment's first particle's index in
    /// the ring, and the master point's parameter on the segment.
    pub seed: (u32, u32, Real),
    /// The ring indices of every surface particle that took part in it, increasing.
    pub ring: Vec<u32>,
}

/// What the laps are grown from at one stage: the boundary ring's predicted positions (m),
/// the time (s) and strokes (m) the stage predicts them for, and how many ring particles
/// share a particle's coefficients.
pub struct Stage<'a> {
    /// Ring particles on either side of a particle that share its coefficients
    /// ([`crate::contact::self_contact::neighbours`]).
    pub neighbours: usize,
    /// Predicted positions of the ring's particles, by ring index (m).
    pub x: &'a [[Real; 2]],
    /// The time they are predicted for (s).
    pub time: Real,
    /// Each tool's stroke then (m).
    pub strokes: Vec<Real>,
}

/// Distance between ring indices `i` and `j` along a ring of `n` particles.
fn ring_distance(i: usize, j: usize, n: usize) -> usize {
    let d = i.abs_diff(j);
    d.min(n - d)
}

/// Whether `pair` joins surface points more than `2 s` apart along a ring of `n`
/// particles, `s` the ring particles that share a particle's coefficients.
pub fn is_lap(pair: &Pair, n: usize, s: usize) -> bool {
    let (k, a) = (pair.slave as usize, pair.segment as usize);
    let d = ring_distance(k, a, n).min(ring_distance(k, (a + 1) % n, n));
    d > 2 * s
}

/// Whether any particle of `a` lies within `s` ring steps of any of `b` (ring indices on a
/// ring of `n`).
fn touching(a: &[u32], b: &[u32], n: usize, s: usize) -> bool {
    a.iter().any(|&i| {
        b.iter()
            .any(|&j| ring_distance(i as usize, j as usize, n) <= s)
    })
}

/// Grows `laps` by the lap pairs among `pairs` (module doc).
pub fn grow(laps: &mut Vec<Lap>, pairs: &[Pair], stage: &Stage<'_>) {
    let (n, s) = (stage.x.len(), stage.neighbours);
    let lap_pairs: Vec<&Pair> = pairs.iter().filter(|p| is_lap(p, n, s)).collect();
    if lap_pairs.is_empty() {
        return;
    }
    // Groups of touching pairs (each pair's slave and master particles), in order of their
    // first pair.
    let mut groups: Vec<(usize, Vec<u32>)> = Vec::new();
    for (i, p) in lap_pairs.iter().enumerate() {
        let mut own = vec![p.slave, p.segment, (p.segment + 1) % n as u32];
        let mut first = i;
        let mut g = 0;
        while g < groups.len() {
            if touching(&groups[g].1, &own, n, s) {
                let (f, members) = groups.remove(g);
                first = first.min(f);
                own.extend(members);
            } else {
                g += 1;
            }
        }
        groups.push((first, own));
    }
    groups.sort_by_key(|g| g.0);
    for (first, mut members) in groups {
        members.sort_unstable();
        members.dedup();
        let touched: Vec<usize> = (0..laps.len())
            .filter(|&l| touching(&laps[l].ring, &members, n, s))
            .collect();
        match touched.first() {
            Some(&keep) => {
                for &l in touched.iter().skip(1).rev() {
                    let gone = laps.remove(l);
                    members.extend(gone.ring);
                }
                let lap = &mut laps[keep];
                lap.ring.extend(members);
                lap.ring.sort_unstable();
                lap.ring.dedup();
            }
            None => {
                let p = lap_pairs[first];
                let (k, a, t) = (p.slave as usize, p.segment as usize, p.along);
                let (xa, xb) = (stage.x[a], stage.x[(a + 1) % n]);
                let c = [(1.0 - t) * xa[0] + t * xb[0], (1.0 - t) * xa[1] + t * xb[1]];
                laps.push(Lap {
                    formed_s: stage.time,
                    formed_strokes_m: stage.strokes.clone(),
                    start_m: [0.5 * (stage.x[k][0] + c[0]), 0.5 * (stage.x[k][1] + c[1])],
                    seed: (p.slave, p.segment, t),
                    ring: members,
                });
            }
        }
    }
}

/// The lap's position now (m): the midpoint of its first contact's slave and master point
/// at the ring's positions `x` (by ring index).
pub fn position(lap: &Lap, x: &[[Real; 2]]) -> [Real; 2] {
    let n = x.len();
    let (k, a, t) = (lap.seed.0 as usize, lap.seed.1 as usize, lap.seed.2);
    let (xa, xb) = (x[a], x[(a + 1) % n]);
    [
        0.5 * (x[k][0] + (1.0 - t) * xa[0] + t * xb[0]),
        0.5 * (x[k][1] + (1.0 - t) * xa[1] + t * xb[1]),
    ]
}

/// The lap's length now (m): the longest run of its particles along the ring (particles at
/// most `s` ring steps apart in one run), measured along the ring's segments at the
/// positions `x`; one face of the fold.
pub fn length(lap: &Lap, x: &[[Real; 2]], s: usize) -> Real {
    let n = x.len();
    let ring = &lap.ring;
    if ring.is_empty() {
        return 0.0;
    }
    let segment = |a: usize| {
        let (p, q) = (x[a], x[(a + 1) % n]);
        (q[0] - p[0]).hypot(q[1] - p[1])
    };
    // Runs of increasing ring index; the run through index 0 wraps round.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let (mut start, mut end) = (ring[0] as usize, ring[0] as usize);
    for &r in &ring[1..] {
        let r = r as usize;
        if r - end <= s {
            end = r;
        } else {
            runs.push((start, end));
            (start, end) = (r, r);
        }
    }
    runs.push((start, end));
    if runs.len() > 1 {
        let (first, last) = (runs[0], runs[runs.len() - 1]);
        if first.0 + n - last.1 <= s {
            runs[0] = (last.0, first.1 + n);
            runs.pop();
        }
    }
    runs.iter()
        .map(|&(s, e)| (s..e).map(|a| segment(a % n)).sum::<Real>())
        .fold(0.0, Real::max)
}

/// A lap as the outputs report it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LapReport {
    /// When it formed (s).
    pub formed_s: Real,
    /// Each tool's stroke then (m), in scene order.
    pub formed_strokes_m: Vec<Real>,
    /// Where it formed (m).
    pub start_m: [Real; 2],
    /// Where the material of its first contact is now (m).
    pub end_m: [Real; 2],
    /// Its length now (m): the longer of its faces along the surface.
    pub length_m: Real,
    /// Where its first contact's slave particle lay in the undeformed workpiece (m): where
    /// on the billet the lap's material comes from.
    pub reference_m: [Real; 2],
    /// Every surface particle that took part in it.
    pub particles: Vec<usize>,
}

/// The report of `lap` on the boundary ring `boundary` (particles, counter-clockwise) at the
/// ring's positions now `x` (m, by ring index), with the particles' undeformed positions
/// `original` (m); `s` ring particles share a particle's coefficients.
pub fn report(
    lap: &Lap,
    boundary: &[u32],
    x: &[[Real; 2]],
    original: &[[Real; 2]],
    s: usize,
) -> LapReport {
    LapReport {
        formed_s: lap.formed_s,
        formed_strokes_m: lap.formed_strokes_m.clone(),
        start_m: lap.start_m,
        end_m: position(lap, x),
        length_m: length(lap, x, s),
        reference_m: original[boundary[lap.seed.0 as usize] as usize],
        particles: lap
            .ring
            .iter()
            .map(|&k| boundary[k as usize] as usize)
            .collect(),
    }
}
