//! Camera model: intrinsics from FOV, validation, projection/deprojection with distortion,
//! extrinsics algebra, JSON, depth-image deprojection.

#![allow(clippy::unwrap_used)]

use bsv_capture::camera::{deproject_depth, CameraCalibration, CameraError, Extrinsics, Intrinsics};

fn distorted() -> Intrinsics {
    Intrinsics {
        width: 640,
        height: 480,
        fx: 600.0,
        fy: 605.0,
        cx: 321.3,
        cy: 238.7,
        k1: 0.12,
        k2: -0.25,
        p1: 0.0012,
        p2: -0.0009,
        k3: 0.08,
    }
}

#[test]
fn from_fov_matches_the_paper_camera() {
    let i = Intrinsics::from_fov(768, 1024, 55.0, 70.0).unwrap();
    assert!((i.fx - 384.0 / 27.5f64.to_radians().tan()).abs() < 1e-9);
    assert!((i.fy - 512.0 / 35.0f64.to_radians().tan()).abs() < 1e-9);
    // The image edge (-0.5 px) sees exactly half the FOV.
    let p = i.deproject([-0.5, i.cy], 1.0);
    assert!((p[0].atan().to_degrees() + 27.5).abs() < 1e-9);
    let p = i.deproject([i.cx, 1023.5], 1.0);
    assert!((p[1].atan().to_degrees() - 35.0).abs() < 1e-9);
}

#[test]
fn bad_parameters_are_rejected_with_their_name() {
    let mut i = distorted();
    i.fx = -3.0;
    let e = i.validate().unwrap_err();
    assert!(matches!(&e, CameraError::NonPositive { param, .. } if param == "fx"));
    assert!(e.to_string().contains("fx"));
    let mut i = distorted();
    i.k2 = f64::NAN;
    assert!(matches!(i.validate().unwrap_err(), CameraError::NonFinite { param, .. } if param == "k2"));
    let mut i = distorted();
    i.width = 0;
    assert!(i.validate().unwrap_err().to_string().contains("width"));
    assert!(matches!(Intrinsics::from_fov(768, 1024, 0.0, 70.0), Err(CameraError::BadFov { .. })));
    assert!(matches!(Intrinsics::from_fov(768, 1024, 55.0, 180.0), Err(CameraError::BadFov { .. })));
    assert!(matches!(Intrinsics::from_fov(768, 1024, f64::NAN, 70.0), Err(CameraError::NonFinite { .. })));
    assert!(matches!(
        Extrinsics::look_at([0.0, 1.0, 2.0], [0.0, 1.0, 2.0], [0.0, 1.0, 0.0]),
        Err(CameraError::DegenerateLookAt)
    ));
    assert!(matches!(
        Extrinsics::look_at([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]),
        Err(CameraError::DegenerateLookAt)
    ));
    let mut e = Extrinsics::IDENTITY;
    e.rotation[0][0] = 2.0;
    assert!(matches!(e.validate(), Err(CameraError::NotRotation { .. })));
    let mut e = Extrinsics::IDENTITY;
    e.rotation = [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    assert!(matches!(e.validate(), Err(CameraError::NotRotation { .. })), "reflection must be refused");
    let mut e = Extrinsics::IDENTITY;
    e.translation[1] = f64::INFINITY;
    assert!(e.validate().unwrap_err().to_string().contains("translation[1]"));
}

#[test]
fn project_deproject_round_trip_with_distortion() {
    let i = distorted();
    let mut worst: f64 = 0.0;
    for v in (0..480).step_by(17) {
        for u in (0..640).step_by(13) {
            let px = [u as f64 + 0.25, v as f64 - 0.4];
            let depth = 0.5 + 0.003 * u as f64;
            let p = i.deproject(px, depth);
            assert!((p[2] - depth).abs() < 1e-15);
            let back = i.project(p).unwrap();
            worst = worst.max((back[0] - px[0]).abs()).max((back[1] - px[1]).abs());
        }
    }
    assert!(worst < 1e-9, "round trip error {worst} px");
    // Distortion really matters at the corner (so the test is not vacuous).
    let no = Intrinsics { k1: 0.0, k2: 0.0, p1: 0.0, p2: 0.0, k3: 0.0, ..i };
    let a = i.deproject([0.0, 0.0], 1.0);
    let b = no.deproject([0.0, 0.0], 1.0);
    assert!((a[0] - b[0]).abs() > 1e-3);
    assert!(i.project([0.0, 0.0, -1.0]).is_none());
}

#[test]
fn look_at_builds_an_opencv_frame() {
    // Front camera of the rig: at z = +2, 1 m high, looking at the subject (toward -Z).
    let e = Extrinsics::look_at([0.0, 1.0, 2.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]).unwrap();
    e.validate().unwrap();
    let f = e.forward();
    assert!((f[2] + 1.0).abs() < 1e-12);
    // Image right (+X cam) is world +X (the subject's left, seen face to face); image down is world -Y.
    let x = e.transform_vector([1.0, 0.0, 0.0]);
    let y = e.transform_vector([0.0, 1.0, 0.0]);
    assert!((x[0] - 1.0).abs() < 1e-12 && (y[1] + 1.0).abs() < 1e-12);
    // The origin of the world is 2 m ahead of the camera.
    let p = e.inverse().transform_point([0.0, 1.0, 0.0]);
    assert!((p[0]).abs() < 1e-12 && p[1].abs() < 1e-12 && (p[2] - 2.0).abs() < 1e-12);
}

#[test]
fn inverse_compose_and_perturbation() {
    let e = Extrinsics::look_at([0.3, 1.1, -2.0], [0.1, 0.9, 0.2], [0.0, 1.0, 0.0]).unwrap();
    let id = e.compose(&e.inverse());
    for i in 0..3 {
        assert!(id.translation[i].abs() < 1e-12);
        for j in 0..3 {
            assert!((id.rotation[i][j] - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
        }
    }
    // Translating 1 cm along camera z moves the camera 1 cm along its viewing direction.
    let p = e.perturbed([0.0, 0.0, 0.01], [0.0, 0.0, 0.0]);
    let d: Vec<f64> = (0..3).map(|k| p.translation[k] - e.translation[k]).collect();
    let f = e.forward();
    for k in 0..3 {
        assert!((d[k] - 0.01 * f[k]).abs() < 1e-12);
    }
    // A 1 degree turn about camera y turns the viewing direction by 1 degree.
    let r = e.perturbed([0.0; 3], [0.0, 1f64.to_radians(), 0.0]);
    r.validate().unwrap();
    let f2 = r.forward();
    let c = f[0] * f2[0] + f[1] * f2[1] + f[2] * f2[2];
    assert!((c.acos().to_degrees() - 1.0).abs() < 1e-9);
}

#[test]
fn calibration_json_round_trip() {
    let c = CameraCalibration {
        intrinsics: distorted(),
        camera_to_world: Extrinsics::look_at([0.0, 1.0, -2.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]).unwrap(),
    };
    let text = c.to_json();
    assert!(text.contains("\"camera_to_world\"") && text.contains("\"rotation\"") && text.contains("\"k1\""));
    assert_eq!(CameraCalibration::from_json(&text).unwrap(), c);
    // Distortion may be omitted; bad values are refused by name.
    let minimal = r#"{"intrinsics": {"width": 4, "height": 2, "fx": 3, "fy": 3, "cx": 1.5, "cy": 0.5},
        "camera_to_world": {"rotation": [[1,0,0],[0,1,0],[0,0,1]], "translation": [0,0,0]}}"#;
    assert_eq!(CameraCalibration::from_json(minimal).unwrap().intrinsics.k1, 0.0);
    let bad = minimal.replace("\"fy\": 3", "\"fy\": 0");
    assert!(CameraCalibration::from_json(&bad).unwrap_err().to_string().contains("fy"));
    assert!(matches!(CameraCalibration::from_json("{"), Err(CameraError::Json(_))));
}

#[test]
fn depth_image_deprojection_recovers_a_plane() {
    let i = Intrinsics::from_fov(64, 48, 60.0, 45.0).unwrap();
    // A fronto-parallel plane at 1.5 m, in L515 units of 0.25 mm; one hole.
    let mut depth = vec![6000u16; 64 * 48];
    depth[100] = 0;
    let pts = deproject_depth(&depth, &i, 0.00025).unwrap();
    assert_eq!(pts.len(), 64 * 48 - 1);
    assert!(pts.iter().all(|(idx, p)| *idx != 100 && (p[2] - 1.5).abs() < 1e-12));
    let (idx, p) = pts[0];
    assert_eq!(idx, 0);
    let back = i.project(p).unwrap();
    assert!(back[0].abs() < 1e-9 && back[1].abs() < 1e-9);
    let metres: Vec<f32> = vec![2.0; 64 * 48];
    assert_eq!(deproject_depth(&metres, &i, 1.0).unwrap().len(), 64 * 48);
    assert!(matches!(deproject_depth(&depth[..10], &i, 0.00025), Err(CameraError::DepthSize { .. })));
    assert!(deproject_depth(&depth, &i, 0.0).is_err());
}
