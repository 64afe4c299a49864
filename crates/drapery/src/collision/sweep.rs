//! A particle's straight path over a step against an analytic obstacle: the fail-safe's first
//! stage (docs/MATH.md §16).
//!
//! Conservative advancement on the obstacle's signed distance, which changes along the path at
//! most at the rate of the path's length plus the obstacle's surface speeds ([`advance`]). A
//! particle carried along by a turning obstacle moves a path length per step while staying at
//! the same distance from it, so the advancement takes many small steps; for a sphere, whose
//! surface a turn about its centre leaves in place, a closed-form lower bound of the distance
//! first proves most such paths clear ([`clear_of_sphere`]).

use super::colliders::Shape;
use super::settings::Obstacle;
use crate::math::Vec3;

/// Sweeps `x0 → x1` against an analytic obstacle over `[t0, t0 + h]`; returns the fraction of
/// the path at which the particle comes within `stop` of the surface.
pub(crate) fn sweep(o: &Obstacle, x0: Vec3, x1: Vec3, t0: f64, h: f64, stop: f64) -> Option<f64> {
    let (speed, spin) = o.collider.speed_bound(t0, t0 + h);
    let rate = rate(o, x0, x1, h, speed, spin);
    // When the distance stays at least `stop` all along, each advance is at least
    // `stop / (2 rate)`, so `advance` reaches the end within its 1000 evaluations and returns
    // `None`; a proof of that distance then gives the same answer without the evaluations.
    if 2.0 * rate <= 998.0 * stop && clear_of_sphere(o, x0, x1, t0, h, stop, speed) {
        return None;
    }
    advance(o, x0, x1, t0, h, stop, rate)
}

/// Bound on the change of the signed distance per unit fraction of the path `x0 → x1` over a
/// step `h`: the path's length plus the surface's point speeds (the obstacle's linear `speed`
/// and its turn `spin` at the path's greatest reach from the centre) times `h`.
fn rate(o: &Obstacle, x0: Vec3, x1: Vec3, h: f64, speed: f64, spin: f64) -> f64 {
    let len = (x1 - x0).length();
    let c = o.collider.center();
    let reach = (x0 - c).length().max((x1 - c).length()) + len + speed * h;
    len + h * (speed + spin * reach)
}

/// Conservative advancement along `x0 → x1` with `rate` bounding the change of the signed
/// distance per unit fraction of the path: the fraction where it first comes under `stop`,
/// `None` if it never does (`Some` of where it got to if 1000 evaluations do not reach the end).
fn advance(o: &Obstacle, x0: Vec3, x1: Vec3, t0: f64, h: f64, stop: f64, rate: f64) -> Option<f64> {
    let col = &o.collider;
    let mut s = 0.0;
    for _ in 0..1000 {
        let d = col.closest(x0 + s * (x1 - x0), t0 + s * h).signed_distance;
        if d < stop {
            return Some(s);
        }
        if s >= 1.0 || rate == 0.0 {
            return None;
        }
        s = (s + ((d - 0.5 * stop) / rate).max(1e-6)).min(1.0);
    }
    Some(s)
}

/// Rounding allowance of [`clear_of_sphere`], m: the distances `advance` evaluates go through
/// the obstacle's pose (a rotation there and back), some 1e-15 m off at the scale of a scene.
const ROUNDING: f64 = 1e-9;

/// True when the obstacle is a sphere and the path `x0 → x1` over `[t0, t0 + h]` keeps more
/// than `stop` (plus [`ROUNDING`]) from its surface. A sphere turning about its centre keeps its
/// surface in place, and its centre moves at most `speed · h` over the step (`speed`, the
/// obstacle's speed bound over the step), so at any fraction of the path the particle is at
/// least its distance to the segment's closest point to the start centre, less `speed · h`,
/// less the radius, from the surface.
/// False for other shapes, a non-finite path, or a path the bound cannot tell.
fn clear_of_sphere(
    o: &Obstacle,
    x0: Vec3,
    x1: Vec3,
    t0: f64,
    h: f64,
    stop: f64,
    speed: f64,
) -> bool {
    let Shape::Sphere(sphere) = &o.collider.shape else {
        return false;
    };
    let c = o.collider.transform_point(sphere.center, t0);
    let (p, d) = (x0 - c, x1 - x0);
    let dd = d.dot(d);
    let s = if dd > 0.0 {
        (-p.dot(d) / dd).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let nearest = (p + s * d).length();
    nearest - speed * h - sphere.radius.max(0.0) >= stop + ROUNDING
}

/// What an analytic obstacle does to a particle's path `x0 → end` over `[t0, t0 + h]`.
pub(crate) enum Stop {
    /// It started within `stop` of the obstacle (or inside) and ends so: put it here, `stop`
    /// out at `t0 + h`.
    Project(Vec3),
    /// Its path comes within `stop` at this fraction of it ([`sweep`]).
    Hit(f64),
}

/// The analytic obstacle's rule for a path (the fail-safe's stage 1): a particle that starts
/// within `stop` of it only has to end `stop` out; any other is swept. `None` when the path
/// keeps clear.
pub(crate) fn obstacle_stop(
    o: &Obstacle,
    x0: Vec3,
    end: Vec3,
    t0: f64,
    h: f64,
    stop: f64,
) -> Option<Stop> {
    if o.collider.closest(x0, t0).signed_distance < stop {
        // started (too) close: only make sure it ends outside
        let c = o.collider.closest(end, t0 + h);
        (c.signed_distance < stop).then(|| Stop::Project(c.point + c.normal * stop))
    } else {
        sweep(o, x0, end, t0, h, stop).map(Stop::Hit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::colliders::{Collider, Motion, Sphere};
    use proptest::prelude::*;

    fn sphere(center: Vec3, radius: f64, velocity: Vec3, angular_velocity: Vec3) -> Obstacle {
        Obstacle {
            name: None,
            collider: Collider::moving(
                Shape::Sphere(Sphere { center, radius }),
                Motion::Constant {
                    velocity,
                    angular_velocity,
                },
            ),
            friction: 0.0,
        }
    }

    /// The advancement alone, with `sweep`'s rate.
    fn advanced(o: &Obstacle, x0: Vec3, x1: Vec3, t0: f64, h: f64, stop: f64) -> Option<f64> {
        let (speed, spin) = o.collider.speed_bound(t0, t0 + h);
        advance(o, x0, x1, t0, h, stop, rate(o, x0, x1, h, speed, spin))
    }

    /// [`clear_of_sphere`] with the obstacle's speed bound over the step, as `sweep` calls it.
    fn clear(o: &Obstacle, x0: Vec3, x1: Vec3, t0: f64, h: f64, stop: f64) -> bool {
        clear_of_sphere(o, x0, x1, t0, h, stop, o.collider.speed_bound(t0, t0 + h).0)
    }

    fn vec3(r: f64) -> impl Strategy<Value = Vec3> {
        (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        /// Whenever the sphere bound says a path is clear, the advancement finds no stop
        /// either, so `sweep` gives what the advancement alone gives, on any path: moving and
        /// turning spheres, paths passing by, through or along the surface.
        #[test]
        fn the_sphere_bound_never_hides_a_stop(
            center in vec3(1.0),
            radius in 0.05f64..0.6,
            velocity in vec3(2.0),
            spin in vec3(8.0),
            dir in vec3(1.0),
            gap in 0.0f64..0.05,
            path in vec3(0.08),
            t0 in 0.0f64..2.0,
            stop in 1e-4f64..1e-3,
        ) {
            let o = sphere(center, radius, velocity, spin);
            let h = 0.01;
            let n = if dir.length() > 1e-3 { dir.normalize() } else { Vec3::Y };
            let c0 = o.collider.transform_point(center, t0);
            let x0 = c0 + n * (radius + stop + gap);
            let x1 = x0 + path;
            let want = advanced(&o, x0, x1, t0, h, stop);
            if clear(&o, x0, x1, t0, h, stop) {
                prop_assert_eq!(want, None);
            }
            prop_assert_eq!(sweep(&o, x0, x1, t0, h, stop), want);
        }
    }

    /// The case the bound is for: a particle resting 2 mm above a sphere of radius 0.5 m that
    /// turns at 180°/s, carried 1.6 cm along its surface in a step, is proved clear (without
    /// the bound the advancement would take about `rate / (d - stop/2)` ≈ 17 evaluations).
    #[test]
    fn a_particle_carried_along_a_turning_sphere_is_proved_clear() {
        let w = std::f64::consts::PI;
        let o = sphere(Vec3::ZERO, 0.5, Vec3::ZERO, Vec3::new(0.0, w, 0.0));
        let (h, stop) = (0.01, 2e-4);
        let r = 0.502;
        let x0 = Vec3::new(r, 0.0, 0.0);
        let x1 = Vec3::new(r * (w * h).cos(), 0.0, -r * (w * h).sin());
        assert!(clear(&o, x0, x1, 0.0, h, stop));
        assert_eq!(sweep(&o, x0, x1, 0.0, h, stop), None);
        // and one path that does hit is not
        let into = Vec3::new(0.49, 0.0, 0.0);
        assert!(!clear(&o, x0, into, 0.0, h, stop));
        assert!(sweep(&o, x0, into, 0.0, h, stop).is_some());
    }
}
