//! The triangle mesh type shared by every crate, and the one error for a broken mesh invariant.

use thiserror::Error;

/// A broken invariant of an in-memory triangle mesh, the one error type for it (the
/// PLY/OBJ writers, the volume code and the scanner wrap it and add their remedy).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum MeshInvariant {
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {face} refers to vertex {index} but there are only {n_vertices} vertices")]
    IndexOutOfRange {
        /// Triangle index.
        face: usize,
        /// The bad vertex index.
        index: u32,
        /// Number of vertices.
        n_vertices: usize,
    },
}

/// Checks that every triangle index is below `n_vertices`; the first bad triangle is reported.
pub fn check_indices(triangles: &[[u32; 3]], n_vertices: usize) -> Result<(), MeshInvariant> {
    for (face, t) in triangles.iter().enumerate() {
        if let Some(&index) = t.iter().find(|&&i| i as usize >= n_vertices) {
            return Err(MeshInvariant::IndexOutOfRange { face, index, n_vertices });
        }
    }
    Ok(())
}

/// A triangle mesh in metres (f64 vertices, u32 triangles) with optional segment labels.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions, metres, world frame.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Optional per-vertex segment ids (same length as `vertices`).
    pub vertex_labels: Option<Vec<u8>>,
    /// Optional per-face segment ids (same length as `triangles`).
    pub face_labels: Option<Vec<u8>>,
}

impl TriMesh {
    /// A mesh without labels.
    pub fn new(vertices: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> Self {
        TriMesh { vertices, triangles, vertex_labels: None, face_labels: None }
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Number of triangles.
    pub fn n_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `t`.
    pub fn triangle_points(&self, t: usize) -> [[f64; 3]; 3] {
        let [a, b, c] = self.triangles[t];
        [self.vertices[a as usize], self.vertices[b as usize], self.vertices[c as usize]]
    }

    /// Checks that every triangle refers to an existing vertex (see [`check_indices`]).
    pub fn check_indices(&self) -> Result<(), MeshInvariant> {
        check_indices(&self.triangles, self.vertices.len())
    }
}
