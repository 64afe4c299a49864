//! Helpers shared by the end-to-end tests: the examples folder, running the binary, reading
//! frames, and running an example with `drapery check --scene` on every frame.
#![allow(dead_code)]

use assert_cmd::Command;
use drapery::Vec3;
use drapery::io::obj::read_obj;
use drapery::scene::Scene;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};

pub fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

pub struct Out {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

pub fn drapery(args: &[&OsStr]) -> Out {
    let o = Command::new(env!("CARGO_BIN_EXE_drapery"))
        .args(args)
        .output()
        .expect("the binary runs");
    Out {
        code: o.status.code(),
        stdout: String::from_utf8_lossy(&o.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
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
    let scene_path = examples().join(format!("{name}.toml"));
    let scene = Scene::load(&scene_path).expect("example loads");
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
