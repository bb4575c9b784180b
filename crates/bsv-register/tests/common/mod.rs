//! Shared helpers of the registration tests: clouds from analytic shapes, distances, volumes.
#![allow(dead_code)]

use bsv_capture::sample::sample_surface;
use bsv_core::geometry::{cross, face_normals, normalize, signed_volume, sub};
use bsv_core::{PointCloud, TriMesh};
use bsv_register::{register, ControlFlow, IterationLog, RegisterParams, Registration};

/// A cloud of `n` uniform samples of `mesh`, with the face normals of the samples.
pub fn cloud_of(mesh: &TriMesh, n: usize, seed: u64) -> PointCloud {
    let (points, faces) = sample_surface(mesh, n, seed);
    let fnorm = face_normals(mesh);
    let mut c = PointCloud::new(points);
    c.normals = Some(faces.iter().map(|&f| fnorm[f as usize]).collect());
    c
}

/// Drops the points that neither a front nor a back camera sees: |normal.x| > `limit`.
pub fn drop_sides(cloud: &mut PointCloud, limit: f64) {
    let normals = cloud.normals.clone().expect("normals");
    cloud.retain_indices(|i| normals[i][0].abs() <= limit);
}

/// Volume of a closed mesh, m^3.
pub fn volume(mesh: &TriMesh) -> f64 {
    signed_volume(&mesh.vertices, &mesh.triangles)
}

/// Relative error in percent.
pub fn rel_pct(est: f64, truth: f64) -> f64 {
    (est - truth) / truth * 100.0
}

/// Runs a registration and collects the log.
pub fn run(template: &TriMesh, cloud: &PointCloud, params: &RegisterParams) -> Registration {
    let mut sink = |_: &IterationLog| ControlFlow::Continue(());
    register(template, cloud, params, &mut sink).expect("registration")
}

/// First-order distance of `p` to the ellipsoid with semi-axes `r` centred at the origin.
pub fn ellipsoid_distance(p: [f64; 3], r: [f64; 3]) -> f64 {
    let f: f64 = (0..3).map(|k| p[k] * p[k] / (r[k] * r[k])).sum::<f64>() - 1.0;
    let g: f64 = (0..3).map(|k| (2.0 * p[k] / (r[k] * r[k])).powi(2)).sum::<f64>().sqrt();
    (f / g).abs()
}

/// Bends a vertical (y) capsule of cylinder length `length` in the x-y plane: the axis segment
/// x = z = 0, 0 <= y <= length becomes an arc of radius `radius` about (radius, 0, 0) (arc length
/// preserved; a point at height y and offset x goes to angle y / radius at distance radius - x from
/// the centre); the caps below 0 and above `length` move rigidly with the ends, so the bent capsule
/// is exactly the set of points at distance r from the arc.
pub fn bend(p: [f64; 3], radius: f64, length: f64) -> [f64; 3] {
    let y = p[1].clamp(0.0, length);
    let theta = y / radius;
    let (s, c) = theta.sin_cos();
    let axis = [radius - radius * c, radius * s];
    let along = p[1] - y;
    [axis[0] + p[0] * c + along * s, axis[1] - p[0] * s + along * c, p[2]]
}

/// Distance from `p` to the surface of the capsule of radius `r` around the bent axis
/// (the arc of `bend` from y = 0 to y = `length`).
pub fn bent_capsule_distance(p: [f64; 3], r: f64, length: f64, radius: f64) -> f64 {
    let (dx, dy) = (p[0] - radius, p[1]);
    let ang = dy.atan2(-dx);
    let axis_dist = if ang >= 0.0 && ang <= length / radius {
        let rho = (dx * dx + dy * dy).sqrt();
        ((rho - radius).powi(2) + p[2] * p[2]).sqrt()
    } else {
        let a = bend([0.0, 0.0, 0.0], radius, length);
        let b = bend([0.0, length, 0.0], radius, length);
        let da = sub(p, a);
        let db = sub(p, b);
        let na = (da[0] * da[0] + da[1] * da[1] + da[2] * da[2]).sqrt();
        let nb = (db[0] * db[0] + db[1] * db[1] + db[2] * db[2]).sqrt();
        na.min(nb)
    };
    (axis_dist - r).abs()
}

/// Unused-import guard for helpers only some tests use.
pub fn _unit(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    normalize(cross(a, b))
}
