//! The embedded default templates (MakeHuman, CC0; `assets/template/`, see its README).

use crate::io::ply::{self, PlyError};
use crate::TriMesh;

static DEFAULT_PLY: &[u8] = include_bytes!("../../../assets/template/template.ply");
static FINE_PLY: &[u8] = include_bytes!("../../../assets/template/template_fine.ply");
static FULL_PLY: &[u8] = include_bytes!("../../../assets/template/template_full.ply");

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
}

impl TemplateKind {
    /// Parses "default", "fine" or "full".
    pub fn parse(s: &str) -> Option<TemplateKind> {
        match s {
            "default" => Some(TemplateKind::Default),
            "fine" => Some(TemplateKind::Fine),
            "full" => Some(TemplateKind::Full),
            _ => None,
        }
    }

    /// The embedded PLY bytes (binary little-endian, vertex and face labels).
    pub fn ply_bytes(self) -> &'static [u8] {
        match self {
            TemplateKind::Default => DEFAULT_PLY,
            TemplateKind::Fine => FINE_PLY,
            TemplateKind::Full => FULL_PLY,
        }
    }
}

/// The embedded template of `kind`, labelled, in metres, A-pose, world frame.
pub fn template(kind: TemplateKind) -> Result<TriMesh, PlyError> {
    ply::parse_mesh(kind.ply_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::topology::edge_map;

    #[test]
    fn embedded_templates_are_closed_and_labelled() {
        for (kind, n_segments) in [(TemplateKind::Default, 9), (TemplateKind::Fine, 9), (TemplateKind::Full, 14)] {
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
}
