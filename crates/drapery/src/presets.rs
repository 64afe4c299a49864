//! The standard benchmark scenes, shared by `drapery bench`, `cargo bench` and the tests.
//!
//! Every scene is a 1 m square cloth of `n × n` vertices and 0.1 kg (stretch 1000 N/m, shear
//! 100 N/m, bend 1 N/m, damping 0.01), meant to be stepped once per frame at dt = 1/60 s:
//!
//! * [`Preset::Hang`]: vertical, hanging from its two top corners;
//! * [`Preset::Drape`]: horizontal, 0.4 m above a fixed sphere of radius 0.3 m;
//! * [`Preset::Pile`]: tilted, 0.6 m above the ground plane, so that it folds onto itself.
//!
//! Drape and pile have collisions on (thickness 5 mm, self-collision, friction 0.3).

use crate::collision::colliders::{Collider, Plane, Shape, Sphere};
use crate::collision::settings::{CollisionSettings, Obstacle};
use crate::model::{ClothDesc, MassSpec, Material, Model};
use crate::{Error, Mesh, Result, Simulation, SolverSettings, Vec3};

/// Which standard scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// Hanging from two corners.
    Hang,
    /// Falling onto a sphere.
    Drape,
    /// Falling onto the ground and folding.
    Pile,
}

impl Preset {
    /// Parses `KIND-SIZE` (`hang-64`, `drape-128`, ...) into the preset and the grid size.
    pub fn parse(name: &str) -> Result<(Preset, usize)> {
        let bad = |why: String| Error::Invalid(format!("scene '{name}': {why}"));
        let (kind, n) = name
            .split_once('-')
            .ok_or_else(|| bad("expected KIND-SIZE, e.g. hang-64".into()))?;
        let n: usize = n
            .parse()
            .ok()
            .filter(|&n| (2..=2048).contains(&n))
            .ok_or_else(|| bad("the size must be a whole number from 2 to 2048".into()))?;
        let preset = match kind {
            "hang" => Preset::Hang,
            "drape" => Preset::Drape,
            "pile" => Preset::Pile,
            _ => return Err(bad(format!("unknown kind '{kind}' (hang, drape or pile)"))),
        };
        Ok((preset, n))
    }

    /// Untimed frames to run before timing, so that the collision scenes are in contact.
    pub fn warm_up_frames(self) -> usize {
        match self {
            Preset::Hang => 5,
            Preset::Drape => 30,
            Preset::Pile => 40,
        }
    }

    /// The model of this scene at `n × n` vertices.
    pub fn model(self, n: usize) -> Result<Model> {
        let material = Material {
            stretch_stiffness: 1000.0,
            shear_stiffness: 100.0,
            bend_stiffness: 1.0,
            damping: 0.01,
            air_drag: 0.0,
            mass: MassSpec::Density(0.1),
        };
        let (center, normal, pins, obstacle) = match self {
            Preset::Hang => (
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::Z,
                vec![0, (n - 1) as u32],
                None,
            ),
            Preset::Drape => (
                Vec3::new(0.0, 0.4, 0.0),
                Vec3::Y,
                vec![],
                Some(Shape::Sphere(Sphere {
                    center: Vec3::ZERO,
                    radius: 0.3,
                })),
            ),
            Preset::Pile => (
                Vec3::new(0.0, 0.6, 0.0),
                Vec3::new(0.0, 0.3, 1.0),
                vec![],
                Some(Shape::Plane(Plane {
                    point: Vec3::ZERO,
                    normal: Vec3::Y,
                })),
            ),
        };
        let name = match self {
            Preset::Hang => "hang",
            Preset::Drape => "drape",
            Preset::Pile => "pile",
        };
        let cloth = ClothDesc {
            name: name.into(),
            mesh: Mesh::grid([1.0, 1.0], [n, n], center, normal)?,
            material,
            pins,
            initial_velocity: Vec3::ZERO,
            handles: Vec::new(),
        };
        let mut model = Model::new(vec![cloth], Vec3::new(0.0, -9.81, 0.0))?;
        if let Some(shape) = obstacle {
            model.collision = Some(CollisionSettings {
                thickness: 0.005,
                self_collision: true,
                friction: 0.3,
                stiffness: 1000.0,
            });
            model.obstacles = vec![Obstacle {
                name: None,
                collider: Collider::fixed(shape),
                friction: 0.3,
            }];
        }
        Ok(model)
    }

    /// The simulation of this scene with the default solver at PCG tolerance `tolerance`.
    pub fn simulation(self, n: usize, tolerance: f64) -> Result<Simulation> {
        let settings = SolverSettings {
            tolerance,
            max_iterations: 20_000,
            ..Default::default()
        };
        Simulation::new(self.model(n)?, settings)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_and_bad_names_are_refused() {
        assert_eq!(Preset::parse("hang-64").unwrap(), (Preset::Hang, 64));
        assert_eq!(Preset::parse("pile-2").unwrap(), (Preset::Pile, 2));
        for bad in ["hang", "hang-1", "hang-x", "swing-64", "drape-5000"] {
            assert!(Preset::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn hang_is_pinned_at_two_corners_and_collision_scenes_have_an_obstacle() {
        let m = Preset::Hang.model(8).unwrap();
        assert_eq!(m.pinned.iter().filter(|&&p| p).count(), 2);
        assert!(m.collision.is_none());
        for p in [Preset::Drape, Preset::Pile] {
            let m = p.model(8).unwrap();
            assert!(m.collision.is_some_and(|c| c.self_collision));
            assert_eq!(m.obstacles.len(), 1);
            assert!((m.total_mass() - 0.1).abs() < 1e-12);
        }
    }
}
