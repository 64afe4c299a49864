//! How much of the fail-safe's self-collision work lies inside flat patches (issue 18, the
//! lead of normal-cone culling; BENCHMARKS.md, "Thirty-first session").
//!
//! `cargo run --release -p drapery --example cone_stats -- N FILE...` restores each saved
//! `spin-N` state FILE, takes the step's motion to be `x₁ = x₀ + h v₀`, lists the cloth's
//! vertex–triangle and edge–edge pairs whose moving boxes meet with the thickness as margin
//! (what the fail-safe's traversal lists, [`candidates`]), and asks of each pair whether both
//! its primitives lie in one node of a triangle hierarchy whose normals stay within a cone of
//! half-angle under 90° over the whole step. Such a node cannot collide with itself unless its
//! boundary, projected along the cone's axis, crosses itself (Volino & Magnenat-Thalmann's
//! condition): culling there would skip the pair. So the share printed is an upper bound of
//! what normal-cone culling could save, before any contour test.
//!
//! The hierarchy: the triangles ordered by median splits of their centroids along the longest
//! axis, halved down to leaves of at most 8, as the fail-safe's trees are. A triangle's normals
//! over the step, `n(t) = (1−t)² n₀ + 2t(1−t) n_m + t² n₁` with `n_m = ½(e₁(0)×e₂(1) +
//! e₁(1)×e₂(0))` (the cross product of its linearly moving edges, in Bernstein form), are in the
//! cone spanned by `n₀`, `n_m` and `n₁`; a node is flat when one axis (the normalized sum of
//! its unit vectors) makes an acute angle with every one of them (a cosine above `CONE_COS`
//! from the environment, default 1e-9, when set). A vertex or an edge belongs to its first
//! incident triangle.

mod common;

use drapery::Vec3;
use drapery::collision::broad_phase::candidates;

/// Leaves of at most this many triangles.
const LEAF: usize = 8;

/// Orders `order` (triangle indices) by median splits of `c` along the longest axis.
fn split(order: &mut [u32], c: &[Vec3]) {
    if order.len() <= LEAF {
        return;
    }
    let (lo, hi) = order.iter().fold(
        (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &t| (lo.min(c[t as usize]), hi.max(c[t as usize])),
    );
    let e = hi - lo;
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let half = order.len() / 2;
    order.select_nth_unstable_by(half, |&a, &b| {
        c[a as usize][axis].total_cmp(&c[b as usize][axis])
    });
    let (l, r) = order.split_at_mut(half);
    split(l, c);
    split(r, c);
}

/// Per node, keyed by `(start, len)` in `out`: whether it is flat (every normal within `cos`
/// of the axis) and its axis. Returns the node's sum of unit normals.
fn flat_nodes(
    start: usize,
    len: usize,
    cos: f64,
    normals: &[[Vec3; 3]],
    out: &mut std::collections::HashMap<(usize, usize), (bool, Vec3)>,
) -> Vec3 {
    let sum = if len <= LEAF {
        normals[start..start + len]
            .iter()
            .flatten()
            .fold(Vec3::ZERO, |s, n| s + *n)
    } else {
        let half = len / 2;
        flat_nodes(start, half, cos, normals, out)
            + flat_nodes(start + half, len - half, cos, normals, out)
    };
    let axis = sum.normalize_or_zero();
    let flat = axis != Vec3::ZERO
        && normals[start..start + len]
            .iter()
            .flatten()
            .all(|n| axis.dot(*n) > cos);
    out.insert((start, len), (flat, axis));
    sum
}

/// The smallest node holding leaf positions `a` and `b`.
fn lca(mut start: usize, mut len: usize, a: usize, b: usize) -> (usize, usize) {
    while len > LEAF {
        let half = len / 2;
        let (la, lb) = (a < start + half, b < start + half);
        if la != lb {
            break;
        }
        if la {
            len = half;
        } else {
            start += half;
            len -= half;
        }
    }
    (start, len)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).ok_or("usage: cone_stats N FILE...")?.parse()?;
    // a node is flat when every normal is within this cosine of its axis (CONE_COS; default
    // just above 0: a half-angle under 90°)
    let cos: f64 = match std::env::var("CONE_COS") {
        Ok(c) => c.parse()?,
        Err(_) => 1e-9,
    };
    println!("state pairs vt ee flat_vt flat_ee share flat_nodes_of_size(>=64,>=1024,>=16384)");
    for file in &args[2..] {
        let common::SpinMotion {
            sim,
            thickness,
            x0,
            x1,
        } = common::spin_motion(n, file)?;
        let tris = sim.model().triangles();
        let edges = sim.model().edges();
        let cand = candidates(&x0, &x1, &tris, &edges, thickness);
        // unit normals at the start, the end and the Bernstein middle
        let unit = |t: &[u32; 3]| -> [Vec3; 3] {
            let p = |x: &[Vec3], k: usize| x[t[k] as usize];
            let (a0, b0, c0) = (p(&x0, 0), p(&x0, 1), p(&x0, 2));
            let (a1, b1, c1) = (p(&x1, 0), p(&x1, 1), p(&x1, 2));
            let (e10, e20, e11, e21) = (b0 - a0, c0 - a0, b1 - a1, c1 - a1);
            let n0 = e10.cross(e20);
            let n1 = e11.cross(e21);
            let nm = 0.5 * (e10.cross(e21) + e11.cross(e20));
            [n0, nm, n1].map(|v| v.normalize_or_zero())
        };
        let centroids: Vec<Vec3> = tris
            .iter()
            .map(|t| (x0[t[0] as usize] + x0[t[1] as usize] + x0[t[2] as usize]) / 3.0)
            .collect();
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        split(&mut order, &centroids);
        let mut pos = vec![0usize; tris.len()];
        for (k, &t) in order.iter().enumerate() {
            pos[t as usize] = k;
        }
        let normals: Vec<[Vec3; 3]> = order.iter().map(|&t| unit(&tris[t as usize])).collect();
        let mut nodes = std::collections::HashMap::new();
        flat_nodes(0, tris.len(), cos, &normals, &mut nodes);
        // owners: first incident triangle of each vertex and edge
        let mut vertex_owner = vec![u32::MAX; x0.len()];
        let mut edge_owner = std::collections::HashMap::new();
        for (k, t) in tris.iter().enumerate() {
            for i in 0..3 {
                let v = t[i] as usize;
                if vertex_owner[v] == u32::MAX {
                    vertex_owner[v] = k as u32;
                }
                let (a, b) = (t[i], t[(i + 1) % 3]);
                edge_owner.entry((a.min(b), a.max(b))).or_insert(k as u32);
            }
        }
        let flat = |ta: u32, tb: u32| {
            let node = lca(0, tris.len(), pos[ta as usize], pos[tb as usize]);
            nodes.get(&node).is_some_and(|(f, _)| *f)
        };
        let flat_vt = (cand.vt.iter())
            .filter(|&&(v, t)| flat(vertex_owner[v as usize], t))
            .count();
        let owner = |e: u32| {
            let [a, b] = edges[e as usize];
            edge_owner[&(a.min(b), a.max(b))]
        };
        let flat_ee = (cand.ee.iter())
            .filter(|&&(a, b)| flat(owner(a), owner(b)))
            .count();
        let sizes = [64, 1024, 16384].map(|s| {
            nodes
                .iter()
                .filter(|((_, len), (f, _))| *f && *len >= s)
                .count()
        });
        let total = cand.vt.len() + cand.ee.len();
        println!(
            "{file} {total} {} {} {flat_vt} {flat_ee} {:.3} {sizes:?}",
            cand.vt.len(),
            cand.ee.len(),
            (flat_vt + flat_ee) as f64 / total.max(1) as f64
        );
    }
    Ok(())
}
