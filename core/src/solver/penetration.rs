//! How deep particles lie inside the tools, beyond the symmetry planes and inside the
//! workpiece's own other parts, measured on their physical positions
//! `x_J = X_J + sum_I N_I(X_J) d_I` (m) against each tool's polyline in its position at the
//! same time, each plane, and the boundary ring through the particles' physical positions;
//! and the scene's bound on it (`checks.max_penetration_rel`).
//!
//! Three measures, none limited to the particles the contact stage treats as slaves:
//! - at every step with a contact force, the particles that took one from a tool or a plane
//!   ([`crate::contact::Contact::near`]: every particle the stage found inside a tool or
//!   beyond a plane at its predicted position) and the self-contact slaves, whose predicted
//!   gap reached half the bound (the corrector only pushes a particle in contact out), at
//!   their physical positions; past the bound in a tool or beyond a plane the run stops with
//!   the step, time, particle, where it lies and the depth;
//! - at each output sample ([`measure`], [`super::Simulation::measure_sample`]), every particle against
//!   every segment of every tool at any depth and against every plane; and every ring
//!   particle against the rest of the boundary ring: how deep it lies inside another part
//!   of the workpiece (the ring covers a point near it twice,
//!   [`crate::geometry::winding`]) and how many pairs of the ring's segments cross.

use super::discretization::Discretization;
use super::state::State;
use super::workspace::Workspace;
use crate::contact::self_contact::is_neighbour_segment;
use crate::contact::Surface;
use crate::error::{Error, Result};
use crate::geometry::{closest_on_segment, crossings, left_normal, vertex_normal, winding};
use crate::math::Real;
use crate::scene::Scene;
use crate::tools::Tool;

/// Crossings of the boundary ring within this many smallest spacings of a segment's end are
/// a penalty contact's own gap (about a thousandth of a spacing), not the surface passing
/// through itself ([`crate::geometry::crossings`]).
pub const CROSSING_TOLERANCE_SPACINGS: Real = 0.01;

/// Where a particle lies that should not.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Within {
    /// Nowhere (a zero depth).
    #[default]
    Nothing,
    /// A tool, by index.
    Tool(usize),
    /// A symmetry plane, by index.
    Plane(usize),
    /// Inside another part of the workpiece: the boundary ring's segment from this ring
    /// index to the next.
    Itself(usize),
}

/// The deepest particle inside a tool, beyond a plane or inside the workpiece itself.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Penetrated {
    /// Depth (m).
    pub depth: Real,
    /// The particle.
    pub particle: usize,
    /// Where it lies.
    pub into: Within,
}

/// The measures of one sample.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Depths {
    /// The deepest particle inside a tool.
    pub tools: Penetrated,
    /// The deepest particle beyond a symmetry plane or the axis.
    pub planes: Penetrated,
    /// The deepest surface particle inside another part of the workpiece.
    pub itself: Penetrated,
    /// How many pairs of the boundary ring's segments cross by more than
    /// `CROSSING_TOLERANCE_SPACINGS` (0: the ring is simple up to contact gaps).
    pub crossings: usize,
}

/// The step's check: the deepest of the particles in contact whose predicted gap reached
/// half the bound, within the search depth (m), in a tool, beyond a plane or inside the
/// workpiece's own surface; kept as the run's largest and stopped at the scene's bound.
pub(super) fn check(
    scene: &Scene,
    disc: &Discretization,
    tools: &[Tool],
    st: &mut State,
    ws: &Workspace,
) -> Result<()> {
    let h = disc.h_min();
    let watch = 0.5 * scene.checks.max_penetration_rel * h;
    let deep: Vec<(usize, Surface)> = ws
        .contact
        .near()
        .filter(|n| n.3 >= watch)
        .map(|n| (n.0, n.1))
        .collect();
    let (mut in_tools, mut planes) = (Penetrated::default(), Penetrated::default());
    for (j, surface) in deep {
        let x = disc.position(&st.d, j);
        let (depth, worst, into) = match surface {
            Surface::Tool(t) => (
                tools[t].penetration(x).map(|p| p.gap),
                &mut in_tools,
                Within::Tool(t),
            ),
            Surface::Plane(p) => (
                Some(disc.planes[p].beyond(x)),
                &mut planes,
                Within::Plane(p),
            ),
        };
        if let Some(depth) = depth.filter(|&d| d > worst.depth) {
            *worst = Penetrated {
                depth,
                particle: j,
                into,
            };
        }
    }
    let itself = deep_self_contacts(disc, st, ws, watch);
    record(
        scene,
        disc,
        tools,
        st,
        Depths {
            tools: in_tools,
            planes,
            itself,
            crossings: 0,
        },
    )
}

/// The self-contact slaves whose predicted gap reached `watch` (m), at their physical
/// positions against their master segments (behind the segment's side): the deepest.
fn deep_self_contacts(
    disc: &Discretization,
    st: &State,
    ws: &Workspace,
    watch: Real,
) -> Penetrated {
    let mut worst = Penetrated::default();
    let (pairs, _) = ws.contact.self_pairs();
    let ring = &disc.boundary;
    let n = ring.len();
    for pair in pairs.iter().filter(|p| p.gap >= watch) {
        let (k, a) = (pair.slave as usize, pair.segment as usize);
        let b = (a + 1) % n;
        let [xk, xa, xb] = [k, a, b].map(|i| disc.position(&st.d, ring[i] as usize));
        let (_, c, d2) = closest_on_segment(xa, xb, xk);
        let d = d2.sqrt();
        let n_ab = left_normal(xa, xb);
        let behind = (xk[0] - c[0]) * n_ab[0] + (xk[1] - c[1]) * n_ab[1] > 0.0;
        if behind && d > worst.depth {
            worst = Penetrated {
                depth: d,
                particle: ring[k] as usize,
                into: Within::Itself(a),
            };
        }
    }
    worst
}

/// [`depths`] with the particles at their physical `positions` now (m), also kept as the
/// run's largest; past the scene's bound in a tool or beyond a plane an error naming the
/// particle, where it lies and the depth.
pub(super) fn measure(
    scene: &Scene,
    disc: &Discretization,
    tools: &[Tool],
    st: &mut State,
    positions: &[[Real; 2]],
) -> Result<Depths> {
    let d = depths(disc, tools, positions);
    record(scene, disc, tools, st, d)?;
    Ok(d)
}

/// Every particle at its physical position `positions` (m) against every tool at any depth
/// and every symmetry plane, and the boundary ring against itself (zero depths when
/// nothing lies inside), without keeping it.
pub(super) fn depths(disc: &Discretization, tools: &[Tool], positions: &[[Real; 2]]) -> Depths {
    let mut d = Depths::default();
    for (j, &x) in positions.iter().enumerate() {
        for (t, tool) in tools.iter().enumerate() {
            if let Some(depth) = tool.depth_inside(x) {
                if depth > d.tools.depth {
                    d.tools = Penetrated {
                        depth,
                        particle: j,
                        into: Within::Tool(t),
                    };
                }
            }
        }
        for (p, plane) in disc.planes.iter().enumerate() {
            let depth = plane.beyond(x);
            if depth > d.planes.depth {
                d.planes = Penetrated {
                    depth,
                    particle: j,
                    into: Within::Plane(p),
                };
            }
        }
    }
    let ring: Vec<[Real; 2]> = disc
        .boundary
        .iter()
        .map(|&j| positions[j as usize])
        .collect();
    d.itself = inside_itself(disc, &ring);
    d.crossings = crossings(&ring, CROSSING_TOLERANCE_SPACINGS * disc.h_min());
    d
}

/// The deepest ring particle inside another part of the workpiece, the ring at `ring` (m):
/// a ring particle lies inside other material when the ring covers a point just inside its
/// own part (a millionth of a spacing along its inward normal) twice, and as deep as the
/// nearest segment that is not one of its own two; a fold at the scale of the particles (a
/// kink whose segments cross) is inside by about its own size.
fn inside_itself(disc: &Discretization, ring: &[[Real; 2]]) -> Penetrated {
    let n = ring.len();
    let mut worst = Penetrated::default();
    let eps = 1e-6 * disc.h_min();
    for (k, &xk) in ring.iter().enumerate() {
        let Some(inward) = vertex_normal(ring, k) else {
            continue;
        };
        if winding(ring, [xk[0] + eps * inward[0], xk[1] + eps * inward[1]]) < 2 {
            continue;
        }
        let (d, a) = (0..n)
            .filter(|&a| !is_neighbour_segment(a, k, n, 0))
            .map(|a| {
                (
                    closest_on_segment(ring[a], ring[(a + 1) % n], xk).2.sqrt(),
                    a,
                )
            })
            .fold((Real::INFINITY, 0), |b, c| if c.0 < b.0 { c } else { b });
        if d > worst.depth && d.is_finite() {
            worst = Penetrated {
                depth: d,
                particle: disc.boundary[k] as usize,
                into: Within::Itself(a),
            };
        }
    }
    worst
}

/// What `into` names in a diagnosis.
fn describe(scene: &Scene, disc: &Discretization, tools: &[Tool], into: Within) -> String {
    match into {
        Within::Nothing => "nothing".into(),
        Within::Tool(t) => format!("inside tool `{}`", tools[t].name),
        Within::Plane(p) => format!("beyond {}", disc.planes[p].describe(scene.model.kinematics)),
        Within::Itself(a) => {
            let n = disc.boundary.len();
            format!(
                "inside the workpiece's own surface (the boundary segment from particle {} to {})",
                disc.boundary[a],
                disc.boundary[(a + 1) % n]
            )
        }
    }
}

/// Keeps each of `d` that is the run's deepest of its kind, and stops the run when a
/// particle lies deeper in a tool or beyond a plane than the bound. The workpiece inside
/// itself is measured and reported ([`super::Simulation::surface_warning`]) but does not
/// stop the run: a fold shorter than the kernel's support (two surface particles swapping
/// places on a coarse grid) cannot be held by contact (`crate::contact::self_contact`),
/// only resolved by a finer grid.
fn record(
    scene: &Scene,
    disc: &Discretization,
    tools: &[Tool],
    st: &mut State,
    d: Depths,
) -> Result<()> {
    st.max_penetration = st.max_penetration.max(d.tools.depth);
    st.max_beyond_plane = st.max_beyond_plane.max(d.planes.depth);
    st.max_inside_itself = st.max_inside_itself.max(d.itself.depth);
    st.max_crossings = st.max_crossings.max(d.crossings as u32);
    let h = disc.h_min();
    let bound = scene.checks.max_penetration_rel;
    let Some(worst) = [d.tools, d.planes]
        .into_iter()
        .filter(|p| p.depth > bound * h)
        .reduce(|a, b| if b.depth > a.depth { b } else { a })
    else {
        return Ok(());
    };
    Err(Error::Penetration {
        step: st.step,
        time: st.time,
        particle: worst.particle,
        reference: disc.original[worst.particle],
        into: describe(scene, disc, tools, worst.into),
        depth: worst.depth,
        depth_rel: worst.depth / h,
        bound,
    })
}
