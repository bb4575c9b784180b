//! `bsv-cli scan`: virtual two-camera capture of a labelled mesh.

use crate::output::{check_writable, CliError};
use bsv_capture::scanner::{scan, write_capture, Condition, Rig, Room};
use bsv_core::io;
use std::path::PathBuf;

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
    check_writable(&a.output, a.force)?;
    if let Some(dir) = &a.images {
        if dir.read_dir().map(|mut d| d.next().is_some()).unwrap_or(false) && !a.force {
            return Err(format!("{} is not empty; pass --force to write into it", dir.display()).into());
        }
    }
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
        println!("  {:<5} camera: {:>7} points", v.name, v.cloud_range.len());
    }
    let room = if a.room { ", in a room" } else { "" };
    println!(
        "scanned {} ({condition}, seed {}{room}) in {secs:.2} s: {} points",
        a.mesh.display(),
        a.seed,
        s.cloud.len()
    );
    io::write_point_cloud(&a.output, &s.cloud)?;
    println!("cloud written to {}", a.output.display());
    if let Some(dir) = &a.images {
        write_capture(&s, dir)?;
        println!("capture images written to {}", dir.display());
    }
    Ok(())
}
