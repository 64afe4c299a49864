//! Stitched neighbourhoods: the contact pairs a seam must be allowed to close through.
//!
//! A stitch pulls its two vertices together, so the triangles and edges around them must be
//! let through each other's repulsion and continuous collision detection. The *neighbourhood*
//! of a stitched pair `(a, b)` is `a`, `b` and every vertex that shares a triangle with either;
//! its *sides* are `a` with the vertices sharing a triangle with `a`, and `b` with those of `b`.
//! A vertex–triangle or edge–edge pair whose four particles all lie in one neighbourhood, some
//! on one side only and some on the other side only, is exempt: the seam closes across its
//! sides. A pair within one side is not (the stitch does not pull a side onto itself, so a fold
//! there is held apart like any other). With no stitch nothing is exempt.

/// For each cloth particle, the stitched pairs whose neighbourhood holds it (CSR, each list
/// increasing) and on which of their sides it lies.
#[derive(Clone, Debug, Default)]
pub struct Seams {
    ptr: Vec<u32>,
    pairs: Vec<u32>,
    /// Per entry of `pairs`: bit 0 on the first end's side, bit 1 on the second's; 0 for
    /// groups without sides ([`Seams::around`]).
    sides: Vec<u8>,
}

impl Seams {
    /// The neighbourhoods of the stitched pairs `stitches` over `n` particles and the cloth
    /// `triangles`, with their sides.
    pub fn new(n: usize, triangles: &[[u32; 3]], stitches: &[[u32; 2]]) -> Seams {
        let groups: Vec<&[u32]> = stitches.iter().map(|s| &s[..]).collect();
        Seams::build(n, triangles, &groups, true)
    }

    /// The neighbourhoods of any groups of particles: each group and every particle sharing a
    /// triangle with one of its members (a pair of crossed triangles, [`crate::step`]'s
    /// starting tangles, is a group of six). They have no sides: a pair within one is exempt.
    pub fn around(n: usize, triangles: &[[u32; 3]], groups: &[&[u32]]) -> Seams {
        Seams::build(n, triangles, groups, false)
    }

    /// The neighbourhoods of `groups`; with `sided`, each group is a stitched pair and its
    /// members' sides are recorded.
    fn build(n: usize, triangles: &[[u32; 3]], groups: &[&[u32]], sided: bool) -> Seams {
        if groups.is_empty() {
            return Seams::default();
        }
        // the triangles of each particle
        let mut around: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (t, tri) in triangles.iter().enumerate() {
            for &p in tri {
                around[p as usize].push(t as u32);
            }
        }
        let mut members: Vec<Vec<(u32, u8)>> = vec![Vec::new(); n];
        for (s, group) in groups.iter().enumerate() {
            let mut hood: Vec<(u32, u8)> = Vec::new();
            for (k, &end) in group.iter().enumerate() {
                let side = if sided { 1u8 << k } else { 0 };
                hood.push((end, side));
                for &t in &around[end as usize] {
                    hood.extend(triangles[t as usize].iter().map(|&p| (p, side)));
                }
            }
            hood.sort_unstable();
            // one entry per particle, its sides merged
            let mut merged: Vec<(u32, u8)> = Vec::with_capacity(hood.len());
            for (p, side) in hood {
                match merged.last_mut() {
                    Some(last) if last.0 == p => last.1 |= side,
                    _ => merged.push((p, side)),
                }
            }
            for (p, side) in merged {
                members[p as usize].push((s as u32, side));
            }
        }
        let mut ptr = Vec::with_capacity(n + 1);
        ptr.push(0u32);
        let (mut pairs, mut sides) = (Vec::new(), Vec::new());
        for m in members {
            for (s, side) in m {
                pairs.push(s);
                sides.push(side);
            }
            ptr.push(pairs.len() as u32);
        }
        Seams { ptr, pairs, sides }
    }

    /// True when there is no stitch.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Whether particle `p` lies in some neighbourhood.
    pub fn holds(&self, p: u32) -> bool {
        !self.range(p).is_empty()
    }

    /// The range of `pairs` and `sides` for particle `p` (empty beyond the cloth).
    fn range(&self, p: u32) -> std::ops::Range<usize> {
        match self.ptr.get(p as usize + 1) {
            Some(&end) => self.ptr[p as usize] as usize..end as usize,
            None => 0..0,
        }
    }

    /// Whether the contact pair of particles `ids` lies within one stitched neighbourhood and
    /// across its sides.
    pub fn exempt(&self, ids: &[u32; 4]) -> bool {
        if self.is_empty() {
            return false;
        }
        let first = self.range(ids[0]);
        self.pairs[first.clone()]
            .iter()
            .zip(&self.sides[first])
            .any(|(s, &side)| {
                let mut common = side;
                ids[1..].iter().all(|&p| {
                    let r = self.range(p);
                    match self.pairs[r.clone()].binary_search(s) {
                        Ok(i) => {
                            common &= self.sides[r.start + i];
                            true
                        }
                        Err(_) => false,
                    }
                }) && common == 0
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pair_is_exempt_only_within_one_neighbourhood() {
        // a strip of triangles 0-1-2, 1-2-3, 2-3-4, 3-4-5, 4-5-6, and particle 7 alone
        let tris: Vec<[u32; 3]> = (0..5).map(|i| [i, i + 1, i + 2]).collect();
        let none = Seams::new(8, &tris, &[]);
        assert!(none.is_empty() && !none.exempt(&[0, 1, 2, 3]));
        let s = Seams::new(8, &tris, &[[0, 7]]);
        // the neighbourhood of (0, 7): 0, 7 and 0's triangle 0-1-2
        assert!(s.exempt(&[7, 0, 1, 2]) && s.exempt(&[2, 1, 0, 7]));
        assert!(!s.exempt(&[7, 1, 2, 3]), "3 shares no triangle with 0 or 7");
        // particles beyond the cloth (obstacle vertices) are never exempt
        assert!(!s.exempt(&[7, 0, 1, 8]));
        // two stitches: a pair spanning both neighbourhoods but lying in neither is not exempt
        let s = Seams::new(8, &tris, &[[0, 7], [6, 7]]);
        assert!(s.exempt(&[7, 4, 5, 6]) && s.exempt(&[7, 0, 1, 2]));
        assert!(!s.exempt(&[0, 1, 5, 6]));
    }

    #[test]
    fn a_pair_within_one_side_of_a_seam_is_not_exempt() {
        // the strip of triangles i, i+1, i+2 (i = 0..5) sewn at 2 to particle 7: the side of 2
        // is 0..=4 (its triangles 0-1-2, 1-2-3, 2-3-4), the other side 7 alone
        let tris: Vec<[u32; 3]> = (0..5).map(|i| [i, i + 1, i + 2]).collect();
        let s = Seams::new(8, &tris, &[[2, 7]]);
        assert!(s.exempt(&[7, 1, 3, 4]) && s.exempt(&[0, 1, 2, 7]));
        // a fold of the cloth around 2 is held apart as anywhere else
        assert!(!s.exempt(&[0, 1, 3, 4]) && !s.exempt(&[2, 0, 3, 4]));
        // groups without sides (starting tangles) exempt every pair within them
        let a = Seams::around(8, &tris, &[&[0, 1, 2]]);
        assert!(a.exempt(&[0, 1, 2, 3]) && a.exempt(&[1, 2, 3, 4]));
    }
}
