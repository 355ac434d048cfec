//! The die-fill check of the step: which named points of each tool (cavity corners,
//! `[[tools]] fill_points`) the material has reached and when (read out, with how much of
//! each tool's length the workpiece touches, in `tool_readings.rs`). The test itself,
//! [`reach_points`], is generic over the dimension: the 3D solver's check
//! (`solid/fill.rs`) calls it on the body's surface particles.
//!
//! A fill point is reached at the first step after which a surface particle (of the
//! boundary ring, or any particle in contact with a tool) lies, at its physical position
//! `x_J = X_J + sum_I N_I(X_J) d_I`, within `output.fill_distance_rel` smallest spacings of
//! the point (which moves with the tool). A point still empty at the end of the stroke is
//! underfill.
//!
//! The contact length of a tool is the length of the workpiece's surface polygon (the
//! boundary ring's physical positions) over the segments whose two particles both lie on
//! the tool: inside it, or outside by at most [`ON_TOOL_SPACINGS`] smallest spacings (the
//! corrector leaves a particle in contact at about zero gap, on either side); its fraction
//! is that over the length of the tool's polyline. Both are read from the state alone, so a
//! restored state reports them as first computed.

use super::discretization::Discretization;
use super::state::{Filled, State};
use super::tool_readings::FillPoint;
use super::workspace::Workspace;
use crate::math::Real;
use crate::scene::Scene;
use crate::tools::Tool;

/// Farthest outside a tool a surface particle counts as on it, in smallest spacings: the
/// acceptance bound on penetration, taken on the other side.
pub const ON_TOOL_SPACINGS: Real = 0.05;

/// After a step with contact: records the fill points that a surface particle now reaches.
/// The predicted positions of the ring and of the particles in contact (a step ahead, from
/// the contact stage) pick those within a spacing more than the reach; their physical
/// positions decide.
pub(super) fn check(
    scene: &Scene,
    disc: &Discretization,
    tools: &[Tool],
    st: &mut State,
    ws: &Workspace,
) {
    if st.fill.iter().all(Option::is_some) {
        return;
    }
    let h = disc.h_min();
    let open = open_points(scene_points(scene, tools), &st.fill);
    let touching = ws.contact.near().map(|n| (n.0, n.2));
    let d = &st.d;
    reach_points(
        &open,
        ws.contact.ring_predicted().chain(touching),
        |j| disc.position(d, j),
        Reach {
            reach: scene.output.fill_distance_rel * h,
            h,
            time: st.time,
        },
        &mut st.fill,
        |t| tools[t].state.stroke,
    );
}

/// How near a particle must come to fill a point, and when.
pub(crate) struct Reach {
    /// The fill distance (m): `output.fill_distance_rel` smallest spacings.
    pub reach: Real,
    /// The smallest spacing (m), the margin the candidates' predicted positions get.
    pub h: Real,
    /// The time a point reached now is recorded with (s).
    pub time: Real,
}

/// The fill check of either dimension: of the `open` points (index in `fill`, position now
/// (m), tool), those a particle reaches are recorded in `fill` with the time and the tool's
/// `stroke` (m). The `candidates` (particle, a position near its physical one, m) within
/// `reach + h` of an open point are picked; their physical positions `position(j)` (m)
/// decide: a point is reached when `|x_J - p| <= reach`.
pub(crate) fn reach_points<const D: usize>(
    open: &[(usize, [Real; D], usize)],
    candidates: impl Iterator<Item = (usize, [Real; D])>,
    position: impl Fn(usize) -> [Real; D],
    at: Reach,
    fill: &mut [Option<Filled>],
    stroke: impl Fn(usize) -> Real,
) {
    // A point farther than `r` along an axis is farther than `r` (`hypot` is at least each
    // of its arguments): the box rules out most pairs before the distance is taken.
    let near = |x: [Real; D], p: [Real; D], r: Real| {
        (0..D).all(|k| (x[k] - p[k]).abs() <= r) && distance(x, p) <= r
    };
    let particles: Vec<usize> = candidates
        .filter(|&(_, x)| open.iter().any(|&(_, p, _)| near(x, p, at.reach + at.h)))
        .map(|(j, _)| j)
        .collect();
    for j in particles {
        let x = position(j);
        for &(k, p, t) in open {
            if fill[k].is_none() && near(x, p, at.reach) {
                fill[k] = Some(Filled {
                    time_s: at.time,
                    stroke_m: stroke(t),
                });
            }
        }
    }
}

/// `|a - b|` (m) by repeated `hypot` (in 2D `hypot(a_x - b_x, a_y - b_y)`).
fn distance<const D: usize>(a: [Real; D], b: [Real; D]) -> Real {
    (0..D).fold(0.0, |r: Real, k| r.hypot(a[k] - b[k]))
}

/// Every fill point as (index in the state's `fill`, position now (m), tool, name), tool by
/// tool in scene order, in either dimension: each tool given as its shift from its start
/// now, `s a` (m; `s` the stroke, `a` the unit axis), and its points at the start `p_0`
/// (m), which move with it: `p = p_0 + s a`.
pub(crate) fn points_now<'a, const D: usize, P>(
    tools: impl Iterator<Item = ([Real; D], P)> + 'a,
) -> impl Iterator<Item = (usize, [Real; D], usize, &'a str)> + 'a
where
    P: IntoIterator<Item = (&'a str, [Real; D])> + 'a,
{
    tools
        .enumerate()
        .flat_map(|(t, (shift, points))| {
            points.into_iter().map(move |(name, p0)| {
                let at: [Real; D] = std::array::from_fn(|k| p0[k] + shift[k]);
                (at, t, name)
            })
        })
        .enumerate()
        .map(|(k, (at, t, name))| (k, at, t, name))
}

/// The points of [`points_now`] that no particle has reached yet, as [`reach_points`] takes
/// them.
pub(crate) fn open_points<'a, const D: usize, P>(
    tools: impl Iterator<Item = ([Real; D], P)> + 'a,
    fill: &[Option<Filled>],
) -> Vec<(usize, [Real; D], usize)>
where
    P: IntoIterator<Item = (&'a str, [Real; D])> + 'a,
{
    points_now(tools)
        .filter(|&(k, ..)| fill[k].is_none())
        .map(|(k, at, t, _)| (k, at, t))
        .collect()
}

/// The points of [`points_now`] with when they filled, as the simulations report them.
pub(crate) fn fill_points<'a, const D: usize, P>(
    tools: impl Iterator<Item = ([Real; D], P)> + 'a,
    fill: &[Option<Filled>],
) -> Vec<FillPoint<D>>
where
    P: IntoIterator<Item = (&'a str, [Real; D])> + 'a,
{
    points_now(tools)
        .map(|(k, at_m, tool, name)| FillPoint {
            tool,
            name: name.to_owned(),
            at_m,
            filled: fill[k],
        })
        .collect()
}

/// The 2D tools' fill points as [`points_now`] takes them: each tool's shift and points.
pub(super) fn scene_points<'a>(
    scene: &'a Scene,
    tools: &'a [Tool],
) -> impl Iterator<Item = ([Real; 2], impl Iterator<Item = (&'a str, [Real; 2])> + 'a)> + 'a {
    scene.tools.iter().zip(tools).map(|(spec, tool)| {
        let s = tool.state.stroke;
        let shift = [s * tool.axis[0], s * tool.axis[1]];
        (
            shift,
            spec.fill_points.iter().map(|p| (&p.name[..], p.at_m)),
        )
    })
}
