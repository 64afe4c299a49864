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

/// A bumpy 2 m grid deforming over 4 files at 10 files per second: file `k` moves vertex `i`
/// by a different amount along each axis.
fn deforming_grid() -> (Vec<Vec<Vec3>>, Vec<[u32; 3]>) {
    let g = crate::mesh::Mesh::grid([2.0, 2.0], [7, 6], Vec3::ZERO, Vec3::Z).unwrap();
    let frames = (0..4)
        .map(|k| {
            let f = k as f64;
            g.positions
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let a = i as f64 * 0.37 + f;
                    *p + Vec3::new(0.1 * f, 0.05 * (a.sin()), 0.2 * (a * 1.3).cos() + 0.1 * f)
                })
                .collect()
        })
        .collect();
    (frames, g.triangles())
}

#[test]
fn a_mesh_sequence_blends_its_files_linearly_and_holds_at_both_ends() {
    let (frames, tris) = deforming_grid();
    let s = MeshSequence::new(frames.clone(), tris, 10.0);
    for (k, f) in frames.iter().enumerate() {
        assert_eq!(&s.vertices_at(k as f64 / 10.0), f, "file {k}");
    }
    assert_eq!(s.vertices_at(-1.0), frames[0]);
    assert_eq!(s.vertices_at(5.0), frames[3]);
    let mid = s.vertices_at(0.125);
    for i in 0..mid.len() {
        let want = frames[1][i] + 0.25 * (frames[2][i] - frames[1][i]);
        assert!((mid[i] - want).length() < 1e-15);
    }
    assert!(Shape::Sequence(s.clone()).deforms() && !Shape::Sequence(s).is_solid());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// The per-interval BVH boxes hold every blend: the closest point equals brute force at any
    /// time; the surface velocity is the blend of the vertices' velocities, which is the time
    /// derivative of the material point; the speed bound holds.
    #[test]
    fn mesh_sequence_queries_match_brute_force_at_any_time(
        p in prop::array::uniform3(-1.5..1.5f64),
        t in -0.05..0.4f64,
    ) {
        let (frames, tris) = deforming_grid();
        let s = MeshSequence::new(frames, tris.clone(), 10.0);
        let c = Collider::fixed(Shape::Sequence(s.clone()));
        let p = Vec3::from_array(p);
        let v = s.vertices_at(t);
        let brute = tris
            .iter()
            .map(|tr| point_triangle(p, v[tr[0] as usize], v[tr[1] as usize], v[tr[2] as usize]).dist)
            .fold(f64::INFINITY, f64::min);
        let r = c.closest(p, t);
        prop_assert!((r.signed_distance - brute).abs() < 1e-14, "{} vs {brute}", r.signed_distance);
        // the material point with the closest point's barycentric weights, followed in time
        let ti = r.triangle.unwrap() as usize;
        let pt = point_triangle(p, v[tris[ti][0] as usize], v[tris[ti][1] as usize], v[tris[ti][2] as usize]);
        let at = |t: f64| {
            let w = s.vertices_at(t);
            let [a, b, cc] = tris[ti].map(|i| w[i as usize]);
            a * pt.bary[0] + b * pt.bary[1] + cc * pt.bary[2]
        };
        let interior = |t: f64| {
            let f = t * 10.0;
            f > 0.0 && f < 3.0 && (f - f.round()).abs() > 1e-4
        };
        if interior(t) {
            let d = 1e-6;
            let fd = (at(t + d) - at(t - d)) / (2.0 * d);
            prop_assert!((fd - r.velocity_at_point).length() < 1e-7, "{fd} vs {}", r.velocity_at_point);
            prop_assert!(r.velocity_at_point.length() <= c.speed_bound(t, t).0 * (1.0 + 1e-12));
        }
        // carried along, the point stays at the same barycentric place and offset
        let moved = c.carry(p, t, t + 0.05);
        prop_assert!((moved - (at(t + 0.05) + (p - pt.q))).length() < 1e-12);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// A keyframed collider's surface velocity at a contact is the time derivative of that
    /// material point's path, in both interpolations.
    #[test]
    fn keyframed_surface_velocity_is_the_derivative_of_the_material_path(
        which in 0usize..4,
        p in prop::array::uniform3(-1.5..1.5f64),
        t in 0.01..2.9f64,
        smooth in any::<bool>(),
    ) {
        use crate::animation::{Interpolation, Keyframe, Track};
        let keys = vec![
            Keyframe::at(0.0),
            Keyframe { time: 1.0, translation: Vec3::new(0.3, 0.1, 0.0), rotation: DQuat::from_rotation_y(0.8) },
            Keyframe { time: 2.0, translation: Vec3::new(0.1, 0.5, -0.2), rotation: DQuat::from_rotation_x(-0.5) },
            Keyframe { time: 3.0, translation: Vec3::ZERO, rotation: DQuat::from_rotation_z(1.0) },
        ];
        let interp = if smooth { Interpolation::Smooth } else { Interpolation::Linear };
        let c = Collider::moving(
            shapes()[which].clone(),
            Motion::Keyframed(Track::new(keys, interp, "c").unwrap()),
        );
        let r = c.closest(Vec3::from_array(p), t);
        let x0 = c.to_local(r.point, t);
        let d = 1e-6;
        if ((t + 0.5) % 1.0 - 0.5).abs() > 2.0 * d || smooth {
            let fd = (c.transform_point(x0, t + d) - c.transform_point(x0, t - d)) / (2.0 * d);
            prop_assert!((fd - r.velocity_at_point).length() < 1e-6, "{fd} vs {}", r.velocity_at_point);
        }
    }
}
