//! Reproducibility: the fitted mesh and the log are bit-identical for any thread count and from
//! run to run (issue 14).

#![allow(clippy::unwrap_used)]

use bsv_capture::scanner::{scan, Condition, Rig};
use bsv_core::template::{template, TemplateKind};
use bsv_core::{PointCloud, TriMesh};
use bsv_register::{register, ControlFlow, IterationLog, RegisterParams, Registration};

/// The default template and the noisy scan of a slightly wider body (the template scaled by 1.04
/// across and 1.01 in height about its centroid), so the fit has work to do.
fn body() -> (TriMesh, PointCloud) {
    let t = template(TemplateKind::Default).unwrap();
    let n = t.vertices.len() as f64;
    let c = (0..3).map(|k| t.vertices.iter().map(|p| p[k]).sum::<f64>() / n).collect::<Vec<_>>();
    let mut truth = t.clone();
    for p in &mut truth.vertices {
        let s = [1.04, 1.01, 1.04];
        for k in 0..3 {
            p[k] = c[k] + (p[k] - c[k]) * s[k];
        }
    }
    let s = scan(&truth, &Rig::paper_default(), Condition::L5Ca, 3).unwrap();
    (t, s.cloud)
}

fn run(t: &TriMesh, cloud: &PointCloud, threads: usize) -> Registration {
    let params = RegisterParams { threads, ..Default::default() };
    register(t, cloud, &params, &mut |_: &IterationLog| ControlFlow::Continue(())).unwrap()
}

fn bits(reg: &Registration) -> Vec<[u64; 3]> {
    reg.mesh.vertices.iter().map(|p| p.map(f64::to_bits)).collect()
}

/// The numbers of the log that the fit computes (not the timings), as bits.
fn log_bits(reg: &Registration) -> Vec<[u64; 7]> {
    reg.log
        .iter()
        .map(|l| {
            [
                l.energy_start.to_bits(),
                l.energy_after_local.to_bits(),
                l.energy.arap.to_bits(),
                l.energy.reg.to_bits(),
                l.energy.data.to_bits(),
                l.rms_mesh_to_points_mm.to_bits(),
                l.rms_points_to_mesh_mm.unwrap_or(-1.0).to_bits(),
            ]
        })
        .collect()
}

#[test]
fn fitted_vertices_are_bit_identical_for_any_thread_count() {
    let (t, cloud) = body();
    let one = run(&t, &cloud, 1);
    let reference = bits(&one);
    let log = log_bits(&one);
    for threads in [2, 3, 3, 1] {
        let reg = run(&t, &cloud, threads);
        let b = bits(&reg);
        let differ = reference.iter().zip(&b).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "{threads} threads: {differ} of {} vertices differ from 1 thread", b.len());
        assert_eq!(log, log_bits(&reg), "{threads} threads: the log differs from 1 thread");
        assert_eq!(one.rms_mesh_to_points_mm.to_bits(), reg.rms_mesh_to_points_mm.to_bits());
        assert_eq!(one.rms_points_to_mesh_mm.to_bits(), reg.rms_points_to_mesh_mm.to_bits());
        assert_eq!(one.mesh.vertex_labels, reg.mesh.vertex_labels);
    }
}
