//! The functions of `bsv._bsv` (see `python/bsv/_bsv.pyi`): conversion, one library call, conversion.

use crate::classes::{from_kwargs, to_py, PyVolumeReport};
use crate::convert::{
    cloud_from, cloud_to, label_values, labelled_mesh_from, mesh_from, mesh_to, planar_points_from,
    planar_segments_from, points_from, triangles_from,
};
use crate::errors::{input_error, py_err};
use bsv_capture::scanner::{self, Condition, Look, Rig, Room};
use bsv_core::io::{self, PlyEncoding};
use bsv_core::template::{template, TemplateKind};
use bsv_core::TriMesh;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
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
    let mesh = py.detach(|| io::read_mesh(&path)).map_err(py_err)?;
    mesh_to(py, &mesh)
}

/// Reads a PLY point cloud: `(points, normals, colors, labels)`.
#[pyfunction]
fn read_point_cloud<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyTuple>> {
    let cloud = py.detach(|| io::read_point_cloud(&path)).map_err(py_err)?;
    cloud_to(py, &cloud)
}

/// Writes a mesh (PLY or OBJ by extension).
#[pyfunction]
#[pyo3(signature = (path, vertices, faces, vertex_labels=None, face_labels=None, ascii=false))]
fn write_mesh(
    py: Python<'_>,
    path: PathBuf,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    vertex_labels: Option<&Bound<'_, PyAny>>,
    face_labels: Option<&Bound<'_, PyAny>>,
    ascii: bool,
) -> PyResult<()> {
    let mesh = mesh_from(vertices, faces, vertex_labels, face_labels)?;
    py.detach(|| io::write_mesh_with(&path, &mesh, encoding(ascii))).map_err(py_err)
}

/// Writes a point cloud (PLY).
#[pyfunction]
#[pyo3(signature = (path, points, normals=None, colors=None, labels=None, ascii=false))]
fn write_point_cloud(
    py: Python<'_>,
    path: PathBuf,
    points: &Bound<'_, PyAny>,
    normals: Option<&Bound<'_, PyAny>>,
    colors: Option<&Bound<'_, PyAny>>,
    labels: Option<&Bound<'_, PyAny>>,
    ascii: bool,
) -> PyResult<()> {
    let cloud = cloud_from(points, normals, colors, labels)?;
    py.detach(|| io::write_point_cloud_with(&path, &cloud, encoding(ascii))).map_err(py_err)
}

/// The mesh-check report (`bsv_core::check::MeshReport`) as a dict.
#[pyfunction]
fn check_mesh<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let mesh = mesh_from(vertices, faces, None, None)?;
    to_py(py, &bsv_core::check::check_mesh(&mesh))
}

/// The volumes report of a closed mesh. `labels` (per vertex or per face, told apart by length)
/// overrides the mesh's own; `islands`: merge small label islands first (`SegmentOptions::fitted()`,
/// the policy for registered meshes).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (vertices, faces, vertex_labels=None, face_labels=None, labels=None, density=1000.0, close_holes=false, islands=false))]
fn volumes(
    py: Python<'_>,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    vertex_labels: Option<&Bound<'_, PyAny>>,
    face_labels: Option<&Bound<'_, PyAny>>,
    labels: Option<&Bound<'_, PyAny>>,
    density: f64,
    close_holes: bool,
    islands: bool,
) -> PyResult<PyVolumeReport> {
    let mesh = labelled_mesh_from(vertices, faces, vertex_labels, face_labels, labels)?;
    let opts = volume_options(close_holes, islands);
    let inner = py.detach(|| bsv_volume::report_with(&mesh, density, &opts)).map_err(py_err)?;
    Ok(PyVolumeReport { inner })
}

/// The segment options of the `close_holes` and `islands` arguments (`islands`:
/// `SegmentOptions::fitted()`, the policy for registered meshes).
pub fn volume_options(close_holes: bool, islands: bool) -> bsv_volume::SegmentOptions {
    let base = if islands { bsv_volume::SegmentOptions::fitted() } else { bsv_volume::SegmentOptions::default() };
    bsv_volume::SegmentOptions { close_holes, ..base }
}

/// The embedded template (9 segments, or 14 with `full`), or the one named `kind` (`TemplateKind::NAMES`).
#[pyfunction]
#[pyo3(signature = (full=false, kind=None))]
fn default_template<'py>(py: Python<'py>, full: bool, kind: Option<&str>) -> PyResult<Bound<'py, PyTuple>> {
    let kind = match kind {
        Some(k) => {
            let k = parse_kind(k)?;
            if full && k != TemplateKind::Full {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "full=True and kind={:?} ask for two templates: give one",
                    k.name()
                )));
            }
            k
        }
        None if full => TemplateKind::Full,
        None => TemplateKind::Default,
    };
    let mesh = template(kind).map_err(py_err)?;
    mesh_to(py, &mesh)
}

/// `kind` as a template kind, or a ValueError naming the accepted ones.
fn parse_kind(kind: &str) -> PyResult<TemplateKind> {
    TemplateKind::parse(kind).ok_or_else(|| {
        pyo3::exceptions::PyValueError::new_err(format!(
            "template kind {kind:?}: expected one of {:?}",
            TemplateKind::NAMES
        ))
    })
}

/// The joint rings of the embedded template `kind` (`TemplateKind::NAMES`): a list of
/// `(name, vertex indices, weights, centre)`, sorted by name.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn template_joints(kind: &str) -> PyResult<Vec<(String, Vec<usize>, Vec<f64>, [f64; 3])>> {
    let k = parse_kind(kind)?;
    Ok(bsv_core::template::template_joints(k).into_iter().map(|r| (r.name, r.vertices, r.weights, r.centre)).collect())
}

/// The rig's room from the `room` argument: absent, `None` or `False`: no room; `True`: the clinic
/// room varied by `seed`; a dict: `Room` keys (missing keys take the clinic's values, no variation).
fn room_from(room: Option<&Bound<'_, PyAny>>, seed: u64) -> PyResult<Option<Room>> {
    let Some(r) = room.filter(|r| !r.is_none()) else { return Ok(None) };
    if let Ok(flag) = r.extract::<bool>() {
        return Ok(flag.then(|| Room::clinic().varied(seed)));
    }
    let Ok(d) = r.cast::<PyDict>() else {
        return Err(input_error("room", None, "room must be True, False or a dict of Room keys".into()));
    };
    let room: Room = from_kwargs("room", d)?;
    Ok(Some(room))
}

/// The looks asked for from the `look` argument: absent or `None`: none; a dict of `Look` keys.
fn look_from(look: Option<&Bound<'_, PyAny>>) -> PyResult<Look> {
    let Some(l) = look.filter(|l| !l.is_none()) else { return Ok(Look::default()) };
    let Ok(d) = l.cast::<PyDict>() else {
        return Err(input_error(
            "look",
            None,
            "look must be None or a dict of Look keys (long_hair, top, smooth_shading, colour_sensor)".into(),
        ));
    };
    from_kwargs("look", d)
}

/// Virtual two-camera capture: the merged labelled cloud (the body's points only); optionally writes
/// the capture files; `room` puts the rig in a room (see [`room_from`]), `look` asks for looks beyond the
/// seed's (see [`look_from`]).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (vertices, faces, vertex_labels=None, face_labels=None, condition="noer", seed=0, images_dir=None, room=None, look=None))]
fn scan<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    vertex_labels: Option<&Bound<'py, PyAny>>,
    face_labels: Option<&Bound<'py, PyAny>>,
    condition: &str,
    seed: u64,
    images_dir: Option<PathBuf>,
    room: Option<&Bound<'py, PyAny>>,
    look: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let mesh = mesh_from(vertices, faces, vertex_labels, face_labels)?;
    let condition: Condition = condition.parse().map_err(py_err)?;
    let mut rig = Rig::paper_default();
    rig.room = room_from(room, seed)?;
    rig.look = look_from(look)?;
    let s = py
        .detach(|| {
            let s = scanner::scan(&mesh, &rig, condition, seed)?;
            if let Some(dir) = &images_dir {
                scanner::write_capture(&s, dir)?;
            }
            Ok::<_, scanner::ScanError>(s)
        })
        .map_err(py_err)?;
    cloud_to(py, &s.cloud)
}

/// Exact distance (metres) from every point to the surface of the mesh (point-to-triangle).
#[pyfunction]
fn surface_distances<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let p = points_from(points, "points")?;
    let v = points_from(vertices, "vertices")?;
    let t = triangles_from(faces, v.len(), "faces")?;
    let mesh = TriMesh::new(v, t);
    let d = py.detach(|| bsv_capture::distance::surface_distances(&p, &mesh)).map_err(py_err)?;
    Ok(PyArray1::from_vec(py, d))
}

/// Distances (N,) and triangle indices (N,) of [`surface_nearest`].
type NearestArrays<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<u32>>);

/// Exact distance (metres) from every point to the surface of the mesh and the index of the triangle
/// that holds the nearest surface point: `(distances (N,), triangles (N,))`.
#[pyfunction]
fn surface_nearest<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
) -> PyResult<NearestArrays<'py>> {
    let p = points_from(points, "points")?;
    let v = points_from(vertices, "vertices")?;
    let t = triangles_from(faces, v.len(), "faces")?;
    let mesh = TriMesh::new(v, t);
    let near = py.detach(|| bsv_capture::distance::surface_nearest(&p, &mesh)).map_err(py_err)?;
    let (d, f): (Vec<f64>, Vec<u32>) = near.into_iter().unzip();
    Ok((PyArray1::from_vec(py, d), PyArray1::from_vec(py, f)))
}

/// For every image-plane point (N, 2), the distance to the nearest of the line segments (M, 4: ax, ay,
/// bx, by; `bsv_capture::planar::nearest_segment_distances`); infinity when M is 0.
#[pyfunction]
fn nearest_segment_distances<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    segments: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let p = planar_points_from(points, "points")?;
    let s = planar_segments_from(segments, "segments")?;
    let d = py.detach(|| bsv_capture::planar::nearest_segment_distances(&p, &s));
    Ok(PyArray1::from_vec(py, d))
}

/// Face labels from vertex labels: the one rule of `bsv_volume::face_labels_from_vertices` (the
/// label shared by two corners; three different: the corner with the smallest vertex index).
#[pyfunction]
fn face_labels_from_vertices<'py>(
    py: Python<'py>,
    faces: &Bound<'py, PyAny>,
    vertex_labels: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<u8>>> {
    let vl = label_values(vertex_labels, "vertex_labels")?;
    let t = triangles_from(faces, vl.len(), "faces")?;
    Ok(PyArray1::from_vec(py, bsv_volume::face_labels_from_vertices(&t, &vl)))
}

/// Vertex labels from face labels: the one rule of `bsv_volume::vertex_labels_from_faces` (the most
/// common label of the incident faces, ties to the smallest id; vertices on no face get 0).
#[pyfunction]
fn vertex_labels_from_faces<'py>(
    py: Python<'py>,
    n_vertices: usize,
    faces: &Bound<'py, PyAny>,
    face_labels: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<u8>>> {
    let t = triangles_from(faces, n_vertices, "faces")?;
    let fl = label_values(face_labels, "face_labels")?;
    if fl.len() != t.len() {
        return Err(input_error(
            "face_labels",
            None,
            format!("face_labels has {} entries, expected {} (one per face)", fl.len(), t.len()),
        ));
    }
    Ok(PyArray1::from_vec(py, bsv_volume::vertex_labels_from_faces(n_vertices, &t, &fl)))
}

/// Area-weighted unit vertex normals (`bsv_core::geometry::vertex_normals`; zero for isolated vertices).
#[pyfunction]
fn vertex_normals<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let v = points_from(vertices, "vertices")?;
    let t = triangles_from(faces, v.len(), "faces")?;
    let mesh = TriMesh::new(v, t);
    Ok(crate::convert::points_to(py, &bsv_core::geometry::vertex_normals(&mesh)))
}

/// Adds the virtual rig's calibration model as module constants (`bsv.uncertainty` builds its copies
/// from these): `COVARIANCE_PARAMETERS` (names of the 6 extrinsic parameters), `COVARIANCE_FRAME`
/// (their parameterisation) and `PAPER_CALIBRATION_STD` (camera name -> the paper's 6 standard
/// deviations, the rig's calibration sigmas).
fn register_calibration(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("COVARIANCE_PARAMETERS", PyTuple::new(py, scanner::COVARIANCE_PARAMETERS)?)?;
    m.add("COVARIANCE_FRAME", scanner::COVARIANCE_FRAME)?;
    let std = PyDict::new(py);
    for cam in Rig::paper_default().cameras {
        std.set_item(cam.name, PyTuple::new(py, cam.calibration_sigma.std())?)?;
    }
    m.add("PAPER_CALIBRATION_STD", std)?;
    Ok(())
}

/// Adds `QUALITY_LIMITS`: the limits beyond which a fitted segment is doubtful
/// (`bsv_register::DOUBT_*`; the report explains them from this dict).
fn register_quality(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let limits = PyDict::new(m.py());
    limits.set_item("rms_mm", bsv_register::DOUBT_RMS_MM)?;
    limits.set_item("exposed_uncovered", bsv_register::DOUBT_EXPOSED)?;
    limits.set_item("coverage", bsv_register::DOUBT_COVERAGE)?;
    limits.set_item("folded", bsv_register::DOUBT_FOLDED)?;
    limits.set_item("folded_torso", bsv_register::DOUBT_FOLDED_TORSO)?;
    m.add("QUALITY_LIMITS", limits)?;
    Ok(())
}

/// Registers the functions and the calibration and quality constants on the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    register_calibration(m)?;
    register_quality(m)?;
    m.add_function(wrap_pyfunction!(read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(read_point_cloud, m)?)?;
    m.add_function(wrap_pyfunction!(write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(write_point_cloud, m)?)?;
    m.add_function(wrap_pyfunction!(check_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(nearest_segment_distances, m)?)?;
    m.add_function(wrap_pyfunction!(volumes, m)?)?;
    m.add_function(wrap_pyfunction!(default_template, m)?)?;
    m.add_function(wrap_pyfunction!(template_joints, m)?)?;
    m.add_function(wrap_pyfunction!(scan, m)?)?;
    m.add_function(wrap_pyfunction!(surface_distances, m)?)?;
    m.add_function(wrap_pyfunction!(surface_nearest, m)?)?;
    m.add_function(wrap_pyfunction!(face_labels_from_vertices, m)?)?;
    m.add_function(wrap_pyfunction!(vertex_labels_from_faces, m)?)?;
    m.add_function(wrap_pyfunction!(vertex_normals, m)?)?;
    Ok(())
}
