//! Property tests: random bytes and random mutations of valid PLY/OBJ files never make the readers
//! panic (they return a value or a typed error), and what parses as a mesh is internally consistent.
#![allow(clippy::unwrap_used)]

use bsv_core::io::{obj, ply, PlyEncoding};
use bsv_core::shapes::cuboid;
use bsv_core::PointCloud;
use proptest::prelude::*;

fn valid_ply(encoding: PlyEncoding) -> Vec<u8> {
    let mut m = cuboid([1.0, 2.0, 0.5]);
    m.vertex_labels = Some(vec![1, 2, 3, 4, 5, 6, 7, 8]);
    m.face_labels = Some((0..12).collect());
    ply::mesh_to_bytes(&m, encoding).expect("valid mesh")
}

fn valid_cloud_ply(encoding: PlyEncoding) -> Vec<u8> {
    let mut c = PointCloud::new((0..6).map(|i| [i as f64, 0.5 * i as f64, -1.0]).collect());
    c.normals = Some(vec![[0.0, 0.0, 1.0]; 6]);
    c.colors = Some(vec![[1, 2, 3]; 6]);
    ply::cloud_to_bytes(&c, encoding).expect("valid cloud")
}

/// A PLY with lists in unusual places (vertex list property, unknown list element, ushort counts).
fn odd_ply() -> Vec<u8> {
    let mut b =
        b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty list ushort char tags\n\
property float y\nproperty float z\nelement material 1\nproperty list uint uchar name\nelement face 1\n\
property list ushort uint vertex_index\nproperty short label\nend_header\n"
            .to_vec();
    for i in 0..3u16 {
        b.extend((i as f32).to_be_bytes());
        b.extend(2u16.to_be_bytes());
        b.extend([1u8, 255]);
        b.extend(1.5f32.to_be_bytes());
        b.extend((-(i as f32)).to_be_bytes());
    }
    b.extend(3u32.to_be_bytes());
    b.extend(b"abc");
    b.extend(3u16.to_be_bytes());
    for i in [0u32, 1, 2] {
        b.extend(i.to_be_bytes());
    }
    b.extend(4i16.to_be_bytes());
    b
}

const VALID_OBJ: &str = "# test\nmtllib a.mtl\nv 0 0 0\nv 1 0 0 1\nv 1 1 0\nv 0 1 0 0.5 0.5 0.5\nv 0.5 0.5 1\nvt 0 0\nvn 0 0 1\n\
g torso\nf 1/1/1 2/1/1 3/1/1 4/1/1\no thigh_l\nf -5//1 -4//1 -1//1\ng unknown\nf 2/1 3/1 5/1\ns 1\nusemtl m\nf 3 4 5\nf 4 1 5\n";

/// Mesh invariants of anything the parsers accept.
fn assert_consistent_ply(bytes: &[u8]) {
    if let Ok(d) = ply::parse(bytes) {
        let n = d.points.len();
        assert!(d.points.iter().all(|p| p.iter().all(|c| c.is_finite())));
        for l in
            [d.normals.as_ref().map(Vec::len), d.colors.as_ref().map(Vec::len), d.vertex_labels.as_ref().map(Vec::len)]
                .into_iter()
                .flatten()
        {
            assert_eq!(l, n);
        }
        if let Some(t) = &d.triangles {
            assert!(t.iter().all(|t| t.iter().all(|&i| (i as usize) < n)));
            if let Some(fl) = &d.face_labels {
                assert_eq!(fl.len(), t.len());
            }
        }
        assert!(d.vertex_labels.iter().flatten().chain(d.face_labels.iter().flatten()).all(|&l| l <= 14));
        // Whatever was read can be written back and read again identically.
        let again =
            ply::parse(&ply::to_bytes(&d, PlyEncoding::BinaryLittleEndian).expect("re-encode")).expect("re-read");
        assert_eq!(again.points, d.points);
        assert_eq!(again.triangles, d.triangles);
    }
}

fn assert_consistent_obj(bytes: &[u8]) {
    if let Ok((m, _)) = obj::parse(bytes) {
        let n = m.n_vertices();
        assert!(m.triangles.iter().all(|t| t.iter().all(|&i| (i as usize) < n)));
        if let Some(fl) = &m.face_labels {
            assert_eq!(fl.len(), m.n_triangles());
        }
        if let Some(vl) = &m.vertex_labels {
            assert_eq!(vl.len(), n);
        }
    }
    let _ = obj::parse_points(bytes);
}

#[derive(Debug, Clone)]
enum Mutation {
    Flip(usize, u8),
    Truncate(usize),
    Insert(usize, Vec<u8>),
    Delete(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::Flip(i, b)),
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), prop::collection::vec(any::<u8>(), 1..8)).prop_map(|(i, v)| Mutation::Insert(i, v)),
        (any::<usize>(), 1usize..16).prop_map(|(i, n)| Mutation::Delete(i, n)),
    ]
}

fn apply(mut b: Vec<u8>, muts: &[Mutation]) -> Vec<u8> {
    for m in muts {
        let len = b.len().max(1);
        match m {
            Mutation::Flip(i, x) => {
                if !b.is_empty() {
                    b[i % len] ^= x | 1;
                }
            }
            Mutation::Truncate(i) => b.truncate(i % len),
            Mutation::Insert(i, v) => {
                let at = i % (b.len() + 1);
                b.splice(at..at, v.iter().copied());
            }
            Mutation::Delete(i, n) => {
                let at = i % len;
                let end = (at + n).min(b.len());
                if at < end {
                    b.drain(at..end);
                }
            }
        }
    }
    b
}

/// Mutations aimed at the header text (digits and keywords are where the interesting failures are).
fn header_mutation() -> impl Strategy<Value = (usize, &'static str)> {
    (
        any::<usize>(),
        prop::sample::select(vec![
            "0",
            "9",
            "99999999999",
            "18446744073709551615",
            "-1",
            "list",
            "uchar",
            "double",
            "char",
            "\n",
            " ",
            "element",
            "property",
            "end_header\n",
            "face",
            "vertex",
        ]),
    )
}

/// Cases per property: 4000 by default (a few seconds), more with `BSV_FUZZ_CASES=N`.
fn fuzz_cases() -> u32 {
    std::env::var("BSV_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(4000)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: fuzz_cases(), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        assert_consistent_ply(&bytes);
        assert_consistent_obj(&bytes);
        let mut with_magic = b"ply\n".to_vec();
        with_magic.extend(&bytes);
        assert_consistent_ply(&with_magic);
        let mut with_header = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
        with_header.extend(&bytes);
        assert_consistent_ply(&with_header);
    }

    #[test]
    fn mutated_ply_never_panics(which in 0usize..6, muts in prop::collection::vec(mutation(), 1..5)) {
        let base = match which {
            0 => valid_ply(PlyEncoding::BinaryLittleEndian),
            1 => valid_ply(PlyEncoding::BinaryBigEndian),
            2 => valid_ply(PlyEncoding::Ascii),
            3 => valid_cloud_ply(PlyEncoding::BinaryLittleEndian),
            4 => valid_cloud_ply(PlyEncoding::Ascii),
            _ => odd_ply(),
        };
        assert_consistent_ply(&apply(base, &muts));
    }

    #[test]
    fn mutated_ply_header_never_panics(which in 0usize..3, edits in prop::collection::vec(header_mutation(), 1..4)) {
        let mut b = match which {
            0 => valid_ply(PlyEncoding::BinaryLittleEndian),
            1 => valid_ply(PlyEncoding::Ascii),
            _ => odd_ply(),
        };
        let header_len = b.windows(11).position(|w| w == b"end_header\n").unwrap_or(0);
        for (i, s) in edits {
            let at = i % (header_len + 1);
            b.splice(at..at, s.bytes());
        }
        assert_consistent_ply(&b);
    }

    #[test]
    fn mutated_obj_never_panics(muts in prop::collection::vec(mutation(), 1..6)) {
        assert_consistent_obj(&apply(VALID_OBJ.as_bytes().to_vec(), &muts));
    }

    #[test]
    fn random_obj_lines_never_panic(lines in prop::collection::vec(
        prop_oneof![
            Just("v 0 0 0".to_string()),
            Just("g torso".to_string()),
            Just("o".to_string()),
            (-4i64..6, -4i64..6, -4i64..6, prop::option::of(-4i64..6)).prop_map(|(a, b, c, d)| match d {
                Some(d) => format!("f {a}/1 {b}//2 {c}/3/4 {d}"),
                None => format!("f {a} {b} {c}"),
            }),
            "[ -~]{0,20}",
        ],
        0..20,
    )) {
        assert_consistent_obj(lines.join("\n").as_bytes());
    }
}

#[test]
fn the_seeds_are_valid() {
    for b in [
        valid_ply(PlyEncoding::BinaryLittleEndian),
        valid_ply(PlyEncoding::BinaryBigEndian),
        valid_ply(PlyEncoding::Ascii),
        odd_ply(),
    ] {
        let m = ply::parse_mesh(&b).expect("seed parses");
        assert!(!m.triangles.is_empty());
    }
    let d = ply::parse(&odd_ply()).expect("odd");
    assert_eq!(d.points, vec![[0.0, 1.5, 0.0], [1.0, 1.5, -1.0], [2.0, 1.5, -2.0]]);
    assert_eq!(d.face_labels, Some(vec![4]));
    assert_eq!(ply::parse_cloud(&valid_cloud_ply(PlyEncoding::Ascii)).expect("cloud").len(), 6);
    let (m, r) = obj::parse(VALID_OBJ.as_bytes()).expect("obj seed");
    assert_eq!(m.n_triangles(), 6);
    assert_eq!(m.face_labels, Some(vec![2, 2, 9, 0, 0, 0]));
    assert_eq!(r.unknown_groups, vec!["unknown".to_string()]);
}
