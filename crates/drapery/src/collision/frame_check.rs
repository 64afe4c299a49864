//! Checking one output frame against the "nothing passes through anything" rule: what
//! `drapery check` counts.
//!
//! [`check_frame`] takes the cloth positions and triangles of a frame (all cloths together: a
//! pair of triangles from two cloths is checked like a pair from one) and the colliders, and
//! counts at the frame's time `t`:
//! * intersecting cloth triangle pairs not sharing a vertex, the two vertices of a stitched pair
//!   counting as one ([`super::check::count_sewn_intersections`]);
//! * cloth vertices deeper than `tol` inside an analytic collider ([`super::check::count_penetrations`]);
//! * pairs (cloth triangle, obstacle triangle) that intersect, for each mesh collider posed at `t`
//!   ([`super::check::count_intersections_between`]).

use super::check::{count_intersections_between, count_penetrations, count_sewn_intersections};
use super::colliders::Collider;
use crate::math::Vec3;

/// What [`check_frame`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameCheck {
    /// Intersecting cloth triangle pairs (within a cloth or between cloths).
    pub self_intersections: usize,
    /// Cloth vertices inside an analytic collider by more than the tolerance.
    pub penetrations: usize,
    /// Intersecting (cloth triangle, mesh-collider triangle) pairs, over all mesh colliders.
    pub mesh_intersections: usize,
}

impl FrameCheck {
    /// True when nothing intersects.
    pub fn is_clean(&self) -> bool {
        *self == FrameCheck::default()
    }
}

/// Counts the intersections of one frame at time `t` (see the module docs), with the stitched
/// particle pairs `stitches`. `tol` is the depth,
/// in metres, below which a vertex inside an analytic collider is not counted.
pub fn check_frame(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    stitches: &[[u32; 2]],
    colliders: &[Collider],
    t: f64,
    tol: f64,
) -> FrameCheck {
    let mut r = FrameCheck {
        self_intersections: count_sewn_intersections(x, triangles, stitches),
        penetrations: count_penetrations(x, colliders, t, tol),
        mesh_intersections: 0,
    };
    for c in colliders {
        if let Some((posed, tris)) = c.surface(t) {
            r.mesh_intersections += count_intersections_between(x, triangles, &posed, tris);
        }
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    #[allow(unused_imports)]
    use crate::collision::colliders::{
        Capsule, Collider, Cuboid, Motion, Plane, Shape, Sphere, TriangleMesh,
    };
    use crate::mesh::Mesh;

    #[test]
    fn counts_each_kind_and_follows_the_collider_motion() {
        let sheet = Mesh::grid([1.0, 1.0], [5, 5], Vec3::ZERO, Vec3::Y).unwrap();
        let tris = sheet.triangles();
        let x = sheet.positions.clone();
        // a plate mesh 0.5 m above the sheet, moving down at 1 m/s
        let plate = Mesh::grid([0.5, 0.5], [2, 2], Vec3::new(0.0, 0.5, 0.0), Vec3::X).unwrap();
        let plate = Collider {
            shape: Shape::Mesh(TriangleMesh::new(
                plate.positions.clone(),
                plate.triangles(),
            )),
            motion: Motion::Constant {
                velocity: Vec3::new(0.0, -1.0, 0.0),
                angular_velocity: Vec3::ZERO,
            },
        };
        let ball = Collider::fixed(Shape::Sphere(Sphere {
            center: Vec3::new(0.3, 0.3, 0.3),
            radius: 0.1,
        }));
        let cs = [plate, ball];
        let early = check_frame(&x, &tris, &[], &cs, 0.0, 1e-9);
        assert_eq!(early.mesh_intersections, 0);
        assert!(early.is_clean(), "{early:?}");
        let late = check_frame(&x, &tris, &[], &cs, 0.5, 1e-9);
        assert!(late.mesh_intersections > 0);
        assert_eq!(late.self_intersections, 0);
        // push a vertex into the sphere
        let mut y = x.clone();
        y[24] = Vec3::new(0.3, 0.25, 0.3);
        assert_eq!(check_frame(&y, &tris, &[], &cs, 0.0, 1e-9).penetrations, 1);
    }
}
