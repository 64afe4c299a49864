//! Impact zones that translate: the fail-safe's first answer to cloth–cloth collisions
//! (docs/MATH.md §16, "Impact zones").
//!
//! The vertices of colliding cloth pairs are merged into zones (union–find over the pairs, so
//! zones that share a vertex or collide with each other become one), and every vertex of a zone
//! moves over the step by the zone's mean displacement instead of its own. A zone then
//! translates: the vectors between its vertices stay those of the start of the step, so no pair
//! inside it changes its distance, and none can collide (the start is free of crossings). The
//! common motion is kept: cloth carried along by a spinning obstacle keeps moving with it, where
//! pulling the colliding vertices back along their own paths would leave them behind their
//! neighbours by up to a step's motion (centimetres, stretching their triangles several times
//! over).
//!
//! A zone's displacement is the mean of its vertices' (their momentum, for equal masses); a zone
//! with pinned vertices moves as they do, and cannot translate if they move differently.
//!
//! Partial zones, the fail-safe's second try at a step that would otherwise fail, move what they
//! can: a vertex whose new path meets an obstacle keeps its end, and pinned vertices that move
//! alike up to rounding move their zone by the first one's displacement ([`Refusal::Strict`]).

use crate::math::Vec3;

/// The zones of one fail-safe call.
pub(crate) struct Zones {
    /// Union–find parent of each cloth vertex (itself when a root).
    parent: Vec<u32>,
    /// Whether the vertex is in a zone (was in a colliding pair).
    member: Vec<bool>,
}

impl Zones {
    /// No zone yet, over `n` cloth vertices.
    pub fn new(n: usize) -> Zones {
        Zones {
            parent: (0..n as u32).collect(),
            member: vec![false; n],
        }
    }

    fn root(&mut self, i: u32) -> u32 {
        super::union_find::root(&mut self.parent, i)
    }

    /// Merges the vertices of each colliding pair into one zone, then sets every zone vertex's
    /// end position `ye` to its start `x0` plus its zone's displacement (`start - x0` averaged
    /// over the zone, or the pinned vertices' common displacement), marking in `moved` those
    /// whose end changed. Changes nothing in `ye` and returns why when some zone has pinned
    /// vertices that move differently or no end position changed (the zones cannot make
    /// progress, [`Refusal::Stuck`]), or when `clear(i, end)` is false for a vertex `i` whose
    /// end would change (its new path meets an obstacle) or pinned vertices move alike only up
    /// to rounding ([`Refusal::Strict`]). With `partial` such vertices keep their ends instead,
    /// and the others move (see [`Refusal::Strict`]).
    /// `pairs` must name cloth vertices only.
    #[allow(clippy::too_many_arguments)]
    pub fn translate<'a>(
        &mut self,
        pairs: impl Iterator<Item = &'a [u32; 4]>,
        x0: &[Vec3],
        start: &[Vec3],
        pinned: &[bool],
        clear: &(dyn Fn(usize, Vec3) -> bool + Sync),
        partial: bool,
        ye: &mut [Vec3],
        moved: &mut [bool],
    ) -> Result<(), Refusal> {
        for ids in pairs {
            let mut r = self.root(ids[0]);
            for &i in ids {
                self.member[i as usize] = true;
                let s = self.root(i);
                if s != r {
                    // the smaller index is the root: the zones do not depend on the order
                    let (lo, hi) = (r.min(s), r.max(s));
                    self.parent[hi as usize] = lo;
                    r = lo;
                }
            }
        }
        let n = self.parent.len();
        // per root: displacement sum, count, and the pinned vertices' displacement
        let mut sum = vec![Vec3::ZERO; n];
        let mut count = vec![0u32; n];
        let mut pin: Vec<Option<Vec3>> = vec![None; n];
        // pinned vertices that move alike only up to rounding (a handle's vertices, each its
        // own target less its own position), which the strict mode refuses
        let mut rounding = false;
        for i in 0..n {
            if !self.member[i] {
                continue;
            }
            let r = self.root(i as u32) as usize;
            let d = start[i] - x0[i];
            sum[r] += d;
            count[r] += 1;
            if pinned[i] {
                match pin[r] {
                    None => pin[r] = Some(d),
                    Some(p) if p == d => {}
                    Some(p) if alike(p, d, x0[i], start[i]) => rounding = true,
                    Some(_) => return Err(Refusal::Stuck),
                }
            }
        }
        let mut ends = Vec::new();
        for i in 0..n {
            if !self.member[i] || pinned[i] {
                continue;
            }
            let r = self.root(i as u32) as usize;
            let d = pin[r].unwrap_or(sum[r] / count[r] as f64);
            let end = x0[i] + d;
            if end != ye[i] {
                ends.push((i, end));
            }
        }
        let before = ends.len();
        ends.retain(|&(i, end)| clear(i, end));
        if (rounding || ends.len() < before) && !partial {
            return Err(Refusal::Strict);
        }
        if ends.is_empty() {
            return Err(Refusal::Stuck);
        }
        for (i, end) in ends {
            ye[i] = end;
            moved[i] = true;
        }
        Ok(())
    }
}

/// Whether two pinned vertices' displacements `p` and `d` (the second from `x0` to `start`)
/// differ by rounding alone: by at most `10⁻¹²` of the coordinates, thousands of times the
/// rounding of a difference of two positions.
fn alike(p: Vec3, d: Vec3, x0: Vec3, start: Vec3) -> bool {
    let scale = x0.abs().max_element() + start.abs().max_element();
    (p - d).abs().max_element() <= 1e-12 * scale
}

/// Why [`Zones::translate`] moved nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Refusal {
    /// Only the strict mode's rules refused: a zone vertex's new path meets an obstacle, or a
    /// zone's pinned vertices move alike only up to rounding. Without `partial` the zones then
    /// give way to the pull-back. With it, a blocked vertex keeps its end and the rest of its
    /// zone moves, by the first pinned vertex's displacement where the zone has pinned
    /// vertices (each of them keeps its own). The zone is then no longer exactly a
    /// translation, and the CCD rounds that follow find what it left colliding. That is what a
    /// zone holding a handle's vertices and cloth lying on a collider needs: the handle cannot
    /// be pulled back, and the whole zone cannot follow it.
    Strict,
    /// No end would change, or a zone's pinned vertices move differently.
    Stuck,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_zone_moves_by_its_mean_displacement_and_keeps_its_shape() {
        // two pairs sharing vertex 2: one zone of 0..6; vertex 7 stays out
        let x0: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new(i as f64, 0.1 * i as f64, 0.0))
            .collect();
        let start: Vec<Vec3> = (0..8)
            .map(|i| x0[i] + Vec3::new(0.01 * i as f64, -0.02, 0.003 * (i * i) as f64))
            .collect();
        let pairs = [[0, 1, 2, 3], [2, 4, 5, 6]];
        type Clear<'a> = &'a (dyn Fn(usize, Vec3) -> bool + Sync);
        let go = |z: &mut Zones, clear: Clear, ye: &mut [Vec3], moved: &mut [bool]| {
            z.translate(
                pairs.iter(),
                &x0,
                &start,
                &[false; 8],
                clear,
                false,
                ye,
                moved,
            )
        };
        let (mut ye, mut moved) = (start.clone(), vec![false; 8]);
        let mut z = Zones::new(8);
        assert_eq!(go(&mut z, &|_, _| true, &mut ye, &mut moved), Ok(()));
        let mean = (0..7).map(|i| start[i] - x0[i]).sum::<Vec3>() / 7.0;
        for i in 0..7 {
            assert!((ye[i] - x0[i] - mean).length() < 1e-15);
            assert!(moved[i]);
            // the zone's shape is the start's
            let (a, b) = (ye[i] - ye[0], x0[i] - x0[0]);
            assert!((a - b).length() < 1e-14, "{i}");
        }
        assert_eq!(ye[7], start[7]);
        assert!(!moved[7]);
        // the same pairs again: nothing changes, no progress
        moved.iter_mut().for_each(|m| *m = false);
        assert_eq!(
            go(&mut z, &|_, _| true, &mut ye, &mut moved),
            Err(Refusal::Stuck)
        );
        // a zone whose path meets an obstacle does not move
        let mut ye = start.clone();
        assert_eq!(
            go(&mut Zones::new(8), &|i, _| i != 3, &mut ye, &mut moved),
            Err(Refusal::Strict)
        );
        assert_eq!(ye, start);
    }

    /// The zones of the one pair `[0, 1, 2, 3]` from a fresh start ([`Zones::translate`]), with
    /// `ye` the ends on entry and on exit; the outcome and which ends changed.
    fn one_pair(
        x0: &[Vec3],
        start: &[Vec3],
        pinned: &[bool],
        clear: &(dyn Fn(usize, Vec3) -> bool + Sync),
        partial: bool,
        ye: &mut [Vec3],
    ) -> (Result<(), Refusal>, [bool; 4]) {
        let mut moved = [false; 4];
        let pairs = [[0, 1, 2, 3]];
        let mut z = Zones::new(4);
        let out = z.translate(
            pairs.iter(),
            x0,
            start,
            pinned,
            clear,
            partial,
            ye,
            &mut moved,
        );
        (out, moved)
    }

    #[test]
    fn a_partial_zone_moves_the_vertices_whose_paths_are_clear() {
        // vertex 0 pinned and moving; 1..4 free, their own paths spread; vertex 2's new path
        // meets an obstacle
        let x0: Vec<Vec3> = (0..4).map(|i| Vec3::new(i as f64, 0.0, 0.0)).collect();
        let d = Vec3::new(0.3, -0.1, 0.0);
        let mut start: Vec<Vec3> = (0..4)
            .map(|i| x0[i] + Vec3::new(0.0, 0.05 * i as f64, 0.0))
            .collect();
        start[0] = x0[0] + d;
        let pinned = [true, false, false, false];
        let clear = |i: usize, _: Vec3| i != 2;
        let mut ye = start.clone();
        let (out, _) = one_pair(&x0, &start, &pinned, &clear, false, &mut ye);
        assert_eq!((out, &ye), (Err(Refusal::Strict), &start));
        let (out, moved) = one_pair(&x0, &start, &pinned, &clear, true, &mut ye);
        assert_eq!(out, Ok(()));
        // the clear ones follow the pinned vertex, which keeps its own end; vertex 2 stays
        assert_eq!(ye[0], start[0]);
        for i in [1, 3] {
            assert_eq!(ye[i], x0[i] + d);
        }
        assert_eq!(ye[2], start[2]);
        assert_eq!(moved, [false, true, false, true]);
        // nothing left to move: no progress
        let (out, _) = one_pair(&x0, &start, &pinned, &clear, true, &mut ye);
        assert_eq!(out, Err(Refusal::Stuck));
    }

    #[test]
    fn a_zone_with_a_pinned_vertex_moves_with_it_or_not_at_all() {
        let x0: Vec<Vec3> = (0..4).map(|i| Vec3::new(i as f64, 0.0, 0.0)).collect();
        let mut start = x0.clone();
        start[1] += Vec3::new(0.0, 0.5, 0.0);
        start[2] += Vec3::new(0.0, -0.1, 0.0);
        // one pair's zone from a fresh start; the end positions it leaves, or None
        let zone = |start: &[Vec3], pinned: &[bool]| {
            let mut ye = start.to_vec();
            let (ok, _) = one_pair(&x0, start, pinned, &|_, _| true, false, &mut ye);
            ok.is_ok().then_some(ye)
        };
        let mut pinned = [true, false, false, false];
        // the pinned vertex does not move, so neither does its zone
        assert_eq!(zone(&start, &pinned), Some(x0.clone()));
        // two pinned vertices moving differently: no translation
        pinned[3] = true;
        start[3] += Vec3::new(0.1, 0.0, 0.0);
        assert_eq!(zone(&start, &pinned), None);
    }

    #[test]
    fn pinned_vertices_that_move_alike_up_to_rounding_move_a_partial_zone() {
        // a handle's two vertices, each at its own target: the same displacement but for the
        // last bit of one coordinate
        let x0: Vec<Vec3> = (0..4)
            .map(|i| Vec3::new(0.3 * i as f64, 0.7, 0.1))
            .collect();
        let d = Vec3::new(0.006666666666666671, -0.00075, 0.0025);
        let d3 = Vec3::new(d.x, d.y, f64::from_bits(d.z.to_bits() + 1));
        let start = [
            x0[0] + d,
            x0[1],
            x0[2] + Vec3::new(0.0, 0.01, 0.0),
            x0[3] + d3,
        ];
        let pinned = [true, false, false, true];
        let clear = |_: usize, _: Vec3| true;
        let mut ye = start.to_vec();
        let (out, _) = one_pair(&x0, &start, &pinned, &clear, false, &mut ye);
        assert_eq!((out, &ye[..]), (Err(Refusal::Strict), &start[..]));
        let (out, _) = one_pair(&x0, &start, &pinned, &clear, true, &mut ye);
        assert_eq!(out, Ok(()));
        assert_eq!([ye[0], ye[3]], [start[0], start[3]]);
        for i in [1, 2] {
            assert_eq!(ye[i], x0[i] + d);
        }
        // a real difference is not rounding
        let mut far = start;
        far[3] += Vec3::new(1e-9, 0.0, 0.0);
        let mut ye = far.to_vec();
        let (out, _) = one_pair(&x0, &far, &pinned, &clear, true, &mut ye);
        assert_eq!(out, Err(Refusal::Stuck));
    }
}
