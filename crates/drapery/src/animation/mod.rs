//! Prescribed motion: how colliders and handles move over time.
//!
//! [`Motion`] is one type for everything that moves by prescription: fixed, constant velocity,
//! or keyframed. A [`Track`] is a list of [`Keyframe`]s interpolated linearly or smoothly
//! ([`Interpolation`]); it gives the pose at any time, its exact time derivatives, and true
//! upper bounds on its speeds over an interval (for conservative advancement in collision
//! sweeps). The equations are in `docs/MATH.md §19`.

pub mod keyframes;
pub mod motion;

pub use keyframes::{Interpolation, Keyframe, Track};
pub use motion::Motion;
