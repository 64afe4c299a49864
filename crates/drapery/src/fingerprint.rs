//! The scene fingerprint: a 64-bit FNV-1a hash of everything a scene is made of, so that a
//! front end can tell whether a saved run (see [`crate::snapshot`]) belongs to the scene it is
//! given: the drapery version, the scene file's bytes, every cloth's mesh as loaded (name,
//! positions to the bit, faces, line elements) and, when the scene has collisions, the
//! collision settings and every collider (mesh colliders' vertices and triangles included).
//! Editing the scene file or any mesh it uses changes the fingerprint.

use crate::collision::settings::Obstacle;
use crate::scene::Scene;

/// FNV-1a, 64 bits: a small, stable hash (the same value on every platform and version), used
/// for the scene fingerprint and for the checksum of a [`crate::snapshot::Snapshot`]'s bytes.
#[derive(Clone, Copy, Debug)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Fnv {
        Fnv::new()
    }
}

impl Fnv {
    /// The hash of nothing (the FNV-1a 64 offset basis).
    pub fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    /// Feeds bytes.
    pub fn bytes(&mut self, b: &[u8]) -> &mut Fnv {
        for &x in b {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
        self
    }
    /// Feeds a `u64` as its 8 little-endian bytes.
    pub fn u64(&mut self, v: u64) -> &mut Fnv {
        self.bytes(&v.to_le_bytes())
    }
    /// The hash of everything fed so far.
    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// The fingerprint of a scene: FNV-1a 64 over the drapery version, the scene file's bytes
/// (`scene_text`, as read from [`Scene::path`]) and every cloth's mesh as loaded (name,
/// positions to the bit, faces, line elements) and, when the scene has collisions, the
/// collision settings and every collider (mesh colliders' vertices and triangles included), so
/// editing the scene or any mesh it uses changes it.
pub fn fingerprint(scene: &Scene, scene_text: &[u8]) -> u64 {
    let mut h = Fnv::new();
    h.bytes(b"drapery ")
        .bytes(env!("CARGO_PKG_VERSION").as_bytes())
        .u64(scene_text.len() as u64)
        .bytes(scene_text);
    for c in &scene.cloths {
        h.u64(c.name.len() as u64).bytes(c.name.as_bytes());
        h.u64(c.mesh.positions.len() as u64);
        for p in &c.mesh.positions {
            for k in 0..3 {
                h.u64(p[k].to_bits());
            }
        }
        h.u64(c.mesh.faces.len() as u64);
        for f in &c.mesh.faces {
            h.u64(f.indices().len() as u64);
            for &i in f.indices() {
                h.u64(i as u64);
            }
        }
        h.u64(c.mesh.lines.len() as u64);
        for l in &c.mesh.lines {
            h.u64(l[0] as u64).u64(l[1] as u64);
        }
        // texture coordinates orient the shell model's warp and weft (hashed only for shells,
        // so the fingerprints of spring cloths stay as they were)
        if c.material.model == crate::model::ClothModel::Shell {
            h.bytes(b"uv").u64(c.mesh.face_uv.len() as u64);
            for uv in c.mesh.face_uv.iter().flatten().flatten() {
                h.u64(uv.to_bits());
            }
        }
    }
    // Collisions (only when the scene has them, so older fingerprints stay valid): the
    // settings and every collider as loaded, mesh collider vertices and triangles included.
    if let Some(c) = &scene.collision {
        h.bytes(b"collision");
        for x in [c.thickness, c.friction, c.stiffness] {
            h.u64(x.to_bits());
        }
        h.u64(c.self_collision as u64);
        h.u64(scene.obstacles.len() as u64);
        for o in &scene.obstacles {
            hash_obstacle(&mut h, o);
        }
    }
    h.finish()
}

fn hash_obstacle(h: &mut Fnv, o: &Obstacle) {
    h.u64(o.friction.to_bits());
    o.collider.motion.hash(h);
    o.collider.shape.hash(h);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn fnv1a_matches_the_reference_values() {
        assert_eq!(Fnv::new().finish(), 0xcbf29ce484222325);
        assert_eq!(Fnv::new().bytes(b"a").finish(), 0xaf63dc4c8601ec8c);
        assert_eq!(Fnv::new().bytes(b"foobar").finish(), 0x85944171f73967e8);
    }

    const SHEET: &str = r#"
[simulation]
duration = 1.0
dt = 0.01
frame_rate = 10

[[cloth]]
name = "sheet"
grid = { size = [1.0, 1.0], resolution = [4, 4], center = [0.0, 1.0, 0.0], normal = [0.0, 0.0, 1.0] }
density = 0.1
"#;

    /// `x` moved by one unit in the last place, away from zero.
    fn one_ulp_up(x: f64) -> f64 {
        f64::from_bits(x.to_bits() + 1)
    }

    #[test]
    fn a_cloth_vertex_moved_by_one_ulp_changes_the_fingerprint() {
        let scene = Scene::from_str(SHEET, Path::new("sheet.toml")).unwrap();
        let base = fingerprint(&scene, SHEET.as_bytes());
        let again = Scene::from_str(SHEET, Path::new("sheet.toml")).unwrap();
        assert_eq!(
            fingerprint(&again, SHEET.as_bytes()),
            base,
            "not deterministic"
        );
        for k in 0..3 {
            let mut moved = scene.clone();
            let p = &mut moved.cloths[0].mesh.positions[5];
            p[k] = one_ulp_up(p[k]);
            assert_ne!(fingerprint(&moved, SHEET.as_bytes()), base, "axis {k}");
        }
        // The scene text counts too, even a change that parses to the same scene.
        let text = format!("{SHEET}\n");
        assert_ne!(fingerprint(&scene, text.as_bytes()), base);
    }

    #[test]
    fn a_collider_mesh_vertex_moved_by_one_ulp_in_its_file_changes_the_fingerprint() {
        let dir = tempfile::tempdir().unwrap();
        let text = format!("{SHEET}\n[[collider]]\nshape = \"mesh\"\nmesh = \"body.obj\"\n");
        let scene_path = dir.path().join("scene.toml");
        std::fs::write(&scene_path, &text).unwrap();
        let body = |y: f64| format!("v 0 {y:?} 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
        let load = || {
            let scene = Scene::load(&scene_path).unwrap();
            fingerprint(&scene, text.as_bytes())
        };
        std::fs::write(dir.path().join("body.obj"), body(0.1)).unwrap();
        let base = load();
        assert_eq!(load(), base, "not deterministic");
        std::fs::write(dir.path().join("body.obj"), body(one_ulp_up(0.1))).unwrap();
        assert_ne!(load(), base);
    }
}
