//! Deterministic, parallel sums of per-pair terms, for the forces that act along particle
//! pairs (springs, spring damping).
//!
//! A pair `s = (i, j)` contributes a vector `g_s` as `+g_s` to particle `i` and `-g_s` to
//! `j`, and a block `B_s` as `+B_s` to blocks `(i, i)` and `(j, j)` and `-B_s` to `(i, j)` and
//! `(j, i)`. The terms are first evaluated in parallel, one per pair; then every particle (and
//! every matrix block) gathers its own contributions in increasing pair order. No two tasks
//! write the same place, and each sum has a fixed order, so the result is the same bits on any
//! number of threads. The gather lists are built on first use and, for blocks, rebuilt when
//! the matrix pattern changes. [`PairSums::add_linearization`] takes a force's two vectors
//! (force and Jacobian product) and its block from one evaluation per pair: one term pass, one
//! gather over particles for both vectors and one over blocks.

use crate::linalg::BlockMatrix;
use crate::linalg::bsr::Pattern;
use crate::math::{Mat3, Vec3};
use rayon::prelude::*;
use std::sync::{Arc, Mutex, Weak};

/// Gather lists and term buffers of one set of pairs (empty until first used).
#[derive(Debug, Default)]
pub struct PairSums {
    state: Mutex<State>,
}

impl Clone for PairSums {
    /// A fresh cache: the lists are rebuilt on first use.
    fn clone(&self) -> Self {
        PairSums::default()
    }
}

/// Contributions to gather, CSR by target: entry `2 s` adds term `s`, `2 s + 1` subtracts it.
#[derive(Debug, Default)]
struct Lists {
    ptr: Vec<u32>,
    src: Vec<u32>,
}

impl Lists {
    /// Builds lists for `targets` places from `(place, entry)` in increasing entry order.
    fn build(targets: usize, items: impl Iterator<Item = (usize, u32)> + Clone) -> Self {
        let mut ptr = vec![0u32; targets + 1];
        for (t, _) in items.clone() {
            ptr[t + 1] += 1;
        }
        for t in 0..targets {
            ptr[t + 1] += ptr[t];
        }
        let mut fill: Vec<u32> = ptr[..targets].to_vec();
        let mut src = vec![0u32; ptr[targets] as usize];
        for (t, e) in items {
            src[fill[t] as usize] = e;
            fill[t] += 1;
        }
        Lists { ptr, src }
    }

    /// Place `t`'s sum of `±term(s)`, in increasing entry order.
    #[inline]
    fn gather<T>(&self, t: usize, term: impl Fn(usize) -> T, zero: T) -> T
    where
        T: Copy + std::ops::Add<Output = T> + std::ops::Sub<Output = T>,
    {
        let mut acc = zero;
        for &e in &self.src[self.ptr[t] as usize..self.ptr[t + 1] as usize] {
            let term = term((e >> 1) as usize);
            acc = if e & 1 == 0 { acc + term } else { acc - term };
        }
        acc
    }
}

#[derive(Debug, Default)]
struct State {
    /// Per particle, for `n` particles.
    particles: Option<(usize, Lists)>,
    /// Per stored block of a pattern.
    blocks: Option<(Weak<Pattern>, Lists)>,
    vectors: Vec<Vec3>,
    products: Vec<Vec3>,
    mats: Vec<Mat3>,
}

/// The two vector terms of a pair in [`PairSums::add_linearization`], summed in one gather
/// componentwise (each component on its own, so each sum has the bits of a separate gather).
#[derive(Clone, Copy, Debug, Default)]
struct VecPair(Vec3, Vec3);

impl std::ops::Add for VecPair {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        VecPair(self.0 + o.0, self.1 + o.1)
    }
}

impl std::ops::Sub for VecPair {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        VecPair(self.0 - o.0, self.1 - o.1)
    }
}

/// The per-particle lists for `n` particles, built if missing.
fn particle_lists<'a>(
    cache: &'a mut Option<(usize, Lists)>,
    i: &[u32],
    j: &[u32],
    n: usize,
) -> &'a Lists {
    if cache.as_ref().is_none_or(|(m, _)| *m != n) {
        let items = (0..i.len()).flat_map(|s| {
            [
                (i[s] as usize, 2 * s as u32),
                (j[s] as usize, 2 * s as u32 + 1),
            ]
        });
        *cache = Some((n, Lists::build(n, items)));
    }
    &cache.as_ref().expect("built").1
}

/// The per-block lists for `m`'s pattern, rebuilt when the pattern changed.
fn block_lists<'a>(
    cache: &'a mut Option<(Weak<Pattern>, Lists)>,
    i: &[u32],
    j: &[u32],
    m: &BlockMatrix,
) -> &'a Lists {
    let current = m.pattern();
    let stale = cache
        .as_ref()
        .is_none_or(|(w, _)| !w.upgrade().is_some_and(|p| Arc::ptr_eq(&p, current)));
    if stale {
        let slot = |a: u32, b: u32| {
            m.find(a as usize, b as usize)
                .expect("pair block missing from the pattern")
        };
        // in increasing entry order, as `Lists::build` requires
        let mut items = Vec::with_capacity(4 * i.len());
        for s in 0..i.len() {
            let (a, b, e) = (i[s], j[s], 2 * s as u32);
            items.extend([
                (slot(a, a), e),
                (slot(b, b), e),
                (slot(a, b), e + 1),
                (slot(b, a), e + 1),
            ]);
        }
        let lists = Lists::build(m.nnz_blocks(), items.iter().copied());
        *cache = Some((Arc::downgrade(current), lists));
    }
    &cache.as_ref().expect("built").1
}

/// Evaluates `term` for every pair into `buf`, in parallel.
fn evaluate<T: Send + Copy + Default>(
    buf: &mut Vec<T>,
    pairs: usize,
    term: impl Fn(usize) -> T + Sync,
) {
    buf.resize(pairs, T::default());
    buf.par_iter_mut()
        .enumerate()
        .with_min_len(1024)
        .for_each(|(s, t)| *t = term(s));
}

/// `m += ` each block's gathered terms, row-parallel.
fn gather_blocks(lists: &Lists, terms: &[Mat3], m: &mut BlockMatrix) {
    m.for_each_row_mut(|_, base, _, vals| {
        for (k, v) in vals.iter_mut().enumerate() {
            *v += lists.gather(base + k, |s| terms[s], Mat3::ZERO);
        }
    });
}

impl PairSums {
    /// `out[i] += g_s`, `out[j] -= g_s` for every pair `s = (i[s], j[s])`, with
    /// `g_s = term(s)`.
    pub fn add_vectors<F>(&self, i: &[u32], j: &[u32], term: F, out: &mut [Vec3])
    where
        F: Fn(usize) -> Vec3 + Sync,
    {
        let mut guard = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let st = &mut *guard;
        evaluate(&mut st.vectors, i.len(), term);
        let lists = particle_lists(&mut st.particles, i, j, out.len());
        let terms = &st.vectors;
        out.par_iter_mut()
            .enumerate()
            .with_min_len(512)
            .for_each(|(p, o)| *o += lists.gather(p, |s| terms[s], Vec3::ZERO));
    }

    /// Adds `B_s = term(s)` to blocks `(i, i)`, `(j, j)` and `-B_s` to `(i, j)`, `(j, i)` of
    /// `m` for every pair (all four blocks must be in the pattern).
    pub fn add_blocks<F>(&self, i: &[u32], j: &[u32], term: F, m: &mut BlockMatrix)
    where
        F: Fn(usize) -> Mat3 + Sync,
    {
        let mut guard = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let st = &mut *guard;
        evaluate(&mut st.mats, i.len(), term);
        let lists = block_lists(&mut st.blocks, i, j, m);
        gather_blocks(lists, &st.mats, m);
    }

    /// [`PairSums::add_vectors`] of `g_s` into `f` and of `p_s` into `out` (when given), and
    /// [`PairSums::add_blocks`] of `B_s` into `m`, from one call `term(s) = (g_s, p_s, B_s)`
    /// per pair: the same sums in the same order, so the same bits as the three calls.
    pub fn add_linearization<F>(
        &self,
        i: &[u32],
        j: &[u32],
        term: F,
        f: &mut [Vec3],
        out: Option<&mut [Vec3]>,
        m: &mut BlockMatrix,
    ) where
        F: Fn(usize) -> (Vec3, Vec3, Mat3) + Sync,
    {
        let mut guard = self.state.lock().unwrap_or_else(|e| e.into_inner());
        let st = &mut *guard;
        let pairs = i.len();
        let (g, p, mats) = (&mut st.vectors, &mut st.products, &mut st.mats);
        g.resize(pairs, Vec3::ZERO);
        mats.resize(pairs, Mat3::ZERO);
        let lists = particle_lists(&mut st.particles, i, j, f.len());
        match out {
            Some(out) => {
                p.resize(pairs, Vec3::ZERO);
                g.par_iter_mut()
                    .zip(p.par_iter_mut())
                    .zip(mats.par_iter_mut())
                    .enumerate()
                    .with_min_len(1024)
                    .for_each(|(s, ((gs, ps), bs))| (*gs, *ps, *bs) = term(s));
                let (g, p) = (&*g, &*p);
                f.par_iter_mut()
                    .zip(out.par_iter_mut())
                    .enumerate()
                    .with_min_len(512)
                    .for_each(|(q, (fq, oq))| {
                        let sum = lists.gather(q, |s| VecPair(g[s], p[s]), VecPair::default());
                        *fq += sum.0;
                        *oq += sum.1;
                    });
            }
            None => {
                g.par_iter_mut()
                    .zip(mats.par_iter_mut())
                    .enumerate()
                    .with_min_len(1024)
                    .for_each(|(s, (gs, bs))| (*gs, _, *bs) = term(s));
                let g = &*g;
                f.par_iter_mut()
                    .enumerate()
                    .with_min_len(512)
                    .for_each(|(q, fq)| *fq += lists.gather(q, |s| g[s], Vec3::ZERO));
            }
        }
        let lists = block_lists(&mut st.blocks, i, j, m);
        gather_blocks(lists, &st.mats, m);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Against the plain sequential scatter, on random pair lists (duplicates and both
        /// orientations included), on one and two threads; the fused sums against the
        /// separate ones.
        #[test]
        fn sums_match_the_sequential_scatter(
            pairs in prop::collection::vec((0u32..12, 0u32..12), 1..40),
            seed in 0.0..1.0f64,
        ) {
            let pairs: Vec<(u32, u32)> = pairs.into_iter().filter(|(a, b)| a != b).collect();
            prop_assume!(!pairs.is_empty());
            let (i, j): (Vec<u32>, Vec<u32>) = pairs.iter().copied().unzip();
            let g = |s: usize| Vec3::new((s as f64 + seed).sin(), seed * s as f64, 1.0 / (1.0 + s as f64));
            let b = |s: usize| Mat3::from_cols_array(&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]) * g(s).x
                + Mat3::from_diagonal(g(s));
            let n = 12;
            let mut f_ref = vec![Vec3::ZERO; n];
            let mut m_ref = BlockMatrix::from_pairs(n, &pairs);
            for s in 0..i.len() {
                let (a, c) = (i[s] as usize, j[s] as usize);
                f_ref[a] += g(s);
                f_ref[c] -= g(s);
                m_ref.add(a, a, b(s));
                m_ref.add(c, c, b(s));
                m_ref.add(a, c, -b(s));
                m_ref.add(c, a, -b(s));
            }
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                let sums = PairSums::default();
                let mut f = vec![Vec3::ZERO; n];
                let mut m = BlockMatrix::from_pairs(n, &pairs);
                pool.install(|| {
                    sums.add_vectors(&i, &j, g, &mut f);
                    sums.add_blocks(&i, &j, b, &mut m);
                });
                for p in 0..n {
                    prop_assert!((f[p] - f_ref[p]).abs().max_element() <= 1e-12);
                }
                for (x, y) in m.values.iter().zip(&m_ref.values) {
                    prop_assert!(crate::math::max_abs(&(*x - *y)) <= 1e-12);
                }
                // all three from one term: the bits of the separate sums
                let mut fl = vec![Vec3::ZERO; n];
                let mut ol = vec![Vec3::ZERO; n];
                let mut ml = BlockMatrix::from_pairs(n, &pairs);
                let mut o_ref = vec![Vec3::ZERO; n];
                pool.install(|| {
                    sums.add_vectors(&i, &j, |s| -2.0 * g(s), &mut o_ref);
                    let term = |s: usize| (g(s), -2.0 * g(s), b(s));
                    sums.add_linearization(&i, &j, term, &mut fl, Some(&mut ol), &mut ml);
                });
                prop_assert_eq!(&fl, &f);
                prop_assert_eq!(&ol, &o_ref);
                prop_assert!(ml.values == m.values);
                let mut fl = vec![Vec3::ZERO; n];
                pool.install(|| {
                    let term = |s: usize| (g(s), Vec3::ZERO, b(s));
                    sums.add_linearization(&i, &j, term, &mut fl, None, &mut ml);
                });
                prop_assert_eq!(&fl, &f);
            }
        }
    }

    #[test]
    fn a_new_pattern_rebuilds_the_block_lists() {
        let sums = PairSums::default();
        let (i, j) = (vec![0u32], vec![1u32]);
        let mut small = BlockMatrix::from_pairs(3, &[(0, 1)]);
        sums.add_blocks(&i, &j, |_| Mat3::IDENTITY, &mut small);
        let mut big = BlockMatrix::from_pairs(3, &[(0, 1), (1, 2), (0, 2)]);
        sums.add_blocks(&i, &j, |_| Mat3::IDENTITY, &mut big);
        assert_eq!(big.values[big.find(0, 1).unwrap()], -Mat3::IDENTITY);
        assert_eq!(big.values[big.find(1, 1).unwrap()], Mat3::IDENTITY);
        assert_eq!(big.values[big.find(1, 2).unwrap()], Mat3::ZERO);
        assert_eq!(big.values[big.find(2, 2).unwrap()], Mat3::ZERO);
    }
}
