//! Prescribed motion: how colliders and handles move over time.
//!
//! [`motion::Motion`] is one type for everything that moves by prescription: fixed, constant
//! velocity, or keyframed (a track of poses sampled at any time).

pub mod motion;

pub use motion::Motion;
