//! `modelDescription.xml` for FMI 3.0 Co-Simulation, written from [`crate::variable_table3`]
//! over the parts FMI 2.0 shares ([`crate::document`]): the 2.0 variables as `Float64`,
//! `Int32` and `String` with the same names and value references, the independent variable
//! `time` after them, the early-return switches (`Boolean`), the `instantiationToken` (the
//! 2.0 GUID) and the capabilities of `fmu/src/ffi3.rs` (early return, intermediate update).

use crate::document::{self, Doc, Version};
use crate::xml::Header;
use crate::{Causality, Kind, Variable};
use quick_xml::events::BytesStart;

/// Write the whole FMI 3.0 document; `time_vr` is the value reference of `time`.
pub fn write(header: &Header, vars: &[Variable], time_vr: u32) -> Result<String, String> {
    let version = Version {
        fmi_version: "3.0",
        guid_attribute: "instantiationToken",
        root_extra: &[],
        capabilities: &[
            "canHandleVariableCommunicationStepSize",
            "canGetAndSetFMUState",
            "canSerializeFMUState",
            "mightReturnEarlyFromDoStep",
            "providesIntermediateUpdate",
        ],
    };
    let variables = |w: &mut Doc| {
        let time_vr = time_vr.to_string();
        let mut time = BytesStart::new("Float64");
        time.push_attribute(("name", "time"));
        time.push_attribute(("valueReference", time_vr.as_str()));
        time.push_attribute(("causality", "independent"));
        time.push_attribute(("variability", "continuous"));
        time.push_attribute(("description", "simulation time"));
        time.push_attribute(("unit", "s"));
        w.empty(time)?;
        vars.iter().try_for_each(|v| write_variable(w, v))
    };
    let structure = |w: &mut Doc| {
        for list in ["Output", "InitialUnknown"] {
            for v in vars.iter().filter(|v| v.causality == Causality::Output) {
                let mut u = BytesStart::new(list);
                u.push_attribute(("valueReference", v.value_reference.to_string().as_str()));
                w.empty(u)?;
            }
        }
        Ok(())
    };
    document::write(&version, header, vars, variables, structure)
}

/// One variable as its type element (`Float64`, `Int32`, `String`, `Boolean`), with unit
/// and start; an array's `Dimension` and a string's `Start` inside it.
fn write_variable(w: &mut Doc, v: &Variable) -> Result<(), String> {
    let tag = match v.kind {
        Kind::Real(_) | Kind::RealArray(_) => "Float64",
        Kind::Integer(_) => "Int32",
        Kind::String(_) => "String",
        Kind::Boolean(_) => "Boolean",
    };
    let mut e = document::variable(tag, v);
    if v.causality == Causality::Output {
        e.push_attribute(("intermediateUpdate", "true"));
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
    let inner = match &v.kind {
        Kind::RealArray(n) => Some(("Dimension", "start", n.to_string())),
        Kind::String(Some(s)) => Some(("Start", "value", s.clone())),
        _ => None,
    };
    match inner {
        Some((name, key, value)) => {
            w.start(e)?;
            let mut inner = BytesStart::new(name);
            inner.push_attribute((key, value.as_str()));
            w.empty(inner)?;
            w.end(tag)
        }
        None => w.empty(e),
    }
}
