//! `[[collider]]` tables: the common keys (`shape`, `friction`, the motion) here, each kind's
//! own keys in its file under [`crate::collision::colliders`]. Errors are
//! [`Error::Field`](crate::Error::Field)s naming `collider[i].key`; the loader adds the file and line.

use crate::animation::Motion;
use crate::collision::colliders::{Collider, Keys, Shape};
use crate::collision::settings::Obstacle;
use crate::error::Result;
use crate::math::Vec3;
use std::path::Path;

/// The keys every collider may have, whatever its shape.
pub(super) const COMMON_KEYS: &[&str] = &["shape", "friction", "velocity", "angular_velocity"];

/// One `[[collider]]` table as an obstacle.
pub(super) fn obstacle(
    i: usize,
    table: &toml::Table,
    default_friction: f64,
    dir: &Path,
) -> Result<Obstacle> {
    let k = Keys::new(table, format!("collider[{i}]"), dir);
    let shape = Shape::parse(k.string("shape")?, &k, table, COMMON_KEYS)?;
    let friction = match k.has("friction") {
        true => crate::validate::nonneg(&k.path("friction"), k.number("friction")?)?,
        false => default_friction,
    };
    let motion = Motion::constant(
        k.opt_vec3("velocity")?.unwrap_or(Vec3::ZERO),
        k.opt_vec3("angular_velocity")?.unwrap_or(Vec3::ZERO),
    );
    Ok(Obstacle {
        collider: Collider { shape, motion },
        friction,
    })
}
