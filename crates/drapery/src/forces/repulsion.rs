//! Point–triangle and edge–edge repulsion (docs/MATH.md §4) as a force in the implicit solve.
//!
//! Each stencil holds four particles and fixed weights (barycentric for a vertex–triangle pair,
//! edge parameters for an edge–edge pair), chosen at the start of the step; the penalty
//! `E = ½ k (η - d)²` with `d = |Σ wᵢ xᵢ|` and its Jacobian come from
//! [`crate::collision::repulsion::repulsion`]. The tangential term is left out of the matrix
//! (so `-K` stays positive semi-definite) but the force is exact.

use super::stencil::{Full, Gather, Local, StencilForce};
use super::{Linearization, State};
use crate::collision::proximity::Proximity;
use crate::collision::repulsion::{Penalty, Repulsion, repulsion};
use crate::math::{Mat3, Vec3};

/// A set of contact stencils sharing one penalty.
#[derive(Clone, Debug)]
pub struct Repulsions {
    /// The close pairs found at the start of the step.
    pub stencils: Vec<Proximity>,
    /// Thickness and stiffness (`tangential` is ignored: never in the matrix).
    pub penalty: Penalty,
    /// Gather lists for the parallel sums (build with `Gather::default()`).
    pub sums: Gather<Full<4>>,
}

impl Repulsions {
    /// The repulsion of `stencils` under `penalty`.
    pub fn new(stencils: Vec<Proximity>, penalty: Penalty) -> Self {
        Repulsions {
            stencils,
            penalty,
            sums: Gather::default(),
        }
    }

    fn eval(&self, s: usize, x: &[Vec3]) -> Repulsion {
        let s = &self.stencils[s];
        let p = s.particles.map(|i| x[i as usize]);
        repulsion(
            &p,
            &s.weights,
            &Penalty {
                tangential: false,
                ..self.penalty
            },
            s.normal,
        )
    }

    /// `a J w` on stencil `s`, for its Jacobian blocks `jac`.
    fn product(&self, s: usize, jac: &[[Mat3; 4]; 4], a: f64, w: &[Vec3]) -> [Vec3; 4] {
        let particles = &self.stencils[s].particles;
        std::array::from_fn(|i| {
            let mut y = Vec3::ZERO;
            for (j, &q) in particles.iter().enumerate() {
                y += jac[i][j] * w[q as usize];
            }
            a * y
        })
    }
}

/// The stencil's Jacobian blocks times `a`.
fn scaled(jac: &[[Mat3; 4]; 4], a: f64) -> [[Mat3; 4]; 4] {
    jac.map(|row| row.map(|b| a * b))
}

/// Each particle and block takes the stencils' terms one by one ([`super::stencil::Accumulate::Each`]).
impl StencilForce for Repulsions {
    type Shape = Full<4>;
    const NAME: &'static str = "contact repulsion";
    fn gather(&self) -> &Gather<Full<4>> {
        &self.sums
    }
    fn count(&self) -> usize {
        self.stencils.len()
    }
    fn particles(&self, s: usize) -> [u32; 4] {
        self.stencils[s].particles
    }
    fn local_energy(&self, s: usize, _t: f64, x: &[Vec3]) -> f64 {
        self.eval(s, x).energy
    }
    fn local_force(&self, s: usize, at: &State) -> [Vec3; 4] {
        self.eval(s, at.x).forces
    }
    fn has_jacobian(&self, a: f64, _b: f64) -> bool {
        a != 0.0
    }
    fn local_jacobian(&self, s: usize, at: &State, a: f64, _b: f64) -> [[Mat3; 4]; 4] {
        scaled(&self.eval(s, at.x).jac, a)
    }
    fn local_product(&self, s: usize, at: &State, a: f64, _b: f64, w: &[Vec3]) -> [Vec3; 4] {
        self.product(s, &self.eval(s, at.x).jac, a, w)
    }
    /// One penalty evaluation per stencil for the force, the product and the matrix.
    fn local(&self, s: usize, at: &Linearization, _product: bool, _matrix: bool) -> Local<Full<4>> {
        let r = self.eval(s, at.x);
        Local {
            force: r.forces,
            product: self.product(s, &r.jac, at.product.0, at.w),
            matrix: scaled(&r.jac, at.matrix.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Force;
    use super::super::testing::*;
    use super::*;
    use crate::collision::proximity::StencilKind;
    use crate::collision::repulsion::{edge_edge_weights, point_triangle_weights};
    use crate::linalg::BlockMatrix;
    use proptest::prelude::*;

    fn vec3(r: f64) -> impl Strategy<Value = Vec3> {
        (-r..r, -r..r, -r..r).prop_map(|(a, b, c)| Vec3::new(a, b, c))
    }

    proptest! {
        /// Random vertex–triangle and edge–edge stencils sharing particles, close enough to be
        /// active: force = -∇E, and the matrix is the central difference of the force along the
        /// normal direction (the tangential term is left out of the matrix by design, so the check
        /// is on the normal part: K + tangential = FD).
        #[test]
        fn repulsion_force_is_minus_the_energy_gradient_and_its_jacobian_matches_differences(
            x in prop::collection::vec(vec3(0.01), 6), bary in prop::array::uniform3(0.05..1.0f64), s in 0.1..0.9f64, t in 0.1..0.9f64,
        ) {
            let sum: f64 = bary.iter().sum();
            let bary = bary.map(|b| b / sum);
            let stencils = vec![
                Proximity { kind: StencilKind::VertexTriangle, particles: [0, 1, 2, 3], weights: point_triangle_weights(bary), dist: 0.0, normal: Vec3::Z },
                Proximity { kind: StencilKind::EdgeEdge, particles: [4, 5, 1, 2], weights: edge_edge_weights(s, t), dist: 0.0, normal: Vec3::Z },
            ];
            let penalty = Penalty { thickness: 0.05, stiffness: 300.0, tangential: false };
            let rep = Repulsions::new(stencils.clone(), penalty);
            let mut f = vec![Vec3::ZERO; 6];
            rep.add_force(&at(&x, &x), &mut f);
            let fd = fd_gradient(&rep, &x);
            let scale = f.iter().fold(1e-3f64, |m, v| m.max(v.length()));
            for i in 0..6 { prop_assert!((f[i] - fd[i]).length() < 1e-5 * scale); }
            // the full Jacobian (with the tangential term) equals central differences of the force
            let with_tangent: Vec<Vec<f64>> = {
                let mut pairs = Vec::new();
                rep.add_pattern(&mut pairs);
                let mut m = BlockMatrix::from_pairs(6, &pairs);
                for st in &stencils {
                    let p = st.particles.map(|i| x[i as usize]);
                    let r = repulsion(&p, &st.weights, &Penalty { tangential: true, ..penalty }, st.normal);
                    for a in 0..4 { for b in 0..4 { m.add(st.particles[a] as usize, st.particles[b] as usize, r.jac[a][b]); } }
                }
                m.to_dense()
            };
            let fdj = fd_jacobian(&rep, &x, &x, false);
            prop_assert!(rel_diff(&with_tangent, &fdj) < 1e-5, "{}", rel_diff(&with_tangent, &fdj));
            // what goes into the matrix is symmetric and negative semi-definite
            let k = assembled(&rep, &x, &x, 1.0, 0.0);
            let w: Vec<f64> = (0..18).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
            let q: f64 = (0..18).map(|r| (0..18).map(|c| w[r] * k[r][c] * w[c]).sum::<f64>()).sum();
            prop_assert!(q <= 1e-9);
            prop_assert!(check_product(&rep, &x, &x, 1.0, 0.0, &x) < 1e-12);
        }
    }
}
