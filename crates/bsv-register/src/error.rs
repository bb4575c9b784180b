//! The typed errors of a registration: every variant says what was wrong and what to do.

use thiserror::Error;

/// Why a registration could not run (bad cloud, bad template, bad parameters, numerical failure).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RegisterError {
    /// The point cloud holds no point at all.
    #[error("point cloud is empty: capture or load a cloud with at least {min} points")]
    EmptyCloud {
        /// Minimum number of points a registration needs.
        min: usize,
    },
    /// Every point of the (labelled) cloud is a head, hand or foot point, dropped by
    /// `drop_extremities`.
    #[error("all {n} cloud points are labelled head/hand/foot and were dropped (drop_extremities): check the cloud's labels, or keep them (registration parameter drop_extremities = false; Python: bsv.register(..., drop_extremities=False); bsv-cli: --keep-extremities)")]
    OnlyExtremities {
        /// Points in the cloud before dropping.
        n: usize,
    },
    /// The point cloud holds too few points to register anything.
    #[error("point cloud has only {n} points: a registration needs at least {min}; check the capture or the cleaning step")]
    TooFewPoints {
        /// Points found.
        n: usize,
        /// Minimum number of points a registration needs.
        min: usize,
    },
    /// A cloud point has a NaN or infinite coordinate.
    #[error("cloud point {index} is not finite ({point:?}): drop NaN/inf points (invalid depth pixels) before registering")]
    NonFinitePoint {
        /// Index of the first bad point.
        index: usize,
        /// Its coordinates.
        point: [f64; 3],
    },
    /// The cloud is far larger than a human body in metres.
    #[error("point cloud extent {extent_m:.1} (max axis) is larger than {limit_m} m: it looks like millimetres; divide the coordinates by 1000 (bsv-cli: --units mm)")]
    CloudLooksLikeMillimetres {
        /// Largest robust bounding-box side, in the cloud's units.
        extent_m: f64,
        /// The limit used.
        limit_m: f64,
    },
    /// The cloud is far smaller than a human segment in metres.
    #[error("point cloud extent {extent_m:.4} (max axis) is smaller than {limit_m} m: the cloud is too small or not in metres (kilometres? scaled?); convert it to metres")]
    CloudTooSmall {
        /// Largest robust bounding-box side.
        extent_m: f64,
        /// The limit used.
        limit_m: f64,
    },
    /// The template mesh holds no vertex or no triangle.
    #[error("template mesh is empty ({vertices} vertices, {triangles} triangles): load a closed triangle mesh")]
    EmptyTemplate {
        /// Vertex count.
        vertices: usize,
        /// Triangle count.
        triangles: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("template triangle {triangle} refers to vertex {vertex} but the mesh has {n_vertices} vertices: the mesh file is corrupt")]
    BadTriangleIndex {
        /// Triangle index.
        triangle: usize,
        /// The out-of-range vertex id.
        vertex: u32,
        /// Number of vertices.
        n_vertices: usize,
    },
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
    #[error("labels = template was requested but the template has no vertex labels: use a labelled template (OBJ groups / PLY label) or labels = cloud")]
    TemplateWithoutLabels,
    /// Labels from the cloud were requested but the cloud carries none. Not returned by
    /// [`crate::register`], which falls back to the template's labels (see
    /// [`crate::RegisterParams::labels`]); kept for callers that require cloud labels.
    #[error("labels = cloud was requested but the cloud has no labels: pass a labelled cloud or use labels = template")]
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
    /// The schedule string cannot be parsed.
    #[error("bad schedule {text:?}: {reason}; expected comma-separated KIND:COUNT with KIND m2p or p2m, e.g. \"m2p:5,p2m:5,m2p:10\"")]
    BadSchedule {
        /// The text given.
        text: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A numeric parameter is out of its valid range.
    #[error("parameter {name} = {value} is invalid: {hint}")]
    BadParameter {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// The valid range.
        hint: &'static str,
    },
    /// No correspondence survived the pruning in an iteration.
    #[error("iteration {iteration}: no correspondence survived the pruning; the template and the cloud do not overlap (check units and frame, or loosen the pruning: registration parameters prune_distance_factor / prune_normal_angle_deg, Python: bsv.register(..., prune_distance_factor=..., prune_normal_angle_deg=...))")]
    NoCorrespondences {
        /// The global iteration index.
        iteration: usize,
    },
    /// The linear system could not be factorized or solved.
    #[error("linear solver failed: {0}; the template is probably degenerate (run the mesh check) or the weights are invalid")]
    Solver(String),
    /// A spatial index (k-d tree over the cloud or the fitted vertices) could not be built or
    /// queried.
    #[error("spatial index (k-d tree) failed: {0}; the cloud probably holds very many identical points: remove duplicates (e.g. voxel-downsample the cloud) and retry")]
    Index(String),
    /// The fit produced non-finite vertices.
    #[error("iteration {iteration}: the fit diverged (non-finite vertices); lower the registration parameter data_weight or raise alpha (Python: bsv.register(..., data_weight=..., alpha=...); bsv-cli: --alpha)")]
    Diverged {
        /// The global iteration index.
        iteration: usize,
    },
    /// The thread pool could not be built.
    #[error("could not build a thread pool of {threads} threads: {reason}")]
    ThreadPool {
        /// Requested threads.
        threads: usize,
        /// The error text.
        reason: String,
    },
}
