//! Mesh checks and repairs against meshes with known defects.
#![allow(clippy::unwrap_used)]

use bsv_core::check::{check_mesh, repair_mesh, MeshCheckError};
use bsv_core::shapes::{cuboid, icosphere, subdivided_cuboid, translate};
use bsv_core::TriMesh;

#[test]
fn cube_is_watertight_and_outward() {
    let m = cuboid([1.0, 2.0, 3.0]);
    let r = check_mesh(&m);
    assert_eq!((r.vertices, r.faces, r.components), (8, 12, 1));
    assert!(r.is_watertight && r.is_consistently_oriented);
    assert_eq!((r.boundary_edges, r.boundary_loops, r.non_manifold_edges, r.non_manifold_vertices), (0, 0, 0, 0));
    assert_eq!((r.degenerate_faces, r.duplicate_faces, r.unreferenced_vertices, r.inconsistent_edges), (0, 0, 0, 0));
    assert!((r.signed_volume.expect("closed") - 6.0).abs() < 1e-12);
    assert!((r.area - 22.0).abs() < 1e-12);
    assert_eq!(r.require_closed_manifold("the cube"), Ok(()));
    let text = r.to_string();
    assert!(text.contains("watertight:             yes") && text.contains("6000.000 L"), "{text}");
    let json = serde_json::to_value(&r).expect("serialize");
    assert_eq!(json["faces"], 12);
    assert_eq!(json["is_watertight"], true);
}

#[test]
fn flipped_faces_are_detected_and_repaired() {
    let mut m = subdivided_cuboid([1.0, 0.5, 0.25], 4);
    translate(&mut m, [3.0, -2.0, 1.0]);
    let good = m.clone();
    for t in [0usize, 7, 50, 51, 100] {
        m.triangles[t].swap(0, 1);
    }
    let r = check_mesh(&m);
    assert!(!r.is_consistently_oriented && r.is_watertight && r.signed_volume.is_none());
    assert!(r.inconsistent_edges >= 5, "{}", r.inconsistent_edges);
    let err = r.require_closed_manifold("the template").unwrap_err();
    assert!(matches!(err, MeshCheckError::Inconsistent { .. }));
    assert!(err.to_string().contains("the template") && err.to_string().contains("repair_mesh"), "{err}");
    let log = repair_mesh(&mut m);
    assert_eq!(log.flipped_for_consistency, 5);
    assert_eq!(log.components_turned_outward, 0);
    let r = check_mesh(&m);
    assert!(r.is_consistently_oriented);
    assert!((r.signed_volume.unwrap() - 0.125).abs() < 1e-12);
    for (a, b) in m.triangles.iter().zip(&good.triangles) {
        let mut a = *a;
        let k = a.iter().position(|&v| v == b[0]).unwrap();
        a.rotate_left(k);
        assert_eq!(&a, b);
    }

    // Entirely inside-out: consistent but negative, then turned outward.
    let mut inv = icosphere(1.0, 2);
    for t in &mut inv.triangles {
        t.swap(1, 2);
    }
    let r = check_mesh(&inv);
    assert!(r.signed_volume.unwrap() < 0.0);
    let err = r.require_closed_manifold("mesh").unwrap_err();
    assert!(matches!(err, MeshCheckError::Inward { .. }), "{err:?}");
    let log = repair_mesh(&mut inv);
    assert_eq!(log.components_turned_outward, 1);
    assert!(check_mesh(&inv).require_closed_manifold("mesh").is_ok());
}

#[test]
fn open_box_reports_one_loop() {
    let mut m = cuboid([1.0; 3]);
    m.triangles.truncate(10);
    let r = check_mesh(&m);
    assert!(!r.is_watertight);
    assert_eq!((r.boundary_edges, r.boundary_loops), (4, 1));
    assert!(r.signed_volume.is_none());
    let err = r.require_closed_manifold("the segment").unwrap_err();
    assert_eq!(err, MeshCheckError::Open { what: "the segment".into(), edges: 4, loops: 1 });
    assert!(err.to_string().contains("close the holes"), "{err}");
    // Two holes.
    let mut m = subdivided_cuboid([1.0; 3], 3);
    let n = m.triangles.len();
    m.triangles.remove(n - 1);
    m.triangles.remove(4);
    let r = check_mesh(&m);
    assert_eq!(r.boundary_loops, 2);
}

#[test]
fn non_manifold_edge_and_vertex_detected() {
    // Three triangles on edge 0-1.
    let m = TriMesh::new(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, -1.0, 0.0], [0.5, 0.0, 1.0]],
        vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    );
    let r = check_mesh(&m);
    assert_eq!(r.non_manifold_edges, 1);
    assert!(!r.is_watertight);
    let err = r.require_closed_manifold("mesh").unwrap_err();
    assert!(matches!(err, MeshCheckError::NonManifold { edges: 1, .. }), "{err:?}");
    // Two tetrahedra touching at one vertex: manifold edges, one pinched vertex.
    let mut a = cuboid([1.0; 3]);
    let b = {
        let mut b = cuboid([1.0; 3]);
        translate(&mut b, [1.0, 1.0, 1.0]);
        b
    };
    // Vertex 7 of a (0.5,0.5,0.5) equals vertex 0 of b: share it.
    let off = a.vertices.len() as u32;
    a.vertices.extend(b.vertices.iter().skip(1));
    a.triangles.extend(b.triangles.iter().map(|t| t.map(|v| if v == 0 { 7 } else { v + off - 1 })));
    let r = check_mesh(&a);
    assert_eq!((r.non_manifold_edges, r.non_manifold_vertices, r.components), (0, 1, 2));
    assert!(r.is_watertight);
    assert!(matches!(r.require_closed_manifold("x"), Err(MeshCheckError::NonManifold { vertices: 1, .. })));
}

#[test]
fn duplicates_degenerates_and_unreferenced_removed_with_labels_in_sync() {
    let mut m = cuboid([2.0; 3]);
    let n0 = m.n_vertices() as u32;
    m.vertex_labels = Some((0..8).collect());
    m.face_labels = Some((0..12).collect());
    // Extra vertices: one unreferenced, one collinear point used by a zero-area triangle.
    m.vertices.push([9.0, 9.0, 9.0]);
    m.vertices.push([0.0, -1.0, -1.0]); // midpoint of vertices 0 and 1
    m.vertex_labels.as_mut().unwrap().extend([13, 14]);
    let extra = [
        [0, 1, n0 + 1], // zero area
        [2, 2, 3],      // repeated index
        [3, 0, 2],      // duplicate of [0, 2, 3]
        [4, 7, 5],      // duplicate of [4, 5, 7] (reversed)
    ];
    m.triangles.extend(extra);
    m.face_labels.as_mut().unwrap().extend([12, 12, 12, 12]);
    let r = check_mesh(&m);
    assert_eq!((r.degenerate_faces, r.duplicate_faces, r.unreferenced_vertices), (2, 2, 1));
    assert!(r.non_manifold_edges > 0);
    let log = repair_mesh(&mut m);
    assert_eq!(
        (log.removed_degenerate_faces, log.removed_duplicate_faces, log.removed_unreferenced_vertices),
        (2, 2, 2)
    );
    assert_eq!(m.triangles, cuboid([2.0; 3]).triangles);
    assert_eq!(m.vertex_labels, Some((0..8).collect()));
    assert_eq!(m.face_labels, Some((0..12).collect()));
    let r = check_mesh(&m);
    assert!(r.require_closed_manifold("cube").is_ok(), "{r}");
    assert!((r.signed_volume.unwrap() - 8.0).abs() < 1e-12);

    // Unreferenced vertex in the middle: indices compacted, labels follow.
    let mut m = TriMesh::new(vec![[0.0; 3], [7.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 2, 3]]);
    m.vertex_labels = Some(vec![1, 9, 2, 3]);
    let log = repair_mesh(&mut m);
    assert_eq!(log.removed_unreferenced_vertices, 1);
    assert_eq!(m.vertices, vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
    assert_eq!(m.vertex_labels, Some(vec![1, 2, 3]));
}

#[test]
fn invalid_indices_never_panic() {
    let mut m = TriMesh::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2], [0, 1, 99]]);
    let r = check_mesh(&m);
    assert_eq!(r.invalid_faces, 1);
    assert!(matches!(r.require_closed_manifold("m"), Err(MeshCheckError::InvalidFaces { count: 1, .. })));
    m.face_labels = Some(vec![1]); // wrong length: dropped, not a panic
    let log = repair_mesh(&mut m);
    assert_eq!((log.removed_invalid_faces, log.dropped_label_arrays), (1, 1));
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
    let empty = check_mesh(&TriMesh::default());
    assert!(!empty.is_watertight);
    assert!(matches!(empty.require_closed_manifold("m"), Err(MeshCheckError::Empty { .. })));
}
