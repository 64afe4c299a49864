//! Forces, one file each, behind one trait.
//!
//! Convention (MATH.md): `f(x, v)` is the force, `K = ∂f/∂x` and `D = ∂f/∂v` its Jacobians in
//! 3×3 blocks. For a conservative force `f = -∇E` and `K = -∇²E`. Every force here is checked
//! against central finite differences in its tests.

pub mod damping;
pub mod drag;
pub mod gravity;
pub mod pair_sum;
pub mod repulsion;
pub mod spring;

pub use damping::SpringDamping;
pub use drag::AirDrag;
pub use gravity::Gravity;
pub use repulsion::Repulsions;
pub use spring::Springs;

use crate::linalg::BlockMatrix;
use crate::math::Vec3;

/// A force acting on the particles, with its Jacobians.
pub trait Force: Send + Sync {
    /// Short name, for reports.
    fn name(&self) -> &'static str;

    /// Potential energy `E(x)` (0 for forces with no potential).
    fn energy(&self, _x: &[Vec3]) -> f64 {
        0.0
    }

    /// Dissipation potential `Ψ(x, v)` with `∂Ψ/∂v = -f` for forces linear in `v` (0 otherwise).
    fn dissipation(&self, _x: &[Vec3], _v: &[Vec3]) -> f64 {
        0.0
    }

    /// `f += force(x, v)`.
    fn add_force(&self, x: &[Vec3], v: &[Vec3], f: &mut [Vec3]);

    /// Particle pairs whose off-diagonal blocks this force writes.
    fn add_pattern(&self, _pairs: &mut Vec<(u32, u32)>) {}

    /// `m += a ∂f/∂x + b ∂f/∂v` (the matrix form this force uses: for springs, with the
    /// compression clamp when enabled).
    fn add_jacobian(&self, x: &[Vec3], v: &[Vec3], a: f64, b: f64, m: &mut BlockMatrix);

    /// `out += (a ∂f/∂x + b ∂f/∂v) w`, with the same Jacobian as [`Force::add_jacobian`].
    fn add_jacobian_product(
        &self,
        x: &[Vec3],
        v: &[Vec3],
        a: f64,
        b: f64,
        w: &[Vec3],
        out: &mut [Vec3],
    );
}

#[cfg(test)]
pub(crate) mod testing {
    //! Finite-difference checks shared by the force tests.
    use super::*;

    /// Central-difference force `-∂E/∂x`.
    pub fn fd_gradient(force: &dyn Force, x: &[Vec3]) -> Vec<Vec3> {
        let mut g = vec![Vec3::ZERO; x.len()];
        let mut xp = x.to_vec();
        for i in 0..x.len() {
            for d in 0..3 {
                let e = 1e-6 * (1.0 + x[i][d].abs());
                xp[i][d] = x[i][d] + e;
                let ep = force.energy(&xp);
                xp[i][d] = x[i][d] - e;
                let em = force.energy(&xp);
                xp[i][d] = x[i][d];
                g[i][d] = -(ep - em) / (2.0 * e);
            }
        }
        g
    }

    /// Dense `∂f/∂x` (wrt = false) or `∂f/∂v` (wrt = true) by central differences.
    pub fn fd_jacobian(force: &dyn Force, x: &[Vec3], v: &[Vec3], wrt_v: bool) -> Vec<Vec<f64>> {
        let n = x.len();
        let mut jac = vec![vec![0.0; 3 * n]; 3 * n];
        let (mut xp, mut vp) = (x.to_vec(), v.to_vec());
        for j in 0..n {
            for d in 0..3 {
                let base = if wrt_v { v[j][d] } else { x[j][d] };
                let e = 1e-6 * (1.0 + base.abs());
                let mut eval = |delta: f64| {
                    if wrt_v {
                        vp[j][d] = base + delta;
                    } else {
                        xp[j][d] = base + delta;
                    }
                    let mut f = vec![Vec3::ZERO; n];
                    force.add_force(&xp, &vp, &mut f);
                    if wrt_v {
                        vp[j][d] = base;
                    } else {
                        xp[j][d] = base;
                    }
                    f
                };
                let fp = eval(e);
                let fm = eval(-e);
                for i in 0..n {
                    for r in 0..3 {
                        jac[3 * i + r][3 * j + d] = (fp[i][r] - fm[i][r]) / (2.0 * e);
                    }
                }
            }
        }
        jac
    }

    /// The force's own Jacobian `a ∂f/∂x + b ∂f/∂v`, assembled densely.
    pub fn assembled(force: &dyn Force, x: &[Vec3], v: &[Vec3], a: f64, b: f64) -> Vec<Vec<f64>> {
        let mut pairs = Vec::new();
        force.add_pattern(&mut pairs);
        let mut m = BlockMatrix::from_pairs(x.len(), &pairs);
        force.add_jacobian(x, v, a, b, &mut m);
        m.to_dense()
    }

    /// Max entry-wise difference, relative to the largest entry of `reference` (or 1).
    pub fn rel_diff(got: &[Vec<f64>], reference: &[Vec<f64>]) -> f64 {
        let scale = reference
            .iter()
            .flatten()
            .fold(1.0f64, |m, v| m.max(v.abs()));
        let diff = got
            .iter()
            .flatten()
            .zip(reference.iter().flatten())
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        diff / scale
    }

    /// Checks `add_jacobian_product` against the assembled matrix times `w`.
    pub fn check_product(
        force: &dyn Force,
        x: &[Vec3],
        v: &[Vec3],
        a: f64,
        b: f64,
        w: &[Vec3],
    ) -> f64 {
        let dense = assembled(force, x, v, a, b);
        let mut out = vec![Vec3::ZERO; x.len()];
        force.add_jacobian_product(x, v, a, b, w, &mut out);
        let wf: Vec<f64> = w.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
        let mut worst = 0.0f64;
        let mut scale = 1.0f64;
        for r in 0..3 * x.len() {
            let expect: f64 = dense[r].iter().zip(&wf).map(|(m, q)| m * q).sum();
            worst = worst.max((out[r / 3][r % 3] - expect).abs());
            scale = scale.max(expect.abs());
        }
        worst / scale
    }
}
