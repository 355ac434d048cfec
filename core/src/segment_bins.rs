//! Uniform bins over line segments, so that a point's contact search reads only the
//! segments near it: a tool's polyline ([`crate::tools::Tool`]) or the workpiece's boundary
//! ring ([`crate::contact::self_contact`]).

use crate::math::Real;

/// Uniform bins over segments: a tool's polyline in the tool's own (initial) coordinates,
/// built once as a tool only translates, or the workpiece's boundary ring, built again at
/// each self-contact search ([`crate::contact::self_contact`]). Each segment is listed in every bin
/// that its bounding box, grown by the search depth, overlaps.
#[derive(Debug, Clone, Default)]
pub struct SegmentBins {
    origin: [Real; 2],
    size: Real,
    dims: [usize; 2],
    offsets: Vec<u32>,
    items: Vec<u32>,
    /// Where the next item of each bin goes while filling.
    cursor: Vec<u32>,
}

/// The bounds `[lo, hi]` (m) of `points` grown by `pad` (m) on every side, as the bins of
/// segments through them need.
pub fn padded_bounds(points: &[[Real; 2]], pad: Real) -> [[Real; 2]; 2] {
    let mut lo = [Real::INFINITY; 2];
    let mut hi = [Real::NEG_INFINITY; 2];
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k] - pad);
            hi[k] = hi[k].max(p[k] + pad);
        }
    }
    [lo, hi]
}

impl SegmentBins {
    /// Bins of size `depth` (m) over the segments of `verts`.
    pub fn new(verts: &[[Real; 2]], depth: Real) -> SegmentBins {
        let [lo, hi] = padded_bounds(verts, depth);
        // At most about 4096 bins per direction.
        let size = depth.max((hi[0] - lo[0]).max(hi[1] - lo[1]) / 4096.0);
        let mut bins = SegmentBins::default();
        bins.fill(
            verts.windows(2).map(|s| [s[0], s[1]]),
            [lo, hi],
            depth,
            size,
        );
        bins
    }

    /// Bins of `size` (m) over `bounds` (`[lo, hi]`, m) listing each of `segments` in every
    /// bin its bounding box grown by `depth` (m) overlaps, in segment order, reusing the
    /// buffers (a counting sort: no list per bin).
    pub fn fill(
        &mut self,
        segments: impl Iterator<Item = [[Real; 2]; 2]> + Clone,
        bounds: [[Real; 2]; 2],
        depth: Real,
        size: Real,
    ) {
        let [lo, hi] = bounds;
        self.origin = lo;
        self.size = size;
        self.dims = [0, 1].map(|k| ((hi[k] - lo[k]) / size).ceil().max(1.0) as usize);
        let dims = self.dims;
        let range = |s: &[[Real; 2]; 2], c: usize| {
            let a = ((s[0][c].min(s[1][c]) - depth - lo[c]) / size)
                .floor()
                .max(0.0) as usize;
            let b = ((s[0][c].max(s[1][c]) + depth - lo[c]) / size).floor() as usize;
            a..=b.min(dims[c] - 1)
        };
        self.offsets.clear();
        self.offsets.resize(dims[0] * dims[1] + 1, 0);
        for s in segments.clone() {
            for j in range(&s, 1) {
                for i in range(&s, 0) {
                    self.offsets[j * dims[0] + i + 1] += 1;
                }
            }
        }
        for b in 0..dims[0] * dims[1] {
            self.offsets[b + 1] += self.offsets[b];
        }
        self.items.clear();
        self.items
            .resize(self.offsets[dims[0] * dims[1]] as usize, 0);
        self.cursor.clear();
        self.cursor
            .extend_from_slice(&self.offsets[..dims[0] * dims[1]]);
        for (k, s) in segments.enumerate() {
            for j in range(&s, 1) {
                for i in range(&s, 0) {
                    let b = j * dims[0] + i;
                    self.items[self.cursor[b] as usize] = k as u32;
                    self.cursor[b] += 1;
                }
            }
        }
    }

    /// Segments that may lie within the search depth of the point `x` (tool coordinates).
    pub fn candidates(&self, x: [Real; 2]) -> &[u32] {
        let i = ((x[0] - self.origin[0]) / self.size).floor();
        let j = ((x[1] - self.origin[1]) / self.size).floor();
        if i < 0.0 || j < 0.0 || i >= self.dims[0] as Real || j >= self.dims[1] as Real {
            return &[];
        }
        let b = j as usize * self.dims[0] + i as usize;
        &self.items[self.offsets[b] as usize..self.offsets[b + 1] as usize]
    }
}
