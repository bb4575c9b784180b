//! The volumes report: JSON of DESIGN.md "Formats" and a readable table.

use crate::indices::{aggregates, asymmetries, mass_kg, ratios};
use crate::segments::{segment_volumes_with, SegmentOptions, SegmentVolumes};
use crate::VolumeError;
use bsv_core::{Aggregate, Segment, TriMesh};
use serde::de::{MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// Litres per cubic metre.
const L_PER_M3: f64 = 1000.0;

/// Units of the report (`{"length": "m", "volume": "L"}`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Units {
    /// Length unit of every geometry ("m").
    pub length: String,
    /// Volume unit of `volumes_l` ("L").
    pub volume: String,
}

impl Default for Units {
    fn default() -> Self {
        Units { length: "m".into(), volume: "L".into() }
    }
}

/// Named numbers kept in insertion order (serialized as a JSON object in that order).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NamedValues(pub Vec<(String, f64)>);

impl NamedValues {
    /// The value under `key`, if any.
    pub fn get(&self, key: &str) -> Option<f64> {
        self.0.iter().find(|(k, _)| k == key).map(|(_, v)| *v)
    }

    /// The keys, in order.
    pub fn keys(&self) -> impl Iterator<Item = &str> {
        self.0.iter().map(|(k, _)| k.as_str())
    }

    fn push(&mut self, key: &str, value: f64) {
        self.0.push((key.to_string(), value));
    }
}

impl Serialize for NamedValues {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for NamedValues {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = NamedValues;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an object of name: number")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<NamedValues, A::Error> {
                let mut out = Vec::new();
                while let Some((k, v)) = map.next_entry::<String, f64>()? {
                    out.push((k, v));
                }
                Ok(NamedValues(out))
            }
        }
        deserializer.deserialize_map(V)
    }
}

/// The volumes report of DESIGN.md "Formats". `volumes_l` holds the segments present (id order) then
/// the aggregates that can be computed; an absent segment is absent, never 0. `registration` is
/// `null` unless the registration step (bsv-register / CLI) fills it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VolumeReport {
    /// Version of the crate that wrote the report.
    pub bsv_version: String,
    /// Units: length "m", volume "L".
    pub units: Units,
    /// Volumes in litres by segment name, then by aggregate name (`trunk_limbs`, `whole`, `arm_l`...).
    pub volumes_l: NamedValues,
    /// Volume of the unlabelled region (counted in `whole`, in no segment), litres; null when none.
    pub unlabelled_l: Option<f64>,
    /// Ratios (`forearm_to_upper_arm_l`, `shin_to_thigh_r`, ...) and asymmetries in percent,
    /// `(L - R) / mean(L, R) * 100` (`asymmetry_upper_arm_pct`, ..., `asymmetry_leg_pct`).
    pub ratios: NamedValues,
    /// Density used for the masses, kg/m^3.
    pub density_kg_m3: f64,
    /// Mass of the whole measured mesh, kg (`whole` volume x density).
    pub mass_kg: f64,
    /// Mass of the nine trunk-and-limb segments, kg (null unless all nine are present).
    pub mass_trunk_limbs_kg: Option<f64>,
    /// Remarks (missing labels, unlabelled faces, inverted orientation, closed holes...).
    pub notes: Vec<String>,
    /// Registration summary (`iterations`, `seconds`, `rms_mesh_to_points_mm`, ...), filled by others.
    pub registration: Option<serde_json::Value>,
}

impl VolumeReport {
    /// Builds the report of measured segment volumes at a density (kg/m^3).
    pub fn from_volumes(v: &SegmentVolumes, density_kg_m3: f64) -> Result<VolumeReport, VolumeError> {
        check_density(density_kg_m3)?;
        let mut volumes = NamedValues::default();
        for (s, m3) in &v.segments {
            volumes.push(s.name(), m3 * L_PER_M3);
        }
        let aggs = aggregates(v);
        for (a, m3) in &aggs {
            volumes.push(a.name(), m3 * L_PER_M3);
        }
        let mut r = NamedValues::default();
        for (k, x) in ratios(v).into_iter().chain(asymmetries(v)) {
            r.push(k, x);
        }
        let trunk = aggs.iter().find(|(a, _)| *a == Aggregate::TrunkLimbs).map(|(_, m3)| *m3);
        Ok(VolumeReport {
            bsv_version: env!("CARGO_PKG_VERSION").to_string(),
            units: Units::default(),
            volumes_l: volumes,
            unlabelled_l: v.unlabelled_m3.map(|m3| m3 * L_PER_M3),
            ratios: r,
            density_kg_m3,
            mass_kg: mass_kg(v.whole_m3, density_kg_m3),
            mass_trunk_limbs_kg: trunk.map(|m3| mass_kg(m3, density_kg_m3)),
            notes: v.notes.clone(),
            registration: None,
        })
    }

    /// Pretty-printed JSON.
    pub fn to_json(&self) -> String {
        // Serializing plain numbers, strings and maps cannot fail; keep a fallback instead of a panic.
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }

    /// Parses a report written by `to_json`.
    pub fn from_json(text: &str) -> Result<VolumeReport, serde_json::Error> {
        serde_json::from_str(text)
    }

    /// The `whole` volume in litres.
    pub fn whole_l(&self) -> Option<f64> {
        self.volumes_l.get(Aggregate::Whole.name())
    }

    /// The quantities of this report, as `(name, value)` in order: the one definition of "the
    /// quantities of a volume report that the intervals model" (`bsv.uncertainty` mirrors it on JSON
    /// reports, and a test keeps the two equal). They are the entries of `volumes_l` then those of
    /// `ratios` (volumes in litres, ratios, asymmetries in percent), finite values only; a name given
    /// twice keeps its first place and its last finite value.
    pub fn quantities(&self) -> Vec<(&str, f64)> {
        let mut out: Vec<(&str, f64)> = Vec::new();
        for (k, v) in self.volumes_l.0.iter().chain(&self.ratios.0) {
            if !v.is_finite() {
                continue;
            }
            match out.iter_mut().find(|(name, _)| *name == k.as_str()) {
                Some(slot) => slot.1 = *v,
                None => out.push((k.as_str(), *v)),
            }
        }
        out
    }
}

/// Segment volumes and the report of a mesh at a density (kg/m^3), default options
/// (no hole closing, labels as given).
pub fn report(mesh: &TriMesh, density_kg_m3: f64) -> Result<VolumeReport, VolumeError> {
    report_with(mesh, density_kg_m3, &SegmentOptions::default())
}

/// `report` with options (hole closing, island merging).
pub fn report_with(mesh: &TriMesh, density_kg_m3: f64, opts: &SegmentOptions) -> Result<VolumeReport, VolumeError> {
    check_density(density_kg_m3)?;
    VolumeReport::from_volumes(&segment_volumes_with(mesh, opts)?, density_kg_m3)
}

/// `InvalidDensity` unless the density (kg/m^3) is a positive finite number: the one check of every
/// report (and of callers that take a density before they measure, e.g. the Python `PreparedVolumes`).
pub fn check_density(density_kg_m3: f64) -> Result<(), VolumeError> {
    if density_kg_m3.is_finite() && density_kg_m3 > 0.0 {
        Ok(())
    } else {
        Err(VolumeError::InvalidDensity(density_kg_m3))
    }
}

impl fmt::Display for VolumeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let whole = self.whole_l().unwrap_or(0.0);
        let pct = |l: f64| if whole != 0.0 { format!("{:>8.2}", l / whole * 100.0) } else { format!("{:>8}", "-") };
        let is_segment = |k: &str| Segment::from_name(k).is_some();
        writeln!(f, "{:<16} {:>10} {:>8}", "segment", "litres", "% whole")?;
        let segs: Vec<_> = self.volumes_l.0.iter().filter(|(k, _)| is_segment(k)).collect();
        if segs.is_empty() {
            writeln!(f, "  (no labelled segments)")?;
        }
        for (k, l) in segs {
            writeln!(f, "{k:<16} {l:>10.3} {}", pct(*l))?;
        }
        if let Some(u) = self.unlabelled_l {
            writeln!(f, "{:<16} {u:>10.3} {}", "(unlabelled)", pct(u))?;
        }
        writeln!(f)?;
        writeln!(f, "{:<16} {:>10} {:>8}", "aggregate", "litres", "% whole")?;
        for (k, l) in self.volumes_l.0.iter().filter(|(k, _)| !is_segment(k)) {
            writeln!(f, "{k:<16} {l:>10.3} {}", pct(*l))?;
        }
        let (asym, ratio): (Vec<_>, Vec<_>) = self.ratios.0.iter().partition(|(k, _)| k.starts_with("asymmetry_"));
        if !ratio.is_empty() {
            writeln!(f)?;
            writeln!(f, "ratios (distal / proximal)")?;
            for (k, x) in ratio {
                writeln!(f, "  {k:<28} {x:>8.3}")?;
            }
        }
        if !asym.is_empty() {
            writeln!(f)?;
            writeln!(f, "asymmetry (L - R) / mean(L, R)")?;
            for (k, x) in asym {
                let name = k.trim_start_matches("asymmetry_").trim_end_matches("_pct");
                writeln!(f, "  {name:<28} {x:>+7.2} %")?;
            }
        }
        writeln!(f)?;
        writeln!(f, "mass at {} kg/m^3", self.density_kg_m3)?;
        writeln!(f, "  {:<28} {:>8.2} kg", "whole", self.mass_kg)?;
        if let Some(m) = self.mass_trunk_limbs_kg {
            writeln!(f, "  {:<28} {:>8.2} kg", "trunk_limbs", m)?;
        }
        for n in &self.notes {
            writeln!(f, "note: {n}")?;
        }
        Ok(())
    }
}
