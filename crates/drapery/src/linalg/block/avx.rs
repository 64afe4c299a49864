//! AVX forms of the block kernels: a 3×3 block's columns are 4-lane vectors (the fourth lane
//! reads past the column and is discarded or overwritten), a product's column is three
//! broadcasts, multiplies and adds in glam's order.
//!
//! Every function is compiled for AVX (`#[target_feature(enable = "avx")]`) whatever the
//! build's target CPU; callers reach them only after [`crate::linalg::simd::avx`] said the CPU
//! has it.

use crate::math::{Mat3, Vec3};
use std::arch::x86_64::*;

/// `(x, y, z, 0)`.
#[inline]
#[target_feature(enable = "avx")]
pub(crate) fn load3(v: &Vec3) -> __m256d {
    let p = v as *const Vec3 as *const f64;
    // SAFETY: both loads are within `v` (three `f64`, `#[repr(C)]`).
    unsafe {
        let lo = _mm_loadu_pd(p);
        let hi = _mm_load_sd(p.add(2));
        _mm256_insertf128_pd(_mm256_castpd128_pd256(lo), hi, 1)
    }
}

/// Writes the first three lanes of `a` to `v`.
#[inline]
#[target_feature(enable = "avx")]
pub(crate) fn store3(v: &mut Vec3, a: __m256d) {
    let p = v as *mut Vec3 as *mut f64;
    // SAFETY: both stores are within `v`.
    unsafe {
        _mm_storeu_pd(p, _mm256_castpd256_pd128(a));
        _mm_store_sd(p.add(2), _mm256_extractf128_pd(a, 1));
    }
}

/// The columns of `m` as 4-lane vectors (lane 3 is the next column's first entry, or 0 for
/// the third).
#[inline]
#[target_feature(enable = "avx")]
pub(crate) fn columns(m: &Mat3) -> [__m256d; 3] {
    let p = m as *const Mat3 as *const f64;
    // SAFETY: the 4-lane loads at 0 and 3 end at 4 and 7, within the nine `f64` of a `Mat3`
    // (`#[repr(C)]`, three columns); the third column goes through `load3`.
    unsafe {
        [
            _mm256_loadu_pd(p),
            _mm256_loadu_pd(p.add(3)),
            load3(&m.z_axis),
        ]
    }
}

/// `m v` for the columns `c` of `m`, added in glam's order `(c₀ x + c₁ y) + c₂ z` (lane 3 is
/// not used).
#[inline]
#[target_feature(enable = "avx")]
pub(crate) fn times(c: &[__m256d; 3], v: &Vec3) -> __m256d {
    // (register arithmetic: safe in an AVX function)
    let x = _mm256_mul_pd(c[0], _mm256_set1_pd(v.x));
    let y = _mm256_mul_pd(c[1], _mm256_set1_pd(v.y));
    let z = _mm256_mul_pd(c[2], _mm256_set1_pd(v.z));
    _mm256_add_pd(_mm256_add_pd(x, y), z)
}

/// How far ahead of the block being read [`prefetch_ahead`] asks for memory, in bytes: 32 cache
/// lines, about 28 blocks. The products stream their blocks from memory (a spin-290 matrix is
/// larger than the last-level cache), and the hardware prefetcher alone leaves the cores
/// waiting on it (BENCHMARKS.md, thirty-second session).
pub(crate) const AHEAD: usize = 2048;

/// Asks the CPU to bring the cache line [`AHEAD`] bytes past `p` into the cache: for a loop that
/// walks an array of blocks in order. A hint only: it reads nothing into the program and cannot
/// fault, past the array's end included (`wrapping_add` computes the address without requiring
/// it to lie in the allocation).
#[inline]
#[target_feature(enable = "avx")]
pub(crate) fn prefetch_ahead<T>(p: *const T) {
    _mm_prefetch::<_MM_HINT_T0>((p as *const i8).wrapping_add(AHEAD));
}

/// `acc + Σ_k blocks[k] x[cols[k]]`, in order (reading ahead of the blocks, which for a matrix's
/// rows walked in order are the next rows' blocks).
#[inline]
#[target_feature(enable = "avx")]
pub(crate) fn add_products(acc: Vec3, blocks: &[Mat3], cols: &[u32], x: &[Vec3]) -> Vec3 {
    let mut a = load3(&acc);
    for (m, &j) in blocks.iter().zip(cols) {
        prefetch_ahead(m);
        a = _mm256_add_pd(a, times(&columns(m), &x[j as usize]));
    }
    let mut out = Vec3::ZERO;
    store3(&mut out, a);
    out
}

/// `Σ left[l] right[r]` over `[l, r]` in `terms`, in order from zero.
#[inline]
#[target_feature(enable = "avx")]
pub(crate) fn sum_products(left: &[Mat3], right: &[Mat3], terms: &[[u32; 2]]) -> Mat3 {
    // SAFETY: register arithmetic, then 4-lane stores at 0 and 3 of a `Mat3` and `store3` for
    // its third column, in column order, so that each store's lane 3 (the next column's first
    // entry) is overwritten by the next one.
    unsafe {
        let mut acc = [_mm256_setzero_pd(); 3];
        for &[l, r] in terms {
            let c = columns(&left[l as usize]);
            let b = &right[r as usize];
            for (acc, col) in acc.iter_mut().zip([&b.x_axis, &b.y_axis, &b.z_axis]) {
                *acc = _mm256_add_pd(*acc, times(&c, col));
            }
        }
        let mut out = Mat3::ZERO;
        let po = &mut out as *mut Mat3 as *mut f64;
        _mm256_storeu_pd(po, acc[0]);
        _mm256_storeu_pd(po.add(3), acc[1]);
        store3(&mut out.z_axis, acc[2]);
        out
    }
}
