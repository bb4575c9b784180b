//! The embedded default templates (MakeHuman, CC0; `assets/template/`, see its README).

use crate::io::ply::{self, PlyError};
use crate::TriMesh;

static DEFAULT_PLY: &[u8] = include_bytes!("../../../assets/template/template.ply");
static FINE_PLY: &[u8] = include_bytes!("../../../assets/template/template_fine.ply");
static FULL_PLY: &[u8] = include_bytes!("../../../assets/template/template_full.ply");
static FEMALE_PLY: &[u8] = include_bytes!("../../../assets/template/template_female.ply");
static MALE_PLY: &[u8] = include_bytes!("../../../assets/template/template_male.ply");
static JOINTS_JSON: &str = include_str!("../../../assets/template/template_joints.json");

/// Which embedded template.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TemplateKind {
    /// The paper's template: 9 segments (head, hands, feet removed, holes capped), 4,177 vertices.
    #[default]
    Default,
    /// `Default` after one midpoint subdivision (same shape), 16,702 vertices.
    Fine,
    /// The whole closed MakeHuman body with all 14 segments, 13,380 vertices.
    Full,
    /// `Default`'s mesh (same vertices, faces and labels) at MakeHuman's female end of the gender macro.
    Female,
    /// `Default`'s mesh at MakeHuman's male end of the gender macro.
    Male,
}

impl TemplateKind {
    /// Every kind, in the order of [`TemplateKind::NAMES`].
    pub const ALL: [TemplateKind; 5] =
        [TemplateKind::Default, TemplateKind::Fine, TemplateKind::Full, TemplateKind::Female, TemplateKind::Male];
    /// The kinds' names (command lines, Python): "default", "fine", "full", "female", "male".
    pub const NAMES: [&'static str; 5] = ["default", "fine", "full", "female", "male"];

    /// Parses one of [`TemplateKind::NAMES`].
    pub fn parse(s: &str) -> Option<TemplateKind> {
        Self::NAMES.iter().position(|&n| n == s).map(|i| Self::ALL[i])
    }

    /// This kind's name in [`TemplateKind::NAMES`].
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }

    /// The key of this template in `template_joints.json`.
    fn joints_key(self) -> &'static str {
        match self {
            TemplateKind::Default => "template",
            TemplateKind::Fine => "template_fine",
            TemplateKind::Full => "template_full",
            TemplateKind::Female => "template_female",
            TemplateKind::Male => "template_male",
        }
    }

    /// The embedded PLY bytes (binary little-endian, vertex and face labels).
    pub fn ply_bytes(self) -> &'static [u8] {
        match self {
            TemplateKind::Default => DEFAULT_PLY,
            TemplateKind::Fine => FINE_PLY,
            TemplateKind::Full => FULL_PLY,
            TemplateKind::Female => FEMALE_PLY,
            TemplateKind::Male => MALE_PLY,
        }
    }
}

/// The embedded template of `kind`, labelled, in metres, A-pose, world frame.
pub fn template(kind: TemplateKind) -> Result<TriMesh, PlyError> {
    ply::parse_mesh(kind.ply_bytes())
}

/// A joint centre carried by a template: the convex combination `sum_k weights[k] * v[vertices[k]]`
/// of the ring of template vertices around the limb at the joint (`assets/template/template_joints.json`,
/// made by `bsv.bodies.template_joints` from the MakeHuman rig).
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
pub struct JointRing {
    /// Joint name as `bsv.frontend.landmarks.JOINTS` writes it: `shoulder_l`, `elbow_r`, `hip_l`, ...
    #[serde(skip)]
    pub name: String,
    /// Template vertex indices of the ring.
    pub vertices: Vec<usize>,
    /// Non-negative weights summing to 1, one per vertex.
    pub weights: Vec<f64>,
    /// The centre on the template (metres), for checks.
    pub centre: [f64; 3],
}

impl JointRing {
    /// The joint's position on a mesh with the template's vertex order.
    pub fn position(&self, vertices: &[[f64; 3]]) -> [f64; 3] {
        let mut c = [0.0; 3];
        for (&v, &w) in self.vertices.iter().zip(&self.weights) {
            for k in 0..3 {
                c[k] += w * vertices[v][k];
            }
        }
        c
    }
}

#[derive(serde::Deserialize)]
struct JointsFile {
    templates: std::collections::BTreeMap<String, std::collections::BTreeMap<String, JointRing>>,
}

/// The joint rings of the embedded template of `kind`, sorted by name.
pub fn template_joints(kind: TemplateKind) -> Vec<JointRing> {
    // The file is embedded and checked by the tests below: a parse failure is a build defect.
    let file: JointsFile = match serde_json::from_str(JOINTS_JSON) {
        Ok(f) => f,
        Err(_) => return Vec::new(),
    };
    file.templates
        .get(kind.joints_key())
        .map(|m| m.iter().map(|(name, r)| JointRing { name: name.clone(), ..r.clone() }).collect())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::topology::edge_map;

    /// Every embedded template with its segment and joint-ring counts.
    const EXPECTED: [(TemplateKind, usize, usize); 5] = [
        (TemplateKind::Default, 9, 10),
        (TemplateKind::Fine, 9, 10),
        (TemplateKind::Full, 14, 12),
        (TemplateKind::Female, 9, 10),
        (TemplateKind::Male, 9, 10),
    ];

    #[test]
    fn embedded_templates_are_closed_and_labelled() {
        for (kind, n_segments, _) in EXPECTED {
            let m = template(kind).expect("embedded template parses");
            assert!(edge_map(&m.triangles).values().all(|e| e.faces.len() == 2), "{kind:?} closed");
            let labels = m.vertex_labels.as_ref().expect("vertex labels");
            let mut present: Vec<u8> = labels.clone();
            present.sort_unstable();
            present.dedup();
            assert_eq!(present.len(), n_segments, "{kind:?}");
            assert!(crate::geometry::signed_volume(&m.vertices, &m.triangles) > 0.04);
        }
    }

    #[test]
    fn joint_rings_reproduce_their_centres_on_each_template() {
        for (kind, _, n_joints) in EXPECTED {
            let m = template(kind).expect("embedded template parses");
            let rings = template_joints(kind);
            assert_eq!(rings.len(), n_joints, "{kind:?}");
            for r in &rings {
                assert!(r.weights.iter().all(|&w| w >= 0.0), "{} weights >= 0", r.name);
                assert!((r.weights.iter().sum::<f64>() - 1.0).abs() < 1e-9, "{} weights sum to 1", r.name);
                let p = r.position(&m.vertices);
                let d = crate::geometry::sub(p, r.centre);
                assert!(crate::geometry::dot(d, d).sqrt() < 1e-6, "{kind:?} {} off by {d:?}", r.name);
            }
        }
    }

    #[test]
    fn the_sexed_templates_share_the_default_mesh_and_names_round_trip() {
        for k in TemplateKind::ALL {
            assert_eq!(TemplateKind::parse(k.name()), Some(k));
        }
        assert_eq!(TemplateKind::parse("neutral"), None);
        let d = template(TemplateKind::Default).expect("default");
        for kind in [TemplateKind::Female, TemplateKind::Male] {
            let m = template(kind).expect("sexed template");
            assert_eq!(m.triangles, d.triangles, "{kind:?}");
            assert_eq!(m.vertex_labels, d.vertex_labels, "{kind:?}");
            assert_ne!(m.vertices, d.vertices, "{kind:?}");
        }
    }
}
