//! What the FMI 2.0 ([`crate::xml`]) and 3.0 ([`crate::xml3`]) `modelDescription.xml`
//! share, written once with quick-xml: the declaration and the root element, the
//! `CoSimulation` element with its capabilities, the units, log categories and default
//! experiment, the attributes every variable has, and the `ModelVariables` and
//! `ModelStructure` elements around each version's own entries.

use crate::{Causality, Variability, Variable};
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::Writer;

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

/// What sets one version's document apart in the parts both share.
pub(crate) struct Version<'a> {
    /// `fmiVersion`.
    pub(crate) fmi_version: &'a str,
    /// The root attribute that carries the GUID (`guid`, `instantiationToken`).
    pub(crate) guid_attribute: &'a str,
    /// The root attributes after the ones both versions have.
    pub(crate) root_extra: &'a [(&'a str, &'a str)],
    /// The `CoSimulation` capabilities declared, all `true`.
    pub(crate) capabilities: &'a [&'a str],
}

/// A document under construction.
pub(crate) struct Doc(Writer<Vec<u8>>);

impl Doc {
    fn event(&mut self, e: Event) -> Result<(), String> {
        self.0.write_event(e).map_err(|e| e.to_string())
    }

    /// An empty element.
    pub(crate) fn empty(&mut self, e: BytesStart) -> Result<(), String> {
        self.event(Event::Empty(e))
    }

    /// The start of an element with content.
    pub(crate) fn start(&mut self, e: BytesStart) -> Result<(), String> {
        self.event(Event::Start(e))
    }

    /// The end of the element `name`.
    pub(crate) fn end(&mut self, name: &str) -> Result<(), String> {
        self.event(Event::End(BytesEnd::new(name)))
    }

    /// An element `name` with the entries `entries` writes.
    fn around(
        &mut self,
        name: &str,
        entries: impl FnOnce(&mut Doc) -> Result<(), String>,
    ) -> Result<(), String> {
        self.start(BytesStart::new(name))?;
        entries(self)?;
        self.end(name)
    }
}

/// The SI base units of a unit the variables use, as the attributes of its `<BaseUnit>`
/// (exponents of kg, m, s, K, rad; `factor` and `offset` for a unit that is not coherent:
/// a value `x` in it is `factor x + offset` in the base units); `None` for a unit this
/// table does not know.
fn unit_base(unit: &str) -> Option<&'static [(&'static str, &'static str)]> {
    Some(match unit {
        "m" => &[("m", "1")],
        "m2" => &[("m", "2")],
        "m3" => &[("m", "3")],
        "m3/s" => &[("m", "3"), ("s", "-1")],
        "s" => &[("s", "1")],
        "kg" => &[("kg", "1")],
        "kg.m2" => &[("kg", "1"), ("m", "2")],
        "m/s" => &[("m", "1"), ("s", "-1")],
        "rad" => &[("rad", "1")],
        "rad/s" => &[("rad", "1"), ("s", "-1")],
        "N" => &[("kg", "1"), ("m", "1"), ("s", "-2")],
        "N.s" => &[("kg", "1"), ("m", "1"), ("s", "-1")],
        "N.s/m" => &[("kg", "1"), ("s", "-1")],
        "J" => &[("kg", "1"), ("m", "2"), ("s", "-2")],
        "W" => &[("kg", "1"), ("m", "2"), ("s", "-3")],
        "W/(m.K)" => &[("kg", "1"), ("m", "1"), ("s", "-3"), ("K", "-1")],
        "W/(m2.K)" => &[("kg", "1"), ("s", "-3"), ("K", "-1")],
        "Pa" => &[("kg", "1"), ("m", "-1"), ("s", "-2")],
        "kg/m3" => &[("kg", "1"), ("m", "-3")],
        "1/s" => &[("s", "-1")],
        "1/min" => &[("s", "-1"), ("factor", "0.016666666666666666")],
        "1/K" => &[("K", "-1")],
        "degC" => &[("K", "1"), ("offset", "273.15")],
        "K" => &[("K", "1")],
        "J/(kg.K)" => &[("m", "2"), ("s", "-2"), ("K", "-1")],
        _ => return None,
    })
}

/// `<UnitDefinitions>`: every unit the variables use, with its SI base units; a unit
/// [`unit_base`] does not know is an error naming it and a variable that uses it (a
/// `<BaseUnit>` with no exponents would declare it dimensionless).
fn write_units(w: &mut Doc, vars: &[Variable]) -> Result<(), String> {
    let mut units: Vec<&str> = vars.iter().filter_map(|v| v.unit).collect();
    units.sort_unstable();
    units.dedup();
    w.around("UnitDefinitions", |w| {
        for u in units {
            let base = unit_base(u).ok_or_else(|| {
                let user = vars.iter().find(|v| v.unit == Some(u)).map(|v| &v.name);
                format!("unit `{u}` of variable `{}` has no SI base units in the model description's table", user.map_or("", |n| n))
            })?;
            let mut e = BytesStart::new("Unit");
            e.push_attribute(("name", u));
            w.start(e)?;
            let mut b = BytesStart::new("BaseUnit");
            for &(k, v) in base {
                b.push_attribute((k, v));
            }
            w.empty(b)?;
            w.end("Unit")?;
        }
        Ok(())
    })
}

/// `<LogCategories>` from [`LOG_CATEGORIES`].
fn write_log_categories(w: &mut Doc) -> Result<(), String> {
    w.around("LogCategories", |w| {
        for (name, description) in LOG_CATEGORIES {
            let mut e = BytesStart::new("Category");
            e.push_attribute(("name", name));
            e.push_attribute(("description", description));
            w.empty(e)?;
        }
        Ok(())
    })
}

/// `<DefaultExperiment>`: from 0 to the scene's end at its history interval.
fn write_default_experiment(w: &mut Doc, header: &Header) -> Result<(), String> {
    let mut de = BytesStart::new("DefaultExperiment");
    de.push_attribute(("startTime", "0"));
    de.push_attribute(("stopTime", header.stop_time.to_string().as_str()));
    de.push_attribute(("stepSize", header.step_size.to_string().as_str()));
    w.empty(de)
}

/// The root element `fmiModelDescription`, open.
fn write_root(w: &mut Doc, version: &Version, header: &Header) -> Result<(), String> {
    let mut root = BytesStart::new("fmiModelDescription");
    root.push_attribute(("fmiVersion", version.fmi_version));
    root.push_attribute(("modelName", header.model_name.as_str()));
    root.push_attribute((version.guid_attribute, header.guid.as_str()));
    root.push_attribute(("description", header.description.as_str()));
    root.push_attribute((
        "generationTool",
        concat!("rkforge ", env!("CARGO_PKG_VERSION")),
    ));
    root.push_attribute(("variableNamingConvention", "structured"));
    for &attribute in version.root_extra {
        root.push_attribute(attribute);
    }
    w.start(root)
}

/// `<CoSimulation>` with the model identifier and the version's capabilities.
fn write_co_simulation(w: &mut Doc, version: &Version, header: &Header) -> Result<(), String> {
    let mut cs = BytesStart::new("CoSimulation");
    cs.push_attribute(("modelIdentifier", header.model_identifier.as_str()));
    for &capability in version.capabilities {
        cs.push_attribute((capability, "true"));
    }
    w.empty(cs)
}

fn causality(c: Causality) -> &'static str {
    match c {
        Causality::Parameter => "parameter",
        Causality::Input => "input",
        Causality::Output => "output",
    }
}

fn variability(v: Variability) -> &'static str {
    match v {
        Variability::Fixed => "fixed",
        Variability::Continuous => "continuous",
        Variability::Discrete => "discrete",
    }
}

/// The element `tag` of variable `v` with the attributes every variable has in both
/// versions: name, value reference, description, causality, variability and `initial`
/// (outputs are calculated, parameters exact).
pub(crate) fn variable<'a>(tag: &'a str, v: &Variable) -> BytesStart<'a> {
    let mut e = BytesStart::new(tag);
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
    e
}

/// The whole document of `version` for `header` and `vars`: `variables` writes the entries
/// of `ModelVariables`, `structure` those of `ModelStructure`.
pub(crate) fn write(
    version: &Version,
    header: &Header,
    vars: &[Variable],
    variables: impl FnOnce(&mut Doc) -> Result<(), String>,
    structure: impl FnOnce(&mut Doc) -> Result<(), String>,
) -> Result<String, String> {
    let mut w = Doc(Writer::new_with_indent(Vec::new(), b' ', 2));
    w.event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    write_root(&mut w, version, header)?;
    write_co_simulation(&mut w, version, header)?;
    write_units(&mut w, vars)?;
    write_log_categories(&mut w)?;
    write_default_experiment(&mut w, header)?;
    w.around("ModelVariables", variables)?;
    w.around("ModelStructure", structure)?;
    w.end("fmiModelDescription")?;
    String::from_utf8(w.0.into_inner()).map_err(|e| e.to_string())
}
