//! `bsv-cli info`: what a file holds and whether it is a usable mesh.

use crate::output::{check_outputs, CliError, Output};
use bsv_core::check::{check_mesh, repair_mesh};
use bsv_core::geometry::Aabb;
use bsv_core::io::{self, obj, ply, Format, ReadError};
use bsv_core::{PointCloud, Segment, TriMesh};
use std::path::{Path, PathBuf};

/// Arguments of `info`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A PLY or OBJ file (mesh or point cloud).
    file: PathBuf,
    /// Print the report as JSON instead of text.
    #[arg(long)]
    json: bool,
    /// Repair the mesh (drop degenerate, duplicate and unreferenced elements, orient outward) and write it here.
    #[arg(long, value_name = "OUT")]
    repair: Option<PathBuf>,
    /// Overwrite the --repair output if it exists.
    #[arg(long)]
    force: bool,
}

fn label_counts(labels: &[u8]) -> Vec<(String, usize)> {
    let mut counts = [0usize; 256];
    for &l in labels {
        counts[usize::from(l)] += 1;
    }
    counts
        .iter()
        .enumerate()
        .filter(|(_, &c)| c > 0)
        .map(|(id, &c)| {
            let name = u8::try_from(id)
                .ok()
                .and_then(Segment::from_id)
                .map_or_else(|| format!("id {id}"), |s| s.name().to_string());
            (name, c)
        })
        .collect()
}

/// Whether some line of an OBJ file is a face (`f ...`).
fn obj_has_faces(bytes: &[u8]) -> bool {
    bytes.split(|&b| b == b'\n').any(|line| line.split(u8::is_ascii_whitespace).find(|w| !w.is_empty()) == Some(b"f"))
}

/// Reads `path` once: the file as a point cloud, and as a mesh when it has faces (`Some(Err)`
/// when it has faces that cannot be read).
fn read_file(path: &Path) -> Result<(PointCloud, Option<Result<TriMesh, ReadError>>), ReadError> {
    let format = Format::from_path(path).ok_or_else(|| ReadError::UnsupportedExtension {
        path: path.to_path_buf(),
        extension: path.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default(),
    })?;
    let bytes = std::fs::read(path).map_err(|source| ReadError::Io { path: path.to_path_buf(), source })?;
    match format {
        Format::Ply => {
            let data = ply::parse(&bytes).map_err(|source| ReadError::Ply { path: path.to_path_buf(), source })?;
            let mesh = data.triangles.as_ref().filter(|t| !t.is_empty()).map(|t| {
                Ok(TriMesh {
                    vertices: data.points.clone(),
                    triangles: t.clone(),
                    vertex_labels: data.vertex_labels.clone(),
                    face_labels: data.face_labels.clone(),
                })
            });
            Ok((data.into_cloud(), mesh))
        }
        Format::Obj => {
            let points =
                obj::parse_points(&bytes).map_err(|source| ReadError::Obj { path: path.to_path_buf(), source })?;
            let mesh = obj_has_faces(&bytes).then(|| {
                obj::parse(&bytes).map(|(m, _)| m).map_err(|source| ReadError::Obj { path: path.to_path_buf(), source })
            });
            Ok((PointCloud::new(points), mesh))
        }
    }
}

/// Runs `info`.
pub fn run(a: Args) -> Result<(), CliError> {
    if let Some(out) = &a.repair {
        check_outputs(&[Output::file("--repair", out)], a.force)?;
    }
    let (cloud, mesh) = read_file(&a.file)?;
    let (mesh, mesh_error) = match mesh {
        Some(Ok(m)) if m.n_triangles() > 0 => (Some(m), None),
        Some(Err(e)) => (None, Some(e)),
        _ => (None, None),
    };
    let bbox = Aabb::of_points(&cloud.points);
    let mut json = serde_json::json!({
        "file": a.file.display().to_string(),
        "points": cloud.len(),
        "normals": cloud.normals.is_some(),
        "colors": cloud.colors.is_some(),
        "bounding_box_m": bbox.map(|b| serde_json::json!({"min": b.min, "max": b.max, "extent": b.extent()})),
        "vertex_labels": cloud.labels.as_deref().map(label_counts),
    });
    if !a.json {
        say!("{}: {} vertices/points", a.file.display(), cloud.len());
        say!("  normals: {}, colours: {}", cloud.normals.is_some(), cloud.colors.is_some());
        if let Some(b) = bbox {
            let e = b.extent();
            say!(
                "  bounding box: min {:.4?} max {:.4?} (extent {:.3} x {:.3} x {:.3} m)",
                b.min,
                b.max,
                e[0],
                e[1],
                e[2]
            );
            if bsv_core::geometry::looks_like_millimetres(e.iter().fold(0.0f64, |m, v| m.max(*v))) {
                say!(
                    "  note: larger than {} m: is it in millimetres? BSV expects metres",
                    bsv_core::geometry::MAX_EXTENT_M
                );
            }
        }
        match cloud.labels.as_deref() {
            Some(l) => {
                say!("  labels:");
                for (name, c) in label_counts(l) {
                    say!("    {name:<12} {c:>9}");
                }
            }
            None => say!("  labels: none"),
        }
    }
    if let Some(e) = &mesh_error {
        json["mesh_error"] = e.to_string().into();
        if !a.json {
            say!("  faces: present but unreadable, showing the vertices only: {e}");
        }
    }
    if let Some(mut m) = mesh {
        let report = check_mesh(&m);
        json["mesh"] = serde_json::to_value(&report)?;
        if let Some(fl) = m.face_labels.as_deref() {
            json["face_labels"] = serde_json::to_value(label_counts(fl))?;
        }
        if !a.json {
            say!("{report}");
        }
        if let Some(out) = &a.repair {
            let log = repair_mesh(&mut m);
            io::write_mesh(out, &m)?;
            json["repair"] = serde_json::to_value(&log)?;
            if !a.json {
                say!("{log}");
                say!("repaired mesh written to {}", out.display());
            }
        }
    } else if a.repair.is_some() {
        if let Some(e) = mesh_error {
            return Err(e.into());
        }
        return Err(format!("{} has no faces: only meshes can be repaired", a.file.display()).into());
    }
    if a.json {
        say!("{}", serde_json::to_string_pretty(&json)?);
    }
    Ok(())
}
