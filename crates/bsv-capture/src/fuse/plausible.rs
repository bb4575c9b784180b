//! Plausibility of each view, checked after its cleaning and before the merge, so that a capture that
//! cannot be a standing person seen from its own side stops with a message instead of giving a
//! confident wrong volume:
//! - relief: a person has depth relief (a torso's sides lie 10-20 cm behind its middle); a flat wall
//!   deprojected through a person mask does not ([`MIN_RELIEF_M`]);
//! - sides: +X is the subject's left (DESIGN.md "Conventions"), so the points labelled as left limbs
//!   lie at larger x than the right limbs'. Swapped calibrations or swapped camera folders put each
//!   camera's surface at the mirror of where it belongs, and the limbs change sides.

use super::deproject::ViewPoints;
use super::floor::quantile;
use super::{DepthView, FuseError};
use bsv_core::Segment;

/// Smallest depth relief of a view's person (5-95 % range of the points' distances along the optical
/// axis), metres. A standing person seen by one camera spans 0.15-0.35 m; a flat surface spans its
/// depth noise (a few millimetres).
pub const MIN_RELIEF_M: f64 = 0.03;

/// Fewest points labelled left and right needed to judge a view's sides.
const MIN_SIDE_POINTS: usize = 200;

/// Left and right limb segments (arms, hands, legs, feet) as (left, right) id pairs.
const LIMB_PAIRS: [(Segment, Segment); 6] = [
    (Segment::UpperArmL, Segment::UpperArmR),
    (Segment::ForearmL, Segment::ForearmR),
    (Segment::HandL, Segment::HandR),
    (Segment::ThighL, Segment::ThighR),
    (Segment::ShinL, Segment::ShinR),
    (Segment::FootL, Segment::FootR),
];

/// Checks one cleaned view: depth relief, then the sides of its labelled limbs.
pub(super) fn check_view(view: &DepthView, vp: &ViewPoints) -> Result<(), FuseError> {
    let ext = &view.camera_to_world;
    let c = ext.translation;
    let axis = ext.transform_vector([0.0, 0.0, 1.0]);
    let depth: Vec<f64> =
        vp.points.iter().map(|p| (p[0] - c[0]) * axis[0] + (p[1] - c[1]) * axis[1] + (p[2] - c[2]) * axis[2]).collect();
    let relief = quantile(depth.clone(), 0.95) - quantile(depth, 0.05);
    if relief < MIN_RELIEF_M {
        return Err(FuseError::FlatView { camera: view.name.clone(), relief_m: relief });
    }
    let (mut left, mut right) = (Vec::new(), Vec::new());
    for (p, &l) in vp.points.iter().zip(&vp.labels) {
        for (sl, sr) in LIMB_PAIRS {
            if l == sl.id() {
                left.push(p[0]);
            } else if l == sr.id() {
                right.push(p[0]);
            }
        }
    }
    if left.len() < MIN_SIDE_POINTS || right.len() < MIN_SIDE_POINTS {
        return Ok(());
    }
    let (lx, rx) = (quantile(left, 0.5), quantile(right, 0.5));
    if lx < rx {
        return Err(FuseError::MirroredView { camera: view.name.clone(), left_x: lx, right_x: rx });
    }
    Ok(())
}
