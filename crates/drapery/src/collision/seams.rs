//! Stitched neighbourhoods: the contact pairs a seam must be allowed to close through.
//!
//! A stitch pulls its two vertices together, so the triangles and edges around them must be
//! let through each other's repulsion and continuous collision detection. The *neighbourhood*
//! of a stitched pair `(a, b)` is `a`, `b` and every vertex that shares a triangle with either;
//! a vertex–triangle or edge–edge pair whose four particles all lie in one neighbourhood is
//! exempt. With no stitch nothing is exempt.

/// For each cloth particle, the stitched pairs whose neighbourhood holds it (CSR, each list
/// increasing).
#[derive(Clone, Debug, Default)]
pub struct Seams {
    ptr: Vec<u32>,
    pairs: Vec<u32>,
}

impl Seams {
    /// The neighbourhoods of the stitched pairs `stitches` over `n` particles and the cloth
    /// `triangles`.
    pub fn new(n: usize, triangles: &[[u32; 3]], stitches: &[[u32; 2]]) -> Seams {
        let groups: Vec<&[u32]> = stitches.iter().map(|s| &s[..]).collect();
        Seams::around(n, triangles, &groups)
    }

    /// The neighbourhoods of any groups of particles: each group and every particle sharing a
    /// triangle with one of its members (a stitched pair is a group of two; a pair of crossed
    /// triangles, [`crate::step`]'s starting tangles, a group of six).
    pub fn around(n: usize, triangles: &[[u32; 3]], stitches: &[&[u32]]) -> Seams {
        if stitches.is_empty() {
            return Seams::default();
        }
        // the triangles of each particle
        let mut around: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (t, tri) in triangles.iter().enumerate() {
            for &p in tri {
                around[p as usize].push(t as u32);
            }
        }
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (s, pair) in stitches.iter().enumerate() {
            let mut hood: Vec<u32> = pair.to_vec();
            for &end in pair.iter() {
                for &t in &around[end as usize] {
                    hood.extend_from_slice(&triangles[t as usize]);
                }
            }
            hood.sort_unstable();
            hood.dedup();
            for p in hood {
                members[p as usize].push(s as u32);
            }
        }
        let mut ptr = Vec::with_capacity(n + 1);
        ptr.push(0u32);
        let mut pairs = Vec::new();
        for m in members {
            pairs.extend(m);
            ptr.push(pairs.len() as u32);
        }
        Seams { ptr, pairs }
    }

    /// True when there is no stitch.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// The stitched pairs whose neighbourhood holds particle `p` (none beyond the cloth).
    fn of(&self, p: u32) -> &[u32] {
        match self.ptr.get(p as usize + 1) {
            Some(&end) => &self.pairs[self.ptr[p as usize] as usize..end as usize],
            None => &[],
        }
    }

    /// Whether the contact pair of particles `ids` lies within one stitched neighbourhood.
    pub fn exempt(&self, ids: &[u32; 4]) -> bool {
        if self.is_empty() {
            return false;
        }
        self.of(ids[0]).iter().any(|s| {
            ids[1..]
                .iter()
                .all(|&p| self.of(p).binary_search(s).is_ok())
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
}
