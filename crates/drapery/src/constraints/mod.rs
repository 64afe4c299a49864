//! The velocity filter `S` and the prescribed velocity changes `z` of each solve
//! (docs/MATH.md §5): Baraff & Witkin's way of enforcing constraints exactly inside PCG.
//!
//! A particle's filter `Sᵢ` removes the directions in which its velocity change is prescribed,
//! and `zᵢ` is the prescribed part: the solve finds `Δv = z + S y` (pinned particle: `S = 0`,
//! `z` takes it to its target velocity; a particle held against an obstacle: `S = I - n nᵀ`,
//! `z` sets its normal velocity). [`Constraints`] holds both for one solve; [`pins`] and
//! [`obstacle`] write into it: pins first, then the obstacle contacts the active set holds.

pub mod handles;
pub mod obstacle;
pub mod pins;
pub mod strain_limit;

use crate::math::{Mat3, Vec3};

/// The filter and prescribed velocity change of every particle for one solve.
#[derive(Clone, Debug, Default)]
pub struct Constraints {
    /// `Sᵢ`: identity for a free particle, zero for a pinned one, `I - n nᵀ` against an obstacle.
    pub filter: Vec<Mat3>,
    /// `zᵢ`: the prescribed part of the velocity change (zero where `Sᵢ = I`).
    pub z: Vec<Vec3>,
}

impl Constraints {
    /// Constraints of `n` free particles.
    pub fn free(n: usize) -> Constraints {
        Constraints {
            filter: vec![Mat3::IDENTITY; n],
            z: vec![Vec3::ZERO; n],
        }
    }

    /// Frees particle `i`.
    pub fn release(&mut self, i: usize) {
        self.filter[i] = Mat3::IDENTITY;
        self.z[i] = Vec3::ZERO;
    }

    /// Prescribes the component of particle `i`'s new velocity along unit `n` to be `target`,
    /// from its current velocity `v`: `S = I - n nᵀ`, `z = n (target - n·v)`.
    pub fn hold_normal(&mut self, i: usize, n: Vec3, target: f64, v: Vec3) {
        self.filter[i] = crate::math::tangent_projector(n);
        self.z[i] = n * (target - n.dot(v));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_held_normal_leaves_the_tangent_free_and_sets_the_normal_speed() {
        let mut c = Constraints::free(2);
        let n = Vec3::new(0.6, 0.8, 0.0);
        let v = Vec3::new(1.0, -2.0, 0.5);
        c.hold_normal(1, n, 0.25, v);
        // any y: the new velocity v + z + S y has normal part exactly 0.25
        for y in [Vec3::X, Vec3::new(-3.0, 7.0, 2.0), Vec3::ZERO] {
            let dv = c.z[1] + c.filter[1] * y;
            assert!(((v + dv).dot(n) - 0.25).abs() < 1e-14);
            // and the tangential part of y passes unchanged
            let t = y - n * n.dot(y);
            assert!((c.filter[1] * y - t).length() < 1e-14);
        }
        assert_eq!((c.filter[0], c.z[0]), (Mat3::IDENTITY, Vec3::ZERO));
        c.release(1);
        assert_eq!((c.filter[1], c.z[1]), (Mat3::IDENTITY, Vec3::ZERO));
    }
}
