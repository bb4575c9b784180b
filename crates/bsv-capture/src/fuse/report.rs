//! What cloud building did, per camera and in total (serialised as the "cloud" report of
//! `volumes.json` and shown in the HTML report): points kept and removed at each step, the floor
//! found by each camera as a check of the calibration, and warnings for the operator.

use super::floor::FloorFit;
use super::FuseParams;
use serde::Serialize;
use std::collections::BTreeMap;

/// Whether a camera saw a floor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FloorStatus {
    /// A floor plane was found (the figures of [`FloorReport`] are set).
    Seen,
    /// No floor in view (e.g. an empty virtual background): nothing was removed as floor.
    NotSeen,
}

/// The floor one camera saw, in the world frame of its calibration; the figures are `None` when
/// the floor was not seen. A perfect calibration gives tilt 0 and height 0 (floor at y = 0, +Y up).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FloorReport {
    /// Seen or not seen.
    pub status: FloorStatus,
    /// Unit normal of the fitted plane (world frame, pointing up).
    pub normal: Option<[f64; 3]>,
    /// Angle between the normal and world up, degrees.
    pub tilt_deg: Option<f64>,
    /// Lean of the normal toward +Z (the front), a rotation about world X, degrees.
    pub pitch_deg: Option<f64>,
    /// Lean of the normal toward +X (the subject's left), a rotation about world Z, degrees.
    pub roll_deg: Option<f64>,
    /// Height of the plane at the subject (world y at `subject_xz`), mm.
    pub height_mm: Option<f64>,
    /// Root-mean-square distance of the supporting samples to the plane, mm.
    pub rms_mm: Option<f64>,
    /// Depth samples on the plane (every 4th pixel in both directions), person mask included.
    pub inliers: usize,
    /// Where the subject stands (median world x and z of the person's points), metres.
    pub subject_xz: [f64; 2],
}

impl FloorReport {
    /// The report of a floor fit (or of no floor) at the subject's position.
    pub fn new(fit: Option<&FloorFit>, subject_xz: [f64; 2]) -> Self {
        let p = fit.map(|f| f.plane);
        FloorReport {
            status: if fit.is_some() { FloorStatus::Seen } else { FloorStatus::NotSeen },
            normal: p.map(|p| p.normal),
            tilt_deg: p.map(|p| p.tilt_deg()),
            pitch_deg: p.map(|p| p.pitch_deg()),
            roll_deg: p.map(|p| p.roll_deg()),
            height_mm: p.map(|p| 1000.0 * p.height_at(subject_xz[0], subject_xz[1])),
            rms_mm: fit.map(|f| 1000.0 * f.rms_m),
            inliers: fit.map_or(0, |f| f.inliers),
            subject_xz,
        }
    }

    /// Warnings about this camera's calibration (tilt and height against the thresholds).
    pub fn warnings(&self, camera: &str, params: &FuseParams) -> Vec<String> {
        let mut out = Vec::new();
        if let (Some(t), Some(p), Some(r)) = (self.tilt_deg, self.pitch_deg, self.roll_deg) {
            if t > params.floor_warn_tilt_deg {
                out.push(format!(
                    "camera `{camera}`: its floor tilts {t:.2} deg from world up (pitch {p:+.2}, roll {r:+.2} deg; threshold floor_warn_tilt_deg = {}): the calibration's rotation is off, recalibrate this camera",
                    params.floor_warn_tilt_deg
                ));
            }
        }
        if let Some(h) = self.height_mm {
            if h.abs() > params.floor_warn_height_mm {
                out.push(format!(
                    "camera `{camera}`: its floor lies at y = {h:+.0} mm at the subject instead of 0 (threshold floor_warn_height_mm = {}): recalibrate this camera or check the marker's height above the floor",
                    params.floor_warn_height_mm
                ));
            }
        }
        out
    }
}

/// How two cameras' floors agree (both seen): a check of the calibrations against each other.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FloorAgreement {
    /// The two camera names.
    pub cameras: [String; 2],
    /// Angle between the two floor normals, degrees.
    pub tilt_deg: f64,
    /// Height of the second camera's floor minus the first's at the subject, mm.
    pub height_mm: f64,
}

impl FloorAgreement {
    /// The agreement of two cameras' floor reports; `None` unless both saw the floor.
    pub fn between(a: (&str, &FloorReport), b: (&str, &FloorReport)) -> Option<Self> {
        let (na, nb) = (a.1.normal?, b.1.normal?);
        let d = (na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2]).clamp(-1.0, 1.0);
        Some(FloorAgreement {
            cameras: [a.0.to_string(), b.0.to_string()],
            tilt_deg: d.acos().to_degrees(),
            height_mm: b.1.height_mm? - a.1.height_mm?,
        })
    }

    /// The warning when the two floors disagree beyond the thresholds.
    pub fn warning(&self, params: &FuseParams) -> Option<String> {
        let [a, b] = &self.cameras;
        (self.tilt_deg > params.floor_warn_tilt_deg || self.height_mm.abs() > params.floor_warn_between_mm).then(|| {
            format!(
                "cameras `{a}` and `{b}` disagree on the floor by {:.2} deg and {:+.0} mm at the subject (thresholds floor_warn_tilt_deg = {}, floor_warn_between_mm = {}): their calibrations do not agree, recalibrate both",
                self.tilt_deg, self.height_mm, params.floor_warn_tilt_deg, params.floor_warn_between_mm
            )
        })
    }
}

/// What the cleaning removed from one camera's person mask ("only the person"), in order.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct CleaningReport {
    /// Points on or below the floor plane (plus `floor_margin_m`).
    pub floor_removed: usize,
    /// Depth-edge (mixed) pixels: a neighbour nearer by more than `edge_step_m`.
    pub edge_removed: usize,
    /// Pixels deeper than the person's median depth by more than `far_m` (the wall).
    pub far_removed: usize,
    /// Points in 3-D parts separate from the person (clutter, a chair, flying pixels).
    pub separate_removed: usize,
    /// 3-D parts found (the person is the largest).
    pub parts: usize,
    /// Points of the person's part.
    pub person_points: usize,
    /// Points of the largest other part (0 when there is none).
    pub largest_other_points: usize,
    /// The person's median depth from this camera, metres (when isolation ran).
    pub median_depth_m: Option<f64>,
    /// Wall time of floor fitting and cleaning, seconds.
    pub seconds: f64,
}

impl CleaningReport {
    /// Every point removed by the cleaning.
    pub fn removed(&self) -> usize {
        self.floor_removed + self.edge_removed + self.far_removed + self.separate_removed
    }
}

/// What cloud building did with one camera.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViewReport {
    /// Camera name.
    pub name: String,
    /// Pixels with a segment label (the person mask).
    pub mask_pixels: usize,
    /// Mask pixels without a valid depth (0, non-finite, out of range).
    pub no_depth: usize,
    /// Points deprojected (mask pixels with a valid depth).
    pub deprojected: usize,
    /// The floor this camera saw (a check of its calibration).
    pub floor: FloorReport,
    /// Points removed as floor, edges, far and separate parts.
    pub cleaning: CleaningReport,
    /// Points removed by statistical outlier removal.
    pub sor_removed: usize,
    /// The outlier threshold on the mean neighbour distance (metres), when SOR ran.
    pub sor_threshold_m: Option<f64>,
    /// Points dropped per segment name.
    pub dropped: BTreeMap<String, usize>,
    /// Points of this camera in the final cloud.
    pub kept: usize,
    /// Warnings about this camera (calibration checked against the floor).
    pub warnings: Vec<String>,
    /// Wall time of deprojection (and normals), seconds.
    pub seconds_deproject: f64,
    /// Wall time of outlier removal, seconds.
    pub seconds_sor: f64,
}

/// What cloud building did, per camera and in total.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FuseReport {
    /// One report per view, in input order.
    pub views: Vec<ViewReport>,
    /// Floor agreement of every pair of cameras that both saw the floor.
    pub floor_agreement: Vec<FloorAgreement>,
    /// Every warning (the views' and the agreement's), for the operator.
    pub warnings: Vec<String>,
    /// Points in the final cloud.
    pub points: usize,
    /// Points in the final cloud per segment name.
    pub points_per_segment: BTreeMap<String, usize>,
    /// Points dropped per segment name (all cameras).
    pub dropped: BTreeMap<String, usize>,
    /// Total wall time, seconds.
    pub seconds: f64,
}

impl FuseReport {
    /// Pretty JSON text.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}
