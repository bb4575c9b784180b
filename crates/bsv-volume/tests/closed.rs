//! Volumes of closed meshes, hole closing and the typed errors of bad meshes.
#![allow(clippy::unwrap_used)]

use bsv_core::geometry::{cross, dot, norm, sub};
use bsv_core::shapes::{cuboid, icosphere, translate};
use bsv_core::{MeshInvariant, TriMesh};
use bsv_volume::{close_holes, closed_volume, mesh_volume, segment_volumes, VolumeError};
use std::f64::consts::PI;

/// Polyhedral volume computed differently: sum over faces of area x (plane distance from an interior
/// point q) / 3.
fn pyramid_volume(m: &TriMesh, q: [f64; 3]) -> f64 {
    (0..m.n_triangles())
        .map(|t| {
            let [a, b, c] = m.triangle_points(t);
            let n = cross(sub(b, a), sub(c, a));
            let area = 0.5 * norm(n);
            let h = dot(sub(a, q), n) / norm(n);
            area * h / 3.0
        })
        .sum()
}

#[test]
fn unit_cube_from_12_triangles() {
    let c = cuboid([1.0, 1.0, 1.0]);
    assert_eq!(c.n_triangles(), 12);
    let v = closed_volume(&c).unwrap();
    assert!((v - 1.0).abs() < 1e-12, "{v}");
    // Far from the origin the centroid-relative sum keeps round-off small.
    let mut far = c.clone();
    translate(&mut far, [1.0e4, -2.0e4, 3.0e4]);
    let v = closed_volume(&far).unwrap();
    assert!((v - 1.0).abs() < 1e-9, "{v}");
}

#[test]
fn icosphere_polyhedral_and_analytic() {
    for level in [1, 3] {
        let m = icosphere(0.7, level);
        let v = closed_volume(&m).unwrap();
        let independent = pyramid_volume(&m, [0.1, -0.2, 0.05]);
        assert!((v - independent).abs() < 1e-12 * v, "level {level}: {v} vs {independent}");
        assert!(v < 4.0 / 3.0 * PI * 0.343, "an inscribed polyhedron is smaller than its sphere");
    }
    let r = 0.3;
    let m = icosphere(r, 6);
    let v = closed_volume(&m).unwrap();
    let sphere = 4.0 / 3.0 * PI * r * r * r;
    assert!((v - sphere).abs() / sphere < 1e-3, "level 6: {v} vs {sphere}");
    let independent = pyramid_volume(&m, [0.01, 0.02, -0.03]);
    assert!((v - independent).abs() < 1e-12 * v);
}

fn sphere_with_two_holes() -> (TriMesh, f64) {
    let m = icosphere(1.0, 2);
    let full = closed_volume(&m).unwrap();
    // Faces 0 and the face farthest from it leave two triangular holes.
    let c0 = m.triangle_points(0)[0];
    let far = (0..m.n_triangles())
        .max_by(|&a, &b| {
            let da = bsv_core::geometry::dist2(m.triangle_points(a)[0], c0);
            let db = bsv_core::geometry::dist2(m.triangle_points(b)[0], c0);
            da.total_cmp(&db)
        })
        .unwrap();
    let mut open = m.clone();
    open.triangles = m.triangles.iter().enumerate().filter(|(i, _)| *i != 0 && *i != far).map(|(_, t)| *t).collect();
    (open, full)
}

#[test]
fn open_mesh_is_an_error_with_loop_count_and_positions() {
    let (open, _) = sphere_with_two_holes();
    match closed_volume(&open) {
        Err(VolumeError::OpenMesh { loops, boundary_edges, loop_centroids }) => {
            assert_eq!(loops, 2);
            assert_eq!(boundary_edges, 6);
            assert_eq!(loop_centroids.len(), 2);
            for c in loop_centroids {
                assert!((norm(c) - 1.0).abs() < 0.1, "a hole centroid lies near the sphere: {c:?}");
            }
        }
        other => panic!("expected OpenMesh, got {other:?}"),
    }
    let msg = closed_volume(&open).unwrap_err().to_string();
    assert!(msg.contains("2 boundary loop") && msg.contains("close"), "{msg}");
    assert!(matches!(segment_volumes(&open), Err(VolumeError::OpenMesh { loops: 2, .. })));
}

#[test]
fn closing_triangular_holes_restores_the_volume_exactly() {
    let (open, full) = sphere_with_two_holes();
    let mv = mesh_volume(&open, true).unwrap();
    assert_eq!(mv.holes.len(), 2);
    assert!((mv.volume_m3 - full).abs() < 1e-12, "{} vs {full}", mv.volume_m3);
    let (closed, holes) = close_holes(&open).unwrap();
    assert_eq!(holes.len(), 2);
    assert_eq!(closed.n_vertices(), open.n_vertices() + 2);
    assert!((closed_volume(&closed).unwrap() - full).abs() < 1e-12);
}

#[test]
fn open_box_closed_by_a_fan_has_the_box_volume() {
    // A box without its top (two triangles): the fan of the square loop to its centroid is planar.
    let mut m = cuboid([0.4, 0.3, 0.2]);
    m.triangles.retain(|t| *t != [2, 6, 7] && *t != [2, 7, 3]);
    assert!(matches!(closed_volume(&m), Err(VolumeError::OpenMesh { loops: 1, boundary_edges: 4, .. })));
    let v = mesh_volume(&m, true).unwrap();
    assert!((v.volume_m3 - 0.024).abs() < 1e-15);
    assert!((v.holes[0].perimeter_m - 1.2).abs() < 1e-12);
}

#[test]
fn pinched_holes_are_closed_as_simple_loops() {
    // Two boxes sharing one corner vertex, each with the face at that corner removed: the boundary
    // passes the shared vertex twice. Closing must split it into two manifold fans.
    let a = cuboid([1.0, 1.0, 1.0]);
    let mut b = cuboid([1.0, 1.0, 1.0]);
    translate(&mut b, [1.0, 1.0, 1.0]);
    // Corner 7 of a (0.5,0.5,0.5) is corner 0 of b; merge them.
    let mut m = a.clone();
    let off = m.vertices.len() as u32;
    m.vertices.extend(b.vertices.iter().skip(1));
    let map = |v: u32| if v == 0 { 7 } else { off + v - 1 };
    m.triangles.extend(b.triangles.iter().map(|t| t.map(map)));
    // Remove a's +x faces (use corner 7) and b's -x faces (use corner 0).
    m.triangles.retain(|t| *t != [1, 3, 7] && *t != [1, 7, 5]);
    let (bx0, bx1) = ([0, 4, 6].map(map), [0, 6, 2].map(map));
    m.triangles.retain(|t| *t != bx0 && *t != bx1);
    let mv = mesh_volume(&m, true).unwrap();
    assert_eq!(mv.holes.len(), 2);
    assert!((mv.volume_m3 - 2.0).abs() < 1e-12, "{}", mv.volume_m3);
}

#[test]
fn non_manifold_and_inconsistent_meshes_are_typed_errors() {
    let mut m = cuboid([1.0, 1.0, 1.0]);
    m.vertices.push([0.0, 2.0, 0.0]);
    m.triangles.push([2, 6, 8]); // a fin on edge 2-6, which already has two faces
    match closed_volume(&m) {
        Err(VolumeError::NonManifold { edges, example, faces, .. }) => {
            assert_eq!((edges, example, faces), (1, (2, 6), 3));
        }
        other => panic!("expected NonManifold, got {other:?}"),
    }
    assert!(matches!(segment_volumes(&m), Err(VolumeError::NonManifold { .. })));

    let mut f = cuboid([1.0, 1.0, 1.0]);
    f.triangles[0] = [0, 3, 2];
    assert!(matches!(closed_volume(&f), Err(VolumeError::InconsistentOrientation { edges: 3, .. })));
}

#[test]
fn bad_input_errors() {
    assert_eq!(closed_volume(&TriMesh::default()), Err(VolumeError::EmptyMesh));
    let mut m = cuboid([1.0, 1.0, 1.0]);
    m.vertices[3][1] = f64::NAN;
    assert!(matches!(closed_volume(&m), Err(VolumeError::NonFiniteVertex { vertex: 3, .. })));
    let mut m = cuboid([1.0, 1.0, 1.0]);
    m.triangles[5][2] = 99;
    assert_eq!(
        closed_volume(&m),
        Err(VolumeError::Mesh(MeshInvariant::IndexOutOfRange { face: 5, index: 99, n_vertices: 8 }))
    );
    let mut m = cuboid([1.0, 1.0, 1.0]);
    m.triangles[4] = [0, 1, 1];
    assert_eq!(closed_volume(&m), Err(VolumeError::DegenerateFace { face: 4, vertex: 1 }));
    let mut m = cuboid([1.0, 1.0, 1.0]);
    m.face_labels = Some(vec![2; 11]);
    assert!(matches!(segment_volumes(&m), Err(VolumeError::LabelCountMismatch { got: 11, expected: 12, .. })));
    m.face_labels = Some(vec![15; 12]);
    assert!(matches!(segment_volumes(&m), Err(VolumeError::UnknownLabel { label: 15, .. })));
}

#[test]
fn inward_mesh_has_negative_signed_volume_and_positive_segments() {
    let mut m = cuboid([1.0, 2.0, 1.0]);
    for t in &mut m.triangles {
        t.swap(1, 2);
    }
    assert!((closed_volume(&m).unwrap() + 2.0).abs() < 1e-12);
    m.face_labels = Some(vec![2; 12]);
    let sv = segment_volumes(&m).unwrap();
    assert!(sv.inverted);
    assert!((sv.whole_m3 - 2.0).abs() < 1e-12);
    assert!((sv.get(bsv_core::Segment::Torso).unwrap() - 2.0).abs() < 1e-12);
    assert!(sv.notes.iter().any(|n| n.contains("inward")));
}
