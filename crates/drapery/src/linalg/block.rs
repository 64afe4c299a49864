//! 3×3 block products of the multigrid's set-up (`A P`, `Pᵀ (A P)`, `D⁻¹ A`), with AVX when
//! the build targets a CPU that has it (see `.cargo/config.toml`), and glam's scalar code
//! otherwise. Both add in the same order, so they give the same bits.

use crate::math::Mat3;

#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
#[allow(unsafe_code)]
pub(crate) mod avx;

/// `acc += a b`.
#[inline]
pub(crate) fn add_mul(acc: &mut Mat3, a: &Mat3, b: &Mat3) {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    avx::add_mul(acc, a, b);
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    {
        *acc += *a * *b;
    }
}

/// `a b`.
#[inline]
pub(crate) fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut out = Mat3::ZERO;
    add_mul(&mut out, a, b);
    out
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
        fn products_have_the_scalar_bits(acc in mat(), a in mat(), b in mat()) {
            let mut got = acc;
            add_mul(&mut got, &a, &b);
            prop_assert_eq!(bits(&got), bits(&(acc + a * b)));
            prop_assert_eq!(bits(&mul(&a, &b)), bits(&(a * b)));
        }
    }
}
