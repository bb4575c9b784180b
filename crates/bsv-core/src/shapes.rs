//! Analytic shapes with known volumes (tests, benchmarks, examples). Surface sampling is
//! `bsv_capture::sample::sample_surface`.

use crate::geometry::{add, normalize, scale};
use crate::TriMesh;
use std::collections::HashMap;

/// An axis-aligned box centred at the origin with edge lengths `size`, 12 outward triangles.
pub fn cuboid(size: [f64; 3]) -> TriMesh {
    let h = scale(size, 0.5);
    let vertices = (0..8)
        .map(|i| {
            [
                if i & 1 == 0 { -h[0] } else { h[0] },
                if i & 2 == 0 { -h[1] } else { h[1] },
                if i & 4 == 0 { -h[2] } else { h[2] },
            ]
        })
        .collect();
    let triangles = vec![
        [0, 2, 3],
        [0, 3, 1], // z-
        [4, 5, 7],
        [4, 7, 6], // z+
        [0, 1, 5],
        [0, 5, 4], // y-
        [2, 6, 7],
        [2, 7, 3], // y+
        [0, 4, 6],
        [0, 6, 2], // x-
        [1, 3, 7],
        [1, 7, 5], // x+
    ];
    TriMesh::new(vertices, triangles)
}

/// A box with every face split into an `n` x `n` grid (2 n^2 triangles per face), outward.
pub fn subdivided_cuboid(size: [f64; 3], n: usize) -> TriMesh {
    let n = n.max(1);
    let h = scale(size, 0.5);
    let mut index: HashMap<[i64; 3], u32> = HashMap::new();
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    // Each face: fixed axis, sign, and the two in-plane axes ordered so that u x v points outward.
    let faces: [(usize, f64, usize, usize); 6] =
        [(0, 1.0, 1, 2), (0, -1.0, 2, 1), (1, 1.0, 2, 0), (1, -1.0, 0, 2), (2, 1.0, 0, 1), (2, -1.0, 1, 0)];
    let ni = n as i64;
    for (axis, sign, u, v) in faces {
        let mut id = |i: i64, j: i64, vertices: &mut Vec<[f64; 3]>| -> u32 {
            let mut key = [0i64; 3];
            key[axis] = if sign > 0.0 { ni } else { 0 };
            key[u] = i;
            key[v] = j;
            *index.entry(key).or_insert_with(|| {
                let p = [0, 1, 2].map(|k| -h[k] + size[k] * key[k] as f64 / n as f64);
                vertices.push(p);
                (vertices.len() - 1) as u32
            })
        };
        for i in 0..ni {
            for j in 0..ni {
                let a = id(i, j, &mut vertices);
                let b = id(i + 1, j, &mut vertices);
                let c = id(i + 1, j + 1, &mut vertices);
                let d = id(i, j + 1, &mut vertices);
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
    }
    TriMesh::new(vertices, triangles)
}

/// An icosphere of radius `r` centred at the origin after `level` 4-to-1 subdivisions, outward.
pub fn icosphere(r: f64, level: u32) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut vertices: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|&p| scale(normalize(p), r))
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(triangles.len() * 4);
        let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<[f64; 3]>| -> u32 {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                let p = scale(add(vertices[a as usize], vertices[b as usize]), 0.5);
                vertices.push(scale(normalize(p), r));
                (vertices.len() - 1) as u32
            })
        };
        for [a, b, c] in triangles {
            let ab = midpoint(a, b, &mut vertices);
            let bc = midpoint(b, c, &mut vertices);
            let ca = midpoint(c, a, &mut vertices);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    TriMesh::new(vertices, triangles)
}

/// An icosphere scaled per axis into an ellipsoid with semi-axes `radii`.
pub fn ellipsoid(radii: [f64; 3], level: u32) -> TriMesh {
    let mut m = icosphere(1.0, level);
    for p in &mut m.vertices {
        *p = [p[0] * radii[0], p[1] * radii[1], p[2] * radii[2]];
    }
    m
}

/// A capsule along +y from y = 0 to y = `length` (cylinder part) plus hemispherical caps of radius `r`.
/// `rings` latitude bands per hemisphere, `segments` around, `stacks` along the cylinder.
pub fn capsule(r: f64, length: f64, segments: usize, rings: usize, stacks: usize) -> TriMesh {
    let segments = segments.max(3);
    let rings = rings.max(1);
    let stacks = stacks.max(1);
    // Profile from bottom pole to top pole: (radius, y).
    let mut profile = Vec::new();
    for i in 1..=rings {
        let a = -std::f64::consts::FRAC_PI_2 + std::f64::consts::FRAC_PI_2 * i as f64 / rings as f64;
        profile.push((r * a.cos(), r * a.sin()));
    }
    for i in 1..stacks {
        profile.push((r, length * i as f64 / stacks as f64));
    }
    for i in 0..rings {
        let a = std::f64::consts::FRAC_PI_2 * i as f64 / rings as f64;
        profile.push((r * a.cos(), length + r * a.sin()));
    }
    let mut vertices = vec![[0.0, -r, 0.0]];
    for &(rad, y) in &profile {
        for s in 0..segments {
            let phi = std::f64::consts::TAU * s as f64 / segments as f64;
            vertices.push([rad * phi.cos(), y, -rad * phi.sin()]);
        }
    }
    let top = vertices.len() as u32;
    vertices.push([0.0, length + r, 0.0]);
    let ring = |k: usize, s: usize| (1 + k * segments + s % segments) as u32;
    let mut triangles = Vec::new();
    for s in 0..segments {
        triangles.push([0, ring(0, s + 1), ring(0, s)]);
    }
    for k in 0..profile.len() - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (ring(k, s), ring(k, s + 1), ring(k + 1, s + 1), ring(k + 1, s));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    let last = profile.len() - 1;
    for s in 0..segments {
        triangles.push([top, ring(last, s), ring(last, s + 1)]);
    }
    TriMesh::new(vertices, triangles)
}

/// Rotates every vertex about the vertical (y) axis by `angle` radians.
pub fn rotate_y(mesh: &mut TriMesh, angle: f64) {
    let (s, c) = angle.sin_cos();
    for p in &mut mesh.vertices {
        *p = [c * p[0] + s * p[2], p[1], -s * p[0] + c * p[2]];
    }
}

/// Translates every vertex by `t`.
pub fn translate(mesh: &mut TriMesh, t: [f64; 3]) {
    for p in &mut mesh.vertices {
        *p = add(*p, t);
    }
}

/// Appends `part` to `mesh`, every new face labelled `label` (face labels are created if absent).
pub fn append_labelled(mesh: &mut TriMesh, part: TriMesh, label: u8) {
    let off = mesh.vertices.len() as u32;
    let n_old = mesh.triangles.len();
    mesh.vertices.extend(part.vertices);
    let labels = mesh.face_labels.get_or_insert_with(|| vec![0; n_old]);
    labels.extend(std::iter::repeat_n(label, part.triangles.len()));
    mesh.triangles.extend(part.triangles.iter().map(|t| t.map(|i| i + off)));
}

/// A crude labelled "body" standing on y = 0 for scanner tests and benchmarks: capsules for the torso,
/// arms and legs, a sphere head and (with `hands`) sphere hands, each a separate closed part.
/// `fine` raises the tessellation from ~5k to ~27k triangles.
pub fn capsule_body(fine: bool, hands: bool) -> TriMesh {
    let (torso_res, arm_res, leg_res, ico) =
        if fine { ((64, 12, 40), (32, 6, 30), (40, 8, 50), 4) } else { ((32, 8, 10), (16, 4, 6), (20, 4, 8), 3) };
    let mut m = TriMesh::default();
    let mut torso = capsule(0.15, 0.45, torso_res.0, torso_res.1, torso_res.2);
    translate(&mut torso, [0.0, 0.98, 0.0]);
    append_labelled(&mut m, torso, 2);
    let mut head = icosphere(0.1, ico);
    translate(&mut head, [0.0, 1.72, 0.0]);
    append_labelled(&mut m, head, 1);
    for (x, arm, leg, hand) in [(0.26, 3u8, 9u8, 7u8), (-0.26, 4, 10, 8)] {
        let mut a = capsule(0.045, 0.5, arm_res.0, arm_res.1, arm_res.2);
        translate(&mut a, [x, 0.9, 0.0]);
        append_labelled(&mut m, a, arm);
        if hands {
            let mut h = icosphere(0.04, 2);
            translate(&mut h, [x * 1.25, 0.55, 0.0]);
            append_labelled(&mut m, h, hand);
        }
        let mut l = capsule(0.07, 0.75, leg_res.0, leg_res.1, leg_res.2);
        translate(&mut l, [x * 0.4, 0.08, 0.0]);
        append_labelled(&mut m, l, leg);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::signed_volume;

    #[test]
    fn known_volumes() {
        let c = cuboid([1.0, 2.0, 3.0]);
        assert!((signed_volume(&c.vertices, &c.triangles) - 6.0).abs() < 1e-12);
        let s = subdivided_cuboid([0.5, 0.4, 0.3], 4);
        assert!((signed_volume(&s.vertices, &s.triangles) - 0.06).abs() < 1e-12);
        assert_eq!(s.n_vertices(), 6 * 16 + 2);
        let ico = icosphere(1.0, 4);
        let v = signed_volume(&ico.vertices, &ico.triangles);
        assert!(v > 0.0 && (v - 4.0 / 3.0 * std::f64::consts::PI).abs() / v < 0.01);
        let cap = capsule(0.1, 0.5, 64, 16, 8);
        let exact = std::f64::consts::PI * 0.01 * 0.5 + 4.0 / 3.0 * std::f64::consts::PI * 0.001;
        let v = signed_volume(&cap.vertices, &cap.triangles);
        assert!(v > 0.0 && (v - exact).abs() / exact < 0.01, "{v} {exact}");
    }
}
