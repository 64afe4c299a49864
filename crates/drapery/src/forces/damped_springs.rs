//! Springs and their damping on one list of pairs, evaluated together.
//!
//! Cloth springs are nearly all damped, so [`Springs`] and [`SpringDamping`] as two forces
//! would read the same pairs twice per step, evaluate twice and gather twice (per particle and
//! per matrix block). Here one evaluation per pair gives the sum of both forces, blocks and
//! products from one geometry, with one gather each. The formulas stay in the parts' files; a
//! pair may have zero stiffness or zero damping.

use super::pair_sum::PairSums;
use super::{Force, Linearization, SpringDamping, Springs};
use crate::error::{Error, Result};
use crate::linalg::BlockMatrix;
use crate::math::{Mat3, Vec3};

/// Springs and spring damping on the same pairs.
#[derive(Clone, Debug)]
pub struct DampedSprings {
    springs: Springs,
    damping: SpringDamping,
    sums: PairSums,
}

/// What one pair's geometry gives: the damping's `(n, ℓ, u)`, the total force on the first
/// particle and the spring's Hessian block `H`.
struct Pair {
    geom: Option<(Vec3, f64, Vec3)>,
    force: Vec3,
    hessian: Mat3,
}

impl DampedSprings {
    /// Joins `springs` and `damping`, which must have the same pairs in the same order and one
    /// coefficient per pair (the parts' own gather lists go unused).
    pub fn new(springs: Springs, damping: SpringDamping) -> Result<Self> {
        if springs.i != damping.i || springs.j != damping.j {
            return Err(Error::Invalid(
                "damped springs: the springs and their damping must have the same pairs".into(),
            ));
        }
        let n = springs.i.len();
        if [
            springs.j.len(),
            springs.rest.len(),
            springs.k.len(),
            damping.c.len(),
        ] != [n; 4]
        {
            return Err(Error::Invalid(
                "damped springs: every pair needs a rest length, a stiffness and a damping".into(),
            ));
        }
        Ok(DampedSprings {
            springs,
            damping,
            sums: PairSums::default(),
        })
    }

    // `inline(always)` here and on the parts' helpers: left to itself the compiler kept them as
    // calls, which cost over a third of the step's linearization.
    #[inline(always)]
    fn eval(&self, s: usize, x: &[Vec3], v: &[Vec3]) -> Pair {
        let geom = self.damping.geom(s, x, v);
        let (f, hessian) = match geom {
            Some((n, l, _)) => self.springs.eval_at(s, n, l),
            None => (Vec3::ZERO, Mat3::ZERO),
        };
        let force = f + SpringDamping::force_at(geom, self.damping.c[s]);
        Pair {
            geom,
            force,
            hessian,
        }
    }

    /// Block `(i, i)` of `a ∂f/∂x + b ∂f/∂v` of pair `s` (the spring's `∂f/∂x` block is `-H`).
    #[inline(always)]
    fn block(&self, p: &Pair, s: usize, a: f64, b: f64) -> Mat3 {
        self.damping.block_at(p.geom, self.damping.c[s], a, b) - a * p.hessian
    }

    /// `(a ∂f/∂x + b ∂f/∂v) (w_i - w_j)` of pair `s`.
    #[inline(always)]
    fn product(&self, p: &Pair, s: usize, a: f64, b: f64, w: &[Vec3]) -> Vec3 {
        self.block(p, s, a, b) * (w[self.springs.i[s] as usize] - w[self.springs.j[s] as usize])
    }

    /// Whether `a ∂f/∂x + b ∂f/∂v` can be non-zero: the product is skipped otherwise, by the
    /// separate call and the linearization alike (so their bits agree).
    fn has_jacobian(&self, a: f64, b: f64) -> bool {
        a != 0.0 || self.damping.has_jacobian(a, b)
    }
}

impl Force for DampedSprings {
    fn name(&self) -> &'static str {
        "damped springs"
    }
    fn energy(&self, x: &[Vec3]) -> f64 {
        self.springs.energy(x)
    }
    fn dissipation(&self, x: &[Vec3], v: &[Vec3]) -> f64 {
        self.damping.dissipation(x, v)
    }
    fn add_force(&self, x: &[Vec3], v: &[Vec3], f: &mut [Vec3]) {
        let (i, j) = (&self.springs.i, &self.springs.j);
        self.sums.add_vectors(i, j, |s| self.eval(s, x, v).force, f);
    }
    fn add_pattern(&self, pairs: &mut Vec<(u32, u32)>) {
        self.springs.add_pattern(pairs);
    }
    fn add_jacobian(&self, x: &[Vec3], v: &[Vec3], a: f64, b: f64, m: &mut BlockMatrix) {
        let (i, j) = (&self.springs.i, &self.springs.j);
        let block = |s: usize| self.block(&self.eval(s, x, v), s, a, b);
        self.sums.add_blocks(i, j, block, m);
    }
    fn add_jacobian_product(
        &self,
        x: &[Vec3],
        v: &[Vec3],
        a: f64,
        b: f64,
        w: &[Vec3],
        out: &mut [Vec3],
    ) {
        if !self.has_jacobian(a, b) {
            return;
        }
        let (i, j) = (&self.springs.i, &self.springs.j);
        let product = |s: usize| self.product(&self.eval(s, x, v), s, a, b, w);
        self.sums.add_vectors(i, j, product, out);
    }
    /// One geometry per pair for the force, the matrix block and the product, each the sum of
    /// the spring's and the damping's.
    fn add_linearization(
        &self,
        at: &Linearization,
        f: &mut [Vec3],
        m: &mut BlockMatrix,
        out: &mut [Vec3],
    ) {
        let (i, j) = (&self.springs.i, &self.springs.j);
        let ((am, bm), (ap, bp)) = (at.matrix, at.product);
        let with_product = self.has_jacobian(ap, bp);
        let term = |s: usize| {
            let p = self.eval(s, at.x, at.v);
            let product = if with_product {
                self.product(&p, s, ap, bp, at.w)
            } else {
                Vec3::ZERO
            };
            (p.force, product, self.block(&p, s, am, bm))
        };
        let out = with_product.then_some(out);
        self.sums.add_linearization(i, j, term, f, out, m);
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::*;
    use proptest::prelude::*;

    fn vec3(r: f64) -> impl Strategy<Value = Vec3> {
        (-r..r, -r..r, -r..r).prop_map(|(a, b, c)| Vec3::new(a, b, c))
    }

    const PAIRS: [(u32, u32); 7] = [(0, 1), (1, 2), (2, 3), (3, 4), (0, 2), (4, 1), (0, 3)];

    /// Positions, velocities and the two parts on five particles; each pair's stiffness and
    /// damping is zero or not at random, rest lengths from 0.2× to 3× the current length.
    fn config() -> impl Strategy<Value = (Vec<Vec3>, Vec<Vec3>, Springs, SpringDamping)> {
        let k = prop_oneof![Just(0.0), 0.1..1000.0f64];
        let c = prop_oneof![Just(0.0), 0.01..10.0f64];
        (
            prop::collection::vec(vec3(1.0), 5),
            prop::collection::vec(vec3(5.0), 5),
            prop::collection::vec(0.2..3.0f64, PAIRS.len()),
            prop::collection::vec(k, PAIRS.len()),
            prop::collection::vec(c, PAIRS.len()),
        )
            .prop_filter_map("well separated", |(x, v, ratio, k, c)| {
                let (i, j): (Vec<u32>, Vec<u32>) = PAIRS.iter().copied().unzip();
                let mut rest = Vec::new();
                for (&(a, b), r) in PAIRS.iter().zip(&ratio) {
                    let l = (x[a as usize] - x[b as usize]).length();
                    if l < 0.05 {
                        return None;
                    }
                    rest.push(l * r);
                }
                let springs = Springs {
                    i: i.clone(),
                    j: j.clone(),
                    rest,
                    k,
                    clamp_compression: false,
                    sums: PairSums::default(),
                };
                let damping = SpringDamping {
                    i,
                    j,
                    c,
                    position_jacobian: false,
                    sums: PairSums::default(),
                };
                Some((x, v, springs, damping))
            })
    }

    /// `(a, b)` of a product: none (skipped), the step's (`b = 0`) or any.
    fn product_coefficients() -> impl Strategy<Value = (f64, f64)> {
        prop_oneof![
            Just((0.0, 0.0)),
            (-2.0..2.0f64).prop_map(|a| (a, 0.0)),
            (-2.0..2.0f64, -2.0..2.0f64),
        ]
    }

    /// `(f, out, m)` of one force's [`Force::add_linearization`] from zeros.
    fn linearization(force: &dyn Force, at: &Linearization) -> (Vec<Vec3>, Vec<Vec3>, Vec<Mat3>) {
        let n = at.x.len();
        let mut pairs = Vec::new();
        force.add_pattern(&mut pairs);
        let mut m = BlockMatrix::from_pairs(n, &pairs);
        let (mut f, mut out) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
        force.add_linearization(at, &mut f, &mut m, &mut out);
        (f, out, m.values)
    }

    /// Max `|got - (p + q)|` over entries, and the largest entry of `p` and `q`.
    fn sum_error(got: &[f64], p: &[f64], q: &[f64]) -> (f64, f64) {
        let mut err = 0.0f64;
        let mut scale = 0.0f64;
        for ((g, a), b) in got.iter().zip(p).zip(q) {
            err = err.max((g - (a + b)).abs());
            scale = scale.max(a.abs()).max(b.abs());
        }
        (err, scale)
    }

    fn flat_vecs(v: &[Vec3]) -> Vec<f64> {
        v.iter().flat_map(|p| p.to_array()).collect()
    }

    fn flat_mats(m: &[Mat3]) -> Vec<f64> {
        m.iter().flat_map(|b| b.to_cols_array()).collect()
    }

    proptest! {
        /// Force, matrix and product against the two parts evaluated separately, with the
        /// compression clamp and the position Jacobian on or off.
        #[test]
        fn damped_springs_equal_the_sum_of_their_parts(
            (x, v, mut springs, mut damping) in config(),
            clamp in any::<bool>(),
            position_jacobian in any::<bool>(),
            a in -2.0..2.0f64,
            b in -2.0..2.0f64,
            product in product_coefficients(),
            w in prop::collection::vec(vec3(1.0), 5),
        ) {
            springs.clamp_compression = clamp;
            damping.position_jacobian = position_jacobian;
            let fused = DampedSprings::new(springs.clone(), damping.clone()).unwrap();
            let at = Linearization { x: &x, v: &v, matrix: (a, b), product, w: &w };
            let (f, out, m) = linearization(&fused, &at);
            let (fs, outs, ms) = linearization(&springs, &at);
            let (fd, outd, md) = linearization(&damping, &at);
            for (got, p, q) in [
                (flat_vecs(&f), flat_vecs(&fs), flat_vecs(&fd)),
                (flat_vecs(&out), flat_vecs(&outs), flat_vecs(&outd)),
                (flat_mats(&m), flat_mats(&ms), flat_mats(&md)),
            ] {
                let (err, scale) = sum_error(&got, &p, &q);
                prop_assert!(err <= 1e-12 * scale, "error {err} at scale {scale}");
            }
            prop_assert_eq!(fused.energy(&x), springs.energy(&x));
            prop_assert_eq!(fused.dissipation(&x, &v), damping.dissipation(&x, &v));
        }

        /// The fused evaluation against the three calls, bit for bit, including a pair of zero
        /// length (`collapse`).
        #[test]
        fn damped_springs_linearization_has_the_bits_of_the_separate_calls(
            (mut x, v, mut springs, mut damping) in config(),
            clamp in any::<bool>(),
            position_jacobian in any::<bool>(),
            collapse in any::<bool>(),
            a in -2.0..2.0f64,
            b in -2.0..2.0f64,
            product in product_coefficients(),
            w in prop::collection::vec(vec3(1.0), 5),
        ) {
            springs.clamp_compression = clamp;
            damping.position_jacobian = position_jacobian;
            if collapse {
                x[2] = x[1];
            }
            let fused = DampedSprings::new(springs, damping).unwrap();
            let at = Linearization { x: &x, v: &v, matrix: (a, b), product, w: &w };
            prop_assert!(linearization_is_bitwise_separate(&fused, &at, &w));
        }

        /// With the position Jacobian and no clamp the matrix is the whole derivative.
        #[test]
        fn damped_springs_matrix_matches_central_differences(
            (x, v, springs, mut damping) in config(),
            w in prop::collection::vec(vec3(1.0), 5),
        ) {
            damping.position_jacobian = true;
            let fused = DampedSprings::new(springs, damping).unwrap();
            let (a, b) = (0.7, -1.3);
            let fd_x = fd_jacobian(&fused, &x, &v, false);
            let fd_v = fd_jacobian(&fused, &x, &v, true);
            let fd: Vec<Vec<f64>> = fd_x
                .iter()
                .zip(&fd_v)
                .map(|(rx, rv)| rx.iter().zip(rv).map(|(p, q)| a * p + b * q).collect())
                .collect();
            let got = linearized(&fused, &x, &v, a, b);
            prop_assert!(rel_diff(&got, &fd) < 1e-6, "{}", rel_diff(&got, &fd));
            prop_assert!(check_product(&fused, &x, &v, a, b, &w) < 1e-12);
        }
    }

    #[test]
    fn parts_with_different_pairs_are_refused() {
        let springs = Springs {
            i: vec![0, 1],
            j: vec![1, 2],
            rest: vec![1.0; 2],
            k: vec![1.0; 2],
            clamp_compression: true,
            sums: PairSums::default(),
        };
        let damping = SpringDamping {
            i: vec![0, 1],
            j: vec![1, 0],
            c: vec![1.0; 2],
            position_jacobian: false,
            sums: PairSums::default(),
        };
        assert!(DampedSprings::new(springs.clone(), damping.clone()).is_err());
        let short = SpringDamping {
            j: vec![1, 2],
            c: vec![1.0],
            ..damping
        };
        assert!(DampedSprings::new(springs, short).is_err());
    }

    /// A 40×40 grid's stretch, shear and bend pairs (enough pairs and particles for several
    /// parallel tasks), every 7th without stiffness and every 5th without damping.
    #[test]
    fn damped_springs_have_the_same_bits_on_one_and_two_threads() {
        let side = 40u32;
        let id = |r: u32, c: u32| r * side + c;
        let x: Vec<Vec3> = (0..side * side)
            .map(|p| {
                let (r, c) = ((p / side) as f64, (p % side) as f64);
                Vec3::new(0.1 * c, 0.02 * (0.7 * r + 1.3 * c).sin(), 0.1 * r)
            })
            .collect();
        let v: Vec<Vec3> = (0..x.len())
            .map(|p| Vec3::new((p as f64).sin(), (1.7 * p as f64).cos(), 0.3))
            .collect();
        let mut pairs = Vec::new();
        for r in 0..side {
            for c in 0..side {
                for (dr, dc) in [(0, 1), (1, 0), (1, 1), (0, 2), (2, 0)] {
                    if r + dr < side && c + dc < side {
                        pairs.push((id(r, c), id(r + dr, c + dc)));
                    }
                }
            }
        }
        let (i, j): (Vec<u32>, Vec<u32>) = pairs.iter().copied().unzip();
        let rest: Vec<f64> = pairs
            .iter()
            .map(|&(a, b)| 0.97 * (x[a as usize] - x[b as usize]).length())
            .collect();
        let every = |n: usize, value: f64| -> Vec<f64> {
            (0..pairs.len())
                .map(|s| if s % n == 0 { 0.0 } else { value })
                .collect()
        };
        for position_jacobian in [false, true] {
            let springs = Springs {
                i: i.clone(),
                j: j.clone(),
                rest: rest.clone(),
                k: every(7, 500.0),
                clamp_compression: true,
                sums: PairSums::default(),
            };
            let damping = SpringDamping {
                i: i.clone(),
                j: j.clone(),
                c: every(5, 0.3),
                position_jacobian,
                sums: PairSums::default(),
            };
            let fused = DampedSprings::new(springs, damping).unwrap();
            let at = Linearization {
                x: &x,
                v: &v,
                matrix: (-1e-4, -1e-2),
                product: (1e-2, 0.0),
                w: &v,
            };
            let run = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut m = BlockMatrix::from_pairs(x.len(), &pairs);
                let (mut f, mut out) = (vec![Vec3::ZERO; x.len()], vec![Vec3::ZERO; x.len()]);
                pool.install(|| {
                    fused
                        .clone()
                        .add_linearization(&at, &mut f, &mut m, &mut out)
                });
                let bits = |v: Vec<f64>| v.into_iter().map(f64::to_bits).collect::<Vec<_>>();
                (
                    bits(flat_vecs(&f)),
                    bits(flat_vecs(&out)),
                    bits(flat_mats(&m.values)),
                )
            };
            let (one, two) = (run(1), run(2));
            assert!(one.0.iter().any(|&b| f64::from_bits(b) != 0.0));
            assert_eq!(one, two);
        }
    }
}
