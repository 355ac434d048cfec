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
//! in order) with the unit normal `n` of its vector area `(x_2 - x_0) x (x_3 - x_1) / 2`
//! (out of the body) meets a ridge that faces it (the ridge's pseudo-normal against `n`)
//! where a ridge point `p` projects inside it along `n`: `x(xi, eta) + s n = p` (solved by
//! Newton's method), `xi, eta` in [0, 1], `p` below the facet, `s < 0`. Along the part of
//! the segment that does (each end projected, linear between them), the gap `g = -s` (m)
//! is linear; the contact point is the gap-weighted centroid of that part (a vertex: the
//! vertex), so the force moves continuously as the ridge crosses the facets, and `g` and
//! `(xi, eta)` are its own projection. Per tool and facet the deepest ridge acts, when `g`
//! lies within the tool's search depth (deeper ones belong to material the particle pass
//! holds), and each part of a ridge meets only its nearest facet, as 2D's corner its nearest
//! segment ([`one_facet_per_part`]; a facet the ridge lies in front of, within a quarter of
//! its size past its sides, claims the part and pushes nothing). It gets the paper's normal penalty (eq. 4) with the facet's interpolated mass
//! `m_s = sum_a N_a m_a` (kg), `f_n = m_s g / (dt dt_avg)` (N) along `-n` on the surface,
//! pushing the material past the ridge, plus the tool's friction of eqs. 5-6 from the
//! interpolated velocity `v_s = sum_a N_a v_a` relative to the tool (no stick force is
//! carried between steps) and, for the shear and capped laws, the interpolated flow stress
//! and contact area of the particle pass ([`super::contact`]); the force is shared `N_a f`
//! by the four particles, each spread to the coefficients with eq. 7, and the tool takes
//! the reaction `-f` at the same point `x(xi, eta)`: force and moment are conserved
//! (`sum_a N_a = 1`, `sum_a N_a x_a = x(xi, eta)`), and the tool's work `dt_avg f . v_tool`
//! (J) enters the energy account as the particle pass's does.
//!
//! Cost: nothing without a die with ridges. Otherwise the ridges are clipped to the
//! surface's bounds grown by the search depth; while none reaches the bounds of the
//! surface's last predicted positions grown by how far they may have moved since
//! (`max_J S_J du` per stage, the particle pass's move bound), nothing is computed. Else
//! the surface particles' predicted positions are interpolated, the facets near the ridges
//! binned, and each ridge, cut in pieces of a bin's size, meets only the facets of its
//! bins.
//!
//! Known limits (`ridge_tests.rs`, docs/forging.md): a knife edge midway between two rows
//! is held within 0.3 % of a spacing; an edge a quarter of the way between rows or right
//! over a row, and a pyramid's tip, make the interface generate energy (the pass and the
//! particle pass pushing the same particles, and at the tip false contacts with the
//! block's side faces), which the energy check stops.

use super::contact::{flow_stresses, interface, predicted, Touch};
use super::{SolidDisc, SolidSimulation};
use crate::contact::sidibe2009::{penalty_force, Interface, Slave, SlaveForce};
use crate::contact::Forces;
use crate::math::{dot, Real};
use crate::solid_tool::SolidTool;
use crate::solver::point_outputs::PointOut;
use crate::stl::{cross, sub};
use crate::tools::Penetration;
use crate::triangle_surface::{along, clip_to_box, Ridge};

/// How far past its sides (in `xi`, `eta`) a facet in front of a ridge claims it as the
/// nearest surface ([`one_facet_per_part`]): a ridge over a valley of the surface projects
/// along the normals of the facets on either side past both.
const CLAIM_MARGIN: Real = 0.25;

/// Newton iterations of the projection on a facet (a flat parallelogram takes one).
const NEWTON: usize = 6;

/// Bins along a side of the facets' grid, at most.
const MAX_BINS: usize = 64;

/// A ridge point below a facet (in front of it: a claim of the nearest surface that pushes
/// nothing, when the gap is not positive).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Dent {
    /// The tool.
    pub tool: u32,
    /// The facet, an index into the surface's faces.
    pub facet: u32,
    /// `(xi, eta)` of the contact point on the facet.
    pub at: [Real; 2],
    /// The gap `g` (m), positive below the facet.
    pub gap: Real,
    /// The facet's unit normal `n`, out of the body.
    pub normal: [Real; 3],
    /// The ridge, an index into the clipped ridges.
    ridge: u32,
    /// The part of the ridge below the facet, `[t_0, t_1]` along it.
    span: [Real; 2],
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

/// The facet's unit normal out of the body, `None` for a facet without area.
fn facet_normal(c: &[[Real; 3]; 4]) -> Option<[Real; 3]> {
    let a = cross(sub(c[2], c[0]), sub(c[3], c[1]));
    let l = dot(&a, &a).sqrt();
    (l > 0.0).then(|| a.map(|x| x / l))
}

/// A ridge over a facet: the contact point's `(xi, eta)`, the gap (m), the facet's normal
/// and the part of the ridge over it, `[t_0, t_1]` along it.
type Meeting = ([Real; 2], Real, [Real; 3], [Real; 2]);

/// Where the ridge `r` lies over the facet of corners `c` (m) within `reach` (m) of it:
/// the contact point's `(xi, eta)`, its gap (m; not positive when the ridge lies in front
/// of the facet), the facet's normal and the part of the ridge over the facet, `[t_0,
/// t_1]` along it (module doc).
fn dent(r: &Ridge, c: &[[Real; 3]; 4], reach: Real) -> Option<Meeting> {
    let n = facet_normal(c)?;
    if dot(&n, &r.normal) >= 0.0 {
        return None;
    }
    let lo: [Real; 3] =
        std::array::from_fn(|k| c.iter().map(|p| p[k]).fold(Real::INFINITY, Real::min) - reach);
    let hi: [Real; 3] =
        std::array::from_fn(|k| c.iter().map(|p| p[k]).fold(Real::NEG_INFINITY, Real::max) + reach);
    let [t0, t1] = clip_to_box(r.a, r.b, lo, hi)?;
    let e = sub(r.b, r.a);
    let (qa, qb) = (along(r.a, e, t0), along(r.a, e, t1));
    let (ua, ub) = (project(c, n, qa), project(c, n, qb));
    // The part of [qa, qb] over the facet widened by `margin` on each side: xi + margin,
    // 1 + margin - xi, eta + margin, 1 + margin - eta not negative, each linear along it.
    let over = |margin: Real| -> Option<[Real; 2]> {
        let (mut from, mut to): (Real, Real) = (0.0, 1.0);
        for (fa, fb) in [
            (ua[0], ub[0]),
            (1.0 - ua[0], 1.0 - ub[0]),
            (ua[1], ub[1]),
            (1.0 - ua[1], 1.0 - ub[1]),
        ] {
            let (fa, fb) = (fa + margin, fb + margin);
            if fa == fb {
                if fa < 0.0 {
                    return None;
                }
                continue;
            }
            let root = fa / (fa - fb);
            if fb > fa {
                from = from.max(root);
            } else {
                to = to.min(root);
            }
        }
        (from <= to).then_some([from, to])
    };
    let global = |[from, to]: [Real; 2]| [t0 + (t1 - t0) * from, t0 + (t1 - t0) * to];
    let g = |t: Real| -(ua[2] + t * (ub[2] - ua[2]));
    let claim = over(CLAIM_MARGIN).and_then(|[from, to]| {
        let front = g(from).max(g(to));
        (front <= 0.0 && -front <= reach).then_some(([0.5; 2], front, n, global([from, to])))
    });
    let Some([from, to]) = over(0.0).filter(|&[from, to]| g(from) > 0.0 || g(to) > 0.0) else {
        return claim;
    };
    let span = global([from, to]);
    let (g0, g1) = (g(from), g(to));
    // The part below it, and the gap-weighted centroid of that part.
    let (a, b) = match (g0 > 0.0, g1 > 0.0) {
        (true, true) => (from, to),
        (true, false) => (from, from + (to - from) * g0 / (g0 - g1)),
        _ => (from + (to - from) * g0 / (g0 - g1), to),
    };
    let (ga, gb) = (g(a).max(0.0), g(b).max(0.0));
    let centroid = a + (b - a) * (ga + 2.0 * gb) / (3.0 * (ga + gb));
    let u = project(c, n, along(qa, sub(qb, qa), centroid));
    let gap = -u[2];
    (gap <= reach).then(|| ([u[0].clamp(0.0, 1.0), u[1].clamp(0.0, 1.0)], gap, n, span))
}

/// Each part of a ridge below one facet at most, the nearest, as 2D's corner meets its
/// nearest segment: of two dents (the deepest of each tool and facet) that clash, the
/// shallower stays (the first of equals in the ridges' and facets' order). Two dents of a
/// ridge clash when their parts overlap (by more than [`OVERLAP`] of the shorter, or at a
/// point when one is a point); a dent of a vertex clashes with a dent of any ridge of the
/// tool whose part passes through the vertex. So a ridge over a row of particles, below
/// the facets on both sides of it, pushes the surface once, and a ridge inside the body
/// near a side face (a knife longer than the block, a punch's edges near its tip) is not
/// pushed out through that face: a facet in front of the ridge there claims it.
fn one_facet_per_part(mut dents: Vec<Dent>, ridges: &[(usize, Ridge)]) -> Vec<Dent> {
    dents.sort_by(|p, q| {
        p.gap
            .total_cmp(&q.gap)
            .then(p.ridge.cmp(&q.ridge))
            .then(p.facet.cmp(&q.facet))
    });
    let part = |d: &Dent| {
        let r = &ridges[d.ridge as usize].1;
        let e = sub(r.b, r.a);
        (along(r.a, e, d.span[0]), along(r.a, e, d.span[1]))
    };
    let through = |point: [Real; 3], (a, b): ([Real; 3], [Real; 3])| {
        let e = sub(b, a);
        let l2 = dot(&e, &e);
        let t = match l2 > 0.0 {
            true => (dot(&sub(point, a), &e) / l2).clamp(0.0, 1.0),
            false => 0.0,
        };
        let d = sub(point, along(a, e, t));
        dot(&d, &d) <= (OVERLAP * OVERLAP) * l2.max(Real::MIN_POSITIVE)
    };
    let is_point = |d: &Dent| {
        let r = &ridges[d.ridge as usize].1;
        r.a == r.b
    };
    let mut kept: Vec<Dent> = Vec::with_capacity(dents.len());
    for d in dents {
        let clash = kept.iter().any(|k| {
            if k.ridge == d.ridge {
                let overlap = k.span[1].min(d.span[1]) - k.span[0].max(d.span[0]);
                let shorter = (k.span[1] - k.span[0]).min(d.span[1] - d.span[0]);
                return match shorter > 0.0 {
                    true => overlap > OVERLAP * shorter,
                    false => overlap >= 0.0,
                };
            }
            k.tool == d.tool
                && ((is_point(k) && through(part(k).0, part(&d)))
                    || (is_point(&d) && through(part(&d).0, part(k))))
        });
        if !clash {
            kept.push(d);
        }
    }
    kept
}

/// The share of the shorter part two parts of a ridge below two facets may overlap by
/// without clashing (round-off where a ridge crosses from one facet to the next).
const OVERLAP: Real = 1e-3;

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

/// The deepest ridge of each tool below each facet of `faces` (corners as indices into
/// `x`, the positions of the surface's particles, m), within the tool's search depth, in
/// the order of tools and facets (module doc).
pub(super) fn dents(faces: &[[u32; 4]], x: &[[Real; 3]], tools: &[SolidTool]) -> Vec<Dent> {
    let ridged = || tools.iter().enumerate().filter(|(_, t)| t.has_ridges());
    let reach = ridged().map(|(_, t)| t.depth).fold(0.0, Real::max);
    if x.is_empty() || reach == 0.0 {
        return Vec::new();
    }
    let [lo, hi] = grown(bounds(x), reach);
    let ridges: Vec<(usize, Ridge)> = ridged()
        .flat_map(|(t, tool)| tool.ridges_in(lo, hi).into_iter().map(move |r| (t, r)))
        .collect();
    if ridges.is_empty() {
        return Vec::new();
    }
    // The grid over the ridges' bounds within the surface's, bins of the largest facet.
    let ends: Vec<[Real; 3]> = ridges.iter().flat_map(|(_, r)| [r.a, r.b]).collect();
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
    let range = |[a, b]: [[Real; 3]; 2]| (cell(a), cell(b));
    let overlaps = |[a, b]: &[[Real; 3]; 2]| (0..3).all(|k| a[k] <= ghi[k] && b[k] >= glo[k]);
    // The facets of each bin their box grown by the reach overlaps, as offsets and items.
    let mut count = vec![0u32; dims.iter().product::<usize>() + 1];
    let each = |f: usize, visit: &mut dyn FnMut(usize)| {
        let g = grown(boxes[f], reach);
        if !overlaps(&g) {
            return;
        }
        let (a, b) = range(g);
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
    let smallest = size.iter().copied().fold(Real::INFINITY, Real::min);
    let mut out = Vec::new();
    let mut near = Vec::new();
    for (ri, (t, r)) in ridges.iter().enumerate() {
        let e = sub(r.b, r.a);
        let pieces = ((dot(&e, &e).sqrt() / smallest).ceil() as usize).max(1);
        near.clear();
        for p in 0..pieces {
            let (a, b) = (
                along(r.a, e, p as Real / pieces as Real),
                along(r.a, e, (p + 1) as Real / pieces as Real),
            );
            let (i, j) = range(bounds(&[a, b]));
            for i2 in i[2]..=j[2] {
                for i1 in i[1]..=j[1] {
                    for i0 in i[0]..=j[0] {
                        let b = index([i0, i1, i2]);
                        near.extend_from_slice(&items[count[b] as usize..count[b + 1] as usize]);
                    }
                }
            }
        }
        near.sort_unstable();
        near.dedup();
        for &f in &near {
            if let Some((at, gap, normal, span)) =
                dent(r, &corners(&faces[f as usize]), tools[*t].depth)
            {
                out.push(Dent {
                    tool: *t as u32,
                    facet: f,
                    at,
                    gap,
                    normal,
                    ridge: ri as u32,
                    span,
                });
            }
        }
    }
    out.sort_by(|p, q| {
        (p.tool, p.facet)
            .cmp(&(q.tool, q.facet))
            .then(q.gap.total_cmp(&p.gap))
    });
    out.dedup_by(|later, kept| later.tool == kept.tool && later.facet == kept.facet);
    let mut out = one_facet_per_part(out, &ridges);
    out.retain(|d| d.gap > 0.0);
    out.sort_by_key(|d| (d.tool, d.facet));
    out
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

    /// The pass on the positions a natural step `dt` ahead (s), `dt_avg` the corrector's
    /// step (s), `du` the particle pass's bound on the change of a coefficient's predicted
    /// displacement since the last stage (m): adds to `force` and to the tools' forces
    /// (module doc).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn run(
        &mut self,
        disc: &SolidDisc,
        tools: &mut [SolidTool],
        (d, v): (&[[Real; 3]], &[[Real; 3]]),
        out: &[PointOut],
        flow: &mut Option<Vec<Real>>,
        force: &mut Forces<3>,
        (dt, dt_avg, du): (Real, Real, Real),
    ) -> Touch {
        let surface = &disc.heat_surface;
        if !self.on || surface.particles().is_empty() || !tools.iter().any(SolidTool::has_ridges) {
            return Touch::default();
        }
        let reach = tools.iter().map(|t| t.depth).fold(0.0, Real::max);
        self.moved += disc.sum_abs.iter().copied().fold(0.0, Real::max) * du;
        if let Some(b) = self.bounds.filter(|_| self.moved.is_finite()) {
            let [lo, hi] = grown(b, self.moved + reach);
            if tools.iter().all(|t| t.ridges_in(lo, hi).is_empty()) {
                return Touch::default();
            }
        }
        // The coefficients' velocities after the particle pass's correction.
        let corrected: Vec<[Real; 3]> = v
            .iter()
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
        for dent in dents(surface.parts().1, &x, tools) {
            let j = surface.parts().1[dent.facet as usize]
                .map(|s| surface.particles()[s as usize] as usize);
            let w = weights(dent.at);
            let m: Real = (0..4).map(|a| w[a] * disc.mass[j[a]]).sum();
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
                let flow = flow_stresses(flow, disc, out);
                (0..4).fold(Interface::default(), |s, a| {
                    let i = interface(disc, j[a], flow[j[a]], pen.normal, |i| {
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
            for (a, &ja) in j.iter().enumerate() {
                if w[a] != 0.0 {
                    force.spread(&disc.nodal, ja, f.map(|x| w[a] * x));
                }
            }
            for (a, f) in tool.state.force.iter_mut().zip(f) {
                *a -= f;
            }
            tool.state.normal_force += dot(&f, &pen.normal);
            touch.tool_work += dt_avg * dot(&f, &vt);
            touch.any = true;
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
        dents(surface.parts().1, &x, self.tools())
            .iter()
            .map(|d| d.gap)
            .fold(0.0, Real::max)
    }
}
