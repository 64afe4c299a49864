//! The update of each Newton iteration: the new velocities and positions from the solved
//! change, with a backtracking line search when the step takes more than one iteration.
//!
//! With `newton_iterations > 1` the step minimizes the incremental potential
//! `Φ(v) = ½ (v - v₀)ᵀ M (v - v₀) + E(x₀ + h v) + h Ψ(x₀ + h v, v)` (`Ψ` the dissipation
//! potential of damping and drag; docs/MATH.md §10). The first iteration is the linearized step;
//! each one halves its step along the solved direction until `Φ` does not increase.

use crate::forces::{Force, State};
use crate::math::Vec3;

/// What the update found.
pub(crate) enum Outcome {
    /// Iterate again (or stop: this was the last iteration).
    Continue,
    /// The change was negligible: the iterations have converged.
    Converged,
    /// This particle's position or velocity is not finite.
    NonFinite(usize),
}

/// The model's forces plus this step's contact forces.
pub(crate) fn all_forces<'a>(
    forces: &'a [Box<dyn Force>],
    contacts: &'a [&'a dyn Force],
) -> impl Iterator<Item = &'a dyn Force> {
    forces
        .iter()
        .map(|f| f.as_ref())
        .chain(contacts.iter().copied())
}

/// The forces of a step and where it started.
pub(crate) struct Potential<'a> {
    /// Start of the step, s.
    pub t0: f64,
    /// Particle masses.
    pub mass: &'a [f64],
    /// The model's forces.
    pub forces: &'a [Box<dyn Force>],
    /// The step's contact forces (cloth–cloth, then cloth–collider).
    pub contacts: &'a [&'a dyn Force],
    /// Start of the step.
    pub x0: &'a [Vec3],
    /// Start of the step.
    pub v0: &'a [Vec3],
    /// Step, s.
    pub h: f64,
}

impl Potential<'_> {
    /// `Φ(v)` of the module docs.
    pub fn objective(&self, v: &[Vec3]) -> f64 {
        let (h, t) = (self.h, self.t0 + self.h);
        let x: Vec<Vec3> = self.x0.iter().zip(v).map(|(a, b)| *a + h * *b).collect();
        let inertia: f64 = self
            .mass
            .iter()
            .zip(v.iter().zip(self.v0))
            .map(|(m, (a, b))| 0.5 * m * (*a - *b).length_squared())
            .sum();
        inertia
            + all_forces(self.forces, self.contacts)
                .map(|f| {
                    let at = State { t, x: &x, v };
                    f.energy(t, &x) + h * f.dissipation(&at)
                })
                .sum::<f64>()
    }

    /// Energy stored in the springs and contacts at `x` (every force's potential but
    /// gravity's, the first force, whose work over a step the blow-up test allows for
    /// separately).
    pub fn stored_energy(&self, x: &[Vec3]) -> f64 {
        all_forces(&self.forces[1..], self.contacts)
            .map(|f| f.energy(self.t0, x))
            .sum()
    }
}

/// Moves the iterate `(x, v)` by the solved change `dv` (iteration `it` of `newton`), sets
/// `x = x₀ + h v`, and tells whether to go on. `gh` is `|g| h`, the scale below which a change
/// counts as negligible.
pub(crate) fn update(
    p: &Potential,
    x: &mut [Vec3],
    v: &mut Vec<Vec3>,
    dv: &[Vec3],
    it: u32,
    newton: u32,
    gh: f64,
) -> Outcome {
    let n = v.len();
    let mut alpha = 1.0;
    if newton > 1 {
        let start: Vec<Vec3> = if it == 0 {
            vec![Vec3::ZERO; n]
        } else {
            v.clone()
        };
        let phi0 = p.objective(&start);
        let full: Vec<Vec3> = v.iter().zip(dv).map(|(a, b)| *a + *b).collect();
        let mut cand = full.clone();
        for _ in 0..20 {
            if p.objective(&cand) <= phi0 || !phi0.is_finite() {
                break;
            }
            alpha *= 0.5;
            for i in 0..n {
                cand[i] = start[i] + alpha * (full[i] - start[i]);
            }
        }
        *v = cand;
    } else {
        for i in 0..n {
            v[i] += dv[i];
        }
    }
    for i in 0..n {
        x[i] = p.x0[i] + p.h * v[i];
    }
    if let Some(i) = super::guard::first_non_finite(x, v) {
        return Outcome::NonFinite(i);
    }
    let vmax = v.iter().fold(0.0f64, |m, e| m.max(e.abs().max_element()));
    let dmax = dv.iter().fold(0.0f64, |m, e| m.max(e.abs().max_element()));
    if it + 1 < newton && alpha == 1.0 && dmax <= 1e-12 * vmax.max(gh).max(1e-300) {
        return Outcome::Converged;
    }
    Outcome::Continue
}

#[cfg(test)]
mod tests {
    use super::*;

    fn potential<'a>(x0: &'a [Vec3], v0: &'a [Vec3], mass: &'a [f64]) -> Potential<'a> {
        Potential {
            t0: 0.0,
            mass,
            forces: &[],
            contacts: &[],
            x0,
            v0,
            h: 0.1,
        }
    }

    #[test]
    fn one_iteration_takes_the_full_change_and_moves_x_by_h_v() {
        let x0 = [Vec3::ZERO, Vec3::X];
        let v0 = [Vec3::Y, Vec3::ZERO];
        let p = potential(&x0, &v0, &[1.0, 2.0]);
        let (mut x, mut v) = (x0.to_vec(), v0.to_vec());
        let dv = [Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.0, 0.0, -1.0)];
        assert!(matches!(
            update(&p, &mut x, &mut v, &dv, 0, 1, 0.1),
            Outcome::Continue
        ));
        assert_eq!(v, vec![Vec3::new(0.5, 1.0, 0.0), Vec3::new(0.0, 0.0, -1.0)]);
        for i in 0..2 {
            assert_eq!(x[i], x0[i] + 0.1 * v[i]);
        }
    }

    #[test]
    fn a_negligible_change_converges_and_a_non_finite_one_is_named() {
        let x0 = [Vec3::ZERO; 3];
        let v0 = [Vec3::ZERO; 3];
        let mass = [1.0; 3];
        let p = potential(&x0, &v0, &mass);
        let (mut x, mut v) = (x0.to_vec(), vec![Vec3::X; 3]);
        // a change of 1e-13 m/s against velocities of 1 m/s, before the last iteration
        // (toward v₀, so that the line search takes it whole)
        let tiny = [Vec3::X * -1e-13; 3];
        assert!(matches!(
            update(&p, &mut x, &mut v, &tiny, 1, 3, 0.1),
            Outcome::Converged
        ));
        // at the last iteration there is nothing to stop
        assert!(matches!(
            update(&p, &mut x, &mut v, &tiny, 2, 3, 0.1),
            Outcome::Continue
        ));
        let mut bad = [Vec3::ZERO; 3];
        bad[2].y = f64::INFINITY;
        assert!(matches!(
            update(&p, &mut x, &mut v, &bad, 1, 3, 0.1),
            Outcome::NonFinite(2)
        ));
    }

    #[test]
    fn the_line_search_never_increases_the_objective() {
        // no forces: Φ(v) = ½ Σ m |v - v₀|², minimized at v₀; a change overshooting past
        // v₀ from zero by a factor 3 is halved until Φ is not above Φ(0)
        let x0 = [Vec3::ZERO; 2];
        let v0 = [Vec3::X, Vec3::Y];
        let mass = [1.0, 1.0];
        let p = potential(&x0, &v0, &mass);
        let (mut x, mut v) = (x0.to_vec(), v0.to_vec());
        let dv = [Vec3::X * 2.0, Vec3::Y * 2.0];
        let phi0 = p.objective(&[Vec3::ZERO; 2]);
        update(&p, &mut x, &mut v, &dv, 0, 2, 0.1);
        assert!(p.objective(&v) <= phi0);
        assert!(v[0].x < 3.0, "the overshoot is cut back: {}", v[0]);
    }
}
