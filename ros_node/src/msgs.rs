//! The standard ROS 2 messages rkforge publishes, with their `ros2msg` schema texts for MCAP
//! (profile `ros2`, schema encoding `ros2msg`, message encoding `cdr`) and a small CDR codec.
//!
//! # Distribution and sources
//!
//! The definitions are those of **ROS 2 Humble** (`common_interfaces` 4.2.x to 4.9.x,
//! `rcl_interfaces` 1.2.x), byte for byte with their comments, because rosbag2 copies the
//! installed `.msg` files verbatim. Each text below names the file of `ros2/common_interfaces`
//! or `ros2/rcl_interfaces` it reproduces and where the text was taken from; where a file changed
//! after Humble, the Humble text is used and the later change is named.
//!
//! # Schema layout
//!
//! A `*_SCHEMA` constant is what rosbag2 (`LocalMessageDefinitionSource::get_full_text`, and the
//! `MessageDefinitionCache` of `rosbag2_storage_mcap` in Humble) writes: the top-level `.msg`
//! text, then for each dependency not yet written, depth first and in the sorted order of the
//! type names as spelled in the field declarations, a `\n`, a line of 80 `=`, a line
//! `MSG: pkg/Type` and that type's `.msg` text.
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

/// One line of 80 `=` characters that separates the definitions in a `ros2msg` schema.
macro_rules! separator_line {
    () => {
        "================================================================================\n"
    };
}

/// `builtin_interfaces/msg/Time.msg` of `ros2/rcl_interfaces`, Humble.
// Text: ros2/rcl_interfaces at commit b949fe767f61ef42dcce3a6445427b4cde93de96, with the Humble
// range `[0, 10e9)` that rcl_interfaces#139 (1.3.1, after Humble) changed to `[0, 1e9)`, as
// rendered at docs.ros.org/en/humble/p/builtin_interfaces/interfaces/msg/Time.html.
macro_rules! time_msg {
    () => {
        r"# This message communicates ROS Time defined here:
# https://design.ros2.org/articles/clock_and_time.html

# The seconds component, valid over all int32 values.
int32 sec

# The nanoseconds component, valid in the range [0, 10e9).
uint32 nanosec
"
    };
}

/// `builtin_interfaces/msg/Duration.msg` of `ros2/rcl_interfaces`, Humble.
// Text: docs.ros.org/en/humble/p/builtin_interfaces/interfaces/msg/Duration.html. The index
// holds only the later wording (commit 401fd11e4d8da7b25a0372c46d69c7d88da413b8).
macro_rules! duration_msg {
    () => {
        r"# Duration defines a period between two time points.
# Messages of this datatype are of ROS Time following this design:
# https://design.ros2.org/articles/clock_and_time.html

# Seconds component, range is valid over any possible int32 value.
int32 sec

# Nanoseconds component in the range of [0, 10e9).
uint32 nanosec
"
    };
}

/// `rosgraph_msgs/msg/Clock.msg` of `ros2/rcl_interfaces`.
// Text: ros2/rcl_interfaces at commit f82fdb0705f0b37dc61f3b73378aa04348f797fe.
macro_rules! clock_msg {
    () => {
        r"# This message communicates the current time.
#
# For more information, see https://design.ros2.org/articles/clock_and_time.html
builtin_interfaces/Time clock
"
    };
}

/// `std_msgs/msg/Header.msg` of `ros2/common_interfaces` (unchanged since Foxy).
// Text: foxglove/rosmsg-msgs-common `msgdefs/ros2jazzy/visualization_msgs/msg/Marker.msg`
// (commit 818032d86fa1475ef21a7e2c7e01b652e0ec0ad9), which embeds it; the index holds no
// upstream copy.
macro_rules! header_msg {
    () => {
        r"# Standard metadata for higher-level stamped data types.
# This is generally used to communicate timestamped data
# in a particular coordinate frame.

# Two-integer timestamp that is expressed as seconds and nanoseconds.
builtin_interfaces/Time stamp

# Transform frame with which this data is associated.
string frame_id
"
    };
}

/// `std_msgs/msg/Float64.msg` of `ros2/common_interfaces` (unchanged since Foxy).
// Text: docs.ros2.org/galactic/api/std_msgs/msg/Float64.html, with the blank line of verbatim
// copies. The one upstream copy in the index (commit 44ad8164566d8a4a10fdb9334c5f17883a5918f2)
// words the deprecation differently from every released page (Foxy to Jazzy) and is not used.
macro_rules! float64_msg {
    () => {
        r"# This was originally provided as an example message.
# It is deprecated as of Foxy
# It is recommended to create your own semantically meaningful message.
# However if you would like to continue using this please use the equivalent in example_msgs.

float64 data
"
    };
}

/// `std_msgs/msg/ColorRGBA.msg` of `ros2/common_interfaces`.
// Text: foxglove/rosmsg-msgs-common `msgdefs/ros2jazzy/visualization_msgs/msg/Marker.msg`
// (commit 818032d86fa1475ef21a7e2c7e01b652e0ec0ad9), which embeds it. The upstream copy in the index (commit 3450d09c01ee014a4b53ec75c0968675496cab8f)
// has `float32 a 1`, a default that Humble does not have.
macro_rules! color_rgba_msg {
    () => {
        r"float32 r
float32 g
float32 b
float32 a
"
    };
}

/// `geometry_msgs/msg/Vector3.msg` of `ros2/common_interfaces` (wording of
/// `common_interfaces#115`).
// Text: foxglove/rosmsg-msgs-common `msgdefs/ros2jazzy/visualization_msgs/msg/Marker.msg`
// (commit 818032d86fa1475ef21a7e2c7e01b652e0ec0ad9), which embeds it; the upstream copy in the index (commit 14dded94064948b524a08564815567bead24beab)
// is the older wording.
macro_rules! vector3_msg {
    () => {
        r"# This represents a vector in free space.

# This is semantically different than a point.
# A vector is always anchored at the origin.
# When a transform is applied to a vector, only the rotational component is applied.

float64 x
float64 y
float64 z
"
    };
}

/// `geometry_msgs/msg/Wrench.msg` of `ros2/common_interfaces` (unchanged since Foxy).
// Text: verbatim copies found through the code index, line for line as on docs.ros2.org
// (Galactic); the index holds no upstream copy.
macro_rules! wrench_msg {
    () => {
        r"# This represents force in free space, separated into its linear and angular parts.

Vector3  force
Vector3  torque
"
    };
}

/// `geometry_msgs/msg/WrenchStamped.msg` of `ros2/common_interfaces` (unchanged since Foxy).
// Text: docs.ros.org/en/jazzy/p/geometry_msgs/msg/WrenchStamped.html, with the blank line of
// verbatim copies; the index holds no upstream copy.
macro_rules! wrench_stamped_msg {
    () => {
        r"# A wrench with reference coordinate frame and timestamp

std_msgs/Header header
Wrench wrench
"
    };
}

/// `geometry_msgs/msg/Point.msg` of `ros2/common_interfaces` (unchanged since Foxy).
// Text: foxglove/rosmsg-msgs-common `msgdefs/ros2jazzy/visualization_msgs/msg/Marker.msg`
// (commit 818032d86fa1475ef21a7e2c7e01b652e0ec0ad9), which embeds it.
macro_rules! point_msg {
    () => {
        r"# This contains the position of a point in free space
float64 x
float64 y
float64 z
"
    };
}

/// `geometry_msgs/msg/Quaternion.msg` of `ros2/common_interfaces` (unchanged since Foxy).
// Text: foxglove/rosmsg-msgs-common `msgdefs/ros2jazzy/visualization_msgs/msg/Marker.msg`
// (commit 818032d86fa1475ef21a7e2c7e01b652e0ec0ad9), which embeds it.
macro_rules! quaternion_msg {
    () => {
        r"# This represents an orientation in free space in quaternion form.

float64 x 0
float64 y 0
float64 z 0
float64 w 1
"
    };
}

/// `geometry_msgs/msg/Pose.msg` of `ros2/common_interfaces` (unchanged since Foxy).
// Text: foxglove/rosmsg-msgs-common `msgdefs/ros2jazzy/visualization_msgs/msg/Marker.msg`
// (commit 818032d86fa1475ef21a7e2c7e01b652e0ec0ad9), which embeds it.
macro_rules! pose_msg {
    () => {
        r"# A representation of pose in free space, composed of position and orientation.

Point position
Quaternion orientation
"
    };
}

/// `sensor_msgs/msg/JointState.msg` of `ros2/common_interfaces` (unchanged since Foxy).
// Text: docs.ros.org/en/jazzy/p/sensor_msgs/msg/JointState.html (25 lines, 23 of code, as
// github.com/ros2/common_interfaces/blob/rolling shows it); the index holds no upstream copy.
macro_rules! joint_state_msg {
    () => {
        r"# This is a message that holds data to describe the state of a set of torque controlled joints.
#
# The state of each joint (revolute or prismatic) is defined by:
#  * the position of the joint (rad or m),
#  * the velocity of the joint (rad/s or m/s) and
#  * the effort that is applied in the joint (Nm or N).
#
# Each joint is uniquely identified by its name
# The header specifies the time at which the joint states were recorded. All the joint states
# in one message have to be recorded at the same time.
#
# This message consists of a multiple arrays, one for each part of the joint state.
# The goal is to make each of the fields optional. When e.g. your joints have no
# effort associated with them, you can leave the effort array empty.
#
# All arrays in this message should have the same size, or be empty.
# This is the only way to uniquely associate the joint name with the correct
# states.

std_msgs/Header header

string[] name
float64[] position
float64[] velocity
float64[] effort
"
    };
}

/// `sensor_msgs/msg/PointField.msg` of `ros2/common_interfaces`, Humble.
// Text: ros2/common_interfaces at commit e05fccee49a8fdb40fcb173cb9ce11ff03318834, before the
// INT64/UINT64 entries of common_interfaces#301 (rolling 5.8.3), which Humble does not have.
macro_rules! point_field_msg {
    () => {
        r"# This message holds the description of one point entry in the
# PointCloud2 message format.
uint8 INT8    = 1
uint8 UINT8   = 2
uint8 INT16   = 3
uint8 UINT16  = 4
uint8 INT32   = 5
uint8 UINT32  = 6
uint8 FLOAT32 = 7
uint8 FLOAT64 = 8

# Common PointField names are x, y, z, intensity, rgb, rgba
string name      # Name of field
uint32 offset    # Offset from start of point struct
uint8  datatype  # Datatype enumeration, see above
uint32 count     # How many elements in the field
"
    };
}

/// `sensor_msgs/msg/PointCloud2.msg` of `ros2/common_interfaces` (unchanged since Foxy).
// Text: docs.ros.org/en/jazzy/p/sensor_msgs/msg/PointCloud2.html, 26 lines of which 21 of code
// as github.com/ros2/common_interfaces/blob/humble shows it; the index holds no upstream copy.
macro_rules! point_cloud2_msg {
    () => {
        r#"# This message holds a collection of N-dimensional points, which may
# contain additional information such as normals, intensity, etc. The
# point data is stored as a binary blob, its layout described by the
# contents of the "fields" array.
#
# The point cloud data may be organized 2d (image-like) or 1d (unordered).
# Point clouds organized as 2d images may be produced by camera depth sensors
# such as stereo or time-of-flight.

# Time of sensor data acquisition, and the coordinate frame ID (for 3d points).
std_msgs/Header header

# 2D structure of the point cloud. If the cloud is unordered, height is
# 1 and width is the length of the point cloud.
uint32 height
uint32 width

# Describes the channels and their layout in the binary data blob.
PointField[] fields

bool    is_bigendian # Is this data bigendian?
uint32  point_step   # Length of a point in bytes
uint32  row_step     # Length of a row in bytes
uint8[] data         # Actual point data, size is (row_step*height)

bool is_dense        # True if there are no invalid points
"#
    };
}

/// `sensor_msgs/msg/CompressedImage.msg` of `ros2/common_interfaces`, Humble.
// Text: docs.ros.org/en/humble/p/sensor_msgs/msg/CompressedImage.html. The upstream copy in the
// index (commit 3c0c92d030c3af0c0566cb3c26f23297cdb63984) has the longer `format` description
// of common_interfaces#231 (rolling 5.2.2).
macro_rules! compressed_image_msg {
    () => {
        r"# This message contains a compressed image.

std_msgs/Header header # Header timestamp should be acquisition time of image
                             # Header frame_id should be optical frame of camera
                             # origin of frame should be optical center of cameara
                             # +x should point to the right in the image
                             # +y should point down in the image
                             # +z should point into to plane of the image

string format                # Specifies the format of the data
                             #   Acceptable values:
                             #     jpeg, png, tiff

uint8[] data                 # Compressed image buffer
"
    };
}

/// `visualization_msgs/msg/UVCoordinate.msg` of `ros2/common_interfaces` (Humble, Jazzy).
// Text: ros2/common_interfaces at commit d37e404e44524ed35b2231d360a60610a55a2264 (`float32`;
// the index also holds a `float64` version, commit 2454d79faf21bf0614ee37bb8e7660a39468ebb2).
macro_rules! uv_coordinate_msg {
    () => {
        r"# Location of the pixel as a ratio of the width of a 2D texture.
# Values should be in range: [0.0-1.0].
float32 u
float32 v
"
    };
}

/// `visualization_msgs/msg/MeshFile.msg` of `ros2/common_interfaces` (since 3.0.0).
// Text: ros2/common_interfaces at commit 9b4fb11c3d16cbc4ace91938d736624c1c4336b3.
macro_rules! mesh_file_msg {
    () => {
        r"# Used to send raw mesh files.

# The filename is used for both debug purposes and to provide a file extension
# for whatever parser is used.
string filename

# This stores the raw text of the mesh file.
uint8[] data
"
    };
}

/// `visualization_msgs/msg/Marker.msg` of `ros2/common_interfaces`, Humble.
// Text: ros2/common_interfaces at commit 231ca3e84ccbbdd35b8e796a4541da131d01cd3e without the two
// edits of common_interfaces#242 (rolling 5.3.3, never in Humble): the line
// `int32 ARROW_STRIP=12 # Currently unimplemented` and `ARROW_STRIP, ` in the comment above
// `points`. It keeps the `index.ros.org` link that common_interfaces#244 (5.4.0) replaced; the
// Humble changelog of visualization_msgs lists no change after 4.1.0.
macro_rules! marker_msg {
    () => {
        r#"# See:
#  - http://www.ros.org/wiki/rviz/DisplayTypes/Marker
#  - http://www.ros.org/wiki/rviz/Tutorials/Markers%3A%20Basic%20Shapes
#
# for more information on using this message with rviz.

int32 ARROW=0
int32 CUBE=1
int32 SPHERE=2
int32 CYLINDER=3
int32 LINE_STRIP=4
int32 LINE_LIST=5
int32 CUBE_LIST=6
int32 SPHERE_LIST=7
int32 POINTS=8
int32 TEXT_VIEW_FACING=9
int32 MESH_RESOURCE=10
int32 TRIANGLE_LIST=11

int32 ADD=0
int32 MODIFY=0
int32 DELETE=2
int32 DELETEALL=3

# Header for timestamp and frame id.
std_msgs/Header header
# Namespace in which to place the object.
# Used in conjunction with id to create a unique name for the object.
string ns
# Object ID used in conjunction with the namespace for manipulating and deleting the object later.
int32 id
# Type of object.
int32 type
# Action to take; one of:
#  - 0 add/modify an object
#  - 1 (deprecated)
#  - 2 deletes an object (with the given ns and id)
#  - 3 deletes all objects (or those with the given ns if any)
int32 action
# Pose of the object with respect the frame_id specified in the header.
geometry_msgs/Pose pose
# Scale of the object; 1,1,1 means default (usually 1 meter square).
geometry_msgs/Vector3 scale
# Color of the object; in the range: [0.0-1.0]
std_msgs/ColorRGBA color
# How long the object should last before being automatically deleted.
# 0 indicates forever.
builtin_interfaces/Duration lifetime
# If this marker should be frame-locked, i.e. retransformed into its frame every timestep.
bool frame_locked

# Only used if the type specified has some use for them (eg. POINTS, LINE_STRIP, etc.)
geometry_msgs/Point[] points
# Only used if the type specified has some use for them (eg. POINTS, LINE_STRIP, etc.)
# The number of colors provided must either be 0 or equal to the number of points provided.
# NOTE: alpha is not yet used
std_msgs/ColorRGBA[] colors

# Texture resource is a special URI that can either reference a texture file in
# a format acceptable to (resource retriever)[https://index.ros.org/p/resource_retriever/]
# or an embedded texture via a string matching the format:
#   "embedded://texture_name"
string texture_resource
# An image to be loaded into the rendering engine as the texture for this marker.
# This will be used iff texture_resource is set to embedded.
sensor_msgs/CompressedImage texture
# Location of each vertex within the texture; in the range: [0.0-1.0]
UVCoordinate[] uv_coordinates

# Only used for text markers
string text

# Only used for MESH_RESOURCE markers.
# Similar to texture_resource, mesh_resource uses resource retriever to load a mesh.
# Optionally, a mesh file can be sent in-message via the mesh_file field. If doing so,
# use the following format for mesh_resource:
#   "embedded://mesh_name"
string mesh_resource
MeshFile mesh_file
bool mesh_use_embedded_materials
"#
    };
}

/// `visualization_msgs/msg/MarkerArray.msg` of `ros2/common_interfaces` (unchanged since Foxy).
// Text: foxglove/rosmsg-msgs-common `msgdefs/ros2jazzy/visualization_msgs/msg/MarkerArray.msg`
// (commit 818032d86fa1475ef21a7e2c7e01b652e0ec0ad9).
macro_rules! marker_array_msg {
    () => {
        "Marker[] markers\n"
    };
}

/// The delimiter rosbag2 puts before the definition of dependency `$name`, followed by it.
macro_rules! dependency {
    ($name:literal, $text:expr) => {
        concat!("\n", separator_line!(), "MSG: ", $name, "\n", $text)
    };
}

/// MCAP schema name of [`WrenchStamped`].
pub const WRENCH_STAMPED_TYPE: &str = "geometry_msgs/msg/WrenchStamped";
/// MCAP schema name of [`JointState`].
pub const JOINT_STATE_TYPE: &str = "sensor_msgs/msg/JointState";
/// MCAP schema name of [`PointCloud2`].
pub const POINT_CLOUD2_TYPE: &str = "sensor_msgs/msg/PointCloud2";
/// MCAP schema name of [`Clock`].
pub const CLOCK_TYPE: &str = "rosgraph_msgs/msg/Clock";
/// MCAP schema name of [`Float64`].
pub const FLOAT64_TYPE: &str = "std_msgs/msg/Float64";
/// MCAP schema name of [`MarkerArray`].
pub const MARKER_ARRAY_TYPE: &str = "visualization_msgs/msg/MarkerArray";

/// Complete `ros2msg` definition of `geometry_msgs/msg/WrenchStamped`.
pub const WRENCH_STAMPED_SCHEMA: &str = concat!(
    wrench_stamped_msg!(),
    dependency!("geometry_msgs/Wrench", wrench_msg!()),
    dependency!("geometry_msgs/Vector3", vector3_msg!()),
    dependency!("std_msgs/Header", header_msg!()),
    dependency!("builtin_interfaces/Time", time_msg!()),
);

/// Complete `ros2msg` definition of `sensor_msgs/msg/JointState`.
pub const JOINT_STATE_SCHEMA: &str = concat!(
    joint_state_msg!(),
    dependency!("std_msgs/Header", header_msg!()),
    dependency!("builtin_interfaces/Time", time_msg!()),
);

/// Complete `ros2msg` definition of `sensor_msgs/msg/PointCloud2`.
pub const POINT_CLOUD2_SCHEMA: &str = concat!(
    point_cloud2_msg!(),
    dependency!("sensor_msgs/PointField", point_field_msg!()),
    dependency!("std_msgs/Header", header_msg!()),
    dependency!("builtin_interfaces/Time", time_msg!()),
);

/// Complete `ros2msg` definition of `rosgraph_msgs/msg/Clock`.
pub const CLOCK_SCHEMA: &str = concat!(
    clock_msg!(),
    dependency!("builtin_interfaces/Time", time_msg!()),
);

/// Complete `ros2msg` definition of `std_msgs/msg/Float64` (it has no dependencies).
pub const FLOAT64_SCHEMA: &str = float64_msg!();

/// Complete `ros2msg` definition of `visualization_msgs/msg/MarkerArray`.
pub const MARKER_ARRAY_SCHEMA: &str = concat!(
    marker_array_msg!(),
    dependency!("visualization_msgs/Marker", marker_msg!()),
    dependency!("builtin_interfaces/Duration", duration_msg!()),
    dependency!("geometry_msgs/Point", point_msg!()),
    dependency!("geometry_msgs/Pose", pose_msg!()),
    dependency!("geometry_msgs/Quaternion", quaternion_msg!()),
    dependency!("geometry_msgs/Vector3", vector3_msg!()),
    dependency!("sensor_msgs/CompressedImage", compressed_image_msg!()),
    dependency!("std_msgs/Header", header_msg!()),
    dependency!("builtin_interfaces/Time", time_msg!()),
    dependency!("std_msgs/ColorRGBA", color_rgba_msg!()),
    dependency!("visualization_msgs/MeshFile", mesh_file_msg!()),
    dependency!("visualization_msgs/UVCoordinate", uv_coordinate_msg!()),
);

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

/// A top-level message type with its MCAP schema name and `ros2msg` schema text.
pub trait RosMessage: CdrMessage {
    /// Schema name, e.g. `geometry_msgs/msg/WrenchStamped`.
    const TYPE_NAME: &'static str;
    /// Complete `ros2msg` definition, as rosbag2 writes it.
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

/// `builtin_interfaces/msg/Time`: ROS time as seconds and nanoseconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds to add to `sec`, in `[0, 1e9)`.
    pub nanosec: u32,
}

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

impl CdrMessage for Time {
    fn write_cdr(&self, w: &mut CdrWriter) {
        w.write_i32(self.sec);
        w.write_u32(self.nanosec);
    }
}

impl CdrDecode for Time {
    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            sec: r.read_i32()?,
            nanosec: r.read_u32()?,
        })
    }
}

/// `builtin_interfaces/msg/Duration`: a period as seconds and nanoseconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct Duration {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds to add to `sec`, in `[0, 1e9)`.
    pub nanosec: u32,
}

impl CdrMessage for Duration {
    fn write_cdr(&self, w: &mut CdrWriter) {
        w.write_i32(self.sec);
        w.write_u32(self.nanosec);
    }
}

/// `std_msgs/msg/Header`: timestamp and coordinate frame.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct Header {
    /// Time of the data.
    pub stamp: Time,
    /// Frame the data is expressed in.
    pub frame_id: String,
}

impl CdrMessage for Header {
    fn write_cdr(&self, w: &mut CdrWriter) {
        self.stamp.write_cdr(w);
        w.write_string(&self.frame_id);
    }
}

impl CdrDecode for Header {
    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            stamp: Time::read_cdr(r)?,
            frame_id: r.read_string()?,
        })
    }
}

/// `geometry_msgs/msg/Vector3`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Vector3 {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
    /// z component.
    pub z: f64,
}

impl CdrMessage for Vector3 {
    fn write_cdr(&self, w: &mut CdrWriter) {
        w.write_f64(self.x);
        w.write_f64(self.y);
        w.write_f64(self.z);
    }
}

impl CdrDecode for Vector3 {
    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            x: r.read_f64()?,
            y: r.read_f64()?,
            z: r.read_f64()?,
        })
    }
}

/// `geometry_msgs/msg/Wrench`: force and torque.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wrench {
    /// Force.
    pub force: Vector3,
    /// Torque.
    pub torque: Vector3,
}

impl CdrMessage for Wrench {
    fn write_cdr(&self, w: &mut CdrWriter) {
        self.force.write_cdr(w);
        self.torque.write_cdr(w);
    }
}

impl CdrDecode for Wrench {
    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            force: Vector3::read_cdr(r)?,
            torque: Vector3::read_cdr(r)?,
        })
    }
}

/// `geometry_msgs/msg/WrenchStamped`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct WrenchStamped {
    /// Timestamp and frame.
    pub header: Header,
    /// The wrench.
    pub wrench: Wrench,
}

impl CdrMessage for WrenchStamped {
    fn write_cdr(&self, w: &mut CdrWriter) {
        self.header.write_cdr(w);
        self.wrench.write_cdr(w);
    }
}

impl CdrDecode for WrenchStamped {
    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: Header::read_cdr(r)?,
            wrench: Wrench::read_cdr(r)?,
        })
    }
}

impl RosMessage for WrenchStamped {
    const TYPE_NAME: &'static str = WRENCH_STAMPED_TYPE;
    const SCHEMA: &'static str = WRENCH_STAMPED_SCHEMA;
}

/// `sensor_msgs/msg/JointState`: per-joint arrays, each empty or as long as `name`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointState {
    /// Timestamp and frame.
    pub header: Header,
    /// Joint names.
    pub name: Vec<String>,
    /// Positions (rad or m).
    pub position: Vec<f64>,
    /// Velocities (rad/s or m/s).
    pub velocity: Vec<f64>,
    /// Efforts (N·m or N).
    pub effort: Vec<f64>,
}

impl CdrMessage for JointState {
    fn write_cdr(&self, w: &mut CdrWriter) {
        self.header.write_cdr(w);
        w.write_string_seq(&self.name);
        w.write_f64_seq(&self.position);
        w.write_f64_seq(&self.velocity);
        w.write_f64_seq(&self.effort);
    }
}

impl CdrDecode for JointState {
    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            header: Header::read_cdr(r)?,
            name: r.read_string_seq()?,
            position: r.read_f64_seq()?,
            velocity: r.read_f64_seq()?,
            effort: r.read_f64_seq()?,
        })
    }
}

impl RosMessage for JointState {
    const TYPE_NAME: &'static str = JOINT_STATE_TYPE;
    const SCHEMA: &'static str = JOINT_STATE_SCHEMA;
}

/// `sensor_msgs/msg/PointField`: one channel of the points of a [`PointCloud2`].
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct PointField {
    /// Channel name, e.g. `x`.
    pub name: String,
    /// Byte offset from the start of a point.
    pub offset: u32,
    /// Element type, one of the constants of this type.
    pub datatype: u8,
    /// Number of elements.
    pub count: u32,
}

impl PointField {
    /// `datatype` of a signed 8-bit integer.
    pub const INT8: u8 = 1;
    /// `datatype` of an unsigned 8-bit integer.
    pub const UINT8: u8 = 2;
    /// `datatype` of a signed 16-bit integer.
    pub const INT16: u8 = 3;
    /// `datatype` of an unsigned 16-bit integer.
    pub const UINT16: u8 = 4;
    /// `datatype` of a signed 32-bit integer.
    pub const INT32: u8 = 5;
    /// `datatype` of an unsigned 32-bit integer.
    pub const UINT32: u8 = 6;
    /// `datatype` of a 32-bit float.
    pub const FLOAT32: u8 = 7;
    /// `datatype` of a 64-bit float.
    pub const FLOAT64: u8 = 8;
}

impl CdrMessage for PointField {
    fn write_cdr(&self, w: &mut CdrWriter) {
        w.write_string(&self.name);
        w.write_u32(self.offset);
        w.write_u8(self.datatype);
        w.write_u32(self.count);
    }
}

/// `sensor_msgs/msg/PointCloud2`: points as a binary blob described by `fields`.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct PointCloud2 {
    /// Acquisition time and frame.
    pub header: Header,
    /// Rows (1 for an unordered cloud).
    pub height: u32,
    /// Points per row.
    pub width: u32,
    /// Layout of one point.
    pub fields: Vec<PointField>,
    /// Byte order of `data`.
    pub is_bigendian: bool,
    /// Bytes per point.
    pub point_step: u32,
    /// Bytes per row.
    pub row_step: u32,
    /// Point data, `row_step * height` bytes.
    pub data: Vec<u8>,
    /// True if no point is invalid (NaN or infinite).
    pub is_dense: bool,
}

impl CdrMessage for PointCloud2 {
    fn write_cdr(&self, w: &mut CdrWriter) {
        self.header.write_cdr(w);
        w.write_u32(self.height);
        w.write_u32(self.width);
        w.write_seq(&self.fields);
        w.write_bool(self.is_bigendian);
        w.write_u32(self.point_step);
        w.write_u32(self.row_step);
        w.write_u8_seq(&self.data);
        w.write_bool(self.is_dense);
    }
}

impl RosMessage for PointCloud2 {
    const TYPE_NAME: &'static str = POINT_CLOUD2_TYPE;
    const SCHEMA: &'static str = POINT_CLOUD2_SCHEMA;
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

/// `rosgraph_msgs/msg/Clock`: the current (simulation) time, published on `/clock`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Clock {
    /// Current time.
    pub clock: Time,
}

impl CdrMessage for Clock {
    fn write_cdr(&self, w: &mut CdrWriter) {
        self.clock.write_cdr(w);
    }
}

impl CdrDecode for Clock {
    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            clock: Time::read_cdr(r)?,
        })
    }
}

impl RosMessage for Clock {
    const TYPE_NAME: &'static str = CLOCK_TYPE;
    const SCHEMA: &'static str = CLOCK_SCHEMA;
}

/// `std_msgs/msg/Float64`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Float64 {
    /// The value.
    pub data: f64,
}

impl CdrMessage for Float64 {
    fn write_cdr(&self, w: &mut CdrWriter) {
        w.write_f64(self.data);
    }
}

impl CdrDecode for Float64 {
    fn read_cdr(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            data: r.read_f64()?,
        })
    }
}

impl RosMessage for Float64 {
    const TYPE_NAME: &'static str = FLOAT64_TYPE;
    const SCHEMA: &'static str = FLOAT64_SCHEMA;
}

/// `geometry_msgs/msg/Point`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Point {
    /// x coordinate.
    pub x: f64,
    /// y coordinate.
    pub y: f64,
    /// z coordinate.
    pub z: f64,
}

impl CdrMessage for Point {
    fn write_cdr(&self, w: &mut CdrWriter) {
        w.write_f64(self.x);
        w.write_f64(self.y);
        w.write_f64(self.z);
    }
}

/// `geometry_msgs/msg/Quaternion`. The default is the identity, as in the `.msg` (`w` 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quaternion {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
    /// z component.
    pub z: f64,
    /// w (scalar) component.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

impl CdrMessage for Quaternion {
    fn write_cdr(&self, w: &mut CdrWriter) {
        w.write_f64(self.x);
        w.write_f64(self.y);
        w.write_f64(self.z);
        w.write_f64(self.w);
    }
}

/// `geometry_msgs/msg/Pose`: position and orientation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose {
    /// Position.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

impl CdrMessage for Pose {
    fn write_cdr(&self, w: &mut CdrWriter) {
        self.position.write_cdr(w);
        self.orientation.write_cdr(w);
    }
}

/// `std_msgs/msg/ColorRGBA`, components in `[0, 1]`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ColorRGBA {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Alpha (0 is invisible).
    pub a: f32,
}

impl CdrMessage for ColorRGBA {
    fn write_cdr(&self, w: &mut CdrWriter) {
        w.write_f32(self.r);
        w.write_f32(self.g);
        w.write_f32(self.b);
        w.write_f32(self.a);
    }
}

/// `sensor_msgs/msg/CompressedImage` (the texture of a [`Marker`]).
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct CompressedImage {
    /// Acquisition time and camera frame.
    pub header: Header,
    /// Image format, e.g. `png`.
    pub format: String,
    /// Compressed image bytes.
    pub data: Vec<u8>,
}

impl CdrMessage for CompressedImage {
    fn write_cdr(&self, w: &mut CdrWriter) {
        self.header.write_cdr(w);
        w.write_string(&self.format);
        w.write_u8_seq(&self.data);
    }
}

/// `visualization_msgs/msg/UVCoordinate`: texture coordinates of a vertex, in `[0, 1]`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct UVCoordinate {
    /// Horizontal ratio.
    pub u: f32,
    /// Vertical ratio.
    pub v: f32,
}

impl CdrMessage for UVCoordinate {
    fn write_cdr(&self, w: &mut CdrWriter) {
        w.write_f32(self.u);
        w.write_f32(self.v);
    }
}

/// `visualization_msgs/msg/MeshFile`: a mesh file sent inside a [`Marker`].
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct MeshFile {
    /// File name, whose extension selects the parser.
    pub filename: String,
    /// File contents.
    pub data: Vec<u8>,
}

impl CdrMessage for MeshFile {
    fn write_cdr(&self, w: &mut CdrWriter) {
        w.write_string(&self.filename);
        w.write_u8_seq(&self.data);
    }
}

/// `visualization_msgs/msg/Marker` (Humble fields).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Marker {
    /// Timestamp and frame.
    pub header: Header,
    /// Namespace; with `id` it names the marker.
    pub ns: String,
    /// Identifier within `ns`.
    pub id: i32,
    /// Shape, one of the type constants of this type (e.g. [`Marker::LINE_STRIP`]).
    pub r#type: i32,
    /// One of [`Marker::ADD`], [`Marker::MODIFY`], [`Marker::DELETE`], [`Marker::DELETEALL`].
    pub action: i32,
    /// Pose in the header frame.
    pub pose: Pose,
    /// Scale; for a line strip, `scale.x` is the line width.
    pub scale: Vector3,
    /// Color of the whole marker.
    pub color: ColorRGBA,
    /// Time until automatic deletion, zero for never.
    pub lifetime: Duration,
    /// Whether to re-transform the marker into its frame at every time step.
    pub frame_locked: bool,
    /// Points of point-based types such as [`Marker::LINE_STRIP`].
    pub points: Vec<Point>,
    /// Per-point colors: empty or as many as `points`.
    pub colors: Vec<ColorRGBA>,
    /// Texture URI, or `embedded://name` to use `texture`.
    pub texture_resource: String,
    /// Embedded texture image.
    pub texture: CompressedImage,
    /// Texture coordinates of the vertices.
    pub uv_coordinates: Vec<UVCoordinate>,
    /// Text of [`Marker::TEXT_VIEW_FACING`] markers.
    pub text: String,
    /// Mesh URI of [`Marker::MESH_RESOURCE`] markers, or `embedded://name` to use `mesh_file`.
    pub mesh_resource: String,
    /// Embedded mesh file.
    pub mesh_file: MeshFile,
    /// Whether to use the materials embedded in the mesh.
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// `type`: an arrow.
    pub const ARROW: i32 = 0;
    /// `type`: a box.
    pub const CUBE: i32 = 1;
    /// `type`: a sphere.
    pub const SPHERE: i32 = 2;
    /// `type`: a cylinder.
    pub const CYLINDER: i32 = 3;
    /// `type`: a polyline through `points`.
    pub const LINE_STRIP: i32 = 4;
    /// `type`: a segment for each pair of `points`.
    pub const LINE_LIST: i32 = 5;
    /// `type`: a box at each of `points`.
    pub const CUBE_LIST: i32 = 6;
    /// `type`: a sphere at each of `points`.
    pub const SPHERE_LIST: i32 = 7;
    /// `type`: a point at each of `points`.
    pub const POINTS: i32 = 8;
    /// `type`: `text`, facing the viewer.
    pub const TEXT_VIEW_FACING: i32 = 9;
    /// `type`: the mesh of `mesh_resource`.
    pub const MESH_RESOURCE: i32 = 10;
    /// `type`: a triangle for each triple of `points`.
    pub const TRIANGLE_LIST: i32 = 11;
    /// `action`: add or modify the marker.
    pub const ADD: i32 = 0;
    /// `action`: same as [`Marker::ADD`].
    pub const MODIFY: i32 = 0;
    /// `action`: delete the marker with this `ns` and `id`.
    pub const DELETE: i32 = 2;
    /// `action`: delete all markers (of `ns`, if set).
    pub const DELETEALL: i32 = 3;
}

impl CdrMessage for Marker {
    fn write_cdr(&self, w: &mut CdrWriter) {
        self.header.write_cdr(w);
        w.write_string(&self.ns);
        w.write_i32(self.id);
        w.write_i32(self.r#type);
        w.write_i32(self.action);
        self.pose.write_cdr(w);
        self.scale.write_cdr(w);
        self.color.write_cdr(w);
        self.lifetime.write_cdr(w);
        w.write_bool(self.frame_locked);
        w.write_seq(&self.points);
        w.write_seq(&self.colors);
        w.write_string(&self.texture_resource);
        self.texture.write_cdr(w);
        w.write_seq(&self.uv_coordinates);
        w.write_string(&self.text);
        w.write_string(&self.mesh_resource);
        self.mesh_file.write_cdr(w);
        w.write_bool(self.mesh_use_embedded_materials);
    }
}

/// `visualization_msgs/msg/MarkerArray`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MarkerArray {
    /// The markers.
    pub markers: Vec<Marker>,
}

impl CdrMessage for MarkerArray {
    fn write_cdr(&self, w: &mut CdrWriter) {
        w.write_seq(&self.markers);
    }
}

impl RosMessage for MarkerArray {
    const TYPE_NAME: &'static str = MARKER_ARRAY_TYPE;
    const SCHEMA: &'static str = MARKER_ARRAY_SCHEMA;
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    /// The 80-`=` delimiter line, without its newline.
    const SEPARATOR: &str =
        "================================================================================";

    /// Every `.msg` text used, by the name rosbag2 gives it (package/Type).
    const DEFINITIONS: [(&str, &str); 20] = [
        ("builtin_interfaces/Time", time_msg!()),
        ("builtin_interfaces/Duration", duration_msg!()),
        ("rosgraph_msgs/Clock", clock_msg!()),
        ("std_msgs/Header", header_msg!()),
        ("std_msgs/Float64", float64_msg!()),
        ("std_msgs/ColorRGBA", color_rgba_msg!()),
        ("geometry_msgs/Vector3", vector3_msg!()),
        ("geometry_msgs/Wrench", wrench_msg!()),
        ("geometry_msgs/WrenchStamped", wrench_stamped_msg!()),
        ("geometry_msgs/Point", point_msg!()),
        ("geometry_msgs/Quaternion", quaternion_msg!()),
        ("geometry_msgs/Pose", pose_msg!()),
        ("sensor_msgs/JointState", joint_state_msg!()),
        ("sensor_msgs/PointField", point_field_msg!()),
        ("sensor_msgs/PointCloud2", point_cloud2_msg!()),
        ("sensor_msgs/CompressedImage", compressed_image_msg!()),
        ("visualization_msgs/UVCoordinate", uv_coordinate_msg!()),
        ("visualization_msgs/MeshFile", mesh_file_msg!()),
        ("visualization_msgs/Marker", marker_msg!()),
        ("visualization_msgs/MarkerArray", marker_array_msg!()),
    ];

    fn definition(name: &str) -> &'static str {
        DEFINITIONS
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, text)| *text)
            .unwrap_or_else(|| panic!("no definition for {name}"))
    }

    /// The field types rosbag2 finds in a `.msg` text: the first token of every line that
    /// starts (after blanks) with `[A-Za-z0-9_/]` and continues with blanks, array brackets
    /// stripped, primitives dropped, bare names qualified with `package`.
    fn dependencies(text: &str, package: &str) -> BTreeSet<String> {
        const PRIMITIVES: [&str; 14] = [
            "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
            "int32", "uint32", "int64", "uint64", "string",
        ];
        let mut deps = BTreeSet::new();
        for line in text.lines() {
            let line = line.trim_start();
            let token_len = line
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '/'))
                .unwrap_or(line.len());
            let (token, rest) = line.split_at(token_len);
            let rest = match rest.strip_prefix('[') {
                Some(r) => r.split_once(']').map_or("", |(_, after)| after),
                None => rest,
            };
            if token.is_empty() || !rest.starts_with(char::is_whitespace) {
                continue;
            }
            if PRIMITIVES.contains(&token) {
                continue;
            }
            if token.contains('/') {
                deps.insert(token.to_owned());
            } else {
                deps.insert(format!("{package}/{token}"));
            }
        }
        deps
    }

    /// rosbag2's `get_full_text`, re-implemented over [`DEFINITIONS`].
    fn full_text(root: &str) -> String {
        fn append(name: &str, seen: &mut BTreeSet<String>) -> String {
            let text = definition(name);
            let package = name.split('/').next().unwrap_or_default();
            let mut out = text.to_owned();
            for dep in dependencies(text, package) {
                if seen.insert(dep.clone()) {
                    out.push('\n');
                    out.push_str(SEPARATOR);
                    out.push_str("\nMSG: ");
                    out.push_str(&dep);
                    out.push('\n');
                    out.push_str(&append(&dep, seen));
                }
            }
            out
        }
        append(root, &mut BTreeSet::new())
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

    const SCHEMAS: [(&str, &str, &str); 6] = [
        (
            WRENCH_STAMPED_TYPE,
            "geometry_msgs/WrenchStamped",
            WRENCH_STAMPED_SCHEMA,
        ),
        (
            JOINT_STATE_TYPE,
            "sensor_msgs/JointState",
            JOINT_STATE_SCHEMA,
        ),
        (
            POINT_CLOUD2_TYPE,
            "sensor_msgs/PointCloud2",
            POINT_CLOUD2_SCHEMA,
        ),
        (CLOCK_TYPE, "rosgraph_msgs/Clock", CLOCK_SCHEMA),
        (FLOAT64_TYPE, "std_msgs/Float64", FLOAT64_SCHEMA),
        (
            MARKER_ARRAY_TYPE,
            "visualization_msgs/MarkerArray",
            MARKER_ARRAY_SCHEMA,
        ),
    ];

    #[test]
    fn schemas_match_the_rosbag2_algorithm() {
        for (type_name, short, schema) in SCHEMAS {
            assert_eq!(type_name.replace("/msg/", "/"), short);
            assert_eq!(schema, full_text(short), "{type_name}");
        }
    }

    #[test]
    fn schemas_hold_each_dependency_once_after_a_delimiter() {
        for (type_name, short, schema) in SCHEMAS {
            let sections = sections(schema);
            assert_eq!(sections[0].1, definition(short), "{type_name}");
            let names: Vec<&str> = sections[1..].iter().filter_map(|(n, _)| *n).collect();
            let unique: BTreeSet<&str> = names.iter().copied().collect();
            assert_eq!(names.len(), unique.len(), "{type_name}: {names:?}");
            for (name, text) in &sections[1..] {
                let name = name.expect("dependency sections are named");
                assert_eq!(*text, definition(name), "{type_name}: {name}");
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

    #[test]
    fn schema_dependency_sets() {
        let deps = |schema: &str| -> Vec<String> {
            sections(schema)[1..]
                .iter()
                .filter_map(|(n, _)| n.map(str::to_owned))
                .collect()
        };
        assert_eq!(
            deps(WRENCH_STAMPED_SCHEMA),
            [
                "geometry_msgs/Wrench",
                "geometry_msgs/Vector3",
                "std_msgs/Header",
                "builtin_interfaces/Time"
            ]
        );
        assert_eq!(
            deps(JOINT_STATE_SCHEMA),
            ["std_msgs/Header", "builtin_interfaces/Time"]
        );
        assert_eq!(
            deps(POINT_CLOUD2_SCHEMA),
            [
                "sensor_msgs/PointField",
                "std_msgs/Header",
                "builtin_interfaces/Time"
            ]
        );
        assert_eq!(deps(CLOCK_SCHEMA), ["builtin_interfaces/Time"]);
        assert!(deps(FLOAT64_SCHEMA).is_empty());
        let marker_deps: BTreeSet<String> = deps(MARKER_ARRAY_SCHEMA).into_iter().collect();
        let expected: BTreeSet<String> = [
            "visualization_msgs/Marker",
            "std_msgs/Header",
            "builtin_interfaces/Time",
            "builtin_interfaces/Duration",
            "geometry_msgs/Pose",
            "geometry_msgs/Point",
            "geometry_msgs/Quaternion",
            "geometry_msgs/Vector3",
            "std_msgs/ColorRGBA",
            "sensor_msgs/CompressedImage",
            "visualization_msgs/UVCoordinate",
            "visualization_msgs/MeshFile",
        ]
        .into_iter()
        .map(str::to_owned)
        .collect();
        assert_eq!(marker_deps, expected);
    }

    #[test]
    fn schema_first_lines() {
        assert_eq!(
            WRENCH_STAMPED_SCHEMA.lines().next(),
            Some("# A wrench with reference coordinate frame and timestamp")
        );
        assert_eq!(MARKER_ARRAY_SCHEMA.lines().next(), Some("Marker[] markers"));
        assert_eq!(FLOAT64_SCHEMA, float64_msg!());
        assert!(!MARKER_ARRAY_SCHEMA.contains("ARROW_STRIP"));
        assert!(MARKER_ARRAY_SCHEMA.contains("[0, 10e9)"));
        for (_, _, schema) in SCHEMAS {
            assert!(schema.lines().all(|l| l == l.trim_end()), "trailing blanks");
        }
    }

    #[test]
    fn ros_message_constants() {
        assert_eq!(WrenchStamped::TYPE_NAME, WRENCH_STAMPED_TYPE);
        assert_eq!(JointState::SCHEMA, JOINT_STATE_SCHEMA);
        assert_eq!(PointCloud2::TYPE_NAME, POINT_CLOUD2_TYPE);
        assert_eq!(Clock::SCHEMA, CLOCK_SCHEMA);
        assert_eq!(Float64::TYPE_NAME, FLOAT64_TYPE);
        assert_eq!(MarkerArray::SCHEMA, MARKER_ARRAY_SCHEMA);
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
