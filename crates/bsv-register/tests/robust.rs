//! Room outliers in a labelled cloud: a dense floor patch labelled like the lower segment and a
//! wall sliver behind the upper one (3 % of the points together), as a person mask spills them in
//! a real room. With the default detached-piece removal (`detached_voxel_m`) the fit ignores them;
//! with it off (the behaviour before it) they inflate the volume through the pre-alignment box,
//! the limb axes and the correspondences.

mod common;
use bsv_core::shapes::{capsule, translate};
use bsv_core::{PointCloud, TriMesh};
use bsv_register::{OutlierParams, RegisterParams};
use common::*;

/// Upper ("thigh", 9) and lower ("shin", 11) halves of a vertical capsule split at `y_mid`.
fn label_by_height(points: &[[f64; 3]], y_mid: f64) -> Vec<u8> {
    points.iter().map(|p| if p[1] > y_mid { 9 } else { 11 }).collect()
}

/// A vertical capsule of radius `r` with its bottom at y = 0.08 and the cylinder `length` long.
fn leg(r: f64, length: f64, fine: bool) -> TriMesh {
    let mut m = if fine { capsule(r, length, 48, 10, 60) } else { capsule(r, length, 20, 5, 24) };
    translate(&mut m, [0.0, 0.08 + r, 0.0]);
    m
}

/// The clean, labelled, gappy cloud of the truth (no normals: a depth camera gives none).
fn clean_cloud(truth: &TriMesh, y_mid: f64) -> PointCloud {
    let mut cloud = cloud_of(truth, 60_000, 5);
    drop_sides(&mut cloud, 0.85);
    cloud.normals = None;
    cloud.labels = Some(label_by_height(&cloud.points, y_mid));
    cloud
}

/// `cloud` plus 1.5 % floor points (a dense 4 cm disc at y ~ 0, 12-20 cm beside the bottom,
/// labelled 11) and 1.5 % wall points (a 2 cm band 0.5 m behind, over the upper half, labelled 9).
fn with_room_outliers(cloud: &PointCloud, y_mid: f64, top: f64) -> PointCloud {
    let n = cloud.len() * 15 / 1000;
    let mut out = cloud.clone();
    let labels = out.labels.get_or_insert_with(Vec::new);
    for k in 0..n {
        // Deterministic low-discrepancy spread (golden-angle spiral in the disc, rows on the wall).
        let t = (k as f64 + 0.5) / n as f64;
        let a = k as f64 * 2.399_963;
        let r = 0.04 * t.sqrt();
        out.points.push([0.16 + r * a.cos(), 0.001 * (a.sin()), r * a.sin()]);
        labels.push(11);
        let x = 0.07 + 0.02 * ((k * 7919) % n) as f64 / n as f64;
        out.points.push([x, y_mid + (top - y_mid) * t, -0.5]);
        labels.push(9);
    }
    out
}

/// `cloud` plus 0.5 % mixed pixels scattered 0.35-0.6 m behind the upper half, toward a wall
/// (labelled 9): sparse, so the sparse-point filter drops them from the fit, but by the box's
/// definition (the cloud before that filter) they would stretch it. Mixed pixels closer than
/// `bbox_max_outlier_distance_m` (0.3 m) still count in the box: a known limit.
fn with_mixed_pixels(cloud: &PointCloud, y_mid: f64, top: f64) -> PointCloud {
    let n = cloud.len() * 5 / 1000;
    let mut out = cloud.clone();
    let labels = out.labels.get_or_insert_with(Vec::new);
    for k in 0..n {
        let t = (k as f64 + 0.5) / n as f64;
        let u = ((k * 7919) % n) as f64 / n as f64;
        out.points.push([
            0.07 * (2.0 * u - 1.0),
            y_mid + (top - y_mid) * t,
            -0.42 - 0.25 * ((k * 104_729) % n) as f64 / n as f64,
        ]);
        labels.push(9);
    }
    out
}

/// Whole and per-label (9, 11) volumes of a fitted mesh, m^3.
fn volumes(reg: &bsv_register::Registration) -> [f64; 3] {
    let v = bsv_volume::segment_volumes(&reg.mesh).expect("segment volumes");
    let seg = |id: u8| v.segments.iter().find(|(s, _)| s.id() == id).map_or(0.0, |(_, &m3)| m3);
    [v.whole_m3, seg(9), seg(11)]
}

#[test]
fn three_percent_room_outliers_do_not_inflate_the_segments() {
    let (r, length) = (0.07, 0.75);
    let truth = leg(r, length, true);
    let y_mid = 0.08 + r + length / 2.0;
    let top = 0.08 + 2.0 * r + length;
    let mut template = leg(0.06, 0.7, false);
    template.vertex_labels = Some(label_by_height(&template.vertices, 0.08 + 0.06 + 0.35));
    let clean = clean_cloud(&truth, y_mid);
    let dirty = with_room_outliers(&clean, y_mid, top);
    assert!((dirty.len() - clean.len()) as f64 / clean.len() as f64 > 0.029);

    let mut old = RegisterParams {
        outliers: OutlierParams { detached_voxel_m: 0.0, ..Default::default() },
        ..Default::default()
    };
    old.prealignment.bbox_max_outlier_distance_m = f64::INFINITY;
    let before = volumes(&run(&template, &dirty, &old));
    let truth_v = volume(&truth);
    // The default (ray-parallel removal off) and with it on, as it was before round 2 session 7.
    let mut default_base = None;
    for max_cos in [0.0, 0.2] {
        let params = RegisterParams {
            outliers: OutlierParams { ray_parallel_max_cos: max_cos, ..Default::default() },
            ..Default::default()
        };
        let base = volumes(&run(&template, &clean, &params));
        let robust_reg = run(&template, &dirty, &params);
        let robust = volumes(&robust_reg);
        println!(
            "ray_parallel_max_cos {max_cos}: truth {:.3} L; clean fit {:.3} L; with outliers: {:.3} L (detached {}), old {:.3} L",
            truth_v * 1e3,
            base[0] * 1e3,
            robust[0] * 1e3,
            robust_reg.detached_removed,
            before[0] * 1e3
        );
        for (k, name) in ["whole", "upper (9)", "lower (11)"].iter().enumerate() {
            let (now, was) = (rel_pct(robust[k], base[k]), rel_pct(before[k], base[k]));
            println!("{name}: {now:+.2} % of the clean fit with the removal, {was:+.2} % without");
            assert!(now.abs() < 1.0, "{name}: {now:+.2} % of the clean fit (ray_parallel_max_cos {max_cos})");
        }
        // The outliers go before the fit: the floor patches (12-20 cm beside the bottom) as detached
        // pieces of their segment (with the ray-parallel removal on, most of them as ray-parallel
        // points first).
        let removed = robust_reg.detached_removed + robust_reg.outliers_removed;
        assert!(removed as f64 >= 0.9 * (dirty.len() - clean.len()) as f64, "ray_parallel_max_cos {max_cos}");
        default_base.get_or_insert(base);
    }
    let base = default_base.expect("the loop ran");
    // The behaviour before: the outliers inflate the fit.
    assert!(rel_pct(before[0], base[0]) > 10.0, "the old fit was not inflated: {before:?} vs {base:?}");
}

#[test]
fn far_mixed_pixels_do_not_stretch_the_box() {
    let (r, length) = (0.07, 0.75);
    let truth = leg(r, length, true);
    let y_mid = 0.08 + r + length / 2.0;
    let top = 0.08 + 2.0 * r + length;
    let mut template = leg(0.06, 0.7, false);
    template.vertex_labels = Some(label_by_height(&template.vertices, 0.08 + 0.06 + 0.35));
    let clean = clean_cloud(&truth, y_mid);
    let dirty = with_mixed_pixels(&clean, y_mid, top);
    let params = RegisterParams::default();
    let base = volumes(&run(&template, &clean, &params));
    let now = volumes(&run(&template, &dirty, &params));
    let mut old = RegisterParams::default();
    old.prealignment.bbox_max_outlier_distance_m = f64::INFINITY;
    let before = volumes(&run(&template, &dirty, &old));
    let (e_now, e_before) = (rel_pct(now[0], base[0]), rel_pct(before[0], base[0]));
    println!("mixed pixels: whole volume {e_now:+.2} % of the clean fit, {e_before:+.2} % with every sparse point in the box");
    assert!(e_now.abs() < 1.0, "{e_now:+.2} %");
    assert!(e_before.abs() > 5.0, "the box was not stretched: {e_before:+.2} %");
}
