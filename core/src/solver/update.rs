//! Time integration of the RK coefficients (Belytschko, Liu, Moran 2000, Box 6.1, central
//! differences with lumped masses), in the paper's predictor-corrector form for contact
//! (Sidibe et al. 2009, section II-3):
//!
//! - force gather and predictor: `f_I` summed from the chunk buffers of [`Scatter`] in a
//!   fixed order (N), `v* = v_{n-1/2} - dt_avg f_I / m_I` (m/s);
//! - corrector: `v_{n+1/2} = v* + dt_avg f_c,I / m_I` with the contact forces `f_c`;
//! - update: `d_{n+1} = d_n + dt v_{n+1/2}` (m), with the step's energy sums.
//!
//! Particles are cut into fixed blocks of [`BLOCK`], summed in block order, so the bits do
//! not depend on the number of threads.

use super::discretization::Discretization;
use super::energy::kinetic_energy;
use super::layout::{Scatter, BLOCK};
use super::stable_step::StepLength;
use super::state::State;
use super::workspace::Workspace;
use crate::constraints::Constraints;
use crate::contact::{Forces, Slip};
use crate::error::{Error, Result};
use crate::math::Real;
use crate::team::{part, particle_phase, Parts, Team};
use crate::tools::Tool;

/// Largest velocity component `max_I max(|v_I,x|, |v_I,y|)` (m/s) of `vs`, infinite if
/// one is not finite (then the sum of the magnitudes is not finite either). Written with
/// four independent running maxima and sums, which compile to vector max and add
/// instructions (a single running maximum stays scalar).
fn largest_component(vs: &[[Real; 2]]) -> Real {
    let (mut most, mut sum) = ([0.0; 4], [0.0; 4]);
    let mut chunks = vs.as_flattened().chunks_exact(4);
    for c in &mut chunks {
        for k in 0..4 {
            let a = c[k].abs();
            most[k] = if a > most[k] { a } else { most[k] };
            sum[k] += a;
        }
    }
    for (k, x) in chunks.remainder().iter().enumerate() {
        let a = x.abs();
        most[k] = if a > most[k] { a } else { most[k] };
        sum[k] += a;
    }
    if (sum[0] + sum[1] + sum[2] + sum[3]).is_finite() {
        most.into_iter().fold(0.0, Real::max)
    } else {
        Real::INFINITY
    }
}

/// The predictor: `v* = v_{n-1/2} - dt_avg f_int / m` on `v`, keeping `v_{n-1/2}` in
/// `v_prev`.
pub(super) struct Predictor<'a> {
    /// `(dt_n + dt_{n+1}) / 2` (s).
    pub dt_avg: Real,
    /// Coefficient velocities: `v_{n-1/2}` in, `v*` out (m/s).
    pub v: &'a mut [[Real; 2]],
    /// `v_{n-1/2}` out (m/s), for the energy account.
    pub v_prev: &'a mut [[Real; 2]],
    /// `1 / m_I` (1/kg).
    pub inv_mass: &'a [Real],
    /// Find the largest predicted velocity component (for the contact stage's skipping).
    pub track: bool,
}

/// Internal force gather over fixed blocks of particles on `team`, fused with the
/// predictor: `f_I` (N) sums the chunk buffers `buf` of `sc` covering `I` in chunk order (per block, the
/// overlapping slice of each chunk in turn), then `extra_I` when given (the stabilization
/// of nodal integration). With a [`Predictor`], returns the largest component of `v*` (m/s;
/// 0 when not tracked).
pub(super) fn gather_forces(
    team: &Team,
    sc: &Scatter,
    buf: &[[Real; 2]],
    extra: Option<&[[Real; 2]]>,
    f_int: &mut [[Real; 2]],
    predict: Option<Predictor<'_>>,
) -> Real {
    let np = f_int.len();
    let blocks = np.div_ceil(BLOCK);
    let mut speeds: Vec<Real> = vec![0.0; blocks];
    let track = predict.as_ref().is_some_and(|p| p.track);
    let dt_avg = predict.as_ref().map(|p| p.dt_avg);
    let (v, v_prev, inv_mass) = match predict {
        Some(p) => (p.v, p.v_prev, p.inv_mass),
        None => (&mut [][..], &mut [][..], &[][..]),
    };
    let (f_int, v, v_prev, speed_slots) = (
        Parts::new(f_int),
        Parts::new(v),
        Parts::new(v_prev),
        Parts::new(&mut speeds),
    );
    particle_phase(team, np, blocks, &|b| {
        let range = part(b, BLOCK, np);
        // SAFETY: block `b` alone takes these particles.
        let fs = unsafe { f_int.get(range.clone()) };
        fs.fill([0.0; 2]);
        let chunks = sc.block_offsets[b] as usize..sc.block_offsets[b + 1] as usize;
        for &c in &sc.block_chunks[chunks] {
            let c = c as usize;
            let lo = sc.lo[c] as usize;
            let hi = lo + sc.offsets[c + 1] - sc.offsets[c];
            let (a, e) = (range.start.max(lo), range.end.min(hi));
            let src = &buf[sc.offsets[c] + a - lo..sc.offsets[c] + e - lo];
            for (f, v) in fs[a - range.start..e - range.start].iter_mut().zip(src) {
                f[0] += v[0];
                f[1] += v[1];
            }
        }
        if let Some(extra) = extra {
            for (f, v) in fs.iter_mut().zip(&extra[range.clone()]) {
                f[0] += v[0];
                f[1] += v[1];
            }
        }
        if let Some(dt_avg) = dt_avg {
            // SAFETY: as above.
            let (vs, vps, slot) = unsafe {
                (
                    v.get(range.clone()),
                    v_prev.get(range.clone()),
                    &mut speed_slots.get(b..b + 1)[0],
                )
            };
            vps.copy_from_slice(vs);
            for ((v, f), im) in vs.iter_mut().zip(fs.iter()).zip(&inv_mass[range]) {
                let a = dt_avg * im;
                v[0] -= a * f[0];
                v[1] -= a * f[1];
            }
            if track {
                *slot = largest_component(vs);
            }
        }
    });
    speeds.into_iter().fold(0.0, Real::max)
}

/// Corrector: `v += dt_avg f_c / m` (m/s) with the contact forces `f_con` (N) and the inverse
/// masses `inv_mass` (1/kg), on the coefficients a contact force reached (`f_con.reached()`;
/// every other coefficient's force is zero and its velocity unchanged).
fn correct_velocities(v: &mut [[Real; 2]], f_con: &Forces, inv_mass: &[Real], dt_avg: Real) {
    for &i in f_con.reached() {
        let (v, f) = (&mut v[i as usize], f_con.at[i as usize]);
        let a = dt_avg * inv_mass[i as usize];
        v[0] += a * f[0];
        v[1] += a * f[1];
    }
}

/// Contact work of the step `sum_I dt_avg f_c,I . (v_{n+1/2} + v_{n-1/2}) / 2` (J), the exact
/// discrete identity of the corrector, over the coefficients a contact force reached: in
/// [`BLOCK`]s of particles, each particle into running sum `I mod 4` of its block, the sums
/// added pairwise and the blocks in order, the order of a pass over every particle (the
/// others' terms are zeros, which leave the sums' bits as they are).
fn contact_work(v: &[[Real; 2]], v_prev: &[[Real; 2]], f_con: &Forces, dt_avg: Real) -> Real {
    let sum4 = |x: [Real; 4]| (x[0] + x[1]) + (x[2] + x[3]);
    let (mut total, mut block, mut sums) = (0.0, usize::MAX, [0.0; 4]);
    for &i in f_con.reached() {
        let i = i as usize;
        if i / BLOCK != block {
            total += sum4(sums);
            (block, sums) = (i / BLOCK, [0.0; 4]);
        }
        let (f, v, vp) = (f_con.at[i], v[i], v_prev[i]);
        sums[i % 4] += 0.5 * dt_avg * (f[0] * (v[0] + vp[0]) + f[1] * (v[1] + vp[1]));
    }
    total + sum4(sums)
}

/// What the update reads: the velocities of the step and the internal forces.
struct Motion<'a> {
    /// `v_{n+1/2}` (m/s).
    pub v: &'a [[Real; 2]],
    /// Lumped masses (kg).
    pub mass: &'a [Real],
    /// Internal forces (N).
    pub f_int: &'a [[Real; 2]],
}

/// The step's sums from [`update`] (and [`advance`]).
pub(super) struct Sums {
    /// Kinetic energy `sum m |v_{n+1/2}|^2 / 2` (J).
    pub kinetic: Real,
    /// Contact work `sum dt_avg f_c . (v_{n+1/2} + v_{n-1/2}) / 2` (J).
    pub contact_work: Real,
    /// Internal half-step work `sum dt f_int . v_{n+1/2} / 2` (J).
    pub half_step: Real,
    /// Largest velocity component of `v_{n+1/2}` (m/s; 0 when not tracked).
    pub largest_speed: Real,
}

/// Displacement update `d_{n+1} = d_n + dt v_{n+1/2}` (m) over fixed blocks of particles on
/// `team`, with the kinetic energy and the internal half-step work of the step ([`Sums`]),
/// each summed per block (four interleaved running sums, added pairwise) and the blocks in
/// order (the contact work is [`contact_work`]'s); the largest speed is found when `track`
/// is set.
fn update(team: &Team, d: &mut [[Real; 2]], m: &Motion<'_>, dt: Real, track: bool) -> Sums {
    let np = m.v.len();
    let blocks = np.div_ceil(BLOCK);
    let mut sums = vec![[0.0; 3]; blocks];
    let Motion { v, mass, f_int } = *m;
    let (d, slots) = (Parts::new(d), Parts::new(&mut sums));
    particle_phase(team, np, blocks, &|b| {
        let range = part(b, BLOCK, np);
        // SAFETY: block `b` alone takes these particles and its slot.
        let (ds, slot) = unsafe { (d.get(range.clone()), &mut slots.get(b..b + 1)[0]) };
        let n = ds.len();
        let (vs, ms, fis) = (&v[range.clone()], &mass[range.clone()], &f_int[range]);
        let speed = if track { largest_component(vs) } else { 0.0 };
        // Four running sums per quantity (particle i into sum i mod 4), added pairwise at
        // the end: independent chains instead of one long dependent one.
        let (mut ke, mut hs) = ([0.0; 4], [0.0; 4]);
        for j in (0..n).step_by(4) {
            for k in 0..4.min(n - j) {
                let i = j + k;
                let (v, fi) = (vs[i], fis[i]);
                ke[k] += 0.5 * ms[i] * (v[0] * v[0] + v[1] * v[1]);
                hs[k] += 0.5 * dt * (fi[0] * v[0] + fi[1] * v[1]);
                ds[i][0] += dt * v[0];
                ds[i][1] += dt * v[1];
            }
        }
        let sum4 = |x: [Real; 4]| (x[0] + x[1]) + (x[2] + x[3]);
        *slot = [sum4(ke), sum4(hs), speed];
    });
    let [kinetic, half_step, largest_speed] = sums
        .iter()
        .fold([0.0; 3], |a, s| [a[0] + s[0], a[1] + s[1], a[2].max(s[2])]);
    Sums {
        kinetic,
        contact_work: 0.0,
        half_step,
        largest_speed,
    }
}

/// Whether the contact stage has anything to do: `tools`, symmetry planes or the surface
/// against itself (the predictor and the update then bound how far the particles move, for
/// its skips).
fn contacts_anything(disc: &Discretization, tools: &[Tool], ws: &Workspace) -> bool {
    !tools.is_empty() || !disc.planes.is_empty() || ws.contact.self_contact().is_some()
}

/// Stage 3: the internal force gather ([`gather_forces`] of the stress stage's buffers and
/// the stabilization's force) into `ws.f_int` (N); with `predict`, fused with the
/// predictor on `st.v`, recording the move bound `dt V*` (m) for the contact stage.
pub(super) fn forces(
    disc: &Discretization,
    tools: &[Tool],
    st: &mut State,
    ws: &mut Workspace,
    predict: Option<StepLength>,
) {
    let track = contacts_anything(disc, tools, ws);
    let predictor = predict.map(|step| Predictor {
        dt_avg: step.avg,
        v: &mut st.v,
        v_prev: &mut ws.v_prev,
        inv_mass: &disc.inv_mass,
        track,
    });
    let extra = ws.stabilization.as_ref().map(|s| &s.force[..]);
    let speed = gather_forces(
        &ws.team,
        &disc.scatter,
        &ws.buf,
        extra,
        &mut ws.f_int,
        predictor,
    );
    if let Some(step) = predict {
        ws.contact.predicted_move(step.full * speed);
    }
}

/// Stage 5: the corrector with the contact forces when `contact` forces act, the projection
/// onto the essential conditions, and the friction the corrector did not realise carried
/// to the next step ([`crate::contact::Contact::carry`]; with friction heating, its work
/// booked at the particles), all with the step's `dt_avg` (s).
pub(super) fn correct(
    disc: &Discretization,
    tools: &[Tool],
    st: &mut State,
    ws: &mut Workspace,
    contact: bool,
    dt_avg: Real,
) {
    if contact {
        correct_velocities(&mut st.v, &ws.contact.force, &disc.inv_mass, dt_avg);
    }
    if let Some(c) = &disc.constraints {
        c.project(&mut st.v, &disc.mass);
    }
    if contact {
        let slip = match &mut st.heat {
            Some(h) if !h.friction_work.is_empty() => Some(Slip {
                tools,
                work: &mut h.friction_work,
            }),
            _ => None,
        };
        ws.contact
            .carry(&disc.nodal, &disc.mass, &st.v, &mut st.stick, dt_avg, slip);
    }
}

/// Stage 6: the update of the coefficients over the step `step` ([`update`]), recording the
/// move bound for the contact stage; a velocity that is not finite stops the run naming
/// the particle.
pub(super) fn advance(
    disc: &Discretization,
    tools: &[Tool],
    st: &mut State,
    ws: &mut Workspace,
    contact: bool,
    step: StepLength,
) -> Result<Sums> {
    let motion = Motion {
        v: &st.v,
        mass: &disc.mass,
        f_int: &ws.f_int,
    };
    let track = contacts_anything(disc, tools, ws);
    let mut u = update(&ws.team, &mut st.d, &motion, step.dt, track);
    if contact {
        u.contact_work = contact_work(&st.v, &ws.v_prev, &ws.contact.force, step.avg);
    }
    ws.contact.updated_move(step.dt * u.largest_speed);
    if !u.kinetic.is_finite() {
        let i =
            st.v.iter()
                .position(|v| !(v[0].is_finite() && v[1].is_finite()))
                .unwrap_or(0);
        return Err(Error::Diverged {
            step: st.step,
            time: st.time,
            what: format!(
                "velocity of particle {i} at {:?} m is not finite",
                disc.original[i]
            ),
        });
    }
    Ok(u)
}

/// The initial coefficient velocities (m/s): the workpiece's initial velocity `v0` projected
/// onto the essential conditions with the masses `mass` (kg), and their kinetic energy
/// `sum m_I |v_I|^2 / 2` (J).
pub(super) fn initial_motion(
    v0: [Real; 2],
    constraints: Option<&Constraints>,
    mass: &[Real],
) -> (Vec<[Real; 2]>, Real) {
    let mut v = vec![v0; mass.len()];
    if let Some(c) = constraints {
        c.project(&mut v, mass);
    }
    let initial = kinetic_energy(mass, &v);
    (v, initial)
}
