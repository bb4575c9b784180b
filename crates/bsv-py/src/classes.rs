//! The typed objects of the Python boundary: registration parameters, the registration result and
//! the volume report. Parameters are read from Python keywords through their serde `Deserialize`
//! (`pythonize`), so names, defaults and validation stay in `bsv-register`; Rust results become
//! Python dicts through their `Serialize`. No JSON text crosses the boundary.

use crate::convert::{labelled_mesh_from, points_from, stacked_points_from};
use crate::errors::{parameter_error, py_err};
use crate::functions::volume_options;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use pythonize::{depythonize, pythonize};

/// Any serializable Rust value as a Python object (dicts, lists, floats, strings, None).
pub fn to_py<'py, T: serde::Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    pythonize(py, value)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(format!("cannot convert a result to Python: {e}")))
}

/// Deserializes keyword parameters; on failure, finds the key at fault (each key alone) so the error
/// names it (`kind`: "registration", "cloud-building").
pub fn from_kwargs<T: serde::de::DeserializeOwned>(kind: &'static str, kwargs: &Bound<'_, PyDict>) -> PyResult<T> {
    match depythonize::<T>(kwargs.as_any()) {
        Ok(v) => Ok(v),
        Err(e) => {
            let py = kwargs.py();
            let mut culprit = None;
            for (k, v) in kwargs.iter() {
                let one = PyDict::new(py);
                one.set_item(&k, v)?;
                if depythonize::<T>(one.as_any()).is_err() {
                    culprit = Some(k.str()?.to_string());
                    break;
                }
            }
            Err(parameter_error(kind, culprit, &e))
        }
    }
}

/// `Name(key=value, ...)` of the entries of `d` that differ from `default`.
fn repr_changed(name: &str, d: &Bound<'_, PyAny>, default: &Bound<'_, PyAny>) -> PyResult<String> {
    let mut parts = Vec::new();
    for (k, v) in d.cast::<PyDict>()?.iter() {
        let same = match default.get_item(&k) {
            Ok(dv) => dv.eq(&v)?,
            Err(_) => false,
        };
        if !same {
            parts.push(format!("{}={}", k.str()?, v.repr()?));
        }
    }
    Ok(format!("{name}({})", parts.join(", ")))
}

/// Registration parameters (`bsv_register::RegisterParams`): `RegisterParams(alpha=1e6, schedule="m2p:5,p2m:5,m2p:4,p2m:2", ...)`.
/// Unknown names, wrong types and out-of-range values raise `RegistrationParameterError` naming the
/// parameter. Read a value as an attribute (`p.alpha`), all of them with `to_dict()`.
#[pyclass(name = "RegisterParams", module = "bsv._bsv", frozen)]
pub struct PyRegisterParams {
    /// The parameters.
    pub inner: bsv_register::RegisterParams,
}

#[pymethods]
impl PyRegisterParams {
    #[new]
    #[pyo3(signature = (**kwargs))]
    fn new(py: Python<'_>, kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let empty = PyDict::new(py);
        let inner: bsv_register::RegisterParams = from_kwargs("registration", kwargs.unwrap_or(&empty))?;
        inner.validate().map_err(|e| py_err(bsv_register::RegisterError::from(e)))?;
        Ok(PyRegisterParams { inner })
    }

    /// Every parameter by name (the keyword names of `bsv.register`).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.inner)
    }

    fn __getattr__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        self.to_dict(py)?.get_item(name).map_err(|_| {
            pyo3::exceptions::PyAttributeError::new_err(format!("RegisterParams has no parameter {name:?}"))
        })
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other.cast::<PyRegisterParams>().is_ok_and(|o| o.get().inner == self.inner)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        repr_changed("RegisterParams", &self.to_dict(py)?, &to_py(py, &bsv_register::RegisterParams::default())?)
    }
}

/// The volumes report (`bsv_volume::VolumeReport`, DESIGN.md "Formats"). `to_dict()` is the report
/// as a dict (what `bsv.volumes` returns); `report["volumes_l"]` and the attributes read it too.
#[pyclass(name = "VolumeReport", module = "bsv._bsv", frozen)]
pub struct PyVolumeReport {
    /// The report.
    pub inner: bsv_volume::VolumeReport,
}

#[pymethods]
impl PyVolumeReport {
    /// The report as a dict: bsv_version, units, volumes_l, unlabelled_l, ratios, density_kg_m3,
    /// mass_kg, mass_trunk_limbs_kg, notes, registration.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.inner)
    }

    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        self.to_dict(py)?.get_item(key)
    }

    /// Volumes in litres: segments present (id order), then aggregates.
    #[getter]
    fn volumes_l<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.inner.volumes_l)
    }

    /// Ratios and asymmetries (percent).
    #[getter]
    fn ratios<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.inner.ratios)
    }

    /// Mass of the whole mesh, kg.
    #[getter]
    fn mass_kg(&self) -> f64 {
        self.inner.mass_kg
    }

    /// Density used for the masses, kg/m^3.
    #[getter]
    fn density_kg_m3(&self) -> f64 {
        self.inner.density_kg_m3
    }

    /// Remarks (missing labels, closed holes, ...).
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.inner.notes.clone()
    }

    fn __repr__(&self) -> String {
        let v = &self.inner.volumes_l;
        let segments = v.keys().filter(|k| bsv_core::Segment::from_name(k).is_some()).count();
        let mut parts = Vec::new();
        for key in ["whole", "trunk_limbs"] {
            if let Some(x) = v.get(key) {
                parts.push(format!("{key}={x:.3} L"));
            }
        }
        parts.push(format!("{segments} segments"));
        parts.push(format!("mass_kg={:.2}", self.inner.mass_kg));
        format!("VolumeReport({})", parts.join(", "))
    }
}

/// A labelled closed mesh prepared for re-measuring at many vertex positions
/// (`bsv_volume::PreparedSegments`): the arguments of `volumes`; `quantities` and `volume_report` take
/// the vertices moved (same count and order) and give what `volumes` gives on the moved mesh, without
/// redoing the validation, labels, island merging and caps.
#[pyclass(name = "PreparedVolumes", module = "bsv._bsv", frozen)]
pub struct PyPreparedVolumes {
    /// The prepared mesh.
    inner: bsv_volume::PreparedSegments,
    /// Density of the reports, kg/m^3.
    density: f64,
}

#[pymethods]
impl PyPreparedVolumes {
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (vertices, faces, vertex_labels=None, face_labels=None, labels=None, density=1000.0, close_holes=false, islands=false))]
    fn new(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        vertex_labels: Option<&Bound<'_, PyAny>>,
        face_labels: Option<&Bound<'_, PyAny>>,
        labels: Option<&Bound<'_, PyAny>>,
        density: f64,
        close_holes: bool,
        islands: bool,
    ) -> PyResult<Self> {
        let mesh = labelled_mesh_from(vertices, faces, vertex_labels, face_labels, labels)?;
        bsv_volume::check_density(density).map_err(py_err)?;
        let opts = volume_options(close_holes, islands);
        let inner = py.detach(|| bsv_volume::PreparedSegments::new(&mesh, &opts)).map_err(py_err)?;
        Ok(PyPreparedVolumes { inner, density })
    }

    /// The vertex count every call must pass.
    #[getter]
    fn n_vertices(&self) -> usize {
        self.inner.vertex_count()
    }

    /// Density of the reports, kg/m^3.
    #[getter]
    fn density_kg_m3(&self) -> f64 {
        self.density
    }

    /// The volumes report with the vertices at `vertices` ((N, 3)).
    fn volume_report(&self, py: Python<'_>, vertices: &Bound<'_, PyAny>) -> PyResult<PyVolumeReport> {
        let v = points_from(vertices, "vertices")?;
        let inner = py.detach(|| self.inner.report(&v, self.density)).map_err(py_err)?;
        Ok(PyVolumeReport { inner })
    }

    /// Per quantity of the reports (`bsv_volume::VolumeReport::quantities`, first-seen order), an (S,)
    /// array over the S vertex arrays of `vertices` ((S, N, 3)); NaN where a draw has no finite value.
    /// The arrays are copied first, then evaluated in parallel without the GIL.
    fn quantities<'py>(&self, py: Python<'py>, vertices: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
        // An owned copy (the converter's): with the GIL released another thread could write to the array.
        let (flat, [s, n]) = stacked_points_from(vertices, "vertices")?;
        let table = py.detach(|| self.inner.quantities_stacked(&flat, s, n, self.density)).map_err(py_err)?;
        let out = PyDict::new(py);
        for (k, c) in table.names.into_iter().zip(table.columns) {
            out.set_item(k, PyArray1::from_vec(py, c))?;
        }
        Ok(out)
    }

    fn __repr__(&self) -> String {
        format!("PreparedVolumes({} vertices, density_kg_m3={})", self.inner.vertex_count(), self.density)
    }
}

/// The result of `_bsv.register`: fitted vertices and labels (faces: the template's), the volume
/// report of the fitted mesh (islands merged), the summary, the per-iteration log, the parameters.
#[pyclass(name = "RegistrationResult", module = "bsv._bsv", frozen)]
pub struct PyRegistration {
    /// Fitted vertices (N, 3), metres.
    #[pyo3(get)]
    pub vertices: Py<PyArray2<f64>>,
    /// Fitted vertex labels (N,), or None.
    #[pyo3(get)]
    pub vertex_labels: Option<Py<PyArray1<u8>>>,
    /// Volume report of the fitted mesh.
    #[pyo3(get)]
    pub report: Py<PyVolumeReport>,
    /// Summary (`bsv_register::Registration` without mesh and log) plus iterations, seconds, params.
    #[pyo3(get)]
    pub summary: Py<PyDict>,
    /// One dict per iteration (`bsv_register::IterationLog`).
    #[pyo3(get)]
    pub log: Py<PyList>,
    /// The parameters used.
    #[pyo3(get)]
    pub params: Py<PyRegisterParams>,
    /// Whole registration, seconds.
    #[pyo3(get)]
    pub seconds: f64,
}

#[pymethods]
impl PyRegistration {
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let s = self.summary.bind(py);
        let rms = s.get_item("rms_mesh_to_points_mm")?.map(|x| x.extract::<f64>()).transpose()?.unwrap_or(f64::NAN);
        Ok(format!(
            "RegistrationResult({} vertices, {} iterations, rms_mesh_to_points_mm={rms:.2}, {:.2} s, {})",
            self.vertices.bind(py).len()?,
            self.log.bind(py).len(),
            self.seconds,
            self.report.get().__repr__()
        ))
    }
}
