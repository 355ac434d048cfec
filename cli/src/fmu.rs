//! `rkforge fmu SCENE --out FILE.fmu [--fmi 3]`: one FMI 2.0 (default) or FMI 3.0
//! Co-Simulation FMU per scene.
//!
//! The archive holds `modelDescription.xml` (written from the scene's variable table),
//! the `rkforge-fmu` shared library (it exports both APIs) as
//! `binaries/linux64/<modelIdentifier>.so` (2.0) or `binaries/x86_64-linux/...` (3.0), the
//! scene in `resources/scene.toml` and `documentation/index.html`.

use rkforge_core::scene::solid::is_solid;
use rkforge_core::scene::SolidScene;
use rkforge_core::Scene;
use rkforge_model_description::{
    press, time_value_reference, variable_table, variable_table3, xml, xml3, FmuScene,
};
use std::io::Write;
use std::path::{Path, PathBuf};

const LIBRARY: &str = "librkforge_fmu.so";

/// The shared library: next to this executable, or built from the checkout this binary was
/// built from.
fn shared_library() -> Result<PathBuf, String> {
    let exe = std::env::current_exe().map_err(|e| format!("cannot locate rkforge: {e}"))?;
    if let Some(dir) = exe.parent() {
        let candidate = dir.join(LIBRARY);
        if candidate.is_file() {
            return Ok(candidate);
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    eprintln!("building {LIBRARY} (cargo build --release -p rkforge-fmu) ...");
    let status = std::process::Command::new("cargo")
        .args(["build", "--release", "-p", "rkforge-fmu"])
        .current_dir(&root)
        .status()
        .map_err(|e| {
            format!("{LIBRARY} is not next to rkforge and cargo could not be run to build it: {e}")
        })?;
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let built = target.join("release").join(LIBRARY);
    if status.success() && built.is_file() {
        Ok(built)
    } else {
        Err(format!(
            "building {LIBRARY} failed; run `cargo build --release -p rkforge-fmu`"
        ))
    }
}

fn documentation(
    name: &str,
    description: &str,
    vars: &[rkforge_model_description::Variable],
    version: Version,
) -> String {
    let rows: String = vars
        .iter()
        .map(|v| {
            format!(
                "<tr><td>{}</td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                v.name,
                v.causality,
                v.unit.unwrap_or(""),
                v.start_text(),
                v.description
            )
        })
        .collect();
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{name}</title></head><body>\n\
         <h1>{name}: rkforge FMU</h1>\n<p>{desc}</p>\n\
         <p>FMI {fmi} Co-Simulation of an RKPM forging/impact scene. Inputs are tool velocities along\n\
         each tool's axis (m/s); outputs are tool forces along the axis (N, exerted by the workpiece,\n\
         positive along +axis) and strokes (m). Any communication step is accepted and sub-cycled at\n\
         the solver's stable step. The scene is in resources/scene.toml.</p>\n\
         <table border=\"1\"><tr><th>variable</th><th>causality</th><th>unit</th><th>start</th><th>description</th></tr>\n{rows}</table>\n\
         </body></html>\n",
        name = name,
        desc = description,
        fmi = match version {
            Version::Fmi2 => "2.0",
            Version::Fmi3 => "3.0",
        }
    )
}

/// The FMI version of an FMU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Version {
    /// FMI 2.0 Co-Simulation.
    Fmi2,
    /// FMI 3.0 Co-Simulation.
    Fmi3,
}

impl Version {
    /// From `--fmi`: "3" is FMI 3.0, anything else (clap allows "2") FMI 2.0.
    pub fn from_arg(arg: &str) -> Version {
        if arg == "3" {
            Version::Fmi3
        } else {
            Version::Fmi2
        }
    }
}

/// What the header of an FMU takes from its scene, of either kind: its name, description,
/// end time (s) and history interval (s, the default communication step).
struct About<'a> {
    name: &'a str,
    description: &'a str,
    stop_time: f64,
    step_size: f64,
}

/// Write the FMU of the scene file `scene_path` (2D or 3D) to `out`; returns the model
/// identifier.
pub fn pack(scene_path: &Path, out: &Path, version: Version) -> Result<String, String> {
    let text = std::fs::read_to_string(scene_path)
        .map_err(|e| format!("{}: cannot read: {e}", scene_path.display()))?;
    let file = scene_path.display().to_string();
    // The scene of either kind (the same fields by the same names) and its header.
    macro_rules! pack_as {
        ($kind:ty, $files:expr) => {{
            let scene = <$kind>::from_str_named(&text, &file).map_err(|e| e.to_string())?;
            let about = About {
                name: &scene.name,
                description: &scene.description,
                stop_time: scene.time.end_s,
                step_size: scene.history_interval(),
            };
            let files = $files(&scene)?;
            pack_scene(&scene, &about, &text, &files, out, version)
        }};
    }
    if is_solid(&text) {
        pack_as!(SolidScene, die_files)
    } else {
        pack_as!(Scene, |_: &Scene| Ok::<_, String>(Vec::new()))
    }
}

/// The files a 3D scene's STL tools name, as FMU resources: each at `resources/<file>`, so
/// the FMU, which reads its scene from `resources/scene.toml`, finds it where the scene
/// says (a tool's `file` is relative to the scene's folder).
///
/// # Errors
///
/// A `file` that is absolute or leaves the scene's folder (`..`), which the archive could
/// not hold at the same relative path, or a file that cannot be read; named by its key.
fn die_files(scene: &SolidScene) -> Result<Vec<(String, Vec<u8>)>, String> {
    let mut files = Vec::new();
    for (i, tool) in scene.tools.iter().enumerate() {
        let (Some(file), Some(path)) = (&tool.file, scene.tool_path(i)) else {
            continue;
        };
        let inside = Path::new(file)
            .components()
            .all(|c| matches!(c, std::path::Component::Normal(_)));
        if !inside {
            return Err(format!(
                "tools[{i}].file = \"{file}\": an FMU carries a die's file in resources/ at the path the scene gives, so it must lie in the scene's folder or below it (no absolute path, no ..)"
            ));
        }
        let data = std::fs::read(&path)
            .map_err(|e| format!("tools[{i}].file: cannot read {}: {e}", path.display()))?;
        files.push((format!("resources/{file}"), data));
    }
    Ok(files)
}

/// Write the FMU of `scene` (its text `text`, the files it names `files`: archive name and
/// bytes) to `out`; returns the model identifier.
fn pack_scene<S: FmuScene>(
    scene: &S,
    about: &About<'_>,
    text: &str,
    files: &[(String, Vec<u8>)],
    out: &Path,
    version: Version,
) -> Result<String, String> {
    let vars = match version {
        Version::Fmi2 => variable_table(scene),
        Version::Fmi3 => variable_table3(scene),
    };
    let id: String = about
        .name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let id = if id.starts_with(|c: char| c.is_ascii_digit()) {
        format!("m_{id}")
    } else {
        id
    };
    let header = xml::Header {
        model_name: about.name.to_string(),
        model_identifier: id.clone(),
        guid: xml::guid(text),
        description: about.description.to_string(),
        stop_time: about.stop_time,
        step_size: about.step_size,
    };
    let (md, platform) = match version {
        Version::Fmi2 => (xml::write(&header, &vars)?, "linux64"),
        Version::Fmi3 => (
            xml3::write(&header, &vars, time_value_reference(scene))?,
            "x86_64-linux",
        ),
    };
    let doc = documentation(about.name, about.description, &vars, version);
    write_archive(
        out,
        &md,
        &format!("binaries/{platform}/{id}.so"),
        &std::iter::once(("resources/scene.toml", text.as_bytes()))
            .chain(
                files
                    .iter()
                    .map(|(name, data)| (name.as_str(), data.as_slice())),
            )
            .collect::<Vec<_>>(),
        &doc,
    )?;
    Ok(id)
}

/// Write an FMU archive: the model description, the shared library at `library`, the
/// resource files (archive name and bytes) and the documentation.
fn write_archive(
    out: &Path,
    md: &str,
    library: &str,
    resources: &[(&str, &[u8])],
    doc: &str,
) -> Result<(), String> {
    let lib =
        std::fs::read(shared_library()?).map_err(|e| format!("cannot read {LIBRARY}: {e}"))?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let file =
        std::fs::File::create(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let mut zip = zip::ZipWriter::new(file);
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    let entries = [("modelDescription.xml", md.as_bytes()), (library, &lib)]
        .into_iter()
        .chain(resources.iter().copied())
        .chain([("documentation/index.html", doc.as_bytes())]);
    for (name, data) in entries {
        zip.start_file(name, opts)
            .map_err(|e| format!("zip {name}: {e}"))?;
        zip.write_all(data)
            .map_err(|e| format!("zip {name}: {e}"))?;
    }
    zip.finish().map_err(|e| format!("zip: {e}"))?;
    Ok(())
}

/// Write the FMI 2.0 FMU of the press plant `name` (hydraulic, crank, hammer, screw) to
/// `out`, its `model_copies` starting at `copies` (1: the forging FMU models the whole
/// workpiece); returns the model identifier (`<name>_press`).
pub fn pack_press(name: &str, copies: f64, out: &Path) -> Result<String, String> {
    let kind = press::parse(name).ok_or_else(|| format!("--press {name}: no such press"))?;
    let id = format!("{name}_press");
    let header = press::header(kind, &id);
    let vars = press::variable_table(kind, copies);
    let md = xml::write(&header, &vars)?;
    let doc = documentation(
        &header.model_name,
        &header.description,
        &vars,
        Version::Fmi2,
    );
    let resource = format!("press = \"{name}\"\nmodel_copies = {copies}\n");
    write_archive(
        out,
        &md,
        &format!("binaries/linux64/{id}.so"),
        &[("resources/press.toml", resource.as_bytes())],
        &doc,
    )?;
    Ok(id)
}
