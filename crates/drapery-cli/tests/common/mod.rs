//! Helpers shared by the CLI tests: run the binary, compare run folders, check one-line errors.
#![allow(dead_code)] // each test crate uses some of them

use assert_cmd::Command;
use drapery::Vec3;
use drapery::io::obj::read_obj;
use drapery::scene::Scene;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

pub struct Out {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

pub fn drapery<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Out {
    let o = Command::new(env!("CARGO_BIN_EXE_drapery"))
        .args(args)
        .output()
        .unwrap();
    Out {
        code: o.status.code(),
        stdout: String::from_utf8_lossy(&o.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
    }
}

pub fn run_args(scene: &Path, out: &Path, extra: &[&str]) -> Vec<std::ffi::OsString> {
    let mut v: Vec<std::ffi::OsString> = vec![
        "run".into(),
        scene.into(),
        "-o".into(),
        out.into(),
        "-q".into(),
    ];
    v.extend(extra.iter().map(|s| s.into()));
    v
}

/// Every file of a folder (name → bytes).
pub fn contents(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

pub fn assert_same_folders(want: &Path, got: &Path) {
    let (a, b) = (contents(want), contents(got));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "different file sets"
    );
    for (name, bytes) in &a {
        assert!(
            bytes == &b[name],
            "{name} differs from the uninterrupted run"
        );
    }
}

pub fn assert_one_error(r: &Out, wants: &[&str]) {
    assert_eq!(r.code, Some(1), "stdout {} stderr {}", r.stdout, r.stderr);
    assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
    assert!(r.stderr.starts_with("error: "), "{}", r.stderr);
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    for w in wants {
        assert!(r.stderr.contains(w), "{:?} lacks {w:?}", r.stderr);
    }
}

pub fn frame(dir: &Path, k: usize) -> Vec<Vec3> {
    read_obj(&dir.join(format!("frame_{k:05}.obj")))
        .expect("frame reads")
        .positions
}

/// Runs `examples/NAME.toml` into a temporary folder, checks every frame with
/// `drapery check --scene` (exit 0, no intersection) and returns the folder, the scene and the
/// frames' positions.
pub fn run_and_check(name: &str) -> (tempfile::TempDir, Scene, Vec<Vec<Vec3>>) {
    run_and_check_scene(&examples().join(format!("{name}.toml")))
}

/// [`run_and_check`] for the scene file at `scene_path`.
pub fn run_and_check_scene(scene_path: &Path) -> (tempfile::TempDir, Scene, Vec<Vec<Vec3>>) {
    let name = scene_path.display();
    let scene = Scene::load(scene_path).expect("scene loads");
    let tmp = tempfile::tempdir().expect("temp dir");
    let out = tmp.path().join("out");
    let r = drapery(&[
        "run".as_ref(),
        scene_path.as_os_str(),
        "--output".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(r.code, Some(0), "{name}: run failed: {}", r.stderr);
    assert!(
        !r.stderr.contains("warning"),
        "{name}: the initial state intersects: {}",
        r.stderr
    );
    let c = drapery(&[
        "check".as_ref(),
        out.as_os_str(),
        "--scene".as_ref(),
        scene_path.as_os_str(),
    ]);
    assert_eq!(
        c.code,
        Some(0),
        "{name}: drapery check found intersections:\n{}{}",
        c.stdout,
        c.stderr
    );
    let frames = scene.frame_count() + 1;
    assert!(
        c.stdout
            .contains(&format!("{frames} frames (obj) in {}", out.display()))
            && c.stdout.contains("no intersection"),
        "{}",
        c.stdout
    );
    let x = (0..frames).map(|k| frame(&out, k)).collect();
    (tmp, scene, x)
}

/// A small valid scene (one 5 × 5 sheet, 0.1 s) that bad-input tests add tables to.
pub const BASE: &str = r#"
[simulation]
duration = 0.1
dt = 0.01
frame_rate = 20

[[cloth]]
name = "sheet"
grid = { size = [0.4, 0.4], resolution = [5, 5], center = [0.0, 0.5, 0.0], normal = [0.0, 1.0, 0.0] }
density = 0.1
"#;

/// Runs [`BASE`] plus `extra` as `scene.toml` in a temporary folder holding `files` (paths
/// relative to it): the run must fail with exit code 1 and one error line containing every
/// `wants` (the file at fault and the field), and write no output.
pub fn assert_rejected(extra: &str, files: &[(&str, &str)], wants: &[&str]) {
    let t = tempfile::tempdir().expect("temp dir");
    for (name, content) in files {
        let path = t.path().join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, content).expect("write");
    }
    let scene = t.path().join("scene.toml");
    std::fs::write(&scene, format!("{BASE}\n{extra}")).expect("write");
    let out = t.path().join("out");
    let r = drapery(&[
        "run".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_one_error(&r, wants);
    assert!(!out.exists(), "output written for bad input");
}

/// Rotation angle about +y from `p` to `q` (counter-clockwise seen from above), in (-π, π].
pub fn yaw(p: Vec3, q: Vec3) -> f64 {
    let d = (-q.z).atan2(q.x) - (-p.z).atan2(p.x);
    (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}

/// The distance between the two particles of each stitched pair in the positions `x`.
pub fn stitch_gaps(stitches: &[drapery::model::Stitch], x: &[Vec3]) -> Vec<f64> {
    (stitches.iter())
        .map(|s| (x[s.a as usize] - x[s.b as usize]).length())
        .collect()
}
