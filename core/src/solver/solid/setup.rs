//! Building a [`SolidSimulation`] from a validated 3D scene: the particles of the box
//! lattice or the cylinder's O-grid, the points of the cell rule with their RK shape
//! functions (the same [`KernelCloud`] and [`Lattice`] as 2D, `D = 3`), the row-sum lumped
//! masses, the plane tools and symmetry planes, the critical step.

use super::contact::ToolContact;
use super::fill;
use super::heat::{update_eigenvalue, HeatSurface};
use super::self_contact::SolidSelfContact;
use super::{SolidDisc, SolidSimulation, SolidState, SolidWorkspace};
use crate::cylinder_grid::{CylinderGrid, NodalDomains, Sector, MAX_OCTANTS};
use crate::error::{Error, Result};
use crate::integration::{orthant_shapes, point_shapes, smoothed, DomainBoundaries};
use crate::material::{HenckyJ2, PointState3};
use crate::math::Real;
use crate::memory;
use crate::rk_shape::{for_each_index, KernelCloud, Lattice, ShapeTable, Site};
use crate::scene::solid::{CylinderPart, SolidScene, SolidShape, ToolShape};
use crate::scene::IntegrationRule;
use crate::solid_tool::SolidTool;
use crate::solver::critical_step::{critical_step, stiffening};
use crate::solver::detachment::{nearest_in_rows, Isolation};
use crate::solver::discretization::{Thermal, Transfer};
use crate::solver::energy::Energy;
use crate::solver::fields::Smoothing;
use crate::solver::heat::Heat;
use crate::solver::layout::{Scatter, MAX_GROUP_3D};
use crate::solver::mass_scaling::{scaled, stiffness_bounds, Plan};
use crate::solver::nodal_stabilization::{Forces, Tables};
use crate::solver::point_outputs::PointOut;
use crate::solver::setup::{check_fixed_step, lumped_masses};
use crate::solver::simulation::StageTimes;
use crate::solver::update::initial_motion;
use crate::team::Team;
use crate::tools::SEARCH_DEPTH_SPACINGS;
use std::time::Instant;

/// The particles and points of a 3D workpiece before the masses: positions (m), the
/// point and particle shape functions, the point weights (m^3), the symmetry planes as
/// `(axis, coordinate)`, the hexahedral cells (for the frames) and the smallest spacing.
struct Particles {
    positions: Vec<[Real; 3]>,
    volumes: Vec<Real>,
    points: Vec<[Real; 3]>,
    weights: Vec<Real>,
    pt: ShapeTable<3>,
    nodal: ShapeTable<3>,
    planes: Vec<(usize, Real)>,
    cells: Vec<[u32; 8]>,
    h_min: Real,
    /// Points per layer of cells along z: the chunks of the stress stage are two layers.
    layer_points: usize,
    /// Each particle's cell extents (m): its supports over `discretization.support`.
    extents: Vec<[Real; 3]>,
    /// With SCNI stabilized (`discretization.scni_stabilization`): the octants' smoothed
    /// gradients (rows `8 L + k`) and volumes (m^3).
    octants: Option<(ShapeTable<3>, Vec<Real>)>,
}

/// Does the scene stabilize nodal integration (`discretization.scni_stabilization` above 0
/// with `integration = "scni"`)?
fn stabilized(scene: &SolidScene) -> bool {
    scene.discretization.integration == IntegrationRule::Scni
        && scene
            .discretization
            .scni_stabilization
            .is_some_and(|c| c > 0.0)
}

/// The octants of the O-grid's nodal domains ([`CylinderGrid::octant_domains`]) with
/// their smoothed gradients `B^k_I = (1 / V_k) sum_g N_I(x_g) n w_g` (1/m), built
/// [`OCTANT_BLOCK`] domains at a time so that the boundary points' shape functions are
/// never all held at once; [`MAX_OCTANTS`] rows per domain.
fn cylinder_octants(
    grid: &CylinderGrid,
    cloud: &KernelCloud<3>,
) -> Result<(ShapeTable<3>, Vec<Real>)> {
    let own = grid.particle_octants();
    let mut table = ShapeTable {
        offsets: vec![0],
        ..Default::default()
    };
    let mut volumes = Vec::with_capacity(MAX_OCTANTS * own.len());
    for (b, block) in own.chunks(OCTANT_BLOCK).enumerate() {
        let o = grid.octant_domains(block);
        let first = b * OCTANT_BLOCK;
        let on_faces = cloud.shape_table(&o.sites, &|q| {
            format!("boundary point {q} of the octants of nodal domains {first}..")
        })?;
        table.append(smoothed(None, &on_faces, &o.boundaries, &o.volumes));
        volumes.extend(o.volumes);
    }
    Ok((table, volumes))
}

/// Nodal domains whose octants' boundary points [`cylinder_octants`] evaluates at once.
const OCTANT_BLOCK: usize = 64;

/// Nodal domains whose boundary points [`nodal_table`] evaluates at once: a point on a face
/// two blocks share is evaluated in both, so larger than [`OCTANT_BLOCK`] (64 gave the
/// quarter Taylor bar a quarter more work than one block).
const DOMAIN_BLOCK: usize = 256;

/// SCNI's smoothed shape table on the O-grid's nodal domains ([`CylinderGrid::nodal_domains`]:
/// `N_I` at each centroid and the smoothed gradients), built [`DOMAIN_BLOCK`] domains at a
/// time: each block's centroids and the boundary points its terms name (a point two blocks
/// share is evaluated in each) are evaluated, smoothed and freed before the next. Each
/// point's shape functions are its own, so the table is the one an evaluation of all at
/// once gives.
fn nodal_table(domains: &NodalDomains, cloud: &KernelCloud<3>) -> Result<ShapeTable<3>> {
    let b = &domains.boundaries;
    let n = domains.volumes.len();
    let mut table = ShapeTable {
        offsets: vec![0],
        ..Default::default()
    };
    // The block's row of each boundary point it names (u32::MAX: none yet).
    let mut local = vec![u32::MAX; domains.sites.len()];
    for start in (0..n).step_by(DOMAIN_BLOCK) {
        let block = start..(start + DOMAIN_BLOCK).min(n);
        let terms = b.offsets[block.start]..b.offsets[block.end];
        let mut rows = Vec::new();
        for &q in &b.rows[terms.clone()] {
            if local[q as usize] == u32::MAX {
                local[q as usize] = rows.len() as u32;
                rows.push(q);
            }
        }
        let sites: Vec<[Real; 3]> = rows.iter().map(|&q| domains.sites[q as usize]).collect();
        let on_faces = cloud.shape_table(&sites, &|r| {
            format!("boundary point {} of the nodal domains", rows[r])
        })?;
        let at_centre = cloud.shape_table(&domains.centroids[block.clone()], &|p| {
            format!("nodal integration point {}", block.start + p)
        })?;
        let boundaries = DomainBoundaries {
            offsets: b.offsets[block.start..=block.end]
                .iter()
                .map(|o| o - terms.start)
                .collect(),
            rows: b.rows[terms.clone()]
                .iter()
                .map(|&q| local[q as usize])
                .collect(),
            nw: b.nw[terms].to_vec(),
        };
        table.append(smoothed(
            Some(&at_centre),
            &on_faces,
            &boundaries,
            &domains.volumes[block],
        ));
        for &q in &rows {
            local[q as usize] = u32::MAX;
        }
    }
    Ok(table)
}

/// The cylinder's O-grid ([`CylinderGrid`]) with each particle's own supports, `support`
/// times its cells' extent.
fn cylinder(shape: &SolidShape, scene: &SolidScene) -> Result<Particles> {
    let SolidShape::Cylinder {
        radius_m,
        length_m,
        part,
        cells,
        core_ratio,
    } = *shape
    else {
        unreachable!("called for a cylinder")
    };
    let (sector, planes) = match part {
        CylinderPart::Full => (Sector::Full, vec![]),
        CylinderPart::Half => (Sector::Half, vec![(0, 0.0)]),
        CylinderPart::Quarter => (Sector::Quarter, vec![(0, 0.0), (1, 0.0)]),
    };
    let grid = CylinderGrid::new(radius_m, length_m, cells, core_ratio, sector)
        .map_err(|m| Error::Request(format!("workpiece: {m}")))?;
    let rule = scene.discretization.integration;
    memory::check(
        grid.positions.len(),
        3,
        rule,
        scene.discretization.support,
        "workpiece.cells",
    )?;
    let supports = grid.supports(scene.discretization.support);
    let cloud = KernelCloud::with_supports(grid.positions.clone(), grid.volumes.clone(), supports);
    let (points, weights, pt, layer_points) = if rule == IntegrationRule::Scni {
        let domains = grid.nodal_domains();
        let pt = nodal_table(&domains, &cloud)?;
        let per_layer = domains.centroids.len() / (cells[2] + 1);
        (domains.centroids, domains.volumes, pt, per_layer)
    } else {
        let (points, weights) = grid.points(rule);
        let per_cell = points.len() / grid.cells.len();
        let pt = cloud.shape_table(&points, &|p| {
            format!("integration point {p} (cell {})", p / per_cell)
        })?;
        let per_layer = points.len() / cells[2];
        (points, weights, pt, per_layer)
    };
    let mut nodal = cloud.shape_table(&grid.positions, &|j| format!("particle {j}"))?;
    nodal.drop_gradients();
    let h_min = smallest_edge(&grid.positions, &grid.cells);
    let octants = match stabilized(scene) {
        true => Some(cylinder_octants(&grid, &cloud)?),
        false => None,
    };
    Ok(Particles {
        octants,
        extents: grid.supports(1.0),
        layer_points,
        positions: grid.positions.clone(),
        volumes: grid.volumes.clone(),
        points,
        weights,
        pt,
        nodal,
        planes,
        cells: grid.cells.clone(),
        h_min,
    })
}

/// The box's lattice ([`Lattice`]), its points those of the 2D code in three dimensions.
fn lattice(shape: &SolidShape, scene: &SolidScene) -> Result<Particles> {
    let SolidShape::Box {
        origin_m,
        size_m,
        particles,
        ref symmetry,
    } = *shape
    else {
        unreachable!("called for a box")
    };
    memory::check(
        particles.iter().product(),
        3,
        scene.discretization.integration,
        scene.discretization.support,
        "workpiece.particles",
    )?;
    let h: [Real; 3] = std::array::from_fn(|k| size_m[k] / (particles[k] - 1) as Real);
    let support = h.map(|hk| scene.discretization.support * hk);
    let lattice = Lattice::new(origin_m, h, particles, support);
    let (points, pt) = point_shapes(&lattice, scene.discretization.integration)?;
    let mut sites = Vec::with_capacity(particles.iter().product());
    for_each_index([0; 3], particles, |node| {
        sites.push(Site {
            node,
            offset: [0.0; 3],
        })
    });
    let mut nodal = lattice.shape_table(&sites, &|j| format!("particle {j}"))?;
    nodal.drop_gradients();
    let octants = match stabilized(scene) {
        true => {
            let (octants, table) = orthant_shapes::<3, MAX_OCTANTS>(&lattice)?;
            Some((table, octants.areas))
        }
        false => None,
    };
    let id = |i: [usize; 3]| (i[0] + particles[0] * (i[1] + particles[1] * i[2])) as u32;
    let mut cells = Vec::new();
    for_each_index([0; 3], particles.map(|n| n - 1), |[i, j, k]| {
        cells.push([
            id([i, j, k]),
            id([i + 1, j, k]),
            id([i + 1, j + 1, k]),
            id([i, j + 1, k]),
            id([i, j, k + 1]),
            id([i + 1, j, k + 1]),
            id([i + 1, j + 1, k + 1]),
            id([i, j + 1, k + 1]),
        ])
    });
    // SCNI has a point per particle, the other rules theirs in each cell.
    let layer_points = match scene.discretization.integration {
        IntegrationRule::Scni => particles[0] * particles[1],
        _ => points.positions.len() / (particles[2] - 1),
    };
    Ok(Particles {
        positions: lattice.cloud().positions.clone(),
        volumes: lattice.cloud().volumes.clone(),
        weights: points.areas,
        points: points.positions,
        pt,
        nodal,
        planes: symmetry
            .iter()
            .map(|f| (f.axis(), origin_m[f.axis()]))
            .collect(),
        cells,
        h_min: h[0].min(h[1]).min(h[2]),
        layer_points,
        extents: vec![h; particles.iter().product()],
        octants,
    })
}

/// The twelve edges of a hexahedral cell, as pairs of its corners (in the order of
/// [`crate::cylinder_grid::CylinderGrid::cells`]).
pub(super) const HEX_EDGES: [(usize, usize); 12] = [
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 0),
    (4, 5),
    (5, 6),
    (6, 7),
    (7, 4),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// The shortest edge of the hexahedral `cells` (m) over `positions`: the smallest spacing.
fn smallest_edge(positions: &[[Real; 3]], cells: &[[u32; 8]]) -> Real {
    cells
        .iter()
        .flat_map(|c| {
            HEX_EDGES.iter().map(move |&(a, b)| {
                let (p, q) = (positions[c[a] as usize], positions[c[b] as usize]);
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
            })
        })
        .fold(Real::INFINITY, Real::min)
}

impl SolidSimulation {
    /// Build the discretisation of a validated 3D scene.
    ///
    /// # Errors
    ///
    /// Shape functions that cannot be formed (too small a support), a mass that is not
    /// positive, a fixed step above the critical step.
    pub fn new(scene: &SolidScene) -> Result<SolidSimulation> {
        let t0 = Instant::now();
        let shape = scene
            .workpiece
            .shape()
            .ok_or_else(|| Error::Request("workpiece: the shape's keys are missing".into()))?;
        let t_shapes = Instant::now();
        let mut p = match shape {
            SolidShape::Cylinder { .. } => cylinder(&shape, scene)?,
            SolidShape::Box { .. } => lattice(&shape, scene)?,
        };
        let shape_functions = t_shapes.elapsed();
        let rho = scene.material.density_kg_per_m3;
        let np = p.positions.len();
        let mass = lumped_masses(&p.pt, &p.weights, rho, &p.positions)?;
        let npts = p.points.len();
        let chunk = (2 * p.layer_points).max(64);
        let scatter = Scatter::new(&p.pt, np, chunk, MAX_GROUP_3D);
        let mut material = HenckyJ2::new(
            scene.material.youngs_modulus_pa,
            scene.material.poisson_ratio,
            scene.material.hardening.clone(),
        );
        material.thermoelastic = scene.thermal.as_ref().and_then(|t| t.thermoelastic());
        let wave_speed = material.wave_speed(rho);
        // The octants' table is freed once the stiffness is assembled.
        let stabilization = p.octants.take().map(|(table, volumes)| {
            let m = &scene.material;
            let mu = m.youngs_modulus_pa / (2.0 * (1.0 + m.poisson_ratio));
            let c = scene.discretization.scni_stabilization.unwrap_or(0.0);
            Tables::new::<MAX_OCTANTS>(c, mu, &table, &volumes, np)
        });
        let depth = SEARCH_DEPTH_SPACINGS * p.h_min;
        let mut tools = Vec::with_capacity(scene.tools.len() + p.planes.len());
        for (i, t) in scene.tools.iter().enumerate() {
            let mesh = match t.shape {
                ToolShape::Plane | ToolShape::Cylinder => None,
                ToolShape::Stl => Some(
                    scene
                        .tool_mesh(i)
                        .map_err(|m| Error::Request(format!("tools[{i}].file: {m}")))?,
                ),
            };
            tools.push(SolidTool::new(t, mesh, depth));
        }
        let scene_tools = tools.len();
        fill::check_points(scene, &tools, p.h_min)?;
        tools.extend(
            p.planes
                .iter()
                .map(|&(axis, at)| SolidTool::symmetry(axis, at, depth)),
        );
        let (v, initial) = initial_motion(scene.workpiece.initial_velocity_m_per_s, None, &mass);
        let sum_abs: Vec<Real> = (0..np)
            .map(|j| p.nodal.row(j).map(|e| p.nodal.n[e].abs()).sum())
            .collect();
        // The particles on a symmetry plane start held on it.
        let ntools = tools.len();
        let mut held = vec![false; np * ntools];
        for (t, tool) in tools.iter().enumerate().skip(scene_tools) {
            for (j, x) in p.positions.iter().enumerate() {
                if tool.depth_of(*x).abs() <= 1e-9 * p.h_min {
                    held[j * ntools + t] = true;
                }
            }
        }
        let self_contact = SolidSelfContact::new(
            scene,
            &p.cells,
            &p.positions,
            &p.extents,
            &p.planes,
            p.h_min,
        );
        // The surface the heat stage, the friction laws that need a contact area (the tools'
        // and the surface's own) and the contact readings (`readings.rs`) take their areas on.
        let own_area =
            scene.self_contact.enabled && scene.self_contact.friction.needs_flow_stress();
        // The flow stress at a particle in contact, for the friction laws that need one.
        let flow_smoothing =
            if own_area || scene.tools.iter().any(|t| t.friction.needs_flow_stress()) {
                Smoothing::new(&scatter, &p.weights, np)
            } else {
                Smoothing::default()
            };
        let heat_surface = if scene_tools > 0 || scene.transfers_heat() || own_area {
            HeatSurface::new(&p.cells, &p.positions, &p.planes, p.h_min)
        } else {
            HeatSurface::default()
        };
        let mut disc = SolidDisc {
            inv_mass: mass.iter().map(|m| 1.0 / m).collect(),
            mass,
            material,
            original: p.positions.clone(),
            ref_pos: p.positions,
            volumes: p.volumes,
            point_positions: p.points,
            weights: p.weights,
            inv_radius: vec![0.0; npts],
            reference_jacobian: vec![1.0; npts],
            scatter,
            stabilization,
            nodal: p.nodal,
            neighbours: p.pt.entries() as Real / npts as Real,
            sum_abs,
            h_min: p.h_min,
            initial_spacing: Vec::new(),
            critical_dt0: p.h_min / wave_speed,
            cells: p.cells,
            scene_tools,
            mass_scaling: None,
            scaling_target: None,
            nodal_points: scene.discretization.integration == IntegrationRule::Scni,
            extents: p.extents,
            track_stretch: scene.discretization.rereference_stretch.is_some(),
            thermal: scene.thermal.as_ref().map(|spec| Thermal {
                spec: spec.clone(),
                capacity: spec.heat_capacity(),
                density: rho,
                transfer: scene.transfers_heat().then(|| Transfer {
                    adiabatic_edge: Vec::new(),
                    lambda0: 0.0,
                }),
            }),
            heat_surface,
            flow_smoothing,
        };
        disc.initial_spacing = nearest_in_rows(&disc.nodal, &disc.ref_pos);
        update_eigenvalue(&mut disc)?;
        let temp0 = scene.thermal.as_ref().map(|t| t.initial_temperature_c);
        let mut ws = SolidWorkspace {
            out: vec![PointOut::at(&disc.material, 0.0, temp0); npts],
            buf: disc.scatter.buffers(),
            f_int: vec![[0.0; 3]; np],
            v_prev: v.clone(),
            contact: ToolContact::new(np, ntools),
            self_contact,
            stabilization: disc.stabilization.as_ref().map(|_| Forces::new(np)),
            team: Team::default(),
        };
        let mut st = SolidState {
            step: 0,
            time: 0.0,
            dt_prev: 0.0,
            d: vec![[0.0; 3]; np],
            v,
            points: vec![PointState3::default(); npts],
            tools: tools.iter().map(|t| t.state).collect(),
            energy: Energy::starting(initial),
            held,
            stick: vec![None; np * ntools],
            max_penetration: 0.0,
            max_beyond_plane: 0.0,
            isolation: Isolation::default(),
            plane_feedback_max: 0.0,
            first_contact_s: None,
            kinetic_to_internal_max: 0.0,
            stable_dt: disc.critical_dt0,
            anchor_time: 0.0,
            anchor_step: 0,
            fill: vec![None; scene.tools.iter().map(|t| t.fill_points.len()).sum()],
            pressed: Vec::new(),
            heat: scene.thermal.as_ref().map(|t| {
                let particles = if scene.transfers_heat() { np } else { 0 };
                let friction = scene.heats_by_friction();
                let pressure = scene.transfers_heat_by_pressure();
                // E(T) / E at the initial temperature, unstrained (2D's).
                let thermoelastic = t
                    .thermoelastic()
                    .map(|te| [te.modulus_factor_at(t.initial_temperature_c), 0.0, 0.0, 0.0]);
                Heat::initial(
                    t,
                    npts,
                    scene_tools,
                    particles,
                    friction,
                    pressure,
                    thermoelastic,
                )
            }),
            max_stretch: 0.0,
            reference: None,
            self_touching: vec![false; ws.self_contact.slots()],
            laps: Vec::new(),
            max_fold_crossings: 0,
            first_fold_crossing: None,
        };
        disc.critical_dt0 = measure_critical_step(&disc, &mut st, &mut ws)?;
        if let Some(ms) = scene.time.mass_scaling {
            let plan = match ms.factor {
                Some(f) => Plan::Uniform(f),
                None => Plan::Selective {
                    target: ms.target_dt_s.unwrap_or(0.0),
                    modulus: rho * wave_speed * wave_speed,
                    stiffness: stiffness_bounds(
                        &p.pt,
                        &disc.weights,
                        &disc.inv_radius,
                        false,
                        rho * wave_speed * wave_speed,
                        np,
                    ),
                },
            };
            let v0 = scene.workpiece.initial_velocity_m_per_s;
            let unscaled = disc.mass.clone();
            let (report, target) = scaled(
                plan,
                unscaled,
                disc.critical_dt0,
                scene.time.dt_safety,
                |mass| {
                    // The masses and what depends on them: inverses, the initial motion
                    // and its kinetic energy.
                    let (v, initial) = initial_motion(v0, None, &mass);
                    disc.inv_mass = mass.iter().map(|m| 1.0 / m).collect();
                    disc.mass = mass;
                    st.v.clone_from(&v);
                    ws.v_prev = v;
                    st.energy = Energy::starting(initial);
                    measure_critical_step(&disc, &mut st, &mut ws)
                },
            )?;
            disc.critical_dt0 = report.critical_dt_s;
            disc.mass_scaling = Some(report);
            disc.scaling_target = target.and_then(|t| t.acting(scene.time.mass_scaling));
        }
        st.stable_dt = disc.critical_dt0;
        super::stress_stage(&disc, &mut st, &mut ws, scene.time.dt_s)?;
        super::gather(&disc, &mut st, &mut ws, None);
        let sim = SolidSimulation {
            scene: scene.clone(),
            disc,
            tools,
            st,
            ws,
            times: StageTimes {
                setup: t0.elapsed(),
                shape_functions,
                ..Default::default()
            },
        };
        check_fixed_step(&scene.time, sim.st.stable_dt, sim.disc.h_min / wave_speed)?;
        Ok(sim)
    }
}

/// The critical step `2 / omega_max` of the undeformed discretisation (s) by Lanczos
/// ([`critical_step`]) on the internal force of a displacement of 1e-7 of the smallest
/// spacing, scaled by `sqrt(f_now / f_max)` with a modulus over temperature (2D's
/// [`stiffening`]); the state (its heat included) is left as it was, undeformed.
pub(super) fn measure_critical_step(
    disc: &SolidDisc,
    st: &mut SolidState,
    ws: &mut SolidWorkspace,
) -> Result<Real> {
    let stiffening = stiffening(&disc.material, st.heat.as_ref());
    let saved = (st.points.clone(), st.energy, st.heat.clone());
    let inv_sqrt_m: Vec<Real> = disc.mass.iter().map(|m| 1.0 / m.sqrt()).collect();
    let dt = critical_step(&inv_sqrt_m, 1e-7 * disc.h_min, |d| {
        st.d = d;
        super::stress_stage(disc, st, ws, None)?;
        super::gather(disc, st, ws, None);
        Ok(ws.f_int.clone())
    });
    st.d.fill([0.0; 3]);
    (st.points, st.energy, st.heat) = saved;
    dt.map(|dt| dt * stiffening)
}
