//! `drapery run` writes frames on a writer thread, overlapped with the next step: the files are
//! the same bytes as the library's writers give for the library stepped directly, and a failed
//! write is one clear error naming the file, with nothing claimed on disk beyond it.

mod common;

use common::{assert_one_error, assert_same_folders, contents, drapery, examples, run_args};
use drapery::io::obj::write_obj;
use drapery::io::ply::write_ply;
use drapery::scene::Scene;
use std::path::Path;

/// Steps `scene` with the library and writes every frame as OBJ and PLY into `dir`.
fn reference_frames(scene: &Path, dir: &Path) {
    let scene = Scene::load(scene).unwrap();
    let mut sim = scene.build().unwrap();
    std::fs::create_dir_all(dir).unwrap();
    for k in 0..=scene.frame_count() {
        if k > 0 {
            for _ in 0..scene.steps_per_frame() {
                sim.step(scene.step_size()).unwrap();
            }
        }
        let (cloths, x) = (sim.model().cloths(), sim.model().positions());
        write_obj(&dir.join(format!("frame_{k:05}.obj")), cloths, x).unwrap();
        write_ply(&dir.join(format!("frame_{k:05}.ply")), cloths, x).unwrap();
    }
}

#[test]
fn frames_written_on_the_writer_thread_match_the_library_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, want) = (tmp.path().join("out"), tmp.path().join("want"));
    let scene = examples().join("hang.toml");
    let r = drapery(&run_args(&scene, &out, &["-f", "obj,ply"]));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    reference_frames(&scene, &want);

    let mut got = contents(&out);
    assert!(got.remove("state.bin").is_some());
    let want = contents(&want);
    assert_eq!(want.len(), 2 * 61, "frames 0..=60 as obj and ply");
    assert_eq!(
        got.keys().collect::<Vec<_>>(),
        want.keys().collect::<Vec<_>>()
    );
    for (name, bytes) in &want {
        assert!(bytes == &got[name], "{name} differs from the library's");
    }
}

#[test]
fn a_frame_that_cannot_be_written_is_named_and_nothing_after_it_is_claimed() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = examples().join("hang.toml");
    let (full, out) = (tmp.path().join("full"), tmp.path().join("out"));
    assert_eq!(drapery(&run_args(&scene, &full, &[])).code, Some(0));
    let r = drapery(&run_args(&scene, &out, &["--stop-after-frames", "5"]));
    assert_one_error(&r, &["stopped after frame 5"]);
    assert!(out.join("frame_00005.obj").exists() && out.join("state.bin").exists());

    // frame 10's name is taken by a folder: the rename of its temporary file fails.
    let blocker = out.join("frame_00010.obj");
    std::fs::create_dir(&blocker).unwrap();
    std::fs::write(blocker.join("keep"), "x").unwrap();
    let r = drapery(&run_args(&scene, &out, &["--resume"]));
    assert_one_error(&r, &["frame_00010.obj"]);
    assert!(out.join("frame_00009.obj").is_file());
    assert!(
        !out.join("frame_00011.obj").exists(),
        "frames handed off after the failed one are not written"
    );

    // The state claims no frame past the last one written: resuming gives the full run's bits.
    std::fs::remove_dir_all(&blocker).unwrap();
    let r = drapery(&run_args(&scene, &out, &["--resume"]));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    for e in std::fs::read_dir(&out).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.contains(".tmp"), "{name} left behind");
    }
    assert_same_folders(&full, &out);
}
