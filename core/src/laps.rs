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
use crate::contact::self_contact_3d::{Pair3, Surface};
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

/// Whether any particle of `a` is `near` any of `b`.
fn touching(a: &[u32], b: &[u32], near: &impl Fn(u32, u32) -> bool) -> bool {
    a.iter().any(|&i| b.iter().any(|&j| near(i, j)))
}

/// Joins the lap pairs, each given by its particles (`members`), into groups of pairs whose
/// particles are `near` each other, in order of their first pair: `(first pair, particles
/// increasing)`. Shared by 2D and 3D.
fn join(members: Vec<Vec<u32>>, near: &impl Fn(u32, u32) -> bool) -> Vec<(usize, Vec<u32>)> {
    let mut groups: Vec<(usize, Vec<u32>)> = Vec::new();
    for (i, mut own) in members.into_iter().enumerate() {
        let mut first = i;
        let mut g = 0;
        while g < groups.len() {
            if touching(&groups[g].1, &own, near) {
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
    for g in &mut groups {
        g.1.sort_unstable();
        g.1.dedup();
    }
    groups
}

/// Grows the laps a group of particles `members` (increasing) is `near` by it, the older
/// taking in the others (two laps that grow together become one); `particles(lap)` a lap's
/// particles. Returns the group when it touches no lap (a new one). Shared by 2D and 3D.
fn merge<L>(
    laps: &mut Vec<L>,
    mut members: Vec<u32>,
    particles: impl Fn(&mut L) -> &mut Vec<u32>,
    near: &impl Fn(u32, u32) -> bool,
) -> Option<Vec<u32>> {
    let touched: Vec<usize> = (0..laps.len())
        .filter(|&l| touching(particles(&mut laps[l]), &members, near))
        .collect();
    let Some(&keep) = touched.first() else {
        return Some(members);
    };
    for &l in touched.iter().skip(1).rev() {
        let mut gone = laps.remove(l);
        members.append(particles(&mut gone));
    }
    let lap = particles(&mut laps[keep]);
    lap.extend(members);
    lap.sort_unstable();
    lap.dedup();
    None
}

/// Grows `laps` by the lap pairs among `pairs` (module doc).
pub fn grow(laps: &mut Vec<Lap>, pairs: &[Pair], stage: &Stage<'_>) {
    let (n, s) = (stage.x.len(), stage.neighbours);
    let lap_pairs: Vec<&Pair> = pairs.iter().filter(|p| is_lap(p, n, s)).collect();
    if lap_pairs.is_empty() {
        return;
    }
    let near = |i: u32, j: u32| ring_distance(i as usize, j as usize, n) <= s;
    let members = lap_pairs
        .iter()
        .map(|p| vec![p.slave, p.segment, (p.segment + 1) % n as u32])
        .collect();
    for (first, members) in join(members, &near) {
        let Some(members) = merge(laps, members, |l| &mut l.ring, &near) else {
            continue;
        };
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

/// A lap of a 3D workpiece as the state keeps it ([`crate::contact::self_contact_3d`]): as
/// 2D's [`Lap`], over the surface's particles (slots) and faces. A self-contact is a lap
/// when its slave lies more than `2 s` cells from every corner of its master face in the
/// reference configuration ([`crate::contact::self_contact_3d::Surface::near`], `s` the
/// cells that share a particle's coefficients); lap pairs whose particles lie within `s`
/// cells of each other belong to one lap, grown as 2D's ([`grow`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolidLap {
    /// When it formed (s).
    pub formed_s: Real,
    /// Each tool's stroke then (m), in scene order.
    pub formed_strokes_m: Vec<Real>,
    /// Where it formed: the midpoint of its first contact's slave and master point (m).
    pub start_m: [Real; 3],
    /// Its first contact: the slave's slot, the master face and the master point's weights
    /// on the face's corners.
    pub seed: (u32, u32, [Real; 4]),
    /// The slots of every surface particle that took part in it, increasing.
    pub slots: Vec<u32>,
}

/// What the 3D laps are grown from at one stage: the surface, the cells that share a
/// particle's coefficients, the predicted positions by slot (m), the time they are
/// predicted for (s) and each tool's stroke then (m).
pub struct SolidStage<'a> {
    /// The workpiece's surface.
    pub surface: &'a Surface,
    /// Cells on either side of a particle that share its coefficients.
    pub neighbours: usize,
    /// Predicted positions by slot (m).
    pub x: &'a [[Real; 3]],
    /// The time they are predicted for (s).
    pub time: Real,
    /// Each tool's stroke then (m).
    pub strokes: Vec<Real>,
}

/// The master point of `pair`'s face with `weights` at the positions `x` (m, by slot).
fn master_point(surface: &Surface, face: u32, weights: [Real; 4], x: &[[Real; 3]]) -> [Real; 3] {
    let c = surface.faces[face as usize];
    std::array::from_fn(|i| (0..4).map(|a| weights[a] * x[c[a] as usize][i]).sum())
}

/// Whether a 3D `pair` joins surface points more than `2 s` cells apart (see [`SolidLap`]).
pub fn is_solid_lap(pair: &Pair3, surface: &Surface, s: usize) -> bool {
    let c = surface.faces[pair.face as usize];
    c.iter()
        .all(|&a| !surface.near(pair.slave as usize, a as usize, 2 * s))
}

/// Grows the 3D `laps` by the lap pairs among `pairs` (see [`SolidLap`]).
pub fn grow_solid(laps: &mut Vec<SolidLap>, pairs: &[Pair3], stage: &SolidStage<'_>) {
    let (surface, s) = (stage.surface, stage.neighbours);
    let lap_pairs: Vec<&Pair3> = pairs
        .iter()
        .filter(|p| is_solid_lap(p, surface, s))
        .collect();
    if lap_pairs.is_empty() {
        return;
    }
    let near = |i: u32, j: u32| surface.near(i as usize, j as usize, s);
    let members = lap_pairs
        .iter()
        .map(|p| {
            let mut m = vec![p.slave];
            m.extend(surface.faces[p.face as usize]);
            m
        })
        .collect();
    for (first, members) in join(members, &near) {
        let Some(members) = merge(laps, members, |l| &mut l.slots, &near) else {
            continue;
        };
        let p = lap_pairs[first];
        let q = master_point(surface, p.face, p.weights, stage.x);
        let xk = stage.x[p.slave as usize];
        laps.push(SolidLap {
            formed_s: stage.time,
            formed_strokes_m: stage.strokes.clone(),
            start_m: std::array::from_fn(|i| 0.5 * (xk[i] + q[i])),
            seed: (p.slave, p.face, p.weights),
            slots: members,
        });
    }
}

/// A 3D lap as the outputs report it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolidLapReport {
    /// When it formed (s).
    pub formed_s: Real,
    /// Each tool's stroke then (m), in scene order.
    pub formed_strokes_m: Vec<Real>,
    /// Where it formed (m).
    pub start_m: [Real; 3],
    /// Where the material of its first contact is now (m).
    pub end_m: [Real; 3],
    /// Its extent now: `[min, max]` of x, y and z over its particles (m).
    pub extent_m: [[Real; 2]; 3],
    /// Where its first contact's slave particle lay in the undeformed workpiece (m).
    pub reference_m: [Real; 3],
    /// Every surface particle that took part in it.
    pub particles: Vec<usize>,
}

/// The report of the 3D `lap` on `surface` at the positions now `x` (m, by slot).
pub fn solid_report(lap: &SolidLap, surface: &Surface, x: &[[Real; 3]]) -> SolidLapReport {
    let (k, face, w) = lap.seed;
    let q = master_point(surface, face, w, x);
    let xk = x[k as usize];
    let mut extent = [[Real::INFINITY, Real::NEG_INFINITY]; 3];
    for &s in &lap.slots {
        for (e, c) in extent.iter_mut().zip(x[s as usize]) {
            *e = [e[0].min(c), e[1].max(c)];
        }
    }
    SolidLapReport {
        formed_s: lap.formed_s,
        formed_strokes_m: lap.formed_strokes_m.clone(),
        start_m: lap.start_m,
        end_m: std::array::from_fn(|i| 0.5 * (xk[i] + q[i])),
        extent_m: extent,
        reference_m: surface.reference(k as usize),
        particles: lap
            .slots
            .iter()
            .map(|&s| surface.particles[s as usize] as usize)
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::self_contact_3d::tests::{folded_strip, search};

    #[test]
    fn a_strip_folded_onto_itself_is_one_lap_where_its_parts_overlap() {
        let (x, v, surface) = folded_strip();
        let pairs = search(&x, &surface, &v, &mut vec![false; x.len()]);
        // Near the fold's root (x 5 to 6) the contacts join particles within four cells:
        // not a lap; farther out they do.
        assert!(pairs.iter().any(|p| is_solid_lap(p, &surface, 2)));
        assert!(!pairs.iter().all(|p| is_solid_lap(p, &surface, 2)));
        let mut laps = Vec::new();
        let stage = SolidStage {
            surface: &surface,
            neighbours: 2,
            x: &x,
            time: 1.5,
            strokes: vec![0.25],
        };
        grow_solid(&mut laps, &pairs, &stage);
        assert_eq!(laps.len(), 1, "{laps:?}");
        let report = solid_report(&laps[0], &surface, &x);
        assert_eq!((report.formed_s, report.formed_strokes_m[0]), (1.5, 0.25));
        // Where: between the left part's top face (z 1) and the folded part's (z 0.95),
        // over the overlap (x 0 to 6).
        let s = report.start_m;
        assert!(
            (s[2] - 0.975).abs() < 1e-12 && (0.0..=6.0).contains(&s[0]),
            "{s:?}"
        );
        assert_eq!(report.end_m, s);
        let e = report.extent_m;
        assert!(e[2][0] >= 0.95 - 1e-12 && e[2][1] <= 1.0 + 1e-12, "{e:?}");
        assert!(e[0][1] - e[0][0] >= 2.0, "{e:?}");
        // Both parts of the strip took part in it.
        let r = |j: &usize| surface.reference(*j)[0];
        assert!(report.particles.iter().any(|j| r(j) < 6.5));
        assert!(report.particles.iter().any(|j| r(j) > 6.5));
        // A second stage with the same contacts grows the same lap.
        grow_solid(&mut laps, &pairs, &stage);
        assert_eq!(laps.len(), 1);
    }
}
