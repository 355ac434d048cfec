//! The second pass of the 3D contact stage: the tools' ridges (the convex edges and vertices
//! of STL dies, [`crate::triangle_surface::Ridge`]) against the workpiece's surface between
//! its particles, the 3D counterpart of 2D's corner pass ([`crate::contact::corners`]).
//!
//! The particle pass (`contact.rs`) finds particles inside a tool. A die's sharp edge (a
//! knife, a punch's rim) can sink into the material between two rows of surface particles
//! while both rows stay outside the die: RK particles are points, and the surface between
//! them is the bilinear facet of the hexahedral cells through their positions (the faces
//! of [`super::heat::HeatSurface`], off the symmetry planes). As in 2D's two-pass
//! node-to-segment method (Hallquist, Goudreau and Benson 1985; Wriggers 2006,
//! *Computational Contact Mechanics*, section 9.1), the master's features are checked
//! against the slave's surface: each ridge segment against the facets through the
//! predicted positions `x_a` of their four particles.
//!
//! The pass reads the surface as the particle pass leaves it: the coefficients' predicted
//! velocities corrected by its forces, `v*_I + dt_avg f_I / m_I` (m/s), so that a ridge
//! over a row of particles the particle pass already pushes out of the die is not pushed
//! against twice (which would overshoot and make the interface generate energy).
//!
//! A facet `x(xi, eta) = sum_a N_a(xi, eta) x_a` (bilinear, `N_a` the weights of its corners
//! in order) has the unit normal `n` of its vector area `A_f = (x_2 - x_0) x (x_3 - x_1) / 2`
//! (out of the body). The ridges act at fixed sample points of the die
//! ([`SAMPLES_PER_SPACING`] per particle spacing `h`: a vertex itself, an edge of length
//! `L` at the middles of its `n = ceil(2 L / h)` equal parts, each standing for its part's
//! length `l = L / n`): the force acts where the die is, however the gap varies along the
//! ridge (rather than at the gap-weighted centroid of the part of a ridge below a facet,
//! one point per facet, which moved along the ridge as the surface rocked). A sample
//! point `p` meets its *nearest* facet among those facing the ridge (the facet's normal
//! strictly against the ridge's pseudo-normal `N_r`, `n . N_r < 0`): the one whose point
//! at the projection of `p` along its normal, `x(xi, eta) + s n = p` (Newton's method),
//! clamped to the facet, lies nearest to `p`; the first of equals. When `p` lies behind
//! it (`g = -s > 0`), within [`REACH_SPACINGS`] of a spacing, with the projection on the facet or
//! at most [`PUSH_MARGIN`] past its sides (a ridge under a valley of the surface projects
//! just past the facets on either side), the facet pushes it; when `p` lies in front of
//! its nearest facet it is outside the body there and nothing pushes it. The distance to
//! the clamped point, not the projection's `|s|`, decides: a facet beside the one over a
//! ridge, tilted as its row sinks, has the ridge's extension in front of its plane nearer
//! than the ridge lies below the facet over it, and the old rule (a facet in front within
//! a quarter of its size past its sides vetoing the facet behind) let the ridge sink
//! unopposed, then threw the surface off at `g / dt` (tens of m/s) when the veto lapsed;
//! the side faces of a block lie farther from a pyramid's tip and edges than the top face
//! over them, and no longer push them through the block.
//!
//! Each push is the paper's normal penalty (eq. 4) with the sample's share of the facet's
//! interpolated mass, `m_s = c sum_a N_a m_a` (kg), `c = min(1, l / sqrt |A_f|)` (a vertex
//! `c = 1`, as 2D's corner): `f_n = m_s g / (dt dt_avg)` (N) along `-n` on the surface,
//! pushing the material past the ridge, so that an edge across a facet carries the stiffness
//! 2D's corner gives a segment, however finely it is sampled; plus the tool's friction of
//! eqs. 5-6 from the interpolated velocity `v_s = sum_a N_a v_a` relative to the tool (no
//! stick force is carried between steps) and, for the shear and capped laws, the
//! interpolated flow stress and contact area of the particle pass ([`super::contact`]).
//! The force is shared `N_a f` by the four particles, each spread to the coefficients with
//! eq. 7, and the tool takes the reaction `-f` at the same point `x(xi, eta)`: force and
//! moment are conserved (`sum_a N_a = 1`, `sum_a N_a x_a = x(xi, eta)`), and the tool's work
//! `dt_avg f . v_tool` (J) enters the energy account as the particle pass's does. Each
//! corner's share of the normal force is booked with the particle pass's
//! ([`super::SolidState::pressed`]: the die's pressure and contact area) and in the normal
//! impulse of a heat transfer over pressure.
//!
//! Cost: nothing unless a die with ridges has the pass on (`ridges = true`, opt-in).
//! Otherwise, while no ridge reaches the bounds of the surface's last predicted positions
//! grown by [`REACH_SPACINGS`] and by how far they may have moved since (`max_J S_J du` per
//! stage, the particle pass's move bound), nothing is computed. Else the surface particles'
//! predicted positions are interpolated, the facets binned, and each sample point within
//! that reach of the surface's bounds meets only the facets of its bin, those whose box
//! lies farther than the nearest found passed over before any projection (on the conrod's
//! die, 2054 ridge edges, no measurable cost: 1.42 to 1.45 us per particle-step against
//! 1.50 us without, over the first 2.5 mm).
//!
//! Measured (`ridge_tests.rs`, docs/forging.md): a knife edge midway between two rows, a
//! quarter of the way and right over a row, and a pyramid's tip between four particles,
//! are held within 0.8 % of a spacing with the interface dissipating. Opt-in
//! ([`crate::scene::solid::SolidToolSpec::ridges`]): on the conrod's die (2054 ridge
//! edges, rounds faceted sharper than 20 degrees) the pass runs the full stroke within the
//! energy check but raises the force by up to 29 % on the 1 mm grid, and its interface gains
//! energy over the last millimetre (up to 13.9 J, about 2 % of the tool work then, 5.1 J at
//! the end; without the pass it dissipates 1.3 %).

use super::contact::{flow_stress, interface, predicted, Touch};
use super::{Pressed, SolidDisc, SolidSimulation, SolidState};
use crate::contact::sidibe2009::{penalty_force, Interface, Slave, SlaveForce};
use crate::contact::Forces;
use crate::math::{dot, Real};
use crate::solid_tool::SolidTool;
use crate::solver::point_outputs::PointOut;
use crate::solver::stable_step::StepLength;
use crate::stl::{cross, sub};
use crate::tools::Penetration;
use crate::triangle_surface::along;
use std::collections::HashMap;

/// How far past its sides (in `xi`, `eta`, of its size) the projection of a ridge point
/// on its nearest facet may fall for the facet to push it (the closest point then on the
/// facet's side): a ridge below a valley of the surface, a crease between two facets
/// tilted towards it, projects along either facet's normal just past both.
const PUSH_MARGIN: Real = 0.25;

/// How far past its sides (in `xi`, `eta`) a facet is still a candidate for the nearest
/// surface of a ridge point (its closest point then on the facet's side; farther out the
/// projection along its normal says nothing of the distance).
const NEAR_MARGIN: Real = 1.0;

/// How deep below its nearest facet a ridge sample point may lie for the pass to push it
/// out, in particle spacings (`h_min`), and how far it looks for that facet: the default
/// bound of a particle's depth in a tool (`checks.max_penetration_rel`, 0.1). The pass
/// holds a ridge at the surface from its first touch (within 1 % of a spacing in
/// `ridge_tests.rs`); a point found deeper came through where the pass did not follow it (a
/// fold of the surface turning a facet the ridge lay in front of into one it lies behind, a
/// die placed inside the body), and pushing it out in one step, at `g / dt`, flings the
/// surface off and generates energy: with a spacing, the conrod's full stroke stopped at
/// 5.7 mm, the interface having generated 5 % of the work in one sample's interval.
/// [`SolidSimulation::ridge_depth_now`] measures to the tool's search depth.
const REACH_SPACINGS: Real = 0.1;

/// Newton iterations of the projection on a facet (a flat parallelogram takes one).
const NEWTON: usize = 6;

/// Bins along a side of the facets' grid, at most.
const MAX_BINS: usize = 64;

/// The sample points along a ridge per spacing of the particles (`h_min`): the ridge's
/// penalty acts at fixed points of the die, each with the share of the ridge's length
/// about it.
const SAMPLES_PER_SPACING: Real = 2.0;

/// A ridge sample point below its nearest facet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Dent {
    /// The tool.
    pub tool: u32,
    /// The facet, an index into the surface's faces.
    pub facet: u32,
    /// `(xi, eta)` of the contact point on the facet (the projection, clamped to it).
    pub at: [Real; 2],
    /// The gap `g` (m), positive below the facet.
    pub gap: Real,
    /// The facet's unit normal `n`, out of the body.
    pub normal: [Real; 3],
    /// The sample's share of the facet's mass (-): the ridge's length about it over the
    /// facet's size `sqrt(A_f)`, at most 1; 1 for a vertex.
    pub share: Real,
}

/// The bilinear weights of a facet's corners at `(xi, eta)`.
fn weights([xi, eta]: [Real; 2]) -> [Real; 4] {
    [
        (1.0 - xi) * (1.0 - eta),
        xi * (1.0 - eta),
        xi * eta,
        (1.0 - xi) * eta,
    ]
}

/// `(xi, eta, s)` with `x(xi, eta) + s n = q` on the facet of corners `c` (m), by Newton's
/// method from its centre.
fn project(c: &[[Real; 3]; 4], n: [Real; 3], q: [Real; 3]) -> [Real; 3] {
    let mut u = [0.5, 0.5, 0.0];
    for _ in 0..NEWTON {
        let w = weights([u[0], u[1]]);
        let r: [Real; 3] = std::array::from_fn(|k| {
            w[0] * c[0][k] + w[1] * c[1][k] + w[2] * c[2][k] + w[3] * c[3][k] + u[2] * n[k] - q[k]
        });
        let a: [Real; 3] = std::array::from_fn(|k| {
            (1.0 - u[1]) * (c[1][k] - c[0][k]) + u[1] * (c[2][k] - c[3][k])
        });
        let b: [Real; 3] = std::array::from_fn(|k| {
            (1.0 - u[0]) * (c[3][k] - c[0][k]) + u[0] * (c[2][k] - c[1][k])
        });
        let bn = cross(b, n);
        let det = dot(&a, &bn);
        if det == 0.0 {
            break;
        }
        let m = r.map(|x| -x);
        let du = [
            dot(&m, &bn) / det,
            dot(&a, &cross(m, n)) / det,
            dot(&a, &cross(b, m)) / det,
        ];
        for (x, d) in u.iter_mut().zip(du) {
            *x += d;
        }
    }
    u
}

/// The facet's vector area `(x_2 - x_0) x (x_3 - x_1) / 2` (m^2), out of the body.
fn facet_area(c: &[[Real; 3]; 4]) -> [Real; 3] {
    cross(sub(c[2], c[0]), sub(c[3], c[1])).map(|x| 0.5 * x)
}

/// A ridge sample point against one facet: `(xi, eta)` of the projection along the facet's
/// normal, the gap `g = -s` (m, positive behind the facet), the distance (m) to the
/// facet's point at the projection clamped to it (the nearest-surface measure), and the
/// facet's unit normal; `None` when the facet does not face the ridge (its normal not
/// strictly against the ridge's pseudo-normal `N_r`), has no area, or the projection falls
/// farther than [`NEAR_MARGIN`] past its sides.
fn against(
    c: &[[Real; 3]; 4],
    ridge_normal: [Real; 3],
    p: [Real; 3],
) -> Option<([Real; 2], Real, Real, [Real; 3])> {
    let a = facet_area(c);
    let l = dot(&a, &a).sqrt();
    if l == 0.0 {
        return None;
    }
    let n = a.map(|x| x / l);
    if dot(&n, &ridge_normal) >= 0.0 {
        return None;
    }
    let u = project(c, n, p);
    let outside = |v: Real| !(-NEAR_MARGIN..=1.0 + NEAR_MARGIN).contains(&v);
    if outside(u[0]) || outside(u[1]) {
        return None;
    }
    let at = [u[0].clamp(0.0, 1.0), u[1].clamp(0.0, 1.0)];
    let w = weights(at);
    let q: [Real; 3] = std::array::from_fn(|k| (0..4).map(|i| w[i] * c[i][k]).sum());
    let d = sub(p, q);
    Some(([u[0], u[1]], -u[2], dot(&d, &d).sqrt(), n))
}

/// `[lo, hi]` of `x` (m).
fn bounds(x: &[[Real; 3]]) -> [[Real; 3]; 2] {
    x.iter().fold(
        [[Real::INFINITY; 3], [Real::NEG_INFINITY; 3]],
        |[lo, hi], p| {
            [
                std::array::from_fn(|k| lo[k].min(p[k])),
                std::array::from_fn(|k| hi[k].max(p[k])),
            ]
        },
    )
}

/// `[lo - by, hi + by]`.
fn grown([lo, hi]: [[Real; 3]; 2], by: Real) -> [[Real; 3]; 2] {
    [lo.map(|v| v - by), hi.map(|v| v + by)]
}

/// The nearest facet of a sample point so far: the facet, the projection's `(xi, eta)`, the
/// gap (m), the distance (m) and the facet's normal ([`against`]).
type Nearest = (u32, [Real; 2], Real, Real, [Real; 3]);

/// A point of a ridge at which its penalty acts: the tool, the point (m), the ridge's
/// pseudo-normal and the length of the ridge about it (m; 0 for a vertex).
type Sample = (usize, [Real; 3], [Real; 3], Real);

/// The sample points of the ridges of `tools` that reach into `lo..hi` (m), `spacing` (m)
/// the particles' least spacing (module doc): a vertex itself; an edge of length `L` at the
/// middles of its `n = ceil(L SAMPLES_PER_SPACING / spacing)` equal parts, each of length
/// `L / n`, fixed on the die whatever the box.
fn samples(tools: &[SolidTool], [lo, hi]: [[Real; 3]; 2], spacing: Real) -> Vec<Sample> {
    let inside = |p: &[Real; 3]| (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k]);
    let mut out = Vec::new();
    for (t, tool) in tools.iter().enumerate().filter(|(_, t)| t.has_ridges()) {
        for r in tool.ridges_in(lo, hi) {
            let e = sub(r.b, r.a);
            let length = dot(&e, &e).sqrt();
            if length == 0.0 {
                if inside(&r.a) {
                    out.push((t, r.a, r.normal, 0.0));
                }
                continue;
            }
            let n = ((length * SAMPLES_PER_SPACING / spacing).ceil() as usize).max(1);
            for k in 0..n {
                let p = along(r.a, e, (k as Real + 0.5) / n as Real);
                if inside(&p) {
                    out.push((t, p, r.normal, length / n as Real));
                }
            }
        }
    }
    out
}

/// Each ridge sample point of the tools (module doc) below its nearest facet of `faces`
/// (corners as indices into `x`, the positions of the surface's particles, m), within
/// `reach` (m) and the tool's search depth of it, in the order of the samples; `spacing`
/// (m) the particles' least spacing. The nearest facet is the one whose point at the sample's projection clamped to
/// it lies nearest (the first of equals): when the sample lies in front of it (outside the
/// body there), no facet pushes it.
pub(super) fn dents(
    faces: &[[u32; 4]],
    x: &[[Real; 3]],
    tools: &[SolidTool],
    spacing: Real,
    reach: Real,
) -> Vec<Dent> {
    let reach = tools
        .iter()
        .filter(|t| t.has_ridges())
        .map(|t| t.depth.min(reach))
        .fold(0.0, Real::max);
    if x.is_empty() || reach == 0.0 {
        return Vec::new();
    }
    let [lo, hi] = grown(bounds(x), reach);
    let points = samples(tools, [lo, hi], spacing);
    if points.is_empty() {
        return Vec::new();
    }
    // The grid over the samples' bounds within the surface's, bins of the largest facet.
    let ends: Vec<[Real; 3]> = points.iter().map(|s| s.1).collect();
    let [rlo, rhi] = grown(bounds(&ends), reach);
    let (glo, ghi): ([Real; 3], [Real; 3]) = (
        std::array::from_fn(|k| rlo[k].max(lo[k])),
        std::array::from_fn(|k| rhi[k].min(hi[k])),
    );
    let corners = |f: &[u32; 4]| f.map(|s| x[s as usize]);
    let boxes: Vec<[[Real; 3]; 2]> = faces.iter().map(|f| bounds(&corners(f))).collect();
    let largest = boxes
        .iter()
        .flat_map(|[a, b]| (0..3).map(move |k| b[k] - a[k]))
        .fold(0.0, Real::max);
    let dims: [usize; 3] = std::array::from_fn(|k| {
        (((ghi[k] - glo[k]) / largest.max(reach)).ceil() as usize).clamp(1, MAX_BINS)
    });
    let size: [Real; 3] = std::array::from_fn(|k| (ghi[k] - glo[k]).max(0.0) / dims[k] as Real);
    let cell = |y: [Real; 3]| -> [usize; 3] {
        std::array::from_fn(|k| {
            let f = ((y[k] - glo[k]) / size[k]).floor();
            (f.max(0.0) as usize).min(dims[k] - 1)
        })
    };
    let index = |i: [usize; 3]| i[0] + dims[0] * (i[1] + dims[1] * i[2]);
    let overlaps = |[a, b]: &[[Real; 3]; 2]| (0..3).all(|k| a[k] <= ghi[k] && b[k] >= glo[k]);
    // The facets of each bin their box grown by the reach overlaps, as offsets and items.
    let mut count = vec![0u32; dims.iter().product::<usize>() + 1];
    let each = |f: usize, visit: &mut dyn FnMut(usize)| {
        let g = grown(boxes[f], reach);
        if !overlaps(&g) {
            return;
        }
        let (a, b) = (cell(g[0]), cell(g[1]));
        for i2 in a[2]..=b[2] {
            for i1 in a[1]..=b[1] {
                for i0 in a[0]..=b[0] {
                    visit(index([i0, i1, i2]));
                }
            }
        }
    };
    for f in 0..faces.len() {
        each(f, &mut |b| count[b + 1] += 1);
    }
    for b in 1..count.len() {
        count[b] += count[b - 1];
    }
    let mut fill = count.clone();
    let mut items = vec![0u32; count[count.len() - 1] as usize];
    for f in 0..faces.len() {
        each(f, &mut |b| {
            items[fill[b] as usize] = f as u32;
            fill[b] += 1;
        });
    }
    let mut out = Vec::new();
    for &(t, p, ridge_normal, length) in &points {
        let b = index(cell(p));
        let mut best: Option<Nearest> = None;
        let within = tools[t].depth.min(reach);
        for &f in &items[count[b] as usize..count[b + 1] as usize] {
            // The distance to the facet's box, a lower bound on the distance to any of its
            // points: no nearer than the nearest found, or out of reach, it is passed over.
            let [blo, bhi] = boxes[f as usize];
            let off: Real = (0..3)
                .map(|k| (blo[k] - p[k]).max(p[k] - bhi[k]).max(0.0).powi(2))
                .sum::<Real>()
                .sqrt();
            if off > within || best.is_some_and(|(_, _, _, d, _)| off > d) {
                continue;
            }
            let c = corners(&faces[f as usize]);
            let Some((u, gap, distance, normal)) = against(&c, ridge_normal, p) else {
                continue;
            };
            if distance > within {
                continue;
            }
            let nearer = match best {
                None => true,
                Some((g, _, _, d, _)) => distance < d || (distance == d && f < g),
            };
            if nearer {
                best = Some((f, u, gap, distance, normal));
            }
        }
        let Some((f, u, gap, _, normal)) = best else {
            continue;
        };
        let on = |v: Real| (-PUSH_MARGIN..=1.0 + PUSH_MARGIN).contains(&v);
        if gap <= 0.0 || !on(u[0]) || !on(u[1]) {
            continue;
        }
        let share = match length > 0.0 {
            true => {
                let a = facet_area(&corners(&faces[f as usize]));
                (length / dot(&a, &a).sqrt().sqrt()).min(1.0)
            }
            false => 1.0,
        };
        out.push(Dent {
            tool: t as u32,
            facet: f,
            at: [u[0].clamp(0.0, 1.0), u[1].clamp(0.0, 1.0)],
            gap,
            normal,
            share,
        });
    }
    out
}

/// What the particle pass of a contact stage hands on to the ridge pass
/// ([`RidgePass::run`]).
pub(super) struct ParticlePass<'a> {
    /// The points' outputs (flow stresses for the friction laws that need one).
    pub out: &'a [PointOut],
    /// The contact force on each RK coefficient (N), eq. 7, which the ridge pass adds to.
    pub force: &'a mut Forces<3>,
    /// The particle pass's bound on the change of a coefficient's predicted displacement
    /// `d_I + dt v*_I` since the last stage (m).
    pub du: Real,
}

/// What the pass keeps between stages to skip its work while no ridge is near.
#[derive(Debug, Clone)]
pub(super) struct RidgePass {
    /// Bounds of the surface's predicted positions when last interpolated (m).
    bounds: Option<[[Real; 3]; 2]>,
    /// How far a surface particle may have moved since (m).
    moved: Real,
    /// The pass runs (false only in the tests that show what it prevents).
    pub(super) on: bool,
}

impl RidgePass {
    pub(super) fn new() -> RidgePass {
        RidgePass {
            bounds: None,
            moved: 0.0,
            on: true,
        }
    }

    /// The pass on the positions a natural step `dt = step.full` ahead (s), `dt_avg =
    /// step.avg` the corrector's step (s), after the particle pass `pass`: adds to its
    /// `force` and to the tools' forces (module doc).
    pub(super) fn run(
        &mut self,
        disc: &SolidDisc,
        tools: &mut [SolidTool],
        st: &mut SolidState,
        pass: ParticlePass<'_>,
        step: StepLength,
    ) -> Touch {
        let ParticlePass { out, force, du } = pass;
        let (dt, dt_avg) = (step.full, step.avg);
        let surface = &disc.heat_surface;
        if !self.on || surface.particles().is_empty() || !tools.iter().any(SolidTool::has_ridges) {
            return Touch::default();
        }
        let reach = REACH_SPACINGS * disc.h_min;
        self.moved += disc.sum_abs.iter().copied().fold(0.0, Real::max) * du;
        if let Some(b) = self.bounds.filter(|_| self.moved.is_finite()) {
            let [lo, hi] = grown(b, self.moved + reach);
            if tools
                .iter()
                .filter(|t| t.has_ridges())
                .all(|t| t.ridges_in(lo, hi).is_empty())
            {
                return Touch::default();
            }
        }
        // The coefficients' velocities after the particle pass's correction.
        let d = &st.d;
        let corrected: Vec<[Real; 3]> =
            st.v.iter()
                .zip(&force.at)
                .zip(&disc.inv_mass)
                .map(|((v, f), w)| std::array::from_fn(|k| v[k] + dt_avg * f[k] * w))
                .collect();
        let v = &corrected[..];
        let x: Vec<[Real; 3]> = surface
            .particles()
            .iter()
            .map(|&j| predicted(disc, d, v, dt, j as usize))
            .collect();
        self.bounds = Some(bounds(&x));
        self.moved = 0.0;
        let mut touch = Touch::default();
        // Each pressed particle's normal force on a scene tool, booked with the particle
        // pass's (`SolidState::pressed`, the die pressure and contact area) and the normal
        // impulse of a heat transfer over pressure.
        let mut booked: HashMap<(u32, u32), usize> = HashMap::new();
        for dent in dents(
            surface.parts().1,
            &x,
            tools,
            disc.h_min,
            REACH_SPACINGS * disc.h_min,
        ) {
            let j = surface.parts().1[dent.facet as usize]
                .map(|s| surface.particles()[s as usize] as usize);
            let w = weights(dent.at);
            let m: Real = dent.share * (0..4).map(|a| w[a] * disc.mass[j[a]]).sum::<Real>();
            let vs: [Real; 3] = (0..4).fold([0.0; 3], |s, a| {
                let va = disc.nodal.interpolate(j[a], v);
                std::array::from_fn(|k| s[k] + w[a] * va[k])
            });
            let tool = &mut tools[dent.tool as usize];
            let vt = tool.axis.map(|a| a * tool.state.velocity);
            let pen = Penetration {
                gap: dent.gap,
                normal: dent.normal.map(|x| -x),
            };
            let at = if tool.friction.needs_flow_stress() {
                (0..4).fold(Interface::default(), |s, a| {
                    let flow = flow_stress(disc, out, j[a]);
                    let i = interface(disc, j[a], flow, pen.normal, |i| {
                        predicted(disc, d, v, dt, i)
                    });
                    Interface {
                        flow_stress: s.flow_stress + w[a] * i.flow_stress,
                        area: s.area + w[a] * i.area,
                    }
                })
            } else {
                Interface::default()
            };
            let slave = Slave {
                m,
                v_rel: std::array::from_fn(|k| vs[k] - vt[k]),
                carried: [0.0; 3],
            };
            let SlaveForce { force: f, .. } =
                penalty_force(slave, pen, &tool.friction, at, dt, dt_avg);
            let normal = dot(&f, &pen.normal);
            for (a, &ja) in j.iter().enumerate() {
                if w[a] == 0.0 {
                    continue;
                }
                force.spread(&disc.nodal, ja, f.map(|x| w[a] * x));
                if (dent.tool as usize) < disc.scene_tools {
                    if booked.is_empty() {
                        booked = st
                            .pressed
                            .iter()
                            .enumerate()
                            .map(|(k, p)| ((p.particle, p.tool), k))
                            .collect();
                    }
                    match booked.get(&(ja as u32, dent.tool)) {
                        Some(&k) => st.pressed[k].force_n += w[a] * normal,
                        None => {
                            booked.insert((ja as u32, dent.tool), st.pressed.len());
                            st.pressed.push(Pressed {
                                particle: ja as u32,
                                tool: dent.tool,
                                force_n: w[a] * normal,
                                normal: pen.normal,
                            });
                        }
                    }
                    if let Some(i) = st.heat.as_mut().and_then(|h| h.normal_impulse.get_mut(ja)) {
                        *i += (w[a] * normal).abs() * dt_avg;
                    }
                }
            }
            for (a, f) in tool.state.force.iter_mut().zip(f) {
                *a -= f;
            }
            tool.state.normal_force += normal;
            touch.tool_work += dt_avg * dot(&f, &vt);
            touch.any = true;
            touch.tools |= (dent.tool as usize) < disc.scene_tools;
        }
        touch
    }
}

impl SolidSimulation {
    /// The deepest a scene tool's ridge lies below the workpiece's surface facets through
    /// the particles' physical positions now (m; module doc), within the tool's search
    /// depth: what the particles' penetration cannot see. 0 without a die with ridges.
    pub fn ridge_depth_now(&self) -> Real {
        let surface = &self.disc.heat_surface;
        let x: Vec<[Real; 3]> = surface
            .particles()
            .iter()
            .map(|&j| {
                let j = j as usize;
                let u = self.disc.nodal.interpolate(j, &self.st.d);
                std::array::from_fn(|k| self.disc.ref_pos[j][k] + u[k])
            })
            .collect();
        dents(
            surface.parts().1,
            &x,
            self.tools(),
            self.disc.h_min,
            Real::INFINITY,
        )
        .iter()
        .map(|d| d.gap)
        .fold(0.0, Real::max)
    }
}
