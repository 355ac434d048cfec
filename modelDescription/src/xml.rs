//! `modelDescription.xml` (FMI 2.0 Co-Simulation) written from the variable table with
//! quick-xml over the parts FMI 3.0 shares ([`crate::document`]), and read back with
//! quick-xml to check what a host will see; the [`Header`], log categories and GUID both
//! versions use.

use crate::document::{self, Doc, Version};
pub use crate::document::{Header, LOG_CATEGORIES};
use crate::{Causality, Kind, Variable};
use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;

/// `{xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx}` from two FNV-1a 64-bit digests of `text`: the same
/// scene always gives the same GUID, any change to it a different one.
pub fn guid(text: &str) -> String {
    let fnv = |seed: u64| {
        text.bytes().fold(seed, |h, b| {
            (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01B3)
        })
    };
    let (a, b) = (fnv(0xcbf2_9ce4_8422_2325), fnv(0x8422_2325_cbf2_9ce4));
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

/// Write the whole document.
pub fn write(header: &Header, vars: &[Variable]) -> Result<String, String> {
    let version = Version {
        fmi_version: "2.0",
        guid_attribute: "guid",
        root_extra: &[("numberOfEventIndicators", "0")],
        capabilities: &[
            "canHandleVariableCommunicationStepSize",
            "canGetAndSetFMUstate",
            "canSerializeFMUstate",
            "canNotUseMemoryManagementFunctions",
        ],
    };
    // Outputs (1-based indices into ModelVariables); all of them are initial unknowns too.
    let outputs: Vec<usize> = vars
        .iter()
        .enumerate()
        .filter(|(_, v)| v.causality == Causality::Output)
        .map(|(i, _)| i + 1)
        .collect();
    let variables = |w: &mut Doc| vars.iter().try_for_each(|v| write_variable(w, v));
    let structure = |w: &mut Doc| {
        for list in ["Outputs", "InitialUnknowns"] {
            w.start(BytesStart::new(list))?;
            for i in &outputs {
                let mut u = BytesStart::new("Unknown");
                u.push_attribute(("index", i.to_string().as_str()));
                w.empty(u)?;
            }
            w.end(list)?;
        }
        Ok(())
    };
    document::write(&version, header, vars, variables, structure)
}

/// One `<ScalarVariable>` with its type element (unit, start).
fn write_variable(w: &mut Doc, v: &Variable) -> Result<(), String> {
    w.start(document::variable("ScalarVariable", v))?;
    let (tag, start) = match &v.kind {
        Kind::Real(s) => ("Real", s.map(|x| x.to_string())),
        Kind::Integer(s) => ("Integer", s.map(|x| x.to_string())),
        Kind::String(s) => ("String", s.clone()),
        Kind::Boolean(s) => ("Boolean", s.map(|x| x.to_string())),
        Kind::RealArray(_) => {
            return Err(format!("`{}`: FMI 2.0 has no arrays", v.name));
        }
    };
    let mut t = BytesStart::new(tag);
    if let Some(u) = v.unit {
        t.push_attribute(("unit", u));
    }
    if let Some(s) = &start {
        t.push_attribute(("start", s.as_str()));
    }
    w.empty(t)?;
    w.end("ScalarVariable")
}

/// A variable as read back from the XML.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadVariable {
    /// `name`.
    pub name: String,
    /// `valueReference`.
    pub value_reference: u32,
    /// `causality`.
    pub causality: String,
    /// `variability`.
    pub variability: String,
    /// Type element: `Real`, `Integer` or `String`.
    pub kind: String,
    /// `unit` of the type element.
    pub unit: Option<String>,
    /// `start` of the type element.
    pub start: Option<String>,
}

/// What a host reads from the document.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ReadBack {
    /// `fmiVersion`.
    pub fmi_version: String,
    /// `guid`.
    pub guid: String,
    /// `modelIdentifier` of the CoSimulation element.
    pub model_identifier: String,
    /// Units defined.
    pub units: Vec<String>,
    /// Log categories declared.
    pub log_categories: Vec<String>,
    /// Variables in order.
    pub variables: Vec<ReadVariable>,
    /// Output indices (1-based) listed under ModelStructure/Outputs.
    pub outputs: Vec<usize>,
}

/// Parse a document written by [`write`] (or any FMI 2.0 model description of that shape).
pub fn read(xml: &str) -> Result<ReadBack, String> {
    let mut r = Reader::from_str(xml);
    r.config_mut().trim_text(true);
    let mut out = ReadBack::default();
    let mut in_outputs = false;
    loop {
        let ev = r
            .read_event()
            .map_err(|e| format!("at byte {}: {e}", r.buffer_position()))?;
        let (e, is_empty) = match &ev {
            Event::Start(e) => (e.clone(), false),
            Event::Empty(e) => (e.clone(), true),
            Event::End(e) => {
                if e.name().as_ref() == "Outputs" {
                    in_outputs = false;
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let attr = |name: &str| -> Option<String> {
            e.attributes()
                .flatten()
                .find(|a| a.key.as_ref() == name)
                .and_then(|a| {
                    a.normalized_value(quick_xml::XmlVersion::Explicit1_0)
                        .ok()
                        .map(|v| v.into_owned())
                })
        };
        match e.name().as_ref() {
            "fmiModelDescription" => {
                out.fmi_version = attr("fmiVersion").unwrap_or_default();
                out.guid = attr("guid").unwrap_or_default();
            }
            "CoSimulation" => out.model_identifier = attr("modelIdentifier").unwrap_or_default(),
            "Unit" => out.units.extend(attr("name")),
            "Category" => out.log_categories.extend(attr("name")),
            "ScalarVariable" => out.variables.push(ReadVariable {
                name: attr("name").unwrap_or_default(),
                value_reference: attr("valueReference")
                    .and_then(|v| v.parse().ok())
                    .unwrap_or(u32::MAX),
                causality: attr("causality").unwrap_or_else(|| "local".into()),
                variability: attr("variability").unwrap_or_else(|| "continuous".into()),
                kind: String::new(),
                unit: None,
                start: None,
            }),
            "Real" | "Integer" | "String" | "Boolean" => {
                if let Some(v) = out.variables.last_mut() {
                    v.kind = e.name().as_ref().to_string();
                    v.unit = attr("unit");
                    v.start = attr("start");
                }
            }
            "Outputs" if !is_empty => in_outputs = true,
            "Unknown" if in_outputs => out
                .outputs
                .extend(attr("index").and_then(|i| i.parse::<usize>().ok())),
            _ => {}
        }
    }
    Ok(out)
}
