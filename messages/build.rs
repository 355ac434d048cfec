//! Derives the message, service and action types from the definitions in
//! `msg/<package>/msg/<Type>.msg`, `msg/<package>/srv/<Service>.srv` and
//! `msg/<package>/action/<Action>.action` (the one source of every message): for each
//! message, part of a service (request, response) or part of an action (goal, result,
//! feedback) a Rust struct with its constants and defaults, its serde derives (the CDR
//! codec is `cdr-encoding`'s, `src/msgs.rs`) and its `RosMessage` constants (type name, DDS type name, the text and the
//! full `ros2msg` schema as rosbag2 writes it). The generated code is included by
//! `src/msgs.rs`.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The 80-`=` line rosbag2 puts between the definitions of a schema.
const SEPARATOR: &str =
    "================================================================================";

/// ROS 2 primitive types: (name, Rust type, float?).
const PRIMITIVES: [(&str, &str, bool); 10] = [
    ("bool", "bool", false),
    ("byte", "u8", false),
    ("uint8", "u8", false),
    ("uint16", "u16", false),
    ("int32", "i32", false),
    ("uint32", "u32", false),
    ("uint64", "u64", false),
    ("float32", "f32", true),
    ("float64", "f64", true),
    ("string", "String", false),
];

/// Primitive names rosbag2 does not treat as dependencies (all of ROS 2's, used or not).
const ROS_PRIMITIVES: [&str; 14] = [
    "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32",
    "uint32", "int64", "uint64", "string",
];

/// Type names of Rust's prelude, which a message type must not shadow.
const RUST_PRELUDE: [&str; 5] = ["Box", "Option", "Result", "String", "Vec"];

/// A field of a message: ROS type (`pkg/Type` for messages), name, sequence?, default.
struct Field {
    ty: String,
    name: String,
    seq: bool,
    default: Option<String>,
}

/// One `.msg` file, the request or response part of a `.srv` file, or the goal, result or
/// feedback part of an `.action` file.
struct Message {
    /// `pkg/Type`, as rosbag2 names it after `MSG:` (`pkg/Service_Request` for a part of a
    /// service, `pkg/Action_Goal` for a part of an action).
    name: String,
    path: PathBuf,
    /// `msg`, `srv` for a part of a service, `action` for a part of an action.
    kind: &'static str,
    /// The text: all of a `.msg`, the lines before or after the `---` of a `.srv`, the lines
    /// before, between or after the two `---` of an `.action`.
    text: String,
    fields: Vec<Field>,
    /// (ROS type, name, value).
    constants: Vec<(String, String, String)>,
}

impl Message {
    fn package(&self) -> &str {
        self.name.split('/').next().unwrap_or_default()
    }

    /// The type's name after `pkg/<kind>/`.
    fn type_name(&self) -> &str {
        self.name.rsplit('/').next().unwrap_or_default()
    }

    /// The Rust name: the type's, `Service_Request` written `ServiceRequest` (and
    /// `Action_Goal` `ActionGoal`), and names of
    /// Rust's prelude (`simulation_interfaces/msg/Result`) with the suffix `Msg`.
    fn ident(&self) -> String {
        let ident = self.type_name().replace('_', "");
        if RUST_PRELUDE.contains(&ident.as_str()) {
            ident + "Msg"
        } else {
            ident
        }
    }
}

/// The Rust type of a ROS 2 primitive and whether it is a float.
fn primitive(ty: &str) -> Option<(&'static str, bool)> {
    PRIMITIVES.iter().find(|p| p.0 == ty).map(|p| (p.1, p.2))
}

/// Parse the fields and constants of `text` (a `.msg` of package `package`).
fn parse(path: &Path, package: &str, text: &str) -> (Vec<Field>, Vec<(String, String, String)>) {
    let mut fields = Vec::new();
    let mut constants = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let at = || format!("{}:{}", path.display(), k + 1);
        let code = line.split('#').next().unwrap_or_default().trim();
        if code.is_empty() {
            continue;
        }
        let (ty, rest) = code
            .split_once(char::is_whitespace)
            .unwrap_or_else(|| panic!("{}: a field needs a type and a name", at()));
        let rest = rest.trim();
        if let Some((name, value)) = rest.split_once('=') {
            assert!(primitive(ty).is_some(), "{}: constant of type {ty}", at());
            constants.push((
                ty.to_owned(),
                name.trim().to_owned(),
                value.trim().to_owned(),
            ));
            continue;
        }
        let (base, seq) = match ty.strip_suffix("[]") {
            Some(b) => (b, true),
            None => (ty, false),
        };
        assert!(
            !base.contains(['[', '<', '>']),
            "{}: bounded and fixed-size arrays and strings are not supported",
            at()
        );
        let base = if primitive(base).is_some() || base.contains('/') {
            base.to_owned()
        } else {
            format!("{package}/{base}")
        };
        let mut words = rest.split_whitespace();
        let name = words.next().unwrap_or_default().to_owned();
        let default = words.next().map(str::to_owned);
        assert!(
            words.next().is_none(),
            "{}: unexpected text after the default",
            at()
        );
        fields.push(Field {
            ty: base,
            name,
            seq,
            default,
        });
    }
    (fields, constants)
}

/// The field types rosbag2 finds in a `.msg` text (`LocalMessageDefinitionSource`): the first
/// token of every line that starts (after blanks) with `[A-Za-z0-9_/]` and continues with
/// blanks, array brackets stripped, primitives dropped, bare names qualified with `package`.
fn dependencies(text: &str, package: &str) -> BTreeSet<String> {
    let mut deps = BTreeSet::new();
    for line in text.lines() {
        let line = line.trim_start();
        let token_len = line
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '/'))
            .unwrap_or(line.len());
        let (token, rest) = line.split_at(token_len);
        let rest = match rest.strip_prefix('[') {
            Some(r) => r.split_once(']').map_or("", |(_, after)| after),
            None => rest,
        };
        if token.is_empty() || !rest.starts_with(char::is_whitespace) {
            continue;
        }
        if ROS_PRIMITIVES.contains(&token) {
            continue;
        }
        if token.contains('/') {
            deps.insert(token.to_owned());
        } else {
            deps.insert(format!("{package}/{token}"));
        }
    }
    deps
}

/// rosbag2's full text of `name`: the `.msg` text, then for each
/// dependency not yet written, depth first in sorted order, a delimiter and its text.
fn schema(name: &str, all: &BTreeMap<String, Message>, seen: &mut BTreeSet<String>) -> String {
    let m = &all[name];
    let mut out = m.text.clone();
    for dep in dependencies(&m.text, m.package()) {
        assert!(all.contains_key(&dep), "{name} needs {dep}: no msg file");
        if seen.insert(dep.clone()) {
            let _ = write!(out, "\n{SEPARATOR}\nMSG: {dep}\n");
            out += &schema(&dep, all, seen);
        }
    }
    out
}

/// Rust type of a field.
fn rust_type(f: &Field, all: &BTreeMap<String, Message>) -> String {
    let base = match primitive(&f.ty) {
        Some((rust, _)) => rust.to_owned(),
        None => all[&f.ty].ident(),
    };
    if f.seq {
        format!("Vec<{base}>")
    } else {
        base
    }
}

/// Whether values of message `name` are plain data (`Copy`), and free of floats (`Eq`, `Hash`).
fn traits(name: &str, all: &BTreeMap<String, Message>) -> (bool, bool) {
    let (mut copy, mut eq) = (true, true);
    for f in &all[name].fields {
        let (c, e) = match primitive(&f.ty) {
            Some((rust, float)) => (rust != "String", !float),
            None => traits(&f.ty, all),
        };
        copy &= c && !f.seq;
        eq &= e;
    }
    (copy, eq)
}

fn field_ident(name: &str) -> String {
    if name == "type" {
        "r#type".into()
    } else {
        name.into()
    }
}

/// A `.msg` default or constant value as a Rust literal of `ty`.
fn literal(ty: &str, value: &str) -> String {
    match primitive(ty) {
        Some((_, true)) => format!(
            "{:?}",
            value
                .parse::<f64>()
                .unwrap_or_else(|e| panic!("{value}: {e}"))
        ),
        Some(("bool", _)) => value.to_lowercase(),
        _ => value.to_owned(),
    }
}

fn generate(m: &Message, all: &BTreeMap<String, Message>) -> String {
    let ident = &m.ident();
    let (copy, eq) = traits(&m.name, all);
    let has_defaults = m.fields.iter().any(|f| f.default.is_some());
    let (pkg, kind, ty) = (m.package(), m.kind, m.type_name());
    let file = m
        .path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or_default();
    let mut derives = vec!["Debug", "Clone", "PartialEq"];
    if copy {
        derives.push("Copy");
    }
    if eq {
        derives.extend(["Eq", "Hash"]);
    }
    if !has_defaults {
        derives.push("Default");
    }
    let mut s = format!(
        "/// `{pkg}/{kind}/{ty}`, generated from `msg/{pkg}/{kind}/{file}`.\n#[derive({})]\n\
         #[derive(serde::Serialize, serde::Deserialize)]\npub struct {ident} {{\n",
        derives.join(", ")
    );
    for f in &m.fields {
        let decl = format!("{}{} {}", f.ty, if f.seq { "[]" } else { "" }, f.name);
        // A byte sequence goes to CDR in one piece (count, then the bytes).
        let bytes = match f.seq && primitive(&f.ty).is_some_and(|p| p.0 == "u8") {
            true => "    #[serde(with = \"serde_bytes\")]\n",
            false => "",
        };
        let _ = writeln!(
            s,
            "    /// `{decl}`\n{bytes}    pub {}: {},",
            field_ident(&f.name),
            rust_type(f, all)
        );
    }
    s += "}\n\n";
    if !m.constants.is_empty() {
        let _ = writeln!(s, "impl {ident} {{");
        for (cty, name, value) in &m.constants {
            let rust = primitive(cty).map_or("", |p| p.0);
            let _ = writeln!(
                s,
                "    /// `{cty} {name}={value}`\n    pub const {name}: {rust} = {};",
                literal(cty, value)
            );
        }
        s += "}\n\n";
    }
    if has_defaults {
        let _ = writeln!(
            s,
            "impl Default for {ident} {{\n    /// The defaults of the definition.\n    fn default() -> Self {{\n        Self {{"
        );
        for f in &m.fields {
            let value = f
                .default
                .as_deref()
                .map_or_else(|| "Default::default()".to_owned(), |v| literal(&f.ty, v));
            let _ = writeln!(s, "            {}: {value},", field_ident(&f.name));
        }
        s += "        }\n    }\n}\n\n";
    }
    let full = schema(&m.name, all, &mut BTreeSet::new());
    let _ = write!(
        s,
        "impl RosMessage for {ident} {{\n    const TYPE_NAME: &'static str = \"{pkg}/{kind}/{ty}\";\n    \
         const DDS_TYPE_NAME: &'static str = \"{pkg}::{kind}::dds_::{ty}_\";\n    \
         const DEFINITION: &'static str = {:?};\n    \
         const SCHEMA: &'static str = {full:?};\n}}\n\n\
         #[cfg(feature = \"dds\")]\nimpl ros2_client::Message for {ident} {{}}\n\n",
        m.text
    );
    s
}

/// The types of a definition file `ty.kind` with text `text`: (type name, text) of the
/// `.msg`; of the `_Request` and `_Response` parts of a `.srv` (split at its `---` line);
/// of the `_Goal`, `_Result` and `_Feedback` parts of an `.action` (split at its two `---`
/// lines). Every part but the last keeps the newline before its `---`.
fn split(path: &Path, ty: &str, kind: &str, text: &str) -> Vec<(String, String)> {
    let suffixes: &[&str] = match kind {
        "msg" => return vec![(ty.to_owned(), text.to_owned())],
        "srv" => &["_Request", "_Response"],
        _ => &["_Goal", "_Result", "_Feedback"],
    };
    let parts: Vec<&str> = text.split("\n---\n").collect();
    assert_eq!(
        parts.len(),
        suffixes.len(),
        "{}: expected {} `---` line(s)",
        path.display(),
        suffixes.len() - 1
    );
    let last = parts.len() - 1;
    suffixes
        .iter()
        .zip(parts)
        .enumerate()
        .map(|(k, (suffix, part))| {
            let newline = if k < last { "\n" } else { "" };
            (format!("{ty}{suffix}"), format!("{part}{newline}"))
        })
        .collect()
}

fn main() {
    let root =
        PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it")).join("msg");
    println!("cargo:rerun-if-changed={}", root.display());
    let mut all = BTreeMap::new();
    let mut packages: Vec<_> = std::fs::read_dir(&root)
        .expect("messages/msg holds the message definitions")
        .map(|e| e.expect("readable msg directory").path())
        .filter(|p| p.is_dir())
        .collect();
    packages.sort();
    for dir in packages {
        let package = dir
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_owned();
        for kind in ["msg", "srv", "action"] {
            let Ok(entries) = std::fs::read_dir(dir.join(kind)) else {
                continue;
            };
            let mut files: Vec<_> = entries
                .map(|e| e.expect("readable msg directory").path())
                .filter(|p| p.extension().is_some_and(|x| x == kind))
                .collect();
            files.sort();
            for path in files {
                println!("cargo:rerun-if-changed={}", path.display());
                let ty = path
                    .file_stem()
                    .and_then(|n| n.to_str())
                    .unwrap_or_default();
                let text = std::fs::read_to_string(&path)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                let parts = split(&path, ty, kind, &text);
                for (ty, text) in parts {
                    let (fields, constants) = parse(&path, &package, &text);
                    let name = format!("{package}/{ty}");
                    all.insert(
                        name.clone(),
                        Message {
                            name,
                            path: path.clone(),
                            kind,
                            text,
                            fields,
                            constants,
                        },
                    );
                }
            }
        }
    }
    let mut idents = BTreeSet::new();
    for m in all.values() {
        assert!(idents.insert(m.ident()), "two messages named {}", m.ident());
        for f in &m.fields {
            assert!(
                primitive(&f.ty).is_some() || all.contains_key(&f.ty),
                "{}: field {} of unknown type {}",
                m.name,
                f.name,
                f.ty
            );
        }
    }
    let code: String = all.values().map(|m| generate(m, &all)).collect();
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets it")).join("msgs.rs");
    std::fs::write(&out, code).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
}
