//! Benchmark: virtual scan of a ~27k-triangle body-sized mesh (both cameras, each condition) and
//! statistical outlier removal of 300k points. Prints a table of medians of 5 runs.
//! Run: `cargo run -p bsv-capture --release --example scan_bench [-- --naive] [-- --images DIR]`.

#![allow(clippy::unwrap_used)]

use bsv_capture::clean::{mean_knn_distances, mean_knn_distances_naive, statistical_outliers, SorParams};
use bsv_capture::sample::sample_surface;
use bsv_capture::scanner::{scan, write_capture, Condition, Rig};
use bsv_core::shapes;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Process CPU time (user + system) in seconds, from /proc (Linux); 0 elsewhere.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = after.split_whitespace().collect();
    let tick = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (tick(11) + tick(12)) / 100.0
}

/// Median wall time of `runs` runs; also prints the mean CPU seconds per run (the machine is shared:
/// with 2 idle cores, wall ~ CPU / 2).
fn time<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut times = Vec::new();
    let mut last = None;
    let c0 = cpu_seconds();
    for _ in 0..runs {
        let t = Instant::now();
        last = Some(f());
        times.push(t.elapsed().as_secs_f64());
    }
    eprintln!("  (cpu {:.3} s per run)", (cpu_seconds() - c0) / runs as f64);
    (median(times), last.expect("runs >= 1"))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mesh = shapes::capsule_body(true, false);
    let rig = Rig::paper_default();
    println!("threads: {}", rayon::current_num_threads());
    println!("| step | size | median of 5 (s) |");
    println!("|---|---|---|");
    let sor_only = args.iter().any(|a| a == "--sor-only");
    for c in Condition::ALL.into_iter().filter(|_| !sor_only) {
        let (t, s) = time(5, || scan(&mesh, &rig, c, 1).expect("scan"));
        println!("| scan {c}, 2 cameras 768x1024 | {} tris -> {} pts | {t:.3} |", mesh.triangles.len(), s.cloud.len());
        if let Some(i) = args.iter().position(|a| a == "--images") {
            if let Some(dir) = args.get(i + 1) {
                write_capture(&s, &std::path::Path::new(dir).join(c.name())).expect("write");
            }
        }
    }
    if !sor_only {
        let s = scan(&mesh, &rig, Condition::L515, 1).expect("scan");
        let v = &s.views[0];
        let pts = &s.cloud.points[v.cloud_range.clone()];
        let (t, res) = time(5, || statistical_outliers(pts, SorParams::default()).expect("sor"));
        let kept = res.keep.iter().filter(|&&k| k).count();
        println!("| SOR k=600 std 0.05 on the l515 front view | {} pts (kept {kept}) | {t:.3} |", pts.len());
    }
    let mut ell = shapes::ellipsoid([0.2, 0.85, 0.14], 6);
    shapes::translate(&mut ell, [0.0, 0.9, 0.0]);
    let (points, _) = sample_surface(&ell, 300_000, 1);
    let (t, res) = time(5, || statistical_outliers(&points, SorParams::default()).expect("sor"));
    let kept = res.keep.iter().filter(|&&k| k).count();
    println!("| SOR k=600 std 0.05 (exact, bounded radius) | {} pts (kept {kept}) | {t:.3} |", points.len());
    let (t, res) = time(5, || statistical_outliers(&points, SorParams { k: 30, std_ratio: 1.0 }).expect("sor"));
    let kept = res.keep.iter().filter(|&&k| k).count();
    println!("| SOR k=30 std 1.0 | {} pts (kept {kept}) | {t:.3} |", points.len());
    for k in [1usize, 100, 300] {
        let (t, _) = time(3, || mean_knn_distances(&points, k).expect("knn"));
        println!("| k-NN mean distances k={k} | {} pts | {t:.3} |", points.len());
    }
    if args.iter().any(|a| a == "--naive") {
        let (t2, naive) = time(1, || mean_knn_distances_naive(&points, 600).expect("naive"));
        let fast = mean_knn_distances(&points, 600).expect("fast");
        let maxdiff = fast.iter().zip(&naive).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        println!(
            "| SOR k=600 plain kiddo nearest_n (1 run) | {} pts (max diff {maxdiff:.1e}) | {t2:.3} |",
            points.len()
        );
    }
}
