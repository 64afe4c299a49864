//! Colliders as triangle meshes for `drapery run --format glb` and `drapery render --scene`,
//! and their one-line descriptions for `drapery validate`.

use drapery::Vec3;
use drapery::collision::colliders::Shape;
use drapery::collision::settings::Obstacle;
use drapery::collision::tessellate::{TessellateOptions, tessellate};

/// One collider as triangles.
pub struct ColliderMesh {
    /// `collider_0_sphere`, …
    pub name: String,
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// The shape's name as in the scene file.
pub fn shape_name(s: &Shape) -> &'static str {
    match s {
        Shape::Plane { .. } => "plane",
        Shape::Sphere { .. } => "sphere",
        Shape::Capsule { .. } => "capsule",
        Shape::Box { .. } => "box",
        Shape::Mesh(_) => "mesh",
    }
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
                name: format!("collider_{i}_{}", shape_name(&o.collider.shape)),
                positions,
                triangles,
            }
        })
        .collect()
}

fn v(p: Vec3) -> String {
    format!("[{}, {}, {}]", p.x, p.y, p.z)
}

/// `sphere center [0, 0.25, 0] radius 0.25, friction 0.3, spinning [0, 3.14, 0] rad/s`.
pub fn describe(o: &Obstacle) -> String {
    let shape = match &o.collider.shape {
        Shape::Plane { point, normal } => {
            format!("plane point {} normal {}", v(*point), v(*normal))
        }
        Shape::Sphere { center, radius } => {
            format!("sphere center {} radius {radius} m", v(*center))
        }
        Shape::Capsule { a, b, radius } => {
            format!("capsule a {} b {} radius {radius} m", v(*a), v(*b))
        }
        Shape::Box {
            center,
            half_extents,
            rotation,
        } => format!(
            "box center {} half_extents {} rotation [{}, {}, {}, {}]",
            v(*center),
            v(*half_extents),
            rotation.x,
            rotation.y,
            rotation.z,
            rotation.w
        ),
        Shape::Mesh(m) => format!(
            "mesh of {} vertices, {} triangles (turns about {})",
            m.vertices().len(),
            m.triangles().len(),
            v(o.collider.center())
        ),
    };
    let mut s = format!("{shape}, friction {}", o.friction);
    let m = o.collider.motion;
    if m.velocity != Vec3::ZERO {
        s.push_str(&format!(", velocity {} m/s", v(m.velocity)));
    }
    if m.angular_velocity != Vec3::ZERO {
        s.push_str(&format!(
            ", angular_velocity {} rad/s",
            v(m.angular_velocity)
        ));
    }
    s
}
