//! OBJ reading (quads, negative indices, every index form, groups) and writing (exact round trips).
#![allow(clippy::unwrap_used)]

use bsv_core::io::obj::{self, ObjError};
use bsv_core::io::{self as bio, ReadError};
use bsv_core::shapes::{cuboid, icosphere};
use bsv_core::{Segment, TriMesh};

#[test]
fn quads_negative_indices_and_every_index_form() {
    let text = "# a unit square pyramid\nmtllib x.mtl\no pyramid\nv 0 0 0\nv 1 0 0 1.0\nv 1 0 1 0.5 0.5 0.5\nv 0 0 1\nv 0.5 1 0.5\n\
vt 0 0\nvt 1 0\nvn 0 1 0\ns off\nusemtl skin\n\
f 1/1/1 4/2/1 3//1 2\n\
f -5 -4 -1\nf 2/1 3/2 5/1\nf 3//1 4//1 5//1\nf -2 -5 -1\nl 1 2\n";
    let (m, report) = obj::parse(text.as_bytes()).expect("valid obj");
    assert_eq!(m.n_vertices(), 5);
    assert_eq!(m.vertices[2], [1.0, 0.0, 1.0]);
    assert_eq!(m.triangles, vec![[0, 3, 2], [0, 2, 1], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]);
    assert_eq!(report.polygons_triangulated, 1);
    assert_eq!(report.ignored_statements, 1); // the `l` line
    assert_eq!(report.unknown_groups, vec!["pyramid".to_string()]);
    // "pyramid" is not a segment: no labels.
    assert!(m.face_labels.is_none() && m.vertex_labels.is_none());
    // The pyramid is closed and consistently wound (clockwise as written): volume -1/3.
    let r = bsv_core::check::check_mesh(&m);
    assert!(r.is_watertight && r.is_consistently_oriented, "{r}");
    let v = r.signed_volume.expect("closed");
    assert!((v + 1.0 / 3.0).abs() < 1e-12, "{v}");
}

#[test]
fn groups_label_faces_and_unknown_groups_are_reported() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n\
f 1 3 2\ng torso\nf 1 2 4\ng Thigh_L extra\nf 2 3 4\ng skirt\nf 1 4 3\ng skirt\n";
    let (m, report) = obj::parse(text.as_bytes()).expect("valid");
    assert_eq!(m.face_labels, Some(vec![0, Segment::Torso.id(), Segment::ThighL.id(), 0]));
    assert_eq!(report.unknown_groups, vec!["skirt".to_string()]);
    // Not every face is labelled: no vertex labels.
    assert!(m.vertex_labels.is_none() && !report.vertex_labels_derived);

    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 5 5 5\n\
g torso\nf 1 3 2\nf 1 2 4\no shin_r\nf 2 3 4\ng head\nf 1 4 3\n";
    let (m, report) = obj::parse(text.as_bytes()).expect("valid");
    assert_eq!(m.face_labels, Some(vec![2, 2, 12, 1]));
    assert!(report.vertex_labels_derived);
    // v1: faces torso, torso, head -> torso; v2: torso x2, shin_r -> torso; v3: torso, shin_r, head ->
    // tie -> smallest id (head = 1); v4: torso, shin_r, head -> head; v5 unreferenced -> 0.
    assert_eq!(m.vertex_labels, Some(vec![2, 2, 1, 1, 0]));
}

/// (triangle, face label) pairs of a labelled mesh, sorted (face order aside).
fn sorted_faces(m: &TriMesh) -> Vec<([u32; 3], u8)> {
    let fl = m.face_labels.as_ref().expect("face labels");
    sorted_pairs(m.triangles.iter().copied().zip(fl.iter().copied()).collect())
}

fn sorted_pairs(mut v: Vec<([u32; 3], u8)>) -> Vec<([u32; 3], u8)> {
    v.sort_unstable();
    v
}

/// Enclosed volume by the divergence theorem (m^3).
fn volume(m: &TriMesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

#[test]
fn interleaved_labels_give_one_group_per_segment_and_round_trip() {
    // Face labels that change at every face (as a fitted mesh's do along its cut lines): the writer used
    // to emit one `g` line per run (666 runs for a fitted body); now one per segment.
    let mut m = icosphere(0.5, 2);
    let nf = m.n_triangles();
    let ids = [2u8, 3, 9, 2, 11, 3];
    m.face_labels = Some((0..nf).map(|t| ids[t % ids.len()]).collect());
    let text = obj::to_string(&m).expect("encode");
    for name in ["torso", "upper_arm_l", "thigh_l", "shin_l"] {
        assert_eq!(text.matches(&format!("\ng {name}\n")).count(), 1, "{name}");
    }
    assert_eq!(text.matches("\ng ").count(), 4);
    let (back, report) = obj::parse(text.as_bytes()).expect("decode");
    assert_eq!(back.vertices, m.vertices);
    assert_eq!(sorted_faces(&back), sorted_faces(&m), "the same triangles with the same labels");
    let bl = back.face_labels.as_ref().expect("labels");
    assert!(bl.windows(2).all(|w| w[0] <= w[1]), "faces come grouped by ascending segment id");
    assert!(report.vertex_labels_derived);
    // Vertex labels are derived from the same faces, so they agree; the volume is the same.
    let want =
        bsv_core::labels::vertex_labels_from_faces(m.n_vertices(), &m.triangles, m.face_labels.as_ref().unwrap());
    assert_eq!(back.vertex_labels.as_ref(), Some(&want));
    assert!((volume(&back) - volume(&m)).abs() <= 1e-15 * volume(&m).abs().max(1.0));
    assert!(volume(&m) > 0.5);

    // An unlabelled mesh keeps its face order and gets no group.
    let plain = icosphere(0.5, 1);
    let text = obj::to_string(&plain).expect("encode");
    assert!(!text.contains("\ng "));
    assert_eq!(obj::parse(text.as_bytes()).expect("decode").0.triangles, plain.triangles);
}

#[test]
fn writer_round_trips_exactly_and_groups_by_segment() {
    let mut m = icosphere(0.123_456_789, 2);
    for p in &mut m.vertices {
        p[0] += 1e-9 / 3.0;
    }
    let nf = m.n_triangles();
    m.face_labels = Some((0..nf).map(|t| if t < nf / 2 { 9 } else { 11 }).collect());
    let text = obj::to_string(&m).expect("encode");
    assert!(text.starts_with(&format!("# generated by bsv {}", env!("CARGO_PKG_VERSION"))));
    assert_eq!(text.matches("\ng thigh_l\n").count(), 1);
    assert_eq!(text.matches("\ng shin_l\n").count(), 1);
    let (back, report) = obj::parse(text.as_bytes()).expect("decode");
    assert_eq!(back.vertices, m.vertices, "exact f64 round trip");
    assert_eq!(back.triangles, m.triangles);
    assert_eq!(back.face_labels, m.face_labels);
    assert!(report.unknown_groups.is_empty() && report.vertex_labels_derived);

    // Vertex labels only: faces take the majority of their corners.
    let mut c = cuboid([1.0; 3]);
    c.vertex_labels = Some(c.vertices.iter().map(|p| if p[0] > 0.0 { 5 } else { 3 }).collect());
    let (back, _) = obj::parse(obj::to_string(&c).unwrap().as_bytes()).unwrap();
    let want: Vec<([u32; 3], u8)> = c
        .triangles
        .iter()
        .map(|t| {
            let n5 = t.iter().filter(|&&v| c.vertices[v as usize][0] > 0.0).count();
            (*t, if n5 >= 2 { 5 } else { 3 })
        })
        .collect();
    assert_eq!(sorted_faces(&back), sorted_pairs(want));

    // File level.
    let dir = std::env::temp_dir().join(format!("bsv_io_obj_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("sphere.OBJ");
    bio::write_mesh(&p, &m).expect("write");
    assert_eq!(bio::read_mesh(&p).expect("read").triangles, m.triangles);
    let (_, rep) = bio::read_mesh_with_report(&p).expect("read");
    assert!(rep.unknown_groups.is_empty());
    assert_eq!(bio::read_point_cloud(&p).expect("cloud").points, m.vertices);
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap();
    let err = bio::read_mesh(&dir.join("bad.obj")).unwrap_err();
    assert!(
        matches!(err, ReadError::Obj { source: ObjError::IndexOutOfRange { line: 4, index: 4, vertex_count: 3 }, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("bad.obj") && err.to_string().contains("line 4"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_obj_input_is_typed_with_line_numbers() {
    assert_eq!(obj::parse(b"").unwrap_err(), ObjError::Empty);
    assert_eq!(obj::parse(b"# nothing here\n").unwrap_err(), ObjError::NoVertices);
    assert!(matches!(obj::parse(b"v 0 0\n").unwrap_err(), ObjError::BadVertex { line: 1, .. }));
    assert!(matches!(obj::parse(b"v 0 0 zero\n").unwrap_err(), ObjError::BadVertex { line: 1, .. }));
    let err = obj::parse(b"v 0 0 0\nv 1 nan 0\n").unwrap_err();
    assert!(matches!(err, ObjError::NonFinite { line: 2, vertex: 1, .. }), "{err:?}");
    assert!(matches!(
        obj::parse(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n").unwrap_err(),
        ObjError::FaceTooSmall { line: 4, n: 2 }
    ));
    assert!(matches!(
        obj::parse(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").unwrap_err(),
        ObjError::BadFace { line: 4, .. }
    ));
    assert!(matches!(
        obj::parse(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf a b c\n").unwrap_err(),
        ObjError::BadFace { line: 4, .. }
    ));
    let err = obj::parse(b"v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n").unwrap_err();
    assert_eq!(err, ObjError::IndexOutOfRange { line: 3, index: -3, vertex_count: 2 });
    // One enormous face line is refused, not triangulated into millions of triangles.
    let mut huge = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf".to_vec();
    for _ in 0..=obj::MAX_FACE_CORNERS {
        huge.extend(b" 1 2 3");
    }
    assert_eq!(obj::parse(&huge).unwrap_err(), ObjError::FaceTooLarge { line: 4, max: obj::MAX_FACE_CORNERS });
    // Forward references are allowed when the vertex exists by the end.
    let (m, _) = obj::parse(b"f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").expect("forward refs");
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
    // Writer validation.
    let mut m = TriMesh::new(vec![[0.0; 3]; 3], vec![[0, 1, 2]]);
    m.face_labels = Some(vec![20]);
    assert!(obj::to_string(&m).unwrap_err().to_string().contains("face_labels[0] = 20"));
}
