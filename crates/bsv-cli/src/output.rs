//! Output helpers shared by the commands: the error type, the check of every output before any work,
//! atomic JSON writing and printing that survives a closed pipe.
//!
//! Guarantees (each command calls [`check_outputs`] before reading its inputs):
//! - nothing that exists is replaced without `--force`, a dangling symbolic link included;
//! - two outputs of one command never name the same file;
//! - an output that is a folder, or whose folder does not exist, is refused before the work;
//! - files are written atomically (`bsv_core::io::write_file_atomic`): a failed run leaves no
//!   half-written file;
//! - stdout closed early (`bsv-cli info x.ply | head -1`) stops the printing, not the command.

use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Any failure of a command, with the library error as its source.
pub type CliError = Box<dyn std::error::Error + Send + Sync>;

/// Why an output path is refused before any work is done.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The file exists (or is a symbolic link) and `--force` was not given.
    #[error("{0} already exists; pass --force to overwrite it or choose another output path")]
    Exists(PathBuf),
    /// The output path is a folder.
    #[error("{0} is a folder; give a file path for this output")]
    IsFolder(PathBuf),
    /// A folder output is an existing file.
    #[error("{0} is a file; give a folder path for this output")]
    NotAFolder(PathBuf),
    /// A folder output already holds files.
    #[error("{0} is not empty; pass --force to write into it or choose an empty folder")]
    FolderNotEmpty(PathBuf),
    /// The folder that should hold the output does not exist.
    #[error("the folder of {0} does not exist; create it first or choose another output path")]
    NoFolder(PathBuf),
    /// Two outputs of the command name the same file.
    #[error("{first} and {second} both name {path}; give them different paths")]
    SamePath {
        /// The first option.
        first: &'static str,
        /// The second option.
        second: &'static str,
        /// The shared path.
        path: PathBuf,
    },
}

/// One output of a command: its option name (for messages), its path and whether it is a folder.
#[derive(Debug, Clone, Copy)]
pub struct Output<'a> {
    /// The option that names it (`--output`, `--json`, `--images`).
    pub option: &'static str,
    /// The path given.
    pub path: &'a Path,
    /// True for a folder the command fills (`--images`).
    pub folder: bool,
}

impl<'a> Output<'a> {
    /// A file output.
    pub fn file(option: &'static str, path: &'a Path) -> Self {
        Output { option, path, folder: false }
    }

    /// A folder output.
    pub fn folder(option: &'static str, path: &'a Path) -> Self {
        Output { option, path, folder: true }
    }
}

/// The absolute form of `path` with its folder resolved (the file itself need not exist).
fn resolved(path: &Path) -> PathBuf {
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let parent = parent.canonicalize().unwrap_or_else(|_| parent.to_path_buf());
    match path.file_name() {
        Some(name) => parent.join(name),
        None => parent,
    }
}

fn check_one(o: &Output<'_>, force: bool) -> Result<(), OutputError> {
    let path = o.path.to_path_buf();
    let parent = o.path.parent().filter(|p| !p.as_os_str().is_empty());
    if parent.is_some_and(|p| !p.is_dir()) {
        return Err(OutputError::NoFolder(path));
    }
    let Ok(meta) = std::fs::symlink_metadata(o.path) else { return Ok(()) };
    let is_dir = o.path.is_dir();
    if o.folder {
        if !is_dir {
            return Err(OutputError::NotAFolder(path));
        }
        let empty = std::fs::read_dir(o.path).map(|mut d| d.next().is_none()).unwrap_or(true);
        return if empty || force { Ok(()) } else { Err(OutputError::FolderNotEmpty(path)) };
    }
    if is_dir {
        return Err(OutputError::IsFolder(path));
    }
    if !force && (meta.is_file() || meta.file_type().is_symlink()) {
        return Err(OutputError::Exists(path));
    }
    Ok(())
}

/// Checks every output of a command before any work: all distinct, none a folder (or a file where a
/// folder is expected), each folder present, none existing unless `force`.
pub fn check_outputs(outputs: &[Output<'_>], force: bool) -> Result<(), CliError> {
    for (i, a) in outputs.iter().enumerate() {
        for b in &outputs[i + 1..] {
            let (ra, rb) = (resolved(a.path), resolved(b.path));
            if ra == rb {
                return Err(Box::new(OutputError::SamePath { first: a.option, second: b.option, path: ra }));
            }
        }
        check_one(a, force)?;
    }
    Ok(())
}

/// Writes pretty JSON to `path` atomically (the overwrite check is [`check_outputs`]'s).
pub fn write_json(path: &Path, value: &serde_json::Value) -> Result<(), CliError> {
    let text = serde_json::to_string_pretty(value)? + "\n";
    bsv_core::io::write_file_atomic(path, |f| f.write_all(text.as_bytes()))?;
    Ok(())
}

/// Prints to stdout, silently dropping the text when stdout is closed (a `| head` pipe): the command
/// goes on and writes its files.
pub fn print_out(args: fmt::Arguments<'_>) {
    let _ = std::io::stdout().lock().write_fmt(args);
}

/// `println!` that never panics on a closed stdout ([`print_out`]).
macro_rules! say {
    () => { $crate::output::print_out(format_args!("\n")) };
    ($($t:tt)*) => { $crate::output::print_out(format_args!("{}\n", format_args!($($t)*))) };
}

/// `print!` that never panics on a closed stdout ([`print_out`]).
macro_rules! say_inline {
    ($($t:tt)*) => { $crate::output::print_out(format_args!($($t)*)) };
}

/// Prints to stderr, ignoring a closed stderr.
pub fn print_err(args: fmt::Arguments<'_>) {
    let _ = std::io::stderr().lock().write_fmt(args);
}
