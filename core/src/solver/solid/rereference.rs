//! Kernel re-referencing of a 3D body (`discretization.rereference_stretch`): the 2D stage
//! ([`crate::solver`]'s `rereference.rs`, whose module doc gives the method: Chen, Pan, Wu,
//! Liu 1996, sec. 4; Chen, Wu, Yoon, You 2001) with the full 3D deformation. When a point's
//! largest principal stretch since the last reference reaches the scene's value, the
//! shape functions are rebuilt on the current configuration `x = X + sum_I N_I(X) d_I`:
//! - particles: `X' = x_J`; each particle's cell `G' = F_J G` (m, 3 x 3; `G` at the start the
//!   diagonal of its cell extents, the supports over `discretization.support`) and kernel
//!   volume `V' = det F_J V` (m^3), `F_J` and `det F_J` averaged over the points that see
//!   the particle with weights `|N_J(x_p)| w_p`; support radii `a'_k = s |G'_k.|` (m, the
//!   row's length), so that a stretched region keeps about `s` neighbours per direction,
//!   grown where a particle or point would lie inside fewer than 8 supports
//!   ([`crate::rk_shape::cover_sites`]);
//! - points: `x_p` becomes the point's position, its weight `w_p` kept (the stress and
//!   energy are per original volume), the history pushed forward, `C_p'^{-1} = F C_p^{-1}
//!   F^T` (the elastic left Cauchy-Green tensor `b_e`), and `J_ref' = J_ref det F` so that
//!   the Jacobian and Cauchy stress stay measured from the original configuration;
//! - displacements `d' = 0`; velocities the least-squares coefficients whose interpolation
//!   at the new reference reproduces the physical particle velocities (the 2D fit), the
//!   kinetic energy this changes booked as `Energy::remap` (J); the temperature field of a
//!   scene whose heat moves alike (2D's): the particle coefficients whose interpolation
//!   reproduces the particles' temperatures `sum_I N_I(X_J) T_I`, the points keeping
//!   theirs (the next heat stage gathers what the fit missed into the particles, the heat
//!   kept exactly);
//! - the contact stage's move bound starts again (every particle is evaluated at the next
//!   stage); masses, the planes' states, which particles are held, the friction carried and the
//!   heat surface's faces are the particles' own and stay; the critical step is measured
//!   again on the new shape functions with unstressed points, as at the start, and
//!   conduction's largest eigenvalue on them.

use super::heat::update_eigenvalue;
use super::setup::measure_critical_step;
use super::{SolidDisc, SolidState, SolidWorkspace};
use crate::error::Result;
use crate::material::simo1992_hencky_j2_3d::elastic_left_cauchy_green3;
use crate::material::PointState3;
use crate::math::Real;
use crate::scene::solid::SolidScene;
use crate::solver::energy::kinetic_energy;
use crate::solver::fields::Smoothing;
use crate::solver::layout::MAX_GROUP_3D;
use crate::solver::mass_scaling::{hold, row_sum_bounds};
use crate::solver::rereference::{
    carry_temperatures, failed, fit, particle_temperatures, shapes_on,
};
use serde::{Deserialize, Serialize};

/// The configuration a 3D kernel was last re-referenced on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolidReference {
    /// Re-references so far.
    pub count: u32,
    /// Time of the last one (s).
    pub time_s: Real,
    /// Particle positions `X'` (m).
    pub particles: Vec<[Real; 3]>,
    /// Kernel volumes `V'` (m^3).
    pub volumes: Vec<Real>,
    /// Each particle's deformed cell `G`, row-major (m).
    pub cells: Vec<[Real; 9]>,
    /// Integration point positions (m).
    pub points: Vec<[Real; 3]>,
    /// `J = det F` of each point from the original configuration (-).
    pub point_jacobian: Vec<Real>,
    /// Relative residual of the velocity transfer (-).
    pub fit_residual: Real,
    /// Particles and points, summed over the re-references so far, where the supports
    /// sized from the deformed cells covered too few particles and were grown
    /// ([`crate::rk_shape::cover_sites`]).
    #[serde(default)]
    pub short_sites: u64,
    /// Particles and points, summed over the re-references so far, where the covering
    /// particles left the moment matrix's condition above
    /// [`crate::rk_shape::MAX_CONDITION`] (a sheet that the axis-aligned supports do not
    /// span) and more supports were grown to reach them
    /// ([`crate::rk_shape::condition_sites`]).
    #[serde(default)]
    pub flat_sites: u64,
    /// The lumped masses (kg) with which selective mass scaling holds its target on these
    /// shape functions ([`crate::solver`]'s `mass_scaling::hold`); `None` without it.
    #[serde(default)]
    pub masses: Option<Vec<Real>>,
}

/// `det` of a row-major 3 x 3 matrix.
fn det3(f: &[Real; 9]) -> Real {
    f[0] * (f[4] * f[8] - f[5] * f[7]) - f[1] * (f[3] * f[8] - f[5] * f[6])
        + f[2] * (f[3] * f[7] - f[4] * f[6])
}

/// Stage 0 of the step: re-references the kernel when the last stress stage's largest
/// stretch reached the scene's `discretization.rereference_stretch`; a failure stops the
/// run naming the step.
pub(super) fn if_due(
    scene: &SolidScene,
    disc: &mut SolidDisc,
    st: &mut SolidState,
    ws: &mut SolidWorkspace,
) -> Result<()> {
    match scene.discretization.rereference_stretch {
        Some(limit) if st.max_stretch >= limit => {
            now(scene, disc, st, ws).map_err(|e| failed(st.step, st.time, e))
        }
        _ => Ok(()),
    }
}

/// Re-references the kernel now, on the positions of the current displacement (see the
/// module doc).
pub(super) fn now(
    scene: &SolidScene,
    disc: &mut SolidDisc,
    st: &mut SolidState,
    ws: &mut SolidWorkspace,
) -> Result<()> {
    let np = disc.ref_pos.len();
    let npts = disc.weights.len();
    let positions: Vec<[Real; 3]> = (0..np)
        .map(|j| {
            let u = disc.nodal.interpolate(j, &st.d);
            std::array::from_fn(|k| disc.ref_pos[j][k] + u[k])
        })
        .collect();
    // Each point's F = I + sum_I d_I (x) grad N_I and displacement.
    let motions: Vec<([Real; 9], [Real; 3])> = (0..npts)
        .map(|p| {
            let mut f = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
            let mut u = [0.0; 3];
            for (i, n, g) in disc.scatter.point_entries(p) {
                let d = st.d[i];
                for a in 0..3 {
                    u[a] += d[a] * n;
                    for b in 0..3 {
                        f[3 * a + b] += d[a] * g[b];
                    }
                }
            }
            (f, u)
        })
        .collect();
    // Particle averages of F and det F over the points that see them.
    let mut sum = vec![[0.0; 11]; np];
    for (p, (f, _)) in motions.iter().enumerate() {
        let det = det3(f);
        for (i, n, _) in disc.scatter.point_entries(p) {
            let w = (n * disc.weights[p]).abs();
            let s = &mut sum[i];
            for (sk, fk) in s.iter_mut().zip(f) {
                *sk += w * fk;
            }
            s[9] += w * det;
            s[10] += w;
        }
    }
    let (old_cells, old_volumes, old_jacobian) = current_reference(disc, st);
    let mut cells = Vec::with_capacity(np);
    let mut volumes = Vec::with_capacity(np);
    for (i, s) in sum.iter().enumerate() {
        let (f, det): ([Real; 9], Real) = match s[10] > 0.0 {
            true => (std::array::from_fn(|k| s[k] / s[10]), s[9] / s[10]),
            false => ([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], 1.0),
        };
        let g = old_cells[i];
        cells.push(std::array::from_fn(|rc| {
            let (r, c) = (rc / 3, rc % 3);
            (0..3).map(|k| f[3 * r + k] * g[3 * k + c]).sum()
        }));
        volumes.push(old_volumes[i] * det);
    }
    let points: Vec<[Real; 3]> = motions
        .iter()
        .zip(&disc.point_positions)
        .map(|((_, u), x)| std::array::from_fn(|k| x[k] + u[k]))
        .collect();
    let point_jacobian: Vec<Real> = motions
        .iter()
        .zip(&old_jacobian)
        .map(|((f, _), j)| j * det3(f))
        .collect();
    // The history pushed forward: C_p'^{-1} = b_e = F C_p^{-1} F^T.
    for (state, (f, _)) in st.points.iter_mut().zip(&motions) {
        state.cp_inv = elastic_left_cauchy_green3(*f, state.cp_inv);
    }
    // Physical velocities before the new shape functions replace the old.
    let v_now: Vec<[Real; 3]> = (0..np).map(|j| disc.nodal.interpolate(j, &st.v)).collect();
    let v_before: Vec<[Real; 3]> = (0..np)
        .map(|j| disc.nodal.interpolate(j, &ws.v_prev))
        .collect();
    let kinetic_before = kinetic_energy(&disc.mass, &st.v);
    let before = st.stable_dt;
    let temperature_now =
        particle_temperatures(&disc.nodal, st.heat.as_ref(), disc.thermal.as_ref());
    let mut reference = SolidReference {
        count: st.reference.as_ref().map_or(0, |r| r.count) + 1,
        time_s: st.time,
        particles: positions,
        volumes,
        cells,
        points,
        point_jacobian,
        fit_residual: 0.0,
        short_sites: st.reference.as_ref().map_or(0, |r| r.short_sites),
        flat_sites: st.reference.as_ref().map_or(0, |r| r.flat_sites),
        masses: None,
    };
    let (short, flat) = install(scene, disc, st, ws, &reference)?;
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
    st.d = vec![[0.0; 3]; np];
    let kinetic_after = kinetic_energy(&disc.mass, &st.v);
    st.energy.remap += kinetic_after - kinetic_before;
    st.energy.kinetic += kinetic_after - kinetic_before;
    st.reference = Some(reference);
    st.stable_dt = disc.critical_dt0;
    st.max_stretch = 1.0;
    Ok(())
}

/// The particles' cells and kernel volumes and the points' Jacobians of the current
/// reference (the setup's before the first re-reference).
fn current_reference(disc: &SolidDisc, st: &SolidState) -> (Vec<[Real; 9]>, Vec<Real>, Vec<Real>) {
    match &st.reference {
        Some(r) => (r.cells.clone(), r.volumes.clone(), r.point_jacobian.clone()),
        None => (
            disc.extents
                .iter()
                .map(|e| [e[0], 0.0, 0.0, 0.0, e[1], 0.0, 0.0, 0.0, e[2]])
                .collect(),
            disc.volumes.clone(),
            vec![1.0; disc.weights.len()],
        ),
    }
}

/// Builds the shape functions, the scatter and the critical step on `reference`; the rest
/// of the state is left to the caller. Returns how many sites' supports were grown, too few
/// covering and too flat a cover ([`shapes_on`]).
pub(super) fn install(
    scene: &SolidScene,
    disc: &mut SolidDisc,
    st: &mut SolidState,
    ws: &mut SolidWorkspace,
    reference: &SolidReference,
) -> Result<(usize, usize)> {
    let s = scene.discretization.support;
    let supports = reference
        .cells
        .iter()
        .map(|g| std::array::from_fn(|k| s * g[3 * k].hypot(g[3 * k + 1]).hypot(g[3 * k + 2])))
        .collect();
    let (_, pt, nodal, grown) = shapes_on(
        &reference.particles,
        &reference.volumes,
        supports,
        &reference.points,
        reference.count,
        [s; 3],
    )?;
    let np = reference.particles.len();
    disc.neighbours = pt.entries() as Real / pt.rows() as Real;
    disc.scatter.rebuild(pt, np, MAX_GROUP_3D, &mut ws.buf);
    if !disc.flow_smoothing.is_empty() {
        disc.flow_smoothing = Smoothing::new(&disc.scatter, &disc.weights, np);
    }
    // The contact's move bound measured the coefficients of the old shape functions.
    ws.contact.forget_moves();
    disc.sum_abs = (0..np)
        .map(|j| nodal.row(j).map(|e| nodal.n[e].abs()).sum())
        .collect();
    disc.nodal = nodal;
    disc.ref_pos.clone_from(&reference.particles);
    disc.point_positions.clone_from(&reference.points);
    disc.reference_jacobian
        .clone_from(&reference.point_jacobian);
    if let Some(mass) = &reference.masses {
        set_masses(disc, mass.clone());
    }
    disc.critical_dt0 = measure_unstressed(disc, st, ws)?;
    if let (Some(mass), Some(target)) = (&reference.masses, &disc.scaling_target) {
        let report = target.report(mass, disc.critical_dt0);
        disc.mass_scaling = Some(report);
    }
    // Conduction's largest eigenvalue on the new shape functions.
    update_eigenvalue(disc)?;
    Ok(grown)
}

/// The critical step of the current shape functions and masses (s), measured with
/// unstressed, unheated points as at the start (the stressed ones would answer with their
/// stress, not stiffness); the state is left as it was.
fn measure_unstressed(
    disc: &SolidDisc,
    st: &mut SolidState,
    ws: &mut SolidWorkspace,
) -> Result<Real> {
    let saved = (
        std::mem::replace(
            &mut st.points,
            vec![PointState3::default(); disc.weights.len()],
        ),
        ws.out.clone(),
        st.heat.clone(),
        std::mem::replace(&mut st.dt_prev, 0.0),
        st.d.clone(),
    );
    let measured = measure_critical_step(disc, st, ws);
    (st.points, ws.out, st.heat, st.dt_prev, st.d) = saved;
    measured
}

/// Lumped masses `m_I` (kg) and their inverses.
fn set_masses(disc: &mut SolidDisc, mass: Vec<Real>) {
    disc.inv_mass = mass.iter().map(|m| 1.0 / m).collect();
    disc.mass = mass;
}

/// Selective mass scaling on the new shape functions, as the scene's
/// `time.mass_scaling.at_rereferences` asks (`mass_scaling::hold`, with `before` the
/// critical step the run followed before the re-reference, s, and the stiffness bounds
/// `k_I = M sum_p w_p |grad N_I| sum_J |grad N_J|` from the new shape functions): the
/// masses installed, the critical step and the report updated. Returns the masses, `None`
/// where the masses are kept.
fn hold_target(
    scene: &SolidScene,
    disc: &mut SolidDisc,
    st: &mut SolidState,
    ws: &mut SolidWorkspace,
    before: Real,
) -> Result<Option<Vec<Real>>> {
    let Some(target) = disc.scaling_target.take() else {
        return Ok(None);
    };
    let np = disc.mass.len();
    let stiffness = row_sum_bounds(&disc.weights, target.modulus, np, |p, g| {
        g.extend(
            disc.scatter
                .point_entries(p)
                .map(|(i, _, grad)| (i, grad.iter().map(|x| x * x).sum::<Real>().sqrt())),
        )
    });
    let held = hold(
        &target,
        before,
        &stiffness,
        disc.mass.clone(),
        disc.critical_dt0,
        scene.time.dt_safety,
        |mass| {
            set_masses(disc, mass);
            measure_unstressed(disc, st, ws)
        },
    );
    disc.scaling_target = Some(target);
    let (mass, report) = held?;
    disc.critical_dt0 = report.critical_dt_s;
    disc.mass_scaling = Some(report);
    Ok(Some(mass))
}
