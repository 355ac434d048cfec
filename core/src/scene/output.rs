//! The `[output]` section: what is recorded (history interval, frames, followed faces, the
//! fill distance of the tools' fill points, pressure stations), with what it must be
//! ([`OutputSpec::check`]; the history interval against the end time is checked across the
//! sections, `across_sections.rs`).

use super::constraints::Edge;
use crate::math::Real;
use crate::validation::{pos, Checks};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// What is recorded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Interval between rows of the time history (s); default: end time / 200
    /// ([`crate::Scene::history_interval`]).
    #[serde(default)]
    pub history_interval_s: Option<Real>,
    /// Number of VTK frames and shape plots over the run (0 for none).
    #[serde(default = "default_frames")]
    pub frames: usize,
    /// Workpiece edges whose particles are followed: for each, the bounds of the physical
    /// positions of the particles that started on it (e.g. `["y_min", "y_max"]` for the
    /// Taylor bar's impact-face radius and free-face length).
    #[serde(default)]
    pub faces: Vec<Edge>,
    /// How close (in smallest particle spacings) a particle in contact with a tool must
    /// come to one of the tool's `fill_points` to have filled it: by default one spacing,
    /// the resolution of the particle grid (a particle stands for the material within half
    /// a spacing around it, and penalty contact on both faces of a concave corner keeps it
    /// a fraction of a spacing off the corner).
    #[serde(default = "default_fill_distance")]
    pub fill_distance_rel: Real,
    /// Stations along each tool at which the contact pressure is measured (the FMI 3.0
    /// FMU's array output `<tool>.contact_pressure`): the tool's polyline cut into this many
    /// pieces of equal length; none when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure_stations: Option<usize>,
}

/// History rows over a run whose scene sets no `output.history_interval_s`.
pub const DEFAULT_HISTORY_ROWS: Real = 200.0;

fn default_frames() -> usize {
    5
}

pub(super) fn default_fill_distance() -> Real {
    1.0
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            history_interval_s: None,
            frames: default_frames(),
            faces: Vec::new(),
            fill_distance_rel: default_fill_distance(),
            pressure_stations: None,
        }
    }
}

impl OutputSpec {
    /// The fill distance and the pressure stations a run cannot use, under their dotted
    /// keys `output.*`.
    pub(crate) fn check(&self, out: &mut Checks) {
        out.check(
            pos(self.fill_distance_rel),
            "output.fill_distance_rel",
            format!("must be positive, got {}", self.fill_distance_rel),
        );
        if let Some(n) = self.pressure_stations {
            out.check(
                (1..=10_000).contains(&n),
                "output.pressure_stations",
                format!("must lie in [1, 10000], got {n}"),
            );
        }
    }
}
