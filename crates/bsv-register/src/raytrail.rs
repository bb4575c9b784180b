//! Ray-parallel point removal: flying pixels that stay close to the body.
//!
//! A depth camera's mixed pixels lie on the camera ray of a silhouette pixel, between the surface
//! and what is behind it; neighbouring silhouette pixels make them a thin sheet that contains the
//! viewing direction. The voxel-density filter (`outliers.rs`) removes the far, sparse part of such
//! a trail; the part within a few centimetres of the body is as dense as the surface and stays, right
//! in the lateral gaps, where it pulls the unseen sides outward and, in the label transfer, gives
//! arm vertices the torso's label (measured on L515-like synthetic scans, 5 subjects: torso +2.3 %,
//! upper arms -4.5 %; with the points farther than 8 mm from the true surface removed by an oracle:
//! -0.8 % and -1.5 %).
//!
//! Both cameras look along the world Z axis (DESIGN.md: the subject faces +Z, toward the front
//! camera; the back camera looks the other way), so a point whose local surface contains Z -- its
//! PCA normal over [`NEIGHBOURS`] neighbours is within `acos(max_cos)` of perpendicular to Z -- is
//! seen edge-on by both cameras: a trail point or a grazing one. Such points are 0.7-2.3 % of a
//! two-camera capture (exact / L515-like) but 12.5 % of an all-round sample of the template (the
//! body's sides), so the filter stands down when more than [`MAX_FRACTION`] of the points would go:
//! it is meant for two-view captures. A floor patch (normal along Y) goes too.
//!
//! Off by default (`ray_parallel_max_cos` = 0, round 2 session 7): the other cloud filters now take the
//! trails, and dropping the flanks' grazing points as well shrank L515-like fits (`benchmarks/BENCH.md`).

use crate::correspond::{build_tree, neighbourhood_normal};
use crate::voxels::Voxels;
use rayon::prelude::*;

/// Neighbours of the PCA normal.
pub const NEIGHBOURS: usize = 16;
/// Largest fraction of the cloud removed; above it the cloud is taken for an all-round scan and
/// nothing is removed.
pub const MAX_FRACTION: f64 = 0.07;
/// Cell side of the screening pass (m): a 3 x 3 x 3 block of cells (30 mm) holds 50-150 points of a
/// depth camera's surface (2-4 mm spacing at 1.5-3 m), enough for a plane to stand out of L515-like
/// depth noise.
pub const SCREEN_CELL_M: f64 = 0.01;
/// A cell whose block's PCA normal is at least this close to Z (|n_z|), over at least
/// [`SCREEN_MIN_POINTS`] points, faces the cameras clearly: its points are kept without their own
/// neighbour search. Everything else (grazing surface, trails, sparse or thin parts) is tested
/// point by point. The threshold is raised to `3 max_cos` when that is larger (a stricter test leaves
/// less to the screen); at `max_cos` >= 1/3 nothing is screened.
pub const SCREEN_MIN_COS: f64 = 0.6;
/// Fewest points in a screening block for its normal to decide.
pub const SCREEN_MIN_POINTS: u32 = 2 * NEIGHBOURS as u32;

/// Per point: whether it is kept. Everything is kept when `max_cos` is not in (0, 1), the cloud has
/// fewer than [`NEIGHBOURS`] points, or more than [`MAX_FRACTION`] of them would be removed.
///
/// The test itself is per point (the PCA normal of its [`NEIGHBOURS`] nearest points), but most of a
/// two-camera capture faces the cameras: a screening pass over cells of [`SCREEN_CELL_M`] first
/// keeps every point of a cell whose 3 x 3 x 3 block is a patch facing Z ([`SCREEN_MIN_COS`]), and only
/// the others (about 15 % of a capture) pay for the neighbour search. On noise-free captures the
/// decisions are those of the point-by-point test; with L515-like depth noise the point test also drops
/// about 0.8 % of the facing points, whose 16-point normals the noise tips over, and the screen keeps
/// them (measured neutral on the oracle cohorts, `benchmarks/BENCH.md`).
pub fn keep_not_ray_parallel(points: &[[f64; 3]], max_cos: f64) -> Result<Vec<bool>, String> {
    ray_parallel_test(points, max_cos, true)
}

/// [`keep_not_ray_parallel`], with or without the screening pass.
fn ray_parallel_test(points: &[[f64; 3]], max_cos: f64, screen: bool) -> Result<Vec<bool>, String> {
    let n = points.len();
    if !(max_cos > 0.0 && max_cos < 1.0) || n < NEIGHBOURS {
        return Ok(vec![true; n]);
    }
    let screen_cos = SCREEN_MIN_COS.max(3.0 * max_cos);
    let clear =
        if screen && screen_cos < 1.0 { facing_cells(points, SCREEN_CELL_M, screen_cos) } else { vec![false; n] };
    let tree = build_tree(points)?;
    let keep: Vec<bool> = points
        .par_iter()
        .zip(&clear)
        .map(|(&p, &c)| {
            // A degenerate patch (a line, a few repeated points) is kept: nothing to judge it by.
            c || neighbourhood_normal(&tree, points, p, NEIGHBOURS).is_none_or(|nrm| nrm[2].abs() >= max_cos)
        })
        .collect();
    let removed = keep.iter().filter(|&&k| !k).count();
    if removed as f64 > MAX_FRACTION * n as f64 {
        return Ok(vec![true; n]);
    }
    Ok(keep)
}

/// Moments of the points of one cell, relative to the cell's corner: count, sum, upper triangle of
/// the sum of outer products (xx, xy, xz, yy, yz, zz).
#[derive(Clone, Copy, Default)]
struct Moments {
    n: u32,
    s: [f64; 3],
    ss: [f64; 6],
}

impl Moments {
    fn add(&mut self, d: [f64; 3]) {
        self.n += 1;
        for (s, x) in self.s.iter_mut().zip(d) {
            *s += x;
        }
        self.ss[0] += d[0] * d[0];
        self.ss[1] += d[0] * d[1];
        self.ss[2] += d[0] * d[2];
        self.ss[3] += d[1] * d[1];
        self.ss[4] += d[1] * d[2];
        self.ss[5] += d[2] * d[2];
    }

    /// Adds `o`, whose origin is `t` away from this one's (`o`'s points are at `d + t` here).
    fn add_shifted(&mut self, o: &Moments, t: [f64; 3]) {
        let m = o.n as f64;
        self.n += o.n;
        for ((s, os), ta) in self.s.iter_mut().zip(o.s).zip(t) {
            *s += os + m * ta;
        }
        let pairs = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
        for (k, (a, b)) in pairs.into_iter().enumerate() {
            self.ss[k] += o.ss[k] + t[a] * o.s[b] + o.s[a] * t[b] + m * t[a] * t[b];
        }
    }

    /// The centred scatter matrix.
    fn scatter(&self) -> [[f64; 3]; 3] {
        let m = self.n.max(1) as f64;
        let mu = self.s.map(|x| x / m);
        let c = |k: usize, a: usize, b: usize| self.ss[k] - m * mu[a] * mu[b];
        [
            [c(0, 0, 0), c(1, 0, 1), c(2, 0, 2)],
            [c(1, 0, 1), c(3, 1, 1), c(4, 1, 2)],
            [c(2, 0, 2), c(4, 1, 2), c(5, 2, 2)],
        ]
    }
}

/// Per point: whether its cell (side `cell`) and the 26 around it hold at least
/// [`SCREEN_MIN_POINTS`] points whose PCA normal has |n_z| >= `min_cos`.
fn facing_cells(points: &[[f64; 3]], cell: f64, min_cos: f64) -> Vec<bool> {
    let voxels = Voxels::new(points, 1.0 / cell);
    let mut cells = vec![Moments::default(); voxels.len()];
    for (p, id) in points.iter().zip(&voxels.of_point) {
        if let Some(id) = *id {
            let corner = voxels.keys[id as usize].map(|v| v as f64 * cell);
            cells[id as usize].add([p[0] - corner[0], p[1] - corner[1], p[2] - corner[2]]);
        }
    }
    let facing: Vec<bool> = (0..voxels.len() as u32)
        .into_par_iter()
        .map(|id| {
            let mut block = Moments::default();
            for (b, o) in voxels.block(id) {
                block.add_shifted(&cells[b as usize], o.map(|v| v as f64 * cell));
            }
            block.n >= SCREEN_MIN_POINTS
                && crate::sym3::smallest_eigenvector(&block.scatter())
                    .is_some_and(|(v, l)| l[1] > 1e-6 * l[2] && v[2].abs() >= min_cos)
        })
        .collect();
    voxels.of_point.iter().map(|v| v.is_some_and(|id| facing[id as usize])).collect()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// A 40 x 20 cm patch facing the camera (z = 0) sampled every 5 mm, and a trail: points along
    /// z behind its right edge, one ray every other row of the patch (6 % of the points).
    fn patch_and_trail() -> (Vec<[f64; 3]>, usize) {
        let mut pts = Vec::new();
        for i in 0..80 {
            for j in 0..40 {
                pts.push([i as f64 * 0.005, j as f64 * 0.005, 0.0]);
            }
        }
        let n_patch = pts.len();
        for j in (0..40).step_by(2) {
            for t in 1..=10 {
                pts.push([0.395, j as f64 * 0.005, -0.005 * t as f64]);
            }
        }
        (pts, n_patch)
    }

    #[test]
    fn a_trail_behind_an_edge_goes_and_the_surface_stays() {
        let (pts, n_patch) = patch_and_trail();
        let keep = keep_not_ray_parallel(&pts, 0.2).unwrap();
        let patch_kept = keep[..n_patch].iter().filter(|&&k| k).count();
        // The trail beyond 1 cm behind the edge (its first two points sit among the patch's own).
        let beyond: Vec<bool> = keep[n_patch..].chunks(10).flat_map(|ray| ray[2..].to_vec()).collect();
        let trail_kept = beyond.iter().filter(|&&k| k).count();
        assert!(patch_kept as f64 > 0.97 * n_patch as f64, "{patch_kept} of {n_patch}");
        assert!(trail_kept * 10 < beyond.len(), "{trail_kept} of {}", beyond.len());
    }

    #[test]
    fn an_all_round_scan_and_off_switch_keep_everything() {
        // A cylinder about Y: its sides face X, a third of it is edge-on to Z.
        let mut pts = Vec::new();
        for i in 0..60 {
            for j in 0..30 {
                let a = i as f64 / 60.0 * std::f64::consts::TAU;
                pts.push([0.1 * a.cos(), j as f64 * 0.01, 0.1 * a.sin()]);
            }
        }
        assert!(keep_not_ray_parallel(&pts, 0.2).unwrap().iter().all(|&k| k));
        let (pts, _) = patch_and_trail();
        assert!(keep_not_ray_parallel(&pts, 0.0).unwrap().iter().all(|&k| k));
    }

    /// A two-view capture of a torso-like elliptic cylinder and a thinner limb (axes along Y), every
    /// 3 mm of arc and height, without the lateral bands seen edge-on by both cameras (|n_z| < 0.1),
    /// plus trails behind the silhouettes: the screened test decides every point like the
    /// point-by-point one and searches neighbours for few of them.
    #[test]
    fn the_screen_changes_no_decision_on_a_clean_two_view_capture() {
        let mut pts = Vec::new();
        for &(cx, a, b) in &[(0.0, 0.16, 0.11), (0.3, 0.045, 0.04)] {
            let per = 2.0 * std::f64::consts::PI * ((a * a + b * b) / 2.0f64).sqrt();
            let m = (per / 0.003) as usize;
            for i in 0..m {
                let t = i as f64 / m as f64 * std::f64::consts::TAU;
                let (x, z) = (a * t.cos(), b * t.sin());
                let nz = (z / (b * b)) / ((x / (a * a)).powi(2) + (z / (b * b)).powi(2)).sqrt();
                if nz.abs() < 0.1 {
                    continue;
                }
                for j in 0..100 {
                    pts.push([cx + x, j as f64 * 0.003, z]);
                }
            }
            // A trail behind each silhouette edge of the front view: 3 cm along -Z, every other row.
            for j in (0..100).step_by(2) {
                for t in 1..=10 {
                    pts.push([cx + a * 0.995, j as f64 * 0.003, -0.003 * t as f64]);
                }
            }
        }
        let screened = ray_parallel_test(&pts, 0.2, true).unwrap();
        let exact = ray_parallel_test(&pts, 0.2, false).unwrap();
        let differ = screened.iter().zip(&exact).filter(|(a, b)| a != b).count();
        assert_eq!(differ, 0, "{differ} of {} decisions differ", pts.len());
        assert!(exact.iter().filter(|&&k| !k).count() > 500, "the trails go");
        let clear = facing_cells(&pts, SCREEN_CELL_M, SCREEN_MIN_COS).iter().filter(|&&c| c).count();
        assert!(clear as f64 > 0.6 * pts.len() as f64, "{clear} of {} screened", pts.len());
    }
}
