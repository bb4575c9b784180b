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
    /// Units of the mesh file: m (default) or mm (divided by 1000 on reading). A mesh larger than
    /// 5 m is refused in metres (the rule of registration clouds, `bsv_core::geometry::MAX_EXTENT_M`).
    #[arg(long, default_value = "m", value_parser = ["m", "mm"])]
    units: String,
    /// Overwrite the JSON output if it exists.
    #[arg(long)]
    force: bool,
}

/// Runs `volume`.
pub fn run(a: Args) -> Result<(), CliError> {
    if let Some(out) = &a.json {
        check_outputs(&[Output::file("--json", out)], a.force)?;
    }
    let mut mesh = io::read_mesh(&a.mesh)?;
    if a.units == "mm" {
        mesh.vertices.iter_mut().for_each(|p| *p = p.map(|v| v / 1000.0));
    }
    if let Some(b) = bsv_core::geometry::Aabb::of_points(&mesh.vertices) {
        let largest = b.extent().into_iter().fold(0.0f64, f64::max);
        if bsv_core::geometry::looks_like_millimetres(largest) {
            return Err(format!(
                "{}: mesh extent {largest:.1} (max axis) is larger than {} m: it looks like millimetres; pass --units mm (or divide the coordinates by 1000)",
                a.mesh.display(),
                bsv_core::geometry::MAX_EXTENT_M
            )
            .into());
        }
    }
    let opts = SegmentOptions { close_holes: a.close_holes, ..SegmentOptions::default() };
    let report = report_with(&mesh, a.density, &opts).map_err(|e| format!("{}: {e}", a.mesh.display()))?;
    say_inline!("{report}");
    if let Some(out) = &a.json {
        write_json(out, &serde_json::to_value(&report)?)?;
        say!("volumes written to {}", out.display());
    }
    Ok(())
}
