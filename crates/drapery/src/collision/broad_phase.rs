//! Broad phase: candidate vertex–triangle and edge–edge pairs for deforming triangle meshes.
//!
//! Contract: [`candidates`] reports exactly the pairs whose *swept* boxes (the axis-aligned box of
//! the primitive's vertices at the start and at the end of the step) come within `margin` of each
//! other (each box is inflated by `margin / 2`, boxes touching counts as overlapping), excluding
//! pairs that share a vertex. Several meshes are handled by concatenating their vertex arrays
//! (offsetting indices). The output is sorted and free of duplicates, so it is the same for the
//! same input whatever the number of threads (queries run on rayon's pool).
//!
//! Method: a uniform spatial hash whose cell size is the mean extent of the inserted boxes.
//! Boxes covering too many cells (very fast or very large primitives) are kept aside in a list
//! checked against every query, so the cost stays bounded and nothing is lost. Boxes with
//! non-finite coordinates never overlap anything.

use crate::math::Vec3;
use rayon::prelude::*;
use std::collections::HashMap;

/// An axis-aligned bounding box (closed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box of a set of points (an inverted, empty box for no points; a NaN box, which
    /// overlaps nothing, if any point is not finite).
    pub fn of_points(points: impl IntoIterator<Item = Vec3>) -> Aabb {
        let mut b = Aabb {
            min: Vec3::splat(f64::INFINITY),
            max: Vec3::splat(f64::NEG_INFINITY),
        };
        for p in points {
            if !p.is_finite() {
                return Aabb {
                    min: Vec3::NAN,
                    max: Vec3::NAN,
                };
            }
            b.min = b.min.min(p);
            b.max = b.max.max(p);
        }
        b
    }

    /// The box grown by `r` on every side.
    pub fn inflated(&self, r: f64) -> Aabb {
        Aabb {
            min: self.min - Vec3::splat(r),
            max: self.max + Vec3::splat(r),
        }
    }

    /// True when the closed boxes intersect (false if either has a NaN coordinate).
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.x <= o.max.x
            && o.min.x <= self.max.x
            && self.min.y <= o.max.y
            && o.min.y <= self.max.y
            && self.min.z <= o.max.z
            && o.min.z <= self.max.z
    }

    fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }
}

/// Candidate pairs for the narrow phase, both lists sorted and without duplicates.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Candidates {
    /// `(vertex, triangle)`: vertex index into the positions, triangle index into `triangles`.
    pub vt: Vec<(u32, u32)>,
    /// `(edge, edge)` with the first index smaller, indices into `edges`.
    pub ee: Vec<(u32, u32)>,
}

/// Vertex–triangle and edge–edge candidates of a deforming mesh over one step.
///
/// `x0`, `x1`: positions at the start and end of the step (same length); every vertex is a
/// candidate point. `triangles`, `edges`: index lists (indices must be `< x0.len()`).
/// `margin ≥ 0`: pairs within this distance of each other are reported (use the collision
/// thickness).
pub fn candidates(
    x0: &[Vec3],
    x1: &[Vec3],
    triangles: &[[u32; 3]],
    edges: &[[u32; 2]],
    margin: f64,
) -> Candidates {
    let r = 0.5 * margin.max(0.0);
    let swept = |idx: &[u32]| {
        Aabb::of_points(idx.iter().flat_map(|&i| [x0[i as usize], x1[i as usize]])).inflated(r)
    };
    let vboxes: Vec<Aabb> = (0..x0.len() as u32).map(|v| swept(&[v])).collect();
    let tboxes: Vec<Aabb> = triangles.iter().map(|t| swept(t)).collect();
    let eboxes: Vec<Aabb> = edges.iter().map(|e| swept(e)).collect();

    let mut vt = overlapping_pairs_between(&vboxes, &tboxes);
    vt.retain(|&(v, t)| !triangles[t as usize].contains(&v));
    let mut ee = overlapping_pairs(&eboxes);
    ee.retain(|&(a, b)| {
        let (a, b) = (edges[a as usize], edges[b as usize]);
        !(a.contains(&b[0]) || a.contains(&b[1]))
    });
    Candidates { vt, ee }
}

/// All pairs `(i, j)`, `i < j`, of overlapping boxes, sorted.
pub fn overlapping_pairs(boxes: &[Aabb]) -> Vec<(u32, u32)> {
    let grid = Grid::build(boxes);
    let lists: Vec<Vec<(u32, u32)>> = (0..boxes.len())
        .into_par_iter()
        .map_init(Vec::new, |scratch, i| {
            grid.query(&boxes[i], scratch);
            scratch
                .iter()
                .filter(|&&j| (j as usize) > i && boxes[i].overlaps(&boxes[j as usize]))
                .map(|&j| (i as u32, j))
                .collect()
        })
        .collect();
    lists.into_iter().flatten().collect()
}

/// All pairs `(i, j)` with `a[i]` overlapping `b[j]`, sorted.
pub fn overlapping_pairs_between(a: &[Aabb], b: &[Aabb]) -> Vec<(u32, u32)> {
    let grid = Grid::build(b);
    let lists: Vec<Vec<(u32, u32)>> = (0..a.len())
        .into_par_iter()
        .map_init(Vec::new, |scratch, i| {
            grid.query(&a[i], scratch);
            scratch
                .iter()
                .filter(|&&j| a[i].overlaps(&b[j as usize]))
                .map(|&j| (i as u32, j))
                .collect()
        })
        .collect();
    lists.into_iter().flatten().collect()
}

/// Boxes covering more cells than this go to the always-checked list.
const MAX_CELLS: i64 = 64;

/// Uniform spatial hash of boxes.
struct Grid {
    inv_cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
    /// Boxes too large for the hash (checked against every query).
    large: Vec<u32>,
    /// Number of boxes inserted.
    count: usize,
}

impl Grid {
    fn build(boxes: &[Aabb]) -> Grid {
        let finite: Vec<&Aabb> = boxes.iter().filter(|b| b.is_finite()).collect();
        let mean = if finite.is_empty() {
            1.0
        } else {
            finite
                .iter()
                .map(|b| (b.max - b.min).max_element())
                .sum::<f64>()
                / finite.len() as f64
        };
        let cell = if mean > 0.0 && mean.is_finite() {
            mean
        } else {
            1.0
        };
        let mut g = Grid {
            inv_cell: 1.0 / cell,
            cells: HashMap::new(),
            large: Vec::new(),
            count: boxes.len(),
        };
        for (i, b) in boxes.iter().enumerate() {
            if !b.is_finite() {
                continue;
            }
            let (lo, hi) = g.range(b);
            if (0..3).map(|k| hi[k] - lo[k] + 1).product::<i64>() > MAX_CELLS {
                g.large.push(i as u32);
                continue;
            }
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        g.cells.entry([x, y, z]).or_default().push(i as u32);
                    }
                }
            }
        }
        g
    }

    fn range(&self, b: &Aabb) -> ([i64; 3], [i64; 3]) {
        // `as i64` saturates, and we cap the coordinates so that cell counts cannot overflow
        let f = |v: f64| ((v * self.inv_cell).floor().clamp(-1e15, 1e15)) as i64;
        (
            [f(b.min.x), f(b.min.y), f(b.min.z)],
            [f(b.max.x), f(b.max.y), f(b.max.z)],
        )
    }

    /// Indices of boxes that may overlap `b` (sorted, unique); the caller tests overlap.
    fn query(&self, b: &Aabb, out: &mut Vec<u32>) {
        out.clear();
        if !b.is_finite() {
            return;
        }
        let (lo, hi) = self.range(b);
        let n = (0..3).map(|k| hi[k] - lo[k] + 1).product::<i64>();
        if n > self.cells.len() as i64 || n > 4096 {
            // cheaper to scan everything
            out.extend(0..self.count as u32);
            return;
        }
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    if let Some(list) = self.cells.get(&[x, y, z]) {
                        out.extend_from_slice(list);
                    }
                }
            }
        }
        out.extend_from_slice(&self.large);
        out.sort_unstable();
        out.dedup();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use proptest::prelude::*;

    fn brute(
        x0: &[Vec3],
        x1: &[Vec3],
        tris: &[[u32; 3]],
        edges: &[[u32; 2]],
        margin: f64,
    ) -> Candidates {
        let r = 0.5 * margin;
        let sw = |idx: &[u32]| {
            Aabb::of_points(idx.iter().flat_map(|&i| [x0[i as usize], x1[i as usize]])).inflated(r)
        };
        let mut c = Candidates::default();
        for v in 0..x0.len() as u32 {
            for (t, tri) in tris.iter().enumerate() {
                if !tri.contains(&v) && sw(&[v]).overlaps(&sw(tri)) {
                    c.vt.push((v, t as u32));
                }
            }
        }
        for (a, ea) in edges.iter().enumerate() {
            for (b, eb) in edges.iter().enumerate().skip(a + 1) {
                if !(ea.contains(&eb[0]) || ea.contains(&eb[1])) && sw(ea).overlaps(&sw(eb)) {
                    c.ee.push((a as u32, b as u32));
                }
            }
        }
        c
    }

    /// Pseudo-random numbers without extra dependencies (deterministic per seed).
    fn noise(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40))]

        #[test]
        fn matches_brute_force_on_random_crumpled_meshes(
            seed in any::<u64>(),
            nx in 2usize..9, ny in 2usize..9,
            amp in 0.0..0.5f64, motion in 0.0..0.5f64, margin in 0.0..0.2f64,
            fast in 0usize..3,
        ) {
            let m = Mesh::grid([1.0, 1.0], [nx, ny], Vec3::ZERO, Vec3::Z).unwrap();
            // a second sheet above the first, as a separate mesh in the same arrays
            let m2 = Mesh::grid([0.8, 0.8], [ny, nx], Vec3::new(0.1, 0.0, 0.1), Vec3::Y).unwrap();
            let mut rnd = noise(seed);
            let n1 = m.positions.len() as u32;
            let mut x0: Vec<Vec3> = m.positions.iter().chain(&m2.positions).copied().collect();
            for p in &mut x0 {
                *p += Vec3::new(rnd(), rnd(), rnd()) * amp;
            }
            let mut x1: Vec<Vec3> = x0.iter().map(|p| *p + Vec3::new(rnd(), rnd(), rnd()) * motion).collect();
            // a few very fast vertices to exercise the large-box path
            for _ in 0..fast {
                let i = ((rnd() * 0.5 + 0.5) * (x1.len() - 1) as f64) as usize;
                x1[i] += Vec3::new(rnd(), rnd(), rnd()) * 50.0;
            }
            let mut tris = m.triangles();
            tris.extend(m2.triangles().iter().map(|t| t.map(|i| i + n1)));
            let mut edges = m.edges();
            edges.extend(m2.edges().iter().map(|e| e.map(|i| i + n1)));
            let got = candidates(&x0, &x1, &tris, &edges, margin);
            let want = brute(&x0, &x1, &tris, &edges, margin);
            prop_assert_eq!(&got, &want);
            // deterministic
            prop_assert_eq!(got, candidates(&x0, &x1, &tris, &edges, margin));
        }
    }

    #[test]
    fn shared_vertices_are_excluded_and_degenerate_input_is_harmless() {
        let x = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)];
        let tris = [[0, 1, 2], [1, 3, 2]];
        let edges = [[0, 1], [1, 2], [2, 0], [1, 3], [3, 2]];
        let c = candidates(&x, &x, &tris, &edges, 0.1);
        assert_eq!(c.vt, vec![(0, 1), (3, 0)]);
        assert_eq!(c.ee, vec![]); // opposite sides of the square are 1 apart
        let c = candidates(&x, &x, &tris, &edges, 1.0);
        assert_eq!(c.ee, vec![(0, 4), (2, 3)]);
        assert_eq!(candidates(&[], &[], &[], &[], 0.1), Candidates::default());
        // all points equal (zero-size boxes, zero mean extent)
        let y = vec![Vec3::ONE; 4];
        let c = candidates(&y, &y, &tris, &edges, 0.0);
        assert_eq!(c.vt.len(), 2);
        // non-finite positions produce no pairs for the affected primitives
        let mut z = x.clone();
        z[3].x = f64::NAN;
        let c = candidates(&z, &z, &tris, &edges, 0.1);
        assert_eq!(c.vt, vec![]);
    }
}
