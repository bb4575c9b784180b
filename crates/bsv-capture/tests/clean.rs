//! Point-cloud cleaning: the fast exact k-NN mean distances against plain k-NN, statistical outlier
//! removal on a surface with injected outliers, voxel down-sampling, errors.

#![allow(clippy::unwrap_used)]

use bsv_capture::clean::{
    mean_knn_distances, mean_knn_distances_naive, remove_statistical_outliers, statistical_outliers, voxel_downsample,
    CleanError, SorParams,
};
use bsv_capture::sample::sample_surface;
use bsv_core::{shapes, PointCloud};
use rand::{Rng, SeedableRng};

/// Brute-force mean distance to the k nearest points (itself included).
fn brute(points: &[[f64; 3]], i: usize, k: usize) -> f64 {
    let mut d: Vec<f64> =
        points.iter().map(|q| ((0..3).map(|a| (q[a] - points[i][a]).powi(2)).sum::<f64>()).sqrt()).collect();
    d.sort_by(f64::total_cmp);
    d[..k].iter().sum::<f64>() / k as f64
}

#[test]
fn fast_mean_distances_are_exact() {
    let mut body = shapes::ellipsoid([0.2, 0.8, 0.15], 4);
    shapes::translate(&mut body, [0.0, 0.9, 0.0]);
    let (mut pts, _) = sample_surface(&body, 20_000, 3);
    // Duplicates, a far cluster and isolated points exercise the bounds and the fallbacks.
    let dup = pts[..50].to_vec();
    pts.extend_from_slice(&dup);
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    for _ in 0..300 {
        pts.push([rng.random_range(3.0..3.1), rng.random_range(0.0..0.1), rng.random_range(0.0..0.1)]);
    }
    for _ in 0..20 {
        pts.push([rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)]);
    }
    for k in [1, 7, 600] {
        let fast = mean_knn_distances(&pts, k).unwrap();
        let naive = mean_knn_distances_naive(&pts, k).unwrap();
        let worst = fast.iter().zip(&naive).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-12, "k {k}: max difference {worst}");
        for i in [0, 1234, pts.len() - 1, pts.len() - 25] {
            assert!((fast[i] - brute(&pts, i, k)).abs() < 1e-12, "k {k} point {i}");
        }
    }
    // k larger than the cloud is clamped to the cloud size.
    let small = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
    let m = mean_knn_distances(&small, 10).unwrap();
    assert!((m[0] - 4.0 / 3.0).abs() < 1e-15 && (m[1] - 1.0).abs() < 1e-15);
}

#[test]
fn sor_removes_injected_outliers_and_keeps_the_surface() {
    // A 1 m x 1 m wall sampled at 5 mm plus 200 outliers 5-30 cm in front of it.
    let mut pts = Vec::new();
    for i in 0..200 {
        for j in 0..200 {
            pts.push([i as f64 * 0.005, j as f64 * 0.005, 0.0]);
        }
    }
    let n_surface = pts.len();
    let mut rng = rand::rngs::StdRng::seed_from_u64(9);
    for _ in 0..200 {
        pts.push([rng.random_range(0.0..1.0), rng.random_range(0.0..1.0), rng.random_range(0.05..0.3)]);
    }
    let mut cloud = PointCloud::new(pts);
    cloud.labels = Some((0..cloud.len()).map(|i| u8::from(i >= n_surface) + 2).collect());
    let res = remove_statistical_outliers(&mut cloud, SorParams { k: 30, std_ratio: 1.0 }).unwrap();
    assert!(res.keep[n_surface..].iter().all(|k| !k), "an outlier survived");
    let kept_surface = res.keep[..n_surface].iter().filter(|&&k| k).count();
    assert_eq!(kept_surface, n_surface, "surface points lost");
    assert_eq!(cloud.len(), kept_surface);
    assert!(cloud.labels.as_ref().unwrap().iter().all(|&l| l == 2));
    // The paper's parameters (600, 0.05) are much harsher: they also drop the wall's rim.
    let harsh = statistical_outliers(&cloud.points, SorParams::default()).unwrap();
    assert_eq!(harsh.k, 600);
    let kept = harsh.keep.iter().filter(|&&k| k).count();
    assert!(kept < cloud.len() && kept > cloud.len() / 3, "{kept}");
    // The centre of the wall is kept, a corner is not.
    assert!(harsh.keep[100 * 200 + 100] && !harsh.keep[0]);
}

#[test]
fn bad_parameters_are_errors() {
    let pts = [[0.0, 0.0, 0.0], [1.0, f64::NAN, 0.0]];
    assert!(matches!(mean_knn_distances(&pts, 3), Err(CleanError::NonFinitePoint { index: 1, .. })));
    assert!(matches!(mean_knn_distances(&pts[..1], 0), Err(CleanError::ZeroK)));
    let e = statistical_outliers(&pts[..1], SorParams { k: 5, std_ratio: f64::INFINITY }).unwrap_err();
    assert!(e.to_string().contains("std_ratio"));
    assert!(statistical_outliers(&[], SorParams::default()).unwrap().keep.is_empty());
    let c = PointCloud::new(vec![[0.0; 3]]);
    assert!(matches!(voxel_downsample(&c, 0.0), Err(CleanError::BadVoxel(_))));
}

#[test]
fn voxel_downsample_keeps_one_point_per_voxel() {
    let mut pts = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            pts.push([0.001 + i as f64 * 0.0025, 0.001 + j as f64 * 0.0025, 0.0]);
        }
    }
    let c = PointCloud::new(pts);
    let d = voxel_downsample(&c, 0.01).unwrap();
    // 0.1 m x 0.1 m at 1 cm voxels: 10 x 10 occupied voxels.
    assert_eq!(d.len(), 100);
    let again = voxel_downsample(&c, 0.01).unwrap();
    assert_eq!(d, again);
}
