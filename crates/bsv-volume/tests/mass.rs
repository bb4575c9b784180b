//! Mass properties against exact values: boxes, n-gon prisms (the exact prism formula), Tonon's
//! tetrahedron, a box cut into two labelled halves (each an exact box, their interface centre known),
//! all rotated and translated, to 1e-9 relative; and parry3d's mass properties as a second opinion.
#![allow(clippy::unwrap_used, clippy::needless_range_loop)]

use bsv_core::shapes::{cuboid, icosphere, subdivided_cuboid};
use bsv_core::{Segment, TriMesh};
use bsv_volume::{mass_properties, segment_mass_with, segment_volumes_with, MassProperties, SegmentOptions};
use std::f64::consts::PI;

type M3 = [[f64; 3]; 3];

/// A rotation matrix from axis-angle (Rodrigues).
fn rotation(axis: [f64; 3], angle: f64) -> M3 {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|a| a / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

fn mat_mul(a: &M3, b: &M3) -> M3 {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

fn transpose(a: &M3) -> M3 {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = a[j][i];
        }
    }
    m
}

fn apply(r: &M3, p: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2])
}

/// The mesh moved by x -> R x + t.
fn moved(mut m: TriMesh, r: &M3, t: [f64; 3]) -> TriMesh {
    for p in &mut m.vertices {
        let q = apply(r, *p);
        *p = [q[0] + t[0], q[1] + t[1], q[2] + t[2]];
    }
    m
}

/// Expected properties of a solid known in its own frame (centroid c0, diagonal or full inertia i0),
/// after x -> R x + t: centroid R c0 + t, inertia R I0 R^T.
fn expected_moved(volume: f64, c0: [f64; 3], i0: &M3, r: &M3, t: [f64; 3]) -> MassProperties {
    let c = apply(r, c0);
    MassProperties {
        volume_m3: volume,
        centroid: [c[0] + t[0], c[1] + t[1], c[2] + t[2]],
        inertia_m5: mat_mul(&mat_mul(r, i0), &transpose(r)),
    }
}

/// Relative agreement to `tol`: volume relative to itself, centroid relative to the solid's size
/// (cube root of the volume) plus the translation, inertia relative to its largest entry.
fn assert_close(got: &MassProperties, want: &MassProperties, scale_m: f64, tol: f64, what: &str) {
    assert!(
        (got.volume_m3 - want.volume_m3).abs() <= tol * want.volume_m3.abs(),
        "{what}: volume {} vs {}",
        got.volume_m3,
        want.volume_m3
    );
    for k in 0..3 {
        assert!(
            (got.centroid[k] - want.centroid[k]).abs() <= tol * scale_m,
            "{what}: centroid {:?} vs {:?}",
            got.centroid,
            want.centroid
        );
    }
    let big = want.inertia_m5.iter().flatten().fold(0.0f64, |a, b| a.max(b.abs()));
    for i in 0..3 {
        for j in 0..3 {
            assert!(
                (got.inertia_m5[i][j] - want.inertia_m5[i][j]).abs() <= tol * big,
                "{what}: inertia[{i}][{j}] {} vs {} (of {big})",
                got.inertia_m5[i][j],
                want.inertia_m5[i][j]
            );
        }
    }
}

fn poses() -> Vec<(M3, [f64; 3])> {
    vec![
        (rotation([1.0, 0.0, 0.0], 0.0), [0.0; 3]),
        (rotation([1.0, 2.0, 3.0], 0.7), [0.3, 1.2, -0.8]),
        (rotation([-2.0, 0.5, 1.0], 2.4), [12.0, -5.0, 40.0]),
    ]
}

fn box_inertia(size: [f64; 3]) -> M3 {
    let v = size[0] * size[1] * size[2];
    let [a, b, c] = size.map(|s| s * s);
    [[v * (b + c) / 12.0, 0.0, 0.0], [0.0, v * (a + c) / 12.0, 0.0], [0.0, 0.0, v * (a + b) / 12.0]]
}

#[test]
fn boxes_rotated_and_translated() {
    for size in [[1.0, 1.0, 1.0], [0.3, 0.12, 0.9], [2.0, 0.5, 0.05]] {
        let v = size[0] * size[1] * size[2];
        for (r, t) in poses() {
            for mesh in [cuboid(size), subdivided_cuboid(size, 5)] {
                let got = mass_properties(&moved(mesh, &r, t), false).unwrap();
                let want = expected_moved(v, [0.0; 3], &box_inertia(size), &r, t);
                assert_close(&got, &want, v.cbrt(), 1e-9, &format!("box {size:?}"));
            }
        }
    }
}

/// A right prism over a regular n-gon of circumradius `radius`, axis z, from z = 0 to `h`, outward.
fn ngon_prism(n: usize, radius: f64, h: f64) -> TriMesh {
    let mut v: Vec<[f64; 3]> = Vec::new();
    for z in [0.0, h] {
        for k in 0..n {
            let a = 2.0 * PI * k as f64 / n as f64;
            v.push([radius * a.cos(), radius * a.sin(), z]);
        }
    }
    v.push([0.0, 0.0, 0.0]);
    v.push([0.0, 0.0, h]);
    let (bottom, top) = ((2 * n) as u32, (2 * n + 1) as u32);
    let mut t = Vec::new();
    for k in 0..n as u32 {
        let k1 = (k + 1) % n as u32;
        let nn = n as u32;
        t.push([bottom, k1, k]);
        t.push([top, nn + k, nn + k1]);
        t.push([k, k1, nn + k1]);
        t.push([k, nn + k1, nn + k]);
    }
    TriMesh::new(v, t)
}

#[test]
fn ngon_prisms_match_the_exact_prism_formula() {
    // Regular n-gon, circumradius R, angle q = 2 pi / n: area A = n R^2 sin(q) / 2, polar moment
    // J = A R^2 (2 + cos q) / 6 (sum of the fan triangles' moments about the centre), so the prism
    // of height h has V = A h, Izz = J h, Ixx = Iyy = J h / 2 + V h^2 / 12 (per unit density).
    for (n, radius, h) in [(3, 0.1, 0.4), (7, 0.05, 0.3), (64, 0.06, 0.35), (1000, 0.2, 1.0)] {
        let q = 2.0 * PI / n as f64;
        let area = n as f64 * radius * radius * q.sin() / 2.0;
        let vol = area * h;
        let j = area * radius * radius * (2.0 + q.cos()) / 6.0;
        let ixx = j * h / 2.0 + vol * h * h / 12.0;
        let i0 = [[ixx, 0.0, 0.0], [0.0, ixx, 0.0], [0.0, 0.0, j * h]];
        for (r, t) in poses() {
            let got = mass_properties(&moved(ngon_prism(n, radius, h), &r, t), false).unwrap();
            let want = expected_moved(vol, [0.0, 0.0, h / 2.0], &i0, &r, t);
            assert_close(&got, &want, vol.cbrt(), 1e-9, &format!("{n}-gon prism"));
        }
        if n == 1000 {
            // ... and the cylinder it approximates, to the polygon's own error (~(2 pi / n)^2 / 6).
            let cyl = PI * radius * radius * h;
            assert!((vol - cyl).abs() / cyl < 1e-5);
        }
    }
}

#[test]
fn tonon_tetrahedron() {
    // Tonon (2004), J. Math. Stat. 1(1): 8-11, worked example (density 1): the tetrahedron below has
    // volume 1873.233236 and, about its centre of mass (the mean of its vertices; the paper prints
    // z = 3.732962 where the mean is 3.7296175),
    // a = 43520.33257, b = 194711.28938, c = 191168.76173 (moments about x, y, z) and
    // a' = 4417.66150 (yz), b' = -46343.16662 (zx), c' = 11996.20119 (xy): I = [[a, -c', -b'], [-c', b, -a'], [-b', -a', c]].
    let p = [
        [8.33220, -11.86875, 0.93355],
        [0.75523, 5.00000, 16.37072],
        [52.61236, 5.00000, -5.38580],
        [2.00000, 5.00000, 3.00000],
    ];
    // Outward faces: orient each face away from the opposite vertex.
    let mut tris = Vec::new();
    for skip in 0..4u32 {
        let f: Vec<u32> = (0..4u32).filter(|&k| k != skip).collect();
        let (a, b, c) = (p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]);
        let o = p[skip as usize];
        let n = [
            (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]),
            (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]),
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]),
        ];
        let away = n[0] * (a[0] - o[0]) + n[1] * (a[1] - o[1]) + n[2] * (a[2] - o[2]);
        tris.push(if away > 0.0 { [f[0], f[1], f[2]] } else { [f[0], f[2], f[1]] });
    }
    let got = mass_properties(&TriMesh::new(p.to_vec(), tris), false).unwrap();
    let (a, b, c) = (43520.33257, 194711.28938, 191168.76173);
    let (a1, b1, c1) = (4417.66150, -46343.16662, 11996.20119);
    let want = MassProperties {
        volume_m3: 1873.233236,
        centroid: [0, 1, 2].map(|k| p.iter().map(|q| q[k]).sum::<f64>() / 4.0),
        inertia_m5: [[a, -c1, -b1], [-c1, b, -a1], [-b1, -a1, c]],
    };
    // The paper prints 7-10 significant digits.
    assert_close(&got, &want, 1.0, 1e-6, "Tonon tetrahedron");
}

#[test]
fn box_cut_in_two_labelled_halves_gives_exact_boxes_and_the_joint_centre() {
    // A 2 x 1 x 0.6 box labelled by the plane x = 0: each half is a 1 x 1 x 0.6 box, closed by the
    // shared planar cap; the interface (cap apex) is the box centre.
    let size = [2.0, 1.0, 0.6];
    for (r, t) in poses() {
        let mut m = subdivided_cuboid(size, 6);
        let labels = m
            .triangles
            .iter()
            .map(|tri| {
                let x: f64 = tri.iter().map(|&k| m.vertices[k as usize][0]).sum();
                if x < 0.0 {
                    Segment::UpperArmL.id()
                } else {
                    Segment::ForearmL.id()
                }
            })
            .collect();
        m.face_labels = Some(labels);
        let m = moved(m, &r, t);
        let sm = segment_mass_with(&m, &SegmentOptions::default()).unwrap();
        let half = [1.0, 1.0, 0.6];
        let vh = 0.6;
        for (s, cx) in [(Segment::UpperArmL, -0.5), (Segment::ForearmL, 0.5)] {
            let want = expected_moved(vh, [cx, 0.0, 0.0], &box_inertia(half), &r, t);
            assert_close(&sm.segments[&s], &want, 1.0, 1e-9, s.name());
        }
        let whole = expected_moved(1.2, [0.0; 3], &box_inertia(size), &r, t);
        assert_close(&sm.whole, &whole, 1.0, 1e-9, "whole");
        assert_eq!(sm.interfaces.len(), 1);
        let i = &sm.interfaces[0];
        assert!(i.closed);
        assert_eq!((i.lo, i.hi), (Segment::UpperArmL.id(), Segment::ForearmL.id()));
        for k in 0..3 {
            assert!((i.centroid[k] - t[k]).abs() < 1e-12, "{:?} vs {t:?}", i.centroid);
        }
    }
}

#[test]
fn segment_moments_add_up_and_volumes_match_segment_volumes() {
    // Scattered labels with junctions: volumes equal segment_volumes', and the volume-weighted
    // centroids and parallel-axis inertias of the parts add up to the whole's.
    let mut m = icosphere(0.4, 3);
    let labels: Vec<u8> = m
        .triangles
        .iter()
        .map(|tri| {
            let c = tri.iter().fold([0.0; 3], |a, &k| {
                let p = m.vertices[k as usize];
                [a[0] + p[0], a[1] + p[1], a[2] + p[2]]
            });
            1 + ((c[0] * 7.0).floor() as i64 + (c[1] * 5.0).floor() as i64 * 3).rem_euclid(5) as u8
        })
        .collect();
    m.face_labels = Some(labels);
    let m = moved(m, &rotation([0.2, 1.0, -0.4], 1.1), [1.0, 0.9, -0.3]);
    let sm = segment_mass_with(&m, &SegmentOptions::default()).unwrap();
    let sv = segment_volumes_with(&m, &SegmentOptions::default()).unwrap();
    assert!(sm.segments.len() >= 4);
    let (mut v, mut mx, mut it) = (0.0, [0.0; 3], [[0.0; 3]; 3]);
    for (s, p) in &sm.segments {
        assert!((p.volume_m3 - sv.segments[s]).abs() < 1e-15, "{s}");
        v += p.volume_m3;
        for k in 0..3 {
            mx[k] += p.volume_m3 * p.centroid[k];
        }
    }
    let c = mx.map(|x| x / v);
    for p in sm.segments.values() {
        // Parallel axis: I_whole = sum (I_i + V_i (|d|^2 E - d d^T)), d = c_i - c.
        let d = [0, 1, 2].map(|k| p.centroid[k] - c[k]);
        let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        for i in 0..3 {
            for j in 0..3 {
                let e = if i == j { d2 } else { 0.0 };
                it[i][j] += p.inertia_m5[i][j] + p.volume_m3 * (e - d[i] * d[j]);
            }
        }
    }
    let sum = MassProperties { volume_m3: v, centroid: c, inertia_m5: it };
    assert_close(&sum, &sm.whole, 0.4, 1e-9, "sum of segments");
}

#[test]
fn inward_mesh_is_negated_and_open_mesh_is_an_error() {
    let mut m = cuboid([1.0, 2.0, 3.0]);
    for t in &mut m.triangles {
        t.swap(1, 2);
    }
    assert!(mass_properties(&m, false).unwrap().volume_m3 < 0.0);
    m.face_labels = Some(vec![Segment::Torso.id(); 12]);
    let sm = segment_mass_with(&m, &SegmentOptions::default()).unwrap();
    assert!(sm.inverted);
    assert!((sm.segments[&Segment::Torso].volume_m3 - 6.0).abs() < 1e-12);
    let mut open = cuboid([1.0; 3]);
    open.triangles.pop();
    assert!(mass_properties(&open, false).is_err());
    let closed = mass_properties(&open, true).unwrap();
    assert!(closed.volume_m3 > 0.0);
}

#[test]
fn parry_agrees() {
    use parry3d_f64::mass_properties::MassProperties as Parry;
    use parry3d_f64::math::Vector;
    let r = rotation([1.0, -1.0, 2.0], 0.9);
    for mesh in [moved(ngon_prism(12, 0.1, 0.5), &r, [0.5, 1.0, 0.2]), moved(icosphere(0.3, 3), &r, [2.0, 0.0, 1.0])] {
        let ours = mass_properties(&mesh, false).unwrap();
        let v: Vec<Vector> = mesh.vertices.iter().map(|p| Vector::new(p[0], p[1], p[2])).collect();
        let theirs = Parry::from_trimesh(1.0, &v, &mesh.triangles);
        let it = theirs.reconstruct_inertia_matrix().to_cols_array_2d();
        let com = theirs.local_com;
        let want = MassProperties { volume_m3: theirs.mass(), centroid: [com.x, com.y, com.z], inertia_m5: it };
        // parry sums from its own centre of mass estimate: agreement to a few 1e-9 (ours meets the
        // exact prism formula to 1e-9 above).
        assert_close(&ours, &want, 0.3, 2e-8, "parry");
    }
}

#[test]
fn ellipsoids_exact_under_the_linear_map_and_converging_to_the_analytic_solid() {
    // A polyhedral ellipsoid is the sphere mesh mapped by A = diag(a, b, c): V' = det(A) V and the
    // second moments about the centroid C' = det(A) A C A^T, exactly (1e-9). Against the smooth ellipsoid
    // (V = 4/3 pi a b c, Ixx = V (b^2 + c^2) / 5, ...) the error is the polyhedron's, shrinking ~4x per
    // subdivision level.
    let radii = [0.12, 0.3, 0.07];
    let mut previous = f64::INFINITY;
    for level in [3, 4, 5] {
        let sphere = icosphere(1.0, level);
        let s = mass_properties(&sphere, false).unwrap();
        let mut ell = sphere.clone();
        for p in &mut ell.vertices {
            *p = [0, 1, 2].map(|k| p[k] * radii[k]);
        }
        let (r, t) = (rotation([0.3, 1.0, -0.2], 1.3), [0.4, 1.0, 0.1]);
        let got = mass_properties(&moved(ell, &r, t), false).unwrap();
        // Second moments of the sphere mesh about its centroid, C = tr(I)/2 E - I, mapped by A.
        let tr = (s.inertia_m5[0][0] + s.inertia_m5[1][1] + s.inertia_m5[2][2]) / 2.0;
        let det = radii[0] * radii[1] * radii[2];
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let cij = if i == j { tr - s.inertia_m5[i][j] } else { -s.inertia_m5[i][j] };
                c[i][j] = det * radii[i] * cij * radii[j];
            }
        }
        let trc = c[0][0] + c[1][1] + c[2][2];
        let mut i0 = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                i0[i][j] = if i == j { trc - c[i][j] } else { -c[i][j] };
            }
        }
        let centroid0 = [0, 1, 2].map(|k| s.centroid[k] * radii[k]);
        let want = expected_moved(s.volume_m3 * det, centroid0, &i0, &r, t);
        assert_close(&got, &want, 0.1, 1e-9, &format!("ellipsoid level {level}"));
        // ... and the smooth ellipsoid, to the discretisation error.
        let v = 4.0 / 3.0 * PI * det;
        let [a2, b2, c2] = radii.map(|x| x * x);
        let smooth = expected_moved(
            v,
            [0.0; 3],
            &[[v * (b2 + c2) / 5.0, 0.0, 0.0], [0.0, v * (a2 + c2) / 5.0, 0.0], [0.0, 0.0, v * (a2 + b2) / 5.0]],
            &r,
            t,
        );
        let err = (got.volume_m3 - v).abs() / v;
        assert!(err < previous / 3.0, "level {level}: {err} after {previous}");
        previous = err;
        let tol = 3.0 * err;
        assert_close(&got, &smooth, 0.1, tol, &format!("smooth ellipsoid level {level}"));
    }
    assert!(previous < 2e-3, "{previous}");
}
