//! The virtual two-camera depth scanner of the validation protocol (DESIGN.md).
//!
//! Each camera casts one ray per pixel at the mesh (parry BVH, rayon over rows) with its TRUE
//! extrinsics, records the depth (z along the optical axis), the hit face's segment label and a
//! Lambert shade. In `l515`/`l5ca` the depth gets flying pixels and Gaussian noise
//! ([`DepthNoise`]). The depth is back-projected along the pixel rays and transformed to the world
//! with the ESTIMATED extrinsics, which in `cali`/`l5ca` are the true ones perturbed by a drawn
//! [`ExtrinsicError`]: the cloud is what a miscalibrated rig would give. Deterministic for a seed.
//! [`write_capture`] writes what a real capture writes (depth/colour/label PNGs, camera JSON).
//!
//! With a [`Room`] on the rig, each ray is also cast at the room's own BVH and the nearer hit kept:
//! room pixels carry depth (with the same noise and flying pixels, so pixels straddling the body and
//! the wall appear) but label 0, and the scan's cloud keeps only the body's pixels (an oracle person
//! mask). The colour render then uses an [`Appearance`] drawn from the seed.

mod appearance;
mod capture;
mod cast;
mod noise;
mod rig;
mod room;

pub use appearance::{
    Appearance, BodyHeights, Light, LightSetup, Look, SurfacePixel, UnderwearStyle, COLOUR_BLUR_PX, COLOUR_READ_NOISE,
    COLOUR_SHOT_NOISE, LONG_HAIR_DOWN_M, LONG_HAIR_HALF_WIDTH_M, SKIN_TONES, TOP_BAND,
};
pub use capture::{write_capture, CaptureCamera, ExtrinsicsCovariance, DEPTH_SCALE};
pub use cast::SurfaceImage;
pub use rig::{
    Condition, DepthNoise, ExtrinsicError, ExtrinsicSigma, Rig, RigCamera, COVARIANCE_FRAME, COVARIANCE_PARAMETERS,
    PAPER_CAMERA_DISTANCE, PAPER_CAMERA_HEIGHT, PAPER_HEIGHT, PAPER_HFOV_DEG, PAPER_VFOV_DEG, PAPER_WIDTH,
};
pub use room::{Room, RoomObject, SurfaceKind};

use crate::camera::{CameraError, Extrinsics, Intrinsics};
use bsv_core::labels::face_labels_from_vertices;
use bsv_core::{MeshInvariant, PointCloud, Segment, TriMesh};
use parry3d_f64::math::Vector;
use rand::SeedableRng;
use rayon::prelude::*;
use room::RoomScene;
use std::ops::Range;
use std::path::PathBuf;

/// Errors of the virtual scanner.
#[derive(Debug, thiserror::Error)]
pub enum ScanError {
    /// The mesh has no triangle.
    #[error("mesh to scan has no triangles: load a non-empty surface mesh")]
    EmptyMesh,
    /// A triangle refers to a vertex that does not exist.
    #[error("mesh to scan: {0}: repair the mesh file")]
    Mesh(#[from] MeshInvariant),
    /// A vertex has a NaN or infinite coordinate.
    #[error("mesh vertex {0} has a non-finite coordinate: repair the mesh file")]
    NonFiniteVertex(usize),
    /// A label array whose length does not match.
    #[error("mesh {what} has {got} entries but the mesh has {expected}: fix or drop the labels")]
    LabelCount {
        /// "face_labels" or "vertex_labels".
        what: &'static str,
        /// Entries found.
        got: usize,
        /// Entries expected.
        expected: usize,
    },
    /// parry refused the mesh.
    #[error("building the ray-casting structure failed ({0}): check the mesh triangles")]
    Parry(String),
    /// The rig has no camera.
    #[error("the rig has no camera: use Rig::paper_default() or add cameras")]
    NoCameras,
    /// A camera of the rig has bad parameters.
    #[error("camera `{camera}`: {source}")]
    Camera {
        /// Camera name.
        camera: String,
        /// What is wrong.
        #[source]
        source: CameraError,
    },
    /// A noise or error-model parameter is out of range.
    #[error("scanner noise parameter `{param}` is {value}: use a finite value >= 0 (probabilities within [0, 1])")]
    BadNoise {
        /// Parameter name.
        param: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A room parameter is out of range.
    #[error("room parameter `{param}` is {value}: {remedy}")]
    BadRoom {
        /// Parameter name.
        param: &'static str,
        /// The offending value.
        value: f64,
        /// What to do.
        remedy: &'static str,
    },
    /// A camera of the rig stands outside the room.
    #[error("camera `{camera}` is outside the room (room parameter `{param}`): {remedy}")]
    CameraOutsideRoom {
        /// Camera name.
        camera: String,
        /// The room parameter that puts it outside.
        param: &'static str,
        /// What to do.
        remedy: &'static str,
    },
    /// An unknown condition name.
    #[error("unknown scan condition `{0}`: use one of noer, l515, cali, l5ca")]
    UnknownCondition(String),
    /// A file could not be written.
    #[error("cannot write {path}: {source}; check the output folder exists and is writable")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// An image could not be encoded or written.
    #[error("cannot write image {path}: {message}; check the output folder is writable")]
    Image {
        /// The image file.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
}

/// What one camera of a scan saw.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraView {
    /// Camera name ("front", "back").
    pub name: String,
    /// Intrinsics of the images.
    pub intrinsics: Intrinsics,
    /// True camera-to-world extrinsics (used for ray casting).
    pub true_extrinsics: Extrinsics,
    /// Estimated camera-to-world extrinsics (used to build the cloud; = true in noer/l515).
    pub estimated_extrinsics: Extrinsics,
    /// The applied calibration error (zero in noer/l515).
    pub error: ExtrinsicError,
    /// The spread `error` was drawn from: the rig camera's calibration sigma in cali/l5ca, zero in
    /// noer/l515 (exact extrinsics). `calibration.json` records it as the extrinsics covariance.
    pub error_sigma: ExtrinsicSigma,
    /// Measured depth per pixel, metres, row-major; 0 = no return.
    pub depth: Vec<f32>,
    /// Segment label of the hit face per pixel (0 = none, or the room).
    pub labels: Vec<u8>,
    /// Lambert shade |n · ray| per pixel in [0, 1] (0 = no hit).
    pub shade: Vec<f32>,
    /// The points of this camera in the scan's cloud.
    pub cloud_range: Range<usize>,
    /// Pixel index (row-major) of each of this camera's points.
    pub pixels: Vec<u32>,
    /// With a room: what each pixel hit (kind, world normal and point) for the colour render.
    pub surface: Option<SurfaceImage>,
}

impl CameraView {
    /// This view as cloud-building input ([`crate::fuse::DepthView`]): its depth, the scanner's label
    /// image as the person mask, the estimated extrinsics (what a calibration gives), no colours.
    pub fn depth_view(&self) -> crate::fuse::DepthView {
        crate::fuse::DepthView {
            name: self.name.clone(),
            intrinsics: self.intrinsics,
            camera_to_world: self.estimated_extrinsics,
            depth: crate::fuse::DepthImage::Metres(self.depth.clone()),
            labels: self.labels.clone(),
            colors: None,
        }
    }
}

/// A label image (`width` x `height`, row-major) grown by `pixels` pixels: each unlabelled pixel next
/// to a labelled one (8-neighbourhood, the first in row order) takes its label, `pixels` times over.
/// It imitates a person mask that spills onto the floor and the wall at the outline (MediaPipe's
/// spills 3.5-4.3 % of its pixels there), for the tests and benchmarks of cloud cleaning.
pub fn spill_labels(labels: &[u8], width: usize, height: usize, pixels: usize) -> Vec<u8> {
    let (w, h) = (width as i64, height as i64);
    let mut cur = labels.to_vec();
    for _ in 0..pixels {
        let prev = cur.clone();
        for v in 0..h {
            for u in 0..w {
                let i = (v * w + u) as usize;
                if prev.get(i).is_none_or(|&l| l != 0) {
                    continue;
                }
                let neighbour = (-1..=1)
                    .flat_map(|dv| (-1..=1).map(move |du| (u + du, v + dv)))
                    .filter(|&(uu, vv)| uu >= 0 && vv >= 0 && uu < w && vv < h)
                    .filter_map(|(uu, vv)| prev.get((vv * w + uu) as usize).copied())
                    .find(|&l| l != 0);
                if let Some(l) = neighbour {
                    cur[i] = l;
                }
            }
        }
    }
    cur
}

/// Result of a virtual scan: the merged world-frame cloud and each camera's images.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// The condition scanned.
    pub condition: Condition,
    /// The seed used.
    pub seed: u64,
    /// Merged cloud (world frame, estimated extrinsics) with labels and palette colours.
    pub cloud: PointCloud,
    /// One view per rig camera, in rig order.
    pub views: Vec<CameraView>,
    /// With a room: the look of the colour render ([`Appearance::from_seed`]) and the body heights
    /// that place underwear and hair; `None`: the plain skin-on-grey render.
    pub appearance: Option<(Appearance, BodyHeights)>,
}

/// The parry mesh (BVH) of `mesh`, after checking indices and coordinates.
pub fn parry_mesh(mesh: &TriMesh) -> Result<parry3d_f64::shape::TriMesh, ScanError> {
    if mesh.triangles.is_empty() {
        return Err(ScanError::EmptyMesh);
    }
    if let Some(i) = mesh.vertices.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
        return Err(ScanError::NonFiniteVertex(i));
    }
    mesh.check_indices()?;
    let verts: Vec<Vector> = mesh.vertices.iter().map(|p| Vector::new(p[0], p[1], p[2])).collect();
    parry3d_f64::shape::TriMesh::new(verts, mesh.triangles.clone()).map_err(|e| ScanError::Parry(e.to_string()))
}

/// Segment label of every face: `face_labels`, else the majority of the corners' `vertex_labels`
/// ([`bsv_core::labels::face_labels_from_vertices`]: the corner with the smallest vertex index when all
/// three differ, 0 for a triangle with a missing corner), else 0.
pub fn face_labels(mesh: &TriMesh) -> Result<Vec<u8>, ScanError> {
    let nt = mesh.triangles.len();
    if let Some(fl) = &mesh.face_labels {
        if fl.len() != nt {
            return Err(ScanError::LabelCount { what: "face_labels", got: fl.len(), expected: nt });
        }
        return Ok(fl.clone());
    }
    if let Some(vl) = &mesh.vertex_labels {
        if vl.len() != mesh.vertices.len() {
            return Err(ScanError::LabelCount { what: "vertex_labels", got: vl.len(), expected: mesh.vertices.len() });
        }
        return Ok(face_labels_from_vertices(&mesh.triangles, vl));
    }
    Ok(vec![0; nt])
}

/// Mixes a seed with stream ids into an independent 64-bit seed (splitmix64 finaliser).
pub(crate) fn mix_seed(seed: u64, a: u64, b: u64) -> u64 {
    let mut z = seed ^ a.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ b.wrapping_mul(0xD1B5_4A32_D192_ED03);
    for _ in 0..2 {
        z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
    }
    z
}

/// Stream ids of the random draws (kept apart so conditions share draws for a seed).
const STREAM_CALIBRATION: u64 = 0xCA11;
pub(crate) const STREAM_NOISE: u64 = 0x0153;

/// The world points of a camera's valid pixels: (pixel index, point, label), row-major. With a
/// `body_mask` (scans with a room), only the pixels whose ray hit the body.
fn view_points(
    depth: &[f64],
    labels: &[u8],
    body_mask: Option<&[u8]>,
    intr: &Intrinsics,
    estimated: &Extrinsics,
) -> Vec<(u32, [f64; 3], u8)> {
    let w = intr.width as usize;
    let body = SurfaceKind::Body as u8;
    let per_row: Vec<Vec<(u32, [f64; 3], u8)>> = depth
        .par_chunks(w)
        .enumerate()
        .map(|(v, row)| {
            row.iter()
                .enumerate()
                .filter(|(u, z)| **z > 0.0 && body_mask.is_none_or(|m| m[v * w + u] == body))
                .map(|(u, &z)| {
                    let p = estimated.transform_point(intr.deproject([u as f64, v as f64], z));
                    let i = v * w + u;
                    (i as u32, p, labels[i])
                })
                .collect()
        })
        .collect();
    per_row.into_iter().flatten().collect()
}

/// What every camera of a scan casts its rays at: the body (its BVH, face labels and, for smooth shading, its
/// vertex normals) and the room.
struct Scene<'a> {
    bvh: &'a parry3d_f64::shape::TriMesh,
    labels: &'a [u8],
    smooth: Option<cast::SmoothNormals<'a>>,
    room: Option<&'a RoomScene>,
}

/// One camera's view and its points (world frame, estimated extrinsics).
fn scan_camera(
    scene: &Scene<'_>,
    rig: &Rig,
    ci: usize,
    condition: Condition,
    seed: u64,
) -> (CameraView, Vec<(u32, [f64; 3], u8)>) {
    let cam = &rig.cameras[ci];
    let intr = cam.intrinsics;
    let (bvh, labels) = (scene.bvh, scene.labels);
    let rays = match scene.room {
        Some(r) => cast::cast_camera_room(bvh, labels, scene.smooth.as_ref(), r, &intr, &cam.camera_to_world),
        None => cast::cast_camera(bvh, labels, &intr, &cam.camera_to_world),
    };
    let depth = if condition.has_depth_noise() {
        noise::apply(&rays.depth, intr.width, intr.height, &rig.noise, mix_seed(seed, STREAM_NOISE, ci as u64))
    } else {
        rays.depth
    };
    let error_sigma = if condition.has_calibration_error() { cam.calibration_sigma } else { ExtrinsicSigma::default() };
    let error = if condition.has_calibration_error() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(mix_seed(seed, STREAM_CALIBRATION, ci as u64));
        error_sigma.draw(&mut rng)
    } else {
        ExtrinsicError::default()
    };
    let estimated = error.apply(&cam.camera_to_world);
    let mask = rays.surface.as_ref().map(|s| s.kind.as_slice());
    let points = view_points(&depth, &rays.labels, mask, &intr, &estimated);
    let mut view_labels = rays.labels;
    for (l, z) in view_labels.iter_mut().zip(&depth) {
        if *z <= 0.0 {
            *l = 0;
        }
    }
    let view = CameraView {
        name: cam.name.clone(),
        intrinsics: intr,
        true_extrinsics: cam.camera_to_world,
        estimated_extrinsics: estimated,
        error,
        error_sigma,
        depth: depth.iter().map(|&z| z as f32).collect(),
        labels: view_labels,
        shade: rays.shade,
        cloud_range: 0..0,
        pixels: Vec::new(),
        surface: rays.surface,
    };
    (view, points)
}

/// Scans `mesh` with every camera of `rig` under `condition`; deterministic for `seed`. With a room
/// on the rig, the room is rendered too, the cloud holds the body's pixels only and the scan carries
/// the [`Appearance`] of `seed`.
pub fn scan(mesh: &TriMesh, rig: &Rig, condition: Condition, seed: u64) -> Result<Scan, ScanError> {
    rig.validate()?;
    let labels = face_labels(mesh)?;
    let bvh = parry_mesh(mesh)?;
    let room = rig.room.as_ref().map(RoomScene::build).transpose()?;
    let normals = (room.is_some() && rig.look.smooth_shading).then(|| bsv_core::geometry::vertex_normals(mesh));
    let scene = Scene {
        bvh: &bvh,
        labels: &labels,
        smooth: normals.as_deref().map(|normals| cast::SmoothNormals { normals }),
        room: room.as_ref(),
    };
    let mut cloud = PointCloud::new(Vec::new());
    let mut cloud_labels = Vec::new();
    let mut views = Vec::with_capacity(rig.cameras.len());
    for ci in 0..rig.cameras.len() {
        let (mut view, points) = scan_camera(&scene, rig, ci, condition, seed);
        let start = cloud.points.len();
        for (i, p, l) in points {
            view.pixels.push(i);
            cloud.points.push(p);
            cloud_labels.push(l);
        }
        view.cloud_range = start..cloud.points.len();
        views.push(view);
    }
    cloud.colors =
        Some(cloud_labels.iter().map(|&l| Segment::from_id(l).unwrap_or(Segment::Unlabelled).color()).collect());
    cloud.labels = Some(cloud_labels);
    let appearance =
        rig.room.as_ref().map(|_| (Appearance::from_seed_with(seed, &rig.look), BodyHeights::of(mesh, &labels)));
    Ok(Scan { condition, seed, cloud, views, appearance })
}
