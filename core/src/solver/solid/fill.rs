//! Die fill in 3D: the tools' named points (`[[tools]] fill_points`, three coordinates)
//! and when the material reached them, the 2D check ([`crate::solver::fill`]) on the 3D
//! body.
//!
//! A fill point moves with its tool, `p(t) = p_0 + s(t) a` (m; `s` the stroke, `a` the
//! unit axis). It is reached at the first step after which a particle of the workpiece's
//! surface (the faces of one cell, `heat.rs`'s surface) lies, at its physical position
//! `x_J = X_J + sum_I N_I(X_J) d_I` (m), within `output.fill_distance_rel` smallest
//! spacings of it: `|x_J - p| <= r` (the 2D test, [`reach_points`]). Checked after every
//! step with contact while a point is open, as in 2D. A point must lie on its tool's
//! surface at the start, within the fill distance ([`check_points`]): one deeper inside the
//! die, or out in front of it, is a typing error the run would report as underfill.

use super::{SolidDisc, SolidSimulation, SolidState};
use crate::error::{Error, Result};
use crate::math::Real;
use crate::scene::solid::SolidScene;
use crate::solid_tool::SolidTool;
use crate::solver::fill::{fill_points, open_points, reach_points, Reach};
use crate::solver::tool_readings::FillPoint;

/// The 3D tools' fill points as [`crate::solver::fill::points_now`] takes them: each tool's shift and points.
fn scene_points<'a>(
    scene: &'a SolidScene,
    tools: &'a [SolidTool],
) -> impl Iterator<Item = ([Real; 3], impl Iterator<Item = (&'a str, [Real; 3])> + 'a)> + 'a {
    scene.tools.iter().zip(tools).map(|(spec, tool)| {
        let s = tool.state.stroke;
        let shift = tool.axis.map(|a| s * a);
        (
            shift,
            spec.fill_points.iter().map(|p| (&p.name[..], p.at_m)),
        )
    })
}

/// At setup: every fill point lies on its tool's surface at the start, its signed depth in
/// the tool ([`SolidTool::depth_of`]: a plane's distance, a triangle surface's exact signed
/// distance) within the fill distance `output.fill_distance_rel h_min` (m) either way.
///
/// # Errors
///
/// A point farther from its tool's surface, named by its key
/// `tools[i].fill_points[k].at_m`.
pub(super) fn check_points(scene: &SolidScene, tools: &[SolidTool], h_min: Real) -> Result<()> {
    let reach = scene.output.fill_distance_rel * h_min;
    for (i, (spec, tool)) in scene.tools.iter().zip(tools).enumerate() {
        for (k, p) in spec.fill_points.iter().enumerate() {
            let depth = tool.depth_of(p.at_m);
            if depth.abs() > reach {
                let side = if depth > 0.0 { "inside" } else { "in front of" };
                return Err(Error::Request(format!(
                    "tools[{i}].fill_points[{k}].at_m: `{}` at {:?} m lies {:.4e} m {side} the surface of tool `{}`, farther than output.fill_distance_rel = {} smallest spacings ({reach:.4e} m): a fill point is a point of the tool's surface",
                    p.name,
                    p.at_m,
                    depth.abs(),
                    spec.name,
                    scene.output.fill_distance_rel,
                )));
            }
        }
    }
    Ok(())
}

/// After a step with contact: records the fill points a surface particle now reaches (see
/// the module doc), the planes' scene tools first among `tools`.
pub(super) fn check(
    scene: &SolidScene,
    disc: &SolidDisc,
    tools: &[SolidTool],
    st: &mut SolidState,
) {
    if st.fill.iter().all(Option::is_some) {
        return;
    }
    let open = open_points(scene_points(scene, tools), &st.fill);
    let d = &st.d;
    let position = |j: usize| -> [Real; 3] {
        let u = disc.nodal.interpolate(j, d);
        std::array::from_fn(|k| disc.ref_pos[j][k] + u[k])
    };
    let surface = disc.heat_surface.particles().iter().map(|&j| {
        let j = j as usize;
        (j, position(j))
    });
    reach_points(
        &open,
        surface,
        position,
        Reach {
            reach: scene.output.fill_distance_rel * disc.h_min,
            h: disc.h_min,
            time: st.time,
        },
        &mut st.fill,
        |t| tools[t].state.stroke,
    );
}

impl SolidSimulation {
    /// Every tool's fill points, tool by tool, with where they are now and when they filled.
    pub fn fill_points(&self) -> Vec<FillPoint<3>> {
        fill_points(scene_points(&self.scene, &self.tools), &self.st.fill)
    }
}
