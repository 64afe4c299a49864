//! Colliders as triangle meshes for `drapery run --format glb` and `drapery render --scene`
//! (their one-line descriptions for `drapery validate` are the library's `Obstacle::describe`).

use drapery::Vec3;
use drapery::collision::settings::Obstacle;
use drapery::collision::tessellate::{TessellateOptions, tessellate};

/// One collider as triangles.
pub struct ColliderMesh {
    /// `collider_0_sphere`, …
    pub name: String,
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// Every obstacle posed at time `t`. Planes (infinite) are drawn as squares centred under the
/// middle of `cloth_bounds`, with a half side of half the box diagonal (at least 0.25 m).
pub fn collider_meshes(
    obstacles: &[Obstacle],
    t: f64,
    cloth_bounds: Option<(Vec3, Vec3)>,
) -> Vec<ColliderMesh> {
    let (lo, hi) = cloth_bounds.unwrap_or((Vec3::splat(-0.5), Vec3::splat(0.5)));
    let options = TessellateOptions {
        plane_center: (lo + hi) * 0.5,
        plane_half_size: (0.5 * (hi - lo).length()).max(0.25),
        ..TessellateOptions::default()
    };
    obstacles
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let (positions, triangles) = tessellate(&o.collider, t, &options);
            ColliderMesh {
                name: format!("collider_{i}_{}", o.collider.shape.name()),
                positions,
                triangles,
            }
        })
        .collect()
}
