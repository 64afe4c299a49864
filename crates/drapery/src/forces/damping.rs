//! Damping along springs, docs/MATH.md §3.
//!
//! `u = v_i - v_j`, `f_i = -c (u·n) n = -f_j`, `∂f_i/∂v_i = -c n nᵀ` (symmetric, negative
//! semi-definite). The position derivative
//! `∂f_i/∂x_i = -(c/ℓ) [(u·n) I + n uᵀ - 2 (u·n) n nᵀ]` is not symmetric: Baraff & Witkin leave
//! it out of the matrix, and so does drapery unless `position_jacobian` is set (which then
//! needs the direct solver's LU).

use super::stencil::{Accumulate, Gather, Local, Pair, StencilForce};
use super::{Linearization, State};
use crate::math::{Mat3, Vec3, outer};

/// Damping on a set of springs.
#[derive(Clone, Debug)]
pub struct SpringDamping {
    /// First particle.
    pub i: Vec<u32>,
    /// Second particle.
    pub j: Vec<u32>,
    /// Damping coefficient, N·s/m.
    pub c: Vec<f64>,
    /// Include `∂f/∂x` in the Jacobian (non-symmetric).
    pub position_jacobian: bool,
    /// Gather lists for the parallel sums (build with `Gather::default()`).
    pub sums: Gather<Pair>,
}

/// `(n, ℓ, u)` of a spring: direction, length and relative velocity `v_i - v_j`.
type Geometry = Option<(Vec3, f64, Vec3)>;

impl SpringDamping {
    /// Returns `(n, ℓ, u)` for spring `s`, or `None` when the spring has no length.
    #[inline]
    fn geom(&self, s: usize, x: &[Vec3], v: &[Vec3]) -> Geometry {
        let (i, j) = (self.i[s] as usize, self.j[s] as usize);
        let d = x[i] - x[j];
        let l = d.length();
        if !(l > 1e-300) {
            return None;
        }
        Some((d / l, l, v[i] - v[j]))
    }

    /// `∂f_i/∂x_i` of spring `s` (the block `-G`).
    #[inline]
    fn dfdx(&self, n: Vec3, l: f64, u: Vec3, c: f64) -> Mat3 {
        let un = u.dot(n);
        -(c / l) * (Mat3::from_diagonal(Vec3::splat(un)) + outer(n, u) - 2.0 * un * outer(n, n))
    }

    /// Block `(i, i)` of `a ∂f/∂x + b ∂f/∂v` for a spring of coefficient `c` with geometry
    /// `g` from [`Self::geom`] (the other blocks follow by ±).
    #[inline]
    fn block_at(&self, g: Geometry, c: f64, a: f64, b: f64) -> Mat3 {
        let Some((n, l, u)) = g else {
            return Mat3::ZERO;
        };
        let mut blk = -(b * c) * outer(n, n);
        if self.position_jacobian && a != 0.0 {
            blk += a * self.dfdx(n, l, u, c);
        }
        blk
    }

    /// Force on particle i of a spring of coefficient `c` with geometry `g`.
    #[inline]
    fn force_at(g: Geometry, c: f64) -> Vec3 {
        g.map_or(Vec3::ZERO, |(n, _, u)| -c * u.dot(n) * n)
    }

    /// `B (w_i - w_j)` for spring `s` with block `B`.
    #[inline]
    fn product(&self, s: usize, block: Mat3, w: &[Vec3]) -> Vec3 {
        block * (w[self.i[s] as usize] - w[self.j[s] as usize])
    }
}

impl StencilForce for SpringDamping {
    type Shape = Pair;
    const NAME: &'static str = "spring damping";
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
    fn local_dissipation(&self, s: usize, at: &State) -> f64 {
        self.geom(s, at.x, at.v)
            .map_or(0.0, |(n, _, u)| 0.5 * self.c[s] * u.dot(n).powi(2))
    }
    fn local_force(&self, s: usize, at: &State) -> Vec3 {
        Self::force_at(self.geom(s, at.x, at.v), self.c[s])
    }
    /// Without the position Jacobian, `b = 0` leaves nothing.
    fn has_jacobian(&self, a: f64, b: f64) -> bool {
        b != 0.0 || (self.position_jacobian && a != 0.0)
    }
    fn local_jacobian(&self, s: usize, at: &State, a: f64, b: f64) -> Mat3 {
        self.block_at(self.geom(s, at.x, at.v), self.c[s], a, b)
    }
    fn local_product(&self, s: usize, at: &State, a: f64, b: f64, w: &[Vec3]) -> Vec3 {
        self.product(s, self.local_jacobian(s, at, a, b), w)
    }
    /// One geometry per spring for the force, the matrix block and the product.
    fn local(&self, s: usize, at: &Linearization, product: bool, matrix: bool) -> Local<Pair> {
        let (g, c) = (self.geom(s, at.x, at.v), self.c[s]);
        let ((am, bm), (ap, bp)) = (at.matrix, at.product);
        Local {
            force: Self::force_at(g, c),
            product: if product {
                self.product(s, self.block_at(g, c, ap, bp), at.w)
            } else {
                Vec3::ZERO
            },
            matrix: if matrix {
                self.block_at(g, c, am, bm)
            } else {
                Mat3::ZERO
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Force;
    use super::super::testing::*;
    use super::*;
    use proptest::prelude::*;

    fn vec3(r: f64) -> impl Strategy<Value = Vec3> {
        (-r..r, -r..r, -r..r).prop_map(|(a, b, c)| Vec3::new(a, b, c))
    }

    fn config() -> impl Strategy<Value = (Vec<Vec3>, Vec<Vec3>, SpringDamping)> {
        (
            prop::collection::vec(vec3(1.0), 3),
            prop::collection::vec(vec3(5.0), 3),
            prop::collection::vec(0.01..10.0f64, 3),
        )
            .prop_filter("separated", |(x, _, _)| {
                (x[0] - x[1]).length() > 0.05
                    && (x[1] - x[2]).length() > 0.05
                    && (x[0] - x[2]).length() > 0.05
            })
            .prop_map(|(x, v, c)| {
                (
                    x,
                    v,
                    SpringDamping {
                        i: vec![0, 1, 2],
                        j: vec![1, 2, 0],
                        c,
                        position_jacobian: true,
                        sums: Gather::default(),
                    },
                )
            })
    }

    proptest! {
        #[test]
        fn damping_velocity_jacobian_matches_central_differences((x, v, d) in config()) {
            let got = assembled(&d, &x, &v, 0.0, 1.0);
            prop_assert!(rel_diff(&got, &fd_jacobian(&d, &x, &v, true)) < 1e-7);
            for r in 0..9 { for c in 0..9 { prop_assert!((got[r][c] - got[c][r]).abs() < 1e-12 * (1.0 + got[r][c].abs())); } }
        }

        #[test]
        fn damping_position_jacobian_matches_central_differences((x, v, d) in config()) {
            let got = assembled(&d, &x, &v, 1.0, 0.0);
            let fd = fd_jacobian(&d, &x, &v, false);
            prop_assert!(rel_diff(&got, &fd) < 1e-6, "{}", rel_diff(&got, &fd));
            prop_assert!(check_product(&d, &x, &v, 0.3, -2.0, &v) < 1e-12);
        }

        /// The fused evaluation against the three calls, bit for bit, with and without the
        /// position Jacobian, a product with `b = 0` (skipped without it) and (`collapse`) a
        /// spring of zero length.
        #[test]
        fn damping_linearization_has_the_bits_of_the_separate_calls(
            (mut x, v, mut d) in config(),
            position_jacobian in any::<bool>(),
            collapse in any::<bool>(),
            a in -2.0..2.0f64,
            b in -2.0..2.0f64,
            product_b in prop::sample::select(vec![0.0, 1.0]),
            w in prop::collection::vec(vec3(1.0), 3),
        ) {
            d.position_jacobian = position_jacobian;
            if collapse {
                x[2] = x[0];
            }
            let at = Linearization { t: T, x: &x, v: &v, matrix: (a, b), product: (b, product_b * a), w: &w };
            prop_assert!(linearization_is_bitwise_separate(&d, &at, &w));
        }

        #[test]
        fn damping_linearization_matrix_matches_central_differences((x, v, d) in config()) {
            let got = linearized(&d, &x, &v, 0.7, -1.3);
            let fd_x = fd_jacobian(&d, &x, &v, false);
            let fd_v = fd_jacobian(&d, &x, &v, true);
            let fd: Vec<Vec<f64>> = fd_x
                .iter()
                .zip(&fd_v)
                .map(|(rx, rv)| rx.iter().zip(rv).map(|(p, q)| 0.7 * p - 1.3 * q).collect())
                .collect();
            prop_assert!(rel_diff(&got, &fd) < 1e-6, "{}", rel_diff(&got, &fd));
        }

        #[test]
        fn damping_force_is_minus_the_velocity_gradient_of_the_dissipation((x, v, d) in config()) {
            let mut f = vec![Vec3::ZERO; 3];
            d.add_force(&at(&x, &v), &mut f);
            let mut vp = v.clone();
            for i in 0..3 { for k in 0..3 {
                let e = 1e-6;
                vp[i][k] = v[i][k] + e; let p = d.dissipation(&at(&x, &vp));
                vp[i][k] = v[i][k] - e; let m = d.dissipation(&at(&x, &vp));
                vp[i][k] = v[i][k];
                prop_assert!((-(p - m) / (2.0 * e) - f[i][k]).abs() < 1e-5 * (1.0 + f[i][k].abs()));
            }}
        }

        #[test]
        fn damping_never_adds_energy((x, v, d) in config()) {
            let mut f = vec![Vec3::ZERO; 3];
            d.add_force(&at(&x, &v), &mut f);
            let power: f64 = f.iter().zip(&v).map(|(a, b)| a.dot(*b)).sum();
            prop_assert!(power <= 1e-12);
        }
    }
}
