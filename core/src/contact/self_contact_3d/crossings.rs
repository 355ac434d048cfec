//! Where the root of a fold in the 3D workpiece's surface passes through itself
//! ([`Surface::fold_crossings`]): 2D's crossings of the boundary's segments
//! ([`crate::geometry::crossings`]) for the faces of the 3D surface that lie within the
//! kernel's support of each other, at the particles' physical positions. Those are the faces
//! the self-contact and its lap rule leave out (a particle is no slave of a face with a corner
//! within `s` cells of it in the reference configuration), so a fold whose faces started that
//! close (an edge curling onto its side) passes through itself unheld and unreported, and
//! only this measure sees it.
//!
//! Faces farther apart are the self-contact's: it holds their particles, not their edges,
//! so where two parts of the surface press on each other the chords of their faces can
//! interleave without any material passing through (2D has no such crossings: there a
//! segment crosses another only when a particle passes it), and their crossings are not
//! counted here.

use super::{Geometry, Surface};
use crate::math::Real;
use crate::stl::{cross, dot, sub};
use crate::triangle_surface::closest_on_triangle;
use serde::{Deserialize, Serialize};

/// One crossing of two faces of the surface.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Crossing {
    /// The two faces (indices into [`Surface::faces`]), the lower first.
    pub faces: [u32; 2],
    /// Where an edge of one face passes through the other (m, physical).
    pub at: [Real; 3],
    /// How far apart the two faces' centres were in the reference configuration (m).
    pub apart: Real,
    /// The longest edge of the two faces (m): a face stretched over several spacings is
    /// a chord of the surface it stands for, and may cut through another part where the
    /// material does not.
    pub longest_edge: Real,
}

/// The crossings of the surface at some positions.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Crossings {
    /// How many pairs of faces cross.
    pub count: usize,
    /// The first crossing pair in face order.
    pub first: Option<Crossing>,
}

impl Surface {
    /// The pairs of faces that share no particle, have a corner each within `s` cells of
    /// each other in the reference configuration ([`Surface::near`]) and cross each other
    /// at the positions `x` (m, by slot), with every corner of either farther than
    /// `tolerance` (m) from the other face: 0 where no fold's root has passed through
    /// itself. The tolerance, as 2D's, lets through a corner pressed a hair behind a face.
    ///
    /// Two faces cross when a segment of one (its four edges and the four from its corners
    /// to its centre, the edges of its triangles) passes through a triangle of the other
    /// (the segment-triangle test of Moller and Trumbore 1997, the triangle closed, the
    /// segment open at its ends). The candidate pairs are those whose bounding boxes
    /// overlap, found by a sweep of the boxes sorted along x; every pair is tested in face
    /// order, so the count and the first crossing do not depend on the sweep.
    pub fn fold_crossings(&self, x: &[[Real; 3]], tolerance: Real, s: usize) -> Crossings {
        let mut geo = Geometry::default();
        self.geometry(x, &mut geo);
        let boxes = &geo.boxes;
        let mut order: Vec<usize> = (0..self.faces.len()).collect();
        order.sort_by(|&a, &b| boxes[a][0][0].total_cmp(&boxes[b][0][0]).then(a.cmp(&b)));
        let mut pairs = Vec::new();
        for (i, &f) in order.iter().enumerate() {
            let [lo, hi] = boxes[f];
            for &g in order[i + 1..]
                .iter()
                .take_while(|&&g| boxes[g][0][0] <= hi[0])
            {
                let [glo, ghi] = boxes[g];
                if (1..3).all(|k| glo[k] <= hi[k] && lo[k] <= ghi[k]) {
                    pairs.push((f.min(g), f.max(g)));
                }
            }
        }
        pairs.sort_unstable();
        let mut out = Crossings::default();
        for (f, g) in pairs {
            let (a, b) = (self.faces[f], self.faces[g]);
            if a.iter().any(|p| b.contains(p))
                || !a
                    .iter()
                    .any(|&p| b.iter().any(|&q| self.near(p as usize, q as usize, s)))
            {
                continue;
            }
            let Some(at) = self.through(x, &geo, f, g) else {
                continue;
            };
            if self.corner_within(x, &geo, f, g, tolerance)
                || self.corner_within(x, &geo, g, f, tolerance)
            {
                continue;
            }
            out.count += 1;
            if out.first.is_none() {
                let centre = |c: [u32; 4]| -> [Real; 3] {
                    std::array::from_fn(|k| {
                        0.25 * c
                            .iter()
                            .map(|&s| self.reference[s as usize][k])
                            .sum::<Real>()
                    })
                };
                let d = sub(centre(a), centre(b));
                let longest_edge = [a, b]
                    .iter()
                    .flat_map(|c| (0..4).map(move |q| (c[q], c[(q + 1) % 4])))
                    .map(|(p, e)| {
                        let d = sub(x[e as usize], x[p as usize]);
                        dot(d, d).sqrt()
                    })
                    .fold(0.0, Real::max);
                out.first = Some(Crossing {
                    faces: [f as u32, g as u32],
                    at,
                    apart: dot(d, d).sqrt(),
                    longest_edge,
                });
            }
        }
        out
    }

    /// Where the first segment of one face's triangles (those of `f` first, then `g`'s)
    /// passes through a triangle of the other (m), if one does.
    fn through(&self, x: &[[Real; 3]], geo: &Geometry, f: usize, g: usize) -> Option<[Real; 3]> {
        [(f, g), (g, f)].into_iter().find_map(|(a, b)| {
            let c = self.faces[a];
            (0..4)
                .flat_map(|q| {
                    let p = x[c[q] as usize];
                    [(p, x[c[(q + 1) % 4] as usize]), (p, geo.centre[a])]
                })
                .find_map(|(p, e)| {
                    (0..4).find_map(|r| segment_through(p, e, self.triangle(x, geo, b, r)))
                })
        })
    }

    /// Whether a corner of face `f` lies within `tolerance` (m) of face `g`.
    fn corner_within(
        &self,
        x: &[[Real; 3]],
        geo: &Geometry,
        f: usize,
        g: usize,
        tolerance: Real,
    ) -> bool {
        self.faces[f].iter().any(|&s| {
            let p = x[s as usize];
            (0..4).any(|r| {
                let d = sub(p, closest_on_triangle(p, self.triangle(x, geo, g, r)).0);
                dot(d, d) <= tolerance * tolerance
            })
        })
    }
}

/// Where the open segment from `p` to `e` (m) passes through the closed triangle `t` (m),
/// if it does (Moller and Trumbore 1997): `p + s (e - p)` with `0 < s < 1` at barycentric
/// coordinates `u, v >= 0`, `u + v <= 1`; a segment in the triangle's plane does not.
fn segment_through(p: [Real; 3], e: [Real; 3], [a, b, c]: [[Real; 3]; 3]) -> Option<[Real; 3]> {
    let (e1, e2, d) = (sub(b, a), sub(c, a), sub(e, p));
    let h = cross(d, e2);
    let det = dot(e1, h);
    if det == 0.0 {
        return None;
    }
    let w = sub(p, a);
    let u = dot(w, h) / det;
    let r = cross(w, e1);
    let v = dot(d, r) / det;
    let s = dot(e2, r) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && s > 0.0 && s < 1.0)
        .then(|| std::array::from_fn(|k| p[k] + s * d[k]))
}

#[cfg(test)]
mod tests {
    use super::super::tests::{folded_strip, lattice_box};
    use super::*;

    #[test]
    fn a_segment_through_a_triangle_is_found_where_it_passes() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let at = segment_through([0.25, 0.25, -1.0], [0.25, 0.25, 1.0], t).unwrap();
        assert_eq!(at, [0.25, 0.25, 0.0]);
        // Short of the plane, beside the triangle, in its plane.
        assert!(segment_through([0.25, 0.25, -1.0], [0.25, 0.25, -0.5], t).is_none());
        assert!(segment_through([0.75, 0.75, -1.0], [0.75, 0.75, 1.0], t).is_none());
        assert!(segment_through([-1.0, 0.25, 0.0], [2.0, 0.25, 0.0], t).is_none());
        // Through an edge of the closed triangle.
        assert!(segment_through([0.5, 0.5, -1.0], [0.5, 0.5, 1.0], t).is_some());
    }

    /// A box's surface, undeformed and sheared, does not cross itself.
    #[test]
    fn a_box_does_not_cross_itself() {
        let (mut x, surface) = lattice_box([5, 4, 3]);
        assert_eq!(surface.fold_crossings(&x, 0.01, 2), Crossings::default());
        for p in &mut x {
            p[0] += 0.3 * p[2] + 0.05 * p[1] * p[1];
        }
        assert_eq!(surface.fold_crossings(&x, 0.01, 2).count, 0);
    }

    /// The top edge of a box pushed down and out past the middle of its side: the top face
    /// over it passes through the side face below, a fold one cell long that the contact's
    /// rule leaves out; a support of one cell would not have left it out, nor would a
    /// tolerance above the gap between them.
    #[test]
    fn an_edge_curled_onto_its_side_within_the_support_crosses() {
        let (mut x, surface) = lattice_box([4, 3, 3]);
        for p in &mut x {
            if p[1] == 2.0 && p[2] == 2.0 {
                p[1] = 2.6;
                p[2] = 0.3;
            }
        }
        let found = surface.fold_crossings(&x, 0.01, 2);
        assert!(found.count > 0, "{found:?}");
        let first = found.first.unwrap();
        // On the side face (y = 2) below the curled edge, between faces a cell and a half
        // apart, one of them stretched.
        assert!(
            (first.at[1] - 2.0).abs() < 1e-12 && first.at[2] < 1.0,
            "{first:?}"
        );
        assert!(first.apart < 2.0, "{first:?}");
        assert!(first.longest_edge > 1.5, "{first:?}");
        assert_eq!(surface.fold_crossings(&x, 0.01, 0).count, 0);
        assert_eq!(surface.fold_crossings(&x, 0.5, 2).count, 0);
    }

    /// The strip folded 0.05 through its left part (moved 0.3 along y off its sides): its
    /// faces cross the left part's faces up to eleven cells away. Those beyond the support
    /// are a lap's, which the self-contact holds and reports, and are not counted; those
    /// within it lie at the fold's root (x = 6.5).
    #[test]
    fn a_fold_beyond_the_support_is_left_to_the_contact() {
        let (mut x, _, surface) = folded_strip();
        for (s, p) in x.iter_mut().enumerate() {
            if surface.reference(s)[0] > 6.5 {
                p[1] += 0.3;
            }
        }
        let (root, all) = (
            surface.fold_crossings(&x, 0.01, 2),
            surface.fold_crossings(&x, 0.01, 12),
        );
        assert!(all.count > root.count && root.count > 0, "{root:?} {all:?}");
        let first = root.first.unwrap();
        assert!(first.at[0] > 4.0 && first.apart < 4.0, "{first:?}");
    }
}
