//! Ray casting of one camera: one ray per pixel (rayon over rows) against the body and, with a room,
//! against the room's own BVH, keeping the nearer hit.

use super::room::{RoomScene, SurfaceKind};
use crate::camera::{Extrinsics, Intrinsics};
use parry3d_f64::math::Vector;
use parry3d_f64::query::{Ray, RayCast, RayIntersection};
use rayon::prelude::*;

/// Longest ray, metres (far beyond any room).
const MAX_TOI: f64 = 1.0e3;

/// What each pixel of a camera hit, beyond depth and label: kept for the colour render of a scan
/// with a room (absent without one).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SurfaceImage {
    /// [`SurfaceKind`] code per pixel, row-major (`SurfaceKind::from_code`).
    pub kind: Vec<u8>,
    /// Unit world-frame normal per pixel, turned toward the camera (zero where nothing was hit).
    pub normal: Vec<[f32; 3]>,
    /// World-frame hit point per pixel (true extrinsics; zero where nothing was hit).
    pub point: Vec<[f32; 3]>,
}

/// True depth, label and shade of every pixel of one camera (f64 depth, 0 = no hit).
pub(super) struct RayImage {
    pub depth: Vec<f64>,
    pub labels: Vec<u8>,
    pub shade: Vec<f32>,
    /// With a room: what was hit per pixel.
    pub surface: Option<SurfaceImage>,
}

/// |n . d| / (|n| |d|), clamped to 1: the Lambert shade of the legacy render.
fn shade_of(n: Vector, d: [f64; 3]) -> f32 {
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let c = ((n.x * d[0] + n.y * d[1] + n.z * d[2]) / (len * n.length().max(1e-300))).abs();
    c.min(1.0) as f32
}

/// The world-frame ray of pixel (u, v): origin at the camera centre, direction with unit camera z
/// (so the time of impact is the depth along the optical axis).
fn pixel_ray(intr: &Intrinsics, ext: &Extrinsics, u: usize, v: usize) -> ([f64; 3], Ray) {
    let [x, y] = intr.pixel_ray([u as f64, v as f64]);
    let d = ext.transform_vector([x, y, 1.0]);
    let o = ext.translation;
    (d, Ray::new(Vector::new(o[0], o[1], o[2]), Vector::new(d[0], d[1], d[2])))
}

/// The body alone (no room): depth, label and shade per pixel.
pub(super) fn cast_camera(
    bvh: &parry3d_f64::shape::TriMesh,
    labels: &[u8],
    intr: &Intrinsics,
    ext: &Extrinsics,
) -> RayImage {
    let (w, h) = (intr.width as usize, intr.height as usize);
    let mut out = RayImage { depth: vec![0.0; w * h], labels: vec![0; w * h], shade: vec![0.0; w * h], surface: None };
    out.depth
        .par_chunks_mut(w)
        .zip(out.labels.par_chunks_mut(w))
        .zip(out.shade.par_chunks_mut(w))
        .enumerate()
        .for_each(|(v, ((drow, lrow), srow))| {
            for u in 0..w {
                let (d, ray) = pixel_ray(intr, ext, u, v);
                if let Some(hit) = bvh.cast_local_ray_and_get_normal(&ray, MAX_TOI, false) {
                    drow[u] = hit.time_of_impact;
                    lrow[u] = labels.get(hit.subshape as usize).copied().unwrap_or(0);
                    srow[u] = shade_of(hit.normal, d);
                }
            }
        });
    out
}

/// One pixel of a scan with a room.
#[derive(Clone, Copy)]
struct PixelHit {
    depth: f64,
    label: u8,
    shade: f32,
    kind: u8,
    normal: [f32; 3],
    point: [f32; 3],
}

const NO_HIT: PixelHit =
    PixelHit { depth: 0.0, label: 0, shade: 0.0, kind: SurfaceKind::None as u8, normal: [0.0; 3], point: [0.0; 3] };

/// The body's vertex normals for smooth shading ([`super::Look::smooth_shading`]): the normal at a hit is
/// interpolated across its triangle with the hit's barycentric coordinates.
pub(super) struct SmoothNormals<'a> {
    /// Unit vertex normals, one per vertex of the mesh the BVH was built from.
    pub normals: &'a [[f64; 3]],
}

impl SmoothNormals<'_> {
    /// The interpolated unit normal at `p` on triangle `t` of `bvh`, or None for a degenerate triangle or a
    /// zero interpolated normal.
    fn at(&self, bvh: &parry3d_f64::shape::TriMesh, t: u32, p: Vector) -> Option<Vector> {
        let tri = bvh.indices().get(t as usize)?;
        let v = bvh.vertices();
        let [a, b, c] = tri.map(|i| v[i as usize]);
        let (e0, e1, ep) = (b - a, c - a, p - a);
        let (d00, d01, d11, d20, d21) = (e0.dot(e0), e0.dot(e1), e1.dot(e1), ep.dot(e0), ep.dot(e1));
        let den = d00 * d11 - d01 * d01;
        if den.abs() < 1e-300 {
            return None;
        }
        let (wb, wc) = ((d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den);
        let w = [1.0 - wb - wc, wb, wc].map(|x| x.clamp(0.0, 1.0));
        let mut n = Vector::ZERO;
        for (k, &i) in tri.iter().enumerate() {
            let vn = self.normals.get(i as usize)?;
            n += w[k] * Vector::new(vn[0], vn[1], vn[2]);
        }
        let len = n.length();
        (len > 1e-12).then(|| n / len)
    }
}

/// One pixel's hit; its colour normal is `smooth` where given (the depth, label and shade are the hit's own).
fn pixel_hit(
    hit: &RayIntersection,
    ray: &Ray,
    d: [f64; 3],
    label: u8,
    kind: SurfaceKind,
    smooth: Option<Vector>,
) -> PixelHit {
    // Turned toward the camera by the triangle's own normal: an interpolated normal near the outline may
    // face slightly away, and stays so (turning it alone would flip it across a pixel).
    let face = hit.normal / hit.normal.length().max(1e-300);
    let n = smooth.unwrap_or(face);
    let n = if face.dot(ray.dir) > 0.0 { -n } else { n };
    let p = ray.point_at(hit.time_of_impact);
    PixelHit {
        depth: hit.time_of_impact,
        label,
        shade: shade_of(hit.normal, d),
        kind: kind as u8,
        normal: [n.x as f32, n.y as f32, n.z as f32],
        point: [p.x as f32, p.y as f32, p.z as f32],
    }
}

/// The body and the room: the nearer hit per pixel (the body wins a tie); room pixels have label 0. With
/// `smooth`, the body's colour normals are interpolated from its vertex normals.
pub(super) fn cast_camera_room(
    bvh: &parry3d_f64::shape::TriMesh,
    labels: &[u8],
    smooth: Option<&SmoothNormals<'_>>,
    room: &RoomScene,
    intr: &Intrinsics,
    ext: &Extrinsics,
) -> RayImage {
    let (w, h) = (intr.width as usize, intr.height as usize);
    let rows: Vec<Vec<PixelHit>> = (0..h)
        .into_par_iter()
        .map(|v| {
            (0..w)
                .map(|u| {
                    let (d, ray) = pixel_ray(intr, ext, u, v);
                    let body = bvh.cast_local_ray_and_get_normal(&ray, MAX_TOI, false);
                    let limit = body.as_ref().map_or(MAX_TOI, |b| b.time_of_impact);
                    let wall = room.bvh.as_ref().and_then(|r| r.cast_local_ray_and_get_normal(&ray, limit, false));
                    match (wall, body) {
                        (Some(r), b) if b.as_ref().is_none_or(|b| r.time_of_impact < b.time_of_impact) => {
                            let kind = room.kinds.get(r.subshape as usize).copied().unwrap_or(SurfaceKind::Wall);
                            pixel_hit(&r, &ray, d, 0, kind, None)
                        }
                        (_, Some(b)) => {
                            let label = labels.get(b.subshape as usize).copied().unwrap_or(0);
                            let n = smooth.and_then(|s| s.at(bvh, b.subshape, ray.point_at(b.time_of_impact)));
                            pixel_hit(&b, &ray, d, label, SurfaceKind::Body, n)
                        }
                        _ => NO_HIT,
                    }
                })
                .collect()
        })
        .collect();
    let px: Vec<PixelHit> = rows.into_iter().flatten().collect();
    RayImage {
        depth: px.iter().map(|p| p.depth).collect(),
        labels: px.iter().map(|p| p.label).collect(),
        shade: px.iter().map(|p| p.shade).collect(),
        surface: Some(SurfaceImage {
            kind: px.iter().map(|p| p.kind).collect(),
            normal: px.iter().map(|p| p.normal).collect(),
            point: px.iter().map(|p| p.point).collect(),
        }),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::scanner::{face_labels, parry_mesh, Rig, Room};
    use bsv_core::shapes;

    #[test]
    fn floor_depth_is_the_analytic_plane_intersection() {
        let body = shapes::capsule_body(false, false);
        let (labels, bvh) = (face_labels(&body).unwrap(), parry_mesh(&body).unwrap());
        let room = RoomScene::build(&Room::clinic()).unwrap();
        let rig = Rig::paper_default();
        for cam in &rig.cameras {
            let (intr, ext) = (cam.intrinsics, cam.camera_to_world);
            let img = cast_camera_room(&bvh, &labels, None, &room, &intr, &ext);
            let surf = img.surface.as_ref().unwrap();
            let w = intr.width as usize;
            let mut floor = 0;
            for (i, &k) in surf.kind.iter().enumerate() {
                if k != SurfaceKind::Body as u8 {
                    assert_eq!(img.labels[i], 0, "room pixel {i} has a label");
                }
                if k == SurfaceKind::Floor as u8 {
                    let (d, _) = pixel_ray(&intr, &ext, i % w, i / w);
                    let t = -ext.translation[1] / d[1];
                    assert!((img.depth[i] - t).abs() < 1e-9, "pixel {i}: {} vs {t}", img.depth[i]);
                    assert!(surf.point[i][1].abs() < 1e-5 && surf.normal[i][1] > 0.999);
                    floor += 1;
                }
            }
            assert!(floor > 50_000, "{}: only {floor} floor pixels", cam.name);
            // The body pixels are those of the body-only cast, with the same depth.
            let plain = cast_camera(&bvh, &labels, &intr, &ext);
            for (i, &k) in surf.kind.iter().enumerate() {
                assert_eq!(k == SurfaceKind::Body as u8, plain.depth[i] > 0.0, "pixel {i}");
                if k == SurfaceKind::Body as u8 {
                    assert_eq!(img.depth[i], plain.depth[i]);
                }
            }
        }
    }
}
