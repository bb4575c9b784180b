//! Only the person: rejects person-mask pixels whose depth leaves the person's surface.
//!
//! 1. Depth edges ([`depth_edges`]): a mask pixel with at least [`EDGE_MIN_NEARER`] valid
//!    8-neighbours NEARER by more than `edge_step_m` lies behind a depth discontinuity: a mixed
//!    ("flying") pixel between a silhouette and the background, or background seen next to the
//!    outline. Only the farther side of a step is flagged, so a limb in front of the torso keeps its
//!    own pixels (the torso loses a one-pixel ring around it), and the veil of mixed pixels that
//!    would bridge the body to the wall in 3-D is cut. A single stray pixel in front of the surface
//!    does not flag its neighbours (it is a separate part itself).
//! 2. Far pixels ([`far_from_person`]): deeper than the person's median depth by more than `far_m`
//!    (the wall behind the subject).
//! 3. 3-D components ([`voxel_components`]): points are binned into cubic voxels of side `link_m`;
//!    occupied voxels that touch (26-neighbourhood) are joined (union-find). Two points closer than
//!    `link_m` are always joined, two farther apart than `2 sqrt(3) link_m` never are. The person is
//!    the largest component; every other component is clutter (a chair, the wall, flying pixels),
//!    unless it is comparable to the person ([`choose_person`]): then the view is ambiguous.
//!
//! Working in 3-D (not on image-space depth steps) keeps a forearm held in front of the torso: it is
//! joined to the body through the elbow and shoulder whatever depth step it shows the camera.

use bsv_core::geometry::{dist2, scale};
use rayon::prelude::*;
use rustc_hash::FxHashMap as HashMap;

/// A pixel is a depth edge when at least this many of its 8 neighbours are nearer by more than the step.
pub const EDGE_MIN_NEARER: usize = 2;

/// Flags each of `pixels` (row-major indices into a `width`-wide image) that has at least
/// [`EDGE_MIN_NEARER`] valid 8-neighbours nearer than itself by more than `step` metres. `depth(i)` is
/// pixel `i`'s depth in metres, 0 when invalid.
pub fn depth_edges(
    depth: &(dyn Fn(usize) -> f64 + Sync),
    width: usize,
    height: usize,
    pixels: &[u32],
    step: f64,
) -> Vec<bool> {
    pixels
        .par_iter()
        .map(|&i| {
            let i = i as usize;
            let (u, v) = (i % width, i / width);
            let z = depth(i);
            if z <= 0.0 {
                return false;
            }
            let mut nearer = 0;
            for dv in -1i64..=1 {
                for du in -1i64..=1 {
                    let (uu, vv) = (u as i64 + du, v as i64 + dv);
                    if (du == 0 && dv == 0) || uu < 0 || vv < 0 || uu >= width as i64 || vv >= height as i64 {
                        continue;
                    }
                    let zn = depth(vv as usize * width + uu as usize);
                    if zn > 0.0 && z - zn > step {
                        nearer += 1;
                    }
                }
            }
            nearer >= EDGE_MIN_NEARER
        })
        .collect()
}

/// Flags the depths farther than the median of `depths` by more than `far_m`; also returns the
/// median (NaN when empty).
pub fn far_from_person(depths: &[f64], far_m: f64) -> (Vec<bool>, f64) {
    let median = super::floor::quantile(depths.to_vec(), 0.5);
    (depths.iter().map(|&z| z > median + far_m).collect(), median)
}

/// Connected components of a point set (see the module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Components {
    /// Component of each point; components are numbered by decreasing size (0 = the largest; ties
    /// by first point).
    pub component: Vec<u32>,
    /// Points per component, decreasing.
    pub sizes: Vec<usize>,
}

/// Union-find with path halving and union by size.
struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind { parent: (0..n as u32).collect(), size: vec![1; n] }
    }

    fn find(&mut self, mut a: u32) -> u32 {
        while self.parent[a as usize] != a {
            let p = self.parent[self.parent[a as usize] as usize];
            self.parent[a as usize] = p;
            a = p;
        }
        a
    }

    fn union(&mut self, a: u32, b: u32) {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        if self.size[a as usize] < self.size[b as usize] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b as usize] = a;
        self.size[a as usize] += self.size[b as usize];
    }
}

/// Voxel key of a point (`link_m`-sided cubes).
#[inline]
fn voxel_key(p: [f64; 3], inv: f64) -> [i64; 3] {
    [(p[0] * inv).floor() as i64, (p[1] * inv).floor() as i64, (p[2] * inv).floor() as i64]
}

/// 3-D connected components of `points` with voxels of side `link_m` (see the module docs).
pub fn voxel_components(points: &[[f64; 3]], link_m: f64) -> Components {
    let inv = 1.0 / link_m;
    let keys: Vec<[i64; 3]> = points.par_iter().map(|&p| voxel_key(p, inv)).collect();
    let mut voxel_of: HashMap<[i64; 3], u32> =
        HashMap::with_capacity_and_hasher(points.len() / 16 + 16, Default::default());
    let point_voxel: Vec<u32> = keys
        .iter()
        .map(|k| {
            let next = voxel_of.len() as u32;
            *voxel_of.entry(*k).or_insert(next)
        })
        .collect();
    let mut voxels: Vec<([i64; 3], u32)> = voxel_of.iter().map(|(k, &v)| (*k, v)).collect();
    voxels.sort_unstable_by_key(|&(_, v)| v);
    let mut uf = UnionFind::new(voxels.len());
    for &(k, v) in &voxels {
        for d in NEIGHBOURS_FORWARD {
            if let Some(&w) = voxel_of.get(&[k[0] + d[0], k[1] + d[1], k[2] + d[2]]) {
                uf.union(v, w);
            }
        }
    }
    // Number components by decreasing size, ties by first point.
    let roots: Vec<u32> = point_voxel.iter().map(|&v| uf.find(v)).collect();
    let mut first_and_count: HashMap<u32, (usize, usize)> = HashMap::default();
    for (i, &r) in roots.iter().enumerate() {
        first_and_count.entry(r).or_insert((i, 0)).1 += 1;
    }
    let mut order: Vec<(u32, usize, usize)> = first_and_count.into_iter().map(|(r, (f, c))| (r, f, c)).collect();
    order.sort_unstable_by(|a, b| b.2.cmp(&a.2).then(a.1.cmp(&b.1)));
    let rank: HashMap<u32, u32> = order.iter().enumerate().map(|(k, &(r, _, _))| (r, k as u32)).collect();
    Components {
        component: roots.iter().map(|r| rank.get(r).copied().unwrap_or(0)).collect(),
        sizes: order.iter().map(|o| o.2).collect(),
    }
}

/// The 13 voxel offsets of the 26-neighbourhood that come "after" the centre (each pair once).
const NEIGHBOURS_FORWARD: [[i64; 3]; 13] = [
    [1, 0, 0],
    [-1, 1, 0],
    [0, 1, 0],
    [1, 1, 0],
    [-1, -1, 1],
    [0, -1, 1],
    [1, -1, 1],
    [-1, 0, 1],
    [0, 0, 1],
    [1, 0, 1],
    [-1, 1, 1],
    [0, 1, 1],
    [1, 1, 1],
];

/// Which points are the person, from their components.
#[derive(Debug, Clone, PartialEq)]
pub struct PersonChoice {
    /// Whether each point belongs to the person (the largest component).
    pub keep: Vec<bool>,
    /// Points of the largest component.
    pub main: usize,
    /// Points of the second-largest component (0 when there is one component).
    pub second: usize,
    /// Distance between the centroids of the two largest components, metres (0 with one).
    pub second_distance_m: f64,
}

/// Keeps the largest component; `Err` with the same figures when the second-largest has at least
/// `second_ratio` times the largest's points (two comparable parts: which one is the person?).
pub fn choose_person(points: &[[f64; 3]], comps: &Components, second_ratio: f64) -> Result<PersonChoice, PersonChoice> {
    let main = comps.sizes.first().copied().unwrap_or(0);
    let second = comps.sizes.get(1).copied().unwrap_or(0);
    let keep: Vec<bool> = comps.component.iter().map(|&c| c == 0).collect();
    let centroid = |id: u32| {
        let (mut s, mut n) = ([0.0; 3], 0usize);
        for (p, _) in points.iter().zip(&comps.component).filter(|(_, &c)| c == id) {
            s = [s[0] + p[0], s[1] + p[1], s[2] + p[2]];
            n += 1;
        }
        scale(s, 1.0 / n.max(1) as f64)
    };
    let second_distance_m = if second > 0 { dist2(centroid(0), centroid(1)).sqrt() } else { 0.0 };
    let choice = PersonChoice { keep, main, second, second_distance_m };
    if second > 0 && second as f64 >= second_ratio * main as f64 {
        Err(choice)
    } else {
        Ok(choice)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn blob(centre: [f64; 3], n: usize, spacing: f64) -> Vec<[f64; 3]> {
        let mut out = Vec::new();
        for i in 0..n {
            for j in 0..n {
                out.push([centre[0] + spacing * i as f64, centre[1] + spacing * j as f64, centre[2]]);
            }
        }
        out
    }

    #[test]
    fn components_join_close_points_and_split_distant_ones() {
        let mut pts = blob([0.0, 0.0, 0.0], 40, 0.005);
        pts.extend(blob([0.5, 0.0, 0.0], 10, 0.005));
        pts.extend(blob([0.0, 0.5, 0.0], 20, 0.005));
        let c = voxel_components(&pts, 0.025);
        assert_eq!(c.sizes, vec![1600, 400, 100]);
        assert!(c.component[..1600].iter().all(|&k| k == 0));
        assert!(c.component[1600..1700].iter().all(|&k| k == 2));
        let ok = choose_person(&pts, &c, 0.3).unwrap();
        assert_eq!(ok.keep.iter().filter(|&&k| k).count(), 1600);
        // Centroids (0.0975, 0.0975) and (0.0475, 0.5475).
        assert!((ok.second_distance_m - (0.05f64.powi(2) + 0.45f64.powi(2)).sqrt()).abs() < 1e-9);
        let err = choose_person(&pts, &c, 0.2).unwrap_err();
        assert_eq!((err.main, err.second), (1600, 400));
    }

    #[test]
    fn a_step_flags_only_the_far_side() {
        // 6 x 2 image, both rows: 2.0 2.0 2.0 2.5 2.5 0; then one stray near pixel.
        let mut d = [2.0, 2.0, 2.0, 2.5, 2.5, 0.0, 2.0, 2.0, 2.0, 2.5, 2.5, 0.0];
        let all: Vec<u32> = (0..12).collect();
        let e = depth_edges(&|i: usize| d[i], 6, 2, &all, 0.05);
        let flagged: Vec<usize> = (0..12).filter(|&i| e[i]).collect();
        assert_eq!(flagged, vec![3, 9]);
        d[10] = 1.0;
        let e = depth_edges(&|i: usize| d[i], 6, 2, &all, 0.05);
        let flagged: Vec<usize> = (0..12).filter(|&i| e[i]).collect();
        assert_eq!(flagged, vec![3, 9], "a stray near pixel flags no neighbour");
        let (far, median) = far_from_person(&[2.0, 2.1, 1.9, 3.0], 0.5);
        assert_eq!(far, vec![false, false, false, true]);
        assert!((median - 2.0).abs() < 0.11);
    }
}
