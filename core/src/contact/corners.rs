//! The second pass of the contact stage: a tool's convex corners against the workpiece's
//! surface, so that a die corner cannot cut between two surface particles.
//!
//! The particle pass ([`crate::contact`]) finds particles behind a tool segment. Where the
//! material flows around a convex die corner, the surface particles on either side of the
//! corner can both stay outside the tool while the corner lies inside the material between
//! them (RK particles are points; the surface between them is the polygon through the
//! boundary ring). A two-pass node-to-segment method (Hallquist, Goudreau and Benson 1985;
//! Wriggers 2006, *Computational Contact Mechanics*, section 9.1) also checks the master's
//! nodes against the slave surface: here each convex tool vertex `v` against the polygon of
//! the boundary ring positions `x_a` (counter-clockwise; in a Lagrangian description the
//! material's surface is the image of its reference boundary), read as the particle pass
//! leaves them: predicted, then moved by the corrector's displacement of the particle
//! pass's forces, so that a particle the particle pass pushes out of the tool is not
//! pushed a second time through the segments beside it.
//!
//! A corner inside the polygon, at the distance `g` (m) from its nearest ring segment
//! `(a, b)` at the point `c = (1 - s) x_a + s x_b` among the segments whose push leads away
//! from the tool (`u = (v - c) / g` with `u . (n_1 + n_2) > 0`, `n_1`, `n_2` the outward
//! normals of the faces meeting at the corner, whose sum is its pseudo-normal), gets the
//! paper's normal penalty (eq. 4) with its share `w = g / sum g` (over the corners on the
//! same segment, [`inside`]) of the segment's interpolated mass `m_s = w ((1 - s) m_a + s m_b)` (kg):
//! `f = m_s g / (dt dt_avg) (v - c) / g` (N) on the surface, pushing the material past
//! the corner; it is shared `(1 - s) f` and `s f` by the two ring particles, each spread to
//! the coefficients with eq. 7, and the tool takes the reaction `-f`. The pass is
//! frictionless: a corner touches the material over a point, where the particle pass
//! carries the friction of the faces on either side.
//!
//! Only the pushes that lead away from the tool: where the material flows past a corner
//! into a recess, the corner can lie nearer the ring's chord along the recess wall than the
//! chord under the face (the wheel forging's rim corners, q4 and SCNI on 30 x 30). Pushed
//! past the corner, the wall's chord goes into the tool (a push along the face, `u` at 90
//! degrees or more from the pseudo-normal, leaves the corner's point outside but not the
//! chord's end above the face), and the particle pass pushes it back out: the two passes
//! held the surface particles on the wall, the material folded at the corner, and q4's
//! punch force rose to 2.7 times q2's (SCNI's interface generated energy until the run
//! stopped). The 3D ridge pass (`solver/solid/ridges.rs`) has the rule in its own form: a
//! facet pushes a ridge only when its normal is against the ridge's pseudo-normal.

use crate::geometry::{closest_on_segment, left_normal};
use crate::math::Real;
use crate::tools::Tool;

/// The workpiece's surface as the corner pass reads it.
pub struct Surface<'a> {
    /// The boundary ring's particles, counter-clockwise.
    pub ring: &'a [u32],
    /// Position of each ring particle (m): predicted, corrected by the particle pass.
    pub positions: &'a [[Real; 2]],
    /// Lumped masses of all particles (kg).
    pub mass: &'a [Real],
}

/// A tool corner inside the workpiece.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Corner {
    /// The corner's position (m).
    pub at: [Real; 2],
    /// Index `k` in the ring of the nearest segment `(k, k + 1)`.
    pub segment: usize,
    /// Where on it the nearest point lies, `s` in [0, 1] from particle `k`.
    pub along: Real,
    /// The nearest point `c` on the segment (m).
    pub nearest: [Real; 2],
    /// Distance `g` from the corner to the surface (m), at most the tool's search depth.
    pub gap: Real,
    /// The corner's share of its segment's mass, `g / sum g` over the corners on the
    /// segment ([`inside`]).
    pub share: Real,
}

/// The convex corners of `tool` (in its current position) that lie inside the polygon of
/// the surface, within the tool's search depth of it (deeper ones would belong to material
/// the particle pass holds), each with its share `g_i / sum_j g_j` of its segment's mass
/// over the corners `j` on the same segment. A die's curve faceted finer than the particles
/// (a CAD arc, its vertices a few degrees apart) puts several corners over one segment:
/// each with the whole mass would add their stiffnesses and the explicit penalty would
/// overshoot (the interface generating energy); only the deepest would hand the push from
/// corner to corner as their depths cross (the force chattering). Shared by depth, the
/// segment's push `sum_i g_i^2 / sum_j g_j` is at most its deepest corner's, and a corner
/// coming in at `g = 0` takes nothing at first.
pub fn inside(tool: &Tool, surface: &Surface<'_>) -> Vec<Corner> {
    let x = surface.positions;
    if tool.convex.is_empty() || x.len() < 3 {
        return Vec::new();
    }
    let (lo, hi) = x.iter().fold(
        ([Real::INFINITY; 2], [Real::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    );
    let found: Vec<Corner> = convex_now(tool)
        .zip(outward_normals(tool))
        .filter_map(|(v, normals)| {
            if v[0] <= lo[0] || v[0] >= hi[0] || v[1] <= lo[1] || v[1] >= hi[1] {
                return None;
            }
            if !in_polygon(x, v) {
                return None;
            }
            let corner = nearest_segment(x, v, leaves(normals))?;
            (corner.gap > 0.0 && corner.gap <= tool.depth).then_some(corner)
        })
        .collect();
    found
        .iter()
        .map(|c| {
            let total: Real = found
                .iter()
                .filter(|d| d.segment == c.segment)
                .map(|d| d.gap)
                .sum();
            Corner {
                share: c.gap / total,
                ..*c
            }
        })
        .collect()
}

/// The segments of the closed ring polygon `x` (m, counter-clockwise) that a convex corner
/// of `tool` (in its current position) touches: the segment [`inside`] pushes for a corner
/// inside the polygon, the nearest segment for a corner within `reach` (m) outside it; none
/// for a corner exactly on it
/// (as a particle at zero gap is not in contact: a die placed on the workpiece touches
/// nothing until it presses). Where a tool is held through its corners (a curve faceted
/// finer than the particles), the corners keep the surface's particles just off the tool's
/// faces, and the segments they push are the surface in contact.
pub fn touching(tool: &Tool, x: &[[Real; 2]], reach: Real) -> Vec<usize> {
    if x.len() < 3 {
        return Vec::new();
    }
    convex_now(tool)
        .zip(outward_normals(tool))
        .filter_map(|(v, normals)| {
            let corner = match in_polygon(x, v) {
                true => nearest_segment(x, v, leaves(normals))?,
                false => nearest_segment(x, v, |_| true).filter(|c| c.gap <= reach)?,
            };
            (corner.gap != 0.0).then_some(corner.segment)
        })
        .collect()
}

/// The positions (m) of `tool`'s convex corners at its current stroke.
fn convex_now(tool: &Tool) -> impl Iterator<Item = [Real; 2]> + '_ {
    let s = tool.state.stroke;
    tool.convex.iter().map(move |&k| {
        let p = tool.points0[k as usize];
        [p[0] + s * tool.axis[0], p[1] + s * tool.axis[1]]
    })
}

/// The outward normals (towards the workpiece) of the two faces meeting at each of `tool`'s
/// convex corners, in the order of [`convex_now`].
fn outward_normals(tool: &Tool) -> impl Iterator<Item = [[Real; 2]; 2]> + '_ {
    let p = &tool.points0;
    tool.convex.iter().map(move |&k| {
        let k = k as usize;
        [left_normal(p[k - 1], p[k]), left_normal(p[k], p[k + 1])]
    })
}

/// Whether a push `u` (a unit vector) carries the surface from a convex corner away from
/// the tool: along the corner's pseudo-normal, `u . (n_1 + n_2) > 0`.
fn leaves([n1, n2]: [[Real; 2]; 2]) -> impl Fn([Real; 2]) -> bool {
    move |u| u[0] * (n1[0] + n2[0]) + u[1] * (n1[1] + n2[1]) > 0.0
}

/// The surface force of a corner (N; module doc): `m_s g / (dt dt_avg)` along `v - c`,
/// with the natural step `dt` and the corrector's step `dt_avg` (s) as the particle pass.
pub fn penalty(corner: &Corner, surface: &Surface<'_>, dt: Real, dt_avg: Real) -> [Real; 2] {
    let n = surface.ring.len();
    let (a, b) = (corner.segment, (corner.segment + 1) % n);
    let s = corner.along;
    let m = corner.share
        * ((1.0 - s) * surface.mass[surface.ring[a] as usize]
            + s * surface.mass[surface.ring[b] as usize]);
    let f = m / (dt * dt_avg);
    [
        f * (corner.at[0] - corner.nearest[0]),
        f * (corner.at[1] - corner.nearest[1]),
    ]
}

/// Whether `v` lies inside the closed polygon `x` (even-odd rule: a ray towards +x crosses
/// the edges an odd number of times).
fn in_polygon(x: &[[Real; 2]], v: [Real; 2]) -> bool {
    let n = x.len();
    let mut inside = false;
    for k in 0..n {
        let (a, b) = (x[k], x[(k + 1) % n]);
        if (a[1] > v[1]) != (b[1] > v[1]) {
            let cross = a[0] + (v[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if v[0] < cross {
                inside = !inside;
            }
        }
    }
    inside
}

/// The segment of the closed polygon `x` nearest to `v`, the first of equals, over the
/// segments whose push `u = (v - c) / g` (from the nearest point `c` towards `v`) `allowed`
/// accepts; `None` when none does.
fn nearest_segment(
    x: &[[Real; 2]],
    v: [Real; 2],
    allowed: impl Fn([Real; 2]) -> bool,
) -> Option<Corner> {
    let n = x.len();
    let mut best = Corner {
        at: v,
        segment: 0,
        along: 0.0,
        nearest: x[0],
        gap: Real::INFINITY,
        share: 1.0,
    };
    for k in 0..n {
        let (s, c, d2) = closest_on_segment(x[k], x[(k + 1) % n], v);
        // The squared distance rules out the segments clearly farther than the best so far
        // (the margin covers the roundings of `d2` against `hypot`'s: the same choices).
        if d2 > best.gap * best.gap * (1.0 + 1e-9) {
            continue;
        }
        let gap = (v[0] - c[0]).hypot(v[1] - c[1]);
        if gap < best.gap && (gap == 0.0 || allowed([(v[0] - c[0]) / gap, (v[1] - c[1]) / gap])) {
            best = Corner {
                at: v,
                segment: k,
                along: s,
                nearest: c,
                gap,
                share: 1.0,
            };
        }
    }
    best.gap.is_finite().then_some(best)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::friction::Friction;
    use crate::scene::{Motion, ToolSpec};

    fn tool(points: Vec<[Real; 2]>) -> Tool {
        Tool::new(
            &ToolSpec {
                name: "punch".into(),
                points_m: points,
                axis: [0.0, -1.0],
                motion: Motion::Fixed,
                friction: Friction::Coulomb { mu: 0.0 },
                separation: true,
                fill_points: Vec::new(),
                temperature_c: None,
                heat_transfer_w_per_m2_k: 0.0,
                heat_transfer_by_pressure: Vec::new(),
            },
            0.3,
        )
    }

    /// A unit square of material: a counter-clockwise ring of 8 particles of 2 kg.
    fn square() -> (Vec<[Real; 2]>, Vec<u32>, Vec<Real>) {
        let pts = [
            [0.0, 0.0],
            [0.5, 0.0],
            [1.0, 0.0],
            [1.0, 0.5],
            [1.0, 1.0],
            [0.5, 1.0],
            [0.0, 1.0],
            [0.0, 0.5],
        ];
        (pts.to_vec(), (0..8).collect(), vec![2.0; 8])
    }

    /// A punch whose face runs at y = 1.2 from the right, with a notch down to a corner at
    /// (0.75, `tip`), traversed with the material on its left (below).
    fn notched(tip: Real) -> Tool {
        tool(vec![
            [2.0, 1.2],
            [0.9, 1.2],
            [0.75, tip],
            [0.6, 1.2],
            [-1.0, 1.2],
        ])
    }

    #[test]
    fn a_corner_between_two_surface_particles_is_found_and_pushed_out() {
        let (positions, ring, mass) = square();
        let surface = Surface {
            ring: &ring,
            positions: &positions,
            mass: &mass,
        };
        // The corner dips 0.1 below the top face, between the particles at (1, 1), (0.5, 1).
        let punch = notched(0.9);
        assert_eq!(punch.convex, vec![2]);
        let found = inside(&punch, &surface);
        assert_eq!(found.len(), 1);
        let c = found[0];
        assert_eq!(c.segment, 4, "between (1, 1) and (0.5, 1)");
        assert!((c.gap - 0.1).abs() < 1e-12 && (c.along - 0.5).abs() < 1e-12);
        let f = penalty(&c, &surface, 0.1, 0.1);
        // m_s g / dt^2 = 2 * 0.1 / 0.01 = 20 N, down: the material is pushed past the corner.
        assert!(f[0].abs() < 1e-12 && (f[1] + 20.0).abs() < 1e-9, "{f:?}");
        // The same corner above the surface is outside the material.
        assert!(inside(&notched(1.05), &surface).is_empty());
    }

    /// A punch's face at y = 1 with a recess beyond a corner at (0.97, 1), the tool above
    /// the face and left of the recess wall; the material's top right particle has flowed
    /// past the corner into the recess, to (1, 1.04). The corner lies inside the surface's
    /// polygon, 0.03 from the right face and 0.0375 from the top chord. Pushed past the
    /// corner, the right face would go into the punch (left of its wall), where the particle
    /// pass pushes it back: the two passes held the wheel forging's rim particles on the
    /// punch's wall. The corner takes the top chord, whose push leaves the tool.
    #[test]
    fn a_corner_pushes_the_surface_only_out_of_the_tool() {
        let (mut positions, ring, mass) = square();
        positions[4] = [1.0, 1.04];
        let surface = Surface {
            ring: &ring,
            positions: &positions,
            mass: &mass,
        };
        let punch = tool(vec![[0.97, 2.0], [0.97, 1.0], [-1.0, 1.0]]);
        assert_eq!(punch.convex, vec![1]);
        let found = inside(&punch, &surface);
        assert_eq!(found.len(), 1);
        let c = found[0];
        assert_eq!(c.segment, 4, "the top chord from (1, 1.04) to (0.5, 1)");
        let chord = 0.04 * 0.47 / 0.5;
        assert!(
            (c.gap - chord / (1.0 + 0.08 * 0.08 as Real).sqrt()).abs() < 1e-12,
            "{c:?}"
        );
        let f = penalty(&c, &surface, 0.1, 0.1);
        assert!(
            f[1] < 0.0 && f[1].abs() > 10.0 * f[0].abs(),
            "down, not into the wall: {f:?}"
        );
        // The particle higher up the recess wall, the right face's chord tilted across the
        // corner: its push, along the face (u = (-0.999, -0.043)), would carry the chord's
        // top end into the punch. The top chord, 0.18 away, is pushed instead.
        positions[4] = [0.9702, 1.2];
        let surface = Surface {
            ring: &ring,
            positions: &positions,
            mass: &mass,
        };
        let found = inside(&punch, &surface);
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].segment, 4, "{:?}", found[0]);
        assert!((found[0].gap - 0.18).abs() < 0.01, "{:?}", found[0]);
    }

    /// Two corners of a faceted profile over the same surface segment (between (1, 1) and
    /// (0.5, 1)), 0.05 and 0.1 deep: they share the segment's mass by depth, 1/3 and 2/3, so
    /// the segment's push is `2 (0.05^2 + 0.1^2) / 0.15 / dt^2`, under the deeper one's alone.
    #[test]
    fn corners_over_one_segment_share_its_mass_by_depth() {
        let (positions, ring, mass) = square();
        let surface = Surface {
            ring: &ring,
            positions: &positions,
            mass: &mass,
        };
        let punch = tool(vec![
            [2.0, 1.2],
            [0.9, 1.2],
            [0.8, 0.95],
            [0.75, 1.1],
            [0.7, 0.9],
            [0.6, 1.2],
            [-1.0, 1.2],
        ]);
        assert_eq!(punch.convex, vec![2, 4]);
        let found = inside(&punch, &surface);
        assert_eq!(found.len(), 2);
        assert!(found.iter().all(|c| c.segment == 4));
        assert!((found[0].share - 1.0 / 3.0).abs() < 1e-12, "{found:?}");
        assert!((found[1].share - 2.0 / 3.0).abs() < 1e-12, "{found:?}");
        let push: Real = found
            .iter()
            .map(|c| -penalty(c, &surface, 0.1, 0.1)[1])
            .sum();
        assert!((push - 2.0 * (0.05 * 0.05 + 0.1 * 0.1) / 0.15 / 0.01).abs() < 1e-9);
        assert!(push < 2.0 * 0.1 / 0.01);
    }

    /// A corner touches the segment under it when inside the material or within the
    /// reach outside it, and no segment when farther off.
    #[test]
    fn a_corner_touches_the_segment_it_presses_or_nearly_does() {
        let (positions, _, _) = square();
        assert_eq!(touching(&notched(0.9), &positions, 0.05), vec![4]);
        assert_eq!(touching(&notched(1.04), &positions, 0.05), vec![4]);
        assert!(touching(&notched(1.06), &positions, 0.05).is_empty());
        assert!(touching(&notched(1.0), &positions, 0.05).is_empty());
    }

    #[test]
    fn concave_corners_are_never_checked() {
        // The polyline turns left at (0.75, 0.9): the tool is concave there.
        let concave = tool(vec![[2.0, 0.8], [0.75, 0.9], [-1.0, 0.8]]);
        assert!(concave.convex.is_empty());
    }
}
