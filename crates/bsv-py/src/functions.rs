//! The functions of `bsv._bsv` (see `python/bsv/_bsv.pyi`): conversion, one library call, conversion.

use crate::convert::{cloud_from, cloud_to, mesh_from, mesh_to};
use crate::errors::{format_err, input_err, mesh_err, register_err, scan_err, volume_err, write_err};
use bsv_core::io::{self, PlyEncoding};
use bsv_capture::scanner::{self, Condition, Rig};
use bsv_core::template::{template, TemplateKind};
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use std::path::PathBuf;

fn encoding(ascii: bool) -> PlyEncoding {
    if ascii {
        PlyEncoding::Ascii
    } else {
        PlyEncoding::BinaryLittleEndian
    }
}

/// Reads a PLY/OBJ mesh: `(vertices, faces, vertex_labels, face_labels)`.
#[pyfunction]
fn read_mesh<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyTuple>> {
    let mesh = py.detach(|| io::read_mesh(&path)).map_err(format_err)?;
    mesh_to(py, &mesh)
}

/// Reads a PLY point cloud: `(points, normals, colors, labels)`.
#[pyfunction]
fn read_point_cloud<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyTuple>> {
    let cloud = py.detach(|| io::read_point_cloud(&path)).map_err(format_err)?;
    cloud_to(py, &cloud)
}

/// Writes a mesh (PLY or OBJ by extension).
#[pyfunction]
fn write_mesh(
    py: Python<'_>,
    path: PathBuf,
    vertices: PyReadonlyArray2<'_, f64>,
    faces: PyReadonlyArray2<'_, i64>,
    vertex_labels: Option<PyReadonlyArray1<'_, u8>>,
    face_labels: Option<PyReadonlyArray1<'_, u8>>,
    ascii: bool,
) -> PyResult<()> {
    let mesh = mesh_from(vertices, faces, vertex_labels, face_labels)?;
    py.detach(|| io::write_mesh_with(&path, &mesh, encoding(ascii))).map_err(write_err)
}

/// Writes a point cloud (PLY).
#[pyfunction]
fn write_point_cloud(
    py: Python<'_>,
    path: PathBuf,
    points: PyReadonlyArray2<'_, f64>,
    normals: Option<PyReadonlyArray2<'_, f64>>,
    colors: Option<PyReadonlyArray2<'_, u8>>,
    labels: Option<PyReadonlyArray1<'_, u8>>,
    ascii: bool,
) -> PyResult<()> {
    let cloud = cloud_from(points, normals, colors, labels)?;
    py.detach(|| io::write_point_cloud_with(&path, &cloud, encoding(ascii))).map_err(write_err)
}

/// The mesh-check report as JSON.
#[pyfunction]
fn check_mesh(vertices: PyReadonlyArray2<'_, f64>, faces: PyReadonlyArray2<'_, i64>) -> PyResult<String> {
    let mesh = mesh_from(vertices, faces, None, None)?;
    let report = bsv_core::check::check_mesh(&mesh);
    serde_json::to_string(&report).map_err(input_err)
}

/// The volumes report (DESIGN.md "Formats") as JSON. `islands`: merge small label islands first
/// (`SegmentOptions::fitted()`, the policy for registered meshes).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (vertices, faces, vertex_labels, face_labels, density, close_holes, islands=false))]
fn volumes(
    py: Python<'_>,
    vertices: PyReadonlyArray2<'_, f64>,
    faces: PyReadonlyArray2<'_, i64>,
    vertex_labels: Option<PyReadonlyArray1<'_, u8>>,
    face_labels: Option<PyReadonlyArray1<'_, u8>>,
    density: f64,
    close_holes: bool,
    islands: bool,
) -> PyResult<String> {
    let mesh = mesh_from(vertices, faces, vertex_labels, face_labels)?;
    let base = if islands { bsv_volume::SegmentOptions::fitted() } else { bsv_volume::SegmentOptions::default() };
    let opts = bsv_volume::SegmentOptions { close_holes, ..base };
    let report = py.detach(|| bsv_volume::report_with(&mesh, density, &opts)).map_err(volume_err)?;
    Ok(report.to_json())
}

/// The embedded template (9 segments, or 14 with `full`).
#[pyfunction]
fn default_template<'py>(py: Python<'py>, full: bool) -> PyResult<Bound<'py, PyTuple>> {
    let kind = if full { TemplateKind::Full } else { TemplateKind::Default };
    let mesh = template(kind).map_err(mesh_err)?;
    mesh_to(py, &mesh)
}

/// Virtual two-camera capture: the merged labelled cloud; optionally writes the capture files.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn scan<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'_, f64>,
    faces: PyReadonlyArray2<'_, i64>,
    vertex_labels: Option<PyReadonlyArray1<'_, u8>>,
    face_labels: Option<PyReadonlyArray1<'_, u8>>,
    condition: &str,
    seed: u64,
    images_dir: Option<PathBuf>,
) -> PyResult<Bound<'py, PyTuple>> {
    let mesh = mesh_from(vertices, faces, vertex_labels, face_labels)?;
    let condition: Condition = condition.parse().map_err(scan_err)?;
    let s = py
        .detach(|| {
            let s = scanner::scan(&mesh, &Rig::paper_default(), condition, seed)?;
            if let Some(dir) = &images_dir {
                scanner::write_capture(&s, dir)?;
            }
            Ok::<_, scanner::ScanError>(s)
        })
        .map_err(scan_err)?;
    cloud_to(py, &s.cloud)
}

/// Registers the functions on the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(read_point_cloud, m)?)?;
    m.add_function(wrap_pyfunction!(write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(write_point_cloud, m)?)?;
    m.add_function(wrap_pyfunction!(check_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(volumes, m)?)?;
    m.add_function(wrap_pyfunction!(default_template, m)?)?;
    m.add_function(wrap_pyfunction!(scan, m)?)?;
    m.add_function(wrap_pyfunction!(register_template, m)?)?;
    Ok(())
}

/// Registers a template onto a cloud: `(fitted vertices, vertex labels, result JSON {"summary", "log"})`.
/// Head/hand/foot points are dropped by the library unless `params_json` sets
/// `"drop_extremities": false` (the count is `summary["extremities_dropped"]`). The GIL is released while the
/// solver runs; `progress` (if given) receives each iteration's log as JSON.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(name = "register", signature = (template_vertices, template_faces, template_vertex_labels, template_face_labels, points, normals, labels, params_json, progress=None))]
fn register_template<'py>(
    py: Python<'py>,
    template_vertices: PyReadonlyArray2<'_, f64>,
    template_faces: PyReadonlyArray2<'_, i64>,
    template_vertex_labels: Option<PyReadonlyArray1<'_, u8>>,
    template_face_labels: Option<PyReadonlyArray1<'_, u8>>,
    points: PyReadonlyArray2<'_, f64>,
    normals: Option<PyReadonlyArray2<'_, f64>>,
    labels: Option<PyReadonlyArray1<'_, u8>>,
    params_json: &str,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let tmpl = mesh_from(template_vertices, template_faces, template_vertex_labels, template_face_labels)?;
    let cloud = cloud_from(points, normals, None, labels)?;
    let params: bsv_register::RegisterParams = serde_json::from_str(params_json).map_err(input_err)?;
    let callback = progress.map(|p| p.unbind());
    let mut py_error: Option<PyErr> = None;
    let reg = py
        .detach(|| {
            bsv_register::register(&tmpl, &cloud, &params, &mut |it| {
                if let (Some(cb), None) = (&callback, &py_error) {
                    let line = serde_json::to_string(it).unwrap_or_default();
                    Python::attach(|py| {
                        if let Err(e) = cb.call1(py, (line,)) {
                            py_error = Some(e);
                        }
                    });
                }
            })
        })
        .map_err(register_err)?;
    if let Some(e) = py_error {
        return Err(e);
    }
    let mut summary = serde_json::to_value(&reg).map_err(input_err)?;
    let log = summary.as_object_mut().and_then(|o| o.remove("log")).unwrap_or_default();
    if let Some(o) = summary.as_object_mut() {
        o.insert("iterations".into(), reg.log.len().into());
        o.insert("seconds".into(), reg.total_seconds.into());
        o.insert("params".into(), serde_json::to_value(&params).map_err(input_err)?);
    }
    let result = serde_json::json!({ "summary": summary, "log": log }).to_string();
    let vl = reg.mesh.vertex_labels.as_deref().map(|l| crate::convert::labels_to(py, l));
    (crate::convert::points_to(py, &reg.mesh.vertices), vl, result).into_pyobject(py)
}
