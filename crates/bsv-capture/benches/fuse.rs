//! Cost of "only the person" in cloud building: both 768 x 1024 views of the MakeHuman body scanned
//! standing in a room (floor and wall), the masks dilated by 4 pixels like MediaPipe's spill; cloud
//! building without cleaning, with floor removal only, and with floor removal and person isolation
//! (the default), SOR off as in `bsv process`. `cargo bench -p bsv-capture --bench fuse`.
#![allow(missing_docs, clippy::unwrap_used)]

use bsv_capture::fuse::{build_cloud, DepthView, FuseParams};
use bsv_capture::scanner::{scan, spill_labels, Condition, Rig};
use bsv_core::shapes::append_labelled;
use bsv_core::template::{template, TemplateKind};
use bsv_core::TriMesh;
use criterion::{criterion_group, criterion_main, Criterion};
use std::time::Duration;

fn quad(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> TriMesh {
    TriMesh::new(vec![a, b, c, d], vec![[0, 1, 2], [0, 2, 3]])
}

fn only_the_person(c: &mut Criterion) {
    let mut mesh = template(TemplateKind::Full).unwrap();
    append_labelled(&mut mesh, quad([-3.0, 0.0, -2.6], [3.0, 0.0, -2.6], [3.0, 0.0, 4.0], [-3.0, 0.0, 4.0]), 0);
    append_labelled(&mut mesh, quad([-3.0, 0.0, -2.6], [3.0, 0.0, -2.6], [3.0, 3.0, -2.6], [-3.0, 3.0, -2.6]), 0);
    let s = scan(&mesh, &Rig::paper_default(), Condition::L515, 1).unwrap();
    let views: Vec<DepthView> = s
        .views
        .iter()
        .map(|v| {
            let (w, h) = (v.intrinsics.width as usize, v.intrinsics.height as usize);
            DepthView { labels: spill_labels(&v.labels, w, h, 4), ..v.depth_view() }
        })
        .collect();
    let base = FuseParams { sor: false, ..FuseParams::default() };
    let mut g = c.benchmark_group("build_cloud_two_768x1024_views_in_a_room");
    g.sample_size(20).measurement_time(Duration::from_secs(6));
    for (name, p) in [
        ("no_cleaning", FuseParams { remove_floor: false, isolate_person: false, ..base.clone() }),
        ("floor_only", FuseParams { isolate_person: false, ..base.clone() }),
        ("only_the_person_default", base.clone()),
    ] {
        g.bench_function(name, |b| b.iter(|| build_cloud(&views, &p).unwrap()));
    }
    g.finish();
}

criterion_group!(benches, only_the_person);
criterion_main!(benches);
