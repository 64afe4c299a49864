//! Sparse direct solve of the filtered system with faer.
//!
//! The filtered system `Â y = S (b - A z)`, `Â = S A S + (I - S)`, `x = z + y` has the same
//! solution as the filtered PCG of [`super::pcg`] (for a pinned particle the row of `Â` is the
//! identity and `y_i = 0`). `Â` is symmetric positive definite when `A` is, and is factored by
//! sparse Cholesky (`LLᵀ`, AMD ordering); a non-symmetric `A` (the optional damping position
//! Jacobian) goes to sparse LU. The scalar pattern and the symbolic factorization are kept and
//! reused while the block pattern stays the same.

use super::bsr::BlockMatrix;
use crate::math::{Mat3, Vec3};
use faer::Side;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};

/// Cached pattern and symbolic factorization.
#[derive(Default)]
pub struct DirectSolver {
    key: Option<(bool, Vec<usize>)>,
    symbolic: Option<SymbolicSparseColMat<u32>>,
    /// For each scalar entry: (block index, row in block, column in block).
    entries: Vec<(u32, u8, u8)>,
    llt: Option<SymbolicLlt<u32>>,
    lu: Option<SymbolicLu<u32>>,
    filtered: Vec<Mat3>,
    values: Vec<f64>,
}

impl DirectSolver {
    fn build_pattern(&mut self, a: &BlockMatrix, symmetric: bool) -> Result<(), String> {
        let n = a.n();
        let mut col_ptr = Vec::with_capacity(3 * n + 1);
        let mut row_idx = Vec::new();
        self.entries.clear();
        col_ptr.push(0u32);
        // Column c = 3i + a_ of the matrix: its entries are row 3j + b with A[3j+b][3i+a]
        // = block (j, i)[b][a]; for a symmetric A that is block (i, j)[a][b], read from row i.
        for i in 0..n {
            let (cols, range) = a.row(i);
            for ai in 0..3u8 {
                let c = 3 * i + ai as usize;
                for (k, &j) in range.clone().zip(cols) {
                    for b in 0..3u8 {
                        let r = 3 * j as usize + b as usize;
                        if symmetric && r < c {
                            continue;
                        }
                        row_idx.push(r as u32);
                        if symmetric {
                            self.entries.push((k as u32, ai, b));
                        } else {
                            let kt = a.find(j as usize, i).ok_or("pattern is not symmetric")?;
                            self.entries.push((kt as u32, b, ai));
                        }
                    }
                }
                col_ptr.push(row_idx.len() as u32);
            }
        }
        let sym = SymbolicSparseColMat::new_checked(3 * n, 3 * n, col_ptr, None, row_idx);
        if symmetric {
            self.llt = Some(
                SymbolicLlt::try_new(sym.as_ref(), Side::Lower).map_err(|e| format!("{e:?}"))?,
            );
            self.lu = None;
        } else {
            self.lu = Some(SymbolicLu::try_new(sym.as_ref()).map_err(|e| format!("{e:?}"))?);
            self.llt = None;
        }
        self.symbolic = Some(sym);
        Ok(())
    }

    /// Solves the filtered system (see module docs) into `x`. `symmetric` tells whether `A` is
    /// symmetric. Errors are messages (for example a non-positive pivot).
    pub fn solve(
        &mut self,
        a: &BlockMatrix,
        b: &[Vec3],
        s: &[Mat3],
        z: &[Vec3],
        x: &mut [Vec3],
        symmetric: bool,
    ) -> Result<(), String> {
        let n = a.n();
        let key: Vec<usize> = (0..n)
            .flat_map(|i| a.row(i).0.iter().map(|&c| c as usize).chain([usize::MAX]))
            .collect();
        if self.key.as_ref() != Some(&(symmetric, key.clone())) {
            self.build_pattern(a, symmetric)?;
            self.key = Some((symmetric, key));
        }
        self.filtered.resize(a.nnz_blocks(), Mat3::ZERO);
        for i in 0..n {
            let (cols, range) = a.row(i);
            for (k, &j) in range.zip(cols) {
                let mut m = s[i] * a.values[k] * s[j as usize];
                if j as usize == i {
                    m += Mat3::IDENTITY - s[i];
                }
                self.filtered[k] = m;
            }
        }
        self.values.clear();
        self.values.extend(
            self.entries
                .iter()
                .map(|&(k, r, c)| self.filtered[k as usize].col(c as usize)[r as usize]),
        );
        let mut az = vec![Vec3::ZERO; n];
        a.mul_vec(z, &mut az);
        let mut rhs = faer::Mat::<f64>::zeros(3 * n, 1);
        for i in 0..n {
            let r = s[i] * (b[i] - az[i]);
            for d in 0..3 {
                rhs[(3 * i + d, 0)] = r[d];
            }
        }
        let sym = self.symbolic.as_ref().expect("pattern built");
        let mat = SparseColMatRef::new(sym.as_ref(), &self.values);
        if let Some(llt) = &self.llt {
            let f = Llt::try_new_with_symbolic(llt.clone(), mat, Side::Lower).map_err(|e| {
                format!(
                    "sparse Cholesky failed: the system matrix is not positive definite ({e:?})"
                )
            })?;
            f.solve_in_place(rhs.as_mut());
        } else if let Some(lu) = &self.lu {
            let f = Lu::try_new_with_symbolic(lu.clone(), mat)
                .map_err(|e| format!("sparse LU failed: {e:?}"))?;
            f.solve_in_place(rhs.as_mut());
        }
        for i in 0..n {
            let y = Vec3::new(rhs[(3 * i, 0)], rhs[(3 * i + 1, 0)], rhs[(3 * i + 2, 0)]);
            x[i] = z[i] + s[i] * y;
        }
        if !crate::math::all_finite(x) {
            return Err("direct solve produced non-finite values".into());
        }
        Ok(())
    }
}
