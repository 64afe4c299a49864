//! The fail-safe stage: nothing crosses anything over the step
//! ([`crate::collision::failsafe`]). Particles the fail-safe stopped or carried get the velocity
//! of their corrected path; those only projected out of an obstacle they started in keep
//! theirs (a position correction, not a motion).

use super::pose::Pose;
use crate::collision::bvh::TreeCache;
use crate::collision::failsafe::{FailsafeReport, failsafe};
use crate::collision::seam_crossings::SeamCrossings;
use crate::collision::settings::CollisionSettings;
use crate::math::Vec3;
use crate::model::Model;

/// Corrects the end-of-step positions `x` (and the velocities of the particles it moved),
/// letting through the pairs `exempt` names (see [`crate::collision::failsafe::failsafe`]); returns what it did (colliding
/// pairs CCD found, pairs tested, rounds, swept-box builds), or why collisions could not be
/// resolved.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run(
    model: &Model,
    settings: &CollisionSettings,
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    pose: &Pose,
    exempt: &(dyn Fn(&[u32; 4]) -> bool + Sync),
    seam_crossings: &SeamCrossings,
    x0: &[Vec3],
    x: &mut [Vec3],
    v: &mut [Vec3],
    cache: &mut TreeCache,
) -> Result<FailsafeReport, String> {
    let h = pose.h;
    let before = x.to_vec();
    let r = failsafe(
        x0,
        x,
        &pose.pinned,
        triangles,
        edges,
        &model.obstacles,
        pose.t0,
        h,
        settings.thickness,
        settings.self_collision,
        exempt,
        seam_crossings,
        cache,
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
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::seams::Seams;
    use crate::constraints::pins::PinTargets;
    use crate::step::testing;

    #[test]
    fn a_particle_stopped_at_the_ground_gets_the_velocity_of_its_shortened_path() {
        let m = testing::sheet_on_ground(3, 0.05);
        let settings = m.collision.unwrap();
        let h = 0.01;
        let pose = Pose {
            t0: 0.0,
            h,
            pins: PinTargets::default(),
            pinned: m.pinned.clone(),
            surface_speed: 0.0,
        };
        let x0 = m.x.clone();
        let mut v = vec![Vec3::new(0.0, -1.0, 0.0); x0.len()];
        // particle 0 would go 10 cm down, through the ground
        v[0] = Vec3::new(0.0, -10.0, 0.0);
        let mut x: Vec<Vec3> = x0.iter().zip(&v).map(|(p, u)| *p + h * *u).collect();
        let moved_before = x.clone();
        run(
            &m,
            &settings,
            &[],
            &[],
            &pose,
            &|_| false,
            &SeamCrossings::default(),
            &x0,
            &mut x,
            &mut v,
            &mut TreeCache::default(),
        )
        .unwrap();
        assert!(x[0].y >= 0.0 && x[0].y < x0[0].y, "{}", x[0]);
        assert_eq!(v[0], (x[0] - x0[0]) / h);
        // the others were not touched
        assert_eq!(&x[1..], &moved_before[1..]);
        assert!(v[1..].iter().all(|u| *u == Vec3::new(0.0, -1.0, 0.0)));
    }

    /// Two stacked rows pushed onto each other over a step: the fail-safe holds them apart,
    /// unless they are stitched vertex to vertex (a seam closing).
    #[test]
    fn a_stitched_pair_may_close_through_the_failsafe() {
        let mut m = testing::sheet_on_ground(4, 0.5);
        for i in 8..16 {
            m.x[i] = m.x[i - 8] + Vec3::new(0.0, 0.002, 0.0);
        }
        let settings = m.collision.unwrap();
        let pose = crate::step::pose::at(&m, 0.0, 0.01);
        let (tris, edges) = (m.triangles(), m.edges());
        let x0 = m.x.clone();
        let x1: Vec<Vec3> = (0..16)
            .map(|i| match i >= 8 {
                true => x0[i - 8] + Vec3::new(0.0, 1e-9, 0.0),
                false => x0[i],
            })
            .collect();
        let end = |seams: &Seams| {
            let (mut x, mut v) = (x1.clone(), vec![Vec3::ZERO; 16]);
            run(
                &m,
                &settings,
                &tris,
                &edges,
                &pose,
                &|ids| seams.exempt(ids),
                &SeamCrossings::default(),
                &x0,
                &mut x,
                &mut v,
                &mut TreeCache::default(),
            )
            .unwrap();
            x
        };
        assert_ne!(end(&Seams::default()), x1, "unsewn: held apart");
        let seam: Vec<[u32; 2]> = (8..16).map(|i| [i, i - 8]).collect();
        assert_eq!(end(&Seams::new(16, &tris, &seam)), x1, "sewn: closes");
    }
}
