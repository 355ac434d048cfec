//! Uniform bins over line segments and surface facets, so that a point's contact search
//! reads only the items near it: a tool's polyline ([`crate::tools::Tool`]), the
//! workpiece's boundary ring ([`crate::contact::self_contact`]) or its surface facets in 3D
//! ([`crate::contact::self_contact_3d`]).

use crate::math::Real;

/// Uniform bins over items with bounding boxes in `D` dimensions: a tool's polyline in the
/// tool's own (initial) coordinates, built once as a tool only translates, or the
/// workpiece's boundary ring (2D) or surface facets (3D), built again at each self-contact
/// search ([`crate::contact::self_contact`], [`crate::contact::self_contact_3d`]). Each item
/// is listed in every bin that its bounding box, grown by the search depth, overlaps.
#[derive(Debug, Clone)]
pub struct Bins<const D: usize> {
    origin: [Real; D],
    size: Real,
    dims: [usize; D],
    offsets: Vec<u32>,
    items: Vec<u32>,
    /// Where the next item of each bin goes while filling.
    cursor: Vec<u32>,
}

impl<const D: usize> Default for Bins<D> {
    fn default() -> Self {
        Bins {
            origin: [0.0; D],
            size: 0.0,
            dims: [0; D],
            offsets: Vec::new(),
            items: Vec::new(),
            cursor: Vec::new(),
        }
    }
}

/// Uniform bins over line segments in the plane.
pub type SegmentBins = Bins<2>;

/// The bounds `[lo, hi]` (m) of `points` grown by `pad` (m) on every side, as the bins of
/// items through them need.
pub fn padded_bounds<const D: usize>(points: &[[Real; D]], pad: Real) -> [[Real; D]; 2] {
    let mut lo = [Real::INFINITY; D];
    let mut hi = [Real::NEG_INFINITY; D];
    for p in points {
        for k in 0..D {
            lo[k] = lo[k].min(p[k] - pad);
            hi[k] = hi[k].max(p[k] + pad);
        }
    }
    [lo, hi]
}

impl<const D: usize> Bins<D> {
    /// Bins of `size` (m) over `bounds` (`[lo, hi]`, m) listing each of `boxes` (each
    /// `[lo, hi]`, m) in every bin it overlaps grown by `depth` (m), in item order, reusing
    /// the buffers (a counting sort: no list per bin). Bins are numbered with the first
    /// axis fastest.
    pub fn fill_boxes(
        &mut self,
        boxes: impl Iterator<Item = [[Real; D]; 2]> + Clone,
        bounds: [[Real; D]; 2],
        depth: Real,
        size: Real,
    ) {
        let [lo, hi] = bounds;
        self.origin = lo;
        self.size = size;
        self.dims = std::array::from_fn(|k| ((hi[k] - lo[k]) / size).ceil().max(1.0) as usize);
        let dims = self.dims;
        let range = |b: &[[Real; D]; 2], c: usize| {
            let a = ((b[0][c] - depth - lo[c]) / size).floor().max(0.0) as usize;
            let e = ((b[1][c] + depth - lo[c]) / size).floor() as usize;
            (a, e.min(dims[c] - 1))
        };
        let count: usize = dims.iter().product();
        // Every bin of the ranges, the first axis fastest.
        let each = |b: &[[Real; D]; 2], f: &mut dyn FnMut(usize)| {
            let r: [(usize, usize); D] = std::array::from_fn(|c| range(b, c));
            if r.iter().any(|&(a, e)| a > e) {
                return;
            }
            let mut at: [usize; D] = r.map(|(a, _)| a);
            loop {
                let mut bin = 0;
                for c in (0..D).rev() {
                    bin = bin * dims[c] + at[c];
                }
                f(bin);
                let mut c = 0;
                loop {
                    if c == D {
                        return;
                    }
                    if at[c] < r[c].1 {
                        at[c] += 1;
                        break;
                    }
                    at[c] = r[c].0;
                    c += 1;
                }
            }
        };
        self.offsets.clear();
        self.offsets.resize(count + 1, 0);
        for b in boxes.clone() {
            each(&b, &mut |bin| self.offsets[bin + 1] += 1);
        }
        for b in 0..count {
            self.offsets[b + 1] += self.offsets[b];
        }
        self.items.clear();
        self.items.resize(self.offsets[count] as usize, 0);
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.offsets[..count]);
        for (k, b) in boxes.enumerate() {
            let (items, cursor) = (&mut self.items, &mut self.cursor);
            each(&b, &mut |bin| {
                items[cursor[bin] as usize] = k as u32;
                cursor[bin] += 1;
            });
        }
    }

    /// Items that may lie within the search depth of the point `x`.
    pub fn candidates(&self, x: [Real; D]) -> &[u32] {
        let mut bin = 0;
        for c in (0..D).rev() {
            let i = ((x[c] - self.origin[c]) / self.size).floor();
            if !(i >= 0.0 && i < self.dims[c] as Real) {
                return &[];
            }
            bin = bin * self.dims[c] + i as usize;
        }
        &self.items[self.offsets[bin] as usize..self.offsets[bin + 1] as usize]
    }
}

impl Bins<2> {
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
    /// bin its bounding box grown by `depth` (m) overlaps, in segment order
    /// ([`Bins::fill_boxes`]).
    pub fn fill(
        &mut self,
        segments: impl Iterator<Item = [[Real; 2]; 2]> + Clone,
        bounds: [[Real; 2]; 2],
        depth: Real,
        size: Real,
    ) {
        let boxes = segments.map(|s| {
            [
                [s[0][0].min(s[1][0]), s[0][1].min(s[1][1])],
                [s[0][0].max(s[1][0]), s[0][1].max(s[1][1])],
            ]
        });
        self.fill_boxes(boxes, bounds, depth, size);
    }
}
