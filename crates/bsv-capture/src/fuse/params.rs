//! Parameters of cloud building ([`FuseParams`]) and their checks.

use super::{ColorMode, FuseError};
use bsv_core::{EXTREMITIES, SEGMENT_COUNT};
use serde::{Deserialize, Serialize};

/// Parameters of cloud building; JSON keys are the field names, every one optional.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FuseParams {
    /// Run statistical outlier removal on each camera's cloud.
    pub sor: bool,
    /// Neighbours of the outlier removal (the paper: 600).
    pub sor_k: usize,
    /// Standard-deviation ratio of the outlier removal (the paper: 0.05).
    pub sor_std_ratio: f64,
    /// Segment ids dropped after merging (default: head, hands, feet; empty = keep all).
    pub drop_labels: Vec<u8>,
    /// Depths below this (metres) are ignored.
    pub min_depth: f64,
    /// Depths above this (metres) are ignored (`None` = no limit).
    pub max_depth: Option<f64>,
    /// Estimate a normal per point from its pixel neighbours (oriented toward the camera).
    pub normals: bool,
    /// Largest depth step (metres) between neighbouring pixels used for a normal.
    pub normal_max_step: f64,
    /// Point colours.
    pub colors: ColorMode,
    /// Remove the person points on and below each camera's floor plane (the floor is fitted and
    /// checked either way; a camera that does not see a floor removes nothing).
    pub remove_floor: bool,
    /// Person points less than this (metres) above the fitted floor are floor (mask spill between
    /// and around the feet). Feet are dropped by label anyway.
    pub floor_margin_m: f64,
    /// A depth sample within this distance (metres) of a floor plane supports it.
    pub floor_inlier_m: f64,
    /// Largest angle (degrees) between a floor plane's normal and world up (+Y) that is searched.
    pub floor_max_tilt_deg: f64,
    /// Fewest floor pixels outside the person mask for a camera's floor to count as seen.
    pub floor_min_pixels: usize,
    /// Warn when a camera's floor tilts from world up, or two cameras' floors from each other, by
    /// more than this (degrees): a rotation error of the calibration.
    pub floor_warn_tilt_deg: f64,
    /// Warn when a camera's floor lies more than this (mm) above or below y = 0 at the subject: a
    /// height error of the calibration (or the marker height).
    pub floor_warn_height_mm: f64,
    /// Warn when two cameras' floors differ in height at the subject by more than this (mm): the
    /// calibrations do not agree.
    pub floor_warn_between_mm: f64,
    /// Refuse a view that cannot be a standing person seen from its own side: no depth relief (a flat
    /// wall) or left and right limbs on the wrong sides (swapped calibration or camera folders); see
    /// [`crate::fuse::plausible`].
    pub check_plausible: bool,
    /// Keep only the person: drop mask pixels on depth edges, far behind the person and in 3-D parts
    /// separate from the person (fails when two comparable parts are found).
    pub isolate_person: bool,
    /// A mask pixel with a neighbour nearer by more than this (metres) is a depth-edge (mixed) pixel.
    pub edge_step_m: f64,
    /// Mask pixels deeper than the person's median depth by more than this (metres) are dropped (the wall).
    pub far_m: f64,
    /// Voxel side (metres) of the 3-D components: points closer than this are always joined.
    pub link_m: f64,
    /// A separate part with at least this fraction of the person's points makes the view ambiguous
    /// (an error), a smaller one is dropped.
    pub second_part_ratio: f64,
}

impl Default for FuseParams {
    /// The paper's pipeline: SOR (600, 0.05), head/hands/feet dropped, normals, palette colours,
    /// plus floor removal and person isolation.
    fn default() -> Self {
        FuseParams {
            sor: true,
            sor_k: 600,
            sor_std_ratio: 0.05,
            drop_labels: EXTREMITIES.iter().map(|s| s.id()).collect(),
            min_depth: 0.0,
            max_depth: None,
            normals: true,
            normal_max_step: 0.03,
            colors: ColorMode::Palette,
            remove_floor: true,
            floor_margin_m: 0.02,
            floor_inlier_m: 0.02,
            floor_max_tilt_deg: 10.0,
            floor_min_pixels: 5000,
            floor_warn_tilt_deg: 0.5,
            floor_warn_height_mm: 20.0,
            floor_warn_between_mm: 10.0,
            check_plausible: true,
            isolate_person: true,
            edge_step_m: 0.05,
            far_m: 0.6,
            link_m: 0.025,
            second_part_ratio: 0.25,
        }
    }
}

/// `BadParam` unless `ok`.
fn check(ok: bool, param: &'static str, value: f64, hint: &'static str) -> Result<(), FuseError> {
    if ok {
        Ok(())
    } else {
        Err(FuseError::BadParam { param, value, hint })
    }
}

fn positive(v: f64) -> bool {
    v.is_finite() && v > 0.0
}

impl FuseParams {
    /// Parses JSON parameters (missing keys take their defaults).
    pub fn from_json(text: &str) -> Result<Self, serde_json::Error> {
        if text.trim().is_empty() {
            return Ok(FuseParams::default());
        }
        serde_json::from_str(text)
    }

    /// Checks every parameter's range.
    pub fn validate(&self) -> Result<(), FuseError> {
        check(!(self.sor && self.sor_k == 0), "sor_k", 0.0, "use k >= 1 (the paper uses 600) or sor = false")?;
        let r = self.sor_std_ratio;
        check(r.is_finite(), "sor_std_ratio", r, "use a finite number (the paper uses 0.05)")?;
        let m = self.min_depth;
        check(m.is_finite() && m >= 0.0, "min_depth", m, "use a finite depth >= 0 in metres")?;
        if let Some(m) = self.max_depth {
            check(
                m.is_finite() && m > self.min_depth,
                "max_depth",
                m,
                "use a finite depth in metres above min_depth, or null",
            )?;
        }
        let s = self.normal_max_step;
        check(positive(s), "normal_max_step", s, "use a positive length in metres (e.g. 0.03)")?;
        if let Some(&l) = self.drop_labels.iter().find(|&&l| usize::from(l) >= SEGMENT_COUNT) {
            return Err(FuseError::BadParam {
                param: "drop_labels",
                value: f64::from(l),
                hint: "use segment ids 0..=14",
            });
        }
        self.validate_floor()?;
        self.validate_isolation()
    }

    fn validate_floor(&self) -> Result<(), FuseError> {
        let v = self.floor_margin_m;
        check(v.is_finite() && v >= 0.0, "floor_margin_m", v, "use a length >= 0 in metres (default 0.02)")?;
        let v = self.floor_inlier_m;
        check(positive(v), "floor_inlier_m", v, "use a positive length in metres (default 0.02)")?;
        let v = self.floor_max_tilt_deg;
        check(
            v.is_finite() && v > 0.0 && v < 60.0,
            "floor_max_tilt_deg",
            v,
            "use an angle in (0, 60) degrees (default 10)",
        )?;
        let v = self.floor_min_pixels;
        check(v > 0, "floor_min_pixels", v as f64, "use a pixel count >= 1 (default 5000)")?;
        let v = self.floor_warn_tilt_deg;
        check(positive(v), "floor_warn_tilt_deg", v, "use a positive angle in degrees (default 0.5)")?;
        let v = self.floor_warn_height_mm;
        check(positive(v), "floor_warn_height_mm", v, "use a positive height in mm (default 20)")?;
        let v = self.floor_warn_between_mm;
        check(positive(v), "floor_warn_between_mm", v, "use a positive height in mm (default 10)")
    }

    fn validate_isolation(&self) -> Result<(), FuseError> {
        let v = self.edge_step_m;
        check(positive(v), "edge_step_m", v, "use a positive depth step in metres (default 0.05)")?;
        let v = self.far_m;
        check(positive(v), "far_m", v, "use a positive depth in metres (default 0.6)")?;
        let v = self.link_m;
        check(
            v.is_finite() && v >= 0.002,
            "link_m",
            v,
            "use a voxel side of at least 0.002 m, a few times the point spacing (default 0.025)",
        )?;
        let v = self.second_part_ratio;
        check(v.is_finite() && v > 0.0 && v <= 1.0, "second_part_ratio", v, "use a fraction in (0, 1] (default 0.25)")
    }
}
