//! The cycle and the dense Cholesky solve of the coarsest level.
//!
//! On a level with matrix `A`, right-hand side `b`: `ν` damped block-Jacobi sweeps from
//! `x = 0`, restriction of the residual `Pᵀ (b - A x)`, the coarse correction, `x += P x_c`,
//! and `ν` sweeps again. The coarse correction solves `A_c x_c = b_c` by `γ` cycles of the
//! coarser levels (`γ` = [`AmgParams::coarse_cycles`] on large enough levels, 1 otherwise;
//! 1 is a V-cycle, 2 a W-cycle), each from the residual the previous one left, or exactly on
//! the coarsest level. The Jacobi
//! sweep is self-adjoint in the `A` inner product, so the cycle is a symmetric operator; it is
//! positive definite because the damping keeps `ω ρ(D⁻¹A) < 2`, which makes every cycle a
//! convergent iteration, and `γ` steps of a convergent iteration with a symmetric positive
//! definite operator `B` give the symmetric positive definite `I - (I - B A)^γ` times `A⁻¹`.
//! Where there are couplings outside the pattern ([`super::couplings`]), a level's products
//! (residuals and sweeps) add them; its smoother and the levels below stay those of the
//! majorant, which keeps each level's cycle convergent (docs/MATH.md §12).

use super::couplings::Rows;
use super::{AmgParams, CoarseSolver, Level, Multigrid};
use crate::linalg::block::add_products;
use crate::linalg::vector::chunked_sum;
use crate::math::{Mat3, Vec3};
use rayon::prelude::*;

/// Rows per parallel task.
const ROWS: usize = 256;
/// Levels with fewer rows run on one thread: their loops are shorter than the cost of
/// handing work to another.
const SEQUENTIAL: usize = 256;

/// Minimum rows per task for a loop over `n` rows.
fn min_len(n: usize) -> usize {
    if n < SEQUENTIAL { usize::MAX } else { ROWS }
}

/// `out = S V(r)`; returns `rᵀ out` (a deterministic chunked sum).
pub(super) fn apply(mg: &mut Multigrid, s: &[Mat3], r: &[Vec3], out: &mut [Vec3]) -> f64 {
    let fine = &mut mg.levels[0];
    fine.b.copy_from_slice(r);
    cycle(&mut mg.levels, &mg.coarse, &mg.params, &mg.couplings);
    let x = &mg.levels[0].x;
    chunked_sum(out, &mut mg.partial, |first, out| {
        let mut acc = 0.0;
        for (k, o) in out.iter_mut().enumerate() {
            let i = first + k;
            *o = s[i] * x[i];
            acc += r[i].dot(*o);
        }
        acc
    })
}

/// One cycle from `levels[0]` down: reads `levels[0].b`, writes `levels[0].x`. `couplings`:
/// those of `levels[0]`, `levels[1]`, ... (as many as there are, possibly none), added to the
/// levels' products ([`super::couplings`]).
fn cycle(levels: &mut [Level], coarse: &CoarseSolver, params: &AmgParams, couplings: &[Rows]) {
    let sweeps = params.sweeps;
    let (own, below) = match couplings.split_first() {
        Some((c, rest)) => (Some(c), rest),
        None => (None, couplings),
    };
    let (lvl, rest) = levels.split_first_mut().expect("a level");
    // moved out for the duration of the cycle so that the level's vectors can be borrowed
    let Some(t) = lvl.transfer.take() else {
        if let Some(l) = &coarse.l {
            cholesky_solve(l, coarse.dim, &lvl.b, &mut lvl.x);
        } else {
            smooth(lvl, 2 * sweeps.max(1), own);
        }
        return;
    };
    let next = &mut rest[0];
    smooth(lvl, sweeps, own);
    // w = b - A x
    let (x, b) = (&lvl.x, &lvl.b);
    let rows = min_len(lvl.a.n());
    lvl.sym.mul_then(x, &mut lvl.w, &mut lvl.partial, |i, ax| {
        (b[i] - ax, [0.0; 2])
    });
    if let Some(c) = own {
        c.subtract_product(&lvl.x, &mut lvl.w);
    }
    // b_c = Pᵀ w
    let w = &lvl.w;
    next.b
        .par_iter_mut()
        .enumerate()
        .with_min_len(rows / 4)
        .for_each(|(c, bc)| {
            let e = t.pt_ptr[c] as usize..t.pt_ptr[c + 1] as usize;
            *bc = add_products(Vec3::ZERO, &t.pt[e.clone()], &t.pt_row[e], w);
        });
    cycle(rest, coarse, params, below);
    // more cycles from the residual each leaves (the coarsest level's solve is exact)
    let repeat = rest.len() > 1 && rest[0].a.n() >= params.repeat_rows;
    let gamma = if repeat {
        params.coarse_cycles.max(1)
    } else {
        1
    };
    for k in 1..gamma {
        // b_c ← b_c - A_c x_c: the residual of the sum so far (b_c holds the previous
        // residual and x_c the last correction); the sum is kept in y
        let c = &mut rest[0];
        let (x, b) = (&c.x, &c.b);
        c.sym
            .mul_then(x, &mut c.w, &mut c.partial, |i, ax| (b[i] - ax, [0.0; 2]));
        if let Some(cc) = below.first() {
            cc.subtract_product(&c.x, &mut c.w);
        }
        std::mem::swap(&mut c.b, &mut c.w);
        if k == 1 {
            std::mem::swap(&mut c.x, &mut c.y);
        } else {
            add_to(&mut c.y, &c.x);
        }
        cycle(rest, coarse, params, below);
    }
    if gamma > 1 {
        let c = &mut rest[0];
        add_to(&mut c.x, &c.y);
    }
    // x += P x_c
    let xc = &rest[0].x;
    lvl.x
        .par_iter_mut()
        .enumerate()
        .with_min_len(rows)
        .for_each(|(i, xi)| {
            let r = t.p_ptr[i] as usize..t.p_ptr[i + 1] as usize;
            *xi = add_products(*xi, &t.p[r.clone()], &t.p_col[r], xc);
        });
    lvl.transfer = Some(t);
    smooth_more(lvl, sweeps, own);
}

/// `x += y`.
fn add_to(x: &mut [Vec3], y: &[Vec3]) {
    x.par_iter_mut()
        .zip(y.par_iter())
        .with_min_len(min_len(y.len()))
        .for_each(|(x, y)| *x += *y);
}

/// `sweeps` damped block-Jacobi sweeps from `x = 0` (of the level's matrix plus `couplings`).
fn smooth(lvl: &mut Level, sweeps: usize, couplings: Option<&Rows>) {
    if sweeps == 0 {
        lvl.x.iter_mut().for_each(|v| *v = Vec3::ZERO);
        return;
    }
    let (omega, dinv, b) = (lvl.omega, &lvl.dinv, &lvl.b);
    lvl.x
        .par_iter_mut()
        .enumerate()
        .with_min_len(min_len(b.len()).max(1024))
        .for_each(|(i, xi)| *xi = omega * (dinv[i] * b[i]));
    smooth_more(lvl, sweeps - 1, couplings);
}

/// `sweeps` damped block-Jacobi sweeps `x ← x + ω D⁻¹ (b - A x)` from the current `x`, `A`
/// the level's matrix plus `couplings`.
fn smooth_more(lvl: &mut Level, sweeps: usize, couplings: Option<&Rows>) {
    for _ in 0..sweeps {
        let (x, b, dinv, omega) = (&lvl.x, &lvl.b, &lvl.dinv, lvl.omega);
        lvl.sym.mul_then(x, &mut lvl.w, &mut lvl.partial, |i, ax| {
            (x[i] + omega * (dinv[i] * (b[i] - ax)), [0.0; 2])
        });
        std::mem::swap(&mut lvl.x, &mut lvl.w);
        if let Some(c) = couplings {
            // `w` holds the sweep's starting point
            c.sweep_correction(&lvl.w, &mut lvl.x, &lvl.dinv, lvl.omega);
        }
    }
}

/// Factors the coarsest level's matrix densely (`None` if not positive definite).
pub(super) fn factor_coarsest(mg: &mut Multigrid) {
    let a = &mg.levels.last().expect("a level").a;
    let dim = 3 * a.n();
    let mut l = vec![0.0; dim * dim];
    for i in 0..a.n() {
        let (cols, r) = a.row(i);
        for (&j, m) in cols.iter().zip(&a.values[r]) {
            for p in 0..3 {
                for q in 0..3 {
                    l[(3 * i + p) * dim + 3 * j as usize + q] = m.col(q)[p];
                }
            }
        }
    }
    let ok = cholesky(&mut l, dim);
    mg.coarse = CoarseSolver {
        dim,
        l: ok.then_some(l),
    };
}

/// In-place dense Cholesky `A = L Lᵀ` on the lower triangle (row-major); false when a pivot
/// is not positive.
fn cholesky(a: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let d = a[j * n + j] - (0..j).map(|k| a[j * n + k] * a[j * n + k]).sum::<f64>();
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let s = a[i * n + j] - (0..j).map(|k| a[i * n + k] * a[j * n + k]).sum::<f64>();
            a[i * n + j] = s / d;
        }
    }
    true
}

/// Solves `L Lᵀ x = b`.
fn cholesky_solve(l: &[f64], n: usize, b: &[Vec3], x: &mut [Vec3]) {
    let mut y: Vec<f64> = b.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
    for i in 0..n {
        let row = &l[i * n..i * n + i];
        let s: f64 = row.iter().zip(&y[..i]).map(|(a, b)| a * b).sum();
        y[i] = (y[i] - s) / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = y[i];
        for k in i + 1..n {
            s -= l[k * n + i] * y[k];
        }
        y[i] = s / l[i * n + i];
    }
    for (i, v) in x.iter_mut().enumerate() {
        *v = Vec3::new(y[3 * i], y[3 * i + 1], y[3 * i + 2]);
    }
}
