//! AVX forms of the block kernels: a 3×3 block's columns are 4-lane vectors (the fourth lane
//! reads past the column and is discarded or overwritten), a product's column is three
//! broadcasts, multiplies and adds in glam's order.

use crate::math::{Mat3, Vec3};
use std::arch::x86_64::*;

/// `(x, y, z, 0)`.
#[inline(always)]
pub(crate) fn load3(v: &Vec3) -> __m256d {
    let p = v as *const Vec3 as *const f64;
    // SAFETY: both loads are within `v` (three `f64`, `#[repr(C)]`); the build has AVX (the
    // module is compiled only then).
    unsafe {
        let lo = _mm_loadu_pd(p);
        let hi = _mm_load_sd(p.add(2));
        _mm256_insertf128_pd(_mm256_castpd128_pd256(lo), hi, 1)
    }
}

/// Writes the first three lanes of `a` to `v`.
#[inline(always)]
pub(crate) fn store3(v: &mut Vec3, a: __m256d) {
    let p = v as *mut Vec3 as *mut f64;
    // SAFETY: both stores are within `v`.
    unsafe {
        _mm_storeu_pd(p, _mm256_castpd256_pd128(a));
        _mm_store_sd(p.add(2), _mm256_extractf128_pd(a, 1));
    }
}

/// `acc += a b`.
#[inline(always)]
pub(crate) fn add_mul(acc: &mut Mat3, a: &Mat3, b: &Mat3) {
    let pa = a as *const Mat3 as *const f64;
    let pc = acc as *mut Mat3 as *mut f64;
    // SAFETY: the 4-lane loads at 0 and 3 end at 4 and 7, within the nine `f64` of a `Mat3`
    // (`#[repr(C)]`, three columns); the third column goes through `load3`/`store3`. The
    // 4-lane store of column 0 writes a wrong lane 3 (column 1's first entry), which the store
    // of column 1, loaded before, then overwrites.
    unsafe {
        let (c0, c1, c2) = (
            _mm256_loadu_pd(pa),
            _mm256_loadu_pd(pa.add(3)),
            load3(&a.z_axis),
        );
        let column = |b: &Vec3| {
            let x = _mm256_mul_pd(c0, _mm256_set1_pd(b.x));
            let y = _mm256_mul_pd(c1, _mm256_set1_pd(b.y));
            let z = _mm256_mul_pd(c2, _mm256_set1_pd(b.z));
            _mm256_add_pd(_mm256_add_pd(x, y), z)
        };
        let (r0, r1, r2) = (column(&b.x_axis), column(&b.y_axis), column(&b.z_axis));
        let (a0, a1, a2) = (
            _mm256_loadu_pd(pc),
            _mm256_loadu_pd(pc.add(3)),
            load3(&acc.z_axis),
        );
        _mm256_storeu_pd(pc, _mm256_add_pd(a0, r0));
        _mm256_storeu_pd(pc.add(3), _mm256_add_pd(a1, r1));
        store3(&mut acc.z_axis, _mm256_add_pd(a2, r2));
    }
}

/// `acc + Σ_k blocks[k] x[cols[k]]`, in order.
#[inline(always)]
pub(crate) fn add_products(acc: Vec3, blocks: &[Mat3], cols: &[u32], x: &[Vec3]) -> Vec3 {
    let mut a = load3(&acc);
    for (m, &j) in blocks.iter().zip(cols) {
        let p = m as *const Mat3 as *const f64;
        let v = &x[j as usize];
        // SAFETY: the 4-lane loads at 0 and 3 end within the `Mat3`; the third column goes
        // through `load3`.
        unsafe {
            let x = _mm256_mul_pd(_mm256_loadu_pd(p), _mm256_set1_pd(v.x));
            let y = _mm256_mul_pd(_mm256_loadu_pd(p.add(3)), _mm256_set1_pd(v.y));
            let z = _mm256_mul_pd(load3(&m.z_axis), _mm256_set1_pd(v.z));
            a = _mm256_add_pd(a, _mm256_add_pd(_mm256_add_pd(x, y), z));
        }
    }
    let mut out = Vec3::ZERO;
    store3(&mut out, a);
    out
}

/// `Σ left[l] right[r]` over `[l, r]` in `terms`, in order from zero.
#[inline(always)]
pub(crate) fn sum_products(left: &[Mat3], right: &[Mat3], terms: &[[u32; 2]]) -> Mat3 {
    // SAFETY: as in `add_mul`: 4-lane loads and stores at 0 and 3 of a `Mat3`, `load3` and
    // `store3` for its third column; the stores go in column order, so each one's fourth lane
    // is overwritten by the next.
    unsafe {
        let zero = _mm256_setzero_pd();
        let mut acc = [zero; 3];
        for &[l, r] in terms {
            let a = &left[l as usize];
            let pa = a as *const Mat3 as *const f64;
            let c0 = _mm256_loadu_pd(pa);
            let c1 = _mm256_loadu_pd(pa.add(3));
            let c2 = load3(&a.z_axis);
            let b = &right[r as usize];
            for (acc, col) in acc.iter_mut().zip([&b.x_axis, &b.y_axis, &b.z_axis]) {
                let x = _mm256_mul_pd(c0, _mm256_set1_pd(col.x));
                let y = _mm256_mul_pd(c1, _mm256_set1_pd(col.y));
                let z = _mm256_mul_pd(c2, _mm256_set1_pd(col.z));
                *acc = _mm256_add_pd(*acc, _mm256_add_pd(_mm256_add_pd(x, y), z));
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
