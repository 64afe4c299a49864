//! Intersection checker: the "nothing passes through anything" oracle for tests and reports.
//!
//! * [`count_self_intersections`]: the number of intersecting pairs of triangles of one surface,
//!   excluding pairs that share a vertex (neighbours always touch). Exact: two closed triangles
//!   intersect iff an edge of one meets the other, decided with the exact orientation predicates
//!   of [`super::predicates`] (touching counts; coplanar pairs are tested in 2D).
//! * [`count_intersections_between`]: the same between two different surfaces (cloth and a mesh
//!   obstacle), all pairs considered.
//! * [`count_penetrations`]: vertices whose signed distance to an analytic collider is below
//!   `-tol`, or inside a closed mesh collider deeper than `tol`. Open meshes have no inside and
//!   never count here; use [`count_intersections_between`] for them.
//!
//! Candidate pairs come from the broad phase, so the cost is about linear in the mesh size.
//! Triangles with a non-finite vertex are skipped.

use super::broad_phase::{Aabb, overlapping_pairs, overlapping_pairs_between};
use super::colliders::Collider;
use super::predicates::{orient2d, orient3d};
use crate::math::Vec3;
use rayon::prelude::*;

/// Number of intersecting triangle pairs not sharing a vertex.
pub fn count_self_intersections(x: &[Vec3], triangles: &[[u32; 3]]) -> usize {
    count_sewn_intersections(x, triangles, &[])
}

/// Number of intersecting triangle pairs not sharing a vertex, the two vertices of each
/// stitched pair of `stitches` counting as one: a seam joins its two sides as a shared vertex
/// joins two triangles, and the triangles meeting at a closed seam touch along it.
pub fn count_sewn_intersections(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    stitches: &[[u32; 2]],
) -> usize {
    sewn_intersecting_pairs(x, triangles, stitches).len()
}

/// The intersecting triangle pairs `[i, j]` (`i < j`, indices into `triangles`, in increasing
/// order) that [`count_sewn_intersections`] counts.
pub fn sewn_intersecting_pairs(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    stitches: &[[u32; 2]],
) -> Vec<[u32; 2]> {
    let rep = sewn_representatives(x.len(), stitches);
    let boxes = tri_boxes(x, triangles);
    let mut pairs = overlapping_pairs(&boxes)
        .par_iter()
        .filter(|&&(i, j)| {
            let (a, b) = (triangles[i as usize], triangles[j as usize]);
            let (ra, rb) = (a.map(|v| rep[v as usize]), b.map(|v| rep[v as usize]));
            !ra.iter().any(|v| rb.contains(v)) && triangles_intersect(corners(x, a), corners(x, b))
        })
        .map(|&(i, j)| [i.min(j), i.max(j)])
        .collect::<Vec<_>>();
    pairs.sort_unstable();
    pairs
}

/// Each of `n` vertices' representative: the smallest vertex it is sewn to by `stitches`,
/// through any chain (itself when none).
pub(crate) fn sewn_representatives(n: usize, stitches: &[[u32; 2]]) -> Vec<u32> {
    let mut rep: Vec<u32> = (0..n as u32).collect();
    use super::union_find::root;
    for &[a, b] in stitches {
        let (ra, rb) = (root(&mut rep, a), root(&mut rep, b));
        rep[ra.max(rb) as usize] = ra.min(rb);
    }
    for v in 0..rep.len() as u32 {
        rep[v as usize] = root(&mut rep, v);
    }
    rep
}

/// Number of intersecting pairs (triangle of `a`, triangle of `b`) between two surfaces.
pub fn count_intersections_between(
    xa: &[Vec3],
    triangles_a: &[[u32; 3]],
    xb: &[Vec3],
    triangles_b: &[[u32; 3]],
) -> usize {
    let ba = tri_boxes(xa, triangles_a);
    let bb = tri_boxes(xb, triangles_b);
    overlapping_pairs_between(&ba, &bb)
        .par_iter()
        .filter(|&&(i, j)| {
            triangles_intersect(
                corners(xa, triangles_a[i as usize]),
                corners(xb, triangles_b[j as usize]),
            )
        })
        .count()
}

/// Number of points deeper than `tol` inside at least one collider at time `t`: signed
/// distance `< -tol` to a solid, or inside a closed mesh ([`Collider::inside_at`]) farther than
/// `tol` from its surface. Open meshes have no inside.
pub fn count_penetrations(x: &[Vec3], colliders: &[Collider], t: f64, tol: f64) -> usize {
    let insides: Vec<_> = colliders
        .iter()
        .filter_map(|c| c.inside_at(t).map(|i| (c, i)))
        .collect();
    x.par_iter()
        .filter(|&&p| {
            insides
                .iter()
                .any(|(c, i)| i.contains(p) && c.closest(p, t).signed_distance.abs() > tol)
        })
        .count()
}

fn corners(x: &[Vec3], t: [u32; 3]) -> [Vec3; 3] {
    t.map(|i| x[i as usize])
}

fn tri_boxes(x: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Aabb> {
    triangles
        .iter()
        .map(|t| Aabb::of_points(corners(x, *t)))
        .collect()
}

/// True when the closed triangles intersect (including touching).
pub fn triangles_intersect(t: [Vec3; 3], u: [Vec3; 3]) -> bool {
    if !(t.iter().chain(u.iter()).all(|p| p.is_finite())) {
        return false;
    }
    (0..3).any(|k| segment_triangle(t[k], t[(k + 1) % 3], u))
        || (0..3).any(|k| segment_triangle(u[k], u[(k + 1) % 3], t))
}

/// True when the closed segment `p q` meets the closed triangle `tri`.
pub fn segment_triangle(p: Vec3, q: Vec3, tri: [Vec3; 3]) -> bool {
    let [a, b, c] = tri;
    let op = orient3d(a, b, c, p);
    let oq = orient3d(a, b, c, q);
    if op == 0 && oq == 0 {
        return coplanar_segment_triangle(p, q, tri);
    }
    if op == oq {
        return false; // both strictly on the same side
    }
    // the segment meets the plane; it meets the triangle iff its line passes inside the three
    // edges with a consistent orientation
    let s = [
        orient3d(p, q, a, b),
        orient3d(p, q, b, c),
        orient3d(p, q, c, a),
    ];
    !(s.contains(&1) && s.contains(&-1))
}

/// Segment and triangle in a common plane: project along the dominant axis of the plane normal.
fn coplanar_segment_triangle(p: Vec3, q: Vec3, tri: [Vec3; 3]) -> bool {
    let [a, b, c] = tri;
    let mut n = (b - a).cross(c - a);
    if n.length_squared() == 0.0 {
        // degenerate triangle: use any plane containing it and the segment
        n = (b - a).cross(q - p);
        if n.length_squared() == 0.0 {
            n = (c - a).cross(q - p);
        }
        if n.length_squared() == 0.0 {
            n = (b - a).cross(p - a);
        }
    }
    let n = n.abs();
    let drop = if n.x >= n.y && n.x >= n.z {
        0
    } else if n.y >= n.z {
        1
    } else {
        2
    };
    let proj = |v: Vec3| match drop {
        0 => [v.y, v.z],
        1 => [v.z, v.x],
        _ => [v.x, v.y],
    };
    let (p2, q2) = (proj(p), proj(q));
    let t2 = [proj(a), proj(b), proj(c)];
    let inside = |x: [f64; 2]| {
        let s = [
            orient2d(t2[0], t2[1], x),
            orient2d(t2[1], t2[2], x),
            orient2d(t2[2], t2[0], x),
        ];
        let (pos, neg) = (s.contains(&1), s.contains(&-1));
        // a degenerate triangle (all zero orientations around it) only contains its segments,
        // which the edge tests below catch
        !(pos && neg) && (pos || neg)
    };
    inside(p2) || inside(q2) || (0..3).any(|k| segments_2d(p2, q2, t2[k], t2[(k + 1) % 3]))
}

/// Closed 2D segments intersect.
fn segments_2d(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (o1, o2) = (orient2d(a, b, c), orient2d(a, b, d));
    let (o3, o4) = (orient2d(c, d, a), orient2d(c, d, b));
    if o1 != o2 && o3 != o4 && o1 * o2 <= 0 && o3 * o4 <= 0 && !(o1 == 0 && o2 == 0) {
        return true;
    }
    // collinear cases: overlap of the projections on the line
    let on = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        r[0] >= p[0].min(q[0])
            && r[0] <= p[0].max(q[0])
            && r[1] >= p[1].min(q[1])
            && r[1] <= p[1].max(q[1])
    };
    (o1 == 0 && on(a, b, c))
        || (o2 == 0 && on(a, b, d))
        || (o3 == 0 && on(c, d, a))
        || (o4 == 0 && on(c, d, b))
}

#[cfg(test)]
mod tests {
    use super::*;
    #[allow(unused_imports)]
    use crate::collision::colliders::{
        Capsule, Collider, Cuboid, Motion, Plane, Shape, Sphere, TriangleMesh,
    };
    use crate::mesh::Mesh;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z)
    }

    /// Two flaps sewn along a seam whose ends overshoot by 1 mm: their triangles cross in a
    /// sliver at the seam, which counts unless the seam's pairs count as shared vertices; a
    /// stitch elsewhere does not hide it.
    #[test]
    fn a_closed_seam_is_not_a_crossing_but_a_real_one_still_is() {
        // flap A: triangle 0-1-2 in z = 0; flap B: 3-4-5 tilted, its seam edge 3-4 on A's edge
        // 0-1 but pushed 1 mm into A
        let x = vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.5, 1.0, 0.0),
            v(0.0, 0.001, 0.0),
            v(1.0, 0.001, 0.0),
            v(0.5, -1.0, 0.5),
            v(5.0, 5.0, 5.0),
        ];
        let tris = [[0, 1, 2], [3, 4, 5]];
        assert_eq!(count_self_intersections(&x, &tris), 1);
        assert_eq!(count_sewn_intersections(&x, &tris, &[[0, 3], [4, 1]]), 0);
        // sewn to a vertex of neither triangle
        assert_eq!(count_sewn_intersections(&x, &tris, &[[0, 6], [6, 6]]), 1);
    }

    #[test]
    fn hand_made_triangle_pairs() {
        let t = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        // piercing
        assert!(triangles_intersect(
            t,
            [v(0.2, 0.2, -1.0), v(0.2, 0.2, 1.0), v(2.0, 2.0, 0.5)]
        ));
        // above, parallel
        assert!(!triangles_intersect(t, t.map(|p| p + Vec3::Z * 1e-12)));
        // touching at a vertex (counts)
        assert!(triangles_intersect(
            t,
            [v(0.25, 0.25, 0.0), v(1.0, 1.0, 1.0), v(1.0, 2.0, 1.0)]
        ));
        // crossing the plane outside the triangle
        assert!(!triangles_intersect(
            t,
            [v(0.8, 0.8, -1.0), v(0.8, 0.8, 1.0), v(2.0, 2.0, 0.0)]
        ));
        // coplanar overlapping, coplanar nested, coplanar disjoint
        assert!(triangles_intersect(t, t.map(|p| p + v(0.3, 0.3, 0.0))));
        assert!(triangles_intersect(
            t,
            [v(0.1, 0.1, 0.0), v(0.2, 0.1, 0.0), v(0.1, 0.2, 0.0)]
        ));
        assert!(!triangles_intersect(t, t.map(|p| p + v(2.0, 0.0, 0.0))));
        // degenerate (zero-area) triangle piercing: a segment through the interior
        assert!(triangles_intersect(
            t,
            [v(0.2, 0.2, -1.0), v(0.2, 0.2, 1.0), v(0.2, 0.2, 0.0)]
        ));
        // non-finite: ignored
        assert!(!triangles_intersect(t, [v(f64::NAN, 0.0, 0.0), t[1], t[2]]));
    }

    #[test]
    fn flat_and_folded_sheets() {
        let m = Mesh::grid([1.0, 1.0], [12, 12], Vec3::ZERO, Vec3::Z).unwrap();
        let tris = m.triangles();
        assert_eq!(count_self_intersections(&m.positions, &tris), 0);
        // fold the sheet in half over itself without crossing: z = small separation
        let mut x = m.positions.clone();
        for p in &mut x {
            if p.x > 0.0 {
                *p = v(-p.x, p.y, 0.01 + p.x * 0.1);
            }
        }
        assert_eq!(count_self_intersections(&x, &tris), 0);
        // push one vertex of the upper half through the lower half
        let mut y = x.clone();
        let i = 12 * 6 + 9; // row 6, column 9 (upper half)
        y[i].z = -0.05;
        assert!(count_self_intersections(&y, &tris) > 0);
        // two separate sheets crossing each other (a cross of two strips)
        let a = Mesh::grid([1.0, 0.2], [6, 2], Vec3::ZERO, Vec3::Z).unwrap();
        let b = Mesh::grid([0.2, 1.0], [2, 6], Vec3::ZERO, Vec3::X).unwrap();
        let n =
            count_intersections_between(&a.positions, &a.triangles(), &b.positions, &b.triangles());
        assert!(n > 0);
        let far: Vec<Vec3> = b.positions.iter().map(|p| *p + Vec3::Z).collect();
        assert_eq!(
            count_intersections_between(&a.positions, &a.triangles(), &far, &b.triangles()),
            0
        );
    }

    #[test]
    fn penetrations_of_analytic_colliders() {
        let cs = [
            Collider::fixed(Shape::Sphere(Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
            })),
            Collider::fixed(Shape::Plane(Plane {
                point: v(0.0, -2.0, 0.0),
                normal: Vec3::Y,
            })),
        ];
        let x = [
            v(0.0, 0.5, 0.0),    // inside sphere
            v(0.0, 0.9999, 0.0), // within tolerance
            v(0.0, 3.0, 0.0),    // outside both
            v(5.0, -2.5, 0.0),   // below plane
        ];
        assert_eq!(count_penetrations(&x, &cs, 0.0, 1e-3), 2);
        assert_eq!(count_penetrations(&x, &cs, 0.0, 0.0), 3);
    }
}
