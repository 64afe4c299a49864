//! The friction stage: Coulomb friction on the solved velocities, cloth–cloth contacts first,
//! then obstacle contacts ([`crate::collision::friction`]), and the end-of-step positions.
//!
//! A held obstacle contact's solved normal displacement (what brings the particle to the
//! thickness) is kept as a position correction while its normal velocity is set to the
//! surface's: the particle ends the step at rest on the surface, not flying off it.

use crate::collision::friction::{apply_contact_friction, apply_obstacle_friction};
use crate::collision::settings::CollisionSettings;
use crate::constraints::obstacle::ObstacleContact;
use crate::forces::Repulsions;
use crate::math::Vec3;
use crate::model::Model;

/// Applies friction to `v` and sets `x = x₀ + h v` plus the contacts' position corrections.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run(
    model: &Model,
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
            &model.pinned,
            &r.stencils,
            &r.penalty,
            settings.friction,
            h,
        );
    }
    apply_obstacle_friction(v, &model.mass, contacts, impulse);
    for i in 0..x.len() {
        x[i] = x0[i] + h * v[i];
    }
    for ct in contacts {
        let i = ct.particle as usize;
        x[i] += h * ct.normal * ct.normal.dot(solved[i] - v[i]);
    }
}
