//! Articulated initialisation: per-limb rigid (optionally axially scaled) alignment of the labelled
//! template onto the labelled cloud, blended across the joints.
//!
//! Why: the template's limbs are not in the subject's pose (arm abduction, elbow and knee angles
//! differ by 5-20 degrees). Nearest-neighbour correspondences then pull a limb's vertices onto the
//! nearest edge of the limb's points and the stiff ARAP fit flattens the limb into a ribbon instead
//! of turning it (measured on the synthetic cohort: forearms -26 % in noer, -50 % with pruning off).
//!
//! How, for every limb segment L (upper arms, forearms, thighs, shins; the torso keeps the global
//! pre-alignment) present in both the template's vertex labels and the cloud's labels:
//! 1. centroid and principal axis (largest-eigenvalue eigenvector of the covariance) of the
//!    template's L vertices and of the cloud's L points; the cloud's axis is refined once on the
//!    points nearest to the first axis line (90 %), so flying pixels do not tilt it;
//! 2. the rotation `R_L` is the smallest rotation taking the template axis onto the cloud axis
//!    (sign chosen so that they agree), about the template centroid; the twist about the axis is
//!    left to the non-rigid fit;
//! 3. optionally the axis is scaled so that the segment's extent along it (1 % / 99 % quantiles
//!    of the projections) maps onto the cloud's, ends aligned; and optionally the cross-section's
//!    depth and width are scaled to the cloud's (`section.rs`: from the front and back surfaces and
//!    the silhouette, which the cameras do see);
//! 4. `x -> c_cloud + R_L S_L (x - c_template)` per vertex, then the displacement field is smoothed
//!    by a few Jacobi iterations over the mesh graph: a rigid motion is an affine field, which the
//!    averaging keeps inside a segment, so only the joints are blended. With
//!    `articulate_rigid_shoulders` on and the template's labels kept for the result (the camera
//!    path's `labels = template`; `prepare.rs` decides), the shoulder half of each posed upper arm
//!    ([`shoulder_halves`]) is held out of the averaging: the shoulder is blended on the torso's side
//!    only, so the template's shoulder boundary turns with the arm instead of lagging behind it by an
//!    amount that grows with the arm's abduction.
//!
//! The articulated template becomes the rest shape of the ARAP fit (its rotations are free anyway;
//! only the joints' bending and the axial scale are baked in).

use crate::cotan::CotanWeights;
use crate::section::{fit_section, Section};
use bsv_core::geometry::{cross, dot, normalize, sub};
use bsv_core::Segment;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// Limb segment ids (upper arms, forearms, thighs, shins).
pub const LIMBS: [u8; 8] = [
    Segment::UpperArmL as u8,
    Segment::UpperArmR as u8,
    Segment::ForearmL as u8,
    Segment::ForearmR as u8,
    Segment::ThighL as u8,
    Segment::ThighR as u8,
    Segment::ShinL as u8,
    Segment::ShinR as u8,
];

/// Fewest vertices/points a segment needs to be aligned.
const MIN_ITEMS: usize = 30;
/// Smallest ratio of the largest to the middle eigenvalue of a template limb's vertices, and of a
/// cloud limb's points except the upper arms': below it the axis is not clear. Thighs often fall
/// under it (the upper thigh's wide surface dominates) and stay unarticulated: articulating them at
/// 1.2 made thighs and shins worse (round 2 session 4), and at 1.3 the heavier cohort's shins went
/// +1.1 points (session 32).
pub const MIN_ELONGATION: f64 = 2.0;
/// The same ratio for a cloud upper arm. The camera path's upper arm runs from the armpit line to the
/// elbow, short, and the cameras see only its front and back, which adds to the spread in depth: a
/// plain arm reads 3.3, a deep one 1.5-2.0, a heavy one (BMI 35-41) 1.6-2.0. At 2 such an arm was
/// skipped (no turn, no axial scale, no cross-section sizing), and the fit recruited the torso's
/// shoulder vertices to cover it: upper arms -7 to -11 %, the shoulder loop 7-13 mm distal (round 2
/// session 32). Below [`MIN_TURN_ELONGATION`] it is sized but not turned.
pub const MIN_UPPER_ARM_ELONGATION: f64 = 1.3;
/// Smallest elongation of a cloud upper arm whose axis the limb is turned onto; a less elongated one
/// (from [`MIN_UPPER_ARM_ELONGATION`]) is sized along the template's own axis. Under 1.6 the cloud's
/// axis lay up to 12 degrees off the bone (a deep arm at 1.5: turned 20 degrees, upper arm -9.5 to
/// -11.8 %); turned, such arms of the hard cohort came out 4.35 % off on average, unturned 1.58 %. From
/// 1.6 to 2 the turn pays: heavier bodies' arms (turned by 13 degrees, median) 1.97 % against 4.23 %
/// unturned (round 2 session 32).
pub const MIN_TURN_ELONGATION: f64 = 1.6;
/// Largest angle (degrees) between the template's and the cloud's limb axes: a cloud axis farther
/// off is a cross-section's, not the limb's, and the limb is skipped.
pub const MAX_AXIS_ANGLE_DEG: f64 = 45.0;

/// The per-limb map found by [`segment_poses`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentPose {
    /// Segment id.
    pub label: u8,
    /// Template centroid (pre-aligned frame), metres.
    pub template_centroid: [f64; 3],
    /// Cloud centroid, metres.
    pub cloud_centroid: [f64; 3],
    /// Rotation taking the template axis onto the cloud axis.
    pub rotation: Matrix3<f64>,
    /// Unit template axis (before the rotation).
    pub axis: [f64; 3],
    /// Scale along the axis (1 = rigid).
    pub axial_scale: f64,
    /// Angle between the two axes, degrees.
    pub angle_deg: f64,
    /// The cross-section sizing applied after the rotation (see `section.rs`).
    pub section: Section,
    /// The cloud limb's elongation: the largest over the middle eigenvalue of its points' covariance.
    pub elongation: f64,
}

impl SegmentPose {
    /// Applies the pose to a point.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let d = sub(p, self.template_centroid);
        let a = dot(d, self.axis) * (self.axial_scale - 1.0);
        let d = [d[0] + a * self.axis[0], d[1] + a * self.axis[1], d[2] + a * self.axis[2]];
        let r = self.rotation * Vector3::from(d);
        let r = self.section.apply([r[0], r[1], r[2]]);
        [self.cloud_centroid[0] + r[0], self.cloud_centroid[1] + r[1], self.cloud_centroid[2] + r[2]]
    }
}

/// Centroid and covariance of `pts`.
fn moments(pts: &[[f64; 3]]) -> ([f64; 3], Matrix3<f64>) {
    let n = pts.len().max(1) as f64;
    let mut c = [0.0; 3];
    for p in pts {
        for k in 0..3 {
            c[k] += p[k] / n;
        }
    }
    let mut m = Matrix3::zeros();
    for p in pts {
        let d = Vector3::from(sub(*p, c));
        m += d * d.transpose() / n;
    }
    (c, m)
}

/// Unit eigenvector of the largest eigenvalue and the ratio largest / middle eigenvalue.
fn principal_axis(m: &Matrix3<f64>) -> ([f64; 3], f64) {
    let e = SymmetricEigen::new(*m);
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| e.eigenvalues[b].total_cmp(&e.eigenvalues[a]));
    let v = e.eigenvectors.column(idx[0]);
    let ratio = e.eigenvalues[idx[0]] / e.eigenvalues[idx[1]].max(f64::MIN_POSITIVE);
    (normalize([v[0], v[1], v[2]]), ratio)
}

/// The smallest rotation taking unit `a` onto unit `b` (Rodrigues).
fn rotation_between(a: [f64; 3], b: [f64; 3]) -> Matrix3<f64> {
    let v = cross(a, b);
    let s = dot(v, v).sqrt();
    let c = dot(a, b);
    if s < 1e-12 {
        return Matrix3::identity();
    }
    let k = Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0);
    Matrix3::identity() + k + k * k * ((1.0 - c) / (s * s))
}

/// The `q` and `1 - q` quantiles of the projections of `pts` (about `c`) on `axis`.
fn axial_range(pts: &[[f64; 3]], c: [f64; 3], axis: [f64; 3], q: f64) -> (f64, f64) {
    let mut t: Vec<f64> = pts.iter().map(|p| dot(sub(*p, c), axis)).collect();
    if t.len() < 2 {
        return (0.0, 0.0);
    }
    t.sort_by(f64::total_cmp);
    let lo = ((q * t.len() as f64) as usize).min(t.len() - 1);
    let hi = (((1.0 - q) * t.len() as f64) as usize).min(t.len() - 1);
    (t[lo], t[hi])
}

/// The per-limb poses of the template (`rest`, `vertex_labels`) onto the cloud (`points`,
/// `labels`). Segments absent on either side, too small, not elongated
/// ([`MIN_ELONGATION`], [`MIN_UPPER_ARM_ELONGATION`]) or whose cloud axis lies more than
/// [`MAX_AXIS_ANGLE_DEG`] off the template's are skipped.
pub fn segment_poses(
    rest: &[[f64; 3]],
    vertex_labels: &[u8],
    points: &[[f64; 3]],
    labels: &[u8],
    axial_scale: bool,
    cross_section: bool,
) -> Vec<SegmentPose> {
    let mut out = Vec::new();
    for &l in &LIMBS {
        let tv: Vec<[f64; 3]> = rest.iter().zip(vertex_labels).filter(|(_, &x)| x == l).map(|(p, _)| *p).collect();
        let cp: Vec<[f64; 3]> = points.iter().zip(labels).filter(|(_, &x)| x == l).map(|(p, _)| *p).collect();
        if tv.len() < MIN_ITEMS || cp.len() < MIN_ITEMS {
            continue;
        }
        let (ct, mt) = moments(&tv);
        let (at, rt) = principal_axis(&mt);
        let (cc0, mc) = moments(&cp);
        let (ac0, rc) = principal_axis(&mc);
        let min_cloud = if UPPER_ARMS.contains(&l) { MIN_UPPER_ARM_ELONGATION } else { MIN_ELONGATION };
        if rt < MIN_ELONGATION || rc < min_cloud {
            continue;
        }
        // Refine the cloud axis on the 90 % of points nearest to the first axis line.
        let dist_to_line = |p: &[f64; 3]| {
            let d = sub(*p, cc0);
            let a = dot(d, ac0);
            dot(d, d) - a * a
        };
        let mut d2: Vec<f64> = cp.iter().map(dist_to_line).collect();
        let k = (d2.len() * 9) / 10;
        let k = k.min(d2.len() - 1);
        let (_, &mut lim, _) = d2.select_nth_unstable_by(k, f64::total_cmp);
        let inner: Vec<[f64; 3]> = cp.iter().filter(|p| dist_to_line(p) <= lim).copied().collect();
        let (cc, mc) = if inner.len() >= MIN_ITEMS { moments(&inner) } else { (cc0, mc) };
        let (mut ac, _) = principal_axis(&mc);
        if dot(ac, at) < 0.0 {
            ac = ac.map(|v| -v);
        }
        if dot(ac, at) < MAX_AXIS_ANGLE_DEG.to_radians().cos() {
            continue;
        }
        if rc < MIN_TURN_ELONGATION {
            // Clear enough to size the limb along, not to turn it by (see MIN_TURN_ELONGATION).
            ac = at;
        }
        // Along the axis, map the template's segment interval onto the cloud's (1 % / 99 %
        // quantiles of the projections): ends aligned, not centroids (the template's cap
        // vertices and the cloud's uneven sampling bias the centroids along the axis).
        let (mut scale, mut cc) = (1.0, cc);
        if axial_scale {
            let (t0, t1) = axial_range(&tv, ct, at, 0.01);
            let (c0, c1) = axial_range(&inner, cc, ac, 0.01);
            if t1 > t0 && c1 > c0 {
                scale = ((c1 - c0) / (t1 - t0)).clamp(0.7, 1.4);
                // x -> cc' + R S (x - ct) maps t0 to c0: cc' = cc + ac (c0 - scale t0).
                let off = c0 - scale * t0;
                cc = [cc[0] + ac[0] * off, cc[1] + ac[1] * off, cc[2] + ac[2] * off];
            }
        }
        let mut pose = SegmentPose {
            label: l,
            template_centroid: ct,
            cloud_centroid: cc,
            rotation: rotation_between(at, ac),
            axis: at,
            axial_scale: scale,
            angle_deg: dot(at, ac).clamp(-1.0, 1.0).acos().to_degrees(),
            section: Section::identity(),
            elongation: rc,
        };
        if cross_section {
            let posed: Vec<[f64; 3]> = tv.iter().map(|&x| sub(pose.apply(x), cc)).collect();
            let rel: Vec<[f64; 3]> = cp.iter().map(|&p| sub(p, cc)).collect();
            if let Some(section) = fit_section(&posed, &rel, ac) {
                pose.section = section;
            }
        }
        out.push(pose);
    }
    out
}

/// Upper-arm segment ids (left, right).
const UPPER_ARMS: [u8; 2] = [Segment::UpperArmL as u8, Segment::UpperArmR as u8];
/// The torso's segment id.
const TORSO: u8 = Segment::Torso as u8;
/// Forearm segment ids (left, right).
const FOREARMS: [u8; 2] = [Segment::ForearmL as u8, Segment::ForearmR as u8];

/// Hops over the mesh graph of `weights` from the nearest vertex whose label satisfies `seed`
/// (`usize::MAX` where none is reachable).
fn hops_from(vertex_labels: &[u8], weights: &CotanWeights, seed: impl Fn(u8) -> bool) -> Vec<usize> {
    let mut d = vec![usize::MAX; vertex_labels.len()];
    let mut queue = std::collections::VecDeque::new();
    for (i, &l) in vertex_labels.iter().enumerate() {
        if seed(l) {
            d[i] = 0;
            queue.push_back(i);
        }
    }
    while let Some(i) = queue.pop_front() {
        let (nb, _) = weights.row(i);
        for &j in nb {
            let j = j as usize;
            if d[j] == usize::MAX {
                d[j] = d[i] + 1;
                queue.push_back(j);
            }
        }
    }
    d
}

/// The upper-arm vertices nearer (in mesh hops) to the torso than to their own forearm: the shoulder
/// halves that [`articulate`] keeps rigid with their arm. Only an upper arm that has a pose in
/// `poses` and reaches both a torso and its own side's forearm over the mesh is split; the others hold
/// nothing (an unposed arm's held half would stay at zero displacement while its elbow follows the
/// forearm; a template without forearms would hold its whole upper arm).
pub fn shoulder_halves(vertex_labels: &[u8], weights: &CotanWeights, poses: &[SegmentPose]) -> Vec<bool> {
    let to_torso = hops_from(vertex_labels, weights, |l| l == TORSO);
    // Each arm's own forearm: a template without the left forearm must not reach the right one.
    let to_forearm = [0, 1].map(|side| hops_from(vertex_labels, weights, |l| l == FOREARMS[side]));
    let posed = |l: u8| poses.iter().any(|p| p.label == l);
    vertex_labels
        .iter()
        .enumerate()
        .map(|(i, &l)| match UPPER_ARMS.iter().position(|&u| u == l) {
            Some(side) => {
                let f = to_forearm[side][i];
                posed(l) && f != usize::MAX && to_torso[i] < f
            }
            None => false,
        })
        .collect()
}

/// The articulated positions: each limb vertex moved by its segment's pose, the others unmoved,
/// then the displacement field smoothed by `smooth_iterations` Jacobi steps
/// (`u_i <- (u_i + mean_j u_j) / 2` over the mesh neighbours of `weights`) at every vertex not
/// `held` (a held vertex keeps its segment's rigid motion; `held` is empty or one flag per vertex).
pub fn articulate(
    rest: &[[f64; 3]],
    vertex_labels: &[u8],
    poses: &[SegmentPose],
    weights: &CotanWeights,
    smooth_iterations: usize,
    held: &[bool],
) -> Vec<[f64; 3]> {
    debug_assert!(held.is_empty() || held.len() == rest.len(), "held: one flag per vertex or none");
    let mut by_label: [Option<&SegmentPose>; 256] = [None; 256];
    for p in poses {
        by_label[p.label as usize] = Some(p);
    }
    let mut u: Vec<[f64; 3]> = rest
        .iter()
        .zip(vertex_labels)
        .map(|(&p, &l)| by_label[l as usize].map_or([0.0; 3], |pose| sub(pose.apply(p), p)))
        .collect();
    let mut next = u.clone();
    for _ in 0..smooth_iterations {
        for (i, out) in next.iter_mut().enumerate() {
            let (nb, _) = weights.row(i);
            if nb.is_empty() || held.get(i).copied().unwrap_or(false) {
                *out = u[i];
                continue;
            }
            let mut m = [0.0; 3];
            for &j in nb {
                for k in 0..3 {
                    m[k] += u[j as usize][k];
                }
            }
            let inv = 1.0 / nb.len() as f64;
            for k in 0..3 {
                out[k] = 0.5 * (u[i][k] + m[k] * inv);
            }
        }
        std::mem::swap(&mut u, &mut next);
    }
    rest.iter().zip(&u).map(|(p, d)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of quads along x (two rows of vertices), labelled torso / upper arm / forearm by x.
    fn strip(n: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<u8>) {
        let mut v = Vec::new();
        for i in 0..n {
            v.push([i as f64, 0.0, 0.0]);
            v.push([i as f64, 1.0, 0.0]);
        }
        let mut t = Vec::new();
        for i in 0..n as u32 - 1 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            t.push([a, c, b]);
            t.push([b, c, d]);
        }
        let labels = v
            .iter()
            .map(|p| {
                if p[0] < 4.0 {
                    2
                } else if p[0] < 12.0 {
                    3
                } else {
                    5
                }
            })
            .collect();
        (v, t, labels)
    }

    /// The upper arm (label 3) of [`strip`] moved up by 1 (the identity rotation, moved).
    fn arm_up() -> SegmentPose {
        SegmentPose {
            label: 3,
            template_centroid: [8.0, 0.5, 0.0],
            cloud_centroid: [8.0, 0.5, 1.0],
            rotation: Matrix3::identity(),
            axis: [1.0, 0.0, 0.0],
            axial_scale: 1.0,
            angle_deg: 0.0,
            section: Section::identity(),
            elongation: 3.0,
        }
    }

    #[test]
    fn shoulder_halves_are_the_upper_arm_vertices_nearer_the_torso() {
        let (v, t, l) = strip(16);
        let w = CotanWeights::new(&v, &t);
        let held = shoulder_halves(&l, &w, &[arm_up()]);
        let xs: Vec<f64> = v.iter().zip(&held).filter(|(_, &h)| h).map(|(p, _)| p[0]).collect();
        assert!(!xs.is_empty());
        assert!(xs.iter().all(|&x| (4.0..8.0).contains(&x)), "held x: {xs:?}");
        assert!(xs.contains(&4.0) && xs.contains(&7.0));
    }

    #[test]
    fn a_held_vertex_keeps_its_segments_rigid_motion_and_the_torso_side_is_blended() {
        let (v, t, l) = strip(16);
        let w = CotanWeights::new(&v, &t);
        let pose = arm_up();
        let held = shoulder_halves(&l, &w, &[pose]);
        let blended = articulate(&v, &l, &[pose], &w, 10, &[]);
        let rigid = articulate(&v, &l, &[pose], &w, 10, &held);
        for i in 0..v.len() {
            let (x, dz_b, dz_r) = (v[i][0], blended[i][2], rigid[i][2]);
            if held[i] {
                assert!((dz_r - 1.0).abs() < 1e-12, "held vertex at x = {x} moved {dz_r}");
            }
            if x == 4.0 {
                assert!(dz_b < 0.9, "blending pulls the first arm vertex back: {dz_b}");
            }
            if x == 3.0 {
                assert!(dz_r > dz_b, "the torso side takes more of the arm's motion: {dz_r} vs {dz_b}");
            }
        }
    }

    #[test]
    fn nothing_is_held_without_a_pose_a_torso_or_a_forearm() {
        let (v, t, l) = strip(16);
        let w = CotanWeights::new(&v, &t);
        let none = |held: Vec<bool>| !held.iter().any(|&h| h);
        // The arm was not posed (too few cloud points): its vertices must follow the blending.
        assert!(none(shoulder_halves(&l, &w, &[])));
        let right_arm_only = SegmentPose { label: 4, ..arm_up() };
        assert!(none(shoulder_halves(&l, &w, &[right_arm_only])));
        // No torso labels: no shoulder to split at.
        let no_torso: Vec<u8> = l.iter().map(|&x| if x == 2 { 1 } else { x }).collect();
        assert!(none(shoulder_halves(&no_torso, &w, &[arm_up()])));
        // No forearm labels: the whole upper arm would be "nearer the torso"; hold nothing instead.
        let no_forearm: Vec<u8> = l.iter().map(|&x| if x == 5 { 7 } else { x }).collect();
        assert!(none(shoulder_halves(&no_forearm, &w, &[arm_up()])));
        // Only the other side's forearm: not this arm's elbow.
        let other_side: Vec<u8> = l.iter().map(|&x| if x == 5 { 6 } else { x }).collect();
        assert!(none(shoulder_halves(&other_side, &w, &[arm_up()])));
    }

    /// An elliptic tube along `axis` (unit, in the x-y plane) through the origin, `len` long (60 rings of 48):
    /// with `front_back` only the points the two cameras on z see (|n_z| > 0.3).
    fn tube(axis: [f64; 3], len: f64, rw: f64, rd: f64, front_back: bool) -> Vec<[f64; 3]> {
        let along = (0..60).map(|i| len * (i as f64 / 59.0 - 0.5));
        crate::testshapes::elliptic_tube(axis, along, 48, rw, rd, if front_back { 0.3 } else { 0.0 })
    }

    #[test]
    fn a_short_deep_upper_arm_is_still_sized_and_turned_once_its_axis_is_clear() {
        // The template's upper arm: 28 cm long, 4 cm round, hanging straight down.
        let template = tube([0.0, -1.0, 0.0], 0.28, 0.04, 0.04, false);
        let tl = vec![3u8; template.len()];
        // The cloud's: 25 cm between the armpit line and the elbow, turned 8 degrees, 1.9 and 2.1 x
        // deeper than wide, seen from the front and the back only.
        let a = 8f64.to_radians();
        for (depth, turned) in [(0.064, true), (0.070, false)] {
            let cloud = tube([a.sin(), -a.cos(), 0.0], 0.25, 0.034, depth, true);
            let (_, m) = moments(&cloud);
            let (_, ratio) = principal_axis(&m);
            let band = if turned {
                MIN_TURN_ELONGATION..MIN_ELONGATION
            } else {
                MIN_UPPER_ARM_ELONGATION..MIN_TURN_ELONGATION
            };
            assert!(band.contains(&ratio), "the cloud's elongation {ratio}");
            let poses = segment_poses(&template, &tl, &cloud, &vec![3u8; cloud.len()], true, true);
            assert_eq!(poses.len(), 1, "the short, deep arm is aligned (elongation {ratio})");
            let p = poses[0];
            let angle = if turned { 8.0 } else { 0.0 };
            assert!((p.angle_deg - angle).abs() < 1.0, "elongation {ratio}: turned by {}", p.angle_deg);
            assert!(p.section.depth_scale > 1.4, "depth scale {}", p.section.depth_scale);
            assert!(p.axial_scale < 0.95, "axial scale {}", p.axial_scale);
            assert!((p.elongation - ratio).abs() < 0.2, "elongation {} against {ratio}", p.elongation);
            // A thigh as round as that is left to the fit.
            let (t9, c9) = (vec![9u8; template.len()], vec![9u8; cloud.len()]);
            assert!(segment_poses(&template, &t9, &cloud, &c9, true, true).is_empty());
        }
    }

    #[test]
    fn a_cloud_limb_without_a_clear_or_plausible_axis_is_skipped() {
        let template = tube([0.0, -1.0, 0.0], 0.28, 0.04, 0.04, false);
        let tl = vec![3u8; template.len()];
        // As long as it is wide: no axis to turn the limb onto.
        let blob = tube([0.0, -1.0, 0.0], 0.1, 0.06, 0.06, false);
        assert!(segment_poses(&template, &tl, &blob, &vec![3u8; blob.len()], true, true).is_empty());
        // Long across the template's axis: a cross-section's axis, not the limb's.
        let across = tube([1.0, 0.0, 0.0], 0.28, 0.04, 0.04, false);
        assert!(segment_poses(&template, &tl, &across, &vec![3u8; across.len()], true, true).is_empty());
    }
}
