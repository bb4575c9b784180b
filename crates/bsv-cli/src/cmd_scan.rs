//! `bsv-cli scan`: virtual two-camera capture of a labelled mesh.

use crate::output::{check_outputs, CliError, Output};
use bsv_capture::scanner::{scan, write_capture, Condition, Rig, Room, Scan};
use bsv_core::io;
use std::path::{Path, PathBuf};

/// Arguments of `scan`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A closed mesh in metres, world frame (Y up, facing +Z), ideally labelled.
    mesh: PathBuf,
    /// Error condition: noer (exact), l515 (depth noise + flying pixels), cali (extrinsic error), l5ca (both).
    #[arg(long, default_value = "noer")]
    condition: String,
    /// Seed of the noise and calibration-error draws.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output cloud (PLY, with labels and palette colours).
    #[arg(short, long, default_value = "cloud.ply")]
    output: PathBuf,
    /// Also write what a real capture writes (per camera depth PNG, colour PNG, label PNG, camera.json) here.
    #[arg(long, value_name = "DIR")]
    images: Option<PathBuf>,
    /// Put the rig in a clinic room (floor, walls, ceiling; distances varied by the seed): the images
    /// show the room with label 0 and the colour render a varied subject; the cloud keeps the body only.
    #[arg(long)]
    room: bool,
    /// With --room: also a chair-sized block and a second person partly in the front camera's view.
    #[arg(long, requires = "room")]
    room_objects: bool,
    /// Overwrite outputs that exist.
    #[arg(long)]
    force: bool,
}

/// Runs `scan`.
pub fn run(a: Args) -> Result<(), CliError> {
    let condition: Condition = a.condition.parse()?;
    let mut outputs = vec![Output::file("--output", &a.output)];
    outputs.extend(a.images.as_deref().map(|d| Output::folder("--images", d)));
    check_outputs(&outputs, a.force)?;
    let mesh = io::read_mesh(&a.mesh)?;
    let t = std::time::Instant::now();
    let mut rig = Rig::paper_default();
    if a.room {
        let base = if a.room_objects { Room::clinic_with_objects() } else { Room::clinic() };
        rig = rig.with_room(base.varied(a.seed));
    }
    let s = scan(&mesh, &rig, condition, a.seed)?;
    let secs = t.elapsed().as_secs_f64();
    for v in &s.views {
        say!("  {:<5} camera: {:>7} points", v.name, v.cloud_range.len());
    }
    let room = if a.room { ", in a room" } else { "" };
    say!("scanned {} ({condition}, seed {}{room}) in {secs:.2} s: {} points", a.mesh.display(), a.seed, s.cloud.len());
    if let Some(dir) = &a.images {
        write_capture_atomic(&s, dir)?;
        say!("capture images written to {}", dir.display());
    }
    io::write_point_cloud(&a.output, &s.cloud)?;
    say!("cloud written to {}", a.output.display());
    Ok(())
}

/// Writes the capture into `dir` so that a failure leaves nothing new: into a fresh temporary folder
/// beside `dir`, renamed to `dir` once complete (an existing empty `dir` is replaced). A non-empty
/// `dir` (allowed by `--force`) is written in place.
fn write_capture_atomic(s: &Scan, dir: &Path) -> Result<(), CliError> {
    let in_place = dir.read_dir().map(|mut d| d.next().is_some()).unwrap_or(false);
    if in_place {
        return Ok(write_capture(s, dir)?);
    }
    let parent = dir.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let tmp = tempfile::Builder::new().prefix(".bsv-partial-").tempdir_in(parent)?;
    write_capture(s, tmp.path())?;
    if dir.is_dir() {
        std::fs::remove_dir(dir)?;
    }
    std::fs::rename(tmp.path(), dir).map_err(|e| format!("cannot move the capture into {}: {e}", dir.display()))?;
    Ok(())
}
