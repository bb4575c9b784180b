//! End-to-end runs of the `bsv-cli` binary: template -> scan -> register -> volume, and bad input.

#![allow(clippy::unwrap_used)]

mod common;

use common::{bsv, text, tmpdir};

#[test]
fn template_scan_register_volume_chain() {
    let tmp = tmpdir("chain");
    let d = tmp.path();
    let o = bsv(&["template", "-o", "t.ply"], d);
    assert!(o.status.success(), "{}", text(&o));
    let o = bsv(&["scan", "t.ply", "--condition", "noer", "-o", "c.ply"], d);
    assert!(o.status.success(), "{}", text(&o));
    let o = bsv(&["register", "c.ply", "-o", "fit.ply", "--json", "v.json", "--quiet"], d);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("v.json")).unwrap()).unwrap();
    let fit = v["volumes_l"]["trunk_limbs"].as_f64().unwrap();
    let o = bsv(&["volume", "t.ply", "--json", "t.json"], d);
    assert!(o.status.success(), "{}", text(&o));
    let t: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("t.json")).unwrap()).unwrap();
    let truth = t["volumes_l"]["trunk_limbs"].as_f64().unwrap();
    // The template registered to its own noise-free scan keeps its volume.
    assert!((fit - truth).abs() / truth < 0.02, "fit {fit} L, template {truth} L");
    assert!(v["registration"]["iterations"].as_u64().unwrap() > 0);
    assert_eq!(v["units"]["volume"], "L");
    // Outputs are never overwritten without --force.
    let o = bsv(&["template", "-o", "t.ply"], d);
    assert!(!o.status.success());
    assert!(text(&o).contains("--force"), "{}", text(&o));
    let o = bsv(&["info", "fit.ply", "--json"], d);
    assert!(o.status.success(), "{}", text(&o));
}

#[test]
fn bad_inputs_fail_with_clear_messages() {
    let tmp = tmpdir("bad");
    let d = tmp.path();
    std::fs::write(d.join("empty.ply"), b"").unwrap();
    let o = bsv(&["volume", "empty.ply"], d);
    assert!(!o.status.success());
    assert!(text(&o).contains("empty.ply"), "{}", text(&o));
    // A cloud in millimetres.
    let mut ply = String::from(
        "ply\nformat ascii 1.0\nelement vertex 400\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
    );
    for i in 0..400 {
        ply.push_str(&format!("{} {} {}\n", (i % 20) as f64 * 30.0, (i / 20) as f64 * 90.0, (i % 7) as f64 * 10.0));
    }
    std::fs::write(d.join("mm.ply"), ply).unwrap();
    let o = bsv(&["register", "mm.ply"], d);
    assert!(!o.status.success());
    assert!(text(&o).contains("millimetres"), "{}", text(&o));
    let o = bsv(&["register", "mm.ply", "--schedule", "m2p:x"], d);
    assert!(!o.status.success());
    assert!(text(&o).to_lowercase().contains("schedule"), "{}", text(&o));
    let o = bsv(&["register", "mm.ply", "--stop-motion-mm=-1"], d);
    assert!(!o.status.success());
    assert!(text(&o).contains("--stop-motion-mm"), "{}", text(&o));
    let o = bsv(&["scan", "mm.ply", "--condition", "foggy"], d);
    assert!(!o.status.success());
    assert!(text(&o).contains("foggy"), "{}", text(&o));
}

#[test]
fn info_reports_unreadable_faces() {
    let tmp = tmpdir("info");
    let d = tmp.path();
    // A tetrahedron whose last face refers to a vertex that does not exist.
    std::fs::write(d.join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 9\n")
        .unwrap();
    let o = bsv(&["info", "bad.obj"], d);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("4 vertices/points"), "{}", text(&o));
    assert!(text(&o).contains("unreadable"), "{}", text(&o));
    let o = bsv(&["info", "bad.obj", "--json"], d);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j["mesh_error"].as_str().unwrap().contains("bad.obj"), "{j}");
    assert!(j.get("mesh").is_none(), "{j}");
    let o = bsv(&["info", "bad.obj", "--repair", "r.obj"], d);
    assert!(!o.status.success());
    assert!(!text(&o).contains("has no faces"), "{}", text(&o));
    // The same mesh with a valid last face is a mesh.
    std::fs::write(d.join("ok.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
        .unwrap();
    let o = bsv(&["info", "ok.obj", "--json"], d);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j.get("mesh").is_some() && j.get("mesh_error").is_none(), "{j}");
    // A point cloud (no faces) is no error.
    std::fs::write(d.join("pts.obj"), "v 0 0 0\nv 1 0 0\n").unwrap();
    let o = bsv(&["info", "pts.obj", "--json"], d);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j.get("mesh").is_none() && j.get("mesh_error").is_none(), "{j}");
}

#[test]
fn scan_in_a_room_writes_the_room_into_the_images_not_the_cloud() {
    let tmp = tmpdir("room");
    let d = tmp.path();
    let o = bsv(&["template", "-o", "t.ply"], d);
    assert!(o.status.success(), "{}", text(&o));
    let o = bsv(&["scan", "t.ply", "-o", "plain.ply"], d);
    assert!(o.status.success(), "{}", text(&o));
    let o = bsv(&["scan", "t.ply", "--room", "--room-objects", "-o", "room.ply", "--images", "cap"], d);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("in a room"), "{}", text(&o));
    assert_eq!(std::fs::read(d.join("plain.ply")).unwrap(), std::fs::read(d.join("room.ply")).unwrap());
    assert!(d.join("cap/front/color.png").is_file() && d.join("cap/back/depth.png").is_file());
    let o = bsv(&["scan", "t.ply", "--room-objects", "-o", "x.ply"], d);
    assert!(!o.status.success());
    assert!(text(&o).contains("--room"), "{}", text(&o));
}

#[test]
fn scan_images_record_the_rigs_calibration_covariance() {
    use bsv_capture::scanner::{Rig, COVARIANCE_FRAME, COVARIANCE_PARAMETERS};
    let tmp = tmpdir("covariance");
    let d = tmp.path();
    let o = bsv(&["template", "-o", "t.ply"], d);
    assert!(o.status.success(), "{}", text(&o));
    let rig = Rig::paper_default();
    for (condition, exact) in [("l5ca", false), ("noer", true)] {
        let cloud = format!("{condition}.ply");
        let o = bsv(&["scan", "t.ply", "--condition", condition, "-o", &cloud, "--images", condition], d);
        assert!(o.status.success(), "{}", text(&o));
        let cal: serde_json::Value =
            serde_json::from_slice(&std::fs::read(d.join(condition).join("calibration.json")).unwrap()).unwrap();
        for cam in &rig.cameras {
            let cov = &cal["cameras"][cam.name.as_str()]["extrinsics_covariance"];
            assert_eq!(cov["parameters"], serde_json::json!(COVARIANCE_PARAMETERS), "{condition} {}", cam.name);
            assert_eq!(cov["frame"], COVARIANCE_FRAME);
            let source = if exact { "virtual rig: exact extrinsics" } else { "virtual rig: the paper's repeatability" };
            assert_eq!(cov["source"], source);
            // Diagonal: the variances of the sigmas the rig draws its calibration errors from (none in
            // noer). serde_json's default float parsing may be 1 ulp off, hence the tolerance.
            let std = cam.calibration_sigma.std();
            for (i, row) in cov["matrix"].as_array().unwrap().iter().enumerate() {
                for (j, v) in row.as_array().unwrap().iter().enumerate() {
                    let (got, want) = (v.as_f64().unwrap(), if i == j && !exact { std[i] * std[i] } else { 0.0 });
                    assert!((got - want).abs() <= 1e-15 * want, "{condition} {} [{i}][{j}]: {got} vs {want}", cam.name);
                    assert!(exact || i != j || got > 0.0);
                }
            }
        }
    }
}
