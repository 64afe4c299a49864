//! Friction of the particles held against obstacles, as a force in the implicit solve
//! (docs/MATH.md §25).
//!
//! Each obstacle contact candidate `i` ([`ObstacleContact`]) with a friction coefficient gets
//! the tangential damping `fᵢ = -c (I - n nᵀ)(vᵢ - v_s)` toward the surface velocity `v_s`,
//! with the contact's normal `n` and coefficient `c` fixed at the start of the step: linear in
//! `v`, its `∂f/∂v = -c (I - n nᵀ)` a symmetric negative semi-definite diagonal block (so it
//! lands in the base matrix and the preconditioner), its dissipation potential
//! `½ c |(I - n nᵀ)(vᵢ - v_s)|²`. The coefficient is lagged Coulomb
//! ([`super::obstacle_repulsion::lagged_coulomb`]) with the normal force the contact's
//! constraint exerted in the previous step: at the starting sliding speed the force is `μN`.
//!
//! Being in the solve, the friction is felt by the cloth's elastic forces in the same
//! linear system: a particle that sticks to a moving surface pulls its neighbours through the
//! springs and membrane of the same step, instead of being set to the surface's velocity after
//! the solve while its neighbours are not (which displaced neighbours against each other by up
//! to `|v_s| h` per step, a strain that grows as the mesh gets finer).

use super::State;
use super::stencil::{Full, Gather, StencilForce};
use crate::constraints::obstacle::ObstacleContact;
use crate::math::{Mat3, Vec3, tangent_projector};

/// The in-solve friction of a step's obstacle contacts (those with a positive `damping`).
#[derive(Clone, Debug)]
pub struct ObstacleFrictions {
    /// The contacts, each with its damping coefficient `c` (N·s/m).
    pub contacts: Vec<ObstacleContact>,
    /// Gather lists for the parallel sums.
    pub sums: Gather<Full<1>>,
}

impl ObstacleFrictions {
    /// The friction of `contacts` (those with `damping` 0 add nothing).
    pub fn new(contacts: Vec<ObstacleContact>) -> Self {
        ObstacleFrictions {
            contacts,
            sums: Gather::default(),
        }
    }
}

/// The sliding velocity `(I - n nᵀ)(v - v_s)` of contact `c` for the particle's velocity `v`.
pub(crate) fn sliding(c: &ObstacleContact, v: Vec3) -> Vec3 {
    let u = v - c.surface_velocity;
    u - c.normal * c.normal.dot(u)
}

impl StencilForce for ObstacleFrictions {
    type Shape = Full<1>;
    const NAME: &'static str = "obstacle friction";
    fn gather(&self) -> &Gather<Full<1>> {
        &self.sums
    }
    fn count(&self) -> usize {
        self.contacts.len()
    }
    fn particles(&self, s: usize) -> [u32; 1] {
        [self.contacts[s].particle]
    }
    fn local_dissipation(&self, s: usize, at: &State) -> f64 {
        let c = &self.contacts[s];
        0.5 * c.damping * sliding(c, at.v[c.particle as usize]).length_squared()
    }
    fn local_force(&self, s: usize, at: &State) -> [Vec3; 1] {
        let c = &self.contacts[s];
        [sliding(c, at.v[c.particle as usize]) * (-c.damping)]
    }
    fn has_jacobian(&self, _a: f64, b: f64) -> bool {
        b != 0.0
    }
    fn local_jacobian(&self, s: usize, _at: &State, _a: f64, b: f64) -> [[Mat3; 1]; 1] {
        let c = &self.contacts[s];
        [[tangent_projector(c.normal) * (-b * c.damping)]]
    }
}

#[cfg(test)]
mod tests {
    use super::super::Force;
    use super::super::obstacle_repulsion::{SLIP, lagged_coulomb};
    use super::super::testing::*;
    use super::*;
    use proptest::prelude::*;

    fn vec3(r: f64) -> impl Strategy<Value = Vec3> {
        (-r..r, -r..r, -r..r).prop_map(|(a, b, c)| Vec3::new(a, b, c))
    }

    /// Contacts on particles 0 and 2 of three (particle 1 has none).
    fn contacts(normals: [Vec3; 2], vs: [Vec3; 2], c: [f64; 2]) -> Option<ObstacleFrictions> {
        let mut out = Vec::new();
        for (k, p) in [0u32, 2].into_iter().enumerate() {
            if normals[k].length() < 1e-3 {
                return None;
            }
            out.push(ObstacleContact {
                particle: p,
                normal: normals[k].normalize(),
                normal_velocity: 0.0,
                surface_velocity: vs[k],
                friction: 0.5,
                damping: c[k],
            });
        }
        Some(ObstacleFrictions::new(out))
    }

    proptest! {
        /// `∂f/∂v` in the matrix equals central differences of the force in `v` (exact: the force
        /// is linear in `v`), is symmetric negative semi-definite with no normal part, there is no
        /// `∂f/∂x`, the product is the matrix's, and the force is minus the gradient of the
        /// dissipation potential.
        #[test]
        fn jacobian_matches_differences_and_the_force_dissipates(
            x in prop::collection::vec(vec3(1.0), 3),
            v in prop::collection::vec(vec3(2.0), 3),
            normals in prop::array::uniform2(vec3(1.0)),
            vs in prop::array::uniform2(vec3(2.0)),
            c in prop::array::uniform2(0.01..10.0f64),
        ) {
            let Some(fr) = contacts(normals, vs, c) else { return Ok(()) };
            let d = assembled(&fr, &x, &v, 0.0, 1.0);
            let fd = fd_jacobian_step(&fr, &x, &v, true, 1.0);
            prop_assert!(rel_diff(&d, &fd) < 1e-9, "{}", rel_diff(&d, &fd));
            let k = assembled(&fr, &x, &v, 1.0, 0.0);
            prop_assert!(k.iter().flatten().all(|e| *e == 0.0));
            let fdx = fd_jacobian(&fr, &x, &v, false);
            prop_assert!(fdx.iter().flatten().all(|e| e.abs() < 1e-9));
            for r in 0..9 {
                for q in 0..9 {
                    prop_assert!((d[r][q] - d[q][r]).abs() <= 1e-12 * 10.0);
                }
            }
            let w: Vec<f64> = (0..9).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
            let q: f64 = (0..9).map(|r| (0..9).map(|s| w[r] * d[r][s] * w[s]).sum::<f64>()).sum();
            prop_assert!(q <= 1e-9);
            for ct in &fr.contacts {
                let i = 3 * ct.particle as usize;
                for col in 0..3 {
                    let dn: f64 = (0..3).map(|r| ct.normal[r] * d[i + r][i + col]).sum();
                    prop_assert!(dn.abs() <= 1e-12 * 10.0);
                }
            }
            prop_assert!(check_product(&fr, &x, &v, 0.3, -0.7, &x) < 1e-12);
            let mut f = vec![Vec3::ZERO; 3];
            fr.add_force(&at(&x, &v), &mut f);
            prop_assert_eq!(f[1], Vec3::ZERO);
            let g = fd_dissipation_force(&fr, &x, &v);
            for i in 0..3 {
                for k in 0..3 {
                    prop_assert!((g[i][k] - f[i][k]).abs() <= 1e-6 * (1.0 + f[i][k].abs()), "{} vs {}", g[i][k], f[i][k]);
                }
            }
        }

        /// With the lagged Coulomb coefficient of the normal force `N` and the starting velocity
        /// `v₀` (sliding speeds from 10⁻⁵ to 10 m/s): the force opposes the sliding (no positive
        /// work in the surface's frame), is at most `μN` at `v₀` and exactly `μN` there when the
        /// sliding speed is at least `SLIP`.
        #[test]
        fn lagged_coulomb_friction_is_the_coulomb_force_at_the_starting_speed(
            v0 in vec3(1.0),
            v in vec3(1.0),
            normal in vec3(1.0),
            vs in vec3(1.0),
            mu in 0.05..1.0f64,
            n_force in 1e-6..10.0f64,
            decade in -5.0..1.0f64,
        ) {
            prop_assume!(normal.length() > 1e-3);
            let scale = 10f64.powf(decade);
            let (v0, vs) = (v0 * scale, vs * scale);
            let mut ct = ObstacleContact {
                particle: 0,
                normal: normal.normalize(),
                normal_velocity: 0.0,
                surface_velocity: vs,
                friction: mu,
                damping: 0.0,
            };
            let slide = sliding(&ct, v0).length();
            ct.damping = lagged_coulomb(mu * n_force, slide);
            let fr = ObstacleFrictions::new(vec![ct]);
            let x = [Vec3::ZERO];
            for w in [v, v0] {
                let mut f = [Vec3::ZERO];
                fr.add_force(&at(&x, &[w]), &mut f);
                prop_assert!(f[0].dot(w - vs) <= 1e-12 * f[0].length() * (w - vs).length());
            }
            let mut f = [Vec3::ZERO];
            fr.add_force(&at(&x, &[v0]), &mut f);
            let mu_n = mu * n_force;
            prop_assert!(f[0].length() <= mu_n * (1.0 + 1e-9));
            if slide >= SLIP {
                prop_assert!((f[0].length() - mu_n).abs() <= 1e-9 * mu_n);
            }
        }
    }
}
