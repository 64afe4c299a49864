//! A system matrix kept in two parts, `A = P + C` (docs/MATH.md §11): `P` on a fixed pattern,
//! the matrix the preconditioner is built from, and `C` the blocks of a few couplings outside
//! that pattern (a step's cloth–cloth contacts), held on their own small pattern. A step with
//! contacts then needs no merged pattern: products read `P` (the multigrid's half-size copy of
//! it, in PCG) and add the few rows `C` has.
//!
//! The couplings' diagonal blocks go into `P` together with a block-diagonal majorant of their
//! off-diagonal ones ([`Coupling::move_majorant_into`]), so that `P ≥ A`: a preconditioner
//! that lacks a contact's coupling but keeps only its diagonal is stiffer than `A` where two
//! layers move together and softer where they press into each other; the majorant makes it
//! no softer anywhere.

use super::bsr::BlockMatrix;
use super::eigen::symmetric_eigen;
use crate::math::{Mat3, Vec3};
use rayon::prelude::*;

/// Rows per task in the row-parallel product.
const ROWS: usize = 256;

/// Couplings between particles outside a fixed pattern: a block matrix on the couplings' own
/// pairs, and the particles that have any (the diagonal blocks of the others stay zero: a
/// force on these pairs writes none there).
#[derive(Clone, Debug)]
pub struct Coupling {
    m: BlockMatrix,
    /// Rows with an off-diagonal block, ascending.
    rows: Vec<u32>,
}

impl Coupling {
    /// Zero couplings for `n` particles on the blocks `(i, j)` and `(j, i)` of every pair.
    pub fn new(n: usize, pairs: &[(u32, u32)]) -> Coupling {
        let m = BlockMatrix::from_pairs(n, pairs);
        let ptr = m.row_ptr();
        let rows = (0..n as u32)
            .filter(|&i| ptr[i as usize + 1] - ptr[i as usize] > 1)
            .collect();
        Coupling { m, rows }
    }

    /// The blocks, diagonal ones included.
    pub fn matrix(&self) -> &BlockMatrix {
        &self.m
    }

    /// The blocks, to assemble into.
    pub fn matrix_mut(&mut self) -> &mut BlockMatrix {
        &mut self.m
    }

    /// The particles with an off-diagonal block, ascending.
    pub fn rows(&self) -> &[u32] {
        &self.rows
    }

    /// Moves into `p`'s diagonal blocks the block-diagonal majorant `D` of these couplings,
    /// `D_ii = C_ii + Σ_{j≠i} |C_ij|` with `|M| = (M Mᵀ)^½`, and keeps `C - D`: `p + C` is
    /// unchanged, and `D - C` is positive semi-definite (each pair's
    /// `[[|C_ij|, -C_ij], [-C_ji, |C_ji|]]` is, by the singular value decomposition of
    /// `C_ij`), so the new `p` bounds the whole matrix (the old `p + C`) from above
    /// (docs/MATH.md §11). Rows in parallel, each summed in column order: the same bits on any
    /// number of threads.
    pub fn move_majorant_into(&mut self, p: &mut BlockMatrix) {
        let m = &self.m;
        let parts: Vec<(Mat3, Mat3)> = self
            .rows
            .par_iter()
            .with_min_len(64)
            .map(|&i| {
                let (cols, r) = m.row(i as usize);
                let mut sum = Mat3::ZERO;
                for (&j, k) in cols.iter().zip(r) {
                    if j != i {
                        sum += abs(&m.values[k]);
                    }
                }
                (m.values[m.diag_index(i as usize)] + sum, -sum)
            })
            .collect();
        for (&i, (to_p, kept)) in self.rows.iter().zip(parts) {
            let i = i as usize;
            let k = p.diag_index(i);
            p.values[k] += to_p;
            let k = self.m.diag_index(i);
            self.m.values[k] = kept;
        }
    }

    /// Row `i` of `C x`.
    #[inline]
    pub fn row_product(&self, i: usize, x: &[Vec3]) -> Vec3 {
        self.m.row_product(i, x)
    }
}

/// `|M| = (M Mᵀ)^½`, the symmetric positive semi-definite factor of `M`'s polar decomposition
/// `M = |M| U`.
pub fn abs(m: &Mat3) -> Mat3 {
    let g = *m * m.transpose();
    let a: [[f64; 3]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| g.col(c)[r]));
    let (lambda, q) = symmetric_eigen(&a);
    let mut out = Mat3::ZERO;
    for (k, l) in lambda.iter().enumerate() {
        let v = Vec3::new(q[0][k], q[1][k], q[2][k]);
        out += crate::math::outer(v, v) * l.max(0.0).sqrt();
    }
    out
}

/// `A = P + C`, `C` the blocks of `coupling` when there is one.
#[derive(Clone, Copy, Debug)]
pub struct Split<'a> {
    /// The matrix on the fixed pattern (the preconditioner's).
    pub p: &'a BlockMatrix,
    /// The couplings outside it.
    pub coupling: Option<&'a Coupling>,
}

impl<'a> Split<'a> {
    /// `A = p`.
    pub fn whole(p: &'a BlockMatrix) -> Split<'a> {
        Split { p, coupling: None }
    }

    /// Number of block rows.
    pub fn n(&self) -> usize {
        self.p.n()
    }

    /// Row `i` of `A x`: `P`'s row, then `C`'s.
    #[inline]
    pub fn row_product(&self, i: usize, x: &[Vec3]) -> Vec3 {
        let y = self.p.row_product(i, x);
        match self.coupling {
            Some(c) => y + c.row_product(i, x),
            None => y,
        }
    }

    /// `y = A x`, row-parallel and deterministic.
    pub fn mul_vec(&self, x: &[Vec3], y: &mut [Vec3]) {
        y.par_iter_mut()
            .enumerate()
            .with_min_len(ROWS)
            .for_each(|(i, yi)| *yi = self.row_product(i, x));
    }

    /// `yz = A z` and `yx = A x` in one pass over the rows, for a `z` that is zero at most
    /// particles (the prescribed changes of the constrained ones, say): what each linear solve
    /// starts with (its reference residual and its initial guess's). A row's blocks, streamed
    /// from memory for the one product, are in the cache for the other. A row of `A z` whose
    /// columns all hold zeros of `z` is set to zero without being multiplied (the test reads
    /// its column indices, 4 bytes a block against the block's 72). Both are the bits of
    /// [`Split::mul_vec`] for a finite `A`: a row product starts from `+0`, and adding `±0`
    /// keeps it `+0`.
    pub fn mul_vec_both(&self, z: &[Vec3], x: &[Vec3], yz: &mut [Vec3], yx: &mut [Vec3]) {
        let nonzero: Vec<bool> = z
            .par_iter()
            .with_min_len(4 * ROWS)
            .map(|v| *v != Vec3::ZERO)
            .collect();
        let reaches = |m: &BlockMatrix, i: usize| m.row(i).0.iter().any(|&j| nonzero[j as usize]);
        yz.par_iter_mut()
            .zip(yx.par_iter_mut())
            .enumerate()
            .with_min_len(ROWS)
            .for_each(|(i, (a, b))| {
                let c = self.coupling.is_some_and(|c| reaches(&c.m, i));
                *a = if c || reaches(self.p, i) {
                    self.row_product(i, z)
                } else {
                    Vec3::ZERO
                };
                *b = self.row_product(i, x);
            });
    }

    /// The matrix `P + C` on one merged pattern (for the direct solver and inspection).
    pub fn merged(&self) -> BlockMatrix {
        let Some(c) = self.coupling else {
            return self.p.clone();
        };
        let mut pairs = Vec::new();
        for &i in &c.rows {
            let (cols, _) = c.m.row(i as usize);
            pairs.extend(cols.iter().filter(|&&j| j > i).map(|&j| (i, j)));
        }
        let mut a = self.p.with_pairs(&pairs);
        for i in 0..self.p.n() {
            let (cols, r) = self.p.row(i);
            for (&j, k) in cols.iter().zip(r) {
                a.add(i, j as usize, self.p.values[k]);
            }
        }
        for &i in &c.rows {
            let (cols, r) = c.m.row(i as usize);
            for (&j, k) in cols.iter().zip(r) {
                a.add(i as usize, j as usize, c.m.values[k]);
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Mat3;
    use proptest::prelude::*;

    fn mat(v: &[f64]) -> Mat3 {
        Mat3::from_cols_array(&[v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8]])
    }

    proptest! {
        /// The split product, row by row and whole, is the product with the merged matrix, and
        /// that is `P`'s blocks plus `C`'s.
        #[test]
        fn the_split_product_is_the_merged_product(
            n in 2usize..30,
            base in prop::collection::vec((0u32..30, 0u32..30), 0..60),
            more in prop::collection::vec((0u32..30, 0u32..30), 0..20),
            vals in prop::collection::vec(-1.0f64..1.0, 9 * 200),
            x in prop::collection::vec(-1.0f64..1.0, 90),
            keep in prop::collection::vec(0u32..30, 0..4),
        ) {
            let clip = |v: &[(u32, u32)]| -> Vec<(u32, u32)> {
                v.iter().map(|&(i, j)| (i % n as u32, j % n as u32)).collect()
            };
            let mut p = BlockMatrix::from_pairs(n, &clip(&base));
            let mut c = Coupling::new(n, &clip(&more));
            let mut k = 0;
            let mut next = || {
                k = (k + 9) % vals.len();
                mat(&vals[k..k + 9])
            };
            p.values.iter_mut().for_each(|m| *m = next());
            c.matrix_mut().values.iter_mut().for_each(|m| *m = next());
            // a particle without a pair has no block (a force on these pairs writes none)
            for i in 0..n {
                if !c.rows().contains(&(i as u32)) {
                    let k = c.matrix().diag_index(i);
                    c.matrix_mut().values[k] = Mat3::ZERO;
                }
            }
            let x: Vec<Vec3> = (0..n).map(|i| Vec3::new(x[3 * i], x[3 * i + 1], x[3 * i + 2])).collect();
            let a = Split { p: &p, coupling: Some(&c) };
            let merged = a.merged();
            let (mut y, mut want) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
            a.mul_vec(&x, &mut y);
            merged.mul_vec(&x, &mut want);
            for i in 0..n {
                prop_assert!((y[i] - want[i]).length() <= 1e-12, "row {}", i);
                // by hand: P's row plus C's
                let mut by_hand = p.row_product(i, &x);
                for (j, xj) in x.iter().enumerate() {
                    if let Some(k) = c.matrix().find(i, j) {
                        by_hand += c.matrix().values[k] * *xj;
                    }
                }
                prop_assert!((y[i] - by_hand).length() <= 1e-12, "row {}", i);
                let off = c.matrix().row(i).0.len() > 1;
                prop_assert_eq!(c.rows().contains(&(i as u32)), off);
            }
            // with most of z zero (every particle but those `keep` names), the pass that skips
            // the rows reaching no non-zero of z gives the whole products, to the bit
            let sparse: Vec<Vec3> = (0..n)
                .map(|i| if keep.contains(&(i as u32 % 30)) { x[i] } else { Vec3::ZERO })
                .collect();
            let mut full = vec![Vec3::ZERO; n];
            a.mul_vec(&sparse, &mut full);
            let (mut bz, mut bx) = (vec![Vec3::splat(7.0); n], vec![Vec3::splat(7.0); n]);
            a.mul_vec_both(&sparse, &x, &mut bz, &mut bx);
            for i in 0..n {
                prop_assert_eq!(bz[i].to_array().map(f64::to_bits), full[i].to_array().map(f64::to_bits), "row {}", i);
                prop_assert_eq!(bx[i].to_array().map(f64::to_bits), y[i].to_array().map(f64::to_bits), "row {}", i);
            }
        }

        /// Moving the majorant into `P` keeps `P + C` and leaves `P` at least `P + C`: for
        /// couplings among 4 particles from a random positive semi-definite 12 × 12 matrix
        /// (a contact stencil's Hessian; its blocks are not symmetric), the new `P` minus the
        /// whole matrix has no negative eigenvalue.
        #[test]
        fn the_majorant_keeps_the_sum_and_bounds_the_matrix_from_above(
            g in prop::collection::vec(-1.0f64..1.0, 144),
        ) {
            let n = 4;
            let all: Vec<(u32, u32)> = (0..4).flat_map(|i| (i + 1..4).map(move |j| (i, j))).collect();
            let mut c = Coupling::new(n, &all);
            let h: Vec<Vec<f64>> = (0..12)
                .map(|r| (0..12).map(|q| (0..12).map(|k| g[12 * r + k] * g[12 * q + k]).sum()).collect())
                .collect();
            for i in 0..n {
                for j in 0..n {
                    let b = Mat3::from_cols_array(&std::array::from_fn(|e| h[3 * i + e % 3][3 * j + e / 3]));
                    c.matrix_mut().add(i, j, b);
                }
            }
            let mut p = BlockMatrix::from_pairs(n, &[]);
            let whole = Split { p: &p, coupling: Some(&c) }.merged().to_dense();
            c.move_majorant_into(&mut p);
            let sum = Split { p: &p, coupling: Some(&c) }.merged().to_dense();
            let pd = p.to_dense();
            let mut diff = [[0.0; 12]; 12];
            for r in 0..12 {
                for q in 0..12 {
                    prop_assert!((sum[r][q] - whole[r][q]).abs() <= 1e-12 * (1.0 + whole[r][q].abs()));
                    diff[r][q] = pd[r][q] - whole[r][q];
                }
            }
            let (lambda, _) = symmetric_eigen(&diff);
            let scale = whole.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
            for l in lambda {
                prop_assert!(l >= -1e-10 * scale, "P - A has eigenvalue {} (scale {})", l, scale);
            }
        }
    }

    /// `|M|² = M Mᵀ`, and `|M|` is symmetric positive semi-definite.
    #[test]
    fn abs_is_the_square_root_of_m_mt() {
        let mut v = 0.3f64;
        for _ in 0..200 {
            let m = Mat3::from_cols_array(&std::array::from_fn(|_| {
                v = (v * 9.7 + 0.13).fract();
                2.0 * v - 1.0
            }));
            let a = abs(&m);
            let want = m * m.transpose();
            assert!(crate::math::max_abs(&(a * a - want)) <= 1e-12);
            assert!(crate::math::max_abs(&(a - a.transpose())) <= 1e-12);
            for x in [
                Vec3::X,
                Vec3::Y,
                Vec3::Z,
                Vec3::ONE,
                Vec3::new(1.0, -2.0, 0.5),
            ] {
                assert!(x.dot(a * x) >= -1e-12);
            }
        }
    }

    /// Two particles pressed together by a contact `[[K, -K], [-K, K]]`, `K = k n nᵀ`: `P`
    /// with only the diagonal blocks moved into it lies below the whole matrix where they move
    /// apart (`2k` against `4k`); with the majorant it lies on or above it, moving apart and
    /// moving together.
    #[test]
    fn with_only_the_diagonal_the_preconditioner_is_softer_than_the_contact() {
        let k = crate::math::outer(Vec3::Y, Vec3::Y) * 5.0;
        let mut c = Coupling::new(2, &[(0, 1)]);
        c.matrix_mut().add(0, 0, k);
        c.matrix_mut().add(1, 1, k);
        c.matrix_mut().add(0, 1, -k);
        c.matrix_mut().add(1, 0, -k);
        let energy = |a: Split, x: [Vec3; 2]| {
            let mut y = [Vec3::ZERO; 2];
            a.mul_vec(&x, &mut y);
            x[0].dot(y[0]) + x[1].dot(y[1])
        };
        let (apart, together) = ([Vec3::Y, -Vec3::Y], [Vec3::Y, Vec3::Y]);
        let zero = BlockMatrix::from_pairs(2, &[]);
        let whole = Split {
            p: &zero,
            coupling: Some(&c),
        };
        assert_eq!((energy(whole, apart), energy(whole, together)), (20.0, 0.0));
        let mut diagonal = BlockMatrix::from_pairs(2, &[]);
        diagonal.add(0, 0, k);
        diagonal.add(1, 1, k);
        assert_eq!(energy(Split::whole(&diagonal), apart), 10.0);
        let mut p = BlockMatrix::from_pairs(2, &[]);
        c.move_majorant_into(&mut p);
        let (a, t) = (
            energy(Split::whole(&p), apart),
            energy(Split::whole(&p), together),
        );
        assert!(a >= 20.0 - 1e-12 && t >= 0.0, "{a} {t}");
        let split = Split {
            p: &p,
            coupling: Some(&c),
        };
        assert!((energy(split, apart) - 20.0).abs() < 1e-12);
        assert!(energy(split, together).abs() < 1e-12);
    }
}
