//! The constrain and solve stages: the filtered linear solve of one Newton iteration, on the
//! obstacle active set (docs/MATH.md §5, §11, §14).
//!
//! Each round sets the constraints (pins, then the held obstacle contacts), solves, and lets
//! the [`ActiveSet`] release contacts that pull and hold again released ones that sink; at most
//! [`CONTACT_ROUNDS`] solves per iteration, each from the previous one's solution. Where
//! contact goes on, the first solve holds the contacts that pushed at the end of the previous
//! step and those the initial guess says would sink ([`ActiveSet::continuing`]). Where it
//! begins, or at an impact, it holds every candidate but those the initial guess (the previous
//! step's velocity change) says would pull while their particle leaves the surface anyway,
//! which are released up front. The last round keeps the contact set its solve used, so
//! friction gets contacts that match the velocities they come with. In a step solved tighter
//! than [`ROUND_TOLERANCE`], a round after one that flipped many contacts is solved only to
//! it: such a round only chooses the next set, and a set stands only after a solve at the
//! step's own tolerance kept it (docs/MATH.md §14, "Rough rounds").

use super::report::{StepReport, timed};
use super::settings::{LinearSolver, SolverSettings};
use super::system::System;
use crate::constraints::Constraints;
use crate::constraints::obstacle::ActiveSet;
use crate::constraints::pins::{self, PinTargets};
use crate::linalg::direct::DirectSolver;
use crate::linalg::pcg::{self, PcgScratch, PcgSettings};
use crate::math::Vec3;
use rayon::prelude::*;

/// Linear solves per Newton iteration at most. The rounds stop as soon as the active set stops
/// changing (the pile's first contact steps take 4 to 8); a cap of 2 left contacts that pull hard held
/// at the end of the step, and which ones depended on rounding (docs/ROUNDING.md).
pub(crate) const CONTACT_ROUNDS: usize = 8;

/// PCG tolerance of a *rough* round: one that follows a round that flipped over
/// [`MANY_FLIPS`] of the candidates, in a step solved tighter than this (a first contact or an
/// impact, [`crate::step::FIRST_CONTACT_TOLERANCE`], or a scene's own tight tolerance). Its
/// solution only chooses the next round's set: a round solved to the step's own tolerance
/// always follows before a set stands. Where contact begins on spin-290, the rounds release
/// contacts ring by ring from the rim of the contact patch inward, each round solved to 1e-6
/// in about 30 CG iterations; rough rounds took its two first-contact steps from 486 to 322
/// (BENCHMARKS.md, fortieth session). At 1e-3 the impulses and sinking tests were too inexact
/// and the set never settled.
pub(crate) const ROUND_TOLERANCE: f64 = 1e-4;

/// The share of the candidates a round must flip for the next round to be rough.
pub(crate) const MANY_FLIPS: f64 = 0.02;

/// Particles per task in the per-particle parallel loops.
const PARTICLES: usize = 1024;

/// The linear solvers' working memory, kept between steps.
#[derive(Default)]
pub(crate) struct Solvers {
    /// PCG and its preconditioner (the multigrid hierarchy lives here).
    pub pcg: PcgScratch,
    /// Sparse Cholesky / LU.
    pub direct: DirectSolver,
}

/// Everything one iteration's solve reads.
pub(crate) struct Problem<'a> {
    /// Pinned particles.
    pub pinned: &'a [bool],
    /// Moving pins' targets.
    pub pins: &'a PinTargets,
    /// Velocities of the current iterate.
    pub v: &'a [Vec3],
    /// Right-hand side.
    pub rhs: &'a [Vec3],
    /// Initial guess of the first iteration (the previous step's velocity change).
    pub warm: &'a [Vec3],
    /// Newton iteration, from 0.
    pub iteration: u32,
    /// A released contact is held again when its solved normal velocity is below the
    /// prescribed one by more than this, m/s.
    pub sink_tolerance: f64,
}

/// Scratch of the solve rounds, kept between steps.
#[derive(Default)]
pub(crate) struct Scratch {
    /// The velocity filter and prescribed changes.
    pub constraints: Constraints,
    /// Scratch for the active set's prediction.
    pub w: Vec<Vec3>,
}

impl Scratch {
    /// Buffers for `n` particles.
    pub fn resize(&mut self, n: usize) {
        let c = &mut self.constraints;
        c.filter.resize(n, crate::math::Mat3::IDENTITY);
        for b in [&mut c.z, &mut self.w] {
            b.resize(n, Vec3::ZERO);
        }
    }
}

/// Solves the iteration's system into `dv` on the active set `set` (see the module docs).
/// Returns the reason when a linear solve fails.
#[allow(clippy::too_many_arguments)]
pub(crate) fn on_active_set(
    system: &System,
    solvers: &mut Solvers,
    settings: &SolverSettings,
    p: &Problem,
    set: &mut ActiveSet,
    dv: &mut [Vec3],
    s: &mut Scratch,
    report: &mut StepReport,
) -> Result<(), String> {
    let Scratch { constraints: c, w } = s;
    let (v, rhs, it) = (p.v, p.rhs, p.iteration);
    // Once a round has set up the whole multigrid for this iteration's matrix, later rounds
    // (the same matrix, a few contacts' filters changed) set up only its finest level
    // (docs/MATH.md §14). Never before: the coarse levels would then come from an earlier
    // matrix, and a resumed run, whose multigrid starts empty, would not repeat them.
    let mut set_up = false;
    // the direct solver's solves are exact: never rough
    let tight = settings.linear_solver == LinearSolver::Pcg && settings.tolerance < ROUND_TOLERANCE;
    let rough_settings = SolverSettings {
        tolerance: ROUND_TOLERANCE,
        ..*settings
    };
    let mut rough = false;
    for round in 0..CONTACT_ROUNDS {
        timed(&mut report.stages.constrain, || {
            pins::apply(p.pinned, p.pins, v, c);
            if round == 0 {
                // initial guess: the previous step's change, then the previous round's
                // solution (only the contacts that changed differ)
                dv.par_iter_mut()
                    .enumerate()
                    .with_min_len(PARTICLES)
                    .for_each(|(i, d)| {
                        *d = if it == 0 {
                            p.warm.get(i).copied().unwrap_or(Vec3::ZERO)
                        } else {
                            Vec3::ZERO
                        };
                    });
            }
            set.hold(v, c);
            if round == 0 && it == 0 && set.needs_prediction() {
                set.predict(system.matrix(), rhs, v, dv, c, w);
            }
        });
        let t = std::time::Instant::now();
        report.linear_solves += 1;
        let setups = report.preconditioner_setups;
        let last = round + 1 == CONTACT_ROUNDS;
        let rough_now = rough && !last;
        let round_settings = if rough_now { &rough_settings } else { settings };
        report.rough_solves += rough_now as usize;
        linear(
            system,
            solvers,
            round_settings,
            rhs,
            c,
            dv,
            it,
            set_up,
            report,
        )?;
        set_up |= report.preconditioner_setups > setups;
        let mut done = set.is_empty();
        if !done {
            set.measure(system.matrix(), rhs, dv);
            if last {
                done = true;
            } else {
                // a rough round's set stands only after a tight round confirms it
                let flipped = set.update(v, dv, p.sink_tolerance);
                done = flipped == 0 && !rough_now;
                rough = tight && flipped as f64 > MANY_FLIPS * set.len() as f64;
            }
        }
        report.stages.solve += t.elapsed().as_secs_f64();
        if done {
            break;
        }
    }
    Ok(())
}

/// One linear solve with the constraints `c` into `dv` (its initial guess on entry);
/// `keep_coarse`: the multigrid was set up for this system matrix already (under another
/// filter), so only its finest level is set up again ([`PcgSettings::keep_coarse`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn linear(
    system: &System,
    solvers: &mut Solvers,
    settings: &SolverSettings,
    rhs: &[Vec3],
    c: &Constraints,
    dv: &mut [Vec3],
    it: u32,
    keep_coarse: bool,
    report: &mut StepReport,
) -> Result<(), String> {
    match settings.linear_solver {
        LinearSolver::Pcg => {
            let pcg_settings = PcgSettings {
                tolerance: settings.tolerance,
                max_iterations: settings.max_iterations,
                preconditioner: settings.preconditioner,
                keep_coarse,
            };
            let stats = pcg::solve_split(
                system.matrix(),
                rhs,
                &c.filter,
                &c.z,
                dv,
                &pcg_settings,
                &mut solvers.pcg,
            );
            report.cg_iterations += stats.iterations;
            report.preconditioner_setups += stats.setups;
            report.residual = stats.relative_residual;
            if !stats.converged {
                let why = if stats.indefinite {
                    "the system matrix is not positive definite"
                } else if stats.bad_preconditioner {
                    "the multigrid preconditioner is not positive definite"
                } else {
                    "conjugate gradient did not converge"
                };
                return Err(format!(
                    "{why} (Newton iteration {}, {} CG iterations, relative residual {:.3e}, tolerance {:.1e}); try a smaller dt, a larger solver.max_iterations or linear_solver = \"direct\"",
                    it + 1,
                    stats.iterations,
                    stats.relative_residual,
                    settings.tolerance
                ));
            }
        }
        LinearSolver::Direct => {
            let symmetric = !settings.damping_x_jacobian;
            solvers
                .direct
                .solve(system.merged(), rhs, &c.filter, &c.z, dv, symmetric)?;
        }
    }
    Ok(())
}
