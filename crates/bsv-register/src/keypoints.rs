//! The keypoint term: measured joint centres (MediaPipe's landmarks of both views lifted to 3-D by
//! `bsv.frontend.landmarks`, or any other source) pull the template's own joint centres.
//!
//! A template joint is a fixed convex combination `J = sum_k w_k p_k` of a ring of template vertices
//! ([`JointRing`], from the MakeHuman rig the template comes from), so the energy of a joint with
//! target `q` is `c |J - q|^2`. Because the weights are non-negative and sum to 1, Jensen's inequality
//! makes `sum_k c w_k |p_k - (p*_k + q - J*)|^2` (`*` = the current positions) a majoriser of it that
//! touches it at the current positions: it enters the global step as per-vertex data weights
//! `c w_k` and targets `p*_k + (q - J*)`, merged with the cloud's data term. The system matrix stays
//! diagonal-plus-Laplacian (the symbolic factorization is unchanged) and the iterations still
//! decrease the total energy.
//!
//! `c = keypoint_weight x data_weight x confidence x rho(|q - J*|)` with the robust factor
//! `rho(r) = 1 / (1 + (r / keypoint_robust_m)^2)`: a landmark far from where the fit puts the joint
//! (a mislabelled or occluded one) loses its pull instead of dragging the limb.
//!
//! A keypoint with a [`Keypoint::direction`] measures one coordinate only (a segment boundary's height
//! along the body's axis, say): its ring is pulled along that direction alone, by the component of
//! `q - J*` along it, and its residual is that component.

use crate::error::InputError;
use bsv_core::geometry::{add, dot, scale, sub};
use bsv_core::template::JointRing;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// One measured joint centre.
#[derive(Debug, Clone, PartialEq)]
pub struct Keypoint {
    /// Joint name, as the template's rings name them (`shoulder_l`, `elbow_r`, `hip_l`, `knee_r`, ...).
    pub name: String,
    /// World position (metres, the cloud's frame).
    pub position: [f64; 3],
    /// Confidence in [0, 1] (0 = ignored).
    pub confidence: f64,
    /// The one direction the measurement holds (world frame; normalised here): the ring is pulled along it
    /// alone, whatever `keypoint_axial` says. `None`: a full 3-D position.
    pub direction: Option<[f64; 3]>,
}

/// A measured joint paired with the template ring that carries it.
#[derive(Debug, Clone)]
struct Pair {
    ring: JointRing,
    target: [f64; 3],
    confidence: f64,
    direction: Option<[f64; 3]>,
}

/// Measured joints matched to the template's joint rings, checked against the template.
#[derive(Debug, Clone, Default)]
pub struct Keypoints {
    pairs: Vec<Pair>,
}

/// The distance between one fitted template joint and its measured centre.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct KeypointResidual {
    /// Joint name.
    pub name: String,
    /// Distance (mm) between the fitted template's joint and the measured one.
    pub distance_mm: f64,
    /// The measured joint's confidence.
    pub confidence: f64,
}

impl Keypoints {
    /// Pairs each measured joint with the ring of the same name. `n_vertices` is the template's vertex
    /// count. A measured joint without a ring, a non-finite position, a confidence outside [0, 1]
    /// or a ring that does not fit the template is an [`InputError`] naming it.
    pub fn new(rings: &[JointRing], measured: &[Keypoint], n_vertices: usize) -> Result<Keypoints, InputError> {
        let mut pairs = Vec::with_capacity(measured.len());
        for k in measured {
            let Some(ring) = rings.iter().find(|r| r.name == k.name) else {
                return Err(InputError::UnknownKeypoint {
                    name: k.name.clone(),
                    known: rings.iter().map(|r| r.name.as_str()).collect::<Vec<_>>().join(", "),
                });
            };
            if !k.position.iter().all(|x| x.is_finite()) {
                return Err(InputError::BadKeypoint {
                    name: k.name.clone(),
                    reason: format!("position {:?} is not finite", k.position),
                });
            }
            if !(0.0..=1.0).contains(&k.confidence) {
                return Err(InputError::BadKeypoint {
                    name: k.name.clone(),
                    reason: format!("confidence {} is not in [0, 1]", k.confidence),
                });
            }
            let direction = match k.direction {
                None => None,
                Some(a) => {
                    let n = dot(a, a).sqrt();
                    if !(n.is_finite() && n > 1e-9) {
                        return Err(InputError::BadKeypoint {
                            name: k.name.clone(),
                            reason: format!("direction {a:?} is not a finite non-zero vector"),
                        });
                    }
                    Some(scale(a, 1.0 / n))
                }
            };
            let bad_weights = ring.weights.len() != ring.vertices.len()
                || ring.vertices.is_empty()
                || ring.weights.iter().any(|&w| !(w.is_finite() && w >= 0.0))
                || (ring.weights.iter().sum::<f64>() - 1.0).abs() > 1e-6;
            if bad_weights || ring.vertices.iter().any(|&v| v >= n_vertices) {
                return Err(InputError::BadJointRing { name: ring.name.clone(), n_vertices });
            }
            pairs.push(Pair { ring: ring.clone(), target: k.position, confidence: k.confidence, direction });
        }
        Ok(Keypoints { pairs })
    }

    /// Number of measured joints in use.
    pub fn len(&self) -> usize {
        self.pairs.len()
    }

    /// Whether no joint is in use.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Adds the majorised keypoint energy to the data weights `d` and targets `q` of the current
    /// positions `cur` (see the module doc). `weight` is `keypoint_weight x data_weight`.
    pub(crate) fn apply(
        &self,
        cur: &[[f64; 3]],
        weight: f64,
        robust_m: f64,
        axial: bool,
        d: &mut [f64],
        q: &mut [[f64; 3]],
    ) {
        for p in &self.pairs {
            let centre = p.ring.position(cur);
            let full = sub(p.target, centre);
            let shift = match p.direction {
                Some(a) => scale(a, dot(full, a)),
                None if axial => {
                    let a = ring_axis(&p.ring, cur, centre);
                    scale(a, dot(full, a))
                }
                None => full,
            };
            let r = dot(shift, shift).sqrt() / robust_m;
            let c = weight * p.confidence / (1.0 + r * r);
            if c <= 0.0 {
                continue;
            }
            for (&v, &w) in p.ring.vertices.iter().zip(&p.ring.weights) {
                let cw = c * w;
                let target = add(cur[v], shift);
                let total = d[v] + cw;
                // Two quadratics in p_v: d |p - q|^2 + cw |p - t|^2 = total |p - mean|^2 + const.
                q[v] = scale(add(scale(q[v], d[v]), scale(target, cw)), 1.0 / total);
                d[v] = total;
            }
        }
    }

    /// Distance of each fitted template joint (vertex positions `cur`) to its measured centre (along the
    /// measured direction only, for a keypoint that has one).
    pub fn residuals(&self, cur: &[[f64; 3]]) -> Vec<KeypointResidual> {
        self.pairs
            .iter()
            .map(|p| {
                let e = sub(p.ring.position(cur), p.target);
                let distance = match p.direction {
                    Some(a) => dot(e, a).abs(),
                    None => dot(e, e).sqrt(),
                };
                KeypointResidual { name: p.ring.name.clone(), distance_mm: distance * 1e3, confidence: p.confidence }
            })
            .collect()
    }
}

/// The limb's axis at a ring: the normal of the ring's slab, i.e. the direction in which the weighted
/// ring vertices spread least (smallest eigenvector of their weighted scatter about `centre`).
fn ring_axis(ring: &JointRing, cur: &[[f64; 3]], centre: [f64; 3]) -> [f64; 3] {
    let mut s = Matrix3::<f64>::zeros();
    for (&v, &w) in ring.vertices.iter().zip(&ring.weights) {
        let e = Vector3::from(sub(cur[v], centre));
        s += w * e * e.transpose();
    }
    let eig = SymmetricEigen::new(s);
    let (mut k, mut best) = (0, f64::INFINITY);
    for (i, &l) in eig.eigenvalues.iter().enumerate() {
        if l < best {
            (k, best) = (i, l);
        }
    }
    let a = eig.eigenvectors.column(k);
    [a[0], a[1], a[2]]
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn ring() -> JointRing {
        JointRing { name: "knee_l".into(), vertices: vec![0, 1, 2, 3], weights: vec![0.25; 4], centre: [0.0, 0.0, 0.0] }
    }

    #[test]
    fn majoriser_pulls_the_joint_onto_its_target_when_alone() {
        // Only the keypoint term on four free vertices: the minimiser of the surrogate moves the
        // ring rigidly by the joint's offset.
        let cur = vec![[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
        let k = Keypoints::new(
            &[ring()],
            &[Keypoint { name: "knee_l".into(), position: [0.0, 0.01, 0.0], confidence: 1.0, direction: None }],
            4,
        )
        .unwrap();
        let (mut d, mut q) = (vec![0.0; 4], cur.clone());
        k.apply(&cur, 10.0, 1.0, false, &mut d, &mut q);
        let moved: Vec<[f64; 3]> = q.clone();
        let j = ring().position(&moved);
        assert!((j[1] - 0.01).abs() < 1e-12 && j[0].abs() < 1e-12);
        assert!(d.iter().all(|&x| x > 0.0));
        let r = k.residuals(&moved);
        assert!(r[0].distance_mm < 1e-9);
    }

    #[test]
    fn merged_targets_weigh_both_terms() {
        let cur = vec![[0.0; 3]; 4];
        let k = Keypoints::new(
            &[ring()],
            &[Keypoint { name: "knee_l".into(), position: [0.04, 0.0, 0.0], confidence: 1.0, direction: None }],
            4,
        )
        .unwrap();
        // Data targets at x = 0 with weight 1; keypoint weight 4 per joint = 1 per ring vertex.
        let (mut d, mut q) = (vec![1.0; 4], vec![[0.0; 3]; 4]);
        k.apply(&cur, 4.0, f64::INFINITY, false, &mut d, &mut q);
        assert!(d.iter().all(|&x| (x - 2.0).abs() < 1e-12));
        assert!(q.iter().all(|t| (t[0] - 0.02).abs() < 1e-12));
    }

    #[test]
    fn far_landmarks_lose_their_pull() {
        let cur = vec![[0.0; 3]; 4];
        let near = Keypoint { name: "knee_l".into(), position: [0.01, 0.0, 0.0], confidence: 1.0, direction: None };
        let far = Keypoint { position: [0.30, 0.0, 0.0], ..near.clone() };
        let weight_of = |kp: Keypoint| {
            let k = Keypoints::new(&[ring()], &[kp], 4).unwrap();
            let (mut d, mut q) = (vec![0.0; 4], vec![[0.0; 3]; 4]);
            k.apply(&cur, 1.0, 0.03, false, &mut d, &mut q);
            d[0]
        };
        assert!(weight_of(far) < 0.02 * weight_of(near));
    }

    #[test]
    fn a_directed_keypoint_pulls_along_its_direction_only() {
        // The target lies 1 cm up and 3 cm aside; measured along (0, 2, 0) the ring moves up only, even
        // with the axial setting (whose ring axis, the flattest direction of this square, is y too: the
        // direction decides), and the residual is the component along it.
        let cur = vec![[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
        let kp = Keypoint {
            name: "knee_l".into(),
            position: [0.03, 0.01, 0.0],
            confidence: 1.0,
            direction: Some([0.0, 2.0, 0.0]),
        };
        let k = Keypoints::new(&[ring()], &[kp], 4).unwrap();
        for axial in [false, true] {
            let (mut d, mut q) = (vec![0.0; 4], cur.clone());
            k.apply(&cur, 10.0, 1.0, axial, &mut d, &mut q);
            let j = ring().position(&q);
            assert!((j[1] - 0.01).abs() < 1e-12 && j[0].abs() < 1e-12 && j[2].abs() < 1e-12, "{j:?}");
        }
        assert!((k.residuals(&cur)[0].distance_mm - 10.0).abs() < 1e-9);
        let zero = Keypoint { name: "knee_l".into(), position: [0.0; 3], confidence: 1.0, direction: Some([0.0; 3]) };
        let e = Keypoints::new(&[ring()], &[zero], 4).unwrap_err();
        assert!(e.to_string().contains("knee_l") && e.to_string().contains("direction"), "{e}");
    }

    #[test]
    fn bad_keypoints_are_named() {
        let kp = |name: &str, position: [f64; 3], confidence: f64| Keypoint {
            name: name.into(),
            position,
            confidence,
            direction: None,
        };
        let e = Keypoints::new(&[ring()], &[kp("nose", [0.0; 3], 1.0)], 4).unwrap_err();
        assert!(e.to_string().contains("nose") && e.to_string().contains("knee_l"), "{e}");
        let e = Keypoints::new(&[ring()], &[kp("knee_l", [f64::NAN, 0.0, 0.0], 1.0)], 4).unwrap_err();
        assert!(e.to_string().contains("knee_l"), "{e}");
        let e = Keypoints::new(&[ring()], &[kp("knee_l", [0.0; 3], 1.5)], 4).unwrap_err();
        assert!(e.to_string().contains("confidence"), "{e}");
        let e = Keypoints::new(&[ring()], &[kp("knee_l", [0.0; 3], 1.0)], 3).unwrap_err();
        assert!(e.to_string().contains("knee_l") && e.to_string().contains('3'), "{e}");
    }
}
