//! Smoothed-aggregation algebraic multigrid (Vaněk, Mandel & Brezina 1996) on 3×3 blocks,
//! used as the PCG preconditioner [`super::pcg::Preconditioner::Multigrid`].
//!
//! It works on the matrix graph alone, so any cloth mesh will do:
//!
//! * **Filtered operator.** Level 0 is `Â = S A S + D_c (I - S)`: symmetric positive definite
//!   when `A` is, equal to `A` on the free subspace, with the constrained directions decoupled
//!   and scaled by a tenth of their particle's mean diagonal entry (`numeric::constrained_scale`;
//!   [`super::direct`] uses `c = 1`, which changes nothing there but made the cycle worse).
//! * **Aggregation** ([`setup`]). Block `(i, j)` is strong when
//!   `‖A_ij‖_F ≥ θ_l √(‖A_ii‖_F ‖A_jj‖_F)` (`θ_l = θ / 2^l`). Particles are grouped greedily
//!   into aggregates of a root and its strong neighbours; particles with no strong neighbour
//!   (pinned ones, for instance) stay out of every aggregate and are left to the smoother.
//! * **Prolongator.** The tentative prolongator has one 3×3 identity block per (particle,
//!   aggregate): the three translations are the near-null space. It is smoothed by one damped
//!   Jacobi step on the filtered matrix `A^F` (weak blocks dropped and lumped into the diagonal,
//!   so translations are kept): `P = (I - ω D_F⁻¹ A^F) P_tent`,
//!   `ω = `[`AmgParams::prolongator_weight`]` / ρ̄` with `ρ̄` a Gershgorin bound of
//!   `ρ(D_F⁻¹ A^F)`.
//! * **Coarse operators.** Galerkin, `A_c = Pᵀ A P` (its upper triangle, the lower one by
//!   transposition), recursively until at most [`AmgParams::coarse_size`] particles remain; the
//!   coarsest is solved by dense Cholesky. Every level also keeps its matrix's upper triangle
//!   ([`SymBlockMatrix`]) for the cycle's products.
//! * **Cycle** ([`cycle`]). A W-cycle on large levels and a V-cycle below, with the same number
//!   of damped block-Jacobi sweeps before and after the coarse correction, so it is a symmetric
//!   positive definite operator and CG stays valid.
//! * **Couplings outside the pattern** ([`couplings`]). When PCG's matrix is `P + C` with the
//!   hierarchy built from `P` ([`super::split`]), the cycle's products on every level but the
//!   coarsest add `C`, carried down by Galerkin products ([`Multigrid::set_couplings`]).
//!
//! The structure (aggregates, patterns of `P`, `A P` and `A_c`, and the position of every
//! product term) is built once per matrix pattern. With the default strength threshold 0 it
//! depends on the pattern and the pins only, not on the values at the time it is built, so a
//! run resumed from a saved state rebuilds exactly the hierarchy the uninterrupted run had and
//! ends with the same bits; every call to
//! [`Multigrid::refresh`] then only recomputes values ([`numeric`]). All loops are row-parallel
//! with a fixed order within a row, and the reductions are maxima or sums over chunks fixed by
//! the size, added in order, so the result is the same bits on any number of threads.

mod couplings;
mod cycle;
mod numeric;
mod setup;

use super::bsr::BlockMatrix;
use super::split::Coupling;
use super::sym::SymBlockMatrix;
use crate::math::{Mat3, Vec3};

/// Tunables of the hierarchy and the cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmgParams {
    /// Strength-of-connection threshold `θ` on the finest level (halved on each coarser one).
    pub strength: f64,
    /// Stop coarsening at this many block rows (then solve densely).
    pub coarse_size: usize,
    /// Maximum number of levels, the finest included.
    pub max_levels: usize,
    /// Block-Jacobi sweeps before, and again after, the coarse correction.
    pub sweeps: usize,
    /// Cycles of the coarser levels per coarse correction (`γ`): 1 for a V-cycle, 2 for a
    /// W-cycle; only on levels whose coarser level has at least
    /// [`AmgParams::repeat_rows`] rows (a V-cycle below).
    pub coarse_cycles: usize,
    /// Smallest coarse level that is visited `coarse_cycles` times per correction.
    pub repeat_rows: usize,
    /// Smoother damping `ω = smoother_weight / ρ̄`, `ρ̄` an estimate of `ρ(D⁻¹A)` (see
    /// [`AmgParams::power_steps`]); `ω ρ` must stay below 2 for the cycle to be positive
    /// definite.
    pub smoother_weight: f64,
    /// Power steps estimating `ρ(D⁻¹A)` on each level at every full refresh (at least 20 on
    /// small levels). The estimate is a lower bound; 6 steps reached 0.97–0.99 of `ρ` on the
    /// finest level of the hanging and draped 64² and 128² sheets, so `ω ρ` stays near
    /// `smoother_weight`. With 4 the CG iterations per step of the hanging 64² and 128² cloths
    /// were the same (18.4 and 16.9 over 30 steps) for a third less of the estimate's cost.
    pub power_steps: usize,
    /// Prolongator damping `ω = prolongator_weight / ρ̄(D_F⁻¹A^F)`.
    pub prolongator_weight: f64,
}

impl Default for AmgParams {
    fn default() -> Self {
        AmgParams {
            strength: 0.0,
            coarse_size: 48,
            max_levels: 12,
            sweeps: 1,
            // a W-cycle: on the hanging 64² and 128² cloths it takes 15.0 and 15.9 CG
            // iterations per step where the V-cycle took 18.4 and 20.6. A second visit of the
            // first coarse level costs 15 % more per cycle at 128² (2783 coarse rows), which
            // pays, but 49 % at 64² (704 rows, two threads), where small loops cost more than
            // their work, which does not.
            coarse_cycles: 2,
            repeat_rows: 1024,
            // ω ρ = 1.5 with the estimated ρ: 24.6 → 18.5 CG iterations per step on the
            // hanging 64² cloth and 94 → 23 on the draped one against ω = 1.7 / G (ω ρ ≈ 0.9)
            smoother_weight: 1.5,
            power_steps: 4,
            // the prolongator still damps by a Gershgorin bound, about 1.8 ρ on cloth, so this
            // is the textbook ω ρ = 4/3 (1.8 gave 20.7 CG per step on the hanging 64² cloth,
            // 2.4 gives 19.1, with the smoother weight at 1.4)
            prolongator_weight: 2.4,
        }
    }
}

/// Interpolation from level `l + 1` to level `l`, with what is needed to refresh its values
/// and the Galerkin product.
#[derive(Clone, Debug, Default)]
struct Transfer {
    /// Aggregate of each fine particle ([`NONE`] if left out).
    agg: Vec<u32>,
    /// `P` in block CSR (fine rows, coarse columns).
    p_ptr: Vec<u32>,
    p_col: Vec<u32>,
    p: Vec<Mat3>,
    /// Per fine row, the position in `p` of its own aggregate's column ([`NONE`] if left out).
    p_own: Vec<u32>,
    /// `Pᵀ` by coarse row: the fine row, the position in `p` of each entry and (refreshed
    /// with `p`) its transposed block, stored in this order so that the restriction and the
    /// Galerkin product stream it.
    pt_ptr: Vec<u32>,
    pt_row: Vec<u32>,
    pt_src: Vec<u32>,
    pt: Vec<Mat3>,
    /// Per block of the fine matrix: position in `p` of the slot that block `(i, j)` of `A^F`
    /// feeds (the column `agg(j)` of row `i`), or [`WEAK`].
    a_slot: Vec<u32>,
    /// `T = A P` in block CSR (fine rows, coarse columns); per block of `T`, its products
    /// `A_ik P_kJ` as positions in `A`'s and `P`'s values, in increasing `k`.
    t_ptr: Vec<u32>,
    t: Vec<Mat3>,
    t_terms: Terms,
    /// Per block of the coarse matrix's upper triangle (`J ≥ I`), its products `P_iIᵀ T_iJ` as
    /// positions in `pt` and `t`, in increasing `i` (none for the lower triangle).
    c_terms: Terms,
    /// Each block of the coarse matrix's lower triangle and the position of its transpose
    /// (itself for a diagonal block, which is symmetrized), set after the upper triangle.
    c_lower: Vec<[u32; 2]>,
}

/// The products that make up each block of a matrix product, block by block: block `o` is
/// `Σ left[l] right[r]` over `[l, r]` in `list[ptr[o]..ptr[o + 1]]`, added in that order.
#[derive(Clone, Debug, Default)]
struct Terms {
    ptr: Vec<u32>,
    list: Vec<[u32; 2]>,
}

impl Terms {
    /// From the products in loop order and the block each adds to (a stable counting sort,
    /// so each block keeps its products in loop order).
    fn by_block(blocks: usize, target: &[u32], terms: &[[u32; 2]]) -> Self {
        let mut ptr = vec![0u32; blocks + 1];
        for &o in target {
            ptr[o as usize + 1] += 1;
        }
        for o in 0..blocks {
            ptr[o + 1] += ptr[o];
        }
        let mut fill = ptr[..blocks].to_vec();
        let mut list = vec![[0u32; 2]; terms.len()];
        for (&o, &t) in target.iter().zip(terms) {
            list[fill[o as usize] as usize] = t;
            fill[o as usize] += 1;
        }
        Terms { ptr, list }
    }

    /// The products of block `o`.
    fn of(&self, o: usize) -> &[[u32; 2]] {
        &self.list[self.ptr[o] as usize..self.ptr[o + 1] as usize]
    }
}

/// Marks a weak block in [`Transfer::a_slot`].
const WEAK: u32 = u32::MAX;
/// Marks "no aggregate / no slot".
const NONE: u32 = u32::MAX - 1;

/// One level of the hierarchy.
#[derive(Clone, Debug)]
struct Level {
    a: BlockMatrix,
    /// The upper triangle of `a`, for the cycle's products (half the bytes).
    sym: SymBlockMatrix,
    /// Inverse diagonal blocks and damping of the smoother.
    dinv: Vec<Mat3>,
    omega: f64,
    /// To the next coarser level; `None` on the coarsest.
    transfer: Option<Transfer>,
    /// Cycle vectors: right-hand side, iterate, work, and the previous cycles' sum on a
    /// coarse level visited more than once.
    b: Vec<Vec3>,
    x: Vec<Vec3>,
    w: Vec<Vec3>,
    y: Vec<Vec3>,
    /// Chunk sums of the products.
    partial: Vec<[f64; 2]>,
}

impl Level {
    fn new(a: BlockMatrix) -> Self {
        let n = a.n();
        Level {
            sym: SymBlockMatrix::from_pattern(&a),
            a,
            dinv: vec![Mat3::IDENTITY; n],
            omega: 1.0,
            transfer: None,
            b: vec![Vec3::ZERO; n],
            x: vec![Vec3::ZERO; n],
            w: vec![Vec3::ZERO; n],
            y: vec![Vec3::ZERO; n],
            partial: Vec::new(),
        }
    }
}

/// Dense Cholesky factor of the coarsest matrix (`L`, row-major lower triangle), or `None`
/// when it is not numerically positive definite (then the coarsest level is only smoothed).
#[derive(Clone, Debug, Default)]
struct CoarseSolver {
    dim: usize,
    l: Option<Vec<f64>>,
}

/// Seconds spent in the last [`Multigrid::refresh`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SetupTimes {
    /// Building the structure (0 when the pattern was reused).
    pub structure: f64,
    /// Recomputing the values.
    pub values: f64,
}

/// The hierarchy and its work memory.
#[derive(Clone, Debug, Default)]
pub struct Multigrid {
    /// Tunables; changing them takes effect at the next structure build.
    pub params: AmgParams,
    levels: Vec<Level>,
    coarse: CoarseSolver,
    /// Timings of the last refresh.
    pub times: SetupTimes,
    /// Matrix and filter the structure is built from, when set ([`Multigrid::set_reference`]).
    reference: Option<(BlockMatrix, Vec<Mat3>)>,
    /// Chunk sums of [`Multigrid::apply`].
    partial: Vec<f64>,
    /// The couplings outside the pattern on each level but the coarsest, finest first
    /// ([`Multigrid::set_couplings`]).
    couplings: Vec<couplings::Rows>,
    /// The filter the finest level's values were last computed with, so that
    /// [`Multigrid::refresh_fine`] recomputes only the rows a changed filter reaches.
    fine_filter: Vec<Mat3>,
}

impl Multigrid {
    /// Updates the hierarchy for the matrix `a` and filter `s` (see [`super::pcg`]): the
    /// structure is rebuilt when the pattern of `a` changed (or on the first call), the values
    /// always.
    pub fn refresh(&mut self, a: &BlockMatrix, s: &[Mat3]) {
        self.refresh_damped(a, s, false);
    }

    /// [`Multigrid::refresh`] with every smoother damped by the Gershgorin bound of
    /// `ρ(D⁻¹A)` instead of the power estimate, which guarantees `ω ρ < 2` on every level and
    /// so a positive definite cycle for a symmetric positive definite `a`, at the price of
    /// weaker smoothing. For a solve whose preconditioner turned out indefinite.
    pub fn refresh_bounded(&mut self, a: &BlockMatrix, s: &[Mat3]) {
        self.refresh_damped(a, s, true);
    }

    /// Refreshes the finest level only, for the matrix `a` under a new filter `s`: its filtered
    /// matrix and its smoother's block diagonal are recomputed; the smoother's damping, the
    /// prolongators and the coarse levels are kept as the last refresh left them. For the
    /// obstacle active set's later rounds, where only a few contacts' filters change: the
    /// cycle's coarse correction is then that of the earlier filter, a slightly worse
    /// approximation, but the cycle stays symmetric positive definite (a convergent smoother
    /// with any symmetric positive definite coarse operator; docs/MATH.md §14), and the
    /// products of PCG use the new filtered matrix exactly. The damping `ω = weight / ρ̄` is
    /// kept because `ρ(D⁻¹Â)` hardly moves when a few filters change (spin-290's later
    /// rounds: the power estimate moved by 1e-4 relative, for 19–24 ms of products each);
    /// should it grow past `2 / ω` the cycle is indefinite, which PCG detects and answers with
    /// [`Multigrid::refresh_bounded`]. A full [`Multigrid::refresh`] when `a`'s pattern is not
    /// the hierarchy's.
    ///
    /// The result depends on what the kept levels were refreshed from, so a caller that needs
    /// the same bits after a resume calls it only after a full refresh of the same solve
    /// sequence (see `step::solve`).
    ///
    /// `a` must hold the values the last refresh (full or of the finest level) was given:
    /// only the block rows of particles whose filter changed since, and of their neighbours,
    /// are recomputed (the same bits as recomputing every row).
    pub fn refresh_fine(&mut self, a: &BlockMatrix, s: &[Mat3]) {
        if self.levels.first().is_none_or(|l| !l.a.same_pattern(a)) {
            self.refresh(a, s);
            return;
        }
        let t0 = std::time::Instant::now();
        numeric::refresh_fine(self, a, s);
        self.times.structure = 0.0;
        self.times.values = t0.elapsed().as_secs_f64();
    }

    /// [`Multigrid::refresh`], the smoothers damped by a bound of `ρ` when `bound` is set.
    fn refresh_damped(&mut self, a: &BlockMatrix, s: &[Mat3], bound: bool) {
        let t0 = std::time::Instant::now();
        let rebuild = self.levels.first().is_none_or(|l| !l.a.same_pattern(a));
        if rebuild {
            match self.reference.take() {
                Some((r, rs)) if r.same_pattern(a) => {
                    self.build(&r, &rs, bound);
                    numeric::refresh(self, a, s, bound);
                    self.reference = Some((r, rs));
                }
                other => {
                    self.reference = other;
                    self.build(a, s, bound);
                }
            }
            self.times.structure = t0.elapsed().as_secs_f64();
            self.times.values = 0.0;
        } else {
            numeric::refresh(self, a, s, bound);
            self.times.structure = 0.0;
            self.times.values = t0.elapsed().as_secs_f64();
        }
    }

    /// Whether a refresh for `a` would build the structure from `a`'s own values (no structure
    /// for its pattern yet, and no reference with that pattern): then postponing the refresh
    /// would change the hierarchy.
    pub fn builds_from(&self, a: &BlockMatrix) -> bool {
        self.levels.first().is_none_or(|l| !l.a.same_pattern(a))
            && self
                .reference
                .as_ref()
                .is_none_or(|(r, _)| !r.same_pattern(a))
    }

    /// Forgets the structure: the next refresh rebuilds it from the values it is given.
    pub fn reset(&mut self) {
        self.levels.clear();
    }

    /// Builds the structure (strength of connection, aggregates, patterns) from `a` filtered
    /// by `s` whenever the matrix to refresh has `a`'s pattern, instead of from that matrix's
    /// own values. With a reference fixed by the problem (the system at its initial state, say)
    /// and a positive [`AmgParams::strength`], the aggregates follow the strong couplings and
    /// still do not depend on the step at which the structure happens to be built, so a resumed
    /// run rebuilds the same hierarchy.
    pub fn set_reference(&mut self, a: BlockMatrix, s: Vec<Mat3>) {
        self.reference = Some((a, s));
        self.levels.clear();
    }

    /// Whether a reference is set.
    pub fn has_reference(&self) -> bool {
        self.reference.is_some()
    }

    /// Makes the cycle's products those of `P + C` (`P` the matrix of the last refresh, `C`
    /// the couplings outside its pattern, filtered by `s`, the filter of that refresh) on every
    /// level but the coarsest, `C` carried down by Galerkin products ([`couplings`],
    /// docs/MATH.md §12); `None` removes them. Call after each refresh: the coarse levels'
    /// couplings depend on the prolongators.
    pub fn set_couplings(&mut self, c: Option<&Coupling>, s: &[Mat3]) {
        self.couplings.clear();
        let (Some(c), Some(last)) = (c, self.levels.len().checked_sub(1)) else {
            return;
        };
        // every level but the coarsest, which keeps the factor of its matrix alone
        if last == 0 {
            return;
        }
        self.couplings.push(couplings::Rows::fine(c, s));
        for l in 1..last {
            let t = self.levels[l - 1].transfer.as_ref().expect("a transfer");
            let coarse = self.couplings[l - 1].galerkin(t, self.levels[l].a.n());
            self.couplings.push(coarse);
        }
    }

    /// `out = S V(r)`, one V-cycle applied to `r` (which should already be filtered), then
    /// filtered; returns `rᵀ out` from the same pass (what PCG needs next). Call
    /// [`Multigrid::refresh`] first.
    pub fn apply(&mut self, s: &[Mat3], r: &[Vec3], out: &mut [Vec3]) -> f64 {
        cycle::apply(self, s, r, out)
    }

    /// `y = Â x` with the finest level's filtered matrix `Â = S A S + D_c (I - S)` (see the
    /// module docs); returns `xᵀ y`. For `x` in the free subspace (`S x = x`) this is `S A x`,
    /// the product PCG needs, at about half the bytes of [`BlockMatrix::mul_vec`]. Call
    /// [`Multigrid::refresh`] first; the filter is the one given there.
    pub fn filtered_product(&mut self, x: &[Vec3], y: &mut [Vec3]) -> f64 {
        let fine = &mut self.levels[0];
        let [sum, _] = fine
            .sym
            .mul_then(x, y, &mut fine.partial, |i, ax| (ax, [x[i].dot(ax), 0.0]));
        sum
    }

    /// Number of levels, the finest included.
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// Block rows per level, finest first.
    pub fn level_sizes(&self) -> Vec<usize> {
        self.levels.iter().map(|l| l.a.n()).collect()
    }

    /// Stored blocks per level (operator complexity is their sum over the finest's).
    pub fn level_blocks(&self) -> Vec<usize> {
        self.levels.iter().map(|l| l.a.nnz_blocks()).collect()
    }

    fn build(&mut self, a: &BlockMatrix, s: &[Mat3], bound: bool) {
        self.levels.clear();
        let mut fine = Level::new(a.clone());
        numeric::filter_fine(&mut fine, &mut self.fine_filter, a, s);
        self.levels.push(fine);
        loop {
            let l = self.levels.len() - 1;
            let n = self.levels[l].a.n();
            let lvl = &mut self.levels[l];
            if l > 0 {
                lvl.sym.set_values(&lvl.a);
            }
            numeric::smoother(lvl, &self.params, bound);
            if n <= self.params.coarse_size || l + 1 >= self.params.max_levels {
                break;
            }
            let theta = self.params.strength * 0.5f64.powi(l as i32);
            let Some((transfer, coarse)) = setup::transfer(&self.levels[l].a, theta) else {
                break;
            };
            let mut next = Level::new(coarse);
            let lvl = &mut self.levels[l];
            lvl.transfer = Some(transfer);
            numeric::transfer(lvl, &mut next.a, self.params.prolongator_weight);
            self.levels.push(next);
        }
        cycle::factor_coarsest(self);
    }
}

/// `max_r Σ_c |m_rc|`, the infinity norm.
#[inline]
fn norm_inf(m: &Mat3) -> f64 {
    let (a, b, c) = (m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
    (a + b + c).max_element()
}

/// Inverse of a diagonal block, or the identity scaled by its largest entry when singular.
#[inline]
fn safe_inverse(d: &Mat3) -> Mat3 {
    let inv = d.inverse();
    if inv.is_finite() {
        inv
    } else {
        let m = crate::math::max_abs(d);
        if m > 0.0 && m.is_finite() {
            Mat3::IDENTITY / m
        } else {
            Mat3::IDENTITY
        }
    }
}

#[cfg(test)]
mod tests;
