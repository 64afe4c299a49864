//! Coulomb friction of cloth–cloth contacts (vertex–triangle and edge–edge repulsion stencils),
//! applied to the velocities after the solve.
//!
//! A stencil (particles `xᵢ`, weights `wᵢ` summing to zero, unit normal `n`, see
//! [`super::repulsion`]) has the relative velocity `u = Σ wᵢ vᵢ` of its two closest points.
//! Its normal impulse over the step is estimated from the repulsion the implicit solve applied:
//! with the normal and weights fixed over the step, the linearized penalty force at the end
//! positions `x₁` is `k (η - n·Σ wᵢ x₁ᵢ)` along `n` (MATH.md §4; the Jacobian in the matrix is
//! `-k wwᵀ ⊗ nnᵀ`), so `jₙ = h k max(0, η - n·Σ wᵢ x₁ᵢ)`.
//!
//! Friction is a tangential impulse `P` (against the tangential part `uₜ` of `u`) given to the
//! particles in proportion to their weights and inverse masses, `Δvᵢ = wᵢ P / mᵢ`, which changes
//! `u` by `P Σ wᵢ²/mᵢ = P / m_eff`:
//!
//! * static: if `m_eff |uₜ| ≤ μ jₙ`, then `P = -m_eff uₜ`: the contact stops sliding;
//! * kinetic: otherwise `|P| = μ jₙ` against `uₜ`: the sliding slows down, never reverses.
//!
//! Since `Σ wᵢ = 0`, `Σ mᵢ Δvᵢ = P Σ wᵢ = 0`: linear momentum is conserved (a pinned particle
//! has infinite mass: it does not move and takes the momentum). The normal part of `u` is left
//! alone, and the kinetic energy never grows (`|P| ≤ m_eff |uₜ|`). Contacts are processed one
//! after the other in their (deterministic) order, each with the velocities left by the ones
//! before, so the result is the same whatever the number of threads.

use super::proximity::Proximity;
use super::repulsion::Penalty;
use crate::math::Vec3;

/// Applies Coulomb friction with coefficient `mu` to the cloth–cloth contact `stencils` of a
/// step of `h` seconds whose solve ended at positions `x` (see the module docs). `v` is updated
/// in place; pinned particles keep their velocity.
#[allow(clippy::too_many_arguments)]
pub fn apply_contact_friction(
    v: &mut [Vec3],
    x: &[Vec3],
    mass: &[f64],
    pinned: &[bool],
    stencils: &[Proximity],
    penalty: &Penalty,
    mu: f64,
    h: f64,
) {
    if !(mu > 0.0 && mu.is_finite() && h > 0.0) {
        return;
    }
    for s in stencils {
        let p = s.particles.map(|i| i as usize);
        let n = s.normal;
        let u: Vec3 = (0..4).map(|a| x[p[a]] * s.weights[a]).sum();
        let jn = h * penalty.stiffness * (penalty.thickness - n.dot(u)).max(0.0);
        if !(jn > 0.0 && jn.is_finite()) {
            continue;
        }
        // pinned particles (and, defensively, non-positive masses) do not move
        let inv_mass = p.map(|i| {
            let im = 1.0 / mass[i];
            if pinned[i] || !im.is_finite() || im <= 0.0 {
                0.0
            } else {
                im
            }
        });
        let w_sum: f64 = (0..4)
            .map(|a| s.weights[a] * s.weights[a] * inv_mass[a])
            .sum();
        if !(w_sum > 0.0 && w_sum.is_finite()) {
            continue;
        }
        let rel: Vec3 = (0..4).map(|a| v[p[a]] * s.weights[a]).sum();
        let tangential = rel - n * n.dot(rel);
        let speed = tangential.length();
        if !(speed > 0.0 && speed.is_finite()) {
            continue;
        }
        let m_eff = 1.0 / w_sum;
        let impulse = tangential * (-(m_eff * speed).min(mu * jn) / speed);
        for a in 0..4 {
            if inv_mass[a] > 0.0 {
                v[p[a]] += impulse * (s.weights[a] * inv_mass[a]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::proximity::StencilKind;
    use crate::collision::repulsion::{edge_edge_weights, point_triangle_weights};
    use proptest::prelude::*;

    const PEN: Penalty = Penalty {
        thickness: 0.01,
        stiffness: 1000.0,
        tangential: false,
    };

    fn v3(r: f64) -> impl Strategy<Value = Vec3> {
        (-r..r, -r..r, -r..r).prop_map(|(a, b, c)| Vec3::new(a, b, c))
    }

    fn unit(v: Vec3) -> Vec3 {
        if v.length() > 1e-3 {
            v.normalize()
        } else {
            Vec3::Y
        }
    }

    /// A stencil over particles `ids` with random weights of either kind.
    fn stencil(ids: [u32; 4], a: f64, b: f64, edge: bool, normal: Vec3) -> Proximity {
        let (kind, weights) = if edge {
            (StencilKind::EdgeEdge, edge_edge_weights(a, b))
        } else {
            let (a, b) = (a.min(b), a.max(b));
            (
                StencilKind::VertexTriangle,
                point_triangle_weights([a, b - a, 1.0 - b]),
            )
        };
        Proximity {
            kind,
            particles: ids,
            weights,
            dist: 0.0,
            normal: unit(normal),
        }
    }

    fn momentum(v: &[Vec3], m: &[f64]) -> Vec3 {
        v.iter().zip(m).map(|(v, m)| *v * *m).sum()
    }

    fn kinetic(v: &[Vec3], m: &[f64]) -> f64 {
        v.iter()
            .zip(m)
            .map(|(v, m)| 0.5 * m * v.length_squared())
            .sum()
    }

    fn relative(s: &Proximity, v: &[Vec3]) -> Vec3 {
        (0..4)
            .map(|a| v[s.particles[a] as usize] * s.weights[a])
            .sum()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(400))]

        /// Many random contacts sharing particles: momentum is conserved, kinetic energy does
        /// not grow, pinned particles do not move, and the result is bit-identical on a rerun.
        #[test]
        fn friction_conserves_momentum_and_dissipates(
            x in prop::collection::vec(v3(0.01), 8),
            v in prop::collection::vec(v3(2.0), 8),
            m in prop::collection::vec(1e-4..1e-2f64, 8),
            raw in prop::collection::vec(
                (prop::array::uniform4(0u32..8), 0.0..1.0f64, 0.0..1.0f64, any::<bool>(), v3(1.0)),
                1..12,
            ),
            mu in 0.0..2.0f64,
            pin in prop::option::of(0usize..8),
        ) {
            let stencils: Vec<Proximity> = raw
                .iter()
                .filter(|(ids, ..)| (0..4).all(|a| (a + 1..4).all(|b| ids[a] != ids[b])))
                .map(|&(ids, a, b, edge, n)| stencil(ids, a, b, edge, n))
                .collect();
            let mut pinned = vec![false; 8];
            let mut v0 = v.clone();
            if let Some(p) = pin {
                pinned[p] = true;
                v0[p] = Vec3::ZERO;
            }
            let mut v1 = v0.clone();
            apply_contact_friction(&mut v1, &x, &m, &pinned, &stencils, &PEN, mu, 0.01);
            let scale = momentum(&v0.iter().map(|v| v.abs()).collect::<Vec<_>>(), &m).length() + 1e-12;
            if pin.is_none() {
                prop_assert!((momentum(&v1, &m) - momentum(&v0, &m)).length() <= 1e-12 * scale);
            } else {
                prop_assert_eq!(v1[pin.unwrap()], Vec3::ZERO);
            }
            prop_assert!(kinetic(&v1, &m) <= kinetic(&v0, &m) * (1.0 + 1e-12) + 1e-300);
            let mut again = v0.clone();
            apply_contact_friction(&mut again, &x, &m, &pinned, &stencils, &PEN, mu, 0.01);
            prop_assert_eq!(again, v1);
        }

        /// One contact: the normal relative velocity is kept, the tangential one shrinks along
        /// its own direction (never reverses), to zero when static friction can hold it, and by
        /// exactly μ jₙ / m_eff otherwise.
        #[test]
        fn one_contact_is_coulomb(
            x in prop::collection::vec(v3(0.01), 4),
            v in prop::collection::vec(v3(2.0), 4),
            m in prop::collection::vec(1e-4..1e-2f64, 4),
            a in 0.0..1.0f64, b in 0.0..1.0f64, edge in any::<bool>(), n in v3(1.0),
            mu in 0.0..2.0f64,
        ) {
            let s = stencil([0, 1, 2, 3], a, b, edge, n);
            let n = s.normal;
            let mut v1 = v.clone();
            apply_contact_friction(&mut v1, &x, &m, &[false; 4], &[s], &PEN, mu, 0.01);
            let (r0, r1) = (relative(&s, &v), relative(&s, &v1));
            let scale = 1e-12 * (1.0 + r0.length());
            prop_assert!((n.dot(r1) - n.dot(r0)).abs() <= scale);
            let (t0, t1) = (r0 - n * n.dot(r0), r1 - n * n.dot(r1));
            prop_assert!(t1.length() <= t0.length() + scale);
            prop_assert!(t1.dot(t0) >= -scale * t0.length(), "reversed: {t0} -> {t1}");
            prop_assert!(t1.cross(t0).length() <= scale * (1.0 + t0.length()));
            let u: Vec3 = (0..4).map(|k| x[k] * s.weights[k]).sum();
            let jn = 0.01 * PEN.stiffness * (PEN.thickness - n.dot(u)).max(0.0);
            let m_eff = 1.0 / (0..4).map(|k| s.weights[k].powi(2) / m[k]).sum::<f64>();
            let expect = (t0.length() - mu * jn / m_eff).max(0.0);
            prop_assert!((t1.length() - expect).abs() <= 1e-9 * (1.0 + t0.length()),
                "|uₜ| {} -> {}, expected {expect}", t0.length(), t1.length());
        }
    }

    #[test]
    fn no_friction_without_contact_force_or_coefficient() {
        let s = stencil([0, 1, 2, 3], 0.3, 0.6, false, Vec3::Y);
        let m = [1e-3; 4];
        let v = vec![Vec3::X, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        // the point is above the triangle by more than the thickness at the end of the step
        let far = vec![Vec3::new(0.3, 0.02, 0.3), Vec3::ZERO, Vec3::X, Vec3::Z];
        let mut w = v.clone();
        apply_contact_friction(&mut w, &far, &m, &[false; 4], &[s], &PEN, 1.0, 0.01);
        assert_eq!(w, v);
        let near = vec![Vec3::new(0.3, 0.005, 0.3), Vec3::ZERO, Vec3::X, Vec3::Z];
        let mut w = v.clone();
        apply_contact_friction(&mut w, &near, &m, &[false; 4], &[s], &PEN, 0.0, 0.01);
        assert_eq!(w, v);
        // with both: the point slows down and the triangle is dragged along
        apply_contact_friction(&mut w, &near, &m, &[false; 4], &[s], &PEN, 0.5, 0.01);
        assert!(w[0].x < 1.0 && w[0].x >= 0.0);
        assert!(w[1..].iter().all(|p| p.x >= 0.0) && w[1..].iter().any(|p| p.x > 0.0));
    }
}
