//! Keyframe tracks: a rigid pose `(translation, rotation)` as a function of time, given at
//! keys and interpolated between them (`docs/MATH.md §19`).
//!
//! - [`Interpolation::Linear`]: translation lerp, rotation slerp along the shorter arc; the
//!   velocities are constant on each segment.
//! - [`Interpolation::Smooth`]: C¹ everywhere, holds included. Translation is a cubic Hermite
//!   per segment with non-uniform Catmull-Rom tangents at interior keys and zero tangents at the
//!   first and last key. Rotation is `R(t) = Exp(φ(t)) R_i` on segment `i`: `φ` is a cubic
//!   Hermite in the rotation vectors about key `i`, from `0` to the slerp's rotation vector
//!   `φ_i = Log(R_{i+1} R_iᵀ)`, whose end tangents are chosen so that the world angular velocity
//!   is continuous at the keys. With zero end tangents (a two-key track) it is the slerp
//!   with an eased parameter.
//!
//! Before the first key the pose is the first key's, after the last the last's, and the
//! velocities there are zero. At a key the velocity is that of the segment that starts there.
//!
//! Everything a [`Track`] evaluates per call ([`Track::sample`], [`Track::velocity`]) is
//! precomputed per segment by [`Track::new`]: a call is a binary search and a few dozen flops,
//! no allocation.

use glam::DQuat;

use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::validate;

/// A pose at a time: where the body's origin is and how it is turned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Keyframe {
    /// Time of the key (s).
    pub time: f64,
    /// Translation at that time (m).
    pub translation: Vec3,
    /// Rotation at that time, a quaternion (normalized by [`Track::new`]).
    pub rotation: DQuat,
}

impl Keyframe {
    /// The identity pose (no translation, no rotation) at `time`.
    pub fn at(time: f64) -> Keyframe {
        Keyframe {
            time,
            translation: Vec3::ZERO,
            rotation: DQuat::IDENTITY,
        }
    }
}

/// How a [`Track`] goes from one key to the next.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Interpolation {
    /// Translation lerp, rotation slerp along the shorter arc; velocity piecewise constant.
    #[default]
    Linear,
    /// C¹ in translation (Catmull-Rom, zero tangents at the ends) and in rotation.
    Smooth,
}

impl Interpolation {
    /// The names a scene may give, in the order of the variants.
    pub const NAMES: [&'static str; 2] = ["linear", "smooth"];

    /// Parses a scene's name for an interpolation; `field` names the field in the error.
    pub fn parse(s: &str, field: &str) -> Result<Interpolation> {
        match s {
            "linear" => Ok(Interpolation::Linear),
            "smooth" => Ok(Interpolation::Smooth),
            _ => Err(Error::field(
                field,
                format!("must be \"linear\" or \"smooth\", got \"{s}\""),
            )),
        }
    }

    /// The scene's name for this interpolation.
    pub fn name(self) -> &'static str {
        match self {
            Interpolation::Linear => Self::NAMES[0],
            Interpolation::Smooth => Self::NAMES[1],
        }
    }
}

/// A cubic Hermite curve in a segment's parameter `s ∈ [0, 1]`: values `v0`, `v1` and
/// derivatives (per unit `s`) `d0`, `d1` at its ends. Its derivative is the quadratic Bézier
/// with control vectors `d0`, `dm = 3 (v1 - v0) - d0 - d1`, `d1`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Hermite {
    v0: Vec3,
    v1: Vec3,
    d0: Vec3,
    dm: Vec3,
    d1: Vec3,
}

impl Hermite {
    fn new(v0: Vec3, v1: Vec3, d0: Vec3, d1: Vec3) -> Hermite {
        Hermite {
            v0,
            v1,
            d0,
            dm: 3.0 * (v1 - v0) - d0 - d1,
            d1,
        }
    }

    /// The value at `s`: the chord for [`Interpolation::Linear`], the cubic otherwise.
    #[inline]
    fn value(&self, s: f64, interpolation: Interpolation) -> Vec3 {
        let chord = self.v1 - self.v0;
        match interpolation {
            Interpolation::Linear => self.v0 + chord * s,
            Interpolation::Smooth => {
                let s2 = s * s;
                let s3 = s2 * s;
                let h01 = 3.0 * s2 - 2.0 * s3;
                let h10 = s3 - 2.0 * s2 + s;
                let h11 = s3 - s2;
                self.v0 + chord * h01 + self.d0 * h10 + self.d1 * h11
            }
        }
    }

    /// The derivative with respect to `s` at `s` (smooth: the Bézier form).
    #[inline]
    fn derivative(&self, s: f64, interpolation: Interpolation) -> Vec3 {
        match interpolation {
            Interpolation::Linear => self.v1 - self.v0,
            Interpolation::Smooth => self.blossom(s, s),
        }
    }

    /// The blossom of the derivative: `blossom(s, s)` is the derivative at `s`, and
    /// `blossom(a, a)`, `blossom(a, b)`, `blossom(b, b)` are the Bézier control vectors of its
    /// restriction to `[a, b]`.
    #[inline]
    fn blossom(&self, a: f64, b: f64) -> Vec3 {
        let (ra, rb) = (1.0 - a, 1.0 - b);
        self.d0 * (ra * rb) + self.dm * (ra * b + a * rb) + self.d1 * (a * b)
    }

    /// An upper bound on `|derivative(s)|` of the smooth curve for `s ∈ [a, b] ⊂ [0, 1]`: the
    /// largest control vector of the restriction to each quarter of `[a, b]` (the derivative
    /// lies in their convex hull, where the norm is largest at a vertex), widened by a few
    /// roundings.
    fn derivative_bound(&self, a: f64, b: f64) -> f64 {
        const PIECES: usize = 4;
        let at = |k: usize| {
            if k == PIECES {
                b
            } else {
                a + (b - a) * (k as f64 / PIECES as f64)
            }
        };
        let mut most = 0.0f64;
        for k in 0..PIECES {
            let (u, w) = (at(k), at(k + 1));
            for c in [self.blossom(u, u), self.blossom(u, w), self.blossom(w, w)] {
                most = most.max(c.length());
            }
        }
        let scale = self.d0.length() + self.dm.length() + self.d1.length();
        most * (1.0 + 1e-12) + scale * 1e-14
    }
}

/// One segment between keys `i` and `i + 1`, in `s = (t - t0) / dt`.
#[derive(Clone, Debug, PartialEq)]
struct Segment {
    t0: f64,
    dt: f64,
    /// The translation.
    translation: Hermite,
    /// The rotation vector `φ(s)` about the start key: `R(s) = Exp(φ(s)) R_i`, `φ(0) = 0`,
    /// `φ(1) = Log(R_{i+1} R_iᵀ)`.
    rotation: Hermite,
    /// The start key's rotation, on the same hemisphere as the keys before it.
    q0: DQuat,
}

impl Segment {
    #[inline]
    fn pose(&self, s: f64, interpolation: Interpolation) -> (Vec3, DQuat) {
        let phi = self.rotation.value(s, interpolation);
        (
            self.translation.value(s, interpolation),
            (exp(phi) * self.q0).normalize(),
        )
    }

    #[inline]
    fn velocity(&self, s: f64, interpolation: Interpolation) -> (Vec3, Vec3) {
        let v = self.translation.derivative(s, interpolation) / self.dt;
        let dphi = self.rotation.derivative(s, interpolation);
        let w = match interpolation {
            // φ(s) = s φ_i is parallel to φ_i, which J_l(φ) leaves as it is
            Interpolation::Linear => dphi / self.dt,
            Interpolation::Smooth => {
                left_jacobian(self.rotation.value(s, interpolation), dphi) / self.dt
            }
        };
        (v, w)
    }
}

/// Where a time falls on a track.
enum Place<'a> {
    Before,
    After,
    On(&'a Segment, f64),
}

/// The path of a track's keys in errors: `FIELD.keyframes`, or `keyframes` without a field.
fn keys_field(field: &str) -> String {
    if field.is_empty() {
        "keyframes".to_string()
    } else {
        format!("{field}.keyframes")
    }
}

/// A validated keyframe track. See the module docs.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    keys: Vec<Keyframe>,
    interpolation: Interpolation,
    segments: Vec<Segment>,
}

impl Track {
    /// Validates and normalizes the keys and precomputes the segments. `field` is the path
    /// prefix for errors: with `"collider[0]"` an error names `collider[0].keyframes[2].time`.
    ///
    /// Times must be finite and strictly increasing, translations finite, rotations finite and
    /// nonzero; there must be at least one key. Rotations are normalized, and each is flipped
    /// (`q → -q`, the same rotation) onto the hemisphere of the one before it.
    pub fn new(keys: Vec<Keyframe>, interpolation: Interpolation, field: &str) -> Result<Track> {
        let base = keys_field(field);
        if keys.is_empty() {
            return Err(Error::field(base, "must have at least one key, got none"));
        }
        let mut keys = keys;
        for i in 0..keys.len() {
            let at = |name: &str| format!("{base}[{i}].{name}");
            let k = keys[i];
            if !k.time.is_finite() {
                return Err(Error::field(
                    at("time"),
                    format!("must be a finite number, got {}", k.time),
                ));
            }
            if i > 0 && k.time <= keys[i - 1].time {
                return Err(Error::field(
                    at("time"),
                    format!(
                        "must be greater than the time of the key before it ({}), got {}",
                        keys[i - 1].time,
                        k.time
                    ),
                ));
            }
            validate::finite3(&at("translation"), k.translation)?;
            let mut q = unit_quaternion(&at("rotation"), k.rotation)?;
            if i > 0 && q.dot(keys[i - 1].rotation) < 0.0 {
                q = -q;
            }
            keys[i].rotation = q;
        }
        let segments = segments(&keys, interpolation);
        Ok(Track {
            keys,
            interpolation,
            segments,
        })
    }

    /// A track of keys that are already a track's ([`Track::keys`]), rotations as they are:
    /// [`Track::new`] would normalize them again, which may change their last bits (a
    /// snapshot restores a track with it, [`crate::snapshot`]). The errors of [`Track::new`],
    /// and one for a rotation that is not already unit and on its predecessor's hemisphere
    /// (within `1e-12`).
    pub(crate) fn from_normalized(
        keys: Vec<Keyframe>,
        interpolation: Interpolation,
        field: &str,
    ) -> Result<Track> {
        let normalized = Track::new(keys.clone(), interpolation, field)?;
        for (i, (k, n)) in keys.iter().zip(normalized.keys()).enumerate() {
            if !((k.rotation - n.rotation).length() <= 1e-12) {
                return Err(Error::field(
                    format!("{}[{i}].rotation", keys_field(field)),
                    "must be a track's normalized rotation",
                ));
            }
        }
        let segments = segments(&keys, interpolation);
        Ok(Track {
            keys,
            interpolation,
            segments,
        })
    }

    /// The keys, normalized: unit rotations, each on the hemisphere of the one before it.
    pub fn keys(&self) -> &[Keyframe] {
        &self.keys
    }

    /// How the track interpolates between keys.
    pub fn interpolation(&self) -> Interpolation {
        self.interpolation
    }

    /// Time of the first key.
    pub fn first_time(&self) -> f64 {
        self.keys[0].time
    }

    /// Time of the last key.
    pub fn last_time(&self) -> f64 {
        self.keys[self.keys.len() - 1].time
    }

    /// The segment and its parameter at `t`; `t` at a key falls at the start of the segment
    /// that starts there. NaN counts as before the first key.
    #[inline]
    fn place(&self, t: f64) -> Place<'_> {
        if t.is_nan() || t < self.first_time() {
            return Place::Before;
        }
        if t >= self.last_time() {
            return Place::After;
        }
        // first_time ≤ t < last_time: 1 ≤ i ≤ n - 1
        let i = self.keys.partition_point(|k| k.time <= t);
        let seg = &self.segments[i - 1];
        Place::On(seg, ((t - seg.t0) / seg.dt).clamp(0.0, 1.0))
    }

    /// Pose at time `t`: (translation, unit rotation).
    pub fn sample(&self, t: f64) -> (Vec3, DQuat) {
        let key = |k: &Keyframe| (k.translation, k.rotation);
        match self.place(t) {
            Place::Before => key(&self.keys[0]),
            Place::After => key(&self.keys[self.keys.len() - 1]),
            Place::On(seg, s) => seg.pose(s, self.interpolation),
        }
    }

    /// Time derivatives at `t`: (d translation / dt, angular velocity `ω` in the world frame,
    /// `dR/dt = [ω]× R`). Zero before the first key and from the last key on; at a key, those
    /// of the segment that starts there.
    pub fn velocity(&self, t: f64) -> (Vec3, Vec3) {
        match self.place(t) {
            Place::Before | Place::After => (Vec3::ZERO, Vec3::ZERO),
            Place::On(seg, s) => seg.velocity(s, self.interpolation),
        }
    }

    /// Upper bounds on `|d translation / dt|` and `|ω|` over `[t0, t1]` (the ends in either
    /// order): every [`Track::velocity`] at a time in the interval is within them. Exact for
    /// linear tracks; for smooth ones a few percent above the true maximum (`docs/MATH.md §19`).
    /// A NaN end gives infinite bounds.
    pub fn speed_bound(&self, t0: f64, t1: f64) -> (f64, f64) {
        if t0.is_nan() || t1.is_nan() {
            return (f64::INFINITY, f64::INFINITY);
        }
        let (lo, hi) = (t0.min(t1), t0.max(t1));
        let mut bound = (0.0f64, 0.0f64);
        for seg in &self.segments {
            // the times whose velocity this segment gives: [t0, t0 + dt)
            if seg.t0 > hi || seg.t0 + seg.dt <= lo {
                continue;
            }
            let a = ((lo - seg.t0) / seg.dt).clamp(0.0, 1.0);
            let b = ((hi - seg.t0) / seg.dt).clamp(0.0, 1.0);
            let (v, w) = match self.interpolation {
                // the very expression `velocity` evaluates: constant on the segment
                Interpolation::Linear => {
                    let (v, w) = seg.velocity(a, Interpolation::Linear);
                    (v.length(), w.length())
                }
                // |ω| = |J_l(φ) φ'| / dt ≤ |φ'| / dt: the left Jacobian's singular values are
                // 1 and 2 |sin(θ/2)| / θ ≤ 1
                Interpolation::Smooth => (
                    seg.translation.derivative_bound(a, b) / seg.dt,
                    seg.rotation.derivative_bound(a, b) / seg.dt,
                ),
            };
            bound = (bound.0.max(v), bound.1.max(w));
        }
        bound
    }
}

/// The segments of validated keys (hemisphere-consistent unit rotations).
fn segments(keys: &[Keyframe], interpolation: Interpolation) -> Vec<Segment> {
    let n = keys.len();
    // rotation vector of each segment, R_{i+1} = Exp(φ_i) R_i
    let phis: Vec<Vec3> = keys
        .windows(2)
        .map(|w| log(w[1].rotation * w[0].rotation.conjugate()))
        .collect();
    // per-time tangents at the keys: zero at the ends, Catmull-Rom in between
    let tangent = |i: usize| -> (Vec3, Vec3) {
        if i == 0 || i == n - 1 || interpolation == Interpolation::Linear {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        let span = keys[i + 1].time - keys[i - 1].time;
        (
            (keys[i + 1].translation - keys[i - 1].translation) / span,
            (phis[i - 1] + phis[i]) / span,
        )
    };
    (0..n.saturating_sub(1))
        .map(|i| {
            let (k0, k1) = (&keys[i], &keys[i + 1]);
            let dt = k1.time - k0.time;
            let phi = phis[i];
            let (translation, rotation) = match interpolation {
                Interpolation::Linear => {
                    let (dp, dphi) = (k1.translation - k0.translation, phi);
                    (
                        Hermite::new(k0.translation, k1.translation, dp, dp),
                        Hermite::new(Vec3::ZERO, phi, dphi, dphi),
                    )
                }
                Interpolation::Smooth => {
                    let ((v0, w0), (v1, w1)) = (tangent(i), tangent(i + 1));
                    (
                        Hermite::new(k0.translation, k1.translation, v0 * dt, v1 * dt),
                        // at s = 1, ω = J_l(φ_i) φ'(1) / dt must be w1
                        Hermite::new(
                            Vec3::ZERO,
                            phi,
                            w0 * dt,
                            left_jacobian_inverse(phi, w1 * dt),
                        ),
                    )
                }
            };
            Segment {
                t0: k0.time,
                dt,
                translation,
                rotation,
                q0: k0.rotation,
            }
        })
        .collect()
}

/// `q / |q|`, or an error naming `field` when `q` is not finite or is zero.
fn unit_quaternion(field: &str, q: DQuat) -> Result<DQuat> {
    let shown = || format!("[{}, {}, {}, {}]", q.x, q.y, q.z, q.w);
    if !q.is_finite() {
        return Err(Error::field(
            field,
            format!("must be a finite quaternion [x, y, z, w], got {}", shown()),
        ));
    }
    let len = q.length();
    let u = q / len;
    if len == 0.0 || !u.is_finite() {
        return Err(Error::field(
            field,
            format!(
                "must be a nonzero quaternion [x, y, z, w] (it is normalized), got {}",
                shown()
            ),
        ));
    }
    Ok(u)
}

/// `sin(x) / x`.
#[inline]
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        1.0 - x * x / 6.0
    } else {
        x.sin() / x
    }
}

/// The unit quaternion of the rotation by the rotation vector `phi` (angle `|phi|` about
/// `phi / |phi|`).
#[inline]
fn exp(phi: Vec3) -> DQuat {
    let half = 0.5 * phi.length();
    let v = phi * (0.5 * sinc(half));
    DQuat::from_xyzw(v.x, v.y, v.z, half.cos())
}

/// The rotation vector of a unit quaternion, angle in `[0, π]` (`q` and `-q` give the same).
fn log(q: DQuat) -> Vec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let v = Vec3::new(q.x, q.y, q.z);
    let s = v.length();
    // angle / s = 2 atan2(s, w) / s, → 2 / w as s → 0 (relative error s² / 3)
    let factor = if s < 1e-8 {
        2.0 / q.w
    } else {
        2.0 * s.atan2(q.w) / s
    };
    v * factor
}

/// `J_l(φ) v`: the left Jacobian of SO(3), `d/dt Exp(φ) = [J_l(φ) φ̇]× Exp(φ)`, with
/// `J_l = I + (1 - cos θ)/θ² [φ]× + (θ - sin θ)/θ³ [φ]×²`, `θ = |φ|`.
#[inline]
fn left_jacobian(phi: Vec3, v: Vec3) -> Vec3 {
    let theta = phi.length();
    let half_sinc = sinc(0.5 * theta);
    let a = 0.5 * half_sinc * half_sinc; // (1 - cos θ)/θ² = 2 sin²(θ/2)/θ²
    let t2 = theta * theta;
    let b = if theta < 0.1 {
        1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0 - t2 * t2 * t2 / 362_880.0
    } else {
        (theta - theta.sin()) / (t2 * theta)
    };
    let c = phi.cross(v);
    v + a * c + b * phi.cross(c)
}

/// `J_l(φ)⁻¹ v = v - ½ φ × v + (1/θ² - cot(θ/2) / (2θ)) φ × (φ × v)`, for `θ = |φ| ≤ π`.
fn left_jacobian_inverse(phi: Vec3, v: Vec3) -> Vec3 {
    let theta = phi.length();
    let t2 = theta * theta;
    let k = if theta < 0.1 {
        1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30_240.0 + t2 * t2 * t2 / 1_209_600.0
    } else {
        let half = 0.5 * theta;
        1.0 / t2 - half.cos() / (half.sin() * 2.0 * theta)
    };
    let c = phi.cross(v);
    v - 0.5 * c + k * phi.cross(c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::f64::consts::PI;

    const BOTH: [Interpolation; 2] = [Interpolation::Linear, Interpolation::Smooth];

    fn key(time: f64, translation: [f64; 3], rotation: DQuat) -> Keyframe {
        Keyframe {
            time,
            translation: Vec3::from(translation),
            rotation,
        }
    }

    /// `|a - b|` for rotations: 0 when `a = ±b`.
    fn rot_dist(a: DQuat, b: DQuat) -> f64 {
        let (a, b) = (a.normalize(), b.normalize());
        (a - b).length().min((a + b).length())
    }

    /// Angular velocity by central differences of `sample`: `ω = 2 vec(q̇ q̄)`.
    fn fd_omega(tr: &Track, t: f64, d: f64) -> Vec3 {
        let (qp, qm, q) = (tr.sample(t + d).1, tr.sample(t - d).1, tr.sample(t).1);
        let dq = (qp - qm) * (1.0 / (2.0 * d));
        let w = dq * q.conjugate();
        2.0 * Vec3::new(w.x, w.y, w.z)
    }

    fn fd_velocity(tr: &Track, t: f64, d: f64) -> Vec3 {
        (tr.sample(t + d).0 - tr.sample(t - d).0) / (2.0 * d)
    }

    /// Random keys: increasing times with steps in `[0.5, 2]`, translations in the unit cube,
    /// rotations within `max_angle` (per component of the rotation vector) of the identity,
    /// unnormalized (length in `[0.5, 2]`) and of random sign.
    fn arb_keys(max_angle: f64) -> impl Strategy<Value = Vec<Keyframe>> {
        let one = (
            0.5..2.0f64,
            prop::array::uniform3(-1.0..1.0f64),
            prop::array::uniform3(-max_angle..max_angle),
            0.5..2.0f64,
            any::<bool>(),
        );
        (-1.0..1.0f64, prop::collection::vec(one, 2..7)).prop_map(|(start, raw)| {
            let mut t = start;
            raw.into_iter()
                .map(|(step, p, r, scale, flip)| {
                    t += step;
                    let q = exp(Vec3::from(r)) * if flip { -scale } else { scale };
                    key(t, p, q)
                })
                .collect()
        })
    }

    fn interior_times(tr: &Track, fractions: &[f64]) -> Vec<f64> {
        let k = tr.keys();
        k.windows(2)
            .flat_map(|w| {
                fractions
                    .iter()
                    .map(move |f| w[0].time + f * (w[1].time - w[0].time))
            })
            .collect()
    }

    #[test]
    fn interpolation_names_parse_and_others_are_refused_naming_the_field() {
        for (name, want) in Interpolation::NAMES.iter().zip(BOTH) {
            assert_eq!(Interpolation::parse(name, "x").unwrap(), want);
            assert_eq!(want.name(), *name);
        }
        let e = Interpolation::parse("cubic", "collider[2].interpolation").unwrap_err();
        let Error::Field { field, message } = e else {
            panic!("not a field error: {e}")
        };
        assert_eq!(field, "collider[2].interpolation");
        assert!(
            message.contains("\"linear\"")
                && message.contains("\"smooth\"")
                && message.contains("cubic"),
            "{message}"
        );
    }

    fn field_error(keys: Vec<Keyframe>) -> (String, String) {
        match Track::new(keys, Interpolation::Smooth, "collider[0]") {
            Err(Error::Field { field, message }) => (field, message),
            other => panic!("expected a field error, got {other:?}"),
        }
    }

    #[test]
    fn bad_keys_are_field_errors_naming_the_key_and_the_fault() {
        let ok = |t| Keyframe::at(t);
        let (f, m) = field_error(vec![]);
        assert_eq!(f, "collider[0].keyframes");
        assert!(m.contains("at least one key"), "{m}");

        let (f, m) = field_error(vec![ok(0.0), ok(1.0), ok(1.0)]);
        assert_eq!(f, "collider[0].keyframes[2].time");
        assert!(m.contains("greater than") && m.contains("(1)"), "{m}");
        let (f, m) = field_error(vec![ok(0.0), ok(-0.5)]);
        assert_eq!(f, "collider[0].keyframes[1].time");
        assert!(m.contains("greater than") && m.contains("-0.5"), "{m}");

        let (f, m) = field_error(vec![ok(0.0), ok(f64::NAN)]);
        assert_eq!(f, "collider[0].keyframes[1].time");
        assert!(m.contains("finite") && m.contains("NaN"), "{m}");
        let (f, _) = field_error(vec![ok(f64::NEG_INFINITY)]);
        assert_eq!(f, "collider[0].keyframes[0].time");

        let mut zero = ok(1.0);
        zero.rotation = DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0);
        let (f, m) = field_error(vec![ok(0.0), zero]);
        assert_eq!(f, "collider[0].keyframes[1].rotation");
        assert!(m.contains("nonzero"), "{m}");
        let mut nan = ok(1.0);
        nan.rotation = DQuat::from_xyzw(0.0, f64::NAN, 0.0, 1.0);
        let (f, m) = field_error(vec![ok(0.0), nan]);
        assert_eq!(f, "collider[0].keyframes[1].rotation");
        assert!(m.contains("finite") && m.contains("NaN"), "{m}");

        let mut far = ok(1.0);
        far.translation = Vec3::new(f64::INFINITY, 0.0, 0.0);
        let (f, m) = field_error(vec![ok(0.0), far]);
        assert_eq!(f, "collider[0].keyframes[1].translation");
        assert!(m.contains("finite"), "{m}");

        // without a prefix, the path starts at the keys
        let e = Track::new(vec![], Interpolation::Linear, "").unwrap_err();
        assert!(matches!(e, Error::Field { field, .. } if field == "keyframes"));
    }

    #[test]
    fn rotations_are_normalized_and_flipped_onto_one_hemisphere() {
        let q1 = DQuat::from_rotation_y(0.3);
        let keys = vec![
            key(0.0, [0.0; 3], DQuat::from_xyzw(0.0, 0.0, 0.0, 2.0)),
            key(1.0, [0.0; 3], q1 * -3.0),
        ];
        let tr = Track::new(keys, Interpolation::Linear, "c").unwrap();
        assert_eq!(tr.keys()[0].rotation, DQuat::IDENTITY);
        assert!((tr.keys()[1].rotation - q1).length() < 1e-15);
        assert_eq!((tr.first_time(), tr.last_time()), (0.0, 1.0));
        // one key: that pose at every time, no motion
        let one = Track::new(
            vec![key(2.0, [1.0, 2.0, 3.0], q1)],
            Interpolation::Smooth,
            "c",
        )
        .unwrap();
        let held = (Vec3::new(1.0, 2.0, 3.0), one.keys()[0].rotation);
        assert!(rot_dist(held.1, q1) < 1e-15);
        for t in [-1.0, 2.0, 5.0, f64::NAN] {
            assert_eq!(one.sample(t), held);
            assert_eq!(one.velocity(t), (Vec3::ZERO, Vec3::ZERO));
        }
        assert_eq!(one.speed_bound(-10.0, 10.0), (0.0, 0.0));
    }

    #[test]
    fn linear_translation_is_the_lerp_and_its_velocity_the_chord_over_the_interval() {
        let keys = vec![
            key(0.0, [0.0, 0.0, 0.0], DQuat::IDENTITY),
            key(2.0, [4.0, 8.0, -2.0], DQuat::IDENTITY),
        ];
        let tr = Track::new(keys, Interpolation::Linear, "c").unwrap();
        assert_eq!(tr.sample(0.5).0, Vec3::new(1.0, 2.0, -0.5));
        assert_eq!(tr.sample(1.5).0, Vec3::new(3.0, 6.0, -1.5));
        assert_eq!(tr.velocity(0.0).0, Vec3::new(2.0, 4.0, -1.0));
        assert_eq!(tr.velocity(1.9).0, Vec3::new(2.0, 4.0, -1.0));
        // from the last key on, held
        assert_eq!(tr.velocity(2.0).0, Vec3::ZERO);
        assert_eq!(tr.sample(7.0).0, Vec3::new(4.0, 8.0, -2.0));
    }

    #[test]
    fn linear_midpoint_of_a_quarter_turn_about_y_is_the_eighth_turn() {
        let quarter = DQuat::from_rotation_y(PI / 2.0);
        // the quarter turn given as q, as -q, and as a three-quarter turn the other way round
        for (q1, sign) in [
            (quarter, 1.0),
            (-quarter, 1.0),
            (DQuat::from_rotation_y(-3.0 * PI / 2.0), 1.0),
            // a three-quarter turn: the shorter way is a quarter turn backwards
            (DQuat::from_rotation_y(3.0 * PI / 2.0), -1.0),
        ] {
            let keys = vec![key(0.0, [0.0; 3], DQuat::IDENTITY), key(2.0, [0.0; 3], q1)];
            let tr = Track::new(keys, Interpolation::Linear, "c").unwrap();
            let mid = tr.sample(1.0).1;
            assert!(
                rot_dist(mid, DQuat::from_rotation_y(sign * PI / 4.0)) < 1e-14,
                "{mid}"
            );
            let quarter_way = tr.sample(0.5).1;
            assert!(rot_dist(quarter_way, DQuat::from_rotation_y(sign * PI / 8.0)) < 1e-14);
            let w = tr.velocity(1.0).1;
            assert!(
                (w - Vec3::new(0.0, sign * PI / 4.0, 0.0)).length() < 1e-14,
                "{w}"
            );
        }
    }

    #[test]
    fn a_two_key_smooth_track_is_the_slerp_and_lerp_with_an_eased_parameter() {
        let (q0, q1) = (
            DQuat::from_scaled_axis(Vec3::new(0.2, -0.4, 0.1)),
            DQuat::from_scaled_axis(Vec3::new(-1.0, 0.5, 2.0)),
        );
        let (p0, p1) = (Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 2.0, 0.5));
        let keys = vec![key(1.0, p0.into(), q0), key(3.0, p1.into(), q1)];
        let tr = Track::new(keys, Interpolation::Smooth, "c").unwrap();
        for u in [0.1, 0.25, 0.5, 0.8, 0.99] {
            let e = 3.0 * u * u - 2.0 * u * u * u;
            let (p, q) = tr.sample(1.0 + 2.0 * u);
            assert!((p - p0.lerp(p1, e)).length() < 1e-14);
            assert!(rot_dist(q, q0.slerp(q1, e)) < 1e-13);
        }
        // at rest at both keys
        assert_eq!(tr.velocity(1.0), (Vec3::ZERO, Vec3::ZERO));
    }

    #[test]
    fn uniform_steps_along_a_line_and_about_an_axis_move_uniformly_between_interior_keys() {
        let (dp, axis, angle, dt) = (
            Vec3::new(0.3, -0.1, 0.2),
            Vec3::new(1.0, 2.0, 2.0) / 3.0,
            0.4,
            0.5,
        );
        let keys: Vec<Keyframe> = (0..6)
            .map(|i| {
                let i = i as f64;
                key(
                    i * dt,
                    (Vec3::new(1.0, 1.0, 0.0) + i * dp).into(),
                    exp(axis * (i * angle)),
                )
            })
            .collect();
        let tr = Track::new(keys, Interpolation::Smooth, "c").unwrap();
        // segments 1..=3 lie between interior keys (1..=4)
        for t in [0.5, 0.6, 0.75, 1.0, 1.3, 1.5, 1.9, 2.0 - 1e-9] {
            let (v, w) = tr.velocity(t);
            assert!(
                (v - dp / dt).length() < 1e-12 * (dp / dt).length(),
                "t = {t}: {v}"
            );
            assert!((w - axis * (angle / dt)).length() < 1e-12, "t = {t}: {w}");
            let (p, q) = tr.sample(t);
            let exact = Vec3::new(1.0, 1.0, 0.0) + dp * (t / dt);
            assert!((p - exact).length() < 1e-14);
            assert!(rot_dist(q, exp(axis * (angle * t / dt))) < 1e-14);
        }
        // the first and last segments start and stop at rest
        assert_eq!(tr.velocity(0.0), (Vec3::ZERO, Vec3::ZERO));
        let (v, w) = tr.velocity(2.5 - 1e-9);
        assert!(v.length() < 1e-8 && w.length() < 1e-8);
    }

    #[test]
    fn the_continuity_check_catches_the_kinks_of_a_linear_track() {
        // what `smooth_velocity_is_continuous_at_the_keys` asserts fails for linear keys
        let keys = vec![
            key(0.0, [0.0; 3], DQuat::IDENTITY),
            key(1.0, [1.0, 0.0, 0.0], DQuat::from_rotation_x(0.5)),
            key(2.0, [1.0, 1.0, 0.0], DQuat::from_rotation_y(0.5)),
        ];
        let jump = |interp| {
            let tr = Track::new(keys.clone(), interp, "c").unwrap();
            let ((vl, wl), (vr, wr)) = (tr.velocity(1.0 - 1e-7), tr.velocity(1.0 + 1e-7));
            ((vl - vr).length(), (wl - wr).length())
        };
        let (v, w) = jump(Interpolation::Linear);
        assert!(v > 1.0 && w > 0.5, "{v} {w}");
        let (v, w) = jump(Interpolation::Smooth);
        assert!(v < 1e-5 && w < 1e-5, "{v} {w}");
    }

    #[test]
    fn the_jacobian_helpers_are_inverses_and_match_differences_of_exp() {
        for phi in [
            Vec3::new(1e-9, 0.0, 0.0),
            Vec3::new(0.05, -0.02, 0.07),
            Vec3::new(0.1 - 1e-12, 0.0, 0.0),
            Vec3::new(0.1 + 1e-12, 0.0, 0.0),
            Vec3::new(1.0, 2.0, -0.5),
            Vec3::new(0.0, 0.0, PI),
            Vec3::new(3.0, 3.0, 3.0),
        ] {
            let v = Vec3::new(0.3, -0.7, 0.4);
            if phi.length() <= PI {
                let back = left_jacobian_inverse(phi, left_jacobian(phi, v));
                assert!((back - v).length() < 1e-13, "{phi}: {back}");
                // log inverts exp
                assert!((log(exp(phi)) - phi).length() < 1e-13 * (1.0 + phi.length()));
            }
            // d/dε Exp(φ + ε v) Exp(φ)ᵀ at 0 is [J_l(φ) v]×: central differences
            let e = 1e-6;
            let q = exp(phi);
            let d = (exp(phi + e * v) - exp(phi - e * v)) * (1.0 / (2.0 * e)) * q.conjugate();
            let fd = 2.0 * Vec3::new(d.x, d.y, d.z);
            assert!((fd - left_jacobian(phi, v)).length() < 1e-9, "{phi}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        #[test]
        fn keys_are_hit_exactly_and_held_outside(keys in arb_keys(1.5), smooth in any::<bool>()) {
            let interp = if smooth { Interpolation::Smooth } else { Interpolation::Linear };
            let tr = Track::new(keys.clone(), interp, "c").unwrap();
            for (given, k) in keys.iter().zip(tr.keys()) {
                let (p, q) = tr.sample(given.time);
                prop_assert!((p - given.translation).length() < 1e-12);
                prop_assert!(rot_dist(q, given.rotation) < 1e-12);
                prop_assert!((q - k.rotation).length() < 1e-12);
                prop_assert!((k.rotation.length() - 1.0).abs() < 1e-15);
            }
            let (first, last) = (&keys[0], &keys[keys.len() - 1]);
            for t in [first.time - 1.0, first.time - 1e-9] {
                let (p, q) = tr.sample(t);
                prop_assert!((p - first.translation).length() < 1e-12 && rot_dist(q, first.rotation) < 1e-12);
                prop_assert_eq!(tr.velocity(t), (Vec3::ZERO, Vec3::ZERO));
            }
            for t in [last.time, last.time + 1e-9, last.time + 3.0] {
                let (p, q) = tr.sample(t);
                prop_assert!((p - last.translation).length() < 1e-12 && rot_dist(q, last.rotation) < 1e-12);
                prop_assert_eq!(tr.velocity(t), (Vec3::ZERO, Vec3::ZERO));
            }
        }

        #[test]
        fn rotations_stay_unit_length(keys in arb_keys(1.5), smooth in any::<bool>(), f in 0.0..1.0f64) {
            let interp = if smooth { Interpolation::Smooth } else { Interpolation::Linear };
            let tr = Track::new(keys, interp, "c").unwrap();
            for t in interior_times(&tr, &[f, 0.5, 1e-3]) {
                prop_assert!((tr.sample(t).1.length() - 1.0).abs() < 1e-14);
            }
        }

        #[test]
        fn velocity_matches_central_differences_of_the_pose(
            keys in arb_keys(1.5), smooth in any::<bool>(), f in 0.02..0.98f64,
        ) {
            let interp = if smooth { Interpolation::Smooth } else { Interpolation::Linear };
            let tr = Track::new(keys, interp, "c").unwrap();
            let d = 1e-5;
            for t in interior_times(&tr, &[f, 0.5]) {
                let (v, w) = tr.velocity(t);
                let (fv, fw) = (fd_velocity(&tr, t, d), fd_omega(&tr, t, d));
                prop_assert!((v - fv).length() < 1e-8 * (1.0 + v.length()), "t = {}: {} vs {}", t, v, fv);
                prop_assert!((w - fw).length() < 1e-8 * (1.0 + w.length()), "t = {}: {} vs {}", t, w, fw);
            }
        }

        #[test]
        fn smooth_velocity_is_continuous_at_the_keys_and_zero_at_the_ends(keys in arb_keys(1.5)) {
            let tr = Track::new(keys, Interpolation::Smooth, "c").unwrap();
            let k = tr.keys();
            for i in 1..k.len() - 1 {
                let t = k[i].time;
                let ((vl, wl), (vr, wr)) = (tr.velocity(t - 1e-7), tr.velocity(t + 1e-7));
                let (sv, sw) = tr.speed_bound(k[i - 1].time, k[i + 1].time);
                prop_assert!((vl - vr).length() <= 1e-5 * (vl.length() + vr.length() + sv), "{} {}", vl, vr);
                prop_assert!((wl - wr).length() <= 1e-5 * (wl.length() + wr.length() + sw), "{} {}", wl, wr);
            }
            let (first, last) = (tr.first_time(), tr.last_time());
            prop_assert_eq!(tr.velocity(first), (Vec3::ZERO, Vec3::ZERO));
            // the left limit at the last key: velocity ~ acceleration × 1e-9
            let (v, w) = tr.velocity(last - 1e-9);
            let (sv, sw) = tr.speed_bound(first, last);
            prop_assert!(v.length() <= 1e-7 * sv && w.length() <= 1e-7 * sw);
        }

        #[test]
        fn speed_bounds_hold_and_are_tight(
            keys in arb_keys(0.8), smooth in any::<bool>(), a in -0.2..1.2f64, b in -0.2..1.2f64,
        ) {
            check_speed_bounds(keys, smooth, a, b, 1.1)?;
        }

        #[test]
        fn speed_bounds_hold_for_half_turns_between_keys(
            keys in arb_keys(1.5), smooth in any::<bool>(), a in -0.2..1.2f64, b in -0.2..1.2f64,
        ) {
            // |J_l(φ) x| may be as small as 2/π |x| for θ = π: looser, still within 3×
            check_speed_bounds(keys, smooth, a, b, 3.0)?;
        }
    }

    /// `speed_bound` over `[first + a span, first + b span]` is at least every speed sampled
    /// there and (smooth) at most `slack` times the largest, (linear) equal to it.
    fn check_speed_bounds(
        keys: Vec<Keyframe>,
        smooth: bool,
        a: f64,
        b: f64,
        slack: f64,
    ) -> std::result::Result<(), TestCaseError> {
        let interp = if smooth {
            Interpolation::Smooth
        } else {
            Interpolation::Linear
        };
        let tr = Track::new(keys, interp, "c").unwrap();
        let span = tr.last_time() - tr.first_time();
        let (t0, t1) = (tr.first_time() + a * span, tr.first_time() + b * span);
        let (bv, bw) = tr.speed_bound(t0, t1);
        let (lo, hi) = (t0.min(t1), t0.max(t1));
        let n = 4000;
        let (mut mv, mut mw) = (0.0f64, 0.0f64);
        for j in 0..=n {
            let t = if j == n {
                hi
            } else {
                lo + (hi - lo) * (j as f64 / n as f64)
            };
            let (v, w) = tr.velocity(t);
            prop_assert!(v.length() <= bv, "t = {}: |v| = {} > {}", t, v.length(), bv);
            prop_assert!(w.length() <= bw, "t = {}: |ω| = {} > {}", t, w.length(), bw);
            mv = mv.max(v.length());
            mw = mw.max(w.length());
        }
        if smooth {
            prop_assert!(
                bv <= slack * mv + 1e-12 && bw <= slack * mw + 1e-12,
                "{} {} vs {} {}",
                bv,
                bw,
                mv,
                mw
            );
        } else {
            // exact: the largest segment velocity met
            prop_assert_eq!((bv, bw), (mv, mw));
        }
        Ok(())
    }
}
