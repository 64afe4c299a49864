//! Values of the hierarchy, recomputed on every refresh over the fixed structure:
//! the filtered fine matrix, the smoothers, the smoothed prolongators and the Galerkin
//! coarse operators. Every loop is row-parallel with a fixed order within each row.

use super::{AmgParams, Level, Multigrid, NONE, Transfer, WEAK, cycle, norm_inf, safe_inverse};
use crate::linalg::block::{mul, sum_products};
use crate::linalg::bsr::{BlockMatrix, row_chunks};
use crate::linalg::sym::SymBlockMatrix;
use crate::math::{Mat3, Vec3};
use rayon::prelude::*;

/// Rows per parallel task.
const ROWS: usize = 128;

/// Recomputes every value for a new matrix of the same pattern (the smoothers damped by a
/// bound of `ρ` when `bound` is set, see [`smoother`]).
pub(super) fn refresh(mg: &mut Multigrid, a: &BlockMatrix, s: &[Mat3], bound: bool) {
    filter_fine(&mut mg.levels[0], &mut mg.fine_filter, a, s);
    let params = mg.params;
    for l in 0..mg.levels.len() {
        let (head, tail) = mg.levels.split_at_mut(l + 1);
        let lvl = &mut head[l];
        if l > 0 {
            lvl.sym.set_values(&lvl.a);
        }
        smoother(lvl, &params, bound);
        if let Some(next) = tail.first_mut() {
            transfer(lvl, &mut next.a, params.prolongator_weight);
        }
    }
    cycle::factor_coarsest(mg);
}

/// [`Multigrid::refresh_fine`]: the finest level's filtered matrix and the inverses of its
/// diagonal blocks only; the smoother's damping is the last full refresh's.
///
/// Only the blocks `(i, j)` with a filter `S_i` or `S_j` changed since the last refresh are
/// recomputed: a block of `S A S + D_c (I - S)` depends on `A_ij`, `S_i` and `S_j` alone, and a
/// diagonal inverse on its own row's, so with `a` unchanged the result is the same bits as
/// recomputing every row. Filters are compared by their bits.
pub(super) fn refresh_fine(mg: &mut Multigrid, a: &BlockMatrix, s: &[Mat3]) {
    let fine = &mut mg.levels[0];
    if mg.fine_filter.len() == s.len() {
        let changed: Vec<bool> = s
            .par_iter()
            .zip(&mg.fine_filter)
            .with_min_len(1024)
            .map(|(p, q)| bits(p) != bits(q))
            .collect();
        filter_matrix(a, s, Some(&changed), &mut fine.a, &mut fine.sym);
        diagonal_inverses_of(fine, Some(&changed));
        mg.fine_filter.copy_from_slice(s);
    } else {
        filter_fine(fine, &mut mg.fine_filter, a, s);
        diagonal_inverses(fine);
    }
    if mg.levels.len() == 1 {
        cycle::factor_coarsest(mg);
    }
}

/// The finest level's filtered matrix for `a` and `s`, every row ([`filter_matrix`]), with `s`
/// kept in `kept` as the filter it was computed with ([`refresh_fine`] compares with it).
pub(super) fn filter_fine(fine: &mut Level, kept: &mut Vec<Mat3>, a: &BlockMatrix, s: &[Mat3]) {
    filter_matrix(a, s, None, &mut fine.a, &mut fine.sym);
    kept.clear();
    kept.extend_from_slice(s);
}

/// The bits of a block's entries.
fn bits(m: &Mat3) -> [u64; 9] {
    m.to_cols_array().map(f64::to_bits)
}

/// `out = S A S + D_c (I - S)` (see [`constrained_scale`]) block by block (`out` has the
/// pattern of `a`), and its upper triangle into `upper` in the same pass. With `changed`, only
/// the blocks `(i, j)` with `i` or `j` marked are written (the others are left as they are):
/// the rows of the marked particles, and their columns in their neighbours' rows.
fn filter_matrix(
    a: &BlockMatrix,
    s: &[Mat3],
    changed: Option<&[bool]>,
    out: &mut BlockMatrix,
    upper: &mut SymBlockMatrix,
) {
    // 0: identity, 1: zero, 2: general
    let kind: Vec<u8> = s
        .par_iter()
        .with_min_len(1024)
        .map(|m| {
            if *m == Mat3::IDENTITY {
                0
            } else if *m == Mat3::ZERO {
                1
            } else {
                2
            }
        })
        .collect();
    let ptr = out.row_ptr().to_vec();
    row_chunks(&mut out.values, &ptr, ROWS)
        .into_par_iter()
        .zip(upper.row_chunks_mut(ROWS))
        .for_each(|((rows, vals), (_, up))| {
            let base = ptr[rows.start] as usize;
            let mut at = 0;
            for i in rows {
                let (cols, r) = a.row(i);
                for (&j, k) in cols.iter().zip(r) {
                    let j = j as usize;
                    if let Some(c) = changed
                        && !c[i]
                        && !c[j]
                    {
                        // a block between two unchanged filters keeps its value (the row's
                        // blocks from its diagonal on are its upper-triangle entries)
                        at += (j >= i) as usize;
                        continue;
                    }
                    let m = a.values[k];
                    let mut f = match (kind[i], kind[j]) {
                        (0, 0) => m,
                        (1, _) | (_, 1) => Mat3::ZERO,
                        _ => s[i] * m * s[j],
                    };
                    // a pinned particle's row is the identity's, decoupled (left to the
                    // smoother, in no aggregate); a held one's constrained directions are
                    // scaled to its free ones
                    match kind[i] {
                        1 if i == j => f += Mat3::IDENTITY,
                        2 if i == j => f += (Mat3::IDENTITY - s[i]) * constrained_scale(&m),
                        _ => {}
                    }
                    vals[k - base] = f;
                    if j >= i {
                        up[at] = f;
                        at += 1;
                    }
                }
            }
        });
}

/// The scale `c` of a held particle's constrained directions in the finest level's
/// `Â = S A S + c (I - S)`: a tenth of the mean diagonal entry of its unfiltered block `A_ii`
/// (docs/MATH.md §12). A pinned particle's is 1: its row is decoupled, so `c` would change only
/// the smoother's power estimate. PCG's products and solution do not depend on `c`, only the
/// cycle does: with `c = 1` a held particle's constrained directions weigh 1 whatever its free
/// ones weigh (mass plus `h²` times stiffness, far from 1 for cloth), and the aggregates and
/// the smoothed prolongator that mix them approximate the free motion worse (the Cusick test
/// took 205 CG iterations per step against 137 with a tenth, BENCHMARKS.md, eighteenth
/// session).
fn constrained_scale(a_ii: &Mat3) -> f64 {
    let c = 0.1 * (a_ii.x_axis.x + a_ii.y_axis.y + a_ii.z_axis.z) / 3.0;
    if c > 0.0 && c.is_finite() { c } else { 1.0 }
}

/// Symmetric inverse of a diagonal block (the average of the inverse and its transpose, so
/// that the smoother is exactly symmetric).
fn sym_inverse(d: &Mat3) -> Mat3 {
    let inv = safe_inverse(d);
    0.5 * (inv + inv.transpose())
}

/// Block-Jacobi smoother of a level: `D⁻¹` and `ω = weight / ρ̄`, with the level's
/// upper-triangle copy of its matrix set (the estimate and the cycle multiply by it).
///
/// `ρ̄` estimates `ρ(D⁻¹A)`: the Rayleigh quotient after a few power steps (a lower bound
/// that converges fast; [`AmgParams::power_steps`]). Only when that fails (a matrix that is
/// not positive definite, or not finite) is the Gershgorin bound
/// `G = max_i Σ_j ‖D_i⁻¹ A_ij‖_∞ ≥ ρ` computed instead. `G` is never needed as a cap: the
/// Rayleigh quotient of a symmetric `A` and positive definite `D` is at most `ρ`. On cloth `G`
/// overestimates `ρ` by 1.8–1.9× on the finest level of hanging sheets, and by more on some
/// levels of a draped one, so damping by `G` smoothed far too weakly. With `bound` set, `G` is
/// used anyway: `ω ρ ≤ weight < 2` is then guaranteed, where a power estimate far below `ρ` (a
/// few very stiff contact rows, say) can leave `ω ρ ≥ 2` and the cycle indefinite.
pub(super) fn smoother(lvl: &mut Level, params: &AmgParams, bound: bool) {
    diagonal_inverses(lvl);
    let a = &lvl.a;
    // more steps on the small levels, where they cost nothing
    let steps = if a.n() > COARSE_ROWS {
        params.power_steps
    } else {
        params.power_steps.max(20)
    };
    let estimate = if bound {
        0.0
    } else {
        spectral_estimate(
            &lvl.sym,
            &lvl.dinv,
            steps,
            [&mut lvl.w, &mut lvl.x],
            &mut lvl.partial,
        )
    };
    let rho = if estimate > 0.0 && estimate.is_finite() {
        estimate
    } else {
        gershgorin(a, &lvl.dinv)
    };
    lvl.omega = if rho > 0.0 && rho.is_finite() {
        params.smoother_weight / rho
    } else {
        1.0
    };
}

/// The smoother's `D⁻¹`: the symmetric inverse of each diagonal block of the level's matrix.
fn diagonal_inverses(lvl: &mut Level) {
    diagonal_inverses_of(lvl, None);
}

/// [`diagonal_inverses`] of the rows `only` marks (all without it).
fn diagonal_inverses_of(lvl: &mut Level, only: Option<&[bool]>) {
    let a = &lvl.a;
    lvl.dinv
        .par_iter_mut()
        .enumerate()
        .with_min_len(ROWS)
        .filter(|(i, _)| only.is_none_or(|o| o[*i]))
        .for_each(|(i, dinv)| *dinv = sym_inverse(&a.values[a.diag_index(i)]));
}

/// `max_i Σ_j ‖D_i⁻¹ A_ij‖_∞`, an upper bound of `ρ(D⁻¹A)`.
fn gershgorin(a: &BlockMatrix, dinv: &[Mat3]) -> f64 {
    dinv.par_iter()
        .enumerate()
        .with_min_len(ROWS)
        .map(|(i, dinv)| {
            let (_, r) = a.row(i);
            a.values[r]
                .iter()
                .map(|m| norm_inf(&(*dinv * *m)))
                .sum::<f64>()
        })
        .reduce(|| 0.0, f64::max)
}

/// Levels with at most this many rows get at least 20 power steps.
const COARSE_ROWS: usize = 256;

/// Rayleigh quotient `xᵀAx / xᵀDx` (a lower bound of `ρ(D⁻¹A)`) after `steps` power steps
/// `x ← D⁻¹A x` from a fixed pseudo-random start (0 if it is not positive and finite).
///
/// One pass per step: each row's product `(A x)_i` gives both sums of the quotient (the
/// diagonal block `D_i` is in the row) and the next iterate, scaled by the previous quotient
/// so that its size stays put. The sums are chunked, so the result is the same on any thread
/// count. `x` and `y` are work vectors of the level's size.
fn spectral_estimate(
    a: &SymBlockMatrix,
    dinv: &[Mat3],
    steps: usize,
    [x, y]: [&mut Vec<Vec3>; 2],
    partial: &mut Vec<[f64; 2]>,
) -> f64 {
    for (i, xi) in x.iter_mut().enumerate() {
        let h = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let f = |k: u32| ((h >> k) & 0xffff) as f64 / 65535.0 - 0.5;
        *xi = Vec3::new(f(0), f(16), f(32));
    }
    let (mut estimate, mut scale) = (0.0, 1.0);
    for _ in 0..steps {
        let x_ = &**x;
        let [num, den] = a.mul_then(x_, y, partial, |i, ax| {
            let xi = x_[i];
            (
                scale * (dinv[i] * ax),
                [xi.dot(ax), xi.dot(*a.diag(i) * xi)],
            )
        });
        let q = num / den;
        if !(q > 0.0 && q.is_finite()) {
            return 0.0;
        }
        (estimate, scale) = (q, 1.0 / q);
        std::mem::swap(x, y);
    }
    estimate
}

/// Smoothed prolongator values, then `T = A P` and the coarse operator `Pᵀ T` into `coarse`.
pub(super) fn transfer(lvl: &mut Level, coarse: &mut BlockMatrix, weight: f64) {
    let a = &lvl.a;
    let t = lvl.transfer.as_mut().expect("transfer");
    let omega = prolongator(a, t, weight);
    let Transfer {
        p_ptr, p, p_own, ..
    } = t;
    row_chunks(p, p_ptr, ROWS)
        .into_par_iter()
        .for_each(|(rows, vals)| {
            let base = p_ptr[rows.start] as usize;
            for i in rows {
                for q in p_ptr[i] as usize..p_ptr[i + 1] as usize {
                    let mut m = -omega * vals[q - base];
                    if q as u32 == p_own[i] {
                        m += Mat3::IDENTITY;
                    }
                    vals[q - base] = m;
                }
            }
        });
    let Transfer { pt, pt_src, p, .. } = t;
    pt.par_iter_mut()
        .enumerate()
        .with_min_len(4 * ROWS)
        .for_each(|(e, m)| *m = p[pt_src[e] as usize].transpose());
    galerkin(a, t, coarse);
}

/// Fills `t.p` with `Y = D_F⁻¹ A^F P_tent` and returns `ω = weight / ρ̄(D_F⁻¹ A^F)`.
fn prolongator(a: &BlockMatrix, t: &mut Transfer, weight: f64) -> f64 {
    let Transfer {
        p_ptr, p, a_slot, ..
    } = t;
    let chunks = row_chunks(p, p_ptr, ROWS);
    let bound = chunks
        .into_par_iter()
        .map(|(rows, vals)| {
            let base = p_ptr[rows.start] as usize;
            let mut bound = 0.0f64;
            for i in rows {
                let (_, r) = a.row(i);
                let dk = a.diag_index(i);
                // D_F: the diagonal plus the weak blocks of the row (lumped)
                let mut d = Mat3::ZERO;
                for k in r.clone() {
                    if k == dk || a_slot[k] == WEAK {
                        d += a.values[k];
                    }
                }
                let dinv = sym_inverse(&d);
                let row = &mut vals[p_ptr[i] as usize - base..p_ptr[i + 1] as usize - base];
                row.iter_mut().for_each(|m| *m = Mat3::ZERO);
                let mut sum = 1.0;
                for k in r {
                    let slot = a_slot[k];
                    if slot == WEAK || slot == NONE {
                        continue;
                    }
                    let y = if k == dk {
                        Mat3::IDENTITY
                    } else {
                        mul(&dinv, &a.values[k])
                    };
                    if k != dk {
                        sum += norm_inf(&y);
                    }
                    row[slot as usize - p_ptr[i] as usize] += y;
                }
                bound = bound.max(sum);
            }
            bound
        })
        .reduce(|| 0.0, f64::max);
    if bound > 0.0 && bound.is_finite() {
        weight / bound
    } else {
        0.0
    }
}

/// `T = A P`, then `coarse = Pᵀ T` from the precomputed products of each block (one sum per
/// block, kept in registers): the upper triangle, and the lower one as its transpose (`Pᵀ A P`
/// is symmetric).
fn galerkin(a: &BlockMatrix, t: &mut Transfer, coarse: &mut BlockMatrix) {
    let Transfer {
        p, t: tv, t_terms, ..
    } = t;
    tv.par_iter_mut()
        .enumerate()
        .with_min_len(8 * ROWS)
        .for_each(|(o, m)| *m = sum_products(&a.values, p, t_terms.of(o)));
    let Transfer {
        pt, t: tv, c_terms, ..
    } = t;
    coarse
        .values
        .par_iter_mut()
        .enumerate()
        .with_min_len(4 * ROWS)
        .for_each(|(o, m)| *m = sum_products(pt, tv, c_terms.of(o)));
    // the lower triangle is the transpose of the upper one; diagonal blocks are symmetrized
    for &[k, kt] in &t.c_lower {
        let (k, kt) = (k as usize, kt as usize);
        let m = coarse.values[kt].transpose();
        coarse.values[k] = if k == kt {
            0.5 * (coarse.values[k] + m)
        } else {
            m
        };
    }
}
