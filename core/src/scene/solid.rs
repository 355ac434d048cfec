//! Three-dimensional scenes (`model.kinematics = "3d"`): a box or a cylinder of particles,
//! rigid tools (planes, or dies from STL files read and checked here, [`crate::stl`]) and
//! the symmetry planes of a half, quarter or eighth model, with what each must be
//! ([`SolidScene::validate`]). The sections a 3D scene shares with a 2D one
//! (`[material]`, `[time]`, `[checks]`, `[[reference]]`) are the same types with the same
//! checks; what depends on the dimension (the workpiece, the tools, the discretisation's
//! support) is here. [`SceneFile::from_file`] reads either kind and says which.
//!
//! `[thermal]` is 2D's throughout: plastic and friction heat, conduction, the heat to the
//! tools and the surroundings, and elasticity over temperature.

use super::{
    Checks, HeatContact, IntegrationRule, MaterialSpec, Motion, Reference, Scene, SelfContactSpec,
    ThermalSpec, TimeSpec,
};
use crate::error::Result;
use crate::friction::Friction;
use crate::math::Real;
use crate::stl::{LengthUnit, TriangleMesh};
use crate::validation::{self, is_name, pos};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The kinematics of a 3D scene: the one value `"3d"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub enum ThreeD {
    /// Three dimensions.
    #[serde(rename = "3d")]
    ThreeD,
}

/// The `[model]` section of a 3D scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidModel {
    /// `"3d"`.
    pub kinematics: ThreeD,
}

/// Which part of a cylinder's cross-section is modelled, the rest held by symmetry planes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum CylinderPart {
    /// The whole cylinder.
    Full,
    /// `x >= 0`, the plane `x = 0` a symmetry plane.
    Half,
    /// `x, y >= 0`, the planes `x = 0` and `y = 0` symmetry planes.
    #[default]
    Quarter,
}

/// A face of a box workpiece.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BoxFace {
    /// The face at the smallest x.
    XMin,
    /// The face at the smallest y.
    YMin,
    /// The face at the smallest z.
    ZMin,
}

impl BoxFace {
    /// The coordinate axis normal to the face.
    pub fn axis(self) -> usize {
        match self {
            BoxFace::XMin => 0,
            BoxFace::YMin => 1,
            BoxFace::ZMin => 2,
        }
    }
}

/// The shape of a 3D workpiece and its particles, as the solver reads it
/// ([`SolidWorkpiece::shape`]).
#[derive(Debug, Clone, PartialEq)]
pub enum SolidShape {
    /// A cylinder along z from `z = 0`, its axis on `x = y = 0`, with particles on an O-grid
    /// that follows its round surface ([`crate::cylinder_grid`]).
    Cylinder {
        /// Radius (m).
        radius_m: Real,
        /// Length along z (m).
        length_m: Real,
        /// The part modelled.
        part: CylinderPart,
        /// `[core cells per side (even), ring layers, cells along the axis]`.
        cells: [usize; 3],
        /// The square core's half side over the radius (-).
        core_ratio: Real,
    },
    /// A box `origin + [0, size]` on a regular lattice of particles.
    Box {
        /// The corner of least x, y, z (m).
        origin_m: [Real; 3],
        /// Extents along x, y, z (m).
        size_m: [Real; 3],
        /// Particles along x, y, z.
        particles: [usize; 3],
        /// Faces on symmetry planes.
        symmetry: Vec<BoxFace>,
    },
}

/// Which shape a 3D workpiece has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    /// A cylinder along z (keys `radius_m`, `length_m`, `cells`, `part`, `core_ratio`).
    Cylinder,
    /// A box (keys `origin_m`, `size_m`, `particles`, `symmetry`).
    Box,
}

/// The `[workpiece]` section of a 3D scene: one table whose keys depend on the `shape`
/// (each key checked against it, so a wrong or missing one is named with its line).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidWorkpiece {
    /// `cylinder` or `box`.
    pub shape: ShapeKind,
    /// Cylinder: radius (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_m: Option<Real>,
    /// Cylinder: length along z from `z = 0` (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length_m: Option<Real>,
    /// Cylinder: the part modelled (default `quarter`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub part: Option<CylinderPart>,
    /// Cylinder: `[core cells per side (even), ring layers, cells along the axis]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cells: Option<[usize; 3]>,
    /// Cylinder: the square core's half side over the radius (-), default 0.55.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub core_ratio: Option<Real>,
    /// Box: the corner of least x, y, z (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin_m: Option<[Real; 3]>,
    /// Box: extents along x, y, z (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size_m: Option<[Real; 3]>,
    /// Box: particles along x, y, z (each at least 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub particles: Option<[usize; 3]>,
    /// Box: faces on symmetry planes (`x_min`, `y_min`, `z_min`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub symmetry: Vec<BoxFace>,
    /// Uniform initial velocity (m/s).
    #[serde(default)]
    pub initial_velocity_m_per_s: [Real; 3],
}

impl SolidWorkpiece {
    /// The shape with its keys (defaults filled in); `None` when a key the shape needs is
    /// missing (which the validation reports).
    pub fn shape(&self) -> Option<SolidShape> {
        Some(match self.shape {
            ShapeKind::Cylinder => SolidShape::Cylinder {
                radius_m: self.radius_m?,
                length_m: self.length_m?,
                part: self.part.unwrap_or_default(),
                cells: self.cells?,
                core_ratio: self.core_ratio.unwrap_or(0.55),
            },
            ShapeKind::Box => SolidShape::Box {
                origin_m: self.origin_m?,
                size_m: self.size_m?,
                particles: self.particles?,
                symmetry: self.symmetry.clone(),
            },
        })
    }
}

/// The `[discretization]` section of a 3D scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidDiscretization {
    /// `q4` (2 x 2 x 2 Gauss per cell), `q2` (its four alternate points, weight 2), `scni`
    /// (one point per particle over its nodal domain).
    #[serde(default)]
    pub integration: IntegrationRule,
    /// Kernel support radius in particle spacings (-): of the lattice spacing for a box, of
    /// each particle's own cells' extent for a cylinder.
    #[serde(default = "default_support")]
    pub support: Real,
    /// Re-reference the kernel on the current configuration when a point's largest
    /// principal stretch since the last reference reaches this value (-), as in 2D
    /// (`solver/solid/rereference.rs`). Absent: the Lagrangian kernel throughout.
    #[serde(default)]
    pub rereference_stretch: Option<Real>,
    /// With `integration = "scni"`: the coefficient `c` (-) of the stabilization of nodal
    /// integration over the octants of each nodal domain, as in 2D
    /// ([`super::discretization::Discretization::scni_stabilization`]). Absent or 0: plain
    /// SCNI.
    #[serde(default)]
    pub scni_stabilization: Option<Real>,
}

fn default_support() -> Real {
    2.0
}

impl Default for SolidDiscretization {
    fn default() -> Self {
        SolidDiscretization {
            integration: IntegrationRule::default(),
            support: default_support(),
            rereference_stretch: None,
            scni_stabilization: None,
        }
    }
}

/// The surface of a 3D tool.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ToolShape {
    /// A plane (keys `point_m`, `normal`): the tool fills the half-space behind it.
    #[default]
    Plane,
    /// A closed triangle surface from an STL file (keys `file`, `unit`): the tool is the
    /// solid it encloses ([`crate::stl`]).
    Stl,
    /// A solid circular cylinder (keys `center_m`, `axis_direction`, `radius_m`, and
    /// `length_m` for flat end caps, else unbounded along its axis;
    /// [`crate::solid_tool::Cylinder`]).
    Cylinder,
}

/// A rigid 3D tool: the half-space behind the plane through `point_m` with the normal
/// `normal` (pointing to the workpiece's side), the solid cylinder of radius `radius_m`
/// about the line through `center_m` along `axis_direction` (`shape = "cylinder"`, capped
/// at `center_m +- length_m / 2` along it when `length_m` is given), or the solid an STL
/// file's closed surface encloses (`shape = "stl"`, `file`), moving along `axis`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidToolSpec {
    /// Name, used in outputs (`<name>.force_N`).
    pub name: String,
    /// `plane` (the default), `cylinder` or `stl`.
    #[serde(default, skip_serializing_if = "is_plane")]
    pub shape: ToolShape,
    /// A point of the plane with the tool at its start (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point_m: Option<[Real; 3]>,
    /// Unit normal, pointing out of the tool towards the workpiece.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<[Real; 3]>,
    /// Cylinder: the point of its axis at the middle of its length with the tool at its
    /// start (any point of the axis when unbounded; m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center_m: Option<[Real; 3]>,
    /// Cylinder: unit direction of its axis (either sense).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis_direction: Option<[Real; 3]>,
    /// Cylinder: radius (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_m: Option<Real>,
    /// Cylinder: length between its flat end caps (m), centred on `center_m`; absent:
    /// unbounded along its axis (a roll or a bar longer than the workpiece is wide).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length_m: Option<Real>,
    /// STL: the file (binary or ASCII), relative to the scene file's folder; its
    /// coordinates place the die at its start, its triangles wound with normals out of the
    /// die.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// STL: the unit of the file's coordinates, `m` (the default) or `mm`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<LengthUnit>,
    /// Unit direction along which stroke, velocity and force are measured.
    pub axis: [Real; 3],
    /// Motion along the axis.
    pub motion: Motion,
    /// Friction law of the interface (as in 2D); default frictionless.
    #[serde(default)]
    pub friction: Friction,
    /// Whether a particle may leave the tool again (the default); `false` is the wall of
    /// the finite-element benchmarks, holding every particle that reached it.
    #[serde(default = "default_separation")]
    pub separation: bool,
    /// The tool's temperature (degrees C) in a scene with `[thermal]`; it stays at it (as
    /// in 2D, [`super::ToolSpec::temperature_c`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temperature_c: Option<Real>,
    /// Heat transfer coefficient of the contact between the tool and the workpiece
    /// (W/(m^2 K)), for a surface particle touching the tool; 0 (the default): no heat
    /// crosses.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub heat_transfer_w_per_m2_k: Real,
    /// Heat transfer coefficient rising with the contact pressure instead of the constant:
    /// `[[p (Pa), h (W/(m^2 K))], ...]`, p increasing, linear between the points and held
    /// beyond them; a particle's pressure is its normal contact force on the tool, averaged
    /// over the time since the last heat stage, over its share of the contact.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub heat_transfer_by_pressure: Vec<[Real; 2]>,
    /// Named points of the tool's surface (die fill, as in 2D): the material has reached
    /// one once a surface particle lies within `output.fill_distance_rel` smallest spacings
    /// of it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fill_points: Vec<SolidFillPoint>,
    /// STL: whether the contact's second pass holds the die's ridges (its convex edges and
    /// vertices) against the workpiece's surface between the particles, so that a sharp
    /// edge cannot sink between two rows of surface particles (opt-in, default false: on
    /// the conrod it raises the force by up to 29 % and its interface gains energy over the
    /// last millimetre; docs/forging.md, "Die edges between surface particles").
    #[serde(default, skip_serializing_if = "is_false")]
    pub ridges: bool,
}

/// A named point of a 3D tool's surface, [`super::FillPoint`] with three coordinates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidFillPoint {
    /// Name, used in outputs (`<tool>.<name>.filled`).
    pub name: String,
    /// Position with the tool at its start (m); it moves with the tool. It must lie on the
    /// tool's surface, within the fill distance (checked at setup, where the spacing is
    /// known).
    pub at_m: [Real; 3],
}

fn default_separation() -> bool {
    true
}

fn is_false(b: &bool) -> bool {
    !*b
}

fn is_plane(shape: &ToolShape) -> bool {
    *shape == ToolShape::Plane
}

fn is_zero(x: &Real) -> bool {
    *x == 0.0
}

impl SolidToolSpec {
    /// The tool's temperature and heat transfer (the 2D tool's keys).
    pub fn heat_contact(&self) -> HeatContact<'_> {
        HeatContact {
            temperature_c: self.temperature_c,
            heat_transfer_w_per_m2_k: self.heat_transfer_w_per_m2_k,
            heat_transfer_by_pressure: &self.heat_transfer_by_pressure,
        }
    }
}

/// The `[output]` section of a 3D scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidOutput {
    /// Interval between rows of the time history (s); default: end time / 200.
    #[serde(default)]
    pub history_interval_s: Option<Real>,
    /// Number of VTK frames over the run (0 for none).
    #[serde(default = "default_frames")]
    pub frames: usize,
    /// How near, in smallest particle spacings, a surface particle must come to one of a
    /// tool's `fill_points` to have filled it (as in 2D, `output.fill_distance_rel`).
    #[serde(default = "super::output::default_fill_distance")]
    pub fill_distance_rel: Real,
}

fn default_frames() -> usize {
    5
}

impl Default for SolidOutput {
    fn default() -> Self {
        SolidOutput {
            history_interval_s: None,
            frames: default_frames(),
            fill_distance_rel: super::output::default_fill_distance(),
        }
    }
}

/// A whole 3D scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolidScene {
    /// Short name, used for output folders.
    pub name: String,
    /// Free text shown in reports.
    #[serde(default)]
    pub description: String,
    /// `kinematics = "3d"`.
    pub model: SolidModel,
    /// The deformable body.
    pub workpiece: SolidWorkpiece,
    /// Its material.
    pub material: MaterialSpec,
    /// Temperature and heat, as in 2D ([`ThermalSpec`]): the heating of the plastic work
    /// and of friction at the tools, conduction, the heat to the tools and the
    /// surroundings, elasticity over temperature; a scene without it is isothermal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal: Option<ThermalSpec>,
    /// Speed/accuracy knobs of the discretisation.
    #[serde(default)]
    pub discretization: SolidDiscretization,
    /// Time span and step.
    pub time: TimeSpec,
    /// Rigid tools: planes, or dies from STL files.
    #[serde(default)]
    pub tools: Vec<SolidToolSpec>,
    /// Contact of the workpiece's surface with itself, as in 2D (the same keys and meaning,
    /// on by default): where the surface folds, its parts press on each other, and a fold
    /// between points apart on the surface is reported as a lap
    /// ([`crate::contact::self_contact_3d`]).
    #[serde(default)]
    pub self_contact: SelfContactSpec,
    /// What to record.
    #[serde(default)]
    pub output: SolidOutput,
    /// Run-time checks.
    #[serde(default)]
    pub checks: Checks,
    /// Published results to print beside ours (not used by the solver).
    #[serde(default)]
    pub reference: Vec<Reference>,
    /// The folder of the scene file, which an STL tool's `file` is relative to (set when
    /// the scene is read; the working folder when it is not).
    #[serde(skip)]
    #[schemars(skip)]
    pub folder: PathBuf,
}

/// A workpiece key and whether the scene gives it.
type Given<'a> = (&'a str, bool);

/// A unit vector: three finite components of length 1 within 1e-9.
fn unit(v: [Real; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
        && ((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt() - 1.0).abs() < 1e-9
}

impl SolidScene {
    /// Every non-physical or inconsistent value, as (key path, message), in the order of
    /// the sections.
    pub fn validate(&self) -> Vec<(String, String)> {
        let mut out = validation::Checks::default();
        validation::scene_name(&self.name, &mut out);
        self.check_workpiece(&mut out);
        self.material.check(&mut out);
        match &self.thermal {
            Some(t) => {
                t.check(&mut out);
                self.check_heat(&mut out);
            }
            None => {
                super::across_sections::flow_stress_needs_heat(&self.material, &mut out);
                for (i, tool) in self.tools.iter().enumerate() {
                    out.check(
                        tool.temperature_c.is_none() && !tool.heat_contact().transfers_heat(),
                        &format!("tools[{i}].temperature_c"),
                        "a tool's temperature and heat transfer need the [thermal] section".into(),
                    );
                }
            }
        }
        let d = &self.discretization;
        out.check(
            d.support.is_finite() && (1.05..=4.0).contains(&d.support),
            "discretization.support",
            format!(
                "must lie in [1.05, 4] particle spacings (a linear basis needs more than 1), got {}",
                d.support
            ),
        );
        super::discretization::check_rereference(d.rereference_stretch, d.integration, &mut out);
        super::discretization::check_scni_stabilization(d.scni_stabilization, &mut out);
        self.time.check(&mut out);
        if let Some(mass_scaling) = &self.time.mass_scaling {
            mass_scaling.check(&mut out, d.rereference_stretch.is_some());
        }
        let mut names = std::collections::BTreeSet::new();
        for (i, t) in self.tools.iter().enumerate() {
            let key = |k: &str| format!("tools[{i}].{k}");
            out.check(
                is_name(&t.name) && names.insert(t.name.clone()),
                &key("name"),
                format!(
                    "`{}` must be a unique name of letters, digits and `_`",
                    t.name
                ),
            );
            self.check_tool_surface(i, &mut out);
            out.check(
                unit(t.axis),
                &key("axis"),
                format!("must be a unit vector, got {:?}", t.axis),
            );
            for (suffix, message) in t.friction.validate() {
                out.check(false, &key(&format!("friction{suffix}")), message);
            }
            let points = t.fill_points.iter().map(|p| (&p.name[..], &p.at_m[..]));
            super::tools::check_fill_points(points, &key, &mut out);
            t.motion.check(&key, &mut out);
        }
        self.self_contact.check(&mut out);
        let interval = self
            .output
            .history_interval_s
            .unwrap_or(self.time.end_s / super::DEFAULT_HISTORY_ROWS);
        out.check(
            pos(interval) && interval <= self.time.end_s,
            "output.history_interval_s",
            format!(
                "must be positive and at most time.end_s ({}), got {interval}",
                self.time.end_s
            ),
        );
        out.check(
            pos(self.output.fill_distance_rel),
            "output.fill_distance_rel",
            format!("must be positive, got {}", self.output.fill_distance_rel),
        );
        self.checks.check(&mut out);
        out.0
    }

    /// Tool `i`'s surface: a plane's point and unit normal; a cylinder's finite centre,
    /// unit axis direction and positive radius and length; an STL tool's file, read and
    /// checked ([`SolidScene::tool_mesh`]) and its size and place against the
    /// workpiece's ([`units_finding`]); each shape's keys, and no other's.
    fn check_tool_surface(&self, i: usize, out: &mut validation::Checks) {
        let t = &self.tools[i];
        let key = |k: &str| format!("tools[{i}].{k}");
        let plane = [
            ("point_m", t.point_m.is_some()),
            ("normal", t.normal.is_some()),
        ];
        let cylinder = [
            ("center_m", t.center_m.is_some()),
            ("axis_direction", t.axis_direction.is_some()),
            ("radius_m", t.radius_m.is_some()),
        ];
        let length = ("length_m", t.length_m.is_some());
        let stl = [
            ("file", t.file.is_some()),
            ("unit", t.unit.is_some()),
            ("ridges", t.ridges),
        ];
        let (shape, needed, foreign): (&str, &[Given], Vec<Given>) = match t.shape {
            ToolShape::Plane => ("plane", &plane, [&stl[..], &cylinder, &[length]].concat()),
            ToolShape::Stl => (
                "stl",
                &stl[..1],
                [&plane[..], &cylinder, &[length]].concat(),
            ),
            ToolShape::Cylinder => ("cylinder", &cylinder, [&plane[..], &stl].concat()),
        };
        for (k, given) in needed {
            out.check(*given, &key(k), format!("a {shape} tool needs `{k}`"));
        }
        for (k, given) in &foreign {
            out.check(
                !*given,
                &key(k),
                format!("`{k}` is not a key of a {shape} tool"),
            );
        }
        if let Some(p) = t.point_m {
            out.check(
                p.iter().all(|x| x.is_finite()),
                &key("point_m"),
                format!("must be finite, got {p:?}"),
            );
        }
        if let Some(n) = t.normal {
            out.check(
                unit(n),
                &key("normal"),
                format!("must be a unit vector, got {n:?}"),
            );
        }
        if let Some(c) = t.center_m {
            out.check(
                c.iter().all(|x| x.is_finite()),
                &key("center_m"),
                format!("must be finite, got {c:?}"),
            );
        }
        if let Some(d) = t.axis_direction {
            out.check(
                unit(d),
                &key("axis_direction"),
                format!("must be a unit vector, got {d:?}"),
            );
        }
        for (k, value) in [("radius_m", t.radius_m), ("length_m", t.length_m)] {
            if let Some(v) = value {
                out.check(pos(v), &key(k), format!("must be positive, got {v}"));
            }
        }
        if t.shape != ToolShape::Stl || t.file.is_none() {
            return;
        }
        match self.tool_mesh(i) {
            Err(message) => out.check(false, &key("file"), message),
            Ok(mesh) => {
                if let Some(message) = self
                    .workpiece_bounds()
                    .and_then(|w| units_finding(mesh.bounds(), w, t.unit.unwrap_or_default()))
                {
                    let path = self.tool_path(i).unwrap_or_default();
                    out.check(
                        false,
                        &key("file"),
                        format!("`{}` {message}", path.display()),
                    );
                }
            }
        }
    }

    /// The path of STL tool `i`'s file: its `file` in the scene's folder.
    pub fn tool_path(&self, i: usize) -> Option<PathBuf> {
        let file = self.tools.get(i)?.file.as_ref()?;
        Some(self.folder.join(Path::new(file)))
    }

    /// STL tool `i`'s triangles in metres, read and checked ([`TriangleMesh::read`]).
    ///
    /// # Errors
    ///
    /// The tool has no file, or the file cannot be read or fails a check: the file's
    /// path and the reason.
    pub fn tool_mesh(&self, i: usize) -> std::result::Result<TriangleMesh, String> {
        let path = self
            .tool_path(i)
            .ok_or_else(|| format!("tool {i} is not an STL tool"))?;
        let unit = self.tools[i].unit.unwrap_or_default();
        TriangleMesh::read(&path, unit).map_err(|reason| format!("`{}` {reason}", path.display()))
    }

    /// `[min, max]` of each coordinate of the undeformed workpiece (m), the whole
    /// cylinder's for a part of one; `None` when the shape's keys are missing.
    fn workpiece_bounds(&self) -> Option<[[Real; 2]; 3]> {
        Some(match self.workpiece.shape()? {
            SolidShape::Cylinder {
                radius_m, length_m, ..
            } => [
                [-radius_m, radius_m],
                [-radius_m, radius_m],
                [0.0, length_m],
            ],
            SolidShape::Box {
                origin_m, size_m, ..
            } => std::array::from_fn(|k| [origin_m[k], origin_m[k] + size_m[k]]),
        })
    }

    /// Heat in 3D (`solver/conduction.rs`, `solver/solid/heat.rs`): the plastic work's
    /// heat, friction heat, conduction, the heat to the tools and the surroundings and the
    /// elasticity over temperature, as in 2D; each tool's temperature and heat transfer
    /// checked as a 2D tool's ([`HeatContact::check`]).
    fn check_heat(&self, out: &mut validation::Checks) {
        for (i, tool) in self.tools.iter().enumerate() {
            tool.heat_contact()
                .check(&tool.name, |k| format!("tools[{i}].{k}"), out);
        }
    }

    /// Whether heat moves in the workpiece or across its surface, or is made at it (the
    /// heat stage runs): a `[thermal]` section with conduction, convection or radiation, a
    /// tool with heat transfer or with friction; otherwise heating is adiabatic (2D's
    /// [`super::Scene::transfers_heat`]).
    pub fn transfers_heat(&self) -> bool {
        self.thermal.as_ref().is_some_and(|t| {
            t.conductivity_w_per_m_k > 0.0
                || !t.conductivity_by_temperature.is_empty()
                || t.convection_w_per_m2_k > 0.0
                || t.emissivity > 0.0
                || self.tools.iter().any(|t| t.heat_contact().transfers_heat())
        }) || self.heats_by_friction()
    }

    /// Whether friction at a tool makes heat: a `[thermal]` section and a tool with
    /// friction. The heat stage then takes it into the particles it was made at.
    pub fn heats_by_friction(&self) -> bool {
        self.thermal.is_some() && self.tools.iter().any(|t| !t.friction.is_frictionless())
    }

    /// Whether a tool's heat transfer depends on the contact pressure: the contact stage
    /// then books each particle's normal impulse for the heat stage.
    pub fn transfers_heat_by_pressure(&self) -> bool {
        self.thermal.is_some()
            && self
                .tools
                .iter()
                .any(|t| !t.heat_transfer_by_pressure.is_empty())
    }

    fn check_workpiece(&self, out: &mut validation::Checks) {
        let w = &self.workpiece;
        let v = w.initial_velocity_m_per_s;
        out.check(
            v.iter().all(|x| x.is_finite()),
            "workpiece.initial_velocity_m_per_s",
            format!("must be finite, got {v:?}"),
        );
        let (shape, needed, foreign): (&str, &[Given], &[Given]) = match w.shape {
            ShapeKind::Cylinder => (
                "cylinder",
                &[
                    ("radius_m", w.radius_m.is_some()),
                    ("length_m", w.length_m.is_some()),
                    ("cells", w.cells.is_some()),
                ],
                &[
                    ("origin_m", w.origin_m.is_some()),
                    ("size_m", w.size_m.is_some()),
                    ("particles", w.particles.is_some()),
                    ("symmetry", !w.symmetry.is_empty()),
                ],
            ),
            ShapeKind::Box => (
                "box",
                &[
                    ("origin_m", w.origin_m.is_some()),
                    ("size_m", w.size_m.is_some()),
                    ("particles", w.particles.is_some()),
                ],
                &[
                    ("radius_m", w.radius_m.is_some()),
                    ("length_m", w.length_m.is_some()),
                    ("part", w.part.is_some()),
                    ("cells", w.cells.is_some()),
                    ("core_ratio", w.core_ratio.is_some()),
                ],
            ),
        };
        for (key, given) in needed {
            out.check(
                *given,
                &format!("workpiece.{key}"),
                format!("a {shape} workpiece needs `{key}`"),
            );
        }
        for (key, given) in foreign {
            out.check(
                !*given,
                &format!("workpiece.{key}"),
                format!("`{key}` is not a key of a {shape} workpiece"),
            );
        }
        match w.shape() {
            Some(SolidShape::Cylinder {
                radius_m,
                length_m,
                cells,
                core_ratio,
                ..
            }) => {
                out.check(
                    pos(radius_m),
                    "workpiece.radius_m",
                    format!("must be positive, got {radius_m}"),
                );
                out.check(
                    pos(length_m),
                    "workpiece.length_m",
                    format!("must be positive, got {length_m}"),
                );
                out.check(
                    cells[0] >= 2 && cells[0] % 2 == 0 && cells[1] >= 1 && cells[2] >= 1,
                    "workpiece.cells",
                    format!(
                        "must be [core cells per side (even, at least 2), ring layers (at least 1), axial cells (at least 1)], got {cells:?}"
                    ),
                );
                out.check(
                    core_ratio > 0.0 && core_ratio < std::f64::consts::FRAC_1_SQRT_2,
                    "workpiece.core_ratio",
                    format!("must lie between 0 and 1 / sqrt 2, got {core_ratio}"),
                );
                let count = (cells[0] + 1 + 2 * cells[1])
                    .saturating_pow(2)
                    .saturating_mul(cells[2] + 1);
                out.check(
                    count <= 4_000_000,
                    "workpiece.cells",
                    format!("{cells:?} is more than 4 million particles"),
                );
            }
            Some(SolidShape::Box {
                origin_m,
                size_m,
                particles,
                ..
            }) => {
                out.check(
                    origin_m.iter().all(|x| x.is_finite()),
                    "workpiece.origin_m",
                    format!("must be finite, got {origin_m:?}"),
                );
                out.check(
                    size_m.iter().all(|&x| pos(x)),
                    "workpiece.size_m",
                    format!("every size must be positive, got {size_m:?}"),
                );
                out.check(
                    particles.iter().all(|&n| n >= 2),
                    "workpiece.particles",
                    format!("need at least 2 particles in each direction, got {particles:?}"),
                );
                out.check(
                    particles
                        .iter()
                        .try_fold(1usize, |a, &n| a.checked_mul(n))
                        .is_some_and(|n| n <= 4_000_000),
                    "workpiece.particles",
                    format!("{particles:?} is more than 4 million particles"),
                );
            }
            None => {}
        }
    }

    /// Parse and validate 3D scene text; `file` names it in error messages.
    pub fn from_str_named(text: &str, file: &str) -> Result<SolidScene> {
        crate::scene_overrides::parse(text, file)
    }

    /// The interval between history rows (s): `output.history_interval_s`, or the end time
    /// over [`super::DEFAULT_HISTORY_ROWS`].
    pub fn history_interval(&self) -> Real {
        self.output
            .history_interval_s
            .unwrap_or(self.time.end_s / super::DEFAULT_HISTORY_ROWS)
    }
}

/// How many times larger (or smaller) than the workpiece an STL die may be, and how many
/// workpiece sizes away it may lie, before its unit is suspect (-): a die in millimetres
/// read as metres is 1000 times too large.
pub const UNIT_SUSPECT: Real = 100.0;

/// Whether an STL die with `die` bounds (m) fits a workpiece with `work` bounds (m), read in
/// `unit`: a die more than [`UNIT_SUSPECT`] times the workpiece's largest extent, less than
/// its inverse, or farther than that many extents from it, is refused with the likely
/// mix-up of units.
pub fn units_finding(
    die: [[Real; 2]; 3],
    work: [[Real; 2]; 3],
    unit: LengthUnit,
) -> Option<String> {
    let largest = |b: [[Real; 2]; 3]| b.iter().map(|r| r[1] - r[0]).fold(0.0, Real::max);
    let (d, w) = (largest(die), largest(work));
    let gap = (0..3)
        .map(|k| {
            (die[k][0] - work[k][1])
                .max(work[k][0] - die[k][1])
                .max(0.0)
        })
        .map(|g| g * g)
        .sum::<Real>()
        .sqrt();
    let hint = match unit {
        LengthUnit::M => "millimetres given as metres? Set `unit = \"mm\"`",
        LengthUnit::Mm => "is the file in millimetres?",
    };
    if d > UNIT_SUSPECT * w {
        Some(format!(
            "is {d:.4e} m across, {:.0} times the workpiece's {w:.4e} m: {hint}",
            d / w
        ))
    } else if d * UNIT_SUSPECT < w {
        Some(format!(
            "is {d:.4e} m across, 1/{:.0} of the workpiece's {w:.4e} m: metres given as millimetres? Check `unit`",
            w / d
        ))
    } else if gap > UNIT_SUSPECT * w {
        Some(format!(
            "lies {gap:.4e} m from the workpiece, {:.0} times its size {w:.4e} m: {hint}",
            gap / w
        ))
    } else {
        None
    }
}

/// A scene of either kind, as read from a file.
#[derive(Debug, Clone, PartialEq)]
pub enum SceneFile {
    /// Plane strain or axisymmetric.
    Plane(Box<Scene>),
    /// Three dimensions.
    Solid(Box<SolidScene>),
}

impl SceneFile {
    /// Read and validate a scene of either kind from a file: `model.kinematics = "3d"`
    /// makes it a [`SolidScene`].
    pub fn from_file(path: &std::path::Path) -> Result<SceneFile> {
        SceneFile::from_str_named(&super::read_text(path)?, &path.display().to_string())
    }

    /// Parse and validate scene text of either kind; `file` names it in error messages.
    pub fn from_str_named(text: &str, file: &str) -> Result<SceneFile> {
        if is_solid(text) {
            SolidScene::from_str_named(text, file).map(|s| SceneFile::Solid(Box::new(s)))
        } else {
            Scene::from_str_named(text, file).map(|s| SceneFile::Plane(Box::new(s)))
        }
    }
}

/// Whether scene text asks for three dimensions (`model.kinematics = "3d"`); text that does
/// not parse is not (the 2D reader then reports its syntax error).
pub fn is_solid(text: &str) -> bool {
    toml::from_str::<toml::Table>(text).is_ok_and(|t| {
        t.get("model")
            .and_then(|m| m.get("kinematics"))
            .and_then(|k| k.as_str())
            == Some("3d")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) const QUARTER_BAR: &str = r#"
name = "bar3d"
[model]
kinematics = "3d"
[workpiece]
shape = "cylinder"
radius_m = 0.0032
length_m = 0.0324
part = "quarter"
cells = [4, 2, 10]
initial_velocity_m_per_s = [0.0, 0.0, -227.0]
[material]
density_kg_per_m3 = 8930.0
youngs_modulus_pa = 117e9
poisson_ratio = 0.35
hardening = { law = "linear", yield_stress_pa = 400e6, modulus_pa = 100e6 }
[time]
end_s = 1e-6
[[tools]]
name = "wall"
point_m = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
axis = [0.0, 0.0, -1.0]
motion = { kind = "fixed" }
separation = false
"#;

    fn err(text: &str) -> String {
        SceneFile::from_str_named(text, "s.toml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn a_3d_scene_is_read_as_one() {
        let SceneFile::Solid(s) = SceneFile::from_str_named(QUARTER_BAR, "s.toml").unwrap() else {
            panic!("not read as 3D")
        };
        assert_eq!(s.discretization.support, 2.0);
        assert!(matches!(
            s.workpiece.shape().unwrap(),
            SolidShape::Cylinder {
                part: CylinderPart::Quarter,
                cells: [4, 2, 10],
                ..
            }
        ));
        assert!(!s.tools[0].separation);
    }

    #[test]
    fn bad_3d_values_are_named_with_key_and_line() {
        let cases = [
            (
                "cells = [4, 2, 10]",
                "cells = [3, 2, 10]",
                "workpiece.cells",
                10,
            ),
            (
                "normal = [0.0, 0.0, 1.0]",
                "normal = [0.0, 0.0, 2.0]",
                "tools[0].normal",
                22,
            ),
            (
                "[time]",
                "[thermal]\ninitial_temperature_c = 20.0\nspecific_heat_j_per_kg_k = 385.0\nexpansion_per_k = 1.7e-2\n[time]",
                "thermal.expansion_per_k",
                20,
            ),
            (
                "hardening = { law = \"linear\", yield_stress_pa = 400e6, modulus_pa = 100e6 }",
                "hardening = { law = \"johnson_cook\", a_pa = 90.0e6, b_pa = 292.0e6, n = 0.31, c = 0.025, reference_strain_rate_per_s = 1.0, m = 1.09, reference_temperature_c = 22.0, melting_temperature_c = 1082.85 }",
                "material.hardening.law",
                16,
            ),
            (
                "separation = false",
                "separation = false\nfriction = -0.1\n[thermal]\ninitial_temperature_c = 20.0\nspecific_heat_j_per_kg_k = 385.0",
                "tools[0].friction",
                26,
            ),
            (
                "separation = false",
                "separation = false\ntemperature_c = 20.0",
                "tools[0].temperature_c",
                26,
            ),
            (
                "separation = false",
                "separation = false\nheat_transfer_w_per_m2_k = 1e4\n[thermal]\ninitial_temperature_c = 20.0\nspecific_heat_j_per_kg_k = 385.0",
                "tools[0].heat_transfer_w_per_m2_k",
                26,
            ),
            (
                "end_s = 1e-6",
                "end_s = 1e-6\nmass_scaling = { factor = 0.5 }",
                "time.mass_scaling.factor",
                19,
            ),
            (
                "end_s = 1e-6",
                "end_s = 1e-6\nmass_scaling = { target_dt_s = 1e-6, at_rereferences = \"target\" }",
                "time.mass_scaling.at_rereferences",
                19,
            ),
        ];
        for (from, to, key, line) in cases {
            let e = err(&QUARTER_BAR.replace(from, to));
            assert!(e.contains(key) && e.contains(&format!(":{line}:")), "{e}");
        }
        let e = err(&QUARTER_BAR.replace("part = \"quarter\"", "part = \"third\""));
        assert!(e.contains("third") && e.contains("line 9"), "{e}");
        let e = err(&QUARTER_BAR.replace("radius_m =", "radius_mm ="));
        assert!(e.contains("radius_mm") && e.contains("line 7"), "{e}");
        let e = err(&QUARTER_BAR.replace("cells = [4, 2, 10]\n", ""));
        assert!(e.contains("workpiece.cells") && e.contains("needs"), "{e}");
        let e = err(&QUARTER_BAR.replace("cells =", "particles = [3, 3, 3]\ncells ="));
        assert!(
            e.contains("workpiece.particles") && e.contains(":10:"),
            "{e}"
        );
    }

    /// A cylinder tool's keys: read, and each bad value refused with its key and line; a
    /// missing key named, another shape's key refused.
    #[test]
    fn bad_cylinder_tools_are_named_with_key_and_line() {
        let plane = "point_m = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]";
        let cylinder = "shape = \"cylinder\"\ncenter_m = [0.0, 0.0, -0.01]\naxis_direction = [1.0, 0.0, 0.0]\nradius_m = 0.01\nlength_m = 0.02";
        let text = QUARTER_BAR.replace(plane, cylinder);
        let SceneFile::Solid(s) = SceneFile::from_str_named(&text, "s.toml").unwrap() else {
            panic!("not read as 3D")
        };
        let t = &s.tools[0];
        assert_eq!(t.shape, ToolShape::Cylinder);
        assert_eq!(
            (t.center_m, t.axis_direction, t.radius_m, t.length_m),
            (
                Some([0.0, 0.0, -0.01]),
                Some([1.0, 0.0, 0.0]),
                Some(0.01),
                Some(0.02)
            )
        );
        let cases = [
            ("radius_m = 0.01", "radius_m = 0.0", "tools[0].radius_m", 24),
            (
                "radius_m = 0.01",
                "radius_m = -0.01",
                "tools[0].radius_m",
                24,
            ),
            (
                "axis_direction = [1.0, 0.0, 0.0]",
                "axis_direction = [0.0, 0.0, 0.0]",
                "tools[0].axis_direction",
                23,
            ),
            (
                "axis_direction = [1.0, 0.0, 0.0]",
                "axis_direction = [1.0, 1.0, 0.0]",
                "tools[0].axis_direction",
                23,
            ),
            ("length_m = 0.02", "length_m = 0.0", "tools[0].length_m", 25),
            (
                "center_m = [0.0, 0.0, -0.01]",
                "center_m = [nan, 0.0, -0.01]",
                "tools[0].center_m",
                22,
            ),
        ];
        for (from, to, key, line) in cases {
            let e = err(&text.replace(from, to));
            assert!(e.contains(key) && e.contains(&format!(":{line}:")), "{e}");
        }
        let e = err(&text.replace("radius_m = 0.01\n", ""));
        assert!(
            e.contains("tools[0].radius_m") && e.contains("needs"),
            "{e}"
        );
        let e = err(&text.replace(
            "length_m = 0.02",
            "length_m = 0.02\nnormal = [0.0, 0.0, 1.0]",
        ));
        assert!(
            e.contains("tools[0].normal") && e.contains("not a key"),
            "{e}"
        );
        let e = err(&QUARTER_BAR.replace(plane, &format!("{plane}\nradius_m = 0.01")));
        assert!(
            e.contains("tools[0].radius_m") && e.contains("not a key of a plane tool"),
            "{e}"
        );
        // The ridge pass is an STL die's: a plane or a cylinder has no edges to hold.
        for shaped in [
            text.replace("length_m = 0.02", "length_m = 0.02\nridges = true"),
            QUARTER_BAR.replace(plane, &format!("{plane}\nridges = true")),
        ] {
            let e = err(&shaped);
            assert!(
                e.contains("tools[0].ridges") && e.contains("not a key of a"),
                "{e}"
            );
        }
        // Unbounded: no `length_m`.
        assert!(
            SceneFile::from_str_named(&text.replace("\nlength_m = 0.02", ""), "s.toml").is_ok()
        );
    }
}
