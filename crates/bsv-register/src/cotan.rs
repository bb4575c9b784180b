//! Cotangent weights of a triangle mesh (the global solver assembles the Laplacian from them).
//!
//! `w_ij = (cot a_ij + cot b_ij) / 2`, with `a_ij`, `b_ij` the angles opposite edge ij in its two
//! triangles (one triangle on a boundary edge). Safeguards:
//! - each cotangent is clamped to `[-COT_CLAMP, COT_CLAMP]` (1e3, i.e. angles between ~0.06 deg and
//!   ~179.94 deg), and a degenerate triangle (zero area) contributes nothing;
//! - a total weight below `MIN_WEIGHT` (1e-4; a regular mesh has ~0.58) is raised to it, so every mesh
//!   edge keeps a small positive weight: the weighted graph Laplacian is then a symmetric M-matrix,
//!   positive semi-definite with the constants as its only null space on a connected mesh, and
//!   adding any positive data weight makes it SPD. (Obtuse pairs would give negative weights, which
//!   also break the ARAP local step's covariances.)

/// Largest magnitude a single cotangent may take.
pub const COT_CLAMP: f64 = 1e3;
/// Smallest total edge weight.
pub const MIN_WEIGHT: f64 = 1e-4;

/// Symmetric cotangent edge weights in compressed rows: the neighbours of vertex `i` are
/// `neighbors[offsets[i]..offsets[i + 1]]` (sorted) with `weights` alongside.
#[derive(Debug, Clone, PartialEq)]
pub struct CotanWeights {
    /// Row offsets, `n + 1` entries.
    pub offsets: Vec<usize>,
    /// Neighbour vertex ids, sorted per row.
    pub neighbors: Vec<u32>,
    /// `w_ij` for each stored neighbour (dimensionless).
    pub weights: Vec<f64>,
}

/// Cotangent of the angle at `o` in triangle (o, a, b), clamped; `None` for a degenerate triangle.
#[allow(clippy::neg_cmp_op_on_partial_ord, reason = "a NaN area must count as degenerate")]
fn cot_at(o: [f64; 3], a: [f64; 3], b: [f64; 3]) -> Option<f64> {
    let u = [a[0] - o[0], a[1] - o[1], a[2] - o[2]];
    let v = [b[0] - o[0], b[1] - o[1], b[2] - o[2]];
    let d = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    let c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
    let s = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
    let scale = (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if !(s > 1e-14 * scale.sqrt()) {
        return None;
    }
    Some((d / s).clamp(-COT_CLAMP, COT_CLAMP))
}

impl CotanWeights {
    /// Weights of `triangles` over `vertices` (indices must be in range: check the mesh first).
    pub fn new(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> CotanWeights {
        let n = vertices.len();
        let mut half: Vec<(u32, u32, f64)> = Vec::with_capacity(triangles.len() * 3);
        for t in triangles {
            for k in 0..3 {
                let (o, a, b) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let w =
                    cot_at(vertices[o as usize], vertices[a as usize], vertices[b as usize]).map_or(0.0, |c| 0.5 * c);
                half.push((a.min(b), a.max(b), w));
            }
        }
        half.sort_unstable_by_key(|&(a, b, _)| (a, b));
        // Merge duplicates into undirected edges.
        let mut edges: Vec<(u32, u32, f64)> = Vec::with_capacity(half.len() / 2 + 1);
        for (a, b, w) in half {
            match edges.last_mut() {
                Some(last) if last.0 == a && last.1 == b => last.2 += w,
                _ => edges.push((a, b, w)),
            }
        }
        let mut degree = vec![0usize; n + 1];
        for &(a, b, _) in &edges {
            if a != b {
                degree[a as usize] += 1;
                degree[b as usize] += 1;
            }
        }
        let mut offsets = vec![0usize; n + 1];
        for i in 0..n {
            offsets[i + 1] = offsets[i] + degree[i];
        }
        let mut fill = offsets.clone();
        let m = offsets[n];
        let mut neighbors = vec![0u32; m];
        let mut weights = vec![0.0; m];
        for &(a, b, w) in &edges {
            if a == b {
                continue;
            }
            let w = w.max(MIN_WEIGHT);
            for (x, y) in [(a, b), (b, a)] {
                let s = &mut fill[x as usize];
                neighbors[*s] = y;
                weights[*s] = w;
                *s += 1;
            }
        }
        // Rows are sorted already: edges are sorted by (min, max), and for each row x the entries
        // with y < x come from edges (y, x) in increasing y before those (x, y) in increasing y.
        CotanWeights { offsets, neighbors, weights }
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Neighbours and weights of vertex `i`.
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let r = self.offsets[i]..self.offsets[i + 1];
        (&self.neighbors[r.clone()], &self.weights[r])
    }
}
