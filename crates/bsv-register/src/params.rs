//! Registration parameters, with documented defaults, grouped by the stage that reads them
//! ([`EnergyParams`], [`PruningParams`], [`PrealignParams`], [`CheckParams`], [`OutlierParams`],
//! [`ArticulationParams`]); the groups are flattened in the serde form, so JSON and keyword
//! arguments use the flat names (`alpha`, `data_weight`, `prealign`, ...).
//!
//! The energy, its units and weights are documented on [`EnergyParams`].

use crate::error::ParameterError;
use crate::schedule::Schedule;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
/// How the template is scaled onto the cloud before the non-rigid fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PrealignMode {
    /// The paper: one scale, the ratio of the bounding-box diagonals.
    Isotropic,
    /// One scale per axis, the ratio of the bounding-box sides.
    PerAxis,
    /// Per-axis when the box proportions differ by more than [`PrealignParams::auto_aspect_threshold`],
    /// isotropic otherwise; always isotropic for a labelled human template
    /// ([`PrealignParams::for_template`]).
    Auto,
}

/// Whether the pre-alignment also turns the template about the vertical (y) axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum YawMode {
    /// No rotation (the paper: template and cloud share the world frame).
    Off,
    /// Search a yaw when the horizontal footprints of template and cloud are turned against each
    /// other (a box at 45 degrees), and keep it only when it clearly lowers the cloud-to-template
    /// RMS (see `prealign.rs`). A body facing +Z like its template is never turned.
    Auto,
}

/// Where the fitted mesh takes its vertex labels from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LabelSource {
    /// Each fitted vertex takes the label of its nearest cloud point (the paper). Falls back to the
    /// template's labels (or none) when the cloud is unlabelled.
    Cloud,
    /// Keep the template's own vertex (and face) labels; an error if the template has none.
    Template,
}

/// The energy's weights: read by the local model and the global solver.
///
/// # Units and weights
/// Geometry is in metres. The energy minimised is (see `local.rs` for the derivation)
///
/// ```text
/// E = E_arap + E_reg + E_data
/// E_arap = sum_i w_c sum_{j in N(i)} w_ij |(p'_i - p'_j) - T_i (p_i - p_j)|^2     (m^2)
/// E_reg  = lambda sum_i |T_i - R_i|_F^2,   lambda = alpha * 1e-6 * w_c * A / N      (m^2)
/// E_data = sum_i d_i |p'_i - q_i|^2                                                (m^2)
/// ```
/// with `w_ij` the (dimensionless) cotangent weights, `w_c` = [`Self::cell_weight`],
/// `A` the TOTAL area of the pre-aligned template (m^2), `N` its vertex count, `q_i` the
/// correspondence target and `d_i` = [`Self::data_weight`] (0 without correspondence).
///
/// How this relates to the paper (`lambda_paper = alpha * A`, `w_i = 1e-2`, `alpha = 1e6`): read
/// literally in any unit, the paper's ratio of regularization to ARAP stiffness per cell is
/// `alpha * N / w_c` (about 1e12 for a body template), i.e. T_i would be a rotation and no cell could
/// ever scale. We keep the paper's structure (one global weight proportional to the total area A,
/// so shrinking triangles cannot lower it) and its numbers, but make the weight dimensionless and
/// resolution-independent: `lambda = (alpha / 1e6) * w_c * A / N`, so at the default alpha = 1e6 the
/// penalty for leaving the nearest rotation equals the ARAP stiffness of an average cell
/// (`w_c * A / N`, about a quarter of `w_c * tr(P_i)` on a regular mesh). alpha = 1e8 is practically
/// classic ARAP (T_i = R_i); alpha = 0 lets every cell be any affine map.
///
/// On gappy clouds alpha = 0 does not collapse in this engine (contrary to the paper's "collapses
/// within 5 iterations"): with free affine cells the ARAP term is still an affine-invariant
/// smoothness term, and m2p gives every vertex a target. The regularization's role here is
/// stiffness: larger alpha keeps cells closer to rotations and shrinks the unseen sides more
/// (tests/gaps.rs `alpha_sweep_on_the_gap_torso`). The default 1e6 is kept as the paper's value; the
/// body cohort was tuned with it. (measured: benchmarks/BENCH.md, section Registration)
///
/// The data weight `d` is dimensionless in the same sense as `w_c`: the diagonal of the ARAP system
/// is `2 w_c sum_j w_ij ~ 7 w_c` on a regular mesh, so the default `d = 1`, `w_c = 1e-2` makes a
/// vertex follow its target ~14 times more than its neighbours, while the Laplacian still averages
/// sampling noise over a few rings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct EnergyParams {
    /// Regularization strength (dimensionless, see above). Default 1e6 (the paper's number):
    /// leaving the nearest rotation costs as much as the ARAP stiffness of an average cell.
    /// 0 = free affine cells.
    pub alpha: f64,
    /// Per-cell ARAP weight `w_c` (the paper's `w_i`). Default 1e-2.
    pub cell_weight: f64,
    /// Data weight `d` of a vertex with a correspondence (same scale as `cell_weight`). Default 1.
    pub data_weight: f64,
    /// Fraction of the tangential part of a data residual that is kept (0 = the target slides
    /// along the vertex's tangent plane, a linearised point-to-plane term; 1 = plain point-to-point).
    /// Default 0: sampling noise along the surface does not drag vertices (with 0.1, a sphere
    /// registered to 100k samples of itself drifts 2.5 mm as vertices migrate onto samples).
    pub tangential_weight: f64,
    /// The same fraction in p2m iterations, where the tangential offset is the pull toward the
    /// centroid of the vertex's points (Lloyd relaxation: it evens out vertices that bunched up or
    /// spread along the surface). Default 0 (see the bent-capsule test for a case that wants it).
    pub tangential_weight_p2m: f64,
    /// Weight of a measured joint centre (keypoint term, `keypoints.rs`) in units of one vertex's data
    /// weight: the template's joint is pulled as strongly as `keypoint_weight` vertices are pulled to
    /// the cloud, times the joint's confidence. Default 40. Used only when keypoints are given.
    pub keypoint_weight: f64,
    /// Robust scale (m) of the keypoint term: a joint whose measured centre lies `r` from the fitted
    /// one pulls with the factor `1 / (1 + (r / keypoint_robust_m)^2)`. Default 0.03.
    pub keypoint_robust_m: f64,
    /// Pull a template joint only along its limb (the normal of the joint's ring): the measured joints
    /// place the segment boundaries along the limbs, the cloud keeps the surface. Default true.
    pub keypoint_axial: bool,
    /// The keypoint term acts in the first `keypoint_iterations` iterations only: it places the
    /// template's joints, then the cloud alone finishes the fit (a joint held against the cloud's
    /// pull stretches the limb and thins its unseen sides). Default 10: the first m2p stage and the
    /// p2m stage after it (camera path, seeds 0, 2, 4, 6: the eight limbs' mean error 0.05 points
    /// lower than with 5 in 8 of 8 runs; benchmarks/BENCH.md, "Round 2, session 13").
    pub keypoint_iterations: usize,
    /// Lift the normal part of every data target by the height of the surface under its points'
    /// spread (`curvature.rs`): the mean of the points whose nearest vertex is this one (p2m) lies
    /// under the surface on a convex limb, by 0.26 mm for 16 vertices around a 40 mm forearm
    /// (-1.3 % of its volume). The form comes from the fitted mesh's 1-ring. Default true (measured:
    /// benchmarks/BENCH.md, "Round 2, session 4").
    pub curvature_correction: bool,
}

impl Default for EnergyParams {
    fn default() -> Self {
        EnergyParams {
            alpha: 1e6,
            cell_weight: 1e-2,
            data_weight: 1.0,
            tangential_weight: 0.0,
            tangential_weight_p2m: 0.0,
            keypoint_weight: 40.0,
            keypoint_robust_m: 0.03,
            keypoint_axial: true,
            keypoint_iterations: 10,
            curvature_correction: true,
        }
    }
}

/// Which correspondences are kept in an iteration (see `correspond.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PruningParams {
    /// Drop correspondences longer than `prune_distance_factor` x the median correspondence length
    /// of the iteration (0 or inf = off). Default 3.
    pub prune_distance_factor: f64,
    /// The `prune_distance_factor` of the template's torso vertices when the fit is label-aware (both
    /// the cloud and the template labelled; the same median): the torso's shape varies most between
    /// people (a belly, the buttocks, the breasts) and no articulated cross-section fits it first, so
    /// its gap to the cloud closes last; at 3 x the median, a region of the torso still 2-4 cm off
    /// when the limbs have converged is pruned and never reached (torso -5 % on a full-buttocked
    /// subject). The limbs keep `prune_distance_factor`, where a looser one costs accuracy.
    /// Default 6.
    pub prune_distance_factor_torso: f64,
    /// Never prune correspondences shorter than this (metres), so a perfect fit is not pruned to
    /// noise. Default 0.005 m.
    pub prune_distance_floor_m: f64,
    /// Drop correspondences whose cloud normal and current vertex normal differ by more than this
    /// angle (degrees; >= 180 = off). Used when the cloud has normals or they are estimated.
    /// Default 60.
    pub prune_normal_angle_deg: f64,
    /// Estimate cloud normals by PCA of this many neighbours when the cloud has none (0 = do not;
    /// then no normal pruning). Default 12.
    pub estimate_normals_k: usize,
    /// Label-aware correspondences when the cloud and the template are both labelled: a template
    /// vertex of segment L is matched only to cloud points of segment L and vice versa (matches
    /// across segments are excluded; see `correspond.rs`). Default true.
    pub label_aware: bool,
}

impl Default for PruningParams {
    fn default() -> Self {
        PruningParams {
            prune_distance_factor: 3.0,
            prune_distance_factor_torso: 6.0,
            prune_distance_floor_m: 0.005,
            prune_normal_angle_deg: 60.0,
            estimate_normals_k: 12,
            label_aware: true,
        }
    }
}

/// The similarity pre-alignment (see `prealign.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PrealignParams {
    /// Pre-alignment mode. Default [`PrealignMode::Auto`].
    pub prealign: PrealignMode,
    /// Rotation search about the vertical axis in the pre-alignment. Default [`YawMode::Auto`].
    pub prealign_yaw: YawMode,
    /// [`PrealignMode::Auto`] uses per-axis scaling when, for some axis, the ratio of the cloud's
    /// and the template's normalised box side (side / diagonal) differs from 1 by more than this.
    /// Default 0.5 (50 %): a 1.04 x 0.2 x 0.2 m box against a cube template differs by 66 %, human
    /// proportions against an average template by far less. A pose change also changes the box
    /// (a bent limb is wider): register such shapes with `Isotropic`.
    pub auto_aspect_threshold: f64,
    /// Robust bounding box: the lower/upper quantile of each axis (0 = plain min/max).
    /// Default 0.001 (0.1 % / 99.9 %), so stray points and flying pixels do not stretch the box.
    /// Also the box of the cloud's extent check ([`CheckParams`]).
    pub bbox_quantile: f64,
    /// The box is taken from the cloud before the sparse-point removal ([`OutlierParams`]), so the
    /// flying pixels a depth camera leaves behind the silhouettes count in it (the cohort was tuned
    /// so); but sparse points farther than this from the cloud kept are left out of it (metres;
    /// inf = none, the behaviour before): mixed pixels between the body and a wall 0.3-1 m behind
    /// it stretched the box and the template with it (torso +160 % with 0.5 % of such points).
    /// Default 0.3: the virtual L515's flying pixels reach 0.27-0.28 m.
    pub bbox_max_outlier_distance_m: f64,
}

impl PrealignParams {
    /// The settings for a template: [`PrealignMode::Auto`] becomes [`PrealignMode::Isotropic`] for a
    /// labelled human template (`human`). A body's box proportions say little about its shape: the
    /// arms' abduction sets its width, and a depth camera's flying pixels trail behind every
    /// silhouette and stretch its depth (L515-like scans: by 50-70 %, enough for Auto to scale the
    /// template 1.5-1.7 times in depth; wide-armed subjects then fold their upper arms, -10 to -21 %).
    /// The articulated initialisation fits each limb instead. Explicit modes are kept.
    pub fn for_template(&self, human: bool) -> PrealignParams {
        let mut p = self.clone();
        if human && p.prealign == PrealignMode::Auto {
            p.prealign = PrealignMode::Isotropic;
        }
        p
    }
}

impl Default for PrealignParams {
    fn default() -> Self {
        PrealignParams {
            prealign: PrealignMode::Auto,
            prealign_yaw: YawMode::Auto,
            auto_aspect_threshold: 0.5,
            bbox_quantile: 0.001,
            bbox_max_outlier_distance_m: 0.3,
        }
    }
}

/// The plausibility checks of the cloud (see `prealign::check_cloud`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CheckParams {
    /// Minimum number of cloud points. Default 100.
    pub min_points: usize,
    /// Largest plausible cloud extent (metres): larger clouds are taken as millimetres. Default 5.
    pub max_extent_m: f64,
    /// Smallest plausible cloud extent (metres). Default 0.05.
    pub min_extent_m: f64,
    /// With a labelled human template, refuse a cloud that is not a standing person in the world
    /// frame (flat, compact, not upright, not facing +Z, not of a person's size in metres; see
    /// `plausible.rs`). Default true.
    pub check_plausible: bool,
}

impl Default for CheckParams {
    fn default() -> Self {
        CheckParams {
            min_points: 100,
            max_extent_m: bsv_core::geometry::MAX_EXTENT_M,
            min_extent_m: 0.05,
            check_plausible: true,
        }
    }
}

/// The cloud points dropped before the fit: extremities and sparse outliers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OutlierParams {
    /// Drop the cloud's head, hand and foot points (labels in `bsv_core::EXTREMITIES`: 1, 7, 8, 13,
    /// 14) before the fit, as in the paper: those segments are poorly captured and not measured.
    /// No effect on an unlabelled cloud. Default true.
    pub drop_extremities: bool,
    /// Sparse-point (flying pixel) removal before the fit: voxel side in metres (0 = off). A point
    /// is dropped when the 27 voxels around it hold fewer than
    /// [`Self::outlier_min_fraction`] x the median such count (see `outliers.rs`). Default 0.008.
    pub outlier_voxel_m: f64,
    /// See [`Self::outlier_voxel_m`]. Default 0.1.
    pub outlier_min_fraction: f64,
    /// Detached-piece removal before the fit: voxel side in metres (0 = off). Per segment label
    /// (the whole cloud when unlabelled), points in touching voxels form pieces, and a piece with
    /// fewer points than [`Self::detached_min_fraction`] x the segment's largest piece is dropped:
    /// floor patches and wall slivers that a person mask spilled onto and labelled like the
    /// nearest limb (see `detached.rs`). Default 0.015: pieces more than ~2-5 cm apart are
    /// separate; a segment's own surface, sampled every few millimetres, is one piece per camera.
    pub detached_voxel_m: f64,
    /// See [`Self::detached_voxel_m`]. Default 0.25: a segment's front and back pieces (split by the
    /// lateral gaps) are each far larger; a spill of a few percent of the points is far smaller.
    pub detached_min_fraction: f64,
    /// Ray-parallel point removal before the fit (`raytrail.rs`): a point whose PCA normal makes
    /// an angle with the viewing axis Z whose cosine is below this (it lies on a sheet that contains
    /// the cameras' rays: a flying-pixel trail beside a silhouette, or a grazing point) is dropped;
    /// skipped when more than 7 % of the cloud would go (an all-round scan). 0 = off. Default 0
    /// (off since round 2 session 7): with the sparse-point filter, the detached-piece test and the
    /// box's far-point rule in place, dropping the grazing points too widened the lateral gaps and
    /// shrank L515-like fits (oracle seed 0 l515 trunk_limbs -0.57 -> -0.47 % signed; camera path
    /// neutral; `benchmarks/BENCH.md`). 0.2 is the value it had when on.
    pub ray_parallel_max_cos: f64,
}

impl Default for OutlierParams {
    fn default() -> Self {
        OutlierParams {
            drop_extremities: true,
            outlier_voxel_m: 0.008,
            outlier_min_fraction: 0.1,
            detached_voxel_m: 0.015,
            detached_min_fraction: 0.25,
            ray_parallel_max_cos: 0.0,
        }
    }
}

/// The articulated initialisation of the limbs (see `articulate.rs`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ArticulationParams {
    /// Articulated initialisation when the cloud and the template are both labelled: every limb is
    /// turned (and moved) onto the cloud's limb before the fit. Default true.
    pub articulate: bool,
    /// Scale each limb along its axis by the ratio of the segment lengths in the articulated
    /// initialisation (ends aligned). Default true.
    pub articulate_axial_scale: bool,
    /// Scale each limb's cross-section (depth and width) to the cloud's in the articulated
    /// initialisation (see `section.rs`), so that the fit need not stretch the cells that the
    /// lateral gaps leave without data. Default true.
    pub articulate_cross_section: bool,
    /// Jacobi smoothing steps of the articulation's displacement field (blends the joints).
    /// Default 10.
    pub articulate_smooth_iterations: usize,
    /// Leave the shoulder half of each upper arm out of that blending: its vertices keep the arm's
    /// rigid motion and only the torso side of the shoulder is blended, so the template's shoulder
    /// boundary turns with the arm. Blended, the boundary lags behind the arm's turn and the
    /// template-labelled upper arm's volume follows the arm's abduction (+0.19 % per degree with
    /// exact labels; benchmarks/BENCH.md, round 2 session 10). Applies when the result keeps the
    /// template's labels (`labels` = template, the camera path's); with the cloud's labels the
    /// boundary is the cloud's and the blended shoulder fits the oracle cohort better. Default true.
    pub articulate_rigid_shoulders: bool,
}

impl Default for ArticulationParams {
    fn default() -> Self {
        ArticulationParams {
            articulate: true,
            articulate_axial_scale: true,
            articulate_cross_section: true,
            articulate_smooth_iterations: 10,
            articulate_rigid_shoulders: true,
        }
    }
}

/// Every knob of a registration, grouped by the stage that reads it, with the defaults documented on
/// each field.
///
/// The serde form is flat (the groups are `#[serde(flatten)]`): `{"alpha": 1e6, "schedule":
/// "m2p:5,p2m:5,m2p:10", "drop_extremities": false, ...}`, every key optional (missing keys take
/// their defaults), and an unknown key is an error naming it (see [`PARAMETER_NAMES`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ParamsRepr")]
pub struct RegisterParams {
    /// The energy's weights.
    #[serde(flatten)]
    pub energy: EnergyParams,
    /// Correspondence schedule. Default [`crate::DEFAULT_SCHEDULE`], `m2p:5,p2m:5,m2p:4,p2m:2`.
    pub schedule: Schedule,
    /// The schedule's last stage ends early, after at least [`MIN_FINAL_ITERATIONS`] of its
    /// iterations, at the first iteration that moves the vertices by less than this RMS distance
    /// (mm; 0 = always run every iteration). Default 0.2: by then an iteration changes no segment's
    /// volume by more than the correspondences' own jitter (measured: benchmarks/BENCH.md, "Round 2,
    /// session 6"). It acts on a last stage longer than [`MIN_FINAL_ITERATIONS`] (a user's schedule,
    /// e.g. the paper's `m2p:5,p2m:5,m2p:10`); the default schedule's 2-iteration p2m tail always runs.
    pub stop_motion_mm: f64,
    /// In a p2m iteration that follows a p2m iteration, each cloud point finds its nearest vertex
    /// by walking over the mesh's edges from its previous one (`walk.rs`) instead of a k-d tree
    /// query over the vertices; the first p2m iteration of a stage is always exact. Default true:
    /// the p2m iterations take about a third of the time, the volumes move by less than the
    /// correspondences' own jitter (measured: benchmarks/BENCH.md, "Round 2, session 8").
    pub p2m_warm_start: bool,
    /// Correspondence pruning.
    #[serde(flatten)]
    pub pruning: PruningParams,
    /// Pre-alignment.
    #[serde(flatten)]
    pub prealignment: PrealignParams,
    /// Cloud plausibility checks.
    #[serde(flatten)]
    pub checks: CheckParams,
    /// Worker threads (a rayon pool of this size; 0 = all cores). Default 0. Ignored by
    /// [`crate::register_in`], which runs in the caller's pool.
    pub threads: usize,
    /// Label source of the fitted mesh. Default [`LabelSource::Cloud`]. With `Cloud` and an
    /// unlabelled cloud the fit does not fail: the mesh falls back to the template's vertex labels
    /// (no labels when the template has none either) and `Registration::labels_from` says
    /// `Template` (or `None`).
    pub labels: LabelSource,
    /// Points dropped before the fit.
    #[serde(flatten)]
    pub outliers: OutlierParams,
    /// Move the fitted vertices out by the inscribed-mesh gap `h^2 H / 8` (see
    /// [`crate::surface_correction`]) so that the fitted faces, not only the vertices, lie on the
    /// surface on average: removes the volume bias of a coarse template. Default true.
    pub surface_correction: bool,
    /// Articulated initialisation.
    #[serde(flatten)]
    pub articulation: ArticulationParams,
}

impl Default for RegisterParams {
    fn default() -> Self {
        RegisterParams {
            energy: EnergyParams::default(),
            schedule: Schedule::default(),
            stop_motion_mm: 0.2,
            p2m_warm_start: true,
            pruning: PruningParams::default(),
            prealignment: PrealignParams::default(),
            checks: CheckParams::default(),
            threads: 0,
            labels: LabelSource::Cloud,
            outliers: OutlierParams::default(),
            surface_correction: true,
            articulation: ArticulationParams::default(),
        }
    }
}

/// Every key of the serde form of [`RegisterParams`] (the flat parameter names), in the order of
/// the serialised form. A unit test keeps it equal to the serialised keys.
pub const PARAMETER_NAMES: [&str; 42] = [
    "alpha",
    "cell_weight",
    "data_weight",
    "tangential_weight",
    "tangential_weight_p2m",
    "keypoint_weight",
    "keypoint_robust_m",
    "keypoint_axial",
    "keypoint_iterations",
    "curvature_correction",
    "schedule",
    "stop_motion_mm",
    "p2m_warm_start",
    "prune_distance_factor",
    "prune_distance_factor_torso",
    "prune_distance_floor_m",
    "prune_normal_angle_deg",
    "estimate_normals_k",
    "label_aware",
    "prealign",
    "prealign_yaw",
    "auto_aspect_threshold",
    "bbox_quantile",
    "bbox_max_outlier_distance_m",
    "min_points",
    "max_extent_m",
    "min_extent_m",
    "check_plausible",
    "threads",
    "labels",
    "drop_extremities",
    "outlier_voxel_m",
    "outlier_min_fraction",
    "detached_voxel_m",
    "detached_min_fraction",
    "ray_parallel_max_cos",
    "surface_correction",
    "articulate",
    "articulate_axial_scale",
    "articulate_cross_section",
    "articulate_smooth_iterations",
    "articulate_rigid_shoulders",
];

/// The deserialised form of [`RegisterParams`]: the same groups plus every key no group took.
///
/// serde does not support `deny_unknown_fields` together with `flatten`, so the keys left over
/// after the groups took theirs are collected in `unknown` (a flattened map after the flattened
/// structs receives exactly the keys none of them consumed) and rejected by the `TryFrom`.
#[derive(Deserialize)]
#[serde(default)]
struct ParamsRepr {
    #[serde(flatten)]
    energy: EnergyParams,
    schedule: Schedule,
    stop_motion_mm: f64,
    p2m_warm_start: bool,
    #[serde(flatten)]
    pruning: PruningParams,
    #[serde(flatten)]
    prealignment: PrealignParams,
    #[serde(flatten)]
    checks: CheckParams,
    threads: usize,
    labels: LabelSource,
    #[serde(flatten)]
    outliers: OutlierParams,
    surface_correction: bool,
    #[serde(flatten)]
    articulation: ArticulationParams,
    /// Must stay the last field: it receives the keys the groups above did not take.
    #[serde(flatten)]
    unknown: BTreeMap<String, serde::de::IgnoredAny>,
}

impl Default for ParamsRepr {
    fn default() -> Self {
        let d = RegisterParams::default();
        ParamsRepr {
            energy: d.energy,
            schedule: d.schedule,
            stop_motion_mm: d.stop_motion_mm,
            p2m_warm_start: d.p2m_warm_start,
            pruning: d.pruning,
            prealignment: d.prealignment,
            checks: d.checks,
            threads: d.threads,
            labels: d.labels,
            outliers: d.outliers,
            surface_correction: d.surface_correction,
            articulation: d.articulation,
            unknown: BTreeMap::new(),
        }
    }
}

impl TryFrom<ParamsRepr> for RegisterParams {
    type Error = String;
    fn try_from(r: ParamsRepr) -> Result<Self, String> {
        if let Some(key) = r.unknown.keys().next() {
            let expected = PARAMETER_NAMES.map(|n| format!("`{n}`")).join(", ");
            return Err(format!("unknown field `{key}` (not a registration parameter), expected one of {expected}"));
        }
        Ok(RegisterParams {
            energy: r.energy,
            schedule: r.schedule,
            stop_motion_mm: r.stop_motion_mm,
            p2m_warm_start: r.p2m_warm_start,
            pruning: r.pruning,
            prealignment: r.prealignment,
            checks: r.checks,
            threads: r.threads,
            labels: r.labels,
            outliers: r.outliers,
            surface_correction: r.surface_correction,
            articulation: r.articulation,
        })
    }
}

/// Fewest iterations the schedule's last stage runs before `stop_motion_mm` may end it.
pub const MIN_FINAL_ITERATIONS: usize = 3;

/// Largest `estimate_normals_k`.
pub const MAX_NORMAL_NEIGHBOURS: usize = 1000;
/// Largest `articulate_smooth_iterations`.
pub const MAX_SMOOTH_ITERATIONS: usize = 10_000;
/// Largest `threads`.
pub const MAX_THREADS: usize = 1024;

/// `Ok` when `ok`, else the [`ParameterError::BadParameter`] for `name`.
fn check(name: &'static str, value: f64, ok: bool, hint: &'static str) -> Result<(), ParameterError> {
    if ok {
        Ok(())
    } else {
        Err(ParameterError::BadParameter { name, value, hint })
    }
}

impl RegisterParams {
    /// Checks every numeric parameter's range and that the schedule has an iteration.
    pub fn validate(&self) -> Result<(), ParameterError> {
        self.energy.validate()?;
        check(
            "stop_motion_mm",
            self.stop_motion_mm,
            self.stop_motion_mm.is_finite() && self.stop_motion_mm >= 0.0,
            "must be finite and >= 0 (mm; 0 = run every iteration of the schedule)",
        )?;
        let p = &self.pruning;
        check(
            "prune_distance_factor",
            p.prune_distance_factor,
            p.prune_distance_factor >= 0.0,
            "must be >= 0 (0 or inf = no distance pruning)",
        )?;
        check(
            "prune_distance_factor_torso",
            p.prune_distance_factor_torso,
            p.prune_distance_factor_torso >= 0.0,
            "must be >= 0 (0 or inf = no distance pruning of the torso)",
        )?;
        check(
            "prune_distance_floor_m",
            p.prune_distance_floor_m,
            p.prune_distance_floor_m.is_finite() && p.prune_distance_floor_m >= 0.0,
            "must be finite and >= 0",
        )?;
        check(
            "prune_normal_angle_deg",
            p.prune_normal_angle_deg,
            p.prune_normal_angle_deg > 0.0,
            "must be > 0 degrees (>= 180 = off)",
        )?;
        let a = &self.prealignment;
        check(
            "auto_aspect_threshold",
            a.auto_aspect_threshold,
            a.auto_aspect_threshold.is_finite() && a.auto_aspect_threshold >= 0.0,
            "must be finite and >= 0",
        )?;
        let o = &self.outliers;
        check(
            "outlier_voxel_m",
            o.outlier_voxel_m,
            o.outlier_voxel_m.is_finite() && o.outlier_voxel_m >= 0.0,
            "must be finite and >= 0 metres (0 = no outlier removal)",
        )?;
        check(
            "outlier_min_fraction",
            o.outlier_min_fraction,
            (0.0..=1.0).contains(&o.outlier_min_fraction),
            "must be in [0, 1]",
        )?;
        check(
            "detached_voxel_m",
            o.detached_voxel_m,
            o.detached_voxel_m.is_finite() && o.detached_voxel_m >= 0.0,
            "must be finite and >= 0 metres (0 = no detached-piece removal)",
        )?;
        check(
            "detached_min_fraction",
            o.detached_min_fraction,
            (0.0..=1.0).contains(&o.detached_min_fraction),
            "must be in [0, 1] (0 = keep every piece)",
        )?;
        check(
            "ray_parallel_max_cos",
            o.ray_parallel_max_cos,
            (0.0..1.0).contains(&o.ray_parallel_max_cos),
            "must be in [0, 1) (0 = off)",
        )?;
        check(
            "bbox_max_outlier_distance_m",
            a.bbox_max_outlier_distance_m,
            a.bbox_max_outlier_distance_m > 0.0,
            "must be > 0 metres (inf = keep every sparse point in the box)",
        )?;
        check("bbox_quantile", a.bbox_quantile, (0.0..0.25).contains(&a.bbox_quantile), "must be in [0, 0.25)")?;
        let c = &self.checks;
        check(
            "max_extent_m",
            c.max_extent_m,
            c.max_extent_m > c.min_extent_m && c.min_extent_m >= 0.0,
            "need 0 <= min_extent_m < max_extent_m",
        )?;
        // Counts: a huge value would allocate or loop without end (found by tests/params_fuzz.rs).
        let k = self.pruning.estimate_normals_k;
        check("estimate_normals_k", k as f64, k <= MAX_NORMAL_NEIGHBOURS, "must be 0..=1000 neighbours")?;
        let j = self.articulation.articulate_smooth_iterations;
        check("articulate_smooth_iterations", j as f64, j <= MAX_SMOOTH_ITERATIONS, "must be 0..=10000")?;
        check("threads", self.threads as f64, self.threads <= MAX_THREADS, "must be 0..=1024 (0 = all cores)")?;
        if self.schedule.total_iterations() == 0 {
            return Err(ParameterError::BadSchedule {
                text: self.schedule.to_string(),
                reason: "the schedule has no iteration".to_string(),
            });
        }
        Ok(())
    }
}

impl EnergyParams {
    /// Checks the weights' ranges.
    pub fn validate(&self) -> Result<(), ParameterError> {
        check("alpha", self.alpha, self.alpha.is_finite() && self.alpha >= 0.0, "must be finite and >= 0")?;
        check(
            "cell_weight",
            self.cell_weight,
            self.cell_weight.is_finite() && self.cell_weight > 0.0,
            "must be finite and > 0",
        )?;
        check(
            "data_weight",
            self.data_weight,
            self.data_weight.is_finite() && self.data_weight > 0.0,
            "must be finite and > 0",
        )?;
        check(
            "tangential_weight",
            self.tangential_weight,
            (0.0..=1.0).contains(&self.tangential_weight),
            "must be in [0, 1]",
        )?;
        check(
            "tangential_weight_p2m",
            self.tangential_weight_p2m,
            (0.0..=1.0).contains(&self.tangential_weight_p2m),
            "must be in [0, 1]",
        )?;
        check(
            "keypoint_weight",
            self.keypoint_weight,
            self.keypoint_weight.is_finite() && self.keypoint_weight >= 0.0 && self.keypoint_weight <= 1e6,
            "must be in [0, 1e6] (0 = measured joints are ignored)",
        )?;
        check(
            "keypoint_robust_m",
            self.keypoint_robust_m,
            self.keypoint_robust_m.is_finite() && self.keypoint_robust_m > 0.0,
            "must be finite and > 0 (metres)",
        )
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn schedule_serialises_as_its_string_and_reads_both_forms() {
        let s = Schedule::parse("m2p:10, P2M:5").unwrap();
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(json, "\"m2p:10,p2m:5\"");
        assert_eq!(serde_json::from_str::<Schedule>(&json).unwrap(), s);
        // The old list form still reads.
        let old = r#"[{"kind":"m2p","iterations":10},{"kind":"p2m","iterations":5}]"#;
        assert_eq!(serde_json::from_str::<Schedule>(old).unwrap(), s);
        // Inside the parameters, and a full round trip of the defaults.
        let p: RegisterParams = serde_json::from_str(r#"{"schedule": "m2p:3,p2m:2"}"#).unwrap();
        assert_eq!(p.schedule.to_string(), "m2p:3,p2m:2");
        let d = RegisterParams::default();
        let text = serde_json::to_string(&d).unwrap();
        assert!(text.contains("\"schedule\":\"m2p:5,p2m:5,m2p:4,p2m:2\""), "{text}");
        assert_eq!(serde_json::from_str::<RegisterParams>(&text).unwrap(), d);
        // Bad strings and shapes are errors that say what was wrong.
        let e = serde_json::from_str::<Schedule>("\"m2p:x\"").unwrap_err().to_string();
        assert!(e.contains("m2p:x"), "{e}");
        assert!(serde_json::from_str::<Schedule>("3").is_err());
    }

    #[test]
    fn serde_form_is_flat_with_the_known_names() {
        let value = serde_json::to_value(RegisterParams::default()).unwrap();
        let keys: Vec<&str> = value.as_object().unwrap().keys().map(String::as_str).collect();
        let mut names = PARAMETER_NAMES.to_vec();
        let mut sorted = keys.clone();
        names.sort_unstable();
        sorted.sort_unstable();
        assert_eq!(sorted, names);
        // Flat keys reach their groups; integers read as floats; missing keys take defaults.
        let p: RegisterParams = serde_json::from_str(
            r#"{"alpha": 1000, "drop_extremities": false, "prealign": "per_axis", "threads": 2,
                "label_aware": false, "articulate_smooth_iterations": 3, "min_points": 7}"#,
        )
        .unwrap();
        assert_eq!(p.energy.alpha, 1000.0);
        assert!(!p.outliers.drop_extremities && !p.pruning.label_aware);
        assert_eq!(p.prealignment.prealign, PrealignMode::PerAxis);
        assert_eq!((p.threads, p.articulation.articulate_smooth_iterations, p.checks.min_points), (2, 3, 7));
        assert_eq!(p.energy.cell_weight, EnergyParams::default().cell_weight);
        assert_eq!(serde_json::from_str::<RegisterParams>("{}").unwrap(), RegisterParams::default());
    }

    #[test]
    fn unknown_keys_are_rejected_by_name() {
        for text in [r#"{"alpah": 1.0}"#, r#"{"alpha": 1.0, "energy": {"alpha": 2.0}}"#, r#"{"mode": "auto"}"#] {
            let e = serde_json::from_str::<RegisterParams>(text).unwrap_err().to_string();
            let key = text.split('"').nth(if text.contains("alpah") || text.contains("mode") { 1 } else { 5 }).unwrap();
            assert!(e.contains("unknown field") && e.contains(&format!("`{key}`")), "{text}: {e}");
            assert!(e.contains("`alpha`"), "{e}");
        }
        // A bad value of a known key still says which key.
        let e = serde_json::from_str::<RegisterParams>(r#"{"prealign": "sideways"}"#).unwrap_err().to_string();
        assert!(e.contains("sideways"), "{e}");
    }
}
