//! Penalty repulsion between close primitives (docs/MATH.md §4, with the seed's sign corrected).
//!
//! A contact is a *stencil* of four particles `x₀…x₃` with fixed weights `w` whose weighted sum
//! `u = Σ wᵢ xᵢ` is the separation vector between the two closest points:
//!
//! * point–triangle (point `x₀`, triangle `x₁ x₂ x₃`, closest point `Σ αᵢ xᵢ`):
//!   `w = (1, -α₁, -α₂, -α₃)`, see [`point_triangle_weights`];
//! * edge–edge (edges `x₀ x₁` and `x₂ x₃`, closest parameters `s`, `t`):
//!   `w = (1-s, s, -(1-t), -t)`, see [`edge_edge_weights`].
//!
//! With `d = |u|`, `n = u/d`, thickness `η` and stiffness `k`, the penalty is active for `d < η`:
//!
//! ```text
//! E  = ½ k (η - d)²
//! fᵢ = wᵢ k (η - d) n                                   (= -∂E/∂xᵢ with w fixed)
//! ∂fᵢ/∂xⱼ = wᵢ wⱼ J,   J = -k n nᵀ + k (η - d)/d (I - n nᵀ)
//! ```
//!
//! The Jacobian is symmetric. Its first term is `-k (w wᵀ) ⊗ (n nᵀ)`, negative semi-definite;
//! the second (tangential) term is positive semi-definite and unbounded as `d → 0`, so
//! [`Penalty::tangential`] lets the caller drop it to keep `A = M - h ∂f/∂v - h² ∂f/∂x`
//! positive definite. Forces vanish at and beyond `η` (the energy is C¹ there). When the
//! weights sum to zero (both stencils above) the forces sum to zero: momentum is conserved.
//!
//! When `d` is zero or negligible (`d ≤ 1e-12 η`), `n` is undefined: the caller's
//! `fallback_normal` is used (for point–triangle, the triangle normal oriented toward the side
//! the point came from; for edge–edge, the cross product of the edges oriented likewise) and the
//! tangential term is omitted (it would be infinite).

use crate::math::{Mat3, Vec3, outer};

/// Parameters of the penalty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Penalty {
    /// Collision thickness `η` (m): the penalty acts while the distance is below it.
    pub thickness: f64,
    /// Stiffness `k` (N/m).
    pub stiffness: f64,
    /// Keep the tangential term `k (η-d)/d (I - n nᵀ)` of the Jacobian. Without it the
    /// Jacobian is `-k (w wᵀ) ⊗ (n nᵀ)`: negative semi-definite, but no longer the exact
    /// derivative of the force for sideways motion.
    pub tangential: bool,
}

/// Forces, Jacobian and energy of one contact stencil.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Repulsion {
    /// Force on each stencil particle (N).
    pub forces: [Vec3; 4],
    /// `jac[i][j] = ∂fᵢ/∂xⱼ`, 3×3 blocks of the 12×12 Jacobian.
    pub jac: [[Mat3; 4]; 4],
    /// Penalty energy (J).
    pub energy: f64,
    /// Distance `d = |Σ wᵢ xᵢ|`.
    pub dist: f64,
    /// Unit contact normal used (points from the second primitive toward the first).
    pub normal: Vec3,
}

impl Repulsion {
    /// The zero contact (inactive).
    pub const ZERO: Repulsion = Repulsion {
        forces: [Vec3::ZERO; 4],
        jac: [[Mat3::ZERO; 4]; 4],
        energy: 0.0,
        dist: f64::INFINITY,
        normal: Vec3::ZERO,
    };

    /// True when the contact exerts a force (`d < η`).
    pub fn is_active(&self) -> bool {
        self.energy > 0.0
    }
}

/// Stencil weights `(1, -α₁, -α₂, -α₃)` for a point and its closest point `Σ αᵢ xᵢ` on a
/// triangle (`bary` from [`crate::collision::distance::point_triangle`]).
pub fn point_triangle_weights(bary: [f64; 3]) -> [f64; 4] {
    [1.0, -bary[0], -bary[1], -bary[2]]
}

/// Stencil weights `(1-s, s, -(1-t), -t)` for the closest points of two edges
/// (`s`, `t` from [`crate::collision::distance::segment_segment`]).
pub fn edge_edge_weights(s: f64, t: f64) -> [f64; 4] {
    [1.0 - s, s, -(1.0 - t), -t]
}

/// Penalty forces, Jacobian and energy for a stencil `x` with fixed weights `w`.
///
/// Returns [`Repulsion::ZERO`] (with `dist` set) when `d ≥ η` or when the parameters are not
/// positive and finite. `fallback_normal` is used only when `d ≤ 1e-12 η`; if it is zero too,
/// `+z` is used.
pub fn repulsion(
    x: &[Vec3; 4],
    w: &[f64; 4],
    penalty: &Penalty,
    fallback_normal: Vec3,
) -> Repulsion {
    let eta = penalty.thickness;
    let k = penalty.stiffness;
    let u = x[0] * w[0] + x[1] * w[1] + x[2] * w[2] + x[3] * w[3];
    let d = u.length();
    let valid = eta > 0.0 && k > 0.0 && eta.is_finite() && k.is_finite();
    if !valid || d.is_nan() || d >= eta {
        return Repulsion {
            dist: d,
            ..Repulsion::ZERO
        };
    }
    let tiny = d <= 1e-12 * eta;
    let n = if !tiny {
        u / d
    } else {
        let l = fallback_normal.length();
        if l > 0.0 && l.is_finite() {
            fallback_normal / l
        } else {
            Vec3::Z
        }
    };
    let gap = eta - d;
    let f = n * (k * gap);
    let nn = outer(n, n);
    let mut j = nn * (-k);
    if penalty.tangential && !tiny {
        j += (Mat3::IDENTITY - nn) * (k * gap / d);
    }
    let mut jac = [[Mat3::ZERO; 4]; 4];
    for (a, row) in jac.iter_mut().enumerate() {
        for (b, blk) in row.iter_mut().enumerate() {
            *blk = j * (w[a] * w[b]);
        }
    }
    Repulsion {
        forces: [f * w[0], f * w[1], f * w[2], f * w[3]],
        jac,
        energy: 0.5 * k * gap * gap,
        dist: d,
        normal: n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const PEN: Penalty = Penalty {
        thickness: 0.01,
        stiffness: 1000.0,
        tangential: true,
    };

    /// A stencil with random points and weights, adjusted so that `d = frac · η` exactly (up to
    /// rounding) along a random direction. `kind` 0: point–triangle weights, 1: edge–edge.
    fn stencil(
        pts: [[f64; 3]; 4],
        a: f64,
        b: f64,
        dir: [f64; 3],
        frac: f64,
        kind: u8,
    ) -> Option<([Vec3; 4], [f64; 4])> {
        let x = pts.map(Vec3::from_array);
        let w = if kind == 0 {
            let (a, b) = (a.min(b), a.max(b));
            point_triangle_weights([a, b - a, 1.0 - b])
        } else {
            edge_edge_weights(a, b)
        };
        let dir = Vec3::from_array(dir);
        if dir.length() < 1e-3 {
            return None;
        }
        // move the particle with the largest |w| so that Σ wᵢ xᵢ = target
        let i = (0..4)
            .max_by(|&i, &j| w[i].abs().total_cmp(&w[j].abs()))
            .unwrap();
        let target = dir.normalize() * (frac * PEN.thickness);
        let rest: Vec3 = (0..4).filter(|&j| j != i).map(|j| x[j] * w[j]).sum();
        let mut x = x;
        x[i] = (target - rest) / w[i];
        Some((x, w))
    }

    fn perturbed(x: &[Vec3; 4], i: usize, c: usize, h: f64) -> [Vec3; 4] {
        let mut y = *x;
        y[i][c] += h;
        y
    }

    fn strategy() -> impl Strategy<Value = ([[f64; 3]; 4], f64, f64, [f64; 3], f64, u8)> {
        let p = || [-0.05..0.05f64, -0.05..0.05f64, -0.05..0.05f64];
        let frac = prop_oneof![0.05..0.95f64, 0.95..0.9999f64, 1e-6..1e-3f64, Just(0.5),];
        (
            [p(), p(), p(), p()],
            0.0..1.0f64,
            0.0..1.0f64,
            p(),
            frac,
            0..2u8,
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(600))]

        #[test]
        fn force_is_minus_energy_gradient((pts, a, b, dir, frac, kind) in strategy()) {
            let Some((x, w)) = stencil(pts, a, b, dir, frac, kind) else { return Ok(()) };
            let r = repulsion(&x, &w, &PEN, Vec3::Z);
            prop_assert!(r.is_active());
            let d = r.dist;
            // step well inside both the distance and the remaining gap to η
            let h = 1e-4 * d.min(PEN.thickness - d);
            let fscale = PEN.stiffness * (PEN.thickness - d) + 1e-300;
            for i in 0..4 {
                for c in 0..3 {
                    let ep = repulsion(&perturbed(&x, i, c, h), &w, &PEN, Vec3::Z).energy;
                    let em = repulsion(&perturbed(&x, i, c, -h), &w, &PEN, Vec3::Z).energy;
                    let fd = -(ep - em) / (2.0 * h);
                    prop_assert!((fd - r.forces[i][c]).abs() <= 1e-5 * fscale,
                        "i={i} c={c} fd={fd} f={} d={d}", r.forces[i][c]);
                }
            }
        }

        #[test]
        fn jacobian_is_force_derivative_symmetric_and_conserves_momentum(
            (pts, a, b, dir, frac, kind) in strategy()
        ) {
            let Some((x, w)) = stencil(pts, a, b, dir, frac, kind) else { return Ok(()) };
            let r = repulsion(&x, &w, &PEN, Vec3::Z);
            let d = r.dist;
            let h = 1e-4 * d.min(PEN.thickness - d);
            let jscale = PEN.stiffness * (1.0 + (PEN.thickness - d) / d);
            for j in 0..4 {
                for c in 0..3 {
                    let fp = repulsion(&perturbed(&x, j, c, h), &w, &PEN, Vec3::Z).forces;
                    let fm = repulsion(&perturbed(&x, j, c, -h), &w, &PEN, Vec3::Z).forces;
                    for i in 0..4 {
                        let fd = (fp[i] - fm[i]) / (2.0 * h);
                        let an = r.jac[i][j].col(c);
                        prop_assert!((fd - an).abs().max_element() <= 1e-5 * jscale,
                            "block ({i},{j}) col {c}: fd={fd} an={an} d={d}");
                    }
                }
            }
            for i in 0..4 {
                for j in 0..4 {
                    let diff = r.jac[i][j] - r.jac[j][i].transpose();
                    prop_assert!(crate::math::max_abs(&diff) <= 1e-12 * jscale);
                }
            }
            let total: Vec3 = r.forces.iter().sum();
            prop_assert!(total.length() <= 1e-12 * PEN.stiffness * PEN.thickness);
        }

        #[test]
        fn without_tangential_term_jacobian_is_negative_semidefinite(
            (pts, a, b, dir, frac, kind) in strategy(),
            y in prop::array::uniform4(prop::array::uniform3(-1.0..1.0f64)),
        ) {
            let Some((x, w)) = stencil(pts, a, b, dir, frac, kind) else { return Ok(()) };
            let pen = Penalty { tangential: false, ..PEN };
            let r = repulsion(&x, &w, &pen, Vec3::Z);
            let y = y.map(Vec3::from_array);
            let mut q = 0.0;
            for i in 0..4 {
                for j in 0..4 {
                    q += y[i].dot(r.jac[i][j] * y[j]);
                }
            }
            prop_assert!(q <= 1e-9 * pen.stiffness);
            // and with it, the quadratic form along the normal direction is still -k (w·y_n)²
            let yn: f64 = (0..4).map(|i| w[i] * y[i].dot(r.normal)).sum();
            prop_assert!((q + pen.stiffness * yn * yn).abs() <= 1e-9 * pen.stiffness);
        }
    }

    #[test]
    fn zero_force_at_and_beyond_thickness() {
        let w = point_triangle_weights([0.2, 0.3, 0.5]);
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let q = tri[0] * 0.2 + tri[1] * 0.3 + tri[2] * 0.5;
        for h in [PEN.thickness, PEN.thickness * 1.0001, 1.0, 1e9] {
            let x = [q + Vec3::Z * h, tri[0], tri[1], tri[2]];
            let r = repulsion(&x, &w, &PEN, Vec3::Z);
            assert!(!r.is_active());
            assert_eq!(r.forces, [Vec3::ZERO; 4]);
            assert_eq!(r.energy, 0.0);
        }
        // just inside: force pushes the point away from the triangle, triangle the other way
        let x = [q + Vec3::Z * 0.5 * PEN.thickness, tri[0], tri[1], tri[2]];
        let r = repulsion(&x, &w, &PEN, Vec3::Z);
        assert!(r.forces[0].z > 0.0 && r.forces.iter().skip(1).all(|f| f.z < 0.0));
        assert!((r.forces[0].z - 0.5 * PEN.stiffness * PEN.thickness).abs() < 1e-9);
    }

    #[test]
    fn zero_distance_uses_fallback_normal_and_stays_finite() {
        let w = point_triangle_weights([1.0 / 3.0; 3]);
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let q = (tri[0] + tri[1] + tri[2]) / 3.0;
        let r = repulsion(&[q, tri[0], tri[1], tri[2]], &w, &PEN, -Vec3::Z * 3.0);
        assert!(r.is_active());
        assert!((r.normal + Vec3::Z).length() < 1e-15);
        assert!(r.forces.iter().all(|f| f.is_finite()));
        assert!(r.jac.iter().flatten().all(|m| m.is_finite()));
        let r = repulsion(&[q, tri[0], tri[1], tri[2]], &w, &PEN, Vec3::ZERO);
        assert_eq!(r.normal, Vec3::Z);
        // bad parameters: inactive, no NaN
        let bad = Penalty {
            thickness: f64::NAN,
            ..PEN
        };
        assert!(!repulsion(&[q, tri[0], tri[1], tri[2]], &w, &bad, Vec3::Z).is_active());
    }
}
