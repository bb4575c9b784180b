//! Python exceptions of `bsv._bsv` and the mapping of core errors onto them (message = Rust message).

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(bsv._bsv, BsvError, PyException, "Base class of every BSV error.");
create_exception!(bsv._bsv, FormatError, BsvError, "A file could not be read: malformed, truncated or unsupported.");
create_exception!(bsv._bsv, WriteError, BsvError, "A file could not be written.");
create_exception!(bsv._bsv, InputError, BsvError, "Arrays or parameters passed from Python are not valid.");
create_exception!(bsv._bsv, MeshError, BsvError, "A mesh failed a check: open, non-manifold, degenerate.");
create_exception!(bsv._bsv, VolumeError, BsvError, "Volumes could not be computed (open or non-manifold segments).");
create_exception!(bsv._bsv, RegistrationError, BsvError, "The registration rejected its inputs or failed.");
create_exception!(bsv._bsv, ScanError, BsvError, "The virtual scanner rejected its inputs or failed.");

/// The error's message followed by its chain of causes.
fn message(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(c) = src {
        let m = c.to_string();
        if !s.contains(&m) {
            s.push_str(": ");
            s.push_str(&m);
        }
        src = c.source();
    }
    s
}

/// Converts a read error into `FormatError`.
pub fn format_err(e: impl std::error::Error) -> PyErr {
    FormatError::new_err(message(&e))
}

/// Converts a write error into `WriteError`.
pub fn write_err(e: impl std::error::Error) -> PyErr {
    WriteError::new_err(message(&e))
}

/// Converts a mesh-check error into `MeshError`.
pub fn mesh_err(e: impl std::error::Error) -> PyErr {
    MeshError::new_err(message(&e))
}

/// Converts a volume error into `VolumeError`.
pub fn volume_err(e: impl std::error::Error) -> PyErr {
    VolumeError::new_err(message(&e))
}

/// Converts a registration error into `RegistrationError`.
pub fn register_err(e: impl std::error::Error) -> PyErr {
    RegistrationError::new_err(message(&e))
}

/// Converts a scanner error into `ScanError`.
pub fn scan_err(e: impl std::error::Error) -> PyErr {
    ScanError::new_err(message(&e))
}

/// Converts a JSON (de)serialisation error of parameters into `InputError`.
pub fn input_err(e: impl std::error::Error) -> PyErr {
    InputError::new_err(message(&e))
}

/// Registers the exception classes on the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("BsvError", py.get_type::<BsvError>())?;
    m.add("FormatError", py.get_type::<FormatError>())?;
    m.add("WriteError", py.get_type::<WriteError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("MeshError", py.get_type::<MeshError>())?;
    m.add("VolumeError", py.get_type::<VolumeError>())?;
    m.add("RegistrationError", py.get_type::<RegistrationError>())?;
    m.add("ScanError", py.get_type::<ScanError>())?;
    Ok(())
}
