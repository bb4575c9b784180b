//! Rust errors -> Python exceptions. The classes are defined once, in `python/bsv/errors.py`; this
//! module imports them (cached) and maps every error variant to one class, setting the structured
//! fields of the variant (`path`, `element`, `line`, `index`, `argument`, `parameter`, `iteration`)
//! as attributes of the exception. One [`ToPyErr`] impl per Rust error type.

use bsv_core::io::obj::ObjError;
use bsv_core::io::ply::PlyError;
use bsv_core::io::{ReadError, WriteError};
use bsv_register::RegisterError;
use bsv_volume::VolumeError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyModule;
use std::path::Path;

static ERRORS: PyOnceLock<Py<PyModule>> = PyOnceLock::new();

/// A structured field of an exception.
pub enum Field {
    /// Text (a path, an element or argument name).
    Str(String),
    /// A count or index.
    Int(usize),
}

impl Field {
    fn path(p: &Path) -> Field {
        Field::Str(p.display().to_string())
    }
}

/// An exception of class `class` (a name in `bsv.errors`) with `message` and `fields` as attributes.
pub fn exception(class: &'static str, message: String, fields: Vec<(&'static str, Field)>) -> PyErr {
    Python::attach(|py| build(py, class, message, fields).unwrap_or_else(|e| e))
}

fn build(py: Python<'_>, class: &'static str, message: String, fields: Vec<(&'static str, Field)>) -> PyResult<PyErr> {
    let module = ERRORS.get_or_try_init(py, || py.import("bsv.errors").map(Bound::unbind))?.bind(py);
    let value = module.getattr(class)?.call1((message,))?;
    for (name, field) in fields {
        match field {
            Field::Str(s) => value.setattr(name, s)?,
            Field::Int(i) => value.setattr(name, i)?,
        }
    }
    Ok(PyErr::from_value(value))
}

/// `InputError` for argument `argument` (and the first bad entry `index`, if any).
pub fn input_error(argument: &str, index: Option<usize>, message: String) -> PyErr {
    let mut fields = vec![("argument", Field::Str(argument.to_string()))];
    fields.extend(index.map(|i| ("index", Field::Int(i))));
    exception("InputError", message, fields)
}

/// The error's message followed by its chain of causes.
pub fn message(e: &dyn std::error::Error) -> String {
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

/// A Rust error that maps onto one Python exception class.
pub trait ToPyErr {
    /// The Python exception.
    fn to_py_err(&self) -> PyErr;
}

impl ToPyErr for ReadError {
    fn to_py_err(&self) -> PyErr {
        let mut fields = Vec::new();
        match self {
            ReadError::Io { path, .. } | ReadError::UnsupportedExtension { path, .. } => {
                fields.push(("path", Field::path(path)));
            }
            ReadError::Ply { path, source } => {
                fields.push(("path", Field::path(path)));
                fields.extend(ply_location(source));
            }
            ReadError::Obj { path, source } => {
                fields.push(("path", Field::path(path)));
                fields.extend(obj_line(source).map(|l| ("line", Field::Int(l))));
            }
        }
        exception("FormatError", message(self), fields)
    }
}

/// Element and line of a PLY error, when it has them.
fn ply_location(e: &PlyError) -> Vec<(&'static str, Field)> {
    let mut out = Vec::new();
    match e {
        PlyError::HeaderSyntax { line, .. } | PlyError::UnknownType { line, .. } => {
            out.push(("line", Field::Int(*line)))
        }
        PlyError::AsciiRecord { line, element, .. } => {
            out.push(("line", Field::Int(*line)));
            out.push(("element", Field::Str(element.clone())));
        }
        PlyError::MissingElement { element }
        | PlyError::MissingProperty { element, .. }
        | PlyError::Truncated { element, .. }
        | PlyError::EndsEarly { element, .. }
        | PlyError::ExtraData { element, .. }
        | PlyError::BadListCount { element, .. }
        | PlyError::LabelOutOfRange { element, .. } => out.push(("element", Field::Str(element.clone()))),
        PlyError::FaceTooSmall { .. } | PlyError::FaceIndexOutOfRange { .. } => {
            out.push(("element", Field::Str("face".into())))
        }
        PlyError::NonFinite { .. } => out.push(("element", Field::Str("vertex".into()))),
        _ => {}
    }
    out
}

/// Line of an OBJ error, when it has one.
fn obj_line(e: &ObjError) -> Option<usize> {
    match e {
        ObjError::BadVertex { line, .. }
        | ObjError::NonFinite { line, .. }
        | ObjError::BadFace { line, .. }
        | ObjError::FaceTooSmall { line, .. }
        | ObjError::IndexOutOfRange { line, .. } => Some(*line),
        _ => None,
    }
}

impl ToPyErr for WriteError {
    fn to_py_err(&self) -> PyErr {
        let path = match self {
            WriteError::Io { path, .. }
            | WriteError::UnsupportedExtension { path, .. }
            | WriteError::Invalid { path, .. } => path,
        };
        exception("WriteError", message(self), vec![("path", Field::path(path))])
    }
}

impl ToPyErr for VolumeError {
    fn to_py_err(&self) -> PyErr {
        let at =
            |element: &str, index: usize| vec![("element", Field::Str(element.into())), ("index", Field::Int(index))];
        let fields = match self {
            VolumeError::Mesh(bsv_core::MeshInvariant::IndexOutOfRange { face, .. })
            | VolumeError::DegenerateFace { face, .. } => at("face", *face),
            VolumeError::NonFiniteVertex { vertex, .. } => at("vertex", *vertex),
            VolumeError::UnknownLabel { what, index, .. } => at(what, *index),
            VolumeError::LabelCountMismatch { what, .. } => vec![("element", Field::Str((*what).into()))],
            VolumeError::OpenMesh { .. }
            | VolumeError::NonManifold { .. }
            | VolumeError::InconsistentOrientation { .. } => {
                vec![("element", Field::Str("edge".into()))]
            }
            _ => Vec::new(),
        };
        exception("VolumeError", message(self), fields)
    }
}

impl ToPyErr for RegisterError {
    fn to_py_err(&self) -> PyErr {
        let (class, mut fields) = register_class(self);
        fields.extend(self.parameter().map(|p| ("parameter", Field::Str(p.into()))));
        exception(class, message(self), fields)
    }
}

/// The class of a registration error (one per stage) and its index fields.
fn register_class(e: &RegisterError) -> (&'static str, Vec<(&'static str, Field)>) {
    use bsv_register::{InputError as I, NumericError as N};
    match e {
        RegisterError::Parameter(_) => ("RegistrationParameterError", Vec::new()),
        RegisterError::Implausible(_) => ("ImplausibleCloudError", Vec::new()),
        RegisterError::Numeric(N::NoCorrespondences { iteration } | N::Diverged { iteration }) => {
            ("RegistrationNumericError", vec![("iteration", Field::Int(*iteration))])
        }
        RegisterError::Numeric(_) => ("RegistrationNumericError", Vec::new()),
        RegisterError::Resource(_) => ("RegistrationResourceError", Vec::new()),
        RegisterError::Stopped { iteration } => ("RegistrationStopped", vec![("iteration", Field::Int(*iteration))]),
        RegisterError::Input(I::NonFinitePoint { index, .. } | I::NonFiniteTemplateVertex { index, .. }) => {
            ("RegistrationInputError", vec![("index", Field::Int(*index))])
        }
        RegisterError::Input(
            I::BadTriangleIndex(bsv_core::MeshInvariant::IndexOutOfRange { face: triangle, .. })
            | I::DegenerateTemplate { triangle, .. },
        ) => ("RegistrationInputError", vec![("index", Field::Int(*triangle))]),
        RegisterError::Input(_) => ("RegistrationInputError", Vec::new()),
    }
}

impl ToPyErr for bsv_capture::scanner::ScanError {
    fn to_py_err(&self) -> PyErr {
        use bsv_capture::scanner::ScanError as S;
        let fields = match self {
            S::BadRoom { param, .. } | S::CameraOutsideRoom { param, .. } => {
                vec![("parameter", Field::Str(format!("room.{param}")))]
            }
            S::BadNoise { param, .. } => vec![("parameter", Field::Str((*param).to_string()))],
            _ => Vec::new(),
        };
        exception("ScanError", message(self), fields)
    }
}

impl ToPyErr for bsv_capture::distance::DistanceError {
    fn to_py_err(&self) -> PyErr {
        use bsv_capture::distance::DistanceError as D;
        match self {
            D::NonFinitePoint(i) => input_error("points", Some(*i), message(self)),
            D::Mesh(_) => input_error("mesh", None, message(self)),
        }
    }
}

/// The person could not be isolated in a view: `PersonIsolationError` (`camera`); every other cloud
/// building error is about the inputs: `InputError` (`argument` "views").
impl ToPyErr for bsv_capture::fuse::FuseError {
    fn to_py_err(&self) -> PyErr {
        use bsv_capture::fuse::FuseError as F;
        match self {
            F::PersonNotIsolated { camera, .. } | F::NothingLeft { camera, .. } => {
                exception("PersonIsolationError", message(self), vec![("camera", Field::Str(camera.clone()))])
            }
            F::FlatView { camera, .. } | F::MirroredView { camera, .. } => {
                exception("ImplausibleCaptureError", message(self), vec![("camera", Field::Str(camera.clone()))])
            }
            _ => exception("InputError", message(self), vec![("argument", Field::Str("views".into()))]),
        }
    }
}

/// The embedded template failed to parse (a build defect, not user input).
impl ToPyErr for PlyError {
    fn to_py_err(&self) -> PyErr {
        exception("MeshError", message(self), Vec::new())
    }
}

/// Keyword parameters that do not deserialize (unknown name, wrong type): `parameter` names the key.
pub fn parameter_error(kind: &'static str, parameter: Option<String>, e: &pythonize::PythonizeError) -> PyErr {
    let class = if kind == "registration" { "RegistrationParameterError" } else { "InputError" };
    let text = match &parameter {
        Some(p) => format!("{kind} parameter {p}: {e}"),
        None => format!("{kind} parameters: {e}"),
    };
    let mut fields = Vec::new();
    if let Some(p) = parameter {
        fields.push(("parameter", Field::Str(p.clone())));
        if class == "InputError" {
            fields.push(("argument", Field::Str(p)));
        }
    }
    exception(class, text, fields)
}

/// `map_err` adapter: `.map_err(py_err)`.
pub fn py_err<E: ToPyErr>(e: E) -> PyErr {
    e.to_py_err()
}
