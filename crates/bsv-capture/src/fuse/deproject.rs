//! Deprojection of one view: the person-mask pixels to world points (with normals from the pixel
//! neighbours and colours), and the regular samples of every valid depth pixel for the floor fit.

use super::floor::{FloorSamples, SAMPLE_STRIDE};
use super::{ColorMode, DepthView, FuseParams};
use bsv_core::geometry::{cross, dot, norm, scale, sub};
use bsv_core::Segment;
use rayon::prelude::*;

/// One camera's person points (world frame), in row-major pixel order.
#[derive(Debug, Clone, Default)]
pub(super) struct ViewPoints {
    pub points: Vec<[f64; 3]>,
    /// Empty unless normals are asked for.
    pub normals: Vec<[f64; 3]>,
    pub colors: Vec<[u8; 3]>,
    pub labels: Vec<u8>,
    /// Row-major pixel index of each point.
    pub pixels: Vec<u32>,
}

impl ViewPoints {
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Keeps the points whose `keep` entry is true; returns how many were removed.
    pub fn retain(&mut self, keep: &[bool]) -> usize {
        let before = self.points.len();
        retain(&mut self.points, keep);
        retain(&mut self.normals, keep);
        retain(&mut self.colors, keep);
        retain(&mut self.labels, keep);
        retain(&mut self.pixels, keep);
        before - self.points.len()
    }
}

fn retain<T: Copy>(v: &mut Vec<T>, keep: &[bool]) {
    if v.len() != keep.len() {
        return;
    }
    let mut i = 0;
    v.retain(|_| {
        let k = keep[i];
        i += 1;
        k
    });
}

/// The depth filter of the parameters (valid, within `min_depth..=max_depth`).
pub(super) fn depth_filter(params: &FuseParams) -> impl Fn(f64) -> bool + Sync + Copy {
    let max = params.max_depth.unwrap_or(f64::INFINITY);
    let min = params.min_depth;
    move |z: f64| z > 0.0 && z >= min && z <= max
}

/// The normal at pixel (u, v) from its valid neighbours (central differences where possible),
/// oriented toward the camera; the direction back to the camera when no neighbour pair is usable.
fn pixel_normal(
    view: &DepthView,
    params: &FuseParams,
    depth_ok: &dyn Fn(f64) -> bool,
    u: usize,
    v: usize,
    p: [f64; 3],
) -> [f64; 3] {
    let intr = &view.intrinsics;
    let (w, h) = (intr.width as usize, intr.height as usize);
    let z0 = p[2];
    let at = |uu: usize, vv: usize| -> Option<[f64; 3]> {
        let z = view.depth.metres(vv * w + uu);
        (depth_ok(z) && (z - z0).abs() <= params.normal_max_step).then(|| intr.deproject([uu as f64, vv as f64], z))
    };
    let diff = |a: Option<[f64; 3]>, b: Option<[f64; 3]>| match (a, b) {
        (Some(a), Some(b)) => Some(sub(a, b)),
        (Some(a), None) => Some(sub(a, p)),
        (None, Some(b)) => Some(sub(p, b)),
        (None, None) => None,
    };
    let du = diff((u + 1 < w).then(|| at(u + 1, v)).flatten(), (u > 0).then(|| at(u - 1, v)).flatten());
    let dv = diff((v + 1 < h).then(|| at(u, v + 1)).flatten(), (v > 0).then(|| at(u, v - 1)).flatten());
    let toward_camera = scale(p, -1.0 / norm(p).max(1e-300));
    let (Some(du), Some(dv)) = (du, dv) else { return toward_camera };
    let n = cross(du, dv);
    let len = norm(n);
    if !(len > 0.0 && len.is_finite()) {
        return toward_camera;
    }
    let n = scale(n, 1.0 / len);
    if dot(n, p) > 0.0 {
        scale(n, -1.0)
    } else {
        n
    }
}

type Row = (Vec<([f64; 3], [f64; 3], [u8; 3], u8, u32)>, usize, usize);

/// Deprojects the mask pixels of one view into the world (its extrinsics), with normals and
/// colours as asked; also returns the mask pixel count and the mask pixels without a valid depth.
pub(super) fn deproject_view(view: &DepthView, params: &FuseParams) -> (ViewPoints, usize, usize) {
    let intr = &view.intrinsics;
    let ext = &view.camera_to_world;
    let w = intr.width as usize;
    let depth_ok = depth_filter(params);
    let rows: Vec<Row> = view
        .labels
        .par_chunks(w)
        .enumerate()
        .map(|(v, lrow)| {
            let mut out = Vec::new();
            let (mut mask, mut missing) = (0usize, 0usize);
            for (u, &l) in lrow.iter().enumerate() {
                if l == 0 {
                    continue;
                }
                mask += 1;
                let i = v * w + u;
                let z = view.depth.metres(i);
                if !depth_ok(z) {
                    missing += 1;
                    continue;
                }
                let p = intr.deproject([u as f64, v as f64], z);
                let n = if params.normals { pixel_normal(view, params, &depth_ok, u, v, p) } else { [0.0; 3] };
                let c = match params.colors {
                    ColorMode::None => [0; 3],
                    ColorMode::Palette => Segment::from_id(l).unwrap_or(Segment::Unlabelled).color(),
                    ColorMode::Image => view.colors.as_ref().map_or([0; 3], |c| c[i]),
                };
                out.push((ext.transform_point(p), ext.transform_vector(n), c, l, i as u32));
            }
            (out, mask, missing)
        })
        .collect();
    let (mut mask, mut missing) = (0, 0);
    let n: usize = rows.iter().map(|r| r.0.len()).sum();
    let mut vp = ViewPoints {
        points: Vec::with_capacity(n),
        normals: Vec::with_capacity(if params.normals { n } else { 0 }),
        colors: Vec::with_capacity(n),
        labels: Vec::with_capacity(n),
        pixels: Vec::with_capacity(n),
    };
    for (row, m, x) in rows {
        mask += m;
        missing += x;
        for (p, nn, c, l, i) in row {
            vp.points.push(p);
            if params.normals {
                vp.normals.push(nn);
            }
            vp.colors.push(c);
            vp.labels.push(l);
            vp.pixels.push(i);
        }
    }
    (vp, mask, missing)
}

/// World-frame samples of every valid depth pixel of the view, every [`SAMPLE_STRIDE`] pixels in
/// both directions, flagged when inside the person mask.
pub(super) fn floor_samples(view: &DepthView, params: &FuseParams) -> FloorSamples {
    let intr = &view.intrinsics;
    let ext = &view.camera_to_world;
    let (w, h) = (intr.width as usize, intr.height as usize);
    let depth_ok = depth_filter(params);
    let rows: Vec<Vec<([f64; 3], bool)>> = (0..h)
        .into_par_iter()
        .step_by(SAMPLE_STRIDE)
        .map(|v| {
            (0..w)
                .step_by(SAMPLE_STRIDE)
                .filter_map(|u| {
                    let i = v * w + u;
                    let z = view.depth.metres(i);
                    depth_ok(z)
                        .then(|| (ext.transform_point(intr.deproject([u as f64, v as f64], z)), view.labels[i] != 0))
                })
                .collect()
        })
        .collect();
    let mut s = FloorSamples { pixels_per_sample: SAMPLE_STRIDE * SAMPLE_STRIDE, ..FloorSamples::default() };
    for (p, person) in rows.into_iter().flatten() {
        s.points.push(p);
        s.person.push(person);
    }
    s
}
