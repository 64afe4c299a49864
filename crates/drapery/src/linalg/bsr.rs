//! A square sparse matrix of 3×3 blocks in block-CSR form.
//!
//! The pattern (which blocks exist) is fixed at construction from a list of particle pairs
//! and is always symmetric and contains every diagonal block; only values change from step to
//! step. Rows are independent, so the product `y = A x` runs row-parallel and gives the same
//! bits on any number of threads.

use crate::math::{Mat3, Vec3};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;

/// Which blocks a [`BlockMatrix`] stores; shared (not copied) between clones, so that code
/// caching positions for a pattern can tell by pointer whether it still has the same one.
#[derive(Debug, PartialEq, Eq)]
pub struct Pattern {
    row_ptr: Vec<u32>,
    col: Vec<u32>,
    diag: Vec<u32>,
}

/// Block-CSR matrix of `Mat3` blocks.
#[derive(Clone, Debug)]
pub struct BlockMatrix {
    pattern: Arc<Pattern>,
    /// Block values, in row-major pattern order.
    pub values: Vec<Mat3>,
}

/// Rows per task in row-parallel loops.
const ROWS: usize = 256;

impl BlockMatrix {
    /// Builds the pattern for `n` block rows: every diagonal block, plus `(i, j)` and `(j, i)`
    /// for every pair given. Duplicates are merged. Values start at zero.
    pub fn from_pairs(n: usize, pairs: &[(u32, u32)]) -> Self {
        let mut rows: Vec<Vec<u32>> = (0..n as u32).map(|i| vec![i]).collect();
        for &(i, j) in pairs {
            if i != j {
                rows[i as usize].push(j);
                rows[j as usize].push(i);
            }
        }
        let mut row_ptr = Vec::with_capacity(n + 1);
        let mut col = Vec::new();
        let mut diag = Vec::with_capacity(n);
        row_ptr.push(0u32);
        for (i, r) in rows.iter_mut().enumerate() {
            r.sort_unstable();
            r.dedup();
            let d = r.binary_search(&(i as u32)).expect("diagonal present");
            diag.push((col.len() + d) as u32);
            col.extend_from_slice(r);
            row_ptr.push(col.len() as u32);
        }
        let nnz = col.len();
        BlockMatrix {
            pattern: Arc::new(Pattern { row_ptr, col, diag }),
            values: vec![Mat3::ZERO; nnz],
        }
    }

    /// A matrix (values zero) whose pattern is this one's plus `(i, j)` and `(j, i)` for every
    /// pair given: the same pattern as [`BlockMatrix::from_pairs`] of this pattern's pairs and
    /// these, built by merging each row with its few new columns instead of sorting every row.
    pub fn with_pairs(&self, pairs: &[(u32, u32)]) -> Self {
        let n = self.n();
        let mut extra: Vec<(u32, u32)> = pairs
            .iter()
            .filter(|(i, j)| i != j)
            .flat_map(|&(i, j)| [(i, j), (j, i)])
            .collect();
        extra.sort_unstable();
        extra.dedup();
        let p = &*self.pattern;
        let mut row_ptr = Vec::with_capacity(n + 1);
        let mut col = Vec::with_capacity(p.col.len() + extra.len());
        let mut diag = Vec::with_capacity(n);
        row_ptr.push(0u32);
        let mut e = 0;
        for i in 0..n {
            let start = col.len();
            let old = &p.col[p.row_ptr[i] as usize..p.row_ptr[i + 1] as usize];
            let end = e + extra[e..].partition_point(|&(r, _)| r as usize == i);
            let new = &extra[e..end];
            e = end;
            let (mut a, mut b) = (0, 0);
            while a < old.len() || b < new.len() {
                let next = match (old.get(a), new.get(b).map(|&(_, c)| c)) {
                    (Some(&x), Some(y)) if x == y => {
                        b += 1;
                        a += 1;
                        x
                    }
                    (Some(&x), Some(y)) if x < y => {
                        a += 1;
                        x
                    }
                    (Some(_), Some(y)) | (None, Some(y)) => {
                        b += 1;
                        y
                    }
                    (Some(&x), None) => {
                        a += 1;
                        x
                    }
                    (None, None) => break,
                };
                if next as usize == i {
                    diag.push(col.len() as u32);
                }
                col.push(next);
            }
            debug_assert!(diag.len() == i + 1 && col.len() > start);
            row_ptr.push(col.len() as u32);
        }
        let nnz = col.len();
        BlockMatrix {
            pattern: Arc::new(Pattern { row_ptr, col, diag }),
            values: vec![Mat3::ZERO; nnz],
        }
    }

    /// The shared pattern.
    pub fn pattern(&self) -> &Arc<Pattern> {
        &self.pattern
    }

    /// Number of block rows (particles).
    pub fn n(&self) -> usize {
        self.pattern.diag.len()
    }

    /// Number of stored blocks.
    pub fn nnz_blocks(&self) -> usize {
        self.pattern.col.len()
    }

    /// Column indices and value range of block row `i`.
    pub fn row(&self, i: usize) -> (&[u32], std::ops::Range<usize>) {
        let p = &*self.pattern;
        let r = p.row_ptr[i] as usize..p.row_ptr[i + 1] as usize;
        (&p.col[r.clone()], r)
    }

    /// Position of block `(i, j)` in `values`, if it is in the pattern.
    pub fn find(&self, i: usize, j: usize) -> Option<usize> {
        if i == j {
            return Some(self.pattern.diag[i] as usize);
        }
        let (cols, r) = self.row(i);
        cols.binary_search(&(j as u32)).ok().map(|k| r.start + k)
    }

    /// Row offsets into `values`: row `i` is `row_ptr[i]..row_ptr[i + 1]`.
    pub fn row_ptr(&self) -> &[u32] {
        &self.pattern.row_ptr
    }

    /// Whether `other` has exactly the same pattern (values are not compared).
    pub fn same_pattern(&self, other: &BlockMatrix) -> bool {
        Arc::ptr_eq(&self.pattern, &other.pattern) || self.pattern == other.pattern
    }

    /// Position of the diagonal block of row `i`.
    pub fn diag_index(&self, i: usize) -> usize {
        self.pattern.diag[i] as usize
    }

    /// Sets every value to zero.
    pub fn clear(&mut self) {
        self.values
            .par_iter_mut()
            .with_min_len(16 * ROWS)
            .for_each(|m| *m = Mat3::ZERO);
    }

    /// Sets block `(i, i)` to `diag(i)` and every other block to zero, row-parallel.
    pub fn set_block_diagonal<F>(&mut self, diag: F)
    where
        F: Fn(usize) -> Mat3 + Sync,
    {
        let pattern = Arc::clone(&self.pattern);
        let d = &pattern.diag;
        self.for_each_row_mut(|i, first, _, vals| {
            vals.fill(Mat3::ZERO);
            vals[d[i] as usize - first] = diag(i);
        });
    }

    /// Adds `m` to block `(i, j)`. Panics if the block is not in the pattern (a bug in
    /// the caller's pattern, never a user error).
    pub fn add(&mut self, i: usize, j: usize, m: Mat3) {
        let k = self
            .find(i, j)
            .expect("block (i, j) missing from the pattern");
        self.values[k] += m;
    }

    /// Calls `f(i, first, columns, values)` on every block row `i` (`first`: the position in
    /// [`BlockMatrix::values`] of the row's first block), row-parallel (each row is visited by
    /// one task, so `f` decides the order of its own sums).
    pub fn for_each_row_mut<F>(&mut self, f: F)
    where
        F: Fn(usize, usize, &[u32], &mut [Mat3]) + Sync,
    {
        let p = &*self.pattern;
        let chunks = row_chunks(&mut self.values, &p.row_ptr, ROWS);
        chunks.into_par_iter().for_each(|(rows, vals)| {
            let base = p.row_ptr[rows.start] as usize;
            for i in rows {
                let r = p.row_ptr[i] as usize..p.row_ptr[i + 1] as usize;
                f(
                    i,
                    r.start,
                    &p.col[r.clone()],
                    &mut vals[r.start - base..r.end - base],
                );
            }
        });
    }

    /// `y = A x`, row-parallel and deterministic.
    pub fn mul_vec(&self, x: &[Vec3], y: &mut [Vec3]) {
        y.par_iter_mut()
            .enumerate()
            .with_min_len(ROWS)
            .for_each(|(i, yi)| *yi = self.row_product(i, x));
    }

    /// Row `i` of `A x`, added block by block in column order (with AVX where the CPU has it,
    /// the same bits either way: [`super::block::add_products`]).
    #[inline]
    pub fn row_product(&self, i: usize, x: &[Vec3]) -> Vec3 {
        let (cols, r) = self.row(i);
        super::block::add_products(Vec3::ZERO, &self.values[r], cols, x)
    }

    /// Dense copy (tests and small debugging only).
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let n = 3 * self.n();
        let mut d = vec![vec![0.0; n]; n];
        for i in 0..self.n() {
            let (cols, r) = self.row(i);
            for (c, m) in cols.iter().zip(&self.values[r]) {
                for a in 0..3 {
                    for b in 0..3 {
                        d[3 * i + a][3 * *c as usize + b] = m.col(b)[a];
                    }
                }
            }
        }
        d
    }

    /// Largest `|A_ij - A_ji|` over the stored entries (0 for a symmetric matrix).
    pub fn asymmetry(&self) -> f64 {
        let mut worst = 0.0f64;
        for i in 0..self.n() {
            let (cols, r) = self.row(i);
            for (c, m) in cols.iter().zip(&self.values[r]) {
                let t =
                    self.values[self.find(*c as usize, i).expect("symmetric pattern")].transpose();
                worst = worst.max(crate::math::max_abs(&(*m - t)));
            }
        }
        worst
    }
}

/// Splits `values`, laid out in rows by `ptr`, into chunks of about `rows` rows each, for
/// row-parallel loops that write whole rows.
pub(crate) fn row_chunks<'a, T>(
    mut values: &'a mut [T],
    ptr: &[u32],
    rows: usize,
) -> Vec<(Range<usize>, &'a mut [T])> {
    let n = ptr.len() - 1;
    let mut out = Vec::with_capacity(n.div_ceil(rows.max(1)));
    let mut start = 0;
    while start < n {
        let end = (start + rows).min(n);
        let len = (ptr[end] - ptr[start]) as usize;
        let (head, tail) = values.split_at_mut(len);
        out.push((start..end, head));
        values = tail;
        start = end;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Adding pairs to a pattern gives the pattern of all the pairs at once.
        #[test]
        fn adding_pairs_to_a_pattern_is_building_it_with_them(
            n in 1usize..40,
            base in prop::collection::vec((0u32..40, 0u32..40), 0..120),
            more in prop::collection::vec((0u32..40, 0u32..40), 0..40),
        ) {
            let clip = |v: &[(u32, u32)]| -> Vec<(u32, u32)> {
                v.iter().map(|&(i, j)| (i % n as u32, j % n as u32)).collect()
            };
            let (base, more) = (clip(&base), clip(&more));
            let a = BlockMatrix::from_pairs(n, &base).with_pairs(&more);
            let all: Vec<(u32, u32)> = base.iter().chain(&more).copied().collect();
            let b = BlockMatrix::from_pairs(n, &all);
            prop_assert_eq!(&a.pattern.row_ptr, &b.pattern.row_ptr);
            prop_assert_eq!(&a.pattern.col, &b.pattern.col);
            prop_assert_eq!(&a.pattern.diag, &b.pattern.diag);
            prop_assert_eq!(a.values.len(), b.values.len());
        }
    }

    #[test]
    fn product_matches_dense_product() {
        let pairs = [(0u32, 1u32), (1, 3), (2, 0), (3, 3)];
        let mut a = BlockMatrix::from_pairs(4, &pairs);
        let mut s = 0.37f64;
        for v in a.values.iter_mut() {
            let mut next = || {
                s = (s * 7.13 + 0.11).fract();
                s - 0.5
            };
            *v = Mat3::from_cols_array(&[
                next(),
                next(),
                next(),
                next(),
                next(),
                next(),
                next(),
                next(),
                next(),
            ]);
        }
        let x: Vec<Vec3> = (0..4)
            .map(|i| Vec3::new(i as f64, 1.0 - i as f64, 0.5 * i as f64 + 0.25))
            .collect();
        let mut y = vec![Vec3::ZERO; 4];
        a.mul_vec(&x, &mut y);
        let d = a.to_dense();
        let xf: Vec<f64> = x.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
        for r in 0..12 {
            let expect: f64 = (0..12).map(|c| d[r][c] * xf[c]).sum();
            assert!((y[r / 3][r % 3] - expect).abs() < 1e-14);
        }
        assert_eq!(a.nnz_blocks(), 4 + 2 * 3);
        assert!(a.find(0, 3).is_none());
    }
}
