//! Speed of the capture side: the virtual two-camera scan of a ~27k-triangle labelled body (each
//! condition, and l515 inside the clinic room), the paper's statistical outlier removal (k = 600,
//! std ratio 0.05) on a camera view and on 300k surface samples, and the bounded-radius k-NN mean distances against the plain kiddo
//! `nearest_n` query (the peer, same points, same run). `cargo bench -p bsv-capture --bench scan`.
#![allow(missing_docs, clippy::unwrap_used)]

use bsv_capture::clean::{mean_knn_distances, mean_knn_distances_naive, statistical_outliers, SorParams};
use bsv_capture::sample::sample_surface;
use bsv_capture::scanner::{scan, Condition, Rig, Room};
use bsv_core::shapes;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::time::Duration;

fn scans(c: &mut Criterion) {
    let mesh = shapes::capsule_body(true, false);
    let rig = Rig::paper_default();
    let mut g = c.benchmark_group("scan_two_cameras_768x1024");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    for cond in Condition::ALL {
        g.bench_function(BenchmarkId::from_parameter(cond.name()), |b| b.iter(|| scan(&mesh, &rig, cond, 1).unwrap()));
    }
    // The same rig inside the clinic room: a second BVH per ray and the room's pixels in the noise.
    let roomed = Rig::paper_default().with_room(Room::clinic());
    g.bench_function(BenchmarkId::from_parameter("l515_room"), |b| {
        b.iter(|| scan(&mesh, &roomed, Condition::L515, 1).unwrap())
    });
    g.finish();
}

fn sor(c: &mut Criterion) {
    let mesh = shapes::capsule_body(true, false);
    let s = scan(&mesh, &Rig::paper_default(), Condition::L515, 1).unwrap();
    let view = s.cloud.points[s.views[0].cloud_range.clone()].to_vec();
    let mut ell = shapes::ellipsoid([0.2, 0.85, 0.14], 6);
    shapes::translate(&mut ell, [0.0, 0.9, 0.0]);
    let (points, _) = sample_surface(&ell, 300_000, 1);
    let mut g = c.benchmark_group("sor_k600");
    g.sample_size(10).measurement_time(Duration::from_secs(10));
    g.bench_function(format!("l515_front_view_{}_pts", view.len()), |b| {
        b.iter(|| statistical_outliers(&view, SorParams::default()).unwrap())
    });
    g.bench_function("surface_300k_pts", |b| b.iter(|| statistical_outliers(&points, SorParams::default()).unwrap()));
    g.finish();
}

fn knn_against_peer(c: &mut Criterion) {
    let mut ell = shapes::ellipsoid([0.2, 0.85, 0.14], 5);
    shapes::translate(&mut ell, [0.0, 0.9, 0.0]);
    let (points, _) = sample_surface(&ell, 30_000, 2);
    let mut g = c.benchmark_group("knn_mean_distances_k600_30k_pts");
    g.sample_size(10).measurement_time(Duration::from_secs(10));
    g.bench_function("bsv_bounded_radius", |b| b.iter(|| mean_knn_distances(&points, 600).unwrap()));
    g.bench_function("peer_kiddo_nearest_n", |b| b.iter(|| mean_knn_distances_naive(&points, 600).unwrap()));
    g.finish();
}

criterion_group!(benches, scans, sor, knn_against_peer);
criterion_main!(benches);
