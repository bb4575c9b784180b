//! Reproducibility (issue 14): the scanner and cloud building give bit-identical results for any
//! thread count (run in rayon pools of 1, 2 and 3 threads).

#![allow(clippy::unwrap_used)]

use bsv_capture::fuse::{build_cloud, DepthView, FuseParams};
use bsv_capture::scanner::{scan, spill_labels, Condition, Rig, Room};
use bsv_core::template::{template, TemplateKind};
use bsv_core::PointCloud;

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(f)
}

type Bits = (Vec<[u64; 3]>, Option<Vec<[u64; 3]>>, Option<Vec<u8>>, Option<Vec<[u8; 3]>>);

fn bits(c: &PointCloud) -> Bits {
    let b = |v: &[[f64; 3]]| v.iter().map(|p| p.map(f64::to_bits)).collect::<Vec<_>>();
    (b(&c.points), c.normals.as_deref().map(b), c.labels.clone(), c.colors.clone())
}

#[test]
fn scan_and_build_cloud_are_bit_identical_for_any_thread_count() {
    let body = template(TemplateKind::Default).unwrap();
    let mut rig = Rig::paper_default();
    rig.room = Some(Room::default());
    let params = FuseParams { sor: true, ..FuseParams::default() };
    let run = |threads: usize| {
        in_pool(threads, || {
            let s = scan(&body, &rig, Condition::L5Ca, 11).unwrap();
            let views: Vec<DepthView> = s
                .views
                .iter()
                .map(|v| {
                    let (w, h) = (v.intrinsics.width as usize, v.intrinsics.height as usize);
                    DepthView { labels: spill_labels(&v.labels, w, h, 3), ..v.depth_view() }
                })
                .collect();
            let (cloud, report) = build_cloud(&views, &params).unwrap();
            let removed: Vec<usize> = report.views.iter().map(|r| r.cleaning.removed()).collect();
            (bits(&s.cloud), bits(&cloud), removed)
        })
    };
    let one = run(1);
    assert!(one.1 .0.len() > 10_000, "{} points", one.1 .0.len());
    for threads in [2, 3] {
        let other = run(threads);
        assert!(one.0 == other.0, "scan: {threads} threads differ from 1");
        assert!(one.1 == other.1, "build_cloud: {threads} threads differ from 1");
        assert_eq!(one.2, other.2, "cleaning counts: {threads} threads differ from 1");
    }
}
