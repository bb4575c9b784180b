//! `bsv-cli register`: fit the template to a cloud and report volumes (wired when bsv-register lands).

use crate::output::CliError;
use std::path::PathBuf;

/// Arguments of `register`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The labelled point cloud (PLY), metres.
    cloud: PathBuf,
}

/// Runs `register`.
pub fn run(a: Args) -> Result<(), CliError> {
    Err(format!("register {}: not built yet", a.cloud.display()).into())
}
