//! Coulomb friction (docs/MATH.md §15), applied to the velocities after the solve: cloth–cloth contacts first
//! ([`apply_contact_friction`]), then obstacle contacts ([`apply_obstacle_friction`]), which
//! bound what holds a pile.
//!
//! ## Cloth–cloth
//!
//! Cloth–cloth contacts are vertex–triangle and edge–edge repulsion stencils.
//!
//! A stencil (particles `xᵢ`, weights `wᵢ` summing to zero, unit normal `n`, see
//! [`super::repulsion`]) has the relative velocity `u = Σ wᵢ vᵢ` of its two closest points.
//! Its normal impulse over the step is estimated from the repulsion the implicit solve applied:
//! with the normal and weights fixed over the step, the linearized penalty force at the end
//! positions `x₁` is `k (η - n·Σ wᵢ x₁ᵢ)` along `n` (docs/MATH.md §4; the Jacobian in the matrix is
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
//!
//! A particle in several contacts with different normals gets, from one contact's friction, a
//! velocity change that is partly normal for another. In a crumpled pile that pushed most
//! contacts together: in the 128² pile of `drapery bench`, 86 000 of 101 000 contacts approached
//! faster, by up to 0.66 m/s, and over its first 45 steps the collision fail-safe had 932 000
//! colliding pairs to stop (130 000 without friction) and took 92 s (5.6 s). So a last pass
//! (sweeps until nothing changes, at most [`NORMAL_SWEEPS`]) gives normal impulses `Q n`, `Δvᵢ = wᵢ Q n / mᵢ`, to every contact that now
//! approaches faster than the solve left it (or at all, if it was separating), just enough to
//! take that back. Those impulses conserve momentum too and never add energy: they raise an
//! approach speed `c < t ≤ 0` to `t`, changing the kinetic energy by `m_eff (t - c)(t + c)/2 ≤ 0`.
//! With it, those 45 steps had 271 000 colliding pairs and 10 s of collision handling (with two
//! sweeps at most 14 s, four 6.5 s, eight 17 s: the pile folds differently each time).

use super::proximity::Proximity;
use super::repulsion::Penalty;
use crate::constraints::obstacle::ObstacleContact;
use crate::math::Vec3;

/// Most sweeps of the pass that takes back the approach friction added to other contacts (it
/// stops at the first sweep that changes nothing).
const NORMAL_SWEEPS: usize = 16;

/// A stencil's particles, their inverse masses (0 for pinned particles and, defensively,
/// non-positive masses) and `Σ wᵢ²/mᵢ = 1/m_eff`, or `None` when nothing of it can move.
fn movable(s: &Proximity, mass: &[f64], pinned: &[bool]) -> Option<([usize; 4], [f64; 4], f64)> {
    let p = s.particles.map(|i| i as usize);
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
    (w_sum > 0.0 && w_sum.is_finite()).then_some((p, inv_mass, w_sum))
}

/// The relative velocity `Σ wᵢ vᵢ` of a stencil's two closest points.
fn relative(s: &Proximity, v: &[Vec3]) -> Vec3 {
    (0..4)
        .map(|a| v[s.particles[a] as usize] * s.weights[a])
        .sum()
}

/// Gives the impulse `P` to a stencil: `Δvᵢ = wᵢ P / mᵢ`.
fn give(v: &mut [Vec3], s: &Proximity, p: &[usize; 4], inv_mass: &[f64; 4], impulse: Vec3) {
    for a in 0..4 {
        if inv_mass[a] > 0.0 {
            v[p[a]] += impulse * (s.weights[a] * inv_mass[a]);
        }
    }
}

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
    // normal relative velocity each contact left the solve with
    let solved: Vec<f64> = stencils
        .iter()
        .map(|s| s.normal.dot(relative(s, v)))
        .collect();
    for s in stencils {
        let n = s.normal;
        let u: Vec3 = (0..4)
            .map(|a| x[s.particles[a] as usize] * s.weights[a])
            .sum();
        let jn = h * penalty.stiffness * (penalty.thickness - n.dot(u)).max(0.0);
        if !(jn > 0.0 && jn.is_finite()) {
            continue;
        }
        let Some((p, inv_mass, w_sum)) = movable(s, mass, pinned) else {
            continue;
        };
        let rel = relative(s, v);
        let tangential = rel - n * n.dot(rel);
        let speed = tangential.length();
        if !(speed > 0.0 && speed.is_finite()) {
            continue;
        }
        let m_eff = 1.0 / w_sum;
        let impulse = tangential * (-(m_eff * speed).min(mu * jn) / speed);
        give(v, s, &p, &inv_mass, impulse);
    }
    // Take back the approach friction added to other contacts (see the module docs).
    for _ in 0..NORMAL_SWEEPS {
        let mut changed = false;
        for (s, &un_solved) in stencils.iter().zip(&solved) {
            let target = un_solved.min(0.0);
            let un = s.normal.dot(relative(s, v));
            if un >= target || un.is_nan() {
                continue;
            }
            if let Some((p, inv_mass, w_sum)) = movable(s, mass, pinned) {
                give(v, s, &p, &inv_mass, s.normal * ((target - un) / w_sum));
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
}

/// Obstacle contacts after the solve (`contacts` as the active set held them, with the normal
/// impulses `impulse` their constraints exerted): each particle's normal velocity is set to the
/// surface's (the contact is inelastic: the particle ends the step resting on the surface, not
/// flying off it), then Coulomb friction acts on the tangential velocity relative to the
/// surface, which loses up to `μ λ / m` (static friction when it would reverse).
pub fn apply_obstacle_friction(
    v: &mut [Vec3],
    mass: &[f64],
    contacts: &[ObstacleContact],
    impulse: &[f64],
) {
    for ct in contacts {
        let i = ct.particle as usize;
        let vn = ct.normal.dot(v[i]);
        v[i] += ct.normal * (ct.normal.dot(ct.surface_velocity) - vn);
    }
    for (c, &lambda) in contacts.iter().zip(impulse) {
        if !(lambda > 0.0) || c.friction == 0.0 {
            continue;
        }
        let i = c.particle as usize;
        let rel = v[i] - c.surface_velocity;
        let vn = c.normal * c.normal.dot(rel);
        let vt = rel - vn;
        let speed = vt.length();
        let limit = c.friction * lambda / mass[i];
        let vt = if speed <= limit {
            Vec3::ZERO
        } else {
            vt * (1.0 - limit / speed)
        };
        v[i] = c.surface_velocity + vn + vt;
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
    fn friction_on_the_floor_does_not_push_the_vertex_into_the_wall() {
        // particle 0 slides along a slanted wall (normal n_b, velocity tangent to it) and down
        // toward the floor (normal +y); the floor's static friction alone would stop its
        // sideways motion and leave it falling into the wall at 0.48 m/s
        let n_b = Vec3::new(0.6, 0.8, 0.0);
        let p = Vec3::new(0.0, 0.005, 0.0);
        let (t1, t2) = (Vec3::Z, n_b.cross(Vec3::Z));
        let wall = p - n_b * 0.005;
        let x = vec![
            p,
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 2.0),
            wall + t2,
            wall - t2 * 0.5 + t1,
            wall - t2 * 0.5 - t1,
        ];
        let w = point_triangle_weights([1.0 / 3.0; 3]);
        let contact = |ids: [u32; 4], normal: Vec3| Proximity {
            kind: StencilKind::VertexTriangle,
            particles: ids,
            weights: w,
            dist: 0.005,
            normal,
        };
        let (floor, side) = (contact([0, 1, 2, 3], Vec3::Y), contact([0, 4, 5, 6], n_b));
        let pinned = [false, true, true, true, true, true, true];
        let m = [1e-3; 7];
        let v0 = vec![
            Vec3::new(0.8, -0.6, 0.0),
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
        ];
        let mut v = v0.clone();
        apply_contact_friction(&mut v, &x, &m, &pinned, &[floor, side], &PEN, 0.5, 0.01);
        let un = |s: &Proximity, v: &[Vec3]| s.normal.dot(relative(s, v));
        assert!(
            un(&side, &v) >= -1e-12,
            "pushed into the wall: {}",
            un(&side, &v)
        );
        assert!(un(&floor, &v) >= un(&floor, &v0) - 1e-12);
        assert!(kinetic(&v, &m) < kinetic(&v0, &m));
        // it still lost speed to friction along the floor
        assert!(v[0].x < 0.5, "{v:?}");
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

    proptest! {
        /// Obstacle friction on a contact moving with its surface: the normal velocity becomes
        /// the surface's; the tangential speed relative to the surface drops by `μ λ / m` or
        /// to zero (static), never reverses, and keeps its direction.
        #[test]
        fn obstacle_friction_is_coulomb_relative_to_the_moving_surface(
            slide in prop::array::uniform3(-2.0..2.0f64),
            surface in prop::array::uniform3(-1.0..1.0f64),
            lambda in 0.0..0.05f64,
            mu in 0.0..1.0f64,
        ) {
            let n = Vec3::new(0.0, 0.6, 0.8);
            let surface = Vec3::from_array(surface);
            let m = 0.01;
            let ct = ObstacleContact {
                particle: 0,
                normal: n,
                normal_velocity: 0.3,
                surface_velocity: surface,
                friction: mu,
                damping: 0.0,
            };
            let mut v = [Vec3::from_array(slide)];
            let before = v[0] - surface;
            let vt0 = before - n * n.dot(before);
            apply_obstacle_friction(&mut v, &[m], &[ct], &[lambda]);
            let rel = v[0] - surface;
            prop_assert!(n.dot(rel).abs() < 1e-12, "normal velocity is the surface's");
            let vt = rel - n * n.dot(rel);
            let want = (vt0.length() - mu * lambda / m).max(0.0);
            prop_assert!((vt.length() - want).abs() < 1e-12, "{} vs {want}", vt.length());
            if want > 0.0 {
                prop_assert!(vt.dot(vt0) > 0.0);
            }
        }
    }
}
