//! The pose stage: where everything that moves by prescription (colliders, pins) is over the
//! step `[t, t + h]`.
//!
//! Colliders are evaluated at any time by their motion ([`crate::collision::colliders`]), so
//! the stage only records the interval and the bound on their surface speed that the blow-up
//! test allows for; pins have their end-of-step velocity targets (at rest for fixed pins).

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
    /// Largest linear speed of an obstacle, m/s.
    pub surface_speed: f64,
}

/// The pose of the model's colliders and pins over `[t0, t0 + h]`.
pub(crate) fn at(model: &Model, t0: f64, h: f64) -> Pose {
    let surface_speed = model
        .obstacles
        .iter()
        .map(|o| o.collider.motion.velocity.length())
        .fold(0.0, f64::max);
    Pose {
        t0,
        h,
        pins: PinTargets::default(),
        surface_speed,
    }
}
