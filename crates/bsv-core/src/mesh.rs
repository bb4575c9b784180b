//! The triangle mesh type shared by every crate.

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
}
