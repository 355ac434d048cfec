//! The variable tables of the press plants (`fmu/src/press.rs`): inputs read from a forging
//! FMU, `ram.velocity_m_per_s` written to it, the press's own outputs and its parameters with the
//! defaults of `examples/presses`.

use crate::{xml, Binding, Causality, Kind, Variability, Variable};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Which press.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PressKind {
    /// Pump, compressible oil column and relief valve.
    Hydraulic,
    /// Flywheel, crank and connecting rod.
    Crank,
    /// A falling ram, blow after blow.
    Hammer,
    /// Flywheel and screw.
    Screw,
}

/// A press's name as `rkforge fmu --press` takes it.
pub fn parse(name: &str) -> Option<PressKind> {
    match name {
        "hydraulic" => Some(PressKind::Hydraulic),
        "crank" => Some(PressKind::Crank),
        "hammer" => Some(PressKind::Hammer),
        "screw" => Some(PressKind::Screw),
        _ => None,
    }
}

/// One parameter: name, default, unit, description.
pub type Param = (&'static str, f64, Option<&'static str>, &'static str);

/// The parameters of each press, with the Python examples' defaults.
pub fn parameters(kind: PressKind) -> &'static [Param] {
    match kind {
        PressKind::Hydraulic => &[
            ("flow", 1.0e-3, Some("m3/s"), "pump flow Q"),
            ("area", 0.05, Some("m2"), "ram (piston) area A"),
            ("oil_volume", 0.005, Some("m3"), "oil under compression V"),
            ("bulk_modulus", 1.4e9, Some("Pa"), "oil bulk modulus beta"),
            (
                "relief_pressure",
                20.0e6,
                Some("Pa"),
                "relief valve setting: the tonnage is p_relief A",
            ),
            ("ram_mass", 2000.0, Some("kg"), "ram and moving platen m_r"),
            ("damping", 5.0e5, Some("N.s/m"), "seals and guides c"),
            (
                "substeps",
                20.0,
                None,
                "plant steps per communication step (-)",
            ),
        ],
        PressKind::Crank => &[
            ("crank_radius", 0.10, Some("m"), "crank radius r"),
            ("rod_length", 0.50, Some("m"), "connecting rod l"),
            (
                "strokes_per_minute",
                20.0,
                Some("1/min"),
                "strokes per minute at no load",
            ),
            (
                "inertia",
                3.0e4,
                Some("kg.m2"),
                "flywheel inertia referred to the crankshaft I",
            ),
            ("rated_force", 1.2e6, Some("N"), "rated tonnage"),
            (
                "rated_angle",
                20.0 * PI / 180.0,
                Some("rad"),
                "rated angle before bottom dead centre",
            ),
            (
                "shut_height",
                0.040,
                Some("m"),
                "billet height at bottom dead centre",
            ),
            (
                "billet_height",
                0.060,
                Some("m"),
                "billet height when the co-simulation starts",
            ),
            (
                "ram_gap",
                0.150,
                Some("m"),
                "ram above the billet when the co-simulation starts",
            ),
            (
                "end_angle",
                15.0 * PI / 180.0,
                Some("rad"),
                "after bottom dead centre, where the cycle ends",
            ),
        ],
        PressKind::Hammer => &[
            ("ram_mass", 200.0, Some("kg"), "ram mass m"),
            (
                "impact_speed",
                5.0,
                Some("m/s"),
                "speed v0 at each blow's start",
            ),
            (
                "target_height",
                0.045,
                Some("m"),
                "billet height that ends the forging",
            ),
            (
                "gap",
                1.0e-3,
                Some("m"),
                "ram backed off above the billet between blows",
            ),
            (
                "lift_speed",
                1.0,
                Some("m/s"),
                "speed of the lift between blows",
            ),
            ("max_blows", 20.0, None, "most blows (-)"),
        ],
        PressKind::Screw => &[
            (
                "inertia",
                40.0,
                Some("kg.m2"),
                "inertia of flywheel, screw and ram referred to the screw I",
            ),
            ("lead", 0.25, Some("m"), "screw lead p, ram travel per turn"),
            ("omega", 12.0, Some("rad/s"), "flywheel speed at contact"),
        ],
    }
}

/// The parameter every press has: how many copies of the forging FMU's model make the whole
/// workpiece. A 3D quarter model (symmetry planes x = 0 and y = 0, the ram along z) gives the
/// force and work of a quarter of the billet; the ram feels four times that. `rkforge ssp`
/// binds it from the scene's symmetry planes ([`model_copies`]).
pub const MODEL_COPIES: Param = (
    "model_copies",
    1.0,
    None,
    "copies of the forging FMU's model in the whole workpiece (4 for a quarter model, 2 for a half): the ram feels this times the forging FMU's ram.force_N (-)",
);

/// How many copies of a model with symmetry planes normal to the coordinate axes
/// `plane_axes` (0 = x, 1 = y, 2 = z) make the whole workpiece as the tool moving along
/// `axis` feels it: a plane parallel to the axis doubles the tool's force (its mirror image
/// presses the same tool), a plane across it does not (its mirror image presses a mirrored
/// tool). A plane neither along nor across the axis has no such factor.
///
/// # Errors
///
/// The plane named by its axis when the tool's axis is oblique to it.
pub fn model_copies(plane_axes: &[usize], axis: [f64; 3]) -> Result<f64, String> {
    let length = axis.iter().map(|a| a * a).sum::<f64>().sqrt();
    let mut copies = 1.0;
    for &k in plane_axes {
        let across = axis[k].abs() / length;
        if across <= 1e-12 {
            copies *= 2.0;
        } else if across < 1.0 - 1e-12 {
            return Err(format!(
                "the symmetry plane {} = 0 is neither along nor across the tool's axis {axis:?}: \
                 the whole workpiece's force on the tool is not a multiple of the model's",
                ["x", "y", "z"][k]
            ));
        }
    }
    Ok(copies)
}

/// The outputs of each press besides `ram.velocity_m_per_s` and `finished`: name, unit,
/// description; those without a unit are flags and counts (`discrete`).
pub fn outputs(kind: PressKind) -> &'static [(&'static str, Option<&'static str>, &'static str)] {
    match kind {
        PressKind::Hydraulic => &[("pressure_Pa", Some("Pa"), "cylinder pressure")],
        PressKind::Crank => &[
            (
                "crank_angle_rad",
                Some("rad"),
                "crank angle from top dead centre",
            ),
            ("crank_speed_rad_per_s", Some("rad/s"), "crank speed"),
            (
                "flywheel_energy_J",
                Some("J"),
                "kinetic energy of the flywheel",
            ),
            (
                "allowed_force_N",
                Some("N"),
                "the press's load limit at the crank angle",
            ),
            (
                "overload",
                None,
                "1 once the forging force exceeded the allowed force, else 0",
            ),
        ],
        PressKind::Hammer => &[("blow", None, "number of the blow under way (-)")],
        PressKind::Screw => &[
            ("flywheel_speed_rad_per_s", Some("rad/s"), "flywheel speed"),
            (
                "flywheel_energy_J",
                Some("J"),
                "kinetic energy of the flywheel",
            ),
        ],
    }
}

/// The forging outputs a press reads.
const INPUTS: [(&str, &str, &str); 4] = [
    ("ram.force_N", "N", "force of the workpiece on the ram along the ram's axis (the forging FMU's ram.force_N; negative while pressing)"),
    ("ram.stroke_m", "m", "ram displacement along its axis (the forging FMU's ram.stroke_m)"),
    ("ram.tool_work_J", "J", "work the ram delivered to the workpiece (the forging FMU's energy.tool_work)"),
    ("workpiece.height_m", "m", "workpiece height (the forging FMU's workpiece.height_m)"),
];

/// The variable table of a press: inputs, `ram.velocity_m_per_s`, its outputs, its parameters,
/// `model_copies` starting at `copies` (1 for a forging FMU of the whole workpiece).
pub fn variable_table(kind: PressKind, copies: f64) -> Vec<Variable> {
    let mut t = Vec::new();
    let mut push = |name: String, causality, variability, kind, unit, description: String| {
        let value_reference = t.len() as u32;
        t.push(Variable {
            name,
            value_reference,
            causality,
            variability,
            kind,
            unit,
            description,
            binding: Binding::Press(value_reference as usize),
        });
    };
    for (name, unit, d) in INPUTS {
        push(
            name.into(),
            Causality::Input,
            Variability::Continuous,
            Kind::Real(Some(0.0)),
            Some(unit),
            d.into(),
        );
    }
    push(
        "ram.velocity_m_per_s".into(),
        Causality::Output,
        Variability::Continuous,
        Kind::Real(None),
        Some("m/s"),
        "ram velocity along the ram's axis (the forging FMU's ram.velocity_m_per_s input)".into(),
    );
    push(
        "finished".into(),
        Causality::Output,
        Variability::Discrete,
        Kind::Real(None),
        None,
        "1 once the press's cycle is over (stall, overload, end angle, target height, stopped flywheel), else 0".into(),
    );
    for (name, unit, d) in outputs(kind) {
        push(
            (*name).into(),
            Causality::Output,
            match unit {
                Some(_) => Variability::Continuous,
                None => Variability::Discrete,
            },
            Kind::Real(None),
            *unit,
            (*d).into(),
        );
    }
    let (copies_name, _, copies_unit, copies_description) = MODEL_COPIES;
    let copies = [(copies_name, copies, copies_unit, copies_description)];
    for (name, default, unit, d) in parameters(kind).iter().chain(&copies) {
        push(
            (*name).into(),
            Causality::Parameter,
            Variability::Fixed,
            Kind::Real(Some(*default)),
            *unit,
            (*d).into(),
        );
    }
    t
}

/// A press's model description header.
pub fn header(kind: PressKind, model_identifier: &str) -> xml::Header {
    let name = format!("{kind:?}").to_lowercase();
    xml::Header {
        model_name: format!("{name}_press"),
        model_identifier: model_identifier.to_string(),
        guid: xml::guid(&format!("rkforge press {name}")),
        description: format!("rkforge {name} press plant (examples/presses/{name}.py)"),
        stop_time: 1.0,
        step_size: 1.0e-4,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::xml3;

    /// Every press's variables carry an SI unit, but for its counts and flags; the FMI 2.0
    /// and 3.0 documents write each unit with its base units (an unknown unit is an error).
    #[test]
    fn every_quantity_of_a_press_has_a_unit_with_its_base_units() {
        let dimensionless = [
            "finished",
            "overload",
            "blow",
            "substeps",
            "max_blows",
            "model_copies",
        ];
        for kind in [
            PressKind::Hydraulic,
            PressKind::Crank,
            PressKind::Hammer,
            PressKind::Screw,
        ] {
            let vars = variable_table(kind, 1.0);
            for v in &vars {
                let counted = dimensionless.contains(&v.name.as_str());
                assert_eq!(v.unit.is_none(), counted, "{kind:?} {}", v.name);
                // The outputs that are flags and counts change in steps.
                let discrete = counted && v.causality == Causality::Output;
                assert_eq!(
                    v.variability == Variability::Discrete,
                    discrete,
                    "{kind:?} {}",
                    v.name
                );
            }
            let text = xml::write(&header(kind, "press"), &vars).unwrap();
            let back = xml::read(&text).unwrap();
            for v in vars.iter().filter_map(|v| v.unit) {
                assert!(back.units.iter().any(|u| u == v), "{kind:?} {v}");
            }
            let text3 = xml3::write(&header(kind, "press"), &vars, vars.len() as u32).unwrap();
            for doc in [&text, &text3] {
                assert!(
                    doc.contains(r#"name="finished" valueReference"#)
                        && doc.contains(r#"causality="output" variability="discrete""#),
                    "{doc}"
                );
            }
        }
        let crank = xml::write(
            &header(PressKind::Crank, "press"),
            &variable_table(PressKind::Crank, 1.0),
        )
        .unwrap();
        assert!(
            crank.contains(r#"<Unit name="1/min">"#)
                && crank.contains(r#"<BaseUnit s="-1" factor="0.016666666666666666"/>"#),
            "{crank}"
        );
    }

    /// A unit without base units is refused, naming it and a variable that uses it.
    #[test]
    fn an_unknown_unit_is_refused_by_name() {
        let mut vars = variable_table(PressKind::Screw, 1.0);
        vars[0].unit = Some("furlong");
        let e = xml::write(&header(PressKind::Screw, "press"), &vars).unwrap_err();
        assert!(e.contains("furlong") && e.contains(&vars[0].name), "{e}");
    }

    #[test]
    fn a_plane_along_the_axis_doubles_the_force_and_one_across_it_does_not() {
        let down = [0.0, 0.0, -1.0];
        assert_eq!(model_copies(&[], down), Ok(1.0));
        assert_eq!(model_copies(&[0], down), Ok(2.0));
        assert_eq!(model_copies(&[0, 1], down), Ok(4.0));
        // A box's z_min face on a symmetry plane: its mirror image is pressed by a mirrored
        // ram, not by this one.
        assert_eq!(model_copies(&[0, 1, 2], down), Ok(4.0));
        assert_eq!(model_copies(&[1], [2.0, 0.0, 0.0]), Ok(2.0));
        let oblique = model_copies(&[0], [1.0, 0.0, -1.0]).unwrap_err();
        assert!(oblique.contains("x = 0"), "{oblique}");
    }

    #[test]
    fn every_press_has_model_copies_at_the_start_given() {
        for kind in [
            PressKind::Hydraulic,
            PressKind::Crank,
            PressKind::Hammer,
            PressKind::Screw,
        ] {
            let table = variable_table(kind, 4.0);
            let copies = table.iter().find(|v| v.name == "model_copies").unwrap();
            assert_eq!(copies.causality, Causality::Parameter);
            assert_eq!(copies.kind, Kind::Real(Some(4.0)));
        }
    }
}
