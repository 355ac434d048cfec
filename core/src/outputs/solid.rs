//! The register of a 3D run ([`SOLID_REGISTER`]): the outputs of a [`SolidSimulation`],
//! named as the 2D register names the same figure. The time, the energy account and the
//! thermal measures are the 2D register's own sections, generic over [`Body`]; what only a
//! 3D body has (a tool's force along z, the z bounds) or reads differently (the workpiece's
//! bounds and radius over its particles, the penetration of the plane tools) is here.
//! The contact figures of a tool (`contact_area_m2`, `surface_fraction`, `pressure_mean_Pa`)
//! are over the workpiece's surface patches (`solver/solid/die_contact.rs`); the fill
//! points are 2D's section. Not in 3D yet: the particle fields (2D smooths the points'
//! values onto the particles), followed faces and laps.

use super::register::{
    energy, filled, impulse, kinetic_to_internal_max, mean_force, particles, points, scalar,
    thermal_measures, thermoelastic, time, tool, work,
};
use super::{expand, fields_of, fill_instances, At, Column, Kind, Output, Sample, Shown, When};
use crate::contact::self_contact_3d::Crossings;
use crate::math::Real;
use crate::scene::solid::SolidScene;
use crate::solver::{BodyReadings, SolidSimulation};
use std::cell::OnceCell;

/// The register of a 3D run: its sections in order, each of outputs of one kind.
pub static SOLID_REGISTER: [&[Output<SolidSimulation>]; 10] = [
    &TIME,
    &TOOLS,
    &FILL,
    &WORKPIECE,
    &ENERGY,
    &ENERGY_RUN,
    &ENERGY_THERMOELASTIC,
    &THERMAL,
    &PARTICLE_FIELDS,
    &POINT_FIELDS,
];

const TIME: [Output<SolidSimulation>; 2] = time();
const ENERGY: [Output<SolidSimulation>; 10] = energy();
const ENERGY_THERMOELASTIC: [Output<SolidSimulation>; 1] = [thermoelastic()];
const ENERGY_RUN: [Output<SolidSimulation>; 1] = [kinetic_to_internal_max()];
const THERMAL: [Output<SolidSimulation>; 9] = thermal_measures();
const FILL: [Output<SolidSimulation>; 1] = [filled()];

/// Each tool (the symmetry planes are not tools).
const TOOLS: [Output<SolidSimulation>; 15] = [
    tool::<SolidSimulation>(
        "stroke_m",
        "m",
        "displacement of tool {tool} along its axis",
        |s, k| s.tools()[k].state.stroke,
    ),
    tool::<SolidSimulation>(
        "velocity_m_per_s",
        "m/s",
        "velocity of tool {tool} along its axis during the last step",
        |s, k| s.tools()[k].state.velocity,
    )
    .showing(Shown::NOT_IN_FMU),
    tool::<SolidSimulation>(
        "force_N",
        "N",
        "force of the workpiece on tool {tool} along its axis (positive pushing it along +axis)",
        |s, k| s.tools()[k].axial_force(),
    )
    .showing(Shown::NOT_IN_SUMMARY),
    mean_force(),
    tool::<SolidSimulation>(
        "force_x_N",
        "N",
        "x part of the force of the workpiece on tool {tool}",
        |s, k| s.tools()[k].state.force[0],
    )
    .showing(Shown::NOT_IN_SUMMARY),
    tool::<SolidSimulation>(
        "force_y_N",
        "N",
        "y part of the force of the workpiece on tool {tool}",
        |s, k| s.tools()[k].state.force[1],
    )
    .showing(Shown::NOT_IN_SUMMARY),
    tool::<SolidSimulation>(
        "force_z_N",
        "N",
        "z part of the force of the workpiece on tool {tool}",
        |s, k| s.tools()[k].state.force[2],
    )
    .showing(Shown::NOT_IN_SUMMARY),
    tool::<SolidSimulation>(
        "contact_area_m2",
        "m2",
        "area of the workpiece's surface in contact with tool {tool}, projected on the tool",
        |s, k| s.contact_area(k),
    ),
    tool::<SolidSimulation>(
        "surface_fraction",
        "1",
        "share of the workpiece's surface (less its faces on symmetry planes) in contact with tool {tool}",
        |s, k| s.contact_area(k) / s.surface_area(),
    ),
    tool::<SolidSimulation>(
        "pressure_mean_Pa",
        "Pa",
        "mean contact pressure on tool {tool}: the normal contact force over the contact area",
        |s, k| {
            let area = s.contact_area(k);
            if area > 0.0 {
                s.tools()[k].state.normal_force / area
            } else {
                0.0
            }
        },
    ),
    impulse(),
    work(),
    tool::<SolidSimulation>(
        "peak_force_N",
        "N",
        "largest magnitude of the force on tool {tool} so far",
        |s, k| s.tools()[k].state.peak_force,
    )
    .showing(Shown::NOT_IN_HISTORY),
    tool::<SolidSimulation>(
        "heat_flow_W",
        "W",
        "heat flow from the workpiece into tool {tool} at the last heat stage",
        |s, k| s.tool_heat_flows().map_or(Real::NAN, |f| f[k]),
    )
    .in_group("thermal")
    .present(When::HeatedTool)
    .showing(Shown::NOT_IN_SUMMARY),
    tool::<SolidSimulation>(
        "heat_J",
        "J",
        "heat that has flowed from the workpiece into tool {tool} since the start",
        |s, k| s.tool_heat(k).unwrap_or(Real::NAN),
    )
    .in_group("thermal")
    .present(When::Thermal)
    .showing(Shown::NOT_IN_HISTORY),
];

/// The workpiece as a whole, from its particles' physical positions.
const WORKPIECE: [Output<SolidSimulation>; 14] = [
    bound("x_min_m", "least x of the particles", 0, 0),
    bound("x_max_m", "largest x of the particles", 0, 1),
    bound("y_min_m", "least y of the particles", 1, 0),
    bound("y_max_m", "largest y of the particles", 1, 1),
    bound("z_min_m", "least z of the particles", 2, 0),
    bound("z_max_m", "largest z of the particles", 2, 1),
    scalar::<SolidSimulation>(
        "workpiece",
        "radius_m",
        "m",
        "largest distance of a particle from the z axis (a Taylor bar's foot radius)",
        |s| s.readings().radius,
    ),
    scalar::<SolidSimulation>(
        "workpiece",
        "height_m",
        "m",
        "length of the workpiece along z, z_max - z_min",
        |s| s.readings().height(),
    ),
    scalar::<SolidSimulation>(
        "workpiece",
        "volume_change_rel",
        "1",
        "relative change of the volume its cells enclose through the particles' positions",
        |s| s.volume() / s.reference_volume() - 1.0,
    ),
    scalar::<SolidSimulation>(
        "workpiece",
        "integrated_volume_change_rel",
        "1",
        "relative change of the integration points' own volume, sum J_p w_p",
        |s| s.integrated_volume_change(),
    ),
    scalar::<SolidSimulation>(
        "workpiece",
        "max_plastic_strain",
        "1",
        "largest equivalent plastic strain",
        |s| s.max_plastic_strain(),
    ),
    scalar::<SolidSimulation>(
        "workpiece",
        "max_penetration_rel",
        "1",
        "deepest a particle lies inside a tool, in smallest particle spacings",
        |s| s.penetration()[0] / s.h_min(),
    )
    .showing(Shown::NOT_IN_SUMMARY),
    scalar::<SolidSimulation>(
        "workpiece",
        "beyond_symmetry_rel",
        "1",
        "deepest a particle lies beyond a symmetry plane, in smallest particle spacings",
        |s| s.penetration()[1] / s.h_min(),
    )
    .showing(Shown::NOT_IN_SUMMARY),
    scalar::<SolidSimulation>(
        "workpiece",
        "fold_crossings",
        "1",
        "crossings of the surface's faces within the kernel's support of each other (a fold's root passed through itself, which the self-contact leaves out; 0: none)",
        |s| s.fold_crossings().count as Real,
    )
    .showing(Shown::NOT_IN_SUMMARY)
    .discrete(),
];

/// A bound of the workpiece: `end` 0 (least) or 1 (largest) of coordinate `axis`.
const fn bound(
    name: &'static str,
    description: &'static str,
    axis: usize,
    end: usize,
) -> Output<SolidSimulation> {
    // The reads are fn pointers, so each bound is its own function.
    let read: fn(&Sample<'_, SolidSimulation>) -> Real = match (axis, end) {
        (0, 0) => |s| s.readings().extents[0][0],
        (0, _) => |s| s.readings().extents[0][1],
        (1, 0) => |s| s.readings().extents[1][0],
        (1, _) => |s| s.readings().extents[1][1],
        (_, 0) => |s| s.readings().extents[2][0],
        _ => |s| s.readings().extents[2][1],
    };
    // The summary has the bounds as ranges (`workpiece.x_range_m`), as in 2D.
    scalar::<SolidSimulation>("workpiece", name, "m", description, read)
        .showing(Shown::NOT_IN_SUMMARY)
}

/// Fields per particle.
const PARTICLE_FIELDS: [Output<SolidSimulation>; 3] = [
    particles::<SolidSimulation>("x_m", "m", "x of the particles", |s| coordinate(s, 0)),
    particles::<SolidSimulation>("y_m", "m", "y of the particles", |s| coordinate(s, 1)),
    particles::<SolidSimulation>("z_m", "m", "z of the particles", |s| coordinate(s, 2)),
];

/// Coordinate `axis` of each particle's physical position (m).
fn coordinate(s: &Sample<'_, SolidSimulation>, axis: usize) -> Vec<Real> {
    s.positions().iter().map(|p| p[axis]).collect()
}

/// Fields per integration point.
const POINT_FIELDS: [Output<SolidSimulation>; 5] = [
    points::<SolidSimulation>(
        "plastic_strain",
        "1",
        "equivalent plastic strain at the integration points",
        |s| s.point_plastic_strain(),
    ),
    points::<SolidSimulation>(
        "von_mises_Pa",
        "Pa",
        "von Mises stress (Cauchy) at the integration points at the last stress stage",
        |s| s.point_von_mises(),
    ),
    points::<SolidSimulation>(
        "jacobian",
        "1",
        "J = det F at the integration points at the last stress stage",
        |s| s.point_jacobian(),
    ),
    points::<SolidSimulation>(
        "temperature_c",
        "degC",
        "temperature at the integration points",
        |s| {
            s.point_temperature()
                .map_or_else(Vec::new, <[Real]>::to_vec)
        },
    )
    .present(When::Thermal),
    points::<SolidSimulation>(
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

/// The measures a sample of a 3D simulation takes once.
#[derive(Default)]
pub struct SolidCache {
    positions: OnceCell<Vec<[Real; 3]>>,
    readings: OnceCell<BodyReadings>,
    penetration: OnceCell<[Real; 2]>,
    crossings: OnceCell<Crossings>,
}

impl<'a> Sample<'a, SolidSimulation> {
    /// The simulation now with what [`SolidSimulation::measure_sample`] measured: the
    /// particles' physical `positions` (m) and the penetration `p` (m, in the tools and
    /// beyond the symmetry planes).
    pub fn measured(
        sim: &'a SolidSimulation,
        positions: Vec<[Real; 3]>,
        p: [Real; 2],
    ) -> Sample<'a, SolidSimulation> {
        let sample = Sample::new(sim);
        sample.cache.positions.get_or_init(|| positions);
        sample.cache.penetration.get_or_init(|| p);
        sample
    }

    /// The particles' physical positions (m, [`SolidSimulation::positions`]), formed when
    /// first read.
    pub fn positions(&self) -> &[[Real; 3]] {
        self.cache.positions.get_or_init(|| self.sim.positions())
    }

    /// The workpiece's radius and bounds ([`SolidSimulation::readings`]).
    pub fn readings(&self) -> BodyReadings {
        *self
            .cache
            .readings
            .get_or_init(|| BodyReadings::of(self.positions()))
    }

    /// The workpiece's volume ([`SolidSimulation::volume`], m^3).
    pub fn volume(&self) -> Real {
        self.sim.volume_at(self.positions())
    }

    /// The workpiece's surface area ([`SolidSimulation::surface_area`], m^2).
    pub fn surface_area(&self) -> Real {
        self.sim.surface_area_at(self.positions())
    }

    /// The area in contact with scene tool `t` ([`SolidSimulation::contact_area`], m^2).
    pub fn contact_area(&self, t: usize) -> Real {
        self.sim.contact_area_at(t, self.positions())
    }

    /// The deepest particle in a tool and beyond a symmetry plane (m), measured when first
    /// read ([`SolidSimulation::penetration_now`]).
    pub fn penetration(&self) -> [Real; 2] {
        *self.cache.penetration.get_or_init(|| {
            let [tools, planes] = self.sim.penetration_at(self.positions());
            [tools.0, planes.0]
        })
    }

    /// The crossings of the surface's faces within the support of each other, measured
    /// when first read ([`SolidSimulation::fold_crossings_at`]).
    pub fn fold_crossings(&self) -> Crossings {
        *self
            .cache
            .crossings
            .get_or_init(|| self.sim.fold_crossings_at(self.positions()))
    }
}

impl When {
    /// Whether a 3D scene has the output at `at`: every scene, one with `[thermal]`, one
    /// with elasticity over temperature, a tool with a heat transfer coefficient (constant
    /// or over pressure) in one; what only 2D scenes have never.
    pub fn holds_solid(self, scene: &SolidScene, at: At) -> bool {
        match self {
            When::Always => true,
            When::Thermal => scene.thermal.is_some(),
            When::Thermoelastic => scene
                .thermal
                .as_ref()
                .is_some_and(|t| t.thermoelastic().is_some()),
            When::HeatedTool => {
                scene.thermal.is_some()
                    && matches!(at, At::Tool(k) if scene.tools[k].heat_contact().transfers_heat())
            }
            _ => false,
        }
    }
}

impl Column<SolidSimulation> {
    /// The description with the tool's name put in.
    pub fn description(&self, scene: &SolidScene) -> String {
        match self.at {
            At::Tool(k) => self
                .output
                .description
                .replace("{tool}", &scene.tools[k].name),
            At::FillPoint { tool, within, .. } => {
                let t = &scene.tools[tool];
                self.output
                    .description
                    .replace("{tool}", &t.name)
                    .replace("{point}", &t.fill_points[within].name)
            }
            _ => self.output.description.to_string(),
        }
    }
}

/// Every column of a 3D `scene`, section by section in register order, each section tool
/// by tool.
pub fn solid_columns(scene: &SolidScene) -> Vec<Column<SolidSimulation>> {
    expand(
        &SOLID_REGISTER,
        |kind| match kind {
            Kind::Scalar => vec![(At::Whole, String::new())],
            Kind::PerTool => (0..scene.tools.len())
                .map(|k| (At::Tool(k), scene.tools[k].name.clone()))
                .collect(),
            Kind::PerFillPoint => fill_instances(
                scene
                    .tools
                    .iter()
                    .map(|t| (&t.name[..], t.fill_points.iter().map(|p| &p.name[..]))),
            ),
            _ => Vec::new(),
        },
        |when, at| when.holds_solid(scene, at),
    )
}

/// Every field present in a 3D `scene`, in register order.
pub fn solid_fields(
    scene: &SolidScene,
) -> impl Iterator<Item = &'static Output<SolidSimulation>> + '_ {
    fields_of(&SOLID_REGISTER, move |when| {
        when.holds_solid(scene, At::Whole)
    })
}
