//! Linear springs (stretch, shear and bend alike), docs/MATH.md §2.
//!
//! Between particles i and j with stiffness `k` and rest length `L`: `d = x_i - x_j`,
//! `ℓ = |d|`, `n = d/ℓ`, `E = ½ k (ℓ - L)²`, `f_i = -k (ℓ - L) n = -f_j`.
//! Energy Hessian block `H = k [n nᵀ + (1 - L/ℓ)(I - n nᵀ)]`; `K_ii = K_jj = -H`,
//! `K_ij = K_ji = +H`. With `clamp_compression`, the matrix (never the force) uses
//! `max(0, 1 - L/ℓ)` so that `-K` stays positive semi-definite (Choi & Ko 2002).

use super::pair_sum::PairSums;
use super::{Force, Linearization, linearize_separately};
use crate::linalg::BlockMatrix;
use crate::math::{Mat3, Vec3, outer};

/// A set of springs.
#[derive(Clone, Debug)]
pub struct Springs {
    /// First particle of each spring.
    pub i: Vec<u32>,
    /// Second particle.
    pub j: Vec<u32>,
    /// Rest length, m.
    pub rest: Vec<f64>,
    /// Stiffness, N/m.
    pub k: Vec<f64>,
    /// Clamp the compressed transverse term in the matrix (default true).
    pub clamp_compression: bool,
    /// Gather lists for the parallel sums (build with `PairSums::default()`).
    pub sums: PairSums,
}

/// Below this length a spring has no direction: it exerts no force and no stiffness.
const MIN_LENGTH: f64 = 1e-300;

impl Springs {
    /// Force on particle i and the Hessian block used in the matrix, for spring `s`.
    #[inline]
    fn eval(&self, s: usize, x: &[Vec3]) -> (Vec3, Mat3) {
        let d = x[self.i[s] as usize] - x[self.j[s] as usize];
        let l = d.length();
        if !(l > MIN_LENGTH) {
            return (Vec3::ZERO, Mat3::ZERO);
        }
        let n = d / l;
        let (k, rest) = (self.k[s], self.rest[s]);
        let f = -k * (l - rest) * n;
        let mut t = 1.0 - rest / l;
        if self.clamp_compression {
            t = t.max(0.0);
        }
        let nn = outer(n, n);
        let h = k * (nn + t * (Mat3::IDENTITY - nn));
        (f, h)
    }
}

impl Force for Springs {
    fn name(&self) -> &'static str {
        "springs"
    }
    fn energy(&self, x: &[Vec3]) -> f64 {
        (0..self.i.len())
            .map(|s| {
                let l = (x[self.i[s] as usize] - x[self.j[s] as usize]).length();
                0.5 * self.k[s] * (l - self.rest[s]).powi(2)
            })
            .sum()
    }
    fn add_force(&self, x: &[Vec3], _v: &[Vec3], f: &mut [Vec3]) {
        self.sums
            .add_vectors(&self.i, &self.j, |s| self.eval(s, x).0, f);
    }
    fn add_pattern(&self, pairs: &mut Vec<(u32, u32)>) {
        pairs.extend(self.i.iter().zip(&self.j).map(|(&a, &b)| (a, b)));
    }
    fn add_jacobian(&self, x: &[Vec3], _v: &[Vec3], a: f64, _b: f64, m: &mut BlockMatrix) {
        if a == 0.0 {
            return;
        }
        self.sums
            .add_blocks(&self.i, &self.j, |s| -a * self.eval(s, x).1, m);
    }
    fn add_jacobian_product(
        &self,
        x: &[Vec3],
        _v: &[Vec3],
        a: f64,
        _b: f64,
        w: &[Vec3],
        out: &mut [Vec3],
    ) {
        if a == 0.0 {
            return;
        }
        let (i, j) = (&self.i, &self.j);
        self.sums.add_vectors(
            i,
            j,
            |s| -a * (self.eval(s, x).1 * (w[i[s] as usize] - w[j[s] as usize])),
            out,
        );
    }
    /// One evaluation per spring: the force, `-a H` for the matrix and `-a H (w_i - w_j)` for
    /// the product come from the same `(f, H)`.
    fn add_linearization(
        &self,
        at: &Linearization,
        f: &mut [Vec3],
        m: &mut BlockMatrix,
        out: &mut [Vec3],
    ) {
        let (am, ap) = (at.matrix.0, at.product.0);
        if am == 0.0 || ap == 0.0 {
            return linearize_separately(self, at, f, m, out);
        }
        let (i, j, x, w) = (&self.i, &self.j, at.x, at.w);
        let term = |s: usize| {
            let (g, h) = self.eval(s, x);
            let p = -ap * (h * (w[i[s] as usize] - w[j[s] as usize]));
            (g, p, -am * h)
        };
        self.sums.add_linearization(i, j, term, f, Some(out), m);
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::*;
    use proptest::prelude::*;

    fn vec3() -> impl Strategy<Value = Vec3> {
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(a, b, c)| Vec3::new(a, b, c))
    }

    /// Four particles, springs on a few pairs, rest lengths from 0.2× to 3× the current length
    /// (so both stretched and compressed springs occur).
    fn config() -> impl Strategy<Value = (Vec<Vec3>, Springs)> {
        (
            prop::collection::vec(vec3(), 4),
            prop::collection::vec(0.2..3.0f64, 5),
            prop::collection::vec(0.1..1000.0f64, 5),
        )
            .prop_filter_map("well separated", |(x, ratio, k)| {
                let pairs = [(0u32, 1u32), (1, 2), (2, 3), (0, 2), (3, 1)];
                let mut s = Springs {
                    i: vec![],
                    j: vec![],
                    rest: vec![],
                    k: vec![],
                    clamp_compression: false,
                    sums: PairSums::default(),
                };
                for (p, &(a, b)) in pairs.iter().enumerate() {
                    let l = (x[a as usize] - x[b as usize]).length();
                    if l < 0.05 {
                        return None;
                    }
                    s.i.push(a);
                    s.j.push(b);
                    s.rest.push(l * ratio[p]);
                    s.k.push(k[p]);
                }
                Some((x, s))
            })
    }

    proptest! {
        #[test]
        fn spring_force_is_minus_energy_gradient((x, s) in config()) {
            let mut f = vec![Vec3::ZERO; 4];
            s.add_force(&x, &x, &mut f);
            let fd = fd_gradient(&s, &x);
            let scale = f.iter().fold(1.0f64, |m, v| m.max(v.length()));
            for i in 0..4 {
                prop_assert!((f[i] - fd[i]).length() < 1e-5 * scale, "{:?} vs {:?}", f[i], fd[i]);
            }
        }

        #[test]
        fn spring_jacobian_matches_central_differences((x, s) in config()) {
            let v = vec![Vec3::ZERO; 4];
            let got = assembled(&s, &x, &v, 1.0, 0.0);
            let fd = fd_jacobian(&s, &x, &v, false);
            prop_assert!(rel_diff(&got, &fd) < 1e-6, "rel diff {}", rel_diff(&got, &fd));
            prop_assert!(check_product(&s, &x, &v, 1.0, 0.0, &x) < 1e-12);
            // the fused evaluation's matrix
            let fused = linearized(&s, &x, &v, 1.0, 0.0);
            prop_assert!(rel_diff(&fused, &fd) < 1e-6, "rel diff {}", rel_diff(&fused, &fd));
        }

        /// The fused evaluation against the three calls, bit for bit, with the compression
        /// clamp on or off and (`collapse`) a spring of zero length.
        #[test]
        fn spring_linearization_has_the_bits_of_the_separate_calls(
            (mut x, mut s) in config(),
            clamp in any::<bool>(),
            collapse in any::<bool>(),
            a in -2.0..2.0f64,
            b in -2.0..2.0f64,
            w in prop::collection::vec(vec3(), 4),
        ) {
            s.clamp_compression = clamp;
            if collapse {
                x[3] = x[1];
            }
            let at = Linearization { x: &x, v: &w, matrix: (a, b), product: (b, a), w: &w };
            prop_assert!(linearization_is_bitwise_separate(&s, &at, &w));
        }

        #[test]
        fn spring_jacobian_is_symmetric_with_zero_block_row_sums((x, mut s) in config(), clamp in any::<bool>()) {
            s.clamp_compression = clamp;
            let v = vec![Vec3::ZERO; 4];
            let k = assembled(&s, &x, &v, 1.0, 0.0);
            for r in 0..12 {
                for c in 0..12 {
                    prop_assert!((k[r][c] - k[c][r]).abs() <= 1e-12 * (1.0 + k[r][c].abs()));
                }
                // translation invariance: each row of K sums to zero over the same coordinate
                for d in 0..3 {
                    let sum: f64 = (0..4).map(|j| k[r][3 * j + d]).sum();
                    prop_assert!(sum.abs() < 1e-9 * (1.0 + k[r].iter().fold(0.0f64, |m, v| m.max(v.abs()))));
                }
            }
        }

        #[test]
        fn clamped_spring_matrix_is_negative_semidefinite((x, mut s) in config(), w in prop::collection::vec(vec3(), 4)) {
            s.clamp_compression = true;
            let v = vec![Vec3::ZERO; 4];
            let mut kw = vec![Vec3::ZERO; 4];
            s.add_jacobian_product(&x, &v, 1.0, 0.0, &w, &mut kw);
            let q: f64 = w.iter().zip(&kw).map(|(a, b)| a.dot(*b)).sum();
            prop_assert!(q <= 1e-9, "wᵀKw = {q}");
        }
    }

    #[test]
    fn an_unclamped_compressed_spring_has_an_indefinite_matrix() {
        // the reason for the clamp: transverse term (1 - L/ℓ) < 0
        let s = Springs {
            i: vec![0],
            j: vec![1],
            rest: vec![2.0],
            k: vec![10.0],
            clamp_compression: false,
            sums: PairSums::default(),
        };
        let x = [Vec3::ZERO, Vec3::X];
        let w = [Vec3::Y, -Vec3::Y];
        let mut kw = vec![Vec3::ZERO; 2];
        s.add_jacobian_product(&x, &x, 1.0, 0.0, &w, &mut kw);
        let q: f64 = w.iter().zip(&kw).map(|(a, b)| a.dot(*b)).sum();
        assert!(q > 0.0);
    }
}
