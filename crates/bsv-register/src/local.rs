//! The local step: per cell (vertex one-ring) the linear map `T_i` and its nearest rotation `R_i`.
//!
//! # Energy
//! With rest positions `p` (the pre-aligned template), current positions `p'`, rest edges
//! `e_ij = p_i - p_j`, current edges `e'_ij = p'_i - p'_j`, cotangent weights `w_ij`, cell weight
//! `w_c` and `lambda = alpha * 1e-6 * w_c * A / N` (see `EnergyParams` in `params.rs`):
//!
//! ```text
//! E(p', T, R) = sum_i [ w_c sum_j w_ij |e'_ij - T_i e_ij|^2 + lambda |T_i - R_i|_F^2 ] + sum_i d_i |p'_i - q_i|^2
//! ```
//!
//! # Local update (p' fixed): exact joint minimiser over (T_i, R_i)
//! Write `S_i = sum_j w_ij e'_ij e_ij^T` (covariance, changes with p'), `P_i = sum_j w_ij e_ij e_ij^T`
//! (constant) and `M_i = w_c P_i + lambda I` (constant, SPD for lambda > 0). Per cell,
//! `f(T, R) = w_c sum_j w_ij |e'_j|^2 - 2 w_c tr(T^T S) + w_c tr(T P T^T) + lambda |T - R|^2`.
//!
//! 1. For fixed R, f is a convex quadratic in T; `df/dT = -2 w_c S + 2 w_c T P + 2 lambda (T - R) = 0`
//!    gives `T*(R) = (w_c S + lambda R) M^{-1}` (the lead's formula
//!    `(w_i S_i + lambda R_i)(w_i P_i + lambda I)^{-1}`).
//! 2. Substituting, with `G = w_c S + lambda R` and `|R|^2 = 3`:
//!    `min_T f = c + 3 lambda - tr(G M^{-1} G^T)`, and
//!    `tr(G M^{-1} G^T) = w_c^2 tr(S M^{-1} S^T) + 2 lambda w_c tr(R M^{-1} S^T) + lambda^2 tr(M^{-1})`
//!    (using `R^T R = I` and the symmetry of M). Only the middle term depends on R, so the best
//!    rotation maximises `<R, S M^{-1}>_F`: an orthogonal Procrustes problem,
//!    `R* = polar(S M^{-1})` = `U V^T` from the SVD `S M^{-1} = U Sigma V^T`, with the sign of the
//!    column of U for the smallest singular value flipped when `det(U V^T) < 0` (the reflection fix).
//! 3. Then `T* = T*(R*)`.
//!
//! This is the exact minimiser of the cell energy over both unknowns, better than alternating
//! "R = polar(T), then T" (which, for a stiff lambda, moves R by only O(w_c / lambda) per step).
//! Limits: lambda -> infinity gives `M ~ lambda I`, `R = polar(S)` (classic ARAP, T = R);
//! lambda = 0 gives the unconstrained affine fit `T = S P^{-1}` (P is regularised by 1e-9 of its
//! trace so a flat one-ring stays invertible; R is then irrelevant to the energy).
//!
//! # Global step (T fixed)
//! `dE/dp'_k = 0` gives `sum_j 2 w_c w_kj (p'_k - p'_j) + d_k p'_k = sum_j w_c w_kj (T_k + T_j) e_kj + d_k q_k`,
//! i.e. `(2 w_c L + D) P' = 2 B + D Q` with `L` the cotangent Laplacian and
//! `b_k = sum_j (w_kj / 2)(T_k + T_j) e_kj` scaled by `w_c` (the paper's right-hand side with T in
//! place of R). Each step minimises its own block exactly, so the total energy never increases while
//! the correspondences are fixed.

use crate::cotan::CotanWeights;
use nalgebra::Matrix3;
use rayon::prelude::*;

/// Constant per-cell data of the local step and the energy.
#[derive(Debug, Clone)]
pub struct LocalModel {
    /// Rest positions (pre-aligned template), metres.
    pub rest: Vec<[f64; 3]>,
    /// Cotangent weights.
    pub weights: CotanWeights,
    /// Per-cell weight `w_c`.
    pub cell_weight: f64,
    /// Regularization weight `lambda` (m^2).
    pub lambda: f64,
    /// `M_i^{-1} = (w_c P_i + lambda I)^{-1}` per cell.
    minv: Vec<Matrix3<f64>>,
    /// `P_i` per cell.
    pmat: Vec<Matrix3<f64>>,
}

/// The maps of every cell: linear maps `T_i` and their rotations `R_i`.
#[derive(Debug, Clone, PartialEq)]
pub struct CellMaps {
    /// Linear maps.
    pub t: Vec<Matrix3<f64>>,
    /// Nearest rotations.
    pub r: Vec<Matrix3<f64>>,
}

impl CellMaps {
    /// Identity maps for `n` cells.
    pub fn identity(n: usize) -> CellMaps {
        CellMaps { t: vec![Matrix3::identity(); n], r: vec![Matrix3::identity(); n] }
    }
}

#[inline]
#[rustfmt::skip]
fn outer(a: [f64; 3], b: [f64; 3]) -> Matrix3<f64> {
    Matrix3::new(
        a[0] * b[0], a[0] * b[1], a[0] * b[2],
        a[1] * b[0], a[1] * b[1], a[1] * b[2],
        a[2] * b[0], a[2] * b[1], a[2] * b[2],
    )
}

#[inline]
fn edge(p: &[[f64; 3]], i: usize, j: usize) -> [f64; 3] {
    [p[i][0] - p[j][0], p[i][1] - p[j][1], p[i][2] - p[j][2]]
}

#[inline]
fn mul(m: &Matrix3<f64>, v: [f64; 3]) -> [f64; 3] {
    [
        m[(0, 0)] * v[0] + m[(0, 1)] * v[1] + m[(0, 2)] * v[2],
        m[(1, 0)] * v[0] + m[(1, 1)] * v[1] + m[(1, 2)] * v[2],
        m[(2, 0)] * v[0] + m[(2, 1)] * v[1] + m[(2, 2)] * v[2],
    ]
}

/// The rotation nearest to `m` (polar factor with the reflection fix), identity for a zero matrix.
pub fn nearest_rotation(m: &Matrix3<f64>) -> Matrix3<f64> {
    let svd = m.svd(true, true);
    let (Some(mut u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Matrix3::identity();
    };
    let mut r = u * v_t;
    if r.determinant() < 0.0 {
        let s = &svd.singular_values;
        let mut k = 0;
        for c in 1..3 {
            if s[c] < s[k] {
                k = c;
            }
        }
        for row in 0..3 {
            u[(row, k)] = -u[(row, k)];
        }
        r = u * v_t;
    }
    if r.iter().all(|v| v.is_finite()) {
        r
    } else {
        Matrix3::identity()
    }
}

/// Cells per parallel task of the energy sums: each chunk sums its cells in order and the chunk
/// sums are added in chunk order, so the energies do not depend on the thread count.
const CELL_CHUNK: usize = 256;

/// The sum of (arap, reg) pairs in order.
fn sum_pairs(parts: &[(f64, f64)]) -> (f64, f64) {
    parts.iter().fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
}

impl LocalModel {
    /// Precomputes `P_i` and `M_i^{-1}` for the rest shape.
    pub fn new(rest: Vec<[f64; 3]>, weights: CotanWeights, cell_weight: f64, lambda: f64) -> LocalModel {
        let n = rest.len();
        let (pmat, minv): (Vec<_>, Vec<_>) = (0..n)
            .into_par_iter()
            .map(|i| {
                let (nb, w) = weights.row(i);
                let mut p = Matrix3::zeros();
                for (&j, &wij) in nb.iter().zip(w) {
                    let e = edge(&rest, i, j as usize);
                    p += outer(e, e) * wij;
                }
                let tr = cell_weight * p.trace();
                let reg = lambda.max(1e-9 * tr).max(f64::MIN_POSITIVE);
                let m = p * cell_weight + Matrix3::identity() * reg;
                let inv = m.try_inverse().unwrap_or_else(|| Matrix3::identity() / reg);
                (p, inv)
            })
            .unzip();
        LocalModel { rest, weights, cell_weight, lambda, minv, pmat }
    }

    /// Number of cells.
    pub fn n(&self) -> usize {
        self.rest.len()
    }

    /// Covariance `S_i` and `sum_j w_ij |e'_ij|^2` of cell i for the current positions.
    #[inline]
    fn covariance(&self, cur: &[[f64; 3]], i: usize) -> (Matrix3<f64>, f64) {
        let (nb, w) = self.weights.row(i);
        let mut s = Matrix3::zeros();
        let mut ee = 0.0;
        for (&j, &wij) in nb.iter().zip(w) {
            let j = j as usize;
            let e = edge(&self.rest, i, j);
            let f = edge(cur, i, j);
            s += outer(f, e) * wij;
            ee += wij * (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        }
        (s, ee)
    }

    /// Cell energy (arap, reg) from the covariance for a given map pair.
    #[inline]
    fn cell_energy(&self, i: usize, s: &Matrix3<f64>, ee: f64, t: &Matrix3<f64>, r: &Matrix3<f64>) -> (f64, f64) {
        let p = &self.pmat[i];
        let arap = self.cell_weight * (ee - 2.0 * t.dot(s) + (t * p).dot(t));
        let reg = self.lambda * (t - r).norm_squared();
        (arap.max(0.0), reg)
    }

    /// The exact local update for every cell; returns (arap, reg) energies after it.
    pub fn local_step(&self, cur: &[[f64; 3]], maps: &mut CellMaps) -> (f64, f64) {
        let parts: Vec<(f64, f64)> = maps
            .t
            .par_chunks_mut(CELL_CHUNK)
            .zip(maps.r.par_chunks_mut(CELL_CHUNK))
            .enumerate()
            .map(|(c, (ts, rs))| {
                let mut e = (0.0, 0.0);
                for (k, (t, r)) in ts.iter_mut().zip(rs).enumerate() {
                    let i = c * CELL_CHUNK + k;
                    let (s, ee) = self.covariance(cur, i);
                    let minv = &self.minv[i];
                    let rot = nearest_rotation(&(s * minv));
                    let tt = (s * self.cell_weight + rot * self.lambda) * minv;
                    *t = tt;
                    *r = rot;
                    let (a, g) = self.cell_energy(i, &s, ee, t, r);
                    e.0 += a;
                    e.1 += g;
                }
                e
            })
            .collect();
        sum_pairs(&parts)
    }

    /// (arap, reg) energies of the current positions with the given maps.
    pub fn energy(&self, cur: &[[f64; 3]], maps: &CellMaps) -> (f64, f64) {
        let n = self.n();
        let parts: Vec<(f64, f64)> = (0..n.div_ceil(CELL_CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut e = (0.0, 0.0);
                for i in c * CELL_CHUNK..((c + 1) * CELL_CHUNK).min(n) {
                    let (s, ee) = self.covariance(cur, i);
                    let (a, g) = self.cell_energy(i, &s, ee, &maps.t[i], &maps.r[i]);
                    e.0 += a;
                    e.1 += g;
                }
                e
            })
            .collect();
        sum_pairs(&parts)
    }

    /// The ARAP part of the global right-hand side, `2 b_k = w_c sum_j w_kj (T_k + T_j) e_kj`.
    pub fn rhs(&self, maps: &CellMaps, out: &mut [[f64; 3]]) {
        out.par_iter_mut().enumerate().for_each(|(k, o)| {
            let (nb, w) = self.weights.row(k);
            let mut acc = [0.0; 3];
            for (&j, &wkj) in nb.iter().zip(w) {
                let j = j as usize;
                let m = (maps.t[k] + maps.t[j]) * (self.cell_weight * wkj);
                let v = mul(&m, edge(&self.rest, k, j));
                for a in 0..3 {
                    acc[a] += v[a];
                }
            }
            *o = acc;
        });
    }
}
