//! The inside of a collider: which points a solid or a closed triangle mesh encloses.
//!
//! Solids (plane, sphere, capsule, box) enclose the points of negative signed distance. A
//! triangle mesh encloses something only when it is *closed* (watertight): every edge is shared
//! by exactly two triangles ([`is_closed`]). Its inside is decided by ray parity: a segment from
//! the point to beyond the mesh's bounding box crosses the surface an odd number of times from
//! inside. Each crossing is decided with the exact orientation predicates of
//! [`crate::collision::predicates`]; when the segment grazes an edge, a vertex or lies in a
//! triangle's plane (an exact zero), the next of a fixed list of directions is tried, so the
//! answer is exact and the same on every machine. A point on the surface counts as outside.
//! Open meshes have no inside.

use super::bvh::Bvh;
use crate::collision::broad_phase::Aabb;
use crate::collision::predicates::orient3d;
use crate::math::Vec3;
use std::collections::HashMap;

/// True when every edge of `triangles` (unordered vertex pair) is shared by exactly two of
/// them, and there is at least one triangle.
pub fn is_closed(triangles: &[[u32; 3]]) -> bool {
    let mut uses: HashMap<(u32, u32), u32> = HashMap::with_capacity(triangles.len() * 2);
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    !triangles.is_empty() && uses.values().all(|&u| u == 2)
}

/// A closed surface posed once, ready for many inside tests.
#[derive(Clone, Debug)]
pub struct Interior<'a> {
    vertices: Vec<Vec3>,
    triangles: &'a [[u32; 3]],
    bvh: Bvh,
    boxes: Vec<Aabb>,
    bounds: Aabb,
}

/// Directions tried in turn (the last ones skew, so no two are degenerate for the same cause).
const DIRECTIONS: [[f64; 3]; 6] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.577, 0.361, 0.733],
    [-0.419, 0.811, -0.407],
    [0.263, -0.539, 0.801],
];

impl<'a> Interior<'a> {
    /// The inside of the surface with `vertices` (posed) and `triangles`; `None` unless it is
    /// closed.
    pub fn new(vertices: Vec<Vec3>, triangles: &'a [[u32; 3]]) -> Option<Interior<'a>> {
        if !is_closed(triangles) {
            return None;
        }
        Some(Self::closed(vertices, triangles))
    }

    /// As [`Interior::new`] for triangles already known to be closed.
    pub(crate) fn closed(vertices: Vec<Vec3>, triangles: &'a [[u32; 3]]) -> Interior<'a> {
        let bvh = Bvh::build(&vertices, triangles);
        let boxes = bvh.boxes(triangles, &[&vertices]);
        let bounds = Aabb::of_points(vertices.iter().copied());
        Interior {
            vertices,
            triangles,
            bvh,
            boxes,
            bounds,
        }
    }

    /// True when `p` is strictly inside (see the module docs).
    pub fn contains(&self, p: Vec3) -> bool {
        if !p.is_finite() || !self.bounds.contains(p) {
            return false;
        }
        let reach = 2.0 * (self.bounds.max - self.bounds.min).length() + 1.0;
        for d in DIRECTIONS {
            let q = p + Vec3::from_array(d) * reach;
            if let Some(odd) = self.parity(p, q) {
                return odd;
            }
        }
        false
    }

    /// Whether the segment `p q` crosses the surface an odd number of times, or `None` when
    /// it touches an edge or vertex, lies in a triangle's plane, or `p` is on the surface.
    fn parity(&self, p: Vec3, q: Vec3) -> Option<bool> {
        let query = Aabb::of_points([p, q]);
        let mut odd = false;
        let mut clean = true;
        self.bvh.overlapping(&self.boxes, &query, |ti| {
            if !clean {
                return;
            }
            let [a, b, c] = self.triangles[ti as usize].map(|i| self.vertices[i as usize]);
            let (op, oq) = (orient3d(a, b, c, p), orient3d(a, b, c, q));
            if op == oq && op != 0 {
                return; // both strictly on one side
            }
            if (b - a).cross(c - a) == Vec3::ZERO && op == 0 && oq == 0 {
                return; // a triangle without area: no side to cross
            }
            if op == 0 || oq == 0 {
                clean = false;
                return;
            }
            let s = [
                orient3d(p, q, a, b),
                orient3d(p, q, b, c),
                orient3d(p, q, c, a),
            ];
            if s.contains(&1) && s.contains(&-1) {
                return; // passes beside the triangle
            }
            if s.contains(&0) {
                clean = false; // through an edge or a corner
                return;
            }
            odd = !odd;
        });
        clean.then_some(odd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::colliders::{Collider, Shape, Sphere};
    use crate::collision::tessellate::TessellateOptions;

    /// A unit cube `[0, 1]³` of 12 triangles.
    fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (v, t)
    }

    #[test]
    fn a_cube_is_closed_until_a_face_is_removed() {
        let (_, t) = cube();
        assert!(is_closed(&t));
        assert!(!is_closed(&t[1..]));
        assert!(!is_closed(&[]));
    }

    #[test]
    fn the_cube_encloses_exactly_its_open_interior_even_along_its_diagonals() {
        let (v, t) = cube();
        let inside = Interior::new(v.clone(), &t).unwrap();
        // points on the triangles' shared diagonals and edges' lines (degenerate rays along x)
        for (p, want) in [
            (Vec3::new(0.5, 0.5, 0.5), true),
            (Vec3::new(0.25, 0.25, 0.25), true),
            (Vec3::new(0.9, 0.1, 0.1), true),
            (Vec3::new(-0.5, 0.5, 0.5), false),
            (Vec3::new(0.5, 1.5, 0.5), false),
            (Vec3::new(0.5, 0.5, 1.0), false), // on a face
            (Vec3::new(1e-12, 0.5, 0.5), true),
            (Vec3::new(-1e-12, 0.5, 0.5), false),
        ] {
            assert_eq!(inside.contains(p), want, "{p}");
        }
        // every grid point strictly inside is inside, every one outside is outside
        for i in -2..=12 {
            for j in -2..=12 {
                for k in [-1, 0, 3, 5, 10, 11] {
                    let p = Vec3::new(i as f64, j as f64, k as f64) / 10.0;
                    let strictly = (0.0..1.0).contains(&p.x)
                        && (0.0..1.0).contains(&p.y)
                        && (0.0..1.0).contains(&p.z)
                        && p.min_element() > 0.0;
                    assert_eq!(inside.contains(p), strictly, "{p}");
                }
            }
        }
        assert!(Interior::new(v, &t[2..]).is_none(), "open: no inside");
    }

    #[test]
    fn a_tessellated_ball_agrees_with_the_sphere_away_from_its_surface() {
        let ball = Collider::fixed(Shape::Sphere(Sphere {
            center: Vec3::new(0.1, 0.2, 0.3),
            radius: 0.5,
        }));
        let (v, t) = ball.shape.tessellate(0.0, &TessellateOptions::default());
        let (v, t) = crate::collision::colliders::mesh::welded(v, t);
        let inside = Interior::new(v, &t).expect("the welded ball is closed");
        let mut checked = 0;
        for i in 0..9 {
            for j in 0..9 {
                for k in 0..9 {
                    let p = Vec3::new(i as f64, j as f64, k as f64) * 0.15 - Vec3::splat(0.5);
                    let d = ball.closest(p, 0.0).signed_distance;
                    // the tessellation lies within 2 cm of the sphere
                    if d.abs() > 0.02 {
                        assert_eq!(inside.contains(p), d < 0.0, "{p} at {d}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 600);
    }

    /// The example mannequin is watertight; its torso and limbs are inside, the space around
    /// and between them (between the arm and the hip) outside.
    #[test]
    fn the_mannequin_is_closed_and_encloses_its_body() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/mannequin/mannequin_0001.obj"
        );
        let m = crate::io::obj::read_obj(std::path::Path::new(path)).unwrap();
        let t = m.triangles();
        let inside = Interior::new(m.positions.clone(), &t).expect("closed");
        for (p, want) in [
            ([0.0, 1.1, 0.0], true),   // chest
            ([0.0, 0.95, 0.0], true),  // hips
            ([0.31, 1.0, 0.0], true),  // an arm at the side
            ([0.0, 1.62, 0.0], true),  // head
            ([0.0, 1.1, 0.3], false),  // in front of the chest
            ([0.23, 1.0, 0.0], false), // between the arm and the hip
            ([0.0, 0.5, 0.0], false),  // between the legs
            ([0.0, 1.9, 0.0], false),  // above the head
        ] {
            assert_eq!(inside.contains(Vec3::from_array(p)), want, "{p:?}");
        }
    }
}
