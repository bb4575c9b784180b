//! The warm-started p2m walk (`p2m_warm_start`, `walk.rs`) against the exact k-d tree search on a
//! labelled body: the same fit within the correspondences' jitter.

#![allow(clippy::unwrap_used)]

mod common;

use bsv_capture::scanner::{scan, Condition, Rig};
use bsv_core::template::{template, TemplateKind};
use bsv_register::RegisterParams;
use common::{rel_pct, run, volume};

#[test]
fn the_walk_fits_a_labelled_body_like_the_exact_search() {
    let t = template(TemplateKind::Default).unwrap();
    // A body wider than the template (x 1.05 across, x 1.02 in height), scanned with L515-like noise:
    // the p2m stage has to move the vertices by millimetres.
    let n = t.vertices.len() as f64;
    let c: Vec<f64> = (0..3).map(|k| t.vertices.iter().map(|p| p[k]).sum::<f64>() / n).collect();
    let mut truth = t.clone();
    for p in &mut truth.vertices {
        let s = [1.05, 1.02, 1.05];
        for k in 0..3 {
            p[k] = c[k] + (p[k] - c[k]) * s[k];
        }
    }
    let cloud = scan(&truth, &Rig::paper_default(), Condition::L515, 5).unwrap().cloud;
    assert!(cloud.labels.is_some(), "the scan is labelled, so the walk is label-restricted");
    let walk = run(&t, &cloud, &RegisterParams::default());
    let exact = run(&t, &cloud, &RegisterParams { p2m_warm_start: false, ..Default::default() });
    let (vw, ve, vt) = (volume(&walk.mesh), volume(&exact.mesh), volume(&truth));
    assert!(rel_pct(vw, ve).abs() < 0.15, "volume {vw} (walk) against {ve} (exact), truth {vt}");
    let d2: f64 = walk
        .mesh
        .vertices
        .iter()
        .zip(&exact.mesh.vertices)
        .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>())
        .sum();
    let rms_mm = (d2 / n).sqrt() * 1e3;
    // The vertices slide along the surface between the two fits (measured 1.1 mm RMS, mostly
    // tangential: the volumes agree); a walk stopping at wrong vertices would move them by centimetres.
    assert!(rms_mm < 2.0, "the two fits differ by {rms_mm} mm RMS");
    let (rw, re) = (walk.rms_points_to_mesh_mm, exact.rms_points_to_mesh_mm);
    assert!((rw - re).abs() < 0.1 * re, "points-to-mesh RMS {rw} mm (walk) against {re} mm");
}
