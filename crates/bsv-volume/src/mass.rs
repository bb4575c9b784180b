//! Mass properties of closed triangle meshes and of their segments: volume, centre of mass and the
//! inertia tensor about the centre of mass, per unit density.
//!
//! Divergence theorem on signed tetrahedra (the approach of Tonon 2004, "Explicit exact formulas for
//! the 3-D tetrahedron inertia tensor in terms of its vertex coordinates", J. Math. Stat. 1(1), and of
//! Eberly's "Polyhedral mass properties"): every triangle (a, b, c) of a closed, outward-oriented surface
//! spans with a reference point r a tetrahedron of signed volume det[a - r, b - r, c - r] / 6, and the
//! volume integrals of 1, x_i and x_i x_j over the solid are the sums of those over the tetrahedra.
//! For a tetrahedron with one corner at the origin and the others p_1, p_2, p_3 (coordinates relative
//! to r), with V its signed volume and s = p_1 + p_2 + p_3:
//!   int x_i dV = V s_i / 4,   int x_i x_j dV = V / 20 (sum_k p_k,i p_k,j + s_i s_j).
//! Segments are closed by the same shared caps as their volumes (`segments`), so the segment masses,
//! first moments and second moments add up to the whole's exactly (up to summation round-off).

use crate::closed::prepare;
use crate::edges::det6;
use crate::segments::{label_integrals, labelled, Interface};
use crate::{SegmentOptions, VolumeError};
use bsv_core::geometry::sub;
use bsv_core::{Segment, TriMesh};
use std::collections::BTreeMap;
use std::ops::{AddAssign, Mul, SubAssign};

/// Six-fold volume integrals of a solid relative to a reference point (coordinates relative to it):
/// `[1, x, y, z, xx, yy, zz, xy, yz, zx]`, each times 6 (so that the first entry is the six-fold
/// volume of `det6`, the same number the volumes use).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Moments(pub [f64; 10]);

impl Moments {
    /// The six-fold integrals over the signed tetrahedron (r, a, b, c), relative to r.
    pub(crate) fn tetra(r: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Moments {
        let d = det6(r, a, b, c);
        let (p, q, t) = (sub(a, r), sub(b, r), sub(c, r));
        let s = [p[0] + q[0] + t[0], p[1] + q[1] + t[1], p[2] + q[2] + t[2]];
        let m2 = |i: usize, j: usize| d / 20.0 * (p[i] * p[j] + q[i] * q[j] + t[i] * t[j] + s[i] * s[j]);
        Moments([
            d,
            d * s[0] / 4.0,
            d * s[1] / 4.0,
            d * s[2] / 4.0,
            m2(0, 0),
            m2(1, 1),
            m2(2, 2),
            m2(0, 1),
            m2(1, 2),
            m2(2, 0),
        ])
    }

    /// The mass properties of the solid these integrals describe, relative to reference point `r`.
    pub(crate) fn properties(&self, r: [f64; 3]) -> MassProperties {
        let m = self.0.map(|x| x / 6.0);
        let v = m[0];
        let c = if v != 0.0 { [m[1] / v, m[2] / v, m[3] / v] } else { [0.0; 3] };
        // Second moments about the centroid: C = M2 - V c c^T.
        let cxx = m[4] - v * c[0] * c[0];
        let cyy = m[5] - v * c[1] * c[1];
        let czz = m[6] - v * c[2] * c[2];
        let cxy = m[7] - v * c[0] * c[1];
        let cyz = m[8] - v * c[1] * c[2];
        let czx = m[9] - v * c[2] * c[0];
        MassProperties {
            volume_m3: v,
            centroid: [r[0] + c[0], r[1] + c[1], r[2] + c[2]],
            inertia_m5: [[cyy + czz, -cxy, -czx], [-cxy, cxx + czz, -cyz], [-czx, -cyz, cxx + cyy]],
        }
    }
}

impl AddAssign for Moments {
    fn add_assign(&mut self, o: Moments) {
        for (a, b) in self.0.iter_mut().zip(o.0) {
            *a += b;
        }
    }
}

impl SubAssign for Moments {
    fn sub_assign(&mut self, o: Moments) {
        for (a, b) in self.0.iter_mut().zip(o.0) {
            *a -= b;
        }
    }
}

impl Mul<f64> for Moments {
    type Output = Moments;
    fn mul(self, k: f64) -> Moments {
        Moments(self.0.map(|x| x * k))
    }
}

/// Volume, centre of mass and inertia tensor of a homogeneous solid, per unit density.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct MassProperties {
    /// Volume, m^3 (the mass in kg at a density of 1 kg/m^3).
    pub volume_m3: f64,
    /// Centre of mass (centroid of the solid), metres, world frame.
    pub centroid: [f64; 3],
    /// Inertia tensor about the centroid, world axes, per unit density: m^5 (times a density in kg/m^3
    /// gives kg m^2). Symmetric; `[[Ixx, Ixy, Ixz], ...]` with the products of inertia negated
    /// (`Ixy = -int x y dV`), the convention of OpenSim and of most mechanics texts.
    pub inertia_m5: [[f64; 3]; 3],
}

impl MassProperties {
    /// Mass (kg) at a density (kg/m^3).
    pub fn mass_kg(&self, density_kg_m3: f64) -> f64 {
        self.volume_m3 * density_kg_m3
    }

    /// Inertia tensor about the centroid (kg m^2) at a density (kg/m^3).
    pub fn inertia_kg_m2(&self, density_kg_m3: f64) -> [[f64; 3]; 3] {
        self.inertia_m5.map(|row| row.map(|x| x * density_kg_m3))
    }
}

/// Mass properties (per unit density) of a closed, edge-manifold, consistently oriented mesh; with
/// `close_holes` each boundary loop is first fanned to its centroid, otherwise an open mesh is a
/// `VolumeError::OpenMesh`. An inward-oriented mesh gives a negative volume (as `mesh_volume`).
pub fn mass_properties(mesh: &TriMesh, close_holes: bool) -> Result<MassProperties, VolumeError> {
    let (closed, _, _) = prepare(mesh, close_holes)?;
    let r = crate::edges::used_centroid(&closed.vertices, &closed.triangles);
    let mut m = Moments::default();
    for &[a, b, c] in &closed.triangles {
        m += Moments::tetra(r, closed.vertices[a as usize], closed.vertices[b as usize], closed.vertices[c as usize]);
    }
    Ok(m.properties(r))
}

/// Mass properties of a labelled mesh's segments, closed by the shared caps of `segment_volumes`.
#[derive(Debug, Clone, PartialEq)]
pub struct SegmentMass {
    /// The whole mesh (every segment and the unlabelled region).
    pub whole: MassProperties,
    /// Every labelled segment present (absent segments are absent).
    pub segments: BTreeMap<Segment, MassProperties>,
    /// The interfaces between segments (the caps' apexes): joint centre candidates.
    pub interfaces: Vec<Interface>,
    /// True when the triangles faced inward and every integral was negated.
    pub inverted: bool,
    /// Human-readable remarks (as `SegmentVolumes::notes` for the labels; plus non-positive volumes).
    pub notes: Vec<String>,
}

/// Mass properties (per unit density) of every segment of a labelled closed mesh, with the same
/// labels, island merging and hole closing as `segment_volumes_with` (so each segment's `volume_m3`
/// equals its volume there).
pub fn segment_mass_with(mesh: &TriMesh, opts: &SegmentOptions) -> Result<SegmentMass, VolumeError> {
    let lab = labelled(mesh, opts)?;
    let li = label_integrals::<Moments>(&lab.closed.vertices, &lab.closed.triangles, &lab.table, &lab.labels);
    let inverted = li.whole.0[0] < 0.0;
    let sign = if inverted { -1.0 } else { 1.0 };
    let mut segments = BTreeMap::new();
    let mut notes = Vec::new();
    for (l, m, _) in &li.by_label {
        if let Some(s) = Segment::from_id(*l).filter(|s| *s != Segment::Unlabelled) {
            let p = (*m * sign).properties(li.reference);
            if p.volume_m3 <= 0.0 {
                notes.push(format!(
                    "segment {s} has a non-positive volume ({:.4} L): its centre of mass and inertia are meaningless; merge small islands",
                    p.volume_m3 * 1e3
                ));
            }
            segments.insert(s, p);
        }
    }
    if inverted {
        notes.push("the triangles face inward (negative enclosed volume): every integral was negated".into());
    }
    Ok(SegmentMass {
        whole: (li.whole * sign).properties(li.reference),
        segments,
        interfaces: li.interfaces,
        inverted,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_tetra_moments() {
        // Corner tetrahedron 0, e1, e2, e3: V = 1/6, centroid 1/4, int x^2 = 1/60, int xy = 1/120.
        let m = Moments::tetra([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
        let e = [1.0, 0.25, 0.25, 0.25, 0.1, 0.1, 0.1, 0.05, 0.05, 0.05];
        for (a, b) in m.0.iter().zip(e) {
            assert!((a - b).abs() < 1e-15, "{a} vs {b}");
        }
    }
}
