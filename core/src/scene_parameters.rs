//! The keys of a scene a user may tune from outside (the FMU's parameters), read from the
//! scene's schema: the JSON Schema that `schemars` derives from the scene's types, walked
//! beside the scene's own values.
//!
//! Every number the scene holds (with its defaults filled in) is a parameter under its dotted
//! key, as `--set` and `Scene.set` address it: `time.end_s`, `workpiece.particles[0]`,
//! `tools.top.friction` (a Coulomb coefficient) or `tools.top.friction.m` (a shear factor),
//! `material.hardening.yield_stress_pa`; every string the schema enumerates (`model.kinematics`,
//! `discretization.integration`, `constraints[0].edge`) is an enumerated parameter. A key the
//! scene leaves out (a fixed step, mass scaling) is not one: write it into the scene to tune
//! it. Left out as well: names and free text, booleans, polylines and tables (tool points,
//! velocity tables), the tags that choose a variant (`motion.kind`, `friction.model`,
//! `hardening.law`: they change which keys exist) and `reference` (published figures, not
//! used by the solver).

use serde_json::{Map, Value};

/// What values a parameter takes.
#[derive(Debug, Clone, PartialEq)]
pub enum ParameterKind {
    /// A real number.
    Real,
    /// An integer.
    Integer,
    /// One of these names.
    Enumeration(Vec<String>),
}

/// One tunable key of a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    /// Dotted key, as `SceneSource::set` takes it.
    pub key: String,
    /// Real, integer or enumerated.
    pub kind: ParameterKind,
    /// The scene's value.
    pub start: toml::Value,
    /// SI unit read from the key's suffix (`_s`, `_m`, `_m_per_s`, `_pa`, `_kg_per_m3`,
    /// `_per_s`, `_per_k`, `_c` for degrees Celsius, `_k` for a temperature difference, `_j_per_kg_k`,
    /// `_w_per_m_k`, `_w_per_m2_k`).
    pub unit: Option<&'static str>,
    /// The schema's description (the doc comment of the field).
    pub description: String,
}

/// The tunable keys of `scene`, a 2D [`crate::Scene`] or a 3D
/// [`crate::scene::SolidScene`], sorted by key.
pub fn parameters<S: serde::Serialize + schemars::JsonSchema>(scene: &S) -> Vec<Parameter> {
    let schema = schemars::schema_for!(S);
    let root = schema.as_value();
    let value = serde_json::to_value(scene).unwrap_or(Value::Null);
    let mut out = Vec::new();
    let walk = Walk { root };
    if let (Value::Object(values), Some(props)) = (&value, root.get("properties")) {
        for (k, v) in values {
            if matches!(k.as_str(), "name" | "description" | "reference") {
                continue;
            }
            if let Some(s) = props.get(k) {
                walk.value(v, s, k, "", &mut out);
            }
        }
    }
    out
}

/// The unit a key's suffix names.
fn unit(key: &str) -> Option<&'static str> {
    let last = key.rsplit('.').next().unwrap_or(key);
    let last = last.split('[').next().unwrap_or(last);
    [
        ("_m_per_s", "m/s"),
        ("_kg_per_m3", "kg/m3"),
        ("_j_per_kg_k", "J/(kg.K)"),
        ("_w_per_m_k", "W/(m.K)"),
        ("_w_per_m2_k", "W/(m2.K)"),
        ("_per_s", "1/s"),
        ("_per_k", "1/K"),
        ("_pa", "Pa"),
        ("_s", "s"),
        ("_m", "m"),
        ("_c", "degC"),
        ("_k", "K"),
    ]
    .into_iter()
    .find(|(suffix, _)| last.ends_with(suffix))
    .map(|(_, u)| u)
}

struct Walk<'a> {
    root: &'a Value,
}

impl Walk<'_> {
    /// Follows `$ref` into the root's `$defs`.
    fn deref<'s>(&'s self, schema: &'s Value) -> &'s Value {
        let mut s = schema;
        while let Some(r) = s.get("$ref").and_then(Value::as_str) {
            match r
                .strip_prefix("#/$defs/")
                .and_then(|name| self.root.get("$defs")?.get(name))
            {
                Some(d) => s = d,
                None => break,
            }
        }
        s
    }

    /// The branches of a schema: its `anyOf` or `oneOf` alternatives, or itself.
    fn branches<'s>(&'s self, schema: &'s Value) -> Vec<&'s Value> {
        let s = self.deref(schema);
        match s.get("anyOf").or_else(|| s.get("oneOf")) {
            Some(Value::Array(alts)) => alts.iter().flat_map(|a| self.branches(a)).collect(),
            _ => vec![s],
        }
    }

    /// The branch an object value takes: the one whose tags (`const` properties) it carries
    /// and whose properties hold all its keys.
    fn object_branch<'s>(
        &'s self,
        schema: &'s Value,
        value: &Map<String, Value>,
    ) -> Option<&'s Value> {
        self.branches(schema).into_iter().find(|b| {
            let Some(props) = b.get("properties").and_then(Value::as_object) else {
                return false;
            };
            value.keys().all(|k| props.contains_key(k))
                && props.iter().all(|(k, p)| match p.get("const") {
                    Some(c) => value.get(k) == Some(c),
                    None => true,
                })
        })
    }

    /// The first description on the way from `schema` to its type.
    fn description(&self, schema: &Value) -> String {
        let mut s = schema;
        loop {
            if let Some(d) = s.get("description").and_then(Value::as_str) {
                return d.split_whitespace().collect::<Vec<_>>().join(" ");
            }
            let next = self.deref(s);
            if std::ptr::eq(next, s) {
                return String::new();
            }
            s = next;
        }
    }

    /// Walks `value` under `schema` at `key`; `described` is the enclosing field's
    /// description, for a value whose own schema has none (an array's element).
    fn value(
        &self,
        value: &Value,
        schema: &Value,
        key: &str,
        described: &str,
        out: &mut Vec<Parameter>,
    ) {
        let own = self.description(schema);
        let description = if own.is_empty() { described } else { &own };
        match value {
            Value::Number(n) => {
                let integer = self
                    .branches(schema)
                    .iter()
                    .any(|b| b.get("type") == Some(&Value::from("integer")));
                let (kind, start) = match (integer, n.as_i64()) {
                    (true, Some(i)) => (ParameterKind::Integer, toml::Value::Integer(i)),
                    _ => (
                        ParameterKind::Real,
                        toml::Value::Float(n.as_f64().unwrap_or(f64::NAN)),
                    ),
                };
                out.push(Parameter {
                    key: key.to_string(),
                    kind,
                    start,
                    unit: unit(key),
                    description: description.to_string(),
                });
            }
            Value::String(s) => {
                let names: Vec<String> = self
                    .branches(schema)
                    .iter()
                    .filter_map(|b| b.get("const").and_then(Value::as_str).map(String::from))
                    .chain(
                        self.branches(schema)
                            .iter()
                            .filter_map(|b| b.get("enum").and_then(Value::as_array))
                            .flatten()
                            .filter_map(|v| v.as_str().map(String::from)),
                    )
                    .collect();
                if names.iter().any(|n| n == s) {
                    out.push(Parameter {
                        key: key.to_string(),
                        kind: ParameterKind::Enumeration(names),
                        start: toml::Value::String(s.clone()),
                        unit: None,
                        description: description.to_string(),
                    });
                }
            }
            Value::Object(fields) => {
                let Some(branch) = self.object_branch(schema, fields) else {
                    return;
                };
                let props = branch.get("properties").and_then(Value::as_object);
                for (k, v) in fields {
                    let Some(p) = props.and_then(|p| p.get(k)) else {
                        continue;
                    };
                    if p.get("const").is_some() || k == "name" {
                        continue;
                    }
                    self.value(v, p, &format!("{key}.{k}"), description, out);
                }
            }
            Value::Array(items) => {
                let Some(item_schema) = self
                    .branches(schema)
                    .into_iter()
                    .find_map(|b| b.get("items"))
                else {
                    return;
                };
                for (i, item) in items.iter().enumerate() {
                    let at = match item {
                        // Arrays of arrays are polylines and tables: geometry, not knobs.
                        Value::Array(_) => return,
                        Value::Object(o) => match o.get("name").and_then(Value::as_str) {
                            Some(name) => format!("{key}.{name}"),
                            None => format!("{key}[{i}]"),
                        },
                        _ => format!("{key}[{i}]"),
                    };
                    self.value(item, item_schema, &at, description, out);
                }
            }
            Value::Null | Value::Bool(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    fn scene(name: &str) -> Scene {
        let path = format!("{}/../scenes/{name}", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        Scene::from_str_named(&text, &path).unwrap()
    }

    fn find<'a>(p: &'a [Parameter], key: &str) -> &'a Parameter {
        p.iter().find(|x| x.key == key).unwrap_or_else(|| {
            panic!(
                "no parameter {key} in {:?}",
                p.iter().map(|x| &x.key).collect::<Vec<_>>()
            )
        })
    }

    #[test]
    fn numbers_and_enumerations_are_parameters_under_their_dotted_keys() {
        let p = parameters(&scene("block_forging.toml"));
        let end = find(&p, "time.end_s");
        assert_eq!(
            (end.kind.clone(), end.unit),
            (ParameterKind::Real, Some("s"))
        );
        assert_eq!(end.start, toml::Value::Float(0.015));
        assert!(
            end.description.starts_with("End time"),
            "{}",
            end.description
        );
        let nx = find(&p, "workpiece.particles[0]");
        assert_eq!(
            (nx.kind.clone(), nx.start.clone()),
            (ParameterKind::Integer, toml::Value::Integer(21))
        );
        let rule = find(&p, "discretization.integration");
        assert_eq!(
            rule.kind,
            ParameterKind::Enumeration(vec!["q4".into(), "q2".into(), "scni".into()])
        );
        assert_eq!(find(&p, "material.youngs_modulus_pa").unit, Some("Pa"));
        assert_eq!(
            find(&p, "tools.top.motion.velocity_m_per_s").unit,
            Some("m/s")
        );
        assert_eq!(
            find(&p, "model.kinematics").start,
            toml::Value::String("plane_strain".into())
        );
        // The fixed step the file sets is one; mass scaling, which it leaves out, is not.
        assert_eq!(find(&p, "time.dt_s").unit, Some("s"));
        // Defaults the file leaves out are there with their values.
        assert_eq!(find(&p, "time.dt_safety").kind, ParameterKind::Real);
        // Names, tags, booleans, polylines and absent options are not.
        for key in p.iter().map(|x| x.key.as_str()) {
            let last = key.rsplit('.').next().unwrap_or(key);
            assert!(
                !["name", "kind", "model", "law", "separation", "simd"].contains(&last)
                    && !key.contains("points_m")
                    && !key.starts_with("time.mass_scaling"),
                "{key}"
            );
        }
    }

    #[test]
    fn a_friction_law_gives_its_own_coefficients() {
        let mut s = scene("block_forging.toml");
        let p = parameters(&s);
        assert_eq!(find(&p, "tools.top.friction").kind, ParameterKind::Real);
        s.tools[0].friction = crate::friction::Friction::Shear { m: 0.4 };
        let p = parameters(&s);
        let name = &s.tools[0].name;
        let m = find(&p, &format!("tools.{name}.friction.m"));
        assert_eq!(m.start, toml::Value::Float(0.4));
        assert!(
            m.description.contains("Shear friction factor"),
            "{}",
            m.description
        );
        assert!(!p.iter().any(|x| x.key == format!("tools.{name}.friction")));
    }

    #[test]
    fn every_parameter_of_every_shipped_scene_can_be_set_to_its_start() {
        let dir = format!("{}/../scenes", env!("CARGO_MANIFEST_DIR"));
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let file = path.display().to_string();
            if crate::scene::solid::is_solid(&text) {
                let source = crate::SceneSource::<crate::scene::SolidScene>::of_text(
                    &text,
                    &file,
                    Vec::new(),
                )
                .unwrap();
                each_parameter_set_to_its_start(source, &file);
            } else {
                each_parameter_set_to_its_start(
                    crate::SceneSource::from_file(&path).unwrap(),
                    &file,
                );
            }
        }
    }

    fn each_parameter_set_to_its_start<
        S: crate::scene_overrides::Overridable + schemars::JsonSchema + PartialEq,
    >(
        mut source: crate::SceneSource<S>,
        file: &str,
    ) {
        let params = parameters(source.scene());
        assert!(params.len() > 10, "{file}");
        for p in &params {
            source
                .set(&p.key, p.start.clone())
                .unwrap_or_else(|e| panic!("{file}: {}: {e}", p.key));
        }
        assert_eq!(parameters(source.scene()), params, "{file}");
    }
}
