//! The `[[tools]]` section: the rigid tools, each a polyline with its motion, friction, heat
//! transfer and fill points, with what each must be ([`check`]; a tool's heat transfer,
//! which needs `[thermal]`, in [`ToolSpec::check_heat_transfer`]). The solver's tools are
//! built from it in [`crate::tools`].

use crate::friction::Friction;
use crate::math::Real;
use crate::thermal::properties::interpolate;
use crate::validation::{above_absolute_zero, increasing_table, is_name, Checks};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;

/// How a tool moves along its axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Motion {
    /// Does not move.
    Fixed,
    /// Constant velocity along the axis (m/s).
    Constant {
        /// Velocity along the axis (m/s).
        velocity_m_per_s: Real,
    },
    /// Piecewise-linear velocity over time: `[[t_s, v_m_per_s], ...]`, held after the last.
    Table {
        /// Breakpoints `(t, v)`, strictly increasing in t.
        points: Vec<[Real; 2]>,
    },
    /// Velocity set from outside while running (FMU input, ROS topic).
    External {
        /// Velocity until the first command (m/s).
        #[serde(default)]
        initial_velocity_m_per_s: Real,
    },
}

/// A rigid tool: a polyline; the workpiece lies on the left of its direction of travel
/// (the segment normal is the tangent turned +90 degrees).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ToolSpec {
    /// Name, used in outputs (`<name>.force_N`) and interfaces.
    pub name: String,
    /// Vertices (m), at least two.
    pub points_m: Vec<[Real; 2]>,
    /// Unit direction along which stroke, velocity and force are measured.
    pub axis: [Real; 2],
    /// Motion along the axis.
    pub motion: Motion,
    /// Friction law of the interface ([`Friction`]): a number is a Coulomb coefficient,
    /// a table names the model (`{ model = "shear", m = 0.3 }`); default frictionless.
    #[serde(default)]
    pub friction: Friction,
    /// Whether a particle may leave the tool again (the default). `false` is the wall of
    /// the finite-element benchmarks (Simo 1992): a particle that reached the tool stays on
    /// it, its normal force pulling as well as pushing, and slides along it under the
    /// friction law.
    #[serde(default = "default_separation")]
    pub separation: bool,
    /// The tool's temperature (degrees C) in a scene with `[thermal]`; it stays at it (a
    /// rigid die held at its temperature).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temperature_c: Option<Real>,
    /// Heat transfer coefficient of the contact between the tool and the workpiece
    /// (W/(m^2 K)), for a surface particle touching the tool; 0 (the default): no heat
    /// crosses.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub heat_transfer_w_per_m2_k: Real,
    /// Heat transfer coefficient rising with the contact pressure instead of the constant:
    /// `[[p (Pa), h (W/(m^2 K))], ...]`, p increasing, linear between the points and held
    /// beyond them. A particle's pressure is its normal contact force on the tool, averaged
    /// over the time since the last heat stage, over its share of the contact.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub heat_transfer_by_pressure: Vec<[Real; 2]>,
    /// Named points of the tool's surface (cavity corners) whose filling is reported: when
    /// the material first reached each, and which stay empty (underfill).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fill_points: Vec<FillPoint>,
}

fn default_separation() -> bool {
    true
}

impl ToolSpec {
    /// The tool's temperature and heat transfer.
    pub fn heat_contact(&self) -> HeatContact<'_> {
        HeatContact {
            temperature_c: self.temperature_c,
            heat_transfer_w_per_m2_k: self.heat_transfer_w_per_m2_k,
            heat_transfer_by_pressure: &self.heat_transfer_by_pressure,
        }
    }

    /// Whether heat crosses the contact with this tool: a transfer coefficient, constant or
    /// over pressure.
    pub fn transfers_heat(&self) -> bool {
        self.heat_contact().transfers_heat()
    }

    /// The transfer coefficient (W/(m^2 K)) at contact pressure `p` (Pa).
    pub fn heat_transfer_at(&self, p: Real) -> Real {
        self.heat_contact().heat_transfer_at(p)
    }

    /// The tool's temperature and heat transfer in a scene with `[thermal]`, under
    /// `tools.<name>.*` ([`HeatContact::check`]).
    pub(crate) fn check_heat_transfer(&self, out: &mut Checks) {
        self.heat_contact()
            .check(&self.name, |k| format!("tools.{}.{k}", self.name), out);
    }
}

/// A tool's heat contact with the workpiece, the same keys for a 2D tool and a 3D plane
/// tool: the tool's temperature (degrees C) and the transfer coefficient `h` of the
/// contact, a constant (W/(m^2 K)) or a table over the contact pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeatContact<'a> {
    /// `temperature_c`.
    pub temperature_c: Option<Real>,
    /// `heat_transfer_w_per_m2_k`.
    pub heat_transfer_w_per_m2_k: Real,
    /// `heat_transfer_by_pressure`, `[[p (Pa), h (W/(m^2 K))], ...]`.
    pub heat_transfer_by_pressure: &'a [[Real; 2]],
}

impl HeatContact<'_> {
    /// Whether heat crosses the contact: a transfer coefficient, constant or over pressure.
    pub fn transfers_heat(&self) -> bool {
        self.heat_transfer_w_per_m2_k > 0.0 || !self.heat_transfer_by_pressure.is_empty()
    }

    /// The transfer coefficient (W/(m^2 K)) at contact pressure `p` (Pa): the constant, or
    /// the table linear between its points and held beyond them.
    pub fn heat_transfer_at(&self, p: Real) -> Real {
        if self.heat_transfer_by_pressure.is_empty() {
            self.heat_transfer_w_per_m2_k
        } else {
            interpolate(self.heat_transfer_by_pressure, p)
        }
    }

    /// The tool `name`'s temperature and heat transfer in a scene with `[thermal]`, each
    /// under `key(k)`: a temperature above absolute zero, one coefficient (a constant or an
    /// increasing table over pressure), and a temperature wherever heat crosses.
    pub(crate) fn check(&self, name: &str, key: impl Fn(&str) -> String, out: &mut Checks) {
        if let Some(temp) = self.temperature_c {
            out.check(
                above_absolute_zero(temp),
                &key("temperature_c"),
                format!("must be above absolute zero (-273.15), got {temp}"),
            );
        }
        let h = self.heat_transfer_w_per_m2_k;
        out.check(
            h.is_finite() && h >= 0.0,
            &key("heat_transfer_w_per_m2_k"),
            format!("must be zero or positive, got {h}"),
        );
        let table = self.heat_transfer_by_pressure;
        out.check(
            table.is_empty() || h == 0.0,
            &key("heat_transfer_by_pressure"),
            "give the heat transfer coefficient as a constant or as a table over pressure, \
             not both"
                .into(),
        );
        out.check(
            increasing_table(table, |h| h >= 0.0),
            &key("heat_transfer_by_pressure"),
            format!(
                "must be [[p (Pa), h (W/(m^2 K))], ...] with p increasing and h zero or \
                 positive, got {table:?}"
            ),
        );
        out.check(
            !self.transfers_heat() || self.temperature_c.is_some(),
            &key("heat_transfer_w_per_m2_k"),
            format!("heat transfer to tool {name} needs its temperature_c"),
        );
    }
}

fn is_zero(x: &Real) -> bool {
    *x == 0.0
}

/// A named point of a tool's surface: the material has reached it once a particle in
/// contact with the tool lies within `output.fill_distance_rel` smallest spacings of it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FillPoint {
    /// Name, used in outputs (`<tool>.<name>.filled`).
    pub name: String,
    /// Position with the tool at its start (m); it moves with the tool.
    pub at_m: [Real; 2],
}

/// What each tool of the section must be, under `tools[i].*`: a name of its own, geometry
/// (at least two finite points, no zero-length segment, a unit axis), friction, fill
/// points and motion.
pub(crate) fn check(tools: &[ToolSpec], out: &mut Checks) {
    let mut names = BTreeSet::new();
    for (i, tool) in tools.iter().enumerate() {
        let key = |k: &str| format!("tools[{i}].{k}");
        out.check(
            is_name(&tool.name),
            &key("name"),
            format!(
                "`{}` must be non-empty and use only letters, digits and `_`",
                tool.name
            ),
        );
        out.check(
            names.insert(tool.name.clone()),
            &key("name"),
            format!("`{}` is used by two tools", tool.name),
        );
        out.check(
            tool.points_m.len() >= 2,
            &key("points_m"),
            format!(
                "a tool needs at least 2 points, got {}",
                tool.points_m.len()
            ),
        );
        out.check(
            tool.points_m
                .iter()
                .all(|p| p[0].is_finite() && p[1].is_finite()),
            &key("points_m"),
            "all coordinates must be finite".into(),
        );
        out.check(
            tool.points_m.windows(2).all(|s| s[0] != s[1]),
            &key("points_m"),
            "two consecutive points coincide (a zero-length segment)".into(),
        );
        let an = (tool.axis[0] * tool.axis[0] + tool.axis[1] * tool.axis[1]).sqrt();
        out.check(
            (an - 1.0).abs() < 1e-6,
            &key("axis"),
            format!("must be a unit vector, got {:?} (length {an})", tool.axis),
        );
        for (suffix, message) in tool.friction.validate() {
            out.check(false, &key(&format!("friction{suffix}")), message);
        }
        let points = tool.fill_points.iter().map(|p| (&p.name[..], &p.at_m[..]));
        check_fill_points(points, &key, out);
        tool.motion.check(&key, out);
    }
}

/// A tool's fill points, as (name, position), in 2D or 3D, under `key("fill_points[k]...")`:
/// each a name of its own among the tool's, its coordinates finite.
pub(crate) fn check_fill_points<'a>(
    points: impl Iterator<Item = (&'a str, &'a [Real])>,
    key: &dyn Fn(&str) -> String,
    out: &mut Checks,
) {
    let mut names = BTreeSet::new();
    for (k, (name, at)) in points.enumerate() {
        out.check(
            is_name(name) && names.insert(name.to_string()),
            &key(&format!("fill_points[{k}].name")),
            format!("`{name}` must be a new name of letters, digits and `_`"),
        );
        out.check(
            at.iter().all(|c| c.is_finite()),
            &key(&format!("fill_points[{k}].at_m")),
            "must be finite".into(),
        );
    }
}

impl Motion {
    /// Velocity along the axis (m/s) at time `t` (s): `command` if one was given, else the
    /// motion's (tables interpolate linearly and hold their ends).
    pub fn velocity_at(&self, t: Real, command: Option<Real>) -> Real {
        if let Some(c) = command {
            return c;
        }
        match self {
            Motion::Fixed => 0.0,
            Motion::Constant { velocity_m_per_s } => *velocity_m_per_s,
            Motion::External {
                initial_velocity_m_per_s,
            } => *initial_velocity_m_per_s,
            Motion::Table { points } => {
                let k = points.partition_point(|p| p[0] <= t);
                if k == 0 {
                    points[0][1]
                } else if k == points.len() {
                    points[k - 1][1]
                } else {
                    let (a, b) = (points[k - 1], points[k]);
                    a[1] + (b[1] - a[1]) * (t - a[0]) / (b[0] - a[0])
                }
            }
        }
    }

    /// What the motion's values must be, under `key("motion.*")`: finite velocities, and a
    /// table of at least one point with its times increasing.
    pub(crate) fn check(&self, key: &impl Fn(&str) -> String, out: &mut Checks) {
        match self {
            Motion::Fixed => {}
            Motion::Constant { velocity_m_per_s } => out.check(
                velocity_m_per_s.is_finite(),
                &key("motion.velocity_m_per_s"),
                "must be finite".into(),
            ),
            Motion::Table { points } => {
                out.check(
                    !points.is_empty(),
                    &key("motion.points"),
                    "needs at least one (t, v) point".into(),
                );
                out.check(
                    points.iter().all(|p| p[0].is_finite() && p[1].is_finite()),
                    &key("motion.points"),
                    "all values must be finite".into(),
                );
                out.check(
                    points.windows(2).all(|p| p[1][0] > p[0][0]),
                    &key("motion.points"),
                    "times must increase strictly".into(),
                );
            }
            Motion::External {
                initial_velocity_m_per_s,
            } => out.check(
                initial_velocity_m_per_s.is_finite(),
                &key("motion.initial_velocity_m_per_s"),
                "must be finite".into(),
            ),
        }
    }
}
