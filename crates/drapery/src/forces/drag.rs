//! Linear air drag: `f_i = -c_i v_i`, `∂f_i/∂v_i = -c_i I`, dissipation `Ψ = ½ Σ c_i |v_i|²`.

use super::{Force, State};
use crate::linalg::BlockMatrix;
use crate::math::{Mat3, Vec3};

/// Per-particle linear drag, N·s/m.
#[derive(Clone, Debug)]
pub struct AirDrag {
    /// Drag coefficient of each particle.
    pub c: Vec<f64>,
}

impl Force for AirDrag {
    fn name(&self) -> &'static str {
        "air drag"
    }
    fn dissipation(&self, at: &State) -> f64 {
        self.c
            .iter()
            .zip(at.v)
            .map(|(c, v)| 0.5 * c * v.length_squared())
            .sum()
    }
    fn add_force(&self, at: &State, f: &mut [Vec3]) {
        for ((fi, c), vi) in f.iter_mut().zip(&self.c).zip(at.v) {
            *fi -= *c * *vi;
        }
    }
    fn add_jacobian(&self, _at: &State, _a: f64, b: f64, m: &mut BlockMatrix) {
        for (i, c) in self.c.iter().enumerate() {
            let k = m.diag_index(i);
            m.values[k] -= Mat3::from_diagonal(Vec3::splat(b * c));
        }
    }
    fn add_jacobian_product(&self, _at: &State, _a: f64, b: f64, w: &[Vec3], out: &mut [Vec3]) {
        for ((o, c), wi) in out.iter_mut().zip(&self.c).zip(w) {
            *o -= b * c * *wi;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::*;
    use super::*;

    #[test]
    fn drag_jacobian_matches_finite_differences() {
        let d = AirDrag {
            c: vec![0.3, 1.5, 0.0],
        };
        let x = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let v = [
            Vec3::new(1.0, -2.0, 0.5),
            Vec3::new(0.0, 3.0, 1.0),
            Vec3::new(4.0, 0.0, 0.0),
        ];
        assert!(
            rel_diff(
                &assembled(&d, &x, &v, 0.0, 1.0),
                &fd_jacobian(&d, &x, &v, true)
            ) < 1e-8
        );
        assert!(
            rel_diff(
                &assembled(&d, &x, &v, 1.0, 0.0),
                &fd_jacobian(&d, &x, &v, false)
            ) < 1e-8
        );
        assert!(check_product(&d, &x, &v, 0.7, -1.3, &v) < 1e-14);
    }
}
