//! The ROS 2 message types skillc reads and writes, their CDR encoding and decoding, and the
//! `ros2msg` definition texts registered as MCAP schemas (written in our words: the field lists
//! of the standard packages, each dependency appended after a line of `=` and `MSG: pkg/Type`,
//! as rosbag2 writes them).

use crate::cdr::{CdrError, CdrReader, CdrWriter};

/// `builtin_interfaces/Time`: seconds and nanoseconds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds, 0 to 999 999 999.
    pub nanosec: u32,
}

impl Time {
    /// The time in nanoseconds.
    pub fn nanos(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    /// `t_s` seconds (rounded to the nanosecond; clamped to what `int32` seconds hold).
    pub fn from_seconds(t_s: f64) -> Time {
        let ns = (t_s * 1e9).round().clamp(i32::MIN as f64 * 1e9, i32::MAX as f64 * 1e9) as i64;
        Time {
            sec: ns.div_euclid(1_000_000_000) as i32,
            nanosec: ns.rem_euclid(1_000_000_000) as u32,
        }
    }
}

/// `std_msgs/Header`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Header {
    /// When the data was taken.
    pub stamp: Time,
    /// The frame the data is written in.
    pub frame_id: String,
}

/// `geometry_msgs/PoseStamped`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PoseStamped {
    /// Stamp and parent frame.
    pub header: Header,
    /// Position \[m\].
    pub position: [f64; 3],
    /// Orientation as ROS writes it: `[x, y, z, w]`.
    pub orientation_xyzw: [f64; 4],
}

/// `geometry_msgs/WrenchStamped`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct WrenchStamped {
    /// Stamp and the frame whose axes the wrench is written in.
    pub header: Header,
    /// Force \[N\].
    pub force: [f64; 3],
    /// Torque \[N m\].
    pub torque: [f64; 3],
}

/// `geometry_msgs/TransformStamped`: the pose of `child_frame_id` in `header.frame_id`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TransformStamped {
    /// Stamp and parent frame.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// Translation \[m\].
    pub translation: [f64; 3],
    /// Rotation `[x, y, z, w]`.
    pub rotation_xyzw: [f64; 4],
}

/// `sensor_msgs/JointState`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointState {
    /// Stamp (frame unused).
    pub header: Header,
    /// Joint names.
    pub name: Vec<String>,
    /// Positions \[rad\].
    pub position: Vec<f64>,
    /// Velocities \[rad/s\].
    pub velocity: Vec<f64>,
    /// Efforts \[N m\].
    pub effort: Vec<f64>,
}

/// The types skillc knows, by their MCAP schema names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MsgType {
    /// `geometry_msgs/msg/PoseStamped`.
    PoseStamped,
    /// `geometry_msgs/msg/WrenchStamped`.
    WrenchStamped,
    /// `tf2_msgs/msg/TFMessage`.
    TfMessage,
    /// `sensor_msgs/msg/JointState`.
    JointState,
    /// `std_msgs/msg/String`.
    String,
    /// `std_msgs/msg/Float64MultiArray`.
    Float64MultiArray,
    /// `visualization_msgs/msg/MarkerArray`.
    MarkerArray,
}

impl MsgType {
    /// The schema name rosbag2 writes: `pkg/msg/Type`.
    pub fn schema_name(self) -> &'static str {
        match self {
            MsgType::PoseStamped => "geometry_msgs/msg/PoseStamped",
            MsgType::WrenchStamped => "geometry_msgs/msg/WrenchStamped",
            MsgType::TfMessage => "tf2_msgs/msg/TFMessage",
            MsgType::JointState => "sensor_msgs/msg/JointState",
            MsgType::String => "std_msgs/msg/String",
            MsgType::Float64MultiArray => "std_msgs/msg/Float64MultiArray",
            MsgType::MarkerArray => "visualization_msgs/msg/MarkerArray",
        }
    }

    /// The type a schema name means (`pkg/msg/Type` or `pkg/Type`), if skillc knows it.
    pub fn from_schema_name(name: &str) -> Option<MsgType> {
        let short = name.trim().replace("/msg/", "/");
        [
            MsgType::PoseStamped,
            MsgType::WrenchStamped,
            MsgType::TfMessage,
            MsgType::JointState,
            MsgType::String,
            MsgType::Float64MultiArray,
            MsgType::MarkerArray,
        ]
        .into_iter()
        .find(|ty| ty.schema_name().replace("/msg/", "/") == short)
    }

    /// The names of the type's own fields, in order (what [`definition_fields`] reads out of
    /// its definition).
    pub fn field_names(self) -> &'static [&'static str] {
        match self {
            MsgType::PoseStamped => &["header", "pose"],
            MsgType::WrenchStamped => &["header", "wrench"],
            MsgType::TfMessage => &["transforms"],
            MsgType::JointState => &["header", "name", "position", "velocity", "effort"],
            MsgType::String => &["data"],
            MsgType::Float64MultiArray => &["layout", "data"],
            MsgType::MarkerArray => &["markers"],
        }
    }

    /// The type's own fields as a `ros2msg` definition writes them (`type name` per line).
    pub fn own_fields(self) -> &'static str {
        match self {
            MsgType::PoseStamped => "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
            MsgType::WrenchStamped => "std_msgs/Header header\ngeometry_msgs/Wrench wrench\n",
            MsgType::TfMessage => "geometry_msgs/TransformStamped[] transforms\n",
            MsgType::JointState => {
                "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n"
            }
            MsgType::String => "string data\n",
            MsgType::Float64MultiArray => "std_msgs/MultiArrayLayout layout\nfloat64[] data\n",
            MsgType::MarkerArray => "visualization_msgs/Marker[] markers\n",
        }
    }

    /// The `ros2msg` definition: the type's fields, then each type it uses after a separator
    /// (each once, in the order a depth-first walk of the fields meets them, as rosbag2 writes them).
    pub fn definition(self) -> String {
        let own = self.own_fields();
        let mut deps: Vec<&str> = Vec::new();
        nested_types(own, &mut deps);
        let mut text = own.to_owned();
        for dep in deps {
            text.push_str(&"=".repeat(80));
            text.push_str("\nMSG: ");
            text.push_str(dep);
            text.push('\n');
            text.push_str(fields_of(dep));
        }
        text
    }
}

/// The message types `fields` uses, depth first, each once, appended to `into`.
fn nested_types(fields: &str, into: &mut Vec<&'static str>) {
    for line in fields.lines() {
        let Some(ty) = line.split_whitespace().next() else {
            continue;
        };
        let ty = ty.strip_suffix("[]").unwrap_or(ty);
        if !ty.contains('/') {
            continue;
        }
        let (name, nested) = known_type(ty);
        if !into.contains(&name) {
            into.push(name);
            nested_types(nested, into);
        }
    }
}

/// A type the definitions use, as its `'static` name and fields.
fn known_type(ty: &str) -> (&'static str, &'static str) {
    KNOWN_TYPES
        .iter()
        .find(|(name, _)| *name == ty)
        .copied()
        .unwrap_or_else(|| unreachable!("known_type: every type the definitions use is in KNOWN_TYPES ({ty})"))
}

/// The names of the top-level fields a `ros2msg` definition declares (the lines before the first
/// `===` separator, without comments and constants): `["header", "wrench"]`.
pub fn definition_fields(text: &str) -> Vec<&str> {
    text.lines()
        .take_while(|line| !line.starts_with("==="))
        .map(|line| line.split('#').next().unwrap_or_default())
        .filter(|line| !line.contains('='))
        .filter_map(|line| line.split_whitespace().nth(1))
        .collect()
}

/// The types the definitions above use, with their fields (`pkg/Type`, as definitions name them).
const KNOWN_TYPES: &[(&str, &str)] = &[
    ("std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"),
    ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"),
    (
        "geometry_msgs/Pose",
        "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
    ),
    ("geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"),
    ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"),
    (
        "geometry_msgs/Quaternion",
        "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n",
    ),
    (
        "geometry_msgs/Wrench",
        "geometry_msgs/Vector3 force\ngeometry_msgs/Vector3 torque\n",
    ),
    (
        "geometry_msgs/Transform",
        "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
    ),
    (
        "geometry_msgs/TransformStamped",
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
    ),
    (
        "std_msgs/MultiArrayLayout",
        "std_msgs/MultiArrayDimension[] dim\nuint32 data_offset\n",
    ),
    (
        "std_msgs/MultiArrayDimension",
        "string label\nuint32 size\nuint32 stride\n",
    ),
    // Jazzy's marker, with the texture and embedded-mesh fields it gained after Humble (written
    // empty here: they are for textured and embedded meshes, which skillc does not draw).
    (
        "visualization_msgs/Marker",
        "std_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\ngeometry_msgs/Pose pose\n\
         geometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\nbuiltin_interfaces/Duration lifetime\n\
         bool frame_locked\ngeometry_msgs/Point[] points\nstd_msgs/ColorRGBA[] colors\n\
         string texture_resource\nsensor_msgs/CompressedImage texture\n\
         visualization_msgs/UVCoordinate[] uv_coordinates\nstring text\nstring mesh_resource\n\
         visualization_msgs/MeshFile mesh_file\nbool mesh_use_embedded_materials\n",
    ),
    ("std_msgs/ColorRGBA", "float32 r\nfloat32 g\nfloat32 b\nfloat32 a\n"),
    ("builtin_interfaces/Duration", "int32 sec\nuint32 nanosec\n"),
    (
        "sensor_msgs/CompressedImage",
        "std_msgs/Header header\nstring format\nuint8[] data\n",
    ),
    ("visualization_msgs/UVCoordinate", "float32 u\nfloat32 v\n"),
    ("visualization_msgs/MeshFile", "string filename\nuint8[] data\n"),
];

/// The fields of a type the definitions use.
pub(crate) fn fields_of(ty: &str) -> &'static str {
    known_type(ty).1
}

fn write_header(writer: &mut CdrWriter, header: &Header) {
    writer.i32(header.stamp.sec);
    writer.u32(header.stamp.nanosec);
    writer.string(&header.frame_id);
}

fn read_header(reader: &mut CdrReader<'_>) -> Result<Header, CdrError> {
    let sec = reader.i32("header.stamp.sec")?;
    let nanosec = reader.u32("header.stamp.nanosec")?;
    let frame_id = reader.string("header.frame_id")?;
    Ok(Header {
        stamp: Time { sec, nanosec },
        frame_id,
    })
}

fn write_f64s(writer: &mut CdrWriter, values: &[f64]) {
    for value in values {
        writer.f64(*value);
    }
}

fn read_f64s<const N: usize>(reader: &mut CdrReader<'_>, names: [&str; N]) -> Result<[f64; N], CdrError> {
    let mut out = [0.0; N];
    for (slot, name) in out.iter_mut().zip(names) {
        *slot = reader.f64(name)?;
    }
    Ok(out)
}

impl PoseStamped {
    /// The CDR bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut writer = CdrWriter::new();
        write_header(&mut writer, &self.header);
        write_f64s(&mut writer, &self.position);
        write_f64s(&mut writer, &self.orientation_xyzw);
        writer.finish()
    }

    /// Reads the CDR bytes.
    pub fn decode(data: &[u8]) -> Result<PoseStamped, CdrError> {
        let mut reader = CdrReader::new(data)?;
        let pose = PoseStamped {
            header: read_header(&mut reader)?,
            position: read_f64s(&mut reader, ["pose.position.x", "pose.position.y", "pose.position.z"])?,
            orientation_xyzw: read_f64s(
                &mut reader,
                [
                    "pose.orientation.x",
                    "pose.orientation.y",
                    "pose.orientation.z",
                    "pose.orientation.w",
                ],
            )?,
        };
        reader.finish("pose.orientation.w")?;
        Ok(pose)
    }
}

impl WrenchStamped {
    /// The CDR bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut writer = CdrWriter::new();
        write_header(&mut writer, &self.header);
        write_f64s(&mut writer, &self.force);
        write_f64s(&mut writer, &self.torque);
        writer.finish()
    }

    /// Reads the CDR bytes.
    pub fn decode(data: &[u8]) -> Result<WrenchStamped, CdrError> {
        let mut reader = CdrReader::new(data)?;
        let wrench = WrenchStamped {
            header: read_header(&mut reader)?,
            force: read_f64s(&mut reader, ["wrench.force.x", "wrench.force.y", "wrench.force.z"])?,
            torque: read_f64s(&mut reader, ["wrench.torque.x", "wrench.torque.y", "wrench.torque.z"])?,
        };
        reader.finish("wrench.torque.z")?;
        Ok(wrench)
    }
}

/// Smallest CDR size of one `TransformStamped` (stamp, two empty strings, seven doubles).
const MIN_TRANSFORM_BYTES: usize = 8 + 4 + 4 + 7 * 8;

/// `tf2_msgs/TFMessage`'s CDR bytes.
pub fn encode_tf(transforms: &[TransformStamped]) -> Vec<u8> {
    let mut writer = CdrWriter::new();
    writer.count(transforms.len());
    for transform in transforms {
        write_header(&mut writer, &transform.header);
        writer.string(&transform.child_frame_id);
        write_f64s(&mut writer, &transform.translation);
        write_f64s(&mut writer, &transform.rotation_xyzw);
    }
    writer.finish()
}

/// Reads a `tf2_msgs/TFMessage`.
pub fn decode_tf(data: &[u8]) -> Result<Vec<TransformStamped>, CdrError> {
    let mut reader = CdrReader::new(data)?;
    let count = reader.count("transforms", MIN_TRANSFORM_BYTES)?;
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        let header = read_header(&mut reader)?;
        let child_frame_id = reader.string("child_frame_id")?;
        out.push(TransformStamped {
            header,
            child_frame_id,
            translation: read_f64s(
                &mut reader,
                [
                    "transform.translation.x",
                    "transform.translation.y",
                    "transform.translation.z",
                ],
            )?,
            rotation_xyzw: read_f64s(
                &mut reader,
                [
                    "transform.rotation.x",
                    "transform.rotation.y",
                    "transform.rotation.z",
                    "transform.rotation.w",
                ],
            )?,
        });
    }
    reader.finish(if count == 0 {
        "transforms' length"
    } else {
        "transform.rotation.w"
    })?;
    Ok(out)
}

impl JointState {
    /// The CDR bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut writer = CdrWriter::new();
        write_header(&mut writer, &self.header);
        writer.string_seq(&self.name);
        writer.f64_seq(&self.position);
        writer.f64_seq(&self.velocity);
        writer.f64_seq(&self.effort);
        writer.finish()
    }

    /// Reads the CDR bytes.
    pub fn decode(data: &[u8]) -> Result<JointState, CdrError> {
        let mut reader = CdrReader::new(data)?;
        let joints = JointState {
            header: read_header(&mut reader)?,
            name: reader.string_seq("name")?,
            position: reader.f64_seq("position")?,
            velocity: reader.f64_seq("velocity")?,
            effort: reader.f64_seq("effort")?,
        };
        reader.finish("effort")?;
        Ok(joints)
    }
}

/// `std_msgs/MultiArrayDimension`: one dimension of a multi-array's layout.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct MultiArrayDimension {
    /// Its name.
    pub label: String,
    /// Its length.
    pub size: u32,
    /// Its stride.
    pub stride: u32,
}

/// `std_msgs/Float64MultiArray` (its `layout` flattened: `dim` and `data_offset`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Float64MultiArray {
    /// `layout.dim`.
    pub dim: Vec<MultiArrayDimension>,
    /// `layout.data_offset`: numbers before the array's first element.
    pub data_offset: u32,
    /// The numbers.
    pub data: Vec<f64>,
}

impl Float64MultiArray {
    /// The CDR bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut writer = CdrWriter::new();
        writer.count(self.dim.len());
        for dim in &self.dim {
            writer.string(&dim.label);
            writer.u32(dim.size);
            writer.u32(dim.stride);
        }
        writer.u32(self.data_offset);
        writer.f64_seq(&self.data);
        writer.finish()
    }

    /// Reads the CDR bytes.
    pub fn decode(data: &[u8]) -> Result<Float64MultiArray, CdrError> {
        let mut reader = CdrReader::new(data)?;
        // A dimension is at least a string (length and NUL) and two `uint32`s.
        let count = reader.count("layout.dim", 4 + 1 + 8)?;
        let mut dim = Vec::with_capacity(count);
        for _ in 0..count {
            dim.push(MultiArrayDimension {
                label: reader.string("layout.dim.label")?,
                size: reader.u32("layout.dim.size")?,
                stride: reader.u32("layout.dim.stride")?,
            });
        }
        let array = Float64MultiArray {
            dim,
            data_offset: reader.u32("layout.data_offset")?,
            data: reader.f64_seq("data")?,
        };
        reader.finish("data")?;
        Ok(array)
    }
}

/// `visualization_msgs/Marker`'s shape types skillc writes (the message's `type` constants).
pub mod marker_type {
    /// An arrow from `points[0]` to `points[1]` (scale: shaft diameter, head diameter, head length).
    pub const ARROW: i32 = 0;
    /// A box of extents `scale` centred on the pose.
    pub const CUBE: i32 = 1;
    /// An ellipsoid of diameters `scale`.
    pub const SPHERE: i32 = 2;
    /// A cylinder along the pose's z: diameters `scale.x`, `scale.y`, height `scale.z`.
    pub const CYLINDER: i32 = 3;
    /// Connected line segments through `points` (scale.x: line width).
    pub const LINE_STRIP: i32 = 4;
    /// Text at the pose, facing the viewer (scale.z: letter height).
    pub const TEXT_VIEW_FACING: i32 = 9;
}

/// `visualization_msgs/Marker`'s `action` constants.
pub mod marker_action {
    /// Add or replace the marker `(ns, id)`.
    pub const ADD: i32 = 0;
    /// Remove the marker `(ns, id)`.
    pub const DELETE: i32 = 2;
}

/// `visualization_msgs/Marker`: one shape a 3-D viewer draws. The fields skillc does not use
/// (per-point colours, textures, embedded meshes) are written empty and must be empty when read.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Marker {
    /// Stamp and the frame the pose is in.
    pub header: Header,
    /// Namespace: with `id`, what names the marker.
    pub ns: String,
    /// Its number in the namespace.
    pub id: i32,
    /// One of [`marker_type`] (the message's `type`).
    pub shape: i32,
    /// One of [`marker_action`].
    pub action: i32,
    /// Position of the pose \[m\].
    pub position: [f64; 3],
    /// Orientation of the pose `[x, y, z, w]`.
    pub orientation_xyzw: [f64; 4],
    /// Size, as the shape reads it \[m\].
    pub scale: [f64; 3],
    /// Colour `[r, g, b, a]`, each 0 to 1.
    pub color_rgba: [f32; 4],
    /// How long a viewer shows it (zero: until replaced).
    pub lifetime: Time,
    /// Whether it moves with its frame after it is drawn.
    pub frame_locked: bool,
    /// Points of an arrow or a line \[m\].
    pub points: Vec<[f64; 3]>,
    /// A text marker's text.
    pub text: String,
}

/// Smallest CDR size of one `Marker` (every string empty, every sequence empty).
const MIN_MARKER_BYTES: usize = 100;

fn write_marker(writer: &mut CdrWriter, marker: &Marker) {
    write_header(writer, &marker.header);
    writer.string(&marker.ns);
    writer.i32(marker.id);
    writer.i32(marker.shape);
    writer.i32(marker.action);
    write_f64s(writer, &marker.position);
    write_f64s(writer, &marker.orientation_xyzw);
    write_f64s(writer, &marker.scale);
    for channel in marker.color_rgba {
        writer.f32(channel);
    }
    writer.i32(marker.lifetime.sec);
    writer.u32(marker.lifetime.nanosec);
    writer.bool(marker.frame_locked);
    writer.count(marker.points.len());
    for point in &marker.points {
        write_f64s(writer, point);
    }
    writer.count(0); // colors
    writer.string(""); // texture_resource
    write_header(writer, &Header::default()); // texture.header
    writer.string(""); // texture.format
    writer.bytes(&[]); // texture.data
    writer.count(0); // uv_coordinates
    writer.string(&marker.text);
    writer.string(""); // mesh_resource
    writer.string(""); // mesh_file.filename
    writer.bytes(&[]); // mesh_file.data
    writer.bool(false); // mesh_use_embedded_materials
}

/// Reads one of the fields skillc writes empty, and refuses it when it is not.
fn expect_empty(what: &str, len: usize, offset: usize) -> Result<(), CdrError> {
    if len == 0 {
        Ok(())
    } else {
        Err(CdrError {
            offset,
            reason: format!("marker.{what} holds {len} element(s): skillc reads markers without them"),
        })
    }
}

fn read_marker(reader: &mut CdrReader<'_>) -> Result<Marker, CdrError> {
    let header = read_header(reader)?;
    let ns = reader.string("marker.ns")?;
    let id = reader.i32("marker.id")?;
    let shape = reader.i32("marker.type")?;
    let action = reader.i32("marker.action")?;
    let position = read_f64s(
        reader,
        [
            "marker.pose.position.x",
            "marker.pose.position.y",
            "marker.pose.position.z",
        ],
    )?;
    let orientation_xyzw = read_f64s(
        reader,
        [
            "marker.pose.orientation.x",
            "marker.pose.orientation.y",
            "marker.pose.orientation.z",
            "marker.pose.orientation.w",
        ],
    )?;
    let scale = read_f64s(reader, ["marker.scale.x", "marker.scale.y", "marker.scale.z"])?;
    let mut color_rgba = [0.0f32; 4];
    for (slot, what) in
        color_rgba
            .iter_mut()
            .zip(["marker.color.r", "marker.color.g", "marker.color.b", "marker.color.a"])
    {
        *slot = reader.f32(what)?;
    }
    let lifetime = Time {
        sec: reader.i32("marker.lifetime.sec")?,
        nanosec: reader.u32("marker.lifetime.nanosec")?,
    };
    let frame_locked = reader.bool("marker.frame_locked")?;
    let count = reader.count("marker.points", 24)?;
    let mut points = Vec::with_capacity(count);
    for _ in 0..count {
        points.push(read_f64s(
            reader,
            ["marker.points.x", "marker.points.y", "marker.points.z"],
        )?);
    }
    let at = reader.offset();
    expect_empty("colors", reader.count("marker.colors", 16)?, at)?;
    let _texture_resource = reader.string("marker.texture_resource")?;
    let _texture_header = read_header(reader)?;
    let _texture_format = reader.string("marker.texture.format")?;
    let at = reader.offset();
    expect_empty("texture.data", reader.bytes("marker.texture.data")?.len(), at)?;
    let at = reader.offset();
    expect_empty("uv_coordinates", reader.count("marker.uv_coordinates", 8)?, at)?;
    let text = reader.string("marker.text")?;
    let _mesh_resource = reader.string("marker.mesh_resource")?;
    let _mesh_filename = reader.string("marker.mesh_file.filename")?;
    let at = reader.offset();
    expect_empty("mesh_file.data", reader.bytes("marker.mesh_file.data")?.len(), at)?;
    let _embedded = reader.bool("marker.mesh_use_embedded_materials")?;
    Ok(Marker {
        header,
        ns,
        id,
        shape,
        action,
        position,
        orientation_xyzw,
        scale,
        color_rgba,
        lifetime,
        frame_locked,
        points,
        text,
    })
}

/// `visualization_msgs/MarkerArray`'s CDR bytes.
pub fn encode_markers(markers: &[Marker]) -> Vec<u8> {
    let mut writer = CdrWriter::new();
    writer.count(markers.len());
    for marker in markers {
        write_marker(&mut writer, marker);
    }
    writer.finish()
}

/// Reads a `visualization_msgs/MarkerArray`.
pub fn decode_markers(data: &[u8]) -> Result<Vec<Marker>, CdrError> {
    let mut reader = CdrReader::new(data)?;
    let count = reader.count("markers", MIN_MARKER_BYTES)?;
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        out.push(read_marker(&mut reader)?);
    }
    reader.finish(if count == 0 {
        "markers' length"
    } else {
        "marker.mesh_use_embedded_materials"
    })?;
    Ok(out)
}

/// `std_msgs/String`'s CDR bytes.
pub fn encode_string(text: &str) -> Vec<u8> {
    let mut writer = CdrWriter::new();
    writer.string(text);
    writer.finish()
}

/// Reads a `std_msgs/String`.
pub fn decode_string(data: &[u8]) -> Result<String, CdrError> {
    let mut reader = CdrReader::new(data)?;
    let text = reader.string("data")?;
    reader.finish("data")?;
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hex(bytes: &[u8]) -> String {
        bytes.iter().map(|b| format!("{b:02x}")).collect()
    }

    /// Bytes that `rosbags` (an independent CDR implementation, in Python) writes for the same
    /// messages, pasted from its output: our encoder must produce them byte for byte.
    #[test]
    fn encodings_match_an_independent_implementation() {
        let joints = JointState {
            header: Header {
                stamp: Time {
                    sec: 1_700_000_000,
                    nanosec: 123_456_789,
                },
                frame_id: "base_link".into(),
            },
            name: vec!["joint1".into(), "joint_2".into(), "j3".into()],
            position: vec![0.1, -1.5, std::f64::consts::PI],
            velocity: vec![],
            effort: vec![1.0, 2.0, 3.0],
        };
        assert_eq!(
            hex(&joints.encode()),
            "0001000000f1536515cd5b070a000000626173655f6c696e6b00000003000000070000006a6f696e7431000008000000\
             6a6f696e745f3200030000006a330000030000009a9999999999b93f000000000000f8bf182d4454fb21094000000000\
             03000000000000000000f03f00000000000000400000000000000840"
        );
        assert_eq!(JointState::decode(&joints.encode()).expect("decodes"), joints);
        let wrench = WrenchStamped {
            header: Header {
                stamp: Time { sec: 5, nanosec: 6 },
                frame_id: "tool0".into(),
            },
            force: [1.0, 2.0, 3.0],
            torque: [-0.1, -0.2, -0.3],
        };
        assert_eq!(
            hex(&wrench.encode()),
            "00010000050000000600000006000000746f6f6c3000000000000000000000000000f03f000000000000004000000000\
             000008409a9999999999b9bf9a9999999999c9bf333333333333d3bf"
        );
    }

    /// A marker array as `rosbags` (Python, its ROS 2 Jazzy type store) serialises it, pasted
    /// from its output: a box, then an arrow with two points and a text. Alignment inside a
    /// sequence of markers is counted from the message's start, which only a second marker tests.
    #[test]
    fn marker_arrays_match_an_independent_implementation() {
        let marker = |id: i32, shape: i32, points: Vec<[f64; 3]>, text: &str| Marker {
            header: Header {
                stamp: Time { sec: 3, nanosec: 5 },
                frame_id: "base".into(),
            },
            ns: "scene".into(),
            id,
            shape,
            action: marker_action::ADD,
            position: [0.5, -0.25, 0.125],
            orientation_xyzw: [0.0, 0.0, 0.0, 1.0],
            scale: [0.3, 0.8, 0.05],
            color_rgba: [0.5, 0.25, 1.0, 0.75],
            lifetime: Time::default(),
            frame_locked: true,
            points,
            text: text.into(),
        };
        let markers = vec![
            marker(1, marker_type::CUBE, vec![], ""),
            marker(7, marker_type::ARROW, vec![[0.5, 0.0, 0.1], [0.5, 0.0, 0.2]], "table"),
        ];
        let bytes = encode_markers(&markers);
        assert_eq!(
            hex(&bytes),
            "00010000020000000300000005000000050000006261736500000000060000007363656e650000000100000001000000\
             00000000000000000000e03f000000000000d0bf000000000000c03f0000000000000000000000000000000000000000\
             00000000000000000000f03f333333333333d33f9a9999999999e93f9a9999999999a93f0000003f0000803e0000803f\
             0000403f0000000000000000010000000000000000000000010000000000000000000000000000000100000000000000\
             010000000000000000000000000000000100000000000000010000000000000001000000000000000000000000000000\
             0300000005000000050000006261736500000000060000007363656e6500000007000000000000000000000000000000\
             0000e03f000000000000d0bf000000000000c03f00000000000000000000000000000000000000000000000000000000\
             0000f03f333333333333d33f9a9999999999e93f9a9999999999a93f0000003f0000803e0000803f0000403f00000000\
             000000000100000002000000000000000000e03f00000000000000009a9999999999b93f000000000000e03f00000000\
             000000009a9999999999c93f000000000100000000000000000000000000000001000000000000000100000000000000\
             0000000000000000060000007461626c65000000010000000000000001000000000000000000000000"
        );
        assert_eq!(decode_markers(&bytes), Ok(markers));
        for cut in 0..bytes.len() - 3 {
            assert!(decode_markers(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        assert!(decode_markers(&encode_string("scene")).is_err());
    }

    #[test]
    fn multi_arrays_round_trip_and_refuse_truncation() {
        let array = Float64MultiArray {
            dim: vec![MultiArrayDimension {
                label: "effort".into(),
                size: 3,
                stride: 3,
            }],
            data_offset: 0,
            data: vec![1.5, -2.0, f64::MAX],
        };
        let bytes = array.encode();
        // header, dim count, "effort\0" with its length, size, stride, offset, data count, then
        // the doubles from an 8-byte boundary.
        assert_eq!(&bytes[..8], &[0, 1, 0, 0, 1, 0, 0, 0]);
        assert_eq!(Float64MultiArray::decode(&bytes).expect("decodes"), array);
        for cut in 0..bytes.len() {
            assert!(Float64MultiArray::decode(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        assert_eq!(MsgType::Float64MultiArray.definition().matches("MSG: ").count(), 2);
    }

    #[test]
    fn messages_round_trip() {
        let header = Header {
            stamp: Time::from_seconds(12.345_678_901),
            frame_id: "base".into(),
        };
        assert_eq!(
            header.stamp,
            Time {
                sec: 12,
                nanosec: 345_678_901
            }
        );
        let pose = PoseStamped {
            header: header.clone(),
            position: [0.1, -0.2, 0.3],
            orientation_xyzw: [0.0, 1.0, 0.0, 0.0],
        };
        assert_eq!(PoseStamped::decode(&pose.encode()), Ok(pose));
        let joints = JointState {
            header: header.clone(),
            name: vec!["a".into(), "bb".into()],
            position: vec![1.0, 2.0],
            velocity: vec![],
            effort: vec![3.0, 4.0],
        };
        assert_eq!(JointState::decode(&joints.encode()), Ok(joints));
        let tf = vec![TransformStamped {
            header,
            child_frame_id: "tool".into(),
            translation: [1.0, 2.0, 3.0],
            rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
        }];
        assert_eq!(decode_tf(&encode_tf(&tf)), Ok(tf));
        assert_eq!(decode_string(&encode_string("press")), Ok("press".to_owned()));
    }

    #[test]
    fn one_type_read_as_another_is_an_error() {
        let pose = PoseStamped {
            header: Header {
                stamp: Time::from_seconds(1.0),
                frame_id: "base".into(),
            },
            position: [0.5, 0.0, 0.3],
            orientation_xyzw: [0.0, 1.0, 0.0, 0.0],
        };
        let err = WrenchStamped::decode(&pose.encode()).expect_err("a pose is not a wrench");
        assert!(
            err.reason
                .starts_with("8 byte(s) are left over after the last field (`wrench.torque.z`)"),
            "{err}"
        );
        let wrench = WrenchStamped {
            header: pose.header.clone(),
            ..WrenchStamped::default()
        };
        let err = PoseStamped::decode(&wrench.encode()).expect_err("a wrench is not a pose");
        assert!(err.reason.contains("pose.orientation.w"), "{err}");
        assert!(decode_tf(&pose.encode()).is_err());
        assert!(JointState::decode(&pose.encode()).is_err());
        assert!(decode_string(&pose.encode()).is_err());
    }

    #[test]
    fn empty_frame_ids_of_length_zero_are_read_without_misaligning() {
        let transform = TransformStamped {
            translation: [1.0, 2.0, 3.0],
            rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
            ..TransformStamped::default()
        };
        let written = encode_tf(std::slice::from_ref(&transform));
        assert_eq!(decode_tf(&written), Ok(vec![transform.clone()]));
        // The same transform with both empty strings as length 0 and no bytes: the count and the
        // stamp's seconds as written, then nanoseconds, the two lengths and padding to 24 bytes
        // after the header (all zero), seven doubles.
        let mut zero = written[..12].to_vec();
        zero.extend_from_slice(&[0; 16]);
        for value in [1.0f64, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0] {
            zero.extend_from_slice(&value.to_le_bytes());
        }
        assert_eq!(decode_tf(&zero), Ok(vec![transform]));
        let wrench = WrenchStamped {
            force: [1.0, 2.0, 3.0],
            ..WrenchStamped::default()
        };
        let mut zero = wrench.encode();
        // Length 0 for the empty frame_id's length 1; its NUL (byte 16) is then padding.
        zero[12] = 0;
        assert_eq!(WrenchStamped::decode(&zero), Ok(wrench));
    }

    #[test]
    fn negative_times_keep_nanoseconds_positive() {
        let time = Time::from_seconds(-0.25);
        assert_eq!(
            time,
            Time {
                sec: -1,
                nanosec: 750_000_000
            }
        );
        assert_eq!(time.nanos(), -250_000_000);
    }

    #[test]
    fn schema_names_are_matched_with_or_without_msg() {
        assert_eq!(
            MsgType::from_schema_name("geometry_msgs/PoseStamped"),
            Some(MsgType::PoseStamped)
        );
        assert_eq!(
            MsgType::from_schema_name("tf2_msgs/msg/TFMessage"),
            Some(MsgType::TfMessage)
        );
        assert_eq!(MsgType::from_schema_name("geometry_msgs/msg/Pose"), None);
        for ty in [
            MsgType::PoseStamped,
            MsgType::WrenchStamped,
            MsgType::TfMessage,
            MsgType::JointState,
            MsgType::String,
            MsgType::MarkerArray,
        ] {
            assert_eq!(definition_fields(&ty.definition()), ty.field_names(), "{ty:?}");
        }
        // As rosbag2 writes them: comments, a type without its package, a constant.
        let text =
            "# A wrench\nstd_msgs/Header header # stamp\nWrench wrench\nint8 MODE=1\n\n=====\nMSG: x/Y\nfloat64 z\n";
        assert_eq!(definition_fields(text), ["header", "wrench"]);
        assert!(MsgType::PoseStamped
            .definition()
            .contains("MSG: geometry_msgs/Quaternion\nfloat64 x"));
    }
}
