//! Vector kernels over `[Vec3]` that give the same bits whatever the thread count.
//!
//! Reductions split the input into fixed chunks of [`CHUNK`] items, reduce each chunk
//! sequentially (possibly on different threads) and add the chunk sums in order, so the
//! rounding never depends on how rayon schedules the work.

use crate::math::Vec3;
use rayon::prelude::*;

/// Items per chunk for reductions and parallel loops.
pub const CHUNK: usize = 2048;

/// `Σ aᵢ · bᵢ`, deterministic.
pub fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
    debug_assert_eq!(a.len(), b.len());
    if a.len() <= CHUNK {
        return a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum();
    }
    let partial: Vec<f64> = a
        .par_chunks(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .map(|(ca, cb)| ca.iter().zip(cb).map(|(x, y)| x.dot(*y)).sum::<f64>())
        .collect();
    partial.iter().sum()
}

/// Runs `f(first, chunk)` on the fixed chunks of [`CHUNK`] items of `y` (in parallel, `first`
/// the index of the chunk's first item) and returns the sum of the results, added in chunk
/// order: a fused loop-and-reduction that gives the same bits on any number of threads.
/// `partial` is scratch memory (resized as needed).
pub fn chunked_sum<T: Send>(
    y: &mut [T],
    partial: &mut Vec<f64>,
    f: impl Fn(usize, &mut [T]) -> f64 + Sync,
) -> f64 {
    // a Vec of () does not allocate
    let mut none = vec![(); y.len()];
    chunked_sum2(y, &mut none, partial, |first, a, _| f(first, a))
}

/// [`chunked_sum`] over the matching chunks of two slices of the same length.
pub fn chunked_sum2<A: Send, B: Send>(
    a: &mut [A],
    b: &mut [B],
    partial: &mut Vec<f64>,
    f: impl Fn(usize, &mut [A], &mut [B]) -> f64 + Sync,
) -> f64 {
    assert_eq!(a.len(), b.len());
    if a.len() <= CHUNK {
        return 0.0 + f(0, a, b);
    }
    partial.resize(a.len().div_ceil(CHUNK), 0.0);
    a.par_chunks_mut(CHUNK)
        .zip(b.par_chunks_mut(CHUNK))
        .zip(partial.par_iter_mut())
        .enumerate()
        .for_each(|(k, ((ca, cb), p))| *p = f(k * CHUNK, ca, cb));
    partial.iter().sum()
}

/// `‖a‖₂`.
pub fn norm(a: &[Vec3]) -> f64 {
    dot(a, a).sqrt()
}

/// `y += alpha x`.
pub fn axpy(alpha: f64, x: &[Vec3], y: &mut [Vec3]) {
    y.par_chunks_mut(CHUNK)
        .zip(x.par_chunks(CHUNK))
        .for_each(|(cy, cx)| {
            for (yi, xi) in cy.iter_mut().zip(cx) {
                *yi += alpha * *xi;
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dot_is_bitwise_identical_on_one_and_two_threads() {
        let n = 10 * CHUNK + 17;
        let a: Vec<Vec3> = (0..n)
            .map(|i| {
                Vec3::new(
                    (i as f64).sin(),
                    1.0 / (1.0 + i as f64),
                    (i as f64 * 0.37).cos(),
                )
            })
            .collect();
        let b: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new((i as f64 * 1.3).cos(), (i as f64).sqrt(), -0.5))
            .collect();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| dot(&a, &b));
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap()
            .install(|| dot(&a, &b));
        assert_eq!(one.to_bits(), two.to_bits());
        let naive: f64 = a.iter().zip(&b).map(|(x, y)| x.dot(*y)).sum();
        assert!((one - naive).abs() <= 1e-9 * naive.abs().max(1.0));
    }
}
