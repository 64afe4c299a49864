//! 3×3 block products of the multigrid (`A P`, `Pᵀ (A P)`, `D⁻¹ A` in the set-up, the
//! restriction and the prolongation in the cycle), with AVX when the build targets a CPU that
//! has it (see `.cargo/config.toml`), and glam's scalar code otherwise. Both add in the same
//! order, so they give the same bits.

use crate::math::{Mat3, Vec3};

#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
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
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    return avx::sum_products(left, right, terms);
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    terms.iter().fold(Mat3::ZERO, |acc, &[l, r]| {
        acc + left[l as usize] * right[r as usize]
    })
}

/// `acc + Σ_k blocks[k] x[cols[k]]`, added term by term in order.
#[inline]
pub(crate) fn add_products(acc: Vec3, blocks: &[Mat3], cols: &[u32], x: &[Vec3]) -> Vec3 {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    return avx::add_products(acc, blocks, cols, x);
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
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

    proptest! {
        /// The products have the bits of glam's (`0 + a b` is `a b` unless an entry is `-0`,
        /// which random values are not).
        #[test]
        fn products_have_the_scalar_bits(a in mat(), b in mat()) {
            prop_assert_eq!(bits(&mul(&a, &b)), bits(&(a * b)));
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
        }
    }
}
