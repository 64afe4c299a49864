//! What the scene says about collisions: thickness, self-collision, friction, contact stiffness,
//! and the obstacles.

use super::colliders::Collider;
use crate::error::Result;
use crate::validate;

/// Collision parameters shared by every contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CollisionSettings {
    /// Distance cloth keeps from obstacles and from itself, m (default: 0.005).
    pub thickness: f64,
    /// Cloth against itself and against other cloths (default: true).
    pub self_collision: bool,
    /// Coulomb friction coefficient, static and kinetic, of every contact: cloth–cloth, and
    /// obstacles without their own (default: 0.3).
    pub friction: f64,
    /// Stiffness of the cloth–cloth repulsion, N/m (default: 1000).
    pub stiffness: f64,
}

impl Default for CollisionSettings {
    fn default() -> Self {
        CollisionSettings {
            thickness: 0.005,
            self_collision: true,
            friction: 0.3,
            stiffness: 1000.0,
        }
    }
}

impl CollisionSettings {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<()> {
        validate::positive("collision.thickness", self.thickness)?;
        validate::nonneg("collision.friction", self.friction)?;
        validate::positive("collision.stiffness", self.stiffness)?;
        Ok(())
    }
}

/// An obstacle and its friction coefficient.
#[derive(Clone, Debug, PartialEq)]
pub struct Obstacle {
    /// The collider's name (`name = "table"`), unique in a scene, when it has one.
    pub name: Option<String>,
    /// Shape and rigid motion.
    pub collider: Collider,
    /// Coulomb coefficient for contacts with this obstacle.
    pub friction: f64,
}

impl Obstacle {
    /// One line: `sphere center [0, 0.25, 0] radius 0.25 m, friction 0.3, angular_velocity
    /// [0, 3.14, 0] rad/s`.
    pub fn describe(&self) -> String {
        format!(
            "{}, friction {}{}",
            self.collider.shape.describe(),
            self.friction,
            self.collider.motion.describe()
        )
    }
}
