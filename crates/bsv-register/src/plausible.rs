//! Is the cloud a standing person in the world frame? Checked before the fit, on the cleaned cloud
//! (extremities, sparse points and detached pieces dropped), only when the template is a labelled
//! human template (vertex labels with the torso, an upper arm and a thigh: the embedded templates);
//! other templates (the boxes' cube, analytic shapes) are not checked. Parameter `check_plausible`
//! (default true) turns the checks off.
//!
//! The world frame (DESIGN.md "Conventions"): Y up, floor near y = 0, the subject faces +Z, +X is the
//! subject's left. Figures come from the robust box of the cloud (the 1 % and 99 % quantiles of each
//! axis: `ex`, `ey`, `ez`), in this order, the first failing check is the error:
//!
//! 1. flat: the smallest side below [`FLAT_RATIO`] x the largest -> a plane (a wall, a floor, a
//!    single depth image with no relief), [`ImplausibleError::Flat`];
//! 2. up axis: with labels, the body axis (torso centroid minus the mean of the thigh and shin
//!    centroids) must be within [`MAX_TILT_DEG`] of +Y; without labels `ey` must be at least
//!    [`MIN_UP_RATIO`] x the larger horizontal side. Otherwise [`ImplausibleError::WrongUp`] names the
//!    axis that looks up (the remedy: rotate the cloud, `bsv-cli register --up`);
//! 3. compact: the smallest side above [`MAX_COMPACT_RATIO`] x the largest -> a sphere or a block,
//!    not a standing person (a person is 4-6 times taller than deep), [`ImplausibleError::Compact`];
//! 4. upright without labels: the fraction of points above mid-height below [`MIN_TOP_FRACTION_HEADLESS`]
//!    (a standing person carries its torso and arms in the upper half: 0.62-0.69 on the cohort, 0.5
//!    for a body lying sideways, ~0.35 upside down; ~0.46 for a cloud without head, hands and feet,
//!    so the check also needs the upper half narrower along x than [`MAX_WIDTH_RATIO_UPSIDE_DOWN`] x
//!    the lower half: torso and arms are wider than the legs) -> [`ImplausibleError::WrongUp`];
//! 5. facing: with labels, the left limbs' centroid minus the right limbs' must point to +X (and
//!    more along x than along z); without labels the body must be wider (x) than deep (z) when the
//!    template is. Otherwise [`ImplausibleError::Facing`];
//! 6. size: `ey` in [[`MIN_HEIGHT_M`], [`MAX_HEIGHT_M`]] metres (the body without head and feet:
//!    0.7-1.8 m for 1.0-2.3 m tall people) -> [`ImplausibleError::Size`] (units or scale).
//!
//! Measured on the synthetic cohort's scans (subjects 0-2 of seed 0, all four conditions, with and
//! without a room; `0.1 %` box quantile, before cleaning): `ey / max(ex, ez)` 1.22-1.46, smallest /
//! largest side 0.19-0.37, top fraction 0.62-0.69, left-right offset +0.31 to +0.40 m along x and
//! under 3 mm along z; the labelled body axis is vertical. The default template: 1.24, 0.18, 0.75.
//! `tests/python/test_plausible.py` runs the cohort through the checks in every condition.

use crate::prealign::robust_aabb;
use bsv_core::{PointCloud, Segment, TriMesh};

/// Quantile of the robust box of the checks (1 % / 99 % on each axis).
pub const BOX_QUANTILE: f64 = 0.01;
/// Smallest side / largest side below which the cloud is a plane.
pub const FLAT_RATIO: f64 = 0.04;
/// Largest angle between the labelled body axis and +Y, degrees.
pub const MAX_TILT_DEG: f64 = 45.0;
/// Smallest `ey / max(ex, ez)` of an unlabelled cloud.
pub const MIN_UP_RATIO: f64 = 0.8;
/// Smallest side / largest side above which the cloud is a compact blob (sphere, block).
pub const MAX_COMPACT_RATIO: f64 = 0.6;
/// With the width cue: a cloud with its upper half narrower than this times its lower half and less
/// than [`MIN_TOP_FRACTION_HEADLESS`] of its points in the upper half is upside down (a headless
/// upright cloud: ~0.46 of its points above mid-height, its upper half 2-2.6 times wider).
pub const MAX_WIDTH_RATIO_UPSIDE_DOWN: f64 = 0.8;
/// See [`MAX_WIDTH_RATIO_UPSIDE_DOWN`] (an upside-down headless cloud: ~0.54).
pub const MIN_TOP_FRACTION_HEADLESS: f64 = 0.6;
/// Smallest height (y side of the robust box) of a person without head and feet, metres.
pub const MIN_HEIGHT_M: f64 = 0.4;
/// Largest such height, metres.
pub const MAX_HEIGHT_M: f64 = 2.6;

/// The segments whose labels make a template a human one.
const HUMAN: [Segment; 3] = [Segment::Torso, Segment::UpperArmL, Segment::ThighL];
/// Left and right limb segments (the subject's own left: +X).
const LEFT: [Segment; 4] = [Segment::UpperArmL, Segment::ForearmL, Segment::ThighL, Segment::ShinL];
const RIGHT: [Segment; 4] = [Segment::UpperArmR, Segment::ForearmR, Segment::ThighR, Segment::ShinR];
const LEGS: [Segment; 4] = [Segment::ThighL, Segment::ThighR, Segment::ShinL, Segment::ShinR];

/// True when `template` is a labelled human template (the checks apply).
pub fn is_human_template(template: &TriMesh) -> bool {
    let Some(labels) = &template.vertex_labels else { return false };
    let mut seen = [false; 256];
    labels.iter().for_each(|&l| seen[l as usize] = true);
    HUMAN.iter().all(|s| seen[s.id() as usize] || seen[mirror(*s).id() as usize])
}

/// The right-side twin of a left segment (itself otherwise).
fn mirror(s: Segment) -> Segment {
    match s {
        Segment::UpperArmL => Segment::UpperArmR,
        Segment::ThighL => Segment::ThighR,
        other => other,
    }
}

/// Checks that `cloud` can be a standing person in the world frame for a fit with `template`
/// (see the module). Does nothing for a template that is not a labelled human template.
pub fn check_person(cloud: &PointCloud, template: &TriMesh) -> Result<(), ImplausibleError> {
    if !is_human_template(template) {
        return Ok(());
    }
    let Some(bbox) = robust_aabb(&cloud.points, BOX_QUANTILE) else { return Ok(()) };
    let e = bbox.extent();
    let largest = e[0].max(e[1]).max(e[2]);
    let smallest = e[0].min(e[1]).min(e[2]);
    if largest <= 0.0 {
        return Ok(());
    }
    if smallest < FLAT_RATIO * largest {
        return Err(ImplausibleError::Flat { extent_m: e });
    }
    let labelled = cloud.labels.as_ref().filter(|l| l.len() == cloud.points.len());
    let parts = labelled.map(|l| Centroids::of(&cloud.points, l));
    // 2. The up axis.
    match parts.as_ref().and_then(Centroids::body_axis) {
        Some(axis) => {
            let tilt = axis[1].clamp(-1.0, 1.0).acos().to_degrees();
            if tilt > MAX_TILT_DEG {
                return Err(ImplausibleError::WrongUp {
                    up: axis_name(axis),
                    reason: format!("the body axis (legs to torso, from the labels) is {tilt:.0} degrees from +y"),
                });
            }
        }
        None => {
            if e[1] < MIN_UP_RATIO * e[0].max(e[2]) {
                let k = if e[0] >= e[2] { 0 } else { 2 };
                return Err(ImplausibleError::WrongUp {
                    up: ["x", "y", "z"][k],
                    reason: format!(
                        "its height along y ({:.2}) is smaller than its extent along {} ({:.2})",
                        e[1],
                        ["x", "y", "z"][k],
                        e[k]
                    ),
                });
            }
        }
    }
    // 3. Compact.
    if smallest > MAX_COMPACT_RATIO * largest {
        return Err(ImplausibleError::Compact { extent_m: e });
    }
    // 4. Upright (unlabelled): the upper half holds most points.
    if parts.as_ref().and_then(Centroids::body_axis).is_none() {
        let top = top_fraction(&cloud.points, &bbox, 1, 1.0);
        // A cloud without its head, hands and feet (what a lab registers) carries only about half of
        // its points in the upper half, but its upper half (torso and arms) is still wider than its
        // lower half (the legs); upside down both cues turn. Refuse only when both do.
        let (upper, lower) = (half_width(&cloud.points, &bbox, true), half_width(&cloud.points, &bbox, false));
        if top < MIN_TOP_FRACTION_HEADLESS && upper < MAX_WIDTH_RATIO_UPSIDE_DOWN * lower {
            // The signed axis (of those nearly as long as the longest) whose "upper half" is heaviest.
            let up = (0..6)
                .filter(|&a| e[a / 2] >= MIN_UP_RATIO * largest)
                .map(|a| (a, top_fraction(&cloud.points, &bbox, a / 2, if a % 2 == 0 { 1.0 } else { -1.0 })))
                .max_by(|x, y| x.1.total_cmp(&y.1))
                .map_or(3, |(a, _)| a);
            return Err(ImplausibleError::WrongUp {
                up: ["+x", "-x", "+y", "-y", "+z", "-z"][if up == 2 { 3 } else { up }],
                reason: format!(
                    "only {:.0} % of its points lie in its upper half along y (a standing person: about 65 %)",
                    top * 100.0
                ),
            });
        }
    }
    // 5. Facing.
    match parts.as_ref().and_then(Centroids::left_to_right) {
        Some(d) if d[0] <= 0.0 || d[0].abs() < d[2].abs() => {
            return Err(ImplausibleError::Facing { left_minus_right_m: d });
        }
        Some(_) => {}
        None => {
            let t = bsv_core::geometry::Aabb::of_points(&template.vertices).map_or([0.0; 3], |b| b.extent());
            if t[0] > 1.5 * t[2] && e[0] < e[2] {
                return Err(ImplausibleError::Facing { left_minus_right_m: [0.0; 3] });
            }
        }
    }
    // 6. Size.
    if !(MIN_HEIGHT_M..=MAX_HEIGHT_M).contains(&e[1]) {
        return Err(ImplausibleError::Size { height_m: e[1], min_m: MIN_HEIGHT_M, max_m: MAX_HEIGHT_M });
    }
    Ok(())
}

/// The fraction of `points` beyond the middle of `bbox` along axis `k`, on the side of `sign`.
fn top_fraction(points: &[[f64; 3]], bbox: &bsv_core::geometry::Aabb, k: usize, sign: f64) -> f64 {
    let mid = 0.5 * (bbox.min[k] + bbox.max[k]);
    points.iter().filter(|p| sign * (p[k] - mid) > 0.0).count() as f64 / points.len().max(1) as f64
}

/// The 1 % - 99 % extent along x of the points in the upper (or lower) half along y.
fn half_width(points: &[[f64; 3]], bbox: &bsv_core::geometry::Aabb, upper: bool) -> f64 {
    let mid = 0.5 * (bbox.min[1] + bbox.max[1]);
    let mut x: Vec<f64> = points.iter().filter(|p| (p[1] > mid) == upper).map(|p| p[0]).collect();
    if x.len() < 2 {
        return 0.0;
    }
    x.sort_by(f64::total_cmp);
    let at = |q: f64| x[((q * (x.len() - 1) as f64) as usize).min(x.len() - 1)];
    at(0.99) - at(0.01)
}

/// The axis name (`+x`, `-x`, `+y`, ...) closest to the unit vector `a`.
fn axis_name(a: [f64; 3]) -> &'static str {
    let k = (0..3).max_by(|&i, &j| a[i].abs().total_cmp(&a[j].abs())).unwrap_or(1);
    match (k, a[k] >= 0.0) {
        (0, true) => "+x",
        (0, false) => "-x",
        (1, true) => "+y",
        (1, false) => "-y",
        (2, true) => "+z",
        _ => "-z",
    }
}

/// Per-segment point sums and counts of a labelled cloud.
struct Centroids {
    sum: [[f64; 3]; 256],
    count: [usize; 256],
}

impl Centroids {
    fn of(points: &[[f64; 3]], labels: &[u8]) -> Centroids {
        let mut c = Centroids { sum: [[0.0; 3]; 256], count: [0; 256] };
        for (p, &l) in points.iter().zip(labels) {
            let s = &mut c.sum[l as usize];
            (0..3).for_each(|k| s[k] += p[k]);
            c.count[l as usize] += 1;
        }
        c
    }

    /// The centroid of the points of `segments` (None when fewer than 20 points).
    fn centroid(&self, segments: &[Segment]) -> Option<[f64; 3]> {
        let n: usize = segments.iter().map(|s| self.count[s.id() as usize]).sum();
        if n < 20 {
            return None;
        }
        let s = segments.iter().fold([0.0; 3], |a, s| {
            let v = self.sum[s.id() as usize];
            [a[0] + v[0], a[1] + v[1], a[2] + v[2]]
        });
        Some(s.map(|v| v / n as f64))
    }

    /// The unit vector from the legs' centroid to the torso's.
    fn body_axis(&self) -> Option<[f64; 3]> {
        let (torso, legs) = (self.centroid(&[Segment::Torso])?, self.centroid(&LEGS)?);
        let d = bsv_core::geometry::sub(torso, legs);
        let n = bsv_core::geometry::norm(d);
        (n > 0.0).then(|| d.map(|v| v / n))
    }

    /// The left limbs' centroid minus the right limbs', metres.
    fn left_to_right(&self) -> Option<[f64; 3]> {
        Some(bsv_core::geometry::sub(self.centroid(&LEFT)?, self.centroid(&RIGHT)?))
    }
}

/// Why a cloud cannot be a standing person in the world frame (see the module). Every message
/// says what is wrong and how to fix it; `check_plausible = false` skips the checks.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum ImplausibleError {
    /// The cloud is (nearly) a plane.
    #[error("the cloud is flat (robust extent x {:.3}, y {:.3}, z {:.3}): a plane (a wall, a floor, a depth image without relief), not a standing person; check the capture and its person mask (registration parameter check_plausible = false skips this check)", extent_m[0], extent_m[1], extent_m[2])]
    Flat {
        /// Robust extent per axis (cloud units).
        extent_m: [f64; 3],
    },
    /// The person does not stand along +Y.
    #[error("the cloud is not a person standing along +y (world frame: Y up, floor at y = 0, facing +z): {reason}; its up axis looks like {up}: rotate the cloud so that this axis becomes +y (a transform of the coordinates), or check its labels (registration parameter check_plausible = false skips this check)")]
    WrongUp {
        /// The axis that looks up (`+x`, `-x`, `-y`, `+z`, `-z`; `x` or `z` when the sign is unknown).
        up: &'static str,
        /// What was measured.
        reason: String,
    },
    /// The cloud is about as deep and wide as it is tall.
    #[error("the cloud is compact (robust extent x {:.3}, y {:.3}, z {:.3}): a sphere or a block, not a standing person (about 4-6 times taller than deep); check the input file (registration parameter check_plausible = false skips this check)", extent_m[0], extent_m[1], extent_m[2])]
    Compact {
        /// Robust extent per axis.
        extent_m: [f64; 3],
    },
    /// The subject does not face +Z (left limbs not on +X).
    #[error("the cloud does not face +z with its left on +x: {}; turn the cloud about the vertical (y) axis (180 degrees when left and right are swapped, 90 when it faces x), or fix mirrored coordinates or swapped left/right labels (registration parameter check_plausible = false skips this check)", facing_text(left_minus_right_m))]
    Facing {
        /// Centroid of the left limbs minus that of the right limbs (zero when unlabelled).
        left_minus_right_m: [f64; 3],
    },
    /// The height is not that of a person in metres.
    #[error("the cloud is {height_m:.3} high along y, but a person without head and feet is {min_m}-{max_m} m: the cloud is not in metres (millimetres: divide by 1000; centimetres: by 100) or not a person (registration parameter check_plausible = false skips this check)")]
    Size {
        /// Robust height (y side), cloud units.
        height_m: f64,
        /// The smallest plausible height, metres.
        min_m: f64,
        /// The largest plausible height, metres.
        max_m: f64,
    },
}

/// The measured facing for the message.
fn facing_text(d: &[f64; 3]) -> String {
    if d.iter().all(|&v| v == 0.0) {
        "it is deeper (z) than wide (x) while the template is wider: it faces +x or -x".to_string()
    } else {
        format!(
            "the left limbs' centroid lies {:+.3} m along x and {:+.3} m along z from the right limbs' (a person facing +z: about +0.3 m along x)",
            d[0], d[2]
        )
    }
}
