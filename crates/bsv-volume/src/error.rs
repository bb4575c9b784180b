//! The error type of every volume operation (closing, labelling, segment volumes, reports).

use bsv_core::MeshInvariant;
use thiserror::Error;

/// Why a volume could not be computed. Every message names the offending element and says what to do.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum VolumeError {
    /// The mesh has no triangles.
    #[error("the mesh has no triangles: nothing encloses a volume; check that the file holds faces (a point cloud has none)")]
    EmptyMesh,
    /// A triangle refers to a vertex that does not exist.
    #[error("{0}; the file is corrupt or was cut short")]
    Mesh(#[from] MeshInvariant),
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate {position:?}; remove or repair it before measuring volumes")]
    NonFiniteVertex {
        /// Vertex index.
        vertex: usize,
        /// Its coordinates.
        position: [f64; 3],
    },
    /// A triangle uses the same vertex twice.
    #[error(
        "triangle {face} uses vertex {vertex} twice (degenerate face); remove degenerate faces (mesh repair) first"
    )]
    DegenerateFace {
        /// Triangle index.
        face: usize,
        /// The repeated vertex.
        vertex: u32,
    },
    /// The mesh has holes and closing was not requested.
    #[error(
        "the mesh is open: {boundary_edges} boundary edges in {loops} boundary loop(s){}; a volume needs a closed \
         surface: close the holes (repair the mesh) or ask for closing (close_holes = true, `--close-holes`), \
         which fans each loop to its centroid",
        fmt_centroids(.loop_centroids)
    )]
    OpenMesh {
        /// Number of boundary loops.
        loops: usize,
        /// Number of boundary edges (edges used by one triangle).
        boundary_edges: usize,
        /// Centroids (metres) of the first few loops, largest first, to locate the holes.
        loop_centroids: Vec<[f64; 3]>,
    },
    /// Some edges are shared by more than two triangles.
    #[error(
        "the mesh is non-manifold: {edges} edge(s) are shared by more than two triangles (e.g. edge {}-{} with {faces} \
         triangles at {position:?}); split or remove the extra sheets (mesh repair) before measuring volumes",
        .example.0, .example.1
    )]
    NonManifold {
        /// Number of non-manifold edges.
        edges: usize,
        /// One such edge (vertex ids).
        example: (u32, u32),
        /// Number of triangles on that edge.
        faces: usize,
        /// Midpoint of that edge, metres.
        position: [f64; 3],
    },
    /// Two neighbouring triangles run their common edge in the same direction.
    #[error(
        "the mesh is not consistently oriented: {edges} edge(s) are run the same way by both triangles (e.g. edge \
         {}-{} at {position:?}); orient the faces consistently (mesh repair) before measuring volumes",
        .example.0, .example.1
    )]
    InconsistentOrientation {
        /// Number of such edges.
        edges: usize,
        /// One such edge (vertex ids).
        example: (u32, u32),
        /// Midpoint of that edge, metres.
        position: [f64; 3],
    },
    /// A label array does not match the element count.
    #[error(
        "{what} labels have {got} entries but the mesh has {expected} {what}s; relabel the mesh or drop the labels"
    )]
    LabelCountMismatch {
        /// "vertex" or "face".
        what: &'static str,
        /// Length of the label array.
        got: usize,
        /// Number of vertices or faces.
        expected: usize,
    },
    /// A label is not a segment id (0..=14).
    #[error("{what} {index} has label {label}, which is not a segment id (0..=14, see DESIGN.md); fix the labels")]
    UnknownLabel {
        /// "vertex" or "face".
        what: &'static str,
        /// Element index.
        index: usize,
        /// The bad label.
        label: u8,
    },
    /// A vertex array passed to a prepared mesh (`PreparedSegments`) has another vertex count.
    #[error(
        "vertices: the vertex array has {got} vertices but the prepared mesh has {expected}; pass `vertices` \
         as the prepared mesh's vertices moved (same count and order: {expected} rows of x, y, z), or prepare \
         the mesh that has {got} vertices"
    )]
    VertexCountMismatch {
        /// Vertex count of the prepared mesh.
        expected: usize,
        /// Vertex count given.
        got: usize,
    },
    /// Flat coordinates passed to a prepared mesh (`PreparedSegments::evaluate_coords`) whose length is
    /// not a multiple of 3, so they are not whole vertices.
    #[error(
        "vertices: the flat coordinate array has {len} numbers, which is not a multiple of 3 (x, y, z per \
         vertex); pass the vertices as an (N, 3) array flattened row by row (x0 y0 z0 x1 y1 z1 ...)"
    )]
    CoordinatesNotTriples {
        /// Length of the coordinate array.
        len: usize,
    },
    /// A stack of flat coordinate arrays (`PreparedSegments::quantities_stacked`) whose length is not
    /// draws x vertices x 3.
    #[error(
        "vertices: the stacked coordinate array has {len} numbers but {draws} draws of {vertices} vertices \
         need {draws} x {vertices} x 3; pass a C-ordered (S, N, 3) array with its S and N"
    )]
    StackLengthMismatch {
        /// Length of the coordinate array.
        len: usize,
        /// Number of draws (S) given.
        draws: usize,
        /// Vertex count per draw (N) given.
        vertices: usize,
    },
    /// The density is not a positive finite number.
    #[error("density {0} kg/m^3 is not a positive finite number; use e.g. 1000 (water) or 1010 (body)")]
    InvalidDensity(f64),
}

fn fmt_centroids(c: &[[f64; 3]]) -> String {
    if c.is_empty() {
        return String::new();
    }
    let list: Vec<String> = c.iter().map(|p| format!("({:.4}, {:.4}, {:.4})", p[0], p[1], p[2])).collect();
    format!(" centred at {} m", list.join(", "))
}
