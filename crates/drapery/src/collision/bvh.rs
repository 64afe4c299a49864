//! A bounding-volume hierarchy over *moving boxes*, the broad phase's search structure
//! ([`super::broad_phase`]).
//!
//! Every primitive (a vertex, an edge or a triangle) moves linearly over the step, each vertex
//! from `x0` to `x1`. A point of the primitive at time `t ∈ [0, 1]` is a convex combination of
//! its vertices' `x0 + t (x1 − x0)`, so it lies in the primitive's moving box `B + t D`: `B` the
//! box of its vertices' start positions (inflated by half the margin), `D` the box of their
//! displacements. Two primitives can come within the margin of each other only if their moving
//! boxes overlap at one common `t` ([`MovingBox::meets`], docs/MATH.md §16). Unlike the swept box
//! (the box of the start and end positions), this test does not grow with a motion the two
//! share: neighbours carried along together by a turning obstacle do not meet.
//!
//! The tree: the primitives are ordered by median splits of their boxes' centres along the
//! longest axis, halving down to leaves of at most [`LEAF`], and each node holds the union of its
//! subtree's `B` and `D`. A tree can also be grown on a given order ([`Bvh::with_order`]): the
//! order of an earlier step's tree, since a mesh's patches stay patches as it moves
//! ([`TreeCache`]); only the boxes are new. A node pair is pruned when, on some axis, the two
//! cannot overlap at any time of the step ([`MovingBox::may_meet`]: the union over `t` of
//! `B + tD`, a looser test than a common `t`, cheap enough for every node pair visited).
//!
//! The traversals return their pairs sorted, so the result does not depend on the tree's shape
//! or on the number of threads.

use super::pair_sort::sort_pairs;
use crate::math::Vec3;
use rayon::prelude::*;

/// Most primitives in a leaf.
pub const LEAF: usize = 8;

/// Subtrees of more primitives than this are traversed in parallel.
const PARALLEL: u32 = 2048;

/// A primitive's (or a subtree's) moving box: `[lo, hi] + t [dlo, dhi]` at time `t ∈ [0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MovingBox {
    /// Least corner at the start.
    pub lo: Vec3,
    /// Greatest corner at the start.
    pub hi: Vec3,
    /// Least displacement over the step.
    pub dlo: Vec3,
    /// Greatest displacement over the step.
    pub dhi: Vec3,
}

impl MovingBox {
    /// The box that meets nothing (of a primitive with a non-finite coordinate).
    pub const EMPTY: MovingBox = MovingBox {
        lo: Vec3::INFINITY,
        hi: Vec3::NEG_INFINITY,
        dlo: Vec3::INFINITY,
        dhi: Vec3::NEG_INFINITY,
    };

    /// The moving box of the vertices `ids` going from `x0` to `x1`, inflated by `r` (and by
    /// a relative 1e-12 of the coordinates, so that rounding in the tests cannot lose a pair
    /// that touches), or [`MovingBox::EMPTY`] if a coordinate is not finite.
    pub fn of(ids: &[u32], x0: &[Vec3], x1: &[Vec3], r: f64) -> MovingBox {
        let mut b = MovingBox::EMPTY;
        let mut scale = 0.0f64;
        for &i in ids {
            let (p, q) = (x0[i as usize], x1[i as usize]);
            let d = q - p;
            if !(p.is_finite() && q.is_finite() && d.is_finite()) {
                return MovingBox::EMPTY;
            }
            b.lo = b.lo.min(p);
            b.hi = b.hi.max(p);
            b.dlo = b.dlo.min(d);
            b.dhi = b.dhi.max(d);
            scale = scale.max(p.abs().max_element()).max(q.abs().max_element());
        }
        if ids.is_empty() {
            return b;
        }
        b.grown(scale, r)
    }

    /// Inflated by `r` and by `1e-12 scale` (see [`MovingBox::of`]).
    fn grown(mut self, scale: f64, r: f64) -> MovingBox {
        let s = 1e-12 * scale;
        let grow = Vec3::splat(r + s);
        self.lo -= grow;
        self.hi += grow;
        self.dlo -= Vec3::splat(s);
        self.dhi += Vec3::splat(s);
        self
    }

    /// `[MovingBox::of(ids, x0, x1, r), MovingBox::of(ids, x1, x1, r_end)]` (the same bits)
    /// from one pass over the vertices: the moving box over the step and the box at the end
    /// positions.
    pub fn of_and_end(ids: &[u32], x0: &[Vec3], x1: &[Vec3], r: f64, r_end: f64) -> [MovingBox; 2] {
        let (mut b, mut e) = (MovingBox::EMPTY, MovingBox::EMPTY);
        let (mut scale, mut scale_end) = (0.0f64, 0.0f64);
        let (mut moving, mut end) = (true, true);
        for &i in ids {
            let (p, q) = (x0[i as usize], x1[i as usize]);
            let d = q - p;
            moving &= p.is_finite() && q.is_finite() && d.is_finite();
            // the end box is `of`'s with `p = q`: its displacement `q - q` is `+0`, finite
            // exactly when `q` is
            end &= q.is_finite();
            b.lo = b.lo.min(p);
            b.hi = b.hi.max(p);
            b.dlo = b.dlo.min(d);
            b.dhi = b.dhi.max(d);
            let (pa, qa) = (p.abs().max_element(), q.abs().max_element());
            scale = scale.max(pa).max(qa);
            e.lo = e.lo.min(q);
            e.hi = e.hi.max(q);
            // (`of`'s `scale.max(qa).max(qa)`: `max` is idempotent)
            scale_end = scale_end.max(qa);
        }
        if ids.is_empty() {
            return [b, e];
        }
        // the displacements' bounds, `min`/`max` of the `+0`s
        (e.dlo, e.dhi) = (Vec3::ZERO, Vec3::ZERO);
        [
            if moving {
                b.grown(scale, r)
            } else {
                MovingBox::EMPTY
            },
            if end {
                e.grown(scale_end, r_end)
            } else {
                MovingBox::EMPTY
            },
        ]
    }

    /// The box holding both.
    pub fn union(&self, o: &MovingBox) -> MovingBox {
        MovingBox {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            dlo: self.dlo.min(o.dlo),
            dhi: self.dhi.max(o.dhi),
        }
    }

    /// False when, on some axis, the two boxes cannot overlap at any time of the step (the
    /// difference of their positions, `p + t q`, keeps one sign on that axis over `t ∈ [0, 1]`).
    /// All three axes at once, without branches: it is the first test of every node pair and
    /// primitive pair the traversals meet (BENCHMARKS.md, thirty-fourth session).
    #[inline]
    pub fn may_meet(&self, o: &MovingBox) -> bool {
        // (false for NaN: an empty box meets nothing)
        let (a, b) = (self, o);
        let low = (a.lo - b.hi) + (a.dlo - b.dhi).min(Vec3::ZERO);
        let high = (a.hi - b.lo) + (a.dhi - b.dlo).max(Vec3::ZERO);
        (low.cmple(Vec3::ZERO) & high.cmpge(Vec3::ZERO)).all()
    }

    /// True when the two boxes overlap at some common time `t ∈ [0, 1]` (closed boxes: touching
    /// counts). False if either is [`MovingBox::EMPTY`].
    pub fn meets(&self, o: &MovingBox) -> bool {
        if !self.may_meet(o) {
            return false;
        }
        let (p_lo, p_hi) = ((self.lo - o.hi).to_array(), (self.hi - o.lo).to_array());
        let (q_lo, q_hi) = ((self.dlo - o.dhi).to_array(), (self.dhi - o.dlo).to_array());
        // on each axis `p_lo + t q_lo ≤ 0 ≤ p_hi + t q_hi`: each is `a t ≤ b`
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for k in 0..3 {
            for (a, b) in [(q_lo[k], -p_lo[k]), (-q_hi[k], p_hi[k])] {
                if a > 0.0 {
                    t1 = t1.min(b / a);
                } else if a < 0.0 {
                    t0 = t0.max(b / a);
                } else if b < 0.0 {
                    return false;
                }
            }
        }
        t0 <= t1
    }
}

/// Leaf orders kept from one step's trees to the next (see the module docs). A cache for speed
/// only: the traversals' results do not depend on the order. The orders are made anew every
/// [`TreeCache::REUSE`] uses, and whenever the primitives' count changes.
#[derive(Clone, Debug, Default)]
pub struct TreeCache {
    orders: Vec<Vec<u32>>,
    uses: usize,
}

impl TreeCache {
    /// Uses of one set of orders.
    pub const REUSE: usize = 64;

    /// The trees of primitives `0..counts[k]` with boxes `boxes[k]` (built side by side), on
    /// the kept orders where they fit (the boxes are then computed in leaf order, straight
    /// into the tree).
    pub fn trees(
        &mut self,
        counts: [usize; 3],
        boxes: [&(dyn Fn(u32) -> MovingBox + Sync); 3],
    ) -> [Bvh; 3] {
        let fits = self.orders.len() == 3
            && self.uses < Self::REUSE
            && self.orders.iter().zip(counts).all(|(o, n)| o.len() == n);
        let orders = std::mem::take(&mut self.orders);
        let [o0, o1, o2]: [Vec<u32>; 3] = match fits {
            true => orders.try_into().unwrap_or_default(),
            false => Default::default(),
        };
        let tree = |k: usize, order: Vec<u32>| match fits {
            true => Bvh::from_order(order, boxes[k]),
            false => Bvh::new(
                (0..counts[k] as u32)
                    .into_par_iter()
                    .with_min_len(1024)
                    .map(boxes[k])
                    .collect(),
            ),
        };
        let (a, (b, c)) = rayon::join(
            || tree(0, o0),
            || rayon::join(|| tree(1, o1), || tree(2, o2)),
        );
        self.uses = if fits { self.uses + 1 } else { 1 };
        self.orders = vec![a.order.clone(), b.order.clone(), c.order.clone()];
        [a, b, c]
    }
}

/// A node of a traversal: its index, and its primitives' range in the leaf order.
#[derive(Clone, Copy, Debug)]
struct At {
    node: u32,
    start: u32,
    len: u32,
}

/// The hierarchy (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Primitive indices in leaf order.
    order: Vec<u32>,
    /// The primitives' boxes, in leaf order.
    prims: Vec<MovingBox>,
    /// Each node's box, nodes in pre-order (a node's left child follows it).
    nodes: Vec<MovingBox>,
    /// Each node's right child.
    right: Vec<u32>,
    /// Marked primitives (leaf order) and subtrees holding one, when the tree is marked.
    marks: Option<(Vec<bool>, Vec<bool>)>,
    /// The primitives' vertices in leaf order (a vertex or an edge repeats its last one), when
    /// set ([`Bvh::set_vertices`]): pairs of primitives that share one are not reported.
    vertices: Vec<[u32; 3]>,
}

impl Bvh {
    /// The hierarchy of the given primitive boxes (primitive `i` is `boxes[i]`).
    pub fn new(boxes: Vec<MovingBox>) -> Bvh {
        let centres: Vec<Vec3> = boxes
            .par_iter()
            .with_min_len(1024)
            .map(|b| 0.5 * (b.lo + b.hi) + 0.25 * (b.dlo + b.dhi))
            .collect();
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        split(&mut order, &centres);
        Bvh::with_order(order, &boxes)
    }

    /// The hierarchy of the given primitive boxes grown on `order` (a permutation of the
    /// primitives: the leaf order of an earlier tree of the same primitives).
    pub fn with_order(order: Vec<u32>, boxes: &[MovingBox]) -> Bvh {
        Bvh::from_order(order, |i| boxes[i as usize])
    }

    /// [`Bvh::with_order`] with primitive `i`'s box `boxes(i)`, computed in leaf order.
    pub fn from_order(order: Vec<u32>, boxes: impl Fn(u32) -> MovingBox + Sync) -> Bvh {
        let prims: Vec<MovingBox> = order
            .par_iter()
            .with_min_len(1024)
            .map(|&i| boxes(i))
            .collect();
        let mut t = Bvh {
            order,
            prims,
            ..Bvh::default()
        };
        t.nodes.reserve(2 * t.prims.len() / LEAF + 1);
        if !t.prims.is_empty() {
            t.grow(0, t.prims.len() as u32);
        }
        t
    }

    /// The same hierarchy (same order and nodes) over new boxes of the same primitives.
    pub fn refit(&self, boxes: impl Fn(u32) -> MovingBox + Sync) -> Bvh {
        Bvh {
            vertices: self.vertices.clone(),
            ..Bvh::from_order(self.order.clone(), boxes)
        }
    }

    /// Sets the vertices of each primitive (`of(i)` for primitive `i`; a vertex `[v, v, v]`, an
    /// edge `[a, b, b]`): the traversals then leave out the pairs that share a vertex, before
    /// the box test and `keep`. Read in leaf order, next to the boxes, this costs less than
    /// looking the primitives up in the mesh for each pair.
    pub fn set_vertices(&mut self, of: impl Fn(u32) -> [u32; 3] + Sync) {
        self.vertices = self
            .order
            .par_iter()
            .with_min_len(1024)
            .map(|&i| of(i))
            .collect();
    }

    /// Marks the primitives for which `marked` is true: the traversals then report only the
    /// pairs with a marked primitive.
    pub fn mark(&mut self, marked: impl Fn(u32) -> bool + Sync) {
        let prims: Vec<bool> = self.order.par_iter().map(|&i| marked(i)).collect();
        let mut nodes = vec![false; self.nodes.len()];
        if !prims.is_empty() {
            self.mark_nodes(&prims, &mut nodes, self.root());
        }
        self.marks = Some((prims, nodes));
    }

    fn mark_nodes(&self, prims: &[bool], nodes: &mut [bool], at: At) -> bool {
        let m = match self.children(at) {
            None => prims[at.start as usize..(at.start + at.len) as usize]
                .iter()
                .any(|&m| m),
            Some((l, r)) => {
                let a = self.mark_nodes(prims, nodes, l);
                self.mark_nodes(prims, nodes, r) | a
            }
        };
        nodes[at.node as usize] = m;
        m
    }

    /// Appends the nodes of the primitives `start..start + len` in pre-order; returns the
    /// subtree's root.
    fn grow(&mut self, start: u32, len: u32) -> u32 {
        let k = self.nodes.len() as u32;
        self.nodes.push(MovingBox::EMPTY);
        self.right.push(0);
        let b = if len as usize <= LEAF {
            let leaf = &self.prims[start as usize..(start + len) as usize];
            leaf.iter().fold(MovingBox::EMPTY, |b, p| b.union(p))
        } else {
            let half = len / 2;
            self.grow(start, half);
            let r = self.grow(start + half, len - half);
            self.right[k as usize] = r;
            self.nodes[k as usize + 1].union(&self.nodes[r as usize])
        };
        self.nodes[k as usize] = b;
        k
    }

    fn root(&self) -> At {
        At {
            node: 0,
            start: 0,
            len: self.prims.len() as u32,
        }
    }

    fn children(&self, at: At) -> Option<(At, At)> {
        if at.len as usize <= LEAF {
            return None;
        }
        let half = at.len / 2;
        let l = At {
            node: at.node + 1,
            start: at.start,
            len: half,
        };
        let r = At {
            node: self.right[at.node as usize],
            start: at.start + half,
            len: at.len - half,
        };
        Some((l, r))
    }

    fn is_marked(&self) -> bool {
        self.marks.is_some()
    }

    fn node_marked(&self, at: At) -> bool {
        self.marks
            .as_ref()
            .is_some_and(|(_, n)| n[at.node as usize])
    }

    fn prim_marked(&self, i: usize) -> bool {
        self.marks.as_ref().is_some_and(|(p, _)| p[i])
    }

    /// The pairs `(i, j)` of primitives of this tree whose moving boxes meet, `i < j` by
    /// primitive index, for which `keep(i, j)` is true (asked only of pairs whose boxes meet),
    /// sorted (with marks: only pairs with a marked primitive; with vertices set, only pairs
    /// that share none).
    pub fn self_pairs<K: Fn(u32, u32) -> bool + Sync>(&self, keep: &K) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        if !self.prims.is_empty() {
            self.within(self.root(), keep, &mut out);
        }
        sort_pairs(&mut out);
        out
    }

    /// The pairs `(i, j)`, `i` of this tree's primitives and `j` of `other`'s, whose moving
    /// boxes meet and for which `keep(i, j)` is true (asked only of pairs whose boxes meet),
    /// sorted (with marks on either tree: only pairs with a marked primitive; with vertices set
    /// on both, only pairs that share none).
    pub fn pairs_with<K: Fn(u32, u32) -> bool + Sync>(
        &self,
        other: &Bvh,
        keep: &K,
    ) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        if !self.prims.is_empty() && !other.prims.is_empty() {
            let both = Both { a: self, b: other };
            both.between(self.root(), other.root(), keep, &mut out);
        }
        sort_pairs(&mut out);
        out
    }

    /// The pairs within the subtree `at`.
    fn within<K: Fn(u32, u32) -> bool + Sync>(&self, at: At, keep: &K, out: &mut Vec<(u32, u32)>) {
        if self.is_marked() && !self.node_marked(at) {
            return;
        }
        let both = Both { a: self, b: self };
        let Some((l, r)) = self.children(at) else {
            let s = at.start as usize;
            for i in s..s + at.len as usize {
                for j in i + 1..s + at.len as usize {
                    both.leaf(i, j, keep, out);
                }
            }
            return;
        };
        if at.len > PARALLEL {
            let (mut a, (b, c)) = rayon::join(
                || collect(|o| self.within(l, keep, o)),
                || {
                    rayon::join(
                        || collect(|o| self.within(r, keep, o)),
                        || collect(|o| both.between(l, r, keep, o)),
                    )
                },
            );
            a.extend(b);
            a.extend(c);
            out.extend(a);
        } else {
            self.within(l, keep, out);
            self.within(r, keep, out);
            both.between(l, r, keep, out);
        }
    }
}

/// Two trees (or one twice) traversed together.
#[derive(Clone, Copy)]
struct Both<'a> {
    a: &'a Bvh,
    b: &'a Bvh,
}

impl Both<'_> {
    /// The pair of leaf positions `i` (in `a`) and `j` (in `b`), by primitive index (the
    /// smaller first when both are of one tree).
    fn leaf<K: Fn(u32, u32) -> bool + Sync>(
        self,
        i: usize,
        j: usize,
        keep: &K,
        out: &mut Vec<(u32, u32)>,
    ) {
        let (a, b) = (self.a, self.b);
        if (a.is_marked() || b.is_marked()) && !(a.prim_marked(i) || b.prim_marked(j)) {
            return;
        }
        if !a.vertices.is_empty() && !b.vertices.is_empty() {
            let (u, w) = (a.vertices[i], b.vertices[j]);
            if u.iter().any(|k| w.contains(k)) {
                return;
            }
        }
        let (p, q) = (a.order[i], b.order[j]);
        let (p, q) = if std::ptr::eq(a, b) {
            (p.min(q), p.max(q))
        } else {
            (p, q)
        };
        // `keep` after the box test: it may be a geometric test dearer than the box
        // ([`super::broad_phase::SweptBoxes::close`])
        if a.prims[i].meets(&b.prims[j]) && keep(p, q) {
            out.push((p, q));
        }
    }

    /// The pairs of a primitive under `x` (in `a`) and one under `y` (in `b`).
    fn between<K: Fn(u32, u32) -> bool + Sync>(
        self,
        x: At,
        y: At,
        keep: &K,
        out: &mut Vec<(u32, u32)>,
    ) {
        let (a, b) = (self.a, self.b);
        if (a.is_marked() || b.is_marked()) && !(a.node_marked(x) || b.node_marked(y)) {
            return;
        }
        if !a.nodes[x.node as usize].may_meet(&b.nodes[y.node as usize]) {
            return;
        }
        let (cx, cy) = (a.children(x), b.children(y));
        // split the larger subtree (the one that is not a leaf)
        let split_x = match (cx, cy) {
            (None, None) => {
                // first each primitive against the other leaf's box
                let near = |t: &Bvh, at: At, other: &MovingBox| {
                    let mut m = [0usize; LEAF];
                    let mut k = 0;
                    for i in at.start as usize..(at.start + at.len) as usize {
                        if t.prims[i].may_meet(other) {
                            m[k] = i;
                            k += 1;
                        }
                    }
                    (m, k)
                };
                let (xs, nx) = near(a, x, &b.nodes[y.node as usize]);
                if nx == 0 {
                    return;
                }
                let (ys, ny) = near(b, y, &a.nodes[x.node as usize]);
                for &i in &xs[..nx] {
                    for &j in &ys[..ny] {
                        self.leaf(i, j, keep, out);
                    }
                }
                return;
            }
            (Some(_), None) => true,
            (None, Some(_)) => false,
            (Some(_), Some(_)) => x.len >= y.len,
        };
        let ((p, q), (u, v)) = if split_x {
            let (l, r) = cx.unwrap_or((x, x));
            ((l, y), (r, y))
        } else {
            let (l, r) = cy.unwrap_or((y, y));
            ((x, l), (x, r))
        };
        if x.len + y.len > PARALLEL {
            let (mut s, t) = rayon::join(
                || collect(|o| self.between(p, q, keep, o)),
                || collect(|o| self.between(u, v, keep, o)),
            );
            s.extend(t);
            out.extend(s);
        } else {
            self.between(p, q, keep, out);
            self.between(u, v, keep, out);
        }
    }
}

fn collect(f: impl FnOnce(&mut Vec<(u32, u32)>)) -> Vec<(u32, u32)> {
    let mut v = Vec::new();
    f(&mut v);
    v
}

/// Orders `order` by median splits of `centres` along the longest axis of each range's centres,
/// halving down to [`LEAF`] (the same halving as [`Bvh::grow`]).
fn split(order: &mut [u32], centres: &[Vec3]) {
    if order.len() <= LEAF {
        return;
    }
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &i in order.iter() {
        let c = centres[i as usize];
        if c.is_finite() {
            lo = lo.min(c);
            hi = hi.max(c);
        }
    }
    let e = hi - lo;
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let key = |i: u32| centres[i as usize].to_array()[axis];
    let half = order.len() / 2;
    order.select_nth_unstable_by(half, |&a, &b| key(a).total_cmp(&key(b)).then(a.cmp(&b)));
    let (l, r) = order.split_at_mut(half);
    if l.len() + r.len() > PARALLEL as usize {
        rayon::join(|| split(l, centres), || split(r, centres));
    } else {
        split(l, centres);
        split(r, centres);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn vec3() -> impl Strategy<Value = Vec3> {
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    /// Segments moving linearly: start and end positions of their two vertices.
    fn segments() -> impl Strategy<Value = Vec<[Vec3; 4]>> {
        prop::collection::vec(
            (vec3(), vec3(), vec3(), vec3(), 0.0..0.6f64, 0.0..1.0f64).prop_map(
                |(a, e, d, w, len, speed)| {
                    let b = a + e * 0.3 * len;
                    [a, b, a + d * speed, b + d * speed + w * 0.1 * speed]
                },
            ),
            1..60,
        )
    }

    fn boxes_of(segs: &[[Vec3; 4]], r: f64) -> Vec<MovingBox> {
        segs.iter()
            .map(|s| MovingBox::of(&[0, 1], &s[..2], &s[2..], r))
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// The traversals list exactly the pairs whose boxes meet (brute force over all pairs),
        /// whatever the marks; a refit over the same boxes lists the same.
        #[test]
        fn traversals_match_brute_force(
            segs in segments(), others in segments(), r in 0.0..0.05f64,
            marks in prop::collection::vec(any::<bool>(), 60),
        ) {
            let (a, b) = (boxes_of(&segs, r), boxes_of(&others, r));
            let (ta, tb) = (Bvh::new(a.clone()), Bvh::new(b.clone()));
            let odd = |i: u32, j: u32| !(i + j).is_multiple_of(3);
            let mut want = Vec::new();
            for i in 0..a.len() {
                for j in i + 1..a.len() {
                    if a[i].meets(&a[j]) && odd(i as u32, j as u32) {
                        want.push((i as u32, j as u32));
                    }
                }
            }
            prop_assert_eq!(ta.self_pairs(&odd), want.clone());
            prop_assert_eq!(ta.refit(|i| a[i as usize]).self_pairs(&odd), want.clone());
            let mut between = Vec::new();
            for i in 0..a.len() {
                for j in 0..b.len() {
                    if a[i].meets(&b[j]) && odd(i as u32, j as u32) {
                        between.push((i as u32, j as u32));
                    }
                }
            }
            prop_assert_eq!(ta.pairs_with(&tb, &odd), between.clone());
            // marks: only pairs with a marked primitive
            let mut marked = ta.clone();
            marked.mark(|i| marks[i as usize]);
            let on = |i: u32| marks[i as usize];
            let want_marked: Vec<_> = want.iter().copied().filter(|&(i, j)| on(i) || on(j)).collect();
            prop_assert_eq!(marked.self_pairs(&odd), want_marked);
            // (the other tree unmarked: its primitives count as unmarked)
            let between_marked: Vec<_> = between.iter().copied().filter(|&(i, _)| on(i)).collect();
            prop_assert_eq!(marked.pairs_with(&tb, &odd), between_marked);
            // vertices: pairs that share one are left out (ids from a few, so that many share),
            // on a refit too
            let ids = |i: u32, k: u32| [(i * 7 + k) % 11, (i * 3 + 2 * k) % 13, (i + k) % 5];
            let share = |u: [u32; 3], w: [u32; 3]| u.iter().any(|x| w.contains(x));
            let (mut va, mut vb) = (ta.clone(), tb.clone());
            va.set_vertices(|i| ids(i, 0));
            vb.set_vertices(|j| ids(j, 1));
            let apart = |i: u32, j: u32, k: u32| !share(ids(i, 0), ids(j, k));
            let want_apart: Vec<_> = want.iter().copied().filter(|&(i, j)| apart(i, j, 0)).collect();
            prop_assert_eq!(va.self_pairs(&odd), want_apart.clone());
            prop_assert_eq!(va.refit(|i| a[i as usize]).self_pairs(&odd), want_apart);
            let between_apart: Vec<_> =
                between.iter().copied().filter(|&(i, j)| apart(i, j, 1)).collect();
            prop_assert_eq!(va.pairs_with(&vb, &odd), between_apart);
        }

        /// Conservative: two segments whose points come within `2r` of each other on every axis
        /// at some time of the step (their boxes at that time, inflated by `r`, overlap) meet.
        #[test]
        fn segments_that_come_close_meet(
            segs in segments(), r in 0.0..0.05f64, ts in prop::collection::vec(0.0..=1.0f64, 8),
        ) {
            let boxes = boxes_of(&segs, r);
            for i in 0..segs.len() {
                for j in 0..segs.len() {
                    for &t in ts.iter().chain(&[0.0, 1.0]) {
                        let at = |s: &[Vec3; 4]| {
                            let (p, q) = (s[0].lerp(s[2], t), s[1].lerp(s[3], t));
                            (p.min(q) - Vec3::splat(r), p.max(q) + Vec3::splat(r))
                        };
                        let ((alo, ahi), (blo, bhi)) = (at(&segs[i]), at(&segs[j]));
                        if alo.cmple(bhi).all() && blo.cmple(ahi).all() {
                            prop_assert!(boxes[i].meets(&boxes[j]), "{i} {j} at {t}");
                            prop_assert!(boxes[i].may_meet(&boxes[j]));
                        }
                    }
                }
            }
        }
    }

    /// [`MovingBox::may_meet`] axis by axis, as the sign of `p + t q` over `t ∈ [0, 1]`
    /// reads (the form it had before it tested the three axes at once).
    fn may_meet_by_axis(a: &MovingBox, b: &MovingBox) -> bool {
        let axis = |k: usize| {
            let (q_lo, q_hi) = (a.dlo[k] - b.dhi[k], a.dhi[k] - b.dlo[k]);
            let low = a.lo[k] - b.hi[k] + if q_lo < 0.0 { q_lo } else { 0.0 };
            let high = a.hi[k] - b.lo[k] + if q_hi > 0.0 { q_hi } else { 0.0 };
            low <= 0.0 && high >= 0.0
        };
        axis(0) && axis(1) && axis(2)
    }

    /// A coordinate: mostly ordinary, often a signed zero, a repeated value, an infinity or NaN
    /// (so that boxes touch and meet the special cases).
    fn coordinate() -> impl Strategy<Value = f64> {
        prop_oneof![
            3 => -1.0..1.0f64,
            1 => prop::sample::select(vec![0.0, -0.0, 0.5, f64::INFINITY, f64::NEG_INFINITY, f64::NAN]),
        ]
    }

    fn any_box() -> impl Strategy<Value = MovingBox> {
        let v =
            || (coordinate(), coordinate(), coordinate()).prop_map(|(x, y, z)| Vec3::new(x, y, z));
        prop_oneof![
            8 => (v(), v(), v(), v()).prop_map(|(lo, hi, dlo, dhi)| MovingBox { lo, hi, dlo, dhi }),
            1 => Just(MovingBox::EMPTY),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4096))]

        /// The three-axes-at-once test gives the per-axis definition's answer, signed zeros,
        /// infinities, NaN and empty boxes included.
        #[test]
        fn the_box_test_is_its_per_axis_definition(a in any_box(), b in any_box()) {
            prop_assert_eq!(a.may_meet(&b), may_meet_by_axis(&a, &b));
            // and on touching boxes, where a rounding or a sign of zero would tell
            let touching = MovingBox { lo: a.hi, ..b };
            prop_assert_eq!(a.may_meet(&touching), may_meet_by_axis(&a, &touching));
        }
    }

    proptest! {
        /// One pass for the moving box and the end box gives the two separate boxes' bits,
        /// non-finite coordinates included.
        #[test]
        fn the_moving_and_end_boxes_of_one_pass_are_the_separate_ones(
            x0 in prop::collection::vec(vec3(), 3), x1 in prop::collection::vec(vec3(), 3),
            len in 0usize..=3, bad in 0usize..8, r in 0.0..0.1f64, r_end in 0.0..0.1f64,
        ) {
            let (mut x0, mut x1) = (x0, x1);
            // a non-finite start or end coordinate on some cases
            match bad {
                0 => x0[0].x = f64::NAN,
                1 => x1[1].y = f64::INFINITY,
                2 => x0[2].z = f64::NEG_INFINITY,
                _ => {}
            }
            let ids = [0u32, 1, 2];
            let ids = &ids[..len];
            let bits = |b: &MovingBox| [b.lo, b.hi, b.dlo, b.dhi].map(|v| v.to_array().map(f64::to_bits));
            let [m, e] = MovingBox::of_and_end(ids, &x0, &x1, r, r_end);
            prop_assert_eq!(bits(&m), bits(&MovingBox::of(ids, &x0, &x1, r)));
            prop_assert_eq!(bits(&e), bits(&MovingBox::of(ids, &x1, &x1, r_end)));
        }
    }

    #[test]
    fn a_shared_motion_does_not_make_boxes_meet_and_empty_boxes_meet_nothing() {
        // two unit-spaced points carried 10 along x together: their swept boxes overlap, their
        // moving boxes never meet
        let x0 = [Vec3::ZERO, Vec3::X];
        let x1 = [Vec3::new(10.0, 0.0, 0.0), Vec3::new(11.0, 0.0, 0.0)];
        let (a, b) = (
            MovingBox::of(&[0], &x0, &x1, 0.1),
            MovingBox::of(&[1], &x0, &x1, 0.1),
        );
        assert!(!a.meets(&b) && !a.may_meet(&b));
        // head-on, they meet halfway
        let x1 = [Vec3::X, Vec3::ZERO];
        let (a, b) = (
            MovingBox::of(&[0], &x0, &x1, 0.0),
            MovingBox::of(&[1], &x0, &x1, 0.0),
        );
        assert!(a.meets(&b));
        // crossing on different axes at different times: each axis overlaps at some time, but
        // never both at once
        let x0 = [Vec3::ZERO, Vec3::new(-0.5, -1.5, 0.0)];
        let x1 = [Vec3::ZERO, Vec3::new(1.5, 0.5, 0.0)];
        let (a, b) = (
            MovingBox::of(&[0], &x0, &x1, 0.0),
            MovingBox::of(&[1], &x0, &x1, 0.0),
        );
        assert!(a.may_meet(&b) && !a.meets(&b));
        let nan = [Vec3::new(f64::NAN, 0.0, 0.0)];
        let e = MovingBox::of(&[0], &nan, &nan, 1.0);
        assert_eq!(e, MovingBox::EMPTY);
        assert!(!e.meets(&e) && !e.meets(&a) && !a.meets(&e));
        let t = Bvh::new(vec![e, a, e, b, e, e, a]);
        assert_eq!(t.self_pairs(&|_, _| true), vec![(1, 6)]);
        assert!(Bvh::new(Vec::new()).self_pairs(&|_, _| true).is_empty());
    }
}
