//! Small models for the stages' tests.

use crate::collision::colliders::{Collider, Plane, Shape};
use crate::collision::settings::{CollisionSettings, Obstacle};
use crate::math::Vec3;
use crate::mesh::Mesh;
use crate::model::{ClothDesc, MassSpec, Material, Model};

/// A `k × k` sheet of side 0.3 m in the x–z plane at height `y`, 0.01 kg per vertex, pins as
/// given, a little crumpled so that springs are stretched and compressed.
pub fn sheet(k: usize, y: f64, pins: Vec<u32>) -> Model {
    let mesh = Mesh::grid([0.3, 0.3], [k, k], Vec3::new(0.0, y, 0.0), Vec3::Y).unwrap();
    let rest = mesh.positions.clone();
    let cloth = ClothDesc {
        name: "sheet".into(),
        mesh,
        material: Material {
            mass: MassSpec::PerVertex(0.01),
            ..Material::default()
        },
        pins,
        initial_velocity: Vec3::new(0.1, -0.2, 0.05),
        handles: Vec::new(),
    };
    let mut m = Model::new(vec![cloth], Vec3::new(0.0, -9.81, 0.0)).unwrap();
    for (i, p) in rest.iter().enumerate() {
        let f = i as f64;
        m.x[i] = *p + Vec3::new(0.01 * (f * 0.7).sin(), 0.01 * (f * 1.3).cos(), 0.0);
    }
    m
}

/// [`sheet`] above a ground plane at `y = 0`, with collisions on.
pub fn sheet_on_ground(k: usize, y: f64) -> Model {
    let mut m = sheet(k, y, vec![]);
    m.collision = Some(CollisionSettings::default());
    m.obstacles = vec![Obstacle {
        name: None,
        collider: Collider::fixed(Shape::Plane(Plane {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        })),
        friction: 0.5,
    }];
    m
}
