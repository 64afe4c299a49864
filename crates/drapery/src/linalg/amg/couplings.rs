//! The couplings outside the hierarchy's pattern, on every level the cycle smooths
//! (docs/MATH.md §12).
//!
//! PCG's matrix is `A = P + C` ([`crate::linalg::split`]): the hierarchy is built from `P`,
//! which holds a block-diagonal majorant of the few couplings `C` outside its pattern (a step's
//! cloth–cloth contacts), so `P ≥ A`. A cycle of `P` alone treats two layers pressed together
//! as stiff where they move together, and PCG needs many more iterations where there are many
//! contacts. So the cycle's products (its residuals and smoothing sweeps) add the couplings:
//! on the finest level `Ĉ_0 = S C S` (filtered as the level's matrix is), on level `l + 1`
//! the Galerkin product `Ĉ_{l+1} = P_lᵀ Ĉ_l P_l`, each on its own small set of rows.
//!
//! Every level's products are then those of its true Galerkin operator `A_l = P̂_l + Ĉ_l`; its
//! smoother keeps the block diagonal and damping of the majorant `P̂_l ≥ A_l`, so
//! `ω ρ(D⁻¹A_l) ≤ ω ρ(D⁻¹P̂_l)`, and each coarse correction uses a matrix no softer than the
//! Galerkin product of the level above. Each level's cycle is then still a convergent
//! iteration, and the cycle a symmetric positive definite operator. The coarsest level keeps
//! its factor of `P̂`.

use super::Transfer;
use crate::linalg::block::add_products;
use crate::linalg::split::Coupling;
use crate::math::{Mat3, Vec3};

/// Block rows of one level's couplings: `rows[k]` holds the blocks `val[ptr[k]..ptr[k + 1]]`
/// in the columns `col[..]`, rows and columns ascending.
#[derive(Clone, Debug, Default)]
pub(super) struct Rows {
    rows: Vec<u32>,
    ptr: Vec<u32>,
    col: Vec<u32>,
    val: Vec<Mat3>,
}

impl Rows {
    /// The finest level's `S C S` of the rows of `c`.
    pub fn fine(c: &Coupling, s: &[Mat3]) -> Rows {
        let m = c.matrix();
        let mut out = Rows {
            ptr: vec![0],
            ..Rows::default()
        };
        for &i in c.rows() {
            let (cols, r) = m.row(i as usize);
            let si = s[i as usize];
            for (&j, b) in cols.iter().zip(&m.values[r]) {
                out.col.push(j);
                out.val.push(si * *b * s[j as usize]);
            }
            out.rows.push(i);
            out.ptr.push(out.col.len() as u32);
        }
        out
    }

    /// `Pᵀ Ĉ P` for the transfer `t` to a level of `coarse` rows. Sequential, each sum in a
    /// fixed order: the same bits on any number of threads.
    pub fn galerkin(&self, t: &Transfer, coarse: usize) -> Rows {
        let mut acc = Accumulator::new(coarse);
        let p_row = |i: u32| {
            let r = t.p_ptr[i as usize] as usize..t.p_ptr[i as usize + 1] as usize;
            t.p_col[r.clone()].iter().zip(&t.p[r])
        };
        // `Ĉ P`, by fine row
        let mut cp = Rows {
            ptr: vec![0],
            ..Rows::default()
        };
        for (k, &i) in self.rows.iter().enumerate() {
            let e = self.ptr[k] as usize..self.ptr[k + 1] as usize;
            for (&j, c) in self.col[e.clone()].iter().zip(&self.val[e]) {
                for (&b, p) in p_row(j) {
                    acc.add(b, *c * *p);
                }
            }
            acc.drain_into(&mut cp.col, &mut cp.val);
            cp.rows.push(i);
            cp.ptr.push(cp.col.len() as u32);
        }
        // `Pᵀ (Ĉ P)`: each coarse row sums `P_iaᵀ (Ĉ P)_i` over its fine rows, in their order
        let mut feeds: Vec<(u32, u32, Mat3)> = Vec::new();
        for (k, &i) in cp.rows.iter().enumerate() {
            for (&a, p) in p_row(i) {
                feeds.push((a, k as u32, p.transpose()));
            }
        }
        feeds.sort_by_key(|&(a, k, _)| (a, k));
        let mut out = Rows {
            ptr: vec![0],
            ..Rows::default()
        };
        let mut start = 0;
        while start < feeds.len() {
            let a = feeds[start].0;
            let mut end = start;
            while end < feeds.len() && feeds[end].0 == a {
                let (_, k, pt) = feeds[end];
                let e = cp.ptr[k as usize] as usize..cp.ptr[k as usize + 1] as usize;
                for (&b, m) in cp.col[e.clone()].iter().zip(&cp.val[e]) {
                    acc.add(b, pt * *m);
                }
                end += 1;
            }
            acc.drain_into(&mut out.col, &mut out.val);
            out.rows.push(a);
            out.ptr.push(out.col.len() as u32);
            start = end;
        }
        out
    }

    /// A dense copy, `3n × 3n` (for tests).
    #[cfg(test)]
    pub fn to_dense(&self, n: usize) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; 3 * n]; 3 * n];
        for (k, &i) in self.rows.iter().enumerate() {
            let e = self.ptr[k] as usize..self.ptr[k + 1] as usize;
            for (&j, m) in self.col[e.clone()].iter().zip(&self.val[e]) {
                for a in 0..3 {
                    for b in 0..3 {
                        d[3 * i as usize + a][3 * j as usize + b] = m.col(b)[a];
                    }
                }
            }
        }
        d
    }

    /// Row `k` (of `rows`) of `Ĉ x`.
    #[inline]
    fn row_product(&self, k: usize, x: &[Vec3]) -> Vec3 {
        let e = self.ptr[k] as usize..self.ptr[k + 1] as usize;
        add_products(Vec3::ZERO, &self.val[e.clone()], &self.col[e], x)
    }

    /// `w -= Ĉ x` on the rows.
    pub fn subtract_product(&self, x: &[Vec3], w: &mut [Vec3]) {
        for (k, &i) in self.rows.iter().enumerate() {
            w[i as usize] -= self.row_product(k, x);
        }
    }

    /// Completes a damped Jacobi sweep `x = x₀ + ω D⁻¹ (b − P̂ x₀)` into one of `P̂ + Ĉ`:
    /// `x -= ω D⁻¹ Ĉ x₀` on the rows.
    pub fn sweep_correction(&self, x0: &[Vec3], x: &mut [Vec3], dinv: &[Mat3], omega: f64) {
        for (k, &i) in self.rows.iter().enumerate() {
            let i = i as usize;
            x[i] -= omega * (dinv[i] * self.row_product(k, x0));
        }
    }
}

/// A sparse accumulator of 3×3 blocks by column: sums in the order they are added.
struct Accumulator {
    sum: Vec<Mat3>,
    seen: Vec<bool>,
    touched: Vec<u32>,
}

impl Accumulator {
    fn new(n: usize) -> Accumulator {
        Accumulator {
            sum: vec![Mat3::ZERO; n],
            seen: vec![false; n],
            touched: Vec::new(),
        }
    }

    fn add(&mut self, col: u32, m: Mat3) {
        let c = col as usize;
        if !self.seen[c] {
            self.seen[c] = true;
            self.touched.push(col);
            self.sum[c] = m;
        } else {
            self.sum[c] += m;
        }
    }

    /// Appends the sums by ascending column and clears.
    fn drain_into(&mut self, col: &mut Vec<u32>, val: &mut Vec<Mat3>) {
        self.touched.sort_unstable();
        for &c in &self.touched {
            col.push(c);
            val.push(self.sum[c as usize]);
            self.seen[c as usize] = false;
        }
        self.touched.clear();
    }
}
