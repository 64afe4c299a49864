//! Broad phase: candidate vertex–triangle and edge–edge pairs for deforming triangle meshes.
//!
//! Contract: [`candidates`] reports exactly the pairs whose *moving boxes* meet: each primitive's
//! box at the start of the step (inflated by `margin / 2`) plus `t` times the box of its vertices'
//! displacements must overlap the other's at one common time `t ∈ [0, 1]` (closed boxes: touching
//! counts; [`MovingBox::meets`]), excluding pairs that share a vertex. A pair whose points come
//! within `margin` of each other at some time of the step is always among them (the vertices
//! moving linearly). Several meshes are handled by concatenating their vertex arrays (offsetting
//! indices). The output is sorted and free of duplicates, so it is the same for the same input
//! whatever the number of threads.
//!
//! [`SweptBoxes`] keeps the hierarchies of one step for repeated use: the continuous collision
//! fail-safe pulls a few vertices back along their paths, round after round;
//! [`SweptBoxes::touching`] refits the hierarchies to the new motion and lists only the pairs
//! that involve given vertices. [`SweptBoxes::close`] lists the candidates less the pairs
//! proven to stay farther apart than the margin over the step ([`stay_apart`]): still every
//! pair that comes within it, for far fewer pairs when the margin is a good part of an edge
//! length (the fail-safe and the detect stage use it).
//!
//! Method: bounding-volume hierarchies over the vertices, triangles and edges
//! ([`super::bvh`]), built by median splits at every [`SweptBoxes::new`]; a shared motion (cloth
//! carried along by a turning obstacle) does not make neighbours candidates, as swept boxes
//! would. Boxes with non-finite coordinates never meet anything.
//!
//! [`overlapping_pairs`] and [`overlapping_pairs_between`] (static boxes) use a uniform spatial
//! hash whose cell size is twice the mean extent of the inserted boxes. A pair of boxes is
//! reported from one cell only (the cell holding the lowest corner of their intersection), so no
//! list needs deduplicating. Boxes covering too many cells are kept aside in a list checked
//! against every query.

use super::bvh::{Bvh, MovingBox, TreeCache};
use super::distance::{point_triangle, segment_segment};
use crate::math::Vec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

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

    /// True when the closed box contains `p` (false for NaN).
    pub fn contains(&self, p: Vec3) -> bool {
        self.min.x <= p.x
            && p.x <= self.max.x
            && self.min.y <= p.y
            && p.y <= self.max.y
            && self.min.z <= p.z
            && p.z <= self.max.z
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

#[cfg(test)]
impl Candidates {
    /// Whether every pair of `part` is among these (both sorted).
    pub(crate) fn holds(&self, part: &Candidates) -> bool {
        let sorted = |c: &Candidates| c.vt.is_sorted() && c.ee.is_sorted();
        sorted(self)
            && sorted(part)
            && part.vt.iter().all(|q| self.vt.binary_search(q).is_ok())
            && part.ee.iter().all(|q| self.ee.binary_search(q).is_ok())
    }
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
    SweptBoxes::new(x0, x1, triangles, edges, margin).all()
}

/// The moving boxes of a mesh over one step and their hierarchies (see the module docs).
pub struct SweptBoxes<'a> {
    half_margin: f64,
    triangles: &'a [[u32; 3]],
    edges: &'a [[u32; 2]],
    vertices: Bvh,
    tris: Bvh,
    edge_tree: Bvh,
}

impl<'a> SweptBoxes<'a> {
    /// Boxes and hierarchies for the motion `x0 → x1` (arguments as for [`candidates`]).
    pub fn new(
        x0: &[Vec3],
        x1: &[Vec3],
        triangles: &'a [[u32; 3]],
        edges: &'a [[u32; 2]],
        margin: f64,
    ) -> SweptBoxes<'a> {
        Self::cached(x0, x1, triangles, edges, margin, &mut TreeCache::default())
    }

    /// As [`SweptBoxes::new`], growing the hierarchies on the orders `cache` kept from an
    /// earlier step of the same mesh (the result is the same).
    pub fn cached(
        x0: &[Vec3],
        x1: &[Vec3],
        triangles: &'a [[u32; 3]],
        edges: &'a [[u32; 2]],
        margin: f64,
        cache: &mut TreeCache,
    ) -> SweptBoxes<'a> {
        let r = 0.5 * margin.max(0.0);
        let boxes = |idx: &[u32]| MovingBox::of(idx, x0, x1, r);
        let [mut vertices, mut tris, mut edge_tree] = cache.trees(
            [x0.len(), triangles.len(), edges.len()],
            [&|v| boxes(&[v]), &|t| boxes(&triangles[t as usize]), &|e| {
                boxes(&edges[e as usize])
            }],
        );
        // pairs that share a vertex are never candidates
        vertices.set_vertices(|v| [v; 3]);
        tris.set_vertices(|t| triangles[t as usize]);
        edge_tree.set_vertices(|e| {
            let [a, b] = edges[e as usize];
            [a, b, b]
        });
        SweptBoxes {
            half_margin: r,
            triangles,
            edges,
            vertices,
            tris,
            edge_tree,
        }
    }

    /// Every candidate (as [`candidates`] lists them).
    pub fn all(&self) -> Candidates {
        Candidates {
            vt: self.vertex_triangle(&self.vertices, &self.tris),
            ee: self.edge_edge(&self.edge_tree),
        }
    }

    /// The candidates of [`SweptBoxes::all`] less those that certainly stay farther apart than
    /// the margin over the whole step ([`stay_apart`]), for the motion `x0 → x1` these boxes
    /// were made for. Every pair that comes within the margin at some time of the step is
    /// still among them. On a cloth whose thickness is a good part of an edge length, most
    /// pairs whose boxes meet are neighbours a few edges apart: they cost the callers (the
    /// fail-safe's scan, the narrow phase) more than this test.
    pub fn close(&self, x0: &[Vec3], x1: &[Vec3]) -> Candidates {
        let margin = 2.0 * self.half_margin;
        let (tris, edges) = (self.triangles, self.edges);
        let vt = |v: u32, t: u32| !stay_apart(&[v], &tris[t as usize], x0, x1, margin);
        let ee =
            |e: u32, f: u32| !stay_apart(&edges[e as usize], &edges[f as usize], x0, x1, margin);
        Candidates {
            vt: self.vertices.pairs_with(&self.tris, &vt),
            ee: self.edge_tree.self_pairs(&ee),
        }
    }

    /// (the trees leave out the pairs that share a vertex, [`Bvh::set_vertices`])
    fn vertex_triangle(&self, vertices: &Bvh, tris: &Bvh) -> Vec<(u32, u32)> {
        vertices.pairs_with(tris, &|_, _| true)
    }

    fn edge_edge(&self, edges: &Bvh) -> Vec<(u32, u32)> {
        edges.self_pairs(&|_, _| true)
    }

    /// The candidates of the motion `x0 → x1` (as [`candidates`] would list them) that involve
    /// at least one vertex `i` with `moved[i]` (`moved.len()` = the vertex count), for the same
    /// mesh: the hierarchies of [`SweptBoxes::new`] refitted to the new motion.
    pub fn touching(&self, moved: &[bool], x0: &[Vec3], x1: &[Vec3]) -> Candidates {
        let r = self.half_margin;
        let boxes = |idx: &[u32]| MovingBox::of(idx, x0, x1, r);
        let (tri, edge) = (self.triangles, self.edges);
        let dirty = |idx: &[u32]| idx.iter().any(|&i| moved[i as usize]);
        let refit = |tree: &Bvh,
                     f: &(dyn Fn(u32) -> MovingBox + Sync),
                     m: &(dyn Fn(u32) -> bool + Sync)| {
            let mut t = tree.refit(f);
            t.mark(m);
            t
        };
        let vertices = refit(&self.vertices, &|v| boxes(&[v]), &|v| moved[v as usize]);
        let tris = refit(&self.tris, &|t| boxes(&tri[t as usize]), &|t| {
            dirty(&tri[t as usize])
        });
        let edges = refit(&self.edge_tree, &|e| boxes(&edge[e as usize]), &|e| {
            dirty(&edge[e as usize])
        });
        Candidates {
            vt: self.vertex_triangle(&vertices, &tris),
            ee: self.edge_edge(&edges),
        }
    }
}

/// True when the primitives with vertices `a` and `b` (a vertex and a triangle, or two edges),
/// each vertex moving linearly from `x0` to `x1`, certainly stay farther apart than `margin`
/// over the whole step. False when that is not proven, for non-finite positions among others.
///
/// At time `t` the difference of a point of one and a point of the other is the end's less
/// `(1 − t)` times a convex combination of the relative displacements `d_k − d_l` (`k` a vertex
/// of `a`, `l` of `b`, `d = x1 − x0`), so their distance is at least the distance at the end
/// less `R = max |d_k − d_l|`. The end distance is bounded below first by the gap between the
/// two primitives' projections on the line through their centroids (enough for most
/// neighbours a few edges apart), then computed ([`point_triangle`], [`segment_segment`]: the
/// narrow phase's distances). A relative `10⁻⁹` of `margin` and `10⁻¹²` of the coordinates are
/// left to spare, so rounding cannot drop a pair that comes within `margin`.
pub fn stay_apart(a: &[u32], b: &[u32], x0: &[Vec3], x1: &[Vec3], margin: f64) -> bool {
    let (mut r2, mut scale) = (0.0f64, 0.0f64);
    for &k in a.iter().chain(b) {
        let (p, q) = (x0[k as usize], x1[k as usize]);
        if !(p.is_finite() && q.is_finite()) {
            return false;
        }
        scale = scale.max(p.abs().max_element()).max(q.abs().max_element());
    }
    for &k in a {
        for &l in b {
            let d = (x1[k as usize] - x0[k as usize]) - (x1[l as usize] - x0[l as usize]);
            r2 = r2.max(d.length_squared());
        }
    }
    let limit = margin * (1.0 + 1e-9) + 1e-12 * scale + r2.sqrt();
    let p = |i: &u32| x1[*i as usize];
    let centroid = |ids: &[u32]| ids.iter().map(p).sum::<Vec3>() / ids.len() as f64;
    let axis = centroid(b) - centroid(a);
    let length = axis.length();
    if length > 0.0 {
        let n = axis / length;
        let a_high = a
            .iter()
            .map(|i| p(i).dot(n))
            .fold(f64::NEG_INFINITY, f64::max);
        let b_low = b.iter().map(|i| p(i).dot(n)).fold(f64::INFINITY, f64::min);
        if b_low - a_high > limit {
            return true;
        }
    }
    distance(a, b, |i| x1[i as usize]).is_some_and(|end| end > limit)
}

/// The distance between the primitives with vertices `a` and `b`, a vertex and a triangle or
/// two edges, with vertex `i` at `x(i)` (the narrow phase's [`point_triangle`] and
/// [`segment_segment`]); `None` for other shapes.
pub(crate) fn distance(a: &[u32], b: &[u32], x: impl Fn(u32) -> Vec3) -> Option<f64> {
    match (a, b) {
        ([v], [t0, t1, t2]) => Some(point_triangle(x(*v), x(*t0), x(*t1), x(*t2)).dist),
        ([a0, a1], [b0, b1]) => Some(segment_segment(x(*a0), x(*a1), x(*b0), x(*b1)).dist),
        _ => None,
    }
}

/// All pairs `(i, j)`, `i < j`, of overlapping boxes, sorted.
pub fn overlapping_pairs(boxes: &[Aabb]) -> Vec<(u32, u32)> {
    let grid = Grid::build(boxes);
    let lists: Vec<Vec<(u32, u32)>> = (0..boxes.len())
        .into_par_iter()
        .map_init(Vec::new, |scratch, i| {
            grid.query(&boxes[i], boxes, Some(i as u32), scratch);
            scratch.sort_unstable();
            scratch.iter().map(|&j| (i as u32, j)).collect()
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
            grid.query(&a[i], b, None, scratch);
            scratch.sort_unstable();
            scratch.iter().map(|&j| (i as u32, j)).collect()
        })
        .collect();
    lists.into_iter().flatten().collect()
}

/// Cell size over the mean box extent. Cloth is a surface, so a cell holds fewer boxes than a
/// volume would; twice the mean extent measured fastest on a 128² pile (1× took 2.4× as long).
const CELL_FACTOR: f64 = 2.0;

/// Boxes covering more cells than this go to the always-checked list.
const MAX_CELLS: i64 = 64;

/// FxHash-style hasher for the cell keys (the map is never iterated, so the hash affects speed
/// only, not results).
#[derive(Default)]
struct CellHasher(u64);

impl CellHasher {
    fn add(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl Hasher for CellHasher {
    fn write(&mut self, bytes: &[u8]) {
        for c in bytes.chunks(8) {
            let mut b = [0u8; 8];
            b[..c.len()].copy_from_slice(c);
            self.add(u64::from_le_bytes(b));
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.add(x);
    }
    fn write_i64(&mut self, x: i64) {
        self.add(x as u64);
    }
    fn write_usize(&mut self, x: usize) {
        self.add(x as u64);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

type Cell = [i64; 3];

/// A box in one cell of a [`Grid`].
#[derive(Clone, Copy)]
struct Entry {
    /// Index of the box.
    index: u32,
    /// Bit `k` set when the box's lowest cell has this cell's coordinate `k`: the pair of this
    /// box and a query box is reported from this cell when, on every axis, the bit is set or the
    /// query's lowest cell has this cell's coordinate (this cell then holds the intersection's
    /// lowest corner, since the cell index is monotonic in the coordinate).
    low: u8,
    aabb: Aabb,
}

/// Which coordinates of `cell` equal those of `low`, as bits.
fn low_bits(low: Cell, cell: Cell) -> u8 {
    (0..3).fold(0, |m, k| m | (u8::from(low[k] == cell[k]) << k))
}

/// Uniform spatial hash of boxes: every cell's boxes are stored together (index and a copy of
/// the box), so a query reads memory in order.
struct Grid {
    inv_cell: f64,
    /// `(start, end)` of each non-empty cell's run in `entries`.
    cells: HashMap<Cell, (u32, u32), BuildHasherDefault<CellHasher>>,
    entries: Vec<Entry>,
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
            CELL_FACTOR * mean
        } else {
            1.0
        };
        let mut g = Grid {
            inv_cell: 1.0 / cell,
            cells: HashMap::default(),
            entries: Vec::new(),
            large: Vec::new(),
            count: boxes.len(),
        };
        // boxes going into cells, with their cell ranges
        let mut hashed: Vec<(u32, Cell, Cell)> = Vec::with_capacity(boxes.len());
        for (i, b) in boxes.iter().enumerate() {
            if !b.is_finite() {
                continue;
            }
            let (lo, hi) = g.range(b);
            if (0..3).map(|k| hi[k] - lo[k] + 1).product::<i64>() > MAX_CELLS {
                g.large.push(i as u32);
            } else {
                hashed.push((i as u32, lo, hi));
            }
        }
        let each_cell = |lo: Cell, hi: Cell, f: &mut dyn FnMut(Cell)| {
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        f([x, y, z]);
                    }
                }
            }
        };
        // count, lay the runs out, fill (in box order within each cell)
        for &(_, lo, hi) in &hashed {
            each_cell(lo, hi, &mut |c| g.cells.entry(c).or_insert((0, 0)).1 += 1);
        }
        let mut total = 0u32;
        for run in g.cells.values_mut() {
            let len = run.1;
            *run = (total, total);
            total += len;
        }
        let empty = Entry {
            index: 0,
            low: 0,
            aabb: Aabb {
                min: Vec3::ZERO,
                max: Vec3::ZERO,
            },
        };
        g.entries = vec![empty; total as usize];
        for &(i, lo, hi) in &hashed {
            each_cell(lo, hi, &mut |c| {
                if let Some(run) = g.cells.get_mut(&c) {
                    g.entries[run.1 as usize] = Entry {
                        index: i,
                        low: low_bits(lo, c),
                        aabb: boxes[i as usize],
                    };
                    run.1 += 1;
                }
            });
        }
        g
    }

    fn cell_of(&self, p: Vec3) -> Cell {
        // capped so that cell counts cannot overflow; `floor` without a library call
        let f = |v: f64| {
            let t = (v * self.inv_cell).clamp(-1e15, 1e15);
            let i = t as i64;
            if i as f64 > t { i - 1 } else { i }
        };
        [f(p.x), f(p.y), f(p.z)]
    }

    fn range(&self, b: &Aabb) -> (Cell, Cell) {
        (self.cell_of(b.min), self.cell_of(b.max))
    }

    /// Indices `j > after` (all with `after = None`) of the inserted `boxes` that overlap `b`,
    /// each once, in an order that depends only on the input (unsorted). `boxes` must be the
    /// slice the grid was built from.
    fn query(&self, b: &Aabb, boxes: &[Aabb], after: Option<u32>, out: &mut Vec<u32>) {
        out.clear();
        let first = after.map_or(0, |a| a as u64 + 1);
        if !b.is_finite() {
            return;
        }
        let (lo, hi) = self.range(b);
        let n = (0..3).map(|k| hi[k] - lo[k] + 1).product::<i64>();
        if n > self.cells.len() as i64 || n > 4096 {
            // cheaper to scan everything
            out.extend(
                (first.min(self.count as u64) as u32..self.count as u32)
                    .filter(|&j| b.overlaps(&boxes[j as usize])),
            );
            return;
        }
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let Some(&(start, end)) = self.cells.get(&[x, y, z]) else {
                        continue;
                    };
                    // report each pair from the cell of the intersection's lowest corner
                    let need = !low_bits(lo, [x, y, z]) & 0b111;
                    for e in &self.entries[start as usize..end as usize] {
                        if e.low & need == need && e.index as u64 >= first && b.overlaps(&e.aabb) {
                            out.push(e.index);
                        }
                    }
                }
            }
        }
        out.extend(
            self.large
                .iter()
                .copied()
                .filter(|&j| j as u64 >= first && b.overlaps(&boxes[j as usize])),
        );
    }
}

#[cfg(test)]
pub(crate) mod tests {
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
        let sw = |idx: &[u32]| MovingBox::of(idx, x0, x1, r);
        let mut c = Candidates::default();
        for v in 0..x0.len() as u32 {
            for (t, tri) in tris.iter().enumerate() {
                if !tri.contains(&v) && sw(&[v]).meets(&sw(tri)) {
                    c.vt.push((v, t as u32));
                }
            }
        }
        for (a, ea) in edges.iter().enumerate() {
            for (b, eb) in edges.iter().enumerate().skip(a + 1) {
                if !(ea.contains(&eb[0]) || ea.contains(&eb[1])) && sw(ea).meets(&sw(eb)) {
                    c.ee.push((a as u32, b as u32));
                }
            }
        }
        c
    }

    /// Pseudo-random numbers without extra dependencies (deterministic per seed).
    pub(crate) fn noise(seed: u64) -> impl FnMut() -> f64 {
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
            // a few very fast vertices (long moving boxes)
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

    /// Start and end positions, triangles and edges.
    type Sheets = (Vec<Vec3>, Vec<Vec3>, Vec<[u32; 3]>, Vec<[u32; 2]>);

    /// Two crumpled sheets of `n × n` vertices in one array, moving by up to `motion`.
    fn crumpled(seed: u64, n: usize, motion: f64) -> Sheets {
        let m = Mesh::grid([1.0, 1.0], [n, n], Vec3::ZERO, Vec3::Z).unwrap();
        let m2 = Mesh::grid([0.9, 0.9], [n, n], Vec3::new(0.05, 0.0, 0.02), Vec3::Z).unwrap();
        let mut rnd = noise(seed);
        let n1 = m.positions.len() as u32;
        let x0: Vec<Vec3> = m
            .positions
            .iter()
            .chain(&m2.positions)
            .map(|p| *p + Vec3::new(rnd(), rnd(), rnd()) * 0.02)
            .collect();
        let x1 = x0
            .iter()
            .map(|p| *p + Vec3::new(rnd(), rnd(), rnd()) * motion)
            .collect();
        let mut tris = m.triangles();
        tris.extend(m2.triangles().iter().map(|t| t.map(|i| i + n1)));
        let mut edges = m.edges();
        edges.extend(m2.edges().iter().map(|e| e.map(|i| i + n1)));
        (x0, x1, tris, edges)
    }

    #[test]
    fn the_hierarchy_matches_brute_force_on_sheets_large_enough_to_split_in_parallel() {
        // a few thousand boxes: the traversals split across threads
        for (seed, motion) in [(1, 0.0), (2, 0.01), (3, 0.05)] {
            let (x0, x1, tris, edges) = crumpled(seed, 24, motion);
            let got = candidates(&x0, &x1, &tris, &edges, 0.02);
            assert!(got.vt.len() > 1000 && got.ee.len() > 1000);
            assert_eq!(got, brute(&x0, &x1, &tris, &edges, 0.02));
        }
    }

    /// Trees grown on the order kept from other positions of the same mesh find the same
    /// candidates: the cache changes the speed only.
    #[test]
    fn a_kept_tree_order_finds_the_same_candidates() {
        let mut cache = TreeCache::default();
        for (seed, motion) in [(1, 0.0), (2, 0.05), (3, 0.02), (4, 0.3)] {
            let (x0, x1, tris, edges) = crumpled(seed, 16, motion);
            let got = SweptBoxes::cached(&x0, &x1, &tris, &edges, 0.02, &mut cache).all();
            assert!(!got.vt.is_empty() && !got.ee.is_empty());
            assert_eq!(got, brute(&x0, &x1, &tris, &edges, 0.02));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20))]

        /// After marked vertices moved back along their paths, `touching` lists exactly the
        /// candidates of the new motion that involve a marked vertex.
        #[test]
        fn touching_is_the_candidates_of_the_marked_vertices(
            seed in any::<u64>(), n in 3usize..14, motion in 0.0..0.05f64,
            marks in prop::collection::vec(any::<prop::sample::Index>(), 0..6),
        ) {
            let (x0, x1, tris, edges) = crumpled(seed, n, motion);
            let mut moved = vec![false; x0.len()];
            for m in &marks {
                moved[m.index(x0.len())] = true;
            }
            // the marked vertices moved back part of the way along their paths
            let mut back = x1.clone();
            for (i, m) in marks.iter().enumerate() {
                let v = m.index(x0.len());
                back[v] = x0[v].lerp(x1[v], (i % 3) as f64 * 0.4);
            }
            let all = candidates(&x0, &back, &tris, &edges, 0.03);
            let got = SweptBoxes::new(&x0, &x1, &tris, &edges, 0.03).touching(&moved, &x0, &back);
            let on = |ids: &[u32]| ids.iter().any(|&i| moved[i as usize]);
            let tri = |v: u32, t: u32| { let t = tris[t as usize]; [v, t[0], t[1], t[2]] };
            let edge = |a: u32, b: u32| { let (a, b) = (edges[a as usize], edges[b as usize]); [a[0], a[1], b[0], b[1]] };
            let want = Candidates {
                vt: all.vt.iter().copied().filter(|&(v, t)| on(&tri(v, t))).collect(),
                ee: all.ee.iter().copied().filter(|&(a, b)| on(&edge(a, b))).collect(),
            };
            prop_assert_eq!(got, want);
        }
    }

    /// The smallest distance between the primitives `a` and `b` at times `0, 1/16, ..., 1` of
    /// the linear motion `x0 → x1`.
    fn sampled_distance(a: &[u32], b: &[u32], x0: &[Vec3], x1: &[Vec3]) -> f64 {
        (0..=16)
            .map(|k| {
                let at = |i: u32| x0[i as usize].lerp(x1[i as usize], k as f64 / 16.0);
                distance(a, b, at).expect("a vertex and a triangle, or two edges")
            })
            .fold(f64::INFINITY, f64::min)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40))]

        /// `close` keeps a subset of the candidates that holds every pair within the margin at
        /// some time of the step, whatever the motion (slow, fast, or a few vertices flung far).
        #[test]
        fn close_keeps_every_pair_that_comes_within_the_margin(
            seed in any::<u64>(), n in 3usize..12, motion in 0.0..0.1f64,
            margin in 0.0..0.2f64, fast in 0usize..3,
        ) {
            let (x0, mut x1, tris, edges) = crumpled(seed, n, motion);
            let mut rnd = noise(seed ^ 0x5eed);
            for _ in 0..fast {
                let i = ((rnd() * 0.5 + 0.5) * (x1.len() - 1) as f64) as usize;
                x1[i] += Vec3::new(rnd(), rnd(), rnd());
            }
            let boxes = SweptBoxes::new(&x0, &x1, &tris, &edges, margin);
            let (all, close) = (boxes.all(), boxes.close(&x0, &x1));
            prop_assert!(all.holds(&close));
            for &(v, t) in &all.vt {
                if sampled_distance(&[v], &tris[t as usize], &x0, &x1) <= margin {
                    prop_assert!(close.vt.binary_search(&(v, t)).is_ok(), "lost {:?}", (v, t));
                }
            }
            for &(e, f) in &all.ee {
                if sampled_distance(&edges[e as usize], &edges[f as usize], &x0, &x1) <= margin {
                    prop_assert!(close.ee.binary_search(&(e, f)).is_ok(), "lost {:?}", (e, f));
                }
            }
        }
    }

    /// A flat sheet at rest whose margin is a third of its edge length: most pairs whose boxes
    /// meet are neighbours a few edges apart, and `close` keeps only those within the margin
    /// (at rest, the test is the distance itself).
    #[test]
    fn close_drops_the_neighbours_of_a_flat_sheet_at_rest() {
        let m = Mesh::grid([1.0, 1.0], [21, 21], Vec3::ZERO, Vec3::Z).unwrap();
        let (x, tris, edges) = (m.positions.clone(), m.triangles(), m.edges());
        let margin = 0.05 / 3.0;
        let boxes = SweptBoxes::new(&x, &x, &tris, &edges, margin);
        let (all, close) = (boxes.all(), boxes.close(&x, &x));
        assert!(
            all.vt.len() + all.ee.len() > 500,
            "{}",
            all.vt.len() + all.ee.len()
        );
        // in a flat grid no vertex or edge comes within a third of an edge of a primitive it
        // does not touch
        assert_eq!(close, Candidates::default());
        // a vertex lifted to within the margin above a triangle it is not part of is kept
        let mut y = x.clone();
        let v = 21 * 10 + 10;
        let t = tris
            .iter()
            .position(|t| !t.contains(&(v as u32)) && t.contains(&(v as u32 + 1)))
            .unwrap();
        let c = (x[tris[t][0] as usize] + x[tris[t][1] as usize] + x[tris[t][2] as usize]) / 3.0;
        y[v] = c + Vec3::new(0.0, 0.0, 0.5 * margin);
        let close = SweptBoxes::new(&y, &y, &tris, &edges, margin).close(&y, &y);
        assert!(close.vt.contains(&(v as u32, t as u32)), "{close:?}");
    }

    #[test]
    fn stay_apart_counts_the_relative_motion_and_proves_nothing_for_non_finite_input() {
        // two parallel edges 1 apart, at the end of a step
        let end = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)];
        let (a, b) = ([0u32, 1], [2u32, 3]);
        assert!(stay_apart(&a, &b, &end, &end, 0.9));
        assert!(!stay_apart(&a, &b, &end, &end, 1.0));
        // carried along together by 5: still apart
        let shifted: Vec<Vec3> = end.iter().map(|p| *p - Vec3::splat(5.0)).collect();
        assert!(stay_apart(&a, &b, &shifted, &end, 0.9));
        // the second edge came from 0.8 below the first (through it): not apart
        let mut start = end;
        start[2].y = -0.8;
        start[3].y = -0.8;
        assert!(!stay_apart(&a, &b, &start, &end, 0.1));
        // a vertex coming down onto a triangle from 1.2 above, ending 1 above: apart by the end
        // distance less the whole relative motion (a bound, not the distance: 0.9 is not
        // proven, though the vertex never comes closer than 1)
        let x1 = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.2, 0.2, 1.0)];
        let mut x0 = x1;
        x0[3].z = 1.2;
        assert!(stay_apart(&[3], &[0, 1, 2], &x0, &x1, 0.79));
        assert!(!stay_apart(&[3], &[0, 1, 2], &x0, &x1, 0.81));
        assert!(!stay_apart(&[3], &[0, 1, 2], &x0, &x1, 0.9));
        // ... from below the triangle: it passed through
        x0[3].z = -0.5;
        assert!(!stay_apart(&[3], &[0, 1, 2], &x0, &x1, 0.1));
        let mut nan = x1;
        nan[0].x = f64::NAN;
        assert!(!stay_apart(&[3], &[0, 1, 2], &nan, &x1, 0.1));
        assert!(!stay_apart(&[3], &[0, 1, 2], &x1, &nan, 0.1));
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
