//! The checks that span sections: what one section's values ask of another's. Each is a
//! function over the sections it reads; the scene's validation (`Scene::validate`,
//! `mod.rs`) calls them beside the sections' own checks.

use super::material::MaterialSpec;
use super::model::{Kinematics, Model};
use super::output::OutputSpec;
use super::time::TimeSpec;
use super::tools::ToolSpec;
use super::workpiece::Workpiece;
use crate::math::Real;
use crate::thermal::ThermalSpec;
use crate::validation::{pos, Checks};

/// An axisymmetric model's workpiece (`[model]`, `[workpiece]`): it lies at r >= 0, and
/// has no radial initial velocity when it touches the axis.
pub(super) fn axisymmetric_workpiece(model: &Model, w: &Workpiece, out: &mut Checks) {
    if model.kinematics == Kinematics::Axisymmetric {
        out.check(
            w.origin_m[0] >= 0.0,
            "workpiece.origin_m",
            format!(
                "an axisymmetric workpiece must lie at r >= 0, got r = {}",
                w.origin_m[0]
            ),
        );
        out.check(
            w.initial_velocity_m_per_s[0] == 0.0 || w.origin_m[0] > 0.0,
            "workpiece.initial_velocity_m_per_s",
            "a workpiece on the axis cannot have a radial initial velocity".into(),
        );
    }
}

/// Heat across the sections (`[thermal]`, `[material]`, `[[tools]]`): without `[thermal]`,
/// no flow stress of rate and temperature and no tool temperature or heat transfer; with
/// it, each tool's heat transfer ([`ToolSpec::check_heat_transfer`]).
pub(super) fn heat(
    thermal: Option<&ThermalSpec>,
    material: &MaterialSpec,
    tools: &[ToolSpec],
    out: &mut Checks,
) {
    if thermal.is_some() {
        for tool in tools {
            tool.check_heat_transfer(out);
        }
        return;
    }
    flow_stress_needs_heat(material, out);
    for tool in tools {
        out.check(
            tool.temperature_c.is_none() && tool.heat_transfer_w_per_m2_k == 0.0,
            &format!("tools.{}.temperature_c", tool.name),
            "a tool's temperature and heat transfer need the [thermal] section".into(),
        );
    }
}

/// A scene without `[thermal]` (2D or 3D): no flow stress of rate and temperature
/// (`[material]`).
pub(super) fn flow_stress_needs_heat(material: &MaterialSpec, out: &mut Checks) {
    out.check(
        !material.hardening.is_thermal(),
        "material.hardening.law",
        "a flow stress of rate and temperature needs the [thermal] section \
         (initial_temperature_c, specific_heat_j_per_kg_k)"
            .into(),
    );
}

/// The history interval (`[output]`) against the end time (`[time]`): positive, and at
/// most [`crate::sampling::MAX_SAMPLES`] rows over the run.
pub(super) fn history_interval(output: &OutputSpec, time: &TimeSpec, out: &mut Checks) {
    if let Some(h) = output.history_interval_s {
        out.check(
            pos(h)
                && (time.end_s.is_nan() || time.end_s / h <= crate::sampling::MAX_SAMPLES as Real),
            "output.history_interval_s",
            format!(
                "must be positive and give at most {} samples over time.end_s, got {h}",
                crate::sampling::MAX_SAMPLES
            ),
        );
    }
}
