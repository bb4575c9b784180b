//! The output guarantees of `bsv-cli` (crates/bsv-cli/src/output.rs): outputs checked before the work,
//! never two outputs on one path, folders and dangling links refused, atomic writes under a file-size
//! limit, and a closed stdout (`| head`) that stops the printing but not the command.

#![allow(clippy::unwrap_used)]

mod common;

use common::{bsv, text, tmpdir};
use std::path::Path;
use std::process::{Command, Stdio};

/// Names in `dir`, sorted (hidden temporary files included).
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// A labelled cloud to register: the template's own noise-free scan.
fn cloud(dir: &Path) {
    assert!(bsv(&["template", "-o", "t.ply"], dir).status.success());
    let o = bsv(&["scan", "t.ply", "-o", "c.ply"], dir);
    assert!(o.status.success(), "{}", text(&o));
}

#[test]
fn two_outputs_on_one_path_are_refused_before_the_fit() {
    let tmp = tmpdir("same");
    let d = tmp.path();
    cloud(d);
    let before = listing(d);
    let o = bsv(&["register", "c.ply", "-o", "same.ply", "--json", "./same.ply", "--quiet"], d);
    assert!(!o.status.success());
    assert!(text(&o).contains("--output and --json both name"), "{}", text(&o));
    assert!(!text(&o).contains("registering"), "refused only after the work: {}", text(&o));
    assert_eq!(listing(d), before);
}

#[test]
fn a_missing_folder_or_a_folder_as_output_is_refused_before_the_fit() {
    let tmp = tmpdir("folders");
    let d = tmp.path();
    cloud(d);
    let before = listing(d);
    let o = bsv(&["register", "c.ply", "-o", "fit.ply", "--json", "nodir/v.json", "--quiet"], d);
    assert!(!o.status.success());
    assert!(text(&o).contains("nodir/v.json") && text(&o).contains("does not exist"), "{}", text(&o));
    std::fs::create_dir(d.join("adir")).unwrap();
    let o = bsv(&["register", "c.ply", "-o", "adir", "--force", "--quiet"], d);
    assert!(!o.status.success());
    assert!(text(&o).contains("is a folder"), "{}", text(&o));
    // --images naming a file.
    let o = bsv(&["scan", "t.ply", "-o", "c2.ply", "--images", "t.ply"], d);
    assert!(!o.status.success());
    assert!(text(&o).contains("is a file"), "{}", text(&o));
    let mut after = listing(d);
    after.retain(|n| n != "adir");
    assert_eq!(after, before, "a refused run left files");
}

#[cfg(unix)]
#[test]
fn a_dangling_symlink_is_not_followed_without_force() {
    let tmp = tmpdir("symlink");
    let d = tmp.path();
    std::os::unix::fs::symlink(d.join("target.ply"), d.join("link.ply")).unwrap();
    let o = bsv(&["template", "-o", "link.ply"], d);
    assert!(!o.status.success());
    assert!(text(&o).contains("already exists"), "{}", text(&o));
    assert!(!d.join("target.ply").exists());
}

#[cfg(unix)]
#[test]
fn a_file_size_limit_leaves_no_partial_file() {
    let tmp = tmpdir("ulimit");
    let d = tmp.path();
    // 64 blocks of 512 bytes: far below the template's size.
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -f 64; exec '{}' template --kind fine -o t.ply", env!("CARGO_BIN_EXE_bsv-cli")))
        .current_dir(d)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert_eq!(o.status.code(), Some(1), "killed instead of a typed error: {}", text(&o));
    assert!(text(&o).contains("t.ply"), "{}", text(&o));
    assert!(listing(d).is_empty(), "left {:?}", listing(d));
}

#[cfg(unix)]
#[test]
fn a_closed_stdout_does_not_stop_the_command() {
    let tmp = tmpdir("pipe");
    let d = tmp.path();
    cloud(d);
    // `| head -1`: the reader goes away after the first line.
    let mut child = Command::new(env!("CARGO_BIN_EXE_bsv-cli"))
        .args(["register", "c.ply", "-o", "fit.ply", "--json", "v.json"])
        .current_dir(d)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(!text(&o).contains("panicked"), "{}", text(&o));
    assert!(d.join("fit.ply").exists() && d.join("v.json").exists());
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!("'{}' info t.ply | head -1", env!("CARGO_BIN_EXE_bsv-cli")))
        .current_dir(d)
        .output()
        .unwrap();
    assert!(!text(&o).contains("panicked"), "{}", text(&o));
}

#[test]
fn a_failed_capture_write_leaves_no_cloud() {
    let tmp = tmpdir("capture");
    let d = tmp.path();
    assert!(bsv(&["template", "-o", "t.ply"], d).status.success());
    // The capture folder's parent does not exist: refused before the scan.
    let o = bsv(&["scan", "t.ply", "-o", "c.ply", "--images", "no/such/dir"], d);
    assert!(!o.status.success());
    assert!(!d.join("c.ply").exists());
    // A fresh capture folder is complete when it appears, with no temporary folder left.
    let o = bsv(&["scan", "t.ply", "-o", "c.ply", "--images", "cap"], d);
    assert!(o.status.success(), "{}", text(&o));
    assert!(d.join("cap/front/depth.png").exists() && d.join("c.ply").exists());
    assert!(listing(d).iter().all(|n| !n.starts_with(".bsv-partial")), "{:?}", listing(d));
}
