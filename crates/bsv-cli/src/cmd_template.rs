//! `bsv-cli template`: export an embedded template.

use crate::output::{check_outputs, CliError, Output};
use bsv_core::io;
use bsv_core::template::{template, TemplateKind};
use std::path::PathBuf;

/// Arguments of `template`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output file, .ply (labels and palette colours) or .obj (segment groups).
    #[arg(short, long, default_value = "template.ply")]
    output: PathBuf,
    /// Which template: default (9 segments, 4,177 vertices), fine (subdivided, 16,702), full (14 segments),
    /// female or male (the default mesh at MakeHuman's female or male end of the gender macro).
    #[arg(long, default_value = "default", value_parser = TemplateKind::NAMES)]
    kind: String,
    /// Shorthand for --kind full.
    #[arg(long)]
    full: bool,
    /// Overwrite the output if it exists.
    #[arg(long)]
    force: bool,
}

/// Runs `template`.
pub fn run(a: Args) -> Result<(), CliError> {
    let kind = if a.full { TemplateKind::Full } else { TemplateKind::parse(&a.kind).unwrap_or_default() };
    check_outputs(&[Output::file("--output", &a.output)], a.force)?;
    let mesh = template(kind)?;
    io::write_mesh(&a.output, &mesh)?;
    say!(
        "{kind:?} template ({} vertices, {} triangles) written to {}",
        mesh.n_vertices(),
        mesh.n_triangles(),
        a.output.display()
    );
    Ok(())
}
