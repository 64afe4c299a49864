//! The command's allocator: mimalloc, told to keep the memory a step frees for the next one.
//!
//! - With the system allocator, the large per-step arrays went back to the kernel and were
//!   faulted in again: about 50 000 page faults per spin-290 step (BENCHMARKS.md, twenty-third
//!   session). mimalloc reuses them.
//! - mimalloc still hands memory that stays free for a while (its option `purge_delay`, 1 s by
//!   default in mimalloc 3) back to the system. A spin-290 step frees and allocates the same
//!   large arrays about once a second, so a run of 60 steps still took 370 000–430 000 page
//!   faults and 5.6–8.0 s of system time. [`keep_freed_memory`] turns the purge off (BENCHMARKS.md,
//!   twenty-fifth session).
//!
//! The results are the same bits whatever the allocator. The library sets no allocator
//! (docs/ARCHITECTURE.md).

use std::ffi::{c_int, c_long};

#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

// mimalloc's C interface (linked by the `mimalloc` crate; include/mimalloc.h of mimalloc 3)
unsafe extern "C" {
    fn mi_version() -> c_int;
    #[cfg(test)]
    fn mi_option_get(option: c_int) -> c_long;
    fn mi_option_set_default(option: c_int, value: c_long);
}

/// `mi_option_purge_delay` in mimalloc 3's `mi_option_e`.
const PURGE_DELAY: c_int = 15;

/// The mimalloc major version whose option numbers [`PURGE_DELAY`] is taken from.
const MAJOR: c_int = 3;

/// Turns mimalloc's purging of free memory off (`purge_delay = -1`), unless the environment
/// set it (`MIMALLOC_PURGE_DELAY`) or the linked mimalloc is not version 3 (whose option
/// numbers are known). Call first thing in `main`.
pub fn keep_freed_memory() {
    // SAFETY: mimalloc's documented C functions, called with an option number of the linked
    // version, from the main thread before any other thread starts (mimalloc's options are not
    // thread safe).
    unsafe {
        if mi_version() / 10_000 == MAJOR {
            mi_option_set_default(PURGE_DELAY, -1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The option number is the purge delay's: its default is 1000 ms in mimalloc 3 (no other
    /// option of that version defaults to 1000), and afterwards it reads -1.
    #[test]
    fn the_purge_delay_is_the_option_turned_off() {
        if std::env::var_os("MIMALLOC_PURGE_DELAY").is_some() {
            return;
        }
        // SAFETY: as in `keep_freed_memory` (the test harness's other threads do not set
        // mimalloc options).
        let (version, before) = unsafe { (mi_version(), mi_option_get(PURGE_DELAY)) };
        assert_eq!(
            version / 10_000,
            MAJOR,
            "mimalloc {version}: check the option numbers"
        );
        assert_eq!(before, 1000);
        keep_freed_memory();
        // SAFETY: as above.
        assert_eq!(unsafe { mi_option_get(PURGE_DELAY) }, -1);
    }
}
