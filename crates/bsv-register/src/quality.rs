//! Per-segment quality figures of a finished fit ([`SegmentQuality`], in
//! `Registration::quality`): how closely the fitted segment lies on the cloud where the cameras
//! see it, how much of it the cloud covers, how much lies in the lateral gaps, and a `doubtful`
//! flag.
//!
//! For each fitted vertex, `d` is the distance to its nearest cloud point (the cloud the fit used)
//! and `n` its area-weighted vertex normal. A vertex is
//! - covered when `d <= COVER_M` (10 mm);
//! - in a gap when it is not covered and its normal is lateral, `|n_x| >= GAP_NORMAL_X` (0.5, i.e.
//!   within 60 degrees of +-x): the sides that neither the front nor the back camera sees;
//! - exposed-uncovered otherwise: it faces a camera but no cloud point lies near it.
//!
//! A vertex is on a fold when one of its edges joins two faces that turned more than 90 degrees
//! against each other (`cos < FOLD_COS`) where the template's surface was smooth (`cos >=
//! SMOOTH_COS`: the caps' sharp rims at the neck, wrists and ankles do not count): the fit crossed
//! the surface over itself, which no cloud distance shows (a folded upper arm keeps its RMS and
//! coverage) but which loses volume (-10 to -21 % on the upper arms folded by the depth-stretched
//! pre-alignment of round 2, session 4).
//!
//! Per segment (the fitted mesh's vertex labels; `whole` when it has none): `rms_mm` is the RMS of
//! `d` over the vertices not in a gap with `d <= RMS_CAP_M` (30 mm: the part the data hold; the caps
//! at the neck, wrists and ankles and the crotch have no cloud and are counted by the fractions
//! instead), `coverage` the fraction covered, `gap_fraction` the fraction in gaps,
//! `exposed_uncovered` the fraction exposed-uncovered. The fit of a segment is `doubtful` when
//! `rms_mm > DOUBT_RMS_MM` (10 mm), or `exposed_uncovered > DOUBT_EXPOSED` (0.2), or
//! `coverage < DOUBT_COVERAGE` (0.65), or `folded > DOUBT_FOLDED` (`DOUBT_FOLDED_TORSO` for the torso): the segment left the data where
//! the cameras saw it, the cloud hardly holds it, or it folded over itself. (0.5 until the ray-parallel removal, which thins the grazing edges: a
//! one-iteration fit with its shin 27 % off kept coverage 0.53; good fits of 6 subjects in noer,
//! l515 and l5ca: 0.76 at least, camera path 0.82.)
//!
//! Measured (labelled oracle clouds of subjects 0-1 of the synthetic cohort, all four conditions,
//! with and without a room, default parameters), worst segment: RMS 5.0-7.2 mm, coverage 0.72-0.89,
//! exposed-uncovered 0.06-0.13, no flag; with one limb swollen by 40 % the fit follows it and is not
//! flagged; deliberately bad fits (one iteration): coverage 0.36-0.42, exposed-uncovered 0.32-0.42,
//! 5-9 segments flagged. Unlabelled clouds (template labels, no label-aware correspondences) leave
//! the arms with coverage 0.21-0.38: their arms are flagged.

use bsv_core::geometry::{dot, face_normals, vertex_normals};
use bsv_core::{Segment, TriMesh};
use serde::Serialize;
use std::collections::BTreeMap;

/// A vertex with a cloud point within this distance (metres) is covered.
pub const COVER_M: f64 = 0.01;
/// An uncovered vertex whose normal has `|n_x|` at least this lies in a lateral gap.
pub const GAP_NORMAL_X: f64 = 0.5;
/// Vertices farther than this (metres) from the cloud are left out of the RMS.
pub const RMS_CAP_M: f64 = 0.03;
/// A segment with an RMS above this (mm) is doubtful.
pub const DOUBT_RMS_MM: f64 = 10.0;
/// A segment with more than this fraction of exposed-uncovered vertices is doubtful.
pub const DOUBT_EXPOSED: f64 = 0.2;
/// A segment with less than this fraction of covered vertices is doubtful.
pub const DOUBT_COVERAGE: f64 = 0.65;
/// Two adjacent fitted faces whose normals' cosine is below this are folded against each other.
pub const FOLD_COS: f64 = 0.0;
/// An edge counts for folds only where the template's faces' cosine is at least this (smooth).
pub const SMOOTH_COS: f64 = 0.5;
/// A segment with more than this fraction of its vertices on a fold is doubtful. Measured (L515-like
/// oracle clouds of 7 subjects): good fits 0-4.7 % (torso, forearms, shins: the template's own creases
/// near the caps); upper arms folded by the depth-stretched pre-alignment 6-29 %, the catastrophic
/// ones (-10 to -21 % volume) 14-29 %.
pub const DOUBT_FOLDED: f64 = 0.08;
/// [`DOUBT_FOLDED`] of the torso. Its correspondences are pruned at 6 x the median since round 2
/// session 31 (`prune_distance_factor_torso`), and its good fits then fold 3.4-8.5 % of its vertices
/// (subjects 0-1 of the cohort, four conditions; 3.2-4.7 % before), near the neck's rim and in the
/// crotch, where no cloud lies. Its volume is unharmed (torso -0.5 to +1.5 %, -0.6 to +1.3 % at 3 x).
pub const DOUBT_FOLDED_TORSO: f64 = 0.12;

/// The quality figures of one fitted segment (see the module).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SegmentQuality {
    /// Fitted vertices of the segment.
    pub vertices: usize,
    /// RMS distance (mm) to their nearest cloud point of the segment's vertices not in a gap and
    /// within [`RMS_CAP_M`] of the cloud.
    pub rms_mm: f64,
    /// Fraction of the vertices with a cloud point within [`COVER_M`].
    pub coverage: f64,
    /// Fraction of the vertices in the lateral gaps (uncovered, normal within 60 degrees of +-x).
    pub gap_fraction: f64,
    /// Fraction of the vertices facing a camera with no cloud point within [`COVER_M`].
    pub exposed_uncovered: f64,
    /// Fraction of the vertices on a fold (an edge turned beyond 90 degrees where the template was
    /// smooth; see the module).
    pub folded: f64,
    /// The fit of this segment is doubtful (see the module for the rule).
    pub doubtful: bool,
}

/// Per vertex of `mesh`: whether it is on a fold against `template` (same triangles; see the module).
fn on_fold(mesh: &TriMesh, template: &TriMesh) -> Vec<bool> {
    let fitted = face_normals(mesh);
    let rest = face_normals(template);
    bsv_core::topology::vertices_on_edges(mesh.vertices.len(), &mesh.triangles, |f, g| {
        dot(fitted[f], fitted[g]) < FOLD_COS && dot(rest[f], rest[g]) >= SMOOTH_COS
    })
}

/// The quality of every segment of the fitted `mesh`, keyed by segment name (`whole` for an
/// unlabelled mesh); `nearest[i].1` is the squared distance of vertex `i` to its nearest cloud point;
/// `template` is the mesh it was fitted from (same triangles), for the folds.
pub fn segment_quality(mesh: &TriMesh, nearest: &[(u32, f64)], template: &TriMesh) -> BTreeMap<String, SegmentQuality> {
    let normals = vertex_normals(mesh);
    let folds = on_fold(mesh, template);
    let mut acc: BTreeMap<u8, Tally> = BTreeMap::new();
    for (i, &(_, d2)) in nearest.iter().enumerate() {
        let label = mesh.vertex_labels.as_ref().map_or(0, |l| l.get(i).copied().unwrap_or(0));
        let a = acc.entry(label).or_default();
        a.vertices += 1;
        a.folded += usize::from(folds.get(i).copied().unwrap_or(false));
        let covered = d2 <= COVER_M * COVER_M;
        let lateral = normals.get(i).is_some_and(|n| n[0].abs() >= GAP_NORMAL_X);
        if covered {
            a.covered += 1;
        } else if lateral {
            a.gap += 1;
            continue;
        } else {
            a.exposed += 1;
        }
        if d2 <= RMS_CAP_M * RMS_CAP_M {
            a.rms_count += 1;
            a.rms_sum += d2;
        }
    }
    acc.into_iter()
        .map(|(label, t)| {
            let name = if mesh.vertex_labels.is_none() {
                "whole".to_string()
            } else {
                Segment::from_id(label).map_or_else(|| format!("label_{label}"), |s| s.name().to_string())
            };
            let fold_limit = if label == Segment::Torso as u8 && mesh.vertex_labels.is_some() {
                DOUBT_FOLDED_TORSO
            } else {
                DOUBT_FOLDED
            };
            (name, t.quality(fold_limit))
        })
        .collect()
}

/// The counts of one segment.
#[derive(Default)]
struct Tally {
    vertices: usize,
    folded: usize,
    covered: usize,
    gap: usize,
    exposed: usize,
    /// Vertices in the RMS and their sum of squared distances.
    rms_count: usize,
    rms_sum: f64,
}

impl Tally {
    /// The figures of the tally; `fold_limit` is the segment's folded fraction beyond which it is doubtful.
    fn quality(&self, fold_limit: f64) -> SegmentQuality {
        let n = self.vertices.max(1) as f64;
        let rms_mm = if self.rms_count > 0 { (self.rms_sum / self.rms_count as f64).sqrt() * 1e3 } else { 0.0 };
        let (coverage, exposed_uncovered) = (self.covered as f64 / n, self.exposed as f64 / n);
        let folded = self.folded as f64 / n;
        SegmentQuality {
            vertices: self.vertices,
            rms_mm,
            coverage,
            gap_fraction: self.gap as f64 / n,
            exposed_uncovered,
            folded,
            doubtful: rms_mm > DOUBT_RMS_MM
                || exposed_uncovered > DOUBT_EXPOSED
                || coverage < DOUBT_COVERAGE
                || folded > fold_limit,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bsv_core::shapes::icosphere;

    /// Every vertex at distance 0 from the cloud (the folds alone decide).
    fn on_cloud(mesh: &TriMesh) -> Vec<(u32, f64)> {
        (0..mesh.vertices.len() as u32).map(|i| (i, 0.0)).collect()
    }

    #[test]
    fn a_cap_pushed_through_the_surface_is_a_fold_and_the_template_is_not() {
        // A sphere whose top (z > 0.025) is the upper arm, the rest the torso.
        let mut template = icosphere(0.05, 3);
        let arm = Segment::UpperArmL.id();
        let torso = Segment::Torso.id();
        template.vertex_labels =
            Some(template.vertices.iter().map(|p| if p[2] > 0.025 { arm } else { torso }).collect());
        let q = segment_quality(&template, &on_cloud(&template), &template);
        assert!(q.values().all(|s| s.folded == 0.0 && !s.doubtful));
        // Push the top cap (z > 0.03) down through the sphere: its rim turns over.
        let mut folded = template.clone();
        for p in &mut folded.vertices {
            if p[2] > 0.03 {
                p[2] = 0.03 - 3.0 * (p[2] - 0.03);
            }
        }
        let q = segment_quality(&folded, &on_cloud(&folded), &template);
        let a = q["upper_arm_l"];
        assert!(a.folded > DOUBT_FOLDED, "folded {}", a.folded);
        assert!(a.doubtful);
        assert!(!q["torso"].doubtful, "the torso below is intact: {:?}", q["torso"]);
        // The same fold in a torso (the upper half of the sphere): between the two limits, so a limb
        // would be doubtful and the torso is not.
        let halves: Vec<u8> = template.vertices.iter().map(|p| if p[2] > 0.0 { torso } else { arm }).collect();
        let (mut as_torso, mut rest) = (folded.clone(), template.clone());
        (as_torso.vertex_labels, rest.vertex_labels) = (Some(halves.clone()), Some(halves));
        let t = segment_quality(&as_torso, &on_cloud(&as_torso), &rest)["torso"];
        assert!(t.folded > DOUBT_FOLDED && t.folded < DOUBT_FOLDED_TORSO, "{t:?}");
        assert!(!t.doubtful, "{t:?}");
    }
}
