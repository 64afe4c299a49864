//! Handles: groups of cloth vertices that follow a prescribed rigid motion exactly (moving
//! pins), until an optional release time.
//!
//! A handle vertex with initial position `x₀` is at `p + T(t) + R(t)(x₀ - p)` at time `t`
//! (rotation about the pivot `p`, then translation; [`Motion`]). During a step `[t, t + h]`
//! that starts before the release, the vertex is filtered out of the solve (as a pin) and its
//! velocity is prescribed as the chord velocity `(target(t + h) - x(t)) / h`, so it ends the step
//! where the motion puts it (Baraff & Witkin's prescribed velocity, docs/MATH.md §5); from the
//! release on it is free.
//!
//! An attachment (`attach = "COLLIDER"`) is a handle that follows a collider instead of its own
//! motion: each vertex is bound at `t = 0` to its closest point on the collider (in the
//! collider's frame; on a mesh by the closest triangle's barycentric weights, so it follows an
//! animated mesh sequence) and keeps its offset from that point: its target at `t` is
//! [`crate::collision::colliders::Collider::carry`] of its initial position from 0 to `t`.

use crate::animation::Motion;
use crate::collision::settings::Obstacle;
use crate::error::{Error, Result};
use crate::math::Vec3;

/// A handle as a scene gives it, on one cloth (vertex indices local to that cloth).
#[derive(Clone, Debug, PartialEq)]
pub struct HandleDesc {
    /// 0-based vertex indices of the cloth.
    pub vertices: Vec<u32>,
    /// The point the rotation is about; default: the centroid of the vertices at `t = 0`.
    pub pivot: Option<Vec3>,
    /// The motion (keyframed, constant, or fixed).
    pub motion: Motion,
    /// From this time on the vertices are free.
    pub release: Option<f64>,
    /// Index of the obstacle the vertices are attached to (then `motion` is unused).
    pub attach: Option<usize>,
}

/// A handle of the model: global particle indices and their initial positions.
#[derive(Clone, Debug, PartialEq)]
pub struct Handle {
    /// Particles, in the order given.
    pub particles: Vec<u32>,
    /// Their positions before the motion (the cloth's initial positions).
    pub rest: Vec<Vec3>,
    /// Rotation center.
    pub pivot: Vec3,
    /// Motion.
    pub motion: Motion,
    /// Release time.
    pub release: Option<f64>,
    /// The obstacle the vertices follow, if attached.
    pub attach: Option<usize>,
}

impl Handle {
    /// The handle of `d` on a cloth whose vertices start at `positions` and whose first particle
    /// is `offset`; errors name `field` (`cloth[0].handle[1]`).
    pub fn new(d: &HandleDesc, positions: &[Vec3], offset: u32, field: &str) -> Result<Handle> {
        let n = positions.len();
        if d.vertices.is_empty() {
            return Err(Error::field(
                format!("{field}.vertices"),
                "selects no vertex",
            ));
        }
        if let Some(&v) = d.vertices.iter().find(|&&v| v as usize >= n) {
            return Err(Error::field(
                format!("{field}.vertices"),
                format!(
                    "{v} is out of range: the cloth has {n} vertices, numbered 0 to {} (0-based)",
                    n.saturating_sub(1)
                ),
            ));
        }
        let mut seen = vec![false; n];
        for &v in &d.vertices {
            if std::mem::replace(&mut seen[v as usize], true) {
                return Err(Error::field(
                    format!("{field}.vertices"),
                    format!("vertex {v} is listed twice"),
                ));
            }
        }
        d.motion.validate(field)?;
        let rest: Vec<Vec3> = d.vertices.iter().map(|&v| positions[v as usize]).collect();
        let pivot = match d.pivot {
            Some(p) => crate::validate::finite3(&format!("{field}.pivot"), p)?,
            None => rest.iter().sum::<Vec3>() / rest.len() as f64,
        };
        if let Some(r) = d.release {
            if !r.is_finite() {
                return Err(Error::field(
                    format!("{field}.release"),
                    format!("must be a finite time, got {r}"),
                ));
            }
            if let Motion::Keyframed(track) = &d.motion
                && r < track.first_time()
            {
                return Err(Error::field(
                    format!("{field}.release"),
                    format!("{r} s is before the first key ({} s)", track.first_time()),
                ));
            }
        }
        Ok(Handle {
            particles: d.vertices.iter().map(|&v| v + offset).collect(),
            rest,
            pivot,
            motion: d.motion.clone(),
            release: d.release,
            attach: d.attach,
        })
    }

    /// True when the handle holds its vertices over a step starting at `t0`.
    pub fn holds(&self, t0: f64) -> bool {
        self.release.is_none_or(|r| t0 < r)
    }

    /// Where the motion puts the handle's `k`-th vertex at time `t` (see [`Handle::target`]
    /// for attachments).
    pub fn position(&self, k: usize, t: f64) -> Vec3 {
        let (rot, tr) = self.motion.pose(t);
        self.pivot + tr + rot * (self.rest[k] - self.pivot)
    }

    /// Where the handle puts its `k`-th vertex at time `t`: its motion's position, or for an
    /// attachment, its initial position carried by the obstacle from 0 to `t`.
    pub fn target(&self, k: usize, t: f64, obstacles: &[Obstacle]) -> Vec3 {
        match self.attach.and_then(|i| obstacles.get(i)) {
            Some(o) => o.collider.carry(self.rest[k], 0.0, t),
            None => self.position(k, t),
        }
    }
}

/// For a step `[t0, t0 + h]` from positions `x`: the pinned flags (fixed pins and the handles
/// that hold) and the end-of-step velocities of the handle vertices, by increasing particle.
pub fn step_targets(
    fixed: &[bool],
    handles: &[Handle],
    obstacles: &[Obstacle],
    x: &[Vec3],
    t0: f64,
    h: f64,
) -> (Vec<bool>, Vec<(u32, Vec3)>) {
    let mut pinned = fixed.to_vec();
    let mut moving = Vec::new();
    for hd in handles.iter().filter(|hd| hd.holds(t0)) {
        for (k, &p) in hd.particles.iter().enumerate() {
            pinned[p as usize] = true;
            moving.push((p, (hd.target(k, t0 + h, obstacles) - x[p as usize]) / h));
        }
    }
    moving.sort_by_key(|&(p, _)| p);
    (pinned, moving)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::animation::{Interpolation, Keyframe, Track};
    use glam::DQuat;

    fn turning(release: Option<f64>) -> HandleDesc {
        let keys = vec![
            Keyframe::at(0.0),
            Keyframe {
                time: 1.0,
                translation: Vec3::new(0.0, 1.0, 0.0),
                rotation: DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2),
            },
        ];
        HandleDesc {
            vertices: vec![2, 0],
            pivot: None,
            motion: Motion::Keyframed(Track::new(keys, Interpolation::Linear, "h").unwrap()),
            release,
            attach: None,
        }
    }

    #[test]
    fn a_handle_turns_about_its_centroid_and_its_chord_velocity_lands_on_the_target() {
        let x = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::ZERO,
            Vec3::new(3.0, 0.0, 0.0),
        ];
        let hd = Handle::new(&turning(None), &x, 10, "cloth[0].handle[0]").unwrap();
        assert_eq!(hd.particles, vec![12, 10]);
        assert_eq!(hd.pivot, Vec3::new(2.0, 0.0, 0.0));
        // a quarter turn about +y takes +x to -z, then up by 1
        let p = hd.position(0, 1.0);
        assert!((p - Vec3::new(2.0, 1.0, -1.0)).length() < 1e-15, "{p}");
        assert_eq!(hd.position(1, 0.0), x[0]);
        // end-of-step velocities carry every vertex exactly (to rounding) onto its target
        let mut all = vec![Vec3::ZERO; 13];
        all[12] = x[2];
        all[10] = x[0];
        let (pinned, moving) = step_targets(
            &[false; 13],
            std::slice::from_ref(&hd),
            &[],
            &all,
            0.0,
            0.25,
        );
        assert!(pinned[10] && pinned[12] && !pinned[11]);
        assert_eq!(moving.iter().map(|m| m.0).collect::<Vec<_>>(), vec![10, 12]);
        for (p, v) in moving {
            let k = hd.particles.iter().position(|&q| q == p).unwrap();
            let end = all[p as usize] + 0.25 * v;
            assert!((end - hd.position(k, 0.25)).length() < 1e-15);
        }
    }

    #[test]
    fn released_handles_hold_nothing_and_bad_handles_name_the_field() {
        let x = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let hd = Handle::new(&turning(Some(0.5)), &x, 0, "c").unwrap();
        assert!(hd.holds(0.49) && !hd.holds(0.5));
        let (pinned, moving) = step_targets(&[false; 3], &[hd], &[], &x, 0.5, 0.1);
        assert!(pinned.iter().all(|p| !p) && moving.is_empty());
        let err = |d: HandleDesc| {
            Handle::new(&d, &x, 0, "cloth[1].handle[0]")
                .unwrap_err()
                .to_string()
        };
        let mut d = turning(None);
        d.vertices = vec![0, 3];
        assert!(err(d.clone()).starts_with("cloth[1].handle[0].vertices: 3 is out of range"));
        d.vertices = vec![];
        assert_eq!(
            err(d.clone()),
            "cloth[1].handle[0].vertices: selects no vertex"
        );
        d.vertices = vec![1, 1];
        assert!(err(d.clone()).contains("listed twice"));
        let mut d = turning(Some(-1.0));
        assert!(
            err(d.clone()).starts_with("cloth[1].handle[0].release: -1 s is before the first key")
        );
        d.release = Some(f64::NAN);
        assert!(err(d).contains("release: must be a finite time"));
    }
}
