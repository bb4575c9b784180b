//! File-level I/O errors: the PLY and OBJ format errors and the writers' attribute errors wrapped with
//! the path. Nothing here is imported by the format modules (the attribute errors live in `validate`),
//! so the dependency runs one way: `error` -> `obj`, `ply`, `validate`.

use std::path::PathBuf;

use thiserror::Error;

use super::obj::ObjError;
use super::ply::PlyError;
use super::validate::AttributeError;
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
    #[error(
        "cannot write {path}: unsupported extension {extension:?}; supported extensions are {SUPPORTED_EXTENSIONS}"
    )]
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
