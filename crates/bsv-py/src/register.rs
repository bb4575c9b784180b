//! `_bsv.register`: template + cloud + `RegisterParams` -> `RegistrationResult` (fitted mesh, its
//! volume report computed here in Rust, summary, log). The GIL is released while the solver runs;
//! the progress callback gets each iteration's log as a dict. A Python exception raised by the
//! callback, or Ctrl-C (checked after every iteration), stops the fit and propagates.

use crate::classes::{to_py, PyRegisterParams, PyRegistration, PyVolumeReport};
use crate::convert::{cloud_from, labels_to, mesh_from, points_to};
use crate::errors::py_err;
use bsv_register::{ControlFlow, IterationLog};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// What the progress callback does after an iteration: call Python (the callback and the signal
/// check); the first Python error is kept and stops the fit.
struct Progress {
    callback: Option<Py<PyAny>>,
    error: Option<PyErr>,
}

impl Progress {
    /// `true` to go on, `false` to stop.
    fn iteration(&mut self, it: &IterationLog) -> bool {
        if self.error.is_some() {
            return false;
        }
        let result = Python::attach(|py| -> PyResult<()> {
            py.check_signals()?;
            if let Some(cb) = &self.callback {
                cb.call1(py, (to_py(py, it)?,))?;
            }
            Ok(())
        });
        if let Err(e) = result {
            self.error = Some(e);
        }
        self.error.is_none()
    }
}

/// A template joint ring from Python: `(name, vertex indices, weights)`.
type RingTuple = (String, Vec<usize>, Vec<f64>);
/// A measured keypoint from Python: `(name, xyz, confidence, direction or None)`.
type KeypointTuple = (String, [f64; 3], f64, Option<[f64; 3]>);

/// Registers a template onto a cloud. Head/hand/foot points are dropped by the library unless
/// `params` has `drop_extremities=False` (the count is `summary["extremities_dropped"]`). The fitted
/// mesh is measured here (`SegmentOptions::fitted()`, `density`).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (template_vertices, template_faces, template_vertex_labels, template_face_labels, points, normals, labels, params, density=1000.0, progress=None, keypoints=None, joint_rings=None))]
pub fn register<'py>(
    py: Python<'py>,
    template_vertices: &Bound<'py, PyAny>,
    template_faces: &Bound<'py, PyAny>,
    template_vertex_labels: Option<&Bound<'py, PyAny>>,
    template_face_labels: Option<&Bound<'py, PyAny>>,
    points: &Bound<'py, PyAny>,
    normals: Option<&Bound<'py, PyAny>>,
    labels: Option<&Bound<'py, PyAny>>,
    params: Bound<'py, PyRegisterParams>,
    density: f64,
    progress: Option<Bound<'py, PyAny>>,
    keypoints: Option<Vec<KeypointTuple>>,
    joint_rings: Option<Vec<RingTuple>>,
) -> PyResult<PyRegistration> {
    let measured: Vec<bsv_register::Keypoint> = keypoints
        .unwrap_or_default()
        .into_iter()
        .map(|(name, position, confidence, direction)| bsv_register::Keypoint { name, position, confidence, direction })
        .collect();
    let rings: Vec<bsv_core::template::JointRing> = joint_rings
        .unwrap_or_default()
        .into_iter()
        .map(|(name, vertices, weights)| bsv_core::template::JointRing { name, vertices, weights, centre: [0.0; 3] })
        .collect();
    let tmpl = mesh_from(template_vertices, template_faces, template_vertex_labels, template_face_labels)?;
    let cloud = cloud_from(points, normals, None, labels)?;
    let p = &params.get().inner;
    let mut state = Progress { callback: progress.map(Bound::unbind), error: None };
    let fitted = py.detach(|| {
        // A raising callback or Ctrl-C stops the fit after the current iteration.
        let reg = bsv_register::register_with_keypoints(&tmpl, &rings, &cloud, &measured, p, &mut |it| {
            if state.iteration(it) {
                ControlFlow::Continue(())
            } else {
                ControlFlow::Break(())
            }
        });
        // The fitted mesh is measured as the Python API always did: vertex labels only, islands merged.
        reg.map(|mut reg| {
            reg.mesh.face_labels = None;
            let opts = bsv_volume::SegmentOptions::fitted();
            let report = bsv_volume::report_with(&reg.mesh, density, &opts);
            (reg, report)
        })
    });
    if let Some(e) = state.error {
        return Err(e);
    }
    let (reg, report) = fitted.map_err(py_err)?;
    let report = report.map_err(py_err)?;
    let summary = to_py(py, &reg)?.cast_into::<PyDict>()?;
    let log =
        summary.get_item("log")?.map(|l| l.cast_into::<PyList>()).transpose()?.unwrap_or_else(|| PyList::empty(py));
    summary.del_item("log")?;
    summary.set_item("iterations", reg.log.len())?;
    summary.set_item("seconds", reg.total_seconds)?;
    summary.set_item("params", to_py(py, p)?)?;
    Ok(PyRegistration {
        vertices: points_to(py, &reg.mesh.vertices).unbind(),
        vertex_labels: reg.mesh.vertex_labels.as_deref().map(|l| labels_to(py, l).unbind()),
        report: Py::new(py, PyVolumeReport { inner: report })?,
        summary: summary.unbind(),
        log: log.unbind(),
        params: params.unbind(),
        seconds: reg.total_seconds,
    })
}
