//! Gravity: `f_i = m_i g`, energy `E = -Σ m_i g·x_i`, zero Jacobians.

use super::{Force, State};
use crate::linalg::BlockMatrix;
use crate::math::Vec3;

/// Uniform gravitational field acting on lumped masses.
#[derive(Clone, Debug)]
pub struct Gravity {
    /// `m_i g` per particle.
    pub weight: Vec<Vec3>,
}

impl Gravity {
    /// Gravity `g` (m/s²) on particles of masses `mass` (kg).
    pub fn new(mass: &[f64], g: Vec3) -> Self {
        Gravity {
            weight: mass.iter().map(|&m| m * g).collect(),
        }
    }
}

impl Force for Gravity {
    fn name(&self) -> &'static str {
        "gravity"
    }
    fn energy(&self, _t: f64, x: &[Vec3]) -> f64 {
        -self
            .weight
            .iter()
            .zip(x)
            .map(|(w, p)| w.dot(*p))
            .sum::<f64>()
    }
    fn add_force(&self, _at: &State, f: &mut [Vec3]) {
        for (fi, w) in f.iter_mut().zip(&self.weight) {
            *fi += *w;
        }
    }
    fn add_jacobian(&self, _at: &State, _a: f64, _b: f64, _m: &mut BlockMatrix) {}
    fn add_jacobian_product(&self, _at: &State, _a: f64, _b: f64, _w: &[Vec3], _out: &mut [Vec3]) {}
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::*;

    #[test]
    fn gravity_is_minus_the_gradient_of_its_energy() {
        let g = Gravity::new(&[0.5, 2.0], Vec3::new(0.1, -9.81, 0.3));
        let x = [Vec3::new(1.0, 2.0, 3.0), Vec3::new(-1.0, 0.5, 0.0)];
        let mut f = vec![Vec3::ZERO; 2];
        g.add_force(&at(&x, &x), &mut f);
        let fd = fd_gradient(&g, &x);
        for i in 0..2 {
            assert!((f[i] - fd[i]).length() < 1e-6);
        }
        assert!((f[1] - Vec3::new(0.2, -19.62, 0.6)).length() < 1e-12);
    }
}
