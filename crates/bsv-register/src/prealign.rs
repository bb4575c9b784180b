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

use crate::error::RegisterError;
use crate::params::{PrealignMode, RegisterParams};
use bsv_core::geometry::{cross, dot, sub, Aabb};
use bsv_core::topology::edge_map;
use bsv_core::{PointCloud, TriMesh};
use serde::{Deserialize, Serialize};

/// The map `p -> cloud_center + scale * (p - template_center)` (per-axis scale) applied to the
/// template before the non-rigid fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Similarity {
    /// Robust bounding-box centre of the template, metres.
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
        std::array::from_fn(|k| self.cloud_center[k] + self.scale[k] * (p[k] - self.template_center[k]))
    }
}

/// A bounding box from per-axis quantiles `q` and `1 - q` (plain min/max for q = 0).
pub fn robust_aabb(points: &[[f64; 3]], q: f64) -> Option<Aabb> {
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

/// Checks a cloud: not empty, enough points, finite, attribute lengths, plausible metres.
pub fn check_cloud(cloud: &PointCloud, params: &RegisterParams) -> Result<Aabb, RegisterError> {
    let n = cloud.points.len();
    let min = params.min_points.max(1);
    if n == 0 {
        return Err(RegisterError::EmptyCloud { min });
    }
    if let Some(index) = cloud.points.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        return Err(RegisterError::NonFinitePoint { index, point: cloud.points[index] });
    }
    if n < min {
        return Err(RegisterError::TooFewPoints { n, min });
    }
    if let Some(l) = &cloud.normals {
        if l.len() != n {
            return Err(RegisterError::LengthMismatch { what: "cloud normals", got: l.len(), expected: n });
        }
    }
    if let Some(l) = &cloud.labels {
        if l.len() != n {
            return Err(RegisterError::LengthMismatch { what: "cloud labels", got: l.len(), expected: n });
        }
    }
    let bbox = robust_aabb(&cloud.points, params.bbox_quantile)
        .ok_or(RegisterError::EmptyCloud { min })?;
    let ext = bbox.extent();
    let largest = ext[0].max(ext[1]).max(ext[2]);
    if largest > params.max_extent_m {
        return Err(RegisterError::CloudLooksLikeMillimetres { extent_m: largest, limit_m: params.max_extent_m });
    }
    if largest < params.min_extent_m {
        return Err(RegisterError::CloudTooSmall { extent_m: largest, limit_m: params.min_extent_m });
    }
    Ok(bbox)
}

/// Checks a template: not empty, indices in range, finite, closed 2-manifold edges, no zero-area
/// triangle, label lengths. Returns its (plain) bounding box.
pub fn check_template(template: &TriMesh) -> Result<Aabb, RegisterError> {
    let nv = template.vertices.len();
    let nt = template.triangles.len();
    if nv < 4 || nt < 4 {
        return Err(RegisterError::EmptyTemplate { vertices: nv, triangles: nt });
    }
    if let Some(index) = template.vertices.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
        return Err(RegisterError::NonFiniteTemplateVertex { index, point: template.vertices[index] });
    }
    for (t, tri) in template.triangles.iter().enumerate() {
        if let Some(&v) = tri.iter().find(|&&v| v as usize >= nv) {
            return Err(RegisterError::BadTriangleIndex { triangle: t, vertex: v, n_vertices: nv });
        }
    }
    if let Some(l) = &template.vertex_labels {
        if l.len() != nv {
            return Err(RegisterError::LengthMismatch { what: "template vertex labels", got: l.len(), expected: nv });
        }
    }
    if let Some(l) = &template.face_labels {
        if l.len() != nt {
            return Err(RegisterError::LengthMismatch { what: "template face labels", got: l.len(), expected: nt });
        }
    }
    let bbox = Aabb::of_points(&template.vertices).ok_or(RegisterError::EmptyTemplate { vertices: nv, triangles: nt })?;
    let diag2 = dot(bbox.extent(), bbox.extent());
    let mut degenerate = template.triangles.iter().enumerate().filter(|(_, tri)| {
        let [a, b, c] = tri.map(|v| template.vertices[v as usize]);
        let n = cross(sub(b, a), sub(c, a));
        dot(n, n).sqrt() <= 1e-12 * diag2
    });
    if let Some((first, _)) = degenerate.next() {
        return Err(RegisterError::DegenerateTemplate { triangle: first, count: 1 + degenerate.count() });
    }
    let edges = edge_map(&template.triangles);
    let mut bad: Vec<((u32, u32), usize)> =
        edges.iter().filter(|(_, e)| e.faces.len() != 2).map(|(&k, e)| (k, e.faces.len())).collect();
    if !bad.is_empty() {
        bad.sort_unstable();
        let ((a, b), faces) = bad[0];
        return Err(RegisterError::NonManifoldTemplate { a, b, faces, count: bad.len() });
    }
    Ok(bbox)
}

/// The pre-alignment similarity from the template's and the cloud's robust boxes.
pub fn similarity(template_box: &Aabb, cloud_box: &Aabb, params: &RegisterParams) -> Similarity {
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
    Similarity { template_center: template_box.center(), cloud_center: cloud_box.center(), scale, mode }
}
