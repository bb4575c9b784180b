//! Label conversions (tie rules) and the merging of small label islands.
#![allow(clippy::unwrap_used)]

use bsv_core::geometry::{add, scale};
use bsv_core::shapes::{icosphere, subdivided_cuboid};
use bsv_core::{Segment, TriMesh};
use bsv_volume::{
    face_labels_from_vertices, merge_small_islands, segment_volumes_with, vertex_labels_from_faces, IslandOptions,
    SegmentOptions,
};

#[test]
fn face_labels_majority_and_tie_rule() {
    let tris = [[0, 1, 2], [3, 1, 2], [4, 5, 0], [5, 0, 4], [2, 4, 0]];
    let vl = [7, 7, 3, 3, 9, 1];
    // [7,7,3] -> 7; [3,7,3] -> 3; [9,1,7] all differ -> corner with smallest index (0) -> 7;
    // [1,7,9] -> same vertices, other order -> still vertex 0 -> 7; [3,9,7] -> vertex 0 -> 7.
    assert_eq!(face_labels_from_vertices(&tris, &vl), vec![7, 3, 7, 7, 7]);
    let tris2 = [[5, 4, 3]];
    // [1, 9, 3]: smallest vertex index is 3 -> label 3, whatever the corner order.
    assert_eq!(face_labels_from_vertices(&tris2, &vl), vec![3]);
    assert_eq!(face_labels_from_vertices(&[[3, 5, 4]], &vl), vec![3]);
    // Out-of-range corner -> 0.
    assert_eq!(face_labels_from_vertices(&[[0, 1, 60]], &vl), vec![0]);
}

#[test]
fn vertex_labels_majority_and_tie_rule() {
    // Vertex 0 is in 4 faces: labels 5, 5, 2, 2 -> tie -> smallest id 2.
    let tris = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]];
    let fl = [5, 5, 2, 2];
    let vl = vertex_labels_from_faces(6, &tris, &fl);
    assert_eq!(vl[0], 2);
    assert_eq!(vl[1], 2); // faces 0 (5) and 3 (2) -> tie -> 2
    assert_eq!(vl[2], 5); // faces 0, 1 -> 5
    assert_eq!(vl[3], 2); // faces 1 (5), 2 (2) -> 2
    assert_eq!(vl[5], 0); // unused
                          // Round trip on a cleanly labelled box keeps the face labels.
    let m = subdivided_cuboid([1.0, 1.0, 1.0], 6);
    let fl: Vec<u8> = (0..m.n_triangles()).map(|t| if centroid(&m, t)[1] < 0.0 { 2 } else { 9 }).collect();
    let vl = vertex_labels_from_faces(m.n_vertices(), &m.triangles, &fl);
    let back = face_labels_from_vertices(&m.triangles, &vl);
    let differ = fl.iter().zip(&back).filter(|(a, b)| a != b).count();
    assert!(differ <= fl.len() / 10, "{differ}");
}

fn centroid(m: &TriMesh, t: usize) -> [f64; 3] {
    let [a, b, c] = m.triangle_points(t);
    scale(add(add(a, b), c), 1.0 / 3.0)
}

/// Sphere split into two halves, with speckles of a third label and of each other's label.
fn speckled_sphere() -> (TriMesh, Vec<u8>, Vec<u8>) {
    let m = icosphere(1.0, 3);
    let clean: Vec<u8> = (0..m.n_triangles()).map(|t| if centroid(&m, t)[1] < 0.0 { 9 } else { 2 }).collect();
    let mut noisy = clean.clone();
    for t in (0..m.n_triangles()).step_by(97) {
        noisy[t] = if t % 2 == 0 {
            5
        } else if noisy[t] == 2 {
            9
        } else {
            2
        };
    }
    (m, clean, noisy)
}

#[test]
fn small_islands_are_merged_into_their_surroundings() {
    let (m, clean, mut noisy) = speckled_sphere();
    let changed = clean.iter().zip(&noisy).filter(|(a, b)| a != b).count();
    assert!(changed >= 10);
    let opts = IslandOptions { min_faces: 10, min_area_m2: 0.0, keep_largest: true };
    let rep = merge_small_islands(&m, &mut noisy, &opts);
    // Every speckle was merged back, except the largest patch of label 5 (kept on purpose).
    let fives = noisy.iter().filter(|&&l| l == 5).count();
    assert_eq!(fives, 1, "one protected patch of label 5 remains");
    let wrong = clean.iter().zip(&noisy).filter(|(a, b)| a != b).count();
    assert_eq!(wrong, 1);
    assert_eq!(rep.merged_islands, changed - 1);
    assert_eq!(rep.relabelled_faces, changed - 1);
    // Without protection, label 5 disappears entirely.
    let (_, clean, mut noisy) = speckled_sphere();
    let opts = IslandOptions { min_faces: 10, min_area_m2: 0.0, keep_largest: false };
    merge_small_islands(&m, &mut noisy, &opts);
    assert_eq!(noisy, clean);
}

#[test]
fn island_merging_by_area_and_determinism() {
    let (m, clean, noisy) = speckled_sphere();
    let area_per_face = 4.0 * std::f64::consts::PI / m.n_triangles() as f64;
    let opts = IslandOptions { min_faces: 0, min_area_m2: 3.0 * area_per_face, keep_largest: false };
    let mut a = noisy.clone();
    merge_small_islands(&m, &mut a, &opts);
    assert_eq!(a, clean);
    let mut b = noisy.clone();
    merge_small_islands(&m, &mut b, &opts);
    assert_eq!(a, b);
    // Disabled thresholds change nothing.
    let mut c = noisy.clone();
    let rep = merge_small_islands(&m, &mut c, &IslandOptions { min_faces: 0, min_area_m2: 0.0, keep_largest: true });
    assert_eq!((c, rep.merged_islands), (noisy, 0));
}

#[test]
fn segment_volumes_can_merge_islands_first() {
    let (mut m, clean, noisy) = speckled_sphere();
    m.face_labels = Some(clean);
    let reference = segment_volumes_with(&m, &SegmentOptions::default()).unwrap();
    m.face_labels = Some(noisy);
    let raw = segment_volumes_with(&m, &SegmentOptions::default()).unwrap();
    assert!(raw.get(Segment::ForearmL).is_some());
    let opts = SegmentOptions {
        close_holes: false,
        islands: Some(IslandOptions { keep_largest: false, ..Default::default() }),
    };
    let merged = segment_volumes_with(&m, &opts).unwrap();
    assert_eq!(merged.get(Segment::ForearmL), None);
    assert_eq!(merged.segments, reference.segments);
    assert!(merged.islands.unwrap().merged_islands > 0);
}
