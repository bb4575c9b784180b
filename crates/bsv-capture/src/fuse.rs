//! Cloud building (DESIGN.md "Data flow", step 4): per camera, deproject the colour-aligned depth
//! image with the intrinsics, keep the pixels that carry a segment label (the person mask),
//! remove statistical outliers, transform to the world with the calibration; then merge the cameras
//! and drop head, hand and foot points. Optional per-point normals (from the depth image's pixel
//! neighbours, facing the camera) and colours (the colour image or the segment palette).
//!
//! The order is the paper's: outlier removal runs on each camera's whole person cloud (extremities
//! included), in the camera frame; segments are dropped after merging. Points keep the row-major
//! pixel order of each camera, cameras in the order given.

use crate::camera::{CameraError, Extrinsics, Intrinsics};
use crate::clean::{statistical_outliers, CleanError, SorParams};
use bsv_core::geometry::{cross, dot, norm, scale, sub};
use bsv_core::{PointCloud, Segment, EXTREMITIES, SEGMENT_COUNT};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::time::Instant;

/// Errors of cloud building: which camera and image is wrong, and what to do.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FuseError {
    /// No camera view was given.
    #[error("cloud building got no camera view: pass the front and back captures")]
    NoViews,
    /// An image whose size does not match the intrinsics.
    #[error("camera `{camera}`: the {image} image has {got} pixels but the intrinsics say {width} x {height} = {expected}; use images aligned to the image the intrinsics describe")]
    ImageSize {
        /// Camera name.
        camera: String,
        /// "depth", "labels" or "colour".
        image: &'static str,
        /// Pixels found.
        got: usize,
        /// Expected width * height.
        expected: usize,
        /// Intrinsics width.
        width: u32,
        /// Intrinsics height.
        height: u32,
    },
    /// A depth scale that is not a positive finite number.
    #[error("camera `{camera}`: depth scale {value} is not a positive finite number of metres per unit; read it from the capture's camera.json (L515: 0.00025)")]
    BadDepthScale {
        /// Camera name.
        camera: String,
        /// The offending value.
        value: f64,
    },
    /// Invalid intrinsics or extrinsics.
    #[error("camera `{camera}`: {source}")]
    Camera {
        /// Camera name.
        camera: String,
        /// What is wrong.
        #[source]
        source: CameraError,
    },
    /// A label image value that is not a segment id.
    #[error("camera `{camera}`: label image pixel (u {u}, v {v}) is {value}, not a segment id 0..=14; pass the segmentation's label image")]
    BadLabel {
        /// Camera name.
        camera: String,
        /// Column.
        u: u32,
        /// Row.
        v: u32,
        /// The value.
        value: u8,
    },
    /// The label image has no labelled pixel: no person was segmented.
    #[error("camera `{camera}`: no pixel carries a segment label, so no person was found in this view; check the subject stands in the camera's field of view and the segmentation ran")]
    EmptyMask {
        /// Camera name.
        camera: String,
    },
    /// Labelled pixels exist but none has a valid depth.
    #[error("camera `{camera}`: none of the {mask_pixels} labelled pixels has a valid depth (0, non-finite or outside the depth range); check the depth image is aligned to the colour image and the depth range parameters")]
    NoValidDepth {
        /// Camera name.
        camera: String,
        /// Number of labelled pixels.
        mask_pixels: usize,
    },
    /// Colours from the image were requested but a view has no colour image.
    #[error("camera `{camera}`: colours = \"image\" but this view has no colour image; pass it or use colours \"palette\" or \"none\"")]
    MissingColour {
        /// Camera name.
        camera: String,
    },
    /// Statistical outlier removal failed.
    #[error("camera `{camera}`: outlier removal failed: {source}")]
    Clean {
        /// Camera name.
        camera: String,
        /// The cleaning error.
        #[source]
        source: CleanError,
    },
    /// A parameter out of range.
    #[error("cloud building parameter `{param}` is {value}: {hint}")]
    BadParam {
        /// Parameter name.
        param: &'static str,
        /// The offending value.
        value: f64,
        /// What is expected.
        hint: &'static str,
    },
    /// Nothing is left after dropping segments.
    #[error("no point is left after dropping segments {dropped:?}: the segmentation labelled only dropped segments; check it, or keep the extremities")]
    EmptyCloud {
        /// Names of the dropped segments.
        dropped: Vec<String>,
    },
}

/// A depth image, row-major, aligned to the label (and colour) image.
#[derive(Debug, Clone, PartialEq)]
pub enum DepthImage {
    /// Device units: metres = value x `scale`; 0 = no data.
    Units {
        /// The raw values (e.g. a 16-bit depth PNG).
        data: Vec<u16>,
        /// Metres per unit (L515: 0.00025).
        scale: f64,
    },
    /// Metres; 0 or non-finite = no data.
    Metres(Vec<f32>),
}

impl DepthImage {
    /// Number of pixels.
    pub fn len(&self) -> usize {
        match self {
            DepthImage::Units { data, .. } => data.len(),
            DepthImage::Metres(d) => d.len(),
        }
    }

    /// True when the image has no pixel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Depth of pixel `i` in metres; 0 when there is no data.
    #[inline]
    fn metres(&self, i: usize) -> f64 {
        let z = match self {
            DepthImage::Units { data, scale } => f64::from(data[i]) * scale,
            DepthImage::Metres(d) => f64::from(d[i]),
        };
        if z.is_finite() && z > 0.0 {
            z
        } else {
            0.0
        }
    }
}

/// One camera's inputs to cloud building.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthView {
    /// Camera name ("front", "back"), used in reports and errors.
    pub name: String,
    /// Intrinsics of the (colour-aligned) depth image.
    pub intrinsics: Intrinsics,
    /// Camera-to-world extrinsics from the calibration.
    pub camera_to_world: Extrinsics,
    /// The depth image.
    pub depth: DepthImage,
    /// Per-pixel segment id (0 = not the person), row-major, same size.
    pub labels: Vec<u8>,
    /// Optional sRGB colour image, row-major, same size.
    pub colors: Option<Vec<[u8; 3]>>,
}

/// Where point colours come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ColorMode {
    /// No colours.
    None,
    /// The segment palette colour of each point's label (what MeshLab shows as segments).
    #[default]
    Palette,
    /// The colour image's pixel (every view must carry one).
    Image,
}

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
}

impl Default for FuseParams {
    /// The paper's pipeline: SOR (600, 0.05), head/hands/feet dropped, normals, palette colours.
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
        }
    }
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
        if self.sor && self.sor_k == 0 {
            return Err(FuseError::BadParam {
                param: "sor_k",
                value: 0.0,
                hint: "use k >= 1 (the paper uses 600) or sor = false",
            });
        }
        if !self.sor_std_ratio.is_finite() {
            return Err(FuseError::BadParam {
                param: "sor_std_ratio",
                value: self.sor_std_ratio,
                hint: "use a finite number (the paper uses 0.05)",
            });
        }
        if !(self.min_depth.is_finite() && self.min_depth >= 0.0) {
            return Err(FuseError::BadParam {
                param: "min_depth",
                value: self.min_depth,
                hint: "use a finite depth >= 0 in metres",
            });
        }
        if let Some(m) = self.max_depth {
            if !(m.is_finite() && m > self.min_depth) {
                return Err(FuseError::BadParam {
                    param: "max_depth",
                    value: m,
                    hint: "use a finite depth in metres above min_depth, or null",
                });
            }
        }
        if !(self.normal_max_step.is_finite() && self.normal_max_step > 0.0) {
            return Err(FuseError::BadParam {
                param: "normal_max_step",
                value: self.normal_max_step,
                hint: "use a positive length in metres (e.g. 0.03)",
            });
        }
        if let Some(&l) = self.drop_labels.iter().find(|&&l| usize::from(l) >= SEGMENT_COUNT) {
            return Err(FuseError::BadParam {
                param: "drop_labels",
                value: f64::from(l),
                hint: "use segment ids 0..=14",
            });
        }
        Ok(())
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
    /// Points removed by statistical outlier removal.
    pub sor_removed: usize,
    /// The outlier threshold on the mean neighbour distance (metres), when SOR ran.
    pub sor_threshold_m: Option<f64>,
    /// Points dropped per segment name.
    pub dropped: BTreeMap<String, usize>,
    /// Points of this camera in the final cloud.
    pub kept: usize,
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

/// One camera's points before merging (camera frame until transformed).
struct ViewPoints {
    points: Vec<[f64; 3]>,
    normals: Vec<[f64; 3]>,
    colors: Vec<[u8; 3]>,
    labels: Vec<u8>,
}

fn check_view(view: &DepthView, params: &FuseParams) -> Result<(), FuseError> {
    let camera = || view.name.clone();
    view.intrinsics.validate().map_err(|source| FuseError::Camera { camera: camera(), source })?;
    view.camera_to_world.validate().map_err(|source| FuseError::Camera { camera: camera(), source })?;
    let intr = &view.intrinsics;
    let expected = intr.n_pixels();
    let size = |image: &'static str, got: usize| {
        if got == expected {
            Ok(())
        } else {
            Err(FuseError::ImageSize { camera: camera(), image, got, expected, width: intr.width, height: intr.height })
        }
    };
    size("depth", view.depth.len())?;
    size("labels", view.labels.len())?;
    if let Some(c) = &view.colors {
        size("colour", c.len())?;
    } else if params.colors == ColorMode::Image {
        return Err(FuseError::MissingColour { camera: camera() });
    }
    if let DepthImage::Units { scale, .. } = view.depth {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(FuseError::BadDepthScale { camera: camera(), value: scale });
        }
    }
    if let Some((i, &value)) = view.labels.iter().enumerate().find(|(_, &l)| usize::from(l) >= SEGMENT_COUNT) {
        let w = intr.width as usize;
        return Err(FuseError::BadLabel { camera: camera(), u: (i % w) as u32, v: (i / w) as u32, value });
    }
    Ok(())
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

/// Deprojects the mask pixels of one view (camera frame), with normals and colours as asked.
fn deproject_view(view: &DepthView, params: &FuseParams) -> (ViewPoints, usize, usize) {
    let intr = &view.intrinsics;
    let w = intr.width as usize;
    let max = params.max_depth.unwrap_or(f64::INFINITY);
    let min = params.min_depth;
    let depth_ok = move |z: f64| z > 0.0 && z >= min && z <= max;
    type Row = (Vec<([f64; 3], [f64; 3], [u8; 3], u8)>, usize, usize);
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
                out.push((p, n, c, l));
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
    };
    for (row, m, x) in rows {
        mask += m;
        missing += x;
        for (p, nn, c, l) in row {
            vp.points.push(p);
            if params.normals {
                vp.normals.push(nn);
            }
            vp.colors.push(c);
            vp.labels.push(l);
        }
    }
    (vp, mask, missing)
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

fn segment_name(id: u8) -> String {
    Segment::from_id(id).map_or_else(|| format!("id_{id}"), |s| s.name().to_string())
}

/// Builds the merged, labelled world-frame cloud from the camera views (see the module docs).
pub fn build_cloud(views: &[DepthView], params: &FuseParams) -> Result<(PointCloud, FuseReport), FuseError> {
    let t0 = Instant::now();
    params.validate()?;
    if views.is_empty() {
        return Err(FuseError::NoViews);
    }
    for view in views {
        check_view(view, params)?;
    }
    let mut drop = [false; SEGMENT_COUNT];
    for &l in &params.drop_labels {
        drop[usize::from(l)] = true;
    }
    let mut world = ViewPoints { points: Vec::new(), normals: Vec::new(), colors: Vec::new(), labels: Vec::new() };
    let mut reports = Vec::with_capacity(views.len());
    for view in views {
        reports.push(fuse_view(view, params, &drop, &mut world)?);
    }
    if world.points.is_empty() {
        return Err(FuseError::EmptyCloud { dropped: params.drop_labels.iter().map(|&l| segment_name(l)).collect() });
    }
    let ViewPoints { points, normals, colors, labels } = world;
    let mut cloud = PointCloud::new(points);
    if params.normals {
        cloud.normals = Some(normals);
    }
    if params.colors != ColorMode::None {
        cloud.colors = Some(colors);
    }
    let mut per_segment: BTreeMap<String, usize> = BTreeMap::new();
    for &l in &labels {
        *per_segment.entry(segment_name(l)).or_default() += 1;
    }
    cloud.labels = Some(labels);
    let mut dropped: BTreeMap<String, usize> = BTreeMap::new();
    for r in &reports {
        for (k, v) in &r.dropped {
            *dropped.entry(k.clone()).or_default() += v;
        }
    }
    let report = FuseReport {
        views: reports,
        points: cloud.len(),
        points_per_segment: per_segment,
        dropped,
        seconds: t0.elapsed().as_secs_f64(),
    };
    Ok((cloud, report))
}

/// One view: deprojects its mask, removes its outliers, and appends its kept points to `world`
/// in the world frame.
fn fuse_view(
    view: &DepthView,
    params: &FuseParams,
    drop: &[bool; SEGMENT_COUNT],
    world: &mut ViewPoints,
) -> Result<ViewReport, FuseError> {
    let camera = || view.name.clone();
    let t = Instant::now();
    let (mut vp, mask_pixels, no_depth) = deproject_view(view, params);
    let seconds_deproject = t.elapsed().as_secs_f64();
    if mask_pixels == 0 {
        return Err(FuseError::EmptyMask { camera: camera() });
    }
    if vp.points.is_empty() {
        return Err(FuseError::NoValidDepth { camera: camera(), mask_pixels });
    }
    let deprojected = vp.points.len();
    let t = Instant::now();
    let mut sor_threshold_m = None;
    if params.sor {
        let res = statistical_outliers(&vp.points, SorParams { k: params.sor_k, std_ratio: params.sor_std_ratio })
            .map_err(|source| FuseError::Clean { camera: camera(), source })?;
        sor_threshold_m = res.threshold.is_finite().then_some(res.threshold);
        retain(&mut vp.points, &res.keep);
        retain(&mut vp.normals, &res.keep);
        retain(&mut vp.colors, &res.keep);
        retain(&mut vp.labels, &res.keep);
    }
    let seconds_sor = t.elapsed().as_secs_f64();
    let sor_removed = deprojected - vp.points.len();
    let dropped = append_to_world(&vp, &view.camera_to_world, params, drop, world);
    let kept = vp.points.len() - dropped.values().sum::<usize>();
    Ok(ViewReport {
        name: view.name.clone(),
        mask_pixels,
        no_depth,
        deprojected,
        sor_removed,
        sor_threshold_m,
        dropped,
        kept,
        seconds_deproject,
        seconds_sor,
    })
}

/// Appends the camera-frame points whose label is not dropped to `world` (transformed by `ext`);
/// the count of dropped points per segment name.
fn append_to_world(
    vp: &ViewPoints,
    ext: &Extrinsics,
    params: &FuseParams,
    drop: &[bool; SEGMENT_COUNT],
    world: &mut ViewPoints,
) -> BTreeMap<String, usize> {
    let mut dropped: BTreeMap<String, usize> = BTreeMap::new();
    for (k, (&p, &l)) in vp.points.iter().zip(&vp.labels).enumerate() {
        if drop[usize::from(l)] {
            *dropped.entry(segment_name(l)).or_default() += 1;
            continue;
        }
        world.points.push(ext.transform_point(p));
        if params.normals {
            world.normals.push(ext.transform_vector(vp.normals[k]));
        }
        world.colors.push(vp.colors[k]);
        world.labels.push(l);
    }
    dropped
}
