//! VTK XML output for ParaView: one `.vtu` file per frame plus a `.pvd` collection.
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
    validate_vtu(positions, quads, scalars, vectors)?;
    let mut out = BufWriter::new(File::create(path)?);
    write_vtu_to(&mut out, positions, quads, scalars, vectors)?;
    out.flush()
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

/// Checks every array length, quad index and array name before the file is created.
fn validate_vtu(
    positions: &[[f64; 2]],
    quads: &[[u32; 4]],
    scalars: &[(&str, &[f64])],
    vectors: &[(&str, &[[f64; 2]])],
) -> io::Result<()> {
    let n = positions.len();
    let lengths = scalars
        .iter()
        .map(|(name, data)| (*name, data.len()))
        .chain(vectors.iter().map(|(name, data)| (*name, data.len())));
    let mut seen = HashSet::new();
    for (name, len) in lengths {
        if name.is_empty() {
            return Err(invalid_input("point data array with an empty name".into()));
        }
        if !seen.insert(name) {
            return Err(invalid_input(format!(
                "point data array name '{name}' is used more than once"
            )));
        }
        if len != n {
            return Err(invalid_input(format!(
                "point data array '{name}' has {len} values but there are {n} points"
            )));
        }
    }
    for (cell, quad) in quads.iter().enumerate() {
        if let Some(&bad) = quad.iter().find(|&&i| i as usize >= n) {
            return Err(invalid_input(format!(
                "quad {cell} references point {bad} but there are only {n} points"
            )));
        }
    }
    Ok(())
}

/// Writes the XML document; inputs must have been validated.
fn write_vtu_to(
    out: &mut impl Write,
    positions: &[[f64; 2]],
    quads: &[[u32; 4]],
    scalars: &[(&str, &[f64])],
    vectors: &[(&str, &[[f64; 2]])],
) -> io::Result<()> {
    writeln!(out, "<?xml version=\"1.0\"?>")?;
    writeln!(
        out,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(out, "  <UnstructuredGrid>")?;
    writeln!(
        out,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        positions.len(),
        quads.len()
    )?;

    write!(out, "      <PointData")?;
    if let Some((name, _)) = scalars.first() {
        write!(out, " Scalars=\"{}\"", escape_attr(name))?;
    }
    if let Some((name, _)) = vectors.first() {
        write!(out, " Vectors=\"{}\"", escape_attr(name))?;
    }
    writeln!(out, ">")?;
    for (name, data) in scalars {
        open_array(out, "Float64", name, 1)?;
        write_rows(out, data.iter(), SCALARS_PER_LINE, |o, v| {
            write!(o, "{v:e}")
        })?;
        close_array(out)?;
    }
    for (name, data) in vectors {
        open_array(out, "Float64", name, 3)?;
        write_rows(out, data.iter(), VECTORS_PER_LINE, write_xy0)?;
        close_array(out)?;
    }
    writeln!(out, "      </PointData>")?;

    writeln!(out, "      <Points>")?;
    open_array(out, "Float64", "Points", 3)?;
    write_rows(out, positions.iter(), VECTORS_PER_LINE, write_xy0)?;
    close_array(out)?;
    writeln!(out, "      </Points>")?;

    writeln!(out, "      <Cells>")?;
    open_array(out, "Int64", "connectivity", 1)?;
    write_rows(out, quads.iter(), 1, |o, [a, b, c, d]| {
        write!(o, "{a} {b} {c} {d}")
    })?;
    close_array(out)?;
    open_array(out, "Int64", "offsets", 1)?;
    let offsets = (1..=quads.len()).map(|cell| 4 * cell);
    write_rows(out, offsets, SCALARS_PER_LINE, |o, v| write!(o, "{v}"))?;
    close_array(out)?;
    open_array(out, "UInt8", "types", 1)?;
    let types = quads.iter().map(|_| VTK_QUAD);
    write_rows(out, types, 4 * SCALARS_PER_LINE, |o, v| write!(o, "{v}"))?;
    close_array(out)?;
    writeln!(out, "      </Cells>")?;

    writeln!(out, "    </Piece>")?;
    writeln!(out, "  </UnstructuredGrid>")?;
    writeln!(out, "</VTKFile>")
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

/// Writes a 2D vector as a 3-component tuple with z = 0.
fn write_xy0<W: Write>(out: &mut W, [x, y]: &[f64; 2]) -> io::Result<()> {
    write!(out, "{x:e} {y:e} 0e0")
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
    use std::path::PathBuf;

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

    fn temp_dir(test: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("rkforge_vtu_{}_{test}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("create temp dir");
        dir
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
        let path = temp_dir("grid").join("frame_0001.vtu");
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
        let path = temp_dir("empty").join("empty.vtu");
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
        let path = dir.join("bad.vtu");
        let _ = std::fs::remove_file(&path);
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

    #[test]
    fn pvd_lists_frames() {
        let path = temp_dir("pvd").join("run.pvd");
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
