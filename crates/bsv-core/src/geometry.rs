//! Geometry helpers on meshes and point sets: areas, normals, bounding boxes, vector arithmetic.

use crate::TriMesh;

/// `a - b`.
#[inline]
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a + b`.
#[inline]
pub fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a * s`.
#[inline]
pub fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Dot product.
#[inline]
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product.
#[inline]
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Euclidean norm.
#[inline]
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// Squared distance between two points.
#[inline]
pub fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}

/// `a / |a|`, or zero when `|a|` is zero.
#[inline]
pub fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = norm(a);
    if n > 0.0 {
        scale(a, 1.0 / n)
    } else {
        [0.0; 3]
    }
}

/// The one rule for "not in metres" (registration clouds, `bsv-cli volume` / `info` meshes): a cloud or
/// mesh whose largest (robust) bounding-box side exceeds this many metres is taken as millimetres
/// (no body, box or room the project measures is 5 m long).
pub const MAX_EXTENT_M: f64 = 5.0;

/// True when a largest bounding-box side of `extent` (file units) breaks [`MAX_EXTENT_M`]: the
/// coordinates are probably millimetres.
pub fn looks_like_millimetres(extent: f64) -> bool {
    extent > MAX_EXTENT_M
}

/// An axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: [f64; 3],
    /// Largest corner.
    pub max: [f64; 3],
}

impl Aabb {
    /// The box of a point set, `None` when it is empty or holds a non-finite value.
    pub fn of_points(points: &[[f64; 3]]) -> Option<Aabb> {
        let mut it = points.iter();
        let first = *it.next()?;
        let mut b = Aabb { min: first, max: first };
        for p in it {
            for (k, &v) in p.iter().enumerate() {
                b.min[k] = b.min[k].min(v);
                b.max[k] = b.max[k].max(v);
            }
        }
        let finite = b.min.iter().chain(b.max.iter()).all(|v| v.is_finite())
            && points.iter().all(|p| p.iter().all(|v| v.is_finite()));
        finite.then_some(b)
    }

    /// Box centre.
    pub fn center(&self) -> [f64; 3] {
        scale(add(self.min, self.max), 0.5)
    }

    /// Edge lengths along x, y, z.
    pub fn extent(&self) -> [f64; 3] {
        sub(self.max, self.min)
    }

    /// Length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        norm(self.extent())
    }
}

/// Twice-the-area vector (unnormalised normal) of triangle `t`.
#[inline]
pub fn face_cross(mesh: &TriMesh, t: usize) -> [f64; 3] {
    let [a, b, c] = mesh.triangle_points(t);
    cross(sub(b, a), sub(c, a))
}

/// Area of every triangle, m^2.
pub fn face_areas(mesh: &TriMesh) -> Vec<f64> {
    (0..mesh.n_triangles()).map(|t| 0.5 * norm(face_cross(mesh, t))).collect()
}

/// Total surface area, m^2.
pub fn total_area(mesh: &TriMesh) -> f64 {
    face_areas(mesh).iter().sum()
}

/// Unit face normals (zero for degenerate faces).
pub fn face_normals(mesh: &TriMesh) -> Vec<[f64; 3]> {
    (0..mesh.n_triangles()).map(|t| normalize(face_cross(mesh, t))).collect()
}

/// Area-weighted unit vertex normals (zero for isolated vertices).
pub fn vertex_normals(mesh: &TriMesh) -> Vec<[f64; 3]> {
    let mut acc = vec![[0.0; 3]; mesh.n_vertices()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let n = face_cross(mesh, t);
        for &v in tri {
            acc[v as usize] = add(acc[v as usize], n);
        }
    }
    acc.into_iter().map(normalize).collect()
}

/// Signed volume enclosed by the triangles (divergence theorem; meaningful for closed meshes).
pub fn signed_volume(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> f64 {
    triangles
        .iter()
        .map(|&[a, b, c]| {
            let (a, b, c) = (vertices[a as usize], vertices[b as usize], vertices[c as usize]);
            dot(a, cross(b, c))
        })
        .sum::<f64>()
        / 6.0
}
