//! Pins: particles whose velocity over the step is prescribed.
//!
//! A pinned particle is filtered out of the solve (`S = 0`) and `z` takes its velocity to its
//! target: at rest for a fixed pin (it ends the step exactly where it started), or the velocity
//! that carries it to where a moving pin puts it at the end of the step.

use super::Constraints;
use crate::math::{Mat3, Vec3};
use rayon::prelude::*;

/// Particles per task in the per-particle parallel loops.
const PARTICLES: usize = 1024;

/// The end-of-step velocities of the pins that move during a step. Pins not listed stay at rest.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PinTargets {
    /// `(particle, velocity)` of each moving pin, by increasing particle.
    pub moving: Vec<(u32, Vec3)>,
}

/// Sets `c` to the pins alone: `S = 0` and `z` to the target for every pinned particle,
/// `S = I` and `z = 0` for the others, from the current velocities `v`.
pub fn apply(pinned: &[bool], targets: &PinTargets, v: &[Vec3], c: &mut Constraints) {
    c.z.par_iter_mut()
        .zip(c.filter.par_iter_mut())
        .enumerate()
        .with_min_len(PARTICLES)
        .for_each(|(i, (zi, si))| {
            (*zi, *si) = if pinned[i] {
                // a fixed pin ends the step at rest
                (-v[i], Mat3::ZERO)
            } else {
                (Vec3::ZERO, Mat3::IDENTITY)
            };
        });
    for &(i, target) in &targets.moving {
        let i = i as usize;
        c.z[i] = target - v[i];
    }
}

/// The velocity filter of the pins alone: `0` for a pinned particle, `I` otherwise.
pub fn filter(pinned: &[bool]) -> Vec<Mat3> {
    pinned
        .iter()
        .map(|&p| if p { Mat3::ZERO } else { Mat3::IDENTITY })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pinned_particles_reach_their_target_velocity_whatever_the_solve_gives() {
        let pinned = [true, false, true];
        let v = [Vec3::new(1.0, 2.0, 3.0), Vec3::X, Vec3::new(-0.5, 0.0, 4.0)];
        let targets = PinTargets {
            moving: vec![(2, Vec3::new(0.0, 1.5, 0.0))],
        };
        let mut c = Constraints::free(3);
        apply(&pinned, &targets, &v, &mut c);
        let y = Vec3::new(9.0, -9.0, 9.0);
        let new = |i: usize| v[i] + c.z[i] + c.filter[i] * y;
        assert_eq!(new(0), Vec3::ZERO);
        assert_eq!(new(2), Vec3::new(0.0, 1.5, 0.0));
        assert_eq!(new(1), v[1] + y);
    }
}
