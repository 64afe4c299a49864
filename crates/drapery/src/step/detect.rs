//! The detect stage: the contacts a step starts with, found once at the start positions.
//!
//! * obstacle contacts: candidates of the active set ([`crate::constraints::obstacle::find`]);
//! * cloth–cloth contacts: vertex–triangle and edge–edge pairs closer than the thickness become
//!   repulsion stencils ([`Repulsions`]) whose Jacobians enter the system matrix, except the
//!   exempt ones: those within a stitched neighbourhood ([`Seams`]), which must be free to
//!   close, and those around a crossing the cloth started with ([`super::tangles`]), which
//!   repulsion would hold crossed;
//! * cloth–collider contacts: cloth edges and triangles within twice the thickness of a mesh
//!   collider's sharp edges and vertices become repulsion stencils too
//!   ([`ObstacleRepulsions`], docs/MATH.md §24), except those of cloth being pushed out of a
//!   collider it started inside;
//! * obstacle friction in the solve: each obstacle candidate whose particle was held in the
//!   previous step gets the lagged Coulomb damping of that step's normal force
//!   ([`ObstacleFrictions`], docs/MATH.md §25).

use super::guard::Start;
use super::pose::Pose;
use crate::collision::broad_phase::{Candidates, SweptBoxes};
use crate::collision::bvh::TreeCache;
use crate::collision::obstacle_proximity::{SharpFeatures, obstacle_proximities};
use crate::collision::proximity::{Proximity, proximities};
use crate::collision::repulsion::Penalty;
use crate::constraints::obstacle::{self, ObstacleContact};
use crate::forces::obstacle_friction;
use crate::forces::obstacle_repulsion::{lagged_coulomb, sliding};
use crate::forces::{Force, ObstacleFrictions, ObstacleRepulsions, Repulsions};
use crate::math::Vec3;
use crate::model::Model;

/// The contacts of one step.
#[derive(Clone, Debug, Default)]
pub(crate) struct Contacts {
    /// Candidate obstacle contacts.
    pub obstacle: Vec<ObstacleContact>,
    /// Cloth–cloth repulsion stencils (none without self-collision or close pairs).
    pub repulsions: Option<Repulsions>,
    /// Candidate pairs of the self-contacts (the broad phase's, or the previous fail-safe's).
    pub candidates: usize,
    /// Broad-phase builds (1 with self-collision unless the pairs were known, else 0).
    pub builds: usize,
    /// Cloth–collider repulsion stencils (none without mesh colliders or close pairs).
    pub obstacle_repulsions: Option<ObstacleRepulsions>,
    /// Friction of the obstacle candidates that have a lagged normal force.
    pub obstacle_friction: Option<ObstacleFrictions>,
}

impl Contacts {
    /// The contact forces of the step: cloth–cloth repulsion, cloth–collider repulsion, then
    /// obstacle friction.
    pub fn forces(&self) -> Vec<&dyn Force> {
        let cloth = self.repulsions.as_ref().map(|r| r as &dyn Force);
        let obstacle = self.obstacle_repulsions.as_ref().map(|r| r as &dyn Force);
        let friction = self.obstacle_friction.as_ref().map(|r| r as &dyn Force);
        cloth.into_iter().chain(obstacle).chain(friction).collect()
    }
}

/// The cloth–cloth repulsion stencils at `x` among the candidate pairs `cand`: the pairs closer
/// than `thickness` with a particle that is not pinned and not `exempt` (a seam's
/// neighbourhood, a starting tangle), of a vertex's pairs with the triangles around one edge or
/// vertex only the closest ([`crate::collision::proximity::closest_only`]).
pub(crate) fn self_stencils(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    cand: &Candidates,
    thickness: f64,
    pose: &Pose,
    exempt: &(dyn Fn(&[u32; 4]) -> bool + Sync),
) -> Vec<Proximity> {
    let mut stencils = proximities(x, triangles, edges, cand, thickness);
    stencils
        .retain(|s| s.particles.iter().any(|&p| !pose.pinned[p as usize]) && !exempt(&s.particles));
    crate::collision::proximity::closest_only(&mut stencils);
    stencils
}

/// The contacts at the start of the step (none with collisions off). `normal_force` is each
/// particle's obstacle normal force in the previous step (N; 0 where none held it); `cache`
/// keeps the broad phase's tree orders from step to step (speed only); `known`, when given,
/// holds every cloth pair within the thickness at the start positions (the previous step's
/// fail-safe found them), so the broad phase need not run.
#[allow(clippy::too_many_arguments)]
pub(crate) fn contacts(
    model: &Model,
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    start: &Start,
    pose: &Pose,
    normal_force: &[f64],
    exempt: &(dyn Fn(&[u32; 4]) -> bool + Sync),
    cache: &mut TreeCache,
    known: Option<&Candidates>,
) -> Contacts {
    let Some(c) = &model.collision else {
        return Contacts::default();
    };
    let (x0, v0) = (&start.x0, &start.v0);
    let mut obstacle = obstacle::find(
        x0,
        v0,
        &pose.pinned,
        &model.obstacles,
        pose.t0,
        pose.h,
        c.thickness,
        model.gravity.length() * pose.h,
    );
    // friction in the solve, lagged Coulomb: the previous step's normal force at the starting
    // sliding speed (viscous below 1 mm/s)
    for ct in &mut obstacle {
        let i = ct.particle as usize;
        let n = normal_force.get(i).copied().unwrap_or(0.0);
        let slide = obstacle_friction::sliding(ct, v0[i]).length();
        ct.damping = lagged_coulomb(ct.friction * n, slide);
    }
    let rubbing: Vec<ObstacleContact> = obstacle
        .iter()
        .filter(|ct| ct.damping > 0.0 && ct.damping.is_finite())
        .copied()
        .collect();
    let obstacle_friction = (!rubbing.is_empty()).then(|| ObstacleFrictions::new(rubbing));
    let (mut pairs, mut builds) = (0, 0);
    let penalty = Penalty {
        thickness: c.thickness,
        stiffness: c.stiffness,
        tangential: false,
    };
    let repulsions = if c.self_collision {
        let found;
        let cand = match known {
            Some(k) => k,
            None => {
                let boxes = SweptBoxes::cached(x0, x0, triangles, edges, c.thickness, cache);
                found = boxes.close(x0, x0);
                builds = 1;
                &found
            }
        };
        pairs = cand.vt.len() + cand.ee.len();
        let stencils = self_stencils(x0, triangles, edges, cand, c.thickness, pose, exempt);
        (!stencils.is_empty()).then(|| Repulsions::new(stencils, penalty))
    } else {
        None
    };
    let n = model.particle_count() as u32;
    let mut near = Vec::new();
    for (k, o) in model.obstacles.iter().enumerate() {
        let (Some((v0, tris)), Some((v1, _))) = (
            o.collider.surface(pose.t0),
            o.collider.surface(pose.t0 + pose.h),
        ) else {
            continue;
        };
        let features = SharpFeatures::new(v0, v1, tris);
        let margin = 2.0 * c.thickness;
        let owner = (k as u32, pose.h);
        let mut close = obstacle_proximities(x0, triangles, edges, &features, owner, margin);
        // friction, lagged Coulomb: the Coulomb force of the starting normal force at the
        // starting sliding speed (viscous below 1 mm/s)
        for p in &mut close {
            let normal = c.stiffness * (c.thickness - p.dist).max(0.0);
            p.damping = lagged_coulomb(o.friction * normal, sliding(p, &start.v0).length());
        }
        near.extend(close);
    }
    // (the obstacle is particle `n` for `exempt`, as in the fail-safe's pairs)
    near.retain(|s| {
        let [a, b, c] = s.particles;
        s.particles.iter().any(|&p| !pose.pinned[p as usize]) && !exempt(&[a, b, c, n])
    });
    let obstacle_repulsions = (!near.is_empty()).then(|| ObstacleRepulsions::new(near, penalty));
    Contacts {
        obstacle,
        repulsions,
        candidates: pairs,
        builds,
        obstacle_repulsions,
        obstacle_friction,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::seams::Seams;
    use crate::step::{pose, testing};

    #[test]
    fn contacts_need_collisions_on_and_all_pinned_stencils_are_dropped() {
        let h = 0.01;
        let start = |m: &Model| Start {
            x0: m.x.clone(),
            v0: vec![Vec3::ZERO; m.particle_count()],
            ke0: 0.0,
        };
        // a folded sheet: its two halves 2 mm apart
        let mut m = testing::sheet_on_ground(4, 0.002);
        for i in 8..16 {
            m.x[i] = m.x[i - 8] + Vec3::new(0.0, 0.002, 0.0);
        }
        // the model's contacts, no seam, a fresh tree cache, no pairs passed on
        let plain = |m: &Model, pose: &pose::Pose| {
            let (tris, edges) = (m.triangles(), m.edges());
            let cache = &mut TreeCache::default();
            contacts(
                m,
                &tris,
                &edges,
                &start(m),
                pose,
                &[],
                &|_| false,
                cache,
                None,
            )
        };
        let pose = pose::at(&m, 0.0, h);
        let c = plain(&m, &pose);
        assert!(
            !c.obstacle.is_empty(),
            "particles 2 mm above the ground touch it"
        );
        let r = c
            .repulsions
            .expect("the folded halves are within the thickness");
        assert!(r.stencils.iter().all(|s| s.dist < 0.005));
        // pin every particle: no stencil and no obstacle contact is left
        m.pinned = vec![true; m.particle_count()];
        let pose = pose::at(&m, 0.0, h);
        let c = plain(&m, &pose);
        assert!(c.obstacle.is_empty() && c.repulsions.is_none());
        // collisions off: nothing
        m.collision = None;
        m.pinned = vec![false; m.particle_count()];
        let c = plain(&m, &pose);
        assert!(c.obstacle.is_empty() && c.repulsions.is_none());
    }

    /// The folded sheet again, its halves stitched vertex to vertex: every close pair lies in a
    /// stitched neighbourhood and gets no repulsion; one stitch leaves the others' pairs.
    #[test]
    fn pairs_within_a_stitched_neighbourhood_get_no_repulsion() {
        let mut m = testing::sheet_on_ground(4, 0.5);
        for i in 8..16 {
            m.x[i] = m.x[i - 8] + Vec3::new(0.0, 0.002, 0.0);
        }
        let start = Start {
            x0: m.x.clone(),
            v0: vec![Vec3::ZERO; m.particle_count()],
            ke0: 0.0,
        };
        let (tris, edges) = (m.triangles(), m.edges());
        let pose = pose::at(&m, 0.0, 0.01);
        let n = m.particle_count();
        let count = |seams: &Seams| {
            contacts(
                &m,
                &tris,
                &edges,
                &start,
                &pose,
                &[],
                &|ids| seams.exempt(ids),
                &mut TreeCache::default(),
                None,
            )
            .repulsions
            .map_or(0, |r| r.stencils.len())
        };
        let all: Vec<[u32; 2]> = (8..16).map(|i| [i, i - 8]).collect();
        let unsewn = count(&Seams::default());
        assert!(unsewn > 0);
        assert_eq!(count(&Seams::new(n, &tris, &all)), 0);
        let one = count(&Seams::new(n, &tris, &all[..1]));
        assert!(0 < one && one < unsewn, "{one} of {unsewn}");
    }
}
