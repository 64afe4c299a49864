//! The pose stage: where everything that moves by prescription (colliders, pins) is over the
//! step `[t, t + h]`.
//!
//! Colliders are evaluated at any time by their motion ([`crate::collision::colliders`]), so
//! the stage only records the interval and the bound on their surface speed that the blow-up
//! test allows for; pins have their end-of-step velocity targets (at rest for fixed pins, the
//! chord to the motion's position at `t + h` for handles that hold,
//! [`crate::constraints::handles`]), and `pinned` says which particles the solve filters out
//! during this step.

use crate::constraints::handles::step_targets;
use crate::constraints::pins::PinTargets;
use crate::model::Model;

/// Prescribed motion over one step.
#[derive(Clone, Debug)]
pub(crate) struct Pose {
    /// Start of the step, s.
    pub t0: f64,
    /// Step, s.
    pub h: f64,
    /// End-of-step velocities of moving pins.
    pub pins: PinTargets,
    /// Particles whose velocity is prescribed over this step (fixed pins, held handles).
    pub pinned: Vec<bool>,
    /// Largest linear speed of an obstacle, m/s.
    pub surface_speed: f64,
}

/// The pose of the model's colliders and pins over `[t0, t0 + h]`.
pub(crate) fn at(model: &Model, t0: f64, h: f64) -> Pose {
    let surface_speed = model
        .obstacles
        .iter()
        .map(|o| o.collider.speed_bound(t0, t0 + h).0)
        .fold(0.0, f64::max);
    let (pinned, moving) = step_targets(
        &model.pinned,
        &model.handles,
        &model.obstacles,
        &model.x,
        t0,
        h,
    );
    let surface_speed = moving
        .iter()
        .map(|(_, v)| v.length())
        .fold(surface_speed, f64::max);
    Pose {
        t0,
        h,
        pins: PinTargets { moving },
        pinned,
        surface_speed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[allow(unused_imports)]
    use crate::collision::colliders::{
        Capsule, Collider, Cuboid, Motion, Plane, Shape, Sphere, TriangleMesh,
    };
    use crate::collision::settings::Obstacle;
    use crate::math::Vec3;
    use crate::step::testing;

    #[test]
    fn the_surface_speed_is_the_fastest_collider_and_fixed_pins_have_no_target() {
        let mut m = testing::sheet_on_ground(3, 0.5);
        assert_eq!(at(&m, 0.0, 0.01).surface_speed, 0.0);
        m.obstacles.push(Obstacle {
            name: None,
            collider: Collider {
                shape: Shape::Sphere(Sphere {
                    center: Vec3::ZERO,
                    radius: 0.1,
                }),
                motion: Motion::Constant {
                    velocity: Vec3::new(3.0, 4.0, 0.0),
                    angular_velocity: Vec3::ZERO,
                },
            },
            friction: 0.0,
        });
        let p = at(&m, 1.5, 0.01);
        assert_eq!((p.t0, p.h, p.surface_speed), (1.5, 0.01, 5.0));
        assert!(p.pins.moving.is_empty());
    }
}
