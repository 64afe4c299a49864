//! The detect stage: the contacts a step starts with, found once at the start positions.
//!
//! * obstacle contacts: candidates of the active set ([`crate::constraints::obstacle::find`]);
//! * cloth–cloth contacts: vertex–triangle and edge–edge pairs closer than the thickness become
//!   repulsion stencils ([`Repulsions`]) whose Jacobians enter the system matrix.

use super::guard::Start;
use super::pose::Pose;
use crate::collision::broad_phase::candidates;
use crate::collision::proximity::proximities;
use crate::collision::repulsion::Penalty;
use crate::constraints::obstacle::{self, ObstacleContact};
use crate::forces::Repulsions;
use crate::model::Model;

/// The contacts of one step.
#[derive(Clone, Debug, Default)]
pub(crate) struct Contacts {
    /// Candidate obstacle contacts.
    pub obstacle: Vec<ObstacleContact>,
    /// Cloth–cloth repulsion stencils (none without self-collision or close pairs).
    pub repulsions: Option<Repulsions>,
}

/// The contacts at the start of the step (none with collisions off).
pub(crate) fn contacts(
    model: &Model,
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    start: &Start,
    pose: &Pose,
) -> Contacts {
    let Some(c) = &model.collision else {
        return Contacts::default();
    };
    let (x0, v0) = (&start.x0, &start.v0);
    let obstacle = obstacle::find(
        x0,
        v0,
        &model.pinned,
        &model.obstacles,
        pose.t0,
        pose.h,
        c.thickness,
        model.gravity.length() * pose.h,
    );
    let repulsions = if c.self_collision {
        let cand = candidates(x0, x0, triangles, edges, c.thickness);
        let mut stencils = proximities(x0, triangles, edges, &cand, c.thickness);
        stencils.retain(|s| s.particles.iter().any(|&p| !model.pinned[p as usize]));
        (!stencils.is_empty()).then(|| Repulsions {
            stencils,
            penalty: Penalty {
                thickness: c.thickness,
                stiffness: c.stiffness,
                tangential: false,
            },
        })
    } else {
        None
    };
    Contacts {
        obstacle,
        repulsions,
    }
}
