//! Linear springs (stretch, shear and bend alike), docs/MATH.md §2.
//!
//! Between particles i and j with stiffness `k` and rest length `L`: `d = x_i - x_j`,
//! `ℓ = |d|`, `n = d/ℓ`, `E = ½ k (ℓ - L)²`, `f_i = -k (ℓ - L) n = -f_j`.
//! Energy Hessian block `H = k [n nᵀ + (1 - L/ℓ)(I - n nᵀ)]`; `K_ii = K_jj = -H`,
//! `K_ij = K_ji = +H`. With `clamp_compression`, the matrix (never the force) uses
//! `max(0, 1 - L/ℓ)` so that `-K` stays positive semi-definite (Choi & Ko 2002).

use super::stencil::{Accumulate, Gather, Local, Pair, StencilForce};
use super::{Linearization, State};
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
    /// Gather lists for the parallel sums (build with `Gather::default()`).
    pub sums: Gather<Pair>,
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

    /// `-a H (w_i - w_j)` for spring `s` with Hessian block `h`.
    #[inline]
    fn product(&self, s: usize, h: Mat3, a: f64, w: &[Vec3]) -> Vec3 {
        -a * (h * (w[self.i[s] as usize] - w[self.j[s] as usize]))
    }
}

impl StencilForce for Springs {
    type Shape = Pair;
    const NAME: &'static str = "springs";
    fn gather(&self) -> &Gather<Pair> {
        &self.sums
    }
    fn count(&self) -> usize {
        self.i.len()
    }
    fn particles(&self, s: usize) -> [u32; 2] {
        [self.i[s], self.j[s]]
    }
    fn accumulate(&self) -> Accumulate {
        Accumulate::Sum
    }
    fn local_energy(&self, s: usize, _t: f64, x: &[Vec3]) -> f64 {
        let l = (x[self.i[s] as usize] - x[self.j[s] as usize]).length();
        0.5 * self.k[s] * (l - self.rest[s]).powi(2)
    }
    fn local_force(&self, s: usize, at: &State) -> Vec3 {
        self.eval(s, at.x).0
    }
    fn has_jacobian(&self, a: f64, _b: f64) -> bool {
        a != 0.0
    }
    fn local_jacobian(&self, s: usize, at: &State, a: f64, _b: f64) -> Mat3 {
        -a * self.eval(s, at.x).1
    }
    fn local_product(&self, s: usize, at: &State, a: f64, _b: f64, w: &[Vec3]) -> Vec3 {
        self.product(s, self.eval(s, at.x).1, a, w)
    }
    /// One evaluation per spring: the force, `-a H` for the matrix and `-a H (w_i - w_j)` for
    /// the product come from the same `(f, H)`.
    fn local(&self, s: usize, at: &Linearization, _product: bool, _matrix: bool) -> Local<Pair> {
        let (g, h) = self.eval(s, at.x);
        Local {
            force: g,
            product: self.product(s, h, at.product.0, at.w),
            matrix: -at.matrix.0 * h,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Force;
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
                    sums: Gather::default(),
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
            s.add_force(&at(&x, &x), &mut f);
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
            let at = Linearization { t: T, x: &x, v: &w, matrix: (a, b), product: (b, a), w: &w };
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
            s.add_jacobian_product(&at(&x, &v), 1.0, 0.0, &w, &mut kw);
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
            sums: Gather::default(),
        };
        let x = [Vec3::ZERO, Vec3::X];
        let w = [Vec3::Y, -Vec3::Y];
        let mut kw = vec![Vec3::ZERO; 2];
        s.add_jacobian_product(&at(&x, &x), 1.0, 0.0, &w, &mut kw);
        let q: f64 = w.iter().zip(&kw).map(|(a, b)| a.dot(*b)).sum();
        assert!(q > 0.0);
    }
}
