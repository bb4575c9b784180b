//! Stanford PLY: reader (ascii, binary little- and big-endian, every scalar type and alias, list
//! properties, unknown elements and properties skipped) and writer (binary little-endian by default).
//!
//! What is read: element `vertex` with `x`, `y`, `z` (any numeric type), optional `nx`, `ny`, `nz`
//! (all three or ignored), optional colours `red`, `green`, `blue` (or `diffuse_red`, ...; integer types
//! are clamped to 0..=255, float types are taken as 0..1 and scaled), optional `label` (any numeric type,
//! must be a segment id 0..=14); element `face` with a list `vertex_indices` (or `vertex_index`) of any
//! count and index types, polygons fan-triangulated, and an optional scalar `label`. Everything else is
//! skipped. Comments and `obj_info` lines are kept in [`PlyData::comments`].

mod body;
pub mod header;
mod write;

use thiserror::Error;

use crate::{PointCloud, TriMesh};

pub(crate) use write::{check_cloud, check_mesh, write_cloud_to, write_mesh_to};
pub use write::{cloud_to_bytes, mesh_to_bytes, to_bytes};

/// The body encoding of a PLY file (read from headers, chosen when writing).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlyEncoding {
    /// `format ascii 1.0`.
    Ascii,
    /// `format binary_little_endian 1.0` (the default for writing).
    #[default]
    BinaryLittleEndian,
    /// `format binary_big_endian 1.0`.
    BinaryBigEndian,
}

impl PlyEncoding {
    /// The name used in the `format` header line.
    pub fn header_name(self) -> &'static str {
        match self {
            PlyEncoding::Ascii => "ascii",
            PlyEncoding::BinaryLittleEndian => "binary_little_endian",
            PlyEncoding::BinaryBigEndian => "binary_big_endian",
        }
    }
}

/// Everything BSV takes from a PLY file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlyData {
    /// Encoding of the body that was read.
    pub encoding: PlyEncoding,
    /// `comment` and `obj_info` lines, without the keyword.
    pub comments: Vec<String>,
    /// Vertex positions (metres by convention).
    pub points: Vec<[f64; 3]>,
    /// Vertex normals when `nx`, `ny`, `nz` are present.
    pub normals: Option<Vec<[f64; 3]>>,
    /// Vertex colours when `red`, `green`, `blue` are present.
    pub colors: Option<Vec<[u8; 3]>>,
    /// Vertex segment labels when `label` is present.
    pub vertex_labels: Option<Vec<u8>>,
    /// Triangles (polygons fan-triangulated) when the file has a `face` element.
    pub triangles: Option<Vec<[u32; 3]>>,
    /// Per-triangle segment labels when the face element has `label`.
    pub face_labels: Option<Vec<u8>>,
}

impl PlyData {
    /// The vertices and faces as a mesh (normals and colours are dropped); an error if there is no
    /// face element.
    pub fn into_mesh(self) -> Result<TriMesh, PlyError> {
        let triangles = self.triangles.ok_or(PlyError::NoFaces { vertices: self.points.len() })?;
        Ok(TriMesh {
            vertices: self.points,
            triangles,
            vertex_labels: self.vertex_labels,
            face_labels: self.face_labels,
        })
    }

    /// The vertices with their normals, colours and labels as a point cloud (faces are dropped).
    pub fn into_cloud(self) -> PointCloud {
        PointCloud { points: self.points, normals: self.normals, colors: self.colors, labels: self.vertex_labels }
    }
}

/// Why PLY bytes could not be read. Every message says what to do about it.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlyError {
    /// Zero bytes.
    #[error("the file is empty (0 bytes); check the path, or export the mesh/cloud again")]
    Empty,
    /// The first line is not `ply`.
    #[error("not a PLY file: the first line is not `ply`; check the file type (or the extension)")]
    BadMagic,
    /// No `end_header` line.
    #[error("the PLY header has no `end_header` line (read {lines} lines); the file is truncated or not a PLY file")]
    HeaderNotTerminated {
        /// Header lines read.
        lines: usize,
    },
    /// No `format` line.
    #[error("the PLY header has no `format` line; add `format binary_little_endian 1.0` (or ascii) after `ply`")]
    MissingFormat,
    /// An unknown format or version.
    #[error("unsupported PLY format {format:?}; supported: ascii, binary_little_endian and binary_big_endian, version 1.0 — convert the file (e.g. with MeshLab)")]
    UnsupportedFormat {
        /// The format (and version) found.
        format: String,
    },
    /// A malformed header line.
    #[error("PLY header line {line}: {message}; fix the header")]
    HeaderSyntax {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A property type that PLY does not define.
    #[error("PLY header line {line}: unknown type `{name}`; use one of char/int8, uchar/uint8, short/int16, ushort/uint16, int/int32, uint/uint32, float/float32, double/float64")]
    UnknownType {
        /// 1-based line number.
        line: usize,
        /// The type found.
        name: String,
    },
    /// A required element is not declared.
    #[error("the PLY file has no `{element}` element; a point cloud or mesh needs `element vertex N` with x, y, z")]
    MissingElement {
        /// The element name.
        element: String,
    },
    /// A required property is not declared.
    #[error("element `{element}` has no scalar property `{property}`; {hint}")]
    MissingProperty {
        /// The element.
        element: String,
        /// The property (or the alternatives).
        property: String,
        /// What to do.
        hint: &'static str,
    },
    /// A mesh was asked for but the file has no face element.
    #[error("the PLY file has {vertices} vertices and no `face` element: it is a point cloud, not a mesh; read it as a point cloud or pass a mesh file")]
    NoFaces {
        /// Number of vertices.
        vertices: usize,
    },
    /// A binary body shorter than its header declares.
    #[error("binary body truncated in element `{element}` at record {index} of {count}: {needed} bytes needed from body offset {offset}, {available} available; the file was cut short (copy or export it again) or its header declares too many records")]
    Truncated {
        /// The element.
        element: String,
        /// First incomplete record.
        index: usize,
        /// Declared record count.
        count: usize,
        /// Byte offset (from the start of the body) where the needed span starts.
        offset: usize,
        /// Bytes needed from `offset`.
        needed: usize,
        /// Bytes available from `offset`.
        available: usize,
    },
    /// An ascii body with fewer records than the header declares.
    #[error("the ascii body ends at record {index} of element `{element}` but the header declares {count}; the header's element count does not match the data — fix the count or export the file again")]
    EndsEarly {
        /// The element.
        element: String,
        /// Records found.
        index: usize,
        /// Records declared.
        count: usize,
    },
    /// Data after the last declared record.
    #[error("found {extra} after the last declared record (element `{element}`, {count} declared); the header's element counts do not match the data — fix the counts or export the file again")]
    ExtraData {
        /// The last element of the header.
        element: String,
        /// Its declared count.
        count: usize,
        /// What was found (lines or bytes).
        extra: String,
    },
    /// A malformed ascii record.
    #[error("line {line}: element `{element}` record {index}: {message}; the header's properties do not match the data — fix the file")]
    AsciiRecord {
        /// 1-based line number in the file.
        line: usize,
        /// The element.
        element: String,
        /// Record index.
        index: usize,
        /// What is wrong.
        message: String,
    },
    /// A list count that is negative or not an integer.
    #[error("element `{element}` record {index}: invalid list length {value}; the file is corrupt — export it again")]
    BadListCount {
        /// The element.
        element: String,
        /// Record index.
        index: usize,
        /// The value read.
        value: f64,
    },
    /// A face with fewer than three vertices.
    #[error("face {face} has {n} vertices; faces need at least 3 — remove it (e.g. MeshLab 'Remove Zero Area Faces') or export again")]
    FaceTooSmall {
        /// Face record index.
        face: usize,
        /// Its vertex count.
        n: usize,
    },
    /// A face refers to a vertex that does not exist.
    #[error("face {face} refers to vertex {index} but the file has {vertex_count} vertices (valid: 0..{vertex_count}); the file is corrupt or its vertex count is wrong — export it again")]
    FaceIndexOutOfRange {
        /// Face record index.
        face: usize,
        /// The index read.
        index: f64,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite coordinate ({value}); clean the cloud first (drop invalid depth pixels / NaN points) and write it again")]
    NonFinite {
        /// Vertex index.
        vertex: usize,
        /// The value read.
        value: f64,
    },
    /// A label that is not a segment id.
    #[error("element `{element}` record {index} has label {value}, which is not a segment id (0..=14, see DESIGN.md); fix the labelling or drop the `label` property")]
    LabelOutOfRange {
        /// The element.
        element: String,
        /// Record index.
        index: usize,
        /// The value read.
        value: f64,
    },
}

/// Parses a whole PLY file held in memory.
pub fn parse(bytes: &[u8]) -> Result<PlyData, PlyError> {
    let header = header::parse_header(bytes)?;
    body::read_body(bytes, &header)
}

/// Parses PLY bytes into a mesh (the file needs a face element).
pub fn parse_mesh(bytes: &[u8]) -> Result<TriMesh, PlyError> {
    parse(bytes)?.into_mesh()
}

/// Parses PLY bytes into a point cloud (a mesh's vertices are read as a cloud).
pub fn parse_cloud(bytes: &[u8]) -> Result<PointCloud, PlyError> {
    parse(bytes).map(PlyData::into_cloud)
}
