//! Python binding of cloud building (`bsv_capture::fuse::build_cloud`): dicts of numpy images and a
//! dict of parameters in, the cloud tuple and the report dict out. Conversion only.

use crate::classes::{from_kwargs, to_py};
use crate::convert::{colors_to, labels_to, points_to};
use crate::errors::{input_error, py_err};
use bsv_capture::camera::{Extrinsics, Intrinsics};
use bsv_capture::fuse::{self, DepthImage, DepthView, FuseParams};
use numpy::{PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

/// `InputError` about the views.
fn views_error(message: String) -> PyErr {
    input_error("views", None, message)
}

/// A required key of a view dict.
fn item<'py>(d: &Bound<'py, PyDict>, key: &str, camera: &str) -> PyResult<Bound<'py, PyAny>> {
    d.get_item(key)?.filter(|v| !v.is_none()).ok_or_else(|| {
        views_error(format!(
            "view `{camera}` has no `{key}`; a view is a dict with name, intrinsics, camera_to_world, depth, labels (and optional depth_scale, colors)"
        ))
    })
}

fn float(d: &Bound<'_, PyDict>, key: &str, camera: &str, default: Option<f64>) -> PyResult<f64> {
    match (d.get_item(key)?.filter(|v| !v.is_none()), default) {
        (Some(v), _) => {
            v.extract::<f64>().map_err(|_| views_error(format!("view `{camera}`: `{key}` must be a number, got {v}")))
        }
        (None, Some(x)) => Ok(x),
        (None, None) => Err(views_error(format!("view `{camera}`: intrinsics lack `{key}`"))),
    }
}

fn intrinsics_from(d: &Bound<'_, PyDict>, camera: &str) -> PyResult<Intrinsics> {
    let int = |key: &str| -> PyResult<u32> {
        let v = float(d, key, camera, None)?;
        if v.fract() != 0.0 || !(1.0..=f64::from(u32::MAX)).contains(&v) {
            return Err(views_error(format!(
                "view `{camera}`: intrinsics `{key}` = {v} is not a positive pixel count"
            )));
        }
        Ok(v as u32)
    };
    let mut k = [0.0f64; 5];
    if let Some(c) = d.get_item("coeffs")?.filter(|v| !v.is_none()) {
        let c: Vec<f64> =
            c.extract().map_err(|_| views_error(format!("view `{camera}`: intrinsics `coeffs` must be 5 numbers")))?;
        if c.len() != 5 {
            return Err(views_error(format!(
                "view `{camera}`: intrinsics `coeffs` has {} numbers, expected 5 (k1, k2, p1, p2, k3)",
                c.len()
            )));
        }
        k.copy_from_slice(&c);
    } else {
        for (slot, key) in k.iter_mut().zip(["k1", "k2", "p1", "p2", "k3"]) {
            *slot = float(d, key, camera, Some(0.0))?;
        }
    }
    Ok(Intrinsics {
        width: int("width")?,
        height: int("height")?,
        fx: float(d, "fx", camera, None)?,
        fy: float(d, "fy", camera, None)?,
        cx: float(d, "cx", camera, None)?,
        cy: float(d, "cy", camera, None)?,
        k1: k[0],
        k2: k[1],
        p1: k[2],
        p2: k[3],
        k3: k[4],
    })
}

fn extrinsics_from(d: &Bound<'_, PyAny>, camera: &str) -> PyResult<Extrinsics> {
    let bad = || {
        views_error(format!(
            "view `{camera}`: camera_to_world must be {{\"rotation\": 3x3, \"translation\": 3}} (metres, row-major)"
        ))
    };
    let d = d.cast::<PyDict>().map_err(|_| bad())?;
    let r: Vec<Vec<f64>> = item(d, "rotation", camera)?.extract().map_err(|_| bad())?;
    let t: Vec<f64> = item(d, "translation", camera)?.extract().map_err(|_| bad())?;
    if r.len() != 3 || r.iter().any(|row| row.len() != 3) || t.len() != 3 {
        return Err(bad());
    }
    Ok(Extrinsics {
        rotation: [[r[0][0], r[0][1], r[0][2]], [r[1][0], r[1][1], r[1][2]], [r[2][0], r[2][1], r[2][2]]],
        translation: [t[0], t[1], t[2]],
    })
}

/// Checks an image's leading (H, W) shape against the intrinsics (a transposed image has the
/// right pixel count but the wrong shape).
fn check_shape(shape: &[usize], intr: &Intrinsics, camera: &str, what: &str) -> PyResult<()> {
    let (h, w) = (intr.height as usize, intr.width as usize);
    if shape.len() < 2 || shape[0] != h || shape[1] != w {
        return Err(views_error(format!(
            "view `{camera}`: {what} has shape {shape:?} but the intrinsics say (height {h}, width {w}); pass images aligned to the colour image"
        )));
    }
    Ok(())
}

fn view_from(obj: &Bound<'_, PyAny>, index: usize) -> PyResult<DepthView> {
    let d = obj
        .cast::<PyDict>()
        .map_err(|_| views_error(format!("views[{index}] must be a dict, got {}", obj.get_type())))?;
    let name: String = match d.get_item("name")? {
        Some(n) if !n.is_none() => n.extract()?,
        _ => format!("view {index}"),
    };
    let intr_obj = item(d, "intrinsics", &name)?;
    let intr_dict = intr_obj.cast::<PyDict>().map_err(|_| {
        views_error(format!("view `{name}`: intrinsics must be a dict (width, height, fx, fy, cx, cy, coeffs)"))
    })?;
    let intrinsics = intrinsics_from(intr_dict, &name)?;
    let camera_to_world = extrinsics_from(&item(d, "camera_to_world", &name)?, &name)?;

    let depth_obj = item(d, "depth", &name)?;
    let depth = if let Ok(a) = depth_obj.extract::<PyReadonlyArray2<'_, u16>>() {
        check_shape(a.shape(), &intrinsics, &name, "depth")?;
        let scale = float(d, "depth_scale", &name, None).map_err(|_| {
            views_error(format!(
                "view `{name}`: a uint16 depth image needs `depth_scale` (metres per unit, from camera.json)"
            ))
        })?;
        DepthImage::Units { data: a.as_array().iter().copied().collect(), scale }
    } else if let Ok(a) = depth_obj.extract::<PyReadonlyArray2<'_, f32>>() {
        check_shape(a.shape(), &intrinsics, &name, "depth")?;
        DepthImage::Metres(a.as_array().iter().copied().collect())
    } else {
        return Err(views_error(format!(
            "view `{name}`: depth must be a 2-D uint16 array (with depth_scale) or float32 array in metres"
        )));
    };

    let labels = item(d, "labels", &name)?
        .extract::<PyReadonlyArray2<'_, u8>>()
        .map_err(|_| views_error(format!("view `{name}`: labels must be a 2-D uint8 array of segment ids")))?;
    check_shape(labels.shape(), &intrinsics, &name, "labels")?;
    let labels: Vec<u8> = labels.as_array().iter().copied().collect();

    let colors = match d.get_item("colors")?.filter(|v| !v.is_none()) {
        None => None,
        Some(c) => {
            let a = c
                .extract::<PyReadonlyArray3<'_, u8>>()
                .map_err(|_| views_error(format!("view `{name}`: colors must be an (H, W, 3) uint8 RGB array")))?;
            check_shape(a.shape(), &intrinsics, &name, "colors")?;
            if a.shape()[2] != 3 {
                return Err(views_error(format!(
                    "view `{name}`: colors must have 3 channels (RGB), got {}",
                    a.shape()[2]
                )));
            }
            let flat: Vec<u8> = a.as_array().iter().copied().collect();
            Some(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
        }
    };
    Ok(DepthView { name, intrinsics, camera_to_world, depth, labels, colors })
}

/// Builds the merged labelled world cloud from per-camera views and `FuseParams` keywords:
/// `(points, normals | None, colors | None, labels | None, report dict)`. Only the person is kept
/// (floor removal and isolation, on by default); the report dict carries each camera's floor check,
/// what the cleaning removed and the warnings (`bsv_capture::fuse::FuseReport`).
#[pyfunction]
#[pyo3(signature = (views, params=None))]
fn build_cloud<'py>(
    py: Python<'py>,
    views: Vec<Bound<'py, PyAny>>,
    params: Option<Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyTuple>> {
    let params: FuseParams = from_kwargs("cloud-building", &params.unwrap_or_else(|| PyDict::new(py)))?;
    let views: Vec<DepthView> = views.iter().enumerate().map(|(i, v)| view_from(v, i)).collect::<PyResult<_>>()?;
    let (cloud, report) = py.detach(|| fuse::build_cloud(&views, &params)).map_err(py_err)?;
    let n = cloud.normals.as_deref().map(|n| points_to(py, n));
    let c = cloud.colors.as_deref().map(|c| colors_to(py, c));
    let l = cloud.labels.as_deref().map(|l| labels_to(py, l));
    (points_to(py, &cloud.points), n, c, l, to_py(py, &report)?).into_pyobject(py)
}

/// Registers the cloud-builder functions on the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(build_cloud, m)?)?;
    Ok(())
}
