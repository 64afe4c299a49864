//! `drapery run --format obj,glb,usd,ply`: every format is written and reads back to the same
//! positions as the OBJ frames (f64-exact for PLY, f32 for glTF and USD).

use assert_cmd::Command;
use drapery::Vec3;
use drapery::io::gltf::read_glb;
use drapery::io::obj::read_obj;
use drapery::io::ply::read_ply;
use drapery::io::usd::read_usda;
use drapery::scene::Scene;
use std::path::{Path, PathBuf};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn frame(dir: &Path, k: usize, ext: &str) -> PathBuf {
    dir.join(format!("frame_{k:05}.{ext}"))
}

fn f32s(p: Vec3) -> [f32; 3] {
    p.as_vec3().to_array()
}

/// `drapery run SCENE -o OUT --format FORMATS --quiet`, which must succeed.
fn run_quiet(scene_path: &Path, out: &Path, formats: &str) {
    let o = Command::new(env!("CARGO_BIN_EXE_drapery"))
        .args(["run".as_ref(), scene_path.as_os_str(), "-o".as_ref()])
        .arg(out)
        .args(["--format", formats, "--quiet"])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Runs `example` with every format and compares every output with the OBJ frames.
fn all_formats_agree(example: &str) {
    let scene_path = examples().join(format!("{example}.toml"));
    let scene = Scene::load(&scene_path).unwrap();
    let frames = scene.frame_count() + 1;
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    run_quiet(&scene_path, &out, "obj,glb,usd,ply");

    let obj: Vec<Vec<Vec3>> = (0..frames)
        .map(|k| read_obj(&frame(&out, k, "obj")).unwrap().positions)
        .collect();
    assert!(!frame(&out, frames, "obj").exists());
    let n = obj[0].len();
    assert!(obj.iter().all(|f| f.len() == n));
    assert_ne!(obj[0], obj[frames - 1], "nothing moved");

    // PLY: same f64 bits, same faces as the input mesh.
    for (k, want) in obj.iter().enumerate() {
        let (x, faces) = read_ply(&frame(&out, k, "ply")).unwrap();
        assert_eq!(x.len(), n);
        for (a, b) in x.iter().zip(want) {
            for c in 0..3 {
                assert_eq!(a[c].to_bits(), b[c].to_bits(), "ply frame {k}");
            }
        }
        let face_count: usize = scene.cloths.iter().map(|c| c.mesh.faces.len()).sum();
        assert_eq!(faces.len(), face_count);
    }
    assert!(!frame(&out, frames, "ply").exists());

    // glb: one mesh per cloth, one key per frame at k / frame_rate, positions = f32 of OBJ.
    let glb = read_glb(&out.join(format!("{example}.glb"))).unwrap();
    assert_eq!(glb.times.len(), frames);
    for (k, t) in glb.times.iter().enumerate() {
        assert!(
            (*t as f64 - k as f64 / scene.frame_rate).abs() < 1e-5,
            "key {k} at {t}"
        );
    }
    assert_eq!(glb.meshes.len(), scene.cloths.len());
    let mut offset = 0;
    for (m, c) in glb.meshes.iter().zip(&scene.cloths) {
        assert_eq!(m.name, c.name);
        assert_eq!(m.frames.len(), frames);
        let nv = c.mesh.positions.len();
        for (k, f) in m.frames.iter().enumerate() {
            assert_eq!(f.len(), nv);
            for (i, p) in f.iter().enumerate() {
                let want = f32s(obj[k][offset + i]);
                // Morph targets hold differences to frame 0, so allow f32 rounding of the sum.
                for d in 0..3 {
                    let tol = 4.0 * f32::EPSILON * (1.0 + want[d].abs());
                    assert!(
                        (p[d] - want[d]).abs() <= tol,
                        "glb frame {k} vertex {i}: {p:?} vs {want:?}"
                    );
                }
            }
        }
        offset += nv;
    }

    // usda: one time sample per frame, points = f32 of OBJ exactly.
    let usd = read_usda(&out.join(format!("{example}.usda"))).unwrap();
    assert_eq!(usd.time_codes_per_second, scene.frame_rate);
    assert_eq!(usd.end_time_code, (frames - 1) as f64);
    assert_eq!(usd.meshes.len(), scene.cloths.len());
    let mut offset = 0;
    for (m, c) in usd.meshes.iter().zip(&scene.cloths) {
        assert_eq!(m.samples.len(), frames);
        let nv = c.mesh.positions.len();
        for (k, (t, pts)) in m.samples.iter().enumerate() {
            assert_eq!(*t, k as f64);
            assert_eq!(pts.len(), nv);
            for (i, p) in pts.iter().enumerate() {
                assert_eq!(
                    f32s(*p),
                    f32s(obj[k][offset + i]),
                    "usd frame {k} vertex {i}"
                );
            }
        }
        offset += nv;
    }
}

#[test]
fn hang_in_every_format_reads_back_to_the_obj_positions() {
    all_formats_agree("hang");
}

#[test]
fn obj_cloth_in_every_format_reads_back_to_the_obj_positions() {
    all_formats_agree("obj_cloth");
}

#[test]
fn a_blown_up_run_still_writes_the_whole_run_files_with_the_frames_done() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("m.obj"), "v 0 0 0\nv 1 0 0\nl 1 2\n").unwrap();
    let scene = tmp.path().join("boom.toml");
    std::fs::write(
        &scene,
        r#"
[simulation]
duration = 0.1
dt = 0.01
frame_rate = 20

[[cloth]]
name = "rope"
mesh = "m.obj"
vertex_mass = 0.01
stretch_stiffness = 1e300
pin = [0]
initial_velocity = [1e308, 1e308, 1e308]
"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_drapery"))
        .args(["run".as_ref(), scene.as_os_str(), "-o".as_ref()])
        .arg(&out)
        .args(["--format", "ply,glb,usd"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: frame 1: "), "{stderr}");
    assert!(frame(&out, 0, "ply").exists());
    assert!(!frame(&out, 1, "ply").exists());
    let glb = read_glb(&out.join("boom.glb")).unwrap();
    assert_eq!(glb.meshes[0].frames.len(), 1);
    assert_eq!(glb.meshes[0].frames[0][1], [1.0, 0.0, 0.0]);
    let usd = read_usda(&out.join("boom.usda")).unwrap();
    assert_eq!(usd.meshes[0].samples.len(), 1);
}

/// `got` is `want` to f32 precision, for values made of terms up to `scale` in size.
fn near_f32(got: Vec3, want: Vec3, scale: f64) -> bool {
    (got - want).abs().max_element() <= 8.0 * f32::EPSILON as f64 * (1.0 + scale)
}

#[test]
fn moving_colliders_are_animated_in_glb_and_usd_at_every_frame_and_fixed_ones_are_not() {
    use drapery::collision::tessellate::{TessellateOptions, tessellate};
    let tmp = tempfile::tempdir().unwrap();
    let scene_path = tmp.path().join("mover.toml");
    std::fs::write(
        &scene_path,
        r#"
[simulation]
duration = 0.2
dt = 0.01
frame_rate = 25

[[cloth]]
name = "sheet"
grid = { size = [0.4, 0.4], resolution = [5, 5], center = [0.0, 1.5, 0.0], normal = [0.0, 1.0, 0.0] }
density = 0.1
stretch_stiffness = 1000.0

[[collider]]
shape = "box"
center = [0.4, 0.3, -0.2]
half_extents = [0.2, 0.1, 0.3]
velocity = [0.5, -0.2, 1.0]
angular_velocity = [1.0, 8.0, -2.0]

[[collider]]
shape = "sphere"
center = [-1.0, 0.2, 0.0]
radius = 0.2
"#,
    )
    .unwrap();
    let scene = Scene::load(&scene_path).unwrap();
    let frames = scene.frame_count() + 1;
    let out = tmp.path().join("out");
    run_quiet(&scene_path, &out, "glb,usd");
    let options = TessellateOptions::default();
    let mover = &scene.obstacles[0].collider;
    let fixed = &scene.obstacles[1].collider;
    let time = |k: usize| k as f64 / scene.frame_rate;

    let glb = read_glb(&out.join("mover.glb")).unwrap();
    let names: Vec<&str> = glb.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["sheet", "collider_0_box", "collider_1_sphere"]);
    let b = &glb.meshes[1];
    assert_eq!(b.interpolations, ["LINEAR", "LINEAR"]);
    assert_eq!((b.translations.len(), b.rotations.len()), (frames, frames));
    for k in 0..frames {
        let [x, y, z, w] = b.rotations[k].map(|c| c as f64);
        // v rotated by the unit quaternion (u, w): v + 2w (u × v) + 2 u × (u × v)
        let u = Vec3::new(x, y, z);
        let rotate = |v: Vec3| v + 2.0 * w * u.cross(v) + 2.0 * u.cross(u.cross(v));
        let tr = Vec3::from_array(b.translations[k].map(|c| c as f64));
        let (want, _) = tessellate(mover, time(k), &options);
        assert_eq!(want.len(), b.base.len());
        for (i, (p, w)) in b.base.iter().zip(&want).enumerate() {
            let p = Vec3::from_array(p.map(|c| c as f64));
            let got = rotate(p) + tr;
            assert!(
                near_f32(got, *w, p.length() + tr.length()),
                "glb frame {k} vertex {i}: {got} vs {w}"
            );
        }
    }
    let s = &glb.meshes[2];
    assert!(s.translations.is_empty() && s.rotations.is_empty() && s.interpolations.is_empty());
    let (want, _) = tessellate(fixed, 0.0, &options);
    assert_eq!(
        s.frames,
        vec![want.iter().map(|p| f32s(*p)).collect::<Vec<_>>()]
    );

    let usd = read_usda(&out.join("mover.usda")).unwrap();
    let names: Vec<&str> = usd.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["sheet", "collider_0_box", "collider_1_sphere"]);
    let b = &usd.meshes[1];
    assert_eq!(b.xform_op_order, ["xformOp:translate", "xformOp:orient"]);
    assert_eq!(
        (b.translations.len(), b.orientations.len()),
        (frames, frames)
    );
    for k in 0..frames {
        let ((tk, tr), (rk, r)) = (b.translations[k], b.orientations[k]);
        assert_eq!((tk, rk), (k as f64, k as f64));
        let (want, _) = tessellate(mover, time(k), &options);
        assert_eq!(want.len(), b.points.len());
        for (i, (p, w)) in b.points.iter().zip(&want).enumerate() {
            let got = r * *p + tr;
            assert!(
                near_f32(got, *w, p.length() + tr.length()),
                "usd frame {k} vertex {i}: {got} vs {w}"
            );
        }
    }
    let s = &usd.meshes[2];
    assert!(s.translations.is_empty() && s.xform_op_order.is_empty() && s.samples.is_empty());
    assert_eq!(
        s.points.iter().map(|p| f32s(*p)).collect::<Vec<_>>(),
        want.iter().map(|p| f32s(*p)).collect::<Vec<_>>()
    );
}
