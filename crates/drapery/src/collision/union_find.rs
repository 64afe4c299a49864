//! The root lookup of a union–find forest stored as each element's parent (a root is its own),
//! for the groups the collision code merges: impact zones ([`super::zones`]), sewn vertices
//! ([`super::check`]) and the fail-safe's carried groups ([`super::failsafe`]).

/// The root of `i` in the forest `parent`, halving the path on the way (each element passed
/// then points to its grandparent; no root changes).
pub(crate) fn root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let p = parent[i as usize];
        parent[i as usize] = parent[p as usize];
        i = p;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The root without touching the forest.
    fn walk(parent: &[u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            i = parent[i as usize];
        }
        i
    }

    #[test]
    fn every_element_finds_its_tree_s_root_and_paths_only_shorten() {
        // two chains, 0 <- 1 <- 2 <- 3 <- 4 and 5 <- 6 <- 7, and a lone 8
        let mut parent = vec![0, 0, 1, 2, 3, 5, 5, 6, 8];
        let depth = |p: &[u32], mut i: u32| {
            let mut d = 0;
            while p[i as usize] != i {
                i = p[i as usize];
                d += 1;
            }
            d
        };
        let before = parent.clone();
        for i in 0..9 {
            let want = walk(&before, i);
            let old: Vec<usize> = (0..9).map(|j| depth(&parent, j)).collect();
            assert_eq!(root(&mut parent, i), want, "{i}");
            for j in 0..9u32 {
                assert_eq!(walk(&parent, j), walk(&before, j), "{j}'s tree changed");
                assert!(depth(&parent, j) <= old[j as usize], "{j} got deeper");
            }
        }
        // 4 was four steps from its root; one lookup halves its path
        let mut chain = before.clone();
        root(&mut chain, 4);
        assert_eq!(depth(&chain, 4), 2);
    }
}
