//! The checks every validator shares, each returning an [`Error::Field`] that names the field.
//!
//! One fact, one validator: the model checks its cloths ([`crate::model::Model::new`]), the
//! settings check themselves (`SolverSettings::validate`, `CollisionSettings::validate`), and
//! the scene loader only parses, calls them and words their errors (file and line).

use crate::error::{Error, Result};
use crate::math::Vec3;

/// `v`, a finite number ≥ 0.
pub fn nonneg(field: &str, v: f64) -> Result<f64> {
    if v >= 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(Error::field(
            field,
            format!("must be a finite number ≥ 0, got {v}"),
        ))
    }
}

/// `v`, a finite number > 0.
pub fn positive(field: &str, v: f64) -> Result<f64> {
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(Error::field(
            field,
            format!("must be a finite number > 0, got {v}"),
        ))
    }
}

/// `v`, a finite vector.
pub fn finite3(field: &str, v: Vec3) -> Result<Vec3> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::field(
            field,
            format!("must be finite, got [{}, {}, {}]", v.x, v.y, v.z),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_check_names_the_field_and_the_value() {
        assert_eq!(nonneg("a.b", 0.0).unwrap(), 0.0);
        let e = nonneg("cloth[1].damping", -2.0).unwrap_err().to_string();
        assert_eq!(e, "cloth[1].damping: must be a finite number ≥ 0, got -2");
        assert!(positive("x", 0.0).is_err() && positive("x", f64::NAN).is_err());
        assert!(nonneg("x", f64::INFINITY).is_err());
        let e = finite3("g", Vec3::new(0.0, f64::NAN, 1.0))
            .unwrap_err()
            .to_string();
        assert_eq!(e, "g: must be finite, got [0, NaN, 1]");
    }
}
