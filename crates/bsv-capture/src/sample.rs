//! Uniform surface sampling: the simplest virtual capture, points drawn on a mesh (tests, benchmarks).

use bsv_core::geometry::{add, cross, norm, scale, sub};
use bsv_core::TriMesh;
use rand::{Rng, SeedableRng};

/// `n` points drawn uniformly on the surface (area-weighted), with the index of the face each lies on.
/// Deterministic for a seed.
pub fn sample_surface(mesh: &TriMesh, n: usize, seed: u64) -> (Vec<[f64; 3]>, Vec<u32>) {
    let mut cdf = Vec::with_capacity(mesh.n_triangles());
    let mut acc = 0.0;
    for t in 0..mesh.n_triangles() {
        let [a, b, c] = mesh.triangle_points(t);
        acc += 0.5 * norm(cross(sub(b, a), sub(c, a)));
        cdf.push(acc);
    }
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut points = Vec::with_capacity(n);
    let mut faces = Vec::with_capacity(n);
    if acc <= 0.0 {
        return (points, faces);
    }
    for _ in 0..n {
        let x = rng.random::<f64>() * acc;
        let t = cdf.partition_point(|&v| v < x).min(cdf.len() - 1);
        let (mut u, mut v) = (rng.random::<f64>(), rng.random::<f64>());
        if u + v > 1.0 {
            u = 1.0 - u;
            v = 1.0 - v;
        }
        let [a, b, c] = mesh.triangle_points(t);
        points.push(add(a, add(scale(sub(b, a), u), scale(sub(c, a), v))));
        faces.push(t as u32);
    }
    (points, faces)
}

#[cfg(test)]
mod tests {
    use super::*;
    use bsv_core::shapes::cuboid;

    #[test]
    fn sampling_is_deterministic_and_on_surface() {
        let c = cuboid([1.0, 1.0, 1.0]);
        let (p, f) = sample_surface(&c, 1000, 7);
        assert_eq!(p, sample_surface(&c, 1000, 7).0);
        assert_eq!(f.len(), 1000);
        for q in p {
            assert!(q.iter().any(|v| (v.abs() - 0.5).abs() < 1e-12));
        }
    }
}
