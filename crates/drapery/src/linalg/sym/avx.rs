//! The rows of [`super::SymBlockMatrix`]'s product with AVX: a block's three columns are three
//! 4-lane loads (the fourth lane reads the next value, or the padding after the last block, and
//! meets a zero), `A_ij x_j` is three broadcasts, multiplies and adds, and `A_ijᵀ x_i` is three
//! multiplies and two horizontal adds. Each lane adds in the order of the scalar code
//! ([`super::rows_scalar`]), so the bits are the same (a dot product's last term gains `+ 0`,
//! which can only turn a `-0` into `+0`). The loop asks for the blocks ahead of the one it reads
//! ([`prefetch_ahead`]): a cloth's matrix streams from memory, and without the hint the cores wait
//! on it (a spin-290 product took 2.0 ms without, 1.6 ms with; BENCHMARKS.md, thirty-second
//! session).
//!
//! Compiled for AVX whatever the build's target CPU; reached only after
//! [`crate::linalg::simd::avx`] said the CPU has it.

use crate::linalg::block::avx::{load3, prefetch_ahead, store3, times};
use crate::math::{Mat3, Vec3};
use std::arch::x86_64::*;

/// See [`super::rows_scalar`]; `values` must hold one block past the last one these rows use
/// (the padding block of [`super::SymBlockMatrix`]), which the third column's load reads into.
#[target_feature(enable = "avx")]
pub(super) fn rows(
    row_ptr: &[u32],
    col: &[u32],
    values: &[Mat3],
    first: usize,
    x: &[Vec3],
    y: &mut [Vec3],
) {
    let end = first + y.len();
    let (last, tail) = (row_ptr[end] as usize, values.len());
    assert!(last < tail, "the padding block is missing");
    let v = values.as_ptr() as *const f64;
    for i in first..end {
        let (s, e) = (row_ptr[i] as usize, row_ptr[i + 1] as usize);
        let xi = load3(&x[i]);
        // SAFETY: block k's columns start at 9 k, 9 k + 3 and 9 k + 6; each 4-lane load ends
        // at most at 9 k + 9, within block k + 1 ≤ `last`, which is in `values` (asserted).
        unsafe {
            let columns = |k: usize| block_columns(v, k);
            // the diagonal block first, as in the scalar order
            let mut acc = _mm256_add_pd(load3(&y[i - first]), times(&columns(s), &x[i]));
            for (k, &j) in (s + 1..e).zip(&col[s + 1..e]) {
                let j = j as usize;
                prefetch_ahead(v.wrapping_add(9 * k));
                let c = columns(k);
                acc = _mm256_add_pd(acc, times(&c, &x[j]));
                if j < end {
                    let h01 = _mm256_hadd_pd(_mm256_mul_pd(c[0], xi), _mm256_mul_pd(c[1], xi));
                    let t2 = _mm256_mul_pd(c[2], xi);
                    let h22 = _mm256_hadd_pd(t2, t2);
                    let lo = _mm256_permute2f128_pd(h01, h22, 0x20);
                    let hi = _mm256_permute2f128_pd(h01, h22, 0x31);
                    let yj = &mut y[j - first];
                    store3(yj, _mm256_add_pd(load3(yj), _mm256_add_pd(lo, hi)));
                }
            }
            store3(&mut y[i - first], acc);
        }
    }
}

/// The three columns of block `k` of the values at `v`, as 4-lane loads.
///
/// # Safety
/// `v` must point to at least `9 k + 10` readable `f64`.
#[inline]
#[target_feature(enable = "avx")]
unsafe fn block_columns(v: *const f64, k: usize) -> [__m256d; 3] {
    // SAFETY: the caller's bound covers the last load's four lanes, 9 k + 6 .. 9 k + 10.
    unsafe { [0, 3, 6].map(|c| _mm256_loadu_pd(v.add(9 * k + c))) }
}
