//! Forces, one file each, behind one trait.
//!
//! Convention (docs/MATH.md §0): `f(t, x, v)` is the force, `K = ∂f/∂x` and `D = ∂f/∂v` its
//! Jacobians in 3×3 blocks. For a conservative force `f = -∇E` and `K = -∇²E`. Every force here
//! is checked against central finite differences in its tests.
//!
//! A force acting on small groups of particles (pairs, triangles, hinges, contact stencils)
//! implements [`stencil::StencilForce`] instead of [`Force`]: it writes each stencil's local
//! energy, forces and Jacobian blocks, and the gather of [`stencil`] sums them into the global
//! vectors and matrix, deterministically and in parallel.

pub mod damping;
pub mod drag;
pub mod gravity;
pub mod hinge;
pub mod membrane;
pub mod obstacle_friction;
pub mod obstacle_repulsion;
pub mod pressure;
pub mod repulsion;
pub mod shell;
pub mod spring;
pub mod stencil;
pub mod stitch;
pub mod wind;

pub use damping::SpringDamping;
pub use drag::AirDrag;
pub use gravity::Gravity;
pub use obstacle_friction::ObstacleFrictions;
pub use obstacle_repulsion::ObstacleRepulsions;
pub use pressure::Pressure;
pub use repulsion::Repulsions;
pub use spring::Springs;
pub use stitch::Stitches;
pub use wind::{Wind, WindForce};

use crate::linalg::BlockMatrix;
use crate::math::Vec3;

/// The time and state at which a force is evaluated.
#[derive(Clone, Copy, Debug)]
pub struct State<'a> {
    /// Time, s.
    pub t: f64,
    /// Positions.
    pub x: &'a [Vec3],
    /// Velocities.
    pub v: &'a [Vec3],
}

/// A force acting on the particles, with its Jacobians.
pub trait Force: Send + Sync {
    /// Short name, for reports.
    fn name(&self) -> &'static str;

    /// Potential energy `E(t, x)` (0 for forces with no potential).
    fn energy(&self, _t: f64, _x: &[Vec3]) -> f64 {
        0.0
    }

    /// Dissipation potential `Ψ(t, x, v)` with `∂Ψ/∂v = -f` for forces linear in `v` (0
    /// otherwise).
    fn dissipation(&self, _at: &State) -> f64 {
        0.0
    }

    /// `f += force(t, x, v)`.
    fn add_force(&self, at: &State, f: &mut [Vec3]);

    /// Particle pairs whose off-diagonal blocks this force writes.
    fn add_pattern(&self, _pairs: &mut Vec<(u32, u32)>) {}

    /// `m += a ∂f/∂x + b ∂f/∂v` (the matrix form this force uses: for springs, with the
    /// compression clamp when enabled).
    fn add_jacobian(&self, at: &State, a: f64, b: f64, m: &mut BlockMatrix);

    /// `out += (a ∂f/∂x + b ∂f/∂v) w`, with the same Jacobian as [`Force::add_jacobian`].
    fn add_jacobian_product(&self, at: &State, a: f64, b: f64, w: &[Vec3], out: &mut [Vec3]);

    /// Everything a Newton iteration asks of the force at one point, in one call:
    /// [`Force::add_force`] into `f`, [`Force::add_jacobian`] with `at.matrix` into `m` and
    /// [`Force::add_jacobian_product`] with `at.product` and `at.w` into `out`. Forces whose
    /// three share work (a spring's geometry) do it once; the result has the same bits as the
    /// three calls.
    fn add_linearization(
        &self,
        at: &Linearization,
        f: &mut [Vec3],
        m: &mut BlockMatrix,
        out: &mut [Vec3],
    ) {
        linearize_separately(self, at, f, m, out);
    }
}

/// Where and with which coefficients [`Force::add_linearization`] evaluates.
#[derive(Clone, Copy, Debug)]
pub struct Linearization<'a> {
    /// Time, s.
    pub t: f64,
    /// Positions.
    pub x: &'a [Vec3],
    /// Velocities.
    pub v: &'a [Vec3],
    /// `(a, b)` of the matrix `a ∂f/∂x + b ∂f/∂v`.
    pub matrix: (f64, f64),
    /// `(a, b)` of the product `(a ∂f/∂x + b ∂f/∂v) w`.
    pub product: (f64, f64),
    /// The vector of the product.
    pub w: &'a [Vec3],
}

impl<'a> Linearization<'a> {
    /// The time and state of the linearization point.
    pub fn state(&self) -> State<'a> {
        State {
            t: self.t,
            x: self.x,
            v: self.v,
        }
    }
}

/// [`Force::add_linearization`] by the three separate calls.
pub fn linearize_separately<F: Force + ?Sized>(
    force: &F,
    at: &Linearization,
    f: &mut [Vec3],
    m: &mut BlockMatrix,
    out: &mut [Vec3],
) {
    let state = at.state();
    force.add_force(&state, f);
    force.add_jacobian(&state, at.matrix.0, at.matrix.1, m);
    force.add_jacobian_product(&state, at.product.0, at.product.1, at.w, out);
}

#[cfg(test)]
pub(crate) mod testing;
