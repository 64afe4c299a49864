//! Triangle meshes of colliders, for pictures and output files.
//!
//! [`tessellate`] turns a [`Collider`] into vertices and triangles in its pose at time `t`
//! (every vertex moved with [`Collider::transform_point`]). Triangles are counter-clockwise seen
//! from outside (their normals point out of the solid; for a plane, to the side its normal points
//! to). Spheres and capsules are latitude–longitude meshes whose vertices lie on the surface
//! (the flat triangles between them cut slightly inside); boxes are 12 triangles; a plane,
//! which is infinite, is drawn as a square of a chosen half size around a chosen point
//! (projected onto the plane); a mesh collider is its own triangles.

use super::colliders::Collider;
use crate::math::Vec3;

/// How finely and how large colliders are drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TessellateOptions {
    /// Segments around a sphere or capsule (≥ 3); half as many from pole to pole.
    pub segments: usize,
    /// The plane square is centered at this point projected onto the plane.
    pub plane_center: Vec3,
    /// Half the side of the plane square, m.
    pub plane_half_size: f64,
}

impl Default for TessellateOptions {
    fn default() -> Self {
        TessellateOptions {
            segments: 32,
            plane_center: Vec3::ZERO,
            plane_half_size: 1.0,
        }
    }
}

/// Two unit vectors completing `u` (unit) to a right-handed frame `(e1, e2, u)`.
pub(crate) fn frame(u: Vec3) -> (Vec3, Vec3) {
    let helper = if u.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let e1 = helper.cross(u).normalize();
    let e2 = u.cross(e1);
    (e1, e2)
}

pub(crate) fn unit_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let l = v.length();
    if l > 0.0 && l.is_finite() {
        v / l
    } else {
        fallback
    }
}

/// A capsule around the segment `center ± half_length·u` (a sphere when `half_length = 0`).
pub(crate) fn capsule_mesh(
    center: Vec3,
    u: Vec3,
    half_length: f64,
    radius: f64,
    segments: usize,
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let seg = segments.max(3);
    let half_rings = (seg / 4).max(2); // latitude bands per hemisphere
    let (e1, e2) = frame(u);
    // rings from south to north: (axial offset, ring radius)
    let mut rings: Vec<(f64, f64)> = Vec::new();
    for k in 1..=half_rings {
        let th = -std::f64::consts::FRAC_PI_2 * (1.0 - k as f64 / half_rings as f64);
        rings.push((radius * th.sin() - half_length, radius * th.cos()));
    }
    for k in 0..half_rings {
        if k == 0 && half_length == 0.0 {
            continue; // the equator is already there
        }
        let th = std::f64::consts::FRAC_PI_2 * k as f64 / half_rings as f64;
        rings.push((radius * th.sin() + half_length, radius * th.cos()));
    }
    let mut v = vec![center - u * (half_length + radius)];
    for &(z, r) in &rings {
        for j in 0..seg {
            let phi = std::f64::consts::TAU * j as f64 / seg as f64;
            v.push(center + u * z + (e1 * phi.cos() + e2 * phi.sin()) * r);
        }
    }
    let north = v.len() as u32;
    v.push(center + u * (half_length + radius));
    let at = |k: usize, j: usize| (1 + k * seg + j % seg) as u32;
    let mut t = Vec::new();
    for j in 0..seg {
        t.push([0, at(0, j + 1), at(0, j)]);
    }
    for k in 0..rings.len() - 1 {
        for j in 0..seg {
            t.push([at(k, j), at(k, j + 1), at(k + 1, j + 1)]);
            t.push([at(k, j), at(k + 1, j + 1), at(k + 1, j)]);
        }
    }
    let last = rings.len() - 1;
    for j in 0..seg {
        t.push([north, at(last, j), at(last, j + 1)]);
    }
    (v, t)
}

/// The collider as triangles in its pose at time `t` (see the module docs).
pub fn tessellate(
    collider: &Collider,
    t: f64,
    options: &TessellateOptions,
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (rest, triangles) = collider.shape.tessellate(t, options);
    let posed = rest
        .into_iter()
        .map(|p| collider.transform_point(p, t))
        .collect();
    (posed, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::colliders::{Capsule, Cuboid, Motion, Plane, Shape, Sphere};
    use glam::DQuat;

    fn check_outward(c: &Collider, t: f64) -> usize {
        let (v, tris) = tessellate(c, t, &TessellateOptions::default());
        assert!(!tris.is_empty());
        for tri in &tris {
            let [a, b, cc] = tri.map(|i| v[i as usize]);
            let n = (b - a).cross(cc - a);
            assert!(n.length() > 0.0, "degenerate triangle {tri:?}");
            let centroid = (a + b + cc) / 3.0;
            let out = c.closest(centroid, t).normal;
            assert!(n.dot(out) > 0.0, "{tri:?} is wound inward");
        }
        v.len()
    }

    #[test]
    fn sphere_vertices_lie_on_the_sphere_and_triangles_face_out() {
        let center = Vec3::new(0.1, 0.7, -0.2);
        let c = Collider {
            shape: Shape::Sphere(Sphere {
                center,
                radius: 0.25,
            }),
            motion: Motion::Constant {
                velocity: Vec3::new(0.0, 0.0, 1.0),
                angular_velocity: Vec3::new(0.0, 3.0, 0.0),
            },
        };
        let (v, _) = tessellate(&c, 0.5, &TessellateOptions::default());
        let moved = center + Vec3::new(0.0, 0.0, 0.5);
        for p in &v {
            assert!(((*p - moved).length() - 0.25).abs() < 1e-12);
        }
        check_outward(&c, 0.5);
    }

    #[test]
    fn capsules_boxes_and_planes_face_out() {
        let shapes = [
            Shape::Capsule(Capsule {
                a: Vec3::new(-0.5, 0.0, 0.0),
                b: Vec3::new(0.5, 0.2, 0.1),
                radius: 0.2,
            }),
            Shape::Box(Cuboid {
                center: Vec3::new(0.0, 0.5, 0.0),
                half_extents: Vec3::new(0.5, 0.3, 0.2),
                rotation: DQuat::from_scaled_axis(Vec3::new(0.3, -0.5, 0.8)),
            }),
            Shape::Plane(Plane {
                point: Vec3::new(0.0, -0.1, 0.0),
                normal: Vec3::new(0.0, 2.0, 0.3),
            }),
        ];
        for s in shapes {
            check_outward(&Collider::fixed(s.clone()), 0.0);
            let moving = Collider {
                shape: s,
                motion: Motion::Constant {
                    velocity: Vec3::X,
                    angular_velocity: Vec3::new(1.0, 2.0, 0.5),
                },
            };
            check_outward(&moving, 0.7);
        }
        // capsule vertices lie on the capsule
        let c = Collider::fixed(Shape::Capsule(Capsule {
            a: Vec3::ZERO,
            b: Vec3::Y,
            radius: 0.1,
        }));
        let (v, _) = tessellate(&c, 0.0, &TessellateOptions::default());
        for p in v {
            assert!(c.closest(p, 0.0).signed_distance.abs() < 1e-12);
        }
    }
}
