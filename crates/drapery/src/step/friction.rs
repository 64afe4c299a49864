//! The friction stage: Coulomb friction on the solved velocities, cloth–cloth contacts first,
//! then obstacle contacts ([`crate::collision::friction`]), and the end-of-step positions.
//!
//! Obstacle friction acts twice: in the solve, as the lagged Coulomb damping of the previous
//! step's normal force ([`crate::forces::ObstacleFrictions`]), and here, as Coulomb friction
//! with what is left of this step's budget `μ λ` once the solve's friction impulse
//! `h c |u_t|` is taken off (docs/MATH.md §25): all of it at a first touch, next to nothing on
//! a contact that rests or slides steadily.
//!
//! A held obstacle contact's solved normal displacement (what brings the particle to the
//! thickness) is kept as a position correction while its normal velocity is set to the
//! surface's: the particle ends the step at rest on the surface, not flying off it.

use crate::collision::friction::{apply_contact_friction, apply_obstacle_friction};
use crate::collision::settings::CollisionSettings;
use crate::constraints::obstacle::ObstacleContact;
use crate::forces::Repulsions;
use crate::forces::obstacle_friction::sliding;
use crate::math::Vec3;
use crate::model::Model;

/// Applies friction to `v` and sets `x = x₀ + h v` plus the contacts' position corrections.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run(
    model: &Model,
    pinned: &[bool],
    settings: &CollisionSettings,
    repulsions: Option<&Repulsions>,
    contacts: &[ObstacleContact],
    impulse: &[f64],
    x0: &[Vec3],
    h: f64,
    x: &mut [Vec3],
    v: &mut [Vec3],
) {
    let solved = v.to_vec();
    if let Some(r) = repulsions {
        apply_contact_friction(
            v,
            x,
            &model.mass,
            pinned,
            &r.stencils,
            &r.penalty,
            settings.friction,
            h,
        );
    }
    let left = remaining(contacts, impulse, &solved, h);
    apply_obstacle_friction(v, &model.mass, contacts, &left);
    for i in 0..x.len() {
        x[i] = x0[i] + h * v[i];
    }
    for ct in contacts {
        let i = ct.particle as usize;
        x[i] += h * ct.normal * ct.normal.dot(solved[i] - v[i]);
    }
}

/// Each held contact's normal impulse `λ` less the friction impulse the solve already applied,
/// `h c |u_t|` over `μ` (the impulse whose Coulomb budget that was), never below 0: the normal
/// impulse whose `μ λ` the Coulomb friction after the solve may still use.
fn remaining(contacts: &[ObstacleContact], impulse: &[f64], solved: &[Vec3], h: f64) -> Vec<f64> {
    contacts
        .iter()
        .zip(impulse)
        .map(|(ct, &l)| {
            if ct.damping > 0.0 && ct.friction > 0.0 {
                let u = sliding(ct, solved[ct.particle as usize]).length();
                (l - h * ct.damping * u / ct.friction).max(0.0)
            } else {
                l
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::step::testing;

    #[test]
    fn a_held_particle_keeps_its_solved_normal_displacement_and_ends_at_rest_on_the_surface() {
        let m = testing::sheet_on_ground(3, 0.003);
        let settings = m.collision.unwrap();
        let h = 0.01;
        let x0 = m.x.clone();
        // particle 4 held: the solve gave it the normal velocity that brings it to the
        // thickness, and it slides at 1 m/s; its impulse is large enough for static friction
        let target = (settings.thickness - x0[4].y) / h;
        let ct = ObstacleContact {
            particle: 4,
            normal: Vec3::Y,
            normal_velocity: target,
            surface_velocity: Vec3::ZERO,
            friction: 0.5,
            damping: 0.0,
        };
        let mut v = vec![Vec3::ZERO; x0.len()];
        v[4] = Vec3::new(1.0, target, 0.0);
        v[3] = Vec3::new(0.2, -0.1, 0.0);
        let mut x = x0.clone();
        run(
            &m,
            &m.pinned,
            &settings,
            None,
            &[ct],
            &[1.0],
            &x0,
            h,
            &mut x,
            &mut v,
        );
        assert!((x[4].y - settings.thickness).abs() < 1e-15, "{}", x[4]);
        assert_eq!(
            v[4],
            Vec3::ZERO,
            "static friction stops it and the normal speed is the surface's"
        );
        assert_eq!(x[4].x, x0[4].x);
        // a particle without contact just moves
        assert_eq!(x[3], x0[3] + h * Vec3::new(0.2, -0.1, 0.0));
    }
}
