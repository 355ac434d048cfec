//! The standard ROS 2 messages rkforge publishes and their CDR codec. The types are generated
//! by the build script from the standard definitions in
//! `ros_node/msg/<package>/{msg,srv,action}/` (the ROS 2 **Humble** files, byte for byte with
//! their comments; `msg/SOURCES.md` says where each was taken from): per
//! message, part of a service (`_Request`, `_Response`) or part of an action (`_Goal`,
//! `_Result`, `_Feedback`) a struct with the constants and defaults, its [`CdrMessage`] and
//! [`CdrDecode`] codec and its [`RosMessage`] names and texts.
//!
//! # Schema layout
//!
//! [`RosMessage::SCHEMA`] is what rosbag2 (`LocalMessageDefinitionSource::get_full_text`, and
//! the `MessageDefinitionCache` of `rosbag2_storage_mcap` in Humble) writes for MCAP (schema
//! encoding `ros2msg`): the top-level `.msg` text, then for each dependency not yet written,
//! depth first and in the sorted order of the fully qualified type names found in the field
//! declarations, a `\n`, a line of 80 `=`, a line `MSG: pkg/Type` and that type's `.msg` text.
//!
//! # CDR
//!
//! Serialization is plain CDR (XCDR1) little endian as `rmw_fastrtps` and `rmw_cyclonedds` put it
//! on the wire and rosbag2 stores it: the encapsulation header `00 01 00 00`, then the fields in
//! `.msg` order, every primitive aligned to its size relative to the first byte after the
//! header, strings as a `u32` length counting the terminating NUL followed by the bytes and the
//! NUL, sequences as a `u32` element count followed by the elements (an empty sequence of a
//! primitive type adds no alignment padding), booleans as one byte.

use std::fmt;

/// Size of the CDR encapsulation header that precedes every payload.
const ENCAPSULATION_LEN: usize = 4;
/// Encapsulation header of plain CDR, little endian, no options.
const CDR_LE_HEADER: [u8; ENCAPSULATION_LEN] = [0x00, 0x01, 0x00, 0x00];

/// Writes CDR (XCDR1, little endian) into a buffer that starts with the encapsulation header.
#[derive(Debug, Clone)]
pub struct CdrWriter {
    buf: Vec<u8>,
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl CdrWriter {
    /// A writer holding just the encapsulation header `00 01 00 00`.
    #[must_use]
    pub fn new() -> Self {
        Self {
            buf: CDR_LE_HEADER.to_vec(),
        }
    }

    /// The serialized message: encapsulation header followed by the payload.
    #[must_use]
    pub fn into_bytes(self) -> Vec<u8> {
        self.buf
    }

    /// Pad with zeros so that the payload offset is a multiple of `n`.
    fn align(&mut self, n: usize) {
        let offset = self.buf.len() - ENCAPSULATION_LEN;
        let padding = (n - offset % n) % n;
        self.buf.resize(self.buf.len() + padding, 0);
    }

    /// A length or element count as the `u32` CDR uses.
    ///
    /// # Panics
    ///
    /// If `len` does not fit in a `u32`: CDR cannot represent such a string or sequence.
    fn write_len(&mut self, len: usize) {
        let len = u32::try_from(len).expect("CDR lengths and counts must fit in a u32");
        self.write_u32(len);
    }

    /// A `uint8` (or `byte`).
    pub fn write_u8(&mut self, v: u8) {
        self.buf.push(v);
    }

    /// A `bool`, as one byte 0 or 1.
    pub fn write_bool(&mut self, v: bool) {
        self.buf.push(u8::from(v));
    }

    /// A `uint16`, aligned to 2.
    pub fn write_u16(&mut self, v: u16) {
        self.align(2);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `uint64`, aligned to 8.
    pub fn write_u64(&mut self, v: u64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// An `int32`, aligned to 4.
    pub fn write_i32(&mut self, v: i32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `uint32`, aligned to 4.
    pub fn write_u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float32`, aligned to 4.
    pub fn write_f32(&mut self, v: f32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float64`, aligned to 8.
    pub fn write_f64(&mut self, v: f64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `string`: `u32` length including the terminating NUL, the UTF-8 bytes, the NUL.
    ///
    /// # Panics
    ///
    /// If the string is longer than `u32::MAX - 1` bytes.
    pub fn write_string(&mut self, v: &str) {
        self.write_len(v.len() + 1);
        self.buf.extend_from_slice(v.as_bytes());
        self.buf.push(0);
    }

    /// A `uint8[]`: `u32` count then the bytes.
    ///
    /// # Panics
    ///
    /// If there are more than `u32::MAX` bytes.
    pub fn write_u8_seq(&mut self, v: &[u8]) {
        self.write_len(v.len());
        self.buf.extend_from_slice(v);
    }

    /// A `uint16[]`: `u32` count then the values.
    ///
    /// # Panics
    ///
    /// If there are more than `u32::MAX` values.
    pub fn write_u16_seq(&mut self, v: &[u16]) {
        self.write_len(v.len());
        for &x in v {
            self.write_u16(x);
        }
    }

    /// A `float64[]`: `u32` count then the values, aligned to 8 when there is at least one.
    ///
    /// # Panics
    ///
    /// If there are more than `u32::MAX` values.
    pub fn write_f64_seq(&mut self, v: &[f64]) {
        self.write_len(v.len());
        if !v.is_empty() {
            self.align(8);
            for x in v {
                self.buf.extend_from_slice(&x.to_le_bytes());
            }
        }
    }

    /// A `string[]`: `u32` count then each string.
    ///
    /// # Panics
    ///
    /// If there are more than `u32::MAX` strings.
    pub fn write_string_seq(&mut self, v: &[String]) {
        self.write_len(v.len());
        for s in v {
            self.write_string(s);
        }
    }

    /// A sequence of messages: `u32` count then each message.
    ///
    /// # Panics
    ///
    /// If there are more than `u32::MAX` messages.
    pub fn write_seq<T: CdrMessage>(&mut self, v: &[T]) {
        self.write_len(v.len());
        for m in v {
            m.write_cdr(self);
        }
    }
}

/// A message that can be serialized to CDR.
pub trait CdrMessage {
    /// Write the fields of the message, in `.msg` order, after what `w` already holds.
    fn write_cdr(&self, w: &mut CdrWriter);

    /// The complete serialized message: encapsulation header `00 01 00 00`, then the payload.
    #[must_use]
    fn to_cdr(&self) -> Vec<u8> {
        let mut w = CdrWriter::new();
        self.write_cdr(&mut w);
        w.into_bytes()
    }
}

/// A message type with its names and definition texts, all derived from its `.msg` file.
pub trait RosMessage: CdrMessage + CdrDecode {
    /// Type name, e.g. `geometry_msgs/msg/WrenchStamped` (also the MCAP schema name).
    const TYPE_NAME: &'static str;
    /// DDS type name, e.g. `geometry_msgs::msg::dds_::WrenchStamped_`.
    const DDS_TYPE_NAME: &'static str;
    /// The `.msg` file's text.
    const DEFINITION: &'static str;
    /// Complete `ros2msg` definition with its dependencies, as rosbag2 writes it.
    const SCHEMA: &'static str;
}

/// Why a CDR buffer could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CdrError {
    /// The buffer ended before the field at payload offset `offset`, which needs `needed` bytes.
    UnexpectedEnd {
        /// Payload offset (after the encapsulation header) where the field starts.
        offset: usize,
        /// Bytes the field needs.
        needed: usize,
    },
    /// The encapsulation identifier is not plain CDR (`00 00` big or `00 01` little endian).
    UnsupportedEncapsulation([u8; 2]),
    /// A string has length 0 (no room for the terminating NUL) or does not end with NUL.
    UnterminatedString {
        /// Payload offset of the string's length field.
        offset: usize,
    },
    /// A string is not valid UTF-8.
    InvalidUtf8 {
        /// Payload offset of the string's length field.
        offset: usize,
    },
}

impl fmt::Display for CdrError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::UnexpectedEnd { offset, needed } => write!(
                f,
                "CDR buffer ends before the {needed} byte(s) needed at payload offset {offset}"
            ),
            Self::UnsupportedEncapsulation([a, b]) => write!(
                f,
                "unsupported CDR encapsulation {a:02x} {b:02x} (expected plain CDR: 00 00 or 00 01)"
            ),
            Self::UnterminatedString { offset } => {
                write!(
                    f,
                    "CDR string at payload offset {offset} is not NUL-terminated"
                )
            }
            Self::InvalidUtf8 { offset } => {
                write!(
                    f,
                    "CDR string at payload offset {offset} is not valid UTF-8"
                )
            }
        }
    }
}

impl std::error::Error for CdrError {}

/// Reads plain CDR (XCDR1, either byte order) from a buffer that starts with the encapsulation
/// header. The two option bytes of the header and any bytes after the last field (such as the
/// end padding some writers add) are ignored.
#[derive(Debug, Clone)]
pub struct CdrReader<'a> {
    payload: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl<'a> CdrReader<'a> {
    /// A reader for `bytes`, which must start with the encapsulation header of plain CDR.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if `bytes` is shorter than the header,
    /// [`CdrError::UnsupportedEncapsulation`] if it is not plain CDR (`00 00` or `00 01`).
    pub fn new(bytes: &'a [u8]) -> Result<Self, CdrError> {
        let Some((header, payload)) = bytes.split_first_chunk::<ENCAPSULATION_LEN>() else {
            return Err(CdrError::UnexpectedEnd {
                offset: 0,
                needed: ENCAPSULATION_LEN,
            });
        };
        let big_endian = match [header[0], header[1]] {
            [0x00, 0x00] => true,
            [0x00, 0x01] => false,
            other => return Err(CdrError::UnsupportedEncapsulation(other)),
        };
        Ok(Self {
            payload,
            pos: 0,
            big_endian,
        })
    }

    /// Skip padding so that the payload offset is a multiple of `n`.
    fn align(&mut self, n: usize) -> Result<(), CdrError> {
        let padding = (n - self.pos % n) % n;
        self.take(padding).map(|_| ())
    }

    /// The next `n` bytes.
    fn take(&mut self, n: usize) -> Result<&'a [u8], CdrError> {
        let end = self
            .pos
            .checked_add(n)
            .filter(|&end| end <= self.payload.len())
            .ok_or(CdrError::UnexpectedEnd {
                offset: self.pos,
                needed: n,
            })?;
        let bytes = &self.payload[self.pos..end];
        self.pos = end;
        Ok(bytes)
    }

    /// The next `N` bytes, aligned to `N`, in little-endian order.
    fn take_le<const N: usize>(&mut self) -> Result<[u8; N], CdrError> {
        self.align(N)?;
        let mut raw = [0; N];
        raw.copy_from_slice(self.take(N)?);
        if self.big_endian {
            raw.reverse();
        }
        Ok(raw)
    }

    /// A `uint8` (or `byte`).
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first.
    pub fn read_u8(&mut self) -> Result<u8, CdrError> {
        self.take(1).map(|b| b[0])
    }

    /// A `bool`: any nonzero byte is true.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first.
    pub fn read_bool(&mut self) -> Result<bool, CdrError> {
        self.read_u8().map(|b| b != 0)
    }

    /// A `uint16`.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first.
    pub fn read_u16(&mut self) -> Result<u16, CdrError> {
        self.take_le().map(u16::from_le_bytes)
    }

    /// A `uint64`.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first.
    pub fn read_u64(&mut self) -> Result<u64, CdrError> {
        self.take_le().map(u64::from_le_bytes)
    }

    /// A `float32`.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first.
    pub fn read_f32(&mut self) -> Result<f32, CdrError> {
        self.take_le().map(f32::from_le_bytes)
    }

    /// An `int32`.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first.
    pub fn read_i32(&mut self) -> Result<i32, CdrError> {
        self.take_le().map(i32::from_le_bytes)
    }

    /// A `uint32`.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first.
    pub fn read_u32(&mut self) -> Result<u32, CdrError> {
        self.take_le().map(u32::from_le_bytes)
    }

    /// A `float64`.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first.
    pub fn read_f64(&mut self) -> Result<f64, CdrError> {
        self.take_le().map(f64::from_le_bytes)
    }

    /// A sequence count, checked against the bytes left so that a corrupt count cannot
    /// trigger a huge allocation: each element takes at least `min_element_len` bytes.
    fn read_count(&mut self, min_element_len: usize) -> Result<usize, CdrError> {
        let count = self.read_u32()? as usize;
        let left = self.payload.len() - self.pos;
        if count.saturating_mul(min_element_len) > left {
            return Err(CdrError::UnexpectedEnd {
                offset: self.pos,
                needed: count.saturating_mul(min_element_len),
            });
        }
        Ok(count)
    }

    /// A `string`.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first, [`CdrError::UnterminatedString`] or
    /// [`CdrError::InvalidUtf8`] for a malformed string.
    pub fn read_string(&mut self) -> Result<String, CdrError> {
        let len = self.read_u32()? as usize;
        let offset = self.pos - 4;
        let bytes = self.take(len)?;
        let Some((0, text)) = bytes.split_last() else {
            return Err(CdrError::UnterminatedString { offset });
        };
        String::from_utf8(text.to_vec()).map_err(|_| CdrError::InvalidUtf8 { offset })
    }

    /// A `uint8[]`.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first.
    pub fn read_u8_seq(&mut self) -> Result<Vec<u8>, CdrError> {
        let count = self.read_count(1)?;
        self.take(count).map(<[u8]>::to_vec)
    }

    /// A `uint16[]`.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first.
    pub fn read_u16_seq(&mut self) -> Result<Vec<u16>, CdrError> {
        let count = self.read_count(2)?;
        (0..count).map(|_| self.read_u16()).collect()
    }

    /// A sequence of messages.
    ///
    /// # Errors
    ///
    /// Any [`CdrError`] of the elements read.
    pub fn read_seq<T: CdrDecode>(&mut self) -> Result<Vec<T>, CdrError> {
        // Every message takes at least one byte (messages without fields are not sent).
        let count = self.read_count(1)?;
        (0..count).map(|_| T::read_cdr(self)).collect()
    }

    /// A `float64[]`.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first.
    pub fn read_f64_seq(&mut self) -> Result<Vec<f64>, CdrError> {
        let count = self.read_count(8)?;
        (0..count).map(|_| self.read_f64()).collect()
    }

    /// A `string[]`.
    ///
    /// # Errors
    ///
    /// [`CdrError::UnexpectedEnd`] if the buffer ends first, [`CdrError::UnterminatedString`] or
    /// [`CdrError::InvalidUtf8`] for a malformed string.
    pub fn read_string_seq(&mut self) -> Result<Vec<String>, CdrError> {
        let count = self.read_count(5)?;
        (0..count).map(|_| self.read_string()).collect()
    }
}

/// A message that can be deserialized from CDR.
pub trait CdrDecode: Sized {
    /// Read the fields of the message, in `.msg` order.
    ///
    /// # Errors
    ///
    /// Any [`CdrError`] of the fields read.
    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, CdrError>;

    /// Decode a complete serialized message (encapsulation header included).
    ///
    /// # Errors
    ///
    /// Any [`CdrError`]: not plain CDR, too short, or a malformed string.
    fn from_cdr(bytes: &[u8]) -> Result<Self, CdrError> {
        let mut r = CdrReader::new(bytes)?;
        Self::read_cdr(&mut r)
    }
}

include!(concat!(env!("OUT_DIR"), "/msgs.rs"));

impl Time {
    /// The time `t` seconds after zero, floored to whole nanoseconds.
    ///
    /// Negative and NaN inputs give zero; times past `i32::MAX` seconds saturate at
    /// `{sec: i32::MAX, nanosec: 999_999_999}`. The nanoseconds are computed from `t * 1e9`, so
    /// that e.g. `1.7` gives `{sec: 1, nanosec: 700_000_000}`.
    #[must_use]
    pub fn from_seconds(t: f64) -> Time {
        const NANOS_PER_SEC: u64 = 1_000_000_000;
        // (i32::MAX + 1) seconds in nanoseconds, exactly representable as an f64.
        const LIMIT: f64 = 2_147_483_648e9;
        if t.is_nan() || t <= 0.0 {
            return Time::default();
        }
        let nanos = (t * 1e9).floor();
        if nanos >= LIMIT {
            return Time {
                sec: i32::MAX,
                nanosec: 999_999_999,
            };
        }
        // In [0, LIMIT): the casts below neither truncate nor wrap.
        let nanos = nanos as u64;
        Time {
            sec: (nanos / NANOS_PER_SEC) as i32,
            nanosec: (nanos % NANOS_PER_SEC) as u32,
        }
    }
}

/// One point of the strain cloud built by [`point_cloud_xyz_fields`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StrainPoint {
    /// x coordinate.
    pub x: f32,
    /// y coordinate.
    pub y: f32,
    /// z coordinate.
    pub z: f32,
    /// Equivalent plastic strain.
    pub plastic_strain: f32,
    /// von Mises stress.
    pub von_mises: f32,
}

/// Bytes per point of the cloud built by [`point_cloud_xyz_fields`]: five `f32`.
const STRAIN_POINT_STEP: u32 = 20;

/// An unordered cloud (`height` 1, `width` = number of points) of little-endian `FLOAT32`
/// fields `x`, `y`, `z`, `plastic_strain` and `von_mises` at offsets 0, 4, 8, 12 and 16
/// (`point_step` 20). `is_dense` is true unless a value is NaN or infinite.
///
/// # Panics
///
/// If there are more than `u32::MAX / 20` points (the row would not fit in `row_step`).
#[must_use]
pub fn point_cloud_xyz_fields(header: Header, points: &[StrainPoint]) -> PointCloud2 {
    let width = u32::try_from(points.len())
        .ok()
        .filter(|&w| w <= u32::MAX / STRAIN_POINT_STEP)
        .expect("a PointCloud2 row holds at most u32::MAX / 20 strain points");
    let names = ["x", "y", "z", "plastic_strain", "von_mises"];
    let fields = names
        .iter()
        .zip((0..).step_by(4))
        .map(|(name, offset)| PointField {
            name: (*name).to_owned(),
            offset,
            datatype: PointField::FLOAT32,
            count: 1,
        })
        .collect();
    let mut data = Vec::with_capacity(points.len() * STRAIN_POINT_STEP as usize);
    let mut is_dense = true;
    for p in points {
        for v in [p.x, p.y, p.z, p.plastic_strain, p.von_mises] {
            is_dense &= v.is_finite();
            data.extend_from_slice(&v.to_le_bytes());
        }
    }
    PointCloud2 {
        header,
        height: 1,
        width,
        fields,
        is_bigendian: false,
        point_step: STRAIN_POINT_STEP,
        row_step: STRAIN_POINT_STEP * width,
        data,
        is_dense,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::{BTreeMap, BTreeSet};

    /// The 80-`=` delimiter line, without its newline.
    const SEPARATOR: &str =
        "================================================================================";

    /// Every `.msg` (`kind` "msg") or `.srv` file under `ros_node/msg`, read here:
    /// `pkg/Type` -> text.
    fn msg_files(kind: &str) -> BTreeMap<String, String> {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("msg");
        let mut files = BTreeMap::new();
        for pkg in std::fs::read_dir(&root).unwrap() {
            let pkg = pkg.unwrap().path();
            let Ok(entries) = std::fs::read_dir(pkg.join(kind)) else {
                continue;
            };
            for f in entries {
                let f = f.unwrap().path();
                let name = format!(
                    "{}/{}",
                    pkg.file_name().unwrap().to_str().unwrap(),
                    f.file_stem().unwrap().to_str().unwrap()
                );
                files.insert(name, std::fs::read_to_string(&f).unwrap());
            }
        }
        files
    }

    /// The sections of a schema: (`MSG:` name, or `None` for the top level; text).
    fn sections(schema: &str) -> Vec<(Option<&str>, &str)> {
        let delimiter = format!("\n{SEPARATOR}\nMSG: ");
        let mut parts = schema.split(delimiter.as_str());
        let mut out = vec![(None, parts.next().unwrap_or_default())];
        for part in parts {
            let (name, text) = part
                .split_once('\n')
                .expect("MSG: line ends with a newline");
            out.push((Some(name), text));
        }
        out
    }

    /// (type name, DDS type name, definition, schema) of a message type.
    fn names<T: RosMessage>() -> (&'static str, &'static str, &'static str, &'static str) {
        (T::TYPE_NAME, T::DDS_TYPE_NAME, T::DEFINITION, T::SCHEMA)
    }

    /// The types of the topics.
    fn topic_types() -> [(&'static str, &'static str, &'static str, &'static str); 6] {
        [
            names::<WrenchStamped>(),
            names::<JointState>(),
            names::<PointCloud2>(),
            names::<Clock>(),
            names::<Float64>(),
            names::<MarkerArray>(),
        ]
    }

    /// Each derived schema is made of standard definitions: its first section is the type's
    /// `.msg` file and every further section, named once after a delimiter, is the file of
    /// the dependency it names.
    #[test]
    fn schemas_are_the_msg_files_of_the_type_and_its_dependencies() {
        let files = msg_files("msg");
        assert_eq!(files.len(), 23);
        for (type_name, dds, definition, schema) in topic_types() {
            let (pkg, ty) = type_name.split_once("/msg/").unwrap();
            let short = format!("{pkg}/{ty}");
            assert_eq!(dds, format!("{pkg}::msg::dds_::{ty}_"));
            assert_eq!(definition, files[&short], "{type_name}");
            let sections = sections(schema);
            assert_eq!(sections[0].1, files[&short], "{type_name}");
            let names: Vec<&str> = sections[1..].iter().filter_map(|(n, _)| *n).collect();
            let unique: BTreeSet<&str> = names.iter().copied().collect();
            assert_eq!(names.len(), unique.len(), "{type_name}: {names:?}");
            for (name, text) in &sections[1..] {
                let name = name.expect("dependency sections are named");
                assert_eq!(*text, files[name], "{type_name}: {name}");
                let block = format!("\n{SEPARATOR}\nMSG: {name}\n{text}");
                assert_eq!(schema.matches(block.as_str()).count(), 1);
            }
            // No definition text ends up without its delimiter: every `=` line is exactly
            // 80 long and followed by a `MSG: ` line.
            let lines: Vec<&str> = schema.lines().collect();
            for (i, line) in lines.iter().enumerate() {
                if line.starts_with("===") {
                    assert_eq!(*line, SEPARATOR);
                    assert_eq!(SEPARATOR.len(), 80);
                    assert!(lines[i + 1].starts_with("MSG: "), "{type_name}");
                    assert_eq!(lines[i - 1], "", "{type_name}: blank line before");
                }
            }
            assert!(schema.ends_with('\n'));
        }
    }

    /// Each service's request and response definitions are the parts of its `.srv` file,
    /// with the standard type names.
    #[test]
    fn services_are_their_srv_files() {
        fn parts<Q: RosMessage, R: RosMessage>() -> (String, String, String, String) {
            let (pkg, ty) = Q::TYPE_NAME.split_once("/srv/").unwrap();
            let name = format!("{pkg}/{}", ty.trim_end_matches("_Request"));
            assert_eq!(
                R::TYPE_NAME,
                format!("{pkg}/srv/{}_Response", &name[pkg.len() + 1..])
            );
            assert_eq!(
                Q::DDS_TYPE_NAME,
                format!("{pkg}::srv::dds_::{}_Request_", &name[pkg.len() + 1..])
            );
            let text = format!("{}---\n{}", Q::DEFINITION, R::DEFINITION);
            (name, text, Q::SCHEMA.to_owned(), R::SCHEMA.to_owned())
        }
        let files = msg_files("srv");
        let services = [
            parts::<GetSimulatorFeaturesRequest, GetSimulatorFeaturesResponse>(),
            parts::<GetSimulationStateRequest, GetSimulationStateResponse>(),
            parts::<SetSimulationStateRequest, SetSimulationStateResponse>(),
            parts::<ResetSimulationRequest, ResetSimulationResponse>(),
            parts::<StepSimulationRequest, StepSimulationResponse>(),
        ];
        assert_eq!(files.len(), services.len());
        let msgs = msg_files("msg");
        for (name, text, _, response_schema) in &services {
            assert_eq!(*text, files[name], "{name}");
            for (dep, section) in &sections(response_schema)[1..] {
                assert_eq!(*section, msgs[dep.unwrap()], "{name}: {dep:?}");
            }
        }
        assert_eq!(StepSimulationRequest::default().steps, 1);
        assert_eq!(ResultMsg::RESULT_OK, 1);
    }

    /// The goal, result and feedback of each action are the parts of its `.action` file, with
    /// the DDS type names of rosidl (`pkg::action::dds_::Action_Goal_`).
    #[test]
    fn actions_are_their_action_files() {
        let files = msg_files("action");
        assert_eq!(files.len(), 1);
        let text = format!(
            "{}---\n{}---\n{}",
            SimulateStepsGoal::DEFINITION,
            SimulateStepsResult::DEFINITION,
            SimulateStepsFeedback::DEFINITION
        );
        assert_eq!(text, files["simulation_interfaces/SimulateSteps"]);
        for (name, dds) in [
            (
                SimulateStepsGoal::TYPE_NAME,
                SimulateStepsGoal::DDS_TYPE_NAME,
            ),
            (
                SimulateStepsResult::TYPE_NAME,
                SimulateStepsResult::DDS_TYPE_NAME,
            ),
            (
                SimulateStepsFeedback::TYPE_NAME,
                SimulateStepsFeedback::DDS_TYPE_NAME,
            ),
        ] {
            let (pkg, ty) = name.split_once("/action/").unwrap();
            assert_eq!(pkg, "simulation_interfaces");
            assert_eq!(dds, format!("{pkg}::action::dds_::{ty}_"));
        }
        assert_eq!(
            SimulateStepsGoal::TYPE_NAME,
            "simulation_interfaces/action/SimulateSteps_Goal"
        );
        // The result's one dependency is the standard Result message.
        let msgs = msg_files("msg");
        let sections = sections(SimulateStepsResult::SCHEMA);
        assert_eq!(sections.len(), 2);
        assert_eq!(sections[1].0, Some("simulation_interfaces/Result"));
        assert_eq!(sections[1].1, msgs["simulation_interfaces/Result"]);
        let feedback = SimulateStepsFeedback {
            completed_steps: 3,
            remaining_steps: 5,
        };
        assert_eq!(
            SimulateStepsFeedback::from_cdr(&feedback.to_cdr()),
            Ok(feedback)
        );
        assert_eq!(SimulateStepsGoal::default().steps, 0);
    }

    /// The dependencies in rosbag2's order: depth first, each level sorted by qualified name.
    #[test]
    fn schema_dependency_order() {
        let deps = |schema: &str| -> Vec<String> {
            sections(schema)[1..]
                .iter()
                .filter_map(|(n, _)| n.map(str::to_owned))
                .collect()
        };
        assert_eq!(
            deps(WrenchStamped::SCHEMA),
            [
                "geometry_msgs/Wrench",
                "geometry_msgs/Vector3",
                "std_msgs/Header",
                "builtin_interfaces/Time"
            ]
        );
        assert_eq!(
            deps(JointState::SCHEMA),
            ["std_msgs/Header", "builtin_interfaces/Time"]
        );
        assert_eq!(
            deps(PointCloud2::SCHEMA),
            [
                "sensor_msgs/PointField",
                "std_msgs/Header",
                "builtin_interfaces/Time"
            ]
        );
        assert_eq!(deps(Clock::SCHEMA), ["builtin_interfaces/Time"]);
        assert!(deps(Float64::SCHEMA).is_empty());
        assert_eq!(
            deps(MarkerArray::SCHEMA),
            [
                "visualization_msgs/Marker",
                "builtin_interfaces/Duration",
                "geometry_msgs/Point",
                "geometry_msgs/Pose",
                "geometry_msgs/Quaternion",
                "geometry_msgs/Vector3",
                "sensor_msgs/CompressedImage",
                "std_msgs/Header",
                "builtin_interfaces/Time",
                "std_msgs/ColorRGBA",
                "visualization_msgs/MeshFile",
                "visualization_msgs/UVCoordinate",
            ]
        );
    }

    #[test]
    fn schema_first_lines() {
        assert_eq!(
            WrenchStamped::SCHEMA.lines().next(),
            Some("# A wrench with reference coordinate frame and timestamp")
        );
        assert_eq!(MarkerArray::SCHEMA.lines().next(), Some("Marker[] markers"));
        assert_eq!(Float64::SCHEMA, Float64::DEFINITION);
        assert!(!MarkerArray::SCHEMA.contains("ARROW_STRIP"));
        assert!(MarkerArray::SCHEMA.contains("[0, 10e9)"));
        for (_, _, _, schema) in topic_types() {
            assert!(schema.lines().all(|l| l == l.trim_end()), "trailing blanks");
        }
    }

    #[test]
    fn constants_come_from_the_msg_files() {
        assert_eq!(PointField::FLOAT32, 7);
        assert_eq!(Marker::LINE_STRIP, 4);
        assert_eq!(Marker::MODIFY, Marker::ADD);
        assert_eq!(Marker::DELETEALL, 3);
    }

    /// Float64 {data: 1.5}: header, then the f64 at payload offset 0 (already 8-aligned).
    #[test]
    fn float64_bytes() {
        let mut expected = vec![0x00, 0x01, 0x00, 0x00];
        expected.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0xf8, 0x3f]);
        assert_eq!(Float64 { data: 1.5 }.to_cdr(), expected);
    }

    /// Clock {1 s, 2 ns}: int32 sec at offset 0, uint32 nanosec at offset 4.
    #[test]
    fn clock_bytes() {
        let clock = Clock {
            clock: Time { sec: 1, nanosec: 2 },
        };
        assert_eq!(
            clock.to_cdr(),
            [0x00, 0x01, 0x00, 0x00, 1, 0, 0, 0, 2, 0, 0, 0]
        );
    }

    /// An empty string is its length 1 and the NUL alone.
    #[test]
    fn empty_string_bytes() {
        let mut w = CdrWriter::new();
        w.write_string("");
        assert_eq!(w.into_bytes(), [0x00, 0x01, 0x00, 0x00, 1, 0, 0, 0, 0]);
    }

    /// WrenchStamped, frame "a". Payload offsets:
    /// 0 sec, 4 nanosec, 8 length 2, 12 'a', 13 NUL, 14..16 padding to 8,
    /// 16..64 force x, y, z and torque x, y, z as f64.
    #[test]
    fn wrench_stamped_bytes() {
        let msg = WrenchStamped {
            header: Header {
                stamp: Time { sec: 3, nanosec: 4 },
                frame_id: "a".into(),
            },
            wrench: Wrench {
                force: Vector3 {
                    x: 1.0,
                    y: 2.0,
                    z: 3.0,
                },
                torque: Vector3 {
                    x: 4.0,
                    y: 5.0,
                    z: 6.0,
                },
            },
        };
        let mut expected = vec![0x00, 0x01, 0x00, 0x00];
        expected.extend_from_slice(&[3, 0, 0, 0, 4, 0, 0, 0, 2, 0, 0, 0, b'a', 0, 0, 0]);
        for v in [1.0f64, 2.0, 3.0, 4.0, 5.0, 6.0] {
            expected.extend_from_slice(&v.to_le_bytes());
        }
        let bytes = msg.to_cdr();
        assert_eq!(bytes.len(), 4 + 64);
        assert_eq!(bytes, expected);
    }

    /// JointState, empty frame, names "j1" "j2", two positions, no velocity, one effort.
    /// Payload offsets: 0 sec, 4 nanosec, 8 length 1, 12 NUL, 13..16 padding,
    /// 16 name count 2, 20 length 3, 24 "j1\0", 27 padding, 28 length 3, 32 "j2\0",
    /// 35 padding, 36 position count 2, 40 and 48 positions (8-aligned already),
    /// 56 velocity count 0 (no padding for an empty sequence), 60 effort count 1, 64 effort.
    #[test]
    fn joint_state_bytes() {
        let msg = JointState {
            header: Header::default(),
            name: vec!["j1".into(), "j2".into()],
            position: vec![0.5, -1.0],
            velocity: vec![],
            effort: vec![2.0],
        };
        let mut expected = vec![0x00, 0x01, 0x00, 0x00];
        expected.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0]);
        expected.extend_from_slice(&[2, 0, 0, 0]);
        expected.extend_from_slice(&[3, 0, 0, 0, b'j', b'1', 0, 0]);
        expected.extend_from_slice(&[3, 0, 0, 0, b'j', b'2', 0, 0]);
        expected.extend_from_slice(&[2, 0, 0, 0]);
        expected.extend_from_slice(&0.5f64.to_le_bytes());
        expected.extend_from_slice(&(-1.0f64).to_le_bytes());
        expected.extend_from_slice(&[0, 0, 0, 0, 1, 0, 0, 0]);
        expected.extend_from_slice(&2.0f64.to_le_bytes());
        assert_eq!(msg.to_cdr(), expected);
    }

    /// PointCloud2 with one field and two data bytes. Payload offsets: 0 sec, 4 nanosec,
    /// 8 length 1, 12 NUL, 16 height, 20 width, 24 field count 1, 28 name length 2,
    /// 32 "x\0", 34 padding, 36 offset, 40 datatype, 41 padding, 44 count, 48 is_bigendian,
    /// 49 padding, 52 point_step, 56 row_step, 60 data count 2, 64 data, 66 is_dense.
    #[test]
    fn point_cloud2_bytes() {
        let msg = PointCloud2 {
            header: Header::default(),
            height: 1,
            width: 2,
            fields: vec![PointField {
                name: "x".into(),
                offset: 0,
                datatype: PointField::UINT8,
                count: 1,
            }],
            is_bigendian: false,
            point_step: 1,
            row_step: 2,
            data: vec![7, 9],
            is_dense: true,
        };
        let mut expected = vec![0x00, 0x01, 0x00, 0x00];
        expected.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0]);
        expected.extend_from_slice(&[1, 0, 0, 0, 2, 0, 0, 0, 1, 0, 0, 0]);
        expected.extend_from_slice(&[2, 0, 0, 0, b'x', 0, 0, 0, 0, 0, 0, 0]);
        expected.extend_from_slice(&[2, 0, 0, 0, 1, 0, 0, 0]);
        expected.extend_from_slice(&[0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
        expected.extend_from_slice(&[2, 0, 0, 0, 7, 9, 1]);
        assert_eq!(msg.to_cdr(), expected);
    }

    /// A LINE_STRIP marker with one point, checked field by field at its payload offsets.
    #[test]
    fn marker_array_layout() {
        let marker = Marker {
            header: Header {
                stamp: Time { sec: 1, nanosec: 0 },
                frame_id: "w".into(),
            },
            ns: "n".into(),
            id: 7,
            r#type: Marker::LINE_STRIP,
            action: Marker::ADD,
            scale: Vector3 {
                x: 0.01,
                ..Vector3::default()
            },
            color: ColorRGBA {
                r: 1.0,
                g: 0.0,
                b: 0.0,
                a: 1.0,
            },
            points: vec![Point {
                x: 1.0,
                y: 2.0,
                z: 3.0,
            }],
            ..Marker::default()
        };
        let bytes = MarkerArray {
            markers: vec![marker],
        }
        .to_cdr();
        let p = &bytes[4..];
        let u32_at = |o: usize| u32::from_le_bytes(p[o..o + 4].try_into().unwrap());
        let f64_at = |o: usize| f64::from_le_bytes(p[o..o + 8].try_into().unwrap());
        let f32_at = |o: usize| f32::from_le_bytes(p[o..o + 4].try_into().unwrap());
        // 0 marker count, 4 sec, 8 nanosec, 12 frame length 2, 16 "w\0", 20 ns length 2,
        // 24 "n\0", 28 id, 32 type, 36 action, 40 pose (7 f64, 40..96), 96 scale (3 f64),
        // 120 color (4 f32), 136 lifetime, 144 frame_locked, 148 point count, 152 point.
        assert_eq!(u32_at(0), 1);
        assert_eq!(u32_at(4), 1);
        assert_eq!(u32_at(12), 2);
        assert_eq!(&p[16..18], b"w\0");
        assert_eq!(&p[24..26], b"n\0");
        assert_eq!(u32_at(28), 7);
        assert_eq!(u32_at(32), 4);
        assert_eq!(u32_at(36), 0);
        assert_eq!(f64_at(88), 1.0, "orientation w");
        assert_eq!(f64_at(96), 0.01, "scale x");
        assert_eq!(f32_at(120), 1.0);
        assert_eq!(f32_at(132), 1.0);
        assert_eq!(p[144], 0, "frame_locked");
        assert_eq!(u32_at(148), 1);
        assert_eq!(f64_at(152), 1.0);
        assert_eq!(f64_at(168), 3.0);
        // 176 colors count 0, 180 texture_resource "", 185 padding, 188 texture header
        // (sec 188, nanosec 192, frame 196), 201 padding, 204 format "", 212 data count 0,
        // 216 uv count 0, 220 text "", 228 mesh_resource "", 236 filename "", 244 data 0,
        // 248 mesh_use_embedded_materials.
        assert_eq!(u32_at(176), 0);
        assert_eq!(u32_at(180), 1);
        assert_eq!(u32_at(196), 1);
        assert_eq!(u32_at(204), 1);
        assert_eq!(u32_at(212), 0);
        assert_eq!(u32_at(216), 0);
        assert_eq!(u32_at(220), 1);
        assert_eq!(u32_at(228), 1);
        assert_eq!(u32_at(236), 1);
        assert_eq!(u32_at(244), 0);
        assert_eq!(p.len(), 249);
    }

    #[test]
    fn round_trips() {
        let ws = WrenchStamped {
            header: Header {
                stamp: Time {
                    sec: -5,
                    nanosec: 999_999_999,
                },
                frame_id: "tool_flange/ünï".into(),
            },
            wrench: Wrench {
                force: Vector3 {
                    x: -1e6,
                    y: f64::MIN_POSITIVE,
                    z: 0.25,
                },
                torque: Vector3 {
                    x: f64::MAX,
                    y: -0.0,
                    z: 3.5,
                },
            },
        };
        assert_eq!(WrenchStamped::from_cdr(&ws.to_cdr()), Ok(ws));

        let js = JointState {
            header: Header {
                stamp: Time::from_seconds(12.25),
                frame_id: "base".into(),
            },
            name: vec!["ram".into(), "".into(), "roll_2".into()],
            position: vec![0.1, 0.2, 0.3],
            velocity: vec![],
            effort: vec![-4.0, 5.0, 6.0],
        };
        assert_eq!(JointState::from_cdr(&js.to_cdr()), Ok(js.clone()));
        let empty = JointState::default();
        assert_eq!(JointState::from_cdr(&empty.to_cdr()), Ok(empty));

        let clock = Clock {
            clock: Time {
                sec: i32::MAX,
                nanosec: 1,
            },
        };
        assert_eq!(Clock::from_cdr(&clock.to_cdr()), Ok(clock));

        let f = Float64 { data: -2.5e-300 };
        assert_eq!(Float64::from_cdr(&f.to_cdr()), Ok(f));
    }

    /// The same Float64 and Clock in big-endian CDR (`00 00` encapsulation).
    #[test]
    fn reads_big_endian() {
        let mut bytes = vec![0x00, 0x00, 0x00, 0x00];
        bytes.extend_from_slice(&1.5f64.to_be_bytes());
        assert_eq!(Float64::from_cdr(&bytes), Ok(Float64 { data: 1.5 }));
        let bytes = [0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 2];
        assert_eq!(
            Clock::from_cdr(&bytes),
            Ok(Clock {
                clock: Time { sec: 1, nanosec: 2 }
            })
        );
    }

    #[test]
    fn decode_errors() {
        assert_eq!(
            Float64::from_cdr(&[0, 1]),
            Err(CdrError::UnexpectedEnd {
                offset: 0,
                needed: 4
            })
        );
        assert_eq!(
            Float64::from_cdr(&[0, 1, 0, 0, 1, 2, 3]),
            Err(CdrError::UnexpectedEnd {
                offset: 0,
                needed: 8
            })
        );
        assert_eq!(
            Float64::from_cdr(&[0, 3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]),
            Err(CdrError::UnsupportedEncapsulation([0, 3]))
        );
        // Header with a string of length 2 whose last byte is not NUL.
        let bad = [0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 2, 0, 0, 0, b'a', b'b'];
        assert_eq!(
            JointState::from_cdr(&bad),
            Err(CdrError::UnterminatedString { offset: 8 })
        );
        let zero_len = [0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
        assert_eq!(
            JointState::from_cdr(&zero_len),
            Err(CdrError::UnterminatedString { offset: 8 })
        );
        let not_utf8 = [0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 2, 0, 0, 0, 0xff, 0];
        assert_eq!(
            JointState::from_cdr(&not_utf8),
            Err(CdrError::InvalidUtf8 { offset: 8 })
        );
        // A name count of u32::MAX with nothing behind it fails before allocating.
        let mut huge = JointState::default().to_cdr();
        huge.truncate(4 + 16);
        huge.extend_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(
            JointState::from_cdr(&huge),
            Err(CdrError::UnexpectedEnd { offset: 20, .. })
        ));
        let msg = CdrError::UnexpectedEnd {
            offset: 3,
            needed: 8,
        }
        .to_string();
        assert!(msg.contains("offset 3"), "{msg}");
    }

    #[test]
    fn time_from_seconds() {
        assert_eq!(Time::from_seconds(0.0), Time::default());
        assert_eq!(
            Time::from_seconds(1.5),
            Time {
                sec: 1,
                nanosec: 500_000_000
            }
        );
        assert_eq!(
            Time::from_seconds(1.7),
            Time {
                sec: 1,
                nanosec: 700_000_000
            }
        );
        assert_eq!(
            Time::from_seconds(2.000_000_000_9),
            Time { sec: 2, nanosec: 0 }
        );
        assert_eq!(Time::from_seconds(-3.0), Time::default());
        assert_eq!(Time::from_seconds(f64::NAN), Time::default());
        let max = Time {
            sec: i32::MAX,
            nanosec: 999_999_999,
        };
        assert_eq!(Time::from_seconds(1e12), max);
        assert_eq!(Time::from_seconds(f64::INFINITY), max);
        assert_eq!(Time::from_seconds(2_147_483_647.25).sec, i32::MAX);
    }

    #[test]
    fn strain_point_cloud() {
        let header = Header {
            stamp: Time { sec: 2, nanosec: 0 },
            frame_id: "blank".into(),
        };
        let points = [
            StrainPoint {
                x: 1.0,
                y: 2.0,
                z: 3.0,
                plastic_strain: 0.1,
                von_mises: 250e6,
            },
            StrainPoint::default(),
        ];
        let cloud = point_cloud_xyz_fields(header.clone(), &points);
        assert_eq!(cloud.header, header);
        assert_eq!((cloud.height, cloud.width), (1, 2));
        assert_eq!((cloud.point_step, cloud.row_step), (20, 40));
        assert!(!cloud.is_bigendian);
        assert!(cloud.is_dense);
        let layout: Vec<(&str, u32, u8, u32)> = cloud
            .fields
            .iter()
            .map(|f| (f.name.as_str(), f.offset, f.datatype, f.count))
            .collect();
        assert_eq!(
            layout,
            [
                ("x", 0, 7, 1),
                ("y", 4, 7, 1),
                ("z", 8, 7, 1),
                ("plastic_strain", 12, 7, 1),
                ("von_mises", 16, 7, 1)
            ]
        );
        assert_eq!(cloud.data.len(), 40);
        assert_eq!(&cloud.data[4..8], &2.0f32.to_le_bytes());
        assert_eq!(&cloud.data[16..20], &250e6f32.to_le_bytes());
        assert!(cloud.data[20..].iter().all(|&b| b == 0));
        let nan = StrainPoint {
            von_mises: f32::NAN,
            ..StrainPoint::default()
        };
        assert!(!point_cloud_xyz_fields(Header::default(), &[nan]).is_dense);
        let empty = point_cloud_xyz_fields(Header::default(), &[]);
        assert_eq!((empty.width, empty.row_step, empty.data.len()), (0, 0, 0));
    }

    #[test]
    fn defaults_follow_the_msg_files() {
        assert_eq!(Quaternion::default().w, 1.0);
        assert_eq!(Pose::default().orientation, Quaternion::default());
        assert_eq!(Marker::default().r#type, Marker::ARROW);
        assert_eq!(CdrWriter::default().into_bytes(), CDR_LE_HEADER);
    }
}
