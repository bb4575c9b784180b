//! The global step's sparse SPD system `(2 w_c L + D) P' = 2 B + D Q`, factorized with faer.
//!
//! The sparsity pattern (the mesh edges plus the diagonal) never changes during a registration, so
//! the symbolic Cholesky analysis (fill-reducing ordering, elimination tree, supernodes) runs once.
//! The numeric factorization depends on the data weights `D` only (the Laplacian is fixed), so it is
//! redone only when `D` differs from the cached one; the right-hand side is solved for x, y and z at
//! once (an n x 3 matrix). Everything runs sequentially (`Par::Seq`): on small systems parallel
//! Cholesky is slower, and the rayon pool is busy with the local step anyway.

use crate::cotan::CotanWeights;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// Symbolic factorization, the lower-triangular matrix values and the cached numeric factor.
pub struct GlobalSolver {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Values of `2 w_c L` (lower triangle, column-major).
    base: Vec<f64>,
    /// Values of `2 w_c L + D`.
    values: Vec<f64>,
    /// Position of the diagonal entry of each column in `values`.
    diag_pos: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    factor: Vec<f64>,
    /// The `D` of the current numeric factor (`None` before the first factorization).
    cached_d: Option<Vec<f64>>,
    buffer: MemBuffer,
}

impl std::fmt::Debug for GlobalSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GlobalSolver").field("n", &self.n).field("nnz", &self.row_idx.len()).finish()
    }
}

impl GlobalSolver {
    /// Builds the pattern of `2 w_c L` (lower triangle) and runs the symbolic analysis.
    pub fn new(weights: &CotanWeights, cell_weight: f64) -> Result<GlobalSolver, String> {
        let n = weights.n_vertices();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(weights.neighbors.len() / 2 + n);
        let mut base = Vec::with_capacity(weights.neighbors.len() / 2 + n);
        let mut diag_pos = Vec::with_capacity(n);
        col_ptr.push(0);
        for j in 0..n {
            let (nb, w) = weights.row(j);
            diag_pos.push(row_idx.len());
            row_idx.push(j);
            base.push(2.0 * cell_weight * w.iter().sum::<f64>());
            for (&i, &wij) in nb.iter().zip(w) {
                if (i as usize) > j {
                    row_idx.push(i as usize);
                    base.push(-2.0 * cell_weight * wij);
                }
            }
            col_ptr.push(row_idx.len());
        }
        let symbolic = {
            let sym = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
            factorize_symbolic_cholesky(sym, Side::Lower, Default::default(), Default::default())
                .map_err(|e| format!("symbolic Cholesky failed: {e:?}"))?
        };
        let factor = vec![0.0; symbolic.len_val()];
        let req = symbolic
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(3, Par::Seq));
        let buffer = MemBuffer::try_new(req).map_err(|_| "out of memory for the Cholesky workspace".to_string())?;
        let values = base.clone();
        Ok(GlobalSolver { n, col_ptr, row_idx, base, values, diag_pos, symbolic, factor, cached_d: None, buffer })
    }

    /// Makes the numeric factor match the data weights `d` (refactorizes only when `d` changed).
    /// Returns whether a numeric factorization ran.
    pub fn set_data_weights(&mut self, d: &[f64]) -> Result<bool, String> {
        if d.len() != self.n {
            return Err(format!("{} data weights for {} vertices", d.len(), self.n));
        }
        if self.cached_d.as_deref() == Some(d) {
            return Ok(false);
        }
        self.values.copy_from_slice(&self.base);
        for (j, &dj) in d.iter().enumerate() {
            self.values[self.diag_pos[j]] += dj;
        }
        let mat = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx),
            &self.values,
        );
        let stack = MemStack::new(&mut self.buffer);
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.factor,
                mat,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map_err(|e| {
                format!("the system is not positive definite ({e:?}): a template component has no correspondence")
            })?;
        match &mut self.cached_d {
            Some(c) => c.copy_from_slice(d),
            None => self.cached_d = Some(d.to_vec()),
        }
        Ok(true)
    }

    /// Solves in place for an n x 3 right-hand side (requires [`Self::set_data_weights`] first).
    pub fn solve_in_place(&mut self, rhs: MatMut<'_, f64>) -> Result<(), String> {
        if self.cached_d.is_none() {
            return Err("solve before factorization".to_string());
        }
        if rhs.nrows() != self.n {
            return Err(format!("right-hand side has {} rows for {} vertices", rhs.nrows(), self.n));
        }
        let llt = LltRef::<'_, usize, f64>::new(&self.symbolic, &self.factor);
        llt.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, MemStack::new(&mut self.buffer));
        Ok(())
    }
}
