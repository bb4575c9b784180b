//! Registration benchmark: a 10,242-vertex template (icosphere level 5 scaled to a body-sized
//! ellipsoid) onto a 200k-point front/back cloud of another ellipsoid, the default schedule
//! ([`bsv_register::DEFAULT_SCHEDULE`], 16 iterations; 20 with the paper's until round 2 session 12).
//! Prints the time breakdown once, then lets criterion time the whole call.
#![allow(missing_docs)]

use bsv_capture::sample::sample_surface;
use bsv_core::geometry::face_normals;
use bsv_core::shapes::ellipsoid;
use bsv_core::PointCloud;
use bsv_register::{register, ControlFlow, IterationLog, RegisterParams};
use criterion::{criterion_group, criterion_main, Criterion};
use std::time::Duration;

fn setup() -> (bsv_core::TriMesh, PointCloud) {
    let template = ellipsoid([0.16, 0.85, 0.12], 5);
    let truth = ellipsoid([0.18, 0.88, 0.13], 6);
    let (points, faces) = sample_surface(&truth, 235_000, 9);
    let fnorm = face_normals(&truth);
    let mut cloud = PointCloud::new(points);
    cloud.normals = Some(faces.iter().map(|&f| fnorm[f as usize]).collect());
    let normals = cloud.normals.clone().unwrap_or_default();
    cloud.retain_indices(|i| normals[i][0].abs() <= 0.85);
    (template, cloud)
}

fn bench(c: &mut Criterion) {
    let (template, cloud) = setup();
    let params = RegisterParams::default();
    let mut sink = |_: &IterationLog| ControlFlow::Continue(());
    let reg = register(&template, &cloud, &params, &mut sink).expect("registration");
    let n = reg.log.len() as f64;
    let sum = |f: &dyn Fn(&IterationLog) -> f64| reg.log.iter().map(f).sum::<f64>();
    let (corr, local, solve) = (sum(&|l| l.timings.correspond), sum(&|l| l.timings.local), sum(&|l| l.timings.solve));
    println!(
        "template {} vertices, cloud {} points, {} iterations, threads {}",
        template.n_vertices(),
        cloud.len(),
        reg.log.len(),
        rayon::current_num_threads()
    );
    println!("setup {:.1} ms, total {:.1} ms", reg.setup_seconds * 1e3, reg.total_seconds * 1e3);
    println!(
        "per iteration: correspond {:.1} ms, local {:.1} ms, solve {:.1} ms, all {:.1} ms",
        corr / n * 1e3,
        local / n * 1e3,
        solve / n * 1e3,
        (corr + local + solve) / n * 1e3
    );
    for l in &reg.log {
        println!(
            "  it {:2} {} corr {:5.1} local {:5.1} solve {:5.1} ms refactor {} rms m2p {:.2} mm",
            l.iteration,
            l.kind,
            l.timings.correspond * 1e3,
            l.timings.local * 1e3,
            l.timings.solve * 1e3,
            l.refactorized,
            l.rms_mesh_to_points_mm
        );
    }
    let mut g = c.benchmark_group("register");
    g.sample_size(10).measurement_time(Duration::from_secs(8)).warm_up_time(Duration::from_secs(1));
    g.bench_function("10k_template_200k_cloud_default_schedule", |b| {
        b.iter(|| {
            register(&template, &cloud, &params, &mut |_: &IterationLog| ControlFlow::Continue(()))
                .expect("registration")
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
