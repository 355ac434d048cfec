//! The explicit RKPM solver (total Lagrangian, Lagrangian kernel).
//!
//! Setup (once, reference configuration): particle grid and planar volumes; integration
//! points of the chosen rule; RK shape functions and gradients at the points (point-major
//! rows) and at the particles; the chunked scatter buffers for internal forces;
//! row-sum lumped masses `m_I = sum_p rho N_I(x_p) w_p`; essential conditions.
//!
//! One step `n -> n+1` of the central-difference scheme (Belytschko, Liu, Moran 2000,
//! Box 6.1) with the paper's predictor-corrector contact (section II-3):
//! 1. stress stage: `F = I + sum_I d_I (x) grad N_I` at each point (plus `F_33 = r/R` in
//!    axisymmetry), Hencky J2 update, first Piola-Kirchhoff stress `P`;
//! 2. time step: fixed, or `dt_safety * dt_crit`; `dt_crit = dt_crit0 * h_min / h_min0`,
//!    `dt_crit0 = 2 / omega_max` measured at setup (Lanczos iteration on `M^{-1} K`) and
//!    `h_min` the smallest altitude of the deformed cells
//!    `det F hx hy / max(|F e_x| hx, |F e_y| hy)`;
//! 3. force stage: `f_I = sum_p (P grad N_I + e_r P_33 N_I / R) w_p` scattered per chunk
//!    of points (fused with 1) and summed per particle in a fixed order (fused with 4);
//! 4. predictor: `v* = v_{n-1/2} + dt_avg (-f_int / m)`, `d* = d_n + dt v*`;
//! 5. contact: penetration of the predicted boundary particles into the tools at `t_{n+1}`,
//!    paper eqs. 4-6, spread with eq. 7 (particles that cannot reach a tool skipped);
//!
//! The parallel phases (1 with the scatter; on large models also 4, the contact
//! interpolation and the update of 6) run on a [`Team`] over fixed chunks.
//! 6. corrector: `v_{n+1/2} = v* + dt_avg f_c / m`, Lagrange-multiplier projection onto the
//!    essential conditions, `d_{n+1} = d_n + dt v_{n+1/2}`, tools advance;
//! 7. energy account and divergence checks.

use crate::constraints::Constraints;
use crate::error::{Error, Result};
use crate::integration::{grid_points, nodal_domains, PointSet, SCNI_EDGE_POINTS};
use crate::lanes::{Lanes, LANES};
use crate::material::{HenckyJ2, PointLanes, PointState};
use crate::math::Real;
use crate::rk_shape::{Lattice, ShapeTable, Site};
use crate::scene::{Component, Edge, IntegrationRule, Kinematics, Scene};
use crate::team::{Parts, Team};
use crate::tools::{penalty_force, Tool, ToolState, SEARCH_DEPTH_SPACINGS};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::time::{Duration, Instant};

/// Particles handled by one task of the particle phases (force gather and predictor,
/// energy sums and update); fixed so that results do not depend on the number of threads.
const BLOCK: usize = 128;

/// Boundary particles handled by one task of the contact stage's interpolation.
const BOUNDARY_BLOCK: usize = 32;

/// Particle count from which the particle phases run on the team. Below it the phases take
/// a few microseconds, and handing half the particles to the other core costs more in
/// cache-line transfers than it saves (measured on the 1 071-particle Taylor bar: the
/// force, contact and update stages took 0.45-0.50 s run on one thread against 0.48-0.58 s
/// on two). The blocks and their order are the same either way, and so are the bits.
const PARALLEL_PARTICLES: usize = 4096;

/// Energy account (J), whole ring in axisymmetry, per depth in plane strain.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct Energy {
    /// Kinetic energy at the start.
    pub initial: Real,
    /// Kinetic energy `sum m_I |v_I|^2 / 2` at the last half step.
    pub kinetic: Real,
    /// Stored elastic energy `sum_p W(eps_e) w_p`.
    pub elastic: Real,
    /// Plastic dissipation `sum_p w_p int sigma_y d eps_p`.
    pub plastic: Real,
    /// Work done by the tools' contact forces on the workpiece.
    pub contact_work: Real,
    /// Sum of the magnitudes of the contact work increments (scale for the balance).
    pub contact_work_abs: Real,
    /// Work delivered by the tools' motion, `sum dt_avg f_J . v_tool` (J): what a press
    /// would measure. It differs from `contact_work` by what the penalty interface takes.
    pub tool_work: Real,
    /// Sum of the magnitudes of the tool work increments (J).
    pub tool_work_abs: Real,
    /// Internal work over the half step from `d_n` to `d_{n+1/2}`, `dt f_int . v_{n+1/2} / 2`,
    /// which puts the internal energy at the time of the kinetic energy.
    pub internal_half_step: Real,
}

impl Energy {
    /// Internal energy: stored elastic plus plastic dissipation.
    pub fn internal(&self) -> Real {
        self.elastic + self.plastic
    }
    /// `kinetic + internal - contact_work - initial` (J), all at the half step: zero for an
    /// exact account. Kinetic energy and contact work obey the exact discrete identity
    /// `dKE = dt_avg f . (v_new + v_old) / 2`; the internal energy is the constitutive one at
    /// `d_n` plus the half-step work, which equals the internal force work exactly for a
    /// linear elastic body, so what remains measures the time discretisation of plasticity.
    pub fn balance_error(&self) -> Real {
        self.kinetic + self.internal() + self.internal_half_step - self.contact_work - self.initial
    }
    /// The energy against which the balance error is measured: the larger of the initial
    /// energy and the total contact work exchanged.
    pub fn reference(&self) -> Real {
        self.initial
            .max(self.contact_work_abs)
            .max(self.tool_work_abs)
    }
    /// Energy gained by the penalty interface, `contact_work - tool_work` (J): negative or
    /// near zero (the paper's penalty stops particles at a tool, which dissipates); a clear
    /// gain means the contact produced energy.
    pub fn interface_gain(&self) -> Real {
        self.contact_work - self.tool_work
    }
    /// Balance error relative to the reference energy (0 when nothing happened yet).
    pub fn balance_error_rel(&self) -> Real {
        let r = self.reference();
        if r > 0.0 {
            self.balance_error().abs() / r
        } else {
            0.0
        }
    }
}

/// Wall time spent in each stage.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Whole setup: particles, shape functions, masses, constraints, critical step.
    pub setup: Duration,
    /// Part of `setup`: neighbour search and RK shape functions (and SCNI smoothing).
    pub shape_functions: Duration,
    /// Deformation gradient and stress update at the points.
    pub stress: Duration,
    /// Internal force gather, fused with the predictor.
    pub internal_force: Duration,
    /// Contact search and forces.
    pub contact: Duration,
    /// Time integration, constraints and energy.
    pub integration: Duration,
}

/// Everything that changes during a run: saving and restoring it continues bit for bit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Steps taken.
    pub step: u64,
    /// Time (s).
    pub time: Real,
    /// Length of the last step (s), 0 before the first.
    pub dt_prev: Real,
    /// RK coefficients of the displacement `d_I` (m).
    pub d: Vec<[Real; 2]>,
    /// Coefficient velocities at the last half step (m/s).
    pub v: Vec<[Real; 2]>,
    /// Integration point histories.
    pub points: Vec<PointState>,
    /// Tool states.
    pub tools: Vec<ToolState>,
    /// Energy account.
    pub energy: Energy,
    /// Largest penetration seen at an output time (m).
    pub max_penetration: Real,
    /// Stable step estimate on the deformation at `time` (s).
    pub stable_dt: Real,
    /// Time (s) and step count at the last step that was not a full fixed step: with a
    /// fixed step, `time = anchor_time + (step - anchor_step) dt` has no rounding drift, so
    /// requested instants that are whole multiples of the step are reached exactly.
    pub anchor_time: Real,
    /// Step count at `anchor_time`.
    pub anchor_step: u64,
}

/// Per-point results of the last stress update, and the hardening law evaluated at the
/// point's `eps_p` (cached: recomputed only when the point yields).
#[derive(Debug, Clone, Copy, Default)]
struct PointOut {
    von_mises: Real,
    jacobian: Real,
    /// `sigma_y(eps_p)` (Pa).
    flow_stress: Real,
    /// `int_0^eps_p sigma_y de` (J/m^3).
    plastic_work: Real,
}

impl PointOut {
    fn initial(material: &HenckyJ2) -> PointOut {
        PointOut {
            flow_stress: material.hardening.initial_yield(),
            ..Default::default()
        }
    }

    /// Caches the hardening law at `eps_p`, where the flow stress is `flow` and the
    /// initial yield stress `initial` (Pa).
    fn set_plastic_strain(&mut self, material: &HenckyJ2, eps_p: Real, flow: Real, initial: Real) {
        self.flow_stress = flow;
        self.plastic_work = material.hardening.plastic_work_at(eps_p, flow, initial);
    }
}

/// Sums over one chunk of points in the stress stage.
#[derive(Debug, Clone, Default)]
struct ChunkSums {
    elastic: Real,
    plastic: Real,
    /// Smallest squared altitude of a deformed cell (m^2).
    min_altitude2: Real,
    failure: Option<(usize, String)>,
}

/// Deterministic parallel scatter of point forces. The points are cut into fixed chunks of
/// `chunk` points (cells in row order, so a chunk touches a contiguous band of particles);
/// chunk `c` adds its contributions to particles `lo[c]..lo[c] + len` into its own slice
/// `offsets[c]..offsets[c + 1]` of `buf`, and each particle then sums the slices that cover
/// it in chunk order (a block of [`BLOCK`] particles adds the overlapping part of each
/// chunk in `block_chunks`). The bits do not depend on the number of threads.
#[derive(Debug, Clone, Default)]
struct Scatter {
    chunk: usize,
    lo: Vec<u32>,
    offsets: Vec<usize>,
    buf: Vec<[Real; 2]>,
    /// The chunks whose particles overlap each block of particles, ascending:
    /// `block_chunks[block_offsets[b]..block_offsets[b + 1]]`.
    block_offsets: Vec<u32>,
    block_chunks: Vec<u32>,
    /// For each point: the number of consecutive points, starting at it, processed as
    /// one group over one particle list (at most [`MAX_GROUP`], never across a chunk
    /// boundary), or 0 for a point inside a group. The Gauss points of a cell share their
    /// list; two neighbouring q2 cells, or four neighbouring SCNI points, are grouped over
    /// the union of their lists when it is shorter than the lists together ([`GroupPlan`]).
    group: Vec<u8>,
    /// The groups' particle lists (ascending) as offsets from the group's first particle
    /// `base[p]`: `lists[list_range[p].0..list_range[p].1]` for the first point `p` of a
    /// group. Groups with the same offsets share one stored list.
    lists: Vec<u32>,
    list_range: Vec<[u32; 2]>,
    base: Vec<u32>,
    /// Shape function values and gradients of each group, neighbour-major and interleaved
    /// so that a neighbour's values for the group's `g` points are contiguous:
    /// `[N_1..N_g, N_1,x..N_g,x, N_1,y..N_g,y]` per neighbour (one SIMD load each); zero
    /// where a particle of the union is not in a point's own list, which adds exact zeros
    /// and leaves each point's sums as its own list gives them.
    table: Vec<Real>,
    /// Where each group's entries start in `table` (for the first point of a group).
    /// Groups whose entries are bitwise equal share one stored block. On the lattice that
    /// is every group away from the edges: the shape functions are formed from offsets to
    /// the particles in whole spacings ([`Lattice::shape_table`]), so a large model reads
    /// a few distinct blocks from cache instead of streaming one per group from memory.
    table_start: Vec<u32>,
}

/// Largest group of points processed together in the stress stage (the 4 points of a q4
/// cell).
const MAX_GROUP: usize = 4;

/// The group of points starting at a point and its particle list.
struct GroupPlan {
    size: usize,
    list: Vec<u32>,
}

impl GroupPlan {
    /// The group starting at point `p`, within points `..end`: the consecutive points
    /// sharing `p`'s list (up to `max_group`), or, where those are a single point or a
    /// pair, the group of 4 (or else 2) formed with the next singles or pair when the union
    /// of their lists is shorter than the lists together. A group of 2 or 4 runs the AVX2
    /// gather and scatter with one vector operation per particle of its list, so two q2
    /// cells over their union of 20 particles cost 20 operations instead of 2 x 16.
    fn at(pt: &ShapeTable, p: usize, end: usize, max_group: usize) -> GroupPlan {
        let list = |q: usize| &pt.index[pt.row(q)];
        let run = |q: usize| {
            let mut n = 1;
            while n < max_group && q + n < end && list(q + n) == list(q) {
                n += 1;
            }
            n
        };
        let same = run(p);
        for size in [4, 2] {
            if size > max_group || size <= same || size % same != 0 || p + size > end {
                continue;
            }
            let starts = (p..p + size).step_by(same);
            if starts.clone().any(|q| run(q) != same) {
                continue;
            }
            let separate: usize = starts.clone().map(|q| list(q).len()).sum();
            let mut union: Vec<u32> = starts.flat_map(list).copied().collect();
            union.sort_unstable();
            union.dedup();
            if union.len() < separate {
                return GroupPlan { size, list: union };
            }
        }
        GroupPlan {
            size: same,
            list: list(p).to_vec(),
        }
    }
}

impl ContactCache {
    /// Forgets the clearances and the last step's search boxes, so that the next contact
    /// stage evaluates every boundary particle (after the displacements were set from
    /// outside).
    fn forget(&mut self) {
        self.clearance.fill(0.0);
        self.boxes.clear();
        self.update_move = Real::INFINITY;
    }
}

impl Scatter {
    /// Chunks of `chunk` points over `particles` particles, groups of at most `max_group`
    /// points.
    fn new(pt: &ShapeTable, particles: usize, chunk: usize, max_group: usize) -> Scatter {
        let chunks = pt.rows().div_ceil(chunk);
        let (mut lo, mut offsets) = (Vec::with_capacity(chunks), vec![0usize]);
        let mut covering: Vec<Vec<u32>> = vec![Vec::new(); particles.div_ceil(BLOCK)];
        for c in 0..chunks {
            let rows = part(c, chunk, pt.rows());
            let entries = pt.offsets[rows.start] as usize..pt.offsets[rows.end] as usize;
            let idx = &pt.index[entries];
            let (a, b) = (
                idx.iter().copied().min().unwrap_or(0),
                idx.iter().copied().max().unwrap_or(0),
            );
            let base = offsets[c];
            for list in &mut covering[a as usize / BLOCK..=b as usize / BLOCK] {
                list.push(c as u32);
            }
            lo.push(a);
            offsets.push(base + (b - a) as usize + 1);
        }
        let mut block_offsets = vec![0u32];
        let mut block_chunks = Vec::new();
        for list in covering {
            block_chunks.extend(list);
            block_offsets.push(block_chunks.len() as u32);
        }
        let mut group = vec![0u8; pt.rows()];
        let (mut lists, mut list_range) = (Vec::new(), vec![[0u32; 2]; pt.rows()]);
        let mut base = vec![0u32; pt.rows()];
        let mut table = Vec::new();
        let mut table_start = vec![0u32; pt.rows()];
        let mut stored_lists: HashMap<Vec<u32>, u32> = HashMap::new();
        let mut stored_blocks: HashMap<Vec<u64>, u32> = HashMap::new();
        let mut block = Vec::new();
        let mut p = 0;
        while p < pt.rows() {
            let end = ((p / chunk + 1) * chunk).min(pt.rows());
            let plan = GroupPlan::at(pt, p, end, max_group);
            group[p] = plan.size as u8;
            base[p] = plan.list[0];
            let offsets: Vec<u32> = plan.list.iter().map(|&i| i - base[p]).collect();
            let start = *stored_lists.entry(offsets.clone()).or_insert_with(|| {
                lists.extend(&offsets);
                (lists.len() - offsets.len()) as u32
            });
            list_range[p] = [start, start + offsets.len() as u32];
            // Each point's entries in list order, matched against the union.
            block.clear();
            let mut next: Vec<usize> = (p..p + plan.size).map(|q| pt.row(q).start).collect();
            for &i in &plan.list {
                let mut hit = [None; MAX_GROUP];
                for (q, e) in next.iter_mut().enumerate() {
                    if *e < pt.row(p + q).end && pt.index[*e] == i {
                        hit[q] = Some(*e);
                        *e += 1;
                    }
                }
                for values in [&pt.n, &pt.dx, &pt.dy] {
                    block.extend(
                        hit[..plan.size]
                            .iter()
                            .map(|e| e.map_or(0.0, |e| values[e])),
                    );
                }
            }
            let bits: Vec<u64> = block.iter().map(|x| x.to_bits()).collect();
            table_start[p] = *stored_blocks.entry(bits).or_insert_with(|| {
                table.extend(&block);
                (table.len() - block.len()) as u32
            });
            p += plan.size;
        }
        Scatter {
            group,
            lists,
            list_range,
            base,
            table,
            table_start,
            chunk,
            lo,
            buf: vec![[0.0; 2]; *offsets.last().unwrap_or(&0)],
            offsets,
            block_offsets,
            block_chunks,
        }
    }

    /// Point `p`'s entries in its group's block: each particle of the group's list with
    /// `[N, dN/dX, dN/dY]`, zero where the particle is only in another point's list.
    fn point_row(&self, p: usize) -> impl Iterator<Item = (usize, [Real; 3])> + '_ {
        let first = (0..=p).rev().find(|&q| self.group[q] > 0).unwrap_or(0);
        let (g, q) = (self.group[first] as usize, p - first);
        let [a, b] = self.list_range[first];
        let block = &self.table[self.table_start[first] as usize..];
        let base = self.base[first] as usize;
        self.lists[a as usize..b as usize]
            .iter()
            .enumerate()
            .map(move |(k, &i)| {
                let v = &block[3 * g * k..3 * g * (k + 1)];
                (base + i as usize, [v[q], v[g + q], v[2 * g + q]])
            })
    }
}

/// One chunk's share of the stress stage: points `first..first + states.len()` with their
/// histories and cached outputs, and the chunk's force buffer (particles from `lo`).
struct ChunkWork<'a> {
    first: usize,
    states: &'a mut [PointState],
    outs: &'a mut [PointOut],
    lo: usize,
    buf: &'a mut [[Real; 2]],
}

/// What the stress stage reads, shared by all chunks.
struct StressContext<'a> {
    /// Group particle lists ([`Scatter::lists`]).
    lists: &'a [u32],
    list_range: &'a [[u32; 2]],
    base: &'a [u32],
    /// Group sizes per point ([`Scatter::group`]).
    groups: &'a [u8],
    table: &'a [Real],
    table_start: &'a [u32],
    d: &'a [[Real; 2]],
    material: &'a HenckyJ2,
    weights: &'a [Real],
    inv_radius: &'a [Real],
    axi: bool,
    spacing: [Real; 2],
    /// `sigma_y(0)` (Pa), for the plastic work.
    initial_yield: Real,
}

impl StressContext<'_> {
    /// The first particle of the group of `g` points starting at `p0`, the group's
    /// particles as offsets from it, and the group's interleaved shape-function entries
    /// ([`Scatter::table`]).
    #[inline(always)]
    fn neighbours(&self, p0: usize, g: usize) -> (usize, &[u32], &[Real]) {
        let [a, b] = self.list_range[p0];
        let index = &self.lists[a as usize..b as usize];
        let start = self.table_start[p0] as usize;
        (
            self.base[p0] as usize,
            index,
            &self.table[start..start + 3 * g * index.len()],
        )
    }

    /// Gathers `F = I + sum_I d_I (x) grad N_I` and `u_r = sum_I N_I d_I,r` of the `G`
    /// consecutive points `p0..p0 + G`, which share one particle list (each particle's
    /// displacement is loaded once for the `G` points), into lanes `l0..l0 + G` of `f`
    /// (`[F_xX, F_xY, F_yX, F_yY, u_r]`).
    #[inline(always)]
    fn gather<const G: usize>(&self, p0: usize, f: &mut [Lanes; 5], l0: usize) {
        let (base, index, table) = self.neighbours(p0, G);
        let d = &self.d[base..];
        // xy holds F_xX, F_xY (from d_x) then F_yX, F_yY (from d_y) of the G points in the
        // order of a neighbour's `[N_x.., N_y..]` entries, so each neighbour adds two
        // vectors of 2G products, each a fused multiply-add.
        let mut xy = [[0.0; 2 * MAX_GROUP]; 2];
        xy[0][..G].fill(1.0);
        xy[1][G..2 * G].fill(1.0);
        let mut ur = [0.0; MAX_GROUP];
        for (&i, e) in index.iter().zip(table.chunks_exact(3 * G)) {
            let di = d[i as usize];
            for q in 0..2 * G {
                xy[0][q] = di[0].mul_add(e[G + q], xy[0][q]);
                xy[1][q] = di[1].mul_add(e[G + q], xy[1][q]);
            }
            for j in 0..G {
                ur[j] = di[0].mul_add(e[j], ur[j]);
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
                let l = l0 + j;
                let (n, nx, ny) = (e[j], e[G + j], e[2 * G + j]);
                b[0] += pw[0][l].mul_add(nx, pw[1][l].mul_add(ny, pw[2][l] * n));
                b[1] += px[0][l].mul_add(nx, px[1][l] * ny);
            }
        }
    }

    /// Gather (`SCATTER` false) or scatter a group of `g` points, `g` in `1..=MAX_GROUP`;
    /// pairs and quads through [`group_avx2`] in the AVX2 build (`AVX2`, only from
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
                    self.gather::<$g>(p0, &mut lanes.f, l0)
                }
            };
        }
        #[cfg(target_arch = "x86_64")]
        if AVX2 && (g == 2 || g == 4) {
            let (base, index, table) = self.neighbours(p0, g);
            let (d, buf) = (&self.d[base..], &mut buf[base - lo..]);
            // SAFETY: `AVX2` is true only inside `chunk_avx2`, called where the CPU has AVX2.
            unsafe {
                match (SCATTER, g) {
                    (false, 2) => group_avx2::gather2(index, table, d, &mut lanes.f, l0),
                    (false, _) => group_avx2::gather4(index, table, d, &mut lanes.f, l0),
                    (true, 2) => group_avx2::scatter2(index, table, &lanes.pw, &lanes.px, l0, buf),
                    (true, _) => group_avx2::scatter4(index, table, &lanes.pw, &lanes.px, l0, buf),
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

    /// The stress stage of one chunk of points (`work`). Points go through the
    /// material in batches of whole groups filling up to [`LANES`] lanes; a lane's results
    /// do not depend on the batch, so the bits equal a point-by-point loop.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // lane loops index several component-major arrays
    fn chunk<const AVX2: bool>(&self, work: ChunkWork<'_>) -> ChunkSums {
        let ChunkWork {
            first,
            states,
            outs,
            lo,
            buf,
        } = work;
        let group = &self.groups[first..first + states.len()];
        buf.iter_mut().for_each(|b| *b = [0.0; 2]);
        let mut s = ChunkSums {
            elastic: 0.0,
            plastic: 0.0,
            min_altitude2: Real::INFINITY,
            failure: None,
        };
        let [hx, hy] = self.spacing;
        let mut lanes = Batch {
            f: [[0.0; LANES]; 5],
            pw: [[0.0; LANES]; 3],
            px: [[0.0; LANES]; 2],
        };
        let mut batch = PointLanes::unstressed();
        let mut k = 0;
        while k < states.len() {
            // Whole groups of points, in order, while they fit in the lanes.
            let k0 = k;
            let mut used = 0;
            while k < states.len() && used + group[k] as usize <= LANES {
                let g = group[k] as usize;
                self.group::<false, AVX2>(g, first + k, used, &mut lanes, buf, lo);
                used += g;
                k += g;
            }
            let p0 = first + k0;
            if used < LANES {
                // Unused lanes: undeformed, unstressed, unable to yield.
                for l in used..LANES {
                    lanes.f[0][l] = 1.0;
                    lanes.f[1][l] = 0.0;
                    lanes.f[2][l] = 0.0;
                    lanes.f[3][l] = 1.0;
                    lanes.f[4][l] = 0.0;
                }
                batch = PointLanes::unstressed();
            }
            let mut weight = [0.0; LANES];
            weight[..used].copy_from_slice(&self.weights[p0..p0 + used]);
            let mut inv_radius = [0.0; LANES];
            inv_radius[..used].copy_from_slice(&self.inv_radius[p0..p0 + used]);
            batch.f.copy_from_slice(&lanes.f[..4]);
            for l in 0..LANES {
                batch.f33[l] = if self.axi {
                    1.0 + lanes.f[4][l] * inv_radius[l]
                } else {
                    1.0
                };
            }
            let (states, outs) = (&mut states[k0..k0 + used], &mut outs[k0..k0 + used]);
            for (l, (state, out)) in states.iter().zip(outs.iter()).enumerate() {
                batch.set_history(l, state, out.flow_stress);
            }
            let u = match self.material.update_lanes(&mut batch) {
                Ok(u) => u,
                Err((l, m)) => {
                    s.failure = Some((p0 + l, m));
                    return s;
                }
            };
            // Smallest altitude of the deformed cell spanned by F (hx e_x), F (hy e_y):
            // det F hx hy / max(|F hx e_x|, |F hy e_y|), compared squared (all lanes at
            // once; unused lanes hold F = I and are not read).
            let mut altitude2 = [0.0; LANES];
            for (l, a2) in altitude2.iter_mut().enumerate() {
                let (f11, f12, f21, f22) =
                    (batch.f[0][l], batch.f[1][l], batch.f[2][l], batch.f[3][l]);
                let ex2 = hx * hx * (f11 * f11 + f21 * f21);
                let ey2 = hy * hy * (f12 * f12 + f22 * f22);
                let area = (f11 * f22 - f12 * f21) * hx * hy;
                *a2 = area * area.abs() / ex2.max(ey2);
            }
            // Scatter weights w_p (P grad N_I + e_r P_33 N_I / R_p), all lanes at once.
            for l in 0..LANES {
                let w = weight[l];
                lanes.pw[0][l] = u.piola[0][l] * w;
                lanes.pw[1][l] = u.piola[1][l] * w;
                lanes.px[0][l] = u.piola[2][l] * w;
                lanes.px[1][l] = u.piola[3][l] * w;
                lanes.pw[2][l] = if self.axi {
                    u.piola[4][l] * w * inv_radius[l]
                } else {
                    0.0
                };
            }
            for (l, (state, out)) in states.iter_mut().zip(outs.iter_mut()).enumerate() {
                let eps_p = state.eps_p;
                *state = batch.state(l);
                if state.eps_p != eps_p {
                    let flow = batch.flow_stress[l];
                    out.set_plastic_strain(self.material, state.eps_p, flow, self.initial_yield);
                }
                out.von_mises = u.von_mises[l];
                out.jacobian = u.jacobian[l];
                s.elastic += u.elastic_energy[l] * weight[l];
                s.plastic += out.plastic_work * weight[l];
                s.min_altitude2 = s.min_altitude2.min(altitude2[l]);
            }
            let mut l0 = 0;
            while l0 < used {
                let g = group[k0 + l0] as usize;
                self.group::<true, AVX2>(g, p0 + l0, l0, &mut lanes, buf, lo);
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
    unsafe fn chunk_avx2(&self, work: ChunkWork<'_>) -> ChunkSums {
        self.chunk::<true>(work)
    }
}

/// Gather and scatter of a pair (q2 cell) or a quad (q4 cell) of points sharing a particle
/// list, with explicit 256-bit vectors: a neighbour's entries `[N.., N_x.., N_y..]` give
/// `F_xX`, `F_xY` of all the group's points from products with `d_x`, and `F_yX`, `F_yY`
/// from products with `d_y`. Each lane does the fused multiply-adds of
/// [`StressContext::gather`] and [`StressContext::scatter`] in their order (the generic
/// build's `mul_add` rounds once, as the FMA instruction does), so the bits are the
/// generic build's; left to itself the compiler splits these loops into 128-bit pieces and
/// shuffles (the quad gather took some 70 instructions per neighbour). `index` holds the
/// particles as offsets from the group's first particle, where `d` and `buf` start.
#[cfg(target_arch = "x86_64")]
mod group_avx2 {
    use super::{Lanes, Real};
    use std::arch::x86_64::*;

    /// Loads 4 values.
    #[inline(always)]
    fn load4(x: &[Real]) -> __m256d {
        assert!(x.len() >= 4);
        // SAFETY: 4 values are in bounds (checked above).
        unsafe { _mm256_loadu_pd(x.as_ptr()) }
    }

    /// Loads 2 values.
    #[inline(always)]
    fn load2(x: &[Real]) -> __m128d {
        assert!(x.len() >= 2);
        // SAFETY: 2 values are in bounds (checked above).
        unsafe { _mm_loadu_pd(x.as_ptr()) }
    }

    /// The 4 values of a vector.
    #[inline(always)]
    fn store4(x: __m256d) -> [Real; 4] {
        let mut out = [0.0; 4];
        // SAFETY: `out` holds 4 values.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), x) };
        out
    }

    /// Adds `[b0, b1]` pairs to a buffer entry in order: `((b + p[0]) + p[1]) + ..`.
    #[inline(always)]
    fn add_to(b: &mut [Real; 2], pairs: &[__m128d]) {
        // SAFETY: `b` holds 2 values.
        unsafe {
            let mut acc = _mm_loadu_pd(b.as_ptr());
            for &p in pairs {
                acc = _mm_add_pd(acc, p);
            }
            _mm_storeu_pd(b.as_mut_ptr(), acc);
        }
    }

    /// `F` and `u_r` of a pair into lanes `l0, l0 + 1` of `f`; neighbour entries
    /// `[N_1, N_2, N_1,x, N_2,x, N_1,y, N_2,y]`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn gather2(
        index: &[u32],
        table: &[Real],
        d: &[[Real; 2]],
        f: &mut [Lanes; 5],
        l0: usize,
    ) {
        // [F_xX 1, F_xX 2, F_xY 1, F_xY 2] and [F_yX 1, F_yX 2, F_yY 1, F_yY 2].
        let mut fx = _mm256_setr_pd(1.0, 1.0, 0.0, 0.0);
        let mut fy = _mm256_setr_pd(0.0, 0.0, 1.0, 1.0);
        let mut ur = _mm_setzero_pd();
        for (&i, e) in index.iter().zip(table.chunks_exact(6)) {
            let di = d[i as usize];
            let (v, g) = (load2(e), load4(&e[2..]));
            fx = _mm256_fmadd_pd(_mm256_set1_pd(di[0]), g, fx);
            fy = _mm256_fmadd_pd(_mm256_set1_pd(di[1]), g, fy);
            ur = _mm_fmadd_pd(_mm_set1_pd(di[0]), v, ur);
        }
        let (a, b) = (store4(fx), store4(fy));
        let mut u = [0.0; 2];
        // SAFETY: `u` holds 2 values.
        unsafe { _mm_storeu_pd(u.as_mut_ptr(), ur) };
        f[0][l0..l0 + 2].copy_from_slice(&a[..2]);
        f[1][l0..l0 + 2].copy_from_slice(&a[2..]);
        f[2][l0..l0 + 2].copy_from_slice(&b[..2]);
        f[3][l0..l0 + 2].copy_from_slice(&b[2..]);
        f[4][l0..l0 + 2].copy_from_slice(&u);
    }

    /// `w_p (P grad N_I + e_r P_33 N_I / R_p)` of lanes `l0, l0 + 1` into `buf`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn scatter2(
        index: &[u32],
        table: &[Real],
        pw: &[Lanes; 3],
        px: &[Lanes; 2],
        l0: usize,
        buf: &mut [[Real; 2]],
    ) {
        let w = |x: &Lanes| load2(&x[l0..]);
        let (wxx, wxy, wv, wyx, wyy) = (w(&pw[0]), w(&pw[1]), w(&pw[2]), w(&px[0]), w(&px[1]));
        for (&i, e) in index.iter().zip(table.chunks_exact(6)) {
            let (v, x, y) = (load2(e), load2(&e[2..]), load2(&e[4..]));
            // Per point j: fma(P_xX, N_x, fma(P_xY, N_y, P_33 N / R)), fma(P_yX, N_x, P_yY N_y).
            let sx = _mm_fmadd_pd(wxx, x, _mm_fmadd_pd(wxy, y, _mm_mul_pd(wv, v)));
            let sy = _mm_fmadd_pd(wyx, x, _mm_mul_pd(wyy, y));
            add_to(
                &mut buf[i as usize],
                &[_mm_unpacklo_pd(sx, sy), _mm_unpackhi_pd(sx, sy)],
            );
        }
    }

    /// `F` and `u_r` of a quad into lanes `l0..l0 + 4` of `f`; neighbour entries
    /// `[N_1..N_4, N_1,x..N_4,x, N_1,y..N_4,y]`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn gather4(
        index: &[u32],
        table: &[Real],
        d: &[[Real; 2]],
        f: &mut [Lanes; 5],
        l0: usize,
    ) {
        let one = _mm256_set1_pd(1.0);
        let zero = _mm256_setzero_pd();
        let (mut fxx, mut fxy, mut fyx, mut fyy, mut ur) = (one, zero, zero, one, zero);
        for (&i, e) in index.iter().zip(table.chunks_exact(12)) {
            let di = d[i as usize];
            let (v, x, y) = (load4(e), load4(&e[4..]), load4(&e[8..]));
            let (d0, d1) = (_mm256_set1_pd(di[0]), _mm256_set1_pd(di[1]));
            fxx = _mm256_fmadd_pd(d0, x, fxx);
            fxy = _mm256_fmadd_pd(d0, y, fxy);
            fyx = _mm256_fmadd_pd(d1, x, fyx);
            fyy = _mm256_fmadd_pd(d1, y, fyy);
            ur = _mm256_fmadd_pd(d0, v, ur);
        }
        for (c, x) in [fxx, fxy, fyx, fyy, ur].into_iter().enumerate() {
            f[c][l0..l0 + 4].copy_from_slice(&store4(x));
        }
    }

    /// `w_p (P grad N_I + e_r P_33 N_I / R_p)` of lanes `l0..l0 + 4` into `buf`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn scatter4(
        index: &[u32],
        table: &[Real],
        pw: &[Lanes; 3],
        px: &[Lanes; 2],
        l0: usize,
        buf: &mut [[Real; 2]],
    ) {
        let w = |x: &Lanes| load4(&x[l0..]);
        let (wxx, wxy, wv, wyx, wyy) = (w(&pw[0]), w(&pw[1]), w(&pw[2]), w(&px[0]), w(&px[1]));
        for (&i, e) in index.iter().zip(table.chunks_exact(12)) {
            let (v, x, y) = (load4(e), load4(&e[4..]), load4(&e[8..]));
            // Per point j: fma(P_xX, N_x, fma(P_xY, N_y, P_33 N / R)), fma(P_yX, N_x, P_yY N_y).
            let sx = _mm256_fmadd_pd(wxx, x, _mm256_fmadd_pd(wxy, y, _mm256_mul_pd(wv, v)));
            let sy = _mm256_fmadd_pd(wyx, x, _mm256_mul_pd(wyy, y));
            let (x01, y01) = (_mm256_castpd256_pd128(sx), _mm256_castpd256_pd128(sy));
            let (x23, y23) = (
                _mm256_extractf128_pd::<1>(sx),
                _mm256_extractf128_pd::<1>(sy),
            );
            add_to(
                &mut buf[i as usize],
                &[
                    _mm_unpacklo_pd(x01, y01),
                    _mm_unpackhi_pd(x01, y01),
                    _mm_unpacklo_pd(x23, y23),
                    _mm_unpackhi_pd(x23, y23),
                ],
            );
        }
    }
}

/// Part `k` of `0..n` cut into parts of `size`: `k size..min((k + 1) size, n)`.
fn part(k: usize, size: usize, n: usize) -> std::ops::Range<usize> {
    k * size..((k + 1) * size).min(n)
}

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

/// Runs `body` over `blocks` blocks of a particle phase of a model of `particles`
/// particles: on the team from [`PARALLEL_PARTICLES`] up, else on this thread in block
/// order.
fn particle_phase(team: &Team, particles: usize, blocks: usize, body: &(dyn Fn(usize) + Sync)) {
    if particles >= PARALLEL_PARTICLES {
        team.for_each(blocks, body);
    } else {
        (0..blocks).for_each(body);
    }
}

/// Whether the CPU runs the AVX2 build of the stress stage (x86_64 with AVX2 and FMA; false
/// on other architectures, which use the generic build).
fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    return std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma");
    #[cfg(not(target_arch = "x86_64"))]
    return false;
}

/// Per-batch lanes of the stress stage: gathered `[F_xX, F_xY, F_yX, F_yY, u_r]`, and the
/// weighted stresses to scatter (see [`StressContext::scatter`]).
struct Batch {
    f: [Lanes; 5],
    pw: [Lanes; 3],
    px: [Lanes; 2],
}

/// What the contact stage keeps from step to step to skip boundary particles that cannot
/// reach a tool ([`Simulation::contact_stage`]). None of it is state: dropping it (as
/// `restore` does) only makes the next step evaluate every boundary particle.
#[derive(Debug, Clone, Default)]
struct ContactCache {
    /// `dt V*` of the last two predictors (m), `V*` the largest velocity component of a
    /// particle after the predictor and `dt` the step the contact stage interpolates with.
    predicted_moves: [Real; 2],
    /// `dt V` of the last update (m), `V` the largest velocity component at the half step.
    update_move: Real,
    /// `S_J = sum_I |N_I(X_J)|` of each boundary particle. Between two contact stages
    /// `u_I = d_I + dt v*_I` changes by `dt_n v_{n+1/2} + dt_{n+1} v*_{n+1} - dt_n v*_n`,
    /// at most `du = update_move + predicted_moves[0] + predicted_moves[1]` per component,
    /// so `x_J = X_J + sum_I N_I(X_J) u_I` moves at most `S_J du` per component.
    sum_abs: Vec<Real>,
    /// Lower bound on the distance (largest component) from each boundary particle to
    /// every tool's search box (m); positive means the particle cannot be in one.
    clearance: Vec<Real>,
    /// Predicted position (m) and velocity (m/s) of each boundary particle evaluated this
    /// step.
    motion: Vec<[[Real; 2]; 2]>,
    /// The tools' search boxes at the last step.
    boxes: Vec<Extents>,
    /// Skip the particles with a positive clearance (false only in the test that compares
    /// against evaluating all of them).
    skip: bool,
}

/// Axis-aligned bounds of the deformed workpiece (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Extents {
    /// Smallest and largest x (r).
    pub x: [Real; 2],
    /// Smallest and largest y (z).
    pub y: [Real; 2],
}

/// Particle fields for output frames.
#[derive(Debug, Clone, Default)]
pub struct Fields {
    /// Physical positions `X_J + u(X_J)` (m).
    pub positions: Vec<[Real; 2]>,
    /// Physical displacements `u(X_J)` (m).
    pub displacement: Vec<[Real; 2]>,
    /// Physical velocities (m/s).
    pub velocity: Vec<[Real; 2]>,
    /// Equivalent plastic strain smoothed to particles (-).
    pub plastic_strain: Vec<Real>,
    /// Von Mises stress smoothed to particles (Pa).
    pub von_mises: Vec<Real>,
}

/// Most output samples a run may take (history rows, published samples).
pub const MAX_SAMPLES: u64 = 10_000_000;

/// Output sample times after t = 0 for a run to `end` every `interval` (s): `k * interval`
/// for k = 1, 2, ... (the count rounded when `end / interval` is whole up to rounding errors,
/// else rounded down), then `end` if the last one falls short of it, so that stepping from
/// sample to sample always reaches the end. None if that is more than [`MAX_SAMPLES`].
#[must_use]
pub fn sample_times(end: Real, interval: Real) -> Option<Vec<Real>> {
    let ratio = end / interval;
    let n = if (ratio - ratio.round()).abs() < 1e-9 * ratio.max(1.0) {
        ratio.round()
    } else {
        ratio.floor()
    };
    if n.is_nan() || n > MAX_SAMPLES as Real {
        return None;
    }
    // n is a whole number in [0, MAX_SAMPLES]: the cast is exact.
    let mut times: Vec<Real> = (1..=n as u64)
        .map(|k| (k as Real * interval).min(end))
        .collect();
    if times.last().is_none_or(|&t| t < end * (1.0 - 1e-12)) {
        times.push(end);
    }
    Some(times)
}

/// A running simulation of one scene.
#[derive(Debug, Clone)]
pub struct Simulation {
    scene: Scene,
    material: HenckyJ2,
    nx: usize,
    ny: usize,
    spacing: [Real; 2],
    ref_pos: Vec<[Real; 2]>,
    mass: Vec<Real>,
    /// `1 / m_I` (1/kg): the predictor and corrector multiply by it (two divisions per
    /// particle and step were a quarter of the serial stages' time).
    inv_mass: Vec<Real>,
    points: PointSet,
    weights: Vec<Real>,
    /// `1 / R_p` of each integration point (1/m) in axisymmetry, 1 in plane strain.
    inv_radius: Vec<Real>,
    /// The point shape functions live only in the scatter's shared blocks
    /// ([`Scatter::point_row`]); the point-major table is dropped after setup.
    scatter: Scatter,
    /// `N_I(X_J)` in row `J`, for positions and contact; its gradients are freed after
    /// setup (nothing reads them).
    nodal: ShapeTable,
    boundary: Vec<u32>,
    constraints: Option<Constraints>,
    tools: Vec<Tool>,
    st: State,
    out: Vec<PointOut>,
    f_int: Vec<[Real; 2]>,
    f_con: Vec<[Real; 2]>,
    v_prev: Vec<[Real; 2]>,
    critical_dt0: Real,
    /// Contact bookkeeping carried between steps.
    contact: ContactCache,
    /// The threads of the parallel phases.
    team: Team,
    /// Use the AVX2 build of the stress stage where the CPU has it (same bits either way;
    /// false only in the test that compares the two).
    simd: bool,
    /// Wall time per stage since setup.
    pub times: StageTimes,
}

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
        let (weights, inv_radius): (Vec<Real>, Vec<Real>) = points
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
            .unzip();
        let rho = scene.material.density_kg_per_m3;
        // Row-sum lumped masses m_I = sum_p rho N_I(x_p) w_p.
        let np = ref_pos.len();
        let mut mass = vec![0.0; np];
        for (p, w) in weights.iter().enumerate() {
            for e in pt.row(p) {
                mass[pt.index[e] as usize] += rho * pt.n[e] * w;
            }
        }
        // Chunks of about two rows of cells, at least 64 points: enough chunks to balance
        // the threads, few enough that the buffers overlap little.
        let chunk = (2 * pt.rows() / (ny - 1)).max(64);
        let scatter = Scatter::new(&pt, np, chunk, MAX_GROUP);
        if let Some((i, m)) = mass
            .iter()
            .enumerate()
            .find(|(_, m)| m.is_nan() || **m <= 0.0)
        {
            return Err(Error::ShapeFunctions(format!(
                "lumped mass of particle {i} at {:?} m is {m:.3e} kg; increase the support or the resolution",
                ref_pos[i]
            )));
        }
        // Boundary ring, counter-clockwise.
        let id = |i: usize, j: usize| (j * nx + i) as u32;
        let mut boundary = Vec::new();
        boundary.extend((0..nx).map(|i| id(i, 0)));
        boundary.extend((1..ny).map(|j| id(nx - 1, j)));
        boundary.extend((0..nx - 1).rev().map(|i| id(i, ny - 1)));
        boundary.extend((1..ny - 1).rev().map(|j| id(0, j)));
        // Essential conditions: user edges, plus the axis of an axisymmetric body.
        let edge_particles = |e: Edge| -> Vec<u32> {
            match e {
                Edge::XMin => (0..ny).map(|j| id(0, j)).collect(),
                Edge::XMax => (0..ny).map(|j| id(nx - 1, j)).collect(),
                Edge::YMin => (0..nx).map(|i| id(i, 0)).collect(),
                Edge::YMax => (0..nx).map(|i| id(i, ny - 1)).collect(),
            }
        };
        let mut rows = Vec::new();
        for c in &scene.constraints {
            for comp in &c.fix {
                let k = match comp {
                    Component::X => 0,
                    Component::Y => 1,
                };
                rows.extend(edge_particles(c.edge).into_iter().map(|j| (j, k)));
            }
        }
        if axi && w.origin_m[0] == 0.0 {
            rows.extend(edge_particles(Edge::XMin).into_iter().map(|j| (j, 0)));
        }
        let constraints = Constraints::new(rows, &nodal, &mass)?;
        let material = HenckyJ2::new(
            scene.material.youngs_modulus_pa,
            scene.material.poisson_ratio,
            scene.material.hardening,
        );
        let wave_speed = material.wave_speed(rho);
        let depth = SEARCH_DEPTH_SPACINGS * h[0].max(h[1]);
        let tools: Vec<Tool> = scene.tools.iter().map(|t| Tool::new(t, depth)).collect();
        let mut v = vec![w.initial_velocity_m_per_s; np];
        if let Some(c) = &constraints {
            c.project(&mut v, &mass);
        }
        let initial = 0.5
            * mass
                .iter()
                .zip(&v)
                .map(|(m, v)| m * (v[0] * v[0] + v[1] * v[1]))
                .sum::<Real>();
        let npts = points.positions.len();
        let stable_dt = h[0].min(h[1]) / wave_speed;
        let mut sim = Simulation {
            material,
            nx,
            ny,
            spacing: h,
            inv_mass: mass.iter().map(|m| 1.0 / m).collect(),
            mass,
            weights,
            inv_radius,
            scatter,
            contact: ContactCache {
                sum_abs: boundary
                    .iter()
                    .map(|&j| nodal.row(j as usize).map(|e| nodal.n[e].abs()).sum())
                    .collect(),
                clearance: vec![0.0; boundary.len()],
                motion: vec![[[0.0; 2]; 2]; boundary.len()],
                skip: true,
                ..Default::default()
            },
            boundary,
            constraints,
            st: State {
                step: 0,
                time: 0.0,
                dt_prev: 0.0,
                d: vec![[0.0; 2]; np],
                v: v.clone(),
                points: vec![PointState::default(); npts],
                tools: tools.iter().map(|t| t.state).collect(),
                energy: Energy {
                    initial,
                    kinetic: initial,
                    ..Default::default()
                },
                max_penetration: 0.0,
                stable_dt,
                anchor_time: 0.0,
                anchor_step: 0,
            },
            tools,
            out: vec![PointOut::initial(&material); npts],
            f_int: vec![[0.0; 2]; np],
            f_con: vec![[0.0; 2]; np],
            v_prev: v,
            critical_dt0: stable_dt,
            simd: true,
            team: Team::default(),
            ref_pos,
            points,
            nodal,
            scene: scene.clone(),
            times: StageTimes {
                setup: t0.elapsed(),
                ..Default::default()
            },
        };
        sim.critical_dt0 = sim.measure_critical_step()?;
        sim.stress_stage()?;
        sim.force_stage(None);
        sim.times = StageTimes {
            setup: t0.elapsed(),
            shape_functions,
            ..Default::default()
        };
        if let Some(dt) = scene.time.dt_s {
            if dt > sim.st.stable_dt {
                return Err(Error::Unstable {
                    step: 0,
                    time: 0.0,
                    dt,
                    dt_crit: sim.st.stable_dt,
                    detail: format!(
                        "time.dt_s is above the critical step 2 / omega_max of this discretisation (h_min / c = {:.4e} s); lower it or remove it to use dt_safety",
                        h[0].min(h[1]) / wave_speed
                    ),
                });
            }
        }
        Ok(sim)
    }

    /// The scene being run.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.ref_pos.len()
    }
    /// Number of integration points.
    pub fn point_count(&self) -> usize {
        self.points.positions.len()
    }
    /// Grid size `(nx, ny)`.
    pub fn grid(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }
    /// Particle spacings (m).
    pub fn spacing(&self) -> [Real; 2] {
        self.spacing
    }
    /// Reference particle positions (m).
    pub fn reference_positions(&self) -> &[[Real; 2]] {
        &self.ref_pos
    }
    /// Lumped masses (kg).
    pub fn masses(&self) -> &[Real] {
        &self.mass
    }
    /// Boundary particles, counter-clockwise.
    pub fn boundary(&self) -> &[u32] {
        &self.boundary
    }
    /// Time (s).
    pub fn time(&self) -> Real {
        self.st.time
    }
    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.st.step
    }
    /// Stable step estimate `h_min / c` on the current deformation (s).
    pub fn stable_dt(&self) -> Real {
        self.st.stable_dt
    }
    /// The step the next call to `step` will take when not limited (s).
    pub fn next_dt(&self) -> Real {
        self.scene
            .time
            .dt_s
            .unwrap_or(self.scene.time.dt_safety * self.st.stable_dt)
    }
    /// Energy account.
    pub fn energy(&self) -> Energy {
        self.st.energy
    }
    /// Tools.
    pub fn tools(&self) -> &[Tool] {
        &self.tools
    }
    /// Index of the tool named `name`.
    pub fn tool_index(&self, name: &str) -> Option<usize> {
        self.tools.iter().position(|t| t.name == name)
    }
    /// Set a tool's velocity along its axis (m/s) from outside, overriding the scene motion.
    pub fn set_tool_velocity(&mut self, tool: usize, v: Real) -> Result<()> {
        let t = self
            .tools
            .get_mut(tool)
            .ok_or_else(|| Error::Request(format!("no tool with index {tool}")))?;
        if !t.is_movable() {
            return Err(Error::Request(format!(
                "tool `{}` is fixed in the scene",
                t.name
            )));
        }
        if !v.is_finite() {
            return Err(Error::Request(format!(
                "velocity {v} for tool `{}` is not finite",
                t.name
            )));
        }
        t.state.command = Some(v);
        Ok(())
    }
    /// Total mass of the workpiece (kg; whole ring or per depth).
    pub fn total_mass(&self) -> Real {
        self.mass.iter().sum()
    }
    /// Momentum `sum m_I v_I` (kg m/s) at the last half step.
    pub fn momentum(&self) -> [Real; 2] {
        self.st
            .v
            .iter()
            .zip(&self.mass)
            .fold([0.0; 2], |a, (v, m)| [a[0] + m * v[0], a[1] + m * v[1]])
    }
    /// Largest equivalent plastic strain over the integration points.
    pub fn max_plastic_strain(&self) -> Real {
        self.st.points.iter().map(|s| s.eps_p).fold(0.0, Real::max)
    }
    /// Largest penetration seen at an output time (m).
    pub fn max_penetration(&self) -> Real {
        self.st.max_penetration
    }
    /// The whole changing state.
    pub fn state(&self) -> &State {
        &self.st
    }
    /// Restore a state saved from a simulation of the same scene.
    pub fn restore(&mut self, st: State) -> Result<()> {
        if st.d.len() != self.st.d.len()
            || st.v.len() != self.st.v.len()
            || st.points.len() != self.st.points.len()
            || st.tools.len() != self.st.tools.len()
        {
            return Err(Error::State(
                "the saved state belongs to another discretisation".into(),
            ));
        }
        for (t, s) in self.tools.iter_mut().zip(&st.tools) {
            t.state = *s;
        }
        self.v_prev.clone_from(&st.v);
        self.contact.forget();
        let hardening = &self.material.hardening;
        let initial = hardening.initial_yield();
        for (out, point) in self.out.iter_mut().zip(&st.points) {
            let flow = hardening.flow_stress(point.eps_p);
            out.set_plastic_strain(&self.material, point.eps_p, flow, initial);
        }
        self.st = st;
        Ok(())
    }

    /// One central-difference step, at most `max_dt` long (s). See the module doc.
    pub fn step(&mut self, max_dt: Option<Real>) -> Result<()> {
        let (elastic, plastic) = self.stress_stage()?;
        let t1 = Instant::now();
        let dt_full = self.next_dt();
        let dt = landing_step(dt_full, max_dt);
        if dt.is_nan() || dt <= 0.0 {
            return Err(Error::Request(format!(
                "step length {dt} s is not positive"
            )));
        }
        let dt_avg = 0.5 * (dt + self.st.dt_prev);
        let t2 = Instant::now();
        self.force_stage(Some((dt_avg, dt_full)));
        let t3 = Instant::now();
        // Tools advance over the step at their mid-step velocity.
        let t_mid = self.st.time + 0.5 * dt;
        for t in self.tools.iter_mut() {
            t.state.velocity = t.velocity_at(t_mid);
            t.state.stroke += dt * t.state.velocity;
        }
        let (contact_work_rate, tool_work) = self.contact_stage(dt_full, dt_avg);
        let t4 = Instant::now();
        // Corrector, constraints, update.
        if contact_work_rate {
            for ((v, f), im) in self.st.v.iter_mut().zip(&self.f_con).zip(&self.inv_mass) {
                let a = dt_avg * im;
                v[0] += a * f[0];
                v[1] += a * f[1];
            }
        }
        if let Some(c) = &self.constraints {
            c.project(&mut self.st.v, &self.mass);
        }
        let [kinetic, work, half_step] = self.update_stage(dt, dt_avg, contact_work_rate);
        if !kinetic.is_finite() {
            let i = self
                .st
                .v
                .iter()
                .position(|v| !(v[0].is_finite() && v[1].is_finite()))
                .unwrap_or(0);
            return Err(Error::Diverged {
                step: self.st.step,
                time: self.st.time,
                what: format!(
                    "velocity of particle {i} at {:?} m is not finite",
                    self.ref_pos[i]
                ),
            });
        }
        let e = &mut self.st.energy;
        e.kinetic = kinetic;
        e.elastic = elastic;
        e.plastic = plastic;
        e.contact_work += work;
        e.contact_work_abs += work.abs();
        e.tool_work += tool_work;
        e.tool_work_abs += tool_work.abs();
        e.internal_half_step = half_step;
        self.st.step += 1;
        match self.scene.time.dt_s {
            Some(fixed) if dt == fixed => {
                self.st.time =
                    self.st.anchor_time + (self.st.step - self.st.anchor_step) as Real * fixed;
            }
            _ => {
                self.st.time += dt;
                self.st.anchor_time = self.st.time;
                self.st.anchor_step = self.st.step;
            }
        }
        self.st.dt_prev = dt;
        for (t, s) in self.tools.iter().zip(self.st.tools.iter_mut()) {
            *s = t.state;
        }
        let rel = e.balance_error_rel();
        let tol = self.scene.checks.energy_balance_tol;
        if rel > tol {
            let e = *e;
            return Err(Error::EnergyBalance {
                step: self.st.step,
                time: self.st.time,
                error_rel: rel,
                bound: tol,
                detail: format!(
                    "kinetic {:.4e} J + elastic {:.4e} J + plastic {:.4e} J - contact work {:.4e} J vs initial {:.4e} J; step {:.3e} s, stable estimate {:.3e} s{}",
                    e.kinetic,
                    e.elastic,
                    e.plastic,
                    e.contact_work,
                    e.initial,
                    dt,
                    self.st.stable_dt,
                    if dt > self.st.stable_dt { " (the step exceeds the estimate: likely an instability)" } else { "" }
                ),
            });
        }
        let gain = e.interface_gain();
        if gain > tol * e.reference() {
            let e = *e;
            return Err(Error::EnergyBalance {
                step: self.st.step,
                time: self.st.time,
                error_rel: gain / e.reference(),
                bound: tol,
                detail: format!(
                    "the contact interface generated {gain:.4e} J: the contact forces did {:.4e} J of work on the workpiece while the tools delivered {:.4e} J",
                    e.contact_work, e.tool_work
                ),
            });
        }
        let t5 = Instant::now();
        self.times.contact += t4 - t3;
        self.times.integration += (t2 - t1) + (t5 - t4);
        Ok(())
    }

    /// Step until `time` reaches `t_end` (s), the last step shortened to land on it.
    /// The loop runs on a worker of the current rayon pool, so the parallel stages of each
    /// step start without a thread hand-off.
    pub fn run_to(
        &mut self,
        t_end: Real,
        mut on_step: impl FnMut(&Simulation) + Send,
    ) -> Result<()> {
        let this = &mut *self;
        let mut run = move || -> Result<()> {
            while this.st.time < t_end - 1e-12 * t_end.abs() {
                this.step(Some(t_end - this.st.time))?;
                on_step(this);
            }
            Ok(())
        };
        if rayon::current_thread_index().is_some() {
            run()
        } else {
            // `scope` runs its body on a worker of the global pool.
            rayon::scope(|_| run())
        }
    }

    /// Stress stage and the scatter of the internal force, fused, over fixed chunks of
    /// points in parallel: `F = I + sum_I d_I (x) grad N_I` (and `F_33 = 1 + u_r / R` in
    /// axisymmetry), the Hencky J2 update, and the scatter of
    /// `(P grad N_I + e_r P_33 N_I / R) w_p` into the chunk's buffer, which
    /// [`Simulation::force_stage`] sums. Returns (elastic, plastic) energy (J).
    fn stress_stage(&mut self) -> Result<(Real, Real)> {
        let t0 = Instant::now();
        let axi = self.scene.model.kinematics == Kinematics::Axisymmetric;
        let Scatter {
            chunk,
            lo,
            offsets,
            buf,
            group,
            lists,
            list_range,
            base,
            table,
            table_start,
            ..
        } = &mut self.scatter;
        let cx = StressContext {
            lists,
            list_range,
            base,
            groups: group,
            table,
            table_start,
            d: &self.st.d,
            material: &self.material,
            weights: &self.weights,
            inv_radius: &self.inv_radius,
            axi,
            spacing: self.spacing,
            initial_yield: self.material.hardening.initial_yield(),
        };
        let avx2 = self.simd && has_avx2();
        let (chunk, lo, offsets) = (*chunk, &*lo, &*offsets);
        let points = self.st.points.len();
        let mut sums = vec![ChunkSums::default(); lo.len()];
        let (states, outs, bufs, slots) = (
            Parts::new(&mut self.st.points),
            Parts::new(&mut self.out),
            Parts::new(buf),
            Parts::new(&mut sums),
        );
        self.team.for_each(lo.len(), &|c| {
            let range = part(c, chunk, points);
            // SAFETY: chunk `c` alone takes these points, its buffer slice and its slot.
            let (work, slot) = unsafe {
                (
                    ChunkWork {
                        first: range.start,
                        states: states.get(range.clone()),
                        outs: outs.get(range),
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
        for s in &sums {
            if let Some((p, m)) = &s.failure {
                return Err(Error::Diverged {
                    step: self.st.step,
                    time: self.st.time,
                    what: format!(
                        "integration point {p} (reference position {:?} m): {m}",
                        self.points.positions[*p]
                    ),
                });
            }
            elastic += s.elastic;
            plastic += s.plastic;
            min_altitude2 = min_altitude2.min(s.min_altitude2);
        }
        let min_altitude = min_altitude2.max(0.0).sqrt();
        self.st.stable_dt = self.critical_dt0 * min_altitude / self.spacing[0].min(self.spacing[1]);
        self.times.stress += t0.elapsed();
        Ok((elastic, plastic))
    }

    /// Internal force gather over fixed blocks of particles in parallel, fused with the
    /// predictor: `f_I` sums the chunk buffers covering `I` in chunk order (per block, the
    /// overlapping slice of each chunk in turn); with
    /// `predict = Some(dt_avg)` (s), also `v* = v_{n-1/2} - dt_avg f_I / m_I` (m/s), keeping
    /// `v_{n-1/2}` for the energy account.
    fn force_stage(&mut self, predict: Option<(Real, Real)>) {
        let t0 = Instant::now();
        let sc = &self.scatter;
        let inv_mass = &self.inv_mass;
        let np = self.f_int.len();
        let blocks = np.div_ceil(BLOCK);
        // The largest speeds serve only the contact stage's skipping.
        let track = !self.tools.is_empty();
        let mut speeds: Vec<Real> = vec![0.0; blocks];
        let (f_int, v, v_prev, speed_slots) = (
            Parts::new(&mut self.f_int),
            Parts::new(&mut self.st.v),
            Parts::new(&mut self.v_prev),
            Parts::new(&mut speeds),
        );
        particle_phase(&self.team, np, blocks, &|b| {
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
                let src = &sc.buf[sc.offsets[c] + a - lo..sc.offsets[c] + e - lo];
                for (f, v) in fs[a - range.start..e - range.start].iter_mut().zip(src) {
                    f[0] += v[0];
                    f[1] += v[1];
                }
            }
            if let Some((dt_avg, _)) = predict {
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
        if let Some((_, dt)) = predict {
            let c = &mut self.contact;
            c.predicted_moves = [
                c.predicted_moves[1],
                dt * speeds.into_iter().fold(0.0, Real::max),
            ];
        }
        self.times.internal_force += t0.elapsed();
    }

    /// Displacement update `d_{n+1} = d_n + dt v_{n+1/2}` (m) over fixed blocks of
    /// particles in parallel, with the energy sums of the step, each summed per block (four
    /// interleaved running sums, added pairwise) and the blocks in order: kinetic `sum m |v|^2 / 2`, contact work
    /// `sum dt_avg f_c . (v_{n+1/2} + v_{n-1/2}) / 2` (the exact discrete identity of the
    /// corrector, when `contact` forces act) and internal half-step work
    /// `sum dt f_int . v_{n+1/2} / 2` (J).
    fn update_stage(&mut self, dt: Real, dt_avg: Real, contact: bool) -> [Real; 3] {
        let np = self.st.v.len();
        let blocks = np.div_ceil(BLOCK);
        let mut sums = vec![[0.0; 4]; blocks];
        let track = !self.tools.is_empty();
        let (v, v_prev, mass, f_int, f_con) = (
            &self.st.v,
            &self.v_prev,
            &self.mass,
            &self.f_int,
            &self.f_con,
        );
        let (d, slots) = (Parts::new(&mut self.st.d), Parts::new(&mut sums));
        particle_phase(&self.team, np, blocks, &|b| {
            let range = part(b, BLOCK, np);
            // SAFETY: block `b` alone takes these particles and its slot.
            let (ds, slot) = unsafe { (d.get(range.clone()), &mut slots.get(b..b + 1)[0]) };
            let n = ds.len();
            let (vs, vps, ms) = (
                &v[range.clone()],
                &v_prev[range.clone()],
                &mass[range.clone()],
            );
            let (fis, fcs) = (&f_int[range.clone()], &f_con[range]);
            let speed = if track { largest_component(vs) } else { 0.0 };
            // Four running sums per quantity (particle i into sum i mod 4), added pairwise at
            // the end: independent chains instead of one long dependent one.
            let (mut ke, mut wk, mut hs) = ([0.0; 4], [0.0; 4], [0.0; 4]);
            for j in (0..n).step_by(4) {
                for k in 0..4.min(n - j) {
                    let i = j + k;
                    let (v, vp, fi) = (vs[i], vps[i], fis[i]);
                    ke[k] += 0.5 * ms[i] * (v[0] * v[0] + v[1] * v[1]);
                    hs[k] += 0.5 * dt * (fi[0] * v[0] + fi[1] * v[1]);
                    if contact {
                        let f = fcs[i];
                        wk[k] += 0.5 * dt_avg * (f[0] * (v[0] + vp[0]) + f[1] * (v[1] + vp[1]));
                    }
                    ds[i][0] += dt * v[0];
                    ds[i][1] += dt * v[1];
                }
            }
            let sum4 = |x: [Real; 4]| (x[0] + x[1]) + (x[2] + x[3]);
            let (kinetic, work, half_step) = (sum4(ke), sum4(wk), sum4(hs));
            *slot = [kinetic, work, half_step, speed];
        });
        let [kinetic, work, half_step, speed] = sums.iter().fold([0.0; 4], |a, s| {
            [a[0] + s[0], a[1] + s[1], a[2] + s[2], a[3].max(s[3])]
        });
        self.contact.update_move = dt * speed;
        [kinetic, work, half_step]
    }

    /// Contact of the predicted boundary positions with the tools (paper eqs. 4-7).
    /// The penalty stiffness `m_s / dt^2` uses the solver's natural step `dt` (equal to the
    /// actual step except when a step is shortened to land on a requested time), so a short
    /// step never turns a residual penetration into a huge impulse. A boundary particle is
    /// interpolated only when it may be in a tool's search box: its clearance to the boxes,
    /// measured when last interpolated, shrinks each step by `S_J du + box_move` (the bound
    /// of [`ContactCache`]) and while it stays positive the particle is skipped. Fills
    /// `f_con`; returns whether any force acts.
    fn contact_stage(&mut self, dt: Real, dt_avg: Real) -> (bool, Real) {
        for t in self.tools.iter_mut() {
            t.state.force = [0.0; 2];
        }
        if self.tools.is_empty() {
            return (false, 0.0);
        }
        let mut tool_work = 0.0;
        self.f_con.iter_mut().for_each(|f| *f = [0.0; 2]);
        let bounds: Vec<Extents> = self
            .tools
            .iter()
            .map(|t| bounds_of(&t.vertices(), t.depth))
            .collect();
        // How far any search box moved since the last step (a first step: unbounded).
        let box_move = if self.contact.boxes.len() == bounds.len() {
            bounds
                .iter()
                .zip(&self.contact.boxes)
                .flat_map(|(a, b)| {
                    [
                        a.x[0] - b.x[0],
                        a.x[1] - b.x[1],
                        a.y[0] - b.y[0],
                        a.y[1] - b.y[1],
                    ]
                })
                .fold(0.0, |m: Real, e| m.max(e.abs()))
        } else {
            Real::INFINITY
        };
        // Predicted positions x_J = X_J + sum_I N_I(X_J) u_I, u_I = d_I + dt v*_I, and
        // velocities v_J = sum_I N_I(X_J) v*_I of the boundary particles that may be in a
        // search box: a particle's clearance to the boxes shrinks each step by at most
        // S_J du + box_move, and while it stays positive the particle is skipped (it could
        // not have touched a tool: the bits are those of evaluating every particle).
        let (np, nb) = (self.ref_pos.len(), self.boundary.len());
        let (boundary, nodal, ref_pos) = (&self.boundary, &self.nodal, &self.ref_pos);
        let (d, v) = (&self.st.d, &self.st.v);
        let ContactCache {
            predicted_moves,
            update_move,
            sum_abs,
            clearance,
            motion,
            skip,
            ..
        } = &mut self.contact;
        let du = *update_move + predicted_moves[0] + predicted_moves[1];
        let (skip, sum_abs) = (*skip, &*sum_abs);
        let margin = 1e-9 * self.spacing[0].min(self.spacing[1]);
        let (motion_parts, clearance_parts) = (Parts::new(motion), Parts::new(clearance));
        particle_phase(&self.team, np, nb.div_ceil(BOUNDARY_BLOCK), &|b| {
            let range = part(b, BOUNDARY_BLOCK, nb);
            // SAFETY: block `b` alone takes these boundary particles.
            let (out, clear) = unsafe {
                (
                    motion_parts.get(range.clone()),
                    clearance_parts.get(range.clone()),
                )
            };
            for (k, (m, c)) in range.zip(out.iter_mut().zip(clear.iter_mut())) {
                *c -= sum_abs[k] * du + box_move;
                if skip && *c > 0.0 {
                    continue;
                }
                let j = boundary[k] as usize;
                let (mut x, mut vj) = (ref_pos[j], [0.0; 2]);
                for e in nodal.row(j) {
                    let i = nodal.index[e] as usize;
                    let n = nodal.n[e];
                    x[0] += n * (d[i][0] + dt * v[i][0]);
                    x[1] += n * (d[i][1] + dt * v[i][1]);
                    vj[0] += n * v[i][0];
                    vj[1] += n * v[i][1];
                }
                *m = [x, vj];
                let gap = bounds.iter().fold(Real::INFINITY, |g, b| {
                    let dx = (b.x[0] - x[0]).max(x[0] - b.x[1]);
                    let dy = (b.y[0] - x[1]).max(x[1] - b.y[1]);
                    g.min(dx.max(dy))
                });
                *c = gap - margin;
            }
        });
        let mut any = false;
        for ((&j, &[x, vj]), &c) in self
            .boundary
            .iter()
            .zip(&self.contact.motion)
            .zip(&self.contact.clearance)
        {
            if self.contact.skip && c > 0.0 {
                continue;
            }
            let j = j as usize;
            for (k, tool) in self.tools.iter_mut().enumerate() {
                let b = &bounds[k];
                if x[0] < b.x[0] || x[0] > b.x[1] || x[1] < b.y[0] || x[1] > b.y[1] {
                    continue;
                }
                let Some(pen) = tool.penetration(x) else {
                    continue;
                };
                let vt = [
                    tool.axis[0] * tool.state.velocity,
                    tool.axis[1] * tool.state.velocity,
                ];
                let f = penalty_force(
                    self.mass[j],
                    pen,
                    [vj[0] - vt[0], vj[1] - vt[1]],
                    tool.friction,
                    dt,
                    dt_avg,
                );
                tool.state.force[0] -= f[0];
                tool.state.force[1] -= f[1];
                tool_work += dt_avg * (f[0] * vt[0] + f[1] * vt[1]);
                for e in self.nodal.row(j) {
                    let i = self.nodal.index[e] as usize;
                    let n = self.nodal.n[e];
                    self.f_con[i][0] += n * f[0];
                    self.f_con[i][1] += n * f[1];
                }
                any = true;
            }
        }
        for t in self.tools.iter_mut() {
            let f = t.state.force;
            t.state.peak_force = t.state.peak_force.max((f[0] * f[0] + f[1] * f[1]).sqrt());
        }
        self.contact.boxes = bounds;
        (any, tool_work)
    }

    /// Critical step of central differences with lumped masses on the undeformed
    /// discretisation, `dt_crit = 2 / omega_max` (s), with `omega_max^2` the largest
    /// eigenvalue of `M^{-1} K`, found by Lanczos iteration on the symmetric
    /// `A = M^{-1/2} K M^{-1/2}` (Golub & Van Loan, Matrix Computations, sec. 10.1): the
    /// largest eigenvalue of the tridiagonal `T_k` converges to it from below in a few tens
    /// of products, where power iteration needs hundreds on large models. `K x` is the
    /// internal force of a displacement small enough (1e-7 of the spacing) to stay linear
    /// elastic. The estimate depends on the support, the integration rule and the mass
    /// lumping, which `h / c` ignores.
    fn measure_critical_step(&mut self) -> Result<Real> {
        let np = self.ref_pos.len();
        let saved_points = self.st.points.clone();
        let amplitude = 1e-7 * self.spacing[0].min(self.spacing[1]);
        let inv_sqrt_m: Vec<Real> = self.mass.iter().map(|m| 1.0 / m.sqrt()).collect();
        // Deterministic pseudo-random start (xorshift), so no mode is missed by symmetry.
        let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as Real / (1u64 << 53) as Real - 0.5
        };
        let mut v: Vec<[Real; 2]> = (0..np).map(|_| [rnd(), rnd()]).collect();
        let norm = |x: &[[Real; 2]]| {
            x.iter()
                .map(|a| a[0] * a[0] + a[1] * a[1])
                .sum::<Real>()
                .sqrt()
        };
        let n0 = norm(&v);
        v.iter_mut().for_each(|a| *a = [a[0] / n0, a[1] / n0]);
        let mut v_prev = vec![[0.0; 2]; np];
        let (mut alpha, mut beta) = (Vec::new(), Vec::new());
        let mut lambda = 0.0;
        for it in 0..LANCZOS_MAX {
            // w = A v: K applied to the displacement M^{-1/2} v, scaled to `amplitude`.
            let xmax = v
                .iter()
                .zip(&inv_sqrt_m)
                .map(|(a, s)| (a[0].abs().max(a[1].abs())) * s)
                .fold(0.0, Real::max);
            let scale = amplitude / xmax;
            self.st.d = v
                .iter()
                .zip(&inv_sqrt_m)
                .map(|(a, s)| [a[0] * s * scale, a[1] * s * scale])
                .collect();
            self.stress_stage()?;
            self.force_stage(None);
            let b_prev = beta.last().copied().unwrap_or(0.0);
            let mut w: Vec<[Real; 2]> = self
                .f_int
                .iter()
                .zip(&inv_sqrt_m)
                .zip(&v_prev)
                .map(|((f, s), vp)| {
                    [
                        f[0] * s / scale - b_prev * vp[0],
                        f[1] * s / scale - b_prev * vp[1],
                    ]
                })
                .collect();
            let a: Real = w
                .iter()
                .zip(&v)
                .map(|(x, y)| x[0] * y[0] + x[1] * y[1])
                .sum();
            w.iter_mut().zip(&v).for_each(|(x, y)| {
                x[0] -= a * y[0];
                x[1] -= a * y[1];
            });
            alpha.push(a);
            let next = tridiagonal_max_eigenvalue(&alpha, &beta);
            let b = norm(&w);
            let converged = it >= 10 && (next - lambda).abs() <= 1e-6 * next;
            lambda = next;
            if converged || b <= 1e-12 * next.abs() {
                break;
            }
            beta.push(b);
            w.iter_mut().for_each(|x| *x = [x[0] / b, x[1] / b]);
            v_prev = std::mem::replace(&mut v, w);
        }
        self.st.d = vec![[0.0; 2]; np];
        self.st.points = saved_points;
        if !(lambda > 0.0 && lambda.is_finite()) {
            return Err(Error::ShapeFunctions(format!(
                "the stiffness has no positive eigenvalue ({lambda:.3e})"
            )));
        }
        Ok(2.0 / lambda.sqrt())
    }

    /// Bytes held by the discretisation and the state: shape tables, scatter buffers,
    /// particle and point arrays (the heap data this simulation owns, counted from the lengths
    /// of its arrays).
    pub fn memory_bytes(&self) -> usize {
        let table = |t: &ShapeTable| {
            t.offsets.len() * 4 + t.index.len() * 4 + (t.n.len() + t.dx.len() + t.dy.len()) * 8
        };
        let r2 = std::mem::size_of::<[Real; 2]>();
        let np = self.ref_pos.len();
        let npts = self.points.positions.len();
        table(&self.nodal)
            + self.scatter.buf.len() * r2
            + self.scatter.table.len() * 8
            + (self.scatter.table_start.len()
                + self.scatter.base.len()
                + self.scatter.lists.len()
                + 2 * self.scatter.list_range.len()
                + self.scatter.group.len() / 4)
                * 4
            + (self.scatter.block_chunks.len()
                + self.scatter.block_offsets.len()
                + self.scatter.lo.len())
                * 4
            + np * (5 * r2 + 2 * 8)
            + npts
                * (r2 + 3 * 8 + std::mem::size_of::<PointState>() + std::mem::size_of::<PointOut>())
            + self.boundary.len() * 4
    }

    /// Critical step measured on the undeformed discretisation (s).
    pub fn critical_dt0(&self) -> Real {
        self.critical_dt0
    }

    /// Physical positions `X_J + sum_I N_I(X_J) d_I` of all particles (m).
    pub fn positions(&self) -> Vec<[Real; 2]> {
        (0..self.ref_pos.len())
            .map(|j| {
                let u = self.nodal.interpolate(j, &self.st.d);
                [self.ref_pos[j][0] + u[0], self.ref_pos[j][1] + u[1]]
            })
            .collect()
    }

    /// Bounds of the deformed workpiece over all particles (m).
    pub fn extents(&self) -> Extents {
        bounds(&self.positions())
    }

    /// Volume enclosed by the physical boundary particles now (m^3).
    pub fn volume(&self) -> Real {
        self.volume_of(&self.positions())
    }

    /// Current volume as the integration rule sees it, `sum_p J_p w_p` (m^3), at the last
    /// stress stage.
    pub fn integrated_volume(&self) -> Real {
        self.out
            .iter()
            .zip(&self.weights)
            .map(|(o, w)| o.jacobian * w)
            .sum()
    }

    /// Volume of the undeformed workpiece (m^3).
    pub fn reference_volume(&self) -> Real {
        self.volume_of(&self.ref_pos)
    }

    /// Volume enclosed by the boundary particles of the particle positions `x` (m^3):
    /// Pappus' theorem `2 pi r_c A` in axisymmetry, `A depth` in plane strain.
    pub fn volume_of(&self, x: &[[Real; 2]]) -> Real {
        let ring: Vec<[Real; 2]> = self.boundary.iter().map(|&j| x[j as usize]).collect();
        let (mut a, mut ax) = (0.0, 0.0);
        for k in 0..ring.len() {
            let (p, q) = (ring[k], ring[(k + 1) % ring.len()]);
            let c = p[0] * q[1] - q[0] * p[1];
            a += 0.5 * c;
            ax += (p[0] + q[0]) * c / 6.0;
        }
        match self.scene.model.kinematics {
            Kinematics::Axisymmetric => 2.0 * PI * ax,
            Kinematics::PlaneStrain => a * self.scene.model.depth_m,
        }
    }

    /// Largest penetration of a boundary particle into a tool now (m); also kept as the
    /// run's maximum.
    pub fn measure_penetration(&mut self) -> Real {
        let x = self.positions();
        let mut worst: Real = 0.0;
        for t in &self.tools {
            for &j in &self.boundary {
                if let Some(p) = t.penetration(x[j as usize]) {
                    worst = worst.max(p.gap);
                }
            }
        }
        self.st.max_penetration = self.st.max_penetration.max(worst);
        worst
    }

    /// Particle fields for output: physical positions, displacements and velocities;
    /// plastic strain and von Mises stress smoothed from the points with weights `|N_I| w_p`.
    pub fn fields(&self) -> Fields {
        let np = self.ref_pos.len();
        let mut f = Fields {
            positions: self.positions(),
            ..Default::default()
        };
        let (mut wsum, mut ep, mut vm) = (vec![0.0; np], vec![0.0; np], vec![0.0; np]);
        for p in 0..self.weights.len() {
            let (eps_p, mises) = (self.st.points[p].eps_p, self.out[p].von_mises);
            for (i, [n, _, _]) in self.scatter.point_row(p) {
                let w = (n * self.weights[p]).abs();
                wsum[i] += w;
                ep[i] += w * eps_p;
                vm[i] += w * mises;
            }
        }
        for j in 0..np {
            f.displacement.push(self.nodal.interpolate(j, &self.st.d));
            f.velocity.push(self.nodal.interpolate(j, &self.st.v));
            let w = if wsum[j] > 0.0 { 1.0 / wsum[j] } else { 0.0 };
            f.plastic_strain.push(ep[j] * w);
            f.von_mises.push(vm[j] * w);
        }
        f
    }

    /// Internal force on each coefficient from the current stresses (N); for tests.
    pub fn internal_forces(&mut self) -> Result<Vec<[Real; 2]>> {
        self.stress_stage()?;
        self.force_stage(None);
        Ok(self.f_int.clone())
    }

    /// Set the displacement coefficients directly (m); for tests and restarts.
    pub fn set_displacement(&mut self, d: Vec<[Real; 2]>) -> Result<()> {
        if d.len() != self.st.d.len() {
            return Err(Error::State(format!(
                "expected {} coefficients, got {}",
                self.st.d.len(),
                d.len()
            )));
        }
        self.st.d = d;
        self.contact.forget();
        Ok(())
    }

    /// Shape functions at integration point `p`: each particle `I` of its group's list
    /// with `[N_I, dN_I/dX, dN_I/dY]` (1, 1/m), including zeros where `I` is outside the
    /// point's own support.
    pub fn point_shapes(&self, p: usize) -> impl Iterator<Item = (usize, [Real; 3])> + '_ {
        self.scatter.point_row(p)
    }
    /// Reference volume weights of the integration points (m^3; 2 pi R included).
    pub fn point_weights(&self) -> &[Real] {
        &self.weights
    }
    /// Reference positions of the integration points (m).
    pub fn point_positions(&self) -> &[[Real; 2]] {
        &self.points.positions
    }
    /// Equivalent plastic strain at each integration point.
    pub fn point_plastic_strain(&self) -> Vec<Real> {
        self.st.points.iter().map(|s| s.eps_p).collect()
    }
    /// The material model.
    pub fn material(&self) -> &HenckyJ2 {
        &self.material
    }
    /// Largest physical velocity of a constrained component (m/s): zero up to round-off.
    pub fn constraint_residual(&self) -> Real {
        self.constraints
            .as_ref()
            .map_or(0.0, |c| c.residual(&self.st.v))
    }
}

/// The integration points of `rule` on the lattice and their shape functions.
fn point_shapes(lattice: &Lattice, rule: IntegrationRule) -> Result<(PointSet, ShapeTable)> {
    Ok(match rule {
        IntegrationRule::Scni => {
            let (points, edges, nw) = nodal_domains(lattice);
            let pt = smoothed_shape_table(lattice, &points, &edges, &nw)?;
            (points, pt)
        }
        rule => {
            let points = grid_points(rule, lattice);
            let pt = lattice.shape_table(&points.sites, &|p| {
                format!("integration point {p} (cell {})", points.cells[p])
            })?;
            (points, pt)
        }
    })
}

/// SCNI shape table (Chen, Wu, Yoon, You 2001): per nodal domain `L`, `N_I` at its centroid
/// and the smoothed gradient `B_I = (1 / A_L) sum_edges N_I(x_g) n w_g` from the boundary
/// quadrature points of the domain.
fn smoothed_shape_table(
    lattice: &Lattice,
    points: &PointSet,
    edges: &[Site],
    nw: &[[Real; 2]],
) -> Result<ShapeTable> {
    let at_centre =
        lattice.shape_table(&points.sites, &|p| format!("nodal integration point {p}"))?;
    let on_edges = lattice.shape_table(edges, &|q| {
        format!(
            "boundary point {q} of nodal domain {}",
            q / SCNI_EDGE_POINTS
        )
    })?;
    let mut t = ShapeTable {
        offsets: vec![0],
        ..Default::default()
    };
    let mut row: std::collections::BTreeMap<u32, [Real; 3]> = Default::default();
    for (p, area) in points.areas.iter().enumerate() {
        row.clear();
        for e in at_centre.row(p) {
            row.entry(at_centre.index[e]).or_default()[0] = at_centre.n[e];
        }
        let first = p * SCNI_EDGE_POINTS;
        for (q, w) in nw.iter().enumerate().skip(first).take(SCNI_EDGE_POINTS) {
            for e in on_edges.row(q) {
                let v = row.entry(on_edges.index[e]).or_default();
                v[1] += on_edges.n[e] * w[0] / area;
                v[2] += on_edges.n[e] * w[1] / area;
            }
        }
        for (&i, v) in &row {
            t.index.push(i);
            t.n.push(v[0]);
            t.dx.push(v[1]);
            t.dy.push(v[2]);
        }
        t.offsets.push(t.index.len() as u32);
    }
    Ok(t)
}

/// Length of the next step: the full step `dt_full`, or, when `max_dt` (the time left to a
/// requested instant) is not a whole number of full steps, that time split into equal steps,
/// so that no step is shorter than half a full one. An exact multiple keeps `dt_full` itself.
/// Most Lanczos products for the critical step.
const LANCZOS_MAX: usize = 300;

/// Largest eigenvalue of the symmetric tridiagonal matrix with diagonal `a` and
/// off-diagonal `b` (`b.len() + 1 == a.len()`), by Sturm-sequence bisection between the
/// Gershgorin bounds: the count of eigenvalues below `x` is the number of negative pivots
/// of `T - x I` (Golub & Van Loan, sec. 8.4).
fn tridiagonal_max_eigenvalue(a: &[Real], b: &[Real]) -> Real {
    let radius =
        |i: usize| (if i > 0 { b[i - 1].abs() } else { 0.0 }) + b.get(i).map_or(0.0, |x| x.abs());
    let (mut lo, mut hi) = (Real::INFINITY, Real::NEG_INFINITY);
    for (i, &ai) in a.iter().enumerate() {
        lo = lo.min(ai - radius(i));
        hi = hi.max(ai + radius(i));
    }
    let below = |x: Real| {
        let mut count = 0;
        let mut q = 1.0;
        for (i, &ai) in a.iter().enumerate() {
            let off = if i > 0 { b[i - 1] * b[i - 1] } else { 0.0 };
            q = ai - x - if i > 0 { off / q } else { 0.0 };
            if q == 0.0 {
                q = -Real::EPSILON * (x.abs() + 1.0);
            }
            if q < 0.0 {
                count += 1;
            }
        }
        count
    };
    let n = a.len();
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if below(mid) < n {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

fn landing_step(dt_full: Real, max_dt: Option<Real>) -> Real {
    let Some(left) = max_dt else { return dt_full };
    let tol = 1e-9 * dt_full;
    // Steps still needed, not counting a rounding residue as one more.
    let n = ((left - tol) / dt_full).ceil().max(1.0);
    if (left - n * dt_full).abs() <= tol {
        dt_full
    } else {
        left / n
    }
}

/// Bounds of a point set (m).
pub fn bounds(p: &[[Real; 2]]) -> Extents {
    bounds_of(p, 0.0)
}

/// Bounds of a point set, grown by `pad` (m).
fn bounds_of(p: &[[Real; 2]], pad: Real) -> Extents {
    let mut e = Extents {
        x: [Real::INFINITY, Real::NEG_INFINITY],
        y: [Real::INFINITY, Real::NEG_INFINITY],
    };
    for q in p {
        e.x = [e.x[0].min(q[0]), e.x[1].max(q[0])];
        e.y = [e.y[0].min(q[1]), e.y[1].max(q[1])];
    }
    e.x = [e.x[0] - pad, e.x[1] + pad];
    e.y = [e.y[0] - pad, e.y[1] + pad];
    e
}

#[cfg(test)]
mod tests {
    use super::{landing_step, point_shapes, tridiagonal_max_eigenvalue, Scatter, Simulation};
    use crate::rk_shape::{Lattice, ShapeTable};

    #[test]
    fn tridiagonal_largest_eigenvalue() {
        // Second-difference matrix: eigenvalues 2 - 2 cos(k pi / (n + 1)).
        for n in [1, 2, 5, 40] {
            let a = vec![2.0; n];
            let b = vec![-1.0; n - 1];
            let exact = 2.0 - 2.0 * (n as f64 * std::f64::consts::PI / (n as f64 + 1.0)).cos();
            let got = tridiagonal_max_eigenvalue(&a, &b);
            assert!(
                (got - exact).abs() <= 1e-12 * exact,
                "n {n}: {got} vs {exact}"
            );
        }
        assert_eq!(tridiagonal_max_eigenvalue(&[3.0, -1.0], &[0.0]), 3.0);
    }
    use crate::{IntegrationRule, Scene};

    const RULES: [IntegrationRule; 3] = [
        IntegrationRule::Q4,
        IntegrationRule::Q2,
        IntegrationRule::Scni,
    ];

    /// The shipped Taylor bar with `rule` on a grid of `particles`.
    fn taylor(rule: IntegrationRule, particles: [usize; 2]) -> Scene {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/taylor_bar.toml");
        let mut scene = Scene::from_file(std::path::Path::new(path))
            .unwrap()
            .with_integration(rule);
        scene.workpiece.particles = particles;
        scene
    }

    /// The point shape table of a simulation, built again as its setup builds it.
    fn point_table(sim: &Simulation) -> ShapeTable {
        let (nx, ny) = sim.grid();
        let (h, s) = (sim.spacing(), sim.scene.discretization.support);
        let support = [s[0] * h[0], s[1] * h[1]];
        let lattice = Lattice::new(sim.scene.workpiece.origin_m, h, [nx, ny], support);
        point_shapes(&lattice, sim.scene.discretization.integration)
            .unwrap()
            .1
    }

    /// The stress stage processes points in groups: the 4 points of a q4 cell over their
    /// shared list, two q2 cells (2 + 2 points) and four SCNI points over the union of
    /// their lists, zero-padded. The bits must equal a point-by-point loop.
    #[test]
    fn grouped_points_give_the_bits_of_single_points() {
        for rule in RULES {
            let scene = taylor(rule, [11, 26]);
            let mut grouped = Simulation::new(&scene).unwrap();
            let sc = &grouped.scatter;
            let in_quads = sc.group.iter().filter(|&&g| g == 4).count() * 4;
            assert!(
                in_quads * 10 >= sc.group.len() * 9,
                "{rule:?}: {in_quads} of {} points in groups of 4",
                sc.group.len()
            );
            // Merged groups run over a union longer than one point's own list.
            let longest_union = (0..sc.group.len())
                .filter(|&p| sc.group[p] == 4)
                .map(|p| (sc.list_range[p][1] - sc.list_range[p][0]) as usize)
                .max();
            let pt = point_table(&grouped);
            let longest_own = (0..pt.rows()).map(|p| pt.row(p).len()).max();
            assert_eq!(
                longest_union > longest_own,
                rule != IntegrationRule::Q4,
                "{rule:?}: unions {longest_union:?}, own lists {longest_own:?}"
            );
            let mut single = grouped.clone();
            single.scatter = Scatter::new(&pt, single.ref_pos.len(), grouped.scatter.chunk, 1);
            for _ in 0..200 {
                grouped.step(None).unwrap();
                single.step(None).unwrap();
            }
            assert!(
                grouped.max_plastic_strain() > 0.05,
                "{rule:?}: plastic flow"
            );
            assert_eq!(grouped.st.d, single.st.d, "{rule:?}");
            assert_eq!(grouped.st.points, single.st.points, "{rule:?}");
            assert_eq!(grouped.st.energy, single.st.energy, "{rule:?}");
        }
    }

    /// On a uniform grid the interior groups' shape-function blocks are bitwise equal (they
    /// are formed from lattice offsets) and stored once: on 81 x 201 the stored table is
    /// 0.13 % (q4), 0.15 % (q2) and 0.49 % (SCNI) of one block per group, the distinct
    /// neighbourhoods near the edges.
    #[test]
    fn interior_groups_share_their_stored_tables() {
        for rule in RULES {
            let scene = taylor(rule, [81, 201]);
            let sim = Simulation::new(&scene).unwrap();
            let sc = &sim.scatter;
            let unshared: usize = (0..sc.group.len())
                .filter(|&p| sc.group[p] > 0)
                .map(|p| {
                    let [a, b] = sc.list_range[p];
                    3 * sc.group[p] as usize * (b - a) as usize
                })
                .sum();
            let share = sc.table.len() as f64 / unshared as f64;
            assert!(share < 0.01, "{rule:?}: stored {share:.4} of the blocks");
        }
    }

    /// The point rows read back from the shared blocks are the shape table's rows, bit for
    /// bit, with zeros only where a particle belongs to another point of the group.
    #[test]
    fn point_rows_from_the_shared_blocks_are_the_table_rows() {
        for rule in RULES {
            let scene = taylor(rule, [11, 26]);
            let sim = Simulation::new(&scene).unwrap();
            let pt = point_table(&sim);
            for p in 0..pt.rows() {
                let own: Vec<(usize, [u64; 3])> = pt
                    .row(p)
                    .map(|e| {
                        let v = [pt.n[e], pt.dx[e], pt.dy[e]];
                        (pt.index[e] as usize, v.map(f64::to_bits))
                    })
                    .collect();
                let mut read = Vec::new();
                for (i, v) in sim.point_shapes(p) {
                    if own.iter().any(|&(j, _)| j == i) {
                        read.push((i, v.map(f64::to_bits)));
                    } else {
                        assert_eq!(v, [0.0; 3], "{rule:?}: point {p}, particle {i}");
                    }
                }
                assert_eq!(read, own, "{rule:?}: point {p}");
            }
        }
    }

    /// The AVX2 build of the stress stage gives the bits of the generic build (no fused
    /// multiply-adds, lanes independent), so results do not depend on the CPU's features.
    #[test]
    fn simd_and_generic_stress_stages_give_the_same_bits() {
        #[cfg(target_arch = "x86_64")]
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: both runs take the generic path");
        }
        for rule in RULES {
            let scene = taylor(rule, [11, 26]);
            let mut simd = Simulation::new(&scene).unwrap();
            let mut generic = simd.clone();
            generic.simd = false;
            for _ in 0..300 {
                simd.step(None).unwrap();
                generic.step(None).unwrap();
            }
            assert!(simd.max_plastic_strain() > 0.05, "{rule:?}: plastic flow");
            assert_eq!(simd.st.d, generic.st.d, "{rule:?}");
            assert_eq!(simd.st.points, generic.st.points, "{rule:?}");
            assert_eq!(simd.st.energy, generic.st.energy, "{rule:?}");
        }
    }

    /// Skipping the boundary particles whose clearance to every tool's search box is
    /// positive gives the bits of evaluating all of them, on the shipped scenes, with tool
    /// velocities that jump and reverse, and across a restore; and it does skip where the
    /// tools' search boxes leave room.
    #[test]
    fn contact_skipping_gives_the_bits_of_checking_every_particle() {
        // The least share of evaluations skipped: most of the bar is far from the wall;
        // the block's top and bottom rows are always inside the dies' boxes; the wheel's
        // die is a container whose box holds the whole workpiece.
        for (name, particles, steps, least_skipped) in [
            ("taylor_bar", [11, 26], 600, 0.5),
            ("block_forging", [21, 21], 3000, 0.2),
            ("wheel_forging", [20, 20], 3000, 0.0),
        ] {
            let path = format!("{}/../scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
            let mut scene = Scene::from_file(std::path::Path::new(&path)).unwrap();
            scene.workpiece.particles = particles;
            let mut skipping = Simulation::new(&scene).unwrap();
            let mut all = skipping.clone();
            all.contact.skip = false;
            let (mut skipped, mut evaluated) = (0, 0);
            for step in 0..steps {
                if step == steps / 3 || step == 2 * steps / 3 {
                    // A jump to 50 m/s, then a reversal: the tools leave.
                    let v = if step == steps / 3 { 50.0 } else { -20.0 };
                    for sim in [&mut skipping, &mut all] {
                        for t in 0..sim.tools().len() {
                            if sim.tools()[t].is_movable() {
                                sim.set_tool_velocity(t, v).unwrap();
                            }
                        }
                    }
                }
                if step == steps / 2 {
                    let saved = skipping.state().clone();
                    skipping.restore(saved).unwrap();
                }
                skipping.step(None).unwrap();
                all.step(None).unwrap();
                let positive = skipping
                    .contact
                    .clearance
                    .iter()
                    .filter(|&&c| c > 0.0)
                    .count();
                skipped += positive;
                evaluated += skipping.boundary.len() - positive;
            }
            assert_eq!(skipping.state(), all.state(), "{name}");
            assert!(
                skipping.tools().iter().any(|t| t.state.peak_force > 0.0),
                "{name}: contact"
            );
            assert!(
                skipped as f64 >= least_skipped * (skipped + evaluated) as f64,
                "{name}: skipped {skipped}, evaluated {evaluated}"
            );
        }
    }

    #[test]
    fn landing_steps_are_equal_and_never_overshoot() {
        let dt = 2.0;
        assert_eq!(landing_step(dt, None), dt);
        assert_eq!(landing_step(dt, Some(6.0)), dt);
        assert_eq!(landing_step(dt, Some(6.0 + 1e-12)), dt);
        assert_eq!(landing_step(dt, Some(5.0)), 5.0 / 3.0);
        assert_eq!(landing_step(dt, Some(2.5)), 1.25);
        assert_eq!(landing_step(dt, Some(0.5)), 0.5);
        for left in [0.1, 1.9, 2.0000001, 3.3, 7.77] {
            let h = landing_step(dt, Some(left));
            assert!(
                h <= left * (1.0 + 1e-12) && h <= dt && (h >= 0.5 * dt || left < dt),
                "{left}: {h}"
            );
        }
    }
}
