//! Where the stress stage reads and writes: the integration points cut into fixed chunks,
//! grouped into point groups over one particle list, their shape functions stored as
//! interleaved blocks (bitwise-equal blocks once), and the chunk buffers the internal force
//! is scattered into and gathered from in a fixed order.
//!
//! One source for 2 and 3 dimensions (`Scatter<D>`, the solver's 2D at the default `D = 2`).
//! The internal force `f_I = sum_p (P grad N_I + e_r P_33 N_I / R) w_p` (N; the hoop term in
//! 2D axisymmetry only) is summed in two passes so that its bits do not depend on the number
//! of threads: each chunk of points adds its terms into its own slice of the chunk buffers
//! ([`Scatter::buffers`], [`super::stress`]), then each block of [`BLOCK`] particles adds
//! the overlapping slices in chunk order ([`super::update`]).

use crate::math::Real;
use crate::rk_shape::ShapeTable;
use crate::team::part;
use std::collections::HashMap;
use std::hash::{DefaultHasher, Hasher};

/// Particles handled by one task of the particle phases (force gather and predictor,
/// energy sums and update); fixed so that results do not depend on the number of threads.
pub const BLOCK: usize = 128;

/// Deterministic parallel scatter of point forces. The points are cut into fixed chunks of
/// `chunk` points (cells in row order, so a chunk touches a contiguous band of particles);
/// chunk `c` adds its contributions to particles `lo[c]..lo[c] + len` into its own slice
/// `offsets[c]..offsets[c + 1]` of the chunk buffers ([`Scatter::buffers`], the workspace's),
/// and each particle then sums the slices that cover
/// it in chunk order (a block of [`BLOCK`] particles adds the overlapping part of each
/// chunk in `block_chunks`). The bits do not depend on the number of threads. `D` is the
/// dimension: the buffers hold `D` force components per particle, the blocks `D + 1` entries
/// per point and neighbour.
#[derive(Debug, Clone)]
pub struct Scatter<const D: usize = 2> {
    pub(super) chunk: usize,
    pub(super) lo: Vec<u32>,
    pub(super) offsets: Vec<usize>,
    /// The chunks whose particles overlap each block of particles, ascending:
    /// `block_chunks[block_offsets[b]..block_offsets[b + 1]]`.
    pub(super) block_offsets: Vec<u32>,
    pub(super) block_chunks: Vec<u32>,
    /// For each point: the number of consecutive points, starting at it, processed as
    /// one group over one particle list (at most [`MAX_GROUP`], never across a chunk
    /// boundary), or 0 for a point inside a group. The Gauss points of a cell share their
    /// list (at most [`MAX_GROUP`] in 2D, [`MAX_GROUP_3D`] in 3D); two neighbouring q2
    /// cells (2D), or four neighbouring SCNI points, are grouped over the union of their
    /// lists when it is shorter than the lists together ([`GroupPlan`]).
    pub(super) group: Vec<u8>,
    /// Whether the group starting at a point is a strip: two neighbouring q2 cells whose
    /// particle lists are the same offsets from first particles one apart, so points 0, 1
    /// read particle `base + i` and points 2, 3 `base + 1 + i` for each offset `i` of the
    /// list; its block holds each point's own entries, and the gather and scatter run over
    /// 16 offsets for 4 points (a q4 cell's count) instead of a union of 20. 2D only (never
    /// set in 3D).
    pub(super) strip: Vec<bool>,
    /// The groups' particle lists (ascending) as offsets from the group's first particle
    /// `base[p]`: `lists[list_range[p].0..list_range[p].1]` for the first point `p` of a
    /// group. Groups with the same offsets share one stored list.
    pub(super) lists: Vec<u32>,
    pub(super) list_range: Vec<[u32; 2]>,
    pub(super) base: Vec<u32>,
    /// Shape function values and gradients of each group, neighbour-major and interleaved
    /// so that a neighbour's values for the group's `g` points are contiguous:
    /// `[N_1..N_g, N_1,x..N_g,x, N_1,y..N_g,y]` per neighbour (one SIMD load each; in 3D
    /// `N_1,z..N_g,z` follow, `4 g` entries); zero
    /// where a particle of the union is not in a point's own list, which adds exact zeros
    /// and leaves each point's sums as its own list gives them.
    pub(super) table: Vec<Real>,
    /// Where each group's entries start in `table` (for the first point of a group).
    /// Groups whose entries are bitwise equal share one stored block. On the lattice that
    /// is every group away from the edges: the shape functions are formed from offsets to
    /// the particles in whole spacings ([`crate::rk_shape::Lattice::shape_table`]), so a large model reads
    /// a few distinct blocks from cache instead of streaming one per group from memory.
    pub(super) table_start: Vec<u32>,
}

impl<const D: usize> Default for Scatter<D> {
    fn default() -> Self {
        Scatter {
            chunk: 0,
            lo: Vec::new(),
            offsets: Vec::new(),
            block_offsets: Vec::new(),
            block_chunks: Vec::new(),
            group: Vec::new(),
            strip: Vec::new(),
            lists: Vec::new(),
            list_range: Vec::new(),
            base: Vec::new(),
            table: Vec::new(),
            table_start: Vec::new(),
        }
    }
}

/// Largest group of points processed together in the 2D stress stage (the 4 points of a
/// q4 cell).
pub const MAX_GROUP: usize = 4;

/// Largest group of points processed together in the 3D stress stage (the 8 points of a
/// q4 cell).
pub const MAX_GROUP_3D: usize = 8;

/// The group of points starting at a point and its particle list.
struct GroupPlan {
    size: usize,
    list: Vec<u32>,
    /// A strip ([`Scatter::strip`]): `list` is the first cell's.
    strip: bool,
}

impl GroupPlan {
    /// In 3D, the largest group of 8, 4 or 2 consecutive points from `p` (within `..end`,
    /// at most `max_group`) over the union of their particle lists, when one vector
    /// operation per particle of the union and per 4 lanes costs less than each point
    /// over its own list: `|union| ceil(size / 4) < sum |list|`. The points of a cell
    /// of a cylinder's O-grid, where each particle has its own support, each have a list
    /// of their own (about 75 particles at a support of 2) and a union of about a third
    /// more, so the cell's points are gathered together instead of one by one.
    fn union_3d<const D: usize>(
        pt: &ShapeTable<D>,
        p: usize,
        end: usize,
        max_group: usize,
    ) -> Option<GroupPlan> {
        let list = |q: usize| &pt.index[pt.row(q)];
        [8, 4, 2]
            .into_iter()
            .filter(|&size| size <= max_group && p + size <= end)
            .find_map(|size| {
                let separate: usize = (p..p + size).map(|q| list(q).len()).sum();
                let mut union: Vec<u32> = (p..p + size).flat_map(list).copied().collect();
                union.sort_unstable();
                union.dedup();
                (union.len() * size.div_ceil(4) < separate).then_some(GroupPlan {
                    size,
                    list: union,
                    strip: false,
                })
            })
    }

    /// The group starting at point `p`, within points `..end`: two q2 cells forming a
    /// strip ([`Scatter::strip`]); else the consecutive points
    /// sharing `p`'s list (up to `max_group`), or, where those are a single point or a
    /// pair, the group of 4 (or else 2) formed with the next singles or pair when the union
    /// of their lists is shorter than the lists together. A group of 2 or 4 runs the AVX2
    /// gather and scatter with one vector operation per particle of its list, so two q2
    /// cells over their union of 20 particles cost 20 operations instead of 2 x 16. Strips
    /// are 2D only.
    fn at<const D: usize>(pt: &ShapeTable<D>, p: usize, end: usize, max_group: usize) -> GroupPlan {
        let list = |q: usize| &pt.index[pt.row(q)];
        let run = |q: usize| {
            let mut n = 1;
            while n < max_group && q + n < end && list(q + n) == list(q) {
                n += 1;
            }
            n
        };
        if D == 3 {
            if let Some(plan) = GroupPlan::union_3d(pt, p, end, max_group) {
                return plan;
            }
        }
        let same = run(p);
        if D == 2 && same == 2 && max_group >= 4 && p + 4 <= end && run(p + 2) == 2 {
            let (a, b) = (list(p), list(p + 2));
            if a.len() == b.len() && a.iter().zip(b).all(|(&i, &j)| j == i + 1) {
                return GroupPlan {
                    size: 4,
                    list: a.to_vec(),
                    strip: true,
                };
            }
        }
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
                return GroupPlan {
                    size,
                    list: union,
                    strip: false,
                };
            }
        }
        GroupPlan {
            size: same,
            list: list(p).to_vec(),
            strip: false,
        }
    }
}

/// A hash of a block's length and bits, the key under which [`Scatter::new`] finds the
/// bitwise-equal blocks already stored.
fn bits_hash(block: &[Real]) -> u64 {
    let mut h = DefaultHasher::new();
    h.write_usize(block.len());
    for x in block {
        h.write_u64(x.to_bits());
    }
    h.finish()
}

impl<const D: usize> Scatter<D> {
    /// Chunks of `chunk` points over `particles` particles, groups of at most `max_group`
    /// points (at most [`MAX_GROUP_3D`]).
    pub(super) fn new(
        pt: &ShapeTable<D>,
        particles: usize,
        chunk: usize,
        max_group: usize,
    ) -> Scatter<D> {
        assert!(
            max_group <= MAX_GROUP_3D,
            "groups of at most {MAX_GROUP_3D} points"
        );
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
        let mut strip = vec![false; pt.rows()];
        let (mut lists, mut list_range) = (Vec::new(), vec![[0u32; 2]; pt.rows()]);
        let mut base = vec![0u32; pt.rows()];
        let mut table: Vec<Real> = Vec::new();
        let mut table_start = vec![0u32; pt.rows()];
        let mut stored_lists: HashMap<Vec<u32>, u32> = HashMap::new();
        // Stored blocks by a hash of their bits; each hit is compared with the stored
        // entries, so the map holds starts, not a second copy of the table.
        let mut stored_blocks: HashMap<u64, Vec<u32>> = HashMap::new();
        let mut block = Vec::new();
        let mut p = 0;
        while p < pt.rows() {
            let end = ((p / chunk + 1) * chunk).min(pt.rows());
            let plan = GroupPlan::at(pt, p, end, max_group);
            group[p] = plan.size as u8;
            strip[p] = plan.strip;
            base[p] = plan.list[0];
            let offsets: Vec<u32> = plan.list.iter().map(|&i| i - base[p]).collect();
            let start = *stored_lists.entry(offsets.clone()).or_insert_with(|| {
                lists.extend(&offsets);
                (lists.len() - offsets.len()) as u32
            });
            list_range[p] = [start, start + offsets.len() as u32];
            // Each point's entries in list order, matched against the union (in a strip,
            // each point's own k-th entry for the k-th offset).
            block.clear();
            let mut next: Vec<usize> = (p..p + plan.size).map(|q| pt.row(q).start).collect();
            for &i in &plan.list {
                let mut hit = [None; MAX_GROUP_3D];
                for (q, e) in next.iter_mut().enumerate() {
                    let shift = u32::from(plan.strip && q >= 2);
                    if *e < pt.row(p + q).end && pt.index[*e] == i + shift {
                        hit[q] = Some(*e);
                        *e += 1;
                    }
                }
                for values in std::iter::once(&pt.n).chain(&pt.grad) {
                    block.extend(
                        hit[..plan.size]
                            .iter()
                            .map(|e| e.map_or(0.0, |e| values[e])),
                    );
                }
            }
            let starts = stored_blocks.entry(bits_hash(&block)).or_default();
            let same = |&s: &u32| {
                let stored = table.get(s as usize..s as usize + block.len());
                stored.is_some_and(|t| {
                    t.iter()
                        .zip(&block)
                        .all(|(a, b)| a.to_bits() == b.to_bits())
                })
            };
            table_start[p] = match starts.iter().copied().find(same) {
                Some(s) => s,
                None => {
                    let start = table.len() as u32;
                    starts.push(start);
                    table.extend(&block);
                    start
                }
            };
            p += plan.size;
        }
        Scatter {
            group,
            strip,
            lists,
            list_range,
            base,
            table,
            table_start,
            chunk,
            lo,
            offsets,
            block_offsets,
            block_chunks,
        }
    }

    /// Rebuilds the scatter on new shape functions `pt` (a re-reference), with the same
    /// chunk size, and its chunk buffers `buf`. The old buffers, groups and blocks are
    /// freed before the new are built, and the point table once the scatter holds its
    /// values: a re-reference then holds about one scatter and one table at its peak, not
    /// two of each.
    pub(super) fn rebuild(
        &mut self,
        pt: ShapeTable<D>,
        particles: usize,
        max_group: usize,
        buf: &mut Vec<[Real; D]>,
    ) {
        let chunk = self.chunk;
        *buf = Vec::new();
        *self = Scatter::default();
        *self = Scatter::new(&pt, particles, chunk, max_group);
        drop(pt);
        *buf = self.buffers();
    }

    /// Zeroed chunk buffers for this scatter (N): chunk `c`'s slice is
    /// `offsets[c]..offsets[c + 1]`.
    pub(super) fn buffers(&self) -> Vec<[Real; D]> {
        vec![[0.0; D]; *self.offsets.last().unwrap_or(&0)]
    }

    /// Bytes held by the groups' lists and the shared blocks.
    pub(super) fn memory_bytes(&self) -> usize {
        self.table.len() * 8
            + (self.table_start.len()
                + self.base.len()
                + self.lists.len()
                + 2 * self.list_range.len()
                + self.group.len() / 2)
                * 4
            + (self.block_chunks.len() + self.block_offsets.len() + self.lo.len()) * 4
    }
}

/// One group of points over one particle list ([`Scatter::group`]): its points
/// `first..first + size`, each list entry's particle and values for each point.
pub(super) struct Group<'a> {
    /// The group's first point.
    pub first: usize,
    /// Its number of points.
    pub size: usize,
    base: usize,
    strip: bool,
    list: &'a [u32],
    block: &'a [Real],
}

impl Group<'_> {
    /// Entries in the group's particle list.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// The particle of list entry `k` for the group's point `q` (a strip's points 2 and 3
    /// read the particle one above).
    pub fn particle(&self, k: usize, q: usize) -> usize {
        self.base + self.list[k] as usize + self.shift(q)
    }

    /// Entry `k`'s values for the group's point `q`: `N` and `dN/dX_c` (1, 1/m), zero where
    /// the particle is only in another point's list.
    pub fn entry<const D: usize>(&self, k: usize, q: usize) -> (Real, [Real; D]) {
        let g = self.size;
        let v = &self.block[(D + 1) * g * k..(D + 1) * g * (k + 1)];
        (v[q], std::array::from_fn(|c| v[(c + 1) * g + q]))
    }

    /// Entry `k`'s `N` (-) for each of the group's points, in a `D`-dimensional table, and
    /// its particle for the group's first point ([`Group::shift`] gives the others').
    pub fn values<const D: usize>(&self, k: usize) -> (&[Real], usize) {
        let at = (D + 1) * self.size * k;
        (
            &self.block[at..at + self.size],
            self.base + self.list[k] as usize,
        )
    }

    /// How far the group's point `q` reads past the first point's particle at each entry:
    /// 1 for a strip's points 2 and 3, else 0.
    pub fn shift(&self, q: usize) -> usize {
        usize::from(self.strip && q >= 2)
    }
}

impl<const D: usize> Scatter<D> {
    /// The group starting at point `first` (`group[first] > 0`).
    fn group_at(&self, first: usize) -> Group<'_> {
        let [a, b] = self.list_range[first];
        Group {
            first,
            size: self.group[first] as usize,
            base: self.base[first] as usize,
            strip: self.strip[first],
            list: &self.lists[a as usize..b as usize],
            block: &self.table[self.table_start[first] as usize..],
        }
    }

    /// Every group of points, in point order.
    pub(super) fn groups(&self) -> impl Iterator<Item = Group<'_>> + '_ {
        (0..self.group.len())
            .filter(|&p| self.group[p] > 0)
            .map(|p| self.group_at(p))
    }

    /// Point `p`'s entries in its group's block: each particle of the group's list with
    /// `N` and its gradient `dN/dX_k` (1, 1/m), zero where the particle is only in another
    /// point's list.
    pub(super) fn point_entries(
        &self,
        p: usize,
    ) -> impl Iterator<Item = (usize, Real, [Real; D])> + '_ {
        let first = (0..=p).rev().find(|&q| self.group[q] > 0).unwrap_or(0);
        let (group, q) = (self.group_at(first), p - first);
        (0..group.len()).map(move |k| {
            let (n, grad) = group.entry::<D>(k, q);
            (group.particle(k, q), n, grad)
        })
    }

    /// Point `p`'s shape function values: each particle of its group's list with `N_I`
    /// (-) at the point, zero where the particle is only in another point's list.
    pub(super) fn point_values(&self, p: usize) -> impl Iterator<Item = (usize, Real)> + '_ {
        self.point_entries(p).map(|(i, n, _)| (i, n))
    }
}

impl Scatter {
    /// Point `p`'s entries in its group's block: each particle of the group's list with
    /// `[N, dN/dX, dN/dY]`, zero where the particle is only in another point's list.
    pub(super) fn point_row(&self, p: usize) -> impl Iterator<Item = (usize, [Real; 3])> + '_ {
        self.point_entries(p)
            .map(|(i, n, [nx, ny])| (i, [n, nx, ny]))
    }
}
