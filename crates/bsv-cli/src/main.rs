//! `bsv-cli`: the BSV command-line tool. Thin: parse arguments, call the library crates, print, write.

#[macro_use]
mod output;
mod cmd_info;
mod cmd_register;
mod cmd_scan;
mod cmd_template;
mod cmd_volume;

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// Body segment volumes from two RGB-D cameras.
///
/// Units: metres for every length in every file (a cloud in millimetres is rejected with a hint);
/// volumes are printed and written in litres. World frame: Y up, floor at y = 0, the subject faces +Z,
/// +X is the subject's left. Files: PLY (ascii or binary, either endianness; vertex x y z, optional
/// nx ny nz, red green blue, label) and OBJ (`g <segment name>` groups label faces). Written PLY is
/// binary little-endian with `label` and palette colours. Segment ids: 0 unlabelled, 1 head, 2 torso,
/// 3/4 upper_arm_l/r, 5/6 forearm_l/r, 7/8 hand_l/r, 9/10 thigh_l/r, 11/12 shin_l/r, 13/14 foot_l/r.
#[derive(Parser, Debug)]
#[command(name = "bsv-cli", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Counts, bounding box, labels present and the mesh-check report of a PLY/OBJ file.
    Info(cmd_info::Args),
    /// Segment volumes (litres) of a closed, labelled mesh, with aggregates, ratios and mass.
    Volume(cmd_volume::Args),
    /// Fit the template to a point cloud (regularized ARAP) and report segment volumes.
    Register(cmd_register::Args),
    /// Virtual two-camera capture of a mesh (the paper's rig) into a labelled point cloud.
    Scan(cmd_scan::Args),
    /// Write the embedded default template (9 segments, or 14 with --full).
    Template(cmd_template::Args),
}

/// Lets a file-size limit (`ulimit -f`) fail the write with an error instead of killing the process,
/// so that the atomic writers remove their temporary file and the command reports it.
fn catch_file_size_signal() {
    let _ = signal_hook::flag::register(signal_hook::consts::SIGXFSZ, Arc::new(AtomicBool::new(false)));
}

fn main() -> ExitCode {
    catch_file_size_signal();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info(a) => cmd_info::run(a),
        Command::Volume(a) => cmd_volume::run(a),
        Command::Register(a) => cmd_register::run(a),
        Command::Scan(a) => cmd_scan::run(a),
        Command::Template(a) => cmd_template::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            output::print_err(format_args!("error: {e}\n"));
            let mut src = e.source();
            while let Some(s) = src {
                output::print_err(format_args!("  caused by: {s}\n"));
                src = s.source();
            }
            ExitCode::FAILURE
        }
    }
}
