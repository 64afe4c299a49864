//! Forces over N-particle stencils, summed by one deterministic parallel gather.
//!
//! A *stencil force* ([`StencilForce`]) acts on many small groups of particles, its stencils: a
//! spring's two ends, a triangle, the four particles of a hinge or of a contact. It writes only
//! what happens on one stencil: its energy, the forces on its particles and the 3×3 blocks of
//! `a ∂f/∂x + b ∂f/∂v` among them. Every stencil force is a [`Force`] through the gather here:
//!
//! 1. the local terms are evaluated in parallel, one per stencil, into buffers;
//! 2. every particle (for a vector) and every stored block of the matrix gathers its own
//!    contributions, in increasing stencil order (within a stencil, in local order), in
//!    parallel over particles and over block rows.
//!
//! No two tasks write the same place and every sum has a fixed order, so the result has the
//! same bits on any number of threads. The gather lists (by target, CSR) are built on first
//! use (a force whose stencils change needs a fresh [`Gather`]) and, for blocks, rebuilt when
//! the matrix pattern changes.
//!
//! A force's [`Shape`] says how its terms are stored: [`Full<N>`] keeps the `N` forces and
//! `N × N` blocks of every stencil (triangles, hinges, contacts); [`Pair`] is the `N = 2` case
//! of an antisymmetric pair term (springs, their damping), kept compactly: a pair `(i, j)`
//! stores one vector `g` and one block `B` and contributes `+g` to `i`, `-g` to `j`, `+B` to
//! blocks `(i, i)` and `(j, j)` and `-B` to `(i, j)` and `(j, i)`. Since `acc - g` and
//! `acc + (-g)` have the same bits, a pair sums exactly as its expanded `Full<2>` form would.
//!
//! How each target takes its contributions is the force's [`Accumulate`]: summed first and
//! then added, or added one by one (the bits of a serial loop over the stencils).

use super::{Force, Linearization, State};
use crate::linalg::BlockMatrix;
use crate::linalg::bsr::Pattern;
use crate::math::{Mat3, Vec3};
use rayon::prelude::*;
use std::ops::{Add, Sub};
use std::sync::{Arc, Mutex, Weak};

/// Stencils per task when the local terms are evaluated.
const STENCILS: usize = 1024;

/// Particles per task in the gather over particles.
const PARTICLES: usize = 512;

/// How a stencil's terms are stored and where they go.
///
/// Contributions are named by *entries*: `index << 1 | negate`, `index` into the flattened
/// terms of all stencils ([`Shape::flat_vectors`], [`Shape::flat_blocks`]) and `negate` set
/// when the term is subtracted. (Entries are `u32`: 2³¹ terms of 3×3 blocks would take 150 GB.)
pub trait Shape: Send + Sync + 'static {
    /// Particle indices of one stencil.
    type Particles: Copy + Send + Sync;
    /// The vector terms of one stencil (its forces, or a Jacobian product), as stored.
    type Vectors: Copy + Send + Sync;
    /// The Jacobian blocks of one stencil, as stored.
    type Blocks: Copy + Send + Sync;
    /// Vector terms of zero.
    const ZERO_VECTORS: Self::Vectors;
    /// Blocks of zero.
    const ZERO_BLOCKS: Self::Blocks;
    /// The vector terms of consecutive stencils as one slice.
    fn flat_vectors(v: &[Self::Vectors]) -> &[Vec3];
    /// The blocks of consecutive stencils as one slice.
    fn flat_blocks(b: &[Self::Blocks]) -> &[Mat3];
    /// Calls `to(particle, entry)` for each contribution of stencil `s` to a vector, in local
    /// order.
    fn vector_entries(s: usize, p: Self::Particles, to: impl FnMut(u32, u32));
    /// Calls `to(row, column, entry)` for each contribution of stencil `s` to the matrix, in
    /// local order.
    fn block_entries(s: usize, p: Self::Particles, to: impl FnMut(u32, u32, u32));
    /// Adds the particle pairs whose blocks the stencil writes.
    fn add_pattern(p: Self::Particles, pairs: &mut Vec<(u32, u32)>);
    /// The stencil's blocks times `w` (on its particles).
    fn product(blocks: &Self::Blocks, p: Self::Particles, w: &[Vec3]) -> Self::Vectors;
}

/// `N` particles, with all `N` vectors and `N × N` blocks stored: block `[a][b]` is
/// `∂f_a/∂x_b` (in the combination asked for). A particle may occur more than once.
#[derive(Clone, Copy, Debug)]
pub struct Full<const N: usize>;

impl<const N: usize> Shape for Full<N> {
    type Particles = [u32; N];
    type Vectors = [Vec3; N];
    type Blocks = [[Mat3; N]; N];
    const ZERO_VECTORS: [Vec3; N] = [Vec3::ZERO; N];
    const ZERO_BLOCKS: [[Mat3; N]; N] = [[Mat3::ZERO; N]; N];
    fn flat_vectors(v: &[[Vec3; N]]) -> &[Vec3] {
        v.as_flattened()
    }
    fn flat_blocks(b: &[[[Mat3; N]; N]]) -> &[Mat3] {
        b.as_flattened().as_flattened()
    }
    fn vector_entries(s: usize, p: [u32; N], mut to: impl FnMut(u32, u32)) {
        for (a, &pa) in p.iter().enumerate() {
            to(pa, ((s * N + a) as u32) << 1);
        }
    }
    fn block_entries(s: usize, p: [u32; N], mut to: impl FnMut(u32, u32, u32)) {
        for (a, &pa) in p.iter().enumerate() {
            for (b, &pb) in p.iter().enumerate() {
                to(pa, pb, (((s * N + a) * N + b) as u32) << 1);
            }
        }
    }
    fn add_pattern(p: [u32; N], pairs: &mut Vec<(u32, u32)>) {
        for a in 0..N {
            for b in a + 1..N {
                pairs.push((p[a], p[b]));
            }
        }
    }
    fn product(blocks: &[[Mat3; N]; N], p: [u32; N], w: &[Vec3]) -> [Vec3; N] {
        std::array::from_fn(|a| {
            let mut y = Vec3::ZERO;
            for (b, &pb) in p.iter().enumerate() {
                y += blocks[a][b] * w[pb as usize];
            }
            y
        })
    }
}

/// Two particles `(i, j)` with an antisymmetric term: the stored vector `g` is particle `i`'s
/// (`j` gets `-g`), the stored block `B` is block `(i, i)` (`(j, j)` is `B` too, `(i, j)` and
/// `(j, i)` are `-B`). Entries come in the order of `Full<2>`'s, so a pair sums exactly as
/// `[g, -g]` and `[[B, -B], [-B, B]]` would, even with `i = j`.
#[derive(Clone, Copy, Debug)]
pub struct Pair;

impl Shape for Pair {
    type Particles = [u32; 2];
    type Vectors = Vec3;
    type Blocks = Mat3;
    const ZERO_VECTORS: Vec3 = Vec3::ZERO;
    const ZERO_BLOCKS: Mat3 = Mat3::ZERO;
    fn flat_vectors(v: &[Vec3]) -> &[Vec3] {
        v
    }
    fn flat_blocks(b: &[Mat3]) -> &[Mat3] {
        b
    }
    fn vector_entries(s: usize, [i, j]: [u32; 2], mut to: impl FnMut(u32, u32)) {
        let e = (s as u32) << 1;
        to(i, e);
        to(j, e | 1);
    }
    fn block_entries(s: usize, [i, j]: [u32; 2], mut to: impl FnMut(u32, u32, u32)) {
        let e = (s as u32) << 1;
        to(i, i, e);
        to(i, j, e | 1);
        to(j, i, e | 1);
        to(j, j, e);
    }
    fn add_pattern([i, j]: [u32; 2], pairs: &mut Vec<(u32, u32)>) {
        pairs.push((i, j));
    }
    fn product(blocks: &Mat3, [i, j]: [u32; 2], w: &[Vec3]) -> Vec3 {
        *blocks * (w[i as usize] - w[j as usize])
    }
}

/// How a target (a particle's vector, a matrix block) takes its contributions. Both add them
/// in increasing stencil order, so both give the same bits on any number of threads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accumulate {
    /// Summed from zero, then the sum is added to the target: `t + (c₁ + c₂ + …)`.
    Sum,
    /// Added to the target one by one: `(t + c₁) + c₂ + …`, the bits of a serial loop that
    /// adds each stencil's terms in turn.
    Each,
}

/// Everything a Newton iteration asks of one stencil (see [`StencilForce::local`]).
#[derive(Clone, Copy, Debug)]
pub struct Local<S: Shape> {
    /// The forces on the stencil's particles.
    pub force: S::Vectors,
    /// `(a ∂f/∂x + b ∂f/∂v) w` with the linearization's `product` coefficients.
    pub product: S::Vectors,
    /// The blocks of `a ∂f/∂x + b ∂f/∂v` with the linearization's `matrix` coefficients.
    pub matrix: S::Blocks,
}

/// A stencil's particle indices, for force `F`.
pub type Particles<F> = <<F as StencilForce>::Shape as Shape>::Particles;
/// A stencil's vector terms, for force `F`.
pub type Vectors<F> = <<F as StencilForce>::Shape as Shape>::Vectors;
/// A stencil's blocks, for force `F`.
pub type Blocks<F> = <<F as StencilForce>::Shape as Shape>::Blocks;

/// A force that is a sum over stencils: it writes one stencil's terms, the gather sums them.
/// Every `StencilForce` is a [`Force`].
pub trait StencilForce: Send + Sync {
    /// How its terms are stored: [`Full`] or [`Pair`].
    type Shape: Shape;
    /// Short name, for reports.
    const NAME: &'static str;
    /// The force's gather lists and buffers.
    fn gather(&self) -> &Gather<Self::Shape>;
    /// Number of stencils.
    fn count(&self) -> usize;
    /// Particles of stencil `s`.
    fn particles(&self, s: usize) -> Particles<Self>;
    /// How each target takes its contributions.
    fn accumulate(&self) -> Accumulate {
        Accumulate::Each
    }
    /// Potential energy of stencil `s` (0 for forces with no potential).
    fn local_energy(&self, _s: usize, _t: f64, _x: &[Vec3]) -> f64 {
        0.0
    }
    /// Dissipation potential of stencil `s` (see [`Force::dissipation`]).
    fn local_dissipation(&self, _s: usize, _at: &State) -> f64 {
        0.0
    }
    /// Forces on the particles of stencil `s`.
    fn local_force(&self, s: usize, at: &State) -> Vectors<Self>;
    /// Whether `a ∂f/∂x + b ∂f/∂v` can be non-zero: when not, the matrix and the product are
    /// left alone.
    fn has_jacobian(&self, _a: f64, _b: f64) -> bool {
        true
    }
    /// Blocks of `a ∂f/∂x + b ∂f/∂v` of stencil `s` (the matrix form the force uses).
    fn local_jacobian(&self, s: usize, at: &State, a: f64, b: f64) -> Blocks<Self>;
    /// `(a ∂f/∂x + b ∂f/∂v) w` on stencil `s`: its blocks times `w` unless the force computes
    /// it otherwise.
    fn local_product(&self, s: usize, at: &State, a: f64, b: f64, w: &[Vec3]) -> Vectors<Self> {
        let blocks = self.local_jacobian(s, at, a, b);
        <Self::Shape as Shape>::product(&blocks, self.particles(s), w)
    }
    /// Force, product and matrix blocks of stencil `s` at `at` (those not asked for are not
    /// used): by default the three methods above; a force whose three share work overrides
    /// it, giving the same bits.
    fn local(
        &self,
        s: usize,
        at: &Linearization,
        product: bool,
        matrix: bool,
    ) -> Local<Self::Shape> {
        let state = at.state();
        let ((am, bm), (ap, bp)) = (at.matrix, at.product);
        Local {
            force: self.local_force(s, &state),
            product: if product {
                self.local_product(s, &state, ap, bp, at.w)
            } else {
                <Self::Shape as Shape>::ZERO_VECTORS
            },
            matrix: if matrix {
                self.local_jacobian(s, &state, am, bm)
            } else {
                <Self::Shape as Shape>::ZERO_BLOCKS
            },
        }
    }
}

impl<F: StencilForce> Force for F {
    fn name(&self) -> &'static str {
        F::NAME
    }
    fn energy(&self, t: f64, x: &[Vec3]) -> f64 {
        (0..self.count()).map(|s| self.local_energy(s, t, x)).sum()
    }
    fn dissipation(&self, at: &State) -> f64 {
        (0..self.count())
            .map(|s| self.local_dissipation(s, at))
            .sum()
    }
    fn add_force(&self, at: &State, f: &mut [Vec3]) {
        self.gather()
            .add_vectors(self, |s| self.local_force(s, at), f);
    }
    fn add_pattern(&self, pairs: &mut Vec<(u32, u32)>) {
        for s in 0..self.count() {
            F::Shape::add_pattern(self.particles(s), pairs);
        }
    }
    fn add_jacobian(&self, at: &State, a: f64, b: f64, m: &mut BlockMatrix) {
        if self.has_jacobian(a, b) {
            self.gather()
                .add_blocks(self, |s| self.local_jacobian(s, at, a, b), m);
        }
    }
    fn add_jacobian_product(&self, at: &State, a: f64, b: f64, w: &[Vec3], out: &mut [Vec3]) {
        if self.has_jacobian(a, b) {
            self.gather()
                .add_vectors(self, |s| self.local_product(s, at, a, b, w), out);
        }
    }
    /// One [`StencilForce::local`] per stencil, one gather over particles for the force and
    /// the product and one over blocks: the bits of the three separate calls.
    fn add_linearization(
        &self,
        at: &Linearization,
        f: &mut [Vec3],
        m: &mut BlockMatrix,
        out: &mut [Vec3],
    ) {
        let product = self.has_jacobian(at.product.0, at.product.1);
        let matrix = self.has_jacobian(at.matrix.0, at.matrix.1);
        let term = |s: usize| self.local(s, at, product, matrix);
        self.gather()
            .add_linearization(self, term, f, product.then_some(out), matrix.then_some(m));
    }
}

/// Contributions to gather, CSR by target, each an entry (see [`Shape`]).
#[derive(Debug, Default)]
struct Lists {
    ptr: Vec<u32>,
    src: Vec<u32>,
}

impl Lists {
    /// Builds lists for `targets` places from `(place, entry)`; each place keeps its entries
    /// in the order given.
    fn build(targets: usize, items: &[(u32, u32)]) -> Self {
        let mut ptr = vec![0u32; targets + 1];
        for &(t, _) in items {
            ptr[t as usize + 1] += 1;
        }
        for t in 0..targets {
            ptr[t + 1] += ptr[t];
        }
        let mut fill: Vec<u32> = ptr[..targets].to_vec();
        let mut src = vec![0u32; ptr[targets] as usize];
        for &(t, e) in items {
            src[fill[t as usize] as usize] = e;
            fill[t as usize] += 1;
        }
        Lists { ptr, src }
    }

    /// `init ± term(index)` over place `t`'s entries, in order.
    #[inline]
    fn fold<T>(&self, t: usize, init: T, term: impl Fn(usize) -> T) -> T
    where
        T: Copy + Add<Output = T> + Sub<Output = T>,
    {
        let mut acc = init;
        for &e in &self.src[self.ptr[t] as usize..self.ptr[t + 1] as usize] {
            let term = term((e >> 1) as usize);
            acc = if e & 1 == 0 { acc + term } else { acc - term };
        }
        acc
    }

    /// Adds place `t`'s contributions to `target` as `how` says.
    #[inline]
    fn accumulate<T>(
        &self,
        how: Accumulate,
        t: usize,
        target: &mut T,
        zero: T,
        term: impl Fn(usize) -> T,
    ) where
        T: Copy + Add<Output = T> + Sub<Output = T>,
    {
        *target = match how {
            Accumulate::Sum => *target + self.fold(t, zero, term),
            Accumulate::Each => self.fold(t, *target, term),
        };
    }
}

/// The two vectors of a linearization (force and product), gathered together componentwise:
/// each component has the bits of its own gather.
#[derive(Clone, Copy, Debug)]
struct VecPair(Vec3, Vec3);

impl Add for VecPair {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        VecPair(self.0 + o.0, self.1 + o.1)
    }
}

impl Sub for VecPair {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        VecPair(self.0 - o.0, self.1 - o.1)
    }
}

/// Gather lists and term buffers of one stencil force (empty until first used).
pub struct Gather<S: Shape> {
    cache: Mutex<Cache<S>>,
}

struct Cache<S: Shape> {
    /// Per particle, for `(particles, stencils)`.
    particles: Option<(usize, usize, Lists)>,
    /// Per stored block of a pattern, for a number of stencils.
    blocks: Option<(Weak<Pattern>, usize, Lists)>,
    vectors: Vec<S::Vectors>,
    products: Vec<S::Vectors>,
    mats: Vec<S::Blocks>,
}

impl<S: Shape> Default for Gather<S> {
    fn default() -> Self {
        Gather {
            cache: Mutex::new(Cache {
                particles: None,
                blocks: None,
                vectors: Vec::new(),
                products: Vec::new(),
                mats: Vec::new(),
            }),
        }
    }
}

impl<S: Shape> Clone for Gather<S> {
    /// A fresh cache: the lists are rebuilt on first use.
    fn clone(&self) -> Self {
        Gather::default()
    }
}

impl<S: Shape> std::fmt::Debug for Gather<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gather").finish_non_exhaustive()
    }
}

/// The per-particle lists of `force` for `n` particles, built if missing.
fn particle_lists<'a, F: StencilForce>(
    cache: &'a mut Option<(usize, usize, Lists)>,
    force: &F,
    n: usize,
) -> &'a Lists {
    let count = force.count();
    if cache
        .as_ref()
        .is_none_or(|(m, c, _)| (*m, *c) != (n, count))
    {
        let mut items = Vec::with_capacity(2 * count);
        for s in 0..count {
            F::Shape::vector_entries(s, force.particles(s), |p, e| items.push((p, e)));
        }
        *cache = Some((n, count, Lists::build(n, &items)));
    }
    &cache.as_ref().expect("built").2
}

/// The per-block lists of `force` for `m`'s pattern, rebuilt when the pattern changed.
fn block_lists<'a, F: StencilForce>(
    cache: &'a mut Option<(Weak<Pattern>, usize, Lists)>,
    force: &F,
    m: &BlockMatrix,
) -> &'a Lists {
    let (current, count) = (m.pattern(), force.count());
    let stale = cache.as_ref().is_none_or(|(w, c, _)| {
        *c != count || !w.upgrade().is_some_and(|p| Arc::ptr_eq(&p, current))
    });
    if stale {
        let mut items = Vec::with_capacity(4 * count);
        for s in 0..count {
            F::Shape::block_entries(s, force.particles(s), |a, b, e| {
                let slot = m
                    .find(a as usize, b as usize)
                    .expect("stencil block missing from the pattern");
                items.push((slot as u32, e));
            });
        }
        let lists = Lists::build(m.nnz_blocks(), &items);
        *cache = Some((Arc::downgrade(current), count, lists));
    }
    &cache.as_ref().expect("built").2
}

/// Evaluates `term` for every stencil into `buf`, in parallel.
fn evaluate<T: Copy + Send>(
    buf: &mut Vec<T>,
    count: usize,
    zero: T,
    term: impl Fn(usize) -> T + Sync,
) {
    buf.resize(count, zero);
    buf.par_iter_mut()
        .enumerate()
        .with_min_len(STENCILS)
        .for_each(|(s, t)| *t = term(s));
}

/// `m +=` each block's gathered terms, row-parallel.
fn gather_blocks(lists: &Lists, how: Accumulate, terms: &[Mat3], m: &mut BlockMatrix) {
    m.for_each_row_mut(|_, base, _, vals| {
        for (k, v) in vals.iter_mut().enumerate() {
            lists.accumulate(how, base + k, v, Mat3::ZERO, |e| terms[e]);
        }
    });
}

/// `out +=` each particle's gathered terms, in parallel.
fn gather_vectors(lists: &Lists, how: Accumulate, terms: &[Vec3], out: &mut [Vec3]) {
    out.par_iter_mut()
        .enumerate()
        .with_min_len(PARTICLES)
        .for_each(|(p, o)| lists.accumulate(how, p, o, Vec3::ZERO, |e| terms[e]));
}

/// A run of consecutive stencils' buffers (the optional ones empty when not asked for).
type Run<'a, S> = (
    usize,
    &'a mut [<S as Shape>::Vectors],
    &'a mut [<S as Shape>::Vectors],
    &'a mut [<S as Shape>::Blocks],
);

/// Splits the three buffers into runs of `STENCILS` stencils (empty buffers give empty runs).
fn runs<'a, S: Shape>(
    mut g: &'a mut [S::Vectors],
    mut p: &'a mut [S::Vectors],
    mut m: &'a mut [S::Blocks],
) -> Vec<Run<'a, S>> {
    let mut out = Vec::with_capacity(g.len().div_ceil(STENCILS));
    let mut first = 0;
    while !g.is_empty() {
        let k = g.len().min(STENCILS);
        let (g0, g1) = g.split_at_mut(k);
        let (p0, p1) = p.split_at_mut(k.min(p.len()));
        let (m0, m1) = m.split_at_mut(k.min(m.len()));
        out.push((first, g0, p0, m0));
        (g, p, m) = (g1, p1, m1);
        first += k;
    }
    out
}

impl<S: Shape> Gather<S> {
    /// `out +=` the vectors `term(s)` of every stencil of `force`.
    fn add_vectors<F>(&self, force: &F, term: impl Fn(usize) -> S::Vectors + Sync, out: &mut [Vec3])
    where
        F: StencilForce<Shape = S>,
    {
        let mut guard = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        let st = &mut *guard;
        evaluate(&mut st.vectors, force.count(), S::ZERO_VECTORS, term);
        let lists = particle_lists(&mut st.particles, force, out.len());
        gather_vectors(lists, force.accumulate(), S::flat_vectors(&st.vectors), out);
    }

    /// `m +=` the blocks `term(s)` of every stencil of `force` (all in `m`'s pattern).
    fn add_blocks<F>(
        &self,
        force: &F,
        term: impl Fn(usize) -> S::Blocks + Sync,
        m: &mut BlockMatrix,
    ) where
        F: StencilForce<Shape = S>,
    {
        let mut guard = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        let st = &mut *guard;
        evaluate(&mut st.mats, force.count(), S::ZERO_BLOCKS, term);
        let lists = block_lists(&mut st.blocks, force, m);
        gather_blocks(lists, force.accumulate(), S::flat_blocks(&st.mats), m);
    }

    /// [`Gather::add_vectors`] of the forces into `f` and of the products into `out` (when
    /// given), [`Gather::add_blocks`] of the matrix blocks into `m` (when given), from one
    /// `term(s)` per stencil: the same sums in the same order, so the bits of the three calls.
    fn add_linearization<F>(
        &self,
        force: &F,
        term: impl Fn(usize) -> Local<S> + Sync,
        f: &mut [Vec3],
        out: Option<&mut [Vec3]>,
        m: Option<&mut BlockMatrix>,
    ) where
        F: StencilForce<Shape = S>,
    {
        let mut guard = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        let st = &mut *guard;
        let (count, how) = (force.count(), force.accumulate());
        let (g, p, mats) = (&mut st.vectors, &mut st.products, &mut st.mats);
        g.resize(count, S::ZERO_VECTORS);
        p.resize(if out.is_some() { count } else { 0 }, S::ZERO_VECTORS);
        mats.resize(if m.is_some() { count } else { 0 }, S::ZERO_BLOCKS);
        runs::<S>(g, p, mats)
            .into_par_iter()
            .for_each(|(first, g, p, m)| {
                for (k, gs) in g.iter_mut().enumerate() {
                    let local = term(first + k);
                    *gs = local.force;
                    if let Some(ps) = p.get_mut(k) {
                        *ps = local.product;
                    }
                    if let Some(ms) = m.get_mut(k) {
                        *ms = local.matrix;
                    }
                }
            });
        let lists = particle_lists(&mut st.particles, force, f.len());
        let g = S::flat_vectors(&st.vectors);
        match out {
            Some(out) => {
                let p = S::flat_vectors(&st.products);
                f.par_iter_mut()
                    .zip(out.par_iter_mut())
                    .enumerate()
                    .with_min_len(PARTICLES)
                    .for_each(|(q, (fq, oq))| {
                        let mut both = VecPair(*fq, *oq);
                        let zero = VecPair(Vec3::ZERO, Vec3::ZERO);
                        lists.accumulate(how, q, &mut both, zero, |e| VecPair(g[e], p[e]));
                        (*fq, *oq) = (both.0, both.1);
                    });
            }
            None => gather_vectors(lists, how, g, f),
        }
        if let Some(m) = m {
            let lists = block_lists(&mut st.blocks, force, m);
            gather_blocks(lists, how, S::flat_blocks(&st.mats), m);
        }
    }
}

#[cfg(test)]
mod tests;
