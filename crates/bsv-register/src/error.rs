//! The typed errors of a registration, one enum per stage (parry's style): bad input
//! ([`InputError`]), bad parameters ([`ParameterError`]), numerical failures during the fit
//! ([`NumericError`]) and resources ([`ResourceError`]), joined in [`RegisterError`].
//!
//! Every message says what was wrong and what to do. A remedy names registration parameters
//! ("registration parameter data_weight"), never a front end's flags or calls: the front ends add
//! those, using [`RegisterError::parameters`] to find the parameters a remedy points to.

use crate::params::PARAMETER_NAMES;
pub use crate::plausible::ImplausibleError;
use thiserror::Error;

/// Why a registration could not run or did not finish.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RegisterError {
    /// The cloud or the template is unusable (checked before the fit).
    #[error(transparent)]
    Input(#[from] InputError),
    /// The cloud is not a standing person in the world frame (`plausible.rs`).
    #[error(transparent)]
    Implausible(#[from] ImplausibleError),
    /// A registration parameter is invalid.
    #[error(transparent)]
    Parameter(#[from] ParameterError),
    /// The fit failed numerically.
    #[error(transparent)]
    Numeric(#[from] NumericError),
    /// A resource (thread pool) could not be had.
    #[error(transparent)]
    Resource(#[from] ResourceError),
    /// The progress callback returned `ControlFlow::Break` after iteration `iteration`.
    #[error("the registration was stopped after iteration {iteration} (the progress callback asked to stop)")]
    Stopped {
        /// The global index of the last iteration that ran (0-based).
        iteration: usize,
    },
}

impl RegisterError {
    /// The registration parameters a remedy in the message points to (first the main one), empty
    /// when the remedy is not a parameter. Every name is a key of `RegisterParams`' serde form.
    pub fn parameters(&self) -> &'static [&'static str] {
        match self {
            RegisterError::Input(e) => e.parameters(),
            RegisterError::Implausible(_) => named("check_plausible"),
            RegisterError::Parameter(e) => e.parameters(),
            RegisterError::Numeric(e) => e.parameters(),
            RegisterError::Resource(e) => e.parameters(),
            RegisterError::Stopped { .. } => &[],
        }
    }

    /// The parameter a remedy points to first, if any (see [`Self::parameters`]).
    pub fn parameter(&self) -> Option<&'static str> {
        self.parameters().first().copied()
    }
}

/// The one-element slice of [`PARAMETER_NAMES`] holding `name` (empty when it is not one).
fn named(name: &str) -> &'static [&'static str] {
    match PARAMETER_NAMES.iter().position(|&n| n == name) {
        Some(i) => &PARAMETER_NAMES[i..i + 1],
        None => &[],
    }
}

/// A bad cloud or template (found by the checks before the fit).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum InputError {
    /// The point cloud holds no point at all.
    #[error("point cloud is empty: capture or load a cloud with at least {min} points")]
    EmptyCloud {
        /// Minimum number of points a registration needs.
        min: usize,
    },
    /// Every point of the (labelled) cloud is a head, hand or foot point, dropped by
    /// `drop_extremities`.
    #[error("all {n} cloud points are labelled head/hand/foot and were dropped: check the cloud's labels, or keep them (registration parameter drop_extremities = false)")]
    OnlyExtremities {
        /// Points in the cloud before dropping.
        n: usize,
    },
    /// The point cloud holds too few points to register anything.
    #[error("point cloud has only {n} points: a registration needs at least {min} (registration parameter min_points); check the capture or the cleaning step")]
    TooFewPoints {
        /// Points found.
        n: usize,
        /// Minimum number of points a registration needs.
        min: usize,
    },
    /// A cloud point has a NaN or infinite coordinate.
    #[error(
        "cloud point {index} is not finite ({point:?}): drop NaN/inf points (invalid depth pixels) before registering"
    )]
    NonFinitePoint {
        /// Index of the first bad point.
        index: usize,
        /// Its coordinates.
        point: [f64; 3],
    },
    /// The cloud is far larger than a human body in metres.
    #[error("point cloud extent {extent_m:.1} (max axis) is larger than {limit_m} m (registration parameter max_extent_m): it looks like millimetres; divide the coordinates by 1000")]
    CloudLooksLikeMillimetres {
        /// Largest robust bounding-box side, in the cloud's units.
        extent_m: f64,
        /// The limit used.
        limit_m: f64,
    },
    /// The cloud is far smaller than a human segment in metres.
    #[error("point cloud extent {extent_m:.4} (max axis) is smaller than {limit_m} m (registration parameter min_extent_m): the cloud is too small or not in metres (kilometres? scaled?); convert it to metres")]
    CloudTooSmall {
        /// Largest robust bounding-box side.
        extent_m: f64,
        /// The limit used.
        limit_m: f64,
    },
    /// A measured joint centre names a joint the template does not carry.
    #[error("keypoint `{name}`: the template carries no such joint (it carries: {known}); use one of those names or drop the keypoint")]
    UnknownKeypoint {
        /// The measured joint's name.
        name: String,
        /// The template's joint names.
        known: String,
    },
    /// A measured joint centre is unusable.
    #[error("keypoint `{name}`: {reason}; give a finite position in metres and a confidence in [0, 1]")]
    BadKeypoint {
        /// The measured joint's name.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// A template joint ring does not fit the template (wrong vertex indices or weights).
    #[error("template joint `{name}` does not fit the template ({n_vertices} vertices): its ring refers to other vertices or its weights are not >= 0 summing to 1; give the rings made for this template (the embedded templates carry theirs)")]
    BadJointRing {
        /// The joint's name.
        name: String,
        /// The template's vertex count.
        n_vertices: usize,
    },
    /// The template mesh holds no vertex or no triangle.
    #[error("template mesh is empty ({vertices} vertices, {triangles} triangles): load a closed triangle mesh")]
    EmptyTemplate {
        /// Vertex count.
        vertices: usize,
        /// Triangle count.
        triangles: usize,
    },
    /// A template triangle refers to a vertex that does not exist (core's mesh invariant).
    #[error("template {0}: the mesh file is corrupt; re-export or repair the template")]
    BadTriangleIndex(#[from] bsv_core::MeshInvariant),
    /// A template vertex has a NaN or infinite coordinate.
    #[error("template vertex {index} is not finite ({point:?}): repair or re-export the template")]
    NonFiniteTemplateVertex {
        /// Index of the first bad vertex.
        index: usize,
        /// Its coordinates.
        point: [f64; 3],
    },
    /// An edge of the template is used by a number of faces other than two.
    #[error("template is not a closed manifold: edge ({a}, {b}) is used by {faces} faces (must be 2); {count} such edges in all. Close holes / remove duplicate faces (bsv-core check/repair) before registering")]
    NonManifoldTemplate {
        /// First vertex of the first bad edge.
        a: u32,
        /// Second vertex of the first bad edge.
        b: u32,
        /// Faces using it.
        faces: usize,
        /// Number of bad edges.
        count: usize,
    },
    /// A template triangle has (near) zero area.
    #[error("template triangle {triangle} has zero area ({count} degenerate triangles in all): remove degenerate faces or remesh the template")]
    DegenerateTemplate {
        /// First degenerate triangle.
        triangle: usize,
        /// Number of degenerate triangles.
        count: usize,
    },
    /// Template labels were requested but the template carries none.
    #[error("registration parameter labels = template was requested but the template has no vertex labels: use a labelled template (OBJ groups / PLY label) or labels = cloud")]
    TemplateWithoutLabels,
    /// Labels from the cloud were requested but the cloud carries none. Not returned by
    /// [`crate::register`], which falls back to the template's labels (see
    /// [`crate::RegisterParams::labels`]); kept for callers that require cloud labels.
    #[error("registration parameter labels = cloud was requested but the cloud has no labels: pass a labelled cloud or use labels = template")]
    CloudWithoutLabels,
    /// A per-element attribute has the wrong length.
    #[error("{what} has {got} entries but {expected} were expected: the input arrays do not match")]
    LengthMismatch {
        /// Which attribute.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The expected length.
        expected: usize,
    },
}

impl InputError {
    /// See [`RegisterError::parameters`].
    pub fn parameters(&self) -> &'static [&'static str] {
        match self {
            InputError::OnlyExtremities { .. } => named("drop_extremities"),
            InputError::TooFewPoints { .. } => named("min_points"),
            InputError::CloudLooksLikeMillimetres { .. } => named("max_extent_m"),
            InputError::CloudTooSmall { .. } => named("min_extent_m"),
            InputError::TemplateWithoutLabels | InputError::CloudWithoutLabels => named("labels"),
            InputError::EmptyCloud { .. }
            | InputError::NonFinitePoint { .. }
            | InputError::EmptyTemplate { .. }
            | InputError::BadTriangleIndex(_)
            | InputError::NonFiniteTemplateVertex { .. }
            | InputError::NonManifoldTemplate { .. }
            | InputError::DegenerateTemplate { .. }
            | InputError::LengthMismatch { .. }
            | InputError::UnknownKeypoint { .. }
            | InputError::BadKeypoint { .. }
            | InputError::BadJointRing { .. } => &[],
        }
    }
}

/// A registration parameter out of its valid range, or a schedule that does not parse.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ParameterError {
    /// The schedule string cannot be parsed (or has no iteration).
    #[error("bad schedule {text:?} (registration parameter schedule): {reason}; expected comma-separated KIND:COUNT with KIND m2p or p2m, e.g. \"m2p:5,p2m:5,m2p:10\"")]
    BadSchedule {
        /// The text given.
        text: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A numeric parameter is out of its valid range.
    #[error("registration parameter {name} = {value} is invalid: {hint}")]
    BadParameter {
        /// Parameter name (a key of `RegisterParams`' serde form).
        name: &'static str,
        /// Value given.
        value: f64,
        /// The valid range.
        hint: &'static str,
    },
}

impl ParameterError {
    /// See [`RegisterError::parameters`].
    pub fn parameters(&self) -> &'static [&'static str] {
        match self {
            ParameterError::BadSchedule { .. } => named("schedule"),
            ParameterError::BadParameter { name, .. } => named(name),
        }
    }
}

/// A numerical failure during the fit.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum NumericError {
    /// No correspondence survived the pruning in an iteration.
    #[error("iteration {iteration}: no correspondence survived the pruning; the template and the cloud do not overlap (check units and frame, or loosen the pruning: registration parameters prune_distance_factor / prune_normal_angle_deg)")]
    NoCorrespondences {
        /// The global iteration index.
        iteration: usize,
    },
    /// The linear system could not be factorized or solved.
    #[error("linear solver failed: {reason}; the template is probably degenerate (run the mesh check) or the weights are invalid")]
    Solver {
        /// What the solver reported.
        reason: String,
    },
    /// The fit produced non-finite vertices.
    #[error("iteration {iteration}: the fit diverged (non-finite vertices); lower the registration parameter data_weight or raise alpha")]
    Diverged {
        /// The global iteration index.
        iteration: usize,
    },
    /// A spatial index (k-d tree over the cloud or the fitted vertices) could not be built or
    /// queried.
    #[error("spatial index (k-d tree) failed: {reason}; the cloud probably holds very many identical points: remove duplicates (e.g. voxel-downsample the cloud) and retry")]
    Index {
        /// What the k-d tree reported.
        reason: String,
    },
}

/// The pruning parameters named by [`NumericError::NoCorrespondences`].
const PRUNING: [&str; 2] = ["prune_distance_factor", "prune_normal_angle_deg"];
/// The parameters named by [`NumericError::Diverged`].
const STIFFNESS: [&str; 2] = ["data_weight", "alpha"];

impl NumericError {
    /// See [`RegisterError::parameters`].
    pub fn parameters(&self) -> &'static [&'static str] {
        match self {
            NumericError::NoCorrespondences { .. } => &PRUNING,
            NumericError::Diverged { .. } => &STIFFNESS,
            NumericError::Solver { .. } | NumericError::Index { .. } => &[],
        }
    }

    /// A solver failure (the solver reports text).
    pub(crate) fn solver(reason: String) -> NumericError {
        NumericError::Solver { reason }
    }

    /// A k-d tree failure (kiddo reports text).
    pub(crate) fn index(reason: String) -> NumericError {
        NumericError::Index { reason }
    }
}

/// A resource the registration could not get.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ResourceError {
    /// The thread pool could not be built.
    #[error("could not build a thread pool of {threads} threads (registration parameter threads): {reason}")]
    ThreadPool {
        /// Requested threads.
        threads: usize,
        /// The error text.
        reason: String,
    },
}

impl ResourceError {
    /// See [`RegisterError::parameters`].
    pub fn parameters(&self) -> &'static [&'static str] {
        match self {
            ResourceError::ThreadPool { .. } => named("threads"),
        }
    }
}
