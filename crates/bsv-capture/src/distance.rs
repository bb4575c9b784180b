//! Ground truth for clouds: the exact distance from each point to a true surface (point-to-triangle,
//! parry's point projection on the mesh BVH), and the triangle it lands on. Benchmarks use them to count
//! cloud points far from the body (floor, wall or mask spill that survived the cloud building) and to
//! read the true segment under a fitted surface.

use crate::scanner::{parry_mesh, ScanError};
use bsv_core::TriMesh;
use parry3d_f64::math::Vector;
use parry3d_f64::query::PointQuery;
use rayon::prelude::*;

/// Errors of [`surface_distances`] and [`surface_nearest`].
#[derive(Debug, thiserror::Error)]
pub enum DistanceError {
    /// The mesh cannot be used (empty, bad index, non-finite vertex).
    #[error("surface mesh: {0}")]
    Mesh(#[from] ScanError),
    /// A query point has a NaN or infinite coordinate.
    #[error("point {0} has a non-finite coordinate: drop or repair it before measuring distances")]
    NonFinitePoint(usize),
}

/// The unsigned distance (metres) from every point to the nearest point of the surface `mesh`
/// (its triangles, not its inside: a point inside a closed mesh gets its distance to the surface).
pub fn surface_distances(points: &[[f64; 3]], mesh: &TriMesh) -> Result<Vec<f64>, DistanceError> {
    Ok(surface_nearest(points, mesh)?.into_iter().map(|(d, _)| d).collect())
}

/// For every point, its unsigned distance (metres) to the surface `mesh` and the index of the triangle
/// that holds the nearest surface point (one of them when several are equally near: an edge or a vertex).
pub fn surface_nearest(points: &[[f64; 3]], mesh: &TriMesh) -> Result<Vec<(f64, u32)>, DistanceError> {
    if let Some(i) = points.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
        return Err(DistanceError::NonFinitePoint(i));
    }
    let bvh = parry_mesh(mesh)?;
    Ok(points
        .par_iter()
        .map(|p| {
            let q = Vector::new(p[0], p[1], p[2]);
            let (proj, _) = bvh.project_local_point_and_get_feature(q);
            ((proj.point - q).length(), proj.subshape)
        })
        .collect())
}

/// The fraction of `distances` strictly greater than `threshold` (0 for no distance).
pub fn fraction_beyond(distances: &[f64], threshold: f64) -> f64 {
    if distances.is_empty() {
        return 0.0;
    }
    distances.iter().filter(|&&d| d > threshold).count() as f64 / distances.len() as f64
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use bsv_core::shapes;

    #[test]
    fn distances_to_a_box_are_exact() {
        let b = shapes::cuboid([1.0, 2.0, 4.0]);
        let pts = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.5, 1.0, 2.0], [1.5, 2.0, 0.0], [0.1, 0.2, 0.3]];
        let d = surface_distances(&pts, &b).unwrap();
        let want = [0.5, 1.5, 0.0, (1.0f64 + 1.0).sqrt(), 0.4];
        for (got, w) in d.iter().zip(want) {
            assert!((got - w).abs() < 1e-12, "{got} vs {w}");
        }
        assert!((fraction_beyond(&d, 0.45) - 0.6).abs() < 1e-12);
        assert!(matches!(surface_distances(&[[f64::NAN, 0.0, 0.0]], &b), Err(DistanceError::NonFinitePoint(0))));
        assert!(matches!(surface_distances(&pts, &TriMesh::default()), Err(DistanceError::Mesh(_))));
    }

    #[test]
    fn the_nearest_triangle_is_the_one_under_the_point() {
        let half = [0.5, 1.0, 2.0];
        let b = shapes::cuboid([1.0, 2.0, 4.0]);
        // A point 0.1 off the middle of each of the six sides, and the axis of that side's normal: the
        // triangle found lies in that side's plane.
        let sides = [
            ([0.6, 0.0, 0.0], 0),
            ([-0.6, 0.0, 0.0], 0),
            ([0.1, 1.1, 0.2], 1),
            ([0.1, -1.1, 0.2], 1),
            ([0.1, 0.2, 2.1], 2),
            ([0.1, 0.2, -2.1], 2),
        ];
        let pts: Vec<[f64; 3]> = sides.iter().map(|s| s.0).collect();
        let near = surface_nearest(&pts, &b).unwrap();
        for ((p, axis), (d, t)) in sides.iter().zip(&near) {
            assert!((d - 0.1).abs() < 1e-12, "{d}");
            for v in b.triangles[*t as usize] {
                let c = b.vertices[v as usize][*axis];
                assert!(
                    (c - p[*axis].signum() * half[*axis]).abs() < 1e-12,
                    "triangle {t} is not on the side of {p:?}"
                );
            }
        }
        let d = surface_distances(&pts, &b).unwrap();
        assert_eq!(d, near.iter().map(|x| x.0).collect::<Vec<_>>());
    }
}
