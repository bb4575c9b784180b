//! File-level I/O errors (wrapping the PLY and OBJ format errors with the path) and the attribute
//! errors shared by the writers.

use std::path::PathBuf;

use thiserror::Error;

use super::obj::ObjError;
use super::ply::PlyError;
use super::SUPPORTED_EXTENSIONS;

/// Why a mesh or point cloud could not be read from a file.
#[derive(Debug, Error)]
pub enum ReadError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {source}; check that the path exists and is readable")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The extension is not one we read.
    #[error("cannot read {path}: unsupported extension {extension:?}; supported extensions are {SUPPORTED_EXTENSIONS} (convert the file, e.g. with MeshLab)")]
    UnsupportedExtension {
        /// The file.
        path: PathBuf,
        /// Its extension (empty when it has none).
        extension: String,
    },
    /// The PLY content is invalid.
    #[error("{path}: {source}")]
    Ply {
        /// The file.
        path: PathBuf,
        /// The format error.
        source: PlyError,
    },
    /// The OBJ content is invalid.
    #[error("{path}: {source}")]
    Obj {
        /// The file.
        path: PathBuf,
        /// The format error.
        source: ObjError,
    },
}

/// Why a mesh or point cloud could not be written to a file.
#[derive(Debug, Error)]
pub enum WriteError {
    /// The file could not be created or written.
    #[error("cannot write {path}: {source}; check that the directory exists and is writable")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The extension is not one we write.
    #[error("cannot write {path}: unsupported extension {extension:?}; supported extensions are {SUPPORTED_EXTENSIONS}")]
    UnsupportedExtension {
        /// The file.
        path: PathBuf,
        /// Its extension (empty when it has none).
        extension: String,
    },
    /// The data is inconsistent (lengths, labels, indices, non-finite coordinates).
    #[error("cannot write {path}: {source}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong with the data.
        source: AttributeError,
    },
}

/// An inconsistency in in-memory mesh or cloud data found before encoding it.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum AttributeError {
    /// An attribute array does not have one entry per vertex/face.
    #[error("{what} has {len} entries but there are {expected}; make it one entry per element (or drop it)")]
    LengthMismatch {
        /// Which array (e.g. "vertex_labels").
        what: &'static str,
        /// Its length.
        len: usize,
        /// The number of vertices, points or faces.
        expected: usize,
    },
    /// A segment label above 14.
    #[error("{what}[{index}] = {value} is not a segment id (0..=14); fix the labelling before writing")]
    LabelOutOfRange {
        /// Which array.
        what: &'static str,
        /// Element index.
        index: usize,
        /// The label.
        value: u8,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {face} refers to vertex {index} but there are only {vertex_count} vertices; repair the mesh before writing")]
    IndexOutOfRange {
        /// Triangle index.
        face: usize,
        /// The bad vertex index.
        index: u32,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {index} has a non-finite coordinate {value}; remove or fix it before writing")]
    NonFinite {
        /// Vertex / point index.
        index: usize,
        /// The offending value.
        value: f64,
    },
}
