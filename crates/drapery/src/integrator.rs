//! Linearized implicit Euler (Baraff & Witkin 1998) and its Newton extension.
//! (Implementation in progress: the API below is the contract.)

use crate::error::Result;
use crate::model::Model;

/// Which linear solver handles `(M - h ∂f/∂v - h² ∂f/∂x) Δv = h (f + h ∂f/∂x v)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LinearSolver {
    /// Baraff–Witkin filtered PCG with a 3×3 block-Jacobi preconditioner (default).
    #[default]
    Pcg,
    /// Sparse Cholesky (faer) of the filtered system.
    Direct,
}

/// Tunables of the time step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverSettings {
    /// Newton iterations per step; 1 is the seeds' linearized step (default: 1).
    pub newton_iterations: u32,
    /// PCG relative residual `‖r‖/‖b‖` (default: 1e-6).
    pub tolerance: f64,
    /// PCG iteration cap (default: 1000).
    pub max_iterations: usize,
    /// Linear solver (default: PCG).
    pub linear_solver: LinearSolver,
    /// Also put the (non-symmetric) position derivative of spring damping in the matrix
    /// (default: false, as Baraff & Witkin).
    pub damping_x_jacobian: bool,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            newton_iterations: 1,
            tolerance: 1e-6,
            max_iterations: 1000,
            linear_solver: LinearSolver::Pcg,
            damping_x_jacobian: false,
        }
    }
}

/// What one step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport {
    /// Newton iterations taken.
    pub newton_iterations: u32,
    /// Total (P)CG iterations over the Newton iterations.
    pub cg_iterations: usize,
    /// Final relative residual of the last linear solve.
    pub residual: f64,
    /// Seconds spent assembling forces and matrices.
    pub assembly_seconds: f64,
    /// Seconds spent in the linear solver.
    pub solve_seconds: f64,
}

/// A model plus the solver's working memory. Advance it with [`Simulation::step`].
pub struct Simulation {
    /// The simulated state (positions and velocities are updated in place).
    pub model: Model,
    /// Step settings.
    pub settings: SolverSettings,
    /// Simulated time, s.
    pub time: f64,
    /// Steps taken so far.
    pub steps: u64,
}

impl Simulation {
    /// Prepares a simulation (matrix pattern, solver scratch).
    pub fn new(model: Model, settings: SolverSettings) -> Result<Self> {
        Ok(Simulation {
            model,
            settings,
            time: 0.0,
            steps: 0,
        })
    }

    /// Advances by one step of `h` seconds. On error the state is left as it was before the step.
    pub fn step(&mut self, h: f64) -> Result<StepReport> {
        let _ = h;
        todo!("implicit step")
    }
}
