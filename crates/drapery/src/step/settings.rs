//! The time step's tunables, checked once when the simulation is built.

use crate::error::{Error, Result};
use crate::linalg::pcg::Preconditioner;

/// Which linear solver handles the step's system.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LinearSolver {
    /// Baraff–Witkin filtered PCG (default), preconditioned as [`SolverSettings::preconditioner`] says.
    #[default]
    Pcg,
    /// Sparse Cholesky (faer) of the filtered system; LU when the matrix is not symmetric.
    Direct,
}

/// The PCG tolerance, at most, of a step in which obstacle contact begins: it has contact
/// candidates and none of them had a normal force in the previous step. What the cloth does
/// after such a first contact depends on that step's solve to about this accuracy: a pile
/// dropped at 1e-3 did a ninth of the self-contact work of the exact solve, and at 1e-6 the
/// same (docs/ROUNDING.md, seventeenth session). Later steps keep `tolerance`.
pub const FIRST_CONTACT_TOLERANCE: f64 = 1e-6;

/// An impact: a step whose obstacle contact candidates approach the obstacles with more than
/// this share of the cloth's kinetic energy (counting only each one's approach beyond the speed
/// gravity gives in one step, [`crate::constraints::obstacle::impact_energy`]) is solved to at
/// most [`FIRST_CONTACT_TOLERANCE`] too. The pile's landing steps carry 8e-3 and 2e-2 of it,
/// its later steps 1e-3 or less (docs/ROUNDING.md, twentieth session).
pub const IMPACT_SHARE: f64 = 3e-3;

/// Tunables of the time step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverSettings {
    /// Newton iterations per step; 1 is the seeds' linearized step (default: 1).
    pub newton_iterations: u32,
    /// Newton iterations at most in a step where obstacle contact begins and whose
    /// linearization is far off (default: 3): after such a step's last iteration, one more
    /// follows while a stretch spring's length after the solved change differs from the linear
    /// model's prediction by more than 30 % of its rest length (docs/MATH.md §10). 1, or at
    /// most `newton_iterations`, never adds one.
    pub max_newton_iterations: u32,
    /// PCG relative residual `‖r‖/‖b‖` (default: 1e-6); a step where obstacle contact begins,
    /// or an impact ([`IMPACT_SHARE`]), uses at most [`FIRST_CONTACT_TOLERANCE`].
    pub tolerance: f64,
    /// PCG iteration cap (default: 1000).
    pub max_iterations: usize,
    /// Linear solver (default: PCG).
    pub linear_solver: LinearSolver,
    /// Also put the (non-symmetric) position derivative of spring damping in the matrix
    /// (default: false, as Baraff & Witkin). Needs `linear_solver = Direct`.
    pub damping_x_jacobian: bool,
    /// PCG preconditioner (default: the smoothed-aggregation multigrid).
    pub preconditioner: Preconditioner,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            newton_iterations: 1,
            max_newton_iterations: 3,
            tolerance: 1e-6,
            max_iterations: 1000,
            linear_solver: LinearSolver::Pcg,
            damping_x_jacobian: false,
            preconditioner: Preconditioner::Multigrid,
        }
    }
}

impl SolverSettings {
    /// Checks ranges and combinations.
    pub fn validate(&self) -> Result<()> {
        if self.newton_iterations < 1 {
            return Err(Error::field(
                "solver.newton_iterations",
                format!("must be at least 1, got {}", self.newton_iterations),
            ));
        }
        if self.max_newton_iterations < 1 {
            return Err(Error::field(
                "solver.max_newton_iterations",
                format!("must be at least 1, got {}", self.max_newton_iterations),
            ));
        }
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(Error::field(
                "solver.tolerance",
                format!("must be in (0, 1), got {}", self.tolerance),
            ));
        }
        if self.max_iterations < 1 {
            return Err(Error::field(
                "solver.max_iterations",
                format!("must be at least 1, got {}", self.max_iterations),
            ));
        }
        if self.damping_x_jacobian && self.linear_solver != LinearSolver::Direct {
            return Err(Error::field(
                "solver.damping_x_jacobian",
                "makes the matrix non-symmetric, which conjugate gradient cannot solve: use linear_solver = \"direct\"",
            ));
        }
        Ok(())
    }
}
