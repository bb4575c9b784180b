//! Prints the volumes table and JSON of a synthetic labelled body made of capsules (torso, arms, legs).
//! Run: `cargo run -p bsv-volume --example volume_table`. (Speed: `cargo bench -p bsv-volume --bench volumes`.)

use bsv_core::geometry::{add, scale};
use bsv_core::shapes::{capsule, translate};
use bsv_core::{Segment, TriMesh};
use bsv_volume::{report, DEFAULT_DENSITY_KG_M3};

/// A capsule limb at `x` (vertical), split at `split` (height) into `lower` and `upper` segments.
#[allow(clippy::too_many_arguments)] // an example's plain helper: a parameter struct would only hide the shape
fn limb(
    m: &mut TriMesh,
    labels: &mut Vec<u8>,
    r: f64,
    len: f64,
    at: [f64; 3],
    split: f64,
    lower: Segment,
    upper: Segment,
) {
    let mut c = capsule(r, len, 64, 12, 24);
    translate(&mut c, at);
    let off = m.vertices.len() as u32;
    for t in &c.triangles {
        let p =
            scale(add(add(c.vertices[t[0] as usize], c.vertices[t[1] as usize]), c.vertices[t[2] as usize]), 1.0 / 3.0);
        labels.push(if p[1] < split { lower.id() } else { upper.id() });
    }
    m.vertices.extend(c.vertices);
    m.triangles.extend(c.triangles.iter().map(|t| t.map(|v| v + off)));
}

fn main() {
    let mut m = TriMesh::default();
    let mut labels = Vec::new();
    limb(&mut m, &mut labels, 0.15, 0.5, [0.0, 0.95, 0.0], 10.0, Segment::Torso, Segment::Torso);
    limb(&mut m, &mut labels, 0.065, 0.75, [0.1, 0.1, 0.0], 0.5, Segment::ShinL, Segment::ThighL);
    limb(&mut m, &mut labels, 0.063, 0.75, [-0.1, 0.1, 0.0], 0.5, Segment::ShinR, Segment::ThighR);
    limb(&mut m, &mut labels, 0.04, 0.5, [0.25, 0.9, 0.0], 1.15, Segment::ForearmL, Segment::UpperArmL);
    limb(&mut m, &mut labels, 0.041, 0.5, [-0.25, 0.9, 0.0], 1.15, Segment::ForearmR, Segment::UpperArmR);
    m.face_labels = Some(labels);
    match report(&m, DEFAULT_DENSITY_KG_M3) {
        Ok(r) => {
            println!("{r}");
            println!("{}", r.to_json());
        }
        Err(e) => eprintln!("error: {e}"),
    }
}
