//! Colliders as triangle meshes for `drapery run --format glb,usd` and `drapery render --scene`
//! (their one-line descriptions for `drapery validate` are the library's `Obstacle::describe`).

use drapery::Vec3;
use drapery::collision::settings::Obstacle;
use drapery::collision::tessellate::{TessellateOptions, tessellate};
use drapery::io::gltf::MovingMesh;

/// One collider as triangles.
pub struct ColliderMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// How the colliders are drawn: planes (infinite) as squares centred under the middle of
/// `cloth_bounds`, with a half side of half the box diagonal (at least 0.25 m).
fn options(cloth_bounds: Option<(Vec3, Vec3)>) -> TessellateOptions {
    let (lo, hi) = cloth_bounds.unwrap_or((Vec3::splat(-0.5), Vec3::splat(0.5)));
    TessellateOptions {
        plane_center: (lo + hi) * 0.5,
        plane_half_size: (0.5 * (hi - lo).length()).max(0.25),
        ..TessellateOptions::default()
    }
}

fn name(i: usize, o: &Obstacle) -> String {
    format!("collider_{i}_{}", o.collider.shape.name())
}

/// Every obstacle posed at time `t` (planes sized from `cloth_bounds`, see [`options`]).
pub fn collider_meshes(
    obstacles: &[Obstacle],
    t: f64,
    cloth_bounds: Option<(Vec3, Vec3)>,
) -> Vec<ColliderMesh> {
    let options = options(cloth_bounds);
    obstacles
        .iter()
        .map(|o| {
            let (positions, triangles) = tessellate(&o.collider, t, &options);
            ColliderMesh {
                positions,
                triangles,
            }
        })
        .collect()
}

/// Every obstacle over `frames` frames at `frame_rate` (frame k at k / frame_rate), for the
/// whole-run formats: fixed, moving rigidly or deforming ([`MovingMesh::from_collider`]).
pub fn collider_tracks(
    obstacles: &[Obstacle],
    frames: usize,
    frame_rate: f64,
    cloth_bounds: Option<(Vec3, Vec3)>,
) -> Vec<MovingMesh> {
    let options = options(cloth_bounds);
    let times: Vec<f64> = (0..frames).map(|k| k as f64 / frame_rate).collect();
    obstacles
        .iter()
        .enumerate()
        .map(|(i, o)| MovingMesh::from_collider(name(i, o), &o.collider, &times, &options))
        .collect()
}
