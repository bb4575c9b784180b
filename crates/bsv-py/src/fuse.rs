//! Python bindings of the cloud builder (in progress).

use pyo3::prelude::*;

/// Registers the cloud-builder functions on the module.
pub fn register(_m: &Bound<'_, PyModule>) -> PyResult<()> {
    Ok(())
}
