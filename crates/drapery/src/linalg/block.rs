//! 3×3 block products: the multigrid's (`A P`, `Pᵀ (A P)`, `D⁻¹ A` in the set-up, the
//! restriction and the prolongation in the cycle) and the block rows of a matrix times a vector
//! (`BlockMatrix::row_product`, `Coupling::row_product`), with AVX when the CPU running the
//! program has it ([`super::simd`]), and glam's scalar code otherwise. Both add in the same
//! order, so they give the same bits.

use crate::math::{Mat3, Vec3};

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
pub(crate) mod avx;

/// `a b`.
#[inline]
pub(crate) fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    sum_products(std::slice::from_ref(a), std::slice::from_ref(b), &[[0, 0]])
}

/// `Σ left[l] right[r]` over `[l, r]` in `terms`, added in that order from zero.
#[inline]
pub(crate) fn sum_products(left: &[Mat3], right: &[Mat3], terms: &[[u32; 2]]) -> Mat3 {
    #[cfg(target_arch = "x86_64")]
    if super::simd::avx() {
        #[allow(unsafe_code)]
        // SAFETY: the CPU has AVX.
        return unsafe { avx::sum_products(left, right, terms) };
    }
    sum_products_scalar(left, right, terms)
}

/// [`sum_products`] without AVX.
fn sum_products_scalar(left: &[Mat3], right: &[Mat3], terms: &[[u32; 2]]) -> Mat3 {
    terms.iter().fold(Mat3::ZERO, |acc, &[l, r]| {
        acc + left[l as usize] * right[r as usize]
    })
}

/// `acc + Σ_k blocks[k] x[cols[k]]`, added term by term in order.
#[inline]
pub(crate) fn add_products(acc: Vec3, blocks: &[Mat3], cols: &[u32], x: &[Vec3]) -> Vec3 {
    #[cfg(target_arch = "x86_64")]
    if super::simd::avx() {
        #[allow(unsafe_code)]
        // SAFETY: the CPU has AVX.
        return unsafe { avx::add_products(acc, blocks, cols, x) };
    }
    add_products_scalar(acc, blocks, cols, x)
}

/// [`add_products`] without AVX.
fn add_products_scalar(acc: Vec3, blocks: &[Mat3], cols: &[u32], x: &[Vec3]) -> Vec3 {
    blocks
        .iter()
        .zip(cols)
        .fold(acc, |a, (m, &j)| a + *m * x[j as usize])
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn mat() -> impl Strategy<Value = Mat3> {
        prop::array::uniform9(-1e3..1e3f64).prop_map(|a| Mat3::from_cols_array(&a))
    }

    fn bits(m: &Mat3) -> [u64; 9] {
        m.to_cols_array().map(f64::to_bits)
    }

    /// Both forms of a kernel, for the tests: the scalar one and, when the CPU has AVX, the
    /// AVX one (whatever the build's target CPU and `DRAPERY_SIMD`).
    fn sums_both_ways(left: &[Mat3], right: &[Mat3], terms: &[[u32; 2]]) -> Vec<Mat3> {
        let mut out = vec![sum_products_scalar(left, right, terms)];
        #[cfg(target_arch = "x86_64")]
        if crate::linalg::simd::cpu_has_avx() {
            #[allow(unsafe_code)]
            // SAFETY: the CPU has AVX.
            out.push(unsafe { avx::sum_products(left, right, terms) });
        }
        out
    }

    fn products_both_ways(acc: Vec3, blocks: &[Mat3], cols: &[u32], x: &[Vec3]) -> Vec<Vec3> {
        let mut out = vec![add_products_scalar(acc, blocks, cols, x)];
        #[cfg(target_arch = "x86_64")]
        if crate::linalg::simd::cpu_has_avx() {
            #[allow(unsafe_code)]
            // SAFETY: the CPU has AVX.
            out.push(unsafe { avx::add_products(acc, blocks, cols, x) });
        }
        out
    }

    #[test]
    fn the_avx_kernels_are_tested_where_the_cpu_has_avx() {
        let n = sums_both_ways(&[Mat3::IDENTITY], &[Mat3::IDENTITY], &[[0, 0]]).len();
        assert_eq!(n, 1 + crate::linalg::simd::cpu_has_avx() as usize);
    }

    proptest! {
        /// The products have the bits of glam's (`0 + a b` is `a b` unless an entry is `-0`,
        /// which random values are not), in both forms.
        #[test]
        fn products_have_the_scalar_bits(a in mat(), b in mat()) {
            prop_assert_eq!(bits(&mul(&a, &b)), bits(&(a * b)));
            for m in sums_both_ways(&[a], &[b], &[[0, 0]]) {
                prop_assert_eq!(bits(&m), bits(&(a * b)));
            }
        }

        #[test]
        fn sums_of_block_products_have_the_scalar_bits(
            left in prop::collection::vec(mat(), 1..6),
            right in prop::collection::vec(mat(), 1..6),
            terms in prop::collection::vec((0u32..6, 0u32..6), 0..10),
        ) {
            let terms: Vec<[u32; 2]> = terms
                .into_iter()
                .map(|(l, r)| [l % left.len() as u32, r % right.len() as u32])
                .collect();
            let want = terms
                .iter()
                .fold(Mat3::ZERO, |acc, &[l, r]| acc + left[l as usize] * right[r as usize]);
            prop_assert_eq!(bits(&sum_products(&left, &right, &terms)), bits(&want));
            for m in sums_both_ways(&left, &right, &terms) {
                prop_assert_eq!(bits(&m), bits(&want));
            }
        }

        #[test]
        fn sums_of_products_have_the_scalar_bits(
            blocks in prop::collection::vec(mat(), 0..12),
            x in prop::collection::vec(prop::array::uniform3(-1e3..1e3f64), 1..8),
            seed in any::<u32>(),
            acc in prop::array::uniform3(-1e3..1e3f64),
        ) {
            let x: Vec<Vec3> = x.into_iter().map(Vec3::from_array).collect();
            let cols: Vec<u32> = (0..blocks.len() as u32)
                .map(|k| (k.wrapping_mul(2_654_435_761) ^ seed) % x.len() as u32)
                .collect();
            let acc = Vec3::from_array(acc);
            let want = blocks
                .iter()
                .zip(&cols)
                .fold(acc, |a, (m, &j)| a + *m * x[j as usize]);
            let got = add_products(acc, &blocks, &cols, &x);
            prop_assert_eq!(got.to_array().map(f64::to_bits), want.to_array().map(f64::to_bits));
            for got in products_both_ways(acc, &blocks, &cols, &x) {
                prop_assert_eq!(got.to_array().map(f64::to_bits), want.to_array().map(f64::to_bits));
            }
        }
    }
}
