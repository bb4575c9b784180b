//! `bsv-cli register` writes the same fitted-mesh bytes for any thread count and from run to run
//! (issue 14); `scan` and `volume` do not depend on the thread count either.

#![allow(clippy::unwrap_used)]

mod common;

use common::tmpdir;
use std::path::Path;
use std::process::{Command, Output};

fn bsv(args: &[&str], dir: &Path, rayon_threads: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_bsv-cli"));
    c.args(args).current_dir(dir);
    match rayon_threads {
        Some(t) => c.env("RAYON_NUM_THREADS", t),
        None => c.env_remove("RAYON_NUM_THREADS"),
    };
    c.output().unwrap()
}

fn ok(o: &Output) {
    assert!(o.status.success(), "{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
}

/// The JSON report without its timings.
fn volumes(path: &Path) -> serde_json::Value {
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    v["volumes_l"].clone()
}

#[test]
fn register_writes_the_same_bytes_for_any_thread_count() {
    let tmp = tmpdir("repro");
    let d = tmp.path();
    ok(&bsv(&["template", "-o", "t.ply"], d, None));
    // The scan (noise and calibration error) with one and with three threads.
    ok(&bsv(&["scan", "t.ply", "--condition", "l5ca", "--seed", "5", "-o", "c.ply"], d, Some("1")));
    ok(&bsv(&["scan", "t.ply", "--condition", "l5ca", "--seed", "5", "-o", "c3.ply"], d, Some("3")));
    let cloud = std::fs::read(d.join("c.ply")).unwrap();
    assert!(cloud == std::fs::read(d.join("c3.ply")).unwrap(), "scan depends on the thread count");
    let runs: [(&str, &[&str], Option<&str>); 5] = [
        ("f1.ply", &["--threads", "1"], None),
        ("f2.ply", &["--threads", "2"], None),
        ("f3.ply", &["--threads", "3"], None),
        ("f0a.ply", &[], Some("2")),
        ("f0b.ply", &[], Some("2")),
    ];
    let mut first: Option<(Vec<u8>, serde_json::Value)> = None;
    for (out, extra, env) in runs {
        let json = out.replace(".ply", ".json");
        let mut args = vec!["register", "c.ply", "-o", out, "--json", &json, "--quiet"];
        args.extend_from_slice(extra);
        ok(&bsv(&args, d, env));
        let bytes = std::fs::read(d.join(out)).unwrap();
        let vols = volumes(&d.join(&json));
        match &first {
            None => first = Some((bytes, vols)),
            Some((b, v)) => {
                assert!(*b == bytes, "{out} ({extra:?}, RAYON_NUM_THREADS {env:?}) differs from f1.ply");
                assert_eq!(*v, vols, "{out}: volumes differ");
            }
        }
    }
    // Volumes of the fit with one and with three threads.
    ok(&bsv(&["volume", "f1.ply", "--json", "v1.json"], d, Some("1")));
    ok(&bsv(&["volume", "f1.ply", "--json", "v3.json"], d, Some("3")));
    assert_eq!(volumes(&d.join("v1.json")), volumes(&d.join("v3.json")));
    let _ = std::fs::remove_dir_all(d);
}
