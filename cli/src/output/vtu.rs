//! VTK XML output for ParaView: one `.vtu` file per frame plus a `.pvd` collection. 2D frames
//! ([`write_vtu`]) hold quads, 3D frames ([`write_vtu_3d`]) hexahedra with cell data as well,
//! a die's surface ([`write_vtu_triangles`]) triangles with cell data.
//!
//! Files are written in ASCII so they stay diff-able and easy to inspect. Floating-point values
//! use Rust's shortest round-trip representation in exponent form (`{:e}`), so reading a file
//! back yields bit-identical values. Non-finite values are written as `NaN`, `inf` and `-inf`.

use std::collections::HashSet;
use std::fmt::Write as _;
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// VTK cell type id of a linear quadrilateral (`VTK_QUAD`).
const VTK_QUAD: u8 = 9;

/// VTK cell type id of a linear triangle (`VTK_TRIANGLE`).
const VTK_TRIANGLE: u8 = 5;

/// VTK cell type id of a linear hexahedron (`VTK_HEXAHEDRON`).
const VTK_HEXAHEDRON: u8 = 12;

/// Number of scalar values written per line of a `DataArray`.
const SCALARS_PER_LINE: usize = 6;

/// Number of vector tuples written per line of a `DataArray`.
const VECTORS_PER_LINE: usize = 2;

/// Write one frame as a VTK XML UnstructuredGrid (.vtu), ASCII, points at z = 0, VTK_QUAD (type 9) cells.
///
/// `scalars` and `vectors` become point data arrays (`Float64`, with 1 and 3 components; the z
/// component of vectors is 0). The first scalar and the first vector array are marked as the
/// active ones.
///
/// # Errors
///
/// Returns an [`io::ErrorKind::InvalidInput`] error, before anything is written, when an array
/// length differs from `positions.len()`, a quad references a point that does not exist, or an
/// array name is empty or used twice. I/O failures are returned as they occur.
pub fn write_vtu(
    path: &Path,
    positions: &[[f64; 2]],
    quads: &[[u32; 4]],
    scalars: &[(&str, &[f64])],
    vectors: &[(&str, &[[f64; 2]])],
) -> io::Result<()> {
    let grid = Grid {
        positions,
        cells: quads,
        cell_kind: ("quad", VTK_QUAD),
        point_scalars: scalars,
        point_vectors: vectors,
        cell_scalars: &[],
    };
    grid.write(path)
}

/// Write one 3D frame as a VTK XML UnstructuredGrid (.vtu), ASCII, VTK_HEXAHEDRON (type 12) cells.
///
/// Each hex lists its corners as VTK expects (and the solver gives them): `(-,-,-), (+,-,-),
/// (+,+,-), (-,+,-)`, then the same at `+z`. `point_scalars` and `point_vectors` become point
/// data arrays, `cell_scalars` cell data arrays (`Float64`, with 1 and 3 components); the first
/// array of each kind is marked as the active one. Conventions as [`write_vtu`].
///
/// # Errors
///
/// Returns an [`io::ErrorKind::InvalidInput`] error, before anything is written, when a point
/// array's length differs from `positions.len()`, a cell array's from `hexes.len()`, a hex
/// references a point that does not exist, or an array name is empty or used twice among the
/// point or among the cell arrays. I/O failures are returned as they occur.
pub fn write_vtu_3d(
    path: &Path,
    positions: &[[f64; 3]],
    hexes: &[[u32; 8]],
    point_scalars: &[(&str, &[f64])],
    point_vectors: &[(&str, &[[f64; 3]])],
    cell_scalars: &[(&str, &[f64])],
) -> io::Result<()> {
    let grid = Grid {
        positions,
        cells: hexes,
        cell_kind: ("hex", VTK_HEXAHEDRON),
        point_scalars,
        point_vectors,
        cell_scalars,
    };
    grid.write(path)
}

/// Write a triangulated surface (a die) as a VTK XML UnstructuredGrid (.vtu), ASCII,
/// VTK_TRIANGLE (type 5) cells, `cell_scalars` as cell data arrays. Conventions and errors as
/// [`write_vtu_3d`].
///
/// # Errors
///
/// As [`write_vtu_3d`]'s, for triangles.
pub fn write_vtu_triangles(
    path: &Path,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    cell_scalars: &[(&str, &[f64])],
) -> io::Result<()> {
    let grid = Grid {
        positions,
        cells: triangles,
        cell_kind: ("triangle", VTK_TRIANGLE),
        point_scalars: &[],
        point_vectors: &[],
        cell_scalars,
    };
    grid.write(path)
}

/// Write a ParaView collection (.pvd) listing frames (time in s, file name relative to the .pvd).
///
/// # Errors
///
/// Returns an [`io::ErrorKind::InvalidInput`] error, before anything is written, when a time is
/// not finite. I/O failures are returned as they occur.
pub fn write_pvd(path: &Path, frames: &[(f64, String)]) -> io::Result<()> {
    if let Some((time, file)) = frames.iter().find(|(time, _)| !time.is_finite()) {
        return Err(invalid_input(format!(
            "frame '{file}' has a non-finite time ({time})"
        )));
    }
    let mut xml = String::new();
    xml.push_str("<?xml version=\"1.0\"?>\n");
    xml.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    xml.push_str("  <Collection>\n");
    for (time, file) in frames {
        // Writing into a String cannot fail.
        let _ = writeln!(
            xml,
            "    <DataSet timestep=\"{time:e}\" group=\"\" part=\"0\" file=\"{}\"/>",
            escape_attr(file)
        );
    }
    xml.push_str("  </Collection>\n");
    xml.push_str("</VTKFile>\n");
    let mut out = BufWriter::new(File::create(path)?);
    out.write_all(xml.as_bytes())?;
    out.flush()
}

/// A point or vector written as a 3-component tuple: 2D ones with z = 0.
trait Tuple3 {
    fn write_to<W: Write>(&self, out: &mut W) -> io::Result<()>;
}

impl Tuple3 for [f64; 2] {
    fn write_to<W: Write>(&self, out: &mut W) -> io::Result<()> {
        let [x, y] = self;
        write!(out, "{x:e} {y:e} 0e0")
    }
}

impl Tuple3 for [f64; 3] {
    fn write_to<W: Write>(&self, out: &mut W) -> io::Result<()> {
        let [x, y, z] = self;
        write!(out, "{x:e} {y:e} {z:e}")
    }
}

/// One frame of either writer: points (`P` is `[f64; 2]` or `[f64; 3]`), cells of `K` corners
/// and the data arrays.
struct Grid<'a, P, const K: usize> {
    positions: &'a [P],
    cells: &'a [[u32; K]],
    /// Name of a cell in error messages and its VTK cell type id.
    cell_kind: (&'a str, u8),
    point_scalars: &'a [(&'a str, &'a [f64])],
    point_vectors: &'a [(&'a str, &'a [P])],
    cell_scalars: &'a [(&'a str, &'a [f64])],
}

impl<P: Tuple3, const K: usize> Grid<'_, P, K> {
    /// Validates, then writes the file.
    fn write(&self, path: &Path) -> io::Result<()> {
        self.validate()?;
        let mut out = BufWriter::new(File::create(path)?);
        self.write_to(&mut out)?;
        out.flush()
    }

    /// Checks every array length, cell index and array name before the file is created.
    fn validate(&self) -> io::Result<()> {
        let n = self.positions.len();
        let point_lengths = self
            .point_scalars
            .iter()
            .map(|(name, data)| (*name, data.len()))
            .chain(
                self.point_vectors
                    .iter()
                    .map(|(name, data)| (*name, data.len())),
            );
        check_arrays("point", point_lengths, n, "points")?;
        let cell_lengths = self
            .cell_scalars
            .iter()
            .map(|(name, data)| (*name, data.len()));
        check_arrays("cell", cell_lengths, self.cells.len(), "cells")?;
        let kind = self.cell_kind.0;
        for (cell, corners) in self.cells.iter().enumerate() {
            if let Some(&bad) = corners.iter().find(|&&i| i as usize >= n) {
                return Err(invalid_input(format!(
                    "{kind} {cell} references point {bad} but there are only {n} points"
                )));
            }
        }
        Ok(())
    }

    /// Writes the XML document; inputs must have been validated. Without cell arrays there is
    /// no `CellData` element.
    fn write_to(&self, out: &mut impl Write) -> io::Result<()> {
        writeln!(out, "<?xml version=\"1.0\"?>")?;
        writeln!(
            out,
            "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
        )?;
        writeln!(out, "  <UnstructuredGrid>")?;
        writeln!(
            out,
            "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
            self.positions.len(),
            self.cells.len()
        )?;

        write!(out, "      <PointData")?;
        if let Some((name, _)) = self.point_scalars.first() {
            write!(out, " Scalars=\"{}\"", escape_attr(name))?;
        }
        if let Some((name, _)) = self.point_vectors.first() {
            write!(out, " Vectors=\"{}\"", escape_attr(name))?;
        }
        writeln!(out, ">")?;
        write_scalar_arrays(out, self.point_scalars)?;
        for (name, data) in self.point_vectors {
            open_array(out, "Float64", name, 3)?;
            write_rows(out, data.iter(), VECTORS_PER_LINE, |o, v| v.write_to(o))?;
            close_array(out)?;
        }
        writeln!(out, "      </PointData>")?;

        if let Some((name, _)) = self.cell_scalars.first() {
            writeln!(out, "      <CellData Scalars=\"{}\">", escape_attr(name))?;
            write_scalar_arrays(out, self.cell_scalars)?;
            writeln!(out, "      </CellData>")?;
        }

        writeln!(out, "      <Points>")?;
        open_array(out, "Float64", "Points", 3)?;
        write_rows(out, self.positions.iter(), VECTORS_PER_LINE, |o, p| {
            p.write_to(o)
        })?;
        close_array(out)?;
        writeln!(out, "      </Points>")?;

        writeln!(out, "      <Cells>")?;
        open_array(out, "Int64", "connectivity", 1)?;
        write_rows(out, self.cells.iter(), 1, |o, corners| {
            write_corners(o, corners)
        })?;
        close_array(out)?;
        open_array(out, "Int64", "offsets", 1)?;
        let offsets = (1..=self.cells.len()).map(|cell| K * cell);
        write_rows(out, offsets, SCALARS_PER_LINE, |o, v| write!(o, "{v}"))?;
        close_array(out)?;
        open_array(out, "UInt8", "types", 1)?;
        let types = self.cells.iter().map(|_| self.cell_kind.1);
        write_rows(out, types, 4 * SCALARS_PER_LINE, |o, v| write!(o, "{v}"))?;
        close_array(out)?;
        writeln!(out, "      </Cells>")?;

        writeln!(out, "    </Piece>")?;
        writeln!(out, "  </UnstructuredGrid>")?;
        writeln!(out, "</VTKFile>")
    }
}

/// Checks the `(name, length)` of one set of `association` ("point" or "cell") data arrays:
/// names non-empty and unique, every length `n` (the number of `what`).
fn check_arrays<'a>(
    association: &str,
    lengths: impl IntoIterator<Item = (&'a str, usize)>,
    n: usize,
    what: &str,
) -> io::Result<()> {
    let mut seen = HashSet::new();
    for (name, len) in lengths {
        if name.is_empty() {
            return Err(invalid_input(format!(
                "{association} data array with an empty name"
            )));
        }
        if !seen.insert(name) {
            return Err(invalid_input(format!(
                "{association} data array name '{name}' is used more than once"
            )));
        }
        if len != n {
            return Err(invalid_input(format!(
                "{association} data array '{name}' has {len} values but there are {n} {what}"
            )));
        }
    }
    Ok(())
}

/// Writes named scalar arrays (`Float64`, 1 component).
fn write_scalar_arrays(out: &mut impl Write, arrays: &[(&str, &[f64])]) -> io::Result<()> {
    for (name, data) in arrays {
        open_array(out, "Float64", name, 1)?;
        write_rows(out, data.iter(), SCALARS_PER_LINE, |o, v| {
            write!(o, "{v:e}")
        })?;
        close_array(out)?;
    }
    Ok(())
}

/// Writes a cell's corner indices separated by spaces.
fn write_corners<W: Write>(out: &mut W, corners: &[u32]) -> io::Result<()> {
    for (k, corner) in corners.iter().enumerate() {
        if k > 0 {
            write!(out, " ")?;
        }
        write!(out, "{corner}")?;
    }
    Ok(())
}

/// Writes the opening tag of an ASCII `DataArray`.
fn open_array(out: &mut impl Write, ty: &str, name: &str, components: usize) -> io::Result<()> {
    writeln!(
        out,
        "        <DataArray type=\"{ty}\" Name=\"{}\" NumberOfComponents=\"{components}\" format=\"ascii\">",
        escape_attr(name)
    )
}

/// Writes the closing tag of a `DataArray`.
fn close_array(out: &mut impl Write) -> io::Result<()> {
    writeln!(out, "        </DataArray>")
}

/// Writes `values` as indented rows of `per_line` items, each formatted by `item`.
fn write_rows<W: Write, T>(
    out: &mut W,
    values: impl IntoIterator<Item = T>,
    per_line: usize,
    mut item: impl FnMut(&mut W, T) -> io::Result<()>,
) -> io::Result<()> {
    let mut in_line = 0;
    for value in values {
        if in_line == 0 {
            write!(out, "         ")?;
        }
        write!(out, " ")?;
        item(out, value)?;
        in_line += 1;
        if in_line == per_line {
            writeln!(out)?;
            in_line = 0;
        }
    }
    if in_line > 0 {
        writeln!(out)?;
    }
    Ok(())
}

/// Escapes a string for use inside a double-quoted XML attribute.
fn escape_attr(s: &str) -> String {
    let mut escaped = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => escaped.push_str("&amp;"),
            '<' => escaped.push_str("&lt;"),
            '>' => escaped.push_str("&gt;"),
            '"' => escaped.push_str("&quot;"),
            '\'' => escaped.push_str("&apos;"),
            _ => escaped.push(c),
        }
    }
    escaped
}

/// Builds an [`io::ErrorKind::InvalidInput`] error with the given message.
fn invalid_input(message: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, message)
}

#[cfg(test)]
mod tests {
    use super::*;
    use quick_xml::events::Event;
    use quick_xml::{Reader, XmlVersion};

    /// An XML element with its attributes, text content and children.
    #[derive(Debug, Default)]
    struct Element {
        name: String,
        attrs: Vec<(String, String)>,
        text: String,
        children: Vec<Element>,
    }

    impl Element {
        fn attr(&self, key: &str) -> &str {
            self.attrs
                .iter()
                .find(|(k, _)| k == key)
                .map(|(_, v)| v.as_str())
                .unwrap_or_else(|| panic!("<{}> has no attribute {key}", self.name))
        }

        fn child(&self, name: &str) -> &Element {
            self.children
                .iter()
                .find(|c| c.name == name)
                .unwrap_or_else(|| panic!("<{}> has no child <{name}>", self.name))
        }

        fn array(&self, name: &str) -> &Element {
            self.children
                .iter()
                .find(|c| c.name == "DataArray" && c.attr("Name") == name)
                .unwrap_or_else(|| panic!("<{}> has no DataArray {name}", self.name))
        }

        fn values<T: std::str::FromStr>(&self) -> Vec<T>
        where
            T::Err: std::fmt::Debug,
        {
            self.text
                .split_whitespace()
                .map(|t| t.parse().expect("number"))
                .collect()
        }
    }

    fn element(start: &quick_xml::events::BytesStart) -> Element {
        Element {
            name: start.name().as_ref().to_string(),
            attrs: start
                .attributes()
                .map(|a| {
                    let a = a.expect("attribute");
                    let value = a.normalized_value(XmlVersion::Implicit1_0).expect("value");
                    (a.key.as_ref().to_string(), value.into_owned())
                })
                .collect(),
            ..Element::default()
        }
    }

    /// Parses a whole document and returns its root element.
    fn parse(path: &Path) -> Element {
        let xml = std::fs::read_to_string(path).expect("read back");
        let mut reader = Reader::from_str(&xml);
        let mut stack = vec![Element::default()];
        loop {
            match reader.read_event().expect("well-formed XML") {
                Event::Start(e) => stack.push(element(&e)),
                Event::Empty(e) => {
                    let done = element(&e);
                    stack.last_mut().expect("parent").children.push(done);
                }
                Event::End(_) => {
                    let done = stack.pop().expect("open element");
                    stack.last_mut().expect("parent").children.push(done);
                }
                Event::Text(t) => stack.last_mut().expect("parent").text += &t.xml10_content(),
                Event::Eof => break,
                _ => {}
            }
        }
        assert_eq!(stack.len(), 1, "unclosed elements");
        let mut document = stack.pop().expect("document");
        assert_eq!(document.children.len(), 1, "exactly one root element");
        document.children.remove(0)
    }

    /// A fresh directory for one test's files, removed when it drops.
    fn temp_dir(test: &str) -> tempfile::TempDir {
        tempfile::Builder::new()
            .prefix(&format!("rkforge_vtu_{test}_"))
            .tempdir()
            .expect("create temp dir")
    }

    /// A 3 x 3 node grid with 2 x 2 quads, counter-clockwise corners.
    fn grid() -> (Vec<[f64; 2]>, Vec<[u32; 4]>) {
        let mut positions = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                positions.push([0.1 * f64::from(i), 1.0 / 3.0 * f64::from(j)]);
            }
        }
        let mut quads = Vec::new();
        for j in 0..2u32 {
            for i in 0..2u32 {
                let a = 3 * j + i;
                quads.push([a, a + 1, a + 4, a + 3]);
            }
        }
        (positions, quads)
    }

    #[test]
    fn grid_round_trips_exactly() {
        let (positions, quads) = grid();
        let temperature = [
            20.0,
            0.1,
            1.0 / 3.0,
            -1e-300,
            1e300,
            f64::MIN_POSITIVE,
            -0.0,
            f64::MAX,
            std::f64::consts::PI,
        ];
        let strain: Vec<f64> = (0..9).map(|i| f64::from(i) * 0.7e-3).collect();
        let velocity: Vec<[f64; 2]> = (0..9)
            .map(|i| [f64::from(i).sin(), -f64::from(i).cos() * 1e-7])
            .collect();
        let dir = temp_dir("grid");
        let path = dir.path().join("frame_0001.vtu");
        write_vtu(
            &path,
            &positions,
            &quads,
            &[
                ("temperature", &temperature),
                ("strain <eq> & \"p\"", &strain),
            ],
            &[("velocity", &velocity)],
        )
        .expect("write vtu");

        let root = parse(&path);
        assert_eq!(root.name, "VTKFile");
        assert_eq!(root.attr("type"), "UnstructuredGrid");
        let piece = root.child("UnstructuredGrid").child("Piece");
        assert_eq!(piece.attr("NumberOfPoints"), "9");
        assert_eq!(piece.attr("NumberOfCells"), "4");

        let points = piece.child("Points").array("Points");
        assert_eq!(points.attr("NumberOfComponents"), "3");
        let xyz: Vec<f64> = points.values();
        let expected: Vec<f64> = positions.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
        assert_eq!(xyz, expected);

        let cells = piece.child("Cells");
        let connectivity: Vec<u32> = cells.array("connectivity").values();
        assert_eq!(connectivity, quads.concat());
        let offsets: Vec<u64> = cells.array("offsets").values();
        assert_eq!(offsets, [4, 8, 12, 16]);
        let types: Vec<u8> = cells.array("types").values();
        assert_eq!(types, [9; 4]);

        let point_data = piece.child("PointData");
        assert_eq!(point_data.attr("Scalars"), "temperature");
        assert_eq!(point_data.attr("Vectors"), "velocity");
        for (name, data) in [
            ("temperature", &temperature[..]),
            ("strain <eq> & \"p\"", &strain[..]),
        ] {
            let array = point_data.array(name);
            assert_eq!(array.attr("type"), "Float64");
            assert_eq!(array.attr("NumberOfComponents"), "1");
            let read: Vec<f64> = array.values();
            let read_bits: Vec<u64> = read.iter().map(|v| v.to_bits()).collect();
            let data_bits: Vec<u64> = data.iter().map(|v| v.to_bits()).collect();
            assert_eq!(read_bits, data_bits, "array {name}");
        }
        let array = point_data.array("velocity");
        assert_eq!(array.attr("NumberOfComponents"), "3");
        let read: Vec<f64> = array.values();
        let expected: Vec<f64> = velocity.iter().flat_map(|v| [v[0], v[1], 0.0]).collect();
        assert_eq!(read, expected);
    }

    #[test]
    fn empty_mesh_is_valid() {
        let dir = temp_dir("empty");
        let path = dir.path().join("empty.vtu");
        write_vtu(&path, &[], &[], &[("s", &[])], &[]).expect("write vtu");
        let piece = parse(&path)
            .child("UnstructuredGrid")
            .child("Piece")
            .attrs
            .clone();
        assert!(piece.contains(&("NumberOfPoints".into(), "0".into())));
        assert!(piece.contains(&("NumberOfCells".into(), "0".into())));
    }

    #[test]
    fn invalid_input_is_rejected_without_writing() {
        let (positions, quads) = grid();
        let dir = temp_dir("invalid");
        let path = dir.path().join("bad.vtu");
        let short = [0.0; 8];
        let short_vec = [[0.0; 2]; 10];
        let full = [0.0; 9];
        let bad_quads = [[0, 1, 4, 9]];
        type Case<'a> = (
            &'a str,
            &'a [[u32; 4]],
            &'a [(&'a str, &'a [f64])],
            &'a [(&'a str, &'a [[f64; 2]])],
        );
        let cases: [Case; 5] = [
            ("short scalar", &quads, &[("s", &short)], &[]),
            ("long vector", &quads, &[], &[("v", &short_vec)]),
            ("quad index", &bad_quads, &[("s", &full)], &[]),
            ("duplicate name", &quads, &[("s", &full), ("s", &full)], &[]),
            ("empty name", &quads, &[("", &full)], &[]),
        ];
        for (case, quads, scalars, vectors) in cases {
            let err = write_vtu(&path, &positions, quads, scalars, vectors).expect_err(case);
            assert_eq!(err.kind(), io::ErrorKind::InvalidInput, "{case}: {err}");
            assert!(!path.exists(), "{case}: no file may be written");
        }
    }

    /// A 3 x 2 x 2 node block with 2 x 1 x 1 hexes, corners in VTK order.
    fn block() -> (Vec<[f64; 3]>, Vec<[u32; 8]>) {
        let mut positions = Vec::new();
        for k in 0..2 {
            for j in 0..2 {
                for i in 0..3 {
                    let (x, y, z) = (f64::from(i), f64::from(j), f64::from(k));
                    positions.push([0.1 * x, 1.0 / 3.0 * y + 1e-3 * x, -0.7 * z]);
                }
            }
        }
        let node = |i: u32, j: u32, k: u32| 6 * k + 3 * j + i;
        let hexes = (0..2)
            .map(|i| {
                [
                    node(i, 0, 0),
                    node(i + 1, 0, 0),
                    node(i + 1, 1, 0),
                    node(i, 1, 0),
                    node(i, 0, 1),
                    node(i + 1, 0, 1),
                    node(i + 1, 1, 1),
                    node(i, 1, 1),
                ]
            })
            .collect();
        (positions, hexes)
    }

    fn bits(values: &[f64]) -> Vec<u64> {
        values.iter().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn hex_block_round_trips_exactly() {
        let (positions, hexes) = block();
        assert_eq!(hexes[0], [0, 1, 4, 3, 6, 7, 10, 9]);
        let temperature: Vec<f64> = (0..12).map(|i| 20.0 + f64::from(i) / 7.0).collect();
        let mut pressure = vec![-0.0, 1e-300, f64::MAX, std::f64::consts::E, 3.0, -4.5];
        pressure.extend([f64::MIN_POSITIVE, 0.1, 0.2, 0.3, 1e300, -1.0 / 3.0]);
        let velocity: Vec<[f64; 3]> = (0..12)
            .map(|i| {
                let t = f64::from(i);
                [t.sin(), -t.cos() * 1e-7, t / 3.0]
            })
            .collect();
        let strain = [0.1 + 0.2, f64::NAN];
        let damage = [f64::INFINITY, f64::NEG_INFINITY];
        let dir = temp_dir("hex");
        let path = dir.path().join("frame_0001.vtu");
        write_vtu_3d(
            &path,
            &positions,
            &hexes,
            &[("temperature", &temperature), ("p & <q>", &pressure)],
            &[("velocity", &velocity)],
            &[("plastic strain", &strain), ("damage", &damage)],
        )
        .expect("write vtu");

        let root = parse(&path);
        assert_eq!(root.attr("type"), "UnstructuredGrid");
        let piece = root.child("UnstructuredGrid").child("Piece");
        assert_eq!(piece.attr("NumberOfPoints"), "12");
        assert_eq!(piece.attr("NumberOfCells"), "2");

        let points = piece.child("Points").array("Points");
        assert_eq!(points.attr("NumberOfComponents"), "3");
        let xyz: Vec<f64> = points.values();
        assert_eq!(bits(&xyz), bits(&positions.concat()));

        let cells = piece.child("Cells");
        let connectivity: Vec<u32> = cells.array("connectivity").values();
        assert_eq!(connectivity, hexes.concat());
        let offsets: Vec<u64> = cells.array("offsets").values();
        assert_eq!(offsets, [8, 16]);
        let types: Vec<u8> = cells.array("types").values();
        assert_eq!(types, [12, 12]);

        let point_data = piece.child("PointData");
        assert_eq!(point_data.attr("Scalars"), "temperature");
        assert_eq!(point_data.attr("Vectors"), "velocity");
        for (name, data) in [("temperature", &temperature), ("p & <q>", &pressure)] {
            let array = point_data.array(name);
            assert_eq!(array.attr("NumberOfComponents"), "1");
            assert_eq!(bits(&array.values::<f64>()), bits(data), "array {name}");
        }
        let array = point_data.array("velocity");
        assert_eq!(array.attr("NumberOfComponents"), "3");
        assert_eq!(bits(&array.values::<f64>()), bits(&velocity.concat()));

        let cell_data = piece.child("CellData");
        assert_eq!(cell_data.attr("Scalars"), "plastic strain");
        for (name, data) in [("plastic strain", &strain), ("damage", &damage)] {
            let array = cell_data.array(name);
            assert_eq!(array.attr("type"), "Float64");
            assert_eq!(array.attr("NumberOfComponents"), "1");
            assert_eq!(bits(&array.values::<f64>()), bits(data), "array {name}");
        }
    }

    #[test]
    fn die_triangles_round_trip_with_their_pressure() {
        let positions = [[0.0, 0.0, 0.1], [1e-3, 0.0, 0.1], [0.0, 2e-3, 0.1 + 1e-9]];
        let triangles = [[0, 1, 2], [2, 1, 0]];
        let pressure = [1.25e8, 0.0];
        let dir = temp_dir("die");
        let path = dir.path().join("die_ram_0000.vtu");
        write_vtu_triangles(&path, &positions, &triangles, &[("pressure_Pa", &pressure)])
            .expect("write vtu");
        let root = parse(&path);
        let piece = root.child("UnstructuredGrid").child("Piece");
        assert_eq!(piece.attr("NumberOfPoints"), "3");
        assert_eq!(piece.attr("NumberOfCells"), "2");
        let xyz: Vec<f64> = piece.child("Points").array("Points").values();
        assert_eq!(bits(&xyz), bits(&positions.concat()));
        let cells = piece.child("Cells");
        let connectivity: Vec<u32> = cells.array("connectivity").values();
        assert_eq!(connectivity, triangles.concat());
        let offsets: Vec<u64> = cells.array("offsets").values();
        assert_eq!(offsets, [3, 6]);
        let types: Vec<u8> = cells.array("types").values();
        assert_eq!(types, [5, 5]);
        let cell_data = piece.child("CellData");
        assert_eq!(cell_data.attr("Scalars"), "pressure_Pa");
        let values: Vec<f64> = cell_data.array("pressure_Pa").values();
        assert_eq!(bits(&values), bits(&pressure));
        let bad = write_vtu_triangles(&path, &positions, &[[0, 1, 3]], &[]);
        assert_eq!(bad.unwrap_err().kind(), io::ErrorKind::InvalidInput);
    }

    #[test]
    fn frames_without_cell_data_have_no_cell_data_element() {
        let (positions, hexes) = block();
        let dir = temp_dir("hex_no_cells");
        let path = dir.path().join("frame.vtu");
        write_vtu_3d(&path, &positions, &hexes, &[], &[], &[]).expect("write vtu");
        let piece = parse(&path);
        let piece = piece.child("UnstructuredGrid").child("Piece");
        assert!(piece.children.iter().all(|c| c.name != "CellData"));
        let (positions, quads) = grid();
        write_vtu(&path, &positions, &quads, &[], &[]).expect("write vtu");
        let piece = parse(&path);
        let piece = piece.child("UnstructuredGrid").child("Piece");
        assert!(piece.children.iter().all(|c| c.name != "CellData"));
    }

    #[test]
    fn invalid_hex_input_is_rejected_without_writing() {
        let (positions, hexes) = block();
        let dir = temp_dir("hex_invalid");
        let path = dir.path().join("bad.vtu");
        let points = [0.0; 12];
        let cells = [0.0; 2];
        let bad_hexes = [[0, 1, 4, 3, 6, 7, 10, 12]];
        type Case<'a> = (
            &'a str,
            &'a [[u32; 8]],
            &'a [(&'a str, &'a [f64])],
            &'a [(&'a str, &'a [[f64; 3]])],
            &'a [(&'a str, &'a [f64])],
        );
        let cases: [Case; 8] = [
            (
                "short point scalar",
                &hexes,
                &[("s", &points[1..])],
                &[],
                &[],
            ),
            ("long vector", &hexes, &[], &[("v", &[[0.0; 3]; 13])], &[]),
            ("cell array per point", &hexes, &[], &[], &[("c", &points)]),
            ("short cell array", &hexes, &[], &[], &[("c", &cells[1..])]),
            ("hex index", &bad_hexes, &[], &[], &[("c", &cells[1..])]),
            (
                "duplicate cell name",
                &hexes,
                &[],
                &[],
                &[("c", &cells), ("c", &cells)],
            ),
            ("empty cell name", &hexes, &[], &[], &[("", &cells)]),
            (
                "duplicate point name",
                &hexes,
                &[("s", &points)],
                &[("s", &[[0.0; 3]; 12])],
                &[],
            ),
        ];
        for (case, hexes, point_scalars, point_vectors, cell_scalars) in cases {
            let err = write_vtu_3d(
                &path,
                &positions,
                hexes,
                point_scalars,
                point_vectors,
                cell_scalars,
            )
            .expect_err(case);
            assert_eq!(err.kind(), io::ErrorKind::InvalidInput, "{case}: {err}");
            assert!(!path.exists(), "{case}: no file may be written");
        }
        // A point and a cell array may share a name (ParaView tells them apart).
        let ok = write_vtu_3d(
            &path,
            &positions,
            &hexes,
            &[("s", &points)],
            &[],
            &[("s", &cells)],
        );
        assert!(ok.is_ok());
    }

    #[test]
    fn pvd_lists_frames() {
        let dir = temp_dir("pvd");
        let path = dir.path().join("run.pvd");
        let frames = vec![
            (0.0, "frame_0000.vtu".to_string()),
            (1e-3 / 3.0, "frames/a&b_0001.vtu".to_string()),
        ];
        write_pvd(&path, &frames).expect("write pvd");
        let root = parse(&path);
        assert_eq!(root.attr("type"), "Collection");
        let sets = &root.child("Collection").children;
        assert_eq!(sets.len(), 2);
        for (set, (time, file)) in sets.iter().zip(&frames) {
            assert_eq!(set.name, "DataSet");
            assert_eq!(set.attr("timestep").parse::<f64>().ok(), Some(*time));
            assert_eq!(set.attr("file"), file);
        }
        let err = write_pvd(&path, &[(f64::NAN, "x.vtu".into())]).expect_err("NaN time");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
    }
}
