//! Cloud building against the virtual scanner's own cloud: rebuilding it from the scan's depth and
//! label images (exact f32 depth and 16-bit quantised PNGs read back from a written capture)
//! reproduces the scanner's points, outlier removal removes injected outliers, normals match a
//! sphere's, extremities are dropped, bad inputs give typed errors.

#![allow(clippy::unwrap_used)]

use bsv_capture::camera::{Extrinsics, Intrinsics};
use bsv_capture::fuse::{build_cloud, ColorMode, DepthImage, DepthView, FuseError, FuseParams};
use bsv_capture::scanner::{scan, write_capture, Condition, Rig, DEPTH_SCALE};
use bsv_core::shapes;

/// Parameters that keep every point (no SOR, no floor removal or isolation, no dropping, no
/// normals, palette colours).
fn keep_all() -> FuseParams {
    FuseParams {
        sor: false,
        remove_floor: false,
        isolate_person: false,
        drop_labels: vec![],
        normals: false,
        ..FuseParams::default()
    }
}

fn max_dist(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt())
        .fold(0.0, f64::max)
}

#[test]
fn rebuilding_from_exact_depth_reproduces_the_scanner_cloud() {
    for condition in [Condition::NoEr, Condition::L5Ca] {
        let s = scan(&shapes::capsule_body(false, true), &Rig::paper_default(), condition, 3).unwrap();
        let views: Vec<DepthView> = s.views.iter().map(|v| v.depth_view()).collect();
        let (cloud, report) = build_cloud(&views, &keep_all()).unwrap();
        assert_eq!(cloud.len(), s.cloud.len(), "{condition:?}");
        assert_eq!(cloud.labels, s.cloud.labels, "labels differ ({condition:?})");
        assert_eq!(cloud.colors, s.cloud.colors, "palette colours differ ({condition:?})");
        let d = max_dist(&cloud.points, &s.cloud.points);
        assert!(d < 2e-6, "{condition:?}: max point distance {d} m (f32 depth only)");
        assert_eq!(report.points, s.cloud.len());
        for (r, v) in report.views.iter().zip(&s.views) {
            assert_eq!(r.kept, v.cloud_range.len());
            assert_eq!(r.sor_removed, 0);
            assert_eq!(r.no_depth, 0, "scanner labels are 0 where the depth is 0");
        }
    }
}

#[test]
fn rebuilding_from_written_16_bit_pngs_reproduces_the_scanner_cloud_to_quantisation() {
    let s = scan(&shapes::capsule_body(false, true), &Rig::paper_default(), Condition::NoEr, 1).unwrap();
    let dir = std::env::temp_dir().join(format!("bsv_fuse_png_{}", std::process::id()));
    write_capture(&s, &dir).unwrap();
    let views: Vec<DepthView> = s
        .views
        .iter()
        .map(|v| {
            let cdir = dir.join(&v.name);
            let depth = image::open(cdir.join("depth.png")).unwrap().into_luma16().into_raw();
            let labels = image::open(cdir.join("labels.png")).unwrap().into_luma8().into_raw();
            let rgb = image::open(cdir.join("color.png")).unwrap().into_rgb8().into_raw();
            let cam: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(cdir.join("camera.json")).unwrap()).unwrap();
            let intrinsics: Intrinsics = serde_json::from_value(cam["intrinsics"].clone()).unwrap();
            let camera_to_world: Extrinsics = serde_json::from_value(cam["camera_to_world"].clone()).unwrap();
            DepthView {
                name: v.name.clone(),
                intrinsics,
                camera_to_world,
                depth: DepthImage::Units { data: depth, scale: cam["depth_scale"].as_f64().unwrap() },
                labels,
                colors: Some(rgb.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()),
            }
        })
        .collect();
    std::fs::remove_dir_all(&dir).ok();
    let params = FuseParams { colors: ColorMode::Image, ..keep_all() };
    let (cloud, _) = build_cloud(&views, &params).unwrap();
    assert_eq!(cloud.len(), s.cloud.len());
    assert_eq!(cloud.labels, s.cloud.labels);
    let d = max_dist(&cloud.points, &s.cloud.points);
    // Half a depth unit along a ray at most ~1.2x longer than its z (corner of a 55 x 70 deg view).
    assert!(d <= 0.5 * DEPTH_SCALE * 1.25, "max point distance {d} m");
    let mean: f64 = cloud
        .points
        .iter()
        .zip(&s.cloud.points)
        .map(|(p, q)| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt())
        .sum::<f64>()
        / cloud.len() as f64;
    assert!(mean < 1e-4, "mean point distance {mean} m");
    // Colours come from the skin-tone render, not the palette.
    let colors = cloud.colors.unwrap();
    assert!(colors.iter().all(|c| c[0] > c[2]), "skin tone expected");
}

#[test]
fn extremities_are_dropped_by_default_and_counted() {
    let s = scan(&shapes::capsule_body(false, true), &Rig::paper_default(), Condition::NoEr, 0).unwrap();
    let views: Vec<DepthView> = s.views.iter().map(|v| v.depth_view()).collect();
    // The capsule body's head and hands float free of it: keep them (no isolation) to count them.
    let params = FuseParams { sor: false, isolate_person: false, ..FuseParams::default() };
    let (cloud, report) = build_cloud(&views, &params).unwrap();
    let labels = cloud.labels.as_ref().unwrap();
    assert!(labels.iter().all(|l| ![1, 7, 8, 13, 14].contains(l)));
    let all = s.cloud.labels.as_ref().unwrap();
    let count = |id: u8| all.iter().filter(|&&l| l == id).count();
    assert!(count(1) > 1000 && count(7) > 50);
    assert_eq!(report.dropped["head"], count(1));
    assert_eq!(report.dropped["hand_l"], count(7));
    assert_eq!(report.dropped["hand_r"], count(8));
    assert_eq!(cloud.len() + count(1) + count(7) + count(8), s.cloud.len());
    assert_eq!(report.points_per_segment["torso"], count(2));
    assert_eq!(cloud.normals.as_ref().unwrap().len(), cloud.len());
}

#[test]
fn outlier_removal_removes_injected_flying_points() {
    let s = scan(&shapes::capsule_body(false, true), &Rig::paper_default(), Condition::NoEr, 0).unwrap();
    let mut views: Vec<DepthView> = s.views.iter().map(|v| v.depth_view()).collect();
    // Mark 300 scattered person pixels of the front camera in red and pull them 0.3 m toward it.
    let v = &mut views[0];
    let DepthImage::Metres(depth) = &mut v.depth else { unreachable!() };
    let person: Vec<usize> = (0..depth.len()).filter(|&i| v.labels[i] != 0).collect();
    let mut colors = vec![[0u8, 0, 0]; depth.len()];
    let step = person.len() / 300;
    for &i in person.iter().step_by(step).take(300) {
        depth[i] -= 0.3;
        colors[i] = [255, 0, 0];
    }
    v.colors = Some(colors);
    views[1].colors = Some(vec![[0, 0, 0]; views[1].labels.len()]);
    // Isolation alone would remove them as separate parts; this tests SOR.
    let params =
        FuseParams { drop_labels: vec![], colors: ColorMode::Image, isolate_person: false, ..FuseParams::default() };
    let (cloud, report) = build_cloud(&views, &params).unwrap();
    let red = cloud.colors.as_ref().unwrap().iter().filter(|c| c[0] == 255).count();
    assert_eq!(red, 0, "{red} injected outliers survived");
    let front = &report.views[0];
    assert_eq!(front.deprojected, person.len());
    assert!(front.sor_removed >= 300);
    assert!(front.kept as f64 > 0.3 * person.len() as f64, "kept only {} of {}", front.kept, person.len());
    assert!(front.sor_threshold_m.unwrap() < 0.05);
    // Without SOR they stay.
    let (cloud, _) = build_cloud(&views, &FuseParams { sor: false, ..params }).unwrap();
    assert_eq!(cloud.colors.unwrap().iter().filter(|c| c[0] == 255).count(), 300);
}

/// A front view of a sphere (radius `r`, centre on the optical axis at distance `d`) computed
/// analytically per pixel, every sphere pixel labelled torso.
fn sphere_view(width: u32, height: u32, r: f64, d: f64) -> DepthView {
    let intr = Intrinsics::from_fov(width, height, 55.0, 55.0).unwrap();
    let (w, h) = (width as usize, height as usize);
    let mut depth = vec![0f32; w * h];
    let mut labels = vec![0u8; w * h];
    for v in 0..h {
        for u in 0..w {
            let [x, y] = intr.pixel_ray([u as f64, v as f64]);
            // |t (x, y, 1) - (0, 0, d)|^2 = r^2
            let a = x * x + y * y + 1.0;
            let disc = d * d - a * (d * d - r * r);
            if disc > 0.0 {
                depth[v * w + u] = ((d - disc.sqrt()) / a) as f32;
                labels[v * w + u] = 2;
            }
        }
    }
    DepthView {
        name: "sphere".into(),
        intrinsics: intr,
        camera_to_world: Extrinsics::IDENTITY,
        depth: DepthImage::Metres(depth),
        labels,
        colors: None,
    }
}

#[test]
fn normals_of_a_sphere_point_outward_toward_the_camera() {
    let view = sphere_view(400, 400, 0.4, 2.0);
    let (cloud, _) = build_cloud(&[view], &FuseParams { sor: false, ..FuseParams::default() }).unwrap();
    let normals = cloud.normals.unwrap();
    let mut dots: Vec<f64> = cloud
        .points
        .iter()
        .zip(&normals)
        .map(|(p, n)| {
            let c = [p[0], p[1], p[2] - 2.0];
            let l = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            (c[0] * n[0] + c[1] * n[1] + c[2] * n[2]) / l
        })
        .collect();
    dots.sort_by(f64::total_cmp);
    assert!(dots[dots.len() / 2] > 0.9999, "median cos {}", dots[dots.len() / 2]);
    assert!(dots[dots.len() / 100] > 0.95, "1st percentile cos {}", dots[dots.len() / 100]);
}

#[test]
fn bad_inputs_give_typed_errors() {
    let s = scan(&shapes::capsule_body(false, true), &Rig::paper_default(), Condition::NoEr, 0).unwrap();
    let good = s.views[0].depth_view();
    let p = FuseParams::default();

    assert!(matches!(build_cloud(&[], &p), Err(FuseError::NoViews)));

    let mut v = good.clone();
    v.labels.pop();
    let e = build_cloud(&[v], &p).unwrap_err();
    assert!(matches!(e, FuseError::ImageSize { image: "labels", .. }), "{e}");
    assert!(e.to_string().contains("front"), "{e}");

    let mut v = good.clone();
    v.depth = DepthImage::Metres(vec![1.0; 10]);
    assert!(matches!(build_cloud(&[v], &p), Err(FuseError::ImageSize { image: "depth", .. })));

    let mut v = good.clone();
    v.colors = Some(vec![[0; 3]; 5]);
    assert!(matches!(build_cloud(&[v], &p), Err(FuseError::ImageSize { image: "colour", .. })));

    for scale in [0.0, -1.0, f64::NAN] {
        let mut v = good.clone();
        v.depth = DepthImage::Units { data: vec![4000; good.labels.len()], scale };
        assert!(matches!(build_cloud(&[v], &p), Err(FuseError::BadDepthScale { .. })), "scale {scale}");
    }

    let mut v = good.clone();
    let i = v.labels.iter().position(|&l| l != 0).unwrap();
    v.labels[i] = 20;
    assert!(matches!(build_cloud(&[v], &p), Err(FuseError::BadLabel { value: 20, .. })));

    let mut v = good.clone();
    v.labels.iter_mut().for_each(|l| *l = 0);
    let e = build_cloud(&[v], &p).unwrap_err();
    assert!(matches!(e, FuseError::EmptyMask { .. }));
    assert!(e.to_string().contains("no person"), "{e}");

    let mut v = good.clone();
    v.depth = DepthImage::Metres(vec![0.0; good.labels.len()]);
    assert!(matches!(build_cloud(&[v], &p), Err(FuseError::NoValidDepth { .. })));
    let too_near = FuseParams { max_depth: Some(0.5), ..FuseParams::default() };
    assert!(matches!(build_cloud(std::slice::from_ref(&good), &too_near), Err(FuseError::NoValidDepth { .. })));

    let mut v = good.clone();
    v.intrinsics.fx = -1.0;
    assert!(matches!(build_cloud(&[v], &p), Err(FuseError::Camera { .. })));
    let mut v = good.clone();
    v.camera_to_world.rotation[0][0] = 2.0;
    assert!(matches!(build_cloud(&[v], &p), Err(FuseError::Camera { .. })));

    let image = FuseParams { colors: ColorMode::Image, ..FuseParams::default() };
    assert!(matches!(build_cloud(std::slice::from_ref(&good), &image), Err(FuseError::MissingColour { .. })));

    let bad_k = FuseParams { sor_k: 0, ..FuseParams::default() };
    assert!(matches!(
        build_cloud(std::slice::from_ref(&good), &bad_k),
        Err(FuseError::BadParam { param: "sor_k", .. })
    ));
    let bad_drop = FuseParams { drop_labels: vec![15], ..FuseParams::default() };
    assert!(matches!(
        build_cloud(std::slice::from_ref(&good), &bad_drop),
        Err(FuseError::BadParam { param: "drop_labels", .. })
    ));

    let mut v = good.clone();
    v.labels.iter_mut().filter(|l| **l != 0).for_each(|l| *l = 1);
    let e = build_cloud(&[v], &FuseParams { sor: false, ..FuseParams::default() }).unwrap_err();
    assert!(matches!(e, FuseError::EmptyCloud { .. }), "{e}");

    assert!(FuseParams::from_json("{\"sor_k\": 10, \"colors\": \"none\"}").unwrap().sor_k == 10);
    assert!(FuseParams::from_json("{\"sork\": 10}").is_err());
    assert_eq!(FuseParams::from_json("").unwrap(), FuseParams::default());
}
