//! Captures that cannot be a standing person seen from its own side are refused (issue 14, "silent
//! nonsense from the capture"): a flat wall as depth behind the person mask, swapped front/back
//! calibrations, swapped camera folders. A true capture passes.

#![allow(clippy::unwrap_used)]

use bsv_capture::fuse::{build_cloud, DepthImage, DepthView, FuseError, FuseParams};
use bsv_capture::scanner::{scan, Condition, Rig, Scan};
use bsv_core::template::{template, TemplateKind};

/// The MakeHuman body (14 segments) scanned by the paper's rig, noise-free.
fn scanned() -> Scan {
    scan(&template(TemplateKind::Full).unwrap(), &Rig::paper_default(), Condition::NoEr, 0).unwrap()
}

fn views(s: &Scan) -> Vec<DepthView> {
    s.views.iter().map(|v| v.depth_view()).collect()
}

#[test]
fn a_true_capture_passes() {
    let (cloud, _) = build_cloud(&views(&scanned()), &FuseParams::default()).unwrap();
    assert!(cloud.len() > 50_000);
}

#[test]
fn a_flat_wall_behind_the_mask_is_refused() {
    let mut v = views(&scanned());
    // The front camera's depth replaced by a wall 2.5 m away: the mask still says "person".
    v[0].depth = DepthImage::Metres(vec![2.5; v[0].labels.len()]);
    let e = build_cloud(&v, &FuseParams::default()).unwrap_err();
    assert!(matches!(&e, FuseError::FlatView { camera, relief_m } if camera == "front" && *relief_m < 0.01), "{e:?}");
    assert!(e.to_string().contains("flat surface"), "{e}");
    // The check can be switched off for diagnosis.
    let p = FuseParams { check_plausible: false, isolate_person: false, remove_floor: false, ..FuseParams::default() };
    assert!(build_cloud(&v, &p).is_ok());
}

#[test]
fn swapped_calibrations_and_swapped_folders_are_refused() {
    let s = scanned();
    let v = views(&s);
    // Each camera's images with the other camera's calibration.
    let mut swapped = v.clone();
    swapped[0].camera_to_world = v[1].camera_to_world;
    swapped[1].camera_to_world = v[0].camera_to_world;
    let e = build_cloud(&swapped, &FuseParams::default()).unwrap_err();
    assert!(matches!(&e, FuseError::MirroredView { left_x, right_x, .. } if left_x < right_x), "{e:?}");
    assert!(e.to_string().contains("swapped"), "{e}");
    // The folders swapped: the back images named front (with the front calibration) and vice versa.
    let mut folders = v.clone();
    folders[0].depth = v[1].depth.clone();
    folders[0].labels = v[1].labels.clone();
    folders[1].depth = v[0].depth.clone();
    folders[1].labels = v[0].labels.clone();
    let e = build_cloud(&folders, &FuseParams::default()).unwrap_err();
    assert!(matches!(e, FuseError::MirroredView { .. }), "{e:?}");
}
