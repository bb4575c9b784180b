//! Detached-piece removal: cloud points of a segment that are not attached to the segment's body.
//!
//! In a real room a few percent of the cloud survive cloud cleaning although they are not the body:
//! the person mask spills onto the floor between the feet and onto the wall behind the outline, and
//! those pixels take the label of the nearest limb. They are dense (the sparse-point filter in
//! `outliers.rs` keeps them) and they are far: 5-30 cm (floor) or 0.3-1 m (wall) from the segment
//! they are labelled as. Measured on the synthetic cohort with such points injected, they do their
//! damage before any correspondence: they stretch the cloud's bounding box (the pre-alignment
//! scales the template by it: torso +370 % with a wall sliver of 1.5 % of the points), tilt and move
//! a limb's principal axis and centroid (the articulated initialisation: upper arms -70 to -90 %)
//! and stretch its extent along the axis (the articulation's axial scale aligns the ends: shins
//! +10 % from a floor patch; -4 % with the axial scale off, against -6 % on the clean cloud). The
//! correspondences' own pruning (3 x the median length, normal angle) drops most of them: what
//! reaches the data term adds about 2 points to a shin.
//!
//! What they have in common is that they are detached from their segment: every point of a body
//! segment seen by one camera lies on one connected piece of surface (two pieces, front and back,
//! when the lateral gaps separate them), while the spill is a separate piece much smaller than the
//! segment's. So, per segment label (all points as one group in an unlabelled cloud): the points
//! are binned in voxels of side `voxel`, voxels sharing a face, edge or corner are joined (union
//! find), and a piece whose point count is below `min_fraction` x the segment's largest piece is
//! dropped. Cost: one hash pass and 13 look-ups per occupied voxel. It runs after the sparse-point
//! filter, so that trails of flying or mixed pixels cannot bridge a spill to the body.
//!
//! Limit: the test is relative to the segment's largest piece, so a spill of more than a quarter
//! of a small segment's largest piece (a shin seen by one camera holds ~4 % of the cloud) that
//! forms ONE piece is kept.

use crate::voxels::key;
use rustc_hash::FxHashMap as HashMap;

/// Union-find over voxel ids with path halving.
struct Forest(Vec<u32>);

impl Forest {
    fn find(&mut self, mut a: u32) -> u32 {
        while self.0[a as usize] != a {
            let up = self.0[self.0[a as usize] as usize];
            self.0[a as usize] = up;
            a = up;
        }
        a
    }
    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0[ra.max(rb) as usize] = ra.min(rb);
        }
    }
}

/// The 13 "forward" neighbour offsets of the 26-neighbourhood (each pair is visited once).
fn forward_offsets() -> Vec<[i64; 3]> {
    let mut out = Vec::with_capacity(13);
    for dx in -1..=1i64 {
        for dy in -1..=1i64 {
            for dz in -1..=1i64 {
                if (dx, dy, dz) > (0, 0, 0) {
                    out.push([dx, dy, dz]);
                }
            }
        }
    }
    out
}

/// Per point: whether it is kept (see the module docs). `labels` (one per point) separates the
/// segments; without labels the whole cloud is one segment. Every point is kept when `voxel` is
/// not positive and finite, `min_fraction` is 0 or the cloud is empty; a point that cannot be
/// keyed (non-finite, absurdly far) is dropped.
pub fn attached_points(points: &[[f64; 3]], labels: Option<&[u8]>, voxel: f64, min_fraction: f64) -> Vec<bool> {
    if !(voxel > 0.0 && voxel.is_finite()) || min_fraction <= 0.0 || points.is_empty() {
        return vec![true; points.len()];
    }
    let inv = 1.0 / voxel;
    let label = |i: usize| labels.and_then(|l| l.get(i).copied()).unwrap_or(0);
    // Voxel id of every point (per label), and the voxels' keys and point counts.
    let mut ids: HashMap<(u8, [i64; 3]), u32> = HashMap::with_capacity_and_hasher(points.len() / 8, Default::default());
    let mut voxels: Vec<(u8, [i64; 3])> = Vec::new();
    let mut counts: Vec<u32> = Vec::new();
    let point_voxel: Vec<Option<u32>> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let k = key(p, inv)?;
            let id = *ids.entry((label(i), k)).or_insert_with(|| {
                voxels.push((label(i), k));
                counts.push(0);
                (voxels.len() - 1) as u32
            });
            counts[id as usize] += 1;
            Some(id)
        })
        .collect();
    let mut forest = Forest((0..voxels.len() as u32).collect());
    let offsets = forward_offsets();
    for (id, &(l, k)) in voxels.iter().enumerate() {
        for o in &offsets {
            // |k| <= 2^52, so k + 1 cannot overflow.
            if let Some(&nb) = ids.get(&(l, [k[0] + o[0], k[1] + o[1], k[2] + o[2]])) {
                forest.union(id as u32, nb);
            }
        }
    }
    // Point count of every piece, and the largest piece of every label.
    let mut piece = vec![0u64; voxels.len()];
    for (id, &c) in counts.iter().enumerate() {
        let r = forest.find(id as u32) as usize;
        piece[r] += u64::from(c);
    }
    let mut largest = [0u64; 256];
    for (id, &(l, _)) in voxels.iter().enumerate() {
        largest[l as usize] = largest[l as usize].max(piece[id]);
    }
    let keep_voxel: Vec<bool> = (0..voxels.len())
        .map(|id| {
            let r = forest.find(id as u32) as usize;
            piece[r] as f64 >= min_fraction * largest[voxels[id].0 as usize] as f64
        })
        .collect();
    point_voxel.iter().map(|v| v.is_some_and(|id| keep_voxel[id as usize])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 30 x 30 cm plane at height `y` sampled every 3 mm (10,000 points).
    fn plane(y: f64, x0: f64) -> Vec<[f64; 3]> {
        (0..10_000).map(|i| [x0 + (i % 100) as f64 * 0.003, y, (i / 100) as f64 * 0.003]).collect()
    }

    #[test]
    fn a_small_detached_piece_of_a_segment_goes() {
        // Segment 2: two large pieces (front and back) 10 cm apart, and a dense 300-point blob 30 cm
        // away; segment 3: one piece next to the blob (other labels never join).
        let mut pts = plane(0.0, 0.0);
        pts.extend(plane(0.1, 0.0));
        let blob: Vec<[f64; 3]> =
            (0..300).map(|i| [0.6 + (i % 20) as f64 * 0.002, 0.0, (i / 20) as f64 * 0.002]).collect();
        pts.extend(&blob);
        pts.extend(plane(0.0, 0.605));
        let mut labels = vec![2u8; 20_300];
        labels.extend(vec![3u8; 10_000]);
        let keep = attached_points(&pts, Some(&labels), 0.015, 0.25);
        assert!(keep[..20_000].iter().all(|&k| k), "both large pieces stay");
        assert!(keep[20_000..20_300].iter().all(|&k| !k), "the detached blob goes");
        assert!(keep[20_300..].iter().all(|&k| k), "another label's piece stays");
        // Unlabelled, the blob touches the third plane: everything is one piece or large.
        assert!(attached_points(&pts, None, 0.015, 0.25).iter().all(|&k| k));
        // Off.
        assert!(attached_points(&pts, Some(&labels), 0.0, 0.25).iter().all(|&k| k));
        assert!(attached_points(&pts, Some(&labels), 0.015, 0.0).iter().all(|&k| k));
    }

    #[test]
    fn unkeyable_points_are_dropped_without_panic() {
        let mut pts = plane(0.0, 0.0);
        pts.push([f64::NAN, 0.0, 0.0]);
        pts.push([1e300, 0.0, 0.0]);
        let keep = attached_points(&pts, None, 0.015, 0.25);
        assert!(keep[..10_000].iter().all(|&k| k));
        assert!(!keep[10_000] && !keep[10_001]);
        assert!(attached_points(&[], None, 0.015, 0.25).is_empty());
    }
}
