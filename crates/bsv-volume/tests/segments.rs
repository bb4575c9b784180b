//! Segment volumes: exact parts of planar cuts, the sum property (two segments, three bands, triple
#![allow(clippy::unwrap_used)]
//! junctions, unlabelled faces, closed holes), label sources and absent segments.

use bsv_core::geometry::{add, scale};
use bsv_core::shapes::{capsule, icosphere, subdivided_cuboid};
use bsv_core::{Segment, TriMesh};
use bsv_volume::{closed_volume, segment_volumes, segment_volumes_with, LabelSource, SegmentOptions};
use std::f64::consts::PI;

fn centroid(m: &TriMesh, t: usize) -> [f64; 3] {
    let [a, b, c] = m.triangle_points(t);
    scale(add(add(a, b), c), 1.0 / 3.0)
}

fn label_faces(m: &mut TriMesh, f: impl Fn([f64; 3]) -> Segment) {
    let labels = (0..m.n_triangles()).map(|t| f(centroid(m, t)).id()).collect();
    m.face_labels = Some(labels);
}

fn sum_of_parts(sv: &bsv_volume::SegmentVolumes) -> f64 {
    sv.segments.values().sum::<f64>() + sv.unlabelled_m3.unwrap_or(0.0)
}

#[test]
fn box_split_by_a_plane_gives_exact_halves() {
    let mut m = subdivided_cuboid([1.0, 0.6, 0.4], 10);
    label_faces(&mut m, |c| if c[0] < 0.1 { Segment::Torso } else { Segment::ThighL });
    let sv = segment_volumes(&m).unwrap();
    let left = sv.get(Segment::Torso).unwrap();
    let right = sv.get(Segment::ThighL).unwrap();
    assert!((left - 0.6 * 0.6 * 0.4).abs() < 1e-12, "{left}");
    assert!((right - 0.4 * 0.6 * 0.4).abs() < 1e-12, "{right}");
    assert!((left + right - sv.whole_m3).abs() < 1e-14);
    assert!((sv.whole_m3 - 0.24).abs() < 1e-12);
    assert_eq!(sv.segments.len(), 2);
    assert_eq!(sv.caps.closed_loops, 1);
    assert_eq!(sv.caps.junctions, 0);
}

#[test]
fn box_in_three_parts_with_two_triple_points_is_exact() {
    // x < 0: torso; x > 0 and y < 0: thigh_l; x > 0 and y > 0: thigh_r. The cuts meet on the z axis,
    // which crosses the surface at two triple points.
    let mut m = subdivided_cuboid([1.0, 1.0, 1.0], 10);
    label_faces(&mut m, |c| {
        if c[0] < 0.0 {
            Segment::Torso
        } else if c[1] < 0.0 {
            Segment::ThighL
        } else {
            Segment::ThighR
        }
    });
    let sv = segment_volumes(&m).unwrap();
    assert!((sv.get(Segment::Torso).unwrap() - 0.5).abs() < 1e-12);
    assert!((sv.get(Segment::ThighL).unwrap() - 0.25).abs() < 1e-12);
    assert!((sv.get(Segment::ThighR).unwrap() - 0.25).abs() < 1e-12);
    assert!((sum_of_parts(&sv) - sv.whole_m3).abs() < 1e-14);
    assert_eq!(sv.caps.junctions, 2);
    assert_eq!(sv.caps.open_pieces, 3);
    assert_eq!(sv.caps.clusters, 1);
}

#[test]
fn capsule_limb_in_three_bands() {
    let (r, len, n) = (0.05, 0.4, 48);
    let mut m = capsule(r, len, n, 12, 8);
    label_faces(&mut m, |c| {
        if c[1] < 0.15 {
            Segment::ShinL
        } else if c[1] < 0.3 {
            Segment::ThighL
        } else {
            Segment::Torso
        }
    });
    let sv = segment_volumes(&m).unwrap();
    let whole = closed_volume(&m).unwrap();
    assert!((sv.whole_m3 - whole).abs() < 1e-15);
    assert!((sum_of_parts(&sv) - whole).abs() < 1e-12 * whole);
    // The middle band is a prism over the regular 48-gon: exact.
    let polygon = 0.5 * n as f64 * r * r * (2.0 * PI / n as f64).sin();
    let thigh = sv.get(Segment::ThighL).unwrap();
    assert!((thigh - polygon * 0.15).abs() < 1e-12 * thigh, "{thigh} vs {}", polygon * 0.15);
    // The end bands: hemisphere + cylinder piece, within the faceting error.
    let shin_exact = 2.0 / 3.0 * PI * r.powi(3) + PI * r * r * 0.15;
    let torso_exact = 2.0 / 3.0 * PI * r.powi(3) + PI * r * r * 0.1;
    let shin = sv.get(Segment::ShinL).unwrap();
    let torso = sv.get(Segment::Torso).unwrap();
    assert!((shin - shin_exact).abs() / shin_exact < 0.01, "{shin} vs {shin_exact}");
    assert!((torso - torso_exact).abs() / torso_exact < 0.01, "{torso} vs {torso_exact}");
    assert_eq!(sv.caps.closed_loops, 2);
}

#[test]
fn three_sectors_of_a_sphere_sum_to_the_whole() {
    let mut m = icosphere(0.2, 4);
    label_faces(&mut m, |c| {
        let a = c[2].atan2(c[0]).rem_euclid(2.0 * PI);
        if a < 2.0 * PI / 3.0 {
            Segment::Torso
        } else if a < 4.0 * PI / 3.0 {
            Segment::UpperArmL
        } else {
            Segment::ForearmL
        }
    });
    let sv = segment_volumes(&m).unwrap();
    assert_eq!(sv.segments.len(), 3);
    assert!((sum_of_parts(&sv) - sv.whole_m3).abs() < 1e-12 * sv.whole_m3);
    assert!(sv.caps.junctions >= 2, "{:?}", sv.caps);
    for v in sv.segments.values() {
        assert!((v / sv.whole_m3 - 1.0 / 3.0).abs() < 0.01, "{v} of {}", sv.whole_m3);
    }
}

#[test]
fn unlabelled_faces_count_in_whole_only_and_absent_segments_are_absent() {
    let mut m = subdivided_cuboid([1.0, 1.0, 1.0], 10);
    label_faces(&mut m, |c| if c[1] < 0.0 { Segment::Torso } else { Segment::Unlabelled });
    let sv = segment_volumes(&m).unwrap();
    assert_eq!(sv.segments.keys().copied().collect::<Vec<_>>(), vec![Segment::Torso]);
    assert!((sv.get(Segment::Torso).unwrap() - 0.5).abs() < 1e-12);
    assert!((sv.unlabelled_m3.unwrap() - 0.5).abs() < 1e-12);
    assert!((sv.whole_m3 - 1.0).abs() < 1e-12);
    assert_eq!(sv.get(Segment::Head), None);
    assert!(sv.notes.iter().any(|n| n.contains("unlabelled")));
}

#[test]
fn vertex_labels_are_used_when_there_are_no_face_labels() {
    let mut m = subdivided_cuboid([1.0, 0.6, 0.4], 10);
    let vl = m.vertices.iter().map(|p| if p[0] < 0.05 { Segment::Torso.id() } else { Segment::ThighR.id() }).collect();
    m.vertex_labels = Some(vl);
    let sv = segment_volumes(&m).unwrap();
    assert_eq!(sv.label_source, LabelSource::Vertices);
    assert_eq!(sv.segments.len(), 2);
    assert!((sum_of_parts(&sv) - 0.24).abs() < 1e-12);
    // Faces straddling the cut x in [0, 0.1] have 2 of 3 corners on one side: the cut zigzags, so
    // the parts are near (not exactly) 0.55 and 0.45 of the box.
    let t = sv.get(Segment::Torso).unwrap();
    assert!(t > 0.5 * 0.24 && t < 0.6 * 0.24, "{t}");
}

#[test]
fn no_labels_give_only_the_whole_with_a_note() {
    let m = icosphere(1.0, 2);
    let sv = segment_volumes(&m).unwrap();
    assert_eq!(sv.label_source, LabelSource::None);
    assert!(sv.segments.is_empty());
    assert_eq!(sv.unlabelled_m3, None);
    assert!(sv.whole_m3 > 4.0);
    assert!(sv.notes.iter().any(|n| n.contains("no segment labels")));
}

#[test]
fn open_tube_closed_and_labelled_sums_to_its_closed_volume() {
    // A capsule with both hemispheres cut off: an open tube whose end holes take the band labels.
    let mut m = capsule(0.05, 0.4, 32, 6, 8);
    let keep: Vec<usize> = (0..m.n_triangles())
        .filter(|&t| m.triangle_points(t).iter().all(|p| p[1] > -1e-12 && p[1] < 0.4 + 1e-12))
        .collect();
    m.triangles = keep.iter().map(|&t| m.triangles[t]).collect();
    label_faces(&mut m, |c| if c[1] < 0.2 { Segment::ShinR } else { Segment::ThighR });
    assert!(segment_volumes(&m).is_err());
    let sv = segment_volumes_with(&m, &SegmentOptions { close_holes: true, islands: None }).unwrap();
    assert_eq!(sv.holes.len(), 2);
    let polygon = 0.5 * 32.0 * 0.05 * 0.05 * (2.0 * PI / 32.0).sin();
    assert!((sv.whole_m3 - polygon * 0.4).abs() < 1e-12 * sv.whole_m3);
    assert!((sv.get(Segment::ShinR).unwrap() - polygon * 0.2).abs() < 1e-12 * sv.whole_m3);
    assert!((sv.get(Segment::ThighR).unwrap() - polygon * 0.2).abs() < 1e-12 * sv.whole_m3);
}

#[test]
fn segment_volumes_of_a_30k_triangle_mesh_sum_exactly() {
    let mut m = capsule(0.1, 0.8, 160, 30, 35);
    assert!(m.n_triangles() > 20_000, "{}", m.n_triangles());
    label_faces(&mut m, |c| {
        let bands = [Segment::ShinL, Segment::ThighL, Segment::Torso, Segment::UpperArmL, Segment::ForearmL];
        let k = ((c[1] + 0.1) / 0.2).floor().clamp(0.0, 4.0) as usize;
        bands[k]
    });
    // Speed is measured by `cargo bench -p bsv-volume --bench volumes` (not asserted here).
    let sv = segment_volumes(&m).unwrap();
    assert_eq!(sv.segments.len(), 5);
    assert!((sum_of_parts(&sv) - sv.whole_m3).abs() < 1e-12 * sv.whole_m3);
}
