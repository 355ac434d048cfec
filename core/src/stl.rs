//! Reading and checking a rigid tool's STL file (binary or ASCII, read by the `stl_io`
//! crate) into a [`TriangleMesh`] in metres.
//!
//! A die is the solid its triangles enclose, so a file is refused, with the reason, unless
//! its surface is closed, manifold and consistently oriented with the normals out of the
//! die ([`TriangleMesh::check`]):
//!
//! - every edge is shared by exactly two triangles (one: the surface is open, a hole or a
//!   missing face; more: a non-manifold edge, two bodies touching along it);
//! - the two triangles of an edge traverse it in opposite directions (the same direction
//!   twice: one of them is flipped, the orientation is inconsistent);
//! - the enclosed volume `V = 1/6 sum_t a_t . (b_t x c_t)` (m^3, the divergence theorem over
//!   the triangles `(a, b, c)` wound counter-clockwise seen from outside) is positive (a
//!   negative volume: every normal points into the die, the file is inverted);
//! - no triangle is degenerate: `|(b - a) x (c - a)|` is at least [`DEGENERATE`] times its
//!   longest edge squared (collinear or coincident corners have no normal).
//!
//! The facet normals the file stores are not read: the winding defines the orientation
//! (many exporters write zero normals). Coordinates are single precision in the file; in
//! millimetres (`unit = "mm"`) each is divided by 1000, so a value the file holds exactly
//! (30 mm) gives the correctly rounded metres (0.03 m) a scene would write.

use crate::math::Real;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::Path;

/// Below this ratio of `|(b - a) x (c - a)|` to the longest edge squared (-) a triangle is
/// degenerate: its smallest angle is under about 1e-6 rad, its normal is round-off.
pub const DEGENERATE: Real = 1e-6;

/// The length unit of an STL file's coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LengthUnit {
    /// Metres.
    #[default]
    M,
    /// Millimetres (what CAD exports usually hold).
    Mm,
}

impl LengthUnit {
    /// A coordinate of the file in metres.
    pub fn metres(self, x: f32) -> Real {
        match self {
            LengthUnit::M => Real::from(x),
            LengthUnit::Mm => Real::from(x) / 1000.0,
        }
    }
}

/// A triangulated surface: vertices (m) and triangles as three vertex indices, wound
/// counter-clockwise seen from outside the solid they enclose.
#[derive(Debug, Clone, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions (m), each once (the file's corners merged where their coordinates
    /// are the same bits).
    pub vertices: Vec<[Real; 3]>,
    /// Triangles `[a, b, c]`, indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// Reads an STL file, binary or ASCII, in `unit`, and checks it ([`TriangleMesh::check`]).
    ///
    /// # Errors
    ///
    /// The file cannot be read, is not an STL file, holds no triangles, or fails a check:
    /// the reason, without the file's name (the caller names it).
    pub fn read(path: &Path, unit: LengthUnit) -> Result<TriangleMesh, String> {
        let file = std::fs::File::open(path).map_err(|e| format!("cannot be read: {e}"))?;
        let stl = stl_io::read_stl(&mut std::io::BufReader::new(file))
            .map_err(|e| format!("is not a readable STL file: {e}"))?;
        let mesh = TriangleMesh {
            vertices: stl
                .vertices
                .iter()
                .map(|v| v.0.map(|x| unit.metres(x)))
                .collect(),
            triangles: stl
                .faces
                .iter()
                .map(|f| f.vertices.map(|i| i as u32))
                .collect(),
        };
        mesh.check()?;
        Ok(mesh)
    }

    /// What a die's surface must be (the module's list): finite, not empty, no degenerate
    /// triangle, closed, manifold, consistently oriented, a positive enclosed volume.
    ///
    /// # Errors
    ///
    /// The first check that fails, with the triangles or the edge that fail it.
    pub fn check(&self) -> Result<(), String> {
        if self.triangles.is_empty() {
            return Err("holds no triangles".into());
        }
        if let Some(v) = self
            .vertices
            .iter()
            .find(|v| v.iter().any(|x| !x.is_finite()))
        {
            return Err(format!("has a vertex that is not finite: {v:?}"));
        }
        let degenerate: Vec<usize> = (0..self.triangles.len())
            .filter(|&t| {
                let [a, b, c] = self.corners(t);
                let longest = [sub(b, a), sub(c, b), sub(a, c)]
                    .iter()
                    .map(|e| dot(*e, *e))
                    .fold(0.0, Real::max);
                let n = cross(sub(b, a), sub(c, a));
                dot(n, n).sqrt() < DEGENERATE * longest || longest == 0.0
            })
            .collect();
        if let Some(&t) = degenerate.first() {
            return Err(format!(
                "has {} degenerate triangle(s) (corners collinear or coincident, no normal); the first, triangle {t}, has corners {:?} m",
                degenerate.len(),
                self.corners(t)
            ));
        }
        // Each undirected edge (low, high): how often it is traversed low -> high and
        // high -> low.
        let mut edges: HashMap<(u32, u32), [u32; 2]> = HashMap::new();
        for tri in &self.triangles {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let e = edges.entry((a.min(b), a.max(b))).or_default();
                e[usize::from(a > b)] += 1;
            }
        }
        let mut sorted: Vec<(&(u32, u32), &[u32; 2])> = edges.iter().collect();
        sorted.sort_unstable();
        let at = |(a, b): (u32, u32)| (self.vertices[a as usize], self.vertices[b as usize]);
        let first = |pick: &dyn Fn(&[u32; 2]) -> bool| {
            let found: Vec<(u32, u32)> = sorted
                .iter()
                .filter(|(_, n)| pick(n))
                .map(|(e, _)| **e)
                .collect();
            found.first().map(|&e| (found.len(), at(e)))
        };
        if let Some((n, (a, b))) = first(&|n| n[0] + n[1] == 1) {
            return Err(format!(
                "is an open surface: {n} edge(s) belong to one triangle only (a hole or a missing face), the first from {a:?} to {b:?} m"
            ));
        }
        if let Some((n, (a, b))) = first(&|n| n[0] + n[1] > 2) {
            return Err(format!(
                "is not manifold: {n} edge(s) are shared by more than two triangles, the first from {a:?} to {b:?} m"
            ));
        }
        if let Some((n, (a, b))) = first(&|n| n[0] > 1 || n[1] > 1) {
            return Err(format!(
                "is inconsistently oriented: {n} edge(s) are traversed twice in the same direction (a triangle flipped against its neighbour), the first from {a:?} to {b:?} m"
            ));
        }
        let volume = self.volume();
        if volume <= 0.0 {
            return Err(format!(
                "encloses a negative volume ({volume:.4e} m^3): its normals point into the die (inverted); reverse the triangles' winding or export with outward normals"
            ));
        }
        Ok(())
    }

    /// The corners of triangle `t` (m).
    pub fn corners(&self, t: usize) -> [[Real; 3]; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize])
    }

    /// The enclosed volume `1/6 sum_t a_t . (b_t x c_t)` (m^3), positive for outward normals.
    pub fn volume(&self) -> Real {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                dot(a, cross(b, c))
            })
            .sum::<Real>()
            / 6.0
    }

    /// `[min, max]` of each coordinate over the vertices (m).
    pub fn bounds(&self) -> [[Real; 2]; 3] {
        let mut b = [[Real::INFINITY, Real::NEG_INFINITY]; 3];
        for v in &self.vertices {
            for (bk, x) in b.iter_mut().zip(v) {
                *bk = [bk[0].min(*x), bk[1].max(*x)];
            }
        }
        b
    }
}

/// `a - b`.
pub(crate) fn sub(a: [Real; 3], b: [Real; 3]) -> [Real; 3] {
    std::array::from_fn(|k| a[k] - b[k])
}

/// `a . b`, summed from the first term on.
pub(crate) fn dot(a: [Real; 3], b: [Real; 3]) -> Real {
    crate::math::dot(&a, &b)
}

/// `a x b`.
pub(crate) fn cross(a: [Real; 3], b: [Real; 3]) -> [Real; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The closed box `lo..hi` (m) as 12 triangles wound with outward normals.
    pub(crate) fn box_mesh(lo: [Real; 3], hi: [Real; 3]) -> TriangleMesh {
        let vertices = (0..8)
            .map(|i| std::array::from_fn(|k| if i >> k & 1 == 1 { hi[k] } else { lo[k] }))
            .collect();
        // Corner i has bit k set where coordinate k is at `hi`.
        let quads = [
            [0, 2, 3, 1], // z = lo, normal -z
            [4, 5, 7, 6], // z = hi, normal +z
            [0, 1, 5, 4], // y = lo, normal -y
            [2, 6, 7, 3], // y = hi, normal +y
            [0, 4, 6, 2], // x = lo, normal -x
            [1, 3, 7, 5], // x = hi, normal +x
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        TriangleMesh {
            vertices,
            triangles,
        }
    }

    /// An STL file of `mesh` (binary, or ASCII with `ascii`), its coordinates divided by
    /// `per_unit` (1e-3 writes millimetres).
    pub(crate) fn write_stl(path: &Path, mesh: &TriangleMesh, ascii: bool, per_unit: Real) {
        let tri: Vec<[[f32; 3]; 3]> = (0..mesh.triangles.len())
            .map(|t| mesh.corners(t).map(|v| v.map(|x| (x / per_unit) as f32)))
            .collect();
        if ascii {
            let mut s = String::from("solid die\n");
            for t in &tri {
                s += "facet normal 0 0 0\nouter loop\n";
                for v in t {
                    s += &format!("vertex {:e} {:e} {:e}\n", v[0], v[1], v[2]);
                }
                s += "endloop\nendfacet\n";
            }
            s += "endsolid die\n";
            std::fs::write(path, s).unwrap();
        } else {
            let tris: Vec<stl_io::Triangle> = tri
                .iter()
                .map(|t| stl_io::Triangle {
                    normal: stl_io::Normal::new([0.0; 3]),
                    vertices: t.map(stl_io::Vertex::new),
                })
                .collect();
            let mut f = std::fs::File::create(path).unwrap();
            stl_io::write_stl(&mut f, tris.iter()).unwrap();
        }
    }

    /// A fresh directory for one test's files, removed when it drops.
    fn dir() -> tempfile::TempDir {
        tempfile::Builder::new()
            .prefix("rkforge_stl_")
            .tempdir()
            .unwrap()
    }

    /// A box written as binary and as ASCII, in metres and millimetres, reads back as the
    /// box with its volume; 30 mm reads as the scene's 0.03 m to the bit.
    #[test]
    fn a_closed_box_reads_in_both_forms_and_units() {
        let mesh = box_mesh([0.0, 0.0, 0.0], [0.02, 0.01, 0.03]);
        let dir = dir();
        for (ascii, unit, per) in [
            (false, LengthUnit::M, 1.0),
            (true, LengthUnit::M, 1.0),
            (false, LengthUnit::Mm, 1e-3),
            (true, LengthUnit::Mm, 1e-3),
        ] {
            let path = dir.path().join(format!("box_{ascii}_{per}.stl"));
            write_stl(&path, &mesh, ascii, per);
            let read = TriangleMesh::read(&path, unit).unwrap();
            assert_eq!(read.triangles.len(), 12);
            assert_eq!(read.vertices.len(), 8);
            let v = read.volume();
            assert!((v - 6e-6).abs() < 1e-12, "{v}");
            if unit == LengthUnit::Mm {
                assert!(read.vertices.iter().any(|x| x[2] == 0.03));
            }
        }
    }

    /// Each broken surface is refused with its reason.
    #[test]
    fn broken_surfaces_are_refused_with_the_reason() {
        let good = box_mesh([0.0; 3], [1.0; 3]);
        let mut open = good.clone();
        open.triangles.pop();
        let mut flipped_one = good.clone();
        flipped_one.triangles[0].swap(1, 2);
        let mut inverted = good.clone();
        for t in &mut inverted.triangles {
            t.swap(1, 2);
        }
        let mut degenerate = good.clone();
        degenerate.vertices.push([0.5, 0.5, 0.5]);
        degenerate.triangles.push([0, 7, 8]);
        degenerate.triangles.push([0, 8, 7]);
        let mut doubled = good.clone();
        doubled.triangles.extend(good.triangles.iter().take(2));
        for (mesh, reason) in [
            (&open, "open surface"),
            (&flipped_one, "inconsistently oriented"),
            (&inverted, "inverted"),
            (&degenerate, "degenerate"),
            (&doubled, "not manifold"),
        ] {
            let e = mesh.check().unwrap_err();
            assert!(e.contains(reason), "{e}");
        }
        assert!(good.check().is_ok());
        let dir = dir();
        let path = dir.path().join("not_stl.stl");
        std::fs::write(&path, "hello").unwrap();
        let e = TriangleMesh::read(&path, LengthUnit::M).unwrap_err();
        assert!(e.contains("STL"), "{e}");
    }
}
