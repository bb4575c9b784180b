//! Helpers shared by the `bsv-cli` integration tests: the binary run in a folder, its output as text, and
//! a scratch folder that is removed when the test ends (passed or failed).

#![allow(dead_code, clippy::unwrap_used)]

use std::path::Path;
use std::process::{Command, Output};

/// `bsv-cli args` run in `dir`.
pub fn bsv(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bsv-cli")).args(args).current_dir(dir).output().unwrap()
}

/// A fresh scratch folder `bsv-cli-<name>-...` in the system's temporary folder, removed on drop.
pub fn tmpdir(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new().prefix(&format!("bsv-cli-{name}-")).tempdir().unwrap()
}

/// A command's standard output and error, as text.
pub fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}
