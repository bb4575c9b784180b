//! Point-cloud cleaning: statistical outlier removal (exact k nearest neighbours, kiddo k-d tree,
//! rayon), voxel down-sampling. Dropping segments is `bsv_core::PointCloud::drop_segments`.
//!
//! Statistical outlier removal follows Open3D's `remove_statistical_outlier`, whose parameter names
//! the paper uses (600 neighbours, std ratio 0.05): for each point the mean Euclidean distance to its
//! `k` nearest points (the point itself counts as one of them, distance 0) is computed; a point is kept
//! when that mean is <= global mean + `std_ratio` x standard deviation (sample std) of the means.

use bsv_core::geometry::dist2;
use bsv_core::PointCloud;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZeroUsize;

/// Errors of the cleaning operations.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CleanError {
    /// `k` is zero.
    #[error("statistical outlier removal: k (number of neighbours) is 0; use k >= 1 (the paper uses 600)")]
    ZeroK,
    /// `std_ratio` is not finite.
    #[error("statistical outlier removal: std_ratio is {0}; use a finite number (the paper uses 0.05)")]
    BadStdRatio(f64),
    /// A point has a NaN or infinite coordinate.
    #[error("point {index} of the cloud has a non-finite coordinate {point:?}; remove invalid points (depth 0/NaN) before cleaning")]
    NonFinitePoint {
        /// Index of the point.
        index: usize,
        /// Its coordinates.
        point: [f64; 3],
    },
    /// The k-d tree could not be built.
    #[error(
        "statistical outlier removal: building the k-d tree failed ({0}); the cloud may be too large (> 4e9 points)"
    )]
    Tree(String),
    /// Non-positive or non-finite voxel size.
    #[error("voxel down-sampling: voxel size {0} must be a positive finite length in metres")]
    BadVoxel(f64),
}

/// Parameters of statistical outlier removal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SorParams {
    /// Number of nearest neighbours (the point itself included), clamped to the cloud size.
    pub k: usize,
    /// Keep points whose mean neighbour distance <= mean + std_ratio * std.
    pub std_ratio: f64,
}

impl Default for SorParams {
    /// The paper's values: k = 600, std_ratio = 0.05.
    fn default() -> Self {
        SorParams { k: 600, std_ratio: 0.05 }
    }
}

/// What statistical outlier removal computed.
#[derive(Debug, Clone, PartialEq)]
pub struct SorResult {
    /// Per input point: true = kept.
    pub keep: Vec<bool>,
    /// Per input point: mean distance to its k nearest points (metres).
    pub mean_distances: Vec<f64>,
    /// The threshold used (metres).
    pub threshold: f64,
    /// The `k` actually used (after clamping to the cloud size).
    pub k: usize,
}

/// Points per parallel work unit (consecutive in Morton order).
const CHAIN: usize = 1024;
/// Points per group sharing one radius query.
const GROUP: usize = 24;
/// Largest distance of a group member from the group's anchor, in anchor k-th distances.
const GROUP_REACH: f64 = 0.3;

fn morton_order(points: &[[f64; 3]]) -> Vec<u32> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let ext = (0..3).map(|a| hi[a] - lo[a]).fold(0.0f64, f64::max).max(1e-12);
    let spread = |mut x: u64| {
        x &= 0x1f_ffff;
        x = (x | x << 32) & 0x1f_0000_0000_ffff;
        x = (x | x << 16) & 0x1f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        x = (x | x << 2) & 0x1249_2492_4924_9249;
        x
    };
    let mut keyed: Vec<(u64, u32)> = points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let q = |a: usize| (((p[a] - lo[a]) / ext) * 2_097_151.0) as u64;
            (spread(q(0)) | spread(q(1)) << 1 | spread(q(2)) << 2, i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// Mean distance from each point to its `k` nearest points (itself included), exact.
///
/// Points are visited in Morton order. If q is a visited point whose k-th neighbour distance is
/// `r_q`, the k-th neighbour distance of p is at most `r_q + |p - q|` (triangle inequality). A group
/// of up to 24 consecutive points near q shares one kiddo radius query around q (radius
/// `r_q + 2 max |p - q|`, which contains every member's bound ball); each member then filters the
/// candidates by its own bound. A lower bound `r_q - |p - q|` (fewer than k points lie strictly
/// inside it) lets the candidates below it be summed directly, so only a thin shell is selected.
/// A point where the Morton order jumps (up to 3 r_q away) queries its own bound ball. This is exact
/// and ~4x faster than a k-NN heap query per point at k = 600. Chain starts and longer jumps use
/// kiddo's exact `nearest_n`.
pub fn mean_knn_distances(points: &[[f64; 3]], k: usize) -> Result<Vec<f64>, CleanError> {
    if k == 0 {
        return Err(CleanError::ZeroK);
    }
    if let Some((index, p)) = points.iter().enumerate().find(|(_, p)| !p.iter().all(|x| x.is_finite())) {
        return Err(CleanError::NonFinitePoint { index, point: *p });
    }
    let n = points.len();
    if n == 0 {
        return Ok(Vec::new());
    }
    let k = k.min(n);
    let order = morton_order(points);
    let sorted: Vec<[f64; 3]> = order.iter().map(|&i| points[i as usize]).collect();
    let tree: ImmutableKdTree<f64, 3> =
        ImmutableKdTree::new_from_slice(&sorted).map_err(|e| CleanError::Tree(format!("{e:?}")))?;
    let kk = NonZeroUsize::new(k).ok_or(CleanError::ZeroK)?;
    let knn = MortonKnn { sorted: &sorted, tree: &tree, k, kk };
    let mut means_sorted = vec![0.0; n];
    means_sorted.par_chunks_mut(CHAIN).enumerate().for_each(|(c, out)| knn.chain(c * CHAIN, out));
    let mut means = vec![0.0; n];
    for (s, &i) in order.iter().enumerate() {
        means[i as usize] = means_sorted[s];
    }
    Ok(means)
}

#[inline]
fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    dist2(a, b).sqrt()
}

/// The points in Morton order with their k-d tree: the shared input of every chain.
struct MortonKnn<'a> {
    sorted: &'a [[f64; 3]],
    tree: &'a ImmutableKdTree<f64, 3>,
    k: usize,
    kk: NonZeroUsize,
}

/// Per-chain buffers, reused for every group.
struct Scratch {
    /// Candidates in structure-of-arrays form so that the distance loop vectorises.
    cand: [Vec<f64>; 3],
    d2: Vec<f64>,
    buf: Vec<u64>,
}

impl MortonKnn<'_> {
    /// Exact k-NN of one point: (mean distance, k-th distance).
    fn exact(&self, p: &[f64; 3]) -> (f64, f64) {
        let res = self.tree.query(p).nearest_n::<SquaredEuclidean<f64>>(self.kk).execute();
        let sum: f64 = res.iter().map(|h| h.distance.sqrt()).sum();
        (sum / self.k as f64, res.last().map(|h| h.distance.sqrt()).unwrap_or(0.0))
    }

    /// Mean distances of the chain of points starting at `base` (one `out` slot per point).
    fn chain(&self, base: usize, out: &mut [f64]) {
        let (sorted, k) = (self.sorted, self.k);
        let len = out.len();
        let mut scratch = Scratch {
            cand: [Vec::with_capacity(4 * k), Vec::with_capacity(4 * k), Vec::with_capacity(4 * k)],
            d2: Vec::with_capacity(4 * k),
            buf: Vec::with_capacity(4 * k),
        };
        let mut anchor: Option<([f64; 3], f64)> = None;
        let mut i = 0;
        while i < len {
            let Some((q, rq)) = anchor else {
                let p = sorted[base + i];
                let (m, r) = self.exact(&p);
                out[i] = m;
                anchor = Some((p, r));
                i += 1;
                continue;
            };
            let first = dist(sorted[base + i], q);
            if first > 3.0 * rq {
                anchor = None;
                continue;
            }
            let (end, centre, radius) = self.group(base, i, len, (q, rq), first);
            self.gather_candidates(centre, radius, &mut scratch.cand);
            let mut prev = (q, rq);
            for j in i..end {
                let p = sorted[base + j];
                let (m, r) = self.member(p, (q, rq), prev, &mut scratch);
                out[j] = m;
                prev = (p, r);
            }
            anchor = Some(prev);
            i = end;
        }
    }

    /// The group starting at chain index `i` near anchor `(q, rq)`: its end and the centre and radius
    /// of the query ball that holds every member's bound ball.
    fn group(&self, base: usize, i: usize, len: usize, (q, rq): ([f64; 3], f64), first: f64) -> (usize, [f64; 3], f64) {
        let sorted = self.sorted;
        let mut end = i;
        if first > 0.5 * rq {
            // A jump of the Morton order: this point alone, its own bound ball.
            end += 1;
            return (end, sorted[base + i], rq + first);
        }
        let mut reach: f64 = 0.0;
        while end < len && end - i < GROUP {
            let s = dist(sorted[base + end], q);
            // Far members would inflate the shared query: a group stays within GROUP_REACH r_q.
            if end > i && s > (GROUP_REACH * rq).max(first) {
                break;
            }
            reach = reach.max(s);
            end += 1;
        }
        (end, q, rq + 2.0 * reach)
    }

    /// Replaces `cand` with the points within `radius` of `centre` (padded against rounding).
    fn gather_candidates(&self, centre: [f64; 3], radius: f64, cand: &mut [Vec<f64>; 3]) {
        for c in cand.iter_mut() {
            c.clear();
        }
        for h in self
            .tree
            .query(&centre)
            .within::<SquaredEuclidean<f64>>(radius * radius * (1.0 + 1e-9) + 1e-300)
            .unsorted()
            .execute()
        {
            let c = self.sorted[h.item as usize];
            for a in 0..3 {
                cand[a].push(c[a]);
            }
        }
    }

    /// (mean distance, k-th distance) of group member `p` from the group's candidates, bounded by
    /// the anchor `(q, rq)` and the previous member `prev`; exact k-NN when the bounds do not settle it.
    #[inline]
    fn member(&self, p: [f64; 3], (q, rq): ([f64; 3], f64), prev: ([f64; 3], f64), s: &mut Scratch) -> (f64, f64) {
        let k = self.k;
        let (sq, sp) = (dist(p, q), dist(p, prev.0));
        // Upper bound of p's k-th distance: every candidate beyond it is out.
        let hi = (rq + sq).min(prev.1 + sp);
        // Lower bound: fewer than k points lie strictly inside it, so all of them are in.
        let lo = (rq - sq).max(prev.1 - sp).max(0.0);
        let hi2 = hi * hi * (1.0 + 1e-9) + 1e-300;
        let lo2 = lo * lo * (1.0 - 1e-9);
        s.buf.clear();
        let mut sure_sum = 0.0;
        let mut sure = 0usize;
        s.d2.clear();
        let cand = &s.cand;
        s.d2.extend(cand[0].iter().zip(&cand[1]).zip(&cand[2]).map(|((x, y), z)| {
            let (dx, dy, dz) = (x - p[0], y - p[1], z - p[2]);
            dx * dx + dy * dy + dz * dz
        }));
        for &d in &s.d2 {
            if d < lo2 {
                sure_sum += d.sqrt();
                sure += 1;
            } else if d <= hi2 {
                // Non-negative f64 order like their bit patterns: select on u64.
                s.buf.push(d.to_bits());
            }
        }
        if sure < k && sure + s.buf.len() >= k {
            let need = k - sure;
            let (_, kth, _) = s.buf.select_nth_unstable(need - 1);
            let kth = f64::from_bits(*kth).sqrt();
            let sum: f64 = sure_sum + s.buf[..need].iter().map(|&b| f64::from_bits(b).sqrt()).sum::<f64>();
            (sum / k as f64, kth)
        } else {
            self.exact(&p)
        }
    }
}

/// Mean distances by plain k-NN queries (kiddo `nearest_n` per point): the reference the fast
/// path is tested against.
pub fn mean_knn_distances_naive(points: &[[f64; 3]], k: usize) -> Result<Vec<f64>, CleanError> {
    if k == 0 {
        return Err(CleanError::ZeroK);
    }
    if points.is_empty() {
        return Ok(Vec::new());
    }
    let k = k.min(points.len());
    let tree: ImmutableKdTree<f64, 3> =
        ImmutableKdTree::new_from_slice(points).map_err(|e| CleanError::Tree(format!("{e:?}")))?;
    let kk = NonZeroUsize::new(k).ok_or(CleanError::ZeroK)?;
    Ok(points
        .par_iter()
        .map(|p| {
            let res = tree.query(p).nearest_n::<SquaredEuclidean<f64>>(kk).execute();
            res.iter().map(|h| h.distance.sqrt()).sum::<f64>() / k as f64
        })
        .collect())
}

/// Statistical outlier removal statistics for `points` (does not modify anything).
pub fn statistical_outliers(points: &[[f64; 3]], params: SorParams) -> Result<SorResult, CleanError> {
    if !params.std_ratio.is_finite() {
        return Err(CleanError::BadStdRatio(params.std_ratio));
    }
    let means = mean_knn_distances(points, params.k)?;
    let n = means.len();
    let k = params.k.min(n);
    if n < 2 {
        return Ok(SorResult { keep: vec![true; n], mean_distances: means, threshold: f64::INFINITY, k });
    }
    let mean = means.iter().sum::<f64>() / n as f64;
    let var = means.iter().map(|m| (m - mean) * (m - mean)).sum::<f64>() / (n - 1) as f64;
    let threshold = mean + params.std_ratio * var.sqrt();
    let keep = means.iter().map(|&m| m <= threshold).collect();
    Ok(SorResult { keep, mean_distances: means, threshold, k })
}

/// Removes statistical outliers from `cloud` in place (attributes follow); returns the statistics.
pub fn remove_statistical_outliers(cloud: &mut PointCloud, params: SorParams) -> Result<SorResult, CleanError> {
    let res = statistical_outliers(&cloud.points, params)?;
    cloud.retain_indices(|i| res.keep[i]);
    Ok(res)
}

/// Keeps one point per occupied cubic voxel of edge `voxel` (the point nearest the voxel's centroid
/// of points, with its attributes); deterministic.
pub fn voxel_downsample(cloud: &PointCloud, voxel: f64) -> Result<PointCloud, CleanError> {
    if !(voxel > 0.0 && voxel.is_finite()) {
        return Err(CleanError::BadVoxel(voxel));
    }
    if let Some((index, p)) = cloud.points.iter().enumerate().find(|(_, p)| !p.iter().all(|x| x.is_finite())) {
        return Err(CleanError::NonFinitePoint { index, point: *p });
    }
    let key = |p: &[f64; 3]| p.map(|x| (x / voxel).floor() as i64);
    let mut idx: Vec<u32> = (0..cloud.len() as u32).collect();
    idx.par_sort_unstable_by_key(|&i| key(&cloud.points[i as usize]));
    let mut chosen = Vec::new();
    let mut s = 0;
    while s < idx.len() {
        let kk = key(&cloud.points[idx[s] as usize]);
        let mut e = s + 1;
        while e < idx.len() && key(&cloud.points[idx[e] as usize]) == kk {
            e += 1;
        }
        let mut c = [0.0; 3];
        for &i in &idx[s..e] {
            for (ca, pa) in c.iter_mut().zip(cloud.points[i as usize]) {
                *ca += pa;
            }
        }
        let c = c.map(|x| x / (e - s) as f64);
        let best = idx[s..e]
            .iter()
            .copied()
            .min_by(|&a, &b| dist2(cloud.points[a as usize], c).total_cmp(&dist2(cloud.points[b as usize], c)))
            .unwrap_or(idx[s]);
        chosen.push(best as usize);
        s = e;
    }
    chosen.sort_unstable();
    let mut keep = vec![false; cloud.len()];
    for i in chosen {
        keep[i] = true;
    }
    let mut out = cloud.clone();
    out.retain_indices(|i| keep[i]);
    Ok(out)
}
