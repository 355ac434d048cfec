//! Scene files: the one place that decides what is modelled (TOML, SI units).
//!
//! A scene gives the workpiece (a particle grid over a rectangle, plane strain or
//! axisymmetric), its material, the discretisation knobs, the rigid tools and how they move,
//! essential conditions, the time span and what to record. Every syntax error, missing,
//! unknown or mistyped key and every non-physical value is reported with the key and its
//! line; nothing here panics on user input.
//!
//! This file holds the [`Scene`] itself, how it is read and what its validation checks in
//! which order ([`Scene::validate`]). Each section has its own file with its types and its
//! own checks, under the section's dotted keys: `model.rs` (`[model]`), `workpiece.rs`,
//! `material.rs`, [`crate::thermal`]'s `settings.rs` (`[thermal]`), `discretization.rs`,
//! `time.rs` (with the mass scaling), `constraints.rs`, `self_contact.rs`, `tools.rs`,
//! `output.rs`, `checks.rs` (the run's limits) and `reference.rs`. What one section asks of
//! another is checked in `across_sections.rs`. The findings and the predicates the checks
//! share are in `validation.rs`; where a key stands in the text, in [`crate::scene_keys`].

mod across_sections;
mod checks;
mod constraints;
mod discretization;
mod material;
mod model;
mod output;
mod reference;
mod self_contact;
pub mod solid;
mod time;
mod tools;
mod workpiece;

pub use crate::friction::Friction;
pub use crate::thermal::ThermalSpec;
pub use checks::Checks;
pub use constraints::{Component, ConstraintSpec, Edge};
pub use discretization::{Discretization, IntegrationRule};
pub use material::MaterialSpec;
pub use model::{Kinematics, Model};
pub use output::{OutputSpec, DEFAULT_HISTORY_ROWS};
pub use reference::Reference;
pub use self_contact::SelfContactSpec;
pub use solid::{SceneFile, SolidScene};
pub use time::{AtRereference, MassScaling, TimeSpec};
pub use tools::{FillPoint, HeatContact, Motion, ToolSpec};
pub use workpiece::Workpiece;

use crate::error::{Error, Result};
use crate::math::Real;
use crate::validation;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A whole scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name, used for output folders and FMU identifiers.
    pub name: String,
    /// Free text shown in reports.
    #[serde(default)]
    pub description: String,
    /// Kinematic model.
    pub model: Model,
    /// The deformable body.
    pub workpiece: Workpiece,
    /// Its material.
    pub material: MaterialSpec,
    /// Temperature and heat; a scene without it is isothermal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal: Option<ThermalSpec>,
    /// Speed/accuracy knobs of the discretisation.
    #[serde(default)]
    pub discretization: Discretization,
    /// Time span and step.
    pub time: TimeSpec,
    /// Essential conditions on the physical displacement of workpiece edges.
    #[serde(default)]
    pub constraints: Vec<ConstraintSpec>,
    /// Rigid tools (polylines).
    #[serde(default)]
    pub tools: Vec<ToolSpec>,
    /// Contact of the workpiece's surface with itself (on unless the scene turns it off).
    #[serde(default)]
    pub self_contact: SelfContactSpec,
    /// What to record.
    #[serde(default)]
    pub output: OutputSpec,
    /// Run-time checks.
    #[serde(default)]
    pub checks: Checks,
    /// Published results to print beside ours (not used by the solver).
    #[serde(default)]
    pub reference: Vec<Reference>,
}

impl Scene {
    /// Whether heat moves in the workpiece or across its surface, or is made at it: a
    /// `[thermal]` section with conduction, convection or radiation, a tool with heat
    /// transfer or with friction (the heat stage runs); otherwise heating is adiabatic.
    pub fn transfers_heat(&self) -> bool {
        self.thermal.as_ref().is_some_and(|t| {
            t.conductivity_w_per_m_k > 0.0
                || !t.conductivity_by_temperature.is_empty()
                || t.convection_w_per_m2_k > 0.0
                || t.emissivity > 0.0
                || self.tools.iter().any(ToolSpec::transfers_heat)
        }) || self.heats_by_friction()
    }

    /// Whether friction at a tool makes heat: a `[thermal]` section and a tool with
    /// friction. The heat stage then takes it into the particles it was made at.
    pub fn heats_by_friction(&self) -> bool {
        self.thermal.is_some() && self.tools.iter().any(|t| !t.friction.is_frictionless())
    }

    /// Whether a tool's heat transfer depends on the contact pressure: the contact stage
    /// then books each particle's normal impulse for the heat stage.
    pub fn transfers_heat_by_pressure(&self) -> bool {
        self.thermal.is_some()
            && self
                .tools
                .iter()
                .any(|t| !t.heat_transfer_by_pressure.is_empty())
    }

    /// Every non-physical or inconsistent value, as (key path, message): the scene's name,
    /// then each section's own checks in the order of the fields above, each check that
    /// spans sections (`across_sections.rs`) beside a section it reads, and the mass
    /// scaling (`time.mass_scaling`) last.
    pub fn validate(&self) -> Vec<(String, String)> {
        let mut out = validation::Checks::default();
        validation::scene_name(&self.name, &mut out);
        self.model.check(&mut out);
        self.workpiece.check(&mut out);
        across_sections::axisymmetric_workpiece(&self.model, &self.workpiece, &mut out);
        self.material.check(&mut out);
        if let Some(thermal) = &self.thermal {
            thermal.check(&mut out);
        }
        across_sections::heat(self.thermal.as_ref(), &self.material, &self.tools, &mut out);
        self.discretization.check(&mut out);
        self.time.check(&mut out);
        constraints::check(&self.constraints, &mut out);
        self.self_contact.check(&mut out);
        tools::check(&self.tools, &mut out);
        across_sections::history_interval(&self.output, &self.time, &mut out);
        self.output.check(&mut out);
        self.checks.check(&mut out);
        if let Some(mass_scaling) = &self.time.mass_scaling {
            mass_scaling.check(&mut out, self.discretization.rereference_stretch.is_some());
        }
        out.0
    }

    /// Read and validate a scene from a file.
    pub fn from_file(path: &std::path::Path) -> Result<Scene> {
        Scene::from_str_named(&read_text(path)?, &path.display().to_string())
    }

    /// Parse and validate scene text; `file` names it in error messages.
    pub fn from_str_named(text: &str, file: &str) -> Result<Scene> {
        crate::scene_overrides::parse(text, file)
    }

    /// The interval between history rows (s): `output.history_interval_s`, or the end time
    /// over [`DEFAULT_HISTORY_ROWS`]. Every front end samples at it.
    pub fn history_interval(&self) -> Real {
        self.output
            .history_interval_s
            .unwrap_or(self.time.end_s / DEFAULT_HISTORY_ROWS)
    }

    /// The integration rule, overridable from outside (CLI, FMU parameter).
    pub fn with_integration(mut self, rule: IntegrationRule) -> Scene {
        self.discretization.integration = rule;
        self
    }
}

/// The text of the scene file at `path`; a file that cannot be read is a syntax error
/// naming it.
pub fn read_text(path: &std::path::Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| Error::SceneSyntax {
        file: path.display().to_string(),
        message: format!("cannot read: {e}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
name = "t"
[model]
kinematics = "axisymmetric"
[workpiece]
origin_m = [0.0, 0.0]
size_m = [0.0032, 0.0324]
particles = [5, 11]
initial_velocity_m_per_s = [0.0, -227.0]
[material]
density_kg_per_m3 = 8930.0
youngs_modulus_pa = 117e9
poisson_ratio = 0.35
hardening = { law = "linear", yield_stress_pa = 400e6, modulus_pa = 100e6 }
[time]
end_s = 1e-6
[[tools]]
name = "wall"
points_m = [[0.0, 0.0], [0.02, 0.0]]
axis = [0.0, -1.0]
motion = { kind = "fixed" }
"#;

    fn err(text: &str) -> String {
        Scene::from_str_named(text, "s.toml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn good_scene_parses() {
        let s = Scene::from_str_named(GOOD, "s.toml").unwrap();
        assert_eq!(s.workpiece.particles, [5, 11]);
        assert_eq!(s.discretization.integration, IntegrationRule::Q2);
    }

    #[test]
    fn missing_key_is_named_with_its_line() {
        let e = err(&GOOD.replace("density_kg_per_m3 = 8930.0\n", ""));
        // The key is absent, so its table's header line is named.
        assert!(
            e.contains("density_kg_per_m3") && e.contains("line 10"),
            "{e}"
        );
    }

    #[test]
    fn wrong_type_is_named_with_its_key_and_line() {
        let e = err(&GOOD.replace("poisson_ratio = 0.35", "poisson_ratio = \"soft\""));
        assert!(
            e.contains("line 13") && e.contains("`material.poisson_ratio`"),
            "{e}"
        );
        let e = err(&GOOD.replace("axis = [0.0, -1.0]", "axis = [0.0, \"down\"]"));
        assert!(
            e.contains("line 20") && e.contains("`tools[0].axis[1]`"),
            "{e}"
        );
    }

    #[test]
    fn unknown_key_is_named_with_its_line() {
        let e = err(&GOOD.replace("end_s = 1e-6", "end_s = 1e-6\nend_time = 3"));
        assert!(e.contains("end_time") && e.contains("line 17"), "{e}");
    }

    #[test]
    fn non_physical_values_are_refused_with_key_and_line() {
        let cases = [
            (
                "density_kg_per_m3 = 8930.0",
                "density_kg_per_m3 = -1.0",
                "material.density_kg_per_m3",
                11,
            ),
            (
                "poisson_ratio = 0.35",
                "poisson_ratio = 0.5",
                "material.poisson_ratio",
                13,
            ),
            (
                "particles = [5, 11]",
                "particles = [0, 11]",
                "workpiece.particles",
                8,
            ),
            (
                "axis = [0.0, -1.0]",
                "axis = [0.0, -2.0]",
                "tools[0].axis",
                20,
            ),
        ];
        for (from, to, key, line) in cases {
            let e = err(&GOOD.replace(from, to));
            assert!(e.contains(key) && e.contains(&format!(":{line}:")), "{e}");
        }
    }

    #[test]
    fn friction_laws_and_their_errors_name_key_and_line() {
        let with = |f: &str| {
            GOOD.replace(
                "motion = { kind = \"fixed\" }",
                &format!("motion = {{ kind = \"fixed\" }}\n{f}"),
            )
        };
        let s = Scene::from_str_named(&with("friction = 0.2"), "s.toml").unwrap();
        assert_eq!(s.tools[0].friction, Friction::Coulomb { mu: 0.2 });
        assert!(s.tools[0].separation);
        let s = Scene::from_str_named(
            &with("friction = { model = \"shear\", m = 0.3 }\nseparation = false"),
            "s.toml",
        )
        .unwrap();
        assert_eq!(s.tools[0].friction, Friction::Shear { m: 0.3 });
        assert!(!s.tools[0].separation);
        let e = err(&with("friction = { model = \"shear\", m = 1.5 }"));
        assert!(
            e.contains("tools[0].friction.m") && e.contains(":22:"),
            "{e}"
        );
        let e = err(&with(
            "friction = { model = \"capped\", mu = -0.1, m = 0.5 }",
        ));
        assert!(
            e.contains("tools[0].friction.mu") && e.contains(":22:"),
            "{e}"
        );
        let e = err(&with("friction = -0.1"));
        assert!(e.contains("tools[0].friction") && e.contains(":22:"), "{e}");
        let e = err(&with("friction = { model = \"sticky\", m = 0.5 }"));
        assert!(e.contains("line 22") && e.contains("sticky"), "{e}");
    }
}
