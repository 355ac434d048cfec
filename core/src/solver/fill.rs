//! The die-fill check of the step: which named points of each tool (cavity corners,
//! `[[tools]] fill_points`) the material has reached and when (read out, with how much of
//! each tool's length the workpiece touches, in `tool_readings.rs`).
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
    let reach = scene.output.fill_distance_rel * h;
    let open: Vec<(usize, [Real; 2], usize)> = points_now(scene, tools)
        .filter(|&(k, _, _)| st.fill[k].is_none())
        .collect();
    let near = |x: [Real; 2], at: [Real; 2], r: Real| (x[0] - at[0]).hypot(x[1] - at[1]) <= r;
    let touching = ws.contact.near().map(|n| (n.0, n.2));
    let particles: Vec<usize> = ws
        .contact
        .ring_predicted()
        .chain(touching)
        .filter(|&(_, x)| open.iter().any(|&(_, at, _)| near(x, at, reach + h)))
        .map(|(j, _)| j)
        .collect();
    for j in particles {
        let x = disc.position(&st.d, j);
        for &(k, at, t) in &open {
            if st.fill[k].is_none() && near(x, at, reach) {
                st.fill[k] = Some(Filled {
                    time_s: st.time,
                    stroke_m: tools[t].state.stroke,
                });
            }
        }
    }
}

/// Every fill point of `scene` as (index in [`State::fill`], position now (m), tool), tool
/// by tool in scene order, with `tools` where they are now.
pub(super) fn points_now<'a>(
    scene: &'a Scene,
    tools: &'a [Tool],
) -> impl Iterator<Item = (usize, [Real; 2], usize)> + 'a {
    scene
        .tools
        .iter()
        .enumerate()
        .flat_map(move |(t, spec)| {
            let tool = &tools[t];
            let s = tool.state.stroke;
            spec.fill_points.iter().map(move |p| {
                let at = [p.at_m[0] + s * tool.axis[0], p.at_m[1] + s * tool.axis[1]];
                (at, t)
            })
        })
        .enumerate()
        .map(|(k, (at, t))| (k, at, t))
}
