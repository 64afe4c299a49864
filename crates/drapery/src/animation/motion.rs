//! [`Motion`]: a rigid motion over time, about a center `c` given by its owner (a collider's
//! center, a handle's pivot).
//!
//! A material point at `x` at `t = 0` is at `c + T(t) + R(t) (x - c)` at time `t`: rotation
//! `R(t)` about the center, then translation `T(t)`. Its velocity is `T'(t) + ω(t) × (p - c(t))`
//! with `c(t) = c + T(t)` and `ω` the angular velocity (`R' = [ω]× R`).
//!
//! * `Fixed`: `T = 0`, `R = I`.
//! * `Constant`: `T = v t`, `R = exp(ω t)` (rotation by `|ω| t` about `ω/|ω|`).
//! * `Keyframed`: `T` and `R` from a [`Track`] (holding its first pose before the first key
//!   and its last after the last).
//!
//! Before `t = 0` (a pre-roll) every motion holds its pose at 0, at rest.

use super::keyframes::Track;
use crate::error::Result;
use crate::fingerprint::Fnv;
use crate::math::Vec3;
use glam::DQuat;

/// A rigid motion over time (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Motion {
    /// Does not move.
    #[default]
    Fixed,
    /// Constant linear velocity of the center and constant angular velocity about it.
    Constant {
        /// Velocity of the center, m/s.
        velocity: Vec3,
        /// Angular velocity about the center, rad/s (axis × rate).
        angular_velocity: Vec3,
    },
    /// Poses from keyframes.
    Keyframed(Track),
}

impl Motion {
    /// Constant motion; `Fixed` when both velocities are zero.
    pub fn constant(velocity: Vec3, angular_velocity: Vec3) -> Motion {
        if velocity == Vec3::ZERO && angular_velocity == Vec3::ZERO {
            Motion::Fixed
        } else {
            Motion::Constant {
                velocity,
                angular_velocity,
            }
        }
    }

    /// Checks that every number is finite; `field` names the owner (`collider[0]`).
    pub fn validate(&self, field: &str) -> Result<()> {
        if let Motion::Constant {
            velocity,
            angular_velocity,
        } = self
        {
            crate::validate::finite3(&format!("{field}.velocity"), *velocity)?;
            crate::validate::finite3(&format!("{field}.angular_velocity"), *angular_velocity)?;
        }
        Ok(())
    }

    /// `(R(t), T(t))`.
    pub fn pose(&self, t: f64) -> (DQuat, Vec3) {
        match self {
            Motion::Fixed => (DQuat::IDENTITY, Vec3::ZERO),
            Motion::Constant {
                velocity,
                angular_velocity,
            } => {
                let t = t.max(0.0);
                (
                    DQuat::from_scaled_axis(*angular_velocity * t),
                    *velocity * t,
                )
            }
            Motion::Keyframed(track) => {
                let (tr, rot) = track.sample(t);
                (rot, tr)
            }
        }
    }

    /// `(T'(t), ω(t))`.
    pub fn velocity(&self, t: f64) -> (Vec3, Vec3) {
        match self {
            Motion::Fixed => (Vec3::ZERO, Vec3::ZERO),
            Motion::Constant { .. } if t < 0.0 => (Vec3::ZERO, Vec3::ZERO),
            Motion::Constant {
                velocity,
                angular_velocity,
            } => (*velocity, *angular_velocity),
            Motion::Keyframed(track) => track.velocity(t),
        }
    }

    /// Upper bounds on `|T'|` and `|ω|` over `[t0, t1]`.
    pub fn speed_bound(&self, t0: f64, t1: f64) -> (f64, f64) {
        match self {
            Motion::Keyframed(track) => track.speed_bound(t0, t1),
            _ => {
                let (v, w) = self.velocity(t0.max(t1));
                (v.length(), w.length())
            }
        }
    }

    /// True when the motion is not `Fixed`.
    pub fn moves(&self) -> bool {
        !matches!(self, Motion::Fixed)
    }

    /// Feeds the motion to a fingerprint (a fixed or constant motion as its two velocities,
    /// keyframes as their times, poses and interpolation).
    // (not `std::hash::Hash`: a fingerprint of the exact bits, the same on every platform)
    #[allow(clippy::should_implement_trait)]
    pub fn hash(&self, h: &mut Fnv) {
        let vec = |h: &mut Fnv, x: Vec3| {
            for k in 0..3 {
                h.u64(x[k].to_bits());
            }
        };
        match self {
            Motion::Keyframed(track) => {
                h.bytes(b"keyframes")
                    .bytes(track.interpolation().name().as_bytes());
                for k in track.keys() {
                    h.u64(k.time.to_bits());
                    vec(h, k.translation);
                    for q in k.rotation.to_array() {
                        h.u64(q.to_bits());
                    }
                }
            }
            _ => {
                let (v, w) = self.velocity(0.0);
                vec(h, v);
                vec(h, w);
            }
        }
    }

    /// `, velocity [..] m/s, angular_velocity [..] rad/s` for one-line descriptions ("" when
    /// fixed).
    pub fn describe(&self) -> String {
        let v3 = |p: Vec3| format!("[{}, {}, {}]", p.x, p.y, p.z);
        let mut s = String::new();
        if let Motion::Keyframed(track) = self {
            s.push_str(&format!(
                ", {} {} keyframes from {} s to {} s",
                track.keys().len(),
                track.interpolation().name(),
                track.first_time(),
                track.last_time()
            ));
        }
        if let Motion::Constant {
            velocity,
            angular_velocity,
        } = self
        {
            if *velocity != Vec3::ZERO {
                s.push_str(&format!(", velocity {} m/s", v3(*velocity)));
            }
            if *angular_velocity != Vec3::ZERO {
                s.push_str(&format!(
                    ", angular_velocity {} rad/s",
                    v3(*angular_velocity)
                ));
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_motion_turns_and_translates_and_its_velocity_is_the_derivative() {
        let m = Motion::constant(Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 2.0));
        let (r, tr) = m.pose(0.25);
        assert_eq!(tr, Vec3::new(0.25, 0.0, 0.0));
        // 0.5 rad about z
        assert!((r * Vec3::X - Vec3::new(0.5f64.cos(), 0.5f64.sin(), 0.0)).length() < 1e-15);
        // central difference of a material point's path against T' + ω × (p - c(t))
        let x0 = Vec3::new(0.3, -0.2, 0.7);
        let at = |t: f64| {
            let (r, tr) = m.pose(t);
            tr + r * x0
        };
        let (t, d) = (0.4, 1e-6);
        let fd = (at(t + d) - at(t - d)) / (2.0 * d);
        let (v, w) = m.velocity(t);
        let (_, tr) = m.pose(t);
        assert!((fd - (v + w.cross(at(t) - tr))).length() < 1e-8);
        assert_eq!(Motion::constant(Vec3::ZERO, Vec3::ZERO), Motion::Fixed);
        assert_eq!(m.speed_bound(0.0, 1.0), (1.0, 2.0));
        // before t = 0 (a pre-roll) it holds its pose at 0, at rest
        assert_eq!(m.pose(-0.5), m.pose(0.0));
        assert_eq!(m.velocity(-0.5), (Vec3::ZERO, Vec3::ZERO));
        assert_eq!(m.speed_bound(-0.5, -0.1), (0.0, 0.0));
        let bad = Motion::Constant {
            velocity: Vec3::new(0.0, f64::NAN, 0.0),
            angular_velocity: Vec3::ZERO,
        };
        let e = bad.validate("collider[3]").unwrap_err().to_string();
        assert!(e.starts_with("collider[3].velocity: must be finite"), "{e}");
    }
}
