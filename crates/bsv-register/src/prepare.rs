//! Stage 1 of a registration: the prepared input. Checks the template and the cloud, drops the
//! cloud's extremities, the detached pieces of its segments and sparse outliers, pre-aligns the template ([`crate::prealign`]) and
//! runs the articulated initialisation of the limbs ([`crate::articulate`]). The result is the
//! rest shape that [`crate::Registrar`] fits.

use crate::articulate;
use crate::cotan::CotanWeights;
use crate::detached;
use crate::error::{InputError, NumericError, RegisterError};
use crate::outliers;
use crate::params::{ArticulationParams, LabelSource, OutlierParams, RegisterParams};
use crate::prealign::{self, Similarity};
use crate::result::LimbAlignment;
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
    // Detached pieces of a segment (floor and wall spill labelled like a limb): before anything
    // aggregates the cloud (the box, the limb axes, the correspondences); the box is redone.
    let mut detached_removed = 0;
    if let Some((c, n)) = drop_detached(&cloud, &params.outliers, params.checks.min_points) {
        (cloud, detached_removed) = (Cow::Owned(c), n);
        cloud_box = prealign::check_cloud(&cloud, &params.checks, params.prealignment.bbox_quantile)?;
    }
    // Sparse-point removal (flying pixels trail behind the silhouettes, right where the
    // gaps are, and would attract the gap-side vertices).
    let mut outliers_removed = 0;
    if let Some((c, n)) = drop_outliers(&cloud, &params.outliers, params.checks.min_points) {
        (cloud, outliers_removed) = (Cow::Owned(c), n);
    }
    if params.labels == LabelSource::Template && template.vertex_labels.is_none() {
        return Err(InputError::TemplateWithoutLabels.into());
    }
    let similarity =
        prealign::prealign(&template.vertices, &template_box, &cloud.points, &cloud_box, &params.prealignment)
            .map_err(NumericError::index)?;
    let rest: Vec<[f64; 3]> = template.vertices.iter().map(|&p| similarity.apply(p)).collect();
    let (rest, articulation) = articulate_limbs(rest, template, &cloud, &params.articulation);
    Ok(Prepared {
        template,
        cloud,
        rest,
        similarity,
        articulation,
        extremities_dropped,
        detached_removed,
        outliers_removed,
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

/// The cloud without the detached pieces of its segments (see [`crate::detached`]) and how many
/// points were dropped, or `None` when none is dropped or fewer than `min_points` would remain.
fn drop_detached(cloud: &PointCloud, params: &OutlierParams, min_points: usize) -> Option<(PointCloud, usize)> {
    let keep = detached::attached_points(
        &cloud.points,
        cloud.labels.as_deref(),
        params.detached_voxel_m,
        params.detached_min_fraction,
    );
    let removed = keep.iter().filter(|&&k| !k).count();
    if removed > 0 && cloud.points.len() - removed >= min_points.max(1) {
        let mut c = cloud.clone();
        c.retain_indices(|i| keep[i]);
        Some((c, removed))
    } else {
        None
    }
}

/// The cloud without its sparse points (see [`crate::outliers`]) and how many were dropped, or
/// `None` when none is dropped or fewer than `min_points` would remain.
fn drop_outliers(cloud: &PointCloud, params: &OutlierParams, min_points: usize) -> Option<(PointCloud, usize)> {
    let keep = outliers::sparse_points(&cloud.points, params.outlier_voxel_m, params.outlier_min_fraction);
    let removed = keep.iter().filter(|&&k| !k).count();
    if removed > 0 && cloud.points.len() - removed >= min_points.max(1) {
        let mut c = cloud.clone();
        c.retain_indices(|i| keep[i]);
        Some((c, removed))
    } else {
        None
    }
}

/// The articulated initialisation (labelled template and cloud, `articulate` on): the rest shape
/// with every limb turned onto the cloud's, and the limbs moved. Unchanged otherwise.
fn articulate_limbs(
    rest: Vec<[f64; 3]>,
    template: &TriMesh,
    cloud: &PointCloud,
    params: &ArticulationParams,
) -> (Vec<[f64; 3]>, Vec<LimbAlignment>) {
    let (true, Some(cl), Some(tl)) = (params.articulate, &cloud.labels, &template.vertex_labels) else {
        return (rest, Vec::new());
    };
    let poses = articulate::segment_poses(&rest, tl, &cloud.points, cl, params.articulate_axial_scale);
    if poses.is_empty() {
        return (rest, Vec::new());
    }
    let w0 = CotanWeights::new(&rest, &template.triangles);
    let rest = articulate::articulate(&rest, tl, &poses, &w0, params.articulate_smooth_iterations);
    let limbs = poses
        .iter()
        .map(|p| LimbAlignment {
            label: p.label,
            angle_deg: p.angle_deg,
            axial_scale: p.axial_scale,
            shift_mm: bsv_core::geometry::dist2(p.cloud_centroid, p.template_centroid).sqrt() * 1e3,
        })
        .collect();
    (rest, limbs)
}
