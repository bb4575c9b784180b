//! Prepared segment volumes: re-measuring a mesh at moved vertex positions gives what
//! `segment_volumes_with` gives on the moved mesh (scaled, rigidly moved, jittered, mirrored; with
//! junctions, unlabelled faces, island merging and closed holes), batches equal one-by-one results,
//! and a wrong vertex count is a typed error.
#![allow(clippy::unwrap_used)]

use bsv_core::geometry::{add, scale};
use bsv_core::shapes::{capsule, icosphere, subdivided_cuboid};
use bsv_core::{Segment, TriMesh};
use bsv_volume::{
    report_with, segment_volumes_with, IslandOptions, PreparedSegments, QuantityTable, SegmentOptions, SegmentVolumes,
    VolumeError,
};
use std::f64::consts::PI;

fn centroid(m: &TriMesh, t: usize) -> [f64; 3] {
    let [a, b, c] = m.triangle_points(t);
    scale(add(add(a, b), c), 1.0 / 3.0)
}

fn label_faces(m: &mut TriMesh, f: impl Fn([f64; 3]) -> u8) {
    let labels = (0..m.n_triangles()).map(|t| f(centroid(m, t))).collect();
    m.face_labels = Some(labels);
}

/// A deterministic generator of numbers in [-1, 1).
fn lcg(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// Sphere in three sectors about the y axis (two triple points at the poles, open pieces, a cluster).
fn sectors() -> TriMesh {
    let mut m = icosphere(0.2, 3);
    label_faces(&mut m, |c| {
        let a = c[2].atan2(c[0]).rem_euclid(2.0 * PI);
        if a < 2.0 * PI / 3.0 {
            Segment::Torso.id()
        } else if a < 4.0 * PI / 3.0 {
            Segment::UpperArmL.id()
        } else {
            Segment::ForearmL.id()
        }
    });
    m
}

/// Box in three parts with a band of unlabelled faces (closed loops, junctions, unlabelled region).
fn box_parts() -> TriMesh {
    let mut m = subdivided_cuboid([1.0, 0.8, 0.6], 8);
    label_faces(&mut m, |c| {
        if c[0] < -0.2 {
            Segment::Torso.id()
        } else if c[0] < 0.0 {
            0
        } else if c[1] < 0.0 {
            Segment::ThighL.id()
        } else {
            Segment::ThighR.id()
        }
    });
    m
}

/// Capsule limb in three bands (two closed loops).
fn limb() -> TriMesh {
    let mut m = capsule(0.05, 0.4, 32, 10, 6);
    label_faces(&mut m, |c| {
        if c[1] < 0.15 {
            Segment::ShinL.id()
        } else if c[1] < 0.3 {
            Segment::ThighL.id()
        } else {
            Segment::Torso.id()
        }
    });
    m
}

/// Sphere halves with speckles of a third label and of each other's (merged by `fitted()`).
fn speckled() -> TriMesh {
    let mut m = icosphere(1.0, 3);
    label_faces(&mut m, |c| if c[1] < 0.0 { Segment::ThighR.id() } else { Segment::UpperArmL.id() });
    let labels = m.face_labels.as_mut().unwrap();
    for t in (0..labels.len()).step_by(97) {
        labels[t] = if t % 2 == 0 { Segment::ForearmR.id() } else { Segment::Torso.id() };
    }
    m
}

/// Labelled sphere with two triangular holes (closed by fans with `close_holes`).
fn holed() -> TriMesh {
    let mut m = icosphere(1.0, 2);
    label_faces(&mut m, |c| if c[0] < 0.1 { Segment::Torso.id() } else { Segment::ThighL.id() });
    let far = (0..m.n_triangles()).max_by(|&a, &b| centroid(&m, a)[1].total_cmp(&centroid(&m, b)[1])).unwrap();
    let near = (0..m.n_triangles()).min_by(|&a, &b| centroid(&m, a)[1].total_cmp(&centroid(&m, b)[1])).unwrap();
    let keep: Vec<usize> = (0..m.n_triangles()).filter(|&t| t != far && t != near).collect();
    let labels = m.face_labels.as_ref().unwrap();
    TriMesh {
        vertices: m.vertices.clone(),
        triangles: keep.iter().map(|&t| m.triangles[t]).collect(),
        vertex_labels: None,
        face_labels: Some(keep.iter().map(|&t| labels[t]).collect()),
    }
}

/// The moved vertex arrays: scaled, anisotropically scaled, rigidly moved, jittered, mirrored
/// (inward triangles), and the nominal ones.
fn moves(v: &[[f64; 3]], seed: u64) -> Vec<Vec<[f64; 3]>> {
    let (c, s) = (0.7f64.cos(), 0.7f64.sin());
    let rigid = |p: [f64; 3]| [c * p[0] - s * p[1] + 0.3, s * p[0] + c * p[1] - 1.2, p[2] + 2.5];
    let mut rnd = lcg(seed);
    vec![
        v.to_vec(),
        v.iter().map(|p| scale(*p, 1.3)).collect(),
        v.iter().map(|p| [p[0] * 0.8, p[1] * 1.1, p[2] * 1.7]).collect(),
        v.iter().map(|p| rigid(*p)).collect(),
        v.iter().map(|p| [p[0] + 0.004 * rnd(), p[1] + 0.004 * rnd(), p[2] + 0.004 * rnd()]).collect(),
        v.iter().map(|p| [-p[0], p[1], p[2]]).collect(),
    ]
}

fn with_vertices(m: &TriMesh, v: &[[f64; 3]]) -> TriMesh {
    TriMesh { vertices: v.to_vec(), ..m.clone() }
}

fn close(a: f64, b: f64, scale_m3: f64) -> bool {
    (a - b).abs() <= 1e-12 * scale_m3.abs().max(f64::MIN_POSITIVE)
}

/// `got` equals `want` (volumes to 1e-12 of the whole, everything else exactly).
fn assert_same(got: &SegmentVolumes, want: &SegmentVolumes, what: &str) {
    let w = want.whole_m3;
    assert!(close(got.whole_m3, w, w), "{what}: whole {} vs {w}", got.whole_m3);
    assert_eq!(got.segments.keys().collect::<Vec<_>>(), want.segments.keys().collect::<Vec<_>>(), "{what}");
    for (s, v) in &want.segments {
        assert!(close(got.segments[s], *v, w), "{what}: {s} {} vs {v}", got.segments[s]);
    }
    match (got.unlabelled_m3, want.unlabelled_m3) {
        (Some(a), Some(b)) => assert!(close(a, b, w), "{what}: unlabelled {a} vs {b}"),
        (a, b) => assert_eq!(a, b, "{what}"),
    }
    assert_eq!(got.holes.len(), want.holes.len(), "{what}");
    for (a, b) in got.holes.iter().zip(&want.holes) {
        assert_eq!(a.edges, b.edges, "{what}");
        assert!((a.perimeter_m - b.perimeter_m).abs() <= 1e-12 * b.perimeter_m, "{what}");
        for k in 0..3 {
            assert!((a.centroid[k] - b.centroid[k]).abs() <= 1e-12, "{what}: hole centroid");
        }
    }
    assert_eq!(got.label_source, want.label_source, "{what}");
    assert_eq!(got.inverted, want.inverted, "{what}");
    assert_eq!(got.islands, want.islands, "{what}");
    assert_eq!(got.caps, want.caps, "{what}");
    assert_eq!(got.notes, want.notes, "{what}");
}

fn cases() -> Vec<(&'static str, TriMesh, SegmentOptions)> {
    let holes = SegmentOptions { close_holes: true, ..SegmentOptions::default() };
    vec![
        ("sectors", sectors(), SegmentOptions::default()),
        ("box parts", box_parts(), SegmentOptions::default()),
        ("box parts, islands", box_parts(), SegmentOptions::fitted()),
        ("limb", limb(), SegmentOptions::fitted()),
        ("speckled, islands", speckled(), SegmentOptions::fitted()),
        ("holed, closed", holed(), holes),
        ("holed, closed, islands", holed(), SegmentOptions { close_holes: true, ..SegmentOptions::fitted() }),
    ]
}

#[test]
fn prepared_evaluation_equals_segment_volumes_of_the_moved_mesh() {
    for (k, (name, mesh, opts)) in cases().into_iter().enumerate() {
        let prepared = PreparedSegments::new(&mesh, &opts).unwrap();
        assert_eq!(prepared.vertex_count(), mesh.vertices.len());
        for (j, v) in moves(&mesh.vertices, k as u64 + 1).iter().enumerate() {
            let want = segment_volumes_with(&with_vertices(&mesh, v), &opts).unwrap();
            let got = prepared.evaluate(v).unwrap();
            assert_same(&got, &want, &format!("{name}, move {j}"));
            let flat: Vec<f64> = v.iter().flatten().copied().collect();
            assert_eq!(prepared.evaluate_coords(&flat).unwrap(), got, "{name}, move {j}: coords");
        }
    }
}

#[test]
fn the_moves_change_the_volumes_as_expected() {
    // Guards the comparison above against comparing constants: scaling by 1.3 scales every segment by
    // 1.3^3, a rigid motion keeps them, the mirror image is inverted (and re-signed).
    let mesh = sectors();
    let prepared = PreparedSegments::new(&mesh, &SegmentOptions::default()).unwrap();
    let m = moves(&mesh.vertices, 1);
    let (nominal, scaled, rigid, mirrored) = (
        prepared.evaluate(&m[0]).unwrap(),
        prepared.evaluate(&m[1]).unwrap(),
        prepared.evaluate(&m[3]).unwrap(),
        prepared.evaluate(&m[5]).unwrap(),
    );
    for (s, v) in &nominal.segments {
        assert!((scaled.segments[s] / v - 1.3f64.powi(3)).abs() < 1e-12, "{s}");
        assert!((rigid.segments[s] / v - 1.0).abs() < 1e-12, "{s}");
    }
    assert!(mirrored.inverted && !nominal.inverted);
    assert!((mirrored.whole_m3 - nominal.whole_m3).abs() < 1e-12 * nominal.whole_m3);
    // Hole centroids follow the vertices.
    let mesh = holed();
    let prepared =
        PreparedSegments::new(&mesh, &SegmentOptions { close_holes: true, ..SegmentOptions::default() }).unwrap();
    let moved: Vec<[f64; 3]> = mesh.vertices.iter().map(|p| add(*p, [0.0, 0.0, 5.0])).collect();
    let (a, b) = (prepared.evaluate(&mesh.vertices).unwrap(), prepared.evaluate(&moved).unwrap());
    assert_eq!(a.holes.len(), 2);
    for (ha, hb) in a.holes.iter().zip(&b.holes) {
        assert!((hb.centroid[2] - ha.centroid[2] - 5.0).abs() < 1e-12);
    }
}

#[test]
fn island_merging_at_preparation_matches_the_moved_meshes() {
    // The default island options count faces, not area: the merged labels do not depend on positions,
    // so re-measuring with the nominal mesh's merged labels is exact for any move.
    assert_eq!(IslandOptions::default().min_area_m2, 0.0);
    let mesh = speckled();
    let prepared = PreparedSegments::new(&mesh, &SegmentOptions::fitted()).unwrap();
    let nominal = prepared.evaluate(&mesh.vertices).unwrap();
    assert!(nominal.islands.unwrap().merged_islands > 0);
    let mut rnd = lcg(9);
    for _ in 0..5 {
        let s = 1.0 + 0.5 * rnd();
        let v: Vec<[f64; 3]> = mesh.vertices.iter().map(|p| [p[0] * s + 0.01 * rnd(), p[1], p[2] / s]).collect();
        let want = segment_volumes_with(&with_vertices(&mesh, &v), &SegmentOptions::fitted()).unwrap();
        assert_same(&prepared.evaluate(&v).unwrap(), &want, "speckled");
    }
}

#[test]
fn batches_equal_one_by_one_results_in_order() {
    let mesh = box_parts();
    let opts = SegmentOptions::fitted();
    let prepared = PreparedSegments::new(&mesh, &opts).unwrap();
    let draws: Vec<Vec<[f64; 3]>> = (0..6).flat_map(|s| moves(&mesh.vertices, s)).collect();
    let one: Vec<SegmentVolumes> = draws.iter().map(|v| prepared.evaluate(v).unwrap()).collect();
    assert_eq!(prepared.evaluate_many(&draws).unwrap(), one);
    let flat: Vec<Vec<f64>> = draws.iter().map(|v| v.iter().flatten().copied().collect()).collect();
    assert_eq!(prepared.evaluate_many_coords(&flat).unwrap(), one);
    let reports = prepared.reports_many_coords(&flat, 1010.0).unwrap();
    for (r, v) in reports.iter().zip(&draws) {
        let want = report_with(&with_vertices(&mesh, v), 1010.0, &opts).unwrap();
        assert_eq!(r.volumes_l.keys().collect::<Vec<_>>(), want.volumes_l.keys().collect::<Vec<_>>());
        for ((_, a), (_, b)) in r.volumes_l.0.iter().zip(&want.volumes_l.0) {
            assert!((a - b).abs() <= 1e-12 * b.abs(), "{a} vs {b}");
        }
        assert_eq!(r.ratios.keys().collect::<Vec<_>>(), want.ratios.keys().collect::<Vec<_>>());
        for ((_, a), (_, b)) in r.ratios.0.iter().zip(&want.ratios.0) {
            assert!((a - b).abs() <= 1e-9 * b.abs().max(1.0), "{a} vs {b}");
        }
    }
    assert!(prepared.evaluate_many::<Vec<[f64; 3]>>(&[]).unwrap().is_empty());
}

#[test]
fn wrong_vertex_counts_and_bad_values_are_typed_errors() {
    let mesh = limb();
    let n = mesh.vertices.len();
    let prepared = PreparedSegments::new(&mesh, &SegmentOptions::default()).unwrap();
    let err = prepared.evaluate(&mesh.vertices[..n - 1]).unwrap_err();
    assert_eq!(err, VolumeError::VertexCountMismatch { expected: n, got: n - 1 });
    let text = err.to_string();
    assert!(text.contains(&n.to_string()) && text.contains(&(n - 1).to_string()) && text.contains("prepare"), "{text}");
    assert!(text.starts_with("vertices:") && text.contains("pass `vertices`"), "{text}");
    let flat: Vec<f64> = mesh.vertices.iter().flatten().copied().collect();
    assert_eq!(
        prepared.evaluate_coords(&flat[..flat.len() - 3]).unwrap_err(),
        VolumeError::VertexCountMismatch { expected: n, got: n - 1 }
    );
    // A length that is not whole vertices: its own error, not a truncated vertex count.
    let err = prepared.evaluate_coords(&flat[..flat.len() - 1]).unwrap_err();
    assert_eq!(err, VolumeError::CoordinatesNotTriples { len: flat.len() - 1 });
    let text = err.to_string();
    assert!(text.contains(&(flat.len() - 1).to_string()) && text.contains("not a multiple of 3"), "{text}");
    assert!(text.contains("vertices"), "{text}");
    // In a batch: the first failing draw's error, whatever the threads did.
    let mut bad = mesh.vertices.clone();
    bad[7][1] = f64::NAN;
    let draws = vec![mesh.vertices.clone(), bad, mesh.vertices[..3].to_vec()];
    assert!(matches!(prepared.evaluate_many(&draws), Err(VolumeError::NonFiniteVertex { vertex: 7, .. })));
    assert!(matches!(
        prepared.reports_many_coords(std::slice::from_ref(&flat), 0.0),
        Err(VolumeError::InvalidDensity(_))
    ));
    // Preparation fails as segment_volumes_with fails.
    let open = holed();
    assert_eq!(
        PreparedSegments::new(&open, &SegmentOptions::default()).err(),
        segment_volumes_with(&open, &SegmentOptions::default()).err()
    );
}

#[test]
fn stacks_check_the_vertex_count_first_even_when_empty() {
    let mesh = limb();
    let n = mesh.vertices.len();
    let prepared = PreparedSegments::new(&mesh, &SegmentOptions::default()).unwrap();
    // No draws but the wrong N: still the vertex count error (not an empty table).
    for (draws, vertices) in [(0, n - 1), (0, 0), (2, n + 1)] {
        let coords = vec![0.0; draws * vertices * 3];
        assert_eq!(
            prepared.quantities_stacked(&coords, draws, vertices, 1000.0).unwrap_err(),
            VolumeError::VertexCountMismatch { expected: n, got: vertices },
            "{draws} x {vertices}"
        );
    }
    // No draws and the right N: the empty table.
    assert_eq!(prepared.quantities_stacked(&[], 0, n, 1000.0).unwrap(), QuantityTable::default());
    // A length that does not match the shape.
    let flat: Vec<f64> = mesh.vertices.iter().flatten().copied().collect();
    assert_eq!(
        prepared.quantities_stacked(&flat, 2, n, 1000.0).unwrap_err(),
        VolumeError::StackLengthMismatch { len: 3 * n, draws: 2, vertices: n }
    );
    assert!(matches!(prepared.quantities_stacked(&flat, 1, n, -1.0), Err(VolumeError::InvalidDensity(_))));
}

#[test]
fn the_quantity_table_holds_each_reports_quantities() {
    let mesh = box_parts();
    let opts = SegmentOptions::fitted();
    let prepared = PreparedSegments::new(&mesh, &opts).unwrap();
    let draws: Vec<Vec<[f64; 3]>> = moves(&mesh.vertices, 3);
    let flat: Vec<f64> = draws.iter().flatten().flatten().copied().collect();
    let n = mesh.vertices.len();
    let table = prepared.quantities_stacked(&flat, draws.len(), n, 1010.0).unwrap();
    let reports = prepared.reports_stacked(&flat, draws.len(), n, 1010.0).unwrap();
    assert_eq!(table, QuantityTable::of_reports(&reports));
    assert_eq!(table.names.len(), table.columns.len());
    for (i, (r, v)) in reports.iter().zip(&draws).enumerate() {
        let q = r.quantities();
        let one = report_with(&with_vertices(&mesh, v), 1010.0, &opts).unwrap();
        assert_eq!(
            q.iter().map(|(k, _)| *k).collect::<Vec<_>>(),
            one.quantities().iter().map(|(k, _)| *k).collect::<Vec<_>>()
        );
        // volumes_l then ratios, finite only, in the report's order.
        let want: Vec<(&str, f64)> = r
            .volumes_l
            .0
            .iter()
            .chain(&r.ratios.0)
            .filter(|(_, x)| x.is_finite())
            .map(|(k, x)| (k.as_str(), *x))
            .collect();
        assert_eq!(q, want, "draw {i}");
        for (j, name) in table.names.iter().enumerate() {
            match q.iter().find(|(k, _)| k == name) {
                Some((_, x)) => assert_eq!(table.columns[j][i].to_bits(), x.to_bits(), "{name}"),
                None => assert!(table.columns[j][i].is_nan(), "{name}"),
            }
        }
    }
    assert!(table.names.iter().any(|k| k == "whole") && table.names.iter().any(|k| k.starts_with("asymmetry_")));
}

#[test]
fn report_quantities_are_the_finite_volumes_then_ratios() {
    let mut r = prepared_report();
    let n_volumes = r.volumes_l.0.len();
    r.ratios.0.push(("asymmetry_test_pct".into(), f64::NAN));
    r.ratios.0.push(("test_ratio".into(), 0.5));
    r.volumes_l.0[0].1 = f64::INFINITY;
    let first = r.volumes_l.0[0].0.clone();
    let q = r.quantities();
    assert!(q.iter().all(|(k, x)| x.is_finite() && *k != first && *k != "asymmetry_test_pct"));
    assert_eq!(q[..n_volumes - 1], r.volumes_l.0[1..].iter().map(|(k, x)| (k.as_str(), *x)).collect::<Vec<_>>()[..]);
    assert_eq!(q.last(), Some(&("test_ratio", 0.5)));
    // The table: NaN where a report lacks a quantity, names in first-seen order.
    let table = QuantityTable::of_reports(&[r.clone(), prepared_report()]);
    let j = table.names.iter().position(|k| *k == first).unwrap();
    assert!(table.columns[j][0].is_nan() && table.columns[j][1].is_finite());
    assert_eq!(table.names.last().map(String::as_str), Some(first.as_str()));
    let t = table.names.iter().position(|k| k == "test_ratio").unwrap();
    assert_eq!(table.columns[t][0], 0.5);
    assert!(table.columns[t][1].is_nan());
}

fn prepared_report() -> bsv_volume::VolumeReport {
    let mesh = box_parts();
    let prepared = PreparedSegments::new(&mesh, &SegmentOptions::fitted()).unwrap();
    prepared.report(&mesh.vertices, 1000.0).unwrap()
}
