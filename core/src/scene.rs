//! Scene files: the one place that decides what is modelled (TOML, SI units).
//!
//! A scene gives the workpiece (a particle grid over a rectangle, plane strain or
//! axisymmetric), its material, the discretisation knobs, the rigid tools and how they move,
//! essential conditions, the time span and what to record. Every syntax error, missing,
//! unknown or mistyped key and every non-physical value is reported with the key and its
//! line; nothing here panics on user input.

use crate::error::{Error, Result};
pub use crate::friction::Friction;
use crate::material::Hardening;
use crate::math::Real;
use crate::scene_keys::{key_line, syntax_message};
use crate::thermal::properties::interpolate;
pub use crate::thermal::ThermalSpec;
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

/// Plane strain (x, y) or axisymmetric (r, z) kinematics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Kinematics {
    /// Plane strain in (x, y); forces per `depth_m` of depth.
    PlaneStrain,
    /// Axisymmetric about x = r = 0 in (r, z); forces are for the whole ring.
    Axisymmetric,
}

/// The kinematic model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Model {
    /// `plane_strain` or `axisymmetric`.
    pub kinematics: Kinematics,
    /// Out-of-plane depth (m) for plane strain; forces and masses are per this depth.
    #[serde(default = "one")]
    pub depth_m: Real,
}

fn one() -> Real {
    1.0
}

/// A rectangular workpiece filled with a regular grid of particles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Workpiece {
    /// Lower-left corner (m).
    pub origin_m: [Real; 2],
    /// Width and height (m).
    pub size_m: [Real; 2],
    /// Particles along x and y (each at least 2).
    pub particles: [usize; 2],
    /// Uniform initial velocity (m/s).
    #[serde(default)]
    pub initial_velocity_m_per_s: [Real; 2],
}

/// Material constants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Mass density (kg/m^3).
    pub density_kg_per_m3: Real,
    /// Young's modulus (Pa).
    pub youngs_modulus_pa: Real,
    /// Poisson's ratio (-), in (-1, 0.5).
    pub poisson_ratio: Real,
    /// Isotropic hardening law (`law = "linear"`, `"power"`; with `[thermal]` also
    /// `"johnson_cook"`, `"hensel_spittel"`, `"sellars_tegart"`, `"table"`).
    pub hardening: Hardening,
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
}

/// Background-cell integration rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum IntegrationRule {
    /// 2x2 Gauss rule per cell.
    Q4,
    /// The paper's two-point rule: points at +-(1/sqrt3, 1/sqrt3) on a cell diagonal, weight 2.
    #[default]
    Q2,
    /// Stabilized conforming nodal integration (Chen, Wu, Yoon, You 2001): one point per
    /// particle, gradients smoothed over the particle's domain.
    Scni,
}

impl IntegrationRule {
    /// The scene/CLI name.
    pub fn name(self) -> &'static str {
        match self {
            IntegrationRule::Q4 => "q4",
            IntegrationRule::Q2 => "q2",
            IntegrationRule::Scni => "scni",
        }
    }
    /// Parse a scene/CLI name.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "q4" => Some(IntegrationRule::Q4),
            "q2" => Some(IntegrationRule::Q2),
            "scni" => Some(IntegrationRule::Scni),
            _ => None,
        }
    }
}

/// Discretisation knobs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Discretization {
    /// Integration rule: `q4` (2x2 Gauss per cell), `q2` (the paper's two-point rule) or
    /// `scni` (stabilized conforming nodal integration).
    #[serde(default)]
    pub integration: IntegrationRule,
    /// Kernel support radius per direction, in particle spacings (-).
    #[serde(default = "default_support")]
    pub support: [Real; 2],
    /// Re-reference the kernel when an integration point's largest principal in-plane
    /// stretch since the last reference reaches this value (-): the shape functions are
    /// rebuilt on the current configuration and the state carried over
    /// ([`crate::solver`]'s `rereference.rs`). Absent: the Lagrangian kernel throughout.
    #[serde(default)]
    pub rereference_stretch: Option<Real>,
    /// With `integration = "scni"`: the coefficient `c` (-) of the stabilization of nodal
    /// integration (Puso, Chen, Zywicz, Elmer 2008's MSCNI; [`crate::solver`]'s
    /// `nodal_stabilization.rs`), a stiffness `c mu` against the variation of the
    /// displacement gradient over the quadrants of each nodal domain, which holds the
    /// saw-tooth SCNI leaves free on a surface. Absent or 0: plain SCNI.
    #[serde(default)]
    pub scni_stabilization: Option<Real>,
}

fn default_support() -> [Real; 2] {
    [2.0, 2.0]
}

impl Default for Discretization {
    fn default() -> Self {
        Discretization {
            integration: IntegrationRule::default(),
            support: default_support(),
            rereference_stretch: None,
            scni_stabilization: None,
        }
    }
}

/// Time span and step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// End time (s).
    pub end_s: Real,
    /// Fixed step (s); when absent, `dt_safety` times the stable step, updated every step.
    #[serde(default)]
    pub dt_s: Option<Real>,
    /// Fraction of the stable step used when `dt_s` is absent (-), in (0, 1].
    #[serde(default = "default_safety")]
    pub dt_safety: Real,
    /// Added mass that lengthens the explicit step; none when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass_scaling: Option<MassScaling>,
}

/// Mass scaling: mass added to the particles so that the explicit step, bounded by the
/// wave speed `sqrt((K + 4G/3) / rho)`, grows (the critical step grows with the square root
/// of the mass). For rate-independent forming, where inertia is negligible, a factor `f^2`
/// on the mass has the effect of running the tools `f` times faster; the run watches that
/// inertia stays negligible (`checks.kinetic_to_internal_max`). One of the two keys.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MassScaling {
    /// Uniform: every particle's mass times `factor` (-), at least 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub factor: Option<Real>,
    /// Selective (as LS-DYNA's DT2MS): mass is added only to the particles whose local
    /// step is below what it takes for the run's step, `dt_safety` times the critical
    /// step of the undeformed discretisation, to reach `target_dt_s` (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_dt_s: Option<Real>,
}

fn default_safety() -> Real {
    0.5
}

/// A workpiece edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Edge {
    /// Particles with the smallest x.
    XMin,
    /// Particles with the largest x.
    XMax,
    /// Particles with the smallest y.
    YMin,
    /// Particles with the largest y.
    YMax,
}

impl Edge {
    /// The edge's name in scene files and outputs (`x_min`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Edge::XMin => "x_min",
            Edge::XMax => "x_max",
            Edge::YMin => "y_min",
            Edge::YMax => "y_max",
        }
    }

    /// The particles on this edge of an `nx` x `ny` grid numbered row by row.
    pub fn particles(self, nx: usize, ny: usize) -> Vec<u32> {
        let id = |i: usize, j: usize| (j * nx + i) as u32;
        match self {
            Edge::XMin => (0..ny).map(|j| id(0, j)).collect(),
            Edge::XMax => (0..ny).map(|j| id(nx - 1, j)).collect(),
            Edge::YMin => (0..nx).map(|i| id(i, 0)).collect(),
            Edge::YMax => (0..nx).map(|i| id(i, ny - 1)).collect(),
        }
    }
}

/// A displacement component.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Component {
    /// x (or r).
    X,
    /// y (or z).
    Y,
}

/// The physical displacement component `fix` of the particles on `edge` stays zero
/// (a symmetry plane). The axis r = 0 of an axisymmetric workpiece is added automatically.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConstraintSpec {
    /// Which edge.
    pub edge: Edge,
    /// Which components are held.
    pub fix: Vec<Component>,
}

/// Contact of the workpiece's surface with itself: where the surface folds, its parts press
/// on each other instead of passing through, and a fold between surface points that were
/// apart along the surface is reported as a lap ([`crate::contact::self_contact`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SelfContactSpec {
    /// Whether the surface holds against itself (the default). `false` saves the search
    /// where a scene cannot fold, and lets a fold pass through itself unreported.
    #[serde(default = "default_true")]
    pub enabled: bool,
    /// Friction law between the surface's parts, as a tool's ([`Friction`]): a number is a
    /// Coulomb coefficient, a table names the model; default frictionless.
    #[serde(default)]
    pub friction: Friction,
}

fn default_true() -> bool {
    true
}

impl Default for SelfContactSpec {
    fn default() -> Self {
        SelfContactSpec {
            enabled: true,
            friction: Friction::default(),
        }
    }
}

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
    /// Whether heat crosses the contact with this tool: a transfer coefficient, constant or
    /// over pressure.
    pub fn transfers_heat(&self) -> bool {
        self.heat_transfer_w_per_m2_k > 0.0 || !self.heat_transfer_by_pressure.is_empty()
    }

    /// The transfer coefficient (W/(m^2 K)) at contact pressure `p` (Pa).
    pub fn heat_transfer_at(&self, p: Real) -> Real {
        if self.heat_transfer_by_pressure.is_empty() {
            self.heat_transfer_w_per_m2_k
        } else {
            interpolate(&self.heat_transfer_by_pressure, p)
        }
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

/// What is recorded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Interval between rows of the time history (s); default: end time / 200
    /// ([`Scene::history_interval`]).
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

fn default_fill_distance() -> Real {
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

/// Run-time checks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Checks {
    /// Largest energy balance error, relative to the reference energy, before the run stops.
    #[serde(default = "default_energy_tol")]
    pub energy_balance_tol: Real,
    /// Largest ratio of the workpiece's kinetic to internal energy (-) after the start-up
    /// (`kinetic_to_internal_from`) before the run stops: the quasi-static assumption
    /// that mass scaling rests on. Absent: the ratio is reported (and a mass-scaled run
    /// warns above 5 %) but never stops the run.
    #[serde(default)]
    pub kinetic_to_internal_max: Option<Real>,
    /// Start of the kinetic-to-internal watch (-), in [0, 1): this fraction of the time from
    /// the first contact (t = 0 for a workpiece without tools) to `time.end_s`. The first
    /// contact accelerates the touched layer to the tool speed while the internal energy is
    /// still small (the ratio is 0.26 at 1 % of the shipped block forging's stroke and below
    /// 0.02 from 10 % on).
    #[serde(default = "default_watch_from")]
    pub kinetic_to_internal_from: Real,
    /// Deepest a particle may lie inside a tool, in smallest particle spacings (-), before
    /// the run stops with the step, time, particle, tool and depth named. The penalty's own
    /// penetration under forging pressures is a few thousandths of a spacing
    /// (`g = p h dt^2 / (m_J / h)`, about `0.8 h p / (K + 4G/3)`), so 0.1 only trips when
    /// the contact lets material through.
    #[serde(default = "default_max_penetration")]
    pub max_penetration_rel: Real,
}

fn default_max_penetration() -> Real {
    0.1
}

fn default_watch_from() -> Real {
    0.1
}

fn default_energy_tol() -> Real {
    0.05
}

impl Default for Checks {
    fn default() -> Self {
        Checks {
            energy_balance_tol: default_energy_tol(),
            kinetic_to_internal_max: None,
            kinetic_to_internal_from: default_watch_from(),
            max_penetration_rel: default_max_penetration(),
        }
    }
}

/// A published result to compare with: `values` maps summary keys to numbers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Reference {
    /// Where the numbers come from.
    pub source: String,
    /// The integration rule this reference corresponds to, if any.
    #[serde(default)]
    pub integration: Option<IntegrationRule>,
    /// Summary key -> value, e.g. `"workpiece.radius_m" = 7.11e-3`.
    pub values: std::collections::BTreeMap<String, Real>,
}

impl Scene {
    /// Read and validate a scene from a file.
    pub fn from_file(path: &std::path::Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::SceneSyntax {
            file: path.display().to_string(),
            message: format!("cannot read: {e}"),
        })?;
        Scene::from_str_named(&text, &path.display().to_string())
    }

    /// Parse and validate scene text; `file` names it in error messages.
    pub fn from_str_named(text: &str, file: &str) -> Result<Scene> {
        let scene: Scene = toml::from_str(text).map_err(|e| Error::SceneSyntax {
            file: file.to_string(),
            message: syntax_message(text, &e),
        })?;
        if let Some((key, message)) = scene.validate().into_iter().next() {
            return Err(Error::SceneValue {
                file: file.to_string(),
                line: key_line(text, &key).unwrap_or(0),
                key,
                message,
            });
        }
        Ok(scene)
    }

    /// Deserialise a scene from a TOML document (not yet validated); the error is toml's
    /// message.
    pub(crate) fn deserialize_table(doc: toml::Table) -> std::result::Result<Scene, String> {
        Scene::deserialize(toml::Value::Table(doc)).map_err(|e| e.message().trim().to_string())
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
