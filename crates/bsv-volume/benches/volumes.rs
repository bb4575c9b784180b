//! Speed of the segment volumes (closing every segment with shared caps, divergence theorem) of a
//! labelled ~27k-triangle capsule body, against the whole mesh's single-pass signed volume (the floor
//! any volume costs, same mesh, same run). `cargo bench -p bsv-volume --bench volumes`.
#![allow(missing_docs, clippy::unwrap_used)]

use bsv_core::geometry::signed_volume;
use bsv_core::shapes;
use bsv_volume::{report, segment_volumes, DEFAULT_DENSITY_KG_M3};
use criterion::{criterion_group, criterion_main, Criterion};

fn volumes(c: &mut Criterion) {
    let mesh = shapes::capsule_body(true, false);
    let mut g = c.benchmark_group(format!("volumes_{}_triangles", mesh.triangles.len()));
    g.bench_function("segment_volumes", |b| b.iter(|| segment_volumes(&mesh).unwrap()));
    g.bench_function("report", |b| b.iter(|| report(&mesh, DEFAULT_DENSITY_KG_M3).unwrap()));
    g.bench_function("peer_whole_signed_volume", |b| b.iter(|| signed_volume(&mesh.vertices, &mesh.triangles)));
    g.finish();
}

criterion_group!(benches, volumes);
criterion_main!(benches);
