//! The floor under the subject, seen by each camera: a plane fitted robustly to ALL valid depth
//! pixels of the view (not only the person mask), in the world frame of that camera's calibration.
//!
//! Samples: every [`SAMPLE_STRIDE`]-th pixel in both directions, deprojected and transformed with the
//! camera's extrinsics. Search: only samples at most [`SEARCH_ABOVE_PERSON_M`] above the person's
//! lowest points take part, RANSAC hypotheses (three samples, deterministic draws) whose normal leans
//! at most `max_tilt_deg` from world up and whose height at the subject is at most
//! [`ABOVE_PERSON_TOLERANCE_M`] above the person's lowest points (a table or a ceiling never
//! qualifies); the hypothesis with the most inliers wins and is refitted by least squares
//! (`y = a x + b z + c`) on its inliers, three times. It counts as the floor ("seen") when enough of
//! its inliers lie outside the person mask (`min_pixels`, in full-resolution pixels): the soles of a
//! body standing in an empty room are never taken for a floor.
//!
//! The fitted plane is then a check of the calibration, which puts the floor at y = 0 with +Y up:
//! its tilt from world up (pitch about world X, roll about world Z) and its height at the subject.

use bsv_core::geometry::{cross, dot, norm, scale, sub};
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::Serialize;

/// The floor samples are taken every `SAMPLE_STRIDE` pixels along rows and columns.
pub const SAMPLE_STRIDE: usize = 4;
/// Only samples at most this far (metres) above the person's lowest points take part in the search.
pub const SEARCH_ABOVE_PERSON_M: f64 = 0.10;
/// A floor hypothesis may lie at most this far (metres) above the person's lowest points at the subject.
pub const ABOVE_PERSON_TOLERANCE_M: f64 = 0.05;
/// Fraction of the person's points taken as its lowest points (robust to a few stray pixels).
pub const PERSON_LOW_QUANTILE: f64 = 0.005;
/// Number of RANSAC hypotheses.
pub const RANSAC_HYPOTHESES: usize = 256;
/// At most this many samples (a regular subset) score each hypothesis.
const SCORE_SAMPLES: usize = 8192;
/// Least-squares refits of the winning hypothesis.
const REFITS: usize = 3;

/// A plane in the world frame: the points `p` with `dot(normal, p) = offset`; `normal` is a unit
/// vector pointing up (`normal[1] > 0`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Plane {
    /// Unit normal, pointing up.
    pub normal: [f64; 3],
    /// `dot(normal, p)` of the plane's points, metres.
    pub offset: f64,
}

impl Plane {
    /// The plane through three points, normal turned up; `None` when they are (nearly) collinear.
    pub fn through(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Option<Plane> {
        let n = cross(sub(b, a), sub(c, a));
        let len = norm(n);
        if !(len > 1e-12 && len.is_finite()) {
            return None;
        }
        let n = scale(n, if n[1] < 0.0 { -1.0 / len } else { 1.0 / len });
        Some(Plane { normal: n, offset: dot(n, a) })
    }

    /// Signed distance of `p` above the plane (along the normal), metres.
    #[inline]
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        dot(self.normal, p) - self.offset
    }

    /// Height (world y) of the plane at world (x, z); NaN for a vertical plane.
    pub fn height_at(&self, x: f64, z: f64) -> f64 {
        let n = self.normal;
        (self.offset - n[0] * x - n[2] * z) / n[1]
    }

    /// Angle between the normal and world up (+Y), degrees.
    pub fn tilt_deg(&self) -> f64 {
        self.normal[1].clamp(-1.0, 1.0).acos().to_degrees()
    }

    /// Lean of the normal toward +Z (the front camera), a rotation about world X, degrees.
    pub fn pitch_deg(&self) -> f64 {
        self.normal[2].atan2(self.normal[1]).to_degrees()
    }

    /// Lean of the normal toward +X (the subject's left), a rotation about world Z, degrees.
    pub fn roll_deg(&self) -> f64 {
        self.normal[0].atan2(self.normal[1]).to_degrees()
    }

    /// Angle between two planes' normals, degrees.
    pub fn angle_deg(&self, other: &Plane) -> f64 {
        dot(self.normal, other.normal).clamp(-1.0, 1.0).acos().to_degrees()
    }
}

/// World-frame samples of one camera's valid depth pixels.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FloorSamples {
    /// Sample points, world frame.
    pub points: Vec<[f64; 3]>,
    /// Whether each sample's pixel belongs to the person mask.
    pub person: Vec<bool>,
    /// Pixels each sample stands for (the stride squared).
    pub pixels_per_sample: usize,
}

/// Search settings of [`fit_floor`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorSearch {
    /// A sample within this distance (metres) of a plane is an inlier.
    pub inlier_m: f64,
    /// Largest angle between a floor's normal and world up, degrees.
    pub max_tilt_deg: f64,
    /// Fewest inliers outside the person mask (full-resolution pixels) for the floor to count as seen.
    pub min_pixels: usize,
}

/// A floor found in one camera's view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorFit {
    /// The refitted plane.
    pub plane: Plane,
    /// Samples on the plane.
    pub inliers: usize,
    /// Samples on the plane outside the person mask.
    pub background_inliers: usize,
    /// Root-mean-square distance of the inliers to the plane, metres.
    pub rms_m: f64,
}

/// The value at fraction `q` (0..=1) of the sorted values (nearest rank); NaN when empty.
pub fn quantile(mut values: Vec<f64>, q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let k = ((values.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    *values.select_nth_unstable_by(k, f64::total_cmp).1
}

/// The floor of one view, or `None` when no plane qualifies (see the module docs). `person_low_y`:
/// the person's lowest height ([`PERSON_LOW_QUANTILE`] of its points), `subject_xz`: where the
/// subject stands (world x, z).
pub fn fit_floor(
    samples: &FloorSamples,
    person_low_y: f64,
    subject_xz: [f64; 2],
    search: &FloorSearch,
) -> Option<FloorFit> {
    let ceiling = person_low_y + SEARCH_ABOVE_PERSON_M;
    let cand: Vec<usize> = (0..samples.points.len()).filter(|&i| samples.points[i][1] <= ceiling).collect();
    let per = samples.pixels_per_sample.max(1);
    let background = cand.iter().filter(|&&i| !samples.person[i]).count();
    if cand.len() < 3 || background * per < search.min_pixels {
        return None;
    }
    let pts: Vec<[f64; 3]> = cand.iter().map(|&i| samples.points[i]).collect();
    let cos_max = search.max_tilt_deg.to_radians().cos();
    let admissible = |p: &Plane| {
        p.normal[1] >= cos_max && p.height_at(subject_xz[0], subject_xz[1]) <= person_low_y + ABOVE_PERSON_TOLERANCE_M
    };
    let best = ransac(&pts, search.inlier_m, &admissible)?;
    let mut plane = best;
    for _ in 0..REFITS {
        let inl: Vec<[f64; 3]> = pts.iter().copied().filter(|&p| plane.distance(p).abs() <= search.inlier_m).collect();
        plane = least_squares_plane(&inl).unwrap_or(plane);
    }
    if !admissible(&plane) {
        return None;
    }
    let (mut inliers, mut background_inliers, mut sq) = (0usize, 0usize, 0.0f64);
    for (&i, &p) in cand.iter().zip(&pts) {
        let d = plane.distance(p);
        if d.abs() <= search.inlier_m {
            inliers += 1;
            sq += d * d;
            background_inliers += usize::from(!samples.person[i]);
        }
    }
    if background_inliers * per < search.min_pixels {
        return None;
    }
    Some(FloorFit { plane, inliers, background_inliers, rms_m: (sq / inliers.max(1) as f64).sqrt() })
}

/// The admissible three-point plane with the most inliers among [`RANSAC_HYPOTHESES`] deterministic
/// draws (ties: the earliest draw), scored on at most `SCORE_SAMPLES` samples.
fn ransac(pts: &[[f64; 3]], inlier_m: f64, admissible: &(dyn Fn(&Plane) -> bool + Sync)) -> Option<Plane> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(0x0F1 + pts.len() as u64);
    let n = pts.len();
    let draws: Vec<[usize; 3]> = (0..RANSAC_HYPOTHESES)
        .map(|_| [rng.random_range(0..n), rng.random_range(0..n), rng.random_range(0..n)])
        .collect();
    let step = n.div_ceil(SCORE_SAMPLES).max(1);
    let scored: Vec<(usize, usize, Plane)> = draws
        .par_iter()
        .enumerate()
        .filter_map(|(k, d)| {
            let p = Plane::through(pts[d[0]], pts[d[1]], pts[d[2]])?;
            if !admissible(&p) {
                return None;
            }
            let score = pts.iter().step_by(step).filter(|&&q| p.distance(q).abs() <= inlier_m).count();
            Some((score, k, p))
        })
        .collect();
    scored.into_iter().max_by(|a, b| a.0.cmp(&b.0).then(b.1.cmp(&a.1))).map(|(_, _, p)| p)
}

/// Least-squares plane `y = a x + b z + c` through `pts` (the floor is near horizontal, so the
/// vertical residual is the distance to within cos(tilt)); `None` when degenerate.
pub fn least_squares_plane(pts: &[[f64; 3]]) -> Option<Plane> {
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let mean = pts.iter().fold([0.0; 3], |m, p| [m[0] + p[0], m[1] + p[1], m[2] + p[2]]).map(|s| s / n);
    let (mut sxx, mut sxz, mut szz, mut sxy, mut szy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for p in pts {
        let (x, y, z) = (p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]);
        sxx += x * x;
        sxz += x * z;
        szz += z * z;
        sxy += x * y;
        szy += z * y;
    }
    let det = sxx * szz - sxz * sxz;
    if det.abs() <= 1e-12 * (sxx * szz).max(1e-300) || !det.is_finite() {
        return None;
    }
    let a = (sxy * szz - szy * sxz) / det;
    let b = (szy * sxx - sxy * sxz) / det;
    let c = mean[1] - a * mean[0] - b * mean[2];
    let len = (a * a + 1.0 + b * b).sqrt();
    let plane = Plane { normal: [-a / len, 1.0 / len, -b / len], offset: c / len };
    plane.normal.iter().all(|v| v.is_finite()).then_some(plane)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn grid(f: impl Fn(f64, f64) -> f64, person: bool) -> Vec<([f64; 3], bool)> {
        let mut out = Vec::new();
        for i in 0..60 {
            for j in 0..60 {
                let (x, z) = (-1.5 + 0.05 * f64::from(i), -1.5 + 0.05 * f64::from(j));
                out.push(([x, f(x, z), z], person));
            }
        }
        out
    }

    fn samples(parts: Vec<Vec<([f64; 3], bool)>>) -> FloorSamples {
        let all: Vec<([f64; 3], bool)> = parts.into_iter().flatten().collect();
        FloorSamples {
            points: all.iter().map(|p| p.0).collect(),
            person: all.iter().map(|p| p.1).collect(),
            pixels_per_sample: 16,
        }
    }

    const SEARCH: FloorSearch = FloorSearch { inlier_m: 0.02, max_tilt_deg: 10.0, min_pixels: 5000 };

    #[test]
    fn a_tilted_floor_is_recovered_and_a_table_above_the_feet_is_not_taken() {
        let tilt = 1.0f64.to_radians().tan();
        let floor = grid(|_, z| 0.01 + tilt * z, false);
        let table = grid(|_, _| 0.75, false);
        let fit = fit_floor(&samples(vec![floor, table]), 0.02, [0.0, 0.0], &SEARCH).unwrap();
        assert!((fit.plane.pitch_deg() + 1.0).abs() < 1e-6, "pitch {}", fit.plane.pitch_deg());
        assert!(fit.plane.roll_deg().abs() < 1e-6);
        assert!((fit.plane.height_at(0.0, 0.0) - 0.01).abs() < 1e-9);
        assert_eq!(fit.inliers, 3600);
        assert!(fit.rms_m < 1e-9);
    }

    #[test]
    fn a_floor_made_of_person_pixels_only_is_not_seen() {
        let soles = grid(|_, _| 0.0, true);
        assert!(fit_floor(&samples(vec![soles]), 0.0, [0.0, 0.0], &SEARCH).is_none());
        let steep = grid(|x, _| 0.5 * x, false);
        assert!(fit_floor(&samples(vec![steep]), 0.0, [0.0, 0.0], &SEARCH).is_none());
    }

    #[test]
    fn least_squares_and_quantile() {
        let pts: Vec<[f64; 3]> = grid(|x, z| 0.1 + 0.02 * x - 0.01 * z, false).into_iter().map(|p| p.0).collect();
        let p = least_squares_plane(&pts).unwrap();
        assert!(pts.iter().all(|&q| p.distance(q).abs() < 1e-12));
        assert!((p.height_at(1.0, 1.0) - 0.11).abs() < 1e-12);
        assert_eq!(quantile(vec![3.0, 1.0, 2.0], 0.0), 1.0);
        assert_eq!(quantile(vec![3.0, 1.0, 2.0], 1.0), 3.0);
        assert!(quantile(vec![], 0.5).is_nan());
    }
}
