//! Narrow phase of the repulsion: turns broad-phase candidates into contact stencils.
//!
//! Contract: [`proximities`] returns, for each candidate pair closer than `thickness`, the four
//! particle indices, the stencil weights of [`super::repulsion`] and the current distance and
//! normal, in the order of the candidates (vertex–triangle first, then edge–edge), so the output
//! is deterministic. Pass `particles`, `weights` and `normal` to
//! [`super::repulsion::repulsion`] and scatter its forces and 4×4 Jacobian blocks with
//! `particles`.
//!
//! Edge–edge pairs whose closest points lie at an end of either edge are skipped: those are
//! vertex–edge or vertex–vertex proximities, already represented by a vertex–triangle pair of a
//! triangle adjacent to the edge (counting them twice would double the force). Free line
//! elements (edges without triangles) therefore only repel in their interiors.
//!
//! [`closest_only`] then keeps, among a vertex's pairs with the triangles around one edge or
//! vertex of the other surface, only the closest: a vertex over a triangle near its edge is
//! also within the thickness of the triangle across the edge, but that pair's closest point is
//! on the edge and its normal oblique, and its force would push the vertex along the surface.

use super::broad_phase::Candidates;
use super::distance::{may_meet_inside_within, point_triangle, segment_segment};
use super::repulsion::{edge_edge_weights, point_triangle_weights};
use crate::math::Vec3;
use rayon::prelude::*;

/// Kind of stencil.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StencilKind {
    /// `particles = [vertex, a, b, c]`.
    VertexTriangle,
    /// `particles = [p0, p1, q0, q1]`.
    EdgeEdge,
}

/// A close pair, ready for [`super::repulsion::repulsion`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Proximity {
    /// Vertex–triangle or edge–edge.
    pub kind: StencilKind,
    /// Particle indices of the stencil.
    pub particles: [u32; 4],
    /// Stencil weights (sum to zero).
    pub weights: [f64; 4],
    /// Current distance.
    pub dist: f64,
    /// Unit normal from the second primitive toward the first: `(Σ wᵢ xᵢ)/d`, or when `d = 0`
    /// the triangle normal (vertex–triangle) or the edges' cross product (edge–edge), `+z` if
    /// those vanish too. For `d = 0` the side is arbitrary: orient it with the positions at the
    /// start of the step before using it as the fallback normal.
    pub normal: Vec3,
}

fn unit_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let l = v.length();
    if l > 0.0 && l.is_finite() {
        v / l
    } else {
        fallback
    }
}

/// False when every point of the segment or triangle `points` is farther than `thickness` from
/// every point of `others`: their bounding balls about the centroids are that far apart (with a
/// relative `10⁻⁹` to spare, so that no pair the exact distance keeps is dropped by rounding). A
/// cheap first test for vertex–triangle pairs: most broad-phase candidates of a smooth sheet are
/// neighbours a few edges apart, which it rejects before the closest-point computation. Edge
/// pairs go straight to [`may_meet_inside_within`]: their balls are loose, and it passed 98.6 %
/// of a spin-290 step's edge candidates (BENCHMARKS.md, thirty-third session).
fn may_be_within(points: &[Vec3], others: &[Vec3], thickness: f64) -> bool {
    let ball = |p: &[Vec3]| {
        let c = p.iter().copied().sum::<Vec3>() / p.len() as f64;
        let r = p.iter().map(|q| (*q - c).length()).fold(0.0, f64::max);
        (c, r)
    };
    let ((c, r), (d, s)) = (ball(points), ball(others));
    let gap = (c - d).length() - r - s;
    !(gap > thickness * (1.0 + 1e-9) + 1e-12 * (c.abs().max_element() + d.abs().max_element()))
}

/// Close pairs (distance `< thickness`) among the candidates, at positions `x`.
pub fn proximities(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    candidates: &Candidates,
    thickness: f64,
) -> Vec<Proximity> {
    let vt = candidates
        .vt
        .par_iter()
        .with_min_len(1024)
        .filter_map(|&(v, t)| {
            let tri = triangles[t as usize];
            let [a, b, c] = tri.map(|i| x[i as usize]);
            let p = x[v as usize];
            if !may_be_within(&[p], &[a, b, c], thickness) {
                return None;
            }
            let r = point_triangle(p, a, b, c);
            (r.dist < thickness).then(|| {
                let fallback = unit_or((b - a).cross(c - a), Vec3::Z);
                Proximity {
                    kind: StencilKind::VertexTriangle,
                    particles: [v, tri[0], tri[1], tri[2]],
                    weights: point_triangle_weights(r.bary),
                    dist: r.dist,
                    normal: unit_or(p - r.q, fallback),
                }
            })
        });
    let ee = candidates
        .ee
        .par_iter()
        .with_min_len(1024)
        .filter_map(|&(e, f)| {
            let (ea, eb) = (edges[e as usize], edges[f as usize]);
            let [p0, p1] = ea.map(|i| x[i as usize]);
            let [q0, q1] = eb.map(|i| x[i as usize]);
            if !may_meet_inside_within(p0, p1, q0, q1, thickness) {
                return None;
            }
            let r = segment_segment(p0, p1, q0, q1);
            let interior = r.s > 0.0 && r.s < 1.0 && r.t > 0.0 && r.t < 1.0;
            (r.dist < thickness && interior).then(|| {
                let fallback = unit_or((p1 - p0).cross(q1 - q0), Vec3::Z);
                Proximity {
                    kind: StencilKind::EdgeEdge,
                    particles: [ea[0], ea[1], eb[0], eb[1]],
                    weights: edge_edge_weights(r.s, r.t),
                    dist: r.dist,
                    normal: unit_or(r.p - r.q, fallback),
                }
            })
        });
    // `collect` keeps the candidates' order, whatever the thread count
    let mut out: Vec<Proximity> = vt.collect();
    out.par_extend(ee);
    out
}

/// The vertices of a vertex–triangle stencil's triangle whose weight is not zero: the feature
/// (an edge, a vertex, or the whole triangle) that holds the closest point.
fn feature(s: &Proximity) -> impl Iterator<Item = u32> + Clone + '_ {
    (1..4)
        .filter(|&j| s.weights[j] < 0.0)
        .map(move |j| s.particles[j])
}

/// Drops every vertex–triangle stencil of `stencils` (in [`proximities`]' order: a vertex's
/// pairs together) whose closest point lies on an edge or at a vertex of its triangle (a
/// barycentric weight is zero) when another of the same vertex's stencils has a triangle that
/// also holds that edge or vertex and is closer (or as close and earlier in the list). Then, of
/// two vertices close to each other, each the closest point of the other's pair (`v` with a
/// triangle at its vertex `w`, and `w` with a triangle at `v`), only the pair of the lower
/// numbered vertex stays: both are the same vertex–vertex contact.
///
/// So the contact of a vertex with one smooth patch of surface is its pair with the closest
/// triangle, as for the distance to the surface itself. The dropped pairs are the vertex's
/// distances to the patch's edges and vertices through the triangles around them: on a flat
/// sheet their normals lean away from the vertical, and a vertex sliding across the sheet's
/// edges felt their stiff repulsion along the sheet (a drag with no friction at all), and a
/// vertex exactly over an edge or a vertex was pushed two or more times over. The closest pair
/// of each vertex is never dropped but for the second rule, nor a pair whose closest point is
/// inside its triangle, nor edge–edge pairs.
pub fn closest_only(stencils: &mut Vec<Proximity>) {
    let vt = stencils
        .iter()
        .take_while(|s| s.kind == StencilKind::VertexTriangle)
        .count();
    let mut keep = vec![true; stencils.len()];
    let mut start = 0;
    while start < vt {
        let v = stencils[start].particles[0];
        let end = start
            + stencils[start..vt]
                .iter()
                .take_while(|s| s.particles[0] == v)
                .count();
        for k in start..end {
            let t = &stencils[k];
            if feature(t).count() == 3 {
                continue;
            }
            keep[k] = !(start..end).any(|m| {
                let u = &stencils[m];
                m != k
                    && (u.dist, m) < (t.dist, k)
                    && feature(t).all(|w| u.particles[1..].contains(&w))
            });
        }
        start = end;
    }
    // the vertex–vertex contacts that stay, as (vertex, the other vertex)
    let at_vertex = |k: usize| {
        let mut f = feature(&stencils[k]);
        match (f.next(), f.next()) {
            (Some(w), None) => Some((stencils[k].particles[0], w)),
            _ => None,
        }
    };
    let pairs: std::collections::HashSet<(u32, u32)> =
        (0..vt).filter(|&k| keep[k]).filter_map(at_vertex).collect();
    for k in 0..vt {
        if let Some((v, w)) = at_vertex(k) {
            keep[k] &= !(v > w && pairs.contains(&(w, v)));
        }
    }
    let mut k = 0;
    stencils.retain(|_| {
        k += 1;
        keep[k - 1]
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::broad_phase::candidates;
    use crate::mesh::Mesh;
    use proptest::prelude::*;

    fn point() -> impl Strategy<Value = Vec3> {
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// On two sheets, crumpled or flat, one over the other (their vertices one above the
        /// other or not), [`closest_only`] keeps a subset of the stencils and every edge–edge
        /// pair, and every vertex keeps a pair as close as its closest: its own, or for a
        /// vertex–vertex contact the other vertex's.
        #[test]
        fn closest_only_keeps_every_vertex_s_closest_contact(
            seed in any::<u64>(), amp in prop_oneof![Just(0.0), 0.0..0.03f64], gap in 0.0..0.06f64,
            eta in 0.02..0.12f64, aligned in any::<bool>(),
        ) {
            let mut rnd = crate::collision::broad_phase::tests::noise(seed);
            let a = Mesh::grid([1.0, 1.0], [6, 6], Vec3::ZERO, Vec3::Z).unwrap();
            let shift = if aligned { Vec3::ZERO } else { Vec3::new(0.07, 0.03, 0.0) };
            let b = Mesh::grid([0.6, 0.6], [4, 4], shift + Vec3::Z * gap, Vec3::Z).unwrap();
            let n = a.positions.len() as u32;
            let x: Vec<Vec3> = (a.positions.iter().chain(&b.positions))
                .map(|p| *p + Vec3::new(rnd(), rnd(), rnd()) * amp)
                .collect();
            let mut tris = a.triangles();
            tris.extend(b.triangles().iter().map(|t| t.map(|i| i + n)));
            let mut edges = a.edges();
            edges.extend(b.edges().iter().map(|e| e.map(|i| i + n)));
            let c = candidates(&x, &x, &tris, &edges, eta);
            let all = proximities(&x, &tris, &edges, &c, eta);
            let mut kept = all.clone();
            closest_only(&mut kept);
            prop_assert!(kept.iter().all(|k| all.contains(k)));
            let ee = |v: &[Proximity]| v.iter().filter(|p| p.kind == StencilKind::EdgeEdge).count();
            prop_assert_eq!(ee(&kept), ee(&all));
            let vt = |v: &[Proximity], i: u32| -> Vec<Proximity> {
                v.iter()
                    .filter(|p| p.kind == StencilKind::VertexTriangle && p.particles[0] == i)
                    .copied()
                    .collect()
            };
            let closest = |v: &[Proximity]| v.iter().map(|p| p.dist).fold(f64::INFINITY, f64::min);
            for i in 0..x.len() as u32 {
                let before = closest(&vt(&all, i));
                if before.is_infinite() {
                    continue;
                }
                if closest(&vt(&kept, i)) == before {
                    continue;
                }
                // else its closest pair was a vertex–vertex contact, kept from the other side
                let other = vt(&all, i).into_iter().find(|p| p.dist == before).map(|p| {
                    let f: Vec<u32> = feature(&p).collect();
                    f
                });
                let Some([w]) = other.as_deref() else {
                    return Err(TestCaseError::fail(format!("vertex {i} lost its closest pair")));
                };
                let back = vt(&kept, *w)
                    .into_iter()
                    .any(|p| feature(&p).eq([i]) && (p.dist - before).abs() <= 1e-12 * eta);
                prop_assert!(back, "vertex {} lost its contact with vertex {}", i, w);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// The ball test never drops a pair closer than the thickness, and does drop pairs
        /// farther than their extents plus the thickness.
        #[test]
        fn the_ball_test_keeps_every_close_pair(
            p in point(), a in point(), b in point(), c in point(), d in point(),
            thickness in 0.0..1.0f64,
        ) {
            let tri = point_triangle(p, a, b, c).dist;
            if tri < thickness {
                prop_assert!(may_be_within(&[p], &[a, b, c], thickness));
            }
            let seg = segment_segment(p, a, b, c).dist;
            if seg < thickness {
                prop_assert!(may_be_within(&[p, a], &[b, c], thickness));
            }
            // far apart: rejected
            let far = Vec3::splat(10.0);
            prop_assert!(!may_be_within(&[p + far], &[a, b, c], thickness));
            prop_assert!(!may_be_within(&[p + far, a + far], &[b, c], thickness));
            prop_assert!(!may_be_within(&[d + far], &[d], thickness));
        }
    }

    #[test]
    fn stencils_reproduce_the_distance_and_find_all_close_pairs() {
        // two parallel sheets 0.02 apart, the upper one slightly wavy
        let a = Mesh::grid([1.0, 1.0], [8, 8], Vec3::ZERO, Vec3::Z).unwrap();
        let n = a.positions.len() as u32;
        let mut x = a.positions.clone();
        x.extend(
            a.positions
                .iter()
                .enumerate()
                .map(|(i, p)| *p + Vec3::new(0.013, 0.007, 0.02 + 0.005 * (i as f64).sin())),
        );
        let mut tris = a.triangles();
        tris.extend(a.triangles().iter().map(|t| t.map(|i| i + n)));
        let mut edges = a.edges();
        edges.extend(a.edges().iter().map(|e| e.map(|i| i + n)));
        let eta = 0.03;
        let c = candidates(&x, &x, &tris, &edges, eta);
        let prox = proximities(&x, &tris, &edges, &c, eta);
        assert!(!prox.is_empty());
        for p in &prox {
            let u: Vec3 = (0..4)
                .map(|i| x[p.particles[i] as usize] * p.weights[i])
                .sum();
            assert!((u.length() - p.dist).abs() < 1e-12);
            assert!(p.dist < eta);
            assert!(p.weights.iter().sum::<f64>().abs() < 1e-12);
            if p.dist > 0.0 {
                assert!((u / p.dist - p.normal).length() < 1e-9);
            }
        }
        // every vertex of the upper sheet is within η of the lower sheet (and vice versa)
        let vt: std::collections::BTreeSet<u32> = prox
            .iter()
            .filter(|p| p.kind == StencilKind::VertexTriangle)
            .map(|p| p.particles[0])
            .collect();
        assert_eq!(vt.len(), 2 * n as usize);
    }

    /// Over a flat sheet every point at height `g` is at distance `g` from the sheet, so the
    /// repulsion of a vertex at that height is `k (η - g)` straight up wherever it is: over a
    /// triangle, near or on an edge, on a vertex. The vertex is within the thickness of up to
    /// six triangles there; without [`closest_only`] it was pushed twice over an edge, six
    /// times over a vertex, and sideways near them.
    #[test]
    fn a_vertex_over_a_flat_sheet_is_pushed_straight_up_as_by_its_distance() {
        use crate::collision::repulsion::{Penalty, repulsion};
        let sheet = Mesh::grid([1.0, 1.0], [5, 5], Vec3::ZERO, Vec3::Z).unwrap();
        let (tris, edges) = (sheet.triangles(), sheet.edges());
        let (eta, g) = (0.05, 0.02);
        let penalty = Penalty {
            thickness: eta,
            stiffness: 1000.0,
            tangential: false,
        };
        // the sheet's vertices are 0.25 apart at -0.5, -0.25, 0, 0.25, 0.5
        let places = [
            (0.1, 0.07),    // inside a triangle
            (0.125, 0.0),   // over an edge's midpoint
            (0.125, 0.004), // near that edge
            (0.0, 0.0),     // over an inner vertex
            (0.003, -0.002),
            (0.25, 0.25),
            (0.1, 0.1), // over a diagonal
            (0.24, 0.01),
        ];
        for (px, py) in places {
            let mut x = sheet.positions.clone();
            let v = x.len() as u32;
            x.push(Vec3::new(px, py, g));
            let c = candidates(&x, &x, &tris, &edges, eta);
            let mut prox = proximities(&x, &tris, &edges, &c, eta);
            closest_only(&mut prox);
            let mine: Vec<&Proximity> = prox.iter().filter(|p| p.particles[0] == v).collect();
            let force: Vec3 = mine
                .iter()
                .map(|p| {
                    let q = p.particles.map(|i| x[i as usize]);
                    repulsion(&q, &p.weights, &penalty, p.normal).forces[0]
                })
                .sum();
            let expected = Vec3::Z * (penalty.stiffness * (eta - g));
            assert!(
                (force - expected).length() < 1e-9 * expected.length(),
                "at ({px}, {py}): {force:?} from {} stencils, expected {expected:?}",
                mine.len()
            );
        }
    }

    /// A vertex of a triangle rising steeply from just above a vertex of a flat sheet: each
    /// vertex is the other's closest point, and the two pairs (the top vertex with the sheet's
    /// triangles, the sheet's vertex with the top triangle) are one contact, pushing the two
    /// vertices apart by `k (η - g)`, not twice that.
    #[test]
    fn two_vertices_close_to_each_other_are_one_contact() {
        use crate::collision::repulsion::{Penalty, repulsion};
        let sheet = Mesh::grid([1.0, 1.0], [5, 5], Vec3::ZERO, Vec3::Z).unwrap();
        let (mut tris, edges) = (sheet.triangles(), sheet.edges());
        let (eta, g) = (0.05, 0.02);
        let penalty = Penalty {
            thickness: eta,
            stiffness: 1000.0,
            tangential: false,
        };
        let mut x = sheet.positions.clone();
        let w = x.iter().position(|p| p.length() < 1e-12).unwrap() as u32;
        let u = x.len() as u32;
        x.extend([
            Vec3::new(0.0, 0.0, g),
            Vec3::new(0.3, 0.05, 0.5),
            Vec3::new(0.05, 0.3, 0.5),
        ]);
        tris.push([u, u + 1, u + 2]);
        let mut all_edges = edges.clone();
        all_edges.extend([[u, u + 1], [u + 1, u + 2], [u, u + 2]]);
        let c = candidates(&x, &x, &tris, &all_edges, eta);
        let mut prox = proximities(&x, &tris, &all_edges, &c, eta);
        closest_only(&mut prox);
        let force = |i: u32| -> Vec3 {
            prox.iter()
                .map(|p| {
                    let q = p.particles.map(|j| x[j as usize]);
                    let r = repulsion(&q, &p.weights, &penalty, p.normal);
                    (0..4)
                        .filter(|&j| p.particles[j] == i)
                        .map(|j| r.forces[j])
                        .sum::<Vec3>()
                })
                .sum()
        };
        let expected = Vec3::Z * (penalty.stiffness * (eta - g));
        for (i, sign) in [(u, 1.0), (w, -1.0)] {
            let f = force(i);
            assert!(
                (f - expected * sign).length() < 1e-9 * expected.length(),
                "vertex {i}: {f:?}, expected {:?} ({} stencils)",
                expected * sign,
                prox.len()
            );
        }
    }
}
