//! Close pairs between cloth and the sharp features of mesh colliders (docs/MATH.md §24).
//!
//! Obstacle contact (§14) holds cloth *particles* against a collider's closest point. A sharp
//! collider feature, a rim or a box edge, can meet the interior of a cloth triangle or of a
//! cloth edge instead, where no particle is; these pairs find those places:
//!
//! * **edge–edge**: a sharp collider edge and a cloth edge whose closest points are interior to
//!   both (`0 < s < 1` on the cloth edge, `0 < t < 1` on the collider edge). At an end of the
//!   cloth edge a particle contact acts; at an end of the collider edge one of the next two does;
//! * **vertex–triangle**: a vertex of a sharp edge whose closest point on a cloth triangle is
//!   interior to it (all barycentric weights positive);
//! * **vertex–edge**: a vertex of a sharp edge whose closest point on a cloth triangle lies inside
//!   one of its edges, and on no triangle next to that edge inside the triangle: the edge is then
//!   the closest feature of the cloth, found once per (vertex, edge). A closest point at a cloth
//!   vertex is a particle contact's.
//!
//! A collider edge is *sharp* when its faces turn by more than [`SHARP_ANGLE`] (the angle between
//! their normals), or when it has one face or more than two. Edges of flat and smooth regions are
//! left to particle contact: there a cloth primitive between particles held at the thickness is
//! no closer than the thickness itself, and a pair hovering at it would only add the penalty's
//! stiffness to the matrix.
//!
//! Each pair is a stencil of up to three cloth particles with weights `w` (summing to 1, the
//! cloth point `Σ wᵢ xᵢ`) and one collider point `q`, kinematic: the separation is
//! `u = Σ wᵢ xᵢ - q`, and [`super::repulsion::repulsion`] gives the penalty with the collider
//! point as a fourth stencil point of weight `-1`. The pairs are found at the start of the step
//! within `margin` (the caller uses twice the thickness, as obstacle contacts do); their weights
//! stay fixed over the step and `q` is the collider point at the end of the step, where the
//! implicit step evaluates its forces. The output is in a fixed order (edge–edge, then
//! vertex–triangle, then vertex–edge, each sorted by collider feature and cloth primitive),
//! whatever the thread count.

use super::broad_phase::{Aabb, overlapping_pairs_between};
use super::distance::{may_meet_inside_within, point_segment, point_triangle, segment_segment};
use crate::math::Vec3;
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet};

/// Faces turning by more than this (radians, the angle between their normals) meet at a sharp
/// edge: 30°.
pub const SHARP_ANGLE: f64 = std::f64::consts::PI / 6.0;

/// What a cloth–collider stencil pairs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum ObstacleStencilKind {
    /// A collider edge and a cloth edge: `particles = [a, b, a]`, weights `[1-s, s, 0]`.
    EdgeEdge,
    /// A collider vertex and a cloth triangle: `particles = [a, b, c]`, barycentric weights.
    VertexTriangle,
    /// A collider vertex and a cloth edge: `particles = [a, b, a]`, weights `[1-s, s, 0]`.
    VertexEdge,
}

/// A cloth primitive close to a sharp collider feature.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstacleProximity {
    /// Which features.
    pub kind: ObstacleStencilKind,
    /// Cloth particles (the first repeated, with weight 0, when the stencil has two).
    pub particles: [u32; 3],
    /// Their weights (sum 1): the cloth point is `Σ wᵢ xᵢ`.
    pub weights: [f64; 3],
    /// The collider point at the end of the step.
    pub point: Vec3,
    /// Distance at the start of the step.
    pub dist: f64,
    /// Unit normal from the collider toward the cloth at the start of the step (the fallback
    /// normal of the penalty when the distance vanishes).
    pub normal: Vec3,
    /// Index of the obstacle.
    pub obstacle: u32,
    /// Velocity of the collider point over the step (its displacement over `h`).
    pub velocity: Vec3,
    /// Coefficient `c` (N·s/m) of the tangential damping that stands in for friction (set by
    /// the caller; 0 here).
    pub damping: f64,
}

impl ObstacleProximity {
    /// The stencil of [`super::repulsion::repulsion`]: the cloth particles' positions in `x` and
    /// the collider point, with the weights `[w₀, w₁, w₂, -1]`.
    pub fn stencil(&self, x: &[Vec3]) -> ([Vec3; 4], [f64; 4]) {
        let [a, b, c] = self.particles.map(|i| x[i as usize]);
        let w = self.weights;
        ([a, b, c, self.point], [w[0], w[1], w[2], -1.0])
    }
}

/// A mesh collider's sharp features, posed at the start (`x0`) and the end (`x1`) of a step.
#[derive(Clone, Debug, Default)]
pub struct SharpFeatures {
    /// Vertices at the start of the step.
    pub x0: Vec<Vec3>,
    /// Vertices at the end of the step.
    pub x1: Vec<Vec3>,
    /// Sharp edges, `[lo, hi]`, sorted.
    pub edges: Vec<[u32; 2]>,
    /// The vertices of the sharp edges, sorted.
    pub vertices: Vec<u32>,
}

impl SharpFeatures {
    /// The sharp features of the mesh `triangles` with vertices `x0` at the start of the step
    /// (the angles are measured there) and `x1` at its end.
    pub fn new(x0: Vec<Vec3>, x1: Vec<Vec3>, triangles: &[[u32; 3]]) -> SharpFeatures {
        let edges = sharp_edges(&x0, triangles, SHARP_ANGLE);
        let vertices: BTreeSet<u32> = edges.iter().flatten().copied().collect();
        SharpFeatures {
            x0,
            x1,
            edges,
            vertices: vertices.into_iter().collect(),
        }
    }
}

/// The edges of `triangles` whose faces turn by more than `angle`, or that have one face or more
/// than two, each once as `[lo, hi]`, sorted. A face without area counts as turning.
pub fn sharp_edges(x: &[Vec3], triangles: &[[u32; 3]], angle: f64) -> Vec<[u32; 2]> {
    let mut faces: BTreeMap<[u32; 2], Vec<Vec3>> = BTreeMap::new();
    for t in triangles {
        let [a, b, c] = t.map(|i| x[i as usize]);
        let n = (b - a).cross(c - a);
        let l = n.length();
        let n = if l > 0.0 && l.is_finite() {
            n / l
        } else {
            Vec3::ZERO
        };
        for [i, j] in [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]] {
            faces.entry([i.min(j), i.max(j)]).or_default().push(n);
        }
    }
    let cos = angle.cos();
    faces
        .into_iter()
        .filter(|(_, n)| n.len() != 2 || n[0].dot(n[1]) < cos)
        .map(|(e, _)| e)
        .collect()
}

/// The cloth–collider pairs of one obstacle (index `obstacle`, features `f`) closer than
/// `margin` at the cloth positions `x` (see the module docs); `h` is the step (the collider
/// points' velocities are their displacements over it).
pub fn obstacle_proximities(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    f: &SharpFeatures,
    (obstacle, h): (u32, f64),
    margin: f64,
) -> Vec<ObstacleProximity> {
    let pair =
        |kind, particles, weights, point: Vec3, start: Vec3, dist, normal| ObstacleProximity {
            kind,
            particles,
            weights,
            point,
            dist,
            normal,
            obstacle,
            velocity: (point - start) / h,
            damping: 0.0,
        };
    if f.edges.is_empty() {
        return Vec::new();
    }
    let r = 0.5 * margin;
    let boxes =
        |ids: &[u32], x: &[Vec3]| Aabb::of_points(ids.iter().map(|&i| x[i as usize])).inflated(r);
    let cloth_edges: Vec<Aabb> = edges.par_iter().map(|e| boxes(e, x)).collect();
    let sharp: Vec<Aabb> = f.edges.iter().map(|e| boxes(e, &f.x0)).collect();
    let pairs = overlapping_pairs_between(&sharp, &cloth_edges);
    let unit = |v: Vec3, fallback: Vec3| {
        let l = v.length();
        if l > 0.0 && l.is_finite() {
            v / l
        } else {
            fallback
        }
    };
    let ee = pairs.par_iter().filter_map(|&(k, e)| {
        let [c0, c1] = f.edges[k as usize];
        let [a, b] = edges[e as usize];
        let (p0, p1) = (x[a as usize], x[b as usize]);
        let (q0, q1) = (f.x0[c0 as usize], f.x0[c1 as usize]);
        if !may_meet_inside_within(p0, p1, q0, q1, margin) {
            return None;
        }
        let r = segment_segment(p0, p1, q0, q1);
        let interior = r.s > 0.0 && r.s < 1.0 && r.t > 0.0 && r.t < 1.0;
        (r.dist < margin && interior).then(|| {
            let fallback = unit((p1 - p0).cross(q1 - q0), Vec3::Y);
            pair(
                ObstacleStencilKind::EdgeEdge,
                [a, b, a],
                [1.0 - r.s, r.s, 0.0],
                f.x1[c0 as usize].lerp(f.x1[c1 as usize], r.t),
                r.q,
                r.dist,
                unit(r.p - r.q, fallback),
            )
        })
    });
    let mut out: Vec<ObstacleProximity> = ee.collect();
    // vertices against triangles: interior points, and the edges' interior points
    let tri_boxes: Vec<Aabb> = triangles.par_iter().map(|t| boxes(t, x)).collect();
    let vboxes: Vec<Aabb> = f.vertices.iter().map(|&v| boxes(&[v], &f.x0)).collect();
    let pairs = overlapping_pairs_between(&vboxes, &tri_boxes);
    let near: Vec<(u32, u32, [f64; 3], f64)> = pairs
        .par_iter()
        .filter_map(|&(k, t)| {
            let q = f.x0[f.vertices[k as usize] as usize];
            let [a, b, c] = triangles[t as usize].map(|i| x[i as usize]);
            let r = point_triangle(q, a, b, c);
            (r.dist < margin).then_some((k, t, r.bary, r.dist))
        })
        .collect();
    // (vertex, triangle) pairs whose closest point is interior: a vertex–edge pair is dropped
    // when a triangle holding the edge has one
    let interior: BTreeSet<(u32, [u32; 2])> = near
        .iter()
        .filter(|(_, _, w, _)| w.iter().all(|&w| w > 0.0))
        .flat_map(|&(k, t, _, _)| {
            let [a, b, c] = triangles[t as usize];
            [[a, b], [b, c], [c, a]].map(|[i, j]| (k, [i.min(j), i.max(j)]))
        })
        .collect();
    let mut edge_pairs: BTreeSet<(u32, [u32; 2])> = BTreeSet::new();
    for &(k, t, w, dist) in &near {
        let v = f.vertices[k as usize];
        let q0 = f.x0[v as usize];
        let tri = triangles[t as usize];
        let zeros = w.iter().filter(|&&w| w <= 0.0).count();
        if zeros == 0 {
            let p: Vec3 = (0..3).map(|i| x[tri[i] as usize] * w[i]).sum();
            let fallback = {
                let [a, b, c] = tri.map(|i| x[i as usize]);
                unit((b - a).cross(c - a), Vec3::Y)
            };
            let fallback = if fallback.dot(p - q0) < 0.0 {
                -fallback
            } else {
                fallback
            };
            out.push(pair(
                ObstacleStencilKind::VertexTriangle,
                tri,
                w,
                f.x1[v as usize],
                q0,
                dist,
                unit(p - q0, fallback),
            ));
        } else if zeros == 1 {
            let z = (0..3).find(|&i| w[i] <= 0.0).unwrap_or(0);
            let (i, j) = (tri[(z + 1) % 3], tri[(z + 2) % 3]);
            let key = (k, [i.min(j), i.max(j)]);
            if !interior.contains(&key) {
                edge_pairs.insert(key);
            }
        }
    }
    for (k, [a, b]) in edge_pairs {
        let v = f.vertices[k as usize];
        let q0 = f.x0[v as usize];
        let (p0, p1) = (x[a as usize], x[b as usize]);
        let r = point_segment(q0, p0, p1);
        if !(r.t > 0.0 && r.t < 1.0 && r.dist < margin) {
            continue;
        }
        // (a zero distance: the direction of the edge's neighbourhood is unknown here, so the
        // normal falls back to the one of the pair's plane with the up axis)
        let fallback = unit((p1 - p0).cross(Vec3::Y).cross(p1 - p0), Vec3::Y);
        let fallback = if fallback.y < 0.0 {
            -fallback
        } else {
            fallback
        };
        out.push(pair(
            ObstacleStencilKind::VertexEdge,
            [a, b, a],
            [1.0 - r.t, r.t, 0.0],
            f.x1[v as usize],
            q0,
            r.dist,
            unit(r.q - q0, fallback),
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::textile::drape::support;

    /// The Cusick support (z up): its two rims, nothing else.
    fn cylinder(segments: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let m = support(0.09, 0.01, segments).unwrap();
        (m.positions.clone(), m.triangles())
    }

    #[test]
    fn the_sharp_edges_of_a_cylinder_are_its_rims() {
        for segments in [16, 128] {
            let (x, tris) = cylinder(segments);
            let sharp = sharp_edges(&x, &tris, SHARP_ANGLE);
            assert_eq!(sharp.len(), 2 * segments);
            // every sharp edge joins two neighbours on one rim (both at z = 0 or z = -h)
            for [a, b] in &sharp {
                let (p, q) = (x[*a as usize], x[*b as usize]);
                assert_eq!(p.z, q.z);
                assert!((p.length() - q.length()).abs() < 1e-12 && p.z.abs() + 1e-12 > 0.0);
                let chord = 2.0 * 0.09 * (std::f64::consts::PI / segments as f64).sin();
                assert!(((p - q).truncate().length() - chord).abs() < 1e-12);
            }
        }
        // an open flat square: its four boundary edges, not its diagonal
        let x = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        assert_eq!(
            sharp_edges(&x, &[[0, 1, 2], [0, 2, 3]], SHARP_ANGLE),
            vec![[0, 1], [0, 3], [1, 2], [2, 3]]
        );
    }

    /// A cloth strip of two triangles `0 1 2`, `1 3 2` lying across the rim of the support
    /// (radius 9 cm, top at z = 0) at height `z`, its vertices 1 cm inside and outside the rim
    /// (around the point (0.09, 0, 0)).
    fn strip(z: f64) -> (Vec<Vec3>, Vec<[u32; 3]>, Vec<[u32; 2]>) {
        let x = vec![
            Vec3::new(0.08, -0.002, z),
            Vec3::new(0.10, -0.002, z),
            Vec3::new(0.08, 0.006, z),
            Vec3::new(0.10, 0.006, z),
        ];
        (
            x,
            vec![[0, 1, 2], [1, 3, 2]],
            vec![[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]],
        )
    }

    fn features(segments: usize) -> SharpFeatures {
        let (x, tris) = cylinder(segments);
        SharpFeatures::new(x.clone(), x, &tris)
    }

    #[test]
    fn cloth_edges_across_the_rim_within_the_margin_are_found_and_far_ones_are_not() {
        let f = features(128);
        let eta = 0.002;
        let (x, tris, edges) = strip(0.5 * eta);
        let near = obstacle_proximities(&x, &tris, &edges, &f, (3, 0.01), eta);
        // the three edges crossing the rim (0-1, 1-2, 2-3) each meet one rim edge
        let ee: Vec<&ObstacleProximity> = near
            .iter()
            .filter(|p| p.kind == ObstacleStencilKind::EdgeEdge)
            .collect();
        let crossing: BTreeSet<[u32; 2]> = ee
            .iter()
            .map(|p| [p.particles[0], p.particles[1]])
            .collect();
        assert_eq!(crossing, BTreeSet::from([[0, 1], [1, 2], [2, 3]]));
        for p in &near {
            let (pts, w) = p.stencil(&x);
            let u: Vec3 = (0..4).map(|i| pts[i] * w[i]).sum();
            assert!((u.length() - p.dist).abs() < 1e-12, "{p:?}");
            assert!((u / p.dist - p.normal).length() < 1e-9);
            // the rim (at z = 0) is right below the strip: every normal points up, every
            // distance is the height
            assert!((p.normal - Vec3::Z).length() < 1e-12, "{p:?}");
            assert!((p.dist - 0.5 * eta).abs() < 1e-15, "{p:?}");
            assert!((w[..3].iter().sum::<f64>() - 1.0).abs() < 1e-15);
            assert_eq!((p.obstacle, p.velocity), (3, Vec3::ZERO));
        }
        // the rim vertices under the strip's interior: vertex–triangle pairs
        let vt = near
            .iter()
            .filter(|p| p.kind == ObstacleStencilKind::VertexTriangle)
            .count();
        assert_eq!(vt, 2, "{near:?}");
        assert_eq!(near.len(), 5, "{near:?}");
        // out of reach: nothing
        let (x, tris, edges) = strip(1.5 * eta);
        assert!(obstacle_proximities(&x, &tris, &edges, &f, (0, 0.01), eta).is_empty());
        // a strip wholly inside the rim, on the flat top: no sharp feature near
        let inside: Vec<Vec3> = strip(0.5 * eta)
            .0
            .iter()
            .map(|p| *p - Vec3::X * 0.05)
            .collect();
        assert!(obstacle_proximities(&inside, &tris, &edges, &f, (0, 0.01), eta).is_empty());
    }

    #[test]
    fn a_rim_vertex_under_a_cloth_edge_is_one_pair_and_under_a_cloth_vertex_none() {
        // 4 segments: rim vertices at (±0.09, 0), (0, ±0.09); the strip's diagonal 1-2 passes
        // over the vertex (0.09, 0, 0)
        let f = features(4);
        let eta = 0.002;
        let x = vec![
            Vec3::new(0.08, -0.01, 0.001),
            Vec3::new(0.10, -0.01, 0.001),
            Vec3::new(0.08, 0.01, 0.001),
            Vec3::new(0.10, 0.01, 0.001),
        ];
        let (tris, edges) = (strip(0.0).1, strip(0.0).2);
        let near = obstacle_proximities(&x, &tris, &edges, &f, (0, 0.01), eta);
        let at_vertex: Vec<&ObstacleProximity> = near
            .iter()
            .filter(|p| (p.point - Vec3::new(0.09, 0.0, 0.0)).length() < 1e-12)
            .filter(|p| p.kind != ObstacleStencilKind::EdgeEdge)
            .collect();
        assert_eq!(at_vertex.len(), 1, "{near:?}");
        assert!((at_vertex[0].dist - 0.001).abs() < 1e-12);
        // moved so that cloth vertex 0 sits over the rim vertex: a particle contact's, no pair
        let x: Vec<Vec3> = x.iter().map(|p| *p + Vec3::new(0.01, 0.01, 0.0)).collect();
        let near = obstacle_proximities(&x, &tris, &edges, &f, (0, 0.01), eta);
        assert!(
            near.iter()
                .all(|p| (p.point - Vec3::new(0.09, 0.0, 0.0)).length() > 1e-12),
            "{near:?}"
        );
    }
}
