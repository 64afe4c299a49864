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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::outer;
    use proptest::prelude::*;

    /// A block matrix with a symmetric pattern (a ring plus chords) and values from `r`: the
    /// off-diagonal blocks independent on each side (not symmetric) unless `symmetric`, the
    /// diagonal dominant so that the filtered matrix is well conditioned.
    fn matrix(n: usize, r: &mut impl FnMut() -> f64, symmetric: bool) -> BlockMatrix {
        let mut pairs: Vec<(u32, u32)> = (0..n as u32).map(|i| (i, (i + 1) % n as u32)).collect();
        pairs.extend(
            (0..n as u32)
                .step_by(3)
                .map(|i| (i, (i + n as u32 / 2) % n as u32)),
        );
        pairs.retain(|(i, j)| i != j);
        let mut a = BlockMatrix::from_pairs(n, &pairs);
        let mut block = || Mat3::from_cols_array(&std::array::from_fn(|_| r()));
        let mut weight = vec![0.0; n];
        for i in 0..n {
            for &j in a.row(i).0.to_vec().iter().filter(|&&j| j as usize > i) {
                let j = j as usize;
                let b = block();
                let c = if symmetric { b.transpose() } else { block() };
                a.add(i, j, b);
                a.add(j, i, c);
                weight[i] += 3.0;
                weight[j] += 3.0;
            }
        }
        for (i, w) in weight.iter().enumerate() {
            let mut d = block();
            if symmetric {
                d = 0.5 * (d + d.transpose());
            }
            a.add(i, i, d + Mat3::from_diagonal(Vec3::splat(w + 2.0)));
        }
        a
    }

    /// The constrained problem solved densely by LU, in a form other than the solver's: the
    /// 3n equations `S_i (A x - b)_i + (I - S_i)(x_i - z_i) = 0`, i.e.
    /// `(S A + I - S) x = S b + (I - S) z`, with no change of unknowns.
    fn dense_reference(a: &BlockMatrix, b: &[Vec3], s: &[Mat3], z: &[Vec3]) -> Vec<Vec3> {
        let n = a.n();
        let mut m = faer::Mat::<f64>::zeros(3 * n, 3 * n);
        let mut rhs = faer::Mat::<f64>::zeros(3 * n, 1);
        for i in 0..n {
            let (cols, range) = a.row(i);
            for (&j, k) in cols.iter().zip(range) {
                let mut blk = s[i] * a.values[k];
                if j as usize == i {
                    blk += Mat3::IDENTITY - s[i];
                }
                for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
                    m[(3 * i + r, 3 * j as usize + c)] = blk.col(c)[r];
                }
            }
            let v = s[i] * b[i] + (Mat3::IDENTITY - s[i]) * z[i];
            for r in 0..3 {
                rhs[(3 * i + r, 0)] = v[r];
            }
        }
        let x = m.partial_piv_lu().solve(&rhs);
        (0..n)
            .map(|i| Vec3::new(x[(3 * i, 0)], x[(3 * i + 1, 0)], x[(3 * i + 2, 0)]))
            .collect()
    }

    /// Random filter: pinned, held against a plane (normal `n`), or free; `z` in the
    /// constrained directions only.
    fn constraints(n: usize, r: &mut impl FnMut() -> f64) -> (Vec<Mat3>, Vec<Vec3>) {
        let mut s = vec![Mat3::IDENTITY; n];
        let mut z = vec![Vec3::ZERO; n];
        for i in 0..n {
            let kind = (r() + 1.0) * 1.5;
            let v = Vec3::new(r(), r(), r());
            if kind < 1.0 {
                s[i] = Mat3::ZERO;
                z[i] = v;
            } else if kind < 2.0 {
                let normal = (Vec3::new(r(), r(), r()) + Vec3::Z).normalize();
                s[i] = Mat3::IDENTITY - outer(normal, normal);
                z[i] = normal * v.x;
            }
        }
        (s, z)
    }

    fn max_norm(v: &[Vec3]) -> f64 {
        v.iter().fold(0.0, |m, e| m.max(e.abs().max_element()))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// The sparse LU path (a non-symmetric `A`, as with the damping position Jacobian) and the
        /// Cholesky path (a symmetric positive definite `A`) give the dense LU's solution of the
        /// constrained system to 1e-10 relative, and meet the constraints exactly.
        #[test]
        fn the_direct_solve_is_the_dense_solution_of_the_constrained_system(
            seed in any::<u64>(), n in 3usize..14, symmetric in any::<bool>(),
        ) {
            let mut state = seed | 1;
            let mut r = move || {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
            };
            let a = matrix(n, &mut r, symmetric);
            prop_assert_eq!(a.asymmetry() == 0.0, symmetric);
            let (s, z) = constraints(n, &mut r);
            let b: Vec<Vec3> = (0..n).map(|_| Vec3::new(r(), r(), r()) * 10.0).collect();
            let want = dense_reference(&a, &b, &s, &z);
            let mut got = vec![Vec3::ZERO; n];
            DirectSolver::default().solve(&a, &b, &s, &z, &mut got, symmetric).unwrap();
            let diff: Vec<Vec3> = got.iter().zip(&want).map(|(g, w)| *g - *w).collect();
            prop_assert!(max_norm(&diff) <= 1e-10 * max_norm(&want), "{} vs {}", max_norm(&diff), max_norm(&want));
            // (I - S) x = z to rounding, S (A x - b) ≈ 0
            let mut ax = vec![Vec3::ZERO; n];
            a.mul_vec(&got, &mut ax);
            for i in 0..n {
                let fixed = (Mat3::IDENTITY - s[i]) * got[i] - z[i];
                prop_assert!(fixed.length() <= 1e-13 * (1.0 + z[i].length()), "{i}: {fixed}");
                let res = s[i] * (ax[i] - b[i]);
                prop_assert!(res.length() <= 1e-10 * max_norm(&b), "{i}: {res}");
            }
        }
    }

    #[test]
    fn the_lu_path_solves_a_matrix_cholesky_rejects() {
        // Â = diag(1, -1) per coordinate is invertible but not positive definite: LU solves it,
        // Cholesky must refuse it.
        let mut a = BlockMatrix::from_pairs(2, &[(0, 1)]);
        a.add(0, 0, Mat3::IDENTITY);
        a.add(1, 1, -Mat3::IDENTITY);
        let b = [Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0)];
        let (s, z) = ([Mat3::IDENTITY; 2], [Vec3::ZERO; 2]);
        let mut x = [Vec3::ZERO; 2];
        let mut direct = DirectSolver::default();
        direct.solve(&a, &b, &s, &z, &mut x, false).unwrap();
        assert_eq!(x, [b[0], -b[1]]);
        let e = direct.solve(&a, &b, &s, &z, &mut x, true).unwrap_err();
        assert!(e.contains("not positive definite"), "{e}");
    }
}
