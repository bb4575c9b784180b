//! numpy <-> core type conversions. Shapes are checked; a wrong shape is an `InputError`.

use crate::errors::InputError;
use bsv_core::{PointCloud, TriMesh};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

/// Copies an (N, 3) float64 array into points, rejecting other shapes.
pub fn points_from(arr: &PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<Vec<[f64; 3]>> {
    let a = arr.as_array();
    if a.ncols() != 3 {
        return Err(InputError::new_err(format!(
            "{what} must have shape (N, 3), got {:?}; pass an array of x, y, z rows in metres",
            a.shape()
        )));
    }
    Ok(a.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
}

/// Copies an (M, 3) integer array of vertex indices into triangles, checking range and sign.
pub fn triangles_from(arr: &PyReadonlyArray2<'_, i64>, n_vertices: usize, what: &str) -> PyResult<Vec<[u32; 3]>> {
    let a = arr.as_array();
    if a.ncols() != 3 {
        return Err(InputError::new_err(format!(
            "{what} must have shape (M, 3) (triangles), got {:?}; triangulate polygons first",
            a.shape()
        )));
    }
    let mut out = Vec::with_capacity(a.nrows());
    for (f, r) in a.rows().into_iter().enumerate() {
        let mut t = [0u32; 3];
        for k in 0..3 {
            let v = r[k];
            if v < 0 || v as u64 >= n_vertices as u64 {
                return Err(InputError::new_err(format!(
                    "{what}[{f}] refers to vertex {v}, but there are {n_vertices} vertices; indices are 0-based"
                )));
            }
            t[k] = v as u32;
        }
        out.push(t);
    }
    Ok(out)
}

/// Copies an optional label array, checking its length and the id range 0..=14.
pub fn labels_from(arr: Option<PyReadonlyArray1<'_, u8>>, expected: usize, what: &str) -> PyResult<Option<Vec<u8>>> {
    let Some(arr) = arr else { return Ok(None) };
    let a = arr.as_array();
    if a.len() != expected {
        return Err(InputError::new_err(format!("{what} has {} entries, expected {expected} (one per element)", a.len())));
    }
    if let Some((i, v)) = a.iter().enumerate().find(|(_, &v)| v > 14) {
        return Err(InputError::new_err(format!("{what}[{i}] = {v} is not a segment id (0..=14)")));
    }
    Ok(Some(a.to_vec()))
}

/// Builds a mesh from numpy arrays.
pub fn mesh_from(
    vertices: PyReadonlyArray2<'_, f64>,
    faces: PyReadonlyArray2<'_, i64>,
    vertex_labels: Option<PyReadonlyArray1<'_, u8>>,
    face_labels: Option<PyReadonlyArray1<'_, u8>>,
) -> PyResult<TriMesh> {
    let v = points_from(&vertices, "vertices")?;
    let t = triangles_from(&faces, v.len(), "faces")?;
    let vl = labels_from(vertex_labels, v.len(), "vertex_labels")?;
    let fl = labels_from(face_labels, t.len(), "face_labels")?;
    Ok(TriMesh { vertices: v, triangles: t, vertex_labels: vl, face_labels: fl })
}

/// (N, 3) float64 array from points.
pub fn points_to<'py>(py: Python<'py>, p: &[[f64; 3]]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = p.iter().flatten().copied().collect();
    Array2::from_shape_vec((p.len(), 3), flat).map(|a| a.into_pyarray(py)).unwrap_or_else(|_| PyArray2::zeros(py, [0, 3], false))
}

/// (M, 3) int64 array from triangles.
pub fn triangles_to<'py>(py: Python<'py>, t: &[[u32; 3]]) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = t.iter().flatten().map(|&i| i64::from(i)).collect();
    Array2::from_shape_vec((t.len(), 3), flat).map(|a| a.into_pyarray(py)).unwrap_or_else(|_| PyArray2::zeros(py, [0, 3], false))
}

/// (N, 3) uint8 array from colours.
pub fn colors_to<'py>(py: Python<'py>, c: &[[u8; 3]]) -> Bound<'py, PyArray2<u8>> {
    let flat: Vec<u8> = c.iter().flatten().copied().collect();
    Array2::from_shape_vec((c.len(), 3), flat).map(|a| a.into_pyarray(py)).unwrap_or_else(|_| PyArray2::zeros(py, [0, 3], false))
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

/// Builds a cloud from numpy arrays.
pub fn cloud_from(
    points: PyReadonlyArray2<'_, f64>,
    normals: Option<PyReadonlyArray2<'_, f64>>,
    colors: Option<PyReadonlyArray2<'_, u8>>,
    labels: Option<PyReadonlyArray1<'_, u8>>,
) -> PyResult<PointCloud> {
    let p = points_from(&points, "points")?;
    let n = match normals {
        Some(a) => {
            let n = points_from(&a, "normals")?;
            if n.len() != p.len() {
                return Err(InputError::new_err(format!("normals has {} rows, points has {}", n.len(), p.len())));
            }
            Some(n)
        }
        None => None,
    };
    let c = match colors {
        Some(a) => {
            let a = a.as_array();
            if a.ncols() != 3 || a.nrows() != p.len() {
                return Err(InputError::new_err(format!("colors must have shape ({}, 3), got {:?}", p.len(), a.shape())));
            }
            Some(a.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
        }
        None => None,
    };
    let l = labels_from(labels, p.len(), "labels")?;
    Ok(PointCloud { points: p, normals: n, colors: c, labels: l })
}
