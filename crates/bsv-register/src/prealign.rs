//! Input checks and the similarity pre-alignment of the template onto the cloud.
//!
//! The paper translates template and cloud to their bounding-box centres and scales the template by
//! the ratio of the bounding-box diagonals (both boxes axis-aligned in the shared world frame, so no
//! rotation is needed). [`PrealignMode::PerAxis`] scales each axis by the ratio of the box sides
//! instead, which a cube template needs for a 1.04 m x 0.2 m x 0.2 m box (isotropic scaling starts
//! it 0.62 m tall and a stiff fit never stretches it that far). [`PrealignMode::Auto`] picks
//! per-axis scaling when, on some axis, the cloud's box side relative to its diagonal differs from
//! the template's by more than `auto_aspect_threshold` (default 50 %), isotropic otherwise.
//!
//! Boxes are robust: on each axis the box runs from the `q` to the `1 - q` quantile of the
//! coordinates (default q = 0.1 %), so a few stray points or flying pixels do not stretch it.
//! Lateral gaps (the sides no camera sees) shrink the cloud's x side a little; the non-rigid fit
//! recovers that, and the Auto threshold is above what such gaps cause on a human.
//!
//! # Yaw search ([`YawMode::Auto`], the default)
//! The paper needs no rotation because its template and subjects share the world frame. A box
//! turned 45 degrees about the vertical does not: its axis-aligned box is a square prism of the
//! wrong proportions, and an axis-aligned cube template would have to fold its corners onto the
//! box faces (2.5 % volume error on the paper's box A). So [`prealign`] first finds, for the cloud
//! and for the template, the direction of the smallest-area horizontal (x-z) bounding rectangle
//! (robust quantiles, 2-degree steps then 0.2-degree refinement, on a subsample of <= 2,000
//! points). When the two differ by less than [`YAW_MIN_DEG`] (modulo 90 degrees) nothing is
//! turned: a body facing +Z like its template stays exactly as the paper aligns it. Otherwise the
//! candidates yaw = 0 and yaw = delta + k * 90 degrees (k = 0..3) are each followed by the
//! similarity and scored by the RMS distance from a cloud subsample to the nearest template vertex
//! (one k-d tree over the few-thousand template vertices per candidate, ~1 ms); a non-zero yaw is
//! kept only when its RMS is below [`YAW_MIN_GAIN`] x that of yaw = 0. Measured: the paper's boxes
//! at 45 degrees with an axis-aligned cube template go from 2.5 % to under 1 % volume error
//! (tests/gaps.rs).

use crate::correspond::{build_tree, nearest_batch};
use crate::error::InputError;
use crate::params::{CheckParams, PrealignMode, PrealignParams, YawMode};
use bsv_core::geometry::{cross, dot, sub, Aabb};
use bsv_core::topology::edge_map;
use bsv_core::{PointCloud, TriMesh};
use serde::{Deserialize, Serialize};

/// The map `p -> cloud_center + scale * (Ry(p - pivot) + pivot - template_center)` (per-axis
/// scale, `Ry` the turn by `yaw_deg` about the vertical through `pivot`) applied to the template
/// before the non-rigid fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Similarity {
    /// Rotation about the vertical (y) axis, degrees (0 unless the yaw search found one), with the
    /// sense of `bsv_core::shapes::rotate_y`.
    pub yaw_deg: f64,
    /// Point of the template the rotation turns about (its bounding-box centre), metres.
    pub pivot: [f64; 3],
    /// Bounding-box centre of the (turned) template, metres.
    pub template_center: [f64; 3],
    /// Robust bounding-box centre of the cloud, metres.
    pub cloud_center: [f64; 3],
    /// Scale per axis (all three equal for an isotropic pre-alignment).
    pub scale: [f64; 3],
    /// The mode actually used (`Auto` resolves to `Isotropic` or `PerAxis`).
    pub mode: PrealignMode,
}

impl Similarity {
    /// Applies the map to one point.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let p = if self.yaw_deg == 0.0 { p } else { rotate_about_y(p, self.pivot, self.yaw_deg.to_radians()) };
        std::array::from_fn(|k| self.cloud_center[k] + self.scale[k] * (p[k] - self.template_center[k]))
    }
}

/// Turns `p` by `angle` radians about the vertical through `pivot` (the sense of
/// `bsv_core::shapes::rotate_y`: x' = c x + s z, z' = -s x + c z).
pub(crate) fn rotate_about_y(p: [f64; 3], pivot: [f64; 3], angle: f64) -> [f64; 3] {
    let (s, c) = angle.sin_cos();
    let (x, z) = (p[0] - pivot[0], p[2] - pivot[2]);
    [pivot[0] + c * x + s * z, p[1], pivot[2] - s * x + c * z]
}

/// A bounding box from per-axis quantiles `q` and `1 - q` (plain min/max for q = 0).
pub(crate) fn robust_aabb(points: &[[f64; 3]], q: f64) -> Option<Aabb> {
    if points.is_empty() {
        return None;
    }
    if q <= 0.0 {
        return Aabb::of_points(points);
    }
    let n = points.len();
    let lo = ((q * n as f64).floor() as usize).min(n - 1);
    let hi = (((1.0 - q) * n as f64).ceil() as usize).saturating_sub(1).clamp(lo, n - 1);
    let mut min = [0.0; 3];
    let mut max = [0.0; 3];
    let mut buf: Vec<f64> = Vec::with_capacity(n);
    for k in 0..3 {
        buf.clear();
        buf.extend(points.iter().map(|p| p[k]));
        if buf.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let (_, &mut a, _) = buf.select_nth_unstable_by(lo, f64::total_cmp);
        min[k] = a;
        let (_, &mut b, _) = buf.select_nth_unstable_by(hi, f64::total_cmp);
        max[k] = b;
    }
    Some(Aabb { min, max })
}

/// Checks a cloud: not empty, enough points, finite, attribute lengths, plausible metres; returns
/// its robust bounding box (quantile `bbox_quantile`).
pub(crate) fn check_cloud(cloud: &PointCloud, params: &CheckParams, bbox_quantile: f64) -> Result<Aabb, InputError> {
    let n = cloud.points.len();
    let min = params.min_points.max(1);
    if n == 0 {
        return Err(InputError::EmptyCloud { min });
    }
    if let Some(index) = cloud.points.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        return Err(InputError::NonFinitePoint { index, point: cloud.points[index] });
    }
    if n < min {
        return Err(InputError::TooFewPoints { n, min });
    }
    if let Some(l) = &cloud.normals {
        if l.len() != n {
            return Err(InputError::LengthMismatch { what: "cloud normals", got: l.len(), expected: n });
        }
    }
    if let Some(l) = &cloud.labels {
        if l.len() != n {
            return Err(InputError::LengthMismatch { what: "cloud labels", got: l.len(), expected: n });
        }
    }
    let bbox = robust_aabb(&cloud.points, bbox_quantile).ok_or(InputError::EmptyCloud { min })?;
    let ext = bbox.extent();
    let largest = ext[0].max(ext[1]).max(ext[2]);
    if largest > params.max_extent_m {
        return Err(InputError::CloudLooksLikeMillimetres { extent_m: largest, limit_m: params.max_extent_m });
    }
    if largest < params.min_extent_m {
        return Err(InputError::CloudTooSmall { extent_m: largest, limit_m: params.min_extent_m });
    }
    Ok(bbox)
}

/// Checks a template: not empty, indices in range, finite, closed 2-manifold edges, no zero-area
/// triangle, label lengths. Returns its (plain) bounding box.
pub(crate) fn check_template(template: &TriMesh) -> Result<Aabb, InputError> {
    let nv = template.vertices.len();
    let nt = template.triangles.len();
    if nv < 4 || nt < 4 {
        return Err(InputError::EmptyTemplate { vertices: nv, triangles: nt });
    }
    if let Some(index) = template.vertices.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        return Err(InputError::NonFiniteTemplateVertex { index, point: template.vertices[index] });
    }
    template.check_indices()?;
    if let Some(l) = &template.vertex_labels {
        if l.len() != nv {
            return Err(InputError::LengthMismatch { what: "template vertex labels", got: l.len(), expected: nv });
        }
    }
    if let Some(l) = &template.face_labels {
        if l.len() != nt {
            return Err(InputError::LengthMismatch { what: "template face labels", got: l.len(), expected: nt });
        }
    }
    let bbox = Aabb::of_points(&template.vertices).ok_or(InputError::EmptyTemplate { vertices: nv, triangles: nt })?;
    let diag2 = dot(bbox.extent(), bbox.extent());
    let mut degenerate = template.triangles.iter().enumerate().filter(|(_, tri)| {
        let [a, b, c] = tri.map(|v| template.vertices[v as usize]);
        let n = cross(sub(b, a), sub(c, a));
        dot(n, n).sqrt() <= 1e-12 * diag2
    });
    if let Some((first, _)) = degenerate.next() {
        return Err(InputError::DegenerateTemplate { triangle: first, count: 1 + degenerate.count() });
    }
    let edges = edge_map(&template.triangles);
    let mut bad: Vec<((u32, u32), usize)> =
        edges.iter().filter(|(_, e)| e.faces.len() != 2).map(|(&k, e)| (k, e.faces.len())).collect();
    if !bad.is_empty() {
        bad.sort_unstable();
        let ((a, b), faces) = bad[0];
        return Err(InputError::NonManifoldTemplate { a, b, faces, count: bad.len() });
    }
    Ok(bbox)
}

/// The pre-alignment similarity from the template's and the cloud's robust boxes.
pub(crate) fn similarity(template_box: &Aabb, cloud_box: &Aabb, params: &PrealignParams) -> Similarity {
    let te = template_box.extent();
    let ce = cloud_box.extent();
    let td = template_box.diagonal().max(f64::MIN_POSITIVE);
    let cd = cloud_box.diagonal();
    let iso = cd / td;
    let per_axis_ok = (0..3).all(|k| te[k] > 1e-9 * td && ce[k] > 1e-9 * cd);
    let mode = match params.prealign {
        PrealignMode::Isotropic => PrealignMode::Isotropic,
        PrealignMode::PerAxis if per_axis_ok => PrealignMode::PerAxis,
        PrealignMode::PerAxis => PrealignMode::Isotropic,
        PrealignMode::Auto => {
            let differs = (0..3).any(|k| ((ce[k] / cd) / (te[k] / td) - 1.0).abs() > params.auto_aspect_threshold);
            if differs && per_axis_ok {
                PrealignMode::PerAxis
            } else {
                PrealignMode::Isotropic
            }
        }
    };
    let scale = match mode {
        PrealignMode::PerAxis => std::array::from_fn(|k| ce[k] / te[k]),
        _ => [iso; 3],
    };
    let c = template_box.center();
    Similarity { yaw_deg: 0.0, pivot: c, template_center: c, cloud_center: cloud_box.center(), scale, mode }
}

/// Smallest yaw difference (degrees, modulo 90) between the template's and the cloud's footprint
/// rectangles for which [`prealign`] tries a rotation.
pub(crate) const YAW_MIN_DEG: f64 = 10.0;
/// A non-zero yaw is kept when its cloud-to-template RMS is below this fraction of yaw 0's.
pub(crate) const YAW_MIN_GAIN: f64 = 0.8;
/// Points used for the footprint and the RMS check (a regular subsample).
const YAW_SAMPLES: usize = 2000;

/// Every `len / max`-th item (at most about `max` items).
fn subsample(points: &[[f64; 3]], max: usize) -> Vec<[f64; 3]> {
    let stride = points.len().div_ceil(max.max(1)).max(1);
    points.iter().step_by(stride).copied().collect()
}

/// Area of the robust (quantiles `q`, `1 - q`) rectangle of the x-z footprint along the
/// direction `angle` (radians) and its perpendicular.
fn footprint_area(points: &[[f64; 3]], angle: f64, q: f64, buf: &mut Vec<f64>) -> f64 {
    let (s, c) = angle.sin_cos();
    let n = points.len();
    let lo = ((q * n as f64).floor() as usize).min(n - 1);
    let hi = (((1.0 - q) * n as f64).ceil() as usize).saturating_sub(1).clamp(lo, n - 1);
    let mut side = |f: &dyn Fn(&[f64; 3]) -> f64| {
        buf.clear();
        buf.extend(points.iter().map(f));
        let (_, &mut a, _) = buf.select_nth_unstable_by(lo, f64::total_cmp);
        let (_, &mut b, _) = buf.select_nth_unstable_by(hi, f64::total_cmp);
        b - a
    };
    let u = side(&|p| c * p[0] + s * p[2]);
    let v = side(&|p| -s * p[0] + c * p[2]);
    u * v
}

/// Direction (radians, in [0, pi/2)) of the smallest-area horizontal bounding rectangle.
pub(crate) fn footprint_angle(points: &[[f64; 3]], q: f64) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let mut buf = Vec::with_capacity(points.len());
    let deg = std::f64::consts::PI / 180.0;
    let best = |angles: &mut dyn Iterator<Item = f64>, buf: &mut Vec<f64>| {
        angles
            .map(|a| (a, footprint_area(points, a, q, buf)))
            .fold((0.0, f64::INFINITY), |b, x| if x.1 < b.1 { x } else { b })
            .0
    };
    let coarse = best(&mut (0..45).map(|k| 2.0 * k as f64 * deg), &mut buf);
    let fine = best(&mut (-10..=10).map(|k| coarse + 0.2 * k as f64 * deg), &mut buf);
    fine.rem_euclid(std::f64::consts::FRAC_PI_2)
}

/// The pre-alignment: the yaw search of [`YawMode::Auto`] (module docs) followed by the
/// [`similarity`] of the (turned) template's box onto the cloud's. `Err` only when a k-d tree
/// cannot be built.
pub(crate) fn prealign(
    template: &[[f64; 3]],
    template_box: &Aabb,
    cloud: &[[f64; 3]],
    cloud_box: &Aabb,
    params: &PrealignParams,
) -> Result<Similarity, String> {
    let base = similarity(template_box, cloud_box, params);
    if params.prealign_yaw == YawMode::Off || template.is_empty() || cloud.is_empty() {
        return Ok(base);
    }
    let cloud_sub = subsample(cloud, YAW_SAMPLES);
    let template_sub = subsample(template, YAW_SAMPLES);
    let q = params.bbox_quantile;
    let delta = footprint_angle(&template_sub, q) - footprint_angle(&cloud_sub, q);
    let quarter = std::f64::consts::FRAC_PI_2;
    // Fold into [-45, 45) degrees.
    let delta = (delta + quarter / 2.0).rem_euclid(quarter) - quarter / 2.0;
    if delta.abs().to_degrees() < YAW_MIN_DEG {
        return Ok(base);
    }
    let pivot = template_box.center();
    let score = |sim: &Similarity| -> Result<f64, String> {
        let moved: Vec<[f64; 3]> = template.iter().map(|&p| sim.apply(p)).collect();
        let tree = build_tree(&moved)?;
        let d = nearest_batch(&tree, &cloud_sub);
        Ok((d.iter().map(|r| r.1).sum::<f64>() / d.len().max(1) as f64).sqrt())
    };
    let base_rms = score(&base)?;
    let mut best = (base, base_rms);
    // Smallest turns first; a later candidate must be 1 % better (a box fits at every k).
    for k in [0.0, 1.0, -1.0, 2.0] {
        let yaw = delta + k * quarter;
        let turned: Vec<[f64; 3]> = template.iter().map(|&p| rotate_about_y(p, pivot, yaw)).collect();
        let Some(tbox) = Aabb::of_points(&turned) else { continue };
        let mut sim = similarity(&tbox, cloud_box, params);
        sim.yaw_deg = yaw.to_degrees();
        sim.pivot = pivot;
        let rms = score(&sim)?;
        if rms < 0.99 * best.1 {
            best = (sim, rms);
        }
    }
    Ok(if best.1 < YAW_MIN_GAIN * base_rms { best.0 } else { base })
}
