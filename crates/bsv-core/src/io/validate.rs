//! Consistency checks run by the writers before encoding (lengths, labels, indices, finiteness) and
//! the error they return.

use thiserror::Error;

use crate::mesh::{check_indices, MeshInvariant};
use crate::segment::SEGMENT_COUNT;

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
    #[error("{0}; repair the mesh before writing")]
    Mesh(#[from] MeshInvariant),
    /// A coordinate is NaN or infinite.
    #[error("vertex {index} has a non-finite coordinate {value}; remove or fix it before writing")]
    NonFinite {
        /// Vertex / point index.
        index: usize,
        /// The offending value.
        value: f64,
    },
}

/// Checks that an optional attribute array has `expected` entries.
pub(crate) fn length<T>(what: &'static str, v: Option<&[T]>, expected: usize) -> Result<(), AttributeError> {
    match v {
        Some(v) if v.len() != expected => Err(AttributeError::LengthMismatch { what, len: v.len(), expected }),
        _ => Ok(()),
    }
}

/// Checks that every label is a segment id.
pub(crate) fn labels(what: &'static str, v: Option<&[u8]>) -> Result<(), AttributeError> {
    if let Some(v) = v {
        if let Some((index, &value)) = v.iter().enumerate().find(|(_, &l)| usize::from(l) >= SEGMENT_COUNT) {
            return Err(AttributeError::LabelOutOfRange { what, index, value });
        }
    }
    Ok(())
}

/// Checks that every coordinate is finite.
pub(crate) fn finite(points: &[[f64; 3]]) -> Result<(), AttributeError> {
    if points.iter().all(|p| p.iter().all(|c| c.is_finite())) {
        return Ok(());
    }
    for (index, p) in points.iter().enumerate() {
        if let Some(&value) = p.iter().find(|c| !c.is_finite()) {
            return Err(AttributeError::NonFinite { index, value });
        }
    }
    Ok(())
}

/// Checks that every triangle index is below `n_vertices`.
pub(crate) fn indices(triangles: &[[u32; 3]], n_vertices: usize) -> Result<(), AttributeError> {
    Ok(check_indices(triangles, n_vertices)?)
}
