//! The stress stage of a step, fused with the scatter of the internal force (Belytschko,
//! Liu, Moran 2000, Box 6.1, steps 4-6, in total Lagrangian form):
//!
//! - deformation gradient `F = I + sum_I d_I (x) grad N_I(X_p)` at each integration point,
//!   with the hoop stretch `F_33 = 1 + u_r / R_p` in axisymmetry (`u_r = sum_I N_I d_I,r`);
//! - the Hencky J2 update of [`crate::material`] (first Piola-Kirchhoff stress `P`, Pa);
//! - the scatter of `w_p (P grad N_I + e_r P_33 N_I / R_p)` (N) into the chunk's buffer of
//!   [`Scatter`], which the force gather of [`super::update`] sums in a fixed order.
//!
//! Points are processed per group over one particle list ([`super::layout`]), whole groups
//! filling up to [`LANES`] (eight) points per batch in SIMD lanes; the AVX2+FMA build ([`avx2`]) is chosen at run time and gives
//! the generic build's bits. Chunks of points run on the team in parallel.
//!
//! One source for 2 and 3 dimensions: the chunk loop ([`StressContext::chunk`]) and
//! [`stage`] are generic over the dimension `D`; what differs (the gathered and weighted
//! lanes, the material's point state and lanes, the deformed cell's altitude, the largest
//! stretch) goes through [`Solid`], implemented for [`Dim<2>`] (plane strain and
//! axisymmetry, with the AVX2 gather and scatter of pairs, quads and strips) and
//! [`Dim<3>`] (`F` of 9 components, groups of up to the 8 points of a q4 cell, the generic
//! gather and scatter in the lanes, [`HenckyJ2::update_lanes3`]). [`run`] is the 2D solver's.

use super::discretization::{Discretization, Thermal};
use super::heat::{Heat, Heating};
use super::layout::{Scatter, MAX_GROUP, MAX_GROUP_3D};
use super::nodal_stabilization;
use super::point_outputs::PointOut;
use super::stable_step::above_estimate;
use super::state::State;
use super::workspace::Workspace;
use crate::error::{Error, Result};
use crate::lanes::{Lanes, LANES};
use crate::material::{
    HenckyJ2, PointLanes, PointLanes3, PointState, PointState3, StressLanes, StressLanes3,
};
use crate::math::{sym_spectral3, Real};
use crate::scene::{Kinematics, Scene};
use crate::team::{part, Parts, Team};

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(test)]
mod tests;

// A 3D group (up to the 8 points of a q4 cell) fills at most one batch.
const _: () = assert!(MAX_GROUP_3D <= LANES);

/// Sums over one chunk of points in the stress stage.
#[derive(Debug, Clone, Default)]
struct ChunkSums {
    elastic: Real,
    plastic: Real,
    /// Elastic energy the changes of temperature put in (J).
    thermoelastic: Real,
    /// Smallest squared altitude of a deformed cell (m^2).
    min_altitude2: Real,
    /// Largest squared principal stretch of `F` (-; in-plane in 2D), when tracked.
    max_stretch2: Real,
    failure: Option<(usize, String)>,
}

/// One chunk's share of the stress stage: points `first..first + states.len()` with their
/// histories (`T`, [`Solid::State`]) and cached outputs, and the chunk's force buffer
/// (particles from `lo`, `D` components).
struct ChunkWork<'a, T, const D: usize> {
    first: usize,
    states: &'a mut [T],
    outs: &'a mut [PointOut],
    /// The chunk's point temperatures (degrees C), plastic work densities (J/m^3) and
    /// plastic strain rates (1/s) in a thermal scene.
    heat: Option<HeatSlices<'a>>,
    lo: usize,
    buf: &'a mut [[Real; D]],
}

/// What the stress stage reads, shared by all chunks, in `D` dimensions.
pub(super) struct StressContext<'a, const D: usize> {
    /// Group particle lists ([`Scatter::lists`]).
    lists: &'a [u32],
    list_range: &'a [[u32; 2]],
    base: &'a [u32],
    /// Group sizes per point ([`Scatter::group`]).
    groups: &'a [u8],
    /// Which groups are strips ([`Scatter::strip`]).
    strips: &'a [bool],
    table: &'a [Real],
    table_start: &'a [u32],
    d: &'a [[Real; D]],
    material: &'a HenckyJ2,
    weights: &'a [Real],
    inv_radius: &'a [Real],
    reference_jacobian: &'a [Real],
    track_stretch: bool,
    axi: bool,
    spacing: [Real; D],
    /// `sigma_y(0)` (Pa), for the plastic work.
    initial_yield: Real,
    /// Adiabatic heating of a thermal scene.
    heating: Option<Heating<'a>>,
}

/// Point `j`'s contribution `[f_x, f_y]` (N) of a group of `G` to the particle of a
/// neighbour entry `e` (`[N.., N_x.., N_y..]`), from lane `l0 + j` of the weighted stresses:
/// `fma(P_xX, N_x, fma(P_xY, N_y, P_33 N / R))`, `fma(P_yX, N_x, P_yY N_y)`.
#[inline(always)]
fn term<const G: usize>(
    pw: &[Lanes; 3],
    px: &[Lanes; 2],
    l0: usize,
    e: &[Real],
    j: usize,
) -> [Real; 2] {
    let l = l0 + j;
    let (n, nx, ny) = (e[j], e[G + j], e[2 * G + j]);
    [
        pw[0][l].mul_add(nx, pw[1][l].mul_add(ny, pw[2][l] * n)),
        px[0][l].mul_add(nx, px[1][l] * ny),
    ]
}

impl<'a, const D: usize> StressContext<'a, D> {
    /// The context of the stage over `scatter` with `input`.
    fn new(scatter: &'a Scatter<D>, input: &Inputs<'a, D>) -> Self {
        StressContext {
            lists: &scatter.lists,
            list_range: &scatter.list_range,
            base: &scatter.base,
            groups: &scatter.group,
            strips: &scatter.strip,
            table: &scatter.table,
            table_start: &scatter.table_start,
            d: input.d,
            material: input.material,
            weights: input.weights,
            inv_radius: input.inv_radius,
            reference_jacobian: input.reference_jacobian,
            track_stretch: input.track_stretch,
            axi: input.axi,
            spacing: input.spacing,
            initial_yield: input.material.hardening.initial_yield(),
            heating: input.heating,
        }
    }

    /// The first particle of the group of `g` points starting at `p0`, the group's
    /// particles as offsets from it, and the group's interleaved shape-function entries
    /// ([`Scatter::table`], `D + 1` per point and particle).
    #[inline(always)]
    fn neighbours(&self, p0: usize, g: usize) -> (usize, &[u32], &[Real]) {
        let [a, b] = self.list_range[p0];
        let index = &self.lists[a as usize..b as usize];
        let start = self.table_start[p0] as usize;
        (
            self.base[p0] as usize,
            index,
            &self.table[start..start + (D + 1) * g * index.len()],
        )
    }
}

impl StressContext<'_, 2> {
    /// Gathers `F = I + sum_I d_I (x) grad N_I` and `u_r = sum_I N_I d_I,r` of the `G`
    /// consecutive points `p0..p0 + G`, which share one particle list (each particle's
    /// displacement is loaded once for the `G` points), into lanes `l0..l0 + G` of `f`
    /// (`[F_xX, F_xY, F_yX, F_yY, u_r]`). In a `strip` ([`Scatter::strip`]) lanes `l0 + 2`,
    /// `l0 + 3` read the particle one above each offset's.
    #[inline(always)]
    fn gather<const G: usize>(&self, p0: usize, f: &mut [Lanes; 5], l0: usize, strip: bool) {
        let (base, index, table) = self.neighbours(p0, G);
        let d = &self.d[base..];
        let second = |lane: usize| usize::from(strip && lane >= 2);
        // xy holds F_xX, F_xY (from d_x) then F_yX, F_yY (from d_y) of the G points in the
        // order of a neighbour's `[N_x.., N_y..]` entries, so each neighbour adds two
        // vectors of 2G products, each a fused multiply-add.
        let mut xy = [[0.0; 2 * MAX_GROUP]; 2];
        xy[0][..G].fill(1.0);
        xy[1][G..2 * G].fill(1.0);
        let mut ur = [0.0; MAX_GROUP];
        for (&i, e) in index.iter().zip(table.chunks_exact(3 * G)) {
            let pair = [d[i as usize], d[i as usize + usize::from(strip)]];
            for q in 0..2 * G {
                let di = pair[second(q % G)];
                xy[0][q] = di[0].mul_add(e[G + q], xy[0][q]);
                xy[1][q] = di[1].mul_add(e[G + q], xy[1][q]);
            }
            for j in 0..G {
                ur[j] = pair[second(j)][0].mul_add(e[j], ur[j]);
            }
        }
        for j in 0..G {
            let l = l0 + j;
            f[0][l] = xy[0][j];
            f[1][l] = xy[0][G + j];
            f[2][l] = xy[1][j];
            f[3][l] = xy[1][G + j];
            f[4][l] = ur[j];
        }
    }

    /// Scatters the weighted stresses of lanes `l0..l0 + G` (points `p0..p0 + G`, sharing
    /// one particle list) as `w_p (P grad N_I + e_r P_33 N_I / R_p)` into `buf`, each buffer
    /// entry read and written once for the `G` points; the contributions are still added
    /// point by point, so the bits equal a one-point loop. `pw = w [P_xX, P_xY, P_33 / R]`,
    /// `px = w [P_yX, P_yY]` per lane. A point's contribution is, with fused multiply-adds,
    /// `fma(P_xX, N_x, fma(P_xY, N_y, P_33 N / R))` and `fma(P_yX, N_x, P_yY N_y)`.
    #[inline(always)]
    fn scatter<const G: usize>(
        &self,
        p0: usize,
        pw: &[Lanes; 3],
        px: &[Lanes; 2],
        l0: usize,
        buf: &mut [[Real; 2]],
        lo: usize,
    ) {
        let (base, index, table) = self.neighbours(p0, G);
        let buf = &mut buf[base - lo..];
        for (&i, e) in index.iter().zip(table.chunks_exact(3 * G)) {
            let b = &mut buf[i as usize];
            for j in 0..G {
                let t = term::<G>(pw, px, l0, e, j);
                b[0] += t[0];
                b[1] += t[1];
            }
        }
    }

    /// [`StressContext::scatter`] for the strip starting at `p0`: each particle takes the
    /// first cell's two points at its offset and then the second cell's at the offset one
    /// below, so its entry adds the four points in point order, as a one-point loop does.
    #[inline(always)]
    fn scatter_strip(
        &self,
        p0: usize,
        pw: &[Lanes; 3],
        px: &[Lanes; 2],
        l0: usize,
        buf: &mut [[Real; 2]],
        lo: usize,
    ) {
        let (base, index, table) = self.neighbours(p0, 4);
        let buf = &mut buf[base - lo..];
        let term = |e: &[Real], j: usize| term::<4>(pw, px, l0, e, j);
        let add = |b: &mut [Real; 2], terms: &[[Real; 2]]| {
            for t in terms {
                b[0] += t[0];
                b[1] += t[1];
            }
        };
        // The second cell's terms at the last offset, for the particle above it.
        let mut pending: Option<(usize, [[Real; 2]; 2])> = None;
        for (&i, e) in index.iter().zip(table.chunks_exact(12)) {
            let i = i as usize;
            let first = [term(e, 0), term(e, 1)];
            match pending {
                Some((j, second)) if j == i => {
                    add(&mut buf[i], &[first[0], first[1], second[0], second[1]])
                }
                Some((j, second)) => {
                    add(&mut buf[j], &second);
                    add(&mut buf[i], &first);
                }
                None => add(&mut buf[i], &first),
            }
            pending = Some((i + 1, [term(e, 2), term(e, 3)]));
        }
        if let Some((j, second)) = pending {
            add(&mut buf[j], &second);
        }
    }

    /// Gather (`SCATTER` false) or scatter a group of `g` points, `g` in `1..=MAX_GROUP`;
    /// pairs and quads through [`avx2`] in the AVX2 build (`AVX2`, only from
    /// `chunk_avx2`).
    #[inline(always)]
    fn group<const SCATTER: bool, const AVX2: bool>(
        &self,
        g: usize,
        p0: usize,
        l0: usize,
        lanes: &mut Batch,
        buf: &mut [[Real; 2]],
        lo: usize,
    ) {
        macro_rules! run {
            ($g:literal) => {
                if SCATTER {
                    self.scatter::<$g>(p0, &lanes.pw, &lanes.px, l0, buf, lo)
                } else {
                    self.gather::<$g>(p0, &mut lanes.f, l0, false)
                }
            };
        }
        if self.strips[p0] {
            #[cfg(target_arch = "x86_64")]
            if AVX2 {
                let (base, index, table) = self.neighbours(p0, 4);
                let (d, buf) = (&self.d[base..], &mut buf[base - lo..]);
                // SAFETY: `AVX2` is true only inside `chunk_avx2`, called where the CPU has AVX2.
                unsafe {
                    match SCATTER {
                        false => avx2::gather_strip(index, table, d, &mut lanes.f, l0),
                        true => avx2::scatter_strip(index, table, &lanes.pw, &lanes.px, l0, buf),
                    }
                }
                return;
            }
            match SCATTER {
                false => self.gather::<4>(p0, &mut lanes.f, l0, true),
                true => self.scatter_strip(p0, &lanes.pw, &lanes.px, l0, buf, lo),
            }
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if AVX2 && (g == 2 || g == 4) {
            let (base, index, table) = self.neighbours(p0, g);
            let (d, buf) = (&self.d[base..], &mut buf[base - lo..]);
            // SAFETY: `AVX2` is true only inside `chunk_avx2`, called where the CPU has AVX2.
            unsafe {
                match (SCATTER, g) {
                    (false, 2) => avx2::gather2(index, table, d, &mut lanes.f, l0),
                    (false, _) => avx2::gather4(index, table, d, &mut lanes.f, l0),
                    (true, 2) => avx2::scatter2(index, table, &lanes.pw, &lanes.px, l0, buf),
                    (true, _) => avx2::scatter4(index, table, &lanes.pw, &lanes.px, l0, buf),
                }
            }
            return;
        }
        match g {
            1 => run!(1),
            2 => run!(2),
            3 => run!(3),
            _ => run!(4),
        }
    }
}

impl<const D: usize> StressContext<'_, D>
where
    Dim<D>: Solid<D>,
{
    /// The stress stage of one chunk of points (`work`). Points go through the
    /// material in batches of whole groups filling up to [`LANES`] lanes; a lane's results
    /// do not depend on the batch, so the bits equal a point-by-point loop.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // lane loops index several component-major arrays
    fn chunk<const AVX2: bool>(
        &self,
        work: ChunkWork<'_, <Dim<D> as Solid<D>>::State, D>,
    ) -> ChunkSums {
        let ChunkWork {
            first,
            states,
            outs,
            mut heat,
            lo,
            buf,
        } = work;
        let group = &self.groups[first..first + states.len()];
        buf.iter_mut().for_each(|b| *b = [0.0; D]);
        let mut s = ChunkSums {
            elastic: 0.0,
            plastic: 0.0,
            thermoelastic: 0.0,
            min_altitude2: Real::INFINITY,
            max_stretch2: 0.0,
            failure: None,
        };
        let mut lanes = Dim::<D>::batch();
        let mut batch = Dim::<D>::unstressed();
        let mut k = 0;
        while k < states.len() {
            // Whole groups of points, in order, while they fit in the lanes.
            let k0 = k;
            let mut used = 0;
            while k < states.len() && used + group[k] as usize <= LANES {
                let g = group[k] as usize;
                Dim::<D>::group::<false, AVX2>(self, g, first + k, used, &mut lanes, buf, lo);
                used += g;
                k += g;
            }
            let p0 = first + k0;
            if used < LANES {
                // Unused lanes: undeformed, unstressed, unable to yield.
                Dim::<D>::undeformed(&mut lanes, used);
                batch = Dim::<D>::unstressed();
            }
            let mut weight = [0.0; LANES];
            weight[..used].copy_from_slice(&self.weights[p0..p0 + used]);
            let mut inv_radius = [0.0; LANES];
            inv_radius[..used].copy_from_slice(&self.inv_radius[p0..p0 + used]);
            Dim::<D>::deformation(self, &lanes, &inv_radius, &mut batch);
            let (states, outs) = (&mut states[k0..k0 + used], &mut outs[k0..k0 + used]);
            for (l, (state, out)) in states.iter().zip(outs.iter()).enumerate() {
                Dim::<D>::set_history(&mut batch, l, state, out.flow_stress);
            }
            if let (Some(h), Some((temps, _, rates, elastic))) = (&self.heating, &mut heat) {
                // The batch's thermal inputs.
                let batch = Dim::<D>::heat_inputs(&mut batch);
                batch.temperature[..used].copy_from_slice(&temps[k0..k0 + used]);
                if let Some((prev, change)) = elastic {
                    // The last heat stage's change ramped in over the heat step that
                    // follows it (a jump would ring through the elastic body); the
                    // temperatures of the last update, and this update's for the next.
                    for l in 0..used {
                        batch.temperature[l] -= h.ramp * change[k0 + l];
                        for c in 0..4 {
                            batch.elastic_prev[c][l] = prev[k0 + l][c];
                        }
                    }
                }
                *batch.inv_dt = h.inv_dt;
                for l in 0..used {
                    batch.guess[l] = if h.inv_dt > 0.0 {
                        rates[k0 + l] / h.inv_dt
                    } else {
                        0.0
                    };
                }
            }
            let stress = match Dim::<D>::update(self.material, &mut batch) {
                Ok(u) => u,
                Err((l, m)) => {
                    s.failure = Some((p0 + l, m));
                    return s;
                }
            };
            let u = Dim::<D>::outputs(&stress);
            if let Some((_, _, _, Some((prev, _)))) = &mut heat {
                for l in 0..used {
                    prev[k0 + l] = std::array::from_fn(|c| u.elastic_now[c][l]);
                }
            }
            // The smallest altitude of the deformed cells (squared, all lanes at once;
            // unused lanes hold F = I and are not read).
            let altitude2 = Dim::<D>::altitude2(&batch, self.spacing);
            if self.track_stretch {
                for l in 0..used {
                    s.max_stretch2 = s.max_stretch2.max(Dim::<D>::stretch2(&batch, l));
                }
            }
            // Scatter weights w_p (P grad N_I + e_r P_33 N_I / R_p), all lanes at once.
            Dim::<D>::weigh(self, &stress, &weight, &inv_radius, &mut lanes);
            for (l, (state, out)) in states.iter_mut().zip(outs.iter_mut()).enumerate() {
                let eps_p = state.eps_p();
                *state = Dim::<D>::state(&batch, l);
                let heated = match (&self.heating, &mut heat) {
                    (Some(h), Some((temps, work, rate, _))) => {
                        Some((h, &mut temps[k0 + l], &mut work[k0 + l], &mut rate[k0 + l]))
                    }
                    _ => None,
                };
                let plastic_work = match heated {
                    None => {
                        if state.eps_p() != eps_p {
                            let flow = Dim::<D>::flow_stress(&batch, l);
                            out.set_plastic_strain(
                                self.material,
                                state.eps_p(),
                                flow,
                                self.initial_yield,
                            );
                        }
                        out.plastic_work
                    }
                    Some((h, temp, work, rate)) => {
                        *rate = (state.eps_p() - eps_p) * h.inv_dt;
                        if state.eps_p() != eps_p {
                            // W_p += dW; T_p += beta dW / (rho_0 c) (in enthalpy); the yield test's flow
                            // stress at the new strain and temperature. The linear and
                            // power laws' step work is the difference of their closed form.
                            let thermal = self.material.hardening.is_thermal();
                            let dw = if thermal {
                                Dim::<D>::plastic_work(&batch, l)
                            } else {
                                let before = out.plastic_work;
                                out.set_plastic_strain(
                                    self.material,
                                    state.eps_p(),
                                    Dim::<D>::flow_stress(&batch, l),
                                    self.initial_yield,
                                );
                                out.plastic_work - before
                            };
                            *work += dw;
                            *temp = h.heated(*temp, dw);
                            if thermal {
                                out.flow_stress = self
                                    .material
                                    .hardening
                                    .flow(state.eps_p(), 0.0, *temp)
                                    .stress;
                            }
                        }
                        *work
                    }
                };
                // F is measured from the last reference: J and the Cauchy stress q / J
                // take the Jacobian J_ref of that reference (1 without re-referencing).
                let j_ref = self.reference_jacobian[p0 + l];
                out.von_mises = u.von_mises[l] / j_ref;
                out.jacobian = u.jacobian[l] * j_ref;
                s.elastic += u.elastic_energy[l] * weight[l];
                s.thermoelastic += u.thermoelastic[l] * weight[l];
                s.plastic += plastic_work * weight[l];
                s.min_altitude2 = s.min_altitude2.min(altitude2[l]);
            }
            let mut l0 = 0;
            while l0 < used {
                let g = group[k0 + l0] as usize;
                Dim::<D>::group::<true, AVX2>(self, g, p0 + l0, l0, &mut lanes, buf, lo);
                l0 += g;
            }
        }
        s
    }

    /// [`StressContext::chunk`] compiled for AVX2, so the lanes run as one register.
    ///
    /// # Safety
    ///
    /// The CPU must support AVX2 (checked by the caller).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn chunk_avx2(&self, work: ChunkWork<'_, <Dim<D> as Solid<D>>::State, D>) -> ChunkSums {
        self.chunk::<true>(work)
    }
}

/// Whether the CPU runs the AVX2 build of the stress stage (x86_64 with AVX2 and FMA; false
/// on other architectures, which use the generic build).
pub(super) fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    return std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma");
    #[cfg(not(target_arch = "x86_64"))]
    return false;
}

/// Per-batch lanes of the 2D stress stage: gathered `[F_xX, F_xY, F_yX, F_yY, u_r]`, and the
/// weighted stresses to scatter (see [`StressContext::scatter`]).
pub(super) struct Batch {
    f: [Lanes; 5],
    pw: [Lanes; 3],
    px: [Lanes; 2],
}

/// Per-batch lanes of the 3D stress stage: gathered `F` (row-major `[F_xX, F_xY, F_xZ,
/// F_yX, .., F_zZ]`), and the weighted stresses `w_p P` to scatter, in the same order
/// (see [`StressContext::scatter3`]).
pub(super) struct Batch3 {
    f: [Lanes; 9],
    pw: [Lanes; 9],
}

/// The dimension `D` of the stress stage, as a type ([`Solid`] is implemented for `Dim<2>`
/// and `Dim<3>`).
pub(super) struct Dim<const D: usize>;

/// The inputs of a batch's material update that a thermal scene sets
/// ([`crate::material::PointLanes`] documents them; the same in 3D).
pub(super) struct HeatInputs<'a> {
    temperature: &'a mut Lanes,
    elastic_prev: &'a mut [Lanes; 4],
    inv_dt: &'a mut Real,
    guess: &'a mut Lanes,
}

/// The results of a batch's material update that do not depend on the dimension
/// ([`crate::material::StressLanes`] documents them).
pub(super) struct Outputs<'a> {
    jacobian: &'a Lanes,
    von_mises: &'a Lanes,
    elastic_energy: &'a Lanes,
    thermoelastic: &'a Lanes,
    elastic_now: &'a [Lanes; 4],
}

/// What differs between the 2D and the 3D stress stage; the chunk loop
/// ([`StressContext::chunk`]) is written once over it. All is inlined into the loop, so the
/// 2D stage compiles to the code it had before the loop was made generic.
pub(super) trait Solid<const D: usize> {
    /// A point's history ([`PointState`], [`PointState3`]).
    type State: Send + PlasticStrain;
    /// A batch of points through the material ([`PointLanes`], [`PointLanes3`]).
    type Lanes;
    /// The material's stresses of a batch ([`StressLanes`], [`StressLanes3`]).
    type Stress;
    /// The gathered deformation and the weighted stresses of a batch ([`Batch`], [`Batch3`]).
    type Batch;
    /// Zeroed batch lanes.
    fn batch() -> Self::Batch;
    /// Gather (`SCATTER` false) the deformation of the group of `g` points starting at
    /// `p0` into lanes `l0..l0 + g`, or scatter their weighted stresses into `buf`
    /// (particles from `lo`); AVX2 paths where `AVX2` (only from
    /// [`StressContext::chunk_avx2`]).
    fn group<const SCATTER: bool, const AVX2: bool>(
        cx: &StressContext<'_, D>,
        g: usize,
        p0: usize,
        l0: usize,
        lanes: &mut Self::Batch,
        buf: &mut [[Real; D]],
        lo: usize,
    );
    /// Lanes `used..` of `lanes` undeformed (`F = I`, `u_r = 0`).
    fn undeformed(lanes: &mut Self::Batch, used: usize);
    /// Every lane undeformed and unable to yield.
    fn unstressed() -> Self::Lanes;
    /// The gathered deformation into the material's lanes (with the hoop stretch
    /// `F_33 = 1 + u_r / R` in 2D axisymmetry; `inv_radius` is `1 / R` per lane).
    fn deformation(
        cx: &StressContext<'_, D>,
        lanes: &Self::Batch,
        inv_radius: &Lanes,
        batch: &mut Self::Lanes,
    );
    /// Loads a point's history and flow stress (Pa) into lane `l`.
    fn set_history(batch: &mut Self::Lanes, l: usize, state: &Self::State, flow: Real);
    /// The thermal inputs of the update.
    fn heat_inputs(batch: &mut Self::Lanes) -> HeatInputs<'_>;
    /// The update ([`HenckyJ2::update_lanes`], [`HenckyJ2::update_lanes3`]).
    fn update(
        material: &HenckyJ2,
        batch: &mut Self::Lanes,
    ) -> std::result::Result<Self::Stress, (usize, String)>;
    /// The update's results that do not depend on the dimension.
    fn outputs(stress: &Self::Stress) -> Outputs<'_>;
    /// Lane `l`'s history after the update.
    fn state(batch: &Self::Lanes, l: usize) -> Self::State;
    /// Lane `l`'s flow stress after the update (Pa).
    fn flow_stress(batch: &Self::Lanes, l: usize) -> Real;
    /// Lane `l`'s plastic work density of the update (J/m^3).
    fn plastic_work(batch: &Self::Lanes, l: usize) -> Real;
    /// Squared smallest altitude of the deformed cell spanned by `F h_k e_k` per lane (m^2,
    /// negative where `det F < 0`), from the particle spacings `h` (m).
    fn altitude2(batch: &Self::Lanes, h: [Real; D]) -> Lanes;
    /// Squared largest principal stretch of lane `l`'s `F`, the largest eigenvalue of
    /// `F^T F` (-; in-plane in 2D).
    fn stretch2(batch: &Self::Lanes, l: usize) -> Real;
    /// The weighted stresses `w_p P` (with `w_p P_33 / R_p` in 2D axisymmetry) into the
    /// batch lanes, for the scatter.
    fn weigh(
        cx: &StressContext<'_, D>,
        stress: &Self::Stress,
        weight: &Lanes,
        inv_radius: &Lanes,
        lanes: &mut Self::Batch,
    );
}

/// The equivalent plastic strain of a point's history (-).
pub(super) trait PlasticStrain {
    fn eps_p(&self) -> Real;
}

impl PlasticStrain for PointState {
    #[inline(always)]
    fn eps_p(&self) -> Real {
        self.eps_p
    }
}

impl PlasticStrain for PointState3 {
    #[inline(always)]
    fn eps_p(&self) -> Real {
        self.eps_p
    }
}

/// The parts of [`Solid`] that are the same for [`PointLanes`] and [`PointLanes3`].
macro_rules! shared_lanes {
    () => {
        #[inline(always)]
        fn unstressed() -> Self::Lanes {
            Self::Lanes::unstressed()
        }

        #[inline(always)]
        fn set_history(batch: &mut Self::Lanes, l: usize, state: &Self::State, flow: Real) {
            batch.set_history(l, state, flow);
        }

        #[inline(always)]
        fn heat_inputs(batch: &mut Self::Lanes) -> HeatInputs<'_> {
            HeatInputs {
                temperature: &mut batch.temperature,
                elastic_prev: &mut batch.elastic_prev,
                inv_dt: &mut batch.inv_dt,
                guess: &mut batch.guess,
            }
        }

        #[inline(always)]
        fn outputs(stress: &Self::Stress) -> Outputs<'_> {
            Outputs {
                jacobian: &stress.jacobian,
                von_mises: &stress.von_mises,
                elastic_energy: &stress.elastic_energy,
                thermoelastic: &stress.thermoelastic,
                elastic_now: &stress.elastic_now,
            }
        }

        #[inline(always)]
        fn state(batch: &Self::Lanes, l: usize) -> Self::State {
            batch.state(l)
        }

        #[inline(always)]
        fn flow_stress(batch: &Self::Lanes, l: usize) -> Real {
            batch.flow_stress[l]
        }

        #[inline(always)]
        fn plastic_work(batch: &Self::Lanes, l: usize) -> Real {
            batch.plastic_work[l]
        }
    };
}

impl Solid<2> for Dim<2> {
    type State = PointState;
    type Lanes = PointLanes;
    type Stress = StressLanes;
    type Batch = Batch;

    shared_lanes!();

    #[inline(always)]
    fn batch() -> Batch {
        Batch {
            f: [[0.0; LANES]; 5],
            pw: [[0.0; LANES]; 3],
            px: [[0.0; LANES]; 2],
        }
    }

    #[inline(always)]
    fn group<const SCATTER: bool, const AVX2: bool>(
        cx: &StressContext<'_, 2>,
        g: usize,
        p0: usize,
        l0: usize,
        lanes: &mut Batch,
        buf: &mut [[Real; 2]],
        lo: usize,
    ) {
        cx.group::<SCATTER, AVX2>(g, p0, l0, lanes, buf, lo);
    }

    #[inline(always)]
    fn undeformed(lanes: &mut Batch, used: usize) {
        for l in used..LANES {
            lanes.f[0][l] = 1.0;
            lanes.f[1][l] = 0.0;
            lanes.f[2][l] = 0.0;
            lanes.f[3][l] = 1.0;
            lanes.f[4][l] = 0.0;
        }
    }

    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // lane loops index several component-major arrays
    fn deformation(
        cx: &StressContext<'_, 2>,
        lanes: &Batch,
        inv_radius: &Lanes,
        batch: &mut PointLanes,
    ) {
        batch.f.copy_from_slice(&lanes.f[..4]);
        for l in 0..LANES {
            batch.f33[l] = if cx.axi {
                1.0 + lanes.f[4][l] * inv_radius[l]
            } else {
                1.0
            };
        }
    }

    #[inline(always)]
    fn update(
        material: &HenckyJ2,
        batch: &mut PointLanes,
    ) -> std::result::Result<StressLanes, (usize, String)> {
        material.update_lanes(batch)
    }

    /// `det F hx hy / max(|F hx e_x|, |F hy e_y|)`, the smaller altitude of the
    /// parallelogram.
    #[inline(always)]
    fn altitude2(batch: &PointLanes, h: [Real; 2]) -> Lanes {
        let [hx, hy] = h;
        let mut altitude2 = [0.0; LANES];
        for (l, a2) in altitude2.iter_mut().enumerate() {
            let (f11, f12, f21, f22) = (batch.f[0][l], batch.f[1][l], batch.f[2][l], batch.f[3][l]);
            let ex2 = hx * hx * (f11 * f11 + f21 * f21);
            let ey2 = hy * hy * (f12 * f12 + f22 * f22);
            let area = (f11 * f22 - f12 * f21) * hx * hy;
            *a2 = area * area.abs() / ex2.max(ey2);
        }
        altitude2
    }

    /// `(|F|^2 + sqrt(|F|^4 - 4 det^2)) / 2`.
    #[inline(always)]
    fn stretch2(batch: &PointLanes, l: usize) -> Real {
        let f = [batch.f[0][l], batch.f[1][l], batch.f[2][l], batch.f[3][l]];
        let norm2 = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] + f[3] * f[3];
        let det = f[0] * f[3] - f[1] * f[2];
        let root = (norm2 * norm2 - 4.0 * det * det).max(0.0).sqrt();
        0.5 * (norm2 + root)
    }

    #[inline(always)]
    fn weigh(
        cx: &StressContext<'_, 2>,
        u: &StressLanes,
        weight: &Lanes,
        inv_radius: &Lanes,
        lanes: &mut Batch,
    ) {
        for l in 0..LANES {
            let w = weight[l];
            lanes.pw[0][l] = u.piola[0][l] * w;
            lanes.pw[1][l] = u.piola[1][l] * w;
            lanes.px[0][l] = u.piola[2][l] * w;
            lanes.px[1][l] = u.piola[3][l] * w;
            lanes.pw[2][l] = if cx.axi {
                u.piola[4][l] * w * inv_radius[l]
            } else {
                0.0
            };
        }
    }
}

impl StressContext<'_, 3> {
    /// Gathers `F = I + sum_I d_I (x) grad N_I` (row-major, `F_iJ = delta_iJ + sum_I d_I,i
    /// N_I,J`) of the `G` consecutive points `p0..p0 + G`, which share one particle list,
    /// into lanes `l0..l0 + G` of `f`; each term a fused multiply-add, in list order.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // component and point indices into several arrays
    fn gather3<const G: usize>(&self, p0: usize, f: &mut [Lanes; 9], l0: usize) {
        let (base, index, table) = self.neighbours(p0, G);
        let d = &self.d[base..];
        let mut acc = [[0.0; MAX_GROUP_3D]; 9];
        for r in 0..3 {
            acc[4 * r][..G].fill(1.0);
        }
        for (&i, e) in index.iter().zip(table.chunks_exact(4 * G)) {
            let di = d[i as usize];
            for r in 0..3 {
                for c in 0..3 {
                    let grad = &e[(c + 1) * G..(c + 2) * G];
                    for j in 0..G {
                        acc[3 * r + c][j] = di[r].mul_add(grad[j], acc[3 * r + c][j]);
                    }
                }
            }
        }
        for (fc, ac) in f.iter_mut().zip(&acc) {
            fc[l0..l0 + G].copy_from_slice(&ac[..G]);
        }
    }

    /// Scatters `w_p P grad N_I` of lanes `l0..l0 + G` (points `p0..p0 + G`, sharing one
    /// particle list) into `buf`, `pw = w_p P` row-major per lane: component `i` of a
    /// point's term is `fma(P_iX, N_x, fma(P_iY, N_y, P_iZ N_z))`, added point by point,
    /// so the bits equal a one-point loop.
    #[inline(always)]
    fn scatter3<const G: usize>(
        &self,
        p0: usize,
        pw: &[Lanes; 9],
        l0: usize,
        buf: &mut [[Real; 3]],
        lo: usize,
    ) {
        let (base, index, table) = self.neighbours(p0, G);
        let buf = &mut buf[base - lo..];
        for (&i, e) in index.iter().zip(table.chunks_exact(4 * G)) {
            // The group's terms over its lanes at once (one vector operation per
            // component), then added to the particle point by point.
            let (nx, ny, nz) = (&e[G..2 * G], &e[2 * G..3 * G], &e[3 * G..4 * G]);
            let mut terms = [[0.0; MAX_GROUP_3D]; 3];
            for (r, tr) in terms.iter_mut().enumerate() {
                for j in 0..G {
                    let l = l0 + j;
                    tr[j] = pw[3 * r][l].mul_add(
                        nx[j],
                        pw[3 * r + 1][l].mul_add(ny[j], pw[3 * r + 2][l] * nz[j]),
                    );
                }
            }
            let b = &mut buf[i as usize];
            for j in 0..G {
                for (br, tr) in b.iter_mut().zip(&terms) {
                    *br += tr[j];
                }
            }
        }
    }
}

impl Solid<3> for Dim<3> {
    type State = PointState3;
    type Lanes = PointLanes3;
    type Stress = StressLanes3;
    type Batch = Batch3;

    shared_lanes!();

    #[inline(always)]
    fn batch() -> Batch3 {
        Batch3 {
            f: [[0.0; LANES]; 9],
            pw: [[0.0; LANES]; 9],
        }
    }

    /// The generic gather and scatter ([`StressContext::gather3`],
    /// [`StressContext::scatter3`]) for every group size; `AVX2` only compiles them for it.
    #[inline(always)]
    fn group<const SCATTER: bool, const AVX2: bool>(
        cx: &StressContext<'_, 3>,
        g: usize,
        p0: usize,
        l0: usize,
        lanes: &mut Batch3,
        buf: &mut [[Real; 3]],
        lo: usize,
    ) {
        macro_rules! run {
            ($g:literal) => {
                if SCATTER {
                    cx.scatter3::<$g>(p0, &lanes.pw, l0, buf, lo)
                } else {
                    cx.gather3::<$g>(p0, &mut lanes.f, l0)
                }
            };
        }
        match g {
            1 => run!(1),
            2 => run!(2),
            3 => run!(3),
            4 => run!(4),
            5 => run!(5),
            6 => run!(6),
            7 => run!(7),
            _ => run!(8),
        }
    }

    #[inline(always)]
    fn undeformed(lanes: &mut Batch3, used: usize) {
        for (c, fc) in lanes.f.iter_mut().enumerate() {
            fc[used..].fill(if c % 4 == 0 { 1.0 } else { 0.0 });
        }
    }

    #[inline(always)]
    fn deformation(_: &StressContext<'_, 3>, lanes: &Batch3, _: &Lanes, batch: &mut PointLanes3) {
        batch.f = lanes.f;
    }

    #[inline(always)]
    fn update(
        material: &HenckyJ2,
        batch: &mut PointLanes3,
    ) -> std::result::Result<StressLanes3, (usize, String)> {
        material.update_lanes3(batch)
    }

    /// `det F hx hy hz / max_k A_k`: the volume of the parallelepiped spanned by the
    /// deformed edges `a_k = F h_k e_k` over its largest face, `A_x = |a_y x a_z|` (and
    /// cyclically), which is its smallest altitude (the distance between the opposite
    /// faces of largest area), as the 2D altitude is the parallelogram's.
    #[inline(always)]
    fn altitude2(batch: &PointLanes3, h: [Real; 3]) -> Lanes {
        let cross = |a: [Real; 3], b: [Real; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let dot = |a: [Real; 3], b: [Real; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let mut altitude2 = [0.0; LANES];
        for (l, a2) in altitude2.iter_mut().enumerate() {
            let edge = |k: usize| std::array::from_fn(|r| batch.f[3 * r + k][l] * h[k]);
            let (ax, ay, az) = (edge(0), edge(1), edge(2));
            let faces = [cross(ay, az), cross(az, ax), cross(ax, ay)];
            let volume = dot(ax, faces[0]);
            let largest = faces.iter().map(|&n| dot(n, n)).fold(0.0, Real::max);
            *a2 = volume * volume.abs() / largest;
        }
        altitude2
    }

    /// The largest eigenvalue of `C = F^T F` ([`sym_spectral3`]).
    #[inline(always)]
    fn stretch2(batch: &PointLanes3, l: usize) -> Real {
        let f = |r: usize, c: usize| batch.f[3 * r + c][l];
        let c = |a: usize, b: usize| (0..3).map(|r| f(r, a) * f(r, b)).sum::<Real>();
        let (eigen, _) = sym_spectral3([c(0, 0), c(1, 1), c(2, 2), c(0, 1), c(1, 2), c(0, 2)]);
        eigen.into_iter().fold(0.0, Real::max)
    }

    #[inline(always)]
    fn weigh(
        _: &StressContext<'_, 3>,
        u: &StressLanes3,
        weight: &Lanes,
        _: &Lanes,
        lanes: &mut Batch3,
    ) {
        for (pw, piola) in lanes.pw.iter_mut().zip(&u.piola) {
            for l in 0..LANES {
                pw[l] = piola[l] * weight[l];
            }
        }
    }
}

/// A thermal scene's per-point temperatures (degrees C), plastic work densities (J/m^3) and
/// plastic strain rates (1/s), which the stress stage updates ([`super::heat::Heat`]), and
/// with elasticity over temperature the last update's elastic state
/// ([`crate::material::PointLanes::elastic_prev`]) and the changes of the last heat stage
/// (K).
pub(super) type HeatSlices<'a> = (
    &'a mut [Real],
    &'a mut [Real],
    &'a mut [Real],
    Option<(&'a mut [[Real; 4]], &'a [Real])>,
);

/// What the stress stage reads besides the layout, in `D` dimensions.
pub(super) struct Inputs<'a, const D: usize = 2> {
    /// RK coefficients of the displacement `d_I` (m).
    pub d: &'a [[Real; D]],
    /// The material.
    pub material: &'a HenckyJ2,
    /// Reference volume weights `w_p` of the points (m^3; 2 pi R included).
    pub weights: &'a [Real],
    /// `1 / R_p` of each point (1/m) in axisymmetry (2D; read for every point in either
    /// dimension, 0 outside axisymmetry).
    pub inv_radius: &'a [Real],
    /// `J_ref = det F` of each point at the last re-reference (-), 1 without one: the
    /// Jacobian and the Cauchy stress are measured from the original configuration.
    pub reference_jacobian: &'a [Real],
    /// Measure the largest principal stretch (for the re-reference trigger).
    pub track_stretch: bool,
    /// Axisymmetric (hoop stretch and stress) or plane strain (2D; not read in 3D).
    pub axi: bool,
    /// Particle spacings (m), for the deformed cells' altitudes.
    pub spacing: [Real; D],
    /// Run the AVX2 build (the CPU must have it, [`has_avx2`]).
    pub avx2: bool,
    /// Adiabatic heating of a thermal scene.
    pub heating: Option<Heating<'a>>,
}

/// What the stress stage sums over all points.
pub(super) struct Sums {
    /// Stored elastic energy `sum_p W(eps_e) w_p` (J).
    pub elastic: Real,
    /// Plastic dissipation `sum_p w_p int sigma_y d eps_p` (J).
    pub plastic: Real,
    /// Elastic energy the changes of temperature since the last stage put in, `sum_p w_p
    /// (W(eps_p, T_p) - W(eps_p, T_p,prev))` (J; 0 without elasticity over temperature).
    pub thermoelastic: Real,
    /// Smallest altitude of a deformed cell (m): `det F hx hy / max(|F hx e_x|, |F hy e_y|)`
    /// in 2D, `det F hx hy hz / max_k A_k` in 3D with the deformed face areas `A_x = |F hy
    /// e_y x F hz e_z|` and cyclically ([`Solid::altitude2`]).
    pub min_altitude: Real,
    /// Largest principal stretch of `F` over the points (-; in-plane in 2D), 0 when not
    /// tracked.
    pub max_stretch: Real,
}

/// Stage 1 of the step: the stress stage ([`stage`]) on the points of `disc` with the
/// coefficients of `st`, and with scni and `discretization.scni_stabilization` the
/// stabilization's force (`nodal_stabilization.rs`); a point whose update fails stops the
/// run with a diagnosis naming it. Sets the stable step estimate `dt_crit0 h_min / h_min0`
/// from the smallest deformed altitude and books the thermoelastic energy. Returns the
/// elastic (the stabilization's included) and plastic energy (J).
pub(super) fn run(
    scene: &Scene,
    disc: &Discretization,
    st: &mut State,
    ws: &mut Workspace,
) -> Result<(Real, Real)> {
    let heating = heating(disc.thermal.as_ref(), st.heat.as_ref(), st.dt_prev);
    let avx2 = ws.simd && has_avx2();
    let input = Inputs {
        d: &st.d,
        material: &disc.material,
        weights: &disc.weights,
        inv_radius: &disc.inv_radius,
        reference_jacobian: &disc.reference_jacobian,
        track_stretch: scene.discretization.rereference_stretch.is_some(),
        axi: scene.model.kinematics == Kinematics::Axisymmetric,
        spacing: disc.spacing,
        avx2,
        heating,
    };
    let sums = stage(
        &ws.team,
        &disc.scatter,
        &mut ws.buf,
        &input,
        &mut st.points,
        &mut ws.out,
        heat_slices(st.heat.as_mut()),
    )
    .map_err(|(p, m)| Error::Diverged {
        step: st.step,
        time: st.time,
        what: format!(
            "integration point {p} (reference position {:?} m): {m}{}",
            disc.points.positions[p],
            above_estimate(scene.time.dt_s, st.dt_prev, st.stable_dt)
        ),
    })?;
    st.stable_dt = disc.critical_dt0 * sums.min_altitude / disc.h_min();
    if scene.discretization.rereference_stretch.is_some() {
        st.max_stretch = sums.max_stretch;
    }
    st.energy.thermoelastic += sums.thermoelastic;
    st.energy.thermoelastic_abs += sums.thermoelastic.abs();
    let stabilization = match (&disc.stabilization, &mut ws.stabilization) {
        (Some(t), Some(s)) => nodal_stabilization::stage(&ws.team, t, s, &st.d, avx2),
        _ => 0.0,
    };
    Ok((sums.elastic + stabilization, sums.plastic))
}

/// What the stress stage needs to heat the points of a scene with `[thermal]` (2D and 3D):
/// [`Heating`] from the scene's `thermal` settings and the last step `dt_prev` (s), with
/// the share `1 - t_since / dt_heat` (-) of the last heat stage's change that the
/// elasticity over temperature does not see yet ([`Heating::ramp`]; 0 before the first heat
/// stage and when the heat does not move).
pub(super) fn heating<'a>(
    thermal: Option<&'a Thermal>,
    heat: Option<&Heat>,
    dt_prev: Real,
) -> Option<Heating<'a>> {
    thermal.map(|th| {
        let mut h = Heating::new(&th.spec, &th.capacity, th.density, dt_prev);
        if let Some(heat) = heat {
            h.ramp = if heat.step_s > 0.0 {
                (1.0 - heat.since_s / heat.step_s).clamp(0.0, 1.0)
            } else {
                0.0
            };
        }
        h
    })
}

/// The points' arrays of `heat` that the stress stage writes (2D and 3D): temperatures,
/// plastic work and rates, and with elasticity over temperature each point's elastic state
/// and the last heat stage's change ([`HeatSlices`]).
pub(super) fn heat_slices(heat: Option<&mut Heat>) -> Option<HeatSlices<'_>> {
    heat.map(|h| {
        (
            &mut h.temperature_c[..],
            &mut h.plastic_work[..],
            &mut h.plastic_rate[..],
            (!h.elastic_state.is_empty())
                .then_some((&mut h.elastic_state[..], &h.stage_change_k[..])),
        )
    })
}

/// Runs the stress stage over all points on `team`: updates each point's history in
/// `states` and its outputs in `outs`, and in a thermal scene the points' temperatures and
/// plastic work in `heat`; fills the chunk buffers `buf` of `scatter`. A point whose update fails
/// stops the stage: `Err((point, message))`, the first in point order. `D` is the dimension
/// (2 for the solver; 3 through [`Dim<3>`]).
pub(super) fn stage<const D: usize>(
    team: &Team,
    scatter: &Scatter<D>,
    buf: &mut [[Real; D]],
    input: &Inputs<'_, D>,
    states: &mut [<Dim<D> as Solid<D>>::State],
    outs: &mut [PointOut],
    heat: Option<HeatSlices<'_>>,
) -> std::result::Result<Sums, (usize, String)>
where
    Dim<D>: Solid<D>,
{
    let cx = StressContext::new(scatter, input);
    let avx2 = input.avx2;
    let Scatter {
        chunk, lo, offsets, ..
    } = scatter;
    let chunk = *chunk;
    let points = states.len();
    let mut sums = vec![ChunkSums::default(); lo.len()];
    let (states, outs, bufs, slots) = (
        Parts::new(states),
        Parts::new(outs),
        Parts::new(buf),
        Parts::new(&mut sums),
    );
    let heat = heat.map(|(t, w, r, e)| {
        (
            Parts::new(t),
            Parts::new(w),
            Parts::new(r),
            e.map(|(p, c)| (Parts::new(p), c)),
        )
    });
    team.for_each(lo.len(), &|c| {
        let range = part(c, chunk, points);
        // SAFETY: chunk `c` alone takes these points, its buffer slice and its slot.
        let (work, slot) = unsafe {
            (
                ChunkWork {
                    first: range.start,
                    states: states.get(range.clone()),
                    outs: outs.get(range.clone()),
                    heat: heat.as_ref().map(|(t, w, r, e)| {
                        (
                            t.get(range.clone()),
                            w.get(range.clone()),
                            r.get(range.clone()),
                            e.as_ref().map(|(p, c)| (p.get(range.clone()), &c[range])),
                        )
                    }),
                    lo: lo[c] as usize,
                    buf: bufs.get(offsets[c]..offsets[c + 1]),
                },
                &mut slots.get(c..c + 1)[0],
            )
        };
        *slot = if avx2 {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: AVX2 support was detected at run time (`has_avx2`).
            unsafe {
                cx.chunk_avx2(work)
            }
            #[cfg(not(target_arch = "x86_64"))]
            unreachable!("AVX2 is detected on x86_64 only")
        } else {
            cx.chunk::<false>(work)
        };
    });
    let (mut elastic, mut plastic, mut min_altitude2) = (0.0, 0.0, Real::INFINITY);
    let mut thermoelastic = 0.0;
    let mut max_stretch2: Real = 0.0;
    for s in sums {
        if let Some(failure) = s.failure {
            return Err(failure);
        }
        elastic += s.elastic;
        plastic += s.plastic;
        thermoelastic += s.thermoelastic;
        min_altitude2 = min_altitude2.min(s.min_altitude2);
        max_stretch2 = max_stretch2.max(s.max_stretch2);
    }
    Ok(Sums {
        elastic,
        plastic,
        thermoelastic,
        min_altitude: min_altitude2.max(0.0).sqrt(),
        max_stretch: max_stretch2.sqrt(),
    })
}
