//! `bsv._bsv.mass_properties`: the segment mass properties of `bsv_volume::segment_mass_with` as
//! Python dicts (conversion only).

use crate::classes::to_py;
use crate::convert::mesh_from;
use crate::errors::py_err;
use bsv_core::Segment;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// Mass properties per unit density of a closed labelled mesh and of each segment:
/// `{"whole": props, "segments": {name: props}, "interfaces": [{"a", "b", "centroid", "vertices",
/// "closed"}], "inverted": bool, "notes": [str]}` with `props = {"volume_m3", "centroid",
/// "inertia_m5"}`. `islands` merges small label islands first (`SegmentOptions::fitted()`).
#[pyfunction]
#[pyo3(signature = (vertices, faces, vertex_labels=None, face_labels=None, close_holes=false, islands=false))]
fn mass_properties<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    vertex_labels: Option<&Bound<'py, PyAny>>,
    face_labels: Option<&Bound<'py, PyAny>>,
    close_holes: bool,
    islands: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let mesh = mesh_from(vertices, faces, vertex_labels, face_labels)?;
    let base = if islands { bsv_volume::SegmentOptions::fitted() } else { bsv_volume::SegmentOptions::default() };
    let opts = bsv_volume::SegmentOptions { close_holes, ..base };
    let sm = py.detach(|| bsv_volume::segment_mass_with(&mesh, &opts)).map_err(py_err)?;
    let out = PyDict::new(py);
    out.set_item("whole", to_py(py, &sm.whole)?)?;
    let segments = PyDict::new(py);
    for (s, p) in &sm.segments {
        segments.set_item(s.name(), to_py(py, p)?)?;
    }
    out.set_item("segments", segments)?;
    let name = |l: u8| Segment::from_id(l).map_or("unknown", Segment::name);
    let interfaces = PyList::empty(py);
    for i in &sm.interfaces {
        let d = PyDict::new(py);
        d.set_item("a", name(i.lo))?;
        d.set_item("b", name(i.hi))?;
        d.set_item("centroid", i.centroid.to_vec())?;
        d.set_item("vertices", i.vertices)?;
        d.set_item("closed", i.closed)?;
        interfaces.append(d)?;
    }
    out.set_item("interfaces", interfaces)?;
    out.set_item("inverted", sm.inverted)?;
    out.set_item("notes", sm.notes.clone())?;
    Ok(out)
}

/// Registers the function on the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(mass_properties, m)?)
}
