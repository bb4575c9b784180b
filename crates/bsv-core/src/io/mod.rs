//! PLY and OBJ readers and writers (DESIGN.md "Formats").
//!
//! File-level entry points pick the format from the extension (`.ply`, `.obj`, case-insensitive) and
//! wrap the format errors with the path. The in-memory parsers and encoders live in [`ply`] and
//! [`obj`] (used by tests and fuzzing).

pub mod error;
pub mod obj;
pub mod ply;
mod validate;

use std::io::Write;
use std::path::Path;

use crate::{PointCloud, TriMesh};

pub use error::{ReadError, WriteError};
pub use ply::PlyEncoding;
pub use validate::AttributeError;

/// File formats known by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Stanford PLY (`.ply`).
    Ply,
    /// Wavefront OBJ (`.obj`).
    Obj,
}

/// The extensions this module reads and writes, for messages.
pub const SUPPORTED_EXTENSIONS: &str = ".ply, .obj";

impl Format {
    /// The format of `path` from its extension (case-insensitive), or `None`.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "ply" => Some(Format::Ply),
            "obj" => Some(Format::Obj),
            _ => None,
        }
    }
}

fn extension_of(path: &Path) -> String {
    path.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default()
}

fn read_bytes(path: &Path) -> Result<Vec<u8>, ReadError> {
    std::fs::read(path).map_err(|source| ReadError::Io { path: path.to_path_buf(), source })
}

/// Reads a triangle mesh from a `.ply` (with a face element) or `.obj` file.
pub fn read_mesh(path: &Path) -> Result<TriMesh, ReadError> {
    read_mesh_with_report(path).map(|(m, _)| m)
}

/// Reads a triangle mesh like [`read_mesh`] and also returns the OBJ report (unknown group names and
/// the like; empty for PLY files).
pub fn read_mesh_with_report(path: &Path) -> Result<(TriMesh, obj::ObjReport), ReadError> {
    let format = Format::from_path(path)
        .ok_or_else(|| ReadError::UnsupportedExtension { path: path.to_path_buf(), extension: extension_of(path) })?;
    let bytes = read_bytes(path)?;
    match format {
        Format::Ply => ply::parse_mesh(&bytes)
            .map(|m| (m, obj::ObjReport::default()))
            .map_err(|source| ReadError::Ply { path: path.to_path_buf(), source }),
        Format::Obj => obj::parse(&bytes).map_err(|source| ReadError::Obj { path: path.to_path_buf(), source }),
    }
}

/// Reads a point cloud: a PLY's vertex element (a mesh PLY's vertices too), or an OBJ's `v` lines.
pub fn read_point_cloud(path: &Path) -> Result<PointCloud, ReadError> {
    let format = Format::from_path(path)
        .ok_or_else(|| ReadError::UnsupportedExtension { path: path.to_path_buf(), extension: extension_of(path) })?;
    let bytes = read_bytes(path)?;
    match format {
        Format::Ply => ply::parse_cloud(&bytes).map_err(|source| ReadError::Ply { path: path.to_path_buf(), source }),
        Format::Obj => obj::parse_points(&bytes)
            .map(PointCloud::new)
            .map_err(|source| ReadError::Obj { path: path.to_path_buf(), source }),
    }
}

fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    write_file_atomic(path, |f| f.write_all(bytes))
}

/// Writes a file atomically: `write` fills a temporary file in `path`'s folder, which then replaces
/// `path` by a rename. A failed or interrupted write (full disk, file-size limit, an error of `write`)
/// leaves `path` as it was and removes the temporary file; readers never see a half-written file.
/// Every writer of this module goes through it; front ends use it for their own files (JSON).
pub fn write_file_atomic(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> Result<(), WriteError> {
    let io_err = |source| WriteError::Io { path: path.to_path_buf(), source };
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new().prefix(".bsv-partial-").tempfile_in(folder).map_err(io_err)?;
    write(tmp.as_file_mut()).map_err(io_err)?;
    tmp.as_file_mut().flush().map_err(io_err)?;
    tmp.persist(path).map_err(|e| io_err(e.error))?;
    Ok(())
}

/// Streams PLY into a new file at `path` (no file-sized buffer in memory) once `check` accepted the data.
fn write_ply_file(
    path: &Path,
    check: impl FnOnce() -> Result<(), AttributeError>,
    write: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> Result<(), WriteError> {
    check().map_err(|source| WriteError::Invalid { path: path.to_path_buf(), source })?;
    write_file_atomic(path, write)
}

fn format_for_write(path: &Path) -> Result<Format, WriteError> {
    Format::from_path(path)
        .ok_or_else(|| WriteError::UnsupportedExtension { path: path.to_path_buf(), extension: extension_of(path) })
}

/// Writes a mesh by extension: `.ply` as binary little-endian PLY, `.obj` as OBJ with segment groups.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<(), WriteError> {
    write_mesh_with(path, mesh, PlyEncoding::BinaryLittleEndian)
}

/// Writes a mesh by extension with the given PLY encoding (ignored for `.obj`).
pub fn write_mesh_with(path: &Path, mesh: &TriMesh, encoding: PlyEncoding) -> Result<(), WriteError> {
    let invalid = |source| WriteError::Invalid { path: path.to_path_buf(), source };
    match format_for_write(path)? {
        Format::Ply => write_ply_file(path, || ply::check_mesh(mesh), |f| ply::write_mesh_to(f, mesh, encoding)),
        Format::Obj => write_bytes(path, obj::to_string(mesh).map_err(invalid)?.as_bytes()),
    }
}

/// Writes a point cloud as binary little-endian PLY (`.ply`) or as OBJ `v` lines (`.obj`).
pub fn write_point_cloud(path: &Path, cloud: &PointCloud) -> Result<(), WriteError> {
    write_point_cloud_with(path, cloud, PlyEncoding::BinaryLittleEndian)
}

/// Writes a point cloud with the given PLY encoding (ignored for `.obj`, which keeps points only).
pub fn write_point_cloud_with(path: &Path, cloud: &PointCloud, encoding: PlyEncoding) -> Result<(), WriteError> {
    let invalid = |source| WriteError::Invalid { path: path.to_path_buf(), source };
    match format_for_write(path)? {
        Format::Ply => write_ply_file(path, || ply::check_cloud(cloud), |f| ply::write_cloud_to(f, cloud, encoding)),
        Format::Obj => {
            let mesh = TriMesh::new(cloud.points.clone(), Vec::new());
            write_bytes(path, obj::to_string(&mesh).map_err(invalid)?.as_bytes())
        }
    }
}
