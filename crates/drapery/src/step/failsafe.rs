//! The fail-safe stage: nothing crosses anything over the step
//! ([`crate::collision::failsafe`]). Particles the fail-safe stopped or carried get the velocity
//! of their corrected path; those only projected out of an obstacle they started in keep
//! theirs (a position correction, not a motion).

use super::pose::Pose;
use crate::collision::failsafe::failsafe;
use crate::collision::settings::CollisionSettings;
use crate::math::Vec3;
use crate::model::Model;

/// Corrects the end-of-step positions `x` (and the velocities of the particles it moved);
/// returns the colliding pairs CCD found, or why collisions could not be resolved.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run(
    model: &Model,
    settings: &CollisionSettings,
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    pose: &Pose,
    x0: &[Vec3],
    x: &mut [Vec3],
    v: &mut [Vec3],
) -> Result<usize, String> {
    let h = pose.h;
    let before = x.to_vec();
    let r = failsafe(
        x0,
        x,
        &model.pinned,
        triangles,
        edges,
        &model.obstacles,
        pose.t0,
        h,
        settings.thickness,
        settings.self_collision,
    )?;
    let mut keep_velocity = vec![false; x.len()];
    r.projected
        .iter()
        .for_each(|&p| keep_velocity[p as usize] = true);
    for i in 0..x.len() {
        if x[i] != before[i] && !keep_velocity[i] {
            v[i] = (x[i] - x0[i]) / h;
        }
    }
    Ok(r.ccd_hits)
}
