//! Tests of the collider kinds and their motion.

use super::*;
use crate::collision::distance::point_triangle;
use proptest::prelude::*;

fn shapes() -> Vec<Shape> {
    vec![
        Shape::Plane(Plane {
            point: Vec3::new(0.0, 0.1, 0.0),
            normal: Vec3::new(0.0, 2.0, 0.0),
        }),
        Shape::Sphere(Sphere {
            center: Vec3::new(0.1, 0.2, 0.3),
            radius: 0.5,
        }),
        Shape::Capsule(Capsule {
            a: Vec3::new(-0.5, 0.0, 0.0),
            b: Vec3::new(0.5, 0.2, 0.0),
            radius: 0.25,
        }),
        Shape::Box(Cuboid {
            center: Vec3::new(0.0, 0.1, 0.0),
            half_extents: Vec3::new(0.5, 0.3, 0.2),
            rotation: DQuat::from_scaled_axis(Vec3::new(0.3, -0.5, 0.8)),
        }),
    ]
}

#[test]
fn hand_values() {
    let c = Collider::fixed(shapes()[0].clone());
    let r = c.closest(Vec3::new(3.0, 1.1, -2.0), 0.0);
    assert!((r.signed_distance - 1.0).abs() < 1e-15 && r.normal == Vec3::Y);
    let c = Collider::fixed(Shape::Sphere(Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    }));
    let r = c.closest(Vec3::new(0.0, 0.0, -3.0), 0.0);
    assert_eq!(
        (r.signed_distance, r.normal, r.point),
        (2.0, -Vec3::Z, -Vec3::Z)
    );
    let r = c.closest(Vec3::ZERO, 0.0);
    assert_eq!((r.signed_distance, r.normal), (-1.0, Vec3::Z));
    let c = Collider::fixed(Shape::Capsule(Capsule {
        a: Vec3::ZERO,
        b: Vec3::X * 2.0,
        radius: 0.5,
    }));
    let r = c.closest(Vec3::new(1.0, 0.0, 0.2), 0.0);
    assert!((r.signed_distance + 0.3).abs() < 1e-15 && r.normal == Vec3::Z);
    let r = c.closest(Vec3::new(3.0, 0.0, 0.0), 0.0);
    assert!((r.signed_distance - 0.5).abs() < 1e-15);
    let c = Collider::fixed(Shape::Box(Cuboid {
        center: Vec3::ZERO,
        half_extents: Vec3::new(1.0, 2.0, 3.0),
        rotation: DQuat::IDENTITY,
    }));
    let r = c.closest(Vec3::new(0.5, 1.9, 0.0), 0.0);
    assert!((r.signed_distance + 0.1).abs() < 1e-15 && r.normal == Vec3::Y);
    let r = c.closest(Vec3::new(2.0, 3.0, 0.0), 0.0);
    assert!((r.signed_distance - 2f64.sqrt()).abs() < 1e-15);
    assert_eq!(r.point, Vec3::new(1.0, 2.0, 0.0));
    // a box rotated 90° about z swaps its x and y extents
    let c = Collider::fixed(Shape::Box(Cuboid {
        center: Vec3::ZERO,
        half_extents: Vec3::new(1.0, 2.0, 3.0),
        rotation: DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2),
    }));
    let r = c.closest(Vec3::new(3.0, 0.0, 0.0), 0.0);
    assert!((r.signed_distance - 1.0).abs() < 1e-12);
    // degenerate parameters
    let c = Collider::fixed(Shape::Plane(Plane {
        point: Vec3::ZERO,
        normal: Vec3::ZERO,
    }));
    assert_eq!(c.closest(Vec3::Z, 0.0).signed_distance, 1.0);
    let c = Collider::fixed(Shape::Box(Cuboid {
        center: Vec3::ZERO,
        half_extents: Vec3::ZERO,
        rotation: DQuat::IDENTITY,
    }));
    assert!(c.closest(Vec3::ZERO, 0.0).normal.is_finite());
}

#[test]
fn moving_shapes() {
    // sphere moving up at 1 m/s
    let c = Collider {
        shape: Shape::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        }),
        motion: Motion::Constant {
            velocity: Vec3::Y,
            angular_velocity: Vec3::Z,
        },
    };
    let r = c.closest(Vec3::new(0.0, 5.0, 0.0), 2.0);
    assert!((r.signed_distance - 2.0).abs() < 1e-12);
    // velocity at the top point (0,3,0): v + ω × (0,1,0) = (0,1,0) + (-1,0,0)
    assert!((r.velocity_at_point - Vec3::new(-1.0, 1.0, 0.0)).length() < 1e-12);
    // rotating plane: normal +y turns about z by π/2 → -x
    let c = Collider {
        shape: Shape::Plane(Plane {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        }),
        motion: Motion::Constant {
            velocity: Vec3::ZERO,
            angular_velocity: Vec3::Z * std::f64::consts::FRAC_PI_2,
        },
    };
    let r = c.closest(Vec3::new(-2.0, 0.0, 0.0), 1.0);
    assert!((r.signed_distance - 2.0).abs() < 1e-12 && (r.normal + Vec3::X).length() < 1e-12);
}

#[test]
fn mesh_collider_matches_brute_force_and_reports_side() {
    let g = crate::mesh::Mesh::grid([2.0, 2.0], [9, 7], Vec3::ZERO, Vec3::Z).unwrap();
    let mut v = g.positions.clone();
    for (i, p) in v.iter_mut().enumerate() {
        p.z = 0.2 * ((i as f64) * 0.7).sin();
    }
    let tris = g.triangles();
    let m = TriangleMesh::new(v.clone(), tris.clone());
    let c = Collider::fixed(Shape::Mesh(m));
    for k in 0..200 {
        let f = k as f64;
        let p = Vec3::new(
            (f * 0.37).sin() * 1.5,
            (f * 0.91).cos() * 1.5,
            (f * 0.13).sin(),
        );
        let r = c.closest(p, 0.0);
        let brute = tris
            .iter()
            .map(|t| point_triangle(p, v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]).dist)
            .fold(f64::INFINITY, f64::min);
        assert!((r.signed_distance - brute).abs() < 1e-14, "{p}");
        assert!(((p - r.point).length() - brute).abs() < 1e-12);
    }
    // flat mesh: side follows the winding (grid normal is +z)
    let flat = TriangleMesh::new(g.positions.clone(), tris.clone());
    let c = Collider::fixed(Shape::Mesh(flat));
    assert_eq!(c.closest(Vec3::new(0.1, 0.1, 0.5), 0.0).side, 1.0);
    let r = c.closest(Vec3::new(0.1, 0.1, -0.5), 0.0);
    assert_eq!((r.side, r.signed_distance), (-1.0, 0.5));
    assert!((r.normal + Vec3::Z).length() < 1e-12);
    let empty = Collider::fixed(Shape::Mesh(TriangleMesh::new(vec![], vec![])));
    assert_eq!(
        empty.closest(Vec3::ZERO, 0.0).signed_distance,
        f64::INFINITY
    );
}

/// A 0.4 m square plate of four triangles centred at `c`, in the plane y = c.y.
fn plate(c: Vec3) -> TriangleMesh {
    let v = [
        (-0.2, -0.2),
        (0.2, -0.2),
        (0.2, 0.2),
        (-0.2, 0.2),
        (0.0, 0.0),
    ]
    .map(|(x, z)| c + Vec3::new(x, 0.0, z));
    TriangleMesh::new(v.to_vec(), vec![[0, 4, 1], [1, 4, 2], [2, 4, 3], [3, 4, 0]])
}

#[test]
fn a_spinning_mesh_turns_about_the_origin_of_its_file_or_its_pivot() {
    let c = Vec3::new(1.0, 0.3, 0.5);
    let w = Vec3::new(0.0, 2.0, 0.0);
    for pivot in [None, Some(Vec3::new(0.7, -1.0, 0.2))] {
        let mut m = plate(c);
        if let Some(p) = pivot {
            m = m.with_pivot(p);
        }
        let o = pivot.unwrap_or(Vec3::ZERO);
        let col = Collider {
            shape: Shape::Mesh(m.clone()),
            motion: Motion::Constant {
                velocity: Vec3::ZERO,
                angular_velocity: w,
            },
        };
        assert_eq!(col.center(), o);
        // step by step, each vertex moves on a circle about the vertical axis through the
        // pivot: same height, same radius
        let radius = |p: Vec3| (p - o).with_y(0.0).length();
        for &v in m.vertices() {
            for k in 1..=600 {
                let t = k as f64 / 60.0;
                let p = col.transform_point(v, t);
                assert!((p.y - v.y).abs() < 1e-14, "{p}");
                assert!((radius(p) - radius(v)).abs() < 1e-13, "{p} at {t}");
            }
            // half a turn takes it to the other side of the pivot
            let p = col.transform_point(v, std::f64::consts::PI / 2.0);
            let want = o + (o - v).with_y(v.y - o.y);
            assert!((p - want).length() < 1e-12, "{p} vs {want}");
        }
        // the surface velocity is that of the rigid rotation about the pivot
        let q = Vec3::new(c.x + 0.05, c.y + 0.1, c.z - 0.03);
        let r = col.closest(q, 0.4);
        let expect = w.cross(r.point - o);
        assert!((r.velocity_at_point - expect).length() < 1e-12);
        assert!(
            r.velocity_at_point.length() > 0.5,
            "off the pivot, it moves"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]

    #[test]
    fn normal_is_gradient_of_signed_distance_and_velocity_is_rigid(
        which in 0usize..4,
        p in prop::array::uniform3(-1.5..1.5f64),
        v in prop::array::uniform3(-1.0..1.0f64),
        w in prop::array::uniform3(-2.0..2.0f64),
        t in 0.0..1.0f64,
    ) {
        let c = Collider {
            shape: shapes()[which].clone(),
            motion: Motion::Constant { velocity: Vec3::from_array(v), angular_velocity: Vec3::from_array(w) },
        };
        let p = Vec3::from_array(p);
        let r = c.closest(p, t);
        prop_assert!((r.normal.length() - 1.0).abs() < 1e-12);
        prop_assert!(((p - r.point).length() - r.signed_distance.abs()).abs() < 1e-12);
        let h = 1e-6;
        let fd = Vec3::new(
            c.closest(p + Vec3::X * h, t).signed_distance - c.closest(p - Vec3::X * h, t).signed_distance,
            c.closest(p + Vec3::Y * h, t).signed_distance - c.closest(p - Vec3::Y * h, t).signed_distance,
            c.closest(p + Vec3::Z * h, t).signed_distance - c.closest(p - Vec3::Z * h, t).signed_distance,
        ) / (2.0 * h);
        // away from the kinks of the distance (medial axis) the gradient is the normal
        let near_kink = (fd.length() - 1.0).abs() > 1e-4;
        if !near_kink {
            prop_assert!((fd - r.normal).length() < 1e-5, "fd={fd} n={}", r.normal);
        }
        // velocity of the closest point as a material point of the moving shape
        let (rot, ct) = c.pose(t);
        let x0 = c.center() + rot.inverse() * (r.point - ct);
        let dt = 1e-6;
        let vfd = (c.transform_point(x0, t + dt) - c.transform_point(x0, t - dt)) / (2.0 * dt);
        prop_assert!((vfd - r.velocity_at_point).length() < 1e-6);
    }
}
