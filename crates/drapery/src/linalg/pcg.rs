//! Baraff & Witkin's modified preconditioned conjugate gradient (docs/MATH.md §5, §11).
//!
//! Solves `A x = b` on the subspace left free by a per-particle filter `S_i`
//! (`I` for a free particle, `0` for a pinned one, `I - n nᵀ` for one held against a plane),
//! with the constrained part of `x` prescribed by `z`: the result satisfies
//! `(I - S_i) x_i = z_i` and `S (A x - b) ≈ 0`. The filter is applied to the residual and the
//! search direction, so constraints are met exactly, with no penalty stiffness.
//!
//! Convergence is declared when `‖S (b - A x)‖ ≤ tolerance · ‖S (b - A z)‖`.

use super::amg::Multigrid;
use super::bsr::BlockMatrix;
use super::split::Split;
use super::vector::{CHUNK, chunked_sum, chunked_sum2, dot};
use crate::math::{Mat3, Vec3};
use rayon::prelude::*;

/// The preconditioner `P⁻¹`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Preconditioner {
    /// None (plain CG).
    Identity,
    /// Inverse of the scalar diagonal.
    Jacobi,
    /// Inverse of each particle's 3×3 diagonal block.
    BlockJacobi,
    /// One V-cycle of smoothed-aggregation algebraic multigrid ([`super::amg`]) (default).
    #[default]
    Multigrid,
}

/// Stopping rule and preconditioner.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PcgSettings {
    /// Relative residual to reach.
    pub tolerance: f64,
    /// Iteration cap.
    pub max_iterations: usize,
    /// Preconditioner.
    pub preconditioner: Preconditioner,
    /// With the multigrid: set up only its finest level for this solve's filter
    /// ([`Multigrid::refresh_fine`]), keeping the coarse levels of the last setup. Only when
    /// that setup was for the same matrix `p` (another filter of it), as in the obstacle
    /// active set's later rounds.
    pub keep_coarse: bool,
}

/// Outcome of a solve.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveStats {
    /// Iterations performed.
    pub iterations: usize,
    /// Final `‖S (b - A x)‖ / ‖S (b - A z)‖` (0 when the right-hand side vanishes).
    pub relative_residual: f64,
    /// Whether the tolerance was met.
    pub converged: bool,
    /// Set when `cᵀ A c ≤ 0` was met: the filtered matrix is not positive definite.
    pub indefinite: bool,
    /// Set when `rᵀ P⁻¹ r ≤ 0` was met: the preconditioner is not positive definite (with the
    /// multigrid, also after its smoothers were damped by a bound, see `bounded_damping`).
    pub bad_preconditioner: bool,
    /// Set when the multigrid turned out not positive definite and the solve went on with its
    /// smoothers damped by an upper bound of `ρ(D⁻¹A)` ([`Multigrid::refresh_bounded`]).
    pub bounded_damping: bool,
    /// Times the preconditioner was set up (multigrid refreshes, the damped one included): 0
    /// when the initial guess already met the tolerance.
    pub setups: usize,
}

/// Reusable work vectors.
#[derive(Default, Debug, Clone)]
pub struct PcgScratch {
    r: Vec<Vec3>,
    c: Vec<Vec3>,
    q: Vec<Vec3>,
    s: Vec<Vec3>,
    /// Chunk sums of the fused reductions.
    partial: Vec<f64>,
    pinv: Vec<Mat3>,
    amg: Multigrid,
}

impl PcgScratch {
    /// The multigrid hierarchy (kept between solves; its structure is rebuilt when the
    /// matrix pattern changes).
    pub fn multigrid(&mut self) -> &mut Multigrid {
        &mut self.amg
    }
}

/// `out = P⁻¹ r` (filtered); returns `rᵀ out`.
fn precondition(
    amg: Option<&mut Multigrid>,
    pinv: &[Mat3],
    s: &[Mat3],
    r: &[Vec3],
    out: &mut [Vec3],
) -> f64 {
    if let Some(amg) = amg {
        return amg.apply(s, r, out);
    }
    out.par_iter_mut()
        .enumerate()
        .with_min_len(1024)
        .for_each(|(i, o)| *o = s[i] * (pinv[i] * r[i]));
    dot(r, out)
}

/// Solves the filtered system; `x` holds the initial guess on entry (its free part is used,
/// its constrained part replaced by `z`) and the solution on exit.
pub fn solve(
    a: &BlockMatrix,
    b: &[Vec3],
    s: &[Mat3],
    z: &[Vec3],
    x: &mut [Vec3],
    settings: &PcgSettings,
    w: &mut PcgScratch,
) -> SolveStats {
    solve_split(Split::whole(a), b, s, z, x, settings, w)
}

/// [`solve`] for `A = P + C` ([`Split`]), the preconditioner built from `P` alone (symmetric
/// positive definite, close to `A`: for instance `A` without the coupling blocks of a step's
/// contacts, so that the multigrid keeps its structure while the contacts change). With the
/// multigrid, the products read its half-size copy of the filtered `P` and add `C`'s rows.
pub fn solve_split(
    a: Split,
    b: &[Vec3],
    s: &[Mat3],
    z: &[Vec3],
    x: &mut [Vec3],
    settings: &PcgSettings,
    w: &mut PcgScratch,
) -> SolveStats {
    let p = a.p;
    let n = a.n();
    for v in [&mut w.r, &mut w.c, &mut w.q, &mut w.s] {
        v.resize(n, Vec3::ZERO);
    }
    let multigrid = settings.preconditioner == Preconditioner::Multigrid;
    // The preconditioner is set up only once an iteration is needed: an initial guess that
    // already meets the tolerance (the obstacle active set's last round, say, when it only
    // released contacts with tiny impulses) costs no multigrid refresh. Unless the refresh
    // would build the hierarchy's structure from `p`'s own values, which must not depend on
    // which solve happens to come first.
    let mut stats = SolveStats::default();
    let mut prepared = false;
    if multigrid && w.amg.builds_from(p) {
        prepare(p, s, settings, w, &mut stats);
        prepared = true;
    }
    // x = z + S x_guess
    x.par_iter_mut()
        .enumerate()
        .with_min_len(CHUNK)
        .for_each(|(i, xi)| *xi = z[i] + s[i] * *xi);
    // The reference residual, of the zero guess on the free part (`z` is zero but at the
    // constrained particles, so only the rows that reach one of them are multiplied), and the
    // guess's, from one pass over the matrix.
    a.mul_vec_both(z, x, &mut w.s, &mut w.q);
    filtered_residual(s, b, &w.s, &mut w.r);
    let r0 = dot(&w.r, &w.r).sqrt();
    if r0 == 0.0 || !r0.is_finite() {
        x.copy_from_slice(z);
        stats.relative_residual = if r0 == 0.0 { 0.0 } else { f64::NAN };
        stats.converged = r0 == 0.0;
        return stats;
    }
    filtered_residual(s, b, &w.q, &mut w.r);
    let target = settings.tolerance * r0;
    let mut rnorm = dot(&w.r, &w.r).sqrt();
    if rnorm <= target {
        stats.relative_residual = rnorm / r0;
        stats.converged = true;
        return stats;
    }
    if !prepared {
        prepare(p, s, settings, w, &mut stats);
    }
    let mut run = |w: &mut PcgScratch, stats: &mut SolveStats, rnorm: &mut f64| {
        iterate(a, s, x, settings, w, target, stats, rnorm)
    };
    run(w, &mut stats, &mut rnorm);
    if stats.bad_preconditioner && multigrid {
        // The cycle was not positive definite (a power estimate of ρ(D⁻¹A) far below ρ leaves
        // ω ρ ≥ 2): damp its smoothers by an upper bound of ρ instead, and restart the
        // conjugate directions from the current iterate.
        w.amg.refresh_bounded(p, s);
        stats.setups += 1;
        stats.bad_preconditioner = false;
        stats.bounded_damping = true;
        run(w, &mut stats, &mut rnorm);
    }
    stats.relative_residual = rnorm / r0;
    stats.converged = rnorm <= target && rnorm.is_finite();
    stats
}

/// `r = S (b - q)`, row by row.
fn filtered_residual(s: &[Mat3], b: &[Vec3], q: &[Vec3], r: &mut [Vec3]) {
    r.par_iter_mut()
        .enumerate()
        .with_min_len(CHUNK)
        .for_each(|(i, ri)| *ri = s[i] * (b[i] - q[i]));
}

/// Sets up the preconditioner for `p` filtered by `s`.
fn prepare(
    p: &BlockMatrix,
    s: &[Mat3],
    settings: &PcgSettings,
    w: &mut PcgScratch,
    stats: &mut SolveStats,
) {
    stats.setups += 1;
    if settings.preconditioner == Preconditioner::Multigrid {
        if settings.keep_coarse {
            w.amg.refresh_fine(p, s);
        } else {
            w.amg.refresh(p, s);
        }
        return;
    }
    w.pinv.resize(p.n(), Mat3::IDENTITY);
    w.pinv
        .par_iter_mut()
        .enumerate()
        .with_min_len(1024)
        .for_each(|(i, pi)| {
            let d = p.values[p.diag_index(i)];
            *pi = match settings.preconditioner {
                Preconditioner::Identity | Preconditioner::Multigrid => Mat3::IDENTITY,
                Preconditioner::Jacobi => Mat3::from_diagonal(Vec3::new(
                    1.0 / d.x_axis.x,
                    1.0 / d.y_axis.y,
                    1.0 / d.z_axis.z,
                )),
                Preconditioner::BlockJacobi => {
                    let inv = d.inverse();
                    if inv.is_finite() { inv } else { Mat3::IDENTITY }
                }
            };
        });
}

/// CG iterations from `x` (with `w.r` its filtered residual) until `‖r‖ ≤ target`, the
/// iteration cap, or a breakdown (recorded in `stats`); `rnorm` is `‖r‖`, kept up to date.
#[allow(clippy::too_many_arguments)]
fn iterate(
    a: Split,
    s: &[Mat3],
    x: &mut [Vec3],
    settings: &PcgSettings,
    w: &mut PcgScratch,
    target: f64,
    stats: &mut SolveStats,
    rnorm: &mut f64,
) {
    let multigrid = settings.preconditioner == Preconditioner::Multigrid;
    if multigrid {
        // the cycle's products add the couplings outside the multigrid's pattern
        w.amg.set_couplings(a.coupling, s);
    }
    let mut delta = precondition(multigrid.then_some(&mut w.amg), &w.pinv, s, &w.r, &mut w.c);
    while stats.iterations < settings.max_iterations {
        if *rnorm <= target {
            break;
        }
        // q = S A c and cᵀq in one pass
        let mut cq = if multigrid {
            // c is filtered, so S P c = P̂ c: the multigrid's copy, half the bytes
            w.amg.filtered_product(&w.c, &mut w.q)
        } else {
            let (c, p) = (&w.c, a.p);
            chunked_sum(&mut w.q, &mut w.partial, |first, q| {
                let mut acc = 0.0;
                for (k, qi) in q.iter_mut().enumerate() {
                    let i = first + k;
                    *qi = s[i] * p.row_product(i, c);
                    acc += c[i].dot(*qi);
                }
                acc
            })
        };
        if let Some(coupling) = a.coupling {
            // + S C c on the few coupled rows, in row order (the same bits on any thread count)
            for &i in coupling.rows() {
                let i = i as usize;
                let d = s[i] * coupling.row_product(i, &w.c);
                w.q[i] += d;
                cq += w.c[i].dot(d);
            }
        }
        if !(cq > 0.0) {
            stats.indefinite = true;
            break;
        }
        let alpha = delta / cq;
        // x += α c, r -= α q and rᵀr in one pass
        let rr = {
            let (c, q) = (&w.c, &w.q);
            chunked_sum2(x, &mut w.r, &mut w.partial, |first, x, r| {
                let mut acc = 0.0;
                for (k, (xi, ri)) in x.iter_mut().zip(r.iter_mut()).enumerate() {
                    let i = first + k;
                    *xi += alpha * c[i];
                    *ri -= alpha * q[i];
                    acc += ri.dot(*ri);
                }
                acc
            })
        };
        stats.iterations += 1;
        *rnorm = rr.sqrt();
        if *rnorm <= target {
            // converged: the next direction, and the preconditioner application it takes,
            // would not be used
            break;
        }
        let delta_new = precondition(multigrid.then_some(&mut w.amg), &w.pinv, s, &w.r, &mut w.s);
        // (`‖r‖ > target` is false here only for a NaN residual: it keeps that case on the
        // path it always took)
        if !(delta_new > 0.0) && *rnorm > target {
            // rᵀ P⁻¹ r ≤ 0 for r ≠ 0: the preconditioner is not positive definite
            stats.bad_preconditioner = true;
            break;
        }
        let beta = delta_new / delta;
        delta = delta_new;
        w.c.par_iter_mut()
            .zip(w.s.par_iter())
            .with_min_len(CHUNK)
            .for_each(|(c, si)| *c = *si + beta * *c);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain of `n` particles with springs of stiffness `k` between neighbours and mass `m`:
    /// `m I + k L` (symmetric positive definite).
    fn chain(n: usize, k: f64, m: f64) -> BlockMatrix {
        let pairs: Vec<(u32, u32)> = (1..n as u32).map(|i| (i - 1, i)).collect();
        let mut a = BlockMatrix::from_pairs(n, &pairs);
        for i in 0..n {
            let neighbours = (i > 0) as usize + (i + 1 < n) as usize;
            a.add(
                i,
                i,
                Mat3::from_diagonal(Vec3::splat(m + k * neighbours as f64)),
            );
            if i + 1 < n {
                a.add(i, i + 1, Mat3::from_diagonal(Vec3::splat(-k)));
                a.add(i + 1, i, Mat3::from_diagonal(Vec3::splat(-k)));
            }
        }
        a
    }

    #[test]
    fn a_guess_that_meets_the_tolerance_costs_no_refresh_and_leaves_no_trace() {
        let n = 400;
        let a = chain(n, 100.0, 1.0);
        let s = vec![Mat3::IDENTITY; n];
        let z = vec![Vec3::ZERO; n];
        let settings = PcgSettings {
            tolerance: 1e-8,
            max_iterations: 500,
            preconditioner: Preconditioner::Multigrid,
            keep_coarse: false,
        };
        let b1: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(1.0, (i % 7) as f64, -2.0))
            .collect();
        let b2: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new((i % 5) as f64, 0.5, 1.0))
            .collect();
        let (mut w, mut fresh) = (PcgScratch::default(), PcgScratch::default());
        let mut x1 = vec![Vec3::ZERO; n];
        let first = solve(&a, &b1, &s, &z, &mut x1, &settings, &mut w);
        assert!(first.converged && first.iterations > 0 && first.setups == 1);
        // the solution as the guess: nothing to do, no refresh, the guess back unchanged
        let mut again = x1.clone();
        let st = solve(&a, &b1, &s, &z, &mut again, &settings, &mut w);
        assert!(st.converged && st.iterations == 0 && st.setups == 0);
        assert!(st.relative_residual <= settings.tolerance);
        assert_eq!(again, x1);
        // the next solve gives the bits of a scratch that never skipped a refresh
        let mut y = vec![Vec3::ZERO; n];
        solve(&a, &b1, &s, &z, &mut y, &settings, &mut fresh);
        let (mut x2, mut y2) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
        let st = solve(&a, &b2, &s, &z, &mut x2, &settings, &mut w);
        let st_fresh = solve(&a, &b2, &s, &z, &mut y2, &settings, &mut fresh);
        assert!(st.converged && st.setups == 1);
        assert_eq!((x2, st.iterations), (y2, st_fresh.iterations));
    }
}
