//! Consistency checks run by the writers before encoding (lengths, labels, indices, finiteness).

use super::error::AttributeError;
use crate::segment::SEGMENT_COUNT;

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
    for (face, t) in triangles.iter().enumerate() {
        if let Some(&index) = t.iter().find(|&&i| i as usize >= n_vertices) {
            return Err(AttributeError::IndexOutOfRange { face, index, vertex_count: n_vertices });
        }
    }
    Ok(())
}
