//! The gather against plain serial loops, bit for bit, on random stencils (particles repeated
//! within and across stencils), on one and two threads.

use super::super::testing::{T, at, linearization_is_bitwise_separate};
use super::*;
use proptest::prelude::*;

/// Particles of the test scenes.
const PARTICLES_N: usize = 8;

/// An arbitrary, non-symmetric 3×3 block from four numbers.
fn block(p: f64, q: f64, r: f64, s: f64) -> Mat3 {
    Mat3::from_cols_array(&[p, q, r, q * s, s, p - r, r * p, -s, q + 1.0])
}

/// A stencil force with made-up terms that depend on the stencil, the local index, the state
/// and the time.
struct Made<const N: usize> {
    stencils: Vec<[u32; N]>,
    how: Accumulate,
    sums: Gather<Full<N>>,
}

impl<const N: usize> Made<N> {
    fn new(stencils: Vec<[u32; N]>, how: Accumulate) -> Self {
        Made {
            stencils,
            how,
            sums: Gather::default(),
        }
    }
}

impl<const N: usize> StencilForce for Made<N> {
    type Shape = Full<N>;
    const NAME: &'static str = "made up";
    fn gather(&self) -> &Gather<Full<N>> {
        &self.sums
    }
    fn count(&self) -> usize {
        self.stencils.len()
    }
    fn particles(&self, s: usize) -> [u32; N] {
        self.stencils[s]
    }
    fn accumulate(&self) -> Accumulate {
        self.how
    }
    fn local_energy(&self, s: usize, t: f64, x: &[Vec3]) -> f64 {
        self.stencils[s]
            .iter()
            .map(|&p| x[p as usize].length_squared() * (s as f64 + t))
            .sum()
    }
    fn local_force(&self, s: usize, at: &State) -> [Vec3; N] {
        let p = self.stencils[s];
        std::array::from_fn(|a| {
            let (xa, va) = (at.x[p[a] as usize], at.v[p[a] as usize]);
            Vec3::new(
                (s as f64 + a as f64).sin(),
                xa.y * va.z,
                at.t / (1.0 + s as f64),
            ) + xa
        })
    }
    fn local_jacobian(&self, s: usize, at: &State, a: f64, b: f64) -> [[Mat3; N]; N] {
        let p = self.stencils[s];
        std::array::from_fn(|r| {
            std::array::from_fn(|c| {
                let (xr, vc) = (at.x[p[r] as usize], at.v[p[c] as usize]);
                block(
                    a * xr.x,
                    b * vc.y + s as f64,
                    (r * N + c) as f64,
                    at.t * xr.z,
                )
            })
        })
    }
}

/// A pair force with the same kind of made-up terms, and its expanded `Full<2>` twin.
struct MadePair {
    stencils: Vec<[u32; 2]>,
    how: Accumulate,
    sums: Gather<Pair>,
}

fn pair_vector(s: usize, at: &State, [i, j]: [u32; 2]) -> Vec3 {
    let d = at.x[i as usize] - at.x[j as usize];
    Vec3::new(d.x * (s as f64 + 0.5).cos(), d.y + at.t, d.z * d.x)
}

fn pair_block(s: usize, at: &State, a: f64, b: f64, [i, j]: [u32; 2]) -> Mat3 {
    let u = at.v[i as usize] - at.v[j as usize];
    block(a * u.x, b * u.y, s as f64, u.z * at.t)
}

impl StencilForce for MadePair {
    type Shape = Pair;
    const NAME: &'static str = "made-up pairs";
    fn gather(&self) -> &Gather<Pair> {
        &self.sums
    }
    fn count(&self) -> usize {
        self.stencils.len()
    }
    fn particles(&self, s: usize) -> [u32; 2] {
        self.stencils[s]
    }
    fn accumulate(&self) -> Accumulate {
        self.how
    }
    fn local_force(&self, s: usize, at: &State) -> Vec3 {
        pair_vector(s, at, self.stencils[s])
    }
    fn local_jacobian(&self, s: usize, at: &State, a: f64, b: f64) -> Mat3 {
        pair_block(s, at, a, b, self.stencils[s])
    }
}

/// [`MadePair`] written out on two particles: `[g, -g]` and `[[B, -B], [-B, B]]`.
struct Expanded(MadePair, Gather<Full<2>>);

impl StencilForce for Expanded {
    type Shape = Full<2>;
    const NAME: &'static str = "made-up pairs, expanded";
    fn gather(&self) -> &Gather<Full<2>> {
        &self.1
    }
    fn count(&self) -> usize {
        self.0.count()
    }
    fn particles(&self, s: usize) -> [u32; 2] {
        self.0.particles(s)
    }
    fn accumulate(&self) -> Accumulate {
        self.0.how
    }
    fn local_force(&self, s: usize, at: &State) -> [Vec3; 2] {
        let g = self.0.local_force(s, at);
        [g, -g]
    }
    fn local_jacobian(&self, s: usize, at: &State, a: f64, b: f64) -> [[Mat3; 2]; 2] {
        let m = self.0.local_jacobian(s, at, a, b);
        [[m, -m], [-m, m]]
    }
    fn local_product(&self, s: usize, at: &State, a: f64, b: f64, w: &[Vec3]) -> [Vec3; 2] {
        let p = self.0.local_product(s, at, a, b, w);
        [p, -p]
    }
}

/// The plain serial loop: each stencil's terms, from `local(s) = (particles, vectors, blocks)`,
/// added to the targets in turn (`Each`), or summed per target first and then added (`Sum`).
fn serial<const N: usize>(
    how: Accumulate,
    count: usize,
    local: impl Fn(usize) -> ([u32; N], [Vec3; N], [[Mat3; N]; N]),
    f: &mut [Vec3],
    m: &mut BlockMatrix,
) {
    let (mut fs, mut ms) = (f.to_vec(), m.clone());
    if how == Accumulate::Sum {
        fs.fill(Vec3::ZERO);
        ms.clear();
    }
    for s in 0..count {
        let (p, v, b) = local(s);
        for r in 0..N {
            fs[p[r] as usize] += v[r];
            for c in 0..N {
                ms.add(p[r] as usize, p[c] as usize, b[r][c]);
            }
        }
    }
    match how {
        Accumulate::Each => {
            f.copy_from_slice(&fs);
            m.values.copy_from_slice(&ms.values);
        }
        Accumulate::Sum => {
            f.iter_mut().zip(&fs).for_each(|(a, b)| *a += *b);
            m.values
                .iter_mut()
                .zip(&ms.values)
                .for_each(|(a, b)| *a += *b);
        }
    }
}

fn same_vectors(a: &[Vec3], b: &[Vec3]) -> bool {
    a.iter()
        .zip(b)
        .all(|(p, q)| p.to_array().map(f64::to_bits) == q.to_array().map(f64::to_bits))
}

fn same_matrix(a: &BlockMatrix, b: &BlockMatrix) -> bool {
    let bits = |m: &Mat3| m.to_cols_array().map(f64::to_bits);
    a.values
        .iter()
        .zip(&b.values)
        .all(|(p, q)| bits(p) == bits(q))
}

/// Positions, velocities and a product vector for the test particles, from `seed`.
fn state(seed: f64) -> (Vec<Vec3>, Vec<Vec3>, Vec<Vec3>) {
    let v = |k: f64| -> Vec<Vec3> {
        (0..PARTICLES_N)
            .map(|i| {
                let q = i as f64 + k * seed;
                Vec3::new(q.sin(), (1.3 * q).cos(), 0.1 * q - 0.4)
            })
            .collect()
    };
    (v(1.0), v(2.0), v(3.0))
}

/// Non-zero starting values (so that `Sum` and `Each` differ), one per particle and block.
fn start(m: &mut BlockMatrix, seed: f64) -> Vec<Vec3> {
    for (k, b) in m.values.iter_mut().enumerate() {
        *b = block(seed * k as f64, 1e-3, -(k as f64), 1e5 * seed);
    }
    (0..PARTICLES_N)
        .map(|i| Vec3::new(1e5 * seed, -(i as f64), 1e-7 * i as f64))
        .collect()
}

/// Checks force, matrix and product of `force` against [`serial`] on one and two threads, and
/// the fused linearization against the separate calls.
fn check<F, const N: usize>(force: &F, seed: f64) -> Result<(), TestCaseError>
where
    F: StencilForce<Shape = Full<N>>,
{
    let (x, v, w) = state(seed);
    let st = at(&x, &v);
    let (a, b) = (0.7 - seed, -1.3 * seed);
    let mut pairs = Vec::new();
    force.add_pattern(&mut pairs);
    let mut m_ref = BlockMatrix::from_pairs(PARTICLES_N, &pairs);
    let f0 = start(&mut m_ref, seed);
    let m0 = m_ref.clone();
    let (mut f_ref, mut out_ref, mut unused) = (f0.clone(), f0.clone(), m0.clone());
    let how = force.accumulate();
    let count = force.count();
    let local = |s: usize| {
        (
            force.particles(s),
            force.local_force(s, &st),
            force.local_jacobian(s, &st, a, b),
        )
    };
    serial(how, count, local, &mut f_ref, &mut m_ref);
    let product = |s: usize| {
        let p = force.particles(s);
        (
            p,
            force.local_product(s, &st, a, b, &w),
            Full::<N>::ZERO_BLOCKS,
        )
    };
    serial(how, count, product, &mut out_ref, &mut unused);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (mut f, mut out, mut m) = (f0.clone(), f0.clone(), m0.clone());
        pool.install(|| {
            force.add_force(&st, &mut f);
            force.add_jacobian(&st, a, b, &mut m);
            force.add_jacobian_product(&st, a, b, &w, &mut out);
        });
        prop_assert!(same_vectors(&f, &f_ref), "{threads} threads: force");
        prop_assert!(same_matrix(&m, &m_ref), "{threads} threads: matrix");
        prop_assert!(same_vectors(&out, &out_ref), "{threads} threads: product");
        let lin = Linearization {
            t: T,
            x: &x,
            v: &v,
            matrix: (a, b),
            product: (b, a),
            w: &w,
        };
        let fused = pool.install(|| linearization_is_bitwise_separate(force, &lin, &f0));
        prop_assert!(fused, "{threads} threads: linearization");
    }
    Ok(())
}

fn how() -> impl Strategy<Value = Accumulate> {
    prop_oneof![Just(Accumulate::Sum), Just(Accumulate::Each)]
}

proptest! {
    /// Pairs, triangles and hinges (stored in full), with particles repeated within and across
    /// stencils.
    #[test]
    fn stencils_sum_as_the_serial_loop(
        pairs in prop::collection::vec(prop::array::uniform2(0..PARTICLES_N as u32), 0..40),
        triangles in prop::collection::vec(prop::array::uniform3(0..PARTICLES_N as u32), 0..40),
        hinges in prop::collection::vec(prop::array::uniform4(0..PARTICLES_N as u32), 0..40),
        how in how(),
        seed in 0.0..1.0f64,
    ) {
        check(&Made::new(pairs, how), seed)?;
        check(&Made::new(triangles, how), seed)?;
        check(&Made::new(hinges, how), seed)?;
    }

    /// The compact pairs against their expanded form (itself checked against the serial loop),
    /// pairs with both ends on one particle included.
    #[test]
    fn compact_pairs_have_the_bits_of_the_expanded_pairs(
        s in prop::collection::vec(prop::array::uniform2(0..PARTICLES_N as u32), 0..40),
        how in how(),
        seed in 0.0..1.0f64,
    ) {
        let pairs = MadePair { stencils: s, how, sums: Gather::default() };
        let expanded = Expanded(MadePair { sums: Gather::default(), ..pairs }, Gather::default());
        check(&expanded, seed)?;
        let pairs = &expanded.0;
        let (x, v, w) = state(seed);
        let st = at(&x, &v);
        let (a, b) = (seed, 1.0 - seed);
        let mut pattern = Vec::new();
        pairs.add_pattern(&mut pattern);
        let mut m1 = BlockMatrix::from_pairs(PARTICLES_N, &pattern);
        let f1 = start(&mut m1, seed);
        let (mut m2, mut f2, mut o1, mut o2) = (m1.clone(), f1.clone(), f1.clone(), f1.clone());
        let mut f1 = f1;
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                pairs.add_force(&st, &mut f1);
                pairs.add_jacobian(&st, a, b, &mut m1);
                pairs.add_jacobian_product(&st, a, b, &w, &mut o1);
                expanded.add_force(&st, &mut f2);
                expanded.add_jacobian(&st, a, b, &mut m2);
                expanded.add_jacobian_product(&st, a, b, &w, &mut o2);
            });
            prop_assert!(same_vectors(&f1, &f2));
            prop_assert!(same_matrix(&m1, &m2));
            prop_assert!(same_vectors(&o1, &o2));
        }
        let lin = Linearization { t: T, x: &x, v: &v, matrix: (a, b), product: (b, a), w: &w };
        prop_assert!(linearization_is_bitwise_separate(pairs, &lin, &f1));
    }
}

/// The force, not the separate calls, skips what it has no Jacobian for: a force without one
/// leaves the matrix and the product alone (not even `-0.0` turned into `0.0`).
#[test]
fn no_jacobian_leaves_the_matrix_and_the_product_untouched() {
    struct Still(MadePair);
    impl StencilForce for Still {
        type Shape = Pair;
        const NAME: &'static str = "still";
        fn gather(&self) -> &Gather<Pair> {
            &self.0.sums
        }
        fn count(&self) -> usize {
            self.0.count()
        }
        fn particles(&self, s: usize) -> [u32; 2] {
            self.0.particles(s)
        }
        fn local_force(&self, s: usize, at: &State) -> Vec3 {
            self.0.local_force(s, at)
        }
        fn has_jacobian(&self, _a: f64, _b: f64) -> bool {
            false
        }
        fn local_jacobian(&self, _s: usize, _at: &State, _a: f64, _b: f64) -> Mat3 {
            Mat3::ZERO
        }
    }
    let force = Still(MadePair {
        stencils: vec![[0, 1], [1, 2]],
        how: Accumulate::Sum,
        sums: Gather::default(),
    });
    let (x, v, w) = state(0.3);
    let mut pairs = Vec::new();
    force.add_pattern(&mut pairs);
    let mut m = BlockMatrix::from_pairs(PARTICLES_N, &pairs);
    m.values.fill(Mat3::from_cols_array(&[-0.0; 9]));
    let mut out = vec![Vec3::splat(-0.0); PARTICLES_N];
    let mut f = vec![Vec3::ZERO; PARTICLES_N];
    let lin = Linearization {
        t: T,
        x: &x,
        v: &v,
        matrix: (1.0, 1.0),
        product: (1.0, 1.0),
        w: &w,
    };
    force.add_linearization(&lin, &mut f, &mut m, &mut out);
    assert!(
        m.values
            .iter()
            .flat_map(|b| b.to_cols_array())
            .all(|e| e.to_bits() == (-0.0f64).to_bits())
    );
    assert!(
        out.iter()
            .flat_map(|p| p.to_array())
            .all(|e| e.to_bits() == (-0.0f64).to_bits())
    );
    let st = at(&x, &v);
    assert_eq!(f[0], pair_vector(0, &st, [0, 1]));
    assert_eq!(f[2], -pair_vector(1, &st, [1, 2]));
}

#[test]
fn a_new_pattern_rebuilds_the_block_lists() {
    let force = Made::<2>::new(vec![[0, 1]], Accumulate::Sum);
    let x = [Vec3::ZERO; 3];
    let st = at(&x, &x);
    let mut small = BlockMatrix::from_pairs(3, &[(0, 1)]);
    force.add_jacobian(&st, 0.0, 0.0, &mut small);
    let mut big = BlockMatrix::from_pairs(3, &[(0, 1), (1, 2), (0, 2)]);
    force.add_jacobian(&st, 0.0, 0.0, &mut big);
    let expect = |r: usize, c: usize| block(0.0, 0.0, (r * 2 + c) as f64, 0.0);
    assert_eq!(big.values[big.find(0, 1).unwrap()], expect(0, 1));
    assert_eq!(big.values[big.find(1, 1).unwrap()], expect(1, 1));
    assert_eq!(big.values[big.find(1, 2).unwrap()], Mat3::ZERO);
    assert_eq!(big.values[big.find(2, 2).unwrap()], Mat3::ZERO);
}
