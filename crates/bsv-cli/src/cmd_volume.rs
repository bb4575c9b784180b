//! `bsv-cli volume`: segment volumes of a closed labelled mesh.

use crate::output::{check_outputs, write_json, CliError, Output};
use bsv_core::io;
use bsv_volume::{report_with, SegmentOptions};
use std::path::PathBuf;

/// Arguments of `volume`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A closed triangle mesh, PLY (vertex or face `label`) or OBJ (`g <segment>` groups), in metres.
    mesh: PathBuf,
    /// Also write the volumes JSON (DESIGN.md "Formats": volumes_l in litres, ratios, mass) here.
    #[arg(long, value_name = "OUT")]
    json: Option<PathBuf>,
    /// Body density for the mass estimate, kg/m^3.
    #[arg(long, default_value_t = bsv_volume::DEFAULT_DENSITY_KG_M3)]
    density: f64,
    /// Close holes with centroid fans instead of refusing an open mesh.
    #[arg(long)]
    close_holes: bool,
    /// Overwrite the JSON output if it exists.
    #[arg(long)]
    force: bool,
}

/// Runs `volume`.
pub fn run(a: Args) -> Result<(), CliError> {
    if let Some(out) = &a.json {
        check_outputs(&[Output::file("--json", out)], a.force)?;
    }
    let mesh = io::read_mesh(&a.mesh)?;
    let opts = SegmentOptions { close_holes: a.close_holes, ..SegmentOptions::default() };
    let report = report_with(&mesh, a.density, &opts).map_err(|e| format!("{}: {e}", a.mesh.display()))?;
    say_inline!("{report}");
    if let Some(out) = &a.json {
        write_json(out, &serde_json::to_value(&report)?)?;
        say!("volumes written to {}", out.display());
    }
    Ok(())
}
