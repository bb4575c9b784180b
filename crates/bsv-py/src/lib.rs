//! `bsv._bsv`: the thin pyo3 layer over the BSV crates. It converts numpy arrays to core types and
//! back, releases the GIL around heavy work, and maps typed Rust errors to Python exceptions.
//! No algorithm lives here.

mod convert;
mod errors;
mod functions;
mod fuse;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _bsv(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    functions::register(m)?;
    fuse::register(m)?;
    Ok(())
}
