//! Validation of a mesh for volume work and its sorted (deterministic) edge table.

use crate::VolumeError;
use bsv_core::geometry::{add, scale};
use bsv_core::{MeshInvariant, TriMesh};

/// An edge used by exactly two triangles that run it in opposite directions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct InteriorEdge {
    /// Start vertex as `face_fwd` runs it.
    pub from: u32,
    /// End vertex as `face_fwd` runs it.
    pub to: u32,
    /// The face running `from -> to`.
    pub face_fwd: u32,
    /// The face running `to -> from`.
    pub face_back: u32,
}

/// The edges of a triangle list, classified; every list is sorted by vertex ids (deterministic).
#[derive(Debug, Clone, Default)]
pub(crate) struct EdgeTable {
    /// Manifold, consistently oriented edges.
    pub interior: Vec<InteriorEdge>,
    /// Boundary half-edges `(from, to, face)` as their single face runs them.
    pub boundary: Vec<(u32, u32, u32)>,
    /// Edges with more than two faces: `(lo, hi, face count)`.
    pub non_manifold: Vec<(u32, u32, usize)>,
    /// Two-face edges run the same way by both faces: `(lo, hi)`.
    pub inconsistent: Vec<(u32, u32)>,
}

impl EdgeTable {
    /// Builds the table by sorting the 3 m half-edges (O(m log m), no hashing).
    pub fn build(triangles: &[[u32; 3]]) -> EdgeTable {
        // (lo, hi, face, forward) where forward means the face runs lo -> hi.
        let mut half: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(triangles.len() * 3);
        for (f, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                half.push((a.min(b), a.max(b), f as u32, a < b));
            }
        }
        half.sort_unstable();
        let mut table = EdgeTable::default();
        let mut i = 0;
        while i < half.len() {
            let (lo, hi, _, _) = half[i];
            let mut j = i + 1;
            while j < half.len() && half[j].0 == lo && half[j].1 == hi {
                j += 1;
            }
            let group = &half[i..j];
            match group {
                [(_, _, f, fwd)] => {
                    let (a, b) = if *fwd { (lo, hi) } else { (hi, lo) };
                    table.boundary.push((a, b, *f));
                }
                [(_, _, f0, d0), (_, _, f1, d1)] => {
                    if d0 == d1 {
                        table.inconsistent.push((lo, hi));
                    } else {
                        let (ffwd, fback) = if *d0 { (*f0, *f1) } else { (*f1, *f0) };
                        table.interior.push(InteriorEdge { from: lo, to: hi, face_fwd: ffwd, face_back: fback });
                    }
                }
                _ => table.non_manifold.push((lo, hi, group.len())),
            }
            i = j;
        }
        table
    }

    /// Errors for non-manifold or inconsistently oriented edges (in that order of priority).
    pub fn check_manifold(&self, vertices: &[[f64; 3]]) -> Result<(), VolumeError> {
        let mid = |a: u32, b: u32| scale(add(vertices[a as usize], vertices[b as usize]), 0.5);
        if let Some(&(lo, hi, faces)) = self.non_manifold.first() {
            return Err(VolumeError::NonManifold {
                edges: self.non_manifold.len(),
                example: (lo, hi),
                faces,
                position: mid(lo, hi),
            });
        }
        if let Some(&(lo, hi)) = self.inconsistent.first() {
            return Err(VolumeError::InconsistentOrientation {
                edges: self.inconsistent.len(),
                example: (lo, hi),
                position: mid(lo, hi),
            });
        }
        Ok(())
    }
}

/// Checks that the mesh has triangles, in-range distinct indices and finite vertices.
pub(crate) fn validate(mesh: &TriMesh) -> Result<(), VolumeError> {
    if mesh.triangles.is_empty() {
        return Err(VolumeError::EmptyMesh);
    }
    let n = mesh.vertices.len();
    for (face, t) in mesh.triangles.iter().enumerate() {
        for &index in t {
            if index as usize >= n {
                return Err(MeshInvariant::IndexOutOfRange { face, index, n_vertices: n }.into());
            }
        }
        if t[0] == t[1] || t[0] == t[2] {
            return Err(VolumeError::DegenerateFace { face, vertex: t[0] });
        }
        if t[1] == t[2] {
            return Err(VolumeError::DegenerateFace { face, vertex: t[1] });
        }
    }
    check_finite(&mesh.vertices)
}

/// A `NonFiniteVertex` error for the first vertex with a NaN or infinite coordinate.
pub(crate) fn check_finite(vertices: &[[f64; 3]]) -> Result<(), VolumeError> {
    if let Some((vertex, p)) = vertices.iter().enumerate().find(|(_, p)| !p.iter().all(|v| v.is_finite())) {
        return Err(VolumeError::NonFiniteVertex { vertex, position: *p });
    }
    Ok(())
}

/// Mean of the vertices used by at least one triangle (the reference point for tetrahedra sums).
pub(crate) fn used_centroid(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> [f64; 3] {
    let mut used = vec![false; vertices.len()];
    for t in triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut acc = [0.0; 3];
    let mut count = 0usize;
    for (p, _) in vertices.iter().zip(&used).filter(|(_, &u)| u) {
        acc = add(acc, *p);
        count += 1;
    }
    if count == 0 {
        [0.0; 3]
    } else {
        scale(acc, 1.0 / count as f64)
    }
}

/// Six times the signed volume of the tetrahedron (r, a, b, c).
#[inline]
pub(crate) fn det6(r: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    use bsv_core::geometry::{cross, dot, sub};
    dot(sub(a, r), cross(sub(b, r), sub(c, r)))
}
