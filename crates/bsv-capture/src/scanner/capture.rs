//! Writing a virtual capture the way a real one is written, so the front-end can be tested
//! without a camera.
//!
//! Layout of `dir`:
//! - `<camera>/depth.png`: 16-bit depth, metres = value x `depth_scale` (0.00025, like the L515), 0 = none;
//! - `<camera>/color.png`: 8-bit RGB, the body in a Lambert-shaded skin tone on a mid-grey background,
//!   or, for a scan with a room, the subject and the room as its [`super::Appearance`] paints them (blurred
//!   and noisy as a sensor records it with [`super::Look::colour_sensor`]);
//! - `<camera>/labels.png`: 8-bit grey, the segment id of each pixel (0 = background/unlabelled);
//! - `<camera>/camera.json`: [`CaptureCamera`] (intrinsics, the estimated extrinsics a calibration
//!   would give, the true ones, the applied error, the depth scale, file names);
//! - `calibration.json`: `{"cameras": {"front": {"intrinsics", "camera_to_world",
//!   "extrinsics_covariance"}, "back": ...}}` with the estimated extrinsics and their covariance
//!   ([`ExtrinsicsCovariance`]: the spread the rig drew the calibration error from, zero in noer/l515);
//! - `scan.json`: condition, seed, cameras, the cloud's size and each camera's range of it
//!   (`camera_points`: name -> [start, end)) and, with a room, the subject's look and the lights
//!   (`appearance`: [`super::Appearance`]).

use super::appearance::{COLOUR_BLUR_PX, COLOUR_READ_NOISE, COLOUR_SHOT_NOISE};
use super::{
    Appearance, CameraView, ExtrinsicError, ExtrinsicSigma, Scan, ScanError, SurfaceKind, SurfacePixel,
    COVARIANCE_FRAME, COVARIANCE_PARAMETERS,
};
use crate::camera::{CameraCalibration, Extrinsics, Intrinsics};
use image::{ImageBuffer, Luma, Rgb};
use rand::{Rng, SeedableRng};
use rand_distr::StandardNormal;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Depth units of the written 16-bit depth PNG, metres per unit (L515 default).
pub const DEPTH_SCALE: f64 = 0.00025;

/// Skin tone of the colour render (sRGB).
const SKIN: [f64; 3] = [224.0, 172.0, 140.0];
/// Background grey of the colour render.
const BACKGROUND: [u8; 3] = [128, 128, 128];

/// Contents of `<camera>/camera.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaptureCamera {
    /// Camera name.
    pub name: String,
    /// Intrinsics of the depth, colour and label images (aligned).
    pub intrinsics: Intrinsics,
    /// Camera-to-world extrinsics as calibrated (the estimated ones).
    pub camera_to_world: Extrinsics,
    /// The true camera-to-world extrinsics (ground truth, virtual captures only).
    pub true_camera_to_world: Extrinsics,
    /// The calibration error applied (camera frame).
    pub extrinsic_error: ExtrinsicError,
    /// Metres per unit of `depth.png`.
    pub depth_scale: f64,
    /// Depth image file name.
    pub depth: String,
    /// Colour image file name.
    pub color: String,
    /// Label image file name.
    pub labels: String,
}

/// The `extrinsics_covariance` entry of a camera in `calibration.json`: the 6 x 6 covariance of its
/// extrinsics (the format `bsv.frontend.calibrate` writes and `bsv.uncertainty` reads).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExtrinsicsCovariance {
    /// Names of the rows and columns ([`COVARIANCE_PARAMETERS`]).
    pub parameters: Vec<String>,
    /// The parameterisation ([`COVARIANCE_FRAME`]).
    pub frame: String,
    /// The 6 x 6 covariance.
    pub matrix: [[f64; 6]; 6],
    /// Where it comes from.
    pub source: String,
}

impl ExtrinsicsCovariance {
    /// The covariance of an error drawn with `sigma`; `exact`: the extrinsics are exact (no error
    /// drawn), else drawn from the paper's repeatability (the rig's calibration sigmas).
    pub fn of_virtual_rig(sigma: &ExtrinsicSigma, exact: bool) -> Self {
        let source = if exact { "virtual rig: exact extrinsics" } else { "virtual rig: the paper's repeatability" };
        ExtrinsicsCovariance {
            parameters: COVARIANCE_PARAMETERS.iter().map(|p| p.to_string()).collect(),
            frame: COVARIANCE_FRAME.to_string(),
            matrix: sigma.covariance(),
            source: source.to_string(),
        }
    }
}

/// One camera of `calibration.json`.
#[derive(Serialize)]
struct CalibrationEntry {
    #[serde(flatten)]
    calibration: CameraCalibration,
    extrinsics_covariance: ExtrinsicsCovariance,
}

#[derive(Serialize)]
struct CalibrationFile {
    cameras: BTreeMap<String, CalibrationEntry>,
}

#[derive(Serialize)]
struct ScanInfo<'a> {
    condition: &'a str,
    seed: u64,
    cameras: Vec<&'a str>,
    n_points: usize,
    /// Per camera, the half-open range `[start, end)` of its points in the scan's merged cloud (the
    /// cloud is the cameras' points in this order): lets a consumer re-express each camera's points
    /// with other extrinsics (a refined calibration) without re-scanning.
    camera_points: BTreeMap<&'a str, [usize; 2]>,
    /// With a room: how the colour render painted the subject and lit the scene (skin, underwear, hair,
    /// lights), so that a benchmark can group its results by look.
    #[serde(skip_serializing_if = "Option::is_none")]
    appearance: Option<&'a Appearance>,
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ScanError + '_ {
    move |source| ScanError::Io { path: path.to_path_buf(), source }
}

/// Writes `value` as pretty JSON to `path` atomically: a hidden temporary file beside it, renamed
/// over it once complete.
fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), ScanError> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| ScanError::Io { path: path.to_path_buf(), source: std::io::Error::other(e) })?;
    let name = path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.tmp"));
    std::fs::write(&tmp, text + "\n").map_err(io_err(&tmp))?;
    std::fs::rename(&tmp, path).map_err(io_err(path))
}

fn image_err(path: &Path) -> impl FnOnce(image::ImageError) -> ScanError + '_ {
    move |e| ScanError::Image { path: path.to_path_buf(), message: e.to_string() }
}

/// The plain render (no room): the body in a Lambert-shaded skin tone on mid-grey.
fn plain_colour(view: &CameraView) -> Vec<u8> {
    let mut rgb = Vec::with_capacity(view.depth.len() * 3);
    for (z, s) in view.depth.iter().zip(&view.shade) {
        if *z > 0.0 {
            let f = 0.3 + 0.7 * f64::from(*s);
            rgb.extend(SKIN.map(|c| (c * f).round().clamp(0.0, 255.0) as u8));
        } else {
            rgb.extend(BACKGROUND);
        }
    }
    rgb
}

/// Stream id of the colour sensor's noise draws.
const STREAM_COLOUR: u64 = 0xC010;

/// The colour a sensor records of the exact render `rgb` (`width` pixels a row): blurred by
/// [`COLOUR_BLUR_PX`], then per pixel and channel Gaussian noise of variance `READ^2 + SHOT x level`;
/// deterministic for `seed` (one generator per image row).
fn sensor_colour(rgb: Vec<u8>, width: u32, height: u32, seed: u64) -> Vec<u8> {
    // A buffer of the wrong size comes back empty, and writing it fails with the size error.
    let Some(img) = ImageBuffer::<Rgb<u8>, _>::from_raw(width, height, rgb) else { return Vec::new() };
    let mut out = image::imageops::blur(&img, COLOUR_BLUR_PX).into_raw();
    let row = 3 * width as usize;
    out.par_chunks_mut(row).enumerate().for_each(|(v, px)| {
        let mut rng = rand::rngs::StdRng::seed_from_u64(super::mix_seed(seed, STREAM_COLOUR, v as u64));
        for c in px.iter_mut() {
            let level = f64::from(*c);
            let n: f64 = rng.sample(StandardNormal);
            let sd = (COLOUR_READ_NOISE * COLOUR_READ_NOISE + COLOUR_SHOT_NOISE * level).sqrt();
            *c = (level + n * sd).round().clamp(0.0, 255.0) as u8;
        }
    });
    out
}

/// The colour image of `view` (the scan's camera `index`): with a room, every pixel shaded by the scan's
/// [`Appearance`] (the true surface, so a flying pixel keeps its surface's colour), as a sensor records it
/// with [`super::Look::colour_sensor`]; else [`plain_colour`].
fn colour_image(scan: &Scan, view: &CameraView, index: usize) -> Vec<u8> {
    let (Some((app, heights)), Some(surf)) = (&scan.appearance, &view.surface) else {
        return plain_colour(view);
    };
    let f = |a: [f32; 3]| a.map(f64::from);
    let mut rgb = Vec::with_capacity(surf.kind.len() * 3);
    for i in 0..surf.kind.len() {
        let px = SurfacePixel {
            kind: SurfaceKind::from_code(surf.kind[i]),
            label: view.labels.get(i).copied().unwrap_or(0),
            point: f(surf.point[i]),
            normal: f(surf.normal[i]),
        };
        rgb.extend(app.shade(heights, &px));
    }
    if app.colour_sensor {
        let seed = super::mix_seed(scan.seed, STREAM_COLOUR, index as u64);
        return sensor_colour(rgb, view.intrinsics.width, view.intrinsics.height, seed);
    }
    rgb
}

/// Writes the capture folder described in the module docs (creating `dir` and sub-folders).
pub fn write_capture(scan: &Scan, dir: &Path) -> Result<(), ScanError> {
    std::fs::create_dir_all(dir).map_err(io_err(dir))?;
    let mut calibration = BTreeMap::new();
    for (index, view) in scan.views.iter().enumerate() {
        let cdir = dir.join(&view.name);
        std::fs::create_dir_all(&cdir).map_err(io_err(&cdir))?;
        let (w, h) = (view.intrinsics.width, view.intrinsics.height);
        let size_err = |p: &Path| ScanError::Image {
            path: p.to_path_buf(),
            message: "image size does not match the intrinsics".into(),
        };

        let depth_path = cdir.join("depth.png");
        let raw: Vec<u16> = view
            .depth
            .iter()
            .map(|&z| if z > 0.0 { (f64::from(z) / DEPTH_SCALE).round().clamp(1.0, 65535.0) as u16 } else { 0 })
            .collect();
        let img: ImageBuffer<Luma<u16>, _> = ImageBuffer::from_raw(w, h, raw).ok_or_else(|| size_err(&depth_path))?;
        img.save(&depth_path).map_err(image_err(&depth_path))?;

        let color_path = cdir.join("color.png");
        let rgb = colour_image(scan, view, index);
        let img: ImageBuffer<Rgb<u8>, _> = ImageBuffer::from_raw(w, h, rgb).ok_or_else(|| size_err(&color_path))?;
        img.save(&color_path).map_err(image_err(&color_path))?;

        let label_path = cdir.join("labels.png");
        let img: ImageBuffer<Luma<u8>, _> =
            ImageBuffer::from_raw(w, h, view.labels.clone()).ok_or_else(|| size_err(&label_path))?;
        img.save(&label_path).map_err(image_err(&label_path))?;

        let cam = CaptureCamera {
            name: view.name.clone(),
            intrinsics: view.intrinsics,
            camera_to_world: view.estimated_extrinsics,
            true_camera_to_world: view.true_extrinsics,
            extrinsic_error: view.error,
            depth_scale: DEPTH_SCALE,
            depth: "depth.png".into(),
            color: "color.png".into(),
            labels: "labels.png".into(),
        };
        write_json(&cdir.join("camera.json"), &cam)?;
        calibration.insert(
            view.name.clone(),
            CalibrationEntry {
                calibration: CameraCalibration {
                    intrinsics: view.intrinsics,
                    camera_to_world: view.estimated_extrinsics,
                },
                extrinsics_covariance: ExtrinsicsCovariance::of_virtual_rig(
                    &view.error_sigma,
                    !scan.condition.has_calibration_error(),
                ),
            },
        );
    }
    write_json(&dir.join("calibration.json"), &CalibrationFile { cameras: calibration })?;
    let info = ScanInfo {
        condition: scan.condition.name(),
        seed: scan.seed,
        cameras: scan.views.iter().map(|v| v.name.as_str()).collect(),
        n_points: scan.cloud.len(),
        camera_points: scan.views.iter().map(|v| (v.name.as_str(), [v.cloud_range.start, v.cloud_range.end])).collect(),
        appearance: scan.appearance.as_ref().map(|(a, _)| a),
    };
    write_json(&dir.join("scan.json"), &info)
}
