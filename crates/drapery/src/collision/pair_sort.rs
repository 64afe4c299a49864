//! Sorting lists of index pairs, the broad phase's output, by a least-significant-digit radix
//! sort.
//!
//! The traversals of [`super::bvh`] list their pairs in an order that depends on the tree and
//! sort them, so that what follows does not. At 290² a fail-safe step lists about 340 000 pairs,
//! and a comparison sort of them took about 5 ms of the step on two threads, this sort about
//! 2 ms on one (BENCHMARKS.md, thirty-fifth session). A pair `(p, q)` is the key `p · 2^b + q`
//! with `b` the bits of the largest `q`, and the keys are sorted in passes of [`DIGIT`] bits,
//! each a stable counting sort. The result is the same as [`slice::sort_unstable`]'s for any
//! list (equal pairs are interchangeable), so it changes no result.

use rayon::prelude::*;

/// Bits sorted per pass: 4 096 counters (32 KB), about the size of the first-level cache.
const DIGIT: u32 = 12;

/// Below this many pairs a comparison sort is as fast.
const SMALL: usize = 4096;

/// Sorts `pairs` in increasing order, `(p, q)` by `p` then `q`.
pub fn sort_pairs(pairs: &mut [(u32, u32)]) {
    if pairs.len() < SMALL {
        pairs.sort_unstable();
        return;
    }
    let (max_p, max_q) = pairs
        .iter()
        .fold((0u32, 0u32), |(a, b), &(p, q)| (a.max(p), b.max(q)));
    let bits = |m: u32| u32::BITS - m.leading_zeros();
    let (bq, total) = (bits(max_q), bits(max_p) + bits(max_q));
    let mut keys: Vec<u64> = pairs
        .par_iter()
        .with_min_len(SMALL)
        .map(|&(p, q)| ((p as u64) << bq) | q as u64)
        .collect();
    let mut spare = vec![0u64; keys.len()];
    let mut shift = 0;
    while shift < total {
        pass(&keys, &mut spare, shift);
        std::mem::swap(&mut keys, &mut spare);
        shift += DIGIT;
    }
    let low = (1u64 << bq) - 1;
    pairs
        .par_iter_mut()
        .zip(&keys)
        .with_min_len(SMALL)
        .for_each(|(pair, k)| *pair = ((k >> bq) as u32, (k & low) as u32));
}

/// One stable counting-sort pass of `keys` into `out` by the digit at `shift`.
fn pass(keys: &[u64], out: &mut [u64], shift: u32) {
    let mask = (1u64 << DIGIT) - 1;
    let digit = |k: u64| ((k >> shift) & mask) as usize;
    let mut at = vec![0usize; 1 << DIGIT];
    keys.iter().for_each(|&k| at[digit(k)] += 1);
    let mut sum = 0;
    for a in at.iter_mut() {
        (*a, sum) = (sum, sum + *a);
    }
    for &k in keys {
        let d = digit(k);
        out[at[d]] = k;
        at[d] += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Pairs with indices below `limit`, as many as `len`, repeats allowed.
    fn pairs(limit: u32, len: std::ops::Range<usize>) -> impl Strategy<Value = Vec<(u32, u32)>> {
        proptest::collection::vec((0..limit, 0..limit), len)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// The radix sort gives the comparison sort's order, for small and large indices,
        /// short lists (the comparison sort's path) and long ones, and repeated pairs.
        #[test]
        fn the_radix_sort_is_the_comparison_sort(
            small in pairs(300, 0..6000),
            wide in pairs(u32::MAX, SMALL..3 * SMALL),
            repeats in pairs(4, SMALL..2 * SMALL),
        ) {
            for list in [small, wide, repeats] {
                let mut want = list.clone();
                want.sort_unstable();
                let mut got = list;
                sort_pairs(&mut got);
                prop_assert_eq!(got, want);
            }
        }
    }

    #[test]
    fn extreme_indices_sort_in_one_piece() {
        // 64 bits of key: both indices at their largest
        let mut v: Vec<(u32, u32)> = (0..2 * SMALL as u32)
            .map(|i| (u32::MAX - i % 3, u32::MAX - i % 5))
            .chain([(0, 0), (0, u32::MAX), (u32::MAX, 0)])
            .collect();
        let mut want = v.clone();
        want.sort_unstable();
        sort_pairs(&mut v);
        assert_eq!(v, want);
    }
}
