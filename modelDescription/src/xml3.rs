//! `modelDescription.xml` for FMI 3.0 Co-Simulation, written from [`crate::variable_table3`]:
//! the 2.0 variables as `Float64`, `Int32` and `String` with the same names and value
//! references, the independent variable `time` after them, the early-return switches
//! (`Boolean`), the `instantiationToken` (the 2.0 GUID) and the capabilities of
//! `fmu/src/ffi3.rs` (early return).

use crate::xml::{
    causality, variability, write_default_experiment, write_log_categories, write_units, Doc,
    Header,
};
use crate::{Causality, Kind, Variable};
use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::Writer;

fn err(e: std::io::Error) -> String {
    e.to_string()
}

/// Write the whole FMI 3.0 document; `time_vr` is the value reference of `time`.
pub fn write(header: &Header, vars: &[Variable], time_vr: u32) -> Result<String, String> {
    let mut w: Doc = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .map_err(err)?;
    let mut root = BytesStart::new("fmiModelDescription");
    root.push_attribute(("fmiVersion", "3.0"));
    root.push_attribute(("modelName", header.model_name.as_str()));
    root.push_attribute(("instantiationToken", header.guid.as_str()));
    root.push_attribute(("description", header.description.as_str()));
    root.push_attribute((
        "generationTool",
        concat!("rkforge ", env!("CARGO_PKG_VERSION")),
    ));
    root.push_attribute(("variableNamingConvention", "structured"));
    w.write_event(Event::Start(root)).map_err(err)?;

    let mut cs = BytesStart::new("CoSimulation");
    cs.push_attribute(("modelIdentifier", header.model_identifier.as_str()));
    cs.push_attribute(("canHandleVariableCommunicationStepSize", "true"));
    cs.push_attribute(("canGetAndSetFMUState", "true"));
    cs.push_attribute(("canSerializeFMUState", "true"));
    cs.push_attribute(("mightReturnEarlyFromDoStep", "true"));
    cs.push_attribute(("providesIntermediateUpdate", "true"));
    w.write_event(Event::Empty(cs)).map_err(err)?;

    write_units(&mut w, vars)?;
    write_log_categories(&mut w)?;
    write_default_experiment(&mut w, header)?;

    w.write_event(Event::Start(BytesStart::new("ModelVariables")))
        .map_err(err)?;
    let time_vr = time_vr.to_string();
    let mut time = BytesStart::new("Float64");
    time.push_attribute(("name", "time"));
    time.push_attribute(("valueReference", time_vr.as_str()));
    time.push_attribute(("causality", "independent"));
    time.push_attribute(("variability", "continuous"));
    time.push_attribute(("description", "simulation time"));
    time.push_attribute(("unit", "s"));
    w.write_event(Event::Empty(time)).map_err(err)?;
    for v in vars {
        let tag = match v.kind {
            Kind::Real(_) | Kind::RealArray(_) => "Float64",
            Kind::Integer(_) => "Int32",
            Kind::String(_) => "String",
            Kind::Boolean(_) => "Boolean",
        };
        let mut e = BytesStart::new(tag);
        e.push_attribute(("name", v.name.as_str()));
        e.push_attribute(("valueReference", v.value_reference.to_string().as_str()));
        e.push_attribute(("description", v.description.as_str()));
        e.push_attribute(("causality", causality(v.causality)));
        e.push_attribute(("variability", variability(v.variability)));
        match v.causality {
            Causality::Output => {
                e.push_attribute(("initial", "calculated"));
                e.push_attribute(("intermediateUpdate", "true"));
            }
            Causality::Parameter => e.push_attribute(("initial", "exact")),
            Causality::Input => {}
        }
        if let Some(u) = v.unit {
            e.push_attribute(("unit", u));
        }
        match &v.kind {
            Kind::Real(Some(x)) => e.push_attribute(("start", x.to_string().as_str())),
            Kind::Integer(Some(i)) => e.push_attribute(("start", i.to_string().as_str())),
            Kind::Boolean(Some(b)) => e.push_attribute(("start", b.to_string().as_str())),
            _ => {}
        }
        if let Kind::RealArray(n) = v.kind {
            w.write_event(Event::Start(e)).map_err(err)?;
            let mut dim = BytesStart::new("Dimension");
            dim.push_attribute(("start", n.to_string().as_str()));
            w.write_event(Event::Empty(dim)).map_err(err)?;
            w.write_event(Event::End(BytesEnd::new(tag))).map_err(err)?;
        } else if let Kind::String(Some(s)) = &v.kind {
            w.write_event(Event::Start(e)).map_err(err)?;
            let mut start = BytesStart::new("Start");
            start.push_attribute(("value", s.as_str()));
            w.write_event(Event::Empty(start)).map_err(err)?;
            w.write_event(Event::End(BytesEnd::new(tag))).map_err(err)?;
        } else {
            w.write_event(Event::Empty(e)).map_err(err)?;
        }
    }
    w.write_event(Event::End(BytesEnd::new("ModelVariables")))
        .map_err(err)?;

    w.write_event(Event::Start(BytesStart::new("ModelStructure")))
        .map_err(err)?;
    for list in ["Output", "InitialUnknown"] {
        for v in vars.iter().filter(|v| v.causality == Causality::Output) {
            let mut u = BytesStart::new(list);
            u.push_attribute(("valueReference", v.value_reference.to_string().as_str()));
            w.write_event(Event::Empty(u)).map_err(err)?;
        }
    }
    w.write_event(Event::End(BytesEnd::new("ModelStructure")))
        .map_err(err)?;
    w.write_event(Event::End(BytesEnd::new("fmiModelDescription")))
        .map_err(err)?;
    String::from_utf8(w.into_inner()).map_err(|e| e.to_string())
}
