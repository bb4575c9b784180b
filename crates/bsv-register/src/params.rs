//! Registration parameters (with documented defaults), the correspondence schedule and the
//! per-iteration log.
//!
//! # Units and weights
//! Geometry is in metres. The energy minimised is (see `local.rs` for the derivation)
//!
//! ```text
//! E = E_arap + E_reg + E_data
//! E_arap = sum_i w_c sum_{j in N(i)} w_ij |(p'_i - p'_j) - T_i (p_i - p_j)|^2     (m^2)
//! E_reg  = lambda sum_i |T_i - R_i|_F^2,   lambda = alpha * 1e-6 * w_c * A / N      (m^2)
//! E_data = sum_i d_i |p'_i - q_i|^2                                                (m^2)
//! ```
//! with `w_ij` the (dimensionless) cotangent weights, `w_c` = [`RegisterParams::cell_weight`],
//! `A` the TOTAL area of the pre-aligned template (m^2), `N` its vertex count, `q_i` the
//! correspondence target and `d_i` = [`RegisterParams::data_weight`] (0 without correspondence).
//!
//! How this relates to the paper (`lambda_paper = alpha * A`, `w_i = 1e-2`, `alpha = 1e6`): read
//! literally in any unit, the paper's ratio of regularization to ARAP stiffness per cell is
//! `alpha * N / w_c` (about 1e12 for a body template), i.e. T_i would be a rotation and no cell could
//! ever scale. We keep the paper's structure (one global weight proportional to the total area A,
//! so shrinking triangles cannot lower it) and its numbers, but make the weight dimensionless and
//! resolution-independent: `lambda = (alpha / 1e6) * w_c * A / N`, so at the default alpha = 1e6 the
//! penalty for leaving the nearest rotation equals the ARAP stiffness of an average cell
//! (`w_c * A / N`, about a quarter of `w_c * tr(P_i)` on a regular mesh). alpha = 1e8 is practically
//! classic ARAP (T_i = R_i); alpha = 0 lets every cell be any affine map.
//!
//! Measured effect of alpha on the gap case (tests/gaps.rs `alpha_sweep_on_the_gap_torso`:
//! 642-vertex ellipsoid template onto 84.5k samples of a 0.17 x 0.30 x 0.12 m ellipsoid without
//! its sides; RMS m2p / p2m in mm, max = largest vertex distance to the true surface):
//!
//! | data term                      | alpha | volume error | RMS m2p | RMS p2m | max     |
//! |--------------------------------|-------|--------------|---------|---------|---------|
//! | point-to-plane (default)       | 0     | -0.21 %      | 9.28    | 5.69    | 2.2 mm  |
//! | point-to-plane (default)       | 1e4   | -0.10 %      | 9.33    | 5.69    | 1.4 mm  |
//! | point-to-plane (default)       | 1e6   | -0.42 %      | 9.27    | 5.69    | 4.3 mm  |
//! | point-to-plane (default)       | 1e8   | -0.79 %      | 9.19    | 5.69    | 7.5 mm  |
//! | point-to-point (`tangential_weight` 1) | 0   | -0.94 %      | 8.01    | 5.70    | 7.2 mm  |
//! | point-to-point                 | 1e6   | -1.20 %      | 8.14    | 5.70    | 10.1 mm |
//! | point-to-point                 | 1e8   | -1.41 %      | 8.36    | 5.70    | 11.9 mm |
//!
//! So alpha = 0 does NOT degrade here, contrary to the paper's "collapses within 5 iterations":
//! with free affine cells the ARAP term is still an affine-invariant smoothness term, and m2p
//! gives every vertex a target, so nothing pulls the cells together. The same held with the p2m
//! Lloyd pull (`tangential_weight_p2m` 1), data weights 0.1 and 0.01, p2m-only schedules, 5k-point
//! clouds and 50 % side limits (alpha 0 was 0.3 to 7 points less biased than 1e6 in each). The
//! regularization's role in this engine is stiffness: larger alpha keeps cells closer to rotations
//! and shrinks the unseen sides more. The default 1e6 is kept as the paper's value; the body
//! cohort was tuned with it.
//! The data weight `d` is dimensionless in the same sense as `w_c`: the diagonal of the ARAP system
//! is `2 w_c sum_j w_ij ~ 7 w_c` on a regular mesh, so the default `d = 1`, `w_c = 1e-2` makes a
//! vertex follow its target ~14 times more than its neighbours, while the Laplacian still averages
//! sampling noise over a few rings.

use crate::error::RegisterError;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Which way nearest neighbours are taken in an iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CorrespondenceKind {
    /// Mesh-to-point: each vertex to its nearest cloud point.
    M2p,
    /// Point-to-mesh: each cloud point to its nearest vertex; a vertex's target is the mean.
    P2m,
}

impl fmt::Display for CorrespondenceKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CorrespondenceKind::M2p => "m2p",
            CorrespondenceKind::P2m => "p2m",
        })
    }
}

/// One stage of the schedule: `iterations` iterations with correspondences of `kind`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Stage {
    /// Correspondence direction.
    pub kind: CorrespondenceKind,
    /// Number of iterations (correspondences + local + global step each).
    pub iterations: usize,
}

/// The correspondence schedule, e.g. `m2p:5,p2m:5,m2p:10` (the paper's).
///
/// Serialises as that string (so JSON/Python users write `"schedule": "m2p:10,p2m:5"`);
/// deserialises from the string or from the older list form
/// `[{"kind": "m2p", "iterations": 5}, ...]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Schedule(pub Vec<Stage>);

impl Serialize for Schedule {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(self)
    }
}

/// The accepted serialised forms of a [`Schedule`].
#[derive(Deserialize)]
#[serde(untagged)]
enum ScheduleRepr {
    /// `"m2p:5,p2m:5,m2p:10"`.
    Text(String),
    /// `[{"kind": "m2p", "iterations": 5}, ...]`.
    Stages(Vec<Stage>),
}

impl<'de> Deserialize<'de> for Schedule {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        match ScheduleRepr::deserialize(deserializer).map_err(|_| {
            serde::de::Error::custom(
                "schedule must be a string like \"m2p:5,p2m:5,m2p:10\" (or a list of {kind, iterations})",
            )
        })? {
            ScheduleRepr::Text(text) => Schedule::parse(&text).map_err(serde::de::Error::custom),
            ScheduleRepr::Stages(stages) => Ok(Schedule(stages)),
        }
    }
}

/// The paper's schedule: 5 m2p, 5 p2m, 10 m2p.
pub const DEFAULT_SCHEDULE: &str = "m2p:5,p2m:5,m2p:10";

impl Schedule {
    /// Parses `KIND:COUNT[,KIND:COUNT...]` (KIND `m2p` or `p2m`, case-insensitive, spaces allowed).
    pub fn parse(text: &str) -> Result<Schedule, RegisterError> {
        let bad = |reason: String| RegisterError::BadSchedule { text: text.to_string(), reason };
        let mut stages = Vec::new();
        for (k, part) in text.split(',').enumerate() {
            let part = part.trim();
            if part.is_empty() {
                return Err(bad(format!("stage {} is empty", k + 1)));
            }
            let (kind, count) =
                part.split_once(':').ok_or_else(|| bad(format!("stage {:?} has no ':'", part)))?;
            let kind = match kind.trim().to_ascii_lowercase().as_str() {
                "m2p" => CorrespondenceKind::M2p,
                "p2m" => CorrespondenceKind::P2m,
                other => return Err(bad(format!("unknown kind {:?}", other))),
            };
            let iterations: usize = count
                .trim()
                .parse()
                .map_err(|_| bad(format!("count {:?} is not a non-negative integer", count.trim())))?;
            stages.push(Stage { kind, iterations });
        }
        if stages.iter().all(|s| s.iterations == 0) {
            return Err(bad("the schedule has no iteration".to_string()));
        }
        Ok(Schedule(stages))
    }

    /// Total number of iterations.
    pub fn total_iterations(&self) -> usize {
        self.0.iter().map(|s| s.iterations).sum()
    }
}

impl Default for Schedule {
    fn default() -> Self {
        Schedule(vec![
            Stage { kind: CorrespondenceKind::M2p, iterations: 5 },
            Stage { kind: CorrespondenceKind::P2m, iterations: 5 },
            Stage { kind: CorrespondenceKind::M2p, iterations: 10 },
        ])
    }
}

impl fmt::Display for Schedule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts: Vec<String> = self.0.iter().map(|s| format!("{}:{}", s.kind, s.iterations)).collect();
        f.write_str(&parts.join(","))
    }
}

impl std::str::FromStr for Schedule {
    type Err = RegisterError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Schedule::parse(s)
    }
}

/// How the template is scaled onto the cloud before the non-rigid fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PrealignMode {
    /// The paper: one scale, the ratio of the bounding-box diagonals.
    Isotropic,
    /// One scale per axis, the ratio of the bounding-box sides.
    PerAxis,
    /// Per-axis when the box proportions differ by more than [`RegisterParams::auto_aspect_threshold`],
    /// isotropic otherwise.
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

/// Every knob of a registration, with the defaults documented on each field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RegisterParams {
    /// Regularization strength (dimensionless, see the module docs). Default 1e6 (the paper's number):
    /// leaving the nearest rotation costs as much as the ARAP stiffness of an average cell.
    /// 0 = free affine cells (degrades on gaps).
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
    /// Correspondence schedule. Default `m2p:5,p2m:5,m2p:10`.
    pub schedule: Schedule,
    /// Drop correspondences longer than `prune_distance_factor` x the median correspondence length
    /// of the iteration (0 or inf = off). Default 3.
    pub prune_distance_factor: f64,
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
    pub bbox_quantile: f64,
    /// Minimum number of cloud points. Default 100.
    pub min_points: usize,
    /// Largest plausible cloud extent (metres): larger clouds are taken as millimetres. Default 5.
    pub max_extent_m: f64,
    /// Smallest plausible cloud extent (metres). Default 0.05.
    pub min_extent_m: f64,
    /// Worker threads (a rayon pool of this size; 0 = all cores). Default 0.
    pub threads: usize,
    /// Label source of the fitted mesh. Default [`LabelSource::Cloud`]. With `Cloud` and an
    /// unlabelled cloud the fit does not fail: the mesh falls back to the template's vertex labels
    /// (no labels when the template has none either) and `Registration::labels_from` says
    /// `Template` (or `None`).
    pub labels: LabelSource,
    /// Label-aware correspondences when the cloud and the template are both labelled: a template
    /// vertex of segment L is matched only to cloud points of segment L and vice versa (see
    /// `correspond.rs`). Default true.
    pub label_aware: bool,
    /// Sparse-point (flying pixel) removal before the fit: voxel side in metres (0 = off). A point
    /// is dropped when the 27 voxels around it hold fewer than
    /// [`Self::outlier_min_fraction`] x the median such count (see `outliers.rs`). Default 0.008.
    pub outlier_voxel_m: f64,
    /// See [`Self::outlier_voxel_m`]. Default 0.1.
    pub outlier_min_fraction: f64,
    /// Move the fitted vertices out by the inscribed-mesh gap `h^2 H / 8` (see
    /// [`crate::surface_correction`]) so that the fitted faces, not only the vertices, lie on the
    /// surface on average: removes the volume bias of a coarse template. Default true.
    pub surface_correction: bool,
    /// Drop the cloud's head, hand and foot points (labels in `bsv_core::EXTREMITIES`: 1, 7, 8, 13,
    /// 14) before the fit, as in the paper: those segments are poorly captured and not measured.
    /// No effect on an unlabelled cloud. Default true.
    pub drop_extremities: bool,
    /// Articulated initialisation when the cloud and the template are both labelled: every limb is
    /// turned (and moved) onto the cloud's limb before the fit (see `articulate.rs`). Default true.
    pub articulate: bool,
    /// Scale each limb along its axis by the ratio of the segment lengths in the articulated
    /// initialisation (ends aligned). Default true.
    pub articulate_axial_scale: bool,
    /// Jacobi smoothing steps of the articulation's displacement field (blends the joints).
    /// Default 10.
    pub articulate_smooth_iterations: usize,
}

impl Default for RegisterParams {
    fn default() -> Self {
        RegisterParams {
            alpha: 1e6,
            cell_weight: 1e-2,
            data_weight: 1.0,
            tangential_weight: 0.0,
            tangential_weight_p2m: 0.0,
            schedule: Schedule::default(),
            prune_distance_factor: 3.0,
            prune_distance_floor_m: 0.005,
            prune_normal_angle_deg: 60.0,
            estimate_normals_k: 12,
            prealign: PrealignMode::Auto,
            prealign_yaw: YawMode::Auto,
            auto_aspect_threshold: 0.5,
            bbox_quantile: 0.001,
            min_points: 100,
            max_extent_m: 5.0,
            min_extent_m: 0.05,
            threads: 0,
            labels: LabelSource::Cloud,
            label_aware: true,
            outlier_voxel_m: 0.008,
            outlier_min_fraction: 0.1,
            surface_correction: true,
            drop_extremities: true,
            articulate: true,
            articulate_axial_scale: true,
            articulate_smooth_iterations: 10,
        }
    }
}

impl RegisterParams {
    /// Checks every numeric parameter's range.
    pub fn validate(&self) -> Result<(), RegisterError> {
        let check = |name: &'static str, value: f64, ok: bool, hint: &'static str| {
            if ok {
                Ok(())
            } else {
                Err(RegisterError::BadParameter { name, value, hint })
            }
        };
        check("alpha", self.alpha, self.alpha.is_finite() && self.alpha >= 0.0, "must be finite and >= 0")?;
        check("cell_weight", self.cell_weight, self.cell_weight.is_finite() && self.cell_weight > 0.0, "must be finite and > 0")?;
        check("data_weight", self.data_weight, self.data_weight.is_finite() && self.data_weight > 0.0, "must be finite and > 0")?;
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
            "prune_distance_factor",
            self.prune_distance_factor,
            self.prune_distance_factor >= 0.0,
            "must be >= 0 (0 or inf = no distance pruning)",
        )?;
        check(
            "prune_distance_floor_m",
            self.prune_distance_floor_m,
            self.prune_distance_floor_m.is_finite() && self.prune_distance_floor_m >= 0.0,
            "must be finite and >= 0",
        )?;
        check(
            "prune_normal_angle_deg",
            self.prune_normal_angle_deg,
            self.prune_normal_angle_deg > 0.0,
            "must be > 0 degrees (>= 180 = off)",
        )?;
        check(
            "auto_aspect_threshold",
            self.auto_aspect_threshold,
            self.auto_aspect_threshold.is_finite() && self.auto_aspect_threshold >= 0.0,
            "must be finite and >= 0",
        )?;
        check(
            "outlier_voxel_m",
            self.outlier_voxel_m,
            self.outlier_voxel_m.is_finite() && self.outlier_voxel_m >= 0.0,
            "must be finite and >= 0 metres (0 = no outlier removal)",
        )?;
        check(
            "outlier_min_fraction",
            self.outlier_min_fraction,
            (0.0..=1.0).contains(&self.outlier_min_fraction),
            "must be in [0, 1]",
        )?;
        check("bbox_quantile", self.bbox_quantile, (0.0..0.25).contains(&self.bbox_quantile), "must be in [0, 0.25)")?;
        check(
            "max_extent_m",
            self.max_extent_m,
            self.max_extent_m > self.min_extent_m && self.min_extent_m >= 0.0,
            "need 0 <= min_extent_m < max_extent_m",
        )?;
        if self.schedule.total_iterations() == 0 {
            return Err(RegisterError::BadSchedule {
                text: self.schedule.to_string(),
                reason: "the schedule has no iteration".to_string(),
            });
        }
        Ok(())
    }
}

/// Energy terms (m^2, see the module docs) at one point of an iteration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Energy {
    /// ARAP/affine term.
    pub arap: f64,
    /// Regularization term.
    pub reg: f64,
    /// Data term.
    pub data: f64,
    /// Sum of the three.
    pub total: f64,
}

/// Wall time of the parts of one iteration, seconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Timings {
    /// Correspondences (k-d tree queries, pruning, normals).
    pub correspond: f64,
    /// Local step (per-cell maps).
    pub local: f64,
    /// Global step (numeric refactorization when needed, right-hand side, solve).
    pub solve: f64,
}

/// What happened in one iteration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IterationLog {
    /// Index of the schedule stage (0-based).
    pub stage: usize,
    /// Global iteration index (0-based).
    pub iteration: usize,
    /// Correspondence kind of the stage.
    pub kind: CorrespondenceKind,
    /// Total energy with this iteration's correspondences and the previous maps (start of iteration).
    pub energy_start: f64,
    /// Total energy after the local step.
    pub energy_after_local: f64,
    /// Energy terms after the global step (end of iteration).
    pub energy: Energy,
    /// RMS distance from the vertices entering this iteration to their nearest cloud point, mm
    /// (before pruning).
    pub rms_mesh_to_points_mm: f64,
    /// RMS distance from the cloud points to their nearest vertex entering this iteration, mm
    /// (p2m iterations only: the query costs as much as the rest of an iteration).
    pub rms_points_to_mesh_mm: Option<f64>,
    /// Correspondences kept after pruning (vertices with a data term).
    pub n_correspondences: usize,
    /// Whether the system was refactorized (the data weights changed).
    pub refactorized: bool,
    /// Time split.
    pub timings: Timings,
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
        assert!(text.contains("\"schedule\":\"m2p:5,p2m:5,m2p:10\""), "{text}");
        assert_eq!(serde_json::from_str::<RegisterParams>(&text).unwrap(), d);
        // Bad strings and shapes are errors that say what was wrong.
        let e = serde_json::from_str::<Schedule>("\"m2p:x\"").unwrap_err().to_string();
        assert!(e.contains("m2p:x"), "{e}");
        assert!(serde_json::from_str::<Schedule>("3").is_err());
    }
}
