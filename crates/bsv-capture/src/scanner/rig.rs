//! The two-camera rig, the capture conditions and the calibration-error model (DESIGN.md,
//! "Validation protocol").
//!
//! Axis mapping of the calibration error. DESIGN.md gives the paper's standard deviations in the
//! physical camera frame "x vertical, y transversal, z longitudinal": an L515 mounted in portrait has
//! its sensor's long (x) axis vertical. Our images are delivered upright (768 wide x 1024 high) in
//! the OpenCV frame of the *image* (+X right = transversal, +Y down = vertical, +Z = optical axis =
//! longitudinal). So paper (x, y, z) -> image (Y, X, Z): the paper's x translation/rotation std goes
//! to our camera Y axis, the paper's y to our X axis, z stays z (signs do not matter for zero-mean
//! normal errors). Example: the back camera's 0.28 deg about the vertical (paper x) is a yaw about
//! our camera Y axis.

use super::appearance::Look;
use super::room::Room;
use super::ScanError;
use crate::camera::{Extrinsics, Intrinsics};
use rand::Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// Capture condition of the validation protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Condition {
    /// Exact depth and extrinsics.
    NoEr,
    /// L515 depth noise and flying pixels.
    L515,
    /// Extrinsic (calibration) error per camera.
    Cali,
    /// Both depth noise and calibration error.
    L5Ca,
}

impl Condition {
    /// Every condition in protocol order.
    pub const ALL: [Condition; 4] = [Condition::NoEr, Condition::L515, Condition::Cali, Condition::L5Ca];

    /// The lower-case key ("noer", "l515", "cali", "l5ca").
    pub fn name(self) -> &'static str {
        match self {
            Condition::NoEr => "noer",
            Condition::L515 => "l515",
            Condition::Cali => "cali",
            Condition::L5Ca => "l5ca",
        }
    }

    /// True when depth noise and flying pixels are simulated.
    pub fn has_depth_noise(self) -> bool {
        matches!(self, Condition::L515 | Condition::L5Ca)
    }

    /// True when the extrinsics used for the cloud are wrong by a drawn error.
    pub fn has_calibration_error(self) -> bool {
        matches!(self, Condition::Cali | Condition::L5Ca)
    }
}

impl fmt::Display for Condition {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Condition {
    type Err = ScanError;
    /// Parses "noer", "l515", "cali", "l5ca" (case-insensitive).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let l = s.trim().to_ascii_lowercase();
        Condition::ALL.into_iter().find(|c| c.name() == l).ok_or_else(|| ScanError::UnknownCondition(s.to_string()))
    }
}

/// A rigid error of one camera's extrinsics, expressed in the camera (image) frame.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ExtrinsicError {
    /// Translation along camera x (right), y (down), z (forward), metres.
    pub translation_m: [f64; 3],
    /// Rotation vector about camera x, y, z, radians.
    pub rotation_rad: [f64; 3],
}

impl ExtrinsicError {
    /// The estimated (wrong) extrinsics: `true_extrinsics ∘ delta` (see [`Extrinsics::perturbed`]).
    pub fn apply(&self, true_extrinsics: &Extrinsics) -> Extrinsics {
        true_extrinsics.perturbed(self.translation_m, self.rotation_rad)
    }
}

/// Names of the 6 parameters of an extrinsics covariance, the order of its rows and columns: the
/// translation (metres) and the rotation vector (radians) of an [`ExtrinsicError`], camera frame.
pub const COVARIANCE_PARAMETERS: [&str; 6] = ["tx_m", "ty_m", "tz_m", "rx_rad", "ry_rad", "rz_rad"];

/// The parameterisation of an extrinsics covariance (that of [`ExtrinsicError::apply`]), written
/// next to every covariance in `calibration.json`.
pub const COVARIANCE_FRAME: &str = "delta in the camera frame (OpenCV: +X right, +Y down, +Z optical axis), \
composed on the right: R' = R Rodrigues(r), t' = R t_delta + t (camera_to_world)";

/// Standard deviations of a zero-mean normal extrinsic error, in the camera (image) frame.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ExtrinsicSigma {
    /// Translation std along camera x, y, z, metres.
    pub translation_m: [f64; 3],
    /// Rotation std about camera x, y, z, radians.
    pub rotation_rad: [f64; 3],
}

impl ExtrinsicSigma {
    /// From the paper's table: centimetres and degrees in the portrait camera's physical axes
    /// (x vertical, y transversal, z longitudinal), mapped to the image frame (module docs).
    pub fn from_paper(translation_cm: [f64; 3], rotation_deg: [f64; 3]) -> Self {
        Self::from_paper_axes(translation_cm.map(|c| c * 0.01), rotation_deg)
    }

    /// As [`ExtrinsicSigma::from_paper`] with the translations in millimetres: the metres are then the
    /// table's decimals exactly (3.4 mm gives 0.0034 m; 0.34 cm gives 0.0034000000000000002 m).
    pub fn from_paper_mm(translation_mm: [f64; 3], rotation_deg: [f64; 3]) -> Self {
        Self::from_paper_axes(translation_mm.map(|c| c / 1000.0), rotation_deg)
    }

    /// Metres and degrees in the paper's axes (x vertical, y transversal) to the image frame.
    fn from_paper_axes(t: [f64; 3], rotation_deg: [f64; 3]) -> Self {
        let r = rotation_deg.map(f64::to_radians);
        ExtrinsicSigma { translation_m: [t[1], t[0], t[2]], rotation_rad: [r[1], r[0], r[2]] }
    }

    /// The six standard deviations in [`COVARIANCE_PARAMETERS`] order.
    pub fn std(&self) -> [f64; 6] {
        let (t, r) = (self.translation_m, self.rotation_rad);
        [t[0], t[1], t[2], r[0], r[1], r[2]]
    }

    /// The covariance of the drawn error: diagonal 6 x 6, the variances in [`COVARIANCE_PARAMETERS`]
    /// order (every component is drawn independently).
    pub fn covariance(&self) -> [[f64; 6]; 6] {
        let std = self.std();
        let mut cov = [[0.0; 6]; 6];
        for (i, s) in std.iter().enumerate() {
            cov[i][i] = s * s;
        }
        cov
    }

    /// Draws one error, each component independent normal with its std.
    pub fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> ExtrinsicError {
        let mut e = ExtrinsicError::default();
        for a in 0..3 {
            let n: f64 = rng.sample(StandardNormal);
            e.translation_m[a] = n * self.translation_m[a];
        }
        for a in 0..3 {
            let n: f64 = rng.sample(StandardNormal);
            e.rotation_rad[a] = n * self.rotation_rad[a];
        }
        e
    }
}

/// L515-like depth noise model.
///
/// 1. Flying pixels: a pixel whose true depth differs from a 4-neighbour's by more than
///    `flying_jump` (or that borders a pixel with no return, whose "background" is taken
///    `silhouette_tail` metres behind it) is, with probability `flying_probability`, given the mixed
///    depth `z + w (z_other - z)`, `w ~ U(0, 1)`, where `z_other` is the neighbour depth differing
///    most (a ToF pixel straddling two surfaces returns a blend). It keeps its own label.
/// 2. Every valid pixel then gets Gaussian depth noise with std `sigma(z) = sigma_at_1m +
///    sigma_slope (z - 1 m)` (floored at 0), moving the point along its pixel ray.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DepthNoise {
    /// Depth std at 1 m, metres (2.5 mm).
    pub sigma_at_1m: f64,
    /// Increase of the std per metre of depth (1.625 mm/m).
    pub sigma_slope: f64,
    /// Depth jump between 4-neighbours that marks a discontinuity, metres.
    pub flying_jump: f64,
    /// Probability that a discontinuity pixel becomes a flying pixel.
    pub flying_probability: f64,
    /// Where the background is assumed behind a silhouette edge, metres (0 disables silhouette flying pixels).
    pub silhouette_tail: f64,
}

impl Default for DepthNoise {
    fn default() -> Self {
        DepthNoise {
            sigma_at_1m: 0.0025,
            sigma_slope: 0.001625,
            flying_jump: 0.05,
            flying_probability: 0.5,
            silhouette_tail: 0.3,
        }
    }
}

impl DepthNoise {
    /// The depth std at depth `z` metres.
    pub fn sigma(&self, z: f64) -> f64 {
        (self.sigma_at_1m + self.sigma_slope * (z - 1.0)).max(0.0)
    }

    /// Checks every value is finite, non-negative, the probability within [0, 1].
    pub fn validate(&self) -> Result<(), ScanError> {
        for (param, v) in [
            ("sigma_at_1m", self.sigma_at_1m),
            ("sigma_slope", self.sigma_slope),
            ("flying_jump", self.flying_jump),
            ("silhouette_tail", self.silhouette_tail),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ScanError::BadNoise { param, value: v });
            }
        }
        if !(0.0..=1.0).contains(&self.flying_probability) {
            return Err(ScanError::BadNoise { param: "flying_probability", value: self.flying_probability });
        }
        Ok(())
    }
}

/// One camera of the rig.
#[derive(Debug, Clone, PartialEq)]
pub struct RigCamera {
    /// Name used for output folders ("front", "back").
    pub name: String,
    /// Intrinsics of the depth image.
    pub intrinsics: Intrinsics,
    /// True camera-to-world extrinsics.
    pub camera_to_world: Extrinsics,
    /// Std of the calibration error drawn in the Cali/L5Ca conditions.
    pub calibration_sigma: ExtrinsicSigma,
}

/// A set of depth cameras and their noise model.
#[derive(Debug, Clone, PartialEq)]
pub struct Rig {
    /// The cameras, scanned in order (points of camera 0 first).
    pub cameras: Vec<RigCamera>,
    /// Depth noise of the L515/L5Ca conditions.
    pub noise: DepthNoise,
    /// The room around the subject; `None`: the body alone on an empty background.
    pub room: Option<Room>,
    /// Looks asked for beyond the seed's (with a room: [`super::Look`]).
    pub look: Look,
}

/// Image width of the portrait L515-like camera.
pub const PAPER_WIDTH: u32 = 768;
/// Image height of the portrait L515-like camera.
pub const PAPER_HEIGHT: u32 = 1024;
/// Horizontal field of view, degrees.
pub const PAPER_HFOV_DEG: f64 = 55.0;
/// Vertical field of view, degrees.
pub const PAPER_VFOV_DEG: f64 = 70.0;
/// Camera height above the floor, metres.
pub const PAPER_CAMERA_HEIGHT: f64 = 1.0;
/// Distance from each camera to the subject (midway), metres.
pub const PAPER_CAMERA_DISTANCE: f64 = 2.0;

impl Rig {
    /// The rig of DESIGN.md: two portrait L515-like cameras (768 x 1024, 55 x 70 deg), 1.0 m high,
    /// front at z = +2 m looking toward -Z, back at z = -2 m looking toward +Z, the paper's error stds.
    pub fn paper_default() -> Rig {
        // The constants are valid, so these cannot fail; fall back to a computed value regardless.
        let intr =
            Intrinsics::from_fov(PAPER_WIDTH, PAPER_HEIGHT, PAPER_HFOV_DEG, PAPER_VFOV_DEG).unwrap_or(Intrinsics {
                width: PAPER_WIDTH,
                height: PAPER_HEIGHT,
                fx: 737.6,
                fy: 731.2,
                cx: 383.5,
                cy: 511.5,
                k1: 0.0,
                k2: 0.0,
                p1: 0.0,
                p2: 0.0,
                k3: 0.0,
            });
        let h = PAPER_CAMERA_HEIGHT;
        let d = PAPER_CAMERA_DISTANCE;
        let cam = |name: &str, z: f64, sigma: ExtrinsicSigma| RigCamera {
            name: name.to_string(),
            intrinsics: intr,
            camera_to_world: Extrinsics::look_at([0.0, h, z], [0.0, h, 0.0], [0.0, 1.0, 0.0])
                .unwrap_or(Extrinsics::IDENTITY),
            calibration_sigma: sigma,
        };
        Rig {
            cameras: vec![
                // DESIGN.md "Cali" (cm there), in mm so the metres are exact decimals.
                cam("front", d, ExtrinsicSigma::from_paper_mm([1.1, 0.3, 0.6], [0.03, 0.01, 0.21])),
                cam("back", -d, ExtrinsicSigma::from_paper_mm([1.5, 0.2, 3.4], [0.28, 0.11, 0.10])),
            ],
            noise: DepthNoise::default(),
            room: None,
            look: Look::default(),
        }
    }

    /// This rig inside `room`.
    pub fn with_room(mut self, room: Room) -> Rig {
        self.room = Some(room);
        self
    }

    /// Checks every camera, the noise model and the room (every camera inside it).
    pub fn validate(&self) -> Result<(), ScanError> {
        if self.cameras.is_empty() {
            return Err(ScanError::NoCameras);
        }
        for c in &self.cameras {
            let wrap = |source| ScanError::Camera { camera: c.name.clone(), source };
            c.intrinsics.validate().map_err(wrap)?;
            c.camera_to_world.validate().map_err(wrap)?;
            for v in c.calibration_sigma.translation_m.iter().chain(&c.calibration_sigma.rotation_rad) {
                if !(v.is_finite() && *v >= 0.0) {
                    return Err(ScanError::BadNoise { param: "calibration_sigma", value: *v });
                }
            }
        }
        self.noise.validate()?;
        if let Some(room) = &self.room {
            room.validate()?;
            for c in &self.cameras {
                room.check_inside(&c.name, c.camera_to_world.translation)?;
            }
        }
        Ok(())
    }
}
