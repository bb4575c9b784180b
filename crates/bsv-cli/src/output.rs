//! Output helpers shared by the commands: the error type, overwrite protection, JSON writing.

use std::path::{Path, PathBuf};

/// Any failure of a command, with the library error as its source.
pub type CliError = Box<dyn std::error::Error + Send + Sync>;

/// A refusal to overwrite a file the user did not ask to replace.
#[derive(Debug)]
pub struct Exists(pub PathBuf);

impl std::fmt::Display for Exists {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} already exists; pass --force to overwrite it or choose another output path", self.0.display())
    }
}

impl std::error::Error for Exists {}

/// Fails when `path` exists and `force` is false.
pub fn check_writable(path: &Path, force: bool) -> Result<(), CliError> {
    if path.exists() && !force {
        return Err(Box::new(Exists(path.to_path_buf())));
    }
    Ok(())
}

/// Writes pretty JSON to `path` (after the overwrite check).
pub fn write_json(path: &Path, value: &serde_json::Value, force: bool) -> Result<(), CliError> {
    check_writable(path, force)?;
    let text = serde_json::to_string_pretty(value)?;
    std::fs::write(path, text + "\n").map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(())
}
