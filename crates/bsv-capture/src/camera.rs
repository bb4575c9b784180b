//! Pinhole camera model: intrinsics with Brown-Conrady distortion, camera-to-world extrinsics,
//! projection, deprojection and whole depth-image deprojection.
//!
//! Camera frame: OpenCV/RealSense, +X right, +Y down, +Z along the optical axis. Pixel coordinates
//! address pixel centres: pixel (u, v) = column u, row v, the image spans [-0.5, width - 0.5].
//! Depth means z along the optical axis (as RealSense depth images), not distance along the ray.

use bsv_core::geometry::{add, cross, dot, norm, normalize, scale, sub};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Errors of the camera model: which parameter is wrong and what to do.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// A parameter that must be a finite number is NaN or infinite.
    #[error("camera parameter `{param}` is {value}, not a finite number: give a finite value (check the calibration/intrinsics file)")]
    NonFinite {
        /// Parameter name (e.g. `fx`, `rotation[1][2]`).
        param: String,
        /// The offending value.
        value: f64,
    },
    /// A parameter that must be strictly positive is zero or negative.
    #[error("camera parameter `{param}` is {value}, it must be > 0: give the image size in pixels and focal lengths in pixels")]
    NonPositive {
        /// Parameter name.
        param: String,
        /// The offending value.
        value: f64,
    },
    /// A field of view outside (0, 180) degrees.
    #[error("field of view `{param}` is {value} deg, it must lie strictly between 0 and 180 deg")]
    BadFov {
        /// "horizontal_fov_deg" or "vertical_fov_deg".
        param: String,
        /// The offending value.
        value: f64,
    },
    /// The extrinsic rotation is not a proper rotation matrix.
    #[error("camera_to_world.rotation is not a rotation (orthonormality error {error:.2e}, det {det:.4}): give an orthonormal 3x3 matrix with determinant +1, row-major")]
    NotRotation {
        /// Max |R^T R - I| entry.
        error: f64,
        /// Determinant.
        det: f64,
    },
    /// `look_at` got an eye equal to the target or an up vector parallel to the view direction.
    #[error("look_at is degenerate: eye and target coincide or `up` is parallel to the viewing direction; move the target or choose another up vector")]
    DegenerateLookAt,
    /// A depth image whose length does not match width x height.
    #[error("depth image has {got} values but the intrinsics say {width} x {height} = {expected}: use the intrinsics of the image the depth is aligned to")]
    DepthSize {
        /// Values found.
        got: usize,
        /// Expected width * height.
        expected: usize,
        /// Intrinsics width.
        width: u32,
        /// Intrinsics height.
        height: u32,
    },
    /// A JSON document that does not parse as a camera calibration.
    #[error("camera JSON does not parse ({0}): expected {{\"intrinsics\": {{...}}, \"camera_to_world\": {{\"rotation\": [[..]], \"translation\": [..]}}}}")]
    Json(String),
}

/// Pinhole intrinsics in pixels with Brown-Conrady distortion (OpenCV order k1, k2, p1, p2, k3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point x, pixels (pixel-centre convention).
    pub cx: f64,
    /// Principal point y, pixels.
    pub cy: f64,
    /// Radial coefficient r^2.
    #[serde(default)]
    pub k1: f64,
    /// Radial coefficient r^4.
    #[serde(default)]
    pub k2: f64,
    /// Tangential coefficient p1.
    #[serde(default)]
    pub p1: f64,
    /// Tangential coefficient p2.
    #[serde(default)]
    pub p2: f64,
    /// Radial coefficient r^6.
    #[serde(default)]
    pub k3: f64,
}

fn check_finite(param: &str, value: f64) -> Result<(), CameraError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(CameraError::NonFinite { param: param.to_string(), value })
    }
}

fn check_positive(param: &str, value: f64) -> Result<(), CameraError> {
    check_finite(param, value)?;
    if value > 0.0 {
        Ok(())
    } else {
        Err(CameraError::NonPositive { param: param.to_string(), value })
    }
}

impl Intrinsics {
    /// Distortion-free intrinsics from the image size and the full horizontal and vertical
    /// fields of view (degrees, edge to edge); the principal point is the image centre.
    pub fn from_fov(width: u32, height: u32, hfov_deg: f64, vfov_deg: f64) -> Result<Self, CameraError> {
        for (param, v) in [("horizontal_fov_deg", hfov_deg), ("vertical_fov_deg", vfov_deg)] {
            check_finite(param, v)?;
            if !(v > 0.0 && v < 180.0) {
                return Err(CameraError::BadFov { param: param.to_string(), value: v });
            }
        }
        check_positive("width", f64::from(width))?;
        check_positive("height", f64::from(height))?;
        let fx = 0.5 * f64::from(width) / (0.5 * hfov_deg.to_radians()).tan();
        let fy = 0.5 * f64::from(height) / (0.5 * vfov_deg.to_radians()).tan();
        let intr = Intrinsics {
            width,
            height,
            fx,
            fy,
            cx: 0.5 * (f64::from(width) - 1.0),
            cy: 0.5 * (f64::from(height) - 1.0),
            k1: 0.0,
            k2: 0.0,
            p1: 0.0,
            p2: 0.0,
            k3: 0.0,
        };
        intr.validate()?;
        Ok(intr)
    }

    /// Checks sizes and focal lengths are positive and every value finite.
    pub fn validate(&self) -> Result<(), CameraError> {
        check_positive("width", f64::from(self.width))?;
        check_positive("height", f64::from(self.height))?;
        check_positive("fx", self.fx)?;
        check_positive("fy", self.fy)?;
        for (p, v) in [
            ("cx", self.cx),
            ("cy", self.cy),
            ("k1", self.k1),
            ("k2", self.k2),
            ("p1", self.p1),
            ("p2", self.p2),
            ("k3", self.k3),
        ] {
            check_finite(p, v)?;
        }
        Ok(())
    }

    /// Number of pixels (width x height).
    pub fn n_pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// True when every distortion coefficient is zero.
    pub fn is_distortion_free(&self) -> bool {
        self.k1 == 0.0 && self.k2 == 0.0 && self.p1 == 0.0 && self.p2 == 0.0 && self.k3 == 0.0
    }

    /// Applies the distortion to normalised coordinates (x/z, y/z).
    pub fn distort(&self, x: f64, y: f64) -> [f64; 2] {
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
        [
            x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x),
            y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y,
        ]
    }

    /// Inverts [`Intrinsics::distort`] by Newton iterations (exact to ~1e-14 for realistic lenses).
    pub fn undistort(&self, xd: f64, yd: f64) -> [f64; 2] {
        if self.is_distortion_free() {
            return [xd, yd];
        }
        let (mut x, mut y) = (xd, yd);
        for _ in 0..30 {
            let r2 = x * x + y * y;
            let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
            let d_radial = self.k1 + r2 * (2.0 * self.k2 + 3.0 * self.k3 * r2);
            let [fx, fy] = self.distort(x, y);
            let (ex, ey) = (fx - xd, fy - yd);
            if ex.abs() < 1e-15 && ey.abs() < 1e-15 {
                break;
            }
            let a = radial + 2.0 * x * x * d_radial + 2.0 * self.p1 * y + 6.0 * self.p2 * x;
            let b = 2.0 * x * y * d_radial + 2.0 * self.p1 * x + 2.0 * self.p2 * y;
            let c = 2.0 * x * y * d_radial + 2.0 * self.p1 * x + 2.0 * self.p2 * y;
            let d = radial + 2.0 * y * y * d_radial + 6.0 * self.p1 * y + 2.0 * self.p2 * x;
            let det = a * d - b * c;
            if det.abs() < 1e-12 || !det.is_finite() {
                break;
            }
            x -= (d * ex - b * ey) / det;
            y -= (-c * ex + a * ey) / det;
        }
        [x, y]
    }

    /// Projects a camera-frame point to pixel coordinates (with distortion); `None` when z <= 0.
    pub fn project(&self, p: [f64; 3]) -> Option<[f64; 2]> {
        if p[2].is_nan() || p[2] <= 0.0 {
            return None;
        }
        let [xd, yd] = self.distort(p[0] / p[2], p[1] / p[2]);
        Some([self.fx * xd + self.cx, self.fy * yd + self.cy])
    }

    /// The camera-frame point seen at `pixel` with depth `depth` (z along the optical axis).
    pub fn deproject(&self, pixel: [f64; 2], depth: f64) -> [f64; 3] {
        let [x, y] = self.pixel_ray(pixel);
        [x * depth, y * depth, depth]
    }

    /// Normalised ray (x/z, y/z) of a pixel, distortion removed.
    pub fn pixel_ray(&self, pixel: [f64; 2]) -> [f64; 2] {
        self.undistort((pixel[0] - self.cx) / self.fx, (pixel[1] - self.cy) / self.fy)
    }
}

/// A depth sample type of a depth image: raw `u16` units or `f32` (metres or other units).
pub trait DepthValue: Copy + Send + Sync {
    /// The depth in units (multiplied by the depth scale to get metres); 0 or non-finite = no data.
    fn units(self) -> f64;
}

impl DepthValue for u16 {
    fn units(self) -> f64 {
        f64::from(self)
    }
}

impl DepthValue for f32 {
    fn units(self) -> f64 {
        f64::from(self)
    }
}

impl DepthValue for f64 {
    fn units(self) -> f64 {
        self
    }
}

/// Deprojects a row-major depth image (`depth[v * width + u]`, metres = value x `depth_scale`;
/// 0 or non-finite = no data) into camera-frame points, returned with their pixel index.
pub fn deproject_depth<D: DepthValue>(
    depth: &[D],
    intr: &Intrinsics,
    depth_scale: f64,
) -> Result<Vec<(usize, [f64; 3])>, CameraError> {
    intr.validate()?;
    check_positive("depth_scale", depth_scale)?;
    if depth.len() != intr.n_pixels() {
        return Err(CameraError::DepthSize {
            got: depth.len(),
            expected: intr.n_pixels(),
            width: intr.width,
            height: intr.height,
        });
    }
    let w = intr.width as usize;
    let rows: Vec<Vec<(usize, [f64; 3])>> = depth
        .par_chunks(w)
        .enumerate()
        .map(|(v, row)| {
            row.iter()
                .enumerate()
                .filter_map(|(u, d)| {
                    let z = d.units() * depth_scale;
                    (z > 0.0 && z.is_finite()).then(|| (v * w + u, intr.deproject([u as f64, v as f64], z)))
                })
                .collect()
        })
        .collect();
    Ok(rows.into_iter().flatten().collect())
}

/// A rigid transform; as camera extrinsics it maps camera-frame points to the world:
/// `p_world = rotation * p_cam + translation` (rotation row-major, its columns are the camera
/// axes in world coordinates, translation is the camera centre).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Extrinsics {
    /// 3x3 rotation, row-major.
    pub rotation: [[f64; 3]; 3],
    /// Translation, metres.
    pub translation: [f64; 3],
}

impl Default for Extrinsics {
    fn default() -> Self {
        Extrinsics::IDENTITY
    }
}

/// Rotation matrix of a rotation vector (axis * angle, radians), Rodrigues' formula.
pub fn rotation_from_vector(w: [f64; 3]) -> [[f64; 3]; 3] {
    let theta = norm(w);
    if theta < 1e-300 {
        return Extrinsics::IDENTITY.rotation;
    }
    let k = scale(w, 1.0 / theta);
    let (s, c) = theta.sin_cos();
    let t = 1.0 - c;
    [
        [c + k[0] * k[0] * t, k[0] * k[1] * t - k[2] * s, k[0] * k[2] * t + k[1] * s],
        [k[1] * k[0] * t + k[2] * s, c + k[1] * k[1] * t, k[1] * k[2] * t - k[0] * s],
        [k[2] * k[0] * t - k[1] * s, k[2] * k[1] * t + k[0] * s, c + k[2] * k[2] * t],
    ]
}

fn mat_vec(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

fn mat_mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut r = [[0.0; 3]; 3];
    for (i, row) in r.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    r
}

fn transpose(a: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    [[a[0][0], a[1][0], a[2][0]], [a[0][1], a[1][1], a[2][1]], [a[0][2], a[1][2], a[2][2]]]
}

impl Extrinsics {
    /// The identity transform.
    pub const IDENTITY: Extrinsics =
        Extrinsics { rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], translation: [0.0; 3] };

    /// Camera-to-world extrinsics of a camera at `eye` looking at `target`, image "up" toward `up`
    /// (OpenCV frame: camera +Z toward the target, +Y down = -up projected).
    pub fn look_at(eye: [f64; 3], target: [f64; 3], up: [f64; 3]) -> Result<Self, CameraError> {
        for (name, v) in [("eye", eye), ("target", target), ("up", up)] {
            for (k, x) in v.iter().enumerate() {
                check_finite(&format!("{name}[{k}]"), *x)?;
            }
        }
        let f = sub(target, eye);
        if norm(f) < 1e-12 {
            return Err(CameraError::DegenerateLookAt);
        }
        let z = normalize(f);
        let up_perp = sub(up, scale(z, dot(up, z)));
        if norm(up_perp) < 1e-9 * norm(up).max(1e-300) || norm(up) == 0.0 {
            return Err(CameraError::DegenerateLookAt);
        }
        let y = scale(normalize(up_perp), -1.0);
        let x = cross(y, z);
        Ok(Extrinsics { rotation: [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]], translation: eye })
    }

    /// Checks every value is finite and the rotation is orthonormal with det +1 (tolerance 1e-6).
    pub fn validate(&self) -> Result<(), CameraError> {
        for i in 0..3 {
            check_finite(&format!("translation[{i}]"), self.translation[i])?;
            for j in 0..3 {
                check_finite(&format!("rotation[{i}][{j}]"), self.rotation[i][j])?;
            }
        }
        let rtr = mat_mul(&transpose(&self.rotation), &self.rotation);
        let mut err = 0.0f64;
        for (i, row) in rtr.iter().enumerate() {
            for (j, x) in row.iter().enumerate() {
                err = err.max((x - if i == j { 1.0 } else { 0.0 }).abs());
            }
        }
        let r = &self.rotation;
        let det = dot(r[0], cross(r[1], r[2]));
        if err > 1e-6 || (det - 1.0).abs() > 1e-6 {
            return Err(CameraError::NotRotation { error: err, det });
        }
        Ok(())
    }

    /// Applies the transform to a point.
    pub fn transform_point(&self, p: [f64; 3]) -> [f64; 3] {
        add(mat_vec(&self.rotation, p), self.translation)
    }

    /// Applies the rotation only (for directions).
    pub fn transform_vector(&self, v: [f64; 3]) -> [f64; 3] {
        mat_vec(&self.rotation, v)
    }

    /// The inverse transform (world-to-camera for camera-to-world extrinsics).
    pub fn inverse(&self) -> Extrinsics {
        let rt = transpose(&self.rotation);
        let t = mat_vec(&rt, self.translation);
        Extrinsics { rotation: rt, translation: scale(t, -1.0) }
    }

    /// Composition `self ∘ other`: applies `other` first, then `self`.
    pub fn compose(&self, other: &Extrinsics) -> Extrinsics {
        Extrinsics {
            rotation: mat_mul(&self.rotation, &other.rotation),
            translation: self.transform_point(other.translation),
        }
    }

    /// The camera's viewing direction (+Z of the camera) in world coordinates.
    pub fn forward(&self) -> [f64; 3] {
        [self.rotation[0][2], self.rotation[1][2], self.rotation[2][2]]
    }

    /// These extrinsics perturbed in the camera's own frame: the camera moves by `translation`
    /// (metres, along camera x, y, z) and turns by the rotation vector `rotation` (radians about
    /// camera x, y, z). Returns `self ∘ delta` with `delta(p) = R(rotation) p + translation`.
    pub fn perturbed(&self, translation: [f64; 3], rotation: [f64; 3]) -> Extrinsics {
        self.compose(&Extrinsics { rotation: rotation_from_vector(rotation), translation })
    }
}

/// One camera's calibration as stored in `calibration.json` / `camera.json`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CameraCalibration {
    /// Intrinsics of the (colour-aligned) depth image.
    pub intrinsics: Intrinsics,
    /// Camera-to-world extrinsics.
    pub camera_to_world: Extrinsics,
}

impl CameraCalibration {
    /// Parses and validates the JSON form.
    pub fn from_json(text: &str) -> Result<Self, CameraError> {
        let c: CameraCalibration = serde_json::from_str(text).map_err(|e| CameraError::Json(e.to_string()))?;
        c.intrinsics.validate()?;
        c.camera_to_world.validate()?;
        Ok(c)
    }

    /// Pretty JSON text.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}
