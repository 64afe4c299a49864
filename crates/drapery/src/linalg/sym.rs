//! The upper triangle of a symmetric [`BlockMatrix`], for products that read half the bytes.
//!
//! A symmetric matrix (`A_ji = A_ijᵀ`) is known from its blocks with `j ≥ i`. The product
//! `y = A x` then reads each stored block once and uses it twice: `y_i += A_ij x_j` and
//! `y_j += A_ijᵀ x_i`. On a cloth the matrix is larger than the caches and every product
//! streams it, so about 45 % fewer bytes is about 45 % less time.
//!
//! **Determinism.** Rows are cut into fixed chunks that depend on the size only. A chunk's
//! task walks its rows in order and scatters the transposed terms into rows of the same chunk;
//! the terms `A_ijᵀ x_i` whose row `i` lies in an earlier chunk ("remote" ones, near the chunk's
//! start for a banded ordering) are gathered afterwards, in a fixed order, by the task of row
//! `j`'s chunk. Each `y_j` is thus summed in one order whatever the thread count.

use super::bsr::{BlockMatrix, row_chunks};
use crate::math::{Mat3, Vec3};
use rayon::prelude::*;

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx;

/// Upper triangle (diagonal included) of a symmetric block matrix, with the lists that make
/// its product row-parallel.
#[derive(Clone, Debug)]
pub struct SymBlockMatrix {
    /// Row `i` is `row_ptr[i]..row_ptr[i + 1]`; its first block is the diagonal.
    row_ptr: Vec<u32>,
    col: Vec<u32>,
    /// The blocks, then one zero block of padding (see [`avx`]).
    values: Vec<Mat3>,
    /// Per row `j`, the remote terms: row `i` (in an earlier chunk) and position of `A_ij`.
    remote_ptr: Vec<u32>,
    remote_row: Vec<u32>,
    remote_pos: Vec<u32>,
    /// Rows per chunk.
    chunk: usize,
}

/// Rows per chunk for `n` rows: about eight chunks (so that two threads balance), at least
/// 256 rows and at most 4096 (the fewer the chunks, the fewer the remote terms).
fn chunk_rows(n: usize) -> usize {
    (n / 8).clamp(256, 4096)
}

impl SymBlockMatrix {
    /// The structure for the upper triangle of `a`'s pattern (which is symmetric and has every
    /// diagonal block); values are zero until [`SymBlockMatrix::set_values`].
    pub fn from_pattern(a: &BlockMatrix) -> Self {
        let n = a.n();
        let chunk = chunk_rows(n);
        let (mut row_ptr, mut col) = (vec![0u32], Vec::new());
        let mut remote: Vec<(u32, u32, u32)> = Vec::new();
        for i in 0..n {
            let (cols, r) = a.row(i);
            let chunk_end = ((i / chunk + 1) * chunk).min(n);
            // the upper part of a sorted row is the part from the diagonal on
            debug_assert_eq!(
                r.start + cols.partition_point(|&j| (j as usize) < i),
                a.diag_index(i)
            );
            for &j in cols.iter().filter(|&&j| j as usize >= i) {
                if j as usize >= chunk_end {
                    remote.push((j, i as u32, col.len() as u32));
                }
                col.push(j);
            }
            row_ptr.push(col.len() as u32);
        }
        // by row j, then by i: the order each row gathers its remote terms in
        remote.sort_unstable();
        let mut remote_ptr = vec![0u32; n + 1];
        for &(j, _, _) in &remote {
            remote_ptr[j as usize + 1] += 1;
        }
        for j in 0..n {
            remote_ptr[j + 1] += remote_ptr[j];
        }
        SymBlockMatrix {
            values: vec![Mat3::ZERO; col.len() + 1],
            row_ptr,
            col,
            remote_ptr,
            remote_row: remote.iter().map(|t| t.1).collect(),
            remote_pos: remote.iter().map(|t| t.2).collect(),
            chunk,
        }
    }

    /// Number of block rows.
    pub fn n(&self) -> usize {
        self.row_ptr.len() - 1
    }

    /// Number of stored blocks.
    pub fn nnz_blocks(&self) -> usize {
        self.col.len()
    }

    /// Copies the upper triangle of `a` (of the pattern this was built from): row by row, the
    /// part of `a`'s row from its diagonal on.
    pub fn set_values(&mut self, a: &BlockMatrix) {
        let chunks = row_chunks(&mut self.values, &self.row_ptr, 1024);
        chunks.into_par_iter().for_each(|(rows, vals)| {
            let mut at = 0;
            for i in rows {
                let (_, r) = a.row(i);
                let upper = &a.values[a.diag_index(i)..r.end];
                vals[at..at + upper.len()].copy_from_slice(upper);
                at += upper.len();
            }
        });
    }

    /// The stored blocks cut into runs of `rows` rows (each row's blocks from its diagonal
    /// on), with their row ranges: for writing the values in parallel, as
    /// [`SymBlockMatrix::set_values`] does.
    pub fn row_chunks_mut(&mut self, rows: usize) -> Vec<(std::ops::Range<usize>, &mut [Mat3])> {
        row_chunks(&mut self.values, &self.row_ptr, rows)
    }

    /// The diagonal block of row `i`.
    pub fn diag(&self, i: usize) -> &Mat3 {
        &self.values[self.row_ptr[i] as usize]
    }

    /// `y = A x`, then `y_i = finish(i, (A x)_i).0` row by row; returns the sums of the `K`
    /// numbers `finish` returned (added row by row within a chunk, then chunk by chunk), so a
    /// following vector operation and dot products fuse with the product. Same bits on any
    /// number of threads. `partial` is scratch memory.
    pub fn mul_then<const K: usize>(
        &self,
        x: &[Vec3],
        y: &mut [Vec3],
        partial: &mut Vec<[f64; K]>,
        finish: impl Fn(usize, Vec3) -> (Vec3, [f64; K]) + Sync,
    ) -> [f64; K] {
        let n = self.n();
        assert!(x.len() == n && y.len() == n);
        partial.resize(n.div_ceil(self.chunk), [0.0; K]);
        y.par_chunks_mut(self.chunk)
            .zip(partial.par_iter_mut())
            .enumerate()
            .for_each(|(c, (y, p))| *p = self.chunk_product(c * self.chunk, x, y, &finish));
        partial.iter().fold([0.0; K], |mut acc, p| {
            acc.iter_mut().zip(p).for_each(|(a, b)| *a += b);
            acc
        })
    }

    /// The rows `first..first + y.len()` of [`SymBlockMatrix::mul_then`].
    fn chunk_product<const K: usize>(
        &self,
        first: usize,
        x: &[Vec3],
        y: &mut [Vec3],
        finish: &impl Fn(usize, Vec3) -> (Vec3, [f64; K]),
    ) -> [f64; K] {
        let end = first + y.len();
        y.iter_mut().for_each(|v| *v = Vec3::ZERO);
        rows(&self.row_ptr, &self.col, &self.values, first, x, y);
        let mut sum = [0.0; K];
        for j in first..end {
            let mut acc = y[j - first];
            for e in self.remote_ptr[j] as usize..self.remote_ptr[j + 1] as usize {
                let m = &self.values[self.remote_pos[e] as usize];
                acc += transpose_mul(m, x[self.remote_row[e] as usize]);
            }
            let (out, s) = finish(j, acc);
            y[j - first] = out;
            sum.iter_mut().zip(s).for_each(|(a, b)| *a += b);
        }
        sum
    }
}

/// The rows of the product ([`rows_scalar`]): the AVX form when the CPU has it.
fn rows(row_ptr: &[u32], col: &[u32], values: &[Mat3], first: usize, x: &[Vec3], y: &mut [Vec3]) {
    #[cfg(target_arch = "x86_64")]
    if super::simd::avx() {
        #[allow(unsafe_code)]
        // SAFETY: the CPU has AVX.
        return unsafe { avx::rows(row_ptr, col, values, first, x, y) };
    }
    rows_scalar(row_ptr, col, values, first, x, y)
}

/// Rows `first..first + y.len()` of the product, less the remote terms: `y_i += A_ij x_j` for
/// the stored blocks of row `i` (diagonal first) and `y_j += A_ijᵀ x_i` for the rows `j` of the
/// same range, rows in order. The portable form, and the reference the AVX one is tested
/// against.
fn rows_scalar(
    row_ptr: &[u32],
    col: &[u32],
    values: &[Mat3],
    first: usize,
    x: &[Vec3],
    y: &mut [Vec3],
) {
    let end = first + y.len();
    for i in first..end {
        let r = row_ptr[i] as usize..row_ptr[i + 1] as usize;
        let xi = x[i];
        let mut acc = y[i - first];
        for (&j, m) in col[r.clone()].iter().zip(&values[r]) {
            let j = j as usize;
            acc += *m * x[j];
            if j != i && j < end {
                y[j - first] += transpose_mul(m, xi);
            }
        }
        y[i - first] = acc;
    }
}

/// `mᵀ v`.
#[inline]
fn transpose_mul(m: &Mat3, v: Vec3) -> Vec3 {
    Vec3::new(m.x_axis.dot(v), m.y_axis.dot(v), m.z_axis.dot(v))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A random symmetric block matrix on `n` rows with `pairs` random off-diagonal pairs
    /// (near the diagonal when `band > 0`, anywhere otherwise), and a random vector.
    fn random(n: usize, pairs: usize, band: usize, seed: u64) -> (BlockMatrix, Vec<Vec3>) {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut unit = move || (next() >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        let mut idx = Vec::new();
        let mut r = 0.37f64;
        for p in 0..pairs {
            r = (r * 7.13 + 0.11 + p as f64 * 1e-3).fract();
            let i = (r * n as f64) as usize % n;
            let j = if band > 0 {
                (i + 1 + (p * 31) % band).min(n - 1)
            } else {
                (p * 7919 + 13) % n
            };
            idx.push((i as u32, j as u32));
        }
        let mut a = BlockMatrix::from_pairs(n, &idx);
        for i in 0..n {
            let (cols, r) = a.row(i);
            for (&j, k) in cols.to_vec().iter().zip(r) {
                if (j as usize) < i {
                    continue;
                }
                let m = Mat3::from_cols_array(&std::array::from_fn(|_| unit()));
                a.values[k] = m;
                let t = a.find(j as usize, i).unwrap();
                a.values[t] = m.transpose();
            }
        }
        let x = (0..n).map(|_| Vec3::new(unit(), unit(), unit())).collect();
        (a, x)
    }

    fn product(a: &BlockMatrix, x: &[Vec3]) -> (Vec<Vec3>, f64) {
        let mut s = SymBlockMatrix::from_pattern(a);
        s.set_values(a);
        let mut y = vec![Vec3::ZERO; a.n()];
        let [dot] = s.mul_then(x, &mut y, &mut Vec::new(), |i, v| (v, [x[i].dot(v)]));
        (y, dot)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        #[test]
        fn product_matches_the_full_matrix(
            n in 1usize..3000, density in 0usize..6, band in 0usize..400, seed in any::<u64>()
        ) {
            let (a, x) = random(n, density * n, band, seed);
            let (y, dot) = product(&a, &x);
            let mut full = vec![Vec3::ZERO; n];
            a.mul_vec(&x, &mut full);
            let scale = full.iter().fold(1.0f64, |m, v| m.max(v.abs().max_element()));
            for (got, want) in y.iter().zip(&full) {
                prop_assert!((*got - *want).abs().max_element() <= 1e-13 * scale);
            }
            let want: f64 = x.iter().zip(&full).map(|(a, b)| a.dot(*b)).sum();
            prop_assert!((dot - want).abs() <= 1e-11 * scale * n as f64);
        }
    }

    #[cfg(target_arch = "x86_64")]
    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// The AVX rows against the scalar ones, bit for bit, on row ranges cut anywhere.
        #[test]
        fn avx_rows_have_the_scalar_bits(
            n in 1usize..600, density in 0usize..6, band in 0usize..100, seed in any::<u64>(),
            cut in 0.0..1.0f64,
        ) {
            // (on a CPU without AVX there is nothing to compare)
            prop_assume!(crate::linalg::simd::cpu_has_avx());
            let (a, x) = random(n, density * n, band, seed);
            let mut s = SymBlockMatrix::from_pattern(&a);
            s.set_values(&a);
            let mid = (cut * n as f64) as usize;
            for range in [0..mid, mid..n, 0..n] {
                let mut got = vec![Vec3::ZERO; range.len()];
                let mut want = got.clone();
                #[allow(unsafe_code)]
                // SAFETY: the CPU has AVX (assumed above).
                unsafe { avx::rows(&s.row_ptr, &s.col, &s.values, range.start, &x, &mut got) };
                rows_scalar(&s.row_ptr, &s.col, &s.values, range.start, &x, &mut want);
                for (g, w) in got.iter().zip(&want) {
                    prop_assert_eq!(g.to_array().map(f64::to_bits), w.to_array().map(f64::to_bits));
                }
            }
        }
    }

    #[test]
    fn same_bits_on_one_and_two_threads() {
        let (a, x) = random(20_000, 60_000, 300, 7);
        let run = |t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .unwrap()
                .install(|| product(&a, &x))
        };
        let (one, two) = (run(1), run(2));
        assert_eq!(one.1.to_bits(), two.1.to_bits());
        assert!(one.0.iter().zip(&two.0).all(|(p, q)| {
            p.to_array()
                .iter()
                .zip(q.to_array())
                .all(|(u, v)| u.to_bits() == v.to_bits())
        }));
        // a banded matrix has remote terms only near the chunk starts
        let s = SymBlockMatrix::from_pattern(&a);
        assert!(!s.remote_row.is_empty() && s.remote_row.len() < s.nnz_blocks() / 4);
    }
}
