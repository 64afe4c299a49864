//! The motions of a snapshot ([`super`]): a front end may replace a collider's or a handle's
//! motion between steps ([`crate::step::Simulation::set_obstacle_motion`],
//! [`crate::step::Simulation::set_handle_motion`]), and a run resumed from the state must then
//! go on with those motions, not the scene's.
//!
//! A motion, little endian: u64 kind (0 fixed, 1 constant, 2 keyframed); a constant one then
//! its velocity and angular velocity (6 f64); a keyframed one its interpolation (u64: 0 linear,
//! 1 smooth), u64 key count, and per key its time, translation and rotation `[x, y, z, w]`
//! (8 f64). Every f64 as its bits, and the keys as the track holds them (normalized), so the
//! restored track is the same bits.

use super::{Reader, damaged};
use crate::animation::Motion;
use crate::animation::keyframes::{Interpolation, Keyframe, Track};
use crate::error::Result;
use crate::math::Vec3;
use glam::DQuat;

/// Appends `m` (see the module docs).
pub(super) fn encode(m: &Motion, out: &mut Vec<u8>) {
    let put = |out: &mut Vec<u8>, v: u64| out.extend_from_slice(&v.to_le_bytes());
    let floats = |out: &mut Vec<u8>, v: &[f64]| {
        v.iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes()))
    };
    match m {
        Motion::Fixed => put(out, 0),
        Motion::Constant {
            velocity,
            angular_velocity,
        } => {
            put(out, 1);
            floats(out, &velocity.to_array());
            floats(out, &angular_velocity.to_array());
        }
        Motion::Keyframed(track) => {
            put(out, 2);
            let kind = match track.interpolation() {
                Interpolation::Linear => 0,
                Interpolation::Smooth => 1,
            };
            put(out, kind);
            put(out, track.keys().len() as u64);
            for k in track.keys() {
                floats(out, &[k.time]);
                floats(out, &k.translation.to_array());
                floats(out, &k.rotation.to_array());
            }
        }
    }
}

/// Reads a motion written by [`encode`]; `field` names it in an error (a damaged file).
pub(super) fn decode(r: &mut Reader, field: &str) -> Result<Motion> {
    let short = || damaged("cut short in the motions");
    let f = |r: &mut Reader| r.u64().map(f64::from_bits).ok_or_else(short);
    let motion = match r.u64().ok_or_else(short)? {
        0 => Motion::Fixed,
        1 => {
            let mut v = [0.0; 6];
            for x in &mut v {
                *x = f(r)?;
            }
            Motion::Constant {
                velocity: Vec3::new(v[0], v[1], v[2]),
                angular_velocity: Vec3::new(v[3], v[4], v[5]),
            }
        }
        2 => {
            let interpolation = match r.u64().ok_or_else(short)? {
                0 => Interpolation::Linear,
                1 => Interpolation::Smooth,
                _ => return Err(damaged("an unknown interpolation")),
            };
            let n = r.u64().ok_or_else(short)?;
            if n.checked_mul(64).is_none_or(|b| b > r.left() as u64) {
                return Err(short());
            }
            let mut keys = Vec::with_capacity(n as usize);
            for _ in 0..n {
                let mut v = [0.0; 8];
                for x in &mut v {
                    *x = f(r)?;
                }
                keys.push(Keyframe {
                    time: v[0],
                    translation: Vec3::new(v[1], v[2], v[3]),
                    rotation: DQuat::from_xyzw(v[4], v[5], v[6], v[7]),
                });
            }
            let track = Track::from_normalized(keys, interpolation, field)
                .map_err(|e| damaged(&format!("a motion that is not valid: {e}")))?;
            Motion::Keyframed(track)
        }
        _ => return Err(damaged("an unknown kind of motion")),
    };
    motion
        .validate(field)
        .map_err(|e| damaged(&format!("a motion that is not valid: {e}")))?;
    Ok(motion)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn roundtrip(m: &Motion) -> Motion {
        let mut b = Vec::new();
        encode(m, &mut b);
        let mut r = Reader { b: &b, at: 0 };
        let back = decode(&mut r, "collider[0]").unwrap();
        assert_eq!(r.at, b.len(), "every byte read");
        back
    }

    #[test]
    fn every_kind_of_motion_comes_back_to_the_bit() {
        // a rotation that normalizing again changes in its last bits (checked below)
        let q = DQuat::from_xyzw(0.638, 0.762, 0.534, -0.498);
        let keys = vec![
            Keyframe {
                time: -0.25,
                translation: Vec3::new(0.1, 1.0 / 3.0, -2.0),
                rotation: DQuat::IDENTITY,
            },
            Keyframe {
                time: 0.7,
                translation: Vec3::new(1e-300, 5.0, 0.0),
                rotation: q,
            },
            Keyframe {
                time: 1.9,
                translation: Vec3::new(-0.0, 2.5, 7.0),
                rotation: -q * DQuat::from_rotation_y(0.4),
            },
        ];
        for interpolation in [Interpolation::Linear, Interpolation::Smooth] {
            let track = Track::new(keys.clone(), interpolation, "").unwrap();
            let again = Track::new(track.keys().to_vec(), interpolation, "").unwrap();
            assert_ne!(
                again, track,
                "the premise: normalizing the keys again changes them"
            );
            let m = Motion::Keyframed(track.clone());
            let back = roundtrip(&m);
            assert_eq!(back, m);
            let Motion::Keyframed(t) = &back else {
                panic!("not keyframed")
            };
            for (a, b) in t.keys().iter().zip(track.keys()) {
                let bits = |k: &Keyframe| {
                    let mut v = vec![k.time.to_bits()];
                    v.extend(k.translation.to_array().map(f64::to_bits));
                    v.extend(k.rotation.to_array().map(f64::to_bits));
                    v
                };
                assert_eq!(bits(a), bits(b));
            }
            // and it moves the same, to the bit
            for t in [-1.0, 0.0, 0.3, 0.7, 1.2, 1.9, 3.0] {
                let (p, q) = (back.pose(t), m.pose(t));
                assert_eq!(
                    p.1.to_array().map(f64::to_bits),
                    q.1.to_array().map(f64::to_bits)
                );
                assert_eq!(
                    p.0.to_array().map(f64::to_bits),
                    q.0.to_array().map(f64::to_bits)
                );
            }
        }
        let c = Motion::constant(
            Vec3::new(0.0, -1.5, 1e-9),
            Vec3::new(0.0, std::f64::consts::PI, 0.0),
        );
        assert_eq!(roundtrip(&c), c);
        assert_eq!(roundtrip(&Motion::Fixed), Motion::Fixed);
    }

    #[test]
    fn a_damaged_motion_is_an_error_not_a_panic() {
        let track = Track::new(
            vec![Keyframe::at(0.0), Keyframe::at(1.0)],
            Interpolation::Linear,
            "",
        )
        .unwrap();
        let mut b = Vec::new();
        encode(&Motion::Keyframed(track), &mut b);
        // every prefix is cut short
        for cut in 0..b.len() {
            let mut r = Reader {
                b: &b[..cut],
                at: 0,
            };
            assert!(decode(&mut r, "handle[0]").is_err(), "cut at {cut}");
        }
        let bad = |edit: &dyn Fn(&mut Vec<u8>)| {
            let mut c = b.clone();
            edit(&mut c);
            let mut r = Reader { b: &c, at: 0 };
            decode(&mut r, "handle[0]").unwrap_err().to_string()
        };
        // an unknown kind, an unknown interpolation, a huge key count
        assert!(bad(&|c| c[0] = 7).contains("unknown kind"));
        assert!(bad(&|c| c[8] = 9).contains("unknown interpolation"));
        assert!(bad(&|c| c[16..24].copy_from_slice(&u64::MAX.to_le_bytes())).contains("cut short"));
        // keys out of order (the second key's time set to -1)
        let e = bad(&|c| c[24 + 64..24 + 72].copy_from_slice(&(-1.0f64).to_le_bytes()));
        assert!(e.contains("handle[0].keyframes[1].time"), "{e}");
        // a rotation that is not unit (its x doubled)
        let mut c = Vec::new();
        let turn = Keyframe {
            time: 1.0,
            translation: Vec3::ZERO,
            rotation: DQuat::from_rotation_x(0.5),
        };
        let track = Track::new(vec![Keyframe::at(0.0), turn], Interpolation::Linear, "").unwrap();
        encode(&Motion::Keyframed(track), &mut c);
        let x = 24 + 64 + 32;
        let doubled = 2.0 * f64::from_le_bytes(c[x..x + 8].try_into().unwrap());
        c[x..x + 8].copy_from_slice(&doubled.to_le_bytes());
        let mut r = Reader { b: &c, at: 0 };
        let e = decode(&mut r, "handle[1]").unwrap_err().to_string();
        assert!(e.contains("handle[1].keyframes[1].rotation"), "{e}");
        // a constant motion that is not finite
        let mut c = Vec::new();
        encode(&Motion::constant(Vec3::X, Vec3::ZERO), &mut c);
        c[8..16].copy_from_slice(&f64::NAN.to_le_bytes());
        let mut r = Reader { b: &c, at: 0 };
        let e = decode(&mut r, "collider[2]").unwrap_err().to_string();
        assert!(e.contains("collider[2].velocity"), "{e}");
    }
}
