//! Virtual scanner against ground truth: points on the mesh with the right labels, noise spread,
//! calibration-error spread, visibility of a box at 45 deg, determinism, capture files.

#![allow(clippy::unwrap_used)]

use bsv_capture::camera::{CameraCalibration, Intrinsics};
use bsv_capture::scanner::{
    face_labels, parry_mesh, scan, write_capture, Condition, ExtrinsicSigma, Rig, ScanError, DEPTH_SCALE,
};
use bsv_core::{shapes, MeshInvariant, TriMesh};
use parry3d_f64::math::Vector;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::TrianglePointLocation;
use rand::SeedableRng;

fn front_only() -> Rig {
    let mut rig = Rig::paper_default();
    rig.cameras.truncate(1);
    rig
}

#[test]
fn noer_points_lie_on_the_mesh_with_the_right_label() {
    let body = shapes::capsule_body(false, false);
    let labels = face_labels(&body).unwrap();
    let bvh = parry_mesh(&body).unwrap();
    let s = scan(&body, &Rig::paper_default(), Condition::NoEr, 7).unwrap();
    let n = s.cloud.len();
    assert!(n > 50_000, "only {n} points");
    let cl = s.cloud.labels.as_ref().unwrap();
    let mut checked = 0;
    let mut worst: f64 = 0.0;
    for i in (0..n).step_by(5) {
        let p = s.cloud.points[i];
        let (proj, (tri, loc)) = bvh.project_local_point_and_get_location(Vector::new(p[0], p[1], p[2]), false);
        let d = (proj.point - Vector::new(p[0], p[1], p[2])).length();
        worst = worst.max(d);
        if matches!(loc, TrianglePointLocation::OnFace(..)) {
            assert_eq!(cl[i], labels[tri as usize], "point {i} label");
            checked += 1;
        }
    }
    assert!(worst < 1e-6, "max distance to the mesh {worst} m");
    assert!(checked > n / 6);
    // Both cameras contribute, every label of the body is seen, views are consistent with the cloud.
    assert_eq!(s.views.len(), 2);
    for v in &s.views {
        assert!(v.cloud_range.len() > 20_000);
        assert_eq!(v.pixels.len(), v.cloud_range.len());
        assert_eq!(v.estimated_extrinsics, v.true_extrinsics);
        for (k, &px) in v.pixels.iter().enumerate().step_by(97) {
            assert_eq!(v.labels[px as usize], cl[v.cloud_range.start + k]);
            assert!(v.depth[px as usize] > 0.0);
        }
    }
    for l in [1u8, 2, 3, 4, 9, 10] {
        assert!(cl.iter().filter(|&&x| x == l).count() > 500, "label {l} barely seen");
    }
    // The front camera sees the subject's left arm (label 3, +x) on the image right.
    let f = &s.views[0];
    let w = f.intrinsics.width as usize;
    let mean_u = |lab: u8| {
        let us: Vec<usize> = (0..f.labels.len()).filter(|&i| f.labels[i] == lab).map(|i| i % w).collect();
        us.iter().sum::<usize>() as f64 / us.len() as f64
    };
    assert!(mean_u(3) > mean_u(4));
}

/// Depth residuals (measured - true) over the interior of the wall's front face.
fn wall_residuals(depth_to_face: f64) -> (Vec<f64>, f64) {
    let mut wall = TriMesh::default();
    let mut b = shapes::cuboid([1.2, 1.4, 0.1]);
    shapes::translate(&mut b, [0.0, 1.0, 2.0 - depth_to_face - 0.05]);
    shapes::append_labelled(&mut wall, b, 2);
    // Distinct label on the front (+z) face: triangles 2 and 3 of shapes::cuboid.
    wall.face_labels.as_mut().unwrap()[2] = 5;
    wall.face_labels.as_mut().unwrap()[3] = 5;
    let rig = front_only();
    let t = scan(&wall, &rig, Condition::NoEr, 1).unwrap();
    let m = scan(&wall, &rig, Condition::L515, 1).unwrap();
    let (vt, vm) = (&t.views[0], &m.views[0]);
    let (w, h) = (vt.intrinsics.width as usize, vt.intrinsics.height as usize);
    let mut res = Vec::new();
    for v in 3..h - 3 {
        for u in 3..w - 3 {
            let interior = (v - 3..=v + 3).all(|y| (u - 3..=u + 3).all(|x| vt.labels[y * w + x] == 5));
            if interior && vm.depth[v * w + u] > 0.0 {
                res.push(f64::from(vm.depth[v * w + u]) - f64::from(vt.depth[v * w + u]));
            }
        }
    }
    (res, rig.noise.sigma(depth_to_face))
}

#[test]
fn depth_noise_matches_sigma_at_two_depths() {
    for z in [1.5, 3.0] {
        let (res, sigma) = wall_residuals(z);
        assert!(res.len() > 50_000, "{} interior pixels", res.len());
        let n = res.len() as f64;
        let mean = res.iter().sum::<f64>() / n;
        let std = (res.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        // f32 storage quantises ~1e-7 m: negligible against mm.
        assert!((std / sigma - 1.0).abs() < 0.10, "z {z}: std {std} vs sigma {sigma}");
        assert!(mean.abs() < 0.05 * sigma, "z {z}: mean residual {mean}");
    }
}

#[test]
fn flying_pixels_appear_only_at_discontinuities_in_l515() {
    // A small box 1.5 m from the camera in front of a wall 3 m away.
    let mut scene = TriMesh::default();
    let mut wall = shapes::cuboid([3.0, 3.0, 0.1]);
    shapes::translate(&mut wall, [0.0, 1.0, -1.05]);
    shapes::append_labelled(&mut scene, wall, 2);
    let mut b = shapes::cuboid([0.3, 0.3, 0.3]);
    shapes::translate(&mut b, [0.0, 1.0, 0.35]);
    shapes::append_labelled(&mut scene, b, 9);
    let rig = front_only();
    let between = |c: Condition| {
        let s = scan(&scene, &rig, c, 4).unwrap();
        s.views[0].depth.iter().filter(|&&z| z > 1.8 && z < 2.7).count()
    };
    assert_eq!(between(Condition::NoEr), 0);
    let flying = between(Condition::L515);
    // The box outline is ~ 4 x 150 px on the box side plus the wall side: hundreds of flyers, far
    // fewer than the image.
    assert!(flying > 100 && flying < 5000, "{flying} flying pixels");
}

#[test]
fn calibration_errors_have_the_requested_spread() {
    let rig = Rig::paper_default();
    // The paper's back-camera yaw (0.28 deg about the vertical) is about camera Y in our portrait image frame.
    let back = rig.cameras[1].calibration_sigma;
    assert!((back.rotation_rad[1] - 0.28f64.to_radians()).abs() < 1e-15);
    assert!((back.translation_m[2] - 0.0034).abs() < 1e-15);
    let front = rig.cameras[0].calibration_sigma;
    assert!((front.translation_m[0] - 0.0003).abs() < 1e-15 && (front.translation_m[1] - 0.0011).abs() < 1e-15);
    for sigma in [front, back] {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let n = 20_000;
        let draws: Vec<_> = (0..n).map(|_| sigma.draw(&mut rng)).collect();
        for a in 0..3 {
            for (vals, want) in [
                (draws.iter().map(|d| d.translation_m[a]).collect::<Vec<_>>(), sigma.translation_m[a]),
                (draws.iter().map(|d| d.rotation_rad[a]).collect::<Vec<_>>(), sigma.rotation_rad[a]),
            ] {
                let mean = vals.iter().sum::<f64>() / n as f64;
                let std = (vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
                assert!((std / want - 1.0).abs() < 0.05, "axis {a}: std {std} vs {want}");
                assert!(mean.abs() < 0.05 * want);
            }
        }
    }
}

#[test]
fn scans_draw_errors_with_the_requested_spread_and_apply_them_to_the_cloud() {
    // Tiny cameras make hundreds of scans cheap: the spread of the errors `scan` really applies.
    let mut rig = Rig::paper_default();
    for c in &mut rig.cameras {
        c.intrinsics = Intrinsics::from_fov(6, 8, 55.0, 70.0).unwrap();
    }
    let mut box_ = shapes::cuboid([0.5, 1.6, 0.4]);
    shapes::translate(&mut box_, [0.0, 0.8, 0.0]);
    let n = 400;
    let mut sq = [0.0f64; 2];
    for seed in 0..n {
        let s = scan(&box_, &rig, Condition::Cali, seed).unwrap();
        for (c, v) in s.views.iter().enumerate() {
            sq[c] += v.error.rotation_rad[1].powi(2);
        }
    }
    for (c, cam) in rig.cameras.iter().enumerate() {
        let std = (sq[c] / n as f64).sqrt();
        let want = cam.calibration_sigma.rotation_rad[1];
        assert!((std / want - 1.0).abs() < 0.15, "camera {c}: yaw std {std} vs {want}");
    }
    // With full-size cameras: the Cali cloud is the NoEr cloud moved by est ∘ true^-1 per camera.
    let rig = Rig::paper_default();
    let exact = scan(&box_, &rig, Condition::NoEr, 5).unwrap();
    let cali = scan(&box_, &rig, Condition::Cali, 5).unwrap();
    assert_eq!(exact.cloud.len(), cali.cloud.len());
    for (ve, vc) in exact.views.iter().zip(&cali.views) {
        assert_eq!(ve.pixels, vc.pixels);
        assert_ne!(vc.error.translation_m, [0.0; 3]);
        let m = vc.estimated_extrinsics.compose(&vc.true_extrinsics.inverse());
        let mut moved: f64 = 0.0;
        for k in ve.cloud_range.clone().step_by(31) {
            let want = m.transform_point(exact.cloud.points[k]);
            let got = cali.cloud.points[k];
            let d = (0..3).map(|a| (want[a] - got[a]).powi(2)).sum::<f64>().sqrt();
            assert!(d < 1e-9);
            moved = moved.max((0..3).map(|a| (got[a] - exact.cloud.points[k][a]).powi(2)).sum::<f64>().sqrt());
        }
        assert!(moved > 1e-5 && moved < 0.05, "moved {moved}");
    }
    // Same seed, same draws: l5ca shares the cali error of its seed.
    let l5ca = scan(&box_, &rig, Condition::L5Ca, 5).unwrap();
    assert_eq!(l5ca.views[1].error, cali.views[1].error);
}

#[test]
fn box_at_45_degrees_shows_two_side_faces_and_the_top_to_each_camera() {
    let mut b = shapes::cuboid([0.558, 0.520, 0.589]);
    // Labels by the face's normal before rotation: z- 1, z+ 2, y- 3, y+ 4, x- 5, x+ 6.
    b.face_labels = Some(vec![1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6]);
    shapes::translate(&mut b, [0.0, 0.26, 0.0]);
    shapes::rotate_y(&mut b, std::f64::consts::FRAC_PI_4);
    let normals = bsv_core::geometry::face_normals(&b);
    let s = scan(&b, &Rig::paper_default(), Condition::NoEr, 0).unwrap();
    // After +45 deg about y: z+ (2) and x- (5) face +Z (front camera), x+ (6) and z- (1) face -Z.
    let expected = [[2u8, 4, 5], [1, 4, 6]];
    for (v, want) in s.views.iter().zip(expected) {
        let cam = v.true_extrinsics.translation;
        let mut counts = [0usize; 7];
        for &l in &v.labels {
            counts[l as usize] += 1;
        }
        for l in 1..7u8 {
            if want.contains(&l) {
                assert!(counts[l as usize] > 2000, "{}: face {l} seen by {} px", v.name, counts[l as usize]);
            } else {
                assert_eq!(counts[l as usize], 0, "{}: face {l} must be hidden", v.name);
            }
        }
        // Every hit face faces the camera.
        for (k, &px) in v.pixels.iter().enumerate().step_by(13) {
            let p = s.cloud.points[v.cloud_range.start + k];
            let l = v.labels[px as usize];
            let t = (0..12).find(|&t| b.face_labels.as_ref().unwrap()[t] == l).unwrap();
            let to_cam = [cam[0] - p[0], cam[1] - p[1], cam[2] - p[2]];
            let n = normals[t];
            assert!(n[0] * to_cam[0] + n[1] * to_cam[1] + n[2] * to_cam[2] > 0.0);
        }
    }
}

#[test]
fn scans_are_deterministic_for_a_seed() {
    let mut b = shapes::ellipsoid([0.2, 0.8, 0.15], 3);
    shapes::translate(&mut b, [0.0, 0.9, 0.0]);
    let a = scan(&b, &Rig::paper_default(), Condition::L5Ca, 3).unwrap();
    let c = scan(&b, &Rig::paper_default(), Condition::L5Ca, 3).unwrap();
    assert_eq!(a, c);
    let d = scan(&b, &Rig::paper_default(), Condition::L5Ca, 4).unwrap();
    assert_ne!(a.cloud.points, d.cloud.points);
}

#[test]
fn bad_inputs_are_rejected_clearly() {
    let b = shapes::cuboid([0.5, 0.5, 0.5]);
    let mut rig = Rig::paper_default();
    rig.cameras[1].intrinsics.fy = 0.0;
    let e = scan(&b, &rig, Condition::NoEr, 0).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, ScanError::Camera { .. }) && msg.contains("back") && msg.contains("fy"), "{msg}");
    let mut rig = Rig::paper_default();
    rig.cameras[0].camera_to_world.rotation[2][2] = 0.5;
    assert!(scan(&b, &rig, Condition::NoEr, 0).unwrap_err().to_string().contains("rotation"));
    let mut rig = Rig::paper_default();
    rig.noise.flying_probability = 2.0;
    assert!(matches!(scan(&b, &rig, Condition::L515, 0), Err(ScanError::BadNoise { .. })));
    rig.cameras.clear();
    assert!(matches!(scan(&b, &rig, Condition::NoEr, 0), Err(ScanError::NoCameras)));
    let rig = Rig::paper_default();
    assert!(matches!(scan(&TriMesh::default(), &rig, Condition::NoEr, 0), Err(ScanError::EmptyMesh)));
    let mut bad = b.clone();
    bad.triangles[3][1] = 99;
    assert!(matches!(
        scan(&bad, &rig, Condition::NoEr, 0),
        Err(ScanError::Mesh(MeshInvariant::IndexOutOfRange { face: 3, index: 99, .. }))
    ));
    let mut bad = b.clone();
    bad.face_labels = Some(vec![1; 5]);
    assert!(scan(&bad, &rig, Condition::NoEr, 0).unwrap_err().to_string().contains("face_labels"));
    let mut bad = b.clone();
    bad.vertices[0][1] = f64::NAN;
    assert!(matches!(scan(&bad, &rig, Condition::NoEr, 0), Err(ScanError::NonFiniteVertex(0))));
    assert_eq!("L5CA".parse::<Condition>().unwrap(), Condition::L5Ca);
    for c in Condition::ALL {
        assert_eq!(c.name().parse::<Condition>().unwrap(), c);
    }
    assert!("l516".parse::<Condition>().unwrap_err().to_string().contains("noer, l515, cali, l5ca"));
    let s = ExtrinsicSigma::from_paper([1.0, 2.0, 3.0], [0.0, 0.0, 0.0]);
    assert_eq!(s.translation_m, [0.02, 0.01, 0.03]);
}

#[test]
fn vertex_labels_give_face_labels_by_majority() {
    let mut m = shapes::cuboid([1.0, 1.0, 1.0]);
    m.vertex_labels = Some(vec![2, 2, 2, 2, 3, 3, 3, 3]);
    let fl = face_labels(&m).unwrap();
    // z- face (vertices 0..3 have z-) is all label 2, z+ all 3.
    assert_eq!(&fl[..4], &[2, 2, 3, 3]);
    assert_eq!(face_labels(&shapes::cuboid([1.0; 3])).unwrap(), vec![0; 12]);
}

#[test]
fn capture_files_round_trip() {
    let mut b = shapes::capsule(0.2, 1.0, 24, 6, 6);
    shapes::translate(&mut b, [0.0, 0.3, 0.0]);
    b.face_labels = Some(vec![2; b.triangles.len()]);
    let s = scan(&b, &Rig::paper_default(), Condition::L5Ca, 9).unwrap();
    let dir = std::env::temp_dir().join(format!("bsv_capture_test_{}", std::process::id()));
    write_capture(&s, &dir).unwrap();
    for v in &s.views {
        let cdir = dir.join(&v.name);
        let depth = image::open(cdir.join("depth.png")).unwrap().into_luma16();
        assert_eq!(depth.dimensions(), (768, 1024));
        for (i, px) in depth.pixels().enumerate().step_by(101) {
            let z = f64::from(v.depth[i]);
            assert!((f64::from(px.0[0]) * DEPTH_SCALE - z).abs() <= 0.5 * DEPTH_SCALE + 1e-6);
        }
        let color = image::open(cdir.join("color.png")).unwrap().into_rgb8();
        let labels = image::open(cdir.join("labels.png")).unwrap().into_luma8();
        let hits = v.depth.iter().filter(|&&z| z > 0.0).count();
        let skin = color.pixels().filter(|p| p.0 != [128, 128, 128]).count();
        assert_eq!(hits, skin);
        assert_eq!(labels.pixels().filter(|p| p.0[0] == 2).count(), hits);
        let text = std::fs::read_to_string(cdir.join("camera.json")).unwrap();
        let cal = CameraCalibration::from_json(&text).unwrap();
        // serde_json parses floats to within 1 ulp.
        let (a, b) = (cal.camera_to_world, v.estimated_extrinsics);
        for i in 0..3 {
            assert!((a.translation[i] - b.translation[i]).abs() < 1e-12);
            for j in 0..3 {
                assert!((a.rotation[i][j] - b.rotation[i][j]).abs() < 1e-12);
            }
        }
        assert!(text.contains("depth_scale") && text.contains("true_camera_to_world"));
    }
    let cal = std::fs::read_to_string(dir.join("calibration.json")).unwrap();
    let j: serde_json::Value = serde_json::from_str(&cal).unwrap();
    assert!(j["cameras"]["front"]["intrinsics"]["fx"].is_number());
    std::fs::remove_dir_all(&dir).unwrap();
    // An unwritable target is a clear error.
    let file = std::env::temp_dir().join(format!("bsv_capture_file_{}", std::process::id()));
    std::fs::write(&file, b"x").unwrap();
    let e = write_capture(&s, &file).unwrap_err();
    assert!(matches!(e, ScanError::Io { .. }), "{e}");
    std::fs::remove_file(&file).unwrap();
}
