//! Derived indices: aggregates (trunk_limbs, whole, arms, legs), proximal/distal ratios, left/right
//! asymmetry and mass.

use crate::SegmentVolumes;
use bsv_core::{Aggregate, Segment};

/// Default body density, kg/m^3 (water; the paper's mass estimate).
pub const DEFAULT_DENSITY_KG_M3: f64 = 1000.0;

/// The volume of an aggregate, m^3: `whole` is always known (the mesh volume, unlabelled faces
/// included); the others only when every member segment is present.
pub fn aggregate(v: &SegmentVolumes, a: Aggregate) -> Option<f64> {
    match a.members() {
        None => Some(v.whole_m3),
        Some(members) => members.iter().map(|s| v.get(*s)).sum(),
    }
}

/// Every aggregate that can be computed, in `Aggregate::ALL` order, m^3.
pub fn aggregates(v: &SegmentVolumes) -> Vec<(Aggregate, f64)> {
    Aggregate::ALL.iter().filter_map(|&a| aggregate(v, a).map(|x| (a, x))).collect()
}

/// Left/right asymmetry in percent: `(L - R) / mean(L, R) * 100`; `None` when the mean is not positive.
pub fn asymmetry_pct(left: f64, right: f64) -> Option<f64> {
    let mean = 0.5 * (left + right);
    (mean > 0.0).then(|| (left - right) / mean * 100.0)
}

/// Distal/proximal ratios per side, keyed as in the JSON `ratios` section:
/// `forearm_to_upper_arm_l/_r`, `shin_to_thigh_l/_r` (only when both segments are present).
pub fn ratios(v: &SegmentVolumes) -> Vec<(&'static str, f64)> {
    let pairs = [
        ("forearm_to_upper_arm_l", Segment::ForearmL, Segment::UpperArmL),
        ("forearm_to_upper_arm_r", Segment::ForearmR, Segment::UpperArmR),
        ("shin_to_thigh_l", Segment::ShinL, Segment::ThighL),
        ("shin_to_thigh_r", Segment::ShinR, Segment::ThighR),
    ];
    pairs
        .iter()
        .filter_map(|&(k, distal, proximal)| match (v.get(distal), v.get(proximal)) {
            (Some(d), Some(p)) if p != 0.0 => Some((k, d / p)),
            _ => None,
        })
        .collect()
}

/// Left/right asymmetry (%) of upper arm, forearm, thigh, shin, arm and leg, keyed
/// `asymmetry_<part>_pct`; a part is reported only when both sides are present.
pub fn asymmetries(v: &SegmentVolumes) -> Vec<(&'static str, f64)> {
    let seg = |l: Segment, r: Segment| Some((v.get(l)?, v.get(r)?));
    let agg = |l: Aggregate, r: Aggregate| Some((aggregate(v, l)?, aggregate(v, r)?));
    let parts = [
        ("asymmetry_upper_arm_pct", seg(Segment::UpperArmL, Segment::UpperArmR)),
        ("asymmetry_forearm_pct", seg(Segment::ForearmL, Segment::ForearmR)),
        ("asymmetry_thigh_pct", seg(Segment::ThighL, Segment::ThighR)),
        ("asymmetry_shin_pct", seg(Segment::ShinL, Segment::ShinR)),
        ("asymmetry_arm_pct", agg(Aggregate::ArmL, Aggregate::ArmR)),
        ("asymmetry_leg_pct", agg(Aggregate::LegL, Aggregate::LegR)),
    ];
    parts.into_iter().filter_map(|(k, lr)| lr.and_then(|(l, r)| asymmetry_pct(l, r)).map(|a| (k, a))).collect()
}

/// Mass (kg) of a volume (m^3) at a density (kg/m^3).
pub fn mass_kg(volume_m3: f64, density_kg_m3: f64) -> f64 {
    volume_m3 * density_kg_m3
}
