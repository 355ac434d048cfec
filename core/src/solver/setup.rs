//! Building a [`Simulation`] from a validated scene: the particle lattice and the points of
//! the integration rule with their RK shape functions, the points' volume weights, the
//! row-sum lumped masses, the boundary ring, the essential conditions, the tools and the
//! contact stage, the critical step and, if the scene asks, mass scaling.

use super::conduction::update_eigenvalue;
use super::contact_stage;
use super::critical_step::measure_critical_step;
use super::detachment::{nearest_in_rows, Isolation};
use super::discretization::{Discretization, Thermal, Transfer};
use super::energy::Energy;
use super::heat::Heat;
use super::layout::{Scatter, MAX_GROUP};
use super::mass_scaling::{self, stiffness_bounds, Plan};
use super::nodal_stabilization::{Forces, Tables};
use super::outline::Outline;
use super::point_outputs::PointOut;
use super::simulation::{Simulation, StageTimes};
use super::state::State;
use super::stress;
use super::update::{self, initial_motion};
use super::workspace::Workspace;
use crate::constraints::Constraints;
use crate::contact::symmetry;
use crate::error::{Error, Result};
use crate::integration::{orthant_shapes, point_shapes, PointSet};
use crate::material::{HenckyJ2, PointState};
use crate::math::Real;
use crate::memory;
use crate::rk_shape::{Lattice, ShapeTable, Site};
use crate::scene::{Component, Edge, IntegrationRule, Kinematics, Scene, TimeSpec};
use crate::team::Team;
use crate::tools::{Tool, SEARCH_DEPTH_SPACINGS};
use std::f64::consts::PI;
use std::time::Instant;

impl Simulation {
    /// Build the discretisation of a validated scene.
    pub fn new(scene: &Scene) -> Result<Simulation> {
        let t0 = Instant::now();
        let axi = scene.model.kinematics == Kinematics::Axisymmetric;
        let w = &scene.workpiece;
        let [nx, ny] = w.particles;
        let h = [
            w.size_m[0] / (nx - 1) as Real,
            w.size_m[1] / (ny - 1) as Real,
        ];
        let support = [
            scene.discretization.support[0] * h[0],
            scene.discretization.support[1] * h[1],
        ];
        let [sx, sy] = scene.discretization.support;
        memory::check(
            nx * ny,
            2,
            scene.discretization.integration,
            (sx * sy).sqrt(),
            "workpiece.particles",
        )?;
        let t_shapes = Instant::now();
        let lattice = Lattice::new(w.origin_m, h, [nx, ny], support);
        let ref_pos = lattice.cloud().positions.clone();
        let (points, pt) = point_shapes(&lattice, scene.discretization.integration)?;
        let particles: Vec<Site> = (0..ny)
            .flat_map(|j| {
                (0..nx).map(move |i| Site {
                    node: [i, j],
                    offset: [0.0; 2],
                })
            })
            .collect();
        let mut nodal = lattice.shape_table(&particles, &|j| format!("particle {j}"))?;
        nodal.drop_gradients();
        let shape_functions = t_shapes.elapsed();
        let (weights, inv_radius) = point_weights(&points, scene);
        let rho = scene.material.density_kg_per_m3;
        let np = ref_pos.len();
        let mass = lumped_masses(&pt, &weights, rho, &ref_pos)?;
        // Chunks of about two rows of cells, at least 64 points: enough chunks to balance
        // the threads, few enough that the buffers overlap little.
        let chunk = (2 * pt.rows() / (ny - 1)).max(64);
        let scatter = Scatter::new(&pt, np, chunk, MAX_GROUP);
        let stabilization = match scene.discretization.scni_stabilization {
            Some(c) if c > 0.0 && scene.discretization.integration == IntegrationRule::Scni => {
                let (quadrants, table) = orthant_shapes::<2, 4>(&lattice)?;
                let (weights, _) = point_weights(&quadrants, scene);
                let m = &scene.material;
                let mu = m.youngs_modulus_pa / (2.0 * (1.0 + m.poisson_ratio));
                Some(Tables::new::<4>(c, mu, &table, &weights, np))
            }
            _ => None,
        };
        let mut material = HenckyJ2::new(
            scene.material.youngs_modulus_pa,
            scene.material.poisson_ratio,
            scene.material.hardening.clone(),
        );
        material.thermoelastic = scene.thermal.as_ref().and_then(|t| t.thermoelastic());
        let wave_speed = material.wave_speed(rho);
        let scaling = scene.time.mass_scaling.map(|ms| match ms.factor {
            Some(f) => Plan::Uniform(f),
            None => Plan::Selective {
                target: ms.target_dt_s.unwrap_or(0.0),
                modulus: rho * wave_speed * wave_speed,
                stiffness: stiffness_bounds(
                    &pt,
                    &weights,
                    &inv_radius,
                    axi,
                    rho * wave_speed * wave_speed,
                    np,
                ),
            },
        });
        let boundary = boundary_ring(nx, ny);
        let outline = Outline::on_lattice(&lattice, nx, &boundary)?;
        let constraints = Constraints::new(essential_rows(scene), &nodal, &mass)?;
        let depth = SEARCH_DEPTH_SPACINGS * h[0].max(h[1]);
        let tools: Vec<Tool> = scene.tools.iter().map(|t| Tool::new(t, depth)).collect();
        let (v, initial) = initial_motion(w.initial_velocity_m_per_s, constraints.as_ref(), &mass);
        let npts = points.positions.len();
        let stable_dt = h[0].min(h[1]) / wave_speed;
        let out = PointOut::at(
            &material,
            0.0,
            scene.thermal.as_ref().map(|t| t.initial_temperature_c),
        );
        let contact = contact_stage::build(
            scene,
            &boundary,
            &nodal,
            &ref_pos,
            &points.positions,
            &tools,
        );
        let planes = symmetry::planes(scene, &ref_pos);
        let self_touching = match scene.self_contact.enabled {
            true => vec![false; boundary.len()],
            false => Vec::new(),
        };
        let plane_held = vec![false; contact.candidate_count() * planes.len()];
        let pairs = contact.candidate_count() * tools.len();
        let held = match tools.iter().all(|t| t.separation) {
            true => Vec::new(),
            false => vec![false; pairs],
        };
        let stick = vec![None; pairs];
        let thermal = scene.thermal.as_ref().map(|spec| Thermal {
            spec: spec.clone(),
            capacity: spec.heat_capacity(),
            density: rho,
            transfer: scene.transfers_heat().then(|| Transfer {
                adiabatic_edge: adiabatic_edges(scene),
                lambda0: 0.0,
            }),
        });
        let initial_spacing = nearest_in_rows(&nodal, &ref_pos);
        let mut disc = Discretization {
            material,
            nx,
            ny,
            spacing: h,
            inv_mass: mass.iter().map(|m| 1.0 / m).collect(),
            mass,
            weights,
            inv_radius,
            ref_pos,
            original: lattice.cloud().positions.clone(),
            lattice_volumes: lattice.cloud().volumes.clone(),
            reference_jacobian: vec![1.0; npts],
            points,
            scatter,
            stabilization,
            nodal,
            initial_spacing,
            boundary,
            outline,
            constraints,
            planes,
            critical_dt0: stable_dt,
            mass_scaling: None,
            scaling_target: None,
            thermal,
        };
        let mut ws = Workspace {
            out: vec![out; npts],
            buf: disc.scatter.buffers(),
            f_int: vec![[0.0; 2]; np],
            v_prev: v.clone(),
            stabilization: disc.stabilization.as_ref().map(|_| Forces::new(np)),
            contact,
            team: Team::default(),
            simd: true,
        };
        let mut st = State {
            step: 0,
            time: 0.0,
            dt_prev: 0.0,
            d: vec![[0.0; 2]; np],
            v: v.clone(),
            points: vec![PointState::default(); npts],
            tools: tools.iter().map(|t| t.state).collect(),
            energy: Energy::starting(initial),
            max_penetration: 0.0,
            stable_dt,
            anchor_time: 0.0,
            anchor_step: 0,
            kinetic_to_internal_max: 0.0,
            first_contact_s: None,
            held,
            plane_held,
            self_touching,
            max_beyond_plane: 0.0,
            isolation: Isolation::default(),
            plane_feedback_max: 0.0,
            max_inside_itself: 0.0,
            max_crossings: 0,
            laps: Vec::new(),
            stick,
            fill: vec![None; scene.tools.iter().map(|t| t.fill_points.len()).sum()],
            reference: None,
            max_stretch: 0.0,
            pressure: vec![0.0; scene.tools.len() * scene.output.pressure_stations.unwrap_or(0)],
            heat: scene.thermal.as_ref().map(|t| {
                let particles = if scene.transfers_heat() { np } else { 0 };
                let (friction, pressure) = (
                    scene.heats_by_friction(),
                    scene.transfers_heat_by_pressure(),
                );
                // E(T) / E at the initial temperature, unstrained.
                let thermoelastic = t
                    .thermoelastic()
                    .map(|te| [te.modulus_factor_at(t.initial_temperature_c), 0.0, 0.0, 0.0]);
                Heat::initial(
                    t,
                    npts,
                    scene.tools.len(),
                    particles,
                    friction,
                    pressure,
                    thermoelastic,
                )
            }),
        };
        disc.critical_dt0 = measure_critical_step(scene, &disc, &mut st, &mut ws)?;
        update_eigenvalue(&mut disc, 0, 0.0)?;
        if let Some(plan) = scaling {
            mass_scaling::scale(scene, &mut disc, &mut st, &mut ws, plan)?;
        }
        stress::run(scene, &disc, &mut st, &mut ws)?;
        update::forces(&disc, &tools, &mut st, &mut ws, None);
        let sim = Simulation {
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
        check_fixed_step(&scene.time, sim.st.stable_dt, h[0].min(h[1]) / wave_speed)?;
        Ok(sim)
    }
}

/// Most steps a run may take at its setup's natural step: as for a fixed `time.dt_s`, past
/// it the run would not end (a `dt_safety` of 1e-20 ran with no sign of progress).
const MOST_STEPS: Real = 1e9;

/// The step of `time` against the setup's critical step `stable_dt` (s): a fixed step
/// (`time.dt_s`) above it stops the setup, `h_c` (`h_min / c`, s) quoted in the message; a
/// natural step (`dt_safety` of it) that would take more than [`MOST_STEPS`] steps to the
/// end time stops it too, naming `time.dt_safety`.
pub(super) fn check_fixed_step(time: &TimeSpec, stable_dt: Real, h_c: Real) -> Result<()> {
    let steps = time.end_s / (time.dt_safety * stable_dt);
    if time.dt_s.is_none() && (steps > MOST_STEPS || steps.is_nan()) {
        return Err(Error::Request(format!(
            "time.dt_safety = {:e} of the critical step {stable_dt:.3e} s gives {steps:.1e} steps to time.end_s = {:e} s, more than {MOST_STEPS:e}: raise time.dt_safety",
            time.dt_safety, time.end_s
        )));
    }
    match time.dt_s {
        Some(dt) if dt > stable_dt => Err(Error::Unstable {
            step: 0,
            time: 0.0,
            dt,
            dt_crit: stable_dt,
            detail: format!(
                "time.dt_s is above the critical step 2 / omega_max of this discretisation (h_min / c = {h_c:.4e} s); lower it or remove it to use dt_safety"
            ),
        }),
        _ => Ok(()),
    }
}

/// Volume weights `w_p` of the points (m^3: `2 pi R_p A_p` in axisymmetry, `A_p depth` in
/// plane strain) and `1 / R_p` (1/m; 1 in plane strain).
fn point_weights(points: &PointSet, scene: &Scene) -> (Vec<Real>, Vec<Real>) {
    let axi = scene.model.kinematics == Kinematics::Axisymmetric;
    points
        .positions
        .iter()
        .zip(&points.areas)
        .map(|(x, a)| {
            if axi {
                (a * 2.0 * PI * x[0], 1.0 / x[0])
            } else {
                (a * scene.model.depth_m, 1.0)
            }
        })
        .unzip()
}

/// Row-sum lumped masses `m_I = sum_p rho N_I(x_p) w_p` (kg) from the points' rows `pt`,
/// weights `weights` (m^3) and density `rho` (kg/m^3); a mass that is not positive (too
/// small a support) is an error naming the particle at `positions` (m).
pub(super) fn lumped_masses<const D: usize>(
    pt: &ShapeTable<D>,
    weights: &[Real],
    rho: Real,
    positions: &[[Real; D]],
) -> Result<Vec<Real>> {
    let mut mass = vec![0.0; positions.len()];
    for (p, w) in weights.iter().enumerate() {
        for e in pt.row(p) {
            mass[pt.index[e] as usize] += rho * pt.n[e] * w;
        }
    }
    match mass
        .iter()
        .enumerate()
        .find(|(_, m)| m.is_nan() || **m <= 0.0)
    {
        Some((i, m)) => Err(Error::ShapeFunctions(format!(
            "lumped mass of particle {i} at {:?} m is {m:.3e} kg; increase the support or the resolution",
            positions[i]
        ))),
        None => Ok(mass),
    }
}

/// The boundary particles of an `nx x ny` lattice, counter-clockwise from the lower-left.
fn boundary_ring(nx: usize, ny: usize) -> Vec<u32> {
    let id = |i: usize, j: usize| (j * nx + i) as u32;
    let mut boundary = Vec::new();
    boundary.extend((0..nx).map(|i| id(i, 0)));
    boundary.extend((1..ny).map(|j| id(nx - 1, j)));
    boundary.extend((0..nx - 1).rev().map(|i| id(i, ny - 1)));
    boundary.extend((1..ny - 1).rev().map(|j| id(0, j)));
    boundary
}

/// The essential conditions' rows `(particle, component)`: the scene's fixed edges, plus
/// the radial component on the axis of an axisymmetric body that reaches it.
fn essential_rows(scene: &Scene) -> Vec<(u32, usize)> {
    let [nx, ny] = scene.workpiece.particles;
    let mut rows = Vec::new();
    for c in &scene.constraints {
        for comp in &c.fix {
            let k = match comp {
                Component::X => 0,
                Component::Y => 1,
            };
            rows.extend(c.edge.particles(nx, ny).into_iter().map(|j| (j, k)));
        }
    }
    let axi = scene.model.kinematics == Kinematics::Axisymmetric;
    if axi && scene.workpiece.origin_m[0] == 0.0 {
        rows.extend(Edge::XMin.particles(nx, ny).into_iter().map(|j| (j, 0)));
    }
    rows
}

/// Which particles lie on a constrained edge (a symmetry plane), whose boundary segments
/// exchange no heat; empty unless the scene's heat moves.
fn adiabatic_edges(scene: &Scene) -> Vec<bool> {
    if !scene.transfers_heat() {
        return Vec::new();
    }
    let [nx, ny] = scene.workpiece.particles;
    let mut on = vec![false; nx * ny];
    for c in &scene.constraints {
        for j in c.edge.particles(nx, ny) {
            on[j as usize] = true;
        }
    }
    on
}
