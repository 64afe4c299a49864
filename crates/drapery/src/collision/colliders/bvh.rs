//! A bounding-volume hierarchy over triangles for closest-point queries: the tree (which
//! triangles each node holds) is built once from the triangles' centroids; the node boxes are
//! computed for any placement of the vertices ([`Bvh::boxes`]), so a mesh that deforms keeps
//! its tree and only recomputes boxes.

use super::super::broad_phase::Aabb;
use super::super::distance::{PointTriangle, point_triangle};
use crate::math::Vec3;

/// A node: `count > 0` for a leaf holding `order[first .. first + count]`, otherwise an inner
/// node whose children are `first` and `first + 1` (always after their parent).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Node {
    first: u32,
    count: u32,
}

/// The tree of a triangle set.
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Triangle indices in leaf order.
    order: Vec<u32>,
}

fn corners(v: &[Vec3], t: [u32; 3]) -> [Vec3; 3] {
    t.map(|i| v[i as usize])
}

impl Bvh {
    /// Splits the triangles at the median centroid along the longest axis of the centroids'
    /// box, down to leaves of at most 4 triangles.
    pub fn build(v: &[Vec3], triangles: &[[u32; 3]]) -> Bvh {
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let mut nodes = Vec::new();
        if order.is_empty() {
            return Bvh { nodes, order };
        }
        let centers: Vec<Vec3> = triangles
            .iter()
            .map(|&t| corners(v, t).iter().sum::<Vec3>() / 3.0)
            .collect();
        nodes.push(Node { first: 0, count: 0 });
        // (node index, range start, range end)
        let mut stack = vec![(0usize, 0usize, order.len())];
        while let Some((ni, lo, hi)) = stack.pop() {
            if hi - lo <= 4 {
                nodes[ni] = Node {
                    first: lo as u32,
                    count: (hi - lo) as u32,
                };
                continue;
            }
            let cb = Aabb::of_points(order[lo..hi].iter().map(|&i| centers[i as usize]));
            let ext = cb.max - cb.min;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = (lo + hi) / 2;
            order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
                centers[a as usize][axis]
                    .total_cmp(&centers[b as usize][axis])
                    .then(a.cmp(&b))
            });
            let child = nodes.len();
            nodes[ni] = Node {
                first: child as u32,
                count: 0,
            };
            nodes.push(Node { first: 0, count: 0 });
            nodes.push(Node { first: 0, count: 0 });
            stack.push((child, lo, mid));
            stack.push((child + 1, mid, hi));
        }
        Bvh { nodes, order }
    }

    /// Node boxes enclosing every triangle's corners in each of `placements` (one placement:
    /// the mesh as it is; two: a box valid for every linear blend of the two).
    pub fn boxes(&self, triangles: &[[u32; 3]], placements: &[&[Vec3]]) -> Vec<Aabb> {
        let mut boxes = vec![
            Aabb {
                min: Vec3::ZERO,
                max: Vec3::ZERO,
            };
            self.nodes.len()
        ];
        // children come after their parents: fill from the last node back
        for ni in (0..self.nodes.len()).rev() {
            let n = self.nodes[ni];
            boxes[ni] = if n.count > 0 {
                let (f, c) = (n.first as usize, n.count as usize);
                Aabb::of_points(self.order[f..f + c].iter().flat_map(|&ti| {
                    placements
                        .iter()
                        .flat_map(move |v| corners(v, triangles[ti as usize]))
                }))
            } else {
                let (l, r) = (boxes[n.first as usize], boxes[n.first as usize + 1]);
                Aabb {
                    min: l.min.min(r.min),
                    max: l.max.max(r.max),
                }
            };
        }
        boxes
    }

    /// Calls `f` with every triangle whose leaf box overlaps `query` (in leaf order), with
    /// `boxes` from [`Bvh::boxes`].
    pub fn overlapping(&self, boxes: &[Aabb], query: &Aabb, mut f: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = vec![0usize];
        while let Some(ni) = stack.pop() {
            if !boxes[ni].overlaps(query) {
                continue;
            }
            let node = self.nodes[ni];
            if node.count > 0 {
                let (first, count) = (node.first as usize, node.count as usize);
                self.order[first..first + count].iter().for_each(|&t| f(t));
            } else {
                stack.push(node.first as usize + 1);
                stack.push(node.first as usize);
            }
        }
    }

    /// The closest triangle to `p` (`(index, result)`, the lowest index among equals), with
    /// `tri(i)` the corners of triangle `i` and `boxes` from [`Bvh::boxes`] for a placement
    /// that holds every `tri(i)`.
    pub fn closest(
        &self,
        boxes: &[Aabb],
        p: Vec3,
        tri: impl Fn(u32) -> [Vec3; 3],
    ) -> Option<(u32, PointTriangle)> {
        let mut best: Option<(u32, PointTriangle)> = None;
        if self.nodes.is_empty() {
            return None;
        }
        let box_dist = |b: &Aabb| (p - p.clamp(b.min, b.max)).length();
        let mut stack = vec![0usize];
        while let Some(ni) = stack.pop() {
            let node = self.nodes[ni];
            let bd = box_dist(&boxes[ni]);
            if best.is_some_and(|(_, r)| bd > r.dist) {
                continue;
            }
            if node.count > 0 {
                let (f, c) = (node.first as usize, node.count as usize);
                for &ti in &self.order[f..f + c] {
                    let [a, b, cc] = tri(ti);
                    let r = point_triangle(p, a, b, cc);
                    let better = match best {
                        None => true,
                        Some((bi, br)) => r.dist < br.dist || (r.dist == br.dist && ti < bi),
                    };
                    if better {
                        best = Some((ti, r));
                    }
                }
            } else {
                // visit the nearer child first
                let (l, r) = (node.first as usize, node.first as usize + 1);
                let (dl, dr) = (box_dist(&boxes[l]), box_dist(&boxes[r]));
                if dl <= dr {
                    stack.push(r);
                    stack.push(l);
                } else {
                    stack.push(l);
                    stack.push(r);
                }
            }
        }
        best
    }
}
