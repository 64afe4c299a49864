//! Small-vector types used everywhere: f64 3-vectors and 3×3 matrices from glam.

pub use glam::{DMat3 as Mat3, DVec3 as Vec3};

/// Outer product `a bᵀ`.
#[inline]
pub fn outer(a: Vec3, b: Vec3) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// The projector `I - n nᵀ` onto the plane normal to unit `n`.
#[inline]
pub fn tangent_projector(n: Vec3) -> Mat3 {
    Mat3::IDENTITY - outer(n, n)
}

/// Largest absolute entry of a matrix.
#[inline]
pub fn max_abs(m: &Mat3) -> f64 {
    m.to_cols_array()
        .iter()
        .fold(0.0f64, |acc, v| acc.max(v.abs()))
}

/// True when every component is finite.
#[inline]
pub fn all_finite(v: &[Vec3]) -> bool {
    v.iter().all(|p| p.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outer_product_entries_are_products_of_components() {
        let a = Vec3::new(1.0, 2.0, 3.0);
        let b = Vec3::new(-1.0, 0.5, 4.0);
        let m = outer(a, b);
        for r in 0..3 {
            for c in 0..3 {
                assert_eq!(m.col(c)[r], a[r] * b[c]);
            }
        }
    }
}
