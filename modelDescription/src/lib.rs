//! The FMU's variable table, derived from a scene.
//!
//! The inputs are named after the scene's tools, `<tool>.velocity_m_per_s` (for every tool
//! that is not fixed); the outputs are the register's ([`rkforge_core::outputs::REGISTER`],
//! the columns it shows in the FMU, [`fmu_columns`]) under the names `history.csv` gives
//! them, the unit in the name and in the `unit` attribute (`<tool>.force_N`,
//! `workpiece.height_m`, `energy.kinetic_J`); the parameters are the scene's own keys under
//! their dotted names (`discretization.integration`, `workpiece.particles[0]`,
//! `tools.top.friction`), as the scene's schema lists them
//! ([`rkforge_core::scene_parameters`]). Value references are assigned in table order, so
//! the same scene always gives the same table. The same table drives `modelDescription.xml`
//! and the FMU's getters and setters, so the two cannot drift.

mod document;
pub mod press;
pub mod xml;
pub mod xml3;

use rkforge_core::outputs::{columns, solid_columns, Body, Column};
use rkforge_core::scene::{Motion, Scene, SolidScene};
use rkforge_core::scene_parameters::{parameters, Parameter, ParameterKind};
use rkforge_core::solver::SolidSimulation;
use rkforge_core::Simulation;

/// A scene an FMU is made of: a 2D [`Scene`] or a 3D [`SolidScene`], what the table reads
/// of either kind.
pub trait FmuScene {
    /// The simulation whose register the outputs read.
    type Body: Body;
    /// Each tool's name and motion, in scene order (the tools' index `k`).
    fn tool_motions(&self) -> Vec<(&str, &Motion)>;
    /// Every column of the scene's register.
    fn register(&self) -> Vec<Column<Self::Body>>;
    /// A column's description with its tool's or face's name put in.
    fn describe(&self, column: &Column<Self::Body>) -> String;
    /// The scene's tunable keys ([`rkforge_core::scene_parameters::parameters`]).
    fn tunable(&self) -> Vec<Parameter>;
    /// The stations of the contact-pressure arrays (FMI 3.0), if the scene asks for them.
    fn pressure_stations(&self) -> Option<usize>;
}

impl FmuScene for Scene {
    type Body = Simulation;
    fn tool_motions(&self) -> Vec<(&str, &Motion)> {
        self.tools
            .iter()
            .map(|t| (t.name.as_str(), &t.motion))
            .collect()
    }
    fn register(&self) -> Vec<Column> {
        columns(self)
    }
    fn describe(&self, column: &Column) -> String {
        column.description(self)
    }
    fn tunable(&self) -> Vec<Parameter> {
        parameters(self)
    }
    fn pressure_stations(&self) -> Option<usize> {
        self.output.pressure_stations
    }
}

impl FmuScene for SolidScene {
    type Body = SolidSimulation;
    fn tool_motions(&self) -> Vec<(&str, &Motion)> {
        self.tools
            .iter()
            .map(|t| (t.name.as_str(), &t.motion))
            .collect()
    }
    fn register(&self) -> Vec<Column<SolidSimulation>> {
        solid_columns(self)
    }
    fn describe(&self, column: &Column<SolidSimulation>) -> String {
        column.description(self)
    }
    fn tunable(&self) -> Vec<Parameter> {
        parameters(self)
    }
    /// A 3D scene has no contact-pressure arrays.
    fn pressure_stations(&self) -> Option<usize> {
        None
    }
}

/// FMI 2.0 causality.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// Set before initialisation.
    Parameter,
    /// Set by the master during simulation.
    Input,
    /// Read by the master.
    Output,
}

/// FMI 2.0 variability.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variability {
    /// Fixed after initialisation.
    Fixed,
    /// Changes continuously in time.
    Continuous,
    /// Changes only in steps (a count or a flag).
    Discrete,
}

/// FMI 2.0 base type with the start value.
#[derive(Debug, Clone, PartialEq)]
pub enum Kind {
    /// `Real` with an optional start value.
    Real(Option<f64>),
    /// `Integer` with an optional start value.
    Integer(Option<i32>),
    /// `String` with an optional start value.
    String(Option<String>),
    /// `Boolean` with an optional start value (FMI 3.0 only: the early-return switches).
    Boolean(Option<bool>),
    /// A `Float64` array of this many values, no start (FMI 3.0 only: the contact
    /// pressure along a tool).
    RealArray(usize),
}

/// What a variable reads or writes in the simulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Binding {
    /// Velocity along the axis of tool `k` (m/s).
    ToolVelocity(usize),
    /// Column `k` of [`fmu_columns`]: an output of the register.
    Output(usize),
    /// Parameter `k` of the scene ([`rkforge_core::scene_parameters::parameters`]): a
    /// scene key under its dotted name.
    Parameter(usize),
    /// FMI 3.0: the contact pressure at tool `k`'s stations (Pa), an array.
    ContactPressure(usize),
    /// Variable `k` of a press plant's own table (`fmu/src/press.rs`).
    Press(usize),
    /// FMI 3.0: return early from a step when tool `k` comes to touch the workpiece (each
    /// time, after it lost contact).
    ReturnOnContact(usize),
    /// FMI 3.0: return early from a step when the force on tool `k` rises to its level (each
    /// time, after it fell below).
    ReturnOnForce(usize),
    /// FMI 3.0: the force level of [`Binding::ReturnOnForce`] (N, magnitude).
    ReturnForceLevel(usize),
}

/// One row of the table.
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Name, unique in the table.
    pub name: String,
    /// Value reference, unique per base type.
    pub value_reference: u32,
    /// Causality.
    pub causality: Causality,
    /// Variability.
    pub variability: Variability,
    /// Base type and start value.
    pub kind: Kind,
    /// SI unit, if any.
    pub unit: Option<&'static str>,
    /// Human description.
    pub description: String,
    /// What it maps to.
    pub binding: Binding,
}

impl Variable {
    /// The start value as text (empty when there is none).
    pub fn start_text(&self) -> String {
        match &self.kind {
            Kind::Real(s) => s.map_or(String::new(), |x| x.to_string()),
            Kind::Integer(s) => s.map_or(String::new(), |x| x.to_string()),
            Kind::String(s) => s.clone().unwrap_or_default(),
            Kind::Boolean(s) => s.map_or(String::new(), |x| x.to_string()),
            Kind::RealArray(_) => String::new(),
        }
    }
}

/// The variable table of a scene, 2D or 3D.
pub fn variable_table<S: FmuScene>(scene: &S) -> Vec<Variable> {
    let columns = fmu_columns(scene);
    let mut t = Vec::new();
    let mut push =
        |name: String, causality, variability, kind, unit, description: String, binding| {
            let value_reference = t.len() as u32;
            t.push(Variable {
                name,
                value_reference,
                causality,
                variability,
                kind,
                unit,
                description,
                binding,
            });
        };
    use Causality::*;
    use Variability::*;
    for (k, (name, motion)) in scene.tool_motions().into_iter().enumerate() {
        let start = match motion {
            Motion::Fixed => None,
            Motion::Constant { velocity_m_per_s } => Some(*velocity_m_per_s),
            Motion::Table { points } => Some(points[0][1]),
            Motion::External {
                initial_velocity_m_per_s,
            } => Some(*initial_velocity_m_per_s),
        };
        if let Some(v) = start {
            push(
                format!("{name}.velocity_m_per_s"),
                Input,
                Continuous,
                Kind::Real(Some(v)),
                Some("m/s"),
                format!("velocity of tool {name} along its axis"),
                Binding::ToolVelocity(k),
            );
        }
    }
    for (k, c) in columns.iter().enumerate() {
        push(
            c.name.clone(),
            Output,
            if c.output.discrete {
                Discrete
            } else {
                Continuous
            },
            Kind::Real(None),
            (c.unit() != "1").then(|| c.unit()),
            scene.describe(c),
            Binding::Output(k),
        );
    }
    for (k, p) in scene.tunable().into_iter().enumerate() {
        // A key an output is named after (a 3D cylinder's `workpiece.radius_m`, the
        // output being the bar's radius now) is no parameter: names are unique.
        if writes_files_only(&p.key) || columns.iter().any(|c| c.name == p.key) {
            continue;
        }
        let kind = match (&p.kind, &p.start) {
            (ParameterKind::Integer, toml::Value::Integer(i)) => {
                Kind::Integer(i32::try_from(*i).ok())
            }
            (ParameterKind::Enumeration(_), toml::Value::String(s)) => {
                Kind::String(Some(s.clone()))
            }
            (_, v) => Kind::Real(v.as_float()),
        };
        let description = match &p.kind {
            ParameterKind::Enumeration(names) => {
                format!("{} (one of: {})", p.description, names.join(", "))
            }
            _ => p.description,
        };
        push(
            p.key,
            Parameter,
            Fixed,
            kind,
            p.unit,
            description,
            Binding::Parameter(k),
        );
    }
    t
}

/// The register's columns of `scene` that the FMU shows ([`rkforge_core::outputs::Shown::fmu`]),
/// in register order: what [`Binding::Output`] indexes.
pub fn fmu_columns<S: FmuScene>(scene: &S) -> Vec<Column<S::Body>> {
    scene
        .register()
        .into_iter()
        .filter(|c| c.output.shown.fmu)
        .collect()
}

/// Value reference of FMI 3.0's independent variable `time`: the one after the 2.0 table's.
pub fn time_value_reference<S: FmuScene>(scene: &S) -> u32 {
    variable_table(scene).len() as u32
}

/// The FMI 3.0 table: the 2.0 table (same value references), then, after `time`, per tool
/// the early-return events of `fmi3DoStep` as parameters: `<tool>.early_return.contact`
/// (Boolean), `<tool>.early_return.force` (Boolean) and `<tool>.early_return.force_level`
/// (N); with `output.pressure_stations` (2D), per tool the array output
/// `<tool>.contact_pressure` (Pa, one value per station).
pub fn variable_table3<S: FmuScene>(scene: &S) -> Vec<Variable> {
    let mut t = variable_table(scene);
    let mut vr = time_value_reference(scene);
    let tools = scene.tool_motions();
    for (k, (name, _)) in tools.iter().enumerate() {
        let rows = [
            (
                "contact",
                Kind::Boolean(Some(false)),
                None,
                format!("return early from a step at the solver step where tool {name} comes to touch the workpiece, each time after it lost contact (when the importer allows early return)"),
                Binding::ReturnOnContact(k),
            ),
            (
                "force",
                Kind::Boolean(Some(false)),
                None,
                format!("return early from a step at the solver step where the magnitude of the force on tool {name} rises to {name}.early_return.force_level, each time after it fell below"),
                Binding::ReturnOnForce(k),
            ),
            (
                "force_level",
                Kind::Real(Some(0.0)),
                Some("N"),
                format!("force level of {name}.early_return.force (magnitude of the force along the axis)"),
                Binding::ReturnForceLevel(k),
            ),
        ];
        for (what, kind, unit, description, binding) in rows {
            vr += 1;
            t.push(Variable {
                name: format!("{name}.early_return.{what}"),
                value_reference: vr,
                causality: Causality::Parameter,
                variability: Variability::Fixed,
                kind,
                unit,
                description,
                binding,
            });
        }
    }
    if let Some(n) = scene.pressure_stations() {
        for (k, (name, _)) in tools.iter().enumerate() {
            vr += 1;
            t.push(Variable {
                name: format!("{name}.contact_pressure_Pa"),
                value_reference: vr,
                causality: Causality::Output,
                variability: Variability::Continuous,
                kind: Kind::RealArray(n),
                unit: Some("Pa"),
                description: format!(
                    "contact pressure along tool {name}: its polyline in {n} stations of equal length from its first point, the normal contact force on each over its area"
                ),
                binding: Binding::ContactPressure(k),
            });
        }
    }
    t
}

/// Keys that only shape the files `rkforge run` writes (frames, the history's rows and
/// faces), which an FMU does not write: no parameters. `output.fill_distance_rel` decides
/// the fill outputs and stays one.
fn writes_files_only(key: &str) -> bool {
    key.starts_with("output.") && key != "output.fill_distance_rel"
}

#[cfg(test)]
mod tests {
    use super::*;
    use rkforge_core::scene::solid::SceneFile;

    fn scene() -> Scene {
        Scene::from_str_named(
            include_str!("../../scenes/taylor_bar.toml"),
            "taylor_bar.toml",
        )
        .unwrap()
    }

    #[test]
    fn names_and_value_references_are_unique() {
        let t = variable_table(&scene());
        let mut names: Vec<_> = t.iter().map(|v| v.name.clone()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), t.len());
        for (i, v) in t.iter().enumerate() {
            assert_eq!(v.value_reference as usize, i);
        }
    }

    #[test]
    fn fixed_tools_have_no_velocity_input_and_moving_tools_do() {
        let mut s = scene();
        let t = variable_table(&s);
        assert!(!t
            .iter()
            .any(|v| v.name == "wall.velocity_m_per_s" && v.causality == Causality::Input));
        assert!(t.iter().any(|v| v.name == "wall.force_N"
            && v.causality == Causality::Output
            && v.unit == Some("N")));
        s.tools[0].motion = Motion::Constant {
            velocity_m_per_s: 10.0,
        };
        let t = variable_table(&s);
        let v = t
            .iter()
            .find(|v| v.name == "wall.velocity_m_per_s")
            .unwrap();
        assert_eq!(
            (v.causality, v.kind.clone()),
            (Causality::Input, Kind::Real(Some(10.0)))
        );
    }

    #[test]
    fn xml_round_trip_matches_the_table() {
        let s = scene();
        let t = variable_table(&s);
        let header = xml::Header {
            model_name: s.name.clone(),
            model_identifier: s.name.clone(),
            guid: xml::guid("scene text"),
            description: s.description.clone(),
            stop_time: s.time.end_s,
            step_size: 1e-6,
        };
        let text = xml::write(&header, &t).unwrap();
        let back = xml::read(&text).unwrap();
        assert_eq!(back.fmi_version, "2.0");
        assert_eq!(back.guid, header.guid);
        assert_eq!(back.model_identifier, "taylor_bar");
        assert_eq!(back.variables.len(), t.len());
        for (r, v) in back.variables.iter().zip(&t) {
            assert_eq!(r.name, v.name);
            assert_eq!(r.value_reference, v.value_reference);
            assert_eq!(r.unit.as_deref(), v.unit);
            let kind = match &v.kind {
                Kind::Real(_) | Kind::RealArray(_) => "Real",
                Kind::Integer(_) => "Integer",
                Kind::String(_) => "String",
                Kind::Boolean(_) => "Boolean",
            };
            assert_eq!(r.kind, kind);
        }
        let outputs: Vec<usize> = t
            .iter()
            .enumerate()
            .filter(|(_, v)| v.causality == Causality::Output)
            .map(|(i, _)| i + 1)
            .collect();
        assert_eq!(back.outputs, outputs);
        for u in ["m", "N", "J"] {
            assert!(back.units.iter().any(|x| x == u), "unit {u}");
        }
        assert_eq!(back.log_categories.len(), 3);
    }

    /// Every shipped scene's FMI 2.0 and 3.0 documents write: each unit its variables use
    /// has base units.
    #[test]
    fn every_shipped_scene_writes_its_units() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let mut written = 0;
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().and_then(|e| e.to_str()) != Some("toml") {
                continue;
            }
            let file = path.file_name().unwrap().to_string_lossy().into_owned();
            let header = |name: &str| xml::Header {
                model_name: name.into(),
                model_identifier: name.into(),
                guid: xml::guid(name),
                description: String::new(),
                stop_time: 1.0,
                step_size: 1e-6,
            };
            let (t2, t3, vr) = match SceneFile::from_file(&path).unwrap() {
                SceneFile::Solid(s) => (
                    variable_table(&*s),
                    variable_table3(&*s),
                    time_value_reference(&*s),
                ),
                SceneFile::Plane(s) => (
                    variable_table(&*s),
                    variable_table3(&*s),
                    time_value_reference(&*s),
                ),
            };
            xml::write(&header(&file), &t2).unwrap_or_else(|e| panic!("{file}: {e}"));
            xml3::write(&header(&file), &t3, vr).unwrap_or_else(|e| panic!("{file}: {e}"));
            written += 1;
        }
        assert!(written >= 20, "{written}");
    }

    #[test]
    fn guid_is_stable_and_content_sensitive() {
        assert_eq!(xml::guid("abc"), xml::guid("abc"));
        assert_ne!(xml::guid("abc"), xml::guid("abd"));
        assert_eq!(xml::guid("abc").len(), 38);
    }

    #[test]
    fn knobs_are_parameters_with_the_scene_as_start() {
        let t = variable_table(&scene());
        let i = t
            .iter()
            .find(|v| v.name == "discretization.integration")
            .unwrap();
        assert_eq!(i.kind, Kind::String(Some("q2".into())));
        assert!(t
            .iter()
            .filter(|v| v.causality == Causality::Parameter)
            .all(|v| v.variability == Variability::Fixed));
        assert!(t.iter().any(|v| v.name == "workpiece.radius_m"));
        assert!(t.iter().any(|v| v.name == "time.end_s"));
        assert!(!t.iter().any(|v| v.name == "output.frames"));
    }

    /// The outputs that count or flag (laps, crossings, a fill point reached) are declared
    /// `discrete` in both versions, every other output `continuous`.
    #[test]
    fn counts_and_flags_are_discrete_outputs() {
        let is_discrete = |n: &str| {
            n.ends_with(".filled")
                || ["laps", "boundary_crossings", "fold_crossings"]
                    .iter()
                    .any(|c| n == format!("workpiece.{c}"))
        };
        let check = |file: &str, t: &[Variable], expect: &[&str]| {
            for v in t.iter().filter(|v| v.causality == Causality::Output) {
                let want = if is_discrete(&v.name) {
                    Variability::Discrete
                } else {
                    Variability::Continuous
                };
                assert_eq!(v.variability, want, "{file}: {}", v.name);
            }
            for n in expect {
                assert!(t.iter().any(|v| v.name == *n), "{file}: {n}");
            }
        };
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let plane = Scene::from_file(&dir.join("closed_die_hub.toml")).unwrap();
        check(
            "closed_die_hub.toml",
            &variable_table(&plane),
            &["workpiece.laps", "workpiece.boundary_crossings"],
        );
        let SceneFile::Solid(conrod) = SceneFile::from_file(&dir.join("conrod_3d.toml")).unwrap()
        else {
            panic!("conrod_3d.toml is 3D")
        };
        let t3 = variable_table3(&*conrod);
        check(
            "conrod_3d.toml",
            &t3,
            &["workpiece.fold_crossings", "die.boss_end.filled"],
        );
        let header = xml::Header {
            model_name: "conrod".into(),
            model_identifier: "conrod".into(),
            guid: xml::guid("conrod"),
            description: String::new(),
            stop_time: 1.0,
            step_size: 1e-6,
        };
        for text in [
            xml::write(&header, &variable_table(&*conrod)).unwrap(),
            xml3::write(&header, &t3, time_value_reference(&*conrod)).unwrap(),
        ] {
            let at = text.find(r#"name="workpiece.fold_crossings""#).unwrap();
            let element = &text[at..at + text[at..].find('>').unwrap()];
            assert!(element.contains(r#"variability="discrete""#), "{element}");
        }
    }

    /// A 3D scene's table: the 2D interface over the 3D register and scene, names unique
    /// (the cylinder's `workpiece.radius_m` key gives way to the output of that name).
    #[test]
    fn a_3d_scene_has_the_2d_interface_and_unique_names() {
        let s = SolidScene::from_str_named(
            include_str!("../../scenes/taylor_bar_3d.toml"),
            "taylor_bar_3d.toml",
        )
        .unwrap();
        let t = variable_table3(&s);
        let mut names: Vec<_> = t.iter().map(|v| v.name.clone()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), t.len());
        let find = |n: &str| t.iter().find(|v| v.name == n).unwrap();
        assert_eq!(find("workpiece.radius_m").causality, Causality::Output);
        assert_eq!(find("wall.force_z_N").unit, Some("N"));
        assert_eq!(find("workpiece.cells[2]").kind, Kind::Integer(Some(60)));
        assert_eq!(find("workpiece.length_m").causality, Causality::Parameter);
        assert!(!t.iter().any(|v| v.causality == Causality::Input));
        assert!(!t.iter().any(|v| matches!(v.kind, Kind::RealArray(_))));
        assert_eq!(time_value_reference(&s), variable_table(&s).len() as u32);
    }
}
