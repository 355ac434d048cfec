//! `rkforge ssp SCENE --press NAME --out FILE.ssp`: a press and a forging as one system any
//! SSP (System Structure and Parameterization 1.0) tool opens: the press FMU
//! (`rkforge fmu --press`) and the scene's forging FMU in `resources/`, and
//! `SystemStructure.ssd` connecting them: the press's `ram.velocity_m_per_s` to the forging's
//! `<tool>.velocity_m_per_s`; the forging's `<tool>.force_N`, `<tool>.stroke_m`, `energy.tool_work_J` and
//! `workpiece.height_m` to the press's `ram.force_N`, `ram.stroke_m`, `ram.tool_work_J` and
//! `workpiece.height_m`. Each component's parameters are bound inline at their start values
//! (the press's defaults, the scene's own keys with the scene's values).
//!
//! The scene may be 2D or 3D (the same forging FMU interface). A 3D scene with symmetry
//! planes models part of the workpiece: the press's `model_copies` is bound to the number of
//! copies of the model the driven tool feels (4 for the quarter models, planes x = 0 and
//! y = 0 with a ram along z), so the press works against the whole billet's force. A 2D
//! plane-strain scene's symmetry edges count alike (a half model held on x = 0 with the die
//! along y: 2); an axisymmetric model is the whole revolution already, its mid-plane across
//! the axis counting 1.

use crate::fmu;
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::Writer;
use rkforge_core::scene::solid::{is_solid, CylinderPart, SolidShape};
use rkforge_core::scene::SolidScene;
use rkforge_core::scene::{Component, Edge, Kinematics};
use rkforge_core::Scene;
use rkforge_model_description::{press, variable_table, Causality, FmuScene, Kind, Variable};
use std::io::Write;
use std::path::Path;

/// The forging outputs each press input reads, and the tool's velocity input.
fn connections(tool: &str) -> Vec<(String, String, String, String)> {
    let c = |a: &str, b: String, d: &str, e: String| (a.to_string(), b, d.to_string(), e);
    vec![
        c(
            "press",
            "ram.velocity_m_per_s".into(),
            "forging",
            format!("{tool}.velocity_m_per_s"),
        ),
        c(
            "forging",
            format!("{tool}.force_N"),
            "press",
            "ram.force_N".into(),
        ),
        c(
            "forging",
            format!("{tool}.stroke_m"),
            "press",
            "ram.stroke_m".into(),
        ),
        c(
            "forging",
            "energy.tool_work_J".into(),
            "press",
            "ram.tool_work_J".into(),
        ),
        c(
            "forging",
            "workpiece.height_m".into(),
            "press",
            "workpiece.height_m".into(),
        ),
    ]
}

fn err(e: std::io::Error) -> String {
    e.to_string()
}

/// `<ssd:Component>` with the connectors of `vars` (inputs and outputs).
fn component(
    w: &mut Writer<Vec<u8>>,
    name: &str,
    source: &str,
    vars: &[Variable],
) -> Result<(), String> {
    let mut c = BytesStart::new("ssd:Component");
    c.push_attribute(("name", name));
    c.push_attribute(("type", "application/x-fmu-sharedlibrary"));
    c.push_attribute(("source", source));
    w.write_event(Event::Start(c)).map_err(err)?;
    w.write_event(Event::Start(BytesStart::new("ssd:Connectors")))
        .map_err(err)?;
    for v in vars {
        let kind = match v.causality {
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Parameter => continue,
        };
        let mut e = BytesStart::new("ssd:Connector");
        e.push_attribute(("name", v.name.as_str()));
        e.push_attribute(("kind", kind));
        w.write_event(Event::Start(e)).map_err(err)?;
        w.write_event(Event::Empty(BytesStart::new("ssc:Real")))
            .map_err(err)?;
        w.write_event(Event::End(BytesEnd::new("ssd:Connector")))
            .map_err(err)?;
    }
    w.write_event(Event::End(BytesEnd::new("ssd:Connectors")))
        .map_err(err)?;
    bindings(w, name, vars)?;
    w.write_event(Event::End(BytesEnd::new("ssd:Component")))
        .map_err(err)?;
    Ok(())
}

/// `<ssd:ParameterBindings>`: every parameter of `vars` at its start value, inline, so that
/// a tool shows them and a user edits them in the system.
fn bindings(w: &mut Writer<Vec<u8>>, name: &str, vars: &[Variable]) -> Result<(), String> {
    let params: Vec<&Variable> = vars
        .iter()
        .filter(|v| v.causality == Causality::Parameter)
        .collect();
    if params.is_empty() {
        return Ok(());
    }
    for tag in [
        "ssd:ParameterBindings",
        "ssd:ParameterBinding",
        "ssd:ParameterValues",
    ] {
        w.write_event(Event::Start(BytesStart::new(tag)))
            .map_err(err)?;
    }
    let mut set = BytesStart::new("ssv:ParameterSet");
    set.push_attribute(("version", "1.0"));
    set.push_attribute(("name", name));
    w.write_event(Event::Start(set)).map_err(err)?;
    w.write_event(Event::Start(BytesStart::new("ssv:Parameters")))
        .map_err(err)?;
    for v in params {
        let mut p = BytesStart::new("ssv:Parameter");
        p.push_attribute(("name", v.name.as_str()));
        w.write_event(Event::Start(p)).map_err(err)?;
        let tag = match v.kind {
            Kind::Real(_) | Kind::RealArray(_) => "ssv:Real",
            Kind::Integer(_) => "ssv:Integer",
            Kind::String(_) => "ssv:String",
            Kind::Boolean(_) => "ssv:Boolean",
        };
        let mut value = BytesStart::new(tag);
        value.push_attribute(("value", v.start_text().as_str()));
        w.write_event(Event::Empty(value)).map_err(err)?;
        w.write_event(Event::End(BytesEnd::new("ssv:Parameter")))
            .map_err(err)?;
    }
    w.write_event(Event::End(BytesEnd::new("ssv:Parameters")))
        .map_err(err)?;
    w.write_event(Event::End(BytesEnd::new("ssv:ParameterSet")))
        .map_err(err)?;
    for tag in [
        "ssd:ParameterValues",
        "ssd:ParameterBinding",
        "ssd:ParameterBindings",
    ] {
        w.write_event(Event::End(BytesEnd::new(tag))).map_err(err)?;
    }
    Ok(())
}

/// What the system takes from the scene besides its forging FMU's table: its name, its end
/// time (s) and how many copies of its model make the whole workpiece for the press.
struct About<'a> {
    name: &'a str,
    end_s: f64,
    copies: f64,
}

/// The system description.
fn ssd<S: FmuScene>(
    scene: &S,
    about: &About<'_>,
    kind: press::PressKind,
    name: &str,
    tool: &str,
) -> Result<String, String> {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .map_err(err)?;
    let mut root = BytesStart::new("ssd:SystemStructureDescription");
    root.push_attribute((
        "xmlns:ssc",
        "http://ssp-standard.org/SSP1/SystemStructureCommon",
    ));
    root.push_attribute((
        "xmlns:ssd",
        "http://ssp-standard.org/SSP1/SystemStructureDescription",
    ));
    root.push_attribute((
        "xmlns:ssv",
        "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
    ));
    root.push_attribute(("version", "1.0"));
    let system_name = format!("{name}_press_{}", about.name);
    root.push_attribute(("name", system_name.as_str()));
    root.push_attribute((
        "generationTool",
        concat!("rkforge ", env!("CARGO_PKG_VERSION")),
    ));
    w.write_event(Event::Start(root)).map_err(err)?;
    let mut system = BytesStart::new("ssd:System");
    system.push_attribute(("name", system_name.as_str()));
    w.write_event(Event::Start(system)).map_err(err)?;
    w.write_event(Event::Start(BytesStart::new("ssd:Elements")))
        .map_err(err)?;
    component(
        &mut w,
        "press",
        &format!("resources/{name}.fmu"),
        &press::variable_table(kind, about.copies),
    )?;
    component(
        &mut w,
        "forging",
        "resources/forging.fmu",
        &variable_table(scene),
    )?;
    w.write_event(Event::End(BytesEnd::new("ssd:Elements")))
        .map_err(err)?;
    w.write_event(Event::Start(BytesStart::new("ssd:Connections")))
        .map_err(err)?;
    for (a, ac, b, bc) in connections(tool) {
        let mut e = BytesStart::new("ssd:Connection");
        e.push_attribute(("startElement", a.as_str()));
        e.push_attribute(("startConnector", ac.as_str()));
        e.push_attribute(("endElement", b.as_str()));
        e.push_attribute(("endConnector", bc.as_str()));
        w.write_event(Event::Empty(e)).map_err(err)?;
    }
    w.write_event(Event::End(BytesEnd::new("ssd:Connections")))
        .map_err(err)?;
    w.write_event(Event::End(BytesEnd::new("ssd:System")))
        .map_err(err)?;
    let mut de = BytesStart::new("ssd:DefaultExperiment");
    de.push_attribute(("startTime", "0"));
    de.push_attribute(("stopTime", about.end_s.to_string().as_str()));
    w.write_event(Event::Empty(de)).map_err(err)?;
    w.write_event(Event::End(BytesEnd::new("ssd:SystemStructureDescription")))
        .map_err(err)?;
    String::from_utf8(w.into_inner()).map_err(|e| e.to_string())
}

/// Write the SSP of the press `name` driving the tool `tool` of the scene file `scene_path`
/// (2D or 3D).
pub fn pack(scene_path: &Path, name: &str, tool: &str, out: &Path) -> Result<(), String> {
    let kind = press::parse(name).ok_or_else(|| format!("--press {name}: no such press"))?;
    let text = std::fs::read_to_string(scene_path)
        .map_err(|e| format!("{}: cannot read: {e}", scene_path.display()))?;
    let file = scene_path.display().to_string();
    let (ssd, copies) = if is_solid(&text) {
        let scene = SolidScene::from_str_named(&text, &file).map_err(|e| e.to_string())?;
        check_tool(&scene, tool)?;
        let about = About {
            name: &scene.name,
            end_s: scene.time.end_s,
            copies: solid_copies(&scene, tool)?,
        };
        (ssd(&scene, &about, kind, name, tool)?, about.copies)
    } else {
        let scene = Scene::from_str_named(&text, &file).map_err(|e| e.to_string())?;
        check_tool(&scene, tool)?;
        let about = About {
            name: &scene.name,
            end_s: scene.time.end_s,
            copies: plane_copies(&scene, tool)?,
        };
        (ssd(&scene, &about, kind, name, tool)?, about.copies)
    };
    let dir = tempfile_dir(out)?;
    let press_fmu = dir.join(format!("{name}.fmu"));
    let forging_fmu = dir.join("forging.fmu");
    fmu::pack_press(name, copies, &press_fmu)?;
    fmu::pack(scene_path, &forging_fmu, fmu::Version::Fmi2)?;
    let file =
        std::fs::File::create(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    let entries = [
        ("SystemStructure.ssd".to_string(), ssd.into_bytes()),
        (format!("resources/{name}.fmu"), read(&press_fmu)?),
        ("resources/forging.fmu".to_string(), read(&forging_fmu)?),
    ];
    for (entry, data) in entries {
        zip.start_file(entry.as_str(), opts)
            .map_err(|e| format!("zip {entry}: {e}"))?;
        zip.write_all(&data)
            .map_err(|e| format!("zip {entry}: {e}"))?;
    }
    zip.finish().map_err(|e| format!("zip: {e}"))?;
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// The tool's velocity an input of the scene's FMU (a moving tool), its force and stroke
/// outputs.
fn check_tool<S: FmuScene>(scene: &S, tool: &str) -> Result<(), String> {
    let table = variable_table(scene);
    let needed = [
        ("velocity_m_per_s", Causality::Input),
        ("force_N", Causality::Output),
        ("stroke_m", Causality::Output),
    ];
    for (needed, causality) in needed.map(|(v, c)| (format!("{tool}.{v}"), c)) {
        if !table
            .iter()
            .any(|v| v.name == needed && v.causality == causality)
        {
            return Err(format!(
                "--tool {tool}: the scene's FMU has no variable `{needed}` (the press drives a tool of the scene that is not fixed)"
            ));
        }
    }
    Ok(())
}

/// How many copies of a 3D scene's model the press's ram feels through the tool `tool`
/// ([`press::model_copies`] over the workpiece's symmetry planes).
fn solid_copies(scene: &SolidScene, tool: &str) -> Result<f64, String> {
    let Some(spec) = scene.tools.iter().find(|t| t.name == tool) else {
        return Err(format!(
            "--tool {tool}: the scene has no tool named `{tool}`"
        ));
    };
    let planes: Vec<usize> = match scene.workpiece.shape() {
        Some(SolidShape::Cylinder { part, .. }) => match part {
            CylinderPart::Full => vec![],
            CylinderPart::Half => vec![0],
            CylinderPart::Quarter => vec![0, 1],
        },
        Some(SolidShape::Box { symmetry, .. }) => symmetry.iter().map(|f| f.axis()).collect(),
        None => Vec::new(),
    };
    press::model_copies(&planes, spec.axis).map_err(|e| format!("--tool {tool}: {e}"))
}

/// How many copies of a 2D scene's model the press's ram feels through the tool `tool`
/// ([`press::model_copies`] over its symmetry edges): an edge `x_min` or `x_max` holding `x`
/// only is a plane normal to x, one `y_min` or `y_max` holding `y` only a plane normal to y
/// (an edge holding both is a clamp, not a mirror). In axisymmetry the planes normal to `r`
/// are the axis, and the model is the whole revolution.
fn plane_copies(scene: &Scene, tool: &str) -> Result<f64, String> {
    let Some(spec) = scene.tools.iter().find(|t| t.name == tool) else {
        return Err(format!(
            "--tool {tool}: the scene has no tool named `{tool}`"
        ));
    };
    let plane_strain = scene.model.kinematics == Kinematics::PlaneStrain;
    let planes: Vec<usize> = scene
        .constraints
        .iter()
        .filter_map(|c| match (c.edge, &c.fix[..]) {
            (Edge::XMin | Edge::XMax, [Component::X]) if plane_strain => Some(0),
            (Edge::YMin | Edge::YMax, [Component::Y]) => Some(1),
            _ => None,
        })
        .collect();
    let [ax, ay] = spec.axis;
    press::model_copies(&planes, [ax, ay, 0.0]).map_err(|e| format!("--tool {tool}: {e}"))
}

fn read(p: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(p).map_err(|e| format!("cannot read {}: {e}", p.display()))
}

/// A fresh folder beside `out` for the FMUs on their way into the archive.
fn tempfile_dir(out: &Path) -> Result<std::path::PathBuf, String> {
    let parent = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent)
        .map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
    let dir = parent.join(format!(".rkforge-ssp-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    Ok(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shipped(name: &str) -> Scene {
        let path = format!("{}/../scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        Scene::from_str_named(&text, &path).unwrap()
    }

    /// The plane-strain quarter model (symmetry on the part's axis x = 0 and on the
    /// mid-plane y = 0, the die along y) is half of what the die presses: its mirror in
    /// x = 0 presses the same die, its mirror in y = 0 a mirrored die on the bed. The
    /// axisymmetric half ring (mid-plane z = 0, the axis r = 0) is the whole revolution.
    /// A clamp (an edge holding both components) is not a mirror.
    #[test]
    fn a_2d_press_feels_the_copies_its_symmetry_edges_make() {
        let mut quarter = shipped("flash_quarter");
        assert_eq!(plane_copies(&quarter, "die"), Ok(2.0));
        assert_eq!(
            plane_copies(&shipped("ring_compression"), "platen"),
            Ok(1.0)
        );
        assert_eq!(plane_copies(&shipped("block_forging"), "top"), Ok(1.0));
        quarter.constraints.retain(|c| c.edge == Edge::YMin);
        assert_eq!(plane_copies(&quarter, "die"), Ok(1.0));
        quarter.constraints[0].edge = Edge::XMin;
        quarter.constraints[0].fix = vec![Component::X, Component::Y];
        assert_eq!(plane_copies(&quarter, "die"), Ok(1.0));
        quarter.tools[0].axis = [0.6, -0.8];
        quarter.constraints[0].fix = vec![Component::X];
        let e = plane_copies(&quarter, "die").unwrap_err();
        assert!(e.starts_with("--tool die: the symmetry plane x = 0"), "{e}");
        assert!(plane_copies(&quarter, "ram")
            .unwrap_err()
            .contains("no tool named `ram`"));
    }
}
