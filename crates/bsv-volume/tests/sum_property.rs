//! Property test: with random labels, segment volumes always add up to the whole volume.
#![allow(clippy::unwrap_used)]

use bsv_core::shapes::{icosphere, subdivided_cuboid};
use bsv_core::TriMesh;
use bsv_volume::{segment_volumes, volumes_by_label};
use proptest::prelude::*;
use std::sync::OnceLock;

fn sphere() -> &'static TriMesh {
    static M: OnceLock<TriMesh> = OnceLock::new();
    M.get_or_init(|| icosphere(0.3, 2))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Random vertex labels (ids 0..=14, from a few distinct values), face labels by majority.
    #[test]
    fn random_vertex_labels_sum_to_whole(
        k in 2u8..8,
        seeds in proptest::collection::vec(any::<u8>(), 162),
    ) {
        let mut m = sphere().clone();
        prop_assert_eq!(m.n_vertices(), seeds.len());
        m.vertex_labels = Some(seeds.iter().map(|s| s % k).collect());
        let sv = segment_volumes(&m).unwrap();
        let sum: f64 = sv.segments.values().sum::<f64>() + sv.unlabelled_m3.unwrap_or(0.0);
        prop_assert!((sum - sv.whole_m3).abs() <= 1e-12 * sv.whole_m3, "{} vs {}", sum, sv.whole_m3);
    }

    /// Random face labels (any u8) on a subdivided box: fully scattered patches and pinch points.
    #[test]
    fn random_face_labels_sum_to_whole(labels in proptest::collection::vec(0u8..5, 6 * 2 * 9)) {
        let m = subdivided_cuboid([0.3, 0.2, 0.1], 3);
        prop_assert_eq!(m.n_triangles(), labels.len());
        let lv = volumes_by_label(&m, &labels).unwrap();
        let sum: f64 = lv.by_label.iter().map(|x| x.1).sum();
        prop_assert!((sum - lv.whole_m3).abs() <= 1e-12 * lv.whole_m3, "{} vs {}", sum, lv.whole_m3);
        prop_assert!((lv.whole_m3 - 0.006).abs() < 1e-15);
    }
}
