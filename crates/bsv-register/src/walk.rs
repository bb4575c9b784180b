//! Warm-started nearest-vertex search of p2m: each cloud point starts at the vertex it went to in
//! the previous p2m iteration and walks over the mesh's edges to the neighbour nearest to it until
//! no neighbour is nearer (greedy descent of the distance on the vertex graph).
//!
//! Between two iterations the vertices move by a few millimetres at most (the `moved` column of
//! the iteration log), so the nearest vertex of a point is its previous one or a neighbour of it: the
//! walk takes one or two steps of a 1-ring each (about 14 distances) where a k-d tree query over
//! the vertices visits several leaves of 32 points, and it needs no tree rebuilt per iteration.
//! The descent stops at a local minimum of the distance on the graph, which is the nearest vertex
//! for points near the surface; a point far from it (deep inside a limb, where the nearest vertex
//! is ambiguous anyway) may stop at a vertex slightly farther than the nearest. `tests` measure how
//! often and by how much on a fit; the registration runs the first p2m iteration of every p2m stage
//! with the exact k-d tree search.
//!
//! With label-aware matching a point of segment L walks only over vertices of segment L (the
//! vertices the exact search allows it).

use crate::cotan::CotanWeights;
use bsv_core::geometry::dist2;
use rayon::prelude::*;

/// Which vertices a point of a given label may go to.
#[derive(Debug, Clone, Copy)]
pub struct Allowed<'a> {
    /// The label of every cloud point.
    pub point_labels: &'a [u8],
    /// The label of every vertex.
    pub vertex_labels: &'a [u8],
    /// `restricted[l]`: points of label `l` go only to vertices of label `l` (otherwise anywhere).
    pub restricted: &'a [bool],
}

/// From vertex `start`, the greedy descent toward `p` over the edges of `graph` (only through
/// vertices of label `only` when given): the vertex where it stops and its squared distance to `p`.
#[inline]
fn descend(
    graph: &CotanWeights,
    vertices: &[[f64; 3]],
    p: [f64; 3],
    start: u32,
    only: Option<(u8, &[u8])>,
) -> (u32, f64) {
    let mut v = start;
    let mut best = dist2(p, vertices[v as usize]);
    loop {
        let mut next = v;
        let (row, _) = graph.row(v as usize);
        for &u in row {
            if let Some((l, vl)) = only {
                if vl[u as usize] != l {
                    continue;
                }
            }
            let d = dist2(p, vertices[u as usize]);
            if d < best {
                best = d;
                next = u;
            }
        }
        if next == v {
            return (v, best);
        }
        v = next;
    }
}

/// The vertex each of `points` walks to from its `start` vertex: (vertex index, squared distance),
/// in point order. `start` holds one valid vertex index per point (the previous iteration's result).
pub fn walk_to_nearest(
    graph: &CotanWeights,
    vertices: &[[f64; 3]],
    points: &[[f64; 3]],
    start: &[u32],
    allowed: Option<Allowed<'_>>,
) -> Vec<(u32, f64)> {
    points
        .par_iter()
        .with_min_len(4096)
        .enumerate()
        .map(|(i, &p)| {
            let only = allowed.and_then(|a| {
                let l = a.point_labels[i];
                a.restricted.get(l as usize).copied().unwrap_or(false).then_some((l, a.vertex_labels))
            });
            descend(graph, vertices, p, start[i], only)
        })
        .collect()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::correspond::{build_tree, nearest_batch};

    /// A UV sphere (rows x cols) of radius `r`.
    fn sphere(rows: usize, cols: usize, r: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut v = vec![[0.0, r, 0.0]];
        for i in 1..rows {
            let th = std::f64::consts::PI * i as f64 / rows as f64;
            for j in 0..cols {
                let ph = 2.0 * std::f64::consts::PI * j as f64 / cols as f64;
                v.push([r * th.sin() * ph.cos(), r * th.cos(), r * th.sin() * ph.sin()]);
            }
        }
        v.push([0.0, -r, 0.0]);
        let last = (v.len() - 1) as u32;
        let at = |i: usize, j: usize| (1 + (i - 1) * cols + j % cols) as u32;
        let mut t = Vec::new();
        for j in 0..cols {
            t.push([0, at(1, j + 1), at(1, j)]);
            t.push([last, at(rows - 1, j), at(rows - 1, j + 1)]);
        }
        for i in 1..rows - 1 {
            for j in 0..cols {
                t.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
                t.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
            }
        }
        (v, t)
    }

    #[test]
    fn the_walk_finds_the_exact_nearest_vertex_after_a_small_motion() {
        let (v0, t) = sphere(24, 48, 0.1);
        let graph = CotanWeights::new(&v0, &t);
        // Points within 3 mm of the sphere, everywhere on it.
        let points: Vec<[f64; 3]> = (0..20_000)
            .map(|k| {
                let (a, b) = (k as f64 * 0.618_034, k as f64 * 0.754_877);
                let th = (1.0 - 2.0 * (b.fract())).acos();
                let ph = 2.0 * std::f64::consts::PI * a.fract();
                let r = 0.1 + 0.003 * ((k % 7) as f64 / 3.0 - 1.0);
                [r * th.sin() * ph.cos(), r * th.cos(), r * th.sin() * ph.sin()]
            })
            .collect();
        let start: Vec<u32> = nearest_batch(&build_tree(&v0).unwrap(), &points).iter().map(|r| r.0).collect();
        // The sphere grows by 4 mm and turns by 2 degrees: every vertex moves by 4-5 mm.
        let (c, s) = (2f64.to_radians().cos(), 2f64.to_radians().sin());
        let v1: Vec<[f64; 3]> =
            v0.iter().map(|p| [1.04 * (c * p[0] - s * p[2]), 1.04 * p[1], 1.04 * (s * p[0] + c * p[2])]).collect();
        let exact = nearest_batch(&build_tree(&v1).unwrap(), &points);
        let walked = walk_to_nearest(&graph, &v1, &points, &start, None);
        let same = exact.iter().zip(&walked).filter(|(e, w)| e.1 == w.1).count();
        assert_eq!(same, points.len(), "the walk missed the nearest vertex of {} points", points.len() - same);
    }

    #[test]
    fn a_labelled_point_walks_only_over_its_segment() {
        let (v, t) = sphere(12, 24, 0.1);
        let graph = CotanWeights::new(&v, &t);
        // Upper half label 1, lower half label 2; a point just below the equator labelled 1.
        let vl: Vec<u8> = v.iter().map(|p| if p[1] >= 0.0 { 1 } else { 2 }).collect();
        let p = [0.1, -0.02, 0.0];
        let start = (0..v.len()).find(|&i| vl[i] == 1 && v[i][1] > 0.05).unwrap() as u32;
        let restricted = [false, true, true];
        let allowed = Allowed { point_labels: &[1], vertex_labels: &vl, restricted: &restricted };
        let (w, _) = walk_to_nearest(&graph, &v, &[p], &[start], Some(allowed))[0];
        assert_eq!(vl[w as usize], 1);
        let best1 =
            (0..v.len()).filter(|&i| vl[i] == 1).min_by(|&a, &b| dist2(p, v[a]).total_cmp(&dist2(p, v[b]))).unwrap();
        assert_eq!(w as usize, best1, "the walk stops at the segment's nearest vertex");
        // Unrestricted, it crosses into the lower half.
        let (w, _) = walk_to_nearest(&graph, &v, &[p], &[start], None)[0];
        assert_eq!(vl[w as usize], 2);
    }
}
