//! Cloud building (DESIGN.md "Data flow", step 4): per camera, deproject the colour-aligned depth
//! image with the intrinsics, keep the pixels that carry a segment label (the person mask), transform
//! to the world with the calibration, keep only the person, remove statistical outliers; then merge
//! the cameras and drop head, hand and foot points. Optional per-point normals (from the depth
//! image's pixel neighbours, facing the camera) and colours (the colour image or the segment palette).
//!
//! "Only the person" (issue 11: a real person mask spills onto the floor and the wall, and those
//! pixels would be fitted as body): each camera fits its floor from all its valid depth pixels
//! ([`floor`]) — also a check of its calibration, reported and warned about — and drops the person
//! points on and just above it; then mask pixels on depth edges, far behind the person, or in 3-D
//! parts separate from the person are dropped ([`isolate`]); two comparable parts are an error
//! ([`FuseError::PersonNotIsolated`]), never a guess. Everything removed is counted in the report.
//!
//! The order is the paper's: outlier removal runs on each camera's whole person cloud (extremities
//! included); segments are dropped after merging. Points keep the row-major pixel order of each
//! camera, cameras in the order given.

mod deproject;
pub mod floor;
pub mod isolate;
mod params;
mod person;
pub mod plausible;
mod report;

pub use params::FuseParams;
pub use report::{CleaningReport, FloorAgreement, FloorReport, FloorStatus, FuseReport, ViewReport};

use crate::camera::{CameraError, Extrinsics, Intrinsics};
use crate::clean::{statistical_outliers, CleanError, SorParams};
use bsv_core::{PointCloud, Segment, SEGMENT_COUNT};
use deproject::{deproject_view, ViewPoints};
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
    /// The person mask holds two comparable separate 3-D parts: which one is the person is unknown.
    #[error("camera `{camera}`: the person cannot be isolated: the labelled pixels form two separate 3-D parts of {person_points} and {other_points} points, {distance_m:.2} m apart (a second person or a large object inside the person mask; parts of at least second_part_ratio = {ratio} of the person are not dropped silently); clear the scene around the subject and check the segmentation mask, or set isolate_person = false to keep every labelled point")]
    PersonNotIsolated {
        /// Camera name.
        camera: String,
        /// Points of the largest part.
        person_points: usize,
        /// Points of the second-largest part.
        other_points: usize,
        /// Distance between the two parts' centroids, metres.
        distance_m: f64,
        /// The `second_part_ratio` parameter.
        ratio: f64,
    },
    /// A view's person has no depth relief: a flat surface behind a person mask, not a person.
    #[error("camera `{camera}`: the person's points span only {relief_m:.3} m in depth (a standing person spans 0.15-0.35 m): the depth image shows a flat surface (a wall, a screen) where the mask sees a person; check that the depth and colour images of this camera belong to the same capture")]
    FlatView {
        /// Camera name.
        camera: String,
        /// 5-95 % depth range of the person's points, metres.
        relief_m: f64,
    },
    /// The subject's left limbs lie on the right in the world: the view is placed as its mirror.
    #[error("camera `{camera}`: the subject's left limbs lie at x = {left_x:.2} m and the right ones at x = {right_x:.2} m, but +X is the subject's left: the calibration or the camera folders are swapped (front <-> back) or this camera's extrinsics are mirrored; give each camera folder its own calibration")]
    MirroredView {
        /// Camera name.
        camera: String,
        /// Median x of the points labelled as left limbs, metres.
        left_x: f64,
        /// Median x of the points labelled as right limbs, metres.
        right_x: f64,
    },
    /// The cleaning removed every labelled point of a view.
    #[error("camera `{camera}`: all {deprojected} labelled points were removed as floor ({floor}), depth edges ({edges}) or far behind the person ({far}): the mask does not cover a person standing on the floor; check the segmentation and the calibration, or set remove_floor = false or isolate_person = false to diagnose")]
    NothingLeft {
        /// Camera name.
        camera: String,
        /// Labelled points with a valid depth.
        deprojected: usize,
        /// Removed as floor.
        floor: usize,
        /// Removed as depth edges.
        edges: usize,
        /// Removed as far.
        far: usize,
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
    // Views are cleaned in parallel, merged in input order; the first failing view's error wins.
    let fused: Vec<Result<(ViewPoints, ViewReport), FuseError>> =
        views.par_iter().map(|view| fuse_view(view, params)).collect();
    let mut world = ViewPoints::default();
    let mut reports = Vec::with_capacity(views.len());
    for f in fused {
        let (vp, mut report) = f?;
        report.dropped = append_to_world(&vp, params, &drop, &mut world);
        report.kept = vp.points.len() - report.dropped.values().sum::<usize>();
        reports.push(report);
    }
    if world.points.is_empty() {
        return Err(FuseError::EmptyCloud { dropped: params.drop_labels.iter().map(|&l| segment_name(l)).collect() });
    }
    let ViewPoints { points, normals, colors, labels, .. } = world;
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
    let floor_agreement = floor_agreement(&reports);
    let mut warnings: Vec<String> = reports.iter().flat_map(|r| r.warnings.iter().cloned()).collect();
    warnings.extend(floor_agreement.iter().filter_map(|a| a.warning(params)));
    let report = FuseReport {
        views: reports,
        floor_agreement,
        warnings,
        points: cloud.len(),
        points_per_segment: per_segment,
        dropped,
        seconds: t0.elapsed().as_secs_f64(),
    };
    Ok((cloud, report))
}

/// The floor agreement of every pair of views that both saw the floor.
fn floor_agreement(reports: &[ViewReport]) -> Vec<FloorAgreement> {
    let mut out = Vec::new();
    for (i, a) in reports.iter().enumerate() {
        for b in &reports[i + 1..] {
            out.extend(FloorAgreement::between((&a.name, &a.floor), (&b.name, &b.floor)));
        }
    }
    out
}

/// One view: deprojects its mask into the world, keeps only the person, removes its outliers; its
/// points and report (`dropped` and `kept` are filled when the points are merged).
fn fuse_view(view: &DepthView, params: &FuseParams) -> Result<(ViewPoints, ViewReport), FuseError> {
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
    let (floor, cleaning) = person::clean_view(view, params, &mut vp)?;
    let t = Instant::now();
    let mut sor_threshold_m = None;
    let mut sor_removed = 0;
    if params.sor {
        let res = statistical_outliers(&vp.points, SorParams { k: params.sor_k, std_ratio: params.sor_std_ratio })
            .map_err(|source| FuseError::Clean { camera: camera(), source })?;
        sor_threshold_m = res.threshold.is_finite().then_some(res.threshold);
        sor_removed = vp.retain(&res.keep);
    }
    let seconds_sor = t.elapsed().as_secs_f64();
    if params.check_plausible {
        plausible::check_view(view, &vp)?;
    }
    let warnings = floor.warnings(&view.name, params);
    let report = ViewReport {
        name: view.name.clone(),
        mask_pixels,
        no_depth,
        deprojected,
        floor,
        cleaning,
        sor_removed,
        sor_threshold_m,
        dropped: BTreeMap::new(),
        kept: 0,
        warnings,
        seconds_deproject,
        seconds_sor,
    };
    Ok((vp, report))
}

/// Appends the points whose label is not dropped to `world`; the count of dropped points per
/// segment name.
fn append_to_world(
    vp: &ViewPoints,
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
        world.points.push(p);
        if params.normals {
            world.normals.push(vp.normals[k]);
        }
        world.colors.push(vp.colors[k]);
        world.labels.push(l);
        world.pixels.push(vp.pixels[k]);
    }
    dropped
}
