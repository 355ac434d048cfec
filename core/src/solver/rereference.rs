//! Kernel re-referencing (`discretization.rereference_stretch`): when an integration point's
//! largest principal in-plane stretch since the last reference reaches the scene's value,
//! the discretisation is rebuilt on the current configuration and the state carried over,
//! as updated-Lagrangian RKPM does at intervals (Chen, Pan, Wu, Liu 1996, sec. 4; Chen, Wu,
//! Yoon, You 2001 for the same transfer in forming). With a Lagrangian kernel the supports
//! stretch with the material; in a forging flash, strains of 5-10 draw them out until a
//! point's neighbours lie nearly on a line and the approximation degrades.
//!
//! At a re-reference (all at the positions `x = X + sum_I N_I(X) d_I` of the end of the
//! last step):
//! - particles: `X' = x_J`; each particle's cell `G' = F_J G` (m; `G = diag(h_x, h_y)` on
//!   the lattice) and kernel volume `V' = det F_J V` (m^2), with `F_J` and `det F_J`
//!   averaged over the points that see the particle with weights `|N_J(x_p)| w_p`; its
//!   support radii `a'_k = s_k (|G'_k1| + |G'_k2|)` (m, `s` = `discretization.support`),
//!   the axis-aligned extent of its deformed cell, so that a stretched region keeps about
//!   `s` neighbours per direction ([`KernelCloud::with_supports`]);
//! - integration points: `x_p` becomes the point's position with its weight `w_p` kept (the
//!   material's energy and stress are per original volume, so `f_I = sum_p w_p tau grad_x
//!   N_I` is the same sum in the new reference), `1 / R_p = 1 / r_p`, and the history pushed
//!   forward, `C_p'^{-1} = F C_p^{-1} F^T` (the elastic left Cauchy-Green tensor `b_e`, and
//!   `F'_33^2 C_p^{-1}_33` out of plane), so that the trial state of the next step is the
//!   one the old reference would give; `J_ref = J` keeps the Jacobian and Cauchy stress
//!   measured from the original configuration;
//! - displacements `d' = 0`; velocities: the coefficients whose interpolation at the new
//!   reference reproduces the physical particle velocities, `sum_I N'_I(X'_J) v'_I = v_J`
//!   (least squares by conjugate gradients on the nodal matrix), projected onto the essential conditions;
//!   the kinetic energy this changes is booked as `Energy::remap` (J); the temperature
//!   field of a scene whose heat moves alike: the particle coefficients whose interpolation
//!   reproduces the particles' temperatures (the points keep theirs, and the next heat
//!   stage gathers what the fit missed into the particles, the heat kept exactly);
//!   conduction's largest eigenvalue is measured again on the new shape functions;
//! - masses, the boundary ring, the tools' state, the contact pairs' held and stick state
//!   are the particles' own and stay; the contact stage, the essential conditions and the
//!   critical step are rebuilt (the step is measured again on the new shape functions with
//!   unstressed points, as at the start).
//!
//! Without re-referencing (the default) nothing here runs and the bits are those of the
//! Lagrangian kernel. SCNI is refused by the scene: its nodal domains are not rebuilt.

use super::conduction;
use super::contact_stage;
use super::critical_step::measure_critical_step;
use super::discretization::{Discretization, Thermal};
use super::energy::kinetic_energy;
use super::heat::Heat;
use super::layout::MAX_GROUP;
use super::mass_scaling::{hold, row_sum_bounds};
use super::outline::Outline;
use super::state::{Reference, State};
use super::workspace::Workspace;
use crate::constraints::Constraints;
use crate::error::{Error, Result};
use crate::material::simo1992_hencky_j2::elastic_left_cauchy_green;
use crate::material::PointState;
use crate::math::Real;
use crate::rk_shape::{condition_sites, cover_sites, KernelCloud, ShapeTable, MAX_CONDITION};
use crate::scene::{Kinematics, Scene};
use crate::tools::Tool;

/// Conjugate-gradient iterations allowed for the velocity transfer.
const FIT_ITERATIONS: usize = 500;
/// Relative residual at which the velocity transfer stops (-).
const FIT_TOLERANCE: Real = 1e-12;

/// The deformation at one integration point: `F = I + sum_I d_I (x) grad N_I`
/// (`[F_xX, F_xY, F_yX, F_yY]`), the out-of-plane stretch and the displacement (m).
struct PointMotion {
    f: [Real; 4],
    f33: Real,
    u: [Real; 2],
}

/// Stage 0 of the step: re-references the kernel when the last stress stage's largest
/// stretch reached the scene's `discretization.rereference_stretch`; a failure stops the
/// run naming the step ([`failed`]).
pub(super) fn if_due(
    scene: &Scene,
    disc: &mut Discretization,
    tools: &[Tool],
    st: &mut State,
    ws: &mut Workspace,
) -> Result<()> {
    match scene.discretization.rereference_stretch {
        Some(limit) if st.max_stretch >= limit => {
            now(scene, disc, tools, st, ws).map_err(|e| failed(st.step, st.time, e))
        }
        _ => Ok(()),
    }
}

/// Re-references the kernel now, on the positions of the current displacement (see the
/// module doc).
pub(super) fn now(
    scene: &Scene,
    disc: &mut Discretization,
    tools: &[Tool],
    st: &mut State,
    ws: &mut Workspace,
) -> Result<()> {
    let axi = scene.model.kinematics == Kinematics::Axisymmetric;
    let np = disc.ref_pos.len();
    let npts = disc.weights.len();
    let positions = disc.positions(&st.d);
    let motions: Vec<PointMotion> = (0..npts)
        .map(|p| point_motion(disc, &st.d, p, axi))
        .collect();
    // Particle averages of F and det F over the points that see them.
    let mut sum = vec![[0.0; 6]; np];
    for (p, m) in motions.iter().enumerate() {
        let det = m.f[0] * m.f[3] - m.f[1] * m.f[2];
        for (i, [n, _, _]) in disc.scatter.point_row(p) {
            let w = (n * disc.weights[p]).abs();
            let s = &mut sum[i];
            for (sk, fk) in s.iter_mut().zip(m.f) {
                *sk += w * fk;
            }
            s[4] += w * det;
            s[5] += w;
        }
    }
    let (old_cells, old_volumes, old_jacobian) = current_reference(disc, st);
    let mut cells = Vec::with_capacity(np);
    let mut volumes = Vec::with_capacity(np);
    for (i, s) in sum.iter().enumerate() {
        let (f, det) = match s[5] > 0.0 {
            true => ([s[0], s[1], s[2], s[3]].map(|x| x / s[5]), s[4] / s[5]),
            false => ([1.0, 0.0, 0.0, 1.0], 1.0),
        };
        let g = old_cells[i];
        cells.push([
            f[0] * g[0] + f[1] * g[2],
            f[0] * g[1] + f[1] * g[3],
            f[2] * g[0] + f[3] * g[2],
            f[2] * g[1] + f[3] * g[3],
        ]);
        volumes.push(old_volumes[i] * det);
    }
    let points: Vec<[Real; 2]> = motions
        .iter()
        .enumerate()
        .map(|(p, m)| {
            let x = disc.points.positions[p];
            [x[0] + m.u[0], x[1] + m.u[1]]
        })
        .collect();
    let point_jacobian: Vec<Real> = motions
        .iter()
        .zip(&old_jacobian)
        .map(|(m, j)| j * (m.f[0] * m.f[3] - m.f[1] * m.f[2]) * m.f33)
        .collect();
    // The history pushed forward: C_p'^{-1} = b_e = F C_p^{-1} F^T (F_33^2 out of plane).
    for (state, m) in st.points.iter_mut().zip(&motions) {
        state.cp_inv = elastic_left_cauchy_green(m.f, m.f33, state.cp_inv);
    }
    // Physical velocities before the new shape functions replace the old.
    let v_now: Vec<[Real; 2]> = (0..np).map(|j| disc.nodal.interpolate(j, &st.v)).collect();
    let v_before: Vec<[Real; 2]> = (0..np)
        .map(|j| disc.nodal.interpolate(j, &ws.v_prev))
        .collect();
    let kinetic_before = kinetic_energy(&disc.mass, &st.v);
    let before = st.stable_dt;
    let temperature_now =
        particle_temperatures(&disc.nodal, st.heat.as_ref(), disc.thermal.as_ref());
    let previous = st.reference.as_ref();
    let mut reference = Reference {
        count: previous.map_or(0, |r| r.count) + 1,
        time_s: st.time,
        particles: positions,
        volumes,
        cells,
        points,
        point_jacobian,
        fit_residual: 0.0,
        short_sites: previous.map_or(0, |r| r.short_sites),
        flat_sites: previous.map_or(0, |r| r.flat_sites),
        masses: None,
    };
    let (short, flat) = install(scene, disc, tools, st, ws, &reference)?;
    reference.short_sites += short as u64;
    reference.flat_sites += flat as u64;
    reference.masses = hold_target(scene, disc, st, ws, before)?;
    let (v, r1) = fit(&disc.nodal, &v_now);
    let (v_prev, r2) = fit(&disc.nodal, &v_before);
    reference.fit_residual = r1.max(r2);
    if let (Some(t), Some(h)) = (temperature_now, st.heat.as_mut()) {
        let r3 = carry_temperatures(&disc.nodal, &t, h);
        reference.fit_residual = reference.fit_residual.max(r3);
    }
    st.v = v;
    ws.v_prev = v_prev;
    if let Some(c) = &disc.constraints {
        c.project(&mut st.v, &disc.mass);
        c.project(&mut ws.v_prev, &disc.mass);
    }
    st.d = vec![[0.0; 2]; np];
    let kinetic_after = kinetic_energy(&disc.mass, &st.v);
    st.energy.remap += kinetic_after - kinetic_before;
    st.energy.kinetic += kinetic_after - kinetic_before;
    st.reference = Some(reference);
    st.stable_dt = disc.critical_dt0;
    st.max_stretch = 1.0;
    Ok(())
}

/// The particles' cells and kernel volumes and the points' Jacobians of the current
/// reference (the lattice's before the first re-reference).
fn current_reference(disc: &Discretization, st: &State) -> (Vec<[Real; 4]>, Vec<Real>, Vec<Real>) {
    match &st.reference {
        Some(r) => (r.cells.clone(), r.volumes.clone(), r.point_jacobian.clone()),
        None => {
            let [hx, hy] = disc.spacing;
            (
                vec![[hx, 0.0, 0.0, hy]; disc.ref_pos.len()],
                disc.lattice_volumes.clone(),
                vec![1.0; disc.weights.len()],
            )
        }
    }
}

/// `F`, `F_33` and the displacement at point `p` from the coefficients `d` (m).
fn point_motion(disc: &Discretization, d: &[[Real; 2]], p: usize, axi: bool) -> PointMotion {
    let (mut f, mut u) = ([1.0, 0.0, 0.0, 1.0], [0.0; 2]);
    for (i, [n, nx, ny]) in disc.scatter.point_row(p) {
        let d = d[i];
        f[0] += d[0] * nx;
        f[1] += d[0] * ny;
        f[2] += d[1] * nx;
        f[3] += d[1] * ny;
        u[0] += d[0] * n;
        u[1] += d[1] * n;
    }
    let f33 = match axi {
        true => 1.0 + u[0] * disc.inv_radius[p],
        false => 1.0,
    };
    PointMotion { f, f33, u }
}

/// Builds the shape functions, the scatter, the essential conditions, the contact stage
/// and the critical step on `reference`, and conduction's eigenvalue; the rest of the
/// state is left to the caller. Returns how many sites' supports were grown, too few
/// covering and too flat a cover ([`shapes_on`]).
pub(super) fn install(
    scene: &Scene,
    disc: &mut Discretization,
    tools: &[Tool],
    st: &mut State,
    ws: &mut Workspace,
    reference: &Reference,
) -> Result<(usize, usize)> {
    let axi = scene.model.kinematics == Kinematics::Axisymmetric;
    let s = scene.discretization.support;
    let supports = reference
        .cells
        .iter()
        .map(|g| [s[0] * g[0].hypot(g[1]), s[1] * g[2].hypot(g[3])])
        .collect();
    let (cloud, pt, nodal, grown) = shapes_on(
        &reference.particles,
        &reference.volumes,
        supports,
        &reference.points,
        reference.count,
        s,
    )?;
    let np = reference.particles.len();
    disc.scatter.rebuild(pt, np, MAX_GROUP, &mut ws.buf);
    if let Some(mass) = &reference.masses {
        disc.inv_mass = mass.iter().map(|m| 1.0 / m).collect();
        disc.mass.clone_from(mass);
    }
    if let Some(c) = &disc.constraints {
        disc.constraints = Constraints::new(c.rows.clone(), &nodal, &disc.mass)?;
    }
    disc.outline = Outline::on_cloud(&cloud, &reference.particles, &disc.boundary)?;
    ws.contact = contact_stage::build(
        scene,
        &disc.boundary,
        &nodal,
        &reference.particles,
        &reference.points,
        tools,
    );
    disc.nodal = nodal;
    disc.ref_pos.clone_from(&reference.particles);
    disc.points.positions.clone_from(&reference.points);
    if axi {
        disc.inv_radius = reference.points.iter().map(|x| 1.0 / x[0]).collect();
    }
    disc.reference_jacobian
        .clone_from(&reference.point_jacobian);
    disc.critical_dt0 = measure_unstressed(scene, disc, st, ws)?;
    if let (Some(mass), Some(target)) = (&reference.masses, &disc.scaling_target) {
        let report = target.report(mass, disc.critical_dt0);
        disc.mass_scaling = Some(report);
    }
    // Conduction's largest eigenvalue on the new shape functions.
    conduction::update_eigenvalue(disc, st.step, st.time)?;
    Ok(grown)
}

/// The critical step of the current shape functions and masses (s), measured with
/// unstressed points as at the start (the stressed ones would answer with their stress,
/// not stiffness); the state is left as it was.
fn measure_unstressed(
    scene: &Scene,
    disc: &Discretization,
    st: &mut State,
    ws: &mut Workspace,
) -> Result<Real> {
    let (points, out) = (st.points.clone(), ws.out.clone());
    st.points = vec![PointState::default(); points.len()];
    let measured = measure_critical_step(scene, disc, st, ws);
    st.points = points;
    ws.out = out;
    measured
}

/// Selective mass scaling on the new shape functions, as the scene's
/// `time.mass_scaling.at_rereferences` asks (`mass_scaling::hold`, with `before` the
/// critical step the run followed before the re-reference, s, and the stiffness bounds
/// `k_I = M sum_p w_p g_I sum_J g_J`, `g_I = |grad N_I| + |N_I| / R` in axisymmetry, from
/// the new shape functions): the masses installed with the essential conditions'
/// projection, the critical step and the report updated. Returns the masses, `None` where
/// the masses are kept.
fn hold_target(
    scene: &Scene,
    disc: &mut Discretization,
    st: &mut State,
    ws: &mut Workspace,
    before: Real,
) -> Result<Option<Vec<Real>>> {
    let Some(target) = disc.scaling_target.take() else {
        return Ok(None);
    };
    let axi = scene.model.kinematics == Kinematics::Axisymmetric;
    let np = disc.mass.len();
    let stiffness = row_sum_bounds(&disc.weights, target.modulus, np, |p, g| {
        let inv_r = disc.inv_radius[p];
        g.extend(disc.scatter.point_row(p).map(|(i, [n, nx, ny])| {
            let grad = nx.hypot(ny);
            (i, if axi { grad + (n * inv_r).abs() } else { grad })
        }))
    });
    let held = hold(
        &target,
        before,
        &stiffness,
        disc.mass.clone(),
        disc.critical_dt0,
        scene.time.dt_safety,
        |mass| {
            if let Some(c) = &disc.constraints {
                disc.constraints = Constraints::new(c.rows.clone(), &disc.nodal, &mass)?;
            }
            disc.inv_mass = mass.iter().map(|m| 1.0 / m).collect();
            disc.mass = mass;
            measure_unstressed(scene, disc, st, ws)
        },
    );
    disc.scaling_target = Some(target);
    let (mass, report) = held?;
    disc.critical_dt0 = report.critical_dt_s;
    disc.mass_scaling = Some(report);
    Ok(Some(mass))
}

/// The temperature field at the particles before the shape functions change (2D and 3D; a
/// scene whose heat moves, `None` otherwise): `T_J = sum_I N_I(X_J) T_I` (degrees C; in
/// enthalpy with a capacity table, [`crate::material::HeatCapacity::interpolate`]) with
/// the `nodal` shape functions and the particles' temperature coefficients `T_I` of
/// `heat`, each in the first component of a `D`-vector for [`fit`].
pub(super) fn particle_temperatures<const D: usize>(
    nodal: &ShapeTable<D>,
    heat: Option<&Heat>,
    thermal: Option<&Thermal>,
) -> Option<Vec<[Real; D]>> {
    match (heat, thermal) {
        (Some(h), Some(th)) if !h.particle_c.is_empty() => Some(
            (0..h.particle_c.len())
                .map(|j| {
                    let row = nodal.row(j);
                    let t = th.capacity.interpolate(
                        row.map(|e| (nodal.n[e], h.particle_c[nodal.index[e] as usize])),
                    );
                    std::array::from_fn(|k| if k == 0 { t } else { 0.0 })
                })
                .collect(),
        ),
        _ => None,
    }
}

/// The temperature coefficients on the new `nodal` shape functions (2D and 3D): those whose
/// interpolation at the particles reproduces `target` ([`particle_temperatures`] before
/// the change), by the velocities' least-squares [`fit`], into `heat`'s `T_I`; the points
/// keep their temperatures, and the next heat stage gathers what the fit missed into the
/// particles (the heat kept exactly). Returns the fit's relative residual (-).
pub(super) fn carry_temperatures<const D: usize>(
    nodal: &ShapeTable<D>,
    target: &[[Real; D]],
    heat: &mut Heat,
) -> Real {
    let (fitted, residual) = fit(nodal, target);
    heat.particle_c = fitted.iter().map(|t| t[0]).collect();
    residual
}

/// The shape functions of re-reference `count` (2D and 3D): the kernel cloud of the
/// `particles` (m) with their kernel `volumes` (m^D) and support radii `supports` (m), the
/// points' table at `points` (m) and the particles' own (values only), with how many
/// particles and points were covered by fewer than `2^D` supports, whose nearest
/// particles' supports were grown to reach them ([`cover_sites`], with the scene's
/// support `s` in spacings per direction), and how many then had a moment matrix
/// conditioned worse than [`MAX_CONDITION`], for which more supports were grown
/// ([`condition_sites`]).
pub(super) fn shapes_on<const D: usize>(
    particles: &[[Real; D]],
    volumes: &[Real],
    mut supports: Vec<[Real; D]>,
    points: &[[Real; D]],
    count: u32,
    s: [Real; D],
) -> Result<(KernelCloud<D>, ShapeTable<D>, ShapeTable<D>, (usize, usize))> {
    let short = cover_sites(particles, &mut supports, particles, 1 << D, s)
        + cover_sites(particles, &mut supports, points, 1 << D, s);
    let flat = condition_sites(
        particles,
        volumes,
        &mut supports,
        particles,
        MAX_CONDITION,
        s,
    ) + condition_sites(particles, volumes, &mut supports, points, MAX_CONDITION, s);
    let cloud = KernelCloud::with_supports(particles.to_vec(), volumes.to_vec(), supports);
    let pt = cloud.shape_table(points, &|p| {
        format!("integration point {p} at re-reference {count}")
    })?;
    let mut nodal = cloud.shape_table(particles, &|j| {
        format!("particle {j} at re-reference {count}")
    })?;
    nodal.drop_gradients();
    Ok((cloud, pt, nodal, (short, flat)))
}

/// The coefficients `c` with `sum_I N_I(X_J) c_I = target_J` at every particle: the
/// least-squares solution of the nodal system `A c = b` by conjugate gradients on the normal
/// equations (CGLS; Paige and Saunders 1982, Bjorck 1996 sec. 7.4), from `c = b`, each
/// component on its own. Returns them with the relative residual `max |b - A c| / max |b|`
/// reached (-).
pub(super) fn fit<const D: usize>(
    nodal: &ShapeTable<D>,
    target: &[[Real; D]],
) -> (Vec<[Real; D]>, Real) {
    let n = target.len();
    let apply = |x: &[Real]| -> Vec<Real> {
        (0..n)
            .map(|j| {
                nodal
                    .row(j)
                    .map(|e| nodal.n[e] * x[nodal.index[e] as usize])
                    .sum()
            })
            .collect()
    };
    let apply_t = |y: &[Real]| -> Vec<Real> {
        let mut out = vec![0.0; n];
        for (j, yj) in y.iter().enumerate() {
            for e in nodal.row(j) {
                out[nodal.index[e] as usize] += nodal.n[e] * yj;
            }
        }
        out
    };
    let dot = |a: &[Real], b: &[Real]| a.iter().zip(b).map(|(x, y)| x * y).sum::<Real>();
    let largest = |a: &[Real]| a.iter().fold(0.0 as Real, |m, x| m.max(x.abs()));
    let mut c = target.to_vec();
    let mut worst: Real = 0.0;
    for k in 0..D {
        let b: Vec<Real> = target.iter().map(|v| v[k]).collect();
        let scale = largest(&b);
        if scale == 0.0 {
            continue;
        }
        let mut x = b.clone();
        let ax = apply(&x);
        let mut r: Vec<Real> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
        let mut s = apply_t(&r);
        let mut p = s.clone();
        let mut gamma = dot(&s, &s);
        for _ in 0..FIT_ITERATIONS {
            if largest(&r) <= FIT_TOLERANCE * scale || gamma == 0.0 {
                break;
            }
            let q = apply(&p);
            let alpha = gamma / dot(&q, &q);
            for (xi, pi) in x.iter_mut().zip(&p) {
                *xi += alpha * pi;
            }
            for (ri, qi) in r.iter_mut().zip(&q) {
                *ri -= alpha * qi;
            }
            s = apply_t(&r);
            let next = dot(&s, &s);
            let beta = next / gamma;
            gamma = next;
            for (pi, si) in p.iter_mut().zip(&s) {
                *pi = si + beta * *pi;
            }
        }
        worst = worst.max(largest(&r) / scale);
        for (ci, xi) in c.iter_mut().zip(&x) {
            ci[k] = *xi;
        }
    }
    (c, worst)
}

/// A re-reference that failed names where it stopped.
pub(super) fn failed(step: u64, time: Real, e: Error) -> Error {
    Error::ShapeFunctions(format!(
        "re-referencing the kernel at step {step} (t = {time:.6e} s): {e}"
    ))
}
