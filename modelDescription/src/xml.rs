//! `modelDescription.xml` (FMI 2.0 Co-Simulation) written from the variable table with
//! quick-xml, and read back with quick-xml to check what a host will see; the parts FMI 3.0
//! shares with it (units, log categories, default experiment) for [`crate::xml3`].

use crate::{Causality, Kind, Variability, Variable};
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::{Reader, Writer};

/// Facts about the FMU besides its variables.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// `modelName`.
    pub model_name: String,
    /// `modelIdentifier`: the shared library's file name without extension.
    pub model_identifier: String,
    /// `guid`, a digest of the scene text.
    pub guid: String,
    /// `description`.
    pub description: String,
    /// Default experiment: stop time (s).
    pub stop_time: f64,
    /// Default experiment: communication step (s).
    pub step_size: f64,
}

/// The log categories the FMU reports under.
pub const LOG_CATEGORIES: [(&str, &str); 3] = [
    ("logStatusWarning", "warnings: ignored or adjusted inputs"),
    (
        "logStatusError",
        "errors: refused calls and inputs, failed steps",
    ),
    ("logAll", "everything, including progress"),
];

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

fn unit_base(unit: &str) -> &'static [(&'static str, &'static str)] {
    match unit {
        "m" => &[("m", "1")],
        "s" => &[("s", "1")],
        "m/s" => &[("m", "1"), ("s", "-1")],
        "N" => &[("kg", "1"), ("m", "1"), ("s", "-2")],
        "J" => &[("kg", "1"), ("m", "2"), ("s", "-2")],
        "W" => &[("kg", "1"), ("m", "2"), ("s", "-3")],
        "W/(m.K)" => &[("kg", "1"), ("m", "1"), ("s", "-3"), ("K", "-1")],
        "W/(m2.K)" => &[("kg", "1"), ("s", "-3"), ("K", "-1")],
        "Pa" => &[("kg", "1"), ("m", "-1"), ("s", "-2")],
        "kg/m3" => &[("kg", "1"), ("m", "-3")],
        "1/s" => &[("s", "-1")],
        "1/K" => &[("K", "-1")],
        "degC" => &[("K", "1"), ("offset", "273.15")],
        "K" => &[("K", "1")],
        "J/(kg.K)" => &[("m", "2"), ("s", "-2"), ("K", "-1")],
        _ => &[],
    }
}

/// The document under construction.
pub(crate) type Doc = Writer<Vec<u8>>;

fn err(e: std::io::Error) -> String {
    e.to_string()
}

/// `<UnitDefinitions>`: every unit the variables use, with its SI base units.
pub(crate) fn write_units(w: &mut Doc, vars: &[Variable]) -> Result<(), String> {
    let mut units: Vec<&str> = vars.iter().filter_map(|v| v.unit).collect();
    units.sort_unstable();
    units.dedup();
    w.write_event(Event::Start(BytesStart::new("UnitDefinitions")))
        .map_err(err)?;
    for u in units {
        let mut e = BytesStart::new("Unit");
        e.push_attribute(("name", u));
        w.write_event(Event::Start(e)).map_err(err)?;
        let mut b = BytesStart::new("BaseUnit");
        for &(k, v) in unit_base(u) {
            b.push_attribute((k, v));
        }
        w.write_event(Event::Empty(b)).map_err(err)?;
        w.write_event(Event::End(BytesEnd::new("Unit")))
            .map_err(err)?;
    }
    w.write_event(Event::End(BytesEnd::new("UnitDefinitions")))
        .map_err(err)?;
    Ok(())
}

/// `<LogCategories>` from [`LOG_CATEGORIES`].
pub(crate) fn write_log_categories(w: &mut Doc) -> Result<(), String> {
    w.write_event(Event::Start(BytesStart::new("LogCategories")))
        .map_err(err)?;
    for (name, description) in LOG_CATEGORIES {
        let mut e = BytesStart::new("Category");
        e.push_attribute(("name", name));
        e.push_attribute(("description", description));
        w.write_event(Event::Empty(e)).map_err(err)?;
    }
    w.write_event(Event::End(BytesEnd::new("LogCategories")))
        .map_err(err)?;
    Ok(())
}

/// `<DefaultExperiment>`: from 0 to the scene's end at its history interval.
pub(crate) fn write_default_experiment(w: &mut Doc, header: &Header) -> Result<(), String> {
    let mut de = BytesStart::new("DefaultExperiment");
    de.push_attribute(("startTime", "0"));
    de.push_attribute(("stopTime", header.stop_time.to_string().as_str()));
    de.push_attribute(("stepSize", header.step_size.to_string().as_str()));
    w.write_event(Event::Empty(de)).map_err(err)?;
    Ok(())
}

pub(crate) fn causality(c: Causality) -> &'static str {
    match c {
        Causality::Parameter => "parameter",
        Causality::Input => "input",
        Causality::Output => "output",
    }
}

pub(crate) fn variability(v: Variability) -> &'static str {
    match v {
        Variability::Fixed => "fixed",
        Variability::Continuous => "continuous",
    }
}

/// Write the whole document.
pub fn write(header: &Header, vars: &[Variable]) -> Result<String, String> {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .map_err(err)?;
    let mut root = BytesStart::new("fmiModelDescription");
    root.push_attribute(("fmiVersion", "2.0"));
    root.push_attribute(("modelName", header.model_name.as_str()));
    root.push_attribute(("guid", header.guid.as_str()));
    root.push_attribute(("description", header.description.as_str()));
    root.push_attribute((
        "generationTool",
        concat!("rkforge ", env!("CARGO_PKG_VERSION")),
    ));
    root.push_attribute(("variableNamingConvention", "structured"));
    root.push_attribute(("numberOfEventIndicators", "0"));
    w.write_event(Event::Start(root)).map_err(err)?;

    let mut cs = BytesStart::new("CoSimulation");
    cs.push_attribute(("modelIdentifier", header.model_identifier.as_str()));
    cs.push_attribute(("canHandleVariableCommunicationStepSize", "true"));
    cs.push_attribute(("canGetAndSetFMUstate", "true"));
    cs.push_attribute(("canSerializeFMUstate", "true"));
    cs.push_attribute(("canNotUseMemoryManagementFunctions", "true"));
    w.write_event(Event::Empty(cs)).map_err(err)?;

    write_units(&mut w, vars)?;
    write_log_categories(&mut w)?;
    write_default_experiment(&mut w, header)?;

    w.write_event(Event::Start(BytesStart::new("ModelVariables")))
        .map_err(err)?;
    for v in vars {
        let mut e = BytesStart::new("ScalarVariable");
        e.push_attribute(("name", v.name.as_str()));
        e.push_attribute(("valueReference", v.value_reference.to_string().as_str()));
        e.push_attribute(("description", v.description.as_str()));
        e.push_attribute(("causality", causality(v.causality)));
        e.push_attribute(("variability", variability(v.variability)));
        match v.causality {
            Causality::Output => e.push_attribute(("initial", "calculated")),
            Causality::Parameter => e.push_attribute(("initial", "exact")),
            Causality::Input => {}
        }
        w.write_event(Event::Start(e)).map_err(err)?;
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
        w.write_event(Event::Empty(t)).map_err(err)?;
        w.write_event(Event::End(BytesEnd::new("ScalarVariable")))
            .map_err(err)?;
    }
    w.write_event(Event::End(BytesEnd::new("ModelVariables")))
        .map_err(err)?;

    // Outputs (1-based indices into ModelVariables); all of them are initial unknowns too.
    let outputs: Vec<usize> = vars
        .iter()
        .enumerate()
        .filter(|(_, v)| v.causality == Causality::Output)
        .map(|(i, _)| i + 1)
        .collect();
    w.write_event(Event::Start(BytesStart::new("ModelStructure")))
        .map_err(err)?;
    for list in ["Outputs", "InitialUnknowns"] {
        w.write_event(Event::Start(BytesStart::new(list)))
            .map_err(err)?;
        for i in &outputs {
            let mut u = BytesStart::new("Unknown");
            u.push_attribute(("index", i.to_string().as_str()));
            w.write_event(Event::Empty(u)).map_err(err)?;
        }
        w.write_event(Event::End(BytesEnd::new(list)))
            .map_err(err)?;
    }
    w.write_event(Event::End(BytesEnd::new("ModelStructure")))
        .map_err(err)?;
    w.write_event(Event::End(BytesEnd::new("fmiModelDescription")))
        .map_err(err)?;
    String::from_utf8(w.into_inner()).map_err(|e| e.to_string())
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
