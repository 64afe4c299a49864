//! Prescribed motion over time: keyframe tracks of rigid poses (translation and rotation).
//!
//! A [`Track`] is a list of [`Keyframe`]s interpolated linearly or smoothly
//! ([`Interpolation`]); it gives the pose at any time, its exact time derivatives, and
//! true upper bounds on its speeds over an interval (for conservative advancement in collision
//! sweeps). The equations are in `docs/MATH.md §19`.

pub mod keyframes;

pub use keyframes::{Interpolation, Keyframe, Track};
