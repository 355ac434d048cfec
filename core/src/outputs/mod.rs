//! The register of outputs: every figure a run reports, listed once ([`REGISTER`]) with its
//! name, unit, description, kind and how it is read, so that every front end shows the same
//! figure under the same name.
//!
//! Names carry their unit as the scene keys do (`_N`, `_m`, `_J`, `_m_per_s`, `_Pa`, `_W`,
//! `_c` for degrees Celsius, `_rel` for ratios; none for strains, fractions and counts), and
//! [`Output::unit`] is the same unit as FMI's `unit` attribute writes it (`"1"`: a pure
//! number).
//!
//! An entry is expanded over a scene into [`Column`]s, one value each ([`columns`]), named
//! `<group>.<instance>.<name>`: the instance is the tool's name for an entry per tool,
//! `<tool>.<point>` per fill point, `face_<edge>` per followed face (`output.faces`), and
//! nothing for a scalar (`energy.kinetic_J`, `top.force_N`, `top.corner.filled`,
//! `workpiece.face_y_min.x_max_m`, `thermal.top.heat_flow_W`). The register is a list of
//! sections, each of entries of one kind, expanded instance by instance: one tool's columns
//! stand side by side. Entries per particle or per integration point are fields, read whole
//! ([`Output::field`]).
//!
//! Who reads it: `history.csv` (the columns [`Shown::history`], in register order),
//! `summary.json` (the columns [`Shown::summary`], at the path the column's name gives: the
//! groups as objects, per tool under `tools[k]`, per fill point under its
//! `tools[k].fill_points[i]`), the ROS node's and the recordings' `outputs` topic and
//! Python's `Simulation.outputs()` (every column and field). The FMU's output variables are
//! to be the columns [`Shown::fmu`], named and read as here; its table still lists its own
//! until it is generated from [`columns`].
//!
//! Every read goes through a [`Sample`] of the simulation: the public methods of
//! [`Simulation`], with the measures several outputs share (the workpiece's extents, the
//! penetration, the particle fields, the thermal measures) taken once.
//!
//! Adding an output is one entry in its section of `register.rs` plus its computation (a
//! public method of [`Simulation`] or a function here, as [`mean_contact_pressure`]).
//!
//! A 3D run has its own register ([`SOLID_REGISTER`], `solid.rs`) of the same types over a
//! [`SolidSimulation`] ([`solid_columns`], [`solid_fields`]): the sections both dimensions
//! read alike (the time, the energy account, the thermal measures) are one definition
//! generic over [`Body`], so a 3D run names and computes them as 2D does.

mod pressure;
mod register;
mod solid;

pub use pressure::{contact_area, mean_contact_pressure};
pub use register::{REGISTER, THERMAL_MEASURES};
pub use solid::{solid_columns, solid_fields, SolidCache, SOLID_REGISTER};

use crate::geometry::Extents;
use crate::math::Real;
use crate::scene::{Edge, Kinematics, Scene};
use crate::solver::{Depths, Energy, Fields, Filled, Simulation, SolidSimulation};
use crate::tools::Account;
use serde::{Deserialize, Serialize};
use std::cell::OnceCell;
use std::ops::Deref;

/// What the register reads of a simulation of either dimension ([`Simulation`],
/// [`SolidSimulation`]): the readings the shared sections take, and the measures a
/// [`Sample`] of it keeps once taken (`Cache`).
pub trait Body: Sized + 'static {
    /// The measures a sample takes once, when first read.
    type Cache: Default;
    /// Time (s).
    fn time_now(&self) -> Real;
    /// Length of the last step (s), 0 before the first.
    fn last_step(&self) -> Real;
    /// Energy account (J).
    fn energy_now(&self) -> Energy;
    /// Largest ratio of kinetic to internal energy since the quasi-static watch began (-).
    fn kinetic_to_internal_max(&self) -> Real;
    /// The thermal measures in the order of [`THERMAL_MEASURES`], `None` for an isothermal
    /// scene.
    fn thermal_now(&self) -> Option<[Real; 9]>;
    /// When each fill point was reached, tool by tool (the state's).
    fn fill_state(&self) -> &[Option<Filled>];
    /// What each tool received from the workpiece since the start, in scene order.
    fn tool_accounts(&self) -> Vec<Account>;
    /// The force of the workpiece on tool `k` along its axis over the last step (N).
    fn tool_axial_force(&self, k: usize) -> Real;
}

impl Body for Simulation {
    type Cache = PlaneCache;
    fn time_now(&self) -> Real {
        self.time()
    }
    fn last_step(&self) -> Real {
        self.state().dt_prev
    }
    fn energy_now(&self) -> Energy {
        self.energy()
    }
    fn kinetic_to_internal_max(&self) -> Real {
        self.kinetic_to_internal_max()
    }
    fn thermal_now(&self) -> Option<[Real; 9]> {
        self.thermal_values()
    }
    fn fill_state(&self) -> &[Option<Filled>] {
        &self.state().fill
    }
    fn tool_accounts(&self) -> Vec<Account> {
        self.tools().iter().map(|t| t.state.account).collect()
    }
    fn tool_axial_force(&self, k: usize) -> Real {
        self.tools()[k].axial_force()
    }
}

impl Body for SolidSimulation {
    type Cache = SolidCache;
    fn time_now(&self) -> Real {
        self.time()
    }
    fn last_step(&self) -> Real {
        self.state().dt_prev
    }
    fn energy_now(&self) -> Energy {
        self.energy()
    }
    fn kinetic_to_internal_max(&self) -> Real {
        self.kinetic_to_internal_max()
    }
    fn thermal_now(&self) -> Option<[Real; 9]> {
        self.thermal_values()
    }
    fn fill_state(&self) -> &[Option<Filled>] {
        &self.state().fill
    }
    fn tool_accounts(&self) -> Vec<Account> {
        self.tools().iter().map(|t| t.state.account).collect()
    }
    fn tool_axial_force(&self, k: usize) -> Real {
        self.tools()[k].axial_force()
    }
}

/// One output of the register, read from a simulation of type `S`.
#[derive(Debug)]
pub struct Output<S: Body = Simulation> {
    /// Name with its unit, without group or instance (`force_N`, `kinetic_J`).
    pub name: &'static str,
    /// Group the name begins with (`workpiece`, `energy`, `thermal`; empty for none).
    pub group: &'static str,
    /// Unit as FMI's `unit` attribute writes it (`N`, `m`, `m/s`, `J`, `Pa`, `degC`; `1`
    /// for a pure number).
    pub unit: &'static str,
    /// What it is, for people: `{tool}`, `{point}` and `{face}` stand for the instance.
    pub description: &'static str,
    /// The scenes (and, per tool, the tools) that have it.
    pub when: When,
    /// The front ends that show it beside those that show every output.
    pub shown: Shown,
    /// Whether it changes only in steps, a count or a flag (the FMU declares it `discrete`,
    /// the others `continuous`).
    pub discrete: bool,
    /// How it is read, which also gives its kind.
    pub read: Read<S>,
}

impl<S: Body> Clone for Output<S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: Body> Copy for Output<S> {}

/// What an output is given for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// One value.
    Scalar,
    /// One value per tool, in scene order.
    PerTool,
    /// One value per fill point of a tool, tool by tool in scene order.
    PerFillPoint,
    /// One value per followed face of the workpiece (`output.faces`).
    PerFace,
    /// A field: one value per particle.
    PerParticle,
    /// A field: one value per integration point.
    PerPoint,
}

/// How an output is read from a [`Sample`] of a simulation of type `S`.
#[derive(Debug)]
pub enum Read<S: Body = Simulation> {
    /// One value.
    Scalar(fn(&Sample<'_, S>) -> Real),
    /// The value for tool `k`.
    Tool(fn(&Sample<'_, S>, usize) -> Real),
    /// The value for fill point `i` of [`Simulation::fill_points`].
    FillPoint(fn(&Sample<'_, S>, usize) -> Real),
    /// The value for the face of the particles that started on an edge.
    Face(fn(&Sample<'_, S>, Edge) -> Real),
    /// One value per particle.
    Particles(fn(&Sample<'_, S>) -> Vec<Real>),
    /// One value per integration point.
    Points(fn(&Sample<'_, S>) -> Vec<Real>),
}

impl<S: Body> Clone for Read<S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S: Body> Copy for Read<S> {}

impl<S: Body> Read<S> {
    /// What the output is given for.
    pub fn kind(&self) -> Kind {
        match self {
            Read::Scalar(_) => Kind::Scalar,
            Read::Tool(_) => Kind::PerTool,
            Read::FillPoint(_) => Kind::PerFillPoint,
            Read::Face(_) => Kind::PerFace,
            Read::Particles(_) => Kind::PerParticle,
            Read::Points(_) => Kind::PerPoint,
        }
    }
}

/// The scenes that have an output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum When {
    /// Every scene.
    Always,
    /// Plane strain.
    PlaneStrain,
    /// Axisymmetry.
    Axisymmetric,
    /// A scene with `[thermal]`.
    Thermal,
    /// A scene with elasticity over temperature.
    Thermoelastic,
    /// Per tool: the tools of a scene with `[thermal]` with a heat transfer coefficient.
    HeatedTool,
}

impl When {
    /// Whether `scene` has the output at `at`.
    pub fn holds(self, scene: &Scene, at: At) -> bool {
        match self {
            When::Always => true,
            When::PlaneStrain => scene.model.kinematics == Kinematics::PlaneStrain,
            When::Axisymmetric => scene.model.kinematics == Kinematics::Axisymmetric,
            When::Thermal => scene.thermal.is_some(),
            When::Thermoelastic => scene
                .thermal
                .as_ref()
                .is_some_and(|t| t.thermoelastic().is_some()),
            When::HeatedTool => {
                scene.thermal.is_some()
                    && matches!(at, At::Tool(k) if scene.tools[k].heat_transfer_w_per_m2_k > 0.0)
            }
        }
    }
}

/// The front ends that show an output, beside the ROS node's `outputs` topic and Python's
/// `Simulation.outputs()`, which show every one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shown {
    /// A column of `history.csv`.
    pub history: bool,
    /// A value of `summary.json`, at the end of the run.
    pub summary: bool,
    /// An output variable of the FMU (FMI 2.0 and 3.0).
    pub fmu: bool,
}

impl Shown {
    /// In the history, the summary and the FMU.
    pub const EVERYWHERE: Shown = Shown {
        history: true,
        summary: true,
        fmu: true,
    };
    /// In the history and the FMU; the summary reports the run in its own way (a largest
    /// value, a vector, a list).
    pub const NOT_IN_SUMMARY: Shown = Shown {
        history: true,
        summary: false,
        fmu: true,
    };
    /// In the summary and the FMU, not as a history column.
    pub const NOT_IN_HISTORY: Shown = Shown {
        history: false,
        summary: true,
        fmu: true,
    };
    /// In the history and the summary; the FMU has the figure as an input of the same name
    /// (a tool's velocity, which an importer commands and reads back).
    pub const NOT_IN_FMU: Shown = Shown {
        history: true,
        summary: true,
        fmu: false,
    };
    /// In the history only (the time, which the FMU has as its own).
    pub const HISTORY_ONLY: Shown = Shown {
        history: true,
        summary: false,
        fmu: false,
    };
    /// In none of them: a field, read whole.
    pub const FIELD: Shown = Shown {
        history: false,
        summary: false,
        fmu: false,
    };
}

/// Which instance of an output a column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum At {
    /// The one value of a scalar.
    Whole,
    /// Tool `k`.
    Tool(usize),
    /// A fill point: its tool, its index in [`Simulation::fill_points`] and among its
    /// tool's points.
    FillPoint {
        /// The tool.
        tool: usize,
        /// Index over every tool's points.
        index: usize,
        /// Index among the tool's own points.
        within: usize,
    },
    /// A followed face.
    Face(Edge),
}

/// One value of an output in a scene: the output at one instance, with its name.
#[derive(Debug)]
pub struct Column<S: Body = Simulation> {
    /// The register's entry.
    pub output: &'static Output<S>,
    /// The instance.
    pub at: At,
    /// `<group>.<instance>.<name>`.
    pub name: String,
}

impl<S: Body> Clone for Column<S> {
    fn clone(&self) -> Self {
        Column {
            output: self.output,
            at: self.at,
            name: self.name.clone(),
        }
    }
}

impl<S: Body> Column<S> {
    /// The value now.
    pub fn value(&self, sample: &Sample<'_, S>) -> Real {
        match (self.output.read, self.at) {
            (Read::Scalar(f), At::Whole) => f(sample),
            (Read::Tool(f), At::Tool(k)) => f(sample, k),
            (Read::FillPoint(f), At::FillPoint { index, .. }) => f(sample, index),
            (Read::Face(f), At::Face(e)) => f(sample, e),
            (read, at) => unreachable!("`columns` gives {:?} no instance {at:?}", read.kind()),
        }
    }

    /// The unit, as FMI's `unit` attribute writes it (`1`: a pure number).
    pub fn unit(&self) -> &'static str {
        self.output.unit
    }
}

impl Column {
    /// The description with the tool's, point's or face's name put in.
    pub fn description(&self, scene: &Scene) -> String {
        let d = self.output.description;
        match self.at {
            At::Whole => d.to_string(),
            At::Tool(k) => d.replace("{tool}", &scene.tools[k].name),
            At::FillPoint { tool, within, .. } => {
                let t = &scene.tools[tool];
                d.replace("{tool}", &t.name)
                    .replace("{point}", &t.fill_points[within].name)
            }
            At::Face(e) => d.replace("{face}", e.name()),
        }
    }
}

/// Every column of `scene`: the scalar entries present in it, section by section in register
/// order, each section instance by instance.
pub fn columns(scene: &Scene) -> Vec<Column> {
    expand(
        &REGISTER,
        |kind| instances(scene, kind),
        |when, at| when.holds(scene, at),
    )
}

/// The columns of `register`: each section's entries that `holds` (when, instance) keeps,
/// section by section, each section instance by instance (`instances` of its kind).
fn expand<S: Body>(
    register: &'static [&'static [Output<S>]],
    instances: impl Fn(Kind) -> Vec<(At, String)>,
    holds: impl Fn(When, At) -> bool,
) -> Vec<Column<S>> {
    let mut out = Vec::new();
    for section in register {
        let Some(first) = section.first() else {
            continue;
        };
        for (at, instance) in instances(first.read.kind()) {
            for output in section.iter().filter(|o| holds(o.when, at)) {
                let name = [output.group, &instance, output.name]
                    .into_iter()
                    .filter(|s| !s.is_empty())
                    .collect::<Vec<_>>()
                    .join(".");
                out.push(Column { output, at, name });
            }
        }
    }
    out
}

/// The instances of a kind in `scene`, with their names; none for a field.
fn instances(scene: &Scene, kind: Kind) -> Vec<(At, String)> {
    match kind {
        Kind::Scalar => vec![(At::Whole, String::new())],
        Kind::PerTool => (0..scene.tools.len())
            .map(|k| (At::Tool(k), scene.tools[k].name.clone()))
            .collect(),
        Kind::PerFillPoint => fill_instances(
            scene
                .tools
                .iter()
                .map(|t| (&t.name[..], t.fill_points.iter().map(|p| &p.name[..]))),
        ),
        Kind::PerFace => scene
            .output
            .faces
            .iter()
            .map(|&e| (At::Face(e), format!("face_{}", e.name())))
            .collect(),
        Kind::PerParticle | Kind::PerPoint => Vec::new(),
    }
}

/// The fill points of either dimension's tools, given as (tool name, its points' names) in
/// scene order, as instances `<tool>.<point>`.
fn fill_instances<'a, P: Iterator<Item = &'a str>>(
    tools: impl Iterator<Item = (&'a str, P)>,
) -> Vec<(At, String)> {
    tools
        .enumerate()
        .flat_map(|(tool, (t, points))| {
            points
                .enumerate()
                .map(move |(within, p)| (tool, within, format!("{t}.{p}")))
        })
        .enumerate()
        .map(|(index, (tool, within, name))| {
            (
                At::FillPoint {
                    tool,
                    index,
                    within,
                },
                name,
            )
        })
        .collect()
}

impl<S: Body> Output<S> {
    /// The field's values now (per particle or per integration point), `None` for an
    /// output of another kind.
    pub fn field(&self, sample: &Sample<'_, S>) -> Option<Vec<Real>> {
        match self.read {
            Read::Particles(f) | Read::Points(f) => Some(f(sample)),
            _ => None,
        }
    }

    /// `<group>.<name>`, the name of a field.
    pub fn full_name(&self) -> String {
        match self.group {
            "" => self.name.to_string(),
            g => format!("{g}.{}", self.name),
        }
    }
}

/// Every field present in `scene` (outputs per particle or per integration point), in
/// register order.
pub fn fields(scene: &Scene) -> impl Iterator<Item = &'static Output> + '_ {
    fields_of(&REGISTER, move |when| when.holds(scene, At::Whole))
}

/// The fields of `register` that `holds` keeps, in register order.
fn fields_of<S: Body>(
    register: &'static [&'static [Output<S>]],
    holds: impl Fn(When) -> bool,
) -> impl Iterator<Item = &'static Output<S>> {
    register.iter().flat_map(|s| s.iter()).filter(move |o| {
        matches!(o.read.kind(), Kind::PerParticle | Kind::PerPoint) && holds(o.when)
    })
}

/// How deep the workpiece lay at a sample (m) in the tools, beyond the symmetry planes and
/// inside itself, and how often its boundary crossed itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Penetration {
    /// Deepest particle inside a tool (m).
    pub tools_m: Real,
    /// Deepest particle beyond a symmetry plane or the axis (m).
    pub planes_m: Real,
    /// Deepest surface particle inside another part of the workpiece (m).
    pub itself_m: Real,
    /// Crossings of the boundary ring's segments.
    pub crossings: Real,
}

impl Penetration {
    /// The depths of a measure.
    pub fn of(d: &Depths) -> Penetration {
        Penetration {
            tools_m: d.tools.depth,
            planes_m: d.planes.depth,
            itself_m: d.itself.depth,
            crossings: d.crossings as Real,
        }
    }

    /// The run's largest so far, what a sample whose measure failed (a particle past the
    /// scene's bound) records.
    pub fn largest(sim: &Simulation) -> Penetration {
        Penetration {
            tools_m: sim.max_penetration(),
            planes_m: sim.max_beyond_symmetry(),
            itself_m: sim.max_inside_itself(),
            crossings: sim.max_boundary_crossings() as Real,
        }
    }
}

/// A simulation at one instant as the outputs read it (it dereferences to the simulation,
/// a [`Simulation`] or a [`SolidSimulation`]): the measures that several outputs share are
/// taken once, when first read (`S::Cache`).
pub struct Sample<'a, S: Body = Simulation> {
    sim: &'a S,
    cache: S::Cache,
    thermal: OnceCell<Option<[Real; 9]>>,
    since: Option<Since>,
}

/// The sample before, as an interval mean reads it ([`force_mean`]): its time and each
/// tool's impulse. Each front end keeps its own: `history.csv` its last row, the FMU the
/// start of its communication step, the ROS node and `rkforge run --mcap` their last
/// sample, Python its last `sample()`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Since {
    /// Time of the sample (s).
    pub time: Real,
    /// Each tool's impulse along its axis at the sample (N s, [`Account::impulse`]).
    pub impulse: Vec<Real>,
}

impl Since {
    /// The simulation now, as the next sample's interval means start from it.
    pub fn of<S: Body>(sim: &S) -> Since {
        Since {
            time: sim.time_now(),
            impulse: sim.tool_accounts().iter().map(|a| a.impulse).collect(),
        }
    }
}

/// The force of the workpiece on tool `k` along its axis averaged over the interval since
/// the sample before ([`Sample::since`]; the start of the run when none was given):
/// `(I - I_0) / (t - t_0)` (N), `I` the tool's impulse ([`Account::impulse`]) and `t` the
/// time, now and at that sample. It is what the tool's momentum took over the interval, so
/// a sample that falls on a shortened step or on one peak of the impact's ringing reads the
/// interval's force; over a zero interval, the force of the last step.
pub fn force_mean<S: Body>(s: &Sample<'_, S>, k: usize) -> Real {
    let (t, impulse) = (s.time_now(), s.tool_accounts()[k].impulse);
    let (t0, i0) = s
        .since
        .as_ref()
        .map_or((0.0, 0.0), |p| (p.time, p.impulse[k]));
    if t > t0 {
        (impulse - i0) / (t - t0)
    } else {
        s.tool_axial_force(k)
    }
}

/// The measures a sample of a 2D simulation takes once.
#[derive(Default)]
pub struct PlaneCache {
    positions: OnceCell<Vec<[Real; 2]>>,
    extents: OnceCell<Extents>,
    penetration: OnceCell<Penetration>,
    fields: OnceCell<Fields>,
}

impl<'a, S: Body> Sample<'a, S> {
    /// The simulation now.
    pub fn new(sim: &'a S) -> Sample<'a, S> {
        Sample {
            sim,
            cache: S::Cache::default(),
            thermal: OnceCell::new(),
            since: None,
        }
    }

    /// The same sample, its interval means taken since `since` (none: since the start).
    pub fn since(mut self, since: Option<&Since>) -> Sample<'a, S> {
        self.since = since.cloned();
        self
    }

    /// The thermal measures ([`Body::thermal_now`]).
    pub fn thermal_values(&self) -> Option<[Real; 9]> {
        *self.thermal.get_or_init(|| self.sim.thermal_now())
    }
}

impl<'a> Sample<'a> {
    /// The simulation now with what [`Simulation::measure_sample`] measured: the particles'
    /// physical `positions` (m) and the penetration `p`.
    pub fn measured(sim: &'a Simulation, positions: Vec<[Real; 2]>, p: Penetration) -> Sample<'a> {
        let sample = Sample::new(sim);
        sample.cache.positions.get_or_init(|| positions);
        sample.cache.penetration.get_or_init(|| p);
        sample
    }

    /// The particles' physical positions (m, [`Simulation::positions`]), formed when first
    /// read.
    pub fn positions(&self) -> &[[Real; 2]] {
        self.cache.positions.get_or_init(|| self.sim.positions())
    }

    /// Bounds of the deformed workpiece over all particles (m), [`Simulation::extents`].
    pub fn extents(&self) -> Extents {
        *self
            .cache
            .extents
            .get_or_init(|| crate::geometry::bounds(self.positions()))
    }

    /// The penetration now ([`Simulation::penetration`], measured when first read).
    pub fn penetration(&self) -> Penetration {
        *self
            .cache
            .penetration
            .get_or_init(|| Penetration::of(&self.sim.penetration_at(self.positions())))
    }

    /// The particle fields, [`Simulation::fields`].
    pub fn particle_fields(&self) -> &Fields {
        self.cache.fields.get_or_init(|| self.sim.fields())
    }

    /// The smallest particle spacing (m), the scale of the `_rel` depths.
    pub fn min_spacing(&self) -> Real {
        let h = self.sim.spacing();
        h[0].min(h[1])
    }
}

impl<S: Body> Deref for Sample<'_, S> {
    type Target = S;

    fn deref(&self) -> &S {
        self.sim
    }
}

#[cfg(test)]
mod tests;
