//! What a registration returns.

use crate::log::IterationLog;
use crate::params::LabelSource;
use crate::prealign::Similarity;
use bsv_core::TriMesh;
use serde::Serialize;

/// The result of a registration.
#[derive(Debug, Clone, Serialize)]
pub struct Registration {
    /// The fitted mesh: fitted vertices, the template's triangles, vertex labels (from the cloud, or
    /// the template's), face labels only in template-label mode.
    #[serde(skip)]
    pub mesh: TriMesh,
    /// One entry per iteration.
    pub log: Vec<IterationLog>,
    /// The pre-alignment used.
    pub prealign: Similarity,
    /// Checks, pre-alignment, weights, k-d tree and symbolic factorization, seconds.
    pub setup_seconds: f64,
    /// Whole registration, seconds.
    pub total_seconds: f64,
    /// RMS distance from the fitted vertices to their nearest cloud point, mm.
    pub rms_mesh_to_points_mm: f64,
    /// RMS distance from the cloud points to their nearest fitted vertex, mm.
    pub rms_points_to_mesh_mm: f64,
    /// Where the vertex labels came from (`None` when the mesh has no labels).
    pub labels_from: Option<LabelSource>,
    /// Head/hand/foot cloud points dropped before the fit
    /// ([`crate::OutlierParams::drop_extremities`]).
    pub extremities_dropped: usize,
    /// Cloud points dropped as detached pieces of their segment
    /// ([`crate::OutlierParams::detached_voxel_m`]).
    pub detached_removed: usize,
    /// Cloud points dropped as sparse outliers ([`crate::OutlierParams::outlier_voxel_m`]).
    pub outliers_removed: usize,
    /// The limbs moved by the articulated initialisation (empty when it did not run).
    pub articulation: Vec<LimbAlignment>,
    /// Per-segment quality figures of the fit, by segment name (`quality.rs`).
    pub quality: std::collections::BTreeMap<String, crate::quality::SegmentQuality>,
    /// Distance of each fitted template joint to its measured centre (empty without keypoints).
    pub keypoints: Vec<crate::keypoints::KeypointResidual>,
}

/// One limb of the articulated initialisation ([`crate::ArticulationParams`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LimbAlignment {
    /// Segment id.
    pub label: u8,
    /// Angle between the template's and the cloud's limb axes, degrees.
    pub angle_deg: f64,
    /// Scale applied along the axis.
    pub axial_scale: f64,
    /// Scale applied to the cross-section's depth (front-back), 1 = none (see `section.rs`).
    pub depth_scale: f64,
    /// Scale applied to the cross-section's width, 1 = none.
    pub width_scale: f64,
    /// Distance between the template's and the cloud's segment centroids (after the global
    /// pre-alignment), mm.
    pub shift_mm: f64,
    /// The cloud limb's elongation (largest over middle eigenvalue of its points' covariance; see
    /// `articulate::MIN_ELONGATION`).
    pub elongation: f64,
}
