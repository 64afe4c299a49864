//! Crossings a seam's neighbourhood would close into ([`SeamCrossings`]).
//!
//! The contact pairs around a stitch are let through each other's repulsion and continuous
//! collision detection so that the seam can close ([`super::seams::Seams`]). Nothing then keeps
//! that neighbourhood from closing crossed: a panel's edge pulled to its partner can cut through
//! the other panel's triangles next to the seam, and stay there. What can be checked instead is
//! the outcome of a step: a pair of triangles by a seam that does not intersect at the start of
//! the step and does at its end (as `drapery check` counts intersections: the two ends of a
//! stitched pair count as one vertex) has crossed during it. The fail-safe
//! ([`super::failsafe::failsafe`]) then pulls the pair's vertices back to their start, as it
//! does for a pair that CCD finds colliding.

use super::broad_phase::{Aabb, overlapping_pairs};
use super::check::{sewn_representatives, triangles_intersect};
use super::seams::Seams;
use crate::math::Vec3;
use rayon::prelude::*;

/// The cloth triangles by a seam, and which vertices a seam joins.
#[derive(Clone, Debug, Default)]
pub struct SeamCrossings {
    /// Triangles with a vertex in a stitched neighbourhood, increasing.
    tris: Vec<u32>,
    /// Each particle's representative: the smallest particle it is sewn to, through any chain.
    rep: Vec<u32>,
}

impl SeamCrossings {
    /// The triangles of `triangles` (over `n` particles) by the neighbourhoods of `seams`, which
    /// were built from the stitched pairs `stitches`.
    pub fn new(
        n: usize,
        triangles: &[[u32; 3]],
        stitches: &[[u32; 2]],
        seams: &Seams,
    ) -> SeamCrossings {
        if seams.is_empty() {
            return SeamCrossings::default();
        }
        let rep = sewn_representatives(n, stitches);
        let tris = (0..triangles.len() as u32)
            .filter(|&t| triangles[t as usize].iter().any(|&p| seams.holds(p)))
            .collect();
        SeamCrossings { tris, rep }
    }

    /// True when there is no seam.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// The pairs of triangles by a seam (indices into `triangles`, `[i, j]` with `i < j`,
    /// increasing) that intersect at `x1` and not at `x0`, two sewn vertices counting as one.
    pub fn new_crossings(&self, triangles: &[[u32; 3]], x0: &[Vec3], x1: &[Vec3]) -> Vec<[u32; 2]> {
        if self.is_empty() {
            return Vec::new();
        }
        let corners = |x: &[Vec3], t: u32| triangles[t as usize].map(|i| x[i as usize]);
        let boxes: Vec<Aabb> = (self.tris.iter())
            .map(|&t| Aabb::of_points(corners(x1, t)))
            .collect();
        let rep = |t: u32| triangles[t as usize].map(|v| self.rep[v as usize]);
        let mut pairs: Vec<[u32; 2]> = overlapping_pairs(&boxes)
            .par_iter()
            .map(|&(i, j)| (self.tris[i as usize], self.tris[j as usize]))
            .filter(|&(a, b)| {
                let (ra, rb) = (rep(a), rep(b));
                !ra.iter().any(|v| rb.contains(v))
                    && triangles_intersect(corners(x1, a), corners(x1, b))
                    && !triangles_intersect(corners(x0, a), corners(x0, b))
            })
            .map(|(a, b)| [a.min(b), a.max(b)])
            .collect();
        pairs.sort_unstable();
        pairs
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::collision::check::count_self_intersections;

    /// Two squares of two triangles each: `a` (0–3) flat at y = 0, split along its diagonal
    /// x + z = 1, and `b` (4–7) standing in the plane z = 0.5, from y = 0.1 to 0.5 less `drop`.
    pub(crate) fn squares(drop: f64) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let v = Vec3::new;
        let mut x = vec![
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, 0.0, 1.0),
            v(1.0, 0.0, 1.0),
        ];
        let b = [
            v(0.2, 0.1, 0.5),
            v(0.6, 0.1, 0.5),
            v(0.2, 0.5, 0.5),
            v(0.6, 0.5, 0.5),
        ];
        x.extend(b.map(|p| p - v(0.0, drop, 0.0)));
        (x, vec![[0, 1, 2], [1, 3, 2], [4, 5, 6], [5, 7, 6]])
    }

    fn crossings(stitches: &[[u32; 2]], x0: &[Vec3], x1: &[Vec3]) -> Vec<[u32; 2]> {
        let tris = squares(0.0).1;
        let seams = Seams::new(x0.len(), &tris, stitches);
        SeamCrossings::new(x0.len(), &tris, stitches, &seams).new_crossings(&tris, x0, x1)
    }

    #[test]
    fn only_pairs_by_a_seam_that_cross_over_the_step_count() {
        let (x0, tris) = squares(0.0);
        let (x1, _) = squares(0.3);
        // lowered by 0.3, `b` pierces y = 0 along z = 0.5: its lower triangle over
        // 0.2 <= x <= 0.4 (inside `a`'s first triangle), its upper one over 0.4 <= x <= 0.6
        // (across the diagonal, both of `a`'s)
        assert_eq!(count_self_intersections(&x0, &tris), 0);
        assert_eq!(count_self_intersections(&x1, &tris), 3);
        // each square sewn within itself: every triangle is by a seam
        let within = [[0, 1], [4, 5]];
        assert_eq!(crossings(&within, &x0, &x1), vec![[0, 2], [0, 3], [1, 3]]);
        // crossed at the start already: not new
        assert!(crossings(&within, &x1, &x1).is_empty());
        // no seam, or a seam in `a` only: `b` is not by one (CCD holds it, not this check)
        assert!(crossings(&[], &x0, &x1).is_empty());
        assert!(crossings(&[[0, 1]], &x0, &x1).is_empty());
        // sewn across (0 to 4): the pair holding both sewn vertices does not count, as in
        // `drapery check`
        assert_eq!(crossings(&[[0, 4]], &x0, &x1), vec![[0, 3], [1, 3]]);
    }
}
