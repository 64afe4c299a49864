//! Repulsion between cloth and the sharp features of mesh colliders (docs/MATH.md §24), as a
//! force in the implicit solve.
//!
//! Each stencil ([`ObstacleProximity`]) holds up to three cloth particles with fixed weights and
//! one kinematic collider point `q`: with `u = Σ wᵢ xᵢ - q`, `d = |u|`, the penalty is the
//! cloth–cloth one (§4), `E = ½ k (η - d)²` for `d < η`, from
//! [`crate::collision::repulsion::repulsion`] with `q` as a fourth point of weight `-1`. Only the
//! cloth particles get forces and Jacobian blocks (`wᵢ wⱼ J` among them); the collider takes the
//! reaction. As for cloth–cloth repulsion the tangential term is left out of the matrix, so
//! `-K` stays positive semi-definite, and the force is exact.
//!
//! Friction is a tangential damping in the solve: `fᵢ = -c wᵢ (I - n nᵀ)(Σ wⱼ vⱼ - v_q)` with the
//! stencil's coefficient `c` and its normal at the start of the step, linear in `v`, its
//! `∂f/∂v = -c (w wᵀ) ⊗ (I - n nᵀ)` symmetric negative semi-definite (in the matrix as it is),
//! its dissipation potential `½ c |(I - n nᵀ)(Σ wⱼ vⱼ - v_q)|²`. The coefficient is a lagged
//! Coulomb one ([`lagged_coulomb`]): `c = μN / max(SLIP, |u_t|)` with the sliding speed `|u_t|`
//! at the start of the step, so that at that speed the force is the Coulomb force `μN`, never
//! more.

use super::stencil::{Full, Gather, Local, StencilForce};
use super::{Linearization, State};
use crate::collision::obstacle_proximity::ObstacleProximity;
use crate::collision::repulsion::{Penalty, Repulsion, repulsion};
use crate::math::{Mat3, Vec3, tangent_projector};

/// The cloth–collider stencils of a step, sharing one penalty.
#[derive(Clone, Debug)]
pub struct ObstacleRepulsions {
    /// The close pairs found at the start of the step.
    pub stencils: Vec<ObstacleProximity>,
    /// Thickness and stiffness (`tangential` is ignored: never in the matrix).
    pub penalty: Penalty,
    /// Gather lists for the parallel sums.
    pub sums: Gather<Full<3>>,
}

impl ObstacleRepulsions {
    /// The repulsion of `stencils` under `penalty`.
    pub fn new(stencils: Vec<ObstacleProximity>, penalty: Penalty) -> Self {
        ObstacleRepulsions {
            stencils,
            penalty,
            sums: Gather::default(),
        }
    }

    /// The penalty of stencil `s` at `x`, with the tangential term of the Jacobian or without.
    pub fn eval(&self, s: usize, x: &[Vec3], tangential: bool) -> Repulsion {
        let st = &self.stencils[s];
        let (p, w) = st.stencil(x);
        let penalty = Penalty {
            tangential,
            ..self.penalty
        };
        repulsion(&p, &w, &penalty, st.normal)
    }
}

/// The sliding speed (m/s) below which the friction of a cloth–collider pair is viscous: its
/// coefficient stops growing there (docs/MATH.md §24).
pub(crate) const SLIP: f64 = 1e-3;

/// The damping coefficient (N·s/m) of lagged Coulomb friction with the Coulomb force `mu_n`
/// (`μN`, N) and the sliding speed `slide` (m/s) at the start of the step: `μN / max(SLIP,
/// slide)`. At the starting speed the force `c |u_t|` is `μN` above `SLIP` and `μN |u_t|/SLIP`
/// below (docs/MATH.md §24).
pub(crate) fn lagged_coulomb(mu_n: f64, slide: f64) -> f64 {
    mu_n / slide.max(SLIP)
}

/// The sliding velocity `(I - n nᵀ)(Σ wᵢ vᵢ - v_q)` of stencil `st`.
pub(crate) fn sliding(st: &ObstacleProximity, v: &[Vec3]) -> Vec3 {
    let u: Vec3 = (0..3)
        .map(|a| v[st.particles[a] as usize] * st.weights[a])
        .sum();
    tangent_projector(st.normal) * (u - st.velocity)
}

/// The cloth particles' forces: the penalty's and the damping `-c wᵢ (I - n nᵀ) u`.
fn cloth_forces(r: &Repulsion, st: &ObstacleProximity, v: &[Vec3]) -> [Vec3; 3] {
    let damp = sliding(st, v) * (-st.damping);
    std::array::from_fn(|i| r.forces[i] + damp * st.weights[i])
}

/// The blocks among the cloth particles of `a ∂f/∂x + b ∂f/∂v`.
fn cloth_blocks(r: &Repulsion, st: &ObstacleProximity, a: f64, b: f64) -> [[Mat3; 3]; 3] {
    let d = tangent_projector(st.normal) * (-b * st.damping);
    let w = st.weights;
    std::array::from_fn(|i| std::array::from_fn(|j| a * r.jac[i][j] + d * (w[i] * w[j])))
}

impl StencilForce for ObstacleRepulsions {
    type Shape = Full<3>;
    const NAME: &'static str = "obstacle repulsion";
    fn gather(&self) -> &Gather<Full<3>> {
        &self.sums
    }
    fn count(&self) -> usize {
        self.stencils.len()
    }
    fn particles(&self, s: usize) -> [u32; 3] {
        self.stencils[s].particles
    }
    fn local_energy(&self, s: usize, _t: f64, x: &[Vec3]) -> f64 {
        self.eval(s, x, false).energy
    }
    fn local_dissipation(&self, s: usize, at: &State) -> f64 {
        let st = &self.stencils[s];
        0.5 * st.damping * sliding(st, at.v).length_squared()
    }
    fn local_force(&self, s: usize, at: &State) -> [Vec3; 3] {
        cloth_forces(&self.eval(s, at.x, false), &self.stencils[s], at.v)
    }
    fn local_jacobian(&self, s: usize, at: &State, a: f64, b: f64) -> [[Mat3; 3]; 3] {
        cloth_blocks(&self.eval(s, at.x, false), &self.stencils[s], a, b)
    }
    /// One penalty evaluation per stencil for the force, the product and the matrix.
    fn local(&self, s: usize, at: &Linearization, _product: bool, _matrix: bool) -> Local<Full<3>> {
        use super::stencil::Shape;
        let (r, st) = (self.eval(s, at.x, false), &self.stencils[s]);
        let ((am, bm), (ap, bp)) = (at.matrix, at.product);
        let product = cloth_blocks(&r, st, ap, bp);
        Local {
            force: cloth_forces(&r, st, at.v),
            product: Full::<3>::product(&product, st.particles, at.w),
            matrix: cloth_blocks(&r, st, am, bm),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Force;
    use super::super::testing::*;
    use super::*;
    use crate::collision::obstacle_proximity::ObstacleStencilKind;
    use crate::linalg::BlockMatrix;
    use proptest::prelude::*;

    fn vec3(r: f64) -> impl Strategy<Value = Vec3> {
        (-r..r, -r..r, -r..r).prop_map(|(a, b, c)| Vec3::new(a, b, c))
    }

    const PENALTY: Penalty = Penalty {
        thickness: 0.05,
        stiffness: 300.0,
        tangential: false,
    };

    /// A vertex–triangle stencil on particles 0, 1, 2 and an edge–edge one on 3, 1 (sharing
    /// particle 1), their collider points placed at the distances `d` (a fraction of `η`) along
    /// random directions from the cloth points.
    fn stencils(
        x: &[Vec3],
        bary: [f64; 3],
        s: f64,
        dirs: [Vec3; 2],
        d: [f64; 2],
    ) -> Option<Vec<ObstacleProximity>> {
        let sum: f64 = bary.iter().sum();
        let bary = bary.map(|b| b / sum);
        let mut out = Vec::new();
        let defs = [
            (ObstacleStencilKind::VertexTriangle, [0u32, 1, 2], bary),
            (ObstacleStencilKind::EdgeEdge, [3, 1, 3], [1.0 - s, s, 0.0]),
        ];
        for (k, (kind, particles, weights)) in defs.into_iter().enumerate() {
            if dirs[k].length() < 1e-3 {
                return None;
            }
            let n = dirs[k].normalize();
            let p: Vec3 = (0..3).map(|i| x[particles[i] as usize] * weights[i]).sum();
            out.push(ObstacleProximity {
                kind,
                particles,
                weights,
                point: p - n * (d[k] * PENALTY.thickness),
                dist: d[k] * PENALTY.thickness,
                normal: n,
                obstacle: 0,
                velocity: Vec3::ZERO,
                damping: 0.0,
            });
        }
        Some(out)
    }

    proptest! {
        /// Force = -∇E, and the Jacobian with its tangential term equals central differences of
        /// the force; what enters the matrix is symmetric and negative semi-definite, and the
        /// product is the matrix's.
        #[test]
        fn force_is_minus_the_energy_gradient_and_the_jacobian_matches_differences(
            x in prop::collection::vec(vec3(0.02), 4),
            bary in prop::array::uniform3(0.05..1.0f64),
            s in 0.1..0.9f64,
            dirs in prop::array::uniform2(vec3(1.0)),
            d in prop::array::uniform2(0.1..0.9f64),
        ) {
            let Some(st) = stencils(&x, bary, s, dirs, d) else { return Ok(()) };
            let rep = ObstacleRepulsions::new(st.clone(), PENALTY);
            let mut f = vec![Vec3::ZERO; 4];
            rep.add_force(&at(&x, &x), &mut f);
            let fd = fd_gradient(&rep, &x);
            let scale = f.iter().fold(1e-3f64, |m, v| m.max(v.length()));
            for i in 0..4 {
                prop_assert!((f[i] - fd[i]).length() < 1e-5 * scale, "{i}: {} vs {}", f[i], fd[i]);
            }
            let with_tangent = {
                let mut pairs = Vec::new();
                rep.add_pattern(&mut pairs);
                let mut m = BlockMatrix::from_pairs(4, &pairs);
                for s in 0..st.len() {
                    let r = rep.eval(s, &x, true);
                    let p = st[s].particles;
                    for a in 0..3 {
                        for b in 0..3 {
                            m.add(p[a] as usize, p[b] as usize, r.jac[a][b]);
                        }
                    }
                }
                m.to_dense()
            };
            let fdj = fd_jacobian(&rep, &x, &x, false);
            prop_assert!(rel_diff(&with_tangent, &fdj) < 1e-5, "{}", rel_diff(&with_tangent, &fdj));
            let k = assembled(&rep, &x, &x, 1.0, 0.0);
            for r in 0..12 {
                for c in 0..12 {
                    prop_assert!((k[r][c] - k[c][r]).abs() <= 1e-12 * PENALTY.stiffness);
                }
            }
            let w: Vec<f64> = (0..12).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
            let q: f64 = (0..12).map(|r| (0..12).map(|c| w[r] * k[r][c] * w[c]).sum::<f64>()).sum();
            prop_assert!(q <= 1e-9);
            prop_assert!(check_product(&rep, &x, &x, 1.0, 0.0, &x) < 1e-12);
        }

        /// The tangential damping: `∂f/∂v` in the matrix equals central differences of the force
        /// in `v` (exact: the force is linear in `v`), is symmetric negative semi-definite, has
        /// no normal part, and the force is minus the gradient of the dissipation potential.
        #[test]
        fn damping_jacobian_matches_differences_and_dissipates(
            x in prop::collection::vec(vec3(0.02), 4),
            v in prop::collection::vec(vec3(1.0), 4),
            bary in prop::array::uniform3(0.05..1.0f64),
            s in 0.1..0.9f64,
            dirs in prop::array::uniform2(vec3(1.0)),
            c in 0.1..10.0f64,
            vq in vec3(1.0),
        ) {
            let Some(mut st) = stencils(&x, bary, s, dirs, [1.5, 1.5]) else { return Ok(()) };
            for p in &mut st { p.damping = c; p.velocity = vq; }
            let rep = ObstacleRepulsions::new(st.clone(), PENALTY);
            let d = assembled(&rep, &x, &v, 0.0, 1.0);
            let fd = fd_jacobian_step(&rep, &x, &v, true, 1.0);
            prop_assert!(rel_diff(&d, &fd) < 1e-9, "{}", rel_diff(&d, &fd));
            let w: Vec<f64> = (0..12).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
            let q: f64 = (0..12).map(|r| (0..12).map(|k| w[r] * d[r][k] * w[k]).sum::<f64>()).sum();
            prop_assert!(q <= 1e-9);
            for r in 0..12 { for k in 0..12 { prop_assert!((d[r][k] - d[k][r]).abs() <= 1e-12 * c); } }
            // -∂Ψ/∂v = f (the penalty is inactive at 1.5 η: the force is the damping alone)
            let mut f = vec![Vec3::ZERO; 4];
            rep.add_force(&at(&x, &v), &mut f);
            let g = fd_dissipation_force(&rep, &x, &v);
            for i in 0..4 {
                for k in 0..3 {
                    prop_assert!((g[i][k] - f[i][k]).abs() <= 1e-6 * (1.0 + f[i][k].abs()), "{} vs {}", g[i][k], f[i][k]);
                }
            }
            // no normal force: each stencil's total damping force is tangential
            for one in &st {
                let rep = ObstacleRepulsions::new(vec![*one], PENALTY);
                let mut f = vec![Vec3::ZERO; 4];
                rep.add_force(&at(&x, &v), &mut f);
                let total: Vec3 = f.iter().sum();
                prop_assert!(total.dot(one.normal).abs() <= 1e-9 * (1.0 + total.length()));
            }
        }

        /// Lagged Coulomb friction, each stencil's coefficient `lagged_coulomb(μ k (η - d₀),
        /// |u_t(v₀)|)` from a starting velocity `v₀` whose sliding speeds span 10⁻⁵ to 10 m/s:
        /// with the lag frozen, `∂f/∂v` in the matrix equals central differences of the force
        /// in `v` (at any `v`); the damping force (the force less its value with every particle
        /// moving with the collider point) does no positive work in the collider's frame,
        /// `Σ fᵢ·(vᵢ - v_q) ≤ 0`; and at `v = v₀` its total is at most `μN`, and equals `μN`
        /// whenever the sliding speed is at least `SLIP`. The viscous coefficient `μN / SLIP`
        /// the branch had before gives `μN |u_t| / SLIP` there: above `μN` at any speed over
        /// `SLIP` (asserted too).
        #[test]
        fn lagged_coulomb_friction_dissipates_and_never_exceeds_the_coulomb_force(
            x in prop::collection::vec(vec3(0.02), 4),
            v0 in prop::collection::vec(vec3(1.0), 4),
            v in prop::collection::vec(vec3(1.0), 4),
            bary in prop::array::uniform3(0.05..1.0f64),
            s in 0.1..0.9f64,
            dirs in prop::array::uniform2(vec3(1.0)),
            d in prop::array::uniform2(0.0..0.95f64),
            mu in 0.05..1.0f64,
            vq in vec3(1.0),
            decade in -5.0..1.0f64,
        ) {
            let Some(st) = stencils(&x, bary, s, dirs, d) else { return Ok(()) };
            let scale = 10f64.powf(decade);
            let (v0, vq): (Vec<Vec3>, Vec3) = (v0.iter().map(|u| *u * scale).collect(), vq * scale);
            for mut one in st {
                one.velocity = vq;
                let mu_n = mu * PENALTY.stiffness * (PENALTY.thickness - one.dist);
                let slide = sliding(&one, &v0).length();
                one.damping = lagged_coulomb(mu_n, slide);
                let rep = ObstacleRepulsions::new(vec![one], PENALTY);
                // the Jacobian in v, the lag frozen
                let dv = assembled(&rep, &x, &v, 0.0, 1.0);
                let fd = fd_jacobian_step(&rep, &x, &v, true, 1.0);
                prop_assert!(rel_diff(&dv, &fd) < 1e-9, "{}", rel_diff(&dv, &fd));
                // the damping force of `rep` at velocities `w`
                let damping = |rep: &ObstacleRepulsions, w: &[Vec3]| {
                    let (mut f, mut f_rest) = (vec![Vec3::ZERO; 4], vec![Vec3::ZERO; 4]);
                    rep.add_force(&at(&x, w), &mut f);
                    rep.add_force(&at(&x, &[vq; 4]), &mut f_rest);
                    (0..4).map(|i| f[i] - f_rest[i]).collect::<Vec<Vec3>>()
                };
                for w in [&v, &v0] {
                    let f = damping(&rep, w);
                    let power: f64 = (0..4).map(|i| f[i].dot(w[i] - vq)).sum();
                    let size: f64 = (0..4).map(|i| f[i].length() * (w[i] - vq).length()).sum();
                    prop_assert!(power <= 1e-12 * size, "power {power}");
                }
                let total: Vec3 = damping(&rep, &v0).iter().sum();
                prop_assert!(total.length() <= mu_n * (1.0 + 1e-9), "{} > μN {mu_n}", total.length());
                if slide >= SLIP {
                    prop_assert!((total.length() - mu_n).abs() <= 1e-9 * mu_n);
                }
                // the old viscous law, c = μN / SLIP, exceeds μN at any sliding over SLIP
                let old = ObstacleRepulsions::new(vec![ObstacleProximity { damping: mu_n / SLIP, ..one }], PENALTY);
                let total_old: Vec3 = damping(&old, &v0).iter().sum();
                if slide > 1.01 * SLIP {
                    prop_assert!(total_old.length() > 1.009 * mu_n, "{} vs μN {mu_n}", total_old.length());
                }
            }
        }

        /// The cloth's forces add up to `k (η - d) n`, pushing it away from the collider point
        /// along the separation, and act at the cloth point: their moment about it vanishes (the
        /// collider takes the opposite force at the same place).
        #[test]
        fn forces_push_the_cloth_point_straight_away_from_the_collider(
            x in prop::collection::vec(vec3(0.02), 4),
            bary in prop::array::uniform3(0.05..1.0f64),
            s in 0.1..0.9f64,
            dirs in prop::array::uniform2(vec3(1.0)),
            d in prop::array::uniform2(0.0..1.2f64),
        ) {
            let Some(st) = stencils(&x, bary, s, dirs, d) else { return Ok(()) };
            for (k, one) in st.iter().enumerate() {
                let rep = ObstacleRepulsions::new(vec![*one], PENALTY);
                let mut f = vec![Vec3::ZERO; 4];
                rep.add_force(&at(&x, &x), &mut f);
                let total: Vec3 = f.iter().sum();
                let gap = (PENALTY.thickness - d[k] * PENALTY.thickness).max(0.0);
                let want = one.normal * (PENALTY.stiffness * gap);
                let tol = 1e-9 * PENALTY.stiffness * PENALTY.thickness;
                prop_assert!((total - want).length() <= tol, "{total} vs {want}");
                let p: Vec3 = (0..3).map(|i| x[one.particles[i] as usize] * one.weights[i]).sum();
                let moment: Vec3 = (0..4).map(|i| (x[i] - p).cross(f[i])).sum();
                prop_assert!(moment.length() <= tol * 0.1);
            }
        }
    }
}
