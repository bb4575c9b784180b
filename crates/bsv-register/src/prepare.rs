//! Stage 1 of a registration: the prepared input. Checks the template and the cloud, drops the
//! cloud's extremities, sparse outliers and the detached pieces of its segments, pre-aligns the
//! template ([`crate::prealign`]) and runs the articulated initialisation of the limbs ([`crate::articulate`]). The result is the
//! rest shape that [`crate::Registrar`] fits.

use crate::articulate;
use crate::correspond::{build_tree, nearest_batch};
use crate::cotan::CotanWeights;
use crate::detached;
use crate::error::{InputError, NumericError, RegisterError};
use crate::keypoints::{Keypoint, Keypoints};
use crate::outliers;
use crate::params::{ArticulationParams, LabelSource, OutlierParams, RegisterParams};
use crate::prealign::{self, Similarity};
use crate::result::LimbAlignment;
use bsv_core::template::JointRing;
use bsv_core::{PointCloud, TriMesh};
use std::borrow::Cow;
use std::time::Instant;

/// A checked, cleaned and pre-aligned registration input (see [`prepare`]).
#[derive(Debug, Clone)]
pub struct Prepared<'a> {
    pub(crate) template: &'a TriMesh,
    /// The cloud without extremities and sparse outliers (borrowed when nothing was dropped).
    pub(crate) cloud: Cow<'a, PointCloud>,
    /// The pre-aligned (and articulated) template vertices: the rest shape of the fit.
    pub(crate) rest: Vec<[f64; 3]>,
    pub(crate) similarity: Similarity,
    pub(crate) articulation: Vec<LimbAlignment>,
    pub(crate) extremities_dropped: usize,
    pub(crate) detached_removed: usize,
    pub(crate) outliers_removed: usize,
    /// Measured joint centres pulling the template's joints (empty: no keypoint term).
    pub(crate) keypoints: Keypoints,
    /// When the registration started (for `Registration::setup_seconds` and `total_seconds`).
    pub(crate) started: Instant,
}

impl<'a> Prepared<'a> {
    /// The template.
    pub fn template(&self) -> &'a TriMesh {
        self.template
    }
    /// The cloud the fit uses (extremities and sparse outliers dropped).
    pub fn cloud(&self) -> &PointCloud {
        &self.cloud
    }
    /// The rest shape: the template's vertices pre-aligned and articulated, metres.
    pub fn rest(&self) -> &[[f64; 3]] {
        &self.rest
    }
    /// Adds the keypoint term: `measured` joint centres pull the template's joints (`rings`, made for
    /// this template: the embedded templates carry theirs, `bsv_core::template::template_joints`).
    /// An [`InputError`] names a joint that is unknown, unusable or whose ring does not fit.
    pub fn with_keypoints(mut self, rings: &[JointRing], measured: &[Keypoint]) -> Result<Self, RegisterError> {
        self.keypoints = Keypoints::new(rings, measured, self.template.vertices.len())?;
        Ok(self)
    }
    /// The pre-alignment used.
    pub fn similarity(&self) -> &Similarity {
        &self.similarity
    }
    /// The limbs moved by the articulated initialisation (empty when it did not run).
    pub fn articulation(&self) -> &[LimbAlignment] {
        &self.articulation
    }
    /// Head/hand/foot cloud points dropped.
    pub fn extremities_dropped(&self) -> usize {
        self.extremities_dropped
    }
    /// Cloud points dropped as detached pieces of their segment.
    pub fn detached_removed(&self) -> usize {
        self.detached_removed
    }
    /// Cloud points dropped as sparse outliers.
    pub fn outliers_removed(&self) -> usize {
        self.outliers_removed
    }
}

/// Prepares `template` and `cloud` (metres, shared world frame) for a fit with `params`: checks
/// (parameters, template, cloud), extremity and sparse-point removal, pre-alignment and the
/// articulated initialisation. Runs on the calling thread (and rayon's global pool for the
/// parallel parts of the outlier filter and the k-d trees of the yaw search).
pub fn prepare<'a>(
    template: &'a TriMesh,
    cloud: &'a PointCloud,
    params: &RegisterParams,
) -> Result<Prepared<'a>, RegisterError> {
    let started = Instant::now();
    params.validate()?;
    let template_box = prealign::check_template(template)?;
    // Head/hand/foot points (the paper drops them: poorly captured, not measured).
    let mut cloud = Cow::Borrowed(cloud);
    let mut extremities_dropped = 0;
    if let Some((c, n)) = drop_extremities(&cloud, &params.outliers)? {
        (cloud, extremities_dropped) = (Cow::Owned(c), n);
    }
    let mut cloud_box = prealign::check_cloud(&cloud, &params.checks, params.prealignment.bbox_quantile)?;
    // Sparse points (flying pixels trail behind the silhouettes, right where the gaps are, and
    // would attract the gap-side vertices), then the detached pieces of a segment (floor and wall
    // spill labelled like a limb) among the points left. The box keeps its definition (the cloud
    // before the sparse-point removal) without the detached pieces and without the sparse points
    // far from the body (mixed pixels toward a wall): redone only when there are such points, so
    // a clean cloud is prepared exactly as without these removals.
    let (mut outliers_removed, mut detached_removed) = (0, 0);
    // Ray-parallel points first: the whole trail, far part included, shows it is a sheet along the
    // rays; after the sparse-point removal only its part near the surface is left, which the
    // surface's own points would hide.
    let keep = crate::raytrail::keep_not_ray_parallel(&cloud.points, params.outliers.ray_parallel_max_cos)
        .map_err(NumericError::index)?;
    let ray_parallel = keep.iter().filter(|&&k| !k).count();
    if ray_parallel > 0 && cloud.points.len() - ray_parallel >= params.checks.min_points {
        let mut c = cloud.into_owned();
        c.retain_indices(|i| keep[i]);
        cloud = Cow::Owned(c);
        outliers_removed += ray_parallel;
        // The box without the trails (they reach tens of centimetres behind the silhouettes).
        cloud_box = prealign::check_cloud(&cloud, &params.checks, params.prealignment.bbox_quantile)?;
    }
    let far = params.prealignment.bbox_max_outlier_distance_m;
    if let Some(cleaned) = clean_cloud(&cloud, &params.outliers, params.checks.min_points, far)? {
        if let Some(box_cloud) = &cleaned.for_box {
            cloud_box = prealign::check_cloud(box_cloud, &params.checks, params.prealignment.bbox_quantile)?;
        }
        (outliers_removed, detached_removed) = (outliers_removed + cleaned.sparse, cleaned.detached);
        cloud = Cow::Owned(cleaned.cloud);
    }
    if params.checks.check_plausible {
        crate::plausible::check_person(&cloud, template)?;
    }
    if params.labels == LabelSource::Template && template.vertex_labels.is_none() {
        return Err(InputError::TemplateWithoutLabels.into());
    }
    let prealignment = params.prealignment.for_template(crate::plausible::is_human_template(template));
    let similarity = prealign::prealign(&template.vertices, &template_box, &cloud.points, &cloud_box, &prealignment)
        .map_err(NumericError::index)?;
    let rest: Vec<[f64; 3]> = template.vertices.iter().map(|&p| similarity.apply(p)).collect();
    let (rest, articulation) = articulate_limbs(rest, template, &cloud, &params.articulation, params.labels);
    Ok(Prepared {
        template,
        cloud,
        rest,
        similarity,
        articulation,
        extremities_dropped,
        detached_removed,
        outliers_removed,
        keypoints: Keypoints::default(),
        started,
    })
}

/// The cloud without its head/hand/foot points and how many were dropped, or `None` when nothing
/// is to be dropped (unlabelled cloud, no extremity, or `drop_extremities` off).
fn drop_extremities(cloud: &PointCloud, params: &OutlierParams) -> Result<Option<(PointCloud, usize)>, InputError> {
    let is_extremity = |l: &u8| bsv_core::EXTREMITIES.iter().any(|s| s.id() == *l);
    match &cloud.labels {
        Some(labels) if params.drop_extremities && labels.len() != cloud.points.len() => {
            Err(InputError::LengthMismatch { what: "cloud labels", got: labels.len(), expected: cloud.points.len() })
        }
        Some(labels) if params.drop_extremities && labels.iter().any(is_extremity) => {
            let mut c = cloud.clone();
            let dropped = c.drop_segments(&bsv_core::EXTREMITIES);
            if c.points.is_empty() {
                return Err(InputError::OnlyExtremities { n: dropped });
            }
            Ok(Some((c, dropped)))
        }
        _ => Ok(None),
    }
}

/// What [`clean_cloud`] dropped.
struct Cleaned {
    /// The cloud without its sparse points and detached pieces.
    cloud: PointCloud,
    /// The box's cloud (without the detached pieces and the far sparse points), when it differs
    /// from the input cloud.
    for_box: Option<PointCloud>,
    /// Sparse points dropped.
    sparse: usize,
    /// Points of detached pieces dropped.
    detached: usize,
}

/// Drops the sparse points ([`crate::outliers`]) and then, among the points left, the detached
/// pieces of the segments ([`crate::detached`]); `None` when nothing is dropped. Either removal
/// is skipped when fewer than `min_points` would remain. The box's cloud also leaves out the
/// sparse points farther than `far` from the cloud kept.
fn clean_cloud(
    cloud: &PointCloud,
    params: &OutlierParams,
    min_points: usize,
    far: f64,
) -> Result<Option<Cleaned>, NumericError> {
    let n = cloud.points.len();
    let min_points = min_points.max(1);
    let mut keep = outliers::sparse_points(&cloud.points, params.outlier_voxel_m, params.outlier_min_fraction);
    let mut sparse = keep.iter().filter(|&&k| !k).count();
    if n - sparse < min_points {
        keep.iter_mut().for_each(|k| *k = true);
        sparse = 0;
    }
    let kept: Vec<usize> = (0..n).filter(|&i| keep[i]).collect();
    let points: Vec<[f64; 3]> = kept.iter().map(|&i| cloud.points[i]).collect();
    let labels: Option<Vec<u8>> = cloud.labels.as_ref().map(|l| kept.iter().map(|&i| l[i]).collect());
    let attached =
        detached::attached_points(&points, labels.as_deref(), params.detached_voxel_m, params.detached_min_fraction);
    let mut out_of_box = vec![false; n];
    for (&i, &a) in kept.iter().zip(&attached) {
        out_of_box[i] = !a;
    }
    let mut detached = attached.iter().filter(|&&a| !a).count();
    // Spill is a few percent of a cloud; a "removal" of half of it means the cloud is too sparse for
    // the voxels to connect its surface (a subsampled cloud), not that half of it is spill.
    if kept.len() - detached < min_points || 2 * detached > kept.len() {
        out_of_box.iter_mut().for_each(|d| *d = false);
        detached = 0;
    }
    if sparse + detached == 0 {
        return Ok(None);
    }
    let final_keep: Vec<bool> = (0..n).map(|i| keep[i] && !out_of_box[i]).collect();
    let far_sparse = mark_far(&cloud.points, &keep, &final_keep, far, &mut out_of_box)?;
    let for_box = (detached + far_sparse > 0).then(|| {
        let mut c = cloud.clone();
        c.retain_indices(|i| !out_of_box[i]);
        c
    });
    let mut c = cloud.clone();
    c.retain_indices(|i| final_keep[i]);
    Ok(Some(Cleaned { cloud: c, for_box, sparse, detached }))
}

/// Marks in `out` the points not in `sparse_kept` (the sparse points) lying farther than `far`
/// from every point of `kept` (those farther by less than `far / 20 * sqrt(3)` may be missed);
/// returns how many. Nothing when `far` is infinite.
fn mark_far(
    points: &[[f64; 3]],
    sparse_kept: &[bool],
    kept: &[bool],
    far: f64,
    out: &mut [bool],
) -> Result<usize, NumericError> {
    let queries: Vec<usize> = (0..points.len()).filter(|&i| !sparse_kept[i]).collect();
    if !far.is_finite() || queries.is_empty() {
        return Ok(0);
    }
    // One kept point per voxel of side far / 20 stands for the cloud (a tree of a few thousand
    // points instead of the whole cloud): the nearest representative is at most a voxel diagonal
    // farther than the nearest kept point, so a point is marked only when that distance less the
    // diagonal exceeds `far` (never a point within `far` of the cloud).
    let inv = 20.0 / far;
    let limit = far * (1.0 + 3f64.sqrt() / 20.0);
    let mut seen = rustc_hash::FxHashSet::default();
    let body: Vec<[f64; 3]> = points
        .iter()
        .zip(kept)
        .filter(|&(p, &k)| k && seen.insert(p.map(|x| (x * inv).floor() as i64)))
        .map(|(p, _)| *p)
        .collect();
    if body.is_empty() {
        return Ok(0);
    }
    let tree = build_tree(&body).map_err(NumericError::index)?;
    let q: Vec<[f64; 3]> = queries.iter().map(|&i| points[i]).collect();
    let mut count = 0;
    for (&i, (_, d2)) in queries.iter().zip(nearest_batch(&tree, &q)) {
        if d2 > limit * limit {
            out[i] = true;
            count += 1;
        }
    }
    Ok(count)
}

/// The articulated initialisation (labelled template and cloud, `articulate` on): the rest shape
/// with every limb turned onto the cloud's, and the limbs moved. Unchanged otherwise. The shoulder
/// halves are held rigid (`articulate_rigid_shoulders`) only when the result keeps the template's
/// labels: that rule carries the template's boundary, which the cloud's labels replace otherwise.
fn articulate_limbs(
    rest: Vec<[f64; 3]>,
    template: &TriMesh,
    cloud: &PointCloud,
    params: &ArticulationParams,
    labels: LabelSource,
) -> (Vec<[f64; 3]>, Vec<LimbAlignment>) {
    let (true, Some(cl), Some(tl)) = (params.articulate, &cloud.labels, &template.vertex_labels) else {
        return (rest, Vec::new());
    };
    let poses = articulate::segment_poses(
        &rest,
        tl,
        &cloud.points,
        cl,
        params.articulate_axial_scale,
        params.articulate_cross_section,
    );
    if poses.is_empty() {
        return (rest, Vec::new());
    }
    let w0 = CotanWeights::new(&rest, &template.triangles);
    let held = if params.articulate_rigid_shoulders && labels == LabelSource::Template {
        articulate::shoulder_halves(tl, &w0, &poses)
    } else {
        Vec::new()
    };
    let rest = articulate::articulate(&rest, tl, &poses, &w0, params.articulate_smooth_iterations, &held);
    let limbs = poses
        .iter()
        .map(|p| LimbAlignment {
            label: p.label,
            angle_deg: p.angle_deg,
            axial_scale: p.axial_scale,
            depth_scale: p.section.depth_scale,
            width_scale: p.section.width_scale,
            shift_mm: bsv_core::geometry::dist2(p.cloud_centroid, p.template_centroid).sqrt() * 1e3,
            elongation: p.elongation,
        })
        .collect();
    (rest, limbs)
}
