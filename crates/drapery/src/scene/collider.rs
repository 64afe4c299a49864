//! `[[collider]]` tables: the common keys (`shape`, `friction`, the motion) here, each kind's
//! own keys in its file under [`crate::collision::colliders`]. Errors are
//! [`Error::Field`](crate::Error::Field)s naming `collider[i].key`; the loader adds the file and line.

use crate::collision::colliders::{Collider, Keys, Shape};
use crate::collision::settings::Obstacle;
use crate::error::Result;
use std::path::Path;

/// The keys every collider may have, whatever its shape.
pub(super) const COMMON_KEYS: &[&str] = &[
    "shape",
    "name",
    "friction",
    "velocity",
    "angular_velocity",
    "keyframes",
    "interpolation",
];

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
    let motion = k.motion()?;
    Ok(Obstacle {
        name: k
            .has("name")
            .then(|| k.string("name").map(str::to_string))
            .transpose()?,
        collider: Collider { shape, motion },
        friction,
    })
}

/// Collider names are unique.
pub(super) fn unique_names(obstacles: &[Obstacle]) -> Result<()> {
    for (i, o) in obstacles.iter().enumerate() {
        let Some(name) = &o.name else { continue };
        if let Some(j) = obstacles[..i]
            .iter()
            .position(|p| p.name.as_ref() == Some(name))
        {
            return Err(crate::Error::field(
                format!("collider[{i}].name"),
                format!("'{name}' is already the name of collider[{j}]"),
            ));
        }
    }
    Ok(())
}
