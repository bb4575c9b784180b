//! Cross-section sizing of a limb in the articulated initialisation: the template limb's depth and
//! width scaled to the cloud's before the non-rigid fit.
//!
//! Why: the ARAP cells resist stretching (the regularization keeps them near rotations), so a limb
//! whose cross-section is larger than the template's is fitted by pulling the front and back patches
//! the cameras see apart while the unseen sides stay short and straighten: on the synthetic cohort
//! the vertices in the lateral gaps sat ~7 mm inside the true surface in noer (forearms -2 %, shins
//! -1 %), and a much deeper limb lost far more. Sizing the rest shape first leaves the fit nothing to
//! stretch.
//!
//! How, per limb, in the cloud limb's frame (axis `a`; depth `d` = the world z axis, the cameras'
//! line of sight, made perpendicular to `a`; width `w = a x d`), over five slices of the middle 60 %
//! of the limb's length (the joints are left alone), for the posed template vertices and the cloud
//! points alike:
//! - width: the extent of the projections on `w` (the silhouette, which both cameras see; depth
//!   noise runs along the rays, i.e. along `d`, and does not move it). The template's is the exact
//!   extent of its vertices. The cloud's points sample the silhouette uniformly in `w` (pixels) up to
//!   its edge, so the edge is extrapolated from the order statistics: with `w_(k)` the k-th largest,
//!   `edge = 2 w_(k) - w_(2k)` for [`EDGE_RANK`] = 3 (exact for a uniform density, and two stray
//!   points cannot move it). The 1 % / 99 % quantiles used before (session 4) sat 1 % of the width
//!   inside each edge on the cloud but not on the vertex ring, and a depth camera's silhouette loses
//!   part of its outermost pixels (mixed, flying): the limbs started 2-5 % too narrow, more in l515;
//! - depth: inside the central band (|w - centre| < half the half-width), the median of the points in
//!   front of the band's middle minus the median of those behind it: the front and back surfaces,
//!   with the depth noise averaged out instead of stretching an extreme quantile.
//!
//! The median over the slices of the cloud/template ratios gives the depth and width scales
//! (clamped to [`MIN_SCALE`, `MAX_SCALE`]); the median offset of the slice centres moves the template's
//! axis onto the cloud's. The depth estimator is the same on both sides, so its own bias (the
//! curvature of the band) cancels in the ratio.

use bsv_core::geometry::{cross, dot, normalize, sub};
use nalgebra::{Matrix3, Vector3};

/// Smallest and largest cross-section scale applied.
pub const MIN_SCALE: f64 = 0.75;
/// See [`MIN_SCALE`].
pub const MAX_SCALE: f64 = 1.6;
/// Slices over the middle of the limb.
const SLICES: usize = 5;
/// Fraction of the limb's length left out at each end (joints).
const END_FRACTION: f64 = 0.2;
/// Fewest template vertices / cloud points a slice needs.
const MIN_VERTICES: usize = 8;
const MIN_POINTS: usize = 30;
/// Fewest usable slices.
const MIN_SLICES: usize = 3;
/// Rank of the order statistic the cloud's silhouette edge is extrapolated from (see the module
/// docs): the edge is `2 w_(k) - w_(2k)` with `k` = this.
pub const EDGE_RANK: usize = 3;

/// How the items of a slice sample its cross-section.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Sampling {
    /// Mesh vertices, clean: the width is their exact extent.
    Vertices,
    /// Camera pixels, uniform across the silhouette up to its edges: the edges are extrapolated.
    Pixels,
}

/// The (low, high) edges of the projections `v` on the width axis (`v` is reordered).
fn width_edges(v: &mut [f64], sampling: Sampling) -> (f64, f64) {
    let n = v.len();
    let k = EDGE_RANK.min(n / 4);
    if sampling == Sampling::Vertices || k == 0 {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        return (lo, hi);
    }
    v.sort_unstable_by(f64::total_cmp);
    (2.0 * v[k - 1] - v[2 * k - 1], 2.0 * v[n - k] - v[n - 2 * k])
}

/// The cross-section change of one limb: `y -> y + shift + f(t) (map - I) (y - origin)` for positions
/// `y` relative to the cloud limb's centroid (the axis component is unchanged), where `f` is 1 over the
/// middle of the limb (where the scales were measured) and falls linearly to 0 at its ends, so that the
/// joints and the torso next to them keep their shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// `I + (depth - 1) d d^T + (width - 1) w w^T`.
    pub map: Matrix3<f64>,
    /// The template's slice centre (relative to the cloud centroid), metres.
    pub origin: [f64; 3],
    /// Offset from the template's slice centre to the cloud's, metres.
    pub shift: [f64; 3],
    /// Depth scale (cloud / template).
    pub depth_scale: f64,
    /// Width scale (cloud / template).
    pub width_scale: f64,
    /// The limb axis (unit).
    pub axis: [f64; 3],
    /// Axial positions (along `axis`): the limb's ends `ends.0`, `ends.3` and the measured middle
    /// `ends.1..ends.2`.
    pub ends: (f64, f64, f64, f64),
}

impl Section {
    /// No change.
    pub fn identity() -> Section {
        Section {
            map: Matrix3::identity(),
            origin: [0.0; 3],
            shift: [0.0; 3],
            depth_scale: 1.0,
            width_scale: 1.0,
            axis: [0.0, 1.0, 0.0],
            ends: (0.0, 0.0, 0.0, 0.0),
        }
    }

    /// Applies the change to `y` (relative to the cloud limb's centroid).
    pub fn apply(&self, y: [f64; 3]) -> [f64; 3] {
        let d = Vector3::from(sub(y, self.origin));
        let r = (self.map - Matrix3::identity()) * d * self.taper(dot(y, self.axis));
        [y[0] + self.shift[0] + r[0], y[1] + self.shift[1] + r[1], y[2] + self.shift[2] + r[2]]
    }

    /// 1 over the measured middle, linear to 0 at the ends, 0 beyond.
    fn taper(&self, t: f64) -> f64 {
        let (t0, a, b, t1) = self.ends;
        if t <= t0 || t >= t1 {
            0.0
        } else if t < a {
            (t - t0) / (a - t0).max(f64::MIN_POSITIVE)
        } else if t > b {
            (t1 - t) / (t1 - b).max(f64::MIN_POSITIVE)
        } else {
            1.0
        }
    }
}

fn quantile(v: &mut [f64], q: f64) -> f64 {
    let k = ((q * v.len() as f64) as usize).min(v.len() - 1);
    *v.select_nth_unstable_by(k, f64::total_cmp).1
}

fn median(v: &mut [f64]) -> Option<f64> {
    (!v.is_empty()).then(|| quantile(v, 0.5))
}

/// (depth, depth centre, width, width centre) of one slice's (u = depth, v = width) projections.
fn slice_extent(uv: &[(f64, f64)], sampling: Sampling) -> Option<(f64, f64, f64, f64)> {
    let mut v: Vec<f64> = uv.iter().map(|p| p.1).collect();
    let (lo, hi) = width_edges(&mut v, sampling);
    let (cw, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
    if half <= 0.0 {
        return None;
    }
    let mut band: Vec<f64> = uv.iter().filter(|p| (p.1 - cw).abs() < 0.5 * half).map(|p| p.0).collect();
    if band.len() < 4 {
        return None;
    }
    let mid = 0.5 * (quantile(&mut band, 0.05) + quantile(&mut band, 0.95));
    let mut front: Vec<f64> = band.iter().copied().filter(|&u| u > mid).collect();
    let mut back: Vec<f64> = band.iter().copied().filter(|&u| u <= mid).collect();
    let (f, b) = (median(&mut front)?, median(&mut back)?);
    (f > b).then_some((f - b, 0.5 * (f + b), hi - lo, cw))
}

/// The cross-section change taking the posed template limb (`posed`, relative to the cloud limb's
/// centroid) onto the cloud limb (`cloud`, relative to the same centroid) about the unit `axis`;
/// `None` when the limb lies along the line of sight or too few slices are usable.
pub fn fit_section(posed: &[[f64; 3]], cloud: &[[f64; 3]], axis: [f64; 3]) -> Option<Section> {
    let z = [0.0, 0.0, 1.0];
    let along = dot(z, axis);
    let dz = sub(z, axis.map(|c| c * along));
    if dot(dz, dz) < 0.25 {
        return None;
    }
    let d = normalize(dz);
    let w = cross(axis, d);
    let mut t: Vec<f64> = cloud.iter().map(|p| dot(*p, axis)).collect();
    if t.len() < MIN_POINTS * SLICES {
        return None;
    }
    let (t0, t1) = (quantile(&mut t, 0.02), quantile(&mut t, 0.98));
    let (a, b) = (t0 + END_FRACTION * (t1 - t0), t1 - END_FRACTION * (t1 - t0));
    let step = (b - a) / SLICES as f64;
    if step <= 0.0 {
        return None;
    }
    let bin = |p: &[f64; 3]| {
        let s = (dot(*p, axis) - a) / step;
        (s >= 0.0 && s < SLICES as f64).then_some(s as usize)
    };
    let split = |pts: &[[f64; 3]]| {
        let mut out: Vec<Vec<(f64, f64)>> = vec![Vec::new(); SLICES];
        for p in pts {
            if let Some(k) = bin(p) {
                out[k].push((dot(*p, d), dot(*p, w)));
            }
        }
        out
    };
    let (ts, cs) = (split(posed), split(cloud));
    let (mut rd, mut rw, mut od, mut ow, mut td, mut tw) = (vec![], vec![], vec![], vec![], vec![], vec![]);
    for (tv, cv) in ts.iter().zip(&cs) {
        if tv.len() < MIN_VERTICES || cv.len() < MIN_POINTS {
            continue;
        }
        let (Some(te), Some(ce)) = (slice_extent(tv, Sampling::Vertices), slice_extent(cv, Sampling::Pixels)) else {
            continue;
        };
        rd.push(ce.0 / te.0);
        rw.push(ce.2 / te.2);
        od.push(ce.1 - te.1);
        ow.push(ce.3 - te.3);
        td.push(te.1);
        tw.push(te.3);
    }
    if rd.len() < MIN_SLICES {
        return None;
    }
    let depth_scale = median(&mut rd)?.clamp(MIN_SCALE, MAX_SCALE);
    let width_scale = median(&mut rw)?.clamp(MIN_SCALE, MAX_SCALE);
    let (sd, sw, cd, cw) = (median(&mut od)?, median(&mut ow)?, median(&mut td)?, median(&mut tw)?);
    let (dv, wv) = (Vector3::from(d), Vector3::from(w));
    let map =
        Matrix3::identity() + dv * dv.transpose() * (depth_scale - 1.0) + wv * wv.transpose() * (width_scale - 1.0);
    let comb = |x: f64, y: f64| [d[0] * x + w[0] * y, d[1] * x + w[1] * y, d[2] * x + w[2] * y];
    Some(Section {
        map,
        origin: comb(cd, cw),
        shift: comb(sd, sw),
        depth_scale,
        width_scale,
        axis,
        ends: (t0, a, b, t1),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An elliptic cylinder along y with semi-axes `rx` (width, x) and `rz` (depth, z), sampled on
    /// its surface; `front_back_only` drops the grazing |nz| < 0.05 band (what two cameras on z miss).
    fn cylinder(rx: f64, rz: f64, n: usize, front_back_only: bool) -> Vec<[f64; 3]> {
        let along = (0..n).map(|i| -0.15 + 0.3 * i as f64 / n as f64);
        crate::testshapes::elliptic_tube([0.0, 1.0, 0.0], along, 72, rx, rz, if front_back_only { 0.05 } else { 0.0 })
    }

    #[test]
    fn recovers_depth_and_width_of_an_elliptic_limb_from_its_front_and_back() {
        let template = cylinder(0.04, 0.04, 30, false);
        let cloud = cylinder(0.036, 0.06, 120, true);
        let s = fit_section(&template, &cloud, [0.0, 1.0, 0.0]).expect("a section");
        assert!((s.depth_scale - 1.5).abs() < 0.03, "depth {}", s.depth_scale);
        assert!((s.width_scale - 0.9).abs() < 0.05, "width {}", s.width_scale);
        let moved = s.apply([0.0, 0.0, 0.04]);
        assert!((moved[2] - 0.06).abs() < 0.002, "{moved:?}");
        let end = s.apply([0.0, 0.2, 0.04]);
        assert!((end[2] - 0.04).abs() < 1e-12, "beyond the limb's end nothing is scaled: {end:?}");
    }

    /// The elliptic cylinder as two cameras on +z and -z see it: per row of pixels (every 3 mm along
    /// y), the front and back surfaces at x every `pitch` (the grid's phase changes from row to row, as
    /// on a limb not aligned with the pixel grid), the outermost pixel of every other row lost (a mixed
    /// or flying pixel), and `stray` points 2 cm outside the silhouette per side in every 25th row (at most two per slice).
    fn pixels(rx: f64, rz: f64, pitch: f64, stray: usize) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        let m = (rx / pitch) as i64 + 1;
        for row in 0..100 {
            let y = -0.15 + 0.003 * row as f64;
            let phase = (row as f64 * 0.618_034).fract() * pitch;
            let xs: Vec<f64> = (-m - 1..=m).map(|i| i as f64 * pitch + phase).filter(|x| x.abs() < rx).collect();
            let lose = usize::from(row % 2 == 0);
            for &x in &xs[lose..xs.len() - lose] {
                let z = rz * (1.0 - (x / rx).powi(2)).sqrt();
                out.push([x, y, z]);
                out.push([x, y, -z]);
            }
            if row % 25 == 0 {
                for k in 0..stray {
                    out.push([rx + 0.02 + 0.001 * k as f64, y, 0.0]);
                    out.push([-rx - 0.02 - 0.001 * k as f64, y, 0.0]);
                }
            }
        }
        out
    }

    #[test]
    fn the_width_comes_from_the_silhouette_edges_of_a_pixel_sampled_cloud() {
        let template = cylinder(0.04, 0.04, 30, false);
        // A 40 mm wide forearm seen with 2.7 mm pixels, half its rim pixels lost: the edge is
        // extrapolated (the 1 % quantiles gave a width 3.4 % short here).
        let s = fit_section(&template, &pixels(0.036, 0.05, 0.0027, 0), [0.0, 1.0, 0.0]).expect("a section");
        assert!((s.width_scale - 0.9).abs() < 0.012, "width {}", s.width_scale);
        assert!((s.depth_scale - 1.25).abs() < 0.03, "depth {}", s.depth_scale);
        // Two stray points per side and slice do not move it.
        let s2 = fit_section(&template, &pixels(0.036, 0.05, 0.0027, 2), [0.0, 1.0, 0.0]).expect("a section");
        assert!(
            (s2.width_scale - s.width_scale).abs() < 0.01,
            "width {} with strays, {} without",
            s2.width_scale,
            s.width_scale
        );
    }

    #[test]
    fn a_limb_along_the_line_of_sight_is_left_alone() {
        let template: Vec<[f64; 3]> = cylinder(0.04, 0.04, 30, false).iter().map(|p| [p[0], p[2], p[1]]).collect();
        assert!(fit_section(&template, &template, [0.0, 0.0, 1.0]).is_none());
    }
}
