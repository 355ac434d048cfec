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
use super::stable_step::{above_estimate, StepLength};
use super::state::State;
use super::workspace::Workspace;
use crate::constraints::Constraints;
use crate::contact::{Forces, Slip};
use crate::error::{Error, Result};
use crate::math::{component_sum, dot, Real};
use crate::team::{part, particle_phase, Parts, Team};
use crate::tools::Tool;

/// Largest velocity component `max_I max_k |v_I,k|` (m/s) of `vs`, infinite if one is not
/// finite (then the sum of the magnitudes is not finite either). Written with four
/// independent running maxima and sums over the components in turn (`I D + k` into
/// running pair `(I D + k) mod 4`), which compile to vector max and add instructions (a
/// single running maximum stays scalar).
fn largest_component<const D: usize>(vs: &[[Real; D]]) -> Real {
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
pub(super) struct Predictor<'a, const D: usize> {
    /// `(dt_n + dt_{n+1}) / 2` (s).
    pub dt_avg: Real,
    /// Coefficient velocities: `v_{n-1/2}` in, `v*` out (m/s).
    pub v: &'a mut [[Real; D]],
    /// `v_{n-1/2}` out (m/s), for the energy account.
    pub v_prev: &'a mut [[Real; D]],
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
pub(super) fn gather_forces<const D: usize>(
    team: &Team,
    sc: &Scatter<D>,
    buf: &[[Real; D]],
    extra: Option<&[[Real; D]]>,
    f_int: &mut [[Real; D]],
    predict: Option<Predictor<'_, D>>,
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
        fs.fill([0.0; D]);
        let chunks = sc.block_offsets[b] as usize..sc.block_offsets[b + 1] as usize;
        for &c in &sc.block_chunks[chunks] {
            let c = c as usize;
            let lo = sc.lo[c] as usize;
            let hi = lo + sc.offsets[c + 1] - sc.offsets[c];
            let (a, e) = (range.start.max(lo), range.end.min(hi));
            let src = &buf[sc.offsets[c] + a - lo..sc.offsets[c] + e - lo];
            for (f, v) in fs[a - range.start..e - range.start].iter_mut().zip(src) {
                add_to(f, v);
            }
        }
        if let Some(extra) = extra {
            for (f, v) in fs.iter_mut().zip(&extra[range.clone()]) {
                add_to(f, v);
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
                for (v, f) in v.iter_mut().zip(f) {
                    *v -= a * f;
                }
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
pub(super) fn correct_velocities<const D: usize>(
    v: &mut [[Real; D]],
    f_con: &Forces<D>,
    inv_mass: &[Real],
    dt_avg: Real,
) {
    for &i in f_con.reached() {
        let (v, f) = (&mut v[i as usize], f_con.at[i as usize]);
        let a = dt_avg * inv_mass[i as usize];
        for (v, f) in v.iter_mut().zip(f) {
            *v += a * f;
        }
    }
}

/// Contact work of the step `sum_I dt_avg f_c,I . (v_{n+1/2} + v_{n-1/2}) / 2` (J), the exact
/// discrete identity of the corrector, over the coefficients a contact force reached: in
/// [`BLOCK`]s of particles, each particle into running sum `I mod 4` of its block, the sums
/// added pairwise and the blocks in order, the order of a pass over every particle (the
/// others' terms are zeros, which leave the sums' bits as they are); each dot product is
/// summed from its first component on ([`component_sum`]).
pub(super) fn contact_work<const D: usize>(
    v: &[[Real; D]],
    v_prev: &[[Real; D]],
    f_con: &Forces<D>,
    dt_avg: Real,
) -> Real {
    let sum4 = |x: [Real; 4]| (x[0] + x[1]) + (x[2] + x[3]);
    let (mut total, mut block, mut sums) = (0.0, usize::MAX, [0.0; 4]);
    for &i in f_con.reached() {
        let i = i as usize;
        if i / BLOCK != block {
            total += sum4(sums);
            (block, sums) = (i / BLOCK, [0.0; 4]);
        }
        let (f, v, vp) = (f_con.at[i], v[i], v_prev[i]);
        sums[i % 4] += 0.5 * dt_avg * component_sum::<D>(|k| f[k] * (v[k] + vp[k]));
    }
    total + sum4(sums)
}

/// `f += g` componentwise (N).
#[inline(always)]
fn add_to<const D: usize>(f: &mut [Real; D], g: &[Real; D]) {
    for (f, g) in f.iter_mut().zip(g) {
        *f += g;
    }
}

/// What the update reads: the velocities of the step and the internal forces.
pub(super) struct Motion<'a, const D: usize> {
    /// `v_{n+1/2}` (m/s).
    pub v: &'a [[Real; D]],
    /// Lumped masses (kg).
    pub mass: &'a [Real],
    /// Internal forces (N).
    pub f_int: &'a [[Real; D]],
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
/// order (the contact work is [`contact_work`]'s), each dot product from its first
/// component on ([`dot`]); the largest speed is found when `track` is set.
pub(super) fn update<const D: usize>(
    team: &Team,
    d: &mut [[Real; D]],
    m: &Motion<'_, D>,
    dt: Real,
    track: bool,
) -> Sums {
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
                ke[k] += 0.5 * ms[i] * dot(&v, &v);
                hs[k] += 0.5 * dt * dot(&fi, &v);
                for (d, v) in ds[i].iter_mut().zip(v) {
                    *d += dt * v;
                }
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
/// the particle, and the scene's fixed step `fixed` (`time.dt_s`, s) when the step ran
/// above the stable estimate ([`above_estimate`]).
pub(super) fn advance(
    disc: &Discretization,
    tools: &[Tool],
    st: &mut State,
    ws: &mut Workspace,
    contact: bool,
    step: StepLength,
    fixed: Option<Real>,
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
                "velocity of particle {i} at {:?} m is not finite{}",
                disc.original[i],
                above_estimate(fixed, step.dt, st.stable_dt)
            ),
        });
    }
    Ok(u)
}

/// The initial coefficient velocities (m/s): the workpiece's initial velocity `v0` projected
/// onto the essential conditions with the masses `mass` (kg), and their kinetic energy
/// `sum m_I |v_I|^2 / 2` (J).
pub(super) fn initial_motion<const D: usize>(
    v0: [Real; D],
    constraints: Option<&Constraints>,
    mass: &[Real],
) -> (Vec<[Real; D]>, Real) {
    let mut v = vec![v0; mass.len()];
    if let Some(c) = constraints {
        c.project(&mut v, mass);
    }
    let initial = kinetic_energy(mass, &v);
    (v, initial)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rk_shape::ShapeTable;

    /// Particles of the 3D tests: three blocks of [`BLOCK`], the last one partial.
    const NP: usize = 300;

    /// A small dyadic value (quarters between -1.25 and 1.25) for entry `i`, component `k`:
    /// the sums and products of the tests are exact in any order.
    fn quarter(i: usize, k: usize) -> Real {
        ((i * 7 + k * 3) % 11) as Real * 0.25 - 1.25
    }

    /// `[quarter(i, 0), quarter(i, 1), quarter(i, 2)]` for `i` in `0..n`, scaled by `s`.
    fn field(n: usize, s: Real) -> Vec<[Real; 3]> {
        (0..n)
            .map(|i| std::array::from_fn(|k| s * quarter(i, k)))
            .collect()
    }

    /// Two chunks of the scatter: chunk 0 on particles 0..200, chunk 1 on 100..300, so
    /// blocks 0 and 1 sum both and block 2 the second alone.
    fn scatter() -> Scatter<3> {
        Scatter {
            lo: vec![0, 100],
            offsets: vec![0, 200, 400],
            block_offsets: vec![0, 2, 4, 5],
            block_chunks: vec![0, 1, 0, 1, 1],
            ..Default::default()
        }
    }

    /// Masses `2^(I mod 3)` (kg): exact inverses.
    fn masses() -> Vec<Real> {
        (0..NP).map(|i| (1u32 << (i % 3)) as Real).collect()
    }

    /// Largest `|x_I,k|` of a field, written out.
    fn largest(x: &[[Real; 3]]) -> Real {
        x.iter().flatten().fold(0.0, |m: Real, a| m.max(a.abs()))
    }

    /// The contact forces of three particles spread to coefficients of three blocks
    /// (ascending, as a contact stage leaves them), and what they sum to at each coefficient.
    fn contact_forces() -> (Forces<3>, Vec<[Real; 3]>) {
        let nodal = ShapeTable::<3> {
            offsets: vec![0, 3, 5, 7],
            index: vec![5, 6, 7, 130, 131, 131, 290],
            n: vec![0.5, 0.25, 0.25, 0.5, 0.5, 0.75, 0.25],
            ..Default::default()
        };
        let f_j = [[1.0, -2.0, 4.0], [8.0, 0.5, -1.0], [2.0, 2.0, -2.0]];
        let mut forces = Forces::<3>::new(NP);
        for (j, &f) in f_j.iter().enumerate() {
            forces.spread(&nodal, j, f);
        }
        let mut expected = vec![[0.0; 3]; NP];
        for (j, f) in f_j.iter().enumerate() {
            for e in nodal.row(j) {
                for (x, f) in expected[nodal.index[e] as usize].iter_mut().zip(f) {
                    *x += nodal.n[e] * f;
                }
            }
        }
        (forces, expected)
    }

    /// In 3D: the gather sums each particle's chunk slices and the extra force, the
    /// predictor gives `v* = v - dt_avg f / m` keeping `v` in `v_prev` and finds the
    /// largest component of `v*`; the corrector adds `dt_avg f_c / m` where a contact force
    /// reached; the contact work is the discrete identity `KE(v) - KE(v_prev) = W_c -
    /// sum dt_avg f_int . (v + v_prev) / 2`; the update moves `d` by `dt v` with the kinetic
    /// energy, half-step work and largest speed. All values are dyadic: exact.
    #[test]
    fn predictor_corrector_and_update_in_3d() {
        let team = Team::default();
        let (sc, buf, extra) = (scatter(), field(400, 2.0), field(NP, 0.5));
        let mass = masses();
        let inv_mass: Vec<Real> = mass.iter().map(|m| 1.0 / m).collect();
        let dt_avg = 0.5;
        let mut f_expected = vec![[0.0; 3]; NP];
        for (i, f) in f_expected.iter_mut().enumerate() {
            for k in 0..3 {
                if i < 200 {
                    f[k] += buf[i][k];
                }
                if i >= 100 {
                    f[k] += buf[200 + i - 100][k];
                }
                f[k] += extra[i][k];
            }
        }

        let mut f_int = vec![[9.0; 3]; NP];
        let none = gather_forces(&team, &sc, &buf, Some(&extra), &mut f_int, None);
        assert_eq!((none, &f_int), (0.0, &f_expected));

        let v_old = field(NP, 1.0);
        let (mut v, mut v_prev) = (v_old.clone(), vec![[0.0; 3]; NP]);
        let predictor = Predictor {
            dt_avg,
            v: &mut v,
            v_prev: &mut v_prev,
            inv_mass: &inv_mass,
            track: true,
        };
        let speed = gather_forces(&team, &sc, &buf, Some(&extra), &mut f_int, Some(predictor));
        let v_star: Vec<[Real; 3]> = (0..NP)
            .map(|i| std::array::from_fn(|k| v_old[i][k] - dt_avg / mass[i] * f_expected[i][k]))
            .collect();
        assert_eq!((&f_int, &v, &v_prev), (&f_expected, &v_star, &v_old));
        assert_eq!(speed, largest(&v_star));

        let (forces, f_c) = contact_forces();
        assert_eq!(forces.reached(), &[5, 6, 7, 130, 131, 290]);
        assert_eq!(forces.at, f_c);
        correct_velocities(&mut v, &forces, &inv_mass, dt_avg);
        let v_new: Vec<[Real; 3]> = (0..NP)
            .map(|i| std::array::from_fn(|k| v_star[i][k] + dt_avg / mass[i] * f_c[i][k]))
            .collect();
        assert_eq!(v, v_new);

        let work_of = |f: &[[Real; 3]]| -> Real {
            (0..NP)
                .map(|i| {
                    (0..3)
                        .map(|k| f[i][k] * (v[i][k] + v_prev[i][k]))
                        .sum::<Real>()
                })
                .sum::<Real>()
                * 0.5
                * dt_avg
        };
        let w_c = contact_work(&v, &v_prev, &forces, dt_avg);
        assert_eq!(w_c, work_of(&f_c));
        let ke = |v: &[[Real; 3]]| -> Real {
            (0..NP)
                .map(|i| 0.5 * mass[i] * (0..3).map(|k| v[i][k] * v[i][k]).sum::<Real>())
                .sum()
        };
        assert_eq!(kinetic_energy(&mass, &v), ke(&v));
        assert_eq!(ke(&v) - ke(&v_prev), w_c - work_of(&f_int));

        let (d_old, dt) = (field(NP, 4.0), 0.25);
        let mut d = d_old.clone();
        let motion = Motion {
            v: &v,
            mass: &mass,
            f_int: &f_int,
        };
        let sums = update(&team, &mut d, &motion, dt, true);
        let d_new: Vec<[Real; 3]> = (0..NP)
            .map(|i| std::array::from_fn(|k| d_old[i][k] + dt * v[i][k]))
            .collect();
        assert_eq!(d, d_new);
        let half_step: Real = (0..NP)
            .map(|i| (0..3).map(|k| f_int[i][k] * v[i][k]).sum::<Real>())
            .sum::<Real>()
            * 0.5
            * dt;
        assert_eq!(
            [sums.kinetic, sums.half_step, sums.largest_speed],
            [ke(&v), half_step, largest(&v)]
        );
        assert_eq!(update(&team, &mut d, &motion, dt, false).largest_speed, 0.0);
    }

    /// The contact work over the reached coefficients has the bits of a pass over every
    /// particle (blocks of [`BLOCK`] in order, particle `I` into running sum `I mod 4`, the
    /// dot product written out from its first component), on values that are not dyadic.
    #[test]
    fn contact_work_has_the_bits_of_a_pass_over_every_particle_in_3d() {
        let (forces, _) = contact_forces();
        let wave = |s: Real| -> Vec<[Real; 3]> {
            (0..NP)
                .map(|i| std::array::from_fn(|k| (s * (i * 3 + k) as Real).sin() * 1.7))
                .collect()
        };
        let (v, v_prev, dt_avg) = (wave(0.37), wave(1.13), 3.1e-7);
        let mut total = 0.0;
        for b in 0..NP.div_ceil(BLOCK) {
            let mut sums = [0.0; 4];
            for i in part(b, BLOCK, NP) {
                let (f, v, vp) = (forces.at[i], v[i], v_prev[i]);
                sums[i % 4] += 0.5
                    * dt_avg
                    * (f[0] * (v[0] + vp[0]) + f[1] * (v[1] + vp[1]) + f[2] * (v[2] + vp[2]));
            }
            total += (sums[0] + sums[1]) + (sums[2] + sums[3]);
        }
        let w = contact_work(&v, &v_prev, &forces, dt_avg);
        assert_eq!(w.to_bits(), total.to_bits(), "{w} {total}");
    }

    /// In 3D the largest component is found in every component and block position, and a
    /// component that is not finite makes it infinite.
    #[test]
    fn largest_component_in_3d() {
        for n in [1, 2, 5, 7, 130] {
            for at in 0..3 * n {
                let mut vs = field(n, 0.5);
                vs[at / 3][at % 3] = -7.5;
                assert_eq!(largest_component(&vs), 7.5);
                vs[at / 3][at % 3] = Real::NAN;
                assert_eq!(largest_component(&vs), Real::INFINITY);
            }
        }
    }

    /// The initial motion in 3D without constraints: every coefficient at `v0`, kinetic
    /// energy `sum m |v0|^2 / 2`.
    #[test]
    fn initial_motion_in_3d() {
        let mass = masses();
        let v0 = [1.5, -2.0, 0.25];
        let (v, ke) = initial_motion(v0, None, &mass);
        assert_eq!(v, vec![v0; NP]);
        assert_eq!(ke, 0.5 * mass.iter().sum::<Real>() * (2.25 + 4.0 + 0.0625));
    }
}
