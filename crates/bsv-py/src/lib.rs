//! `bsv._bsv`: the thin pyo3 layer over the BSV crates. It converts Python arrays to core types and
//! back (the one validation layer of Python input), releases the GIL around heavy work, and raises
//! the exception classes of `bsv.errors` for typed Rust errors. No algorithm lives here.

mod classes;
mod convert;
mod errors;
mod functions;
mod fuse;
mod mass;
mod register;
mod segments;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _bsv(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<classes::PyRegisterParams>()?;
    m.add_class::<classes::PyRegistration>()?;
    m.add_class::<classes::PyVolumeReport>()?;
    m.add_class::<classes::PyPreparedVolumes>()?;
    m.add_function(wrap_pyfunction!(register::register, m)?)?;
    functions::register(m)?;
    fuse::register(m)?;
    segments::register(m)?;
    mass::register(m)?;
    Ok(())
}
