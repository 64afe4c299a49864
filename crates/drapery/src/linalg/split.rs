//! A system matrix kept in two parts, `A = P + C` (docs/MATH.md §11): `P` on a fixed pattern,
//! the matrix the preconditioner is built from, and `C` the off-diagonal blocks of a few
//! couplings outside that pattern (a step's cloth–cloth contacts), held on their own small
//! pattern. A step with contacts then needs no merged pattern: products read `P` (the
//! multigrid's half-size copy of it, in PCG) and add the few rows `C` has.

use super::bsr::BlockMatrix;
use crate::math::Vec3;
use rayon::prelude::*;

/// Rows per task in the row-parallel product.
const ROWS: usize = 256;

/// Couplings between particles outside a fixed pattern: a block matrix on the couplings' own
/// pairs (its diagonal blocks are where their forces put theirs; [`Split`] reads only the
/// off-diagonal ones) and the particles that have any.
#[derive(Clone, Debug)]
pub struct Coupling {
    m: BlockMatrix,
    /// Rows with an off-diagonal block, ascending.
    rows: Vec<u32>,
}

impl Coupling {
    /// Zero couplings for `n` particles on the blocks `(i, j)` and `(j, i)` of every pair.
    pub fn new(n: usize, pairs: &[(u32, u32)]) -> Coupling {
        let m = BlockMatrix::from_pairs(n, pairs);
        let ptr = m.row_ptr();
        let rows = (0..n as u32)
            .filter(|&i| ptr[i as usize + 1] - ptr[i as usize] > 1)
            .collect();
        Coupling { m, rows }
    }

    /// The blocks, diagonal ones included (what forces assemble into).
    pub fn matrix(&self) -> &BlockMatrix {
        &self.m
    }

    /// The blocks, to assemble into.
    pub fn matrix_mut(&mut self) -> &mut BlockMatrix {
        &mut self.m
    }

    /// The particles with an off-diagonal block, ascending.
    pub fn rows(&self) -> &[u32] {
        &self.rows
    }

    /// Row `i` of `C x`, the off-diagonal blocks only.
    #[inline]
    pub fn row_product(&self, i: usize, x: &[Vec3]) -> Vec3 {
        let (cols, r) = self.m.row(i);
        let mut acc = Vec3::ZERO;
        for (&c, m) in cols.iter().zip(&self.m.values[r]) {
            if c as usize != i {
                acc += *m * x[c as usize];
            }
        }
        acc
    }
}

/// `A = P + C`, `C` the off-diagonal blocks of `coupling` when there is one.
#[derive(Clone, Copy, Debug)]
pub struct Split<'a> {
    /// The matrix on the fixed pattern (the preconditioner's).
    pub p: &'a BlockMatrix,
    /// The couplings outside it.
    pub coupling: Option<&'a Coupling>,
}

impl<'a> Split<'a> {
    /// `A = p`.
    pub fn whole(p: &'a BlockMatrix) -> Split<'a> {
        Split { p, coupling: None }
    }

    /// Number of block rows.
    pub fn n(&self) -> usize {
        self.p.n()
    }

    /// Row `i` of `A x`: `P`'s row, then `C`'s.
    #[inline]
    pub fn row_product(&self, i: usize, x: &[Vec3]) -> Vec3 {
        let y = self.p.row_product(i, x);
        match self.coupling {
            Some(c) => y + c.row_product(i, x),
            None => y,
        }
    }

    /// `y = A x`, row-parallel and deterministic.
    pub fn mul_vec(&self, x: &[Vec3], y: &mut [Vec3]) {
        y.par_iter_mut()
            .enumerate()
            .with_min_len(ROWS)
            .for_each(|(i, yi)| *yi = self.row_product(i, x));
    }

    /// The matrix `P + C` on one merged pattern (for the direct solver and inspection).
    pub fn merged(&self) -> BlockMatrix {
        let Some(c) = self.coupling else {
            return self.p.clone();
        };
        let mut pairs = Vec::new();
        for &i in &c.rows {
            let (cols, _) = c.m.row(i as usize);
            pairs.extend(cols.iter().filter(|&&j| j > i).map(|&j| (i, j)));
        }
        let mut a = self.p.with_pairs(&pairs);
        for i in 0..self.p.n() {
            let (cols, r) = self.p.row(i);
            for (&j, k) in cols.iter().zip(r) {
                a.add(i, j as usize, self.p.values[k]);
            }
        }
        for &i in &c.rows {
            let (cols, r) = c.m.row(i as usize);
            for (&j, k) in cols.iter().zip(r) {
                if j != i {
                    a.add(i as usize, j as usize, c.m.values[k]);
                }
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Mat3;
    use proptest::prelude::*;

    fn mat(v: &[f64]) -> Mat3 {
        Mat3::from_cols_array(&[v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]])
    }

    proptest! {
        /// The split product, row by row and whole, is the product with the merged matrix, and
        /// the merged matrix has `P`'s blocks, `C`'s off-diagonal ones, and nothing of `C`'s
        /// diagonal.
        #[test]
        fn the_split_product_is_the_merged_product(
            n in 2usize..30,
            base in prop::collection::vec((0u32..30, 0u32..30), 0..60),
            more in prop::collection::vec((0u32..30, 0u32..30), 0..20),
            vals in prop::collection::vec(-1.0f64..1.0, 9 * 200),
            x in prop::collection::vec(-1.0f64..1.0, 90),
        ) {
            let clip = |v: &[(u32, u32)]| -> Vec<(u32, u32)> {
                v.iter().map(|&(i, j)| (i % n as u32, j % n as u32)).collect()
            };
            let mut p = BlockMatrix::from_pairs(n, &clip(&base));
            let mut c = Coupling::new(n, &clip(&more));
            let mut k = 0;
            let mut next = || {
                k = (k + 9) % vals.len();
                mat(&vals[k..k + 9])
            };
            p.values.iter_mut().for_each(|m| *m = next());
            c.matrix_mut().values.iter_mut().for_each(|m| *m = next());
            let x: Vec<Vec3> = (0..n).map(|i| Vec3::new(x[3 * i], x[3 * i + 1], x[3 * i + 2])).collect();
            let a = Split { p: &p, coupling: Some(&c) };
            let merged = a.merged();
            let (mut y, mut want) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
            a.mul_vec(&x, &mut y);
            merged.mul_vec(&x, &mut want);
            for i in 0..n {
                prop_assert!((y[i] - want[i]).length() <= 1e-12, "row {}", i);
                // by hand: P's row plus C's off-diagonal blocks
                let mut by_hand = p.row_product(i, &x);
                for j in 0..n {
                    if j != i && let Some(k) = c.matrix().find(i, j) {
                        by_hand += c.matrix().values[k] * x[j];
                    }
                }
                prop_assert!((y[i] - by_hand).length() <= 1e-12, "row {}", i);
                let off = c.matrix().row(i).0.len() > 1;
                prop_assert_eq!(c.rows().contains(&(i as u32)), off);
            }
        }
    }
}
