//! Obstacles: analytic shapes and triangle meshes, each moving rigidly.
//!
//! A [`Collider`] is a [`Shape`] given in its pose at `t = 0` plus a [`RigidMotion`]: constant
//! linear velocity `v` of its center `c` and constant angular velocity `ω` about that center,
//! so a material point `x` of the shape is at `c + v t + R(ω t) (x - c)` at time `t`
//! (`R(θ)` = rotation by `|θ|` about `θ/|θ|`). The center is the plane's `point`, the sphere's
//! and box's `center`, the capsule's midpoint, and the mesh's pivot: the origin of the
//! coordinates its vertices are given in (the OBJ file's origin) unless set with
//! [`TriangleMesh::with_pivot`].
//!
//! [`Collider::closest`] answers, for a query point `p` at time `t`: the signed distance (> 0
//! outside, < 0 inside), the unit normal (the gradient of the signed distance wherever it is
//! differentiable, pointing outward), the closest surface point and that point's velocity
//! `v + ω × (point - c(t))`.
//!
//! Meshes (open or closed, zero thickness) have no inside: their `signed_distance` is the
//! unsigned distance (≥ 0), the normal points from the closest surface point toward `p` (the
//! gradient of the unsigned distance), and [`Contact::side`] tells which side of the closest
//! triangle (by its winding) `p` is on. Cloth passing through a mesh is caught by CCD against
//! its triangles, not by the sign.
//!
//! Degenerate parameters never produce NaN: a zero plane normal or a point at a sphere's center
//! uses `+z`, negative radii and half extents count as zero.

use super::broad_phase::Aabb;
use super::distance::{point_segment, point_triangle};
use crate::math::Vec3;
use glam::DQuat;

/// Constant rigid motion: linear velocity of the center and angular velocity about it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RigidMotion {
    /// Velocity of the center (m/s).
    pub velocity: Vec3,
    /// Angular velocity about the center (rad/s, axis × rate).
    pub angular_velocity: Vec3,
}

/// A shape in its pose at `t = 0`.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Half-space below the plane through `point` with outward `normal`.
    Plane {
        /// A point on the plane.
        point: Vec3,
        /// Outward normal (need not be unit length).
        normal: Vec3,
    },
    /// A ball.
    Sphere {
        /// Center.
        center: Vec3,
        /// Radius (m).
        radius: f64,
    },
    /// All points within `radius` of the segment `a b`.
    Capsule {
        /// First end of the axis.
        a: Vec3,
        /// Second end of the axis.
        b: Vec3,
        /// Radius (m).
        radius: f64,
    },
    /// An oriented box.
    Box {
        /// Center.
        center: Vec3,
        /// Half of the side lengths along the box's local axes.
        half_extents: Vec3,
        /// Orientation: local axes to world.
        rotation: DQuat,
    },
    /// A triangle surface of zero thickness.
    Mesh(TriangleMesh),
}

/// A triangle mesh obstacle with a bounding-volume hierarchy for closest-point queries.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleMesh {
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    pivot: Vec3,
    nodes: Vec<Node>,
    /// Triangle indices in BVH leaf order.
    order: Vec<u32>,
}

/// A BVH node: `count > 0` for a leaf holding `order[first .. first + count]`, otherwise an
/// inner node whose children are `first` and `first + 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Node {
    aabb: Aabb,
    first: u32,
    count: u32,
}

impl TriangleMesh {
    /// A mesh from vertices and triangles, turning about the origin of the vertices'
    /// coordinates. Triangles referring to missing vertices are dropped.
    pub fn new(vertices: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> TriangleMesh {
        let n = vertices.len();
        let triangles: Vec<[u32; 3]> = triangles
            .into_iter()
            .filter(|t| t.iter().all(|&i| (i as usize) < n))
            .collect();
        let mut m = TriangleMesh {
            vertices,
            triangles,
            pivot: Vec3::ZERO,
            nodes: Vec::new(),
            order: Vec::new(),
        };
        m.build();
        m
    }

    /// The same mesh turning about `pivot` (in the vertices' coordinates) instead of the origin.
    pub fn with_pivot(mut self, pivot: Vec3) -> TriangleMesh {
        self.pivot = pivot;
        self
    }

    /// The point the mesh turns about, at `t = 0`.
    pub fn pivot(&self) -> Vec3 {
        self.pivot
    }

    /// Vertices in the pose at `t = 0`.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// Triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    fn tri(&self, i: u32) -> [Vec3; 3] {
        self.triangles[i as usize].map(|v| self.vertices[v as usize])
    }

    fn build(&mut self) {
        self.order = (0..self.triangles.len() as u32).collect();
        self.nodes.clear();
        if self.order.is_empty() {
            return;
        }
        let centers: Vec<Vec3> = (0..self.triangles.len() as u32)
            .map(|i| self.tri(i).iter().sum::<Vec3>() / 3.0)
            .collect();
        self.nodes.push(Node {
            aabb: Aabb::of_points([]),
            first: 0,
            count: 0,
        });
        // (node index, range start, range end)
        let mut stack = vec![(0usize, 0usize, self.order.len())];
        while let Some((ni, lo, hi)) = stack.pop() {
            let aabb = Aabb::of_points(self.order[lo..hi].iter().flat_map(|&i| self.tri(i)));
            if hi - lo <= 4 {
                self.nodes[ni] = Node {
                    aabb,
                    first: lo as u32,
                    count: (hi - lo) as u32,
                };
                continue;
            }
            let cb = Aabb::of_points(self.order[lo..hi].iter().map(|&i| centers[i as usize]));
            let ext = cb.max - cb.min;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = (lo + hi) / 2;
            self.order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
                centers[a as usize][axis]
                    .total_cmp(&centers[b as usize][axis])
                    .then(a.cmp(&b))
            });
            let child = self.nodes.len();
            self.nodes[ni] = Node {
                aabb,
                first: child as u32,
                count: 0,
            };
            let empty = Node {
                aabb,
                first: 0,
                count: 0,
            };
            self.nodes.push(empty);
            self.nodes.push(empty);
            stack.push((child, lo, mid));
            stack.push((child + 1, mid, hi));
        }
    }

    /// Closest triangle to `p` in the rest pose: `(triangle index, closest point result)`.
    pub fn closest_triangle(&self, p: Vec3) -> Option<(u32, super::distance::PointTriangle)> {
        let mut best: Option<(u32, super::distance::PointTriangle)> = None;
        if self.nodes.is_empty() {
            return None;
        }
        let box_dist = |b: &Aabb| (p - p.clamp(b.min, b.max)).length();
        let mut stack = vec![0usize];
        while let Some(ni) = stack.pop() {
            let node = self.nodes[ni];
            let bd = box_dist(&node.aabb);
            if best.is_some_and(|(_, r)| bd > r.dist) {
                continue;
            }
            if node.count > 0 {
                let (f, c) = (node.first as usize, node.count as usize);
                for &ti in &self.order[f..f + c] {
                    let [a, b, cc] = self.tri(ti);
                    let r = point_triangle(p, a, b, cc);
                    let better = match best {
                        None => true,
                        Some((bi, br)) => r.dist < br.dist || (r.dist == br.dist && ti < bi),
                    };
                    if better {
                        best = Some((ti, r));
                    }
                }
            } else {
                // visit the nearer child first
                let (l, r) = (node.first as usize, node.first as usize + 1);
                let (dl, dr) = (box_dist(&self.nodes[l].aabb), box_dist(&self.nodes[r].aabb));
                if dl <= dr {
                    stack.push(r);
                    stack.push(l);
                } else {
                    stack.push(l);
                    stack.push(r);
                }
            }
        }
        best
    }
}

/// An obstacle: a shape and its rigid motion.
#[derive(Clone, Debug, PartialEq)]
pub struct Collider {
    /// The shape at `t = 0`.
    pub shape: Shape,
    /// Its motion.
    pub motion: RigidMotion,
}

/// Result of a closest-point query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Signed distance from the query point to the surface (< 0 inside). Unsigned for meshes.
    pub signed_distance: f64,
    /// Unit outward normal at the closest point (gradient of the signed distance).
    pub normal: Vec3,
    /// Closest point on the surface.
    pub point: Vec3,
    /// Velocity of the surface at `point`.
    pub velocity_at_point: Vec3,
    /// `+1` outside / on the front of the closest mesh triangle, `-1` inside / behind it.
    pub side: f64,
    /// For meshes, the index of the closest triangle.
    pub triangle: Option<u32>,
}

fn unit_or_z(v: Vec3) -> Vec3 {
    let l = v.length();
    if l > 0.0 && l.is_finite() {
        v / l
    } else {
        Vec3::Z
    }
}

impl Collider {
    /// A collider that does not move.
    pub fn fixed(shape: Shape) -> Collider {
        Collider {
            shape,
            motion: RigidMotion::default(),
        }
    }

    /// The center the rotation is about, at `t = 0`.
    pub fn center(&self) -> Vec3 {
        match &self.shape {
            Shape::Plane { point, .. } => *point,
            Shape::Sphere { center, .. } | Shape::Box { center, .. } => *center,
            Shape::Capsule { a, b, .. } => (*a + *b) * 0.5,
            Shape::Mesh(m) => m.pivot,
        }
    }

    /// Rotation and center at time `t`.
    fn pose(&self, t: f64) -> (DQuat, Vec3) {
        let rot = DQuat::from_scaled_axis(self.motion.angular_velocity * t);
        (rot, self.center() + self.motion.velocity * t)
    }

    /// Position at time `t` of the material point at `x` at `t = 0`.
    pub fn transform_point(&self, x: Vec3, t: f64) -> Vec3 {
        let (rot, c) = self.pose(t);
        c + rot * (x - self.center())
    }

    /// Where the point at `x` at time `t_from`, moving rigidly with the collider, is at `t_to`.
    pub fn carry(&self, x: Vec3, t_from: f64, t_to: f64) -> Vec3 {
        let (rot, c) = self.pose(t_from);
        self.transform_point(self.center() + rot.inverse() * (x - c), t_to)
    }

    /// Closest point on the surface at time `t` to `p`. See the module docs.
    pub fn closest(&self, p: Vec3, t: f64) -> Contact {
        let (rot, c_t) = self.pose(t);
        let c0 = self.center();
        // query in the rest pose
        let q = c0 + rot.inverse() * (p - c_t);
        let (sd, n, point, side, triangle) = closest_rest(&self.shape, q);
        let point = c_t + rot * (point - c0);
        Contact {
            signed_distance: sd,
            normal: rot * n,
            point,
            velocity_at_point: self.motion.velocity
                + self.motion.angular_velocity.cross(point - c_t),
            side,
            triangle,
        }
    }
}

/// `(signed distance, normal, closest point, side, triangle)` in the rest pose.
fn closest_rest(shape: &Shape, p: Vec3) -> (f64, Vec3, Vec3, f64, Option<u32>) {
    let sign = |d: f64| if d < 0.0 { -1.0 } else { 1.0 };
    match shape {
        Shape::Plane { point, normal } => {
            let n = unit_or_z(*normal);
            let d = (p - *point).dot(n);
            (d, n, p - n * d, sign(d), None)
        }
        Shape::Sphere { center, radius } => ball(p, *center, radius.max(0.0)),
        Shape::Capsule { a, b, radius } => {
            let s = point_segment(p, *a, *b);
            ball(p, s.q, radius.max(0.0))
        }
        Shape::Box {
            center,
            half_extents,
            rotation,
        } => {
            let h = half_extents.max(Vec3::ZERO);
            let l = rotation.inverse() * (p - *center);
            let (d, n, q) = box_local(l, h);
            (d, *rotation * n, *center + *rotation * q, sign(d), None)
        }
        Shape::Mesh(m) => match m.closest_triangle(p) {
            None => (f64::INFINITY, Vec3::Z, p, 1.0, None),
            Some((ti, r)) => {
                let [a, b, c] = m.tri(ti);
                let fnormal = (b - a).cross(c - a);
                let side = if (p - r.q).dot(fnormal) < 0.0 {
                    -1.0
                } else {
                    1.0
                };
                let n = if r.dist > 0.0 {
                    (p - r.q) / r.dist
                } else {
                    unit_or_z(fnormal)
                };
                (r.dist, n, r.q, side, Some(ti))
            }
        },
    }
}

fn ball(p: Vec3, c: Vec3, r: f64) -> (f64, Vec3, Vec3, f64, Option<u32>) {
    let n = unit_or_z(p - c);
    let d = (p - c).length() - r;
    (d, n, c + n * r, if d < 0.0 { -1.0 } else { 1.0 }, None)
}

/// Signed distance, normal and closest point for an axis-aligned box `[-h, h]`.
fn box_local(l: Vec3, h: Vec3) -> (f64, Vec3, Vec3) {
    let q = l.abs() - h;
    if q.max_element() > 0.0 {
        // outside: closest point is the clamp
        let c = l.clamp(-h, h);
        let d = (l - c).length();
        (d, (l - c) / d, c)
    } else {
        // inside: nearest face
        let k = if q.x >= q.y && q.x >= q.z {
            0
        } else if q.y >= q.z {
            1
        } else {
            2
        };
        let s = if l[k] < 0.0 { -1.0 } else { 1.0 };
        let mut n = Vec3::ZERO;
        n[k] = s;
        let mut c = l;
        c[k] = s * h[k];
        (q[k], n, c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn shapes() -> Vec<Shape> {
        vec![
            Shape::Plane {
                point: Vec3::new(0.0, 0.1, 0.0),
                normal: Vec3::new(0.0, 2.0, 0.0),
            },
            Shape::Sphere {
                center: Vec3::new(0.1, 0.2, 0.3),
                radius: 0.5,
            },
            Shape::Capsule {
                a: Vec3::new(-0.5, 0.0, 0.0),
                b: Vec3::new(0.5, 0.2, 0.0),
                radius: 0.25,
            },
            Shape::Box {
                center: Vec3::new(0.0, 0.1, 0.0),
                half_extents: Vec3::new(0.5, 0.3, 0.2),
                rotation: DQuat::from_scaled_axis(Vec3::new(0.3, -0.5, 0.8)),
            },
        ]
    }

    #[test]
    fn hand_values() {
        let c = Collider::fixed(shapes()[0].clone());
        let r = c.closest(Vec3::new(3.0, 1.1, -2.0), 0.0);
        assert!((r.signed_distance - 1.0).abs() < 1e-15 && r.normal == Vec3::Y);
        let c = Collider::fixed(Shape::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        });
        let r = c.closest(Vec3::new(0.0, 0.0, -3.0), 0.0);
        assert_eq!(
            (r.signed_distance, r.normal, r.point),
            (2.0, -Vec3::Z, -Vec3::Z)
        );
        let r = c.closest(Vec3::ZERO, 0.0);
        assert_eq!((r.signed_distance, r.normal), (-1.0, Vec3::Z));
        let c = Collider::fixed(Shape::Capsule {
            a: Vec3::ZERO,
            b: Vec3::X * 2.0,
            radius: 0.5,
        });
        let r = c.closest(Vec3::new(1.0, 0.0, 0.2), 0.0);
        assert!((r.signed_distance + 0.3).abs() < 1e-15 && r.normal == Vec3::Z);
        let r = c.closest(Vec3::new(3.0, 0.0, 0.0), 0.0);
        assert!((r.signed_distance - 0.5).abs() < 1e-15);
        let c = Collider::fixed(Shape::Box {
            center: Vec3::ZERO,
            half_extents: Vec3::new(1.0, 2.0, 3.0),
            rotation: DQuat::IDENTITY,
        });
        let r = c.closest(Vec3::new(0.5, 1.9, 0.0), 0.0);
        assert!((r.signed_distance + 0.1).abs() < 1e-15 && r.normal == Vec3::Y);
        let r = c.closest(Vec3::new(2.0, 3.0, 0.0), 0.0);
        assert!((r.signed_distance - 2f64.sqrt()).abs() < 1e-15);
        assert_eq!(r.point, Vec3::new(1.0, 2.0, 0.0));
        // a box rotated 90° about z swaps its x and y extents
        let c = Collider::fixed(Shape::Box {
            center: Vec3::ZERO,
            half_extents: Vec3::new(1.0, 2.0, 3.0),
            rotation: DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2),
        });
        let r = c.closest(Vec3::new(3.0, 0.0, 0.0), 0.0);
        assert!((r.signed_distance - 1.0).abs() < 1e-12);
        // degenerate parameters
        let c = Collider::fixed(Shape::Plane {
            point: Vec3::ZERO,
            normal: Vec3::ZERO,
        });
        assert_eq!(c.closest(Vec3::Z, 0.0).signed_distance, 1.0);
        let c = Collider::fixed(Shape::Box {
            center: Vec3::ZERO,
            half_extents: Vec3::ZERO,
            rotation: DQuat::IDENTITY,
        });
        assert!(c.closest(Vec3::ZERO, 0.0).normal.is_finite());
    }

    #[test]
    fn moving_shapes() {
        // sphere moving up at 1 m/s
        let c = Collider {
            shape: Shape::Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
            },
            motion: RigidMotion {
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
            shape: Shape::Plane {
                point: Vec3::ZERO,
                normal: Vec3::Y,
            },
            motion: RigidMotion {
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
                .map(|t| {
                    point_triangle(p, v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]).dist
                })
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
                motion: RigidMotion {
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
                motion: RigidMotion { velocity: Vec3::from_array(v), angular_velocity: Vec3::from_array(w) },
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
}
