//! Stitches (seams), docs/MATH.md §2.1: each stitched pair `(a, b)` is pulled together by a
//! zero-rest-length spring of stiffness `k` with damping `c` of the pair's relative velocity.
//!
//! `d = x_a - x_b`, `u = v_a - v_b`: `E = ½ k |d|²`, `Ψ = ½ c |u|²`, `f_a = -k d - c u = -f_b`.
//! The Jacobians are constant: `∂f_a/∂x_a = -k I`, `∂f_a/∂v_a = -c I` (and `+k I`, `+c I` for
//! `∂f_a/∂x_b`, `∂f_a/∂v_b`), so `-K` is positive semi-definite at every configuration and the
//! implicit step closes a seam stably whatever the step size. With zero rest length a closed
//! seam has no direction, so the damping acts on the whole relative velocity, not along a
//! direction.

use super::State;
use super::stencil::{Accumulate, Gather, Pair, StencilForce};
use crate::math::{Mat3, Vec3};

/// Default stitch stiffness, N/m: as stiff as the default stretch springs, so a seam closes in
/// a few tenths of a second and stays closed to well under a millimetre under cloth forces.
pub const DEFAULT_STIFFNESS: f64 = 1000.0;

/// Default stitch damping, N·s/m (none: the cloth's own damping and the implicit step suffice).
pub const DEFAULT_DAMPING: f64 = 0.0;

/// A set of stitched pairs, in global particle indices.
#[derive(Clone, Debug, Default)]
pub struct Stitches {
    /// First particle of each pair.
    pub a: Vec<u32>,
    /// Second particle.
    pub b: Vec<u32>,
    /// Stiffness, N/m.
    pub k: Vec<f64>,
    /// Damping of the relative velocity, N·s/m.
    pub c: Vec<f64>,
    /// Gather lists for the parallel sums (build with `Gather::default()`).
    pub sums: Gather<Pair>,
}

impl Stitches {
    /// `x_a - x_b` of pair `s` in `x`.
    #[inline]
    fn gap(&self, s: usize, x: &[Vec3]) -> Vec3 {
        x[self.a[s] as usize] - x[self.b[s] as usize]
    }
}

impl StencilForce for Stitches {
    type Shape = Pair;
    const NAME: &'static str = "stitches";
    fn gather(&self) -> &Gather<Pair> {
        &self.sums
    }
    fn count(&self) -> usize {
        self.a.len()
    }
    fn particles(&self, s: usize) -> [u32; 2] {
        [self.a[s], self.b[s]]
    }
    fn accumulate(&self) -> Accumulate {
        Accumulate::Sum
    }
    fn local_energy(&self, s: usize, _t: f64, x: &[Vec3]) -> f64 {
        0.5 * self.k[s] * self.gap(s, x).length_squared()
    }
    fn local_dissipation(&self, s: usize, at: &State) -> f64 {
        0.5 * self.c[s] * self.gap(s, at.v).length_squared()
    }
    fn local_force(&self, s: usize, at: &State) -> Vec3 {
        -self.k[s] * self.gap(s, at.x) - self.c[s] * self.gap(s, at.v)
    }
    fn has_jacobian(&self, a: f64, b: f64) -> bool {
        a != 0.0 || b != 0.0
    }
    /// The block `(a, a)` of `a ∂f/∂x + b ∂f/∂v`: `-(a k + b c) I`.
    fn local_jacobian(&self, s: usize, _at: &State, a: f64, b: f64) -> Mat3 {
        Mat3::from_diagonal(Vec3::splat(-(a * self.k[s] + b * self.c[s])))
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::super::{Force, Linearization};
    use super::*;
    use proptest::prelude::*;

    fn vec3() -> impl Strategy<Value = Vec3> {
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(a, b, c)| Vec3::new(a, b, c))
    }

    /// Five particles, stitches on a few pairs (one particle in several stitches, as where
    /// three panels meet), random stiffness and damping.
    fn config() -> impl Strategy<Value = (Vec<Vec3>, Vec<Vec3>, Stitches)> {
        (
            prop::collection::vec(vec3(), 5),
            prop::collection::vec(vec3(), 5),
            prop::collection::vec(0.1..5000.0f64, 4),
            prop::collection::vec(0.0..10.0f64, 4),
        )
            .prop_map(|(x, v, k, c)| {
                let pairs = [(0u32, 1u32), (2, 3), (3, 4), (4, 0)];
                let s = Stitches {
                    a: pairs.iter().map(|p| p.0).collect(),
                    b: pairs.iter().map(|p| p.1).collect(),
                    k,
                    c,
                    sums: Gather::default(),
                };
                (x, v, s)
            })
    }

    proptest! {
        #[test]
        fn stitch_force_at_rest_is_minus_energy_gradient((x, _v, s) in config()) {
            let rest = vec![Vec3::ZERO; x.len()];
            let mut f = vec![Vec3::ZERO; x.len()];
            s.add_force(&at(&x, &rest), &mut f);
            let fd = fd_gradient(&s, &x);
            let scale = f.iter().fold(1.0f64, |m, v| m.max(v.length()));
            for i in 0..x.len() {
                prop_assert!((f[i] - fd[i]).length() < 1e-6 * scale, "{:?} vs {:?}", f[i], fd[i]);
            }
        }

        #[test]
        fn stitch_jacobians_match_central_differences((x, v, s) in config(), a in -2.0..2.0f64, b in -2.0..2.0f64) {
            let kx = fd_jacobian(&s, &x, &v, false);
            let kv = fd_jacobian(&s, &x, &v, true);
            let fd: Vec<Vec<f64>> = kx
                .iter()
                .zip(&kv)
                .map(|(p, q)| p.iter().zip(q).map(|(p, q)| a * p + b * q).collect())
                .collect();
            let got = assembled(&s, &x, &v, a, b);
            prop_assert!(rel_diff(&got, &fd) < 1e-6, "rel diff {}", rel_diff(&got, &fd));
            prop_assert!(check_product(&s, &x, &v, a, b, &x) < 1e-12);
            let fused = linearized(&s, &x, &v, a, b);
            prop_assert!(rel_diff(&fused, &fd) < 1e-6, "rel diff {}", rel_diff(&fused, &fd));
        }

        /// `∂Ψ/∂v = -(damping part of f)`: the dissipation is the damping's potential.
        #[test]
        fn stitch_damping_is_minus_dissipation_gradient((x, v, s) in config()) {
            let mut f = vec![Vec3::ZERO; x.len()];
            s.add_force(&at(&x, &v), &mut f);
            let mut f0 = vec![Vec3::ZERO; x.len()];
            let rest = vec![Vec3::ZERO; x.len()];
            s.add_force(&at(&x, &rest), &mut f0);
            let mut vp = v.clone();
            for i in 0..x.len() {
                for d in 0..3 {
                    let e = 1e-6;
                    vp[i][d] = v[i][d] + e;
                    let p = s.dissipation(&at(&x, &vp));
                    vp[i][d] = v[i][d] - e;
                    let m = s.dissipation(&at(&x, &vp));
                    vp[i][d] = v[i][d];
                    let want = -(p - m) / (2.0 * e);
                    let got = f[i][d] - f0[i][d];
                    prop_assert!((got - want).abs() < 1e-6 * (1.0 + want.abs()), "{got} vs {want}");
                }
            }
        }

        #[test]
        fn stitch_linearization_has_the_bits_of_the_separate_calls(
            (x, v, s) in config(),
            a in -2.0..2.0f64,
            b in -2.0..2.0f64,
            w in prop::collection::vec(vec3(), 5),
        ) {
            let at = Linearization { t: T, x: &x, v: &v, matrix: (a, b), product: (b, a), w: &w };
            prop_assert!(linearization_is_bitwise_separate(&s, &at, &w));
        }

        /// `-K` is positive semi-definite everywhere: `wᵀ K w = -Σ k |w_a - w_b|² ≤ 0`.
        #[test]
        fn stitch_stiffness_matrix_is_negative_semidefinite((x, v, s) in config(), w in prop::collection::vec(vec3(), 5)) {
            let mut kw = vec![Vec3::ZERO; x.len()];
            s.add_jacobian_product(&at(&x, &v), 1.0, 0.0, &w, &mut kw);
            let q: f64 = w.iter().zip(&kw).map(|(a, b)| a.dot(*b)).sum();
            let want: f64 = (0..s.count())
                .map(|p| -s.k[p] * (w[s.a[p] as usize] - w[s.b[p] as usize]).length_squared())
                .sum();
            prop_assert!(q <= 1e-12 && (q - want).abs() <= 1e-9 * (1.0 + want.abs()), "wᵀKw = {q}, want {want}");
        }
    }

    /// A C-shaped sheet: `cols` columns around, `rows` rows down, neighbouring columns a chord
    /// `edge` apart on a circle of `cols` chords, so the gap between the first and last column
    /// is one chord. The seam stitches column `cols - 1` to column 0, row by row.
    fn open_tube(cols: usize, rows: usize, edge: f64) -> (crate::mesh::Mesh, Vec<u32>, Vec<u32>) {
        use std::f64::consts::PI;
        let mut mesh =
            crate::mesh::Mesh::grid([1.0, 1.0], [cols, rows], Vec3::ZERO, Vec3::Z).unwrap();
        let radius = edge / (2.0 * (PI / cols as f64).sin());
        for r in 0..rows {
            for c in 0..cols {
                let angle = 2.0 * PI * c as f64 / cols as f64;
                mesh.positions[r * cols + c] = Vec3::new(
                    radius * angle.cos(),
                    1.0 - edge * r as f64,
                    radius * angle.sin(),
                );
            }
        }
        let first = (0..rows).map(|r| (r * cols) as u32).collect();
        let last = (0..rows).map(|r| (r * cols + cols - 1) as u32).collect();
        (mesh, first, last)
    }

    /// The seam of a falling tube closes under implicit steps 20 ms long (a stitch of
    /// 1000 N/m on 5 g particles: `h √(k/m)` ≈ 9, far beyond an explicit step's limit of 2) and
    /// stays closed, with self-collision on and nothing intersecting.
    #[test]
    fn a_stitched_tube_closes_at_a_large_step_without_blowing_up() {
        use crate::collision::check::count_sewn_intersections;
        use crate::collision::settings::CollisionSettings;
        use crate::model::{ClothDesc, MassSpec, Material, Model, StitchDesc, StitchEnd};
        use crate::step::{Simulation, SolverSettings};
        let (cols, rows, edge) = (16, 8, 0.05);
        let (mesh, first, last) = open_tube(cols, rows, edge);
        let cloth = ClothDesc {
            name: "tube".into(),
            mesh,
            material: Material {
                mass: MassSpec::PerVertex(0.005),
                ..Material::default()
            },
            pins: vec![],
            initial_velocity: Vec3::ZERO,
            handles: vec![],
        };
        let side = |vertices: Vec<u32>| StitchEnd {
            cloth: "tube".into(),
            vertices,
        };
        let model = Model::new(vec![cloth], Vec3::new(0.0, -9.81, 0.0))
            .unwrap()
            .with_stitches(&[StitchDesc {
                a: side(last.clone()),
                b: side(first.clone()),
                stiffness: DEFAULT_STIFFNESS,
                damping: DEFAULT_DAMPING,
            }])
            .unwrap();
        let thickness = CollisionSettings::default().thickness;
        let model = model
            .with_collisions(CollisionSettings::default(), vec![])
            .unwrap();
        let tris = model.triangles();
        let seam: Vec<[u32; 2]> = model.stitches().iter().map(|p| [p.a, p.b]).collect();
        let springs = model.springs().clone();
        let mut sim = Simulation::new(model, SolverSettings::default()).unwrap();
        let gap = |x: &[Vec3]| {
            first
                .iter()
                .zip(&last)
                .map(|(&a, &b)| (x[a as usize] - x[b as usize]).length())
                .fold(0.0f64, f64::max)
        };
        assert!(gap(sim.positions()) > 0.99 * edge);
        for step in 0..50 {
            sim.step(0.02).unwrap();
            let x = sim.positions();
            // no blow-up: every spring within 30 % of its rest length
            for k in 0..springs.len() {
                let l = (x[springs.i[k] as usize] - x[springs.j[k] as usize]).length();
                assert!(
                    l.is_finite() && l < 1.3 * springs.rest[k].max(edge),
                    "step {step}: spring {k} at {l} m, rest {}",
                    springs.rest[k]
                );
            }
            assert_eq!(count_sewn_intersections(x, &tris, &seam), 0, "step {step}");
        }
        let g = gap(sim.positions());
        assert!(g < thickness, "widest stitched pair {g} m apart after 1 s");
    }
}
