//! The update of each Newton iteration: the new velocities and positions from the solved
//! change, with a backtracking line search when the step takes more than one iteration.
//!
//! With `newton_iterations > 1` the step minimizes the incremental potential
//! `Φ(v) = ½ (v - v₀)ᵀ M (v - v₀) + E(x₀ + h v) + h Ψ(x₀ + h v, v)` (`Ψ` the dissipation
//! potential of damping and drag; docs/MATH.md §10). The first iteration is the linearized step;
//! each one halves its step along the solved direction until `Φ` does not increase.
//!
//! Where obstacle contact begins, a step whose linearized solve is far off
//! ([`linearization_error`] over [`RELINEARIZE_STRAIN`]) iterates all the same, up to
//! `max_newton_iterations`, until the error of an iteration's own linearization is under it
//! (docs/MATH.md §10, "Where the linearization is far off").

use crate::forces::{Force, State};
use crate::math::Vec3;
use crate::model::{SpringKind, Springs};
use rayon::prelude::*;

/// The largest [`linearization_error`] a step takes as it is; above it the step iterates
/// (docs/MATH.md §10). A spring turning by `θ` within a step has the error `1 - cos θ`, so this
/// is a turn of 46° within one step; a step that lands a sheet edge-first on the ground can
/// have errors of 3 to 8 (a spring's length off by three to eight rest lengths).
pub(crate) const RELINEARIZE_STRAIN: f64 = 0.3;

/// Springs per task when measuring the linearization error.
const SPRINGS: usize = 4096;

/// How far the step's linear model is off: over the stretch springs (mesh edges), the largest
/// difference between a spring's length after the full change `dv` and the length the
/// linearization predicts for it, as a share of its rest length. The linearization point is
/// `x` (the iterate, `x₀` at the first iteration); the full change ends at
/// `x₀ + h (v + dv)`. The prediction is first order: `ℓ + n·δ` with `n` the spring's direction
/// at `x` and `δ` the change of its vector, so a spring that turns without stretching, or a
/// particle pushed along the plane across its spring, has an error (docs/MATH.md §10). The
/// largest value does not depend on the order of the springs, so neither on the threads.
pub(crate) fn linearization_error(
    springs: &Springs,
    x: &[Vec3],
    x0: &[Vec3],
    v: &[Vec3],
    dv: &[Vec3],
    h: f64,
) -> f64 {
    let one = |k: usize| -> f64 {
        if springs.kind[k] != SpringKind::Stretch {
            return 0.0;
        }
        let (i, j) = (springs.i[k] as usize, springs.j[k] as usize);
        let d = x[i] - x[j];
        let end = x0[i] - x0[j] + h * (v[i] + dv[i] - v[j] - dv[j]);
        let l = d.length();
        if !(l > 0.0) {
            return 0.0;
        }
        let predicted = l + d.dot(end - d) / l;
        (end.length() - predicted).abs() / springs.rest[k]
    };
    (0..springs.len())
        .into_par_iter()
        .with_min_len(SPRINGS)
        .map(one)
        .reduce(|| 0.0, f64::max)
}

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

    /// One stretch spring from particle 0 at the origin to particle 1 at `(L, 0, 0)`, moved in
    /// one step of `h = 1` to `b`, particle 0 staying.
    fn error_of_a_spring_moved_to(b: Vec3) -> f64 {
        let mut springs = Springs::default();
        springs.push(1, 0, 0.5, 1.0, 0.0, SpringKind::Stretch);
        let x = [Vec3::ZERO, Vec3::X * 0.5];
        let v = [Vec3::ZERO; 2];
        let dv = [Vec3::ZERO, b - x[1]];
        linearization_error(&springs, &x, &x, &v, &dv, 1.0)
    }

    #[test]
    fn the_linearization_error_of_a_spring_is_its_second_order_change_of_length() {
        let l = 0.5;
        // stretched along itself: the linear model is exact
        assert!(error_of_a_spring_moved_to(Vec3::X * 0.8).abs() < 1e-15);
        // turned by θ about particle 0: the model predicts the length l cos θ, the spring
        // keeps l, so the error is 1 - cos θ
        for theta in [0.1f64, 0.8, 1.5] {
            let b = l * Vec3::new(theta.cos(), theta.sin(), 0.0);
            let e = error_of_a_spring_moved_to(b);
            assert!((e - (1.0 - theta.cos())).abs() < 1e-14, "{theta}: {e}");
        }
        // the end pushed sideways by s: the model predicts no change, the spring grows to
        // √(l² + s²)
        let s = 2.0;
        let e = error_of_a_spring_moved_to(Vec3::new(l, 0.0, s));
        assert!((e - ((l * l + s * s).sqrt() - l) / l).abs() < 1e-14, "{e}");
        // bend and shear springs do not count
        let mut springs = Springs::default();
        springs.push(1, 0, 0.5, 1.0, 0.0, SpringKind::Bend);
        springs.push(1, 0, 0.5, 1.0, 0.0, SpringKind::Shear);
        let x = [Vec3::ZERO, Vec3::X * 0.5];
        let dv = [Vec3::ZERO, Vec3::Z * 3.0];
        assert_eq!(
            linearization_error(&springs, &x, &x, &[Vec3::ZERO; 2], &dv, 1.0),
            0.0
        );
    }

    #[test]
    fn the_linearization_error_is_measured_from_the_iterate() {
        // a later iteration linearizes at x = x₀ + h v: a spring already turned there and
        // changed no further has no error, though it turned since the start of the step
        let mut springs = Springs::default();
        springs.push(1, 0, 1.0, 1.0, 0.0, SpringKind::Stretch);
        let x0 = [Vec3::ZERO, Vec3::X];
        let v = [Vec3::ZERO, Vec3::Y - Vec3::X];
        let x = [Vec3::ZERO, Vec3::Y];
        let dv = [Vec3::ZERO; 2];
        assert_eq!(linearization_error(&springs, &x, &x0, &v, &dv, 1.0), 0.0);
        // from x₀ the same end has the error of a quarter turn
        let e = linearization_error(&springs, &x0, &x0, &[Vec3::ZERO; 2], &v, 1.0);
        assert!((e - 1.0).abs() < 1e-15, "{e}");
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
