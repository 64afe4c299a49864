//! The linearize stage: forces, system matrix and right-hand side of one Newton iteration
//! (docs/MATH.md §1).
//!
//! At the iterate `(x, v)` (the start of the step at the first iteration), with
//! `w = x₀ + h v - x` (zero at the first iteration):
//!
//! ```text
//! A = M - h D - h² K          rhs = M (v₀ - v) + h f + h K w
//! ```
//!
//! and the iteration solves `A Δv = rhs`. Every force gives its force, matrix blocks and the
//! product `K w` from one evaluation ([`crate::forces::Force::add_linearization`]).

use super::system::System;
use crate::forces::{Force, Linearization};
use crate::math::Vec3;
use rayon::prelude::*;

/// Particles per task in the per-particle parallel loops.
const PARTICLES: usize = 1024;

/// Where a Newton iteration linearizes.
pub(crate) struct Iterate<'a> {
    /// End of the step, s: the time the forces are evaluated at (backward Euler).
    pub t1: f64,
    /// Start of the step.
    pub x0: &'a [Vec3],
    /// Start of the step.
    pub v0: &'a [Vec3],
    /// Current positions.
    pub x: &'a [Vec3],
    /// Current velocities.
    pub v: &'a [Vec3],
    /// Step, s.
    pub h: f64,
}

/// The stage's outputs, and its scratch (kept between steps).
#[derive(Default)]
pub(crate) struct Linearized {
    /// Total force at the iterate.
    pub f: Vec<Vec3>,
    /// Right-hand side of the iteration's system.
    pub rhs: Vec<Vec3>,
    /// `w = x₀ + h v - x`.
    pub w: Vec<Vec3>,
    /// `h K w`.
    pub kw: Vec<Vec3>,
}

impl Linearized {
    /// Buffers for `n` particles.
    pub fn resize(&mut self, n: usize) {
        for b in [&mut self.f, &mut self.rhs, &mut self.w, &mut self.kw] {
            b.resize(n, Vec3::ZERO);
        }
    }
}

/// Assembles the system matrix into `system` and the right-hand side into `out.rhs`.
pub(crate) fn run(
    system: &mut System,
    mass: &[f64],
    forces: &[Box<dyn Force>],
    contacts: &[&dyn Force],
    it: &Iterate,
    out: &mut Linearized,
) {
    let Linearized { f, rhs, w, kw } = out;
    let (x0, v0, x, v, h) = (it.x0, it.v0, it.x, it.v, it.h);
    w.par_iter_mut()
        .zip(f.par_iter_mut())
        .zip(kw.par_iter_mut())
        .enumerate()
        .with_min_len(PARTICLES)
        .for_each(|(i, ((wi, fi), kwi))| {
            *wi = x0[i] + h * v[i] - x[i];
            *fi = Vec3::ZERO;
            *kwi = Vec3::ZERO;
        });
    let at = Linearization {
        t: it.t1,
        x,
        v,
        matrix: (-h * h, -h),
        product: (h, 0.0),
        w,
    };
    system.assemble(mass, forces, &at, contacts, Some((&mut f[..], &mut kw[..])));
    rhs.par_iter_mut()
        .enumerate()
        .with_min_len(PARTICLES)
        .for_each(|(i, r)| *r = mass[i] * (v0[i] - v[i]) + h * f[i] + kw[i]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::step::{SolverSettings, testing};

    #[test]
    fn at_the_start_of_the_step_the_right_hand_side_is_h_f_plus_h2_k_v() {
        let m = testing::sheet(6, 0.5, vec![0, 5]);
        let forces = super::super::model_forces(&m, &SolverSettings::default());
        let n = m.particle_count();
        let h = 0.01;
        let mut sys = System::new(n, &forces);
        let mut out = Linearized::default();
        out.resize(n);
        let it = Iterate {
            t1: h,
            x0: &m.x,
            v0: &m.v,
            x: &m.x,
            v: &m.v,
            h,
        };
        run(&mut sys, &m.mass, &forces, &[], &it, &mut out);
        // independently: f and K v from the forces' own calls
        let mut f = vec![Vec3::ZERO; n];
        let mut kv = vec![Vec3::ZERO; n];
        let at = crate::forces::State {
            t: h,
            x: &m.x,
            v: &m.v,
        };
        for force in &forces {
            force.add_force(&at, &mut f);
            force.add_jacobian_product(&at, 1.0, 0.0, &m.v, &mut kv);
        }
        for i in 0..n {
            let want = h * (f[i] + h * kv[i]);
            assert!(
                (out.rhs[i] - want).length() <= 1e-12 * (1.0 + want.length()),
                "{i}: {} vs {want}",
                out.rhs[i]
            );
        }
        // and A = M - h D - h² K: A v = M v - h D v - h² K v
        let mut av = vec![Vec3::ZERO; n];
        sys.matrix().mul_vec(&m.v, &mut av);
        let mut dk = vec![Vec3::ZERO; n];
        for force in &forces {
            force.add_jacobian_product(&at, -h * h, -h, &m.v, &mut dk);
        }
        for i in 0..n {
            let want = m.mass[i] * m.v[i] + dk[i];
            assert!((av[i] - want).length() <= 1e-12 * (1.0 + want.length()));
        }
    }
}
