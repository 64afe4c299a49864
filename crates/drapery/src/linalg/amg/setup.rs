//! Structure of one coarsening step: strength of connection, greedy aggregation, and the
//! patterns (with product positions) of `P`, `Pᵀ`, `T = A P` and `A_c = Pᵀ T`.
//! Sequential; it runs once per matrix pattern.

use super::{NONE, Terms, Transfer, WEAK};
use crate::linalg::bsr::BlockMatrix;
use crate::math::Mat3;

fn frobenius(m: &Mat3) -> f64 {
    m.to_cols_array().iter().map(|e| e * e).sum::<f64>().sqrt()
}

/// Per block of `a`, its strength `‖A_ij‖ / √(‖A_ii‖ ‖A_jj‖)` if at least `theta`, else 0
/// (the diagonal gets 0 too). With `theta = 0`, every non-zero off-diagonal block has strength
/// 1: the structure then depends only on the pattern and on which blocks are exactly zero
/// (the rows of pinned particles), not on the values at the time it is built.
fn strength(a: &BlockMatrix, theta: f64) -> Vec<f64> {
    let n = a.n();
    let dn: Vec<f64> = (0..n)
        .map(|i| frobenius(&a.values[a.diag_index(i)]))
        .collect();
    let mut out = vec![0.0; a.nnz_blocks()];
    for i in 0..n {
        let (cols, r) = a.row(i);
        for (k, &j) in r.zip(cols) {
            let j = j as usize;
            if j == i {
                continue;
            }
            let scale = (dn[i] * dn[j]).sqrt();
            let ratio = frobenius(&a.values[k]) / scale;
            if theta == 0.0 {
                // structural mode: every non-zero block is strong, with equal weight
                if scale > 0.0 && ratio > 0.0 && ratio.is_finite() {
                    out[k] = 1.0;
                }
            } else if scale > 0.0 && ratio >= theta && ratio.is_finite() {
                out[k] = ratio;
            }
        }
    }
    out
}

/// Greedy aggregation (Vaněk, Mandel & Brezina 1996): roots whose strong neighbours are all
/// free take them; the rest join the aggregate of their strongest aggregated neighbour;
/// leftovers form new aggregates. Particles with no strong neighbour stay out ([`NONE`]).
/// Returns the aggregate of each particle and the number of aggregates.
fn aggregate(a: &BlockMatrix, strong: &[f64]) -> (Vec<u32>, usize) {
    let n = a.n();
    let neighbours = |i: usize| {
        let (cols, r) = a.row(i);
        cols.iter()
            .zip(r)
            .filter(|&(_, k)| strong[k] > 0.0)
            .map(|(&j, k)| (j as usize, strong[k]))
    };
    let mut agg = vec![NONE; n];
    let mut count = 0u32;
    for i in 0..n {
        if agg[i] != NONE || neighbours(i).next().is_none() {
            continue;
        }
        if neighbours(i).all(|(j, _)| agg[j] == NONE) {
            agg[i] = count;
            for (j, _) in neighbours(i) {
                agg[j] = count;
            }
            count += 1;
        }
    }
    let first = agg.clone();
    for (i, g) in agg.iter_mut().enumerate() {
        if *g != NONE {
            continue;
        }
        let best = neighbours(i).filter(|&(j, _)| first[j] != NONE).fold(
            None,
            |b: Option<(usize, f64)>, (j, s)| match b {
                Some((_, bs)) if bs >= s => b,
                _ => Some((j, s)),
            },
        );
        if let Some((j, _)) = best {
            *g = first[j];
        }
    }
    for i in 0..n {
        if agg[i] != NONE || neighbours(i).next().is_none() {
            continue;
        }
        agg[i] = count;
        for (j, _) in neighbours(i) {
            if agg[j] == NONE {
                agg[j] = count;
            }
        }
        count += 1;
    }
    (agg, count as usize)
}

/// Builds the structure of the step from `a` (its values decide strength), or `None` when
/// it would not coarsen (no aggregate, or fewer than 10 % fewer rows). The coarse matrix
/// comes back with its pattern and zero values.
pub(super) fn transfer(a: &BlockMatrix, theta: f64) -> Option<(Transfer, BlockMatrix)> {
    let n = a.n();
    let strong = strength(a, theta);
    let (agg, nc) = aggregate(a, &strong);
    if nc == 0 || nc * 10 > n * 9 {
        return None;
    }
    let mut t = Transfer {
        agg,
        ..Default::default()
    };
    // P: row i has the aggregates of i and of its strong neighbours.
    t.p_ptr.push(0);
    t.a_slot = vec![WEAK; a.nnz_blocks()];
    t.p_own = vec![NONE; n];
    let mut row: Vec<u32> = Vec::new();
    for i in 0..n {
        let (cols, r) = a.row(i);
        row.clear();
        for (&j, k) in cols.iter().zip(r.clone()) {
            let g = t.agg[j as usize];
            if (j as usize == i || strong[k] > 0.0) && g != NONE {
                row.push(g);
            }
        }
        row.sort_unstable();
        row.dedup();
        let base = t.p_col.len() as u32;
        for (&j, k) in cols.iter().zip(r) {
            let g = t.agg[j as usize];
            if j as usize == i {
                // the diagonal of A^F always feeds the row's own aggregate (if any)
                t.a_slot[k] = match row.binary_search(&g) {
                    Ok(p) if g != NONE => base + p as u32,
                    _ => NONE,
                };
            } else if strong[k] > 0.0 && g != NONE {
                t.a_slot[k] = base + row.binary_search(&g).expect("strong neighbour") as u32;
            }
        }
        if t.agg[i] != NONE {
            t.p_own[i] = base + row.binary_search(&t.agg[i]).expect("own") as u32;
        }
        t.p_col.extend_from_slice(&row);
        t.p_ptr.push(t.p_col.len() as u32);
    }
    t.p = vec![Mat3::ZERO; t.p_col.len()];
    // Pᵀ by counting sort on the column.
    let mut count = vec![0u32; nc + 1];
    for &c in &t.p_col {
        count[c as usize + 1] += 1;
    }
    for c in 0..nc {
        count[c + 1] += count[c];
    }
    t.pt_ptr = count.clone();
    t.pt_row = vec![0; t.p_col.len()];
    t.pt_src = vec![0; t.p_col.len()];
    for i in 0..n {
        for q in t.p_ptr[i]..t.p_ptr[i + 1] {
            let c = t.p_col[q as usize] as usize;
            let at = count[c] as usize;
            t.pt_row[at] = i as u32;
            t.pt_src[at] = q;
            count[c] += 1;
        }
    }
    // T = A P: row i gathers the P rows of its columns.
    let mut mark = vec![NONE; nc];
    t.t_ptr.push(0);
    let mut t_col: Vec<u32> = Vec::new();
    let (mut target, mut terms) = (Vec::new(), Vec::new());
    for i in 0..n {
        let (cols, r) = a.row(i);
        row.clear();
        for &j in cols {
            let j = j as usize;
            row.extend_from_slice(&t.p_col[t.p_ptr[j] as usize..t.p_ptr[j + 1] as usize]);
        }
        row.sort_unstable();
        row.dedup();
        let base = t_col.len() as u32;
        for (p, &c) in row.iter().enumerate() {
            mark[c as usize] = base + p as u32;
        }
        for (&j, k) in cols.iter().zip(r) {
            let j = j as usize;
            for q in t.p_ptr[j]..t.p_ptr[j + 1] {
                target.push(mark[t.p_col[q as usize] as usize]);
                terms.push([k as u32, q]);
            }
        }
        t_col.extend_from_slice(&row);
        t.t_ptr.push(t_col.len() as u32);
    }
    t.t = vec![Mat3::ZERO; t_col.len()];
    t.t_terms = Terms::by_block(t.t.len(), &target, &terms);
    // A_c = Pᵀ T: coarse row I gathers the T rows of the fine rows in column I of P.
    let mut pairs = Vec::new();
    for c in 0..nc {
        for e in t.pt_ptr[c]..t.pt_ptr[c + 1] {
            let i = t.pt_row[e as usize] as usize;
            for &j in &t_col[t.t_ptr[i] as usize..t.t_ptr[i + 1] as usize] {
                if j as usize >= c {
                    pairs.push((c as u32, j));
                }
            }
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    let coarse = BlockMatrix::from_pairs(nc, &pairs);
    t.pt = vec![Mat3::ZERO; t.pt_row.len()];
    // only the upper triangle's products (J ≥ I)
    let (mut target, mut terms) = (Vec::new(), Vec::new());
    for c in 0..nc {
        for e in t.pt_ptr[c] as usize..t.pt_ptr[c + 1] as usize {
            let i = t.pt_row[e] as usize;
            let row = t.t_ptr[i] as usize..t.t_ptr[i + 1] as usize;
            for (&j, tk) in t_col[row.clone()].iter().zip(row) {
                if (j as usize) < c {
                    continue;
                }
                let k = coarse.find(c, j as usize).expect("coarse pattern");
                target.push(k as u32);
                terms.push([e as u32, tk as u32]);
            }
        }
    }
    t.c_terms = Terms::by_block(coarse.nnz_blocks(), &target, &terms);
    for c in 0..nc {
        let (cols, r) = coarse.row(c);
        for (&j, k) in cols.iter().zip(r) {
            if (j as usize) <= c {
                let kt = coarse.find(j as usize, c).expect("symmetric pattern");
                t.c_lower.push([k as u32, kt as u32]);
            }
        }
    }
    Some((t, coarse))
}
