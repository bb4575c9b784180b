//! Implausible input (issue 10): a body cloud turned 90 degrees about x, y or z, upside down, a
//! sphere, a plane, and a mesh in millimetres given to `volume`: non-zero exit and a message naming
//! the problem and the fix; `--up` and `--units mm` then make the same files work.

#![allow(clippy::unwrap_used)]

mod common;

use bsv_core::io::{read_mesh, read_point_cloud, write_mesh, write_point_cloud};
use bsv_core::shapes::icosphere;
use bsv_core::PointCloud;
use common::{bsv, text, tmpdir};
use std::path::Path;

/// The template and its noise-free two-camera scan (a standing person in the world frame).
fn scanned(d: &Path) -> PointCloud {
    assert!(bsv(&["template", "-o", "t.ply"], d).status.success());
    let o = bsv(&["scan", "t.ply", "--condition", "noer", "-o", "c.ply"], d);
    assert!(o.status.success(), "{}", text(&o));
    read_point_cloud(&d.join("c.ply")).unwrap()
}

fn write_map(d: &Path, name: &str, c: &PointCloud, f: fn([f64; 3]) -> [f64; 3], labels: bool) {
    let mut out = c.clone();
    out.points.iter_mut().for_each(|p| *p = f(*p));
    out.normals = None;
    if !labels {
        out.labels = None;
    }
    write_point_cloud(&d.join(name), &out).unwrap();
}

#[test]
fn turned_and_upside_down_clouds_exit_non_zero_naming_the_problem() {
    let tmp = tmpdir("turned");
    let d = tmp.path();
    let c = scanned(d);
    type Case = (&'static str, fn([f64; 3]) -> [f64; 3], &'static str);
    let cases: [Case; 4] = [
        ("x90", |[x, y, z]| [x, -z, y], "--up"),
        ("y90", |[x, y, z]| [z, y, -x], "does not face +z"),
        ("z90", |[x, y, z]| [-y, x, z], "--up"),
        ("flip", |[x, y, z]| [x, -y, -z], "--up -y"),
    ];
    for (name, f, hint) in cases {
        for labels in [true, false] {
            let file = format!("{name}-{labels}.ply");
            write_map(d, &file, &c, f, labels);
            let o = bsv(&["register", &file, "--quiet"], d);
            let t = text(&o);
            assert_eq!(o.status.code(), Some(1), "{file}: {t}");
            assert!(t.contains("error:") && t.contains(hint) && !t.contains("panicked"), "{file}: {t}");
        }
    }
    // The remedy works: the upside-down cloud registers with --up -y.
    let o = bsv(&["register", "flip-true.ply", "--up", "-y", "--quiet", "--json", "v.json"], d);
    assert!(o.status.success(), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("v.json")).unwrap()).unwrap();
    assert!(v["registration"]["quality"]["torso"]["coverage"].as_f64().unwrap() > 0.5, "{v}");
    assert!(!text(&o).contains("doubtful"), "{}", text(&o));
    // The remedy for a cloud lying along z: --up +z; then the fit is good (no segment flagged).
    let o = bsv(&["register", "x90-true.ply", "--up", "+z", "--quiet"], d);
    assert!(o.status.success() && !text(&o).contains("doubtful"), "{}", text(&o));
    // A deliberately bad fit (the check switched off, a body facing +x) is flagged per segment.
    let o = bsv(
        &[
            "register",
            "y90-true.ply",
            "--no-plausibility-check",
            "--schedule",
            "m2p:3",
            "--quiet",
            "--json",
            "bad.json",
        ],
        d,
    );
    assert!(o.status.success() && text(&o).contains("is doubtful"), "{}", text(&o));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("bad.json")).unwrap()).unwrap();
    let flagged = v["registration"]["quality"].as_object().unwrap().values().filter(|q| q["doubtful"] == true).count();
    assert!(flagged >= 1, "{v}");
}

#[test]
fn a_sphere_and_a_plane_exit_non_zero_naming_the_shape() {
    let tmp = tmpdir("shapes");
    let d = tmp.path();
    // The sphere: 88 L, standing on the floor.
    let r = (88e-3 * 3.0 / (4.0 * std::f64::consts::PI)).cbrt();
    let mut sphere = PointCloud::new(bsv_capture::sample::sample_surface(&icosphere(r, 4), 20_000, 1).0);
    sphere.points.iter_mut().for_each(|p| p[1] += 1.0);
    write_point_cloud(&d.join("sphere.ply"), &sphere).unwrap();
    let plane =
        PointCloud::new((0..20_000).map(|i| [(i % 100) as f64 / 100.0, (i / 100) as f64 * 0.008, 2.0]).collect());
    write_point_cloud(&d.join("plane.ply"), &plane).unwrap();
    for (file, what) in [("sphere.ply", "compact"), ("plane.ply", "flat")] {
        let o = bsv(&["register", file, "--quiet", "-o", "fit.ply"], d);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{file}: {t}");
        assert!(t.contains(what) && t.contains("--no-plausibility-check"), "{file}: {t}");
        assert!(!d.join("fit.ply").exists());
    }
}

#[test]
fn volume_refuses_a_mesh_in_millimetres_like_register_refuses_a_cloud() {
    let tmp = tmpdir("mm");
    let d = tmp.path();
    assert!(bsv(&["template", "-o", "t.ply"], d).status.success());
    let mut m = read_mesh(&d.join("t.ply")).unwrap();
    m.vertices.iter_mut().for_each(|p| *p = p.map(|v| v * 1000.0));
    write_mesh(&d.join("mm.ply"), &m).unwrap();
    let o = bsv(&["volume", "mm.ply", "--json", "v.json"], d);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("millimetres") && t.contains("--units mm"), "{t}");
    assert!(!d.join("v.json").exists());
    let o = bsv(&["volume", "mm.ply", "--units", "mm", "--json", "v.json"], d);
    assert!(o.status.success(), "{}", text(&o));
    let mm: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("v.json")).unwrap()).unwrap();
    assert!(bsv(&["volume", "t.ply", "--json", "m.json"], d).status.success());
    let m: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("m.json")).unwrap()).unwrap();
    let (a, b) = (mm["volumes_l"]["trunk_limbs"].as_f64().unwrap(), m["volumes_l"]["trunk_limbs"].as_f64().unwrap());
    assert!((a - b).abs() < 1e-6 * b, "{a} vs {b}");
}
