//! Nearest-neighbour correspondences (kiddo k-d trees) with distance and normal pruning.
//!
//! - m2p (mesh to points): each vertex's target is its nearest cloud point. The tree over the cloud
//!   is built once per registration.
//! - p2m (points to mesh): each cloud point goes to its nearest vertex (a tree over the current
//!   vertices, rebuilt every iteration); a vertex's target is the mean of its points; a vertex with
//!   no point gets no data term.
//!
//! Label-aware matching (when the cloud and the template both carry segment labels, see
//! [`CloudIndex::set_label_trees`]): m2p matches a template vertex of segment L only to cloud points of
//! segment L (one tree per segment, built once), p2m sends a cloud point of segment L only to the
//! current template vertices of segment L (one tree per segment, rebuilt every iteration). A label
//! present on one side only falls back to unrestricted matching. This keeps a limb that the pose
//! puts near another surface (a forearm hanging beside the hip, an upper arm against the chest)
//! from being pulled onto it.
//!
//! Pruning (per iteration): a correspondence longer than `factor x median` of the iteration's
//! correspondence lengths (but never below `floor`) is dropped; with label-aware matching the template's
//! torso vertices take their own, looser factor (the torso's shape varies most and no articulated
//! cross-section fits it first, so its gaps close last). Normal pruning compares the
//! current vertex normal with the cloud normal: the given (oriented) normals, or, when the cloud has
//! none, unoriented PCA normals of `k` neighbours estimated lazily for the points that m2p actually
//! matches (and cached); in p2m the normal of the patch of points a vertex collected (PCA of their
//! scatter) is used, so no per-point normal is ever needed. m2p pulls gap-side vertices onto the
//! edges of the gaps; their normals are about 90 degrees from the edge points' normals, which is
//! what the angle test removes.
//!
//! With the curvature correction (`curvature.rs`) the normal part of every target is lifted by the
//! height of the surface under its points' spread (the mean of a p2m patch lies under a convex limb).

use crate::cotan::CotanWeights;
use crate::curvature;
use crate::walk::{walk_to_nearest, Allowed};
use bsv_core::geometry::{add, dot, normalize, scale, sub};
use bsv_core::Segment;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use std::num::NonZeroUsize;
use std::sync::OnceLock;

/// The data residual of one vertex: its offset to the target split into the part along the
/// surface normal(s) and the rest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Residual {
    /// Offset from the vertex to its target (m2p: the nearest point; p2m: the mean of its points).
    pub offset: [f64; 3],
    /// The normal part of the offset: `n (n . offset)` with the cloud normal at the target (m2p),
    /// the mean of `n_k (n_k . d_k)` over the vertex's points (p2m), or, without cloud normals, the
    /// current vertex normal (m2p) or the normal of the vertex's patch of points (p2m).
    /// With the cloud's own normals a vertex lying on the sampled surface has no normal residual even
    /// where the target sits on a neighbouring (tilted) facet.
    pub normal_part: [f64; 3],
}

/// The points a vertex collected in a p2m iteration: count, sum of the offsets, their scatter
/// (upper triangle) and the sum of their normal parts (given normals only).
#[derive(Clone, Copy)]
struct Acc {
    n: u32,
    s: [f64; 3],
    ss: [f64; 6],
    np: [f64; 3],
}

/// Adds `d` to a sum `s` and its outer product to the upper-triangle moments `m`.
#[inline]
fn add_moments(s: &mut [f64; 3], m: &mut [f64; 6], d: [f64; 3]) {
    for k in 0..3 {
        s[k] += d[k];
    }
    let q = moments_of(d);
    for k in 0..6 {
        m[k] += q[k];
    }
}

/// The outer product `d d^T` as an upper triangle (xx, xy, xz, yy, yz, zz).
#[inline]
fn moments_of(d: [f64; 3]) -> [f64; 6] {
    [d[0] * d[0], d[0] * d[1], d[0] * d[2], d[1] * d[1], d[1] * d[2], d[2] * d[2]]
}

/// A residual per vertex: `Some` with a data term, `None` without.
pub type Targets = Vec<Option<Residual>>;

#[inline]
fn project(n: [f64; 3], d: [f64; 3]) -> [f64; 3] {
    let s = dot(n, d);
    [n[0] * s, n[1] * s, n[2] * s]
}

/// Pruning settings of one registration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pruning {
    /// Drop correspondences longer than `distance_factor` x the median (0 or inf = off).
    pub distance_factor: f64,
    /// The factor of the correspondences of template torso vertices when matching is label-aware
    /// (the same median; 0 or inf = off).
    pub torso_distance_factor: f64,
    /// Never prune below this length, metres.
    pub distance_floor: f64,
    /// Cosine of the largest normal angle (-1 = off).
    pub min_cos: f64,
}

/// The template's torso label (its correspondences take [`Pruning::torso_distance_factor`]).
const TORSO: u8 = Segment::Torso as u8;

/// The squared distance limits of one iteration: every vertex's, and the torso vertices' when the
/// matching is label-aware.
#[derive(Debug, Clone, Copy)]
struct Limits<'a> {
    all: f64,
    torso: f64,
    /// The template's vertex labels (label-aware matching only).
    labels: Option<&'a [u8]>,
}

impl Limits<'_> {
    /// The squared limit of a correspondence of vertex `v`.
    fn of(&self, v: usize) -> f64 {
        match self.labels {
            Some(l) if l.get(v) == Some(&TORSO) => self.torso,
            _ => self.all,
        }
    }
}

impl Pruning {
    /// The distance limits (squared) for correspondences with squared lengths `d2` (`factor` x their
    /// median, never below the floor; infinite when the factor is 0 or infinite).
    fn limits2<'a>(&self, d2: &mut [f64], labels: Option<&'a [u8]>) -> Limits<'a> {
        let on = |f: f64| f > 0.0 && f.is_finite();
        if d2.is_empty() || !(on(self.distance_factor) || on(self.torso_distance_factor)) {
            return Limits { all: f64::INFINITY, torso: f64::INFINITY, labels };
        }
        let mid = d2.len() / 2;
        let (_, &mut med2, _) = d2.select_nth_unstable_by(mid, f64::total_cmp);
        let lim = |f: f64| {
            if !on(f) {
                return f64::INFINITY;
            }
            let l = (f * med2.sqrt()).max(self.distance_floor);
            l * l
        };
        Limits { all: lim(self.distance_factor), torso: lim(self.torso_distance_factor), labels }
    }
}

/// The cloud side: the k-d tree over the points (built once) and the normals.
pub struct CloudIndex {
    points: Vec<[f64; 3]>,
    tree: ImmutableKdTree<f64, 3>,
    /// Per segment label: the tree over that segment's points and their global indices.
    by_label: Vec<Option<LabelTree>>,
    /// Segment label of every point (label-aware mode only).
    labels: Option<Vec<u8>>,
    given_normals: Option<Vec<[f64; 3]>>,
    estimated: Vec<OnceLock<[f64; 3]>>,
    k_normals: usize,
}

impl std::fmt::Debug for CloudIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CloudIndex").field("points", &self.points.len()).finish()
    }
}

/// A k-d tree over a subset of points and the subset's indices in the full set.
struct LabelTree {
    tree: ImmutableKdTree<f64, 3>,
    index: Vec<u32>,
}

/// The per-segment k-d trees of label-aware matching ([`CloudIndex::set_label_trees`]): one per
/// label present on both sides with at least 4 points and 4 vertices, built in parallel over labels.
pub struct LabelTrees {
    trees: Vec<Option<LabelTree>>,
    labels: Vec<u8>,
}

impl LabelTrees {
    /// Builds the trees over `points` for the cloud's `labels` (one per point) and the template's
    /// `vertex_labels`.
    pub fn build(points: &[[f64; 3]], labels: &[u8], vertex_labels: &[u8]) -> Result<LabelTrees, String> {
        if labels.len() != points.len() {
            return Err(format!("{} cloud labels for {} points", labels.len(), points.len()));
        }
        let groups = group_by_label(labels);
        let vgroups = group_by_label(vertex_labels);
        let trees: Vec<Option<LabelTree>> = groups
            .into_par_iter()
            .zip(vgroups.par_iter())
            .map(|(g, vg)| {
                if g.len() < MIN_LABEL_ITEMS || vg.len() < MIN_LABEL_ITEMS {
                    return Ok(None);
                }
                let pts: Vec<[f64; 3]> = g.iter().map(|&i| points[i as usize]).collect();
                Ok(Some(LabelTree { tree: build_tree(&pts)?, index: g }))
            })
            .collect::<Result<_, String>>()?;
        Ok(LabelTrees { trees, labels: labels.to_vec() })
    }
}

/// Groups `0..labels.len()` by label: `groups[l]` lists the items with label `l`.
fn group_by_label(labels: &[u8]) -> Vec<Vec<u32>> {
    let mut groups = vec![Vec::new(); 256];
    for (i, &l) in labels.iter().enumerate() {
        groups[l as usize].push(i as u32);
    }
    groups
}

/// Fewest items a per-label tree needs (smaller groups match unrestricted).
const MIN_LABEL_ITEMS: usize = 4;

/// Nearest item of every query in a tree (parallel batch query): (index, squared distance).
pub fn nearest_batch(tree: &ImmutableKdTree<f64, 3>, queries: &[[f64; 3]]) -> Vec<(u32, f64)> {
    tree.query_batch(queries)
        .nearest_one::<SquaredEuclidean<f64>>()
        .execute()
        .iter()
        .map(|r| (r.item, r.distance))
        .collect()
}

/// Builds an immutable k-d tree over `points`.
pub fn build_tree(points: &[[f64; 3]]) -> Result<ImmutableKdTree<f64, 3>, String> {
    ImmutableKdTree::new_from_slice(points).map_err(|e| format!("k-d tree construction failed: {e:?}"))
}

/// Unit normal (smallest-eigenvalue eigenvector, closed form: [`crate::sym3`]) of the scatter matrix
/// `c` (centred), or `None` when the patch is degenerate (fewer than 3 independent points: the middle
/// eigenvalue is not above 1e-6 of the largest).
#[allow(clippy::neg_cmp_op_on_partial_ord, reason = "a NaN eigenvalue must count as degenerate")]
pub fn pca_normal(c: &Matrix3<f64>) -> Option<[f64; 3]> {
    let a: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| c[(i, j)]));
    let (v, l) = crate::sym3::smallest_eigenvector(&a)?;
    (l[1] > 1e-6 * l[2]).then_some(v)
}

/// The PCA normal ([`pca_normal`]) of the `k` (at least 3) points of `tree` (over `points`) nearest
/// to `q`, or `None` when they are degenerate.
pub fn neighbourhood_normal(
    tree: &ImmutableKdTree<f64, 3>,
    points: &[[f64; 3]],
    q: [f64; 3],
    k: usize,
) -> Option<[f64; 3]> {
    let k = NonZeroUsize::new(k.max(3)).unwrap_or(NonZeroUsize::MIN);
    // Unsorted: the scatter matrix does not depend on their order.
    let nb = tree.query(&q).nearest_n::<SquaredEuclidean<f64>>(k).unsorted().execute();
    let mut mean = [0.0; 3];
    for r in &nb {
        let p = points[r.item as usize];
        for a in 0..3 {
            mean[a] += p[a];
        }
    }
    let m = nb.len().max(1) as f64;
    mean = mean.map(|v| v / m);
    let mut c = Matrix3::zeros();
    for r in &nb {
        let v = Vector3::from(sub(points[r.item as usize], mean));
        c += v * v.transpose();
    }
    pca_normal(&c)
}

impl CloudIndex {
    /// Builds the tree; `normals` are used when given (unit, oriented); otherwise, with `k_normals`
    /// > 2, normals are estimated on demand.
    pub fn new(points: &[[f64; 3]], normals: Option<&[[f64; 3]]>, k_normals: usize) -> Result<CloudIndex, String> {
        let tree = build_tree(points)?;
        let estimated = if normals.is_none() && k_normals > 2 {
            (0..points.len()).map(|_| OnceLock::new()).collect()
        } else {
            Vec::new()
        };
        Ok(CloudIndex {
            points: points.to_vec(),
            tree,
            by_label: Vec::new(),
            labels: None,
            given_normals: normals.map(|n| n.iter().map(|&v| normalize(v)).collect()),
            estimated,
            k_normals,
        })
    }

    /// Enables label-aware matching: `trees` ([`LabelTrees::build`], possibly alongside [`Self::new`])
    /// over the same points; m2p and p2m then match per segment. Returns the number of labels matched
    /// that way.
    pub fn set_label_trees(&mut self, trees: LabelTrees) -> usize {
        let count = trees.trees.iter().filter(|b| b.is_some()).count();
        self.by_label = trees.trees;
        self.labels = Some(trees.labels);
        count
    }

    /// Nearest cloud point of each vertex, restricted to the vertex's segment when label-aware
    /// matching is on and `vertex_labels` is given: (global point index, squared distance).
    pub fn nearest_labelled(&self, vertices: &[[f64; 3]], vertex_labels: Option<&[u8]>) -> Vec<(u32, f64)> {
        let Some(vl) = self.label_aware(vertex_labels) else {
            return self.nearest(vertices);
        };
        let groups = group_by_label(vl);
        let mut out = vec![(0u32, f64::INFINITY); vertices.len()];
        let mut rest: Vec<u32> = Vec::new();
        for (l, g) in groups.iter().enumerate() {
            if g.is_empty() {
                continue;
            }
            match &self.by_label[l] {
                Some(lt) => {
                    let q: Vec<[f64; 3]> = g.iter().map(|&v| vertices[v as usize]).collect();
                    for (&v, (i, d)) in g.iter().zip(nearest_batch(&lt.tree, &q)) {
                        out[v as usize] = (lt.index[i as usize], d);
                    }
                }
                None => rest.extend_from_slice(g),
            }
        }
        if !rest.is_empty() {
            let q: Vec<[f64; 3]> = rest.iter().map(|&v| vertices[v as usize]).collect();
            for (&v, r) in rest.iter().zip(self.nearest(&q)) {
                out[v as usize] = r;
            }
        }
        out
    }

    /// Nearest vertex of every cloud point, restricted to the vertices of the point's segment when
    /// label-aware matching is on and `vertex_labels` is given: (vertex index, squared distance).
    /// With `warm` (the mesh's edges and every point's vertex of the previous p2m iteration) the
    /// search is the warm-started walk of [`crate::walk`] instead of k-d trees over the vertices.
    fn points_to_vertices(
        &self,
        vertices: &[[f64; 3]],
        vertex_labels: Option<&[u8]>,
        warm: Option<(&CotanWeights, &[u32])>,
    ) -> Result<Vec<(u32, f64)>, String> {
        if let Some((graph, start)) = warm.filter(|(_, s)| s.len() == self.points.len()) {
            let restricted: Vec<bool> = self.by_label.iter().map(Option::is_some).collect();
            let allowed = match (self.label_aware(vertex_labels), &self.labels) {
                (Some(vl), Some(pl)) => Some(Allowed { point_labels: pl, vertex_labels: vl, restricted: &restricted }),
                _ => None,
            };
            return Ok(walk_to_nearest(graph, vertices, &self.points, start, allowed));
        }
        let (Some(vl), Some(labels)) = (self.label_aware(vertex_labels), &self.labels) else {
            let tree = build_tree(vertices)?;
            return Ok(nearest_batch(&tree, &self.points));
        };
        let vgroups = group_by_label(vl);
        let mut out = vec![(0u32, f64::INFINITY); self.points.len()];
        let mut rest: Vec<u32> = Vec::new();
        for (l, lt) in self.by_label.iter().enumerate() {
            if let Some(lt) = lt {
                let vg = &vgroups[l];
                let vpts: Vec<[f64; 3]> = vg.iter().map(|&v| vertices[v as usize]).collect();
                let tree = build_tree(&vpts)?;
                let q: Vec<[f64; 3]> = lt.index.iter().map(|&i| self.points[i as usize]).collect();
                for (&i, (v, d)) in lt.index.iter().zip(nearest_batch(&tree, &q)) {
                    out[i as usize] = (vg[v as usize], d);
                }
            }
        }
        for (i, &l) in labels.iter().enumerate() {
            if self.by_label[l as usize].is_none() {
                rest.push(i as u32);
            }
        }
        if !rest.is_empty() {
            let tree = build_tree(vertices)?;
            let q: Vec<[f64; 3]> = rest.iter().map(|&i| self.points[i as usize]).collect();
            for (&i, r) in rest.iter().zip(nearest_batch(&tree, &q)) {
                out[i as usize] = r;
            }
        }
        Ok(out)
    }

    /// The template's vertex labels when the matching is label-aware (both sides labelled).
    fn label_aware<'a>(&self, vertex_labels: Option<&'a [u8]>) -> Option<&'a [u8]> {
        vertex_labels.filter(|_| !self.by_label.is_empty())
    }

    /// Nearest cloud point of each query: (index, squared distance).
    pub fn nearest(&self, queries: &[[f64; 3]]) -> Vec<(u32, f64)> {
        nearest_batch(&self.tree, queries)
    }

    /// Whether normals are available (given or estimated) and whether they are oriented.
    pub fn normal_mode(&self) -> Option<bool> {
        if self.given_normals.is_some() {
            Some(true)
        } else if !self.estimated.is_empty() {
            Some(false)
        } else {
            None
        }
    }

    /// The normal of cloud point `i` (given, or estimated by PCA of its neighbours and cached).
    pub fn normal(&self, i: usize) -> Option<[f64; 3]> {
        if let Some(n) = &self.given_normals {
            return n.get(i).copied();
        }
        let cell = self.estimated.get(i)?;
        let n = *cell.get_or_init(|| {
            neighbourhood_normal(&self.tree, &self.points, self.points[i], self.k_normals).unwrap_or([0.0; 3])
        });
        (n != [0.0; 3]).then_some(n)
    }

    /// Does the angle between the vertex normal `vn` and cloud normal `cn` pass the test?
    fn normal_ok(vn: [f64; 3], cn: [f64; 3], oriented: bool, min_cos: f64) -> bool {
        if min_cos <= -1.0 || vn == [0.0; 3] {
            return true;
        }
        let c = dot(vn, cn);
        if oriented {
            c >= min_cos
        } else {
            c.abs() >= min_cos
        }
    }

    /// m2p targets of `vertices` (with their current unit normals), pruned.
    /// Returns the targets and the RMS (m) of all nearest distances before pruning.
    /// With `vertex_labels` (and [`Self::set_label_trees`] called), matching is per segment.
    /// With `curvature` (the mesh's form per vertex) the normal part is curvature-corrected
    /// ([`curvature::Shape::correction`]).
    pub fn m2p(
        &self,
        vertices: &[[f64; 3]],
        normals: &[[f64; 3]],
        pruning: &Pruning,
        vertex_labels: Option<&[u8]>,
        curvature: Option<&[curvature::Shape]>,
    ) -> (Targets, f64) {
        let nn = self.nearest_labelled(vertices, vertex_labels);
        let rms = rms_of(nn.iter().map(|r| r.1));
        let mut d2: Vec<f64> = nn.iter().map(|r| r.1).collect();
        let lim2 = pruning.limits2(&mut d2, self.label_aware(vertex_labels));
        let mode = if pruning.min_cos > -1.0 { self.normal_mode() } else { None };
        let targets = nn
            .par_iter()
            .enumerate()
            .map(|(v, &(i, dd))| {
                if dd > lim2.of(v) {
                    return None;
                }
                let cn = if mode.is_some() || self.given_normals.is_some() { self.normal(i as usize) } else { None };
                if let (Some(oriented), Some(cn)) = (mode, cn) {
                    if !Self::normal_ok(normals[v], cn, oriented, pruning.min_cos) {
                        return None;
                    }
                }
                let offset = sub(self.points[i as usize], vertices[v]);
                let n = match cn {
                    Some(cn) if self.given_normals.is_some() => cn,
                    _ => normals[v],
                };
                let mut normal_part = project(n, offset);
                if let Some(h) = curvature {
                    let c = h[v].correction(&moments_of(offset));
                    normal_part = add(normal_part, scale(normals[v], c));
                }
                Some(Residual { offset, normal_part })
            })
            .collect();
        (targets, rms)
    }

    /// p2m targets: the mean of the (pruned) cloud points whose nearest vertex is each vertex.
    /// Returns the targets, the RMS (m) of all point-to-vertex distances before pruning and every
    /// point's vertex (the `warm` start of the next p2m iteration: with it, the nearest vertices are
    /// found by the walk of [`crate::walk`] over the mesh's edges `CotanWeights`).
    /// With `vertex_labels` (and [`Self::set_label_trees`] called), matching is per segment.
    pub fn p2m(
        &self,
        vertices: &[[f64; 3]],
        normals: &[[f64; 3]],
        pruning: &Pruning,
        vertex_labels: Option<&[u8]>,
        curvature: Option<&[curvature::Shape]>,
        warm: Option<(&CotanWeights, &[u32])>,
    ) -> Result<(Targets, f64, Vec<u32>), String> {
        let nn = self.points_to_vertices(vertices, vertex_labels, warm)?;
        let rms = rms_of(nn.iter().map(|r| r.1));
        let mut d2: Vec<f64> = nn.iter().map(|r| r.1).collect();
        let lim2 = pruning.limits2(&mut d2, self.label_aware(vertex_labels));
        let accs = self.accumulate(&nn, vertices, &lim2);
        let assigned = nn.iter().map(|r| r.0).collect();
        Ok((self.patch_targets(&accs, normals, pruning, curvature), rms, assigned))
    }

    /// Per vertex, the count, sum, scatter (and with given normals, the sum of the normal parts)
    /// of the offsets to the cloud points `nn` sends to it, without those longer than its limit.
    ///
    /// Every vertex sums its points in point order (a counting sort groups them first), so the sums
    /// are bit-identical for any thread count.
    #[allow(clippy::neg_cmp_op_on_partial_ord, reason = "a NaN distance is kept, as before")]
    fn accumulate(&self, nn: &[(u32, f64)], vertices: &[[f64; 3]], lim2: &Limits<'_>) -> Vec<Acc> {
        let n = vertices.len();
        let zero = Acc { n: 0, s: [0.0; 3], ss: [0.0; 6], np: [0.0; 3] };
        let given = self.given_normals.as_deref();
        let kept = |v: u32, dd: f64| !(dd > lim2.of(v as usize));
        // start[v]..start[v + 1]: the kept points of vertex v in `order`, in point order.
        let mut start = vec![0u32; n + 1];
        for &(v, dd) in nn {
            if kept(v, dd) {
                start[v as usize + 1] += 1;
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        let mut next = start.clone();
        let mut order = vec![0u32; start[n] as usize];
        for (i, &(v, dd)) in nn.iter().enumerate() {
            if kept(v, dd) {
                let at = &mut next[v as usize];
                order[*at as usize] = i as u32;
                *at += 1;
            }
        }
        (0..n)
            .into_par_iter()
            .with_min_len(256)
            .map(|v| {
                let mut a = zero;
                for &i in &order[start[v] as usize..start[v + 1] as usize] {
                    let idx = i as usize;
                    let d = sub(self.points[idx], vertices[v]);
                    a.n += 1;
                    if let Some(g) = given {
                        let pr = project(g[idx], d);
                        for (np, p) in a.np.iter_mut().zip(pr) {
                            *np += p;
                        }
                    }
                    add_moments(&mut a.s, &mut a.ss, d);
                }
                a
            })
            .collect()
    }

    /// The target of every vertex from its accumulated points (`None` without points or when the
    /// patch normal fails the angle test against the vertex normal); with `curvature` (the mesh's
    /// form per vertex) the normal part is curvature-corrected ([`curvature::Shape::correction`]).
    fn patch_targets(
        &self,
        accs: &[Acc],
        normals: &[[f64; 3]],
        pruning: &Pruning,
        curvature: Option<&[curvature::Shape]>,
    ) -> Targets {
        let given = self.given_normals.as_deref();
        let use_normals = pruning.min_cos > -1.0;
        accs.par_iter()
            .enumerate()
            .map(|(v, a)| {
                if a.n == 0 {
                    return None;
                }
                let m = a.n as f64;
                let mean = a.s.map(|x| x / m);
                let moments = a.ss.map(|x| x / m);
                let patch_normal = if a.n >= 3 && (use_normals || given.is_none()) {
                    let s = &a.ss;
                    let c = Matrix3::new(s[0], s[1], s[2], s[1], s[3], s[4], s[2], s[4], s[5])
                        - Vector3::from(mean) * Vector3::from(mean).transpose() * m;
                    pca_normal(&c)
                } else {
                    None
                };
                if let (true, Some(pn)) = (use_normals, patch_normal) {
                    if !Self::normal_ok(normals[v], pn, false, pruning.min_cos) {
                        return None;
                    }
                }
                let mut normal_part = if given.is_some() {
                    a.np.map(|x| x / m)
                } else {
                    project(patch_normal.unwrap_or(normals[v]), mean)
                };
                if let Some(h) = curvature {
                    let c = h[v].correction(&moments);
                    normal_part = add(normal_part, scale(normals[v], c));
                }
                Some(Residual { offset: mean, normal_part })
            })
            .collect()
    }

    /// RMS (m) of the distances from each cloud point to its nearest vertex; with `warm` (the mesh's
    /// edges and every point's vertex of the last p2m iteration) found by the walk of [`crate::walk`]
    /// over all vertices instead of a k-d tree.
    pub fn rms_points_to_mesh(
        &self,
        vertices: &[[f64; 3]],
        warm: Option<(&CotanWeights, &[u32])>,
    ) -> Result<f64, String> {
        if let Some((graph, start)) = warm.filter(|(_, s)| s.len() == self.points.len()) {
            let nn = walk_to_nearest(graph, vertices, &self.points, start, None);
            return Ok(rms_of(nn.iter().map(|r| r.1)));
        }
        let tree = build_tree(vertices)?;
        Ok(rms_of(nearest_batch(&tree, &self.points).iter().map(|r| r.1)))
    }
}

/// Root of the mean of squared distances.
fn rms_of(d2: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for v in d2 {
        s += v;
        n += 1;
    }
    if n == 0 {
        0.0
    } else {
        (s / n as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const UPPER_ARM: u8 = Segment::UpperArmL as u8;

    /// Two segments of 40 vertices on a line, each with its point 1 mm off; vertex 0 of each segment
    /// has its point 8 mm off instead (8 x the median: beyond 3 x, within 10 x).
    fn scene() -> (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<u8>) {
        let mut vertices = Vec::new();
        let mut points = Vec::new();
        let mut labels = Vec::new();
        for (k, &label) in [TORSO, UPPER_ARM].iter().enumerate() {
            for i in 0..40 {
                let v = [i as f64 * 0.05, k as f64, 0.0];
                let off = if i == 0 { 0.008 } else { 0.001 };
                vertices.push(v);
                points.push([v[0], v[1], v[2] + off]);
                labels.push(label);
            }
        }
        (vertices, points, labels)
    }

    fn pruning(torso: f64) -> Pruning {
        Pruning { distance_factor: 3.0, torso_distance_factor: torso, distance_floor: 0.0, min_cos: -1.0 }
    }

    #[test]
    fn the_torso_keeps_a_correspondence_the_limbs_prune() {
        let (vertices, points, labels) = scene();
        let normals = vec![[0.0, 0.0, 1.0]; vertices.len()];
        let mut index = CloudIndex::new(&points, None, 0).expect("the tree builds");
        index.set_label_trees(LabelTrees::build(&points, &labels, &labels).expect("the label trees build"));
        let (m2p, _) = index.m2p(&vertices, &normals, &pruning(10.0), Some(&labels), None);
        let (p2m, _, _) = index.p2m(&vertices, &normals, &pruning(10.0), Some(&labels), None, None).expect("p2m runs");
        for targets in [&m2p, &p2m] {
            assert!(targets[0].is_some(), "the torso vertex 8 mm off is kept at 10 x the median");
            assert!(targets[40].is_none(), "the upper-arm vertex 8 mm off is pruned at 3 x the median");
            assert!(targets[1].is_some() && targets[41].is_some());
        }
        // With the torso's factor equal to the limbs', both are pruned.
        let (m2p, _) = index.m2p(&vertices, &normals, &pruning(3.0), Some(&labels), None);
        assert!(m2p[0].is_none() && m2p[40].is_none());
    }

    #[test]
    fn without_label_aware_matching_every_vertex_takes_the_common_factor() {
        let (vertices, points, labels) = scene();
        let normals = vec![[0.0, 0.0, 1.0]; vertices.len()];
        let index = CloudIndex::new(&points, None, 0).expect("the tree builds");
        let (m2p, _) = index.m2p(&vertices, &normals, &pruning(10.0), Some(&labels), None);
        assert!(m2p[0].is_none() && m2p[40].is_none());
    }
}
