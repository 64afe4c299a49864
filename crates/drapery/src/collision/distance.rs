//! Closest points between a point and a segment, a point and a triangle, and two segments.
//!
//! Contract: every function takes finite points and returns finite results, whatever the
//! shape of the input: zero-length segments, zero-area (collinear or needle) triangles and
//! parallel segments are handled explicitly. Parameters and barycentric weights are always
//! clamped to the primitive (`0 ≤ t ≤ 1`, `bary ≥ 0`, `Σ bary = 1`), and the returned closest
//! points are the corresponding affine combinations of the inputs, so the caller can reuse the
//! weights (e.g. for repulsion forces) and recover exactly the reported points.

use crate::math::Vec3;

/// Closest point on a segment `a b` to a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointSegment {
    /// Distance from the point to `q`.
    pub dist: f64,
    /// Parameter of `q` along the segment: `q = (1 - t) a + t b`, `0 ≤ t ≤ 1`.
    pub t: f64,
    /// Closest point on the segment.
    pub q: Vec3,
}

/// Closest point on a triangle `a b c` to a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointTriangle {
    /// Distance from the point to `q`.
    pub dist: f64,
    /// Closest point on the (closed) triangle.
    pub q: Vec3,
    /// Barycentric weights of `q`: `q = bary[0] a + bary[1] b + bary[2] c`, all `≥ 0`, sum 1.
    pub bary: [f64; 3],
}

/// Closest points between segments `p0 p1` and `q0 q1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeEdge {
    /// Distance between `p` and `q`.
    pub dist: f64,
    /// Parameter on the first segment: `p = (1 - s) p0 + s p1`, `0 ≤ s ≤ 1`.
    pub s: f64,
    /// Parameter on the second segment: `q = (1 - t) q0 + t q1`, `0 ≤ t ≤ 1`.
    pub t: f64,
    /// Closest point on the first segment.
    pub p: Vec3,
    /// Closest point on the second segment.
    pub q: Vec3,
}

/// Closest point on segment `a b` to `p`. A zero-length segment gives `t = 0`.
pub fn point_segment(p: Vec3, a: Vec3, b: Vec3) -> PointSegment {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let t = if t.is_nan() { 0.0 } else { t };
    let q = a + ab * t;
    PointSegment {
        dist: (p - q).length(),
        t,
        q,
    }
}

/// Closest point on the closed triangle `a b c` to `p`.
///
/// If the projection of `p` on the triangle's plane falls inside the triangle it is the answer;
/// otherwise the answer lies on the boundary and is the best of the three edges. Triangles whose
/// area is negligible against their edge lengths (collinear or needle) are treated as their
/// three edges, which is exact for them.
pub fn point_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> PointTriangle {
    let ab = b - a;
    let ac = c - a;
    let n = ab.cross(ac);
    let n2 = n.length_squared();
    let scale2 = ab
        .length_squared()
        .max(ac.length_squared())
        .max((c - b).length_squared());
    if n2 > 1e-24 * scale2 * scale2 {
        // Barycentric coordinates of the projection, from signed sub-areas.
        let ap = p - a;
        let beta = ap.cross(ac).dot(n) / n2;
        let gamma = ab.cross(ap).dot(n) / n2;
        let alpha = 1.0 - beta - gamma;
        if alpha >= 0.0 && beta >= 0.0 && gamma >= 0.0 {
            let q = a * alpha + b * beta + c * gamma;
            return PointTriangle {
                dist: (p - q).length(),
                q,
                bary: [alpha, beta, gamma],
            };
        }
    }
    let e_ab = point_segment(p, a, b);
    let e_bc = point_segment(p, b, c);
    let e_ca = point_segment(p, c, a);
    let mut best = PointTriangle {
        dist: e_ab.dist,
        q: e_ab.q,
        bary: [1.0 - e_ab.t, e_ab.t, 0.0],
    };
    if e_bc.dist < best.dist {
        best = PointTriangle {
            dist: e_bc.dist,
            q: e_bc.q,
            bary: [0.0, 1.0 - e_bc.t, e_bc.t],
        };
    }
    if e_ca.dist < best.dist {
        best = PointTriangle {
            dist: e_ca.dist,
            q: e_ca.q,
            bary: [e_ca.t, 0.0, 1.0 - e_ca.t],
        };
    }
    best
}

/// The parameters `(s, t)` of the critical point of `|p0 + s d1 - (q0 + t d2)|²` over the
/// whole plane (`r = p0 - q0`), where the lines through the two segments are closest; `None`
/// for a zero-length or (nearly) parallel direction.
#[inline]
fn critical_point(d1: Vec3, d2: Vec3, r: Vec3) -> Option<(f64, f64)> {
    let a = d1.length_squared();
    let e = d2.length_squared();
    let b = d1.dot(d2);
    let c = d1.dot(r);
    let f = d2.dot(r);
    let denom = a * e - b * b;
    (a > 0.0 && e > 0.0 && denom > 1e-14 * a * e)
        .then(|| ((b * f - c * e) / denom, (a * f - b * c) / denom))
}

/// Whether [`segment_segment`] could find the segments' closest points strictly inside both
/// (`0 < s, t < 1`) and closer than `thickness`: false only when it certainly does not. It
/// computes the interior candidate alone, the way [`segment_segment`] does: that candidate must
/// be strictly inside the square and closer than `thickness`, since a boundary candidate that
/// beats it has `s` or `t` at 0 or 1. A cloth's edge pairs near each other are mostly
/// neighbours in one surface whose lines cross outside the segments, and this rejects them at a
/// fraction of the full computation's cost (BENCHMARKS.md, thirty-third session).
pub fn may_meet_inside_within(p0: Vec3, p1: Vec3, q0: Vec3, q1: Vec3, thickness: f64) -> bool {
    let (d1, d2) = (p1 - p0, q1 - q0);
    let Some((s, t)) = critical_point(d1, d2, p0 - q0) else {
        return false;
    };
    let inside = |u: f64| u > 0.0 && u < 1.0;
    inside(s) && inside(t) && ((p0 + d1 * s) - (q0 + d2 * t)).length() < thickness
}

/// Closest points between segments `p0 p1` and `q0 q1`.
///
/// The minimum of the distance over the parameter square is either an interior critical point
/// (both parameters strictly inside, segments not parallel) or lies on the square's boundary,
/// where one parameter is 0 or 1 and the problem is a point–segment one. All candidates are
/// evaluated and the best kept, which is robust for parallel, nearly parallel and zero-length
/// segments alike. Ties go to the interior solution, then to the boundary candidates in the
/// order `s = 0, s = 1, t = 0, t = 1`.
pub fn segment_segment(p0: Vec3, p1: Vec3, q0: Vec3, q1: Vec3) -> EdgeEdge {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let mut best: Option<EdgeEdge> = None;
    let mut consider = |s: f64, t: f64| {
        let p = p0 + d1 * s;
        let q = q0 + d2 * t;
        let dist = (p - q).length();
        if best.is_none_or(|bst| dist < bst.dist) {
            best = Some(EdgeEdge { dist, s, t, p, q });
        }
    };
    if let Some((s, t)) = critical_point(d1, d2, r)
        && (0.0..=1.0).contains(&s)
        && (0.0..=1.0).contains(&t)
    {
        consider(s, t);
    }
    let ps = point_segment(q0, p0, p1);
    consider(ps.t, 0.0);
    let ps = point_segment(q1, p0, p1);
    consider(ps.t, 1.0);
    let ps = point_segment(p0, q0, q1);
    consider(0.0, ps.t);
    let ps = point_segment(p1, q0, q1);
    consider(1.0, ps.t);
    best.expect("at least one candidate")
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v() -> impl Strategy<Value = Vec3> {
        (-2.0..2.0f64, -2.0..2.0f64, -2.0..2.0f64).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    #[test]
    fn point_triangle_regions() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let r = point_triangle(Vec3::new(0.25, 0.25, 2.0), a, b, c);
        assert!((r.dist - 2.0).abs() < 1e-15);
        assert!((r.bary[0] - 0.5).abs() < 1e-15 && (r.bary[1] - 0.25).abs() < 1e-15);
        let r = point_triangle(Vec3::new(-1.0, -1.0, 0.0), a, b, c);
        assert_eq!(r.bary, [1.0, 0.0, 0.0]);
        assert!((r.dist - 2f64.sqrt()).abs() < 1e-15);
        let r = point_triangle(Vec3::new(1.0, 1.0, 1.0), a, b, c);
        assert!((r.q - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-15);
        assert!((r.bary[1] - 0.5).abs() < 1e-15 && (r.bary[2] - 0.5).abs() < 1e-15);
    }

    #[test]
    fn degenerate_triangles_and_segments_give_finite_answers() {
        let p = Vec3::new(0.3, 1.0, 0.2);
        // collinear
        let r = point_triangle(p, Vec3::ZERO, Vec3::X, Vec3::X * 2.0);
        assert!((r.dist - (1.0f64 + 0.04).sqrt()).abs() < 1e-14, "{r:?}");
        // all three vertices equal
        let r = point_triangle(p, Vec3::ONE, Vec3::ONE, Vec3::ONE);
        assert!(r.dist.is_finite() && (r.q - Vec3::ONE).length() == 0.0);
        assert!((r.bary.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        // needle
        let r = point_triangle(p, Vec3::ZERO, Vec3::X, Vec3::new(0.5, 1e-300, 0.0));
        assert!(r.dist.is_finite() && r.bary.iter().all(|w| w.is_finite()));
        // zero-length segments
        let r = segment_segment(Vec3::ZERO, Vec3::ZERO, Vec3::X, Vec3::X);
        assert_eq!(r.dist, 1.0);
        let r = segment_segment(
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        );
        assert!((r.dist - 1.0).abs() < 1e-15 && (r.t - 0.5).abs() < 1e-15);
        let r = point_segment(Vec3::X, Vec3::Y, Vec3::Y);
        assert_eq!(r.t, 0.0);
    }

    #[test]
    fn parallel_segments() {
        let r = segment_segment(
            Vec3::ZERO,
            Vec3::X * 2.0,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(3.0, 1.0, 0.0),
        );
        assert!((r.dist - 1.0).abs() < 1e-15);
        assert!((r.p - r.q).length() - 1.0 < 1e-15);
        // collinear overlapping
        let r = segment_segment(Vec3::ZERO, Vec3::X * 2.0, Vec3::X, Vec3::X * 3.0);
        assert_eq!(r.dist, 0.0);
        // crossing
        let r = segment_segment(
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, -1.0, 0.5),
            Vec3::new(0.0, 1.0, 0.5),
        );
        assert!((r.dist - 0.5).abs() < 1e-15 && (r.s - 0.5).abs() < 1e-15);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]

        #[test]
        fn point_triangle_is_no_farther_than_any_sampled_point(
            p in v(), a in v(), b in v(), c in v(), needle in 0..3usize
        ) {
            // also exercise nearly degenerate triangles
            let c = match needle { 0 => c, 1 => a + (b - a) * 0.3 + (c - a) * 1e-9, _ => b };
            let r = point_triangle(p, a, b, c);
            prop_assert!(r.bary.iter().all(|&w| w >= 0.0));
            prop_assert!((r.bary.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            let q = a * r.bary[0] + b * r.bary[1] + c * r.bary[2];
            prop_assert!((q - r.q).length() < 1e-12);
            prop_assert!(((p - r.q).length() - r.dist).abs() < 1e-12);
            let n = 24;
            for i in 0..=n {
                for j in 0..=n - i {
                    let (u, w) = (i as f64 / n as f64, j as f64 / n as f64);
                    let s = a * (1.0 - u - w) + b * u + c * w;
                    prop_assert!(r.dist <= (p - s).length() + 1e-12);
                }
            }
        }

        #[test]
        fn segment_segment_is_no_farther_than_any_sampled_pair(
            p0 in v(), p1 in v(), q0 in v(), q1 in v(), kind in 0..3usize
        ) {
            let q1 = match kind { 0 => q1, 1 => q0 + (p1 - p0) * 0.7, _ => q0 };
            let r = segment_segment(p0, p1, q0, q1);
            prop_assert!((0.0..=1.0).contains(&r.s) && (0.0..=1.0).contains(&r.t));
            prop_assert!((p0.lerp(p1, r.s) - r.p).length() < 1e-12);
            prop_assert!((q0.lerp(q1, r.t) - r.q).length() < 1e-12);
            let n = 40;
            for i in 0..=n {
                for j in 0..=n {
                    let d = (p0.lerp(p1, i as f64 / n as f64) - q0.lerp(q1, j as f64 / n as f64)).length();
                    prop_assert!(r.dist <= d + 1e-12);
                }
            }
            // symmetric in the two segments
            let r2 = segment_segment(q0, q1, p0, p1);
            prop_assert!((r.dist - r2.dist).abs() < 1e-12);
        }

        /// The quick test never rejects a pair whose closest points are inside both segments
        /// and closer than the thickness, and with the thickness above that distance it keeps
        /// every such pair; segments that cross are kept for any positive thickness.
        #[test]
        fn the_quick_edge_test_keeps_every_pair_met_inside(
            p0 in v(), p1 in v(), q0 in v(), q1 in v(), kind in 0..4usize, share in 0.0..2.0f64,
        ) {
            let (q0, q1) = match kind {
                // crossing at an inside point of both
                0 => {
                    let m = p0.lerp(p1, 0.37);
                    (m + (q0 - m) * 0.5, m - (q0 - m) * 0.25)
                }
                1 => (q0, q0 + (p1 - p0) * 0.7),
                2 => (q0, q0),
                _ => (q0, q1),
            };
            let r = segment_segment(p0, p1, q0, q1);
            let inside = r.s > 0.0 && r.s < 1.0 && r.t > 0.0 && r.t < 1.0;
            let thickness = r.dist * share + if kind == 0 { 1e-9 } else { 0.0 };
            if inside && r.dist < thickness {
                prop_assert!(may_meet_inside_within(p0, p1, q0, q1, thickness));
            }
            let (d1, d2) = (p1 - p0, q1 - q0);
            let apart = d1.cross(d2).length_squared() > 1e-6 * d1.length_squared() * d2.length_squared();
            if kind == 0 && apart {
                prop_assert!(inside && may_meet_inside_within(p0, p1, q0, q1, 1e-9));
            }
        }
    }
}
