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

use crate::correspond::{build_tree, neighbourhood_normal};
use rayon::prelude::*;

/// Neighbours of the PCA normal.
pub const NEIGHBOURS: usize = 16;
/// Largest fraction of the cloud removed; above it the cloud is taken for an all-round scan and
/// nothing is removed.
pub const MAX_FRACTION: f64 = 0.07;

/// Per point: whether it is kept. Everything is kept when `max_cos` is not in (0, 1), the cloud has
/// fewer than [`NEIGHBOURS`] points, or more than [`MAX_FRACTION`] of them would be removed.
pub fn keep_not_ray_parallel(points: &[[f64; 3]], max_cos: f64) -> Result<Vec<bool>, String> {
    let n = points.len();
    if !(max_cos > 0.0 && max_cos < 1.0) || n < NEIGHBOURS {
        return Ok(vec![true; n]);
    }
    let tree = build_tree(points)?;
    let keep: Vec<bool> = points
        .par_iter()
        .map(|&p| {
            // A degenerate patch (a line, a few repeated points) is kept: nothing to judge it by.
            neighbourhood_normal(&tree, points, p, NEIGHBOURS).is_none_or(|nrm| nrm[2].abs() >= max_cos)
        })
        .collect();
    let removed = keep.iter().filter(|&&k| !k).count();
    if removed as f64 > MAX_FRACTION * n as f64 {
        return Ok(vec![true; n]);
    }
    Ok(keep)
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
}
