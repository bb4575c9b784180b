//! The virtual two-camera depth scanner of the validation protocol (DESIGN.md).
//!
//! Each camera casts one ray per pixel at the mesh (parry BVH, rayon over rows) with its TRUE
//! extrinsics, records the depth (z along the optical axis), the hit face's segment label and a
//! Lambert shade. In `l515`/`l5ca` the depth gets flying pixels and Gaussian noise
//! ([`DepthNoise`]). The depth is back-projected along the pixel rays and transformed to the world
//! with the ESTIMATED extrinsics, which in `cali`/`l5ca` are the true ones perturbed by a drawn
//! [`ExtrinsicError`]: the cloud is what a miscalibrated rig would give. Deterministic for a seed.
//! [`write_capture`] writes what a real capture writes (depth/colour/label PNGs, camera JSON).

mod capture;
mod noise;
mod rig;

pub use capture::{write_capture, CaptureCamera, DEPTH_SCALE};
pub use rig::{
    Condition, DepthNoise, ExtrinsicError, ExtrinsicSigma, Rig, RigCamera, PAPER_CAMERA_DISTANCE, PAPER_CAMERA_HEIGHT,
    PAPER_HEIGHT, PAPER_HFOV_DEG, PAPER_VFOV_DEG, PAPER_WIDTH,
};

use crate::camera::{CameraError, Extrinsics, Intrinsics};
use bsv_core::labels::face_labels_from_vertices;
use bsv_core::{MeshInvariant, PointCloud, Segment, TriMesh};
use parry3d_f64::math::Vector;
use parry3d_f64::query::{Ray, RayCast};
use rand::SeedableRng;
use rayon::prelude::*;
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
    /// Measured depth per pixel, metres, row-major; 0 = no return.
    pub depth: Vec<f32>,
    /// Segment label of the hit face per pixel (0 = none).
    pub labels: Vec<u8>,
    /// Lambert shade |n · ray| per pixel in [0, 1] (0 = no hit).
    pub shade: Vec<f32>,
    /// The points of this camera in the scan's cloud.
    pub cloud_range: Range<usize>,
    /// Pixel index (row-major) of each of this camera's points.
    pub pixels: Vec<u32>,
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

/// True depth, label and shade of every pixel of one camera (f64 depth, 0 = no hit).
struct RayImage {
    depth: Vec<f64>,
    labels: Vec<u8>,
    shade: Vec<f32>,
}

fn cast_camera(bvh: &parry3d_f64::shape::TriMesh, labels: &[u8], intr: &Intrinsics, ext: &Extrinsics) -> RayImage {
    let (w, h) = (intr.width as usize, intr.height as usize);
    let mut out = RayImage { depth: vec![0.0; w * h], labels: vec![0; w * h], shade: vec![0.0; w * h] };
    let o = ext.translation;
    let origin = Vector::new(o[0], o[1], o[2]);
    out.depth
        .par_chunks_mut(w)
        .zip(out.labels.par_chunks_mut(w))
        .zip(out.shade.par_chunks_mut(w))
        .enumerate()
        .for_each(|(v, ((drow, lrow), srow))| {
            for u in 0..w {
                let [x, y] = intr.pixel_ray([u as f64, v as f64]);
                let d = ext.transform_vector([x, y, 1.0]);
                let ray = Ray::new(origin, Vector::new(d[0], d[1], d[2]));
                if let Some(hit) = bvh.cast_local_ray_and_get_normal(&ray, 1.0e3, false) {
                    drow[u] = hit.time_of_impact;
                    lrow[u] = labels.get(hit.subshape as usize).copied().unwrap_or(0);
                    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    let n = hit.normal;
                    let c = ((n.x * d[0] + n.y * d[1] + n.z * d[2]) / (len * n.length().max(1e-300))).abs();
                    srow[u] = c.min(1.0) as f32;
                }
            }
        });
    out
}

/// Scans `mesh` with every camera of `rig` under `condition`; deterministic for `seed`.
pub fn scan(mesh: &TriMesh, rig: &Rig, condition: Condition, seed: u64) -> Result<Scan, ScanError> {
    rig.validate()?;
    let labels = face_labels(mesh)?;
    let bvh = parry_mesh(mesh)?;
    let mut cloud = PointCloud::new(Vec::new());
    let mut cloud_labels = Vec::new();
    let mut views = Vec::with_capacity(rig.cameras.len());
    for (ci, cam) in rig.cameras.iter().enumerate() {
        let intr = cam.intrinsics;
        let w = intr.width as usize;
        let rays = cast_camera(&bvh, &labels, &intr, &cam.camera_to_world);
        let depth = if condition.has_depth_noise() {
            noise::apply(&rays.depth, intr.width, intr.height, &rig.noise, mix_seed(seed, STREAM_NOISE, ci as u64))
        } else {
            rays.depth
        };
        let error = if condition.has_calibration_error() {
            let mut rng = rand::rngs::StdRng::seed_from_u64(mix_seed(seed, STREAM_CALIBRATION, ci as u64));
            cam.calibration_sigma.draw(&mut rng)
        } else {
            ExtrinsicError::default()
        };
        let estimated = error.apply(&cam.camera_to_world);
        let start = cloud.points.len();
        let per_row: Vec<Vec<(u32, [f64; 3], u8)>> = depth
            .par_chunks(w)
            .enumerate()
            .map(|(v, row)| {
                row.iter()
                    .enumerate()
                    .filter(|(_, z)| **z > 0.0)
                    .map(|(u, &z)| {
                        let p = estimated.transform_point(intr.deproject([u as f64, v as f64], z));
                        let i = v * w + u;
                        (i as u32, p, rays.labels[i])
                    })
                    .collect()
            })
            .collect();
        let mut pixels = Vec::new();
        for (i, p, l) in per_row.into_iter().flatten() {
            pixels.push(i);
            cloud.points.push(p);
            cloud_labels.push(l);
        }
        let mut view_labels = rays.labels;
        for (l, z) in view_labels.iter_mut().zip(&depth) {
            if *z <= 0.0 {
                *l = 0;
            }
        }
        views.push(CameraView {
            name: cam.name.clone(),
            intrinsics: intr,
            true_extrinsics: cam.camera_to_world,
            estimated_extrinsics: estimated,
            error,
            depth: depth.iter().map(|&z| z as f32).collect(),
            labels: view_labels,
            shade: rays.shade,
            cloud_range: start..cloud.points.len(),
            pixels,
        });
    }
    cloud.colors =
        Some(cloud_labels.iter().map(|&l| Segment::from_id(l).unwrap_or(Segment::Unlabelled).color()).collect());
    cloud.labels = Some(cloud_labels);
    Ok(Scan { condition, seed, cloud, views })
}
