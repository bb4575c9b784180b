//! Python arrays <-> core types: the ONE validation layer of the arrays passed from Python.
//!
//! Every argument may be any array-like (numpy array of any numeric dtype, list, ...). Shapes, dtypes,
//! vertex-index ranges and segment ids are checked here; a bad argument is an `InputError` whose
//! `argument` attribute names it (and `index` the first bad entry). Nothing is cast silently: float
//! indices or labels must be whole numbers, and a label 270 is an error, not a wrapped 14.

use crate::errors::input_error;
use bsv_core::{PointCloud, TriMesh};
use numpy::ndarray::Array2;
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayDescrMethods, PyArrayMethods, PyUntypedArray,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Largest segment id.
const MAX_LABEL: i64 = 14;

/// Shape as Python prints it: `(8, 2)`, `(30,)`.
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!("({})", shape.iter().map(usize::to_string).collect::<Vec<_>>().join(", ")),
    }
}

/// `numpy.asarray(obj)` (with `dtype` if given), or an `InputError` naming the argument.
fn asarray<'py>(obj: &Bound<'py, PyAny>, dtype: Option<&str>, what: &str) -> PyResult<Bound<'py, PyUntypedArray>> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let kwargs = PyDict::new(py);
    if let Some(d) = dtype {
        kwargs.set_item("dtype", d)?;
    }
    let arr = np
        .call_method("asarray", (obj,), Some(&kwargs))
        .map_err(|e| input_error(what, None, format!("{what} is not a numeric array: {e}")))?;
    arr.cast_into::<PyUntypedArray>().map_err(|_| input_error(what, None, format!("{what} is not a numeric array")))
}

/// dtype kind character (`'f'`, `'i'`, `'u'`, `'b'`, ...).
fn kind(a: &Bound<'_, PyUntypedArray>) -> u8 {
    a.dtype().kind()
}

/// An (N, D) real array as rows, or an `InputError`.
fn rows<const D: usize>(obj: &Bound<'_, PyAny>, what: &str, hint: &str) -> PyResult<Vec<[f64; D]>> {
    let a = asarray(obj, None, what)?;
    if a.ndim() != 2 || a.shape()[1] != D {
        return Err(input_error(
            what,
            None,
            format!("{what} must have shape (N, {D}) ({hint}), got {}", shape_text(a.shape())),
        ));
    }
    if !matches!(kind(&a), b'f' | b'i' | b'u' | b'b') {
        return Err(input_error(what, None, format!("{what} must hold real numbers, got dtype {}", a.dtype())));
    }
    let f = asarray(a.as_any(), Some("float64"), what)?;
    let f = f.cast::<PyArray2<f64>>()?.readonly();
    Ok(f.as_array().rows().into_iter().map(|r| std::array::from_fn(|k| r[k])).collect())
}

/// An (N, 3) real array as rows, or an `InputError`.
fn rows3(obj: &Bound<'_, PyAny>, what: &str, hint: &str) -> PyResult<Vec<[f64; 3]>> {
    rows::<3>(obj, what, hint)
}

/// Copies an (N, 2) array of image-plane points (pixels), or an `InputError`.
pub fn planar_points_from(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; 2]>> {
    rows::<2>(obj, what, "x, y in pixels")
}

/// Copies an (M, 4) array of image-plane line segments (`ax, ay, bx, by` in pixels), or an `InputError`.
pub fn planar_segments_from(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; 4]>> {
    rows::<4>(obj, what, "ax, ay, bx, by in pixels: one line segment per row")
}

/// Copies an (N, 3) array of points (metres).
pub fn points_from(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; 3]>> {
    rows3(obj, what, "x, y, z in metres")
}

/// A stack of S point arrays ((S, N, 3)) copied into an owned buffer, the S arrays one after another
/// (x y z per point, C order), with its (S, N); or an `InputError`. Owned, like the other converters'
/// results, so that it can be read with the GIL released (no other thread can write to it).
pub fn stacked_points_from(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<f64>, [usize; 2])> {
    let a = asarray(obj, None, what)?;
    if a.ndim() != 3 || a.shape()[2] != 3 {
        return Err(input_error(
            what,
            None,
            format!(
                "{what} must have shape (S, N, 3) (S arrays of N points x, y, z in metres; one array: add a \
                 leading axis, vertices[None]), got {}",
                shape_text(a.shape())
            ),
        ));
    }
    if !matches!(kind(&a), b'f' | b'i' | b'u' | b'b') {
        return Err(input_error(what, None, format!("{what} must hold real numbers, got dtype {}", a.dtype())));
    }
    let py = obj.py();
    let c = py
        .import("numpy")?
        .call_method1("ascontiguousarray", (a, "float64"))
        .map_err(|e| input_error(what, None, format!("{what} is not a numeric array: {e}")))?;
    let a = c.cast_into::<PyArray3<f64>>()?.readonly();
    let shape = [a.shape()[0], a.shape()[1]];
    Ok((a.as_slice()?.to_vec(), shape))
}

/// A mesh from array-likes with `labels` (per vertex or per face, told apart by length) replacing the
/// mesh's own when given: the arguments of `volumes` and `PreparedVolumes`.
pub fn labelled_mesh_from(
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    vertex_labels: Option<&Bound<'_, PyAny>>,
    face_labels: Option<&Bound<'_, PyAny>>,
    labels: Option<&Bound<'_, PyAny>>,
) -> PyResult<TriMesh> {
    let mut mesh = mesh_from(vertices, faces, vertex_labels, face_labels)?;
    if let Some(l) = labels.filter(|l| !l.is_none()) {
        let l = label_values(l, "labels")?;
        let (nv, nf) = (mesh.vertices.len(), mesh.triangles.len());
        if l.len() == nv {
            mesh.vertex_labels = Some(l);
        } else if l.len() == nf {
            mesh.face_labels = Some(l);
        } else {
            return Err(input_error(
                "labels",
                None,
                format!("labels has {} entries; expected one per vertex ({nv}) or per face ({nf})", l.len()),
            ));
        }
    }
    Ok(mesh)
}

/// An integer-valued array as i64 (whole-valued floats accepted), or an `InputError`.
fn whole_numbers<'py>(obj: &Bound<'py, PyAny>, what: &str, expected: &str) -> PyResult<Bound<'py, PyUntypedArray>> {
    let a = asarray(obj, None, what)?;
    match kind(&a) {
        b'i' | b'u' | b'b' => asarray(a.as_any(), Some("int64"), what),
        b'f' if a.len() == 0 => asarray(a.as_any(), Some("int64"), what),
        b'f' => {
            let f = asarray(a.as_any(), Some("float64"), what)?;
            let fa = f.cast::<numpy::PyArrayDyn<f64>>()?.readonly();
            if let Some((i, v)) = fa.as_array().iter().enumerate().find(|(_, v)| !(v.is_finite() && v.fract() == 0.0)) {
                return Err(input_error(
                    what,
                    Some(i),
                    format!("{what} must be {expected}, got {} (float64 values, entry {i} = {v})", a.dtype()),
                ));
            }
            asarray(a.as_any(), Some("int64"), what)
        }
        _ => Err(input_error(what, None, format!("{what} must be {expected}, got dtype {}", a.dtype()))),
    }
}

/// Copies an (M, 3) array of vertex indices into triangles, checking shape, type and range.
pub fn triangles_from(obj: &Bound<'_, PyAny>, n_vertices: usize, what: &str) -> PyResult<Vec<[u32; 3]>> {
    let raw = asarray(obj, None, what)?;
    let integral = matches!(kind(&raw), b'i' | b'u') || raw.len() == 0;
    if raw.ndim() != 2 || raw.shape()[1] != 3 || !integral {
        return Err(input_error(
            what,
            None,
            format!(
                "{what} must be an (M, 3) integer array of vertex indices (triangles; triangulate polygons first), got {} {}",
                raw.dtype(),
                shape_text(raw.shape())
            ),
        ));
    }
    let a = asarray(raw.as_any(), Some("int64"), what)?;
    let a = a.cast::<PyArray2<i64>>()?.readonly();
    let mut out = Vec::with_capacity(a.as_array().nrows());
    for (f, r) in a.as_array().rows().into_iter().enumerate() {
        let mut t = [0u32; 3];
        for k in 0..3 {
            let v = r[k];
            if v < 0 || v as u64 >= n_vertices as u64 {
                return Err(input_error(
                    what,
                    Some(f),
                    format!(
                        "{what}[{f}] refers to vertex {v}, but there are {n_vertices} vertices; indices are 0-based"
                    ),
                ));
            }
            t[k] = v as u32;
        }
        out.push(t);
    }
    Ok(out)
}

/// A 1-D array of segment ids 0..=14, unchecked length.
pub fn label_values(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<u8>> {
    if let Ok(a) = obj.cast::<PyArray1<u8>>() {
        let a = a.readonly();
        let a = a.as_array();
        if let Some((i, &v)) = a.iter().enumerate().find(|(_, &v)| i64::from(v) > MAX_LABEL) {
            return Err(input_error(what, Some(i), format!("{what}[{i}] = {v} is not one of the segment ids 0..=14")));
        }
        return Ok(a.to_vec());
    }
    let a = whole_numbers(obj, what, "whole segment ids 0..=14")?;
    if a.ndim() != 1 {
        return Err(input_error(
            what,
            None,
            format!("{what} must be a 1-D array of segment ids, got shape {}", shape_text(a.shape())),
        ));
    }
    let a = a.cast::<PyArray1<i64>>()?.readonly();
    let a = a.as_array();
    if let Some((i, &v)) = a.iter().enumerate().find(|(_, &v)| !(0..=MAX_LABEL).contains(&v)) {
        return Err(input_error(what, Some(i), format!("{what}[{i}] = {v} is not one of the segment ids 0..=14")));
    }
    Ok(a.iter().map(|&v| v as u8).collect())
}

/// Copies an optional label array, checking its length and the id range 0..=14.
pub fn labels_from(obj: Option<&Bound<'_, PyAny>>, expected: usize, what: &str) -> PyResult<Option<Vec<u8>>> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else { return Ok(None) };
    let l = label_values(obj, what)?;
    if l.len() != expected {
        return Err(input_error(
            what,
            None,
            format!("{what} has {} entries, expected {expected} (one per element)", l.len()),
        ));
    }
    Ok(Some(l))
}

/// Builds a mesh from array-likes.
pub fn mesh_from(
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    vertex_labels: Option<&Bound<'_, PyAny>>,
    face_labels: Option<&Bound<'_, PyAny>>,
) -> PyResult<TriMesh> {
    let v = points_from(vertices, "vertices")?;
    let t = triangles_from(faces, v.len(), "faces")?;
    let vl = labels_from(vertex_labels, v.len(), "vertex_labels")?;
    let fl = labels_from(face_labels, t.len(), "face_labels")?;
    Ok(TriMesh { vertices: v, triangles: t, vertex_labels: vl, face_labels: fl })
}

/// The rows of an integer (N, 3) colour array, every value checked to be in 0..=255 (a cast would wrap
/// 300 to 44 and -1 to 255).
fn color_rows(arr: &Bound<'_, PyUntypedArray>) -> PyResult<Vec<[u8; 3]>> {
    let wide = asarray(arr.as_any(), Some("int64"), "colors")?;
    let wide = wide.cast::<PyArray2<i64>>()?.readonly();
    let wide = wide.as_array();
    let mut rows = Vec::with_capacity(wide.nrows());
    for (i, r) in wide.rows().into_iter().enumerate() {
        let mut c = [0u8; 3];
        for (k, &v) in r.iter().enumerate() {
            c[k] = u8::try_from(v).map_err(|_| {
                input_error("colors", Some(i), format!("colors[{i}, {k}] = {v} is outside 0..=255 (8-bit sRGB)"))
            })?;
        }
        rows.push(c);
    }
    Ok(rows)
}

/// Builds a cloud from array-likes.
pub fn cloud_from(
    points: &Bound<'_, PyAny>,
    normals: Option<&Bound<'_, PyAny>>,
    colors: Option<&Bound<'_, PyAny>>,
    labels: Option<&Bound<'_, PyAny>>,
) -> PyResult<PointCloud> {
    let p = points_from(points, "points")?;
    let n = match normals.filter(|o| !o.is_none()) {
        Some(a) => {
            let n = rows3(a, "normals", "unit normals")?;
            if n.len() != p.len() {
                return Err(input_error(
                    "normals",
                    None,
                    format!("normals has {} rows, points has {}", n.len(), p.len()),
                ));
            }
            Some(n)
        }
        None => None,
    };
    let c = match colors.filter(|o| !o.is_none()) {
        Some(a) => {
            let arr = asarray(a, None, "colors")?;
            if arr.ndim() != 2 || arr.shape()[1] != 3 || arr.shape()[0] != p.len() || !matches!(kind(&arr), b'u' | b'i')
            {
                return Err(input_error(
                    "colors",
                    None,
                    format!(
                        "colors must be a ({}, 3) uint8 array, got {} {}",
                        p.len(),
                        arr.dtype(),
                        shape_text(arr.shape())
                    ),
                ));
            }
            Some(color_rows(&arr)?)
        }
        None => None,
    };
    let l = labels_from(labels, p.len(), "labels")?;
    Ok(PointCloud { points: p, normals: n, colors: c, labels: l })
}

/// (N, 3) float64 array from points.
pub fn points_to<'py>(py: Python<'py>, p: &[[f64; 3]]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = p.iter().flatten().copied().collect();
    Array2::from_shape_vec((p.len(), 3), flat)
        .map(|a| a.into_pyarray(py))
        .unwrap_or_else(|_| PyArray2::zeros(py, [0, 3], false))
}

/// (M, 3) int64 array from triangles.
pub fn triangles_to<'py>(py: Python<'py>, t: &[[u32; 3]]) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = t.iter().flatten().map(|&i| i64::from(i)).collect();
    Array2::from_shape_vec((t.len(), 3), flat)
        .map(|a| a.into_pyarray(py))
        .unwrap_or_else(|_| PyArray2::zeros(py, [0, 3], false))
}

/// (N, 3) uint8 array from colours.
pub fn colors_to<'py>(py: Python<'py>, c: &[[u8; 3]]) -> Bound<'py, PyArray2<u8>> {
    let flat: Vec<u8> = c.iter().flatten().copied().collect();
    Array2::from_shape_vec((c.len(), 3), flat)
        .map(|a| a.into_pyarray(py))
        .unwrap_or_else(|_| PyArray2::zeros(py, [0, 3], false))
}

/// uint8 label array.
pub fn labels_to<'py>(py: Python<'py>, l: &[u8]) -> Bound<'py, PyArray1<u8>> {
    PyArray1::from_slice(py, l)
}

/// A mesh as the tuple `(vertices, faces, vertex_labels | None, face_labels | None)`.
pub fn mesh_to<'py>(py: Python<'py>, m: &TriMesh) -> PyResult<Bound<'py, pyo3::types::PyTuple>> {
    let vl = m.vertex_labels.as_deref().map(|l| labels_to(py, l));
    let fl = m.face_labels.as_deref().map(|l| labels_to(py, l));
    (points_to(py, &m.vertices), triangles_to(py, &m.triangles), vl, fl).into_pyobject(py)
}

/// A cloud as the tuple `(points, normals | None, colors | None, labels | None)`.
pub fn cloud_to<'py>(py: Python<'py>, c: &PointCloud) -> PyResult<Bound<'py, pyo3::types::PyTuple>> {
    let n = c.normals.as_deref().map(|n| points_to(py, n));
    let col = c.colors.as_deref().map(|c| colors_to(py, c));
    let l = c.labels.as_deref().map(|l| labels_to(py, l));
    (points_to(py, &c.points), n, col, l).into_pyobject(py)
}
