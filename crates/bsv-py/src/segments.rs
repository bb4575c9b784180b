//! The segment table of `bsv_core::Segment`, exported as module constants (the Python copies of the
//! table are built from these).

use bsv_core::{Aggregate, Segment, EXTREMITIES, PALETTE, TRUNK_LIMBS};
use pyo3::prelude::*;

/// Adds `SEGMENT_NAMES` (name by id, 0 = "unlabelled"), `PALETTE` ((r, g, b) by id),
/// `TRUNK_LIMBS` and `EXTREMITIES` (ids) and `AGGREGATES` (name -> member ids; empty for `whole`, every
/// segment present) to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let all: Vec<Segment> = std::iter::once(Segment::Unlabelled).chain(Segment::ALL).collect();
    let names: Vec<&'static str> = all.iter().map(|s| s.name()).collect();
    let palette: Vec<(u8, u8, u8)> = PALETTE.iter().map(|c| (c[0], c[1], c[2])).collect();
    let ids = |segs: &[Segment]| segs.iter().map(|s| s.id()).collect::<Vec<u8>>();
    let py = m.py();
    m.add("SEGMENT_NAMES", pyo3::types::PyTuple::new(py, names)?)?;
    m.add("PALETTE", pyo3::types::PyTuple::new(py, palette)?)?;
    m.add("TRUNK_LIMBS", pyo3::types::PyTuple::new(py, ids(&TRUNK_LIMBS))?)?;
    m.add("EXTREMITIES", pyo3::types::PyTuple::new(py, ids(&EXTREMITIES))?)?;
    let aggregates = pyo3::types::PyDict::new(py);
    for a in Aggregate::ALL {
        aggregates.set_item(a.name(), pyo3::types::PyTuple::new(py, ids(a.members().unwrap_or(&[])))?)?;
    }
    m.add("AGGREGATES", aggregates)?;
    Ok(())
}
