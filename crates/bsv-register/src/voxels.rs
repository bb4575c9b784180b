//! Voxel keys and the occupied voxels of a point set: what the sparse-point filter
//! (`outliers.rs`), the ray-parallel screen (`raytrail.rs`) and the detached-piece test
//! (`detached.rs`) share.
//!
//! A point more than [`MAX_KEY`] voxels from the origin (or with a non-finite coordinate) cannot be
//! keyed without overflow; it has no voxel.
//!
//! [`Voxels`] numbers the occupied voxels once (one hash insertion per point) so that the work done
//! per voxel -- a 3 x 3 x 3 block of neighbours -- is done once per voxel, not once per point.

use rayon::prelude::*;
use rustc_hash::FxHashMap as HashMap;

/// Largest voxel key magnitude (2^52): keys and their +-1 neighbours never overflow an `i64`, and
/// every integer up to it is exact in an `f64`.
pub const MAX_KEY: f64 = 4_503_599_627_370_496.0;

/// The voxel key of `p` (voxel side `1 / inv`), or `None` when a coordinate is non-finite or beyond
/// [`MAX_KEY`] voxels.
#[inline]
pub(crate) fn key(p: &[f64; 3], inv: f64) -> Option<[i64; 3]> {
    let mut k = [0i64; 3];
    for (ka, &x) in k.iter_mut().zip(p) {
        let v = (x * inv).floor();
        if v.is_nan() || v.abs() > MAX_KEY {
            return None;
        }
        *ka = v as i64;
    }
    Some(k)
}

/// The occupied voxels of a point set, numbered in the order of their first point.
pub(crate) struct Voxels {
    /// The key of every occupied voxel, by id.
    pub keys: Vec<[i64; 3]>,
    /// The voxel id of every point (`None`: the point cannot be keyed).
    pub of_point: Vec<Option<u32>>,
    ids: HashMap<[i64; 3], u32>,
}

impl Voxels {
    /// The voxels of side `1 / inv` holding `points`.
    pub fn new(points: &[[f64; 3]], inv: f64) -> Voxels {
        let point_keys: Vec<Option<[i64; 3]>> = points.par_iter().map(|p| key(p, inv)).collect();
        let mut ids: HashMap<[i64; 3], u32> = HashMap::with_capacity_and_hasher(points.len() / 4, Default::default());
        let mut keys = Vec::new();
        let of_point = point_keys
            .iter()
            .map(|k| {
                let k = (*k)?;
                Some(*ids.entry(k).or_insert_with(|| {
                    keys.push(k);
                    (keys.len() - 1) as u32
                }))
            })
            .collect();
        Voxels { keys, of_point, ids }
    }

    /// How many voxels are occupied.
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    /// The occupied voxels of the 3 x 3 x 3 block around voxel `id` (itself included) with their
    /// offsets from it, in the order of the offsets (dx, then dy, then dz, each -1, 0, 1).
    pub fn block(&self, id: u32) -> impl Iterator<Item = (u32, [i64; 3])> + '_ {
        let k = self.keys[id as usize];
        (0..27).filter_map(move |j: i64| {
            let o = [j / 9 - 1, (j / 3) % 3 - 1, j % 3 - 1];
            // |k| <= 2^52 (MAX_KEY), so k + 1 cannot overflow.
            self.ids.get(&[k[0] + o[0], k[1] + o[1], k[2] + o[2]]).map(|&b| (b, o))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_voxels_by_first_point_and_finds_the_block() {
        let pts = [[0.005, 0.005, 0.005], [0.015, 0.005, 0.005], [0.006, 0.001, 0.009], [f64::NAN, 0.0, 0.0]];
        let v = Voxels::new(&pts, 100.0);
        assert_eq!(v.len(), 2);
        assert_eq!(v.of_point, vec![Some(0), Some(1), Some(0), None]);
        let block: Vec<(u32, [i64; 3])> = v.block(0).collect();
        assert_eq!(block, vec![(0, [0, 0, 0]), (1, [1, 0, 0])]);
        assert_eq!(key(&[1e300, 0.0, 0.0], 1.0), None);
    }
}
