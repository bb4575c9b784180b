//! The smallest eigenvector (and the eigenvalues) of a 3 x 3 symmetric matrix, in closed form.
//!
//! A PCA normal is the eigenvector of the smallest eigenvalue of a neighbourhood's scatter matrix;
//! the ray-parallel filter needs one per cloud point (100k+ per registration) and the
//! correspondences one per vertex and iteration. nalgebra's `SymmetricEigen` is iterative (QR sweeps
//! with Householder tridiagonalisation) and computes all three vectors; here the eigenvalues come from
//! the characteristic polynomial in trigonometric form (O. K. Smith, "Eigenvalues of a symmetric 3 x 3
//! matrix", CACM 4(4), 1961) and the one vector wanted from the cross products of the rows of
//! `A - lambda I`, the largest of the three (its rows span the plane orthogonal to the vector).
//! The matrix is scaled by its largest entry first, so the result does not depend on units.
//! Checked against `SymmetricEigen` on random matrices (tests below).

/// The unit eigenvector of the smallest eigenvalue of the symmetric matrix `a` and the three
/// eigenvalues (ascending), or `None` when the matrix is zero or not finite, or when its two smallest
/// eigenvalues lie within 1e-6 of the largest magnitude of each other (the vector is not defined).
#[allow(clippy::neg_cmp_op_on_partial_ord, reason = "a NaN must count as degenerate")]
pub fn smallest_eigenvector(a: &[[f64; 3]; 3]) -> Option<([f64; 3], [f64; 3])> {
    let s = max_abs(a);
    if s == 0.0 || !s.is_finite() {
        return None;
    }
    let m = scaled(a, 1.0 / s);
    let l = ascending_scaled(&m);
    // The trigonometric form resolves a double root only to about sqrt(machine epsilon).
    if !(l[1] - l[0] > 1e-6 * l[2].abs().max(l[0].abs())) {
        return None;
    }
    let r: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| m[i][j] - if i == j { l[0] } else { 0.0 }));
    let c = [cross(r[0], r[1]), cross(r[0], r[2]), cross(r[1], r[2])];
    let norms = c.map(|v| v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    let k = (0..3).fold(0, |b, i| if norms[i] > norms[b] { i } else { b });
    if !(norms[k] > 0.0) {
        return None;
    }
    let inv = 1.0 / norms[k].sqrt();
    Some((c[k].map(|x| x * inv), l.map(|x| x * s)))
}

/// Eigenvalues, ascending, of a symmetric matrix whose entries are at most 1 in magnitude.
fn ascending_scaled(m: &[[f64; 3]; 3]) -> [f64; 3] {
    let p1 = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
    let q = (m[0][0] + m[1][1] + m[2][2]) / 3.0;
    let d = [m[0][0] - q, m[1][1] - q, m[2][2] - q];
    let p2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + 2.0 * p1;
    if p2 <= 0.0 {
        return [q; 3];
    }
    let p = (p2 / 6.0).sqrt();
    // det((A - qI) / p) / 2 = cos(3 phi).
    let b = [[d[0], m[0][1], m[0][2]], [m[0][1], d[1], m[1][2]], [m[0][2], m[1][2], d[2]]];
    let det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[1][2]) - b[0][1] * (b[0][1] * b[2][2] - b[1][2] * b[0][2])
        + b[0][2] * (b[0][1] * b[1][2] - b[1][1] * b[0][2]);
    let r = (det / (2.0 * p * p * p)).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let largest = q + 2.0 * p * phi.cos();
    let smallest = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    let middle = 3.0 * q - largest - smallest;
    [smallest, middle.clamp(smallest, largest), largest]
}

fn max_abs(a: &[[f64; 3]; 3]) -> f64 {
    let u = [a[0][0], a[0][1], a[0][2], a[1][1], a[1][2], a[2][2]];
    // NaN-propagating (f64::max drops a NaN).
    u.iter().fold(0.0f64, |m, &x| if x.is_nan() || m.is_nan() { f64::NAN } else { m.max(x.abs()) })
}

fn scaled(a: &[[f64; 3]; 3], f: f64) -> [[f64; 3]; 3] {
    // The upper triangle, mirrored: the matrix is symmetric by contract.
    let (a01, a02, a12) = (a[0][1] * f, a[0][2] * f, a[1][2] * f);
    [[a[0][0] * f, a01, a02], [a01, a[1][1] * f, a12], [a02, a12, a[2][2] * f]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, SymmetricEigen};

    /// A small deterministic generator (no test dependency on a RNG crate's stream).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((self.0 >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    fn reference(a: &[[f64; 3]; 3]) -> ([f64; 3], [f64; 3]) {
        let m = Matrix3::from_fn(|i, j| a[i][j]);
        let e = SymmetricEigen::new(m);
        let mut idx = [0, 1, 2];
        idx.sort_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j]));
        let v = e.eigenvectors.column(idx[0]);
        (idx.map(|i| e.eigenvalues[i]), [v[0], v[1], v[2]])
    }

    /// Scatter-like matrices: a random rotation of diag(l0, l1, l2) with spreads from isotropic to a
    /// flat patch (l0 / l2 down to 1e-8) and scales from 1e-8 (mm-size patches in metres) to 1e3.
    #[test]
    fn matches_nalgebra_on_random_scatter_matrices() {
        let mut g = Lcg(7);
        for t in 0..20_000 {
            let scale = 10f64.powf(-8.0 + 11.0 * (g.next() + 1.0) / 2.0);
            let flat = 10f64.powf(-8.0 * (g.next() + 1.0) / 2.0);
            let l = [flat * scale, (0.05 + (g.next() + 1.0) / 2.0) * scale, scale];
            let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                g.next(),
                g.next(),
                g.next(),
                g.next(),
            ));
            let r = q.to_rotation_matrix();
            let m = r.matrix() * Matrix3::from_diagonal(&nalgebra::Vector3::from(l)) * r.matrix().transpose();
            let a: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]));
            let (lr, vr) = reference(&a);
            let (v, lv) = smallest_eigenvector(&a).unwrap();
            for k in 0..3 {
                assert!((lv[k] - lr[k]).abs() <= 1e-9 * lr[2], "case {t}: {lv:?} vs {lr:?}");
            }
            let c = (v[0] * vr[0] + v[1] * vr[1] + v[2] * vr[2]).abs();
            assert!(c > 1.0 - 1e-9, "case {t}: |cos| {c}, spread {flat:e}");
            assert!((v.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn axis_aligned_and_degenerate_cases() {
        let d = [[3.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]];
        let (v, l) = smallest_eigenvector(&d).unwrap();
        assert!(l.iter().zip([1.0, 2.0, 3.0]).all(|(a, b)| (a - b).abs() < 1e-14), "{l:?}");
        assert!((v[1].abs() - 1.0).abs() < 1e-15);
        // Isotropic, zero, a line (two zero eigenvalues), NaN: no vector.
        let iso = [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]];
        assert!(smallest_eigenvector(&iso).is_none());
        assert!(smallest_eigenvector(&[[0.0; 3]; 3]).is_none());
        let line = [[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0]];
        assert!(smallest_eigenvector(&line).is_none());
        let nan = [[f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]];
        assert!(smallest_eigenvector(&nan).is_none());
        // A flat patch: its normal is the vector, whatever the spread in the plane.
        let flat = [[1.0, 0.5, 0.0], [0.5, 1.0, 0.0], [0.0, 0.0, 1e-9]];
        let (v, _) = smallest_eigenvector(&flat).unwrap();
        assert!((v[2].abs() - 1.0).abs() < 1e-12, "{v:?}");
    }
}
