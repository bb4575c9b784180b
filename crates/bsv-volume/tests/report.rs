//! Aggregates, ratios, asymmetry, mass and the JSON / table report.
#![allow(clippy::unwrap_used)]

use bsv_core::geometry::{add, scale};
use bsv_core::shapes::{capsule, subdivided_cuboid, translate};
use bsv_core::{Segment, TriMesh};
use bsv_volume::{
    aggregates, asymmetry_pct, report, segment_volumes, CapStats, LabelSource, SegmentVolumes, VolumeError,
    VolumeReport,
};
use std::collections::BTreeMap;

fn volumes(pairs: &[(Segment, f64)], whole: f64) -> SegmentVolumes {
    SegmentVolumes {
        whole_m3: whole,
        segments: pairs.iter().copied().collect::<BTreeMap<_, _>>(),
        unlabelled_m3: None,
        label_source: LabelSource::Faces,
        holes: Vec::new(),
        inverted: false,
        islands: None,
        caps: CapStats::default(),
        notes: Vec::new(),
    }
}

fn full_body() -> SegmentVolumes {
    use Segment::*;
    let v = [
        (Head, 0.004),
        (Torso, 0.030),
        (UpperArmL, 0.0020),
        (UpperArmR, 0.0016),
        (ForearmL, 0.0010),
        (ForearmR, 0.0012),
        (ThighL, 0.0060),
        (ThighR, 0.0050),
        (ShinL, 0.0030),
        (ShinR, 0.0030),
    ];
    let whole = v.iter().map(|p| p.1).sum();
    volumes(&v, whole)
}

#[test]
fn aggregates_ratios_asymmetry_and_mass() {
    let v = full_body();
    let aggs = aggregates(&v);
    let names: Vec<&str> = aggs.iter().map(|a| a.0.name()).collect();
    assert_eq!(names, ["trunk_limbs", "whole", "arm_l", "arm_r", "leg_l", "leg_r"]);
    let r = VolumeReport::from_volumes(&v, 1000.0).unwrap();
    let l = |k: &str| r.volumes_l.get(k).unwrap();
    assert!((l("trunk_limbs") - 52.8).abs() < 1e-9);
    assert!((l("whole") - 56.8).abs() < 1e-9);
    assert!((l("arm_l") - 3.0).abs() < 1e-9 && (l("leg_r") - 8.0).abs() < 1e-9);
    let x = |k: &str| r.ratios.get(k).unwrap();
    assert!((x("forearm_to_upper_arm_l") - 0.5).abs() < 1e-12);
    assert!((x("forearm_to_upper_arm_r") - 0.75).abs() < 1e-12);
    assert!((x("shin_to_thigh_l") - 0.5).abs() < 1e-12);
    assert!((x("shin_to_thigh_r") - 0.6).abs() < 1e-12);
    assert!((x("asymmetry_upper_arm_pct") - 0.4 / 1.8 * 100.0).abs() < 1e-9);
    assert!((x("asymmetry_forearm_pct") + 0.2 / 1.1 * 100.0).abs() < 1e-9);
    assert!((x("asymmetry_leg_pct") - 1.0 / 8.5 * 100.0).abs() < 1e-9);
    assert!((x("asymmetry_arm_pct") - 0.2 / 2.9 * 100.0).abs() < 1e-9);
    assert!((r.mass_kg - 56.8).abs() < 1e-9);
    assert!((r.mass_trunk_limbs_kg.unwrap() - 52.8).abs() < 1e-9);
    let r2 = VolumeReport::from_volumes(&v, 1010.0).unwrap();
    assert!((r2.mass_kg - 56.8 * 1.01).abs() < 1e-9);
    assert_eq!(asymmetry_pct(0.0, 0.0), None);
    assert!(matches!(VolumeReport::from_volumes(&v, -1.0), Err(VolumeError::InvalidDensity(_))));
    assert!(matches!(VolumeReport::from_volumes(&v, f64::NAN), Err(VolumeError::InvalidDensity(_))));
}

#[test]
fn aggregates_need_all_members() {
    // No right forearm: arm_r, trunk_limbs, their ratios and asymmetries are absent, never 0.
    let mut v = full_body();
    v.segments.remove(&Segment::ForearmR);
    let r = VolumeReport::from_volumes(&v, 1000.0).unwrap();
    let keys: Vec<&str> = r.volumes_l.keys().collect();
    assert!(!keys.contains(&"forearm_r") && !keys.contains(&"arm_r") && !keys.contains(&"trunk_limbs"));
    assert!(keys.contains(&"whole") && keys.contains(&"arm_l") && keys.contains(&"leg_l"));
    assert!(r.ratios.get("forearm_to_upper_arm_r").is_none());
    assert!(r.ratios.get("asymmetry_forearm_pct").is_none() && r.ratios.get("asymmetry_arm_pct").is_none());
    assert!(r.ratios.get("asymmetry_upper_arm_pct").is_some());
    assert_eq!(r.mass_trunk_limbs_kg, None);
    let json: serde_json::Value = serde_json::from_str(&r.to_json()).unwrap();
    assert!(json["volumes_l"].get("forearm_r").is_none());
    assert!(json["mass_trunk_limbs_kg"].is_null());
}

/// A labelled "body" of capsules: a torso and two legs, thighs and shins (no arms, no head).
fn labelled_legs() -> TriMesh {
    let mut m = capsule(0.08, 0.6, 32, 8, 12);
    translate(&mut m, [0.2, 0.0, 0.0]);
    let mut other = capsule(0.08, 0.6, 32, 8, 12);
    translate(&mut other, [-0.2, 0.0, 0.0]);
    let off = m.vertices.len() as u32;
    m.vertices.extend(other.vertices);
    m.triangles.extend(other.triangles.iter().map(|t| t.map(|v| v + off)));
    let labels = (0..m.n_triangles())
        .map(|t| {
            let [a, b, c] = m.triangle_points(t);
            let p = scale(add(add(a, b), c), 1.0 / 3.0);
            let left = p[0] > 0.0;
            match (p[1] < 0.3, left) {
                (true, true) => Segment::ShinL,
                (true, false) => Segment::ShinR,
                (false, true) => Segment::ThighL,
                (false, false) => Segment::ThighR,
            }
            .id()
        })
        .collect();
    m.face_labels = Some(labels);
    m
}

#[test]
fn json_has_the_keys_of_the_design_and_round_trips() {
    let m = labelled_legs();
    let r = report(&m, 1000.0).unwrap();
    let text = r.to_json();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in ["bsv_version", "units", "volumes_l", "ratios", "registration", "mass_kg", "density_kg_m3"] {
        assert!(json.get(key).is_some(), "missing {key} in {text}");
    }
    assert_eq!(json["units"]["length"], "m");
    assert_eq!(json["units"]["volume"], "L");
    assert!(json["registration"].is_null());
    let vols = json["volumes_l"].as_object().unwrap();
    let keys: Vec<&str> = vols.keys().map(|k| k.as_str()).collect();
    for k in ["thigh_l", "thigh_r", "shin_l", "shin_r", "whole", "leg_l", "leg_r"] {
        assert!(keys.contains(&k), "{k} missing: {keys:?}");
    }
    for k in ["torso", "head", "upper_arm_l", "trunk_limbs", "arm_l"] {
        assert!(!keys.contains(&k), "{k} should be absent: {keys:?}");
    }
    // Whole = the two closed capsules; the legs sum to it.
    let whole = json["volumes_l"]["whole"].as_f64().unwrap();
    let legs = json["volumes_l"]["leg_l"].as_f64().unwrap() + json["volumes_l"]["leg_r"].as_f64().unwrap();
    assert!((whole - legs).abs() < 1e-10 * whole);
    assert!((json["ratios"]["asymmetry_leg_pct"].as_f64().unwrap()).abs() < 1e-9);
    // Round trip, in order, and a registration section filled by someone else.
    // (serde_json's default float parser may differ from the written value in the last bit.)
    let back = VolumeReport::from_json(&text).unwrap();
    let close = |a: &bsv_volume::NamedValues, b: &bsv_volume::NamedValues| {
        a.0.len() == b.0.len()
            && a.0.iter().zip(&b.0).all(|(x, y)| x.0 == y.0 && (x.1 - y.1).abs() <= 1e-14 * x.1.abs().max(1.0))
    };
    assert!(close(&back.volumes_l, &r.volumes_l) && close(&back.ratios, &r.ratios));
    assert_eq!(
        (back.units.clone(), back.notes.clone(), back.registration.clone()),
        (r.units.clone(), r.notes.clone(), None)
    );
    assert_eq!((back.density_kg_m3, back.mass_trunk_limbs_kg), (r.density_kg_m3, r.mass_trunk_limbs_kg));
    let mut with_reg = r.clone();
    with_reg.registration = Some(serde_json::json!({"iterations": 20, "seconds": 1.5, "rms_mesh_to_points_mm": 2.1}));
    let again = VolumeReport::from_json(&with_reg.to_json()).unwrap();
    assert_eq!(again.registration.unwrap()["iterations"], 20);
}

#[test]
fn display_prints_a_table() {
    let m = labelled_legs();
    let r = report(&m, 1000.0).unwrap();
    let text = r.to_string();
    assert!(text.contains("segment") && text.contains("litres") && text.contains("% whole"), "{text}");
    let thigh_line = text.lines().find(|l| l.starts_with("thigh_l")).unwrap();
    let litres: f64 = thigh_line.split_whitespace().nth(1).unwrap().parse().unwrap();
    assert!((litres - r.volumes_l.get("thigh_l").unwrap()).abs() < 0.0005 + 1e-12);
    assert!(thigh_line.split_whitespace().nth(1).unwrap().split('.').nth(1).unwrap().len() == 3);
    assert!(text.contains("leg_l") && text.contains("asymmetry") && text.contains("kg"));
    let pct: f64 = thigh_line.split_whitespace().nth(2).unwrap().parse().unwrap();
    assert!((pct - r.volumes_l.get("thigh_l").unwrap() / r.whole_l().unwrap() * 100.0).abs() < 0.01);
}

#[test]
fn unlabelled_mesh_report_has_only_whole_and_a_note() {
    let m = subdivided_cuboid([0.5, 0.4, 0.3], 3);
    let r = report(&m, 1000.0).unwrap();
    assert_eq!(r.volumes_l.keys().collect::<Vec<_>>(), vec!["whole"]);
    assert!((r.whole_l().unwrap() - 60.0).abs() < 1e-9);
    assert!((r.mass_kg - 60.0).abs() < 1e-9);
    assert!(!r.notes.is_empty());
    assert!(r.ratios.0.is_empty());
    let sv = segment_volumes(&m).unwrap();
    assert!(sv.segments.is_empty());
    assert!(r.to_string().contains("no labelled segments"));
}
