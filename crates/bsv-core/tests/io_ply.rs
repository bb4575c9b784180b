//! PLY reading (hand-written headers of every scalar type, both endiannesses and ascii), writer round
//! trips, and typed errors for bad input.
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

use bsv_core::io::ply::{self, PlyData, PlyEncoding, PlyError};
use bsv_core::io::{self as bio, ReadError};
use bsv_core::shapes::{cuboid, icosphere};
use bsv_core::{PointCloud, Segment, TriMesh, PALETTE};

/// Every PLY type name (with aliases) and whether it is signed/float.
const TYPES: [&str; 16] = [
    "char", "int8", "uchar", "uint8", "short", "int16", "ushort", "uint16", "int", "int32", "uint", "uint32", "float",
    "float32", "double", "float64",
];

/// Encodes `v` as PLY type `ty` in the given encoding (ascii: a token followed by a space).
fn enc(ty: &str, v: f64, e: PlyEncoding) -> Vec<u8> {
    let big = e == PlyEncoding::BinaryBigEndian;
    macro_rules! b {
        ($x:expr) => {
            if big {
                $x.to_be_bytes().to_vec()
            } else {
                $x.to_le_bytes().to_vec()
            }
        };
    }
    if e == PlyEncoding::Ascii {
        return format!("{v} ").into_bytes();
    }
    match ty {
        "char" | "int8" => b!(v as i8),
        "uchar" | "uint8" => b!(v as u8),
        "short" | "int16" => b!(v as i16),
        "ushort" | "uint16" => b!(v as u16),
        "int" | "int32" => b!(v as i32),
        "uint" | "uint32" => b!(v as u32),
        "float" | "float32" => b!(v as f32),
        "double" | "float64" => b!(v),
        _ => panic!("bad type {ty}"),
    }
}

fn eol(out: &mut Vec<u8>, e: PlyEncoding) {
    if e == PlyEncoding::Ascii {
        out.push(b'\n');
    }
}

const ENCODINGS: [PlyEncoding; 3] = [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian];

/// A tetrahedron file whose coordinates, label and face list use the given types, with an unknown
/// scalar and an unknown list property on vertices and an unknown element in between.
fn tetra_file(coord: &str, label: &str, count: &str, index: &str, e: PlyEncoding) -> Vec<u8> {
    let signed = !matches!(coord, "uchar" | "uint8" | "ushort" | "uint16" | "uint" | "uint32");
    let pts: [[f64; 3]; 4] = if signed {
        [[0.0, 0.0, 0.0], [2.0, 0.0, -1.0], [0.0, 3.0, 0.0], [-1.0, 0.0, 4.0]]
    } else {
        [[0.0, 0.0, 0.0], [2.0, 0.0, 1.0], [0.0, 3.0, 0.0], [1.0, 0.0, 4.0]]
    };
    let mut out = format!(
        "ply\nformat {} 1.0\ncomment hand written\nobj_info test file\nelement vertex 4\n\
         property {coord} x\nproperty {coord} y\nproperty {coord} z\nproperty float confidence\n\
         property list uchar short junk\nproperty {label} label\n\
         element edge 2\nproperty int vertex1\nproperty list {count} {index} extra\n\
         element face 2\nproperty {label} flags\nproperty list {count} {index} vertex_indices\nproperty {label} label\n\
         end_header\n",
        e.header_name()
    )
    .into_bytes();
    for (i, p) in pts.iter().enumerate() {
        for &c in p {
            out.extend(enc(coord, c, e));
        }
        out.extend(enc("float", 0.5, e));
        out.extend(enc("uchar", 2.0, e));
        out.extend(enc("short", -7.0, e));
        out.extend(enc("short", 9.0, e));
        out.extend(enc(label, (i + 1) as f64, e));
        eol(&mut out, e);
    }
    for k in 0..2 {
        out.extend(enc("int", k as f64, e));
        out.extend(enc(count, 1.0, e));
        out.extend(enc(index, 3.0, e));
        eol(&mut out, e);
    }
    // A triangle and a quad (fan-triangulated into two).
    out.extend(enc(label, 1.0, e));
    out.extend(enc(count, 3.0, e));
    for i in [0.0, 2.0, 1.0] {
        out.extend(enc(index, i, e));
    }
    out.extend(enc(label, 9.0, e));
    eol(&mut out, e);
    out.extend(enc(label, 0.0, e));
    out.extend(enc(count, 4.0, e));
    for i in [0.0, 1.0, 3.0, 2.0] {
        out.extend(enc(index, i, e));
    }
    out.extend(enc(label, 12.0, e));
    eol(&mut out, e);
    out
}

#[test]
fn reads_every_scalar_type_and_alias_in_every_encoding() {
    let index_types = ["char", "uchar", "short", "ushort", "int", "uint", "int32", "uint32", "uint8", "int16"];
    for e in ENCODINGS {
        for (k, &coord) in TYPES.iter().enumerate() {
            let label = TYPES[(k + 3) % TYPES.len()];
            let count = ["uchar", "uint8", "char", "ushort", "int", "uint"][k % 6];
            let index = index_types[k % index_types.len()];
            let bytes = tetra_file(coord, label, count, index, e);
            let data = ply::parse(&bytes).unwrap_or_else(|err| panic!("{e:?} {coord} {label} {count} {index}: {err}"));
            assert_eq!(data.encoding, e);
            assert_eq!(data.comments, vec!["hand written".to_string(), "test file".to_string()]);
            let signed = !matches!(coord, "uchar" | "uint8" | "ushort" | "uint16" | "uint" | "uint32");
            let s = if signed { -1.0 } else { 1.0 };
            assert_eq!(
                data.points,
                vec![[0.0, 0.0, 0.0], [2.0, 0.0, s], [0.0, 3.0, 0.0], [s, 0.0, 4.0]],
                "{e:?} {coord}"
            );
            assert_eq!(data.vertex_labels, Some(vec![1, 2, 3, 4]), "{e:?} {label}");
            assert_eq!(data.triangles, Some(vec![[0, 2, 1], [0, 1, 3], [0, 3, 2]]), "{e:?} {count} {index}");
            assert_eq!(data.face_labels, Some(vec![9, 12, 12]));
            assert!(data.normals.is_none() && data.colors.is_none());
        }
    }
}

#[test]
fn reads_normals_colors_and_float_colors() {
    for e in ENCODINGS {
        let mut bytes = format!(
            "ply\nformat {} 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\n\
             property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n\
             property uchar blue\nproperty uchar alpha\nend_header\n",
            e.header_name()
        )
        .into_bytes();
        for (p, c) in [([0.125, -2.5, 1e-3], [10.0, 20.0, 255.0]), ([1.0, 2.0, 3.0], [0.0, 1.0, 2.0])] {
            for v in p {
                bytes.extend(enc("double", v, e));
            }
            for v in [0.0, 0.0, 1.0] {
                bytes.extend(enc("float", v, e));
            }
            for v in c {
                bytes.extend(enc("uchar", v, e));
            }
            bytes.extend(enc("uchar", 255.0, e));
            eol(&mut bytes, e);
        }
        let cloud = ply::parse_cloud(&bytes).expect("valid cloud");
        assert_eq!(cloud.points, vec![[0.125, -2.5, 1e-3], [1.0, 2.0, 3.0]]);
        assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0]; 2]));
        assert_eq!(cloud.colors, Some(vec![[10, 20, 255], [0, 1, 2]]));
        assert_eq!(cloud.labels, None);
    }
    let text = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
property float diffuse_red\nproperty float diffuse_green\nproperty float diffuse_blue\nend_header\n1 2 3 1.0 0.5 0\n";
    let cloud = ply::parse_cloud(text).expect("valid");
    assert_eq!(cloud.colors, Some(vec![[255, 128, 0]]));
}

fn labelled_cloud(n: usize) -> PointCloud {
    let points: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let t = i as f64 * 0.618_033_988_749_894_9;
            [t.sin() * 0.3, 1.0 + t.cos() / 7.0, (t * 1e-3).tan() + 1e-17]
        })
        .collect();
    let mut c = PointCloud::new(points);
    c.labels = Some((0..n).map(|i| (i % 15) as u8).collect());
    c
}

#[test]
fn cloud_round_trips_exactly_in_every_encoding() {
    let mut c = labelled_cloud(500);
    for e in ENCODINGS {
        let back = ply::parse_cloud(&ply::cloud_to_bytes(&c, e).expect("encode")).expect("decode");
        assert_eq!(back.points, c.points, "{e:?}");
        assert_eq!(back.labels, c.labels);
        // Palette colours from labels, so viewers show the segments.
        let want: Vec<[u8; 3]> =
            c.labels.as_ref().map(|l| l.iter().map(|&l| PALETTE[l as usize]).collect()).expect("labels");
        assert_eq!(back.colors, Some(want));
    }
    c.normals = Some(c.points.iter().map(|p| [p[1], -p[0], 0.25]).collect());
    c.colors = Some((0..c.len()).map(|i| [i as u8, (i * 7) as u8, 3]).collect());
    for e in ENCODINGS {
        let bytes = ply::cloud_to_bytes(&c, e).expect("encode");
        let text = String::from_utf8_lossy(&bytes[..200]).to_string();
        assert!(text.contains(&format!("comment generated by bsv {}", env!("CARGO_PKG_VERSION"))), "{text}");
        assert!(text.contains("property double x"));
        let back = ply::parse_cloud(&bytes).expect("decode");
        assert_eq!(back, c, "{e:?}");
    }
}

#[test]
fn mesh_round_trips_with_labels() {
    let mut m = icosphere(0.37, 3);
    let nf = m.n_triangles();
    m.vertex_labels =
        Some(m.vertices.iter().map(|p| if p[1] > 0.0 { Segment::Torso.id() } else { Segment::ThighL.id() }).collect());
    m.face_labels = Some((0..nf).map(|t| (t % 15) as u8).collect());
    for e in ENCODINGS {
        let bytes = ply::mesh_to_bytes(&m, e).expect("encode");
        let back = ply::parse_mesh(&bytes).expect("decode");
        assert_eq!(back, m, "{e:?}");
        // The vertex palette colours are there for viewers.
        let data = ply::parse(&bytes).expect("decode");
        assert_eq!(
            data.colors.as_ref().map(|c| c[0]),
            Some(Segment::from_id(m.vertex_labels.as_ref().unwrap()[0]).unwrap().color())
        );
    }
    let plain = cuboid([1.0, 2.0, 3.0]);
    let back = ply::parse_mesh(&ply::mesh_to_bytes(&plain, PlyEncoding::BinaryLittleEndian).unwrap()).unwrap();
    assert_eq!(back, plain);
    // PlyData round trip keeps comments.
    let data = PlyData {
        comments: vec!["scanned by test".into()],
        ..ply::parse(&ply::mesh_to_bytes(&plain, PlyEncoding::Ascii).unwrap()).unwrap()
    };
    let again = ply::parse(&ply::to_bytes(&data, PlyEncoding::BinaryBigEndian).unwrap()).unwrap();
    assert!(again.comments.contains(&"scanned by test".to_string()));
    assert_eq!(again.points, data.points);
    assert_eq!(again.triangles, data.triangles);
}

fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("bsv_io_ply_{}_{name}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

#[test]
fn file_level_read_and_write() {
    let dir = tmp_dir("files");
    let mut m = cuboid([0.5, 0.25, 1.0]);
    m.face_labels = Some(vec![2; 12]);
    let p = dir.join("box.PLY");
    bio::write_mesh(&p, &m).expect("write");
    let bytes = std::fs::read(&p).expect("read back");
    assert!(bytes.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
    assert_eq!(bio::read_mesh(&p).expect("read"), m);
    let pa = dir.join("box_ascii.ply");
    bio::write_mesh_with(&pa, &m, PlyEncoding::Ascii).expect("write ascii");
    assert!(std::fs::read(&pa).unwrap().starts_with(b"ply\nformat ascii 1.0\n"));
    assert_eq!(bio::read_mesh(&pa).expect("read"), m);
    // A mesh PLY read as a cloud gives its vertices.
    assert_eq!(bio::read_point_cloud(&p).expect("cloud").points, m.vertices);
    let c = labelled_cloud(100);
    let pc = dir.join("cloud.ply");
    bio::write_point_cloud(&pc, &c).expect("write cloud");
    let back = bio::read_point_cloud(&pc).expect("read cloud");
    assert_eq!(back.points, c.points);
    assert_eq!(back.labels, c.labels);
    // A cloud is not a mesh.
    let err = bio::read_mesh(&pc).unwrap_err();
    assert!(matches!(err, ReadError::Ply { source: PlyError::NoFaces { vertices: 100 }, .. }), "{err}");
    assert!(err.to_string().contains("cloud.ply") && err.to_string().contains("point cloud"), "{err}");
    // Unknown extension.
    let err = bio::read_mesh(&dir.join("mesh.stl")).unwrap_err();
    assert!(matches!(err, ReadError::UnsupportedExtension { .. }));
    assert!(err.to_string().contains(".ply, .obj"), "{err}");
    let err = bio::write_mesh(&dir.join("mesh"), &m).unwrap_err();
    assert!(err.to_string().contains(".ply, .obj"), "{err}");
    // Missing file.
    let err = bio::read_point_cloud(&dir.join("missing.ply")).unwrap_err();
    assert!(matches!(err, ReadError::Io { .. }) && err.to_string().contains("missing.ply"), "{err}");
    // Empty file.
    let pe = dir.join("empty.ply");
    std::fs::write(&pe, b"").unwrap();
    let err = bio::read_point_cloud(&pe).unwrap_err();
    assert!(matches!(err, ReadError::Ply { source: PlyError::Empty, .. }), "{err}");
    assert!(err.to_string().contains("empty.ply") && err.to_string().contains("empty"), "{err}");
    // Writer refuses bad labels with a clear message.
    let mut bad = m.clone();
    bad.face_labels = Some(vec![2; 11]);
    let err = bio::write_mesh(&dir.join("bad.ply"), &bad).unwrap_err();
    assert!(err.to_string().contains("face_labels has 11 entries"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

const CLOUD_HEADER: &str = "ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\nend_header\n";

fn binary_cloud(n_declared: usize, n_written: usize, value: impl Fn(usize, usize) -> f32) -> Vec<u8> {
    let mut b = CLOUD_HEADER.replace("vertex 8", &format!("vertex {n_declared}")).into_bytes();
    for i in 0..n_written {
        for k in 0..3 {
            b.extend(value(i, k).to_le_bytes());
        }
    }
    b
}

#[test]
fn truncated_binary_body_is_a_typed_error() {
    let mut b = binary_cloud(8, 8, |i, k| (i * 3 + k) as f32);
    b.truncate(b.len() - 20); // cuts into record 6
    let err = ply::parse(&b).unwrap_err();
    match &err {
        PlyError::Truncated { element, index, count, needed, available, .. } => {
            assert_eq!((element.as_str(), *index, *count, *needed, *available), ("vertex", 6, 8, 96, 76));
        }
        other => panic!("wrong error {other:?}"),
    }
    let msg = err.to_string();
    assert!(msg.contains("vertex") && msg.contains("96") && msg.contains("76") && msg.contains("cut short"), "{msg}");
    // Truncated inside a face list (streamed path).
    let mut m = ply::mesh_to_bytes(&cuboid([1.0; 3]), PlyEncoding::BinaryLittleEndian).unwrap();
    m.truncate(m.len() - 5);
    let err = ply::parse(&m).unwrap_err();
    assert!(matches!(&err, PlyError::Truncated { element, index: 11, count: 12, .. } if element == "face"), "{err:?}");
    // Header without end_header.
    assert!(matches!(
        ply::parse(b"ply\nformat ascii 1.0\nelement vertex 3\n"),
        Err(PlyError::HeaderNotTerminated { .. })
    ));
}

#[test]
fn header_count_mismatch_is_a_typed_error() {
    // Fewer ascii records than declared.
    let text = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    let err = ply::parse(text).unwrap_err();
    assert!(matches!(&err, PlyError::EndsEarly { element, index: 3, count: 4 } if element == "vertex"), "{err:?}");
    assert!(err.to_string().contains("vertex") && err.to_string().contains("declares 4"), "{err}");
    // More records than declared (ascii and binary).
    let text = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    let err = ply::parse(text).unwrap_err();
    assert!(matches!(&err, PlyError::ExtraData { element, count: 2, .. } if element == "vertex"), "{err:?}");
    assert!(err.to_string().contains("line 10"), "{err}");
    let b = binary_cloud(6, 8, |i, k| (i + k + 1) as f32);
    let err = ply::parse(&b).unwrap_err();
    assert!(matches!(&err, PlyError::ExtraData { element, count: 6, .. } if element == "vertex"), "{err:?}");
    // Declared faces run into a vertex line of the wrong length.
    let text = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let err = ply::parse(text).unwrap_err();
    assert!(
        matches!(&err, PlyError::AsciiRecord { line: 13, element, index: 3, .. } if element == "vertex"),
        "{err:?}"
    );
    assert!(err.to_string().contains("more values"), "{err}");
}

#[test]
fn face_index_out_of_range_names_the_face() {
    let mut m = cuboid([1.0; 3]);
    m.triangles[5][2] = 8;
    // Bypass the writer's validation by patching an ascii file.
    let good = ply::mesh_to_bytes(&cuboid([1.0; 3]), PlyEncoding::Ascii).unwrap();
    let text = String::from_utf8(good).unwrap();
    let bad = text.replace("3 0 5 4\n", "3 0 5 8\n");
    assert_ne!(bad, text);
    let err = ply::parse(bad.as_bytes()).unwrap_err();
    assert!(matches!(err, PlyError::FaceIndexOutOfRange { face: 5, vertex_count: 8, .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.contains("face 5") && msg.contains("vertex 8") && msg.contains("8 vertices"), "{msg}");
    // Negative index in binary.
    let mut b = ply::mesh_to_bytes(&cuboid([1.0; 3]), PlyEncoding::BinaryLittleEndian).unwrap();
    let n = b.len();
    b[n - 4..].copy_from_slice(&(-1i32).to_le_bytes());
    assert!(matches!(ply::parse(&b), Err(PlyError::FaceIndexOutOfRange { face: 11, .. })));
    // Writer refuses out-of-range indices too.
    assert!(ply::mesh_to_bytes(&m, PlyEncoding::BinaryLittleEndian).is_err());
}

#[test]
fn nan_coordinates_name_the_vertex() {
    let b = binary_cloud(8, 8, |i, k| if i == 5 && k == 1 { f32::NAN } else { i as f32 });
    let err = ply::parse(&b).unwrap_err();
    assert!(matches!(err, PlyError::NonFinite { vertex: 5, .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.contains("vertex 5") && msg.contains("clean the cloud"), "{msg}");
    let text = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\nend_header\n0 0 0\n1 inf 0\n";
    assert!(matches!(ply::parse(text), Err(PlyError::NonFinite { vertex: 1, .. })));
    // Large clouds take the parallel path.
    let b = binary_cloud(200_000, 200_000, |i, _| if i == 123_456 { f32::INFINITY } else { 0.5 });
    assert!(matches!(ply::parse(&b), Err(PlyError::NonFinite { vertex: 123_456, .. })));
}

#[test]
fn other_bad_inputs_are_typed_errors() {
    assert_eq!(ply::parse(b""), Err(PlyError::Empty));
    assert_eq!(ply::parse(b"solid cube\nfacet normal 0 0 1\n"), Err(PlyError::BadMagic));
    assert!(matches!(
        ply::parse(b"ply\nformat binary_middle_endian 1.0\nend_header\n"),
        Err(PlyError::UnsupportedFormat { .. })
    ));
    assert!(matches!(ply::parse(b"ply\nformat ascii 2.0\nend_header\n"), Err(PlyError::UnsupportedFormat { .. })));
    assert!(matches!(ply::parse(b"ply\nelement vertex 0\nend_header\n"), Err(PlyError::MissingFormat)));
    let err = ply::parse(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n").unwrap_err();
    assert!(matches!(err, PlyError::UnknownType { line: 4, .. }), "{err:?}");
    let err =
        ply::parse(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n")
            .unwrap_err();
    assert!(
        matches!(&err, PlyError::MissingProperty { element, property, .. } if element == "vertex" && property == "z"),
        "{err:?}"
    );
    let err =
        ply::parse(b"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n")
            .unwrap_err();
    assert!(matches!(err, PlyError::MissingElement { .. }));
    // Label out of range names the element and record.
    let text = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty int label\nend_header\n0 0 0 1\n1 0 0 14\n0 1 0 15\n";
    let err = ply::parse(text).unwrap_err();
    assert!(
        matches!(&err, PlyError::LabelOutOfRange { element, index: 2, value } if element == "vertex" && *value == 15.0),
        "{err:?}"
    );
    assert!(err.to_string().contains("record 2") && err.to_string().contains("label 15"), "{err}");
    // Same in binary (fast path).
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty uchar label\nend_header\n".to_vec();
    for l in [3u8, 200] {
        for _ in 0..3 {
            b.extend(1.0f32.to_le_bytes());
        }
        b.push(l);
    }
    assert!(matches!(ply::parse(&b), Err(PlyError::LabelOutOfRange { index: 1, .. })));
    // Faces with fewer than three vertices, bad list counts, and non-numbers.
    let text = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n";
    assert!(matches!(ply::parse(text), Err(PlyError::FaceTooSmall { face: 0, n: 2 })));
    let text = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 zero 0\n";
    let err = ply::parse(text).unwrap_err();
    assert!(matches!(err, PlyError::AsciiRecord { line: 8, index: 0, .. }), "{err:?}");
    assert!(err.to_string().contains("\"zero\" is not a number"), "{err}");
    // CRLF headers are fine.
    let crlf = b"ply\r\nformat ascii 1.0\r\nelement vertex 1\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\nend_header\r\n1 2 3\r\n";
    assert_eq!(ply::parse_cloud(crlf).expect("crlf").points, vec![[1.0, 2.0, 3.0]]);
    // Classic Mac line endings (a lone CR), header and ascii body.
    let cr = b"ply\rformat ascii 1.0\relement vertex 2\rproperty float x\rproperty float y\rproperty float z\rend_header\r1 2 3\r4 5 6\r";
    assert_eq!(ply::parse_cloud(cr).expect("cr").points, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    // And a CR-only header before a binary body.
    let mut bin = b"ply\rformat binary_little_endian 1.0\relement vertex 1\rproperty float x\rproperty float y\rproperty float z\rend_header\r".to_vec();
    for v in [1.0f32, 2.0, 3.0] {
        bin.extend(v.to_le_bytes());
    }
    assert_eq!(ply::parse_cloud(&bin).expect("cr binary").points, vec![[1.0, 2.0, 3.0]]);
}

#[test]
fn empty_mesh_and_cloud_round_trip() {
    let m = TriMesh::default();
    let back = ply::parse_mesh(&ply::mesh_to_bytes(&m, PlyEncoding::BinaryLittleEndian).unwrap()).unwrap();
    assert_eq!(back, m);
    let c = PointCloud::default();
    assert_eq!(ply::parse_cloud(&ply::cloud_to_bytes(&c, PlyEncoding::Ascii).unwrap()).unwrap(), c);
}

#[test]
fn large_inputs_take_the_parallel_paths_exactly() {
    // Above the parallel thresholds: fused vertex blocks, triangle fast path, blocked writer.
    let mut c = labelled_cloud(150_000);
    c.normals = Some(c.points.iter().map(|p| [p[2], p[0], p[1]]).collect());
    for e in [PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian] {
        let back = ply::parse_cloud(&ply::cloud_to_bytes(&c, e).unwrap()).unwrap();
        assert_eq!(back.points, c.points);
        assert_eq!(back.normals, c.normals);
        assert_eq!(back.labels, c.labels);
    }
    let mut m = bsv_core::shapes::subdivided_cuboid([1.0, 2.0, 3.0], 80); // 76,800 triangles
    m.face_labels = Some((0..m.n_triangles()).map(|t| (t % 15) as u8).collect());
    m.vertex_labels = Some((0..m.n_vertices()).map(|v| (v % 13) as u8).collect());
    let bytes = ply::mesh_to_bytes(&m, PlyEncoding::BinaryLittleEndian).unwrap();
    assert_eq!(ply::parse_mesh(&bytes).unwrap(), m);
    // A bad label deep in a large binary cloud is found with its index.
    let mut bad = c.clone();
    bad.labels.as_mut().unwrap()[140_001] = 14;
    let mut bytes = ply::cloud_to_bytes(&bad, PlyEncoding::BinaryLittleEndian).unwrap();
    let stride = 24 + 24 + 3 + 1;
    let n = bytes.len();
    bytes[n - (150_000 - 140_001) * stride + stride - 1] = 99;
    let err = ply::parse(&bytes).unwrap_err();
    assert!(matches!(err, PlyError::LabelOutOfRange { index: 140_001, .. }), "{err:?}");
}
