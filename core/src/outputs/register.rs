//! The register itself: every output of a run, section by section, in the order of
//! `history.csv`'s columns. Forces are for the whole ring in axisymmetry and per
//! `model.depth_m` of depth in plane strain, as are energies and heat.

use super::{force_mean, mean_contact_pressure, Body, Output, Read, Sample, Shown, When};
use crate::math::Real;
use crate::scene::Edge;
use crate::solver::Simulation;

/// The register: its sections in order, each of outputs of one kind.
pub static REGISTER: [&[Output]; 11] = [
    &TIME,
    &TOOLS,
    &FILL,
    &WORKPIECE,
    &FACES,
    &ENERGY,
    &ENERGY_RUN,
    &THERMAL,
    &TOOL_HEAT,
    &PARTICLE_FIELDS,
    &POINT_FIELDS,
];

/// The instant.
const TIME: [Output; 2] = time();

/// The instant, in either dimension.
pub(super) const fn time<S: Body>() -> [Output<S>; 2] {
    [
        scalar::<S>("", "time_s", "s", "simulation time", |s| s.time_now())
            .showing(Shown::HISTORY_ONLY),
        scalar::<S>(
            "",
            "dt_s",
            "s",
            "length of the last step (0 before the first)",
            |s| s.last_step(),
        )
        .showing(Shown::NOT_IN_SUMMARY),
    ]
}

/// Each tool.
const TOOLS: [Output; 12] = [
    tool::<Simulation>(
        "stroke_m",
        "m",
        "displacement of tool {tool} along its axis",
        |s, k| s.tools()[k].state.stroke,
    ),
    tool::<Simulation>(
        "velocity_m_per_s",
        "m/s",
        "velocity of tool {tool} along its axis during the last step",
        |s, k| s.tools()[k].state.velocity,
    )
    .showing(Shown::NOT_IN_FMU),
    tool::<Simulation>(
        "force_N",
        "N",
        "force of the workpiece on tool {tool} along its axis (positive pushing it along +axis)",
        |s, k| s.tools()[k].axial_force(),
    )
    .showing(Shown::NOT_IN_SUMMARY),
    mean_force(),
    tool::<Simulation>(
        "force_x_N",
        "N",
        "x part of the force of the workpiece on tool {tool}",
        |s, k| s.tools()[k].state.force[0],
    )
    .showing(Shown::NOT_IN_SUMMARY),
    tool::<Simulation>(
        "force_y_N",
        "N",
        "y part of the force of the workpiece on tool {tool}",
        |s, k| s.tools()[k].state.force[1],
    )
    .showing(Shown::NOT_IN_SUMMARY),
    tool::<Simulation>(
        "contact_fraction",
        "1",
        "share of tool {tool}'s length that the workpiece touches",
        |s, k| s.contact_fraction(k),
    ),
    tool::<Simulation>(
        "pressure_mean_Pa",
        "Pa",
        "mean contact pressure on tool {tool}: the normal contact force over the contact area",
        |s, k| mean_contact_pressure(s, k),
    ),
    tool::<Simulation>(
        "contact_length_m",
        "m",
        "length of the workpiece's surface in contact with tool {tool}",
        |s, k| s.contact_length(k),
    )
    .showing(Shown::NOT_IN_HISTORY),
    impulse(),
    work(),
    tool::<Simulation>(
        "peak_force_N",
        "N",
        "largest magnitude of the force on tool {tool} so far",
        |s, k| s.tools()[k].state.peak_force,
    )
    .showing(Shown::NOT_IN_HISTORY),
];

/// The force of the workpiece on a tool along its axis averaged since the sample before
/// ([`force_mean`]), in either dimension.
pub(super) const fn mean_force<S: Body>() -> Output<S> {
    tool::<S>(
        "force_mean_N",
        "N",
        "force of the workpiece on tool {tool} along its axis averaged over the interval since the sample before (history.csv's row before, the FMU's communication step, the ROS node's or the recording's sample before, Python's last sample()): the change of impulse_N_s over the change of time",
        force_mean::<S>,
    )
    .showing(Shown::NOT_IN_SUMMARY)
}

/// A tool's impulse since the start ([`crate::tools::Account::impulse`]), in either
/// dimension.
pub(super) const fn impulse<S: Body>() -> Output<S> {
    tool::<S>(
        "impulse_N_s",
        "N.s",
        "impulse of the workpiece's force on tool {tool} along its axis since the start: force_N times each step's corrector step, summed (the momentum the workpiece gave up to the tool)",
        |s, k| s.tool_accounts()[k].impulse,
    )
}

/// The work of a tool on the workpiece since the start ([`crate::tools::Account::work`]),
/// in either dimension.
pub(super) const fn work<S: Body>() -> Output<S> {
    tool::<S>(
        "work_J",
        "J",
        "work of tool {tool} on the workpiece since the start (positive while it presses); the tools' sum is energy.tool_work_J",
        |s, k| s.tool_accounts()[k].work,
    )
}

/// Each fill point of a tool (die fill).
const FILL: [Output; 1] = [filled()];

/// Whether a fill point of a tool has been reached, in either dimension.
pub(super) const fn filled<S: Body>() -> Output<S> {
    Output {
        name: "filled",
        group: "",
        unit: "1",
        description:
            "1 once the material has reached point {point} of tool {tool} (die fill), else 0",
        when: When::Always,
        shown: Shown::NOT_IN_SUMMARY,
        discrete: true,
        read: Read::FillPoint(|s, i| match s.fill_state()[i] {
            Some(_) => 1.0,
            None => 0.0,
        }),
    }
}

/// The workpiece as a whole.
const WORKPIECE: [Output; 15] = [
    scalar::<Simulation>(
        "workpiece",
        "x_min_m",
        "m",
        "least x (r) of the particles",
        |s| s.extents().x[0],
    )
    .showing(Shown::NOT_IN_SUMMARY),
    scalar::<Simulation>(
        "workpiece",
        "x_max_m",
        "m",
        "largest x (r) of the particles",
        |s| s.extents().x[1],
    )
    .showing(Shown::NOT_IN_SUMMARY),
    scalar::<Simulation>(
        "workpiece",
        "y_min_m",
        "m",
        "least y (z) of the particles",
        |s| s.extents().y[0],
    )
    .showing(Shown::NOT_IN_SUMMARY),
    scalar::<Simulation>(
        "workpiece",
        "y_max_m",
        "m",
        "largest y (z) of the particles",
        |s| s.extents().y[1],
    )
    .showing(Shown::NOT_IN_SUMMARY),
    scalar::<Simulation>(
        "workpiece",
        "radius_m",
        "m",
        "largest radius of the workpiece",
        |s| s.extents().x[1],
    )
    .present(When::Axisymmetric),
    scalar::<Simulation>(
        "workpiece",
        "width_m",
        "m",
        "width of the workpiece",
        |s| {
            let x = s.extents();
            x.x[1] - x.x[0]
        },
    )
    .present(When::PlaneStrain),
    scalar::<Simulation>("workpiece", "height_m", "m", "height of the workpiece", |s| {
        let x = s.extents();
        x.y[1] - x.y[0]
    }),
    scalar::<Simulation>(
        "workpiece",
        "volume_change_rel",
        "1",
        "relative change of the volume its outline encloses",
        |s| s.volume() / s.reference_volume() - 1.0,
    ),
    scalar::<Simulation>(
        "workpiece",
        "integrated_volume_change_rel",
        "1",
        "relative change of the integration points' own volume, sum J_p w_p",
        |s| s.integrated_volume_change(),
    ),
    scalar::<Simulation>(
        "workpiece",
        "max_plastic_strain",
        "1",
        "largest equivalent plastic strain",
        |s| s.max_plastic_strain(),
    ),
    scalar::<Simulation>(
        "workpiece",
        "max_penetration_rel",
        "1",
        "deepest a particle lies inside a tool, in smallest particle spacings",
        |s| s.penetration().tools_m / s.min_spacing(),
    )
    .showing(Shown::NOT_IN_SUMMARY),
    scalar::<Simulation>(
        "workpiece",
        "beyond_symmetry_rel",
        "1",
        "deepest a particle lies beyond a symmetry plane or the axis, in smallest particle spacings",
        |s| s.penetration().planes_m / s.min_spacing(),
    )
    .showing(Shown::NOT_IN_SUMMARY),
    scalar::<Simulation>(
        "workpiece",
        "inside_itself_rel",
        "1",
        "deepest a surface particle lies inside another part of the workpiece, in smallest particle spacings",
        |s| s.penetration().itself_m / s.min_spacing(),
    )
    .showing(Shown::NOT_IN_SUMMARY),
    scalar::<Simulation>(
        "workpiece",
        "boundary_crossings",
        "1",
        "crossings of the boundary's segments (0: the surface does not pass through itself)",
        |s| s.penetration().crossings,
    )
    .showing(Shown::NOT_IN_SUMMARY)
    .discrete(),
    scalar::<Simulation>(
        "workpiece",
        "laps",
        "1",
        "how many laps (folds of the surface onto itself between points apart along it) formed so far",
        |s| s.lap_count() as Real,
    )
    .showing(Shown::NOT_IN_SUMMARY)
    .discrete(),
];

/// Each followed face of the workpiece (`output.faces`): the bounds of the particles that
/// started on an edge.
const FACES: [Output; 4] = [
    face(
        "x_min_m",
        "least x (r) of the particles that started on edge {face}",
        |s, e| s.face_extents(e).x[0],
    ),
    face(
        "x_max_m",
        "largest x (r) of the particles that started on edge {face}",
        |s, e| s.face_extents(e).x[1],
    ),
    face(
        "y_min_m",
        "least y (z) of the particles that started on edge {face}",
        |s, e| s.face_extents(e).y[0],
    ),
    face(
        "y_max_m",
        "largest y (z) of the particles that started on edge {face}",
        |s, e| s.face_extents(e).y[1],
    ),
];

/// The energy account.
const ENERGY: [Output; 10] = energy();

/// The energy account, in either dimension.
pub(super) const fn energy<S: Body>() -> [Output<S>; 10] {
    [
    scalar::<S>(
        "energy",
        "kinetic_J",
        "J",
        "kinetic energy of the workpiece",
        |s| s.energy_now().kinetic,
    ),
    scalar::<S>(
        "energy",
        "elastic_J",
        "J",
        "elastic energy stored in the workpiece",
        |s| s.energy_now().elastic,
    ),
    scalar::<S>(
        "energy",
        "plastic_J",
        "J",
        "plastic dissipation in the workpiece",
        |s| s.energy_now().plastic,
    ),
    scalar::<S>(
        "energy",
        "internal_J",
        "J",
        "internal energy: elastic plus plastic",
        |s| s.energy_now().internal(),
    ),
    scalar::<S>(
        "energy",
        "contact_J",
        "J",
        "work of the contact forces on the workpiece since the start",
        |s| s.energy_now().contact_work,
    ),
    scalar::<S>(
        "energy",
        "tool_work_J",
        "J",
        "work delivered by the tools' motion since the start, summed over the tools",
        |s| s.energy_now().tool_work,
    ),
    scalar::<S>(
        "energy",
        "balance_error_rel",
        "1",
        "error of the energy balance over the energy exchanged",
        |s| s.energy_now().balance_error_rel(),
    ),
    scalar::<S>(
        "energy",
        "kinetic_to_internal",
        "1",
        "ratio of kinetic to internal energy (quasi-static check)",
        |s| s.energy_now().kinetic_to_internal(),
    )
    .showing(Shown::NOT_IN_SUMMARY),
    scalar::<S>(
        "energy",
        "initial_J",
        "J",
        "kinetic energy at the start",
        |s| s.energy_now().initial,
    )
    .showing(Shown::NOT_IN_HISTORY),
    scalar::<S>(
        "energy",
        "contact_interface_J",
        "J",
        "contact work less tool work: what the contact interface gained (negative: friction heat and penalty losses)",
        |s| s.energy_now().interface_gain(),
    )
    .showing(Shown::NOT_IN_HISTORY),
    ]
}

/// What the energy account of a 2D run watches besides.
const ENERGY_RUN: [Output; 2] = [kinetic_to_internal_max(), thermoelastic::<Simulation>()];

/// The largest ratio of kinetic to internal energy after the start-up, 2D or 3D.
pub(super) const fn kinetic_to_internal_max<S: Body>() -> Output<S> {
    scalar::<S>(
        "energy",
        "kinetic_to_internal_max",
        "1",
        "largest ratio of kinetic to internal energy after the start-up (quasi-static check)",
        |s| Body::kinetic_to_internal_max(&**s),
    )
    .showing(Shown::NOT_IN_HISTORY)
}

/// The elastic energy changes of temperature put in, in either dimension (a scene with
/// elasticity over temperature; summary only).
pub(super) const fn thermoelastic<S: Body>() -> Output<S> {
    scalar::<S>(
        "energy",
        "thermoelastic_J",
        "J",
        "elastic energy that changes of temperature put in (elasticity over temperature)",
        |s| s.energy_now().thermoelastic,
    )
    .showing(Shown::NOT_IN_HISTORY)
    .present(When::Thermoelastic)
}

/// The temperatures and heat of a scene with `[thermal]`, in the order of
/// [`crate::Simulation::thermal_values`].
const THERMAL: [Output; 9] = thermal_measures();

/// The thermal measures, in either dimension.
pub(super) const fn thermal_measures<S: Body>() -> [Output<S>; 9] {
    [
        thermal::<S>(
            "temperature_min_c",
            "degC",
            "least temperature of the workpiece's integration points",
            |s| measure(s, 0),
        ),
        thermal::<S>(
            "temperature_max_c",
            "degC",
            "largest temperature of the workpiece's integration points",
            |s| measure(s, 1),
        ),
        thermal::<S>(
            "temperature_mean_c",
            "degC",
            "mean temperature of the workpiece, weighted by the points' volumes",
            |s| measure(s, 2),
        ),
        thermal::<S>(
            "plastic_heat_J",
            "J",
            "heat released by plastic work since the start (Taylor-Quinney share)",
            |s| measure(s, 3),
        ),
        thermal::<S>(
            "friction_heat_J",
            "J",
            "heat made by friction at the tools since the start (the workpiece takes its share)",
            |s| measure(s, 4),
        ),
        thermal::<S>(
            "heat_content_J",
            "J",
            "heat held in the workpiece above its initial temperature",
            |s| measure(s, 5),
        ),
        thermal::<S>(
            "heat_to_tools_J",
            "J",
            "heat that has flowed from the workpiece into the tools since the start",
            |s| measure(s, 6),
        ),
        thermal::<S>(
            "heat_to_surroundings_J",
            "J",
            "heat that has left the free surface by convection and radiation since the start",
            |s| measure(s, 7),
        ),
        thermal::<S>(
            "heat_balance_rel",
            "1",
            "heat content less the heat made plus the heat lost, over the heat made and lost",
            |s| measure(s, 8),
        ),
    ]
}

/// The heat each tool takes from the workpiece.
const TOOL_HEAT: [Output; 2] = [
    tool::<Simulation>(
        "heat_flow_W",
        "W",
        "heat flow from the workpiece into tool {tool} at the last heat stage",
        |s, k| s.tool_heat_flows().map_or(Real::NAN, |f| f[k]),
    )
    .in_group("thermal")
    .present(When::HeatedTool)
    .showing(Shown::NOT_IN_SUMMARY),
    tool::<Simulation>(
        "heat_J",
        "J",
        "heat that has flowed from the workpiece into tool {tool} since the start",
        |s, k| s.tool_heat(k).unwrap_or(Real::NAN),
    )
    .in_group("thermal")
    .present(When::Thermal)
    .showing(Shown::NOT_IN_HISTORY),
];

/// Fields per particle, smoothed from the integration points with weights `|N_I| w_p`.
const PARTICLE_FIELDS: [Output; 4] = [
    particles::<Simulation>(
        "plastic_strain",
        "1",
        "equivalent plastic strain at the particles",
        |s| s.particle_fields().plastic_strain.clone(),
    ),
    particles::<Simulation>(
        "von_mises_Pa",
        "Pa",
        "von Mises stress at the particles",
        |s| s.particle_fields().von_mises.clone(),
    ),
    particles::<Simulation>(
        "temperature_c",
        "degC",
        "temperature at the particles",
        |s| s.particle_fields().temperature.clone().unwrap_or_default(),
    )
    .present(When::Thermal),
    particles::<Simulation>(
        "lap",
        "1",
        "the lap each particle took part in, numbered from 1 in the order they formed (0: none)",
        |s| s.particle_fields().lap.clone(),
    ),
];

/// Fields per integration point.
const POINT_FIELDS: [Output; 5] = [
    points::<Simulation>(
        "plastic_strain",
        "1",
        "equivalent plastic strain at the integration points",
        |s| s.point_plastic_strain(),
    ),
    points::<Simulation>(
        "von_mises_Pa",
        "Pa",
        "von Mises stress (Cauchy) at the integration points at the last stress stage",
        |s| s.point_von_mises(),
    ),
    points::<Simulation>(
        "jacobian",
        "1",
        "J = det F at the integration points at the last stress stage",
        |s| s.point_jacobian(),
    ),
    points::<Simulation>(
        "temperature_c",
        "degC",
        "temperature at the integration points",
        |s| {
            s.point_temperature()
                .map_or_else(Vec::new, <[Real]>::to_vec)
        },
    )
    .present(When::Thermal),
    points::<Simulation>(
        "plastic_strain_rate_per_s",
        "1/s",
        "plastic strain rate at the integration points at the last stress stage",
        |s| {
            s.point_plastic_strain_rate()
                .map_or_else(Vec::new, <[Real]>::to_vec)
        },
    )
    .present(When::Thermal),
];

/// The thermal measures as (name, unit, description) in the order of
/// [`crate::Simulation::thermal_values`], the unit empty for a pure number: the register's
/// `thermal.*` scalars as the FMU's variable table reads them until it reads [`REGISTER`].
pub const THERMAL_MEASURES: [(&str, &str, &str); 9] = {
    let mut m = [("", "", ""); 9];
    let mut k = 0;
    while k < m.len() {
        let o = &THERMAL[k];
        let pure = o.unit.len() == 1 && o.unit.as_bytes()[0] == b'1';
        m[k] = (o.name, if pure { "" } else { o.unit }, o.description);
        k += 1;
    }
    m
};

/// A scalar in every scene and every front end.
pub(super) const fn scalar<S: Body>(
    group: &'static str,
    name: &'static str,
    unit: &'static str,
    description: &'static str,
    read: fn(&Sample<'_, S>) -> Real,
) -> Output<S> {
    Output {
        name,
        group,
        unit,
        description,
        when: When::Always,
        shown: Shown::EVERYWHERE,
        discrete: false,
        read: Read::Scalar(read),
    }
}

/// A value per tool in every scene and every front end.
pub(super) const fn tool<S: Body>(
    name: &'static str,
    unit: &'static str,
    description: &'static str,
    read: fn(&Sample<'_, S>, usize) -> Real,
) -> Output<S> {
    Output {
        name,
        group: "",
        unit,
        description,
        when: When::Always,
        shown: Shown::EVERYWHERE,
        discrete: false,
        read: Read::Tool(read),
    }
}

/// A length per followed face, in every front end.
const fn face(
    name: &'static str,
    description: &'static str,
    read: fn(&Sample<'_>, Edge) -> Real,
) -> Output {
    Output {
        name,
        group: "workpiece",
        unit: "m",
        description,
        when: When::Always,
        shown: Shown::EVERYWHERE,
        discrete: false,
        read: Read::Face(read),
    }
}

/// A thermal measure, in a scene with `[thermal]`.
const fn thermal<S: Body>(
    name: &'static str,
    unit: &'static str,
    description: &'static str,
    read: fn(&Sample<'_, S>) -> Real,
) -> Output<S> {
    scalar::<S>("thermal", name, unit, description, read).present(When::Thermal)
}

/// Thermal measure `k` now (NaN in an isothermal scene, which has none).
fn measure<S: Body>(s: &Sample<'_, S>, k: usize) -> Real {
    s.thermal_values().map_or(Real::NAN, |v| v[k])
}

/// A field per particle.
pub(super) const fn particles<S: Body>(
    name: &'static str,
    unit: &'static str,
    description: &'static str,
    read: fn(&Sample<'_, S>) -> Vec<Real>,
) -> Output<S> {
    Output {
        name,
        group: "particles",
        unit,
        description,
        when: When::Always,
        shown: Shown::FIELD,
        discrete: false,
        read: Read::Particles(read),
    }
}

/// A field per integration point.
pub(super) const fn points<S: Body>(
    name: &'static str,
    unit: &'static str,
    description: &'static str,
    read: fn(&Sample<'_, S>) -> Vec<Real>,
) -> Output<S> {
    Output {
        name,
        group: "points",
        unit,
        description,
        when: When::Always,
        shown: Shown::FIELD,
        discrete: false,
        read: Read::Points(read),
    }
}

impl<S: Body> Output<S> {
    /// Shown as `shown` says.
    pub(super) const fn showing(mut self, shown: Shown) -> Output<S> {
        self.shown = shown;
        self
    }

    /// Present only `when`.
    pub(super) const fn present(mut self, when: When) -> Output<S> {
        self.when = when;
        self
    }

    /// In group `group`.
    pub(super) const fn in_group(mut self, group: &'static str) -> Output<S> {
        self.group = group;
        self
    }

    /// Changing only in steps: a count or a flag.
    pub(super) const fn discrete(mut self) -> Output<S> {
        self.discrete = true;
        self
    }
}
