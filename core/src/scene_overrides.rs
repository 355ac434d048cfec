//! Dotted-key overrides of a scene: `tools.top.friction = 0.1`, `time.end_s = 2e-3`,
//! `workpiece.particles = [11, 26]`.
//!
//! An override replaces (or adds) one key of the scene's TOML document before the document
//! is deserialised and validated exactly like a file, so an override obeys every rule a file
//! does. A key is a dotted path of table keys; an array of tables that carries names
//! (`tools`) is addressed by the name (`tools.top.motion.velocity_m_per_s`), any array also
//! by index (`tools[1].friction`, `constraints[0].fix`). Errors caused by an override name
//! its dotted key; errors in the file keep the file's key and line.

use crate::error::{Error, Result};
use crate::scene::solid::is_solid;
use crate::scene::{Scene, SolidScene};
use crate::scene_keys::{key_line, syntax_message};
use toml::{Table, Value};

/// A scene's text with dotted-key overrides on top, and the validated scene they give: a
/// 2D [`Scene`] or, as `SceneSource<SolidScene>`, a 3D one.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneSource<S = Scene> {
    text: String,
    file: String,
    overrides: Vec<(String, Value)>,
    scene: S,
}

impl SceneSource {
    /// Read and validate a 2D scene file.
    ///
    /// # Errors
    ///
    /// The file cannot be read, or its scene is invalid (key and line named).
    pub fn from_file(path: &std::path::Path) -> Result<SceneSource> {
        SceneSource::from_str_named(&crate::scene::read_text(path)?, &path.display().to_string())
    }

    /// Parse and validate 2D scene text; `file` names it in error messages.
    ///
    /// # Errors
    ///
    /// The scene is invalid (key and line named).
    pub fn from_str_named(text: &str, file: &str) -> Result<SceneSource> {
        SceneSource::with_overrides(text, file, Vec::new())
    }

    /// 2D scene text with overrides applied in order (a later one wins on the same key).
    ///
    /// # Errors
    ///
    /// The scene is invalid; an error caused by an override names its dotted key.
    pub fn with_overrides(
        text: &str,
        file: &str,
        overrides: Vec<(String, Value)>,
    ) -> Result<SceneSource> {
        SceneSource::of_text(text, file, overrides)
    }
}

impl<S: Overridable> SceneSource<S> {
    /// Scene text of the kind `S` (2D or 3D) with overrides applied in order (a later one
    /// wins on the same key): `SceneSource::<SolidScene>::of_text(...)` for a 3D scene.
    ///
    /// # Errors
    ///
    /// The scene is invalid; an error caused by an override names its dotted key.
    pub fn of_text(
        text: &str,
        file: &str,
        overrides: Vec<(String, Value)>,
    ) -> Result<SceneSource<S>> {
        let scene = build(text, file, &overrides)?;
        Ok(SceneSource {
            text: text.to_string(),
            file: file.to_string(),
            overrides,
            scene,
        })
    }

    /// Override the key at dotted path `key` with `value` and validate the result; on an
    /// error the source is left as it was.
    ///
    /// # Errors
    ///
    /// The key cannot be addressed (no such tool, not a table) or the scene it gives is
    /// invalid (wrong type, unknown key, non-physical value), with the dotted key named.
    pub fn set(&mut self, key: &str, value: Value) -> Result<()> {
        let mut overrides = self.overrides.clone();
        overrides.push((key.to_string(), value));
        self.scene = build(&self.text, &self.file, &overrides)?;
        self.overrides = overrides;
        Ok(())
    }

    /// Applies the command-line overrides `KEY=VALUE` (`--set`), the values read as by
    /// [`parse_value`], together: the scene is validated once with all of them, so keys
    /// that constrain each other change together (an end time and a history interval
    /// shortened at once, in either order); a later one wins on the same key.
    ///
    /// # Errors
    ///
    /// An argument is not `KEY=VALUE`, or as [`SceneSource::set`].
    pub fn set_args(&mut self, args: &[impl AsRef<str>]) -> Result<()> {
        let mut overrides = self.overrides.clone();
        for arg in args {
            let (key, value) = split_arg(arg.as_ref())?;
            overrides.push((key.to_string(), parse_value(value)));
        }
        self.scene = build(&self.text, &self.file, &overrides)?;
        self.overrides = overrides;
        Ok(())
    }

    /// The validated scene.
    pub fn scene(&self) -> &S {
        &self.scene
    }

    /// The scene text as read.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The file name used in error messages.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// The overrides applied, in order.
    pub fn overrides(&self) -> &[(String, Value)] {
        &self.overrides
    }
}

/// Splits a command-line override `KEY=VALUE` into its key (trimmed) and value text.
///
/// # Errors
///
/// No `=`, or an empty key.
pub fn split_arg(arg: &str) -> Result<(&str, &str)> {
    arg.split_once('=')
        .map(|(k, v)| (k.trim(), v))
        .filter(|(k, _)| !k.is_empty())
        .ok_or_else(|| {
            Error::Request(format!(
                "--set `{arg}`: expected KEY=VALUE, e.g. tools.top.friction=0.1"
            ))
        })
}

/// A value as written on a command line: TOML (`0.1`, `[11, 26]`, `"q4"`, `true`,
/// `{ kind = "fixed" }`), or else the text itself as a string (`q4`).
pub fn parse_value(text: &str) -> Value {
    let text = text.trim();
    toml::from_str::<Table>(&format!("v = {text}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| Value::String(text.to_string()))
}

/// Split a list of command-line values at the commas that are outside brackets, braces and
/// quotes: `0.1,[1, 2],"a,b"` gives `0.1`, `[1, 2]`, `"a,b"`.
pub fn split_values(text: &str) -> Vec<&str> {
    let mut parts = Vec::new();
    let (mut depth, mut quote, mut start) = (0i32, None, 0);
    for (i, c) in text.char_indices() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '[' | '{') => depth += 1,
            (None, ']' | '}') => depth -= 1,
            (None, ',') if depth == 0 => {
                parts.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&text[start..]);
    parts
}

/// A scene type the overrides apply to: the 2D [`Scene`] and the 3D [`SolidScene`].
pub trait Overridable: serde::Serialize + serde::de::DeserializeOwned {
    /// Whether the type is a 3D scene (`model.kinematics = "3d"`).
    const SOLID: bool;
    /// Every non-physical or inconsistent value, as (key path, message).
    fn findings(&self) -> Vec<(String, String)>;
    /// Records where the scene was read from (`file`), for the files it names.
    fn read_from(&mut self, _file: &str) {}
}

impl Overridable for Scene {
    const SOLID: bool = false;
    fn findings(&self) -> Vec<(String, String)> {
        self.validate()
    }
}

impl Overridable for SolidScene {
    const SOLID: bool = true;
    fn findings(&self) -> Vec<(String, String)> {
        self.validate()
    }
    /// An STL tool's `file` is relative to the folder of the scene file.
    fn read_from(&mut self, file: &str) {
        self.folder = std::path::Path::new(file)
            .parent()
            .map(std::path::Path::to_path_buf)
            .unwrap_or_default();
    }
}

/// Deserialise and validate scene text; `file` names it in error messages, a finding is
/// named with its key and line.
///
/// # Errors
///
/// A syntax error, a missing, unknown or mistyped key, a non-physical value.
pub(crate) fn parse<S: Overridable>(text: &str, file: &str) -> Result<S> {
    build(text, file, &[])
}

/// Deserialise and validate `text` with `overrides` applied.
fn build<S: Overridable>(text: &str, file: &str, overrides: &[(String, Value)]) -> Result<S> {
    let syntax = |e: toml::de::Error| Error::SceneSyntax {
        file: file.to_string(),
        message: syntax_message(text, &e),
    };
    if is_solid(text) && !S::SOLID {
        return Err(Error::SceneValue {
            file: file.to_string(),
            line: key_line(text, "model.kinematics").unwrap_or(0),
            key: "model.kinematics".into(),
            message: "a 3D scene, which `rkforge compare` (the paper's Table 5) and `rkforge ring-chart` do not take: they compare 2D runs; `rkforge run`, `sweep`, `fmu`, `ssp`, the ROS node and the Python package take it".into(),
        });
    }
    if overrides.is_empty() {
        let mut scene: S = toml::from_str(text).map_err(syntax)?;
        scene.read_from(file);
        return match scene.findings().into_iter().next() {
            Some((key, message)) => Err(Error::SceneValue {
                file: file.to_string(),
                line: key_line(text, &key).unwrap_or(0),
                key,
                message,
            }),
            None => Ok(scene),
        };
    }
    let original: Table = toml::from_str(text).map_err(syntax)?;
    // The file alone must deserialise: its errors are reported with their lines.
    let alone = toml::from_str::<S>(text).map_err(syntax)?;
    // The file's scene with its defaults written out: an override inside a key the file
    // leaves to its default (`workpiece.initial_velocity_m_per_s[0]`) starts from it.
    let defaults = Table::try_from(&alone).unwrap_or_default();
    let mut doc = original.clone();
    let mut paths = Vec::with_capacity(overrides.len());
    let mut scene = None;
    for (key, value) in overrides {
        if key == "model.kinematics" && (value.as_str() == Some("3d")) != S::SOLID {
            return Err(Error::Override {
                key: key.clone(),
                message: match S::SOLID {
                    false => "`3d` would make this 2D scene a 3D one, whose workpiece and tools take other keys (a cylinder's `cells` or a box's three `particles`, tools in space): start from a 3D scene file (`model.kinematics = \"3d\"`, as scenes/taylor_bar_3d.toml)",
                    true => "this 3D scene stays 3D: a 2D scene (`plane_strain` or `axisymmetric`) takes other keys; start from a 2D scene file (as scenes/taylor_bar.toml)",
                }
                .into(),
            });
        }
        paths.push(apply(&mut doc, &defaults, key, value.clone())?);
        // Deserialising after each override names the first one that breaks the scene.
        scene = Some(
            S::deserialize(Value::Table(doc.clone())).map_err(|e| Error::Override {
                key: key.clone(),
                message: e.message().trim().to_string(),
            })?,
        );
    }
    let mut scene = scene.unwrap_or_else(|| unreachable!("overrides is not empty"));
    scene.read_from(file);
    if let Some((key, message)) = scene.findings().into_iter().next() {
        let culprit = overrides
            .iter()
            .zip(&paths)
            .rev()
            .find(|(_, path)| overlaps(path, &key));
        return Err(match culprit {
            Some(((dotted, _), _)) => Error::Override {
                key: dotted.clone(),
                message: format!("`{key}` {message}"),
            },
            None => Error::SceneValue {
                file: file.to_string(),
                line: key_line(text, &key).unwrap_or(0),
                key,
                message,
            },
        });
    }
    Ok(scene)
}

/// Whether one key path lies within the other (`tools[0].motion` and
/// `tools[0].motion.velocity_m_per_s`).
fn overlaps(a: &str, b: &str) -> bool {
    let within = |inner: &str, outer: &str| {
        inner == outer
            || inner
                .strip_prefix(outer)
                .is_some_and(|rest| rest.starts_with('.') || rest.starts_with('['))
    };
    within(a, b) || within(b, a)
}

/// One part of a dotted key: a name and an optional index (`tools[1]`).
fn split_part(part: &str) -> std::result::Result<(&str, Option<usize>), String> {
    match part.split_once('[') {
        None => Ok((part, None)),
        Some((name, rest)) => rest
            .strip_suffix(']')
            .and_then(|i| i.trim().parse().ok())
            .map(|i| (name, Some(i)))
            .ok_or_else(|| format!("`{part}`: expected `name[index]`")),
    }
}

/// A short description of a TOML value's kind, for messages.
fn kind(v: &Value) -> &'static str {
    match v {
        Value::String(_) => "a string",
        Value::Integer(_) => "an integer",
        Value::Float(_) => "a number",
        Value::Boolean(_) => "a boolean",
        Value::Datetime(_) => "a date",
        Value::Array(_) => "an array",
        Value::Table(_) => "a table",
    }
}

/// Set `key` in `doc` to `value`; a key on the way that `doc` lacks is taken from `defaults`
/// (the same scene with its defaults written out) when it has it, else an empty table.
/// Returns the key's path in the form validation uses (`tools[0].friction`).
fn apply(doc: &mut Table, defaults: &Table, key: &str, value: Value) -> Result<String> {
    let fail = |message: String| Error::Override {
        key: key.to_string(),
        message,
    };
    let parts: Vec<&str> = key.split('.').map(str::trim).collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(fail(
            "empty key part (expected e.g. `tools.top.friction`)".into(),
        ));
    }
    let mut path = String::new();
    let mut table = doc;
    let mut fallback = Some(defaults);
    let mut k = 0;
    loop {
        let (name, index) = split_part(parts[k]).map_err(&fail)?;
        if !path.is_empty() {
            path.push('.');
        }
        path.push_str(name);
        let last = k + 1 == parts.len();
        if last && index.is_none() {
            table.insert(name.to_string(), value);
            return Ok(path);
        }
        let default = fallback.and_then(|t| t.get(name));
        let entry = table.entry(name.to_string()).or_insert_with(|| {
            default
                .cloned()
                .unwrap_or_else(|| Value::Table(Table::new()))
        });
        let mut default = default;
        let mut current = entry;
        if let Value::Array(items) = current {
            let i = match index {
                Some(i) => i,
                // An array of named tables: the next part is a name.
                None if !last => {
                    k += 1;
                    let wanted = parts[k];
                    let names: Vec<&str> = items
                        .iter()
                        .filter_map(|t| t.get("name").and_then(Value::as_str))
                        .collect();
                    items
                        .iter()
                        .position(|t| t.get("name").and_then(Value::as_str) == Some(wanted))
                        .ok_or_else(|| {
                            fail(format!(
                                "no entry of `{path}` is named `{wanted}` (names: {})",
                                if names.is_empty() {
                                    "none".to_string()
                                } else {
                                    names.join(", ")
                                }
                            ))
                        })?
                }
                None => unreachable!("the last part without an index was set above"),
            };
            let count = items.len();
            default = default.and_then(|d| d.as_array()?.get(i));
            path.push_str(&format!("[{i}]"));
            current = items
                .get_mut(i)
                .ok_or_else(|| fail(format!("`{path}`: `{name}` has {count} entries")))?;
            if k + 1 == parts.len() {
                *current = value;
                return Ok(path);
            }
        } else if index.is_some() {
            return Err(fail(format!("`{path}` is {}, not an array", kind(current))));
        }
        table = match current {
            Value::Table(t) => t,
            other => return Err(fail(format!("`{path}` is {}, not a table", kind(other)))),
        };
        fallback = default.and_then(Value::as_table);
        k += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = r#"
name = "t"
[model]
kinematics = "plane_strain"
[workpiece]
origin_m = [0.0, 0.0]
size_m = [0.01, 0.01]
particles = [5, 5]
[material]
density_kg_per_m3 = 8930.0
youngs_modulus_pa = 117e9
poisson_ratio = 0.35
hardening = { law = "linear", yield_stress_pa = 400e6, modulus_pa = 100e6 }
[time]
end_s = 1e-6
[[tools]]
name = "bottom"
points_m = [[0.02, 0.0], [-0.01, 0.0]]
axis = [0.0, -1.0]
motion = { kind = "fixed" }
[[tools]]
name = "top"
points_m = [[-0.01, 0.01], [0.02, 0.01]]
axis = [0.0, 1.0]
motion = { kind = "constant", velocity_m_per_s = -1.0 }
friction = 0.2
"#;

    fn with(key: &str, value: &str) -> Result<SceneSource> {
        SceneSource::with_overrides(SCENE, "s.toml", vec![(key.into(), parse_value(value))])
    }

    #[test]
    fn tools_are_addressed_by_name_and_index() {
        let s = with("tools.top.friction", "0.1").unwrap();
        assert_eq!(s.scene().tools[1].friction.coefficient(), 0.1);
        assert_eq!(s.scene().tools[0].friction.coefficient(), 0.0);
        // An integer where a number is expected, as in a file.
        let s = with("tools.top.friction", "1").unwrap();
        assert_eq!(s.scene().tools[1].friction.coefficient(), 1.0);
        let s = with("tools[0].friction", "0.3").unwrap();
        assert_eq!(s.scene().tools[0].friction.coefficient(), 0.3);
        let s = with("tools.top.motion.velocity_m_per_s", "-2.5").unwrap();
        assert_eq!(
            s.scene().tools[1].motion,
            crate::scene::Motion::Constant {
                velocity_m_per_s: -2.5
            }
        );
    }

    /// A 2D scene cannot become 3D by an override (nor back): the message says why and what
    /// to start from, where it listed the 2D kinematics alone; the 2D kinematics switch.
    #[test]
    fn kinematics_between_2d_and_3d_are_refused_with_the_reason() {
        let e = with("model.kinematics", "3d").unwrap_err().to_string();
        assert!(
            e.contains("model.kinematics")
                && e.contains("would make this 2D scene a 3D one")
                && e.contains("3D scene file"),
            "{e}"
        );
        let s = with("model.kinematics", "axisymmetric").unwrap();
        assert_eq!(
            s.scene().model.kinematics,
            crate::scene::Kinematics::Axisymmetric
        );
        let solid = include_str!("../../scenes/taylor_bar_3d.toml");
        let e = build::<crate::scene::SolidScene>(
            solid,
            "t.toml",
            &[("model.kinematics".into(), parse_value("plane_strain"))],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("this 3D scene stays 3D"), "{e}");
    }

    #[test]
    fn absent_keys_and_tables_are_added() {
        let s = with("discretization.integration", "q4").unwrap();
        assert_eq!(
            s.scene().discretization.integration,
            crate::IntegrationRule::Q4
        );
        let s = with("workpiece.particles", "[7, 9]").unwrap();
        assert_eq!(s.scene().workpiece.particles, [7, 9]);
        let s = with("time.dt_s", "1e-8").unwrap();
        assert_eq!(s.scene().time.dt_s, Some(1e-8));
    }

    /// Keys that constrain each other change together, in either order: a 3D scene's
    /// history interval above its end time is refused alone, not beside a new end time.
    #[test]
    fn overrides_of_the_command_line_are_validated_together() {
        use crate::scene::SolidScene;
        let text = include_str!("../../scenes/taylor_bar_3d.toml");
        let source = || SceneSource::<SolidScene>::of_text(text, "bar", Vec::new()).unwrap();
        for args in [
            ["time.end_s=1e-7", "output.history_interval_s=1e-8"],
            ["output.history_interval_s=1e-8", "time.end_s=1e-7"],
        ] {
            let mut s = source();
            s.set_args(&args).unwrap();
            assert_eq!(s.scene().time.end_s, 1e-7);
            assert_eq!(s.scene().output.history_interval_s, Some(1e-8));
        }
        let mut s = source();
        let e = s.set_args(&["time.end_s=1e-7"]).unwrap_err().to_string();
        assert!(e.contains("history_interval_s"), "{e}");
        assert_eq!(s.scene().time.end_s, 80e-6);
    }

    #[test]
    fn set_keeps_the_source_unchanged_on_error() {
        let mut s = SceneSource::from_str_named(SCENE, "s.toml").unwrap();
        s.set("tools.top.friction", Value::Float(0.4)).unwrap();
        let before = s.clone();
        assert!(s.set("tools.top.friction", Value::Float(-1.0)).is_err());
        assert_eq!(s, before);
        s.set("time.end_s", Value::Float(2e-6)).unwrap();
        assert_eq!(s.scene().tools[1].friction.coefficient(), 0.4);
        assert_eq!(s.scene().time.end_s, 2e-6);
    }

    #[test]
    fn errors_name_the_override_key() {
        let cases = [
            (
                "tools.middle.friction",
                "0.1",
                "no entry of `tools` is named `middle` (names: bottom, top)",
            ),
            ("tools.top.frction", "0.1", "frction"),
            ("tools.top.friction", "\"high\"", "tools.top.friction"),
            ("tools.top.friction", "-0.5", "must be zero or positive"),
            ("time.end_s.x", "1", "`time.end_s` is a number, not a table"),
            ("material.poisson_ratio", "0.5", "must lie in (-1, 0.5)"),
            ("tools..friction", "1", "empty key part"),
            ("tools[5].friction", "1", "has 2 entries"),
        ];
        for (key, value, expected) in cases {
            let e = with(key, value).unwrap_err().to_string();
            assert!(e.contains(&format!("`{key}`")), "{key}: {e}");
            assert!(e.contains(expected), "{key}: {e}");
        }
    }

    #[test]
    fn file_errors_keep_their_line() {
        let bad = SCENE.replace("poisson_ratio = 0.35", "poisson_ratio = 0.6");
        let e = SceneSource::with_overrides(
            &bad,
            "s.toml",
            vec![("tools.top.friction".into(), Value::Float(0.1))],
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("s.toml:12:") && e.contains("material.poisson_ratio"),
            "{e}"
        );
    }

    #[test]
    fn command_line_values() {
        assert_eq!(parse_value("0.1"), Value::Float(0.1));
        assert_eq!(parse_value("q4"), Value::String("q4".into()));
        assert_eq!(parse_value("\"q4\""), Value::String("q4".into()));
        assert_eq!(
            split_values("0.1,[1, 2],\"a,b\",{ kind = \"fixed\" }"),
            vec!["0.1", "[1, 2]", "\"a,b\"", "{ kind = \"fixed\" }"]
        );
    }
}
