//! Which block kernels run: the AVX forms (`block::avx`, `sym::avx`) when the CPU running the
//! program has AVX, the portable ones otherwise, chosen once at run time. A build for any
//! x86-64 CPU (a release binary, a Python wheel) thus uses AVX where it can. Both forms add in
//! the same order, so a run gives the same bits either way (the proptests beside the kernels
//! compare them on every CPU that has AVX).
//!
//! Setting the environment variable `DRAPERY_SIMD=off` before the first product forces the
//! portable kernels (to compare runs, or to rule the kernels out).

use std::sync::OnceLock;

/// Whether the AVX kernels run (decided at the first call).
#[inline]
pub fn avx() -> bool {
    static AVX: OnceLock<bool> = OnceLock::new();
    *AVX.get_or_init(|| {
        let wanted = std::env::var("DRAPERY_SIMD").map_or(true, |v| v != "off");
        wanted && cpu_has_avx()
    })
}

/// Whether this CPU has AVX.
pub fn cpu_has_avx() -> bool {
    #[cfg(target_arch = "x86_64")]
    return std::arch::is_x86_feature_detected!("avx");
    #[cfg(not(target_arch = "x86_64"))]
    false
}
