//! `drapery run --resume` / `--overwrite`: an interrupted run continues to exactly the bits of an
//! uninterrupted one, and a folder holding another run is never mixed into silently.

mod common;

use common::{assert_one_error, assert_same_folders, contents, drapery, examples, run_args};

const ALL: &str = "obj,glb,usd,ply";

#[test]
fn a_stopped_run_resumes_to_the_same_bits_in_every_file() {
    let scene = examples().join("hang.toml");
    let tmp = tempfile::tempdir().unwrap();
    let (full, cut) = (tmp.path().join("full"), tmp.path().join("cut"));
    let r = drapery(&run_args(&scene, &full, &["-f", ALL]));
    assert_eq!(r.code, Some(0), "{}", r.stderr);

    let r = drapery(&run_args(
        &scene,
        &cut,
        &["-f", ALL, "--stop-after-frames", "17"],
    ));
    assert_one_error(&r, &["stopped after frame 17"]);
    assert!(cut.join("frame_00017.obj").exists());
    assert!(!cut.join("frame_00018.obj").exists());
    assert!(
        !cut.join("hang.glb").exists(),
        "a killed run writes no whole-run file"
    );
    assert!(cut.join("state.bin").exists());

    // A plain rerun is refused and changes nothing.
    let before = contents(&cut);
    let r = drapery(&run_args(&scene, &cut, &["-f", ALL]));
    assert_one_error(
        &r,
        &["frames 0 to 17 of this scene", "--resume", "--overwrite"],
    );
    // Resuming with other formats is refused too.
    let r = drapery(&run_args(&scene, &cut, &["-f", "obj", "--resume"]));
    assert_one_error(&r, &["--format obj,glb,usd,ply"]);
    assert!(contents(&cut) == before, "a refused run changed the folder");

    // Stop once more further on (formats in another order are the same set), then finish.
    let r = drapery(&run_args(
        &scene,
        &cut,
        &[
            "-f",
            "ply,usd,glb,obj",
            "--resume",
            "--stop-after-frames",
            "40",
        ],
    ));
    assert_one_error(&r, &["stopped after frame 40"]);
    let mut args = run_args(&scene, &cut, &["-f", ALL, "--resume"]);
    args.retain(|a| a != "-q");
    let r = drapery(&args);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(r.stdout.contains("20 frames written"), "{}", r.stdout);
    assert!(r.stdout.contains("resumed after frame 40"), "{}", r.stdout);
    assert_same_folders(&full, &cut);

    // Resuming a complete run changes nothing; a plain rerun is refused.
    let r = drapery(&run_args(&scene, &cut, &["-f", ALL, "--resume"]));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert_same_folders(&full, &cut);
    let r = drapery(&run_args(&scene, &cut, &["-f", ALL]));
    assert_one_error(&r, &["complete run of this scene", "--overwrite"]);
}

/// A 17 × 17 sheet over 2 s at 60 frames per second: 121 frames.
const SMALL: &str = r#"
[simulation]
duration = 2.0
dt = 0.008333333333333333
frame_rate = 60

[[cloth]]
name = "sheet"
grid = { size = [1.0, 1.0], resolution = [17, 17], center = [0.0, 1.0, 0.0], normal = [0.0, 0.0, 1.0] }
density = 0.1
pin = [0, 16]
initial_velocity = [0.0, 0.0, 0.5]
"#;

/// Exit code of the hidden `--abort-after-frame` (the run's `ABORT_EXIT_CODE`).
const ABORTED: i32 = 134;

#[test]
fn a_killed_run_resumes_to_the_same_bits() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tmp.path().join("small.toml");
    std::fs::write(&scene, SMALL).unwrap();
    let (full, cut) = (tmp.path().join("full"), tmp.path().join("cut"));
    let r = drapery(&run_args(&scene, &full, &["-f", "obj,glb"]));
    assert_eq!(r.code, Some(0), "{}", r.stderr);

    // Killed right after frame 10's files and state are on disk, while the step loop may be
    // frames ahead: the process ends there, as under a kill, with nothing printed.
    let r = drapery(&run_args(
        &scene,
        &cut,
        &["-f", "obj,glb", "--abort-after-frame", "10"],
    ));
    assert_eq!(r.code, Some(ABORTED), "{}", r.stderr);
    assert_eq!(r.stderr, "");
    assert!(cut.join("frame_00010.obj").exists());
    assert!(!cut.join("frame_00011.obj").exists());
    assert!(!cut.join("small.glb").exists());
    assert!(cut.join("state.bin").exists());

    // What a kill a little later, inside frame 11's write, would add after the last state: a
    // whole frame 11 file (here one that is wrong), a temporary file of a write cut short, and
    // frame 11's positions appended to the history (here garbage). Resuming rewrites frame 11
    // and cuts the history back to the frames the state names.
    std::fs::write(cut.join("frame_00011.obj"), "v 0 0 0\n").unwrap();
    std::fs::write(cut.join(".frame_00012.obj.tmp99999"), "v 0").unwrap();
    let history = cut.join("history.bin");
    let mut h = std::fs::read(&history).unwrap();
    assert_eq!(h.len(), 11 * 17 * 17 * 24, "frames 0 to 10 in the history");
    h.extend(std::iter::repeat_n(0xa5, 17 * 17 * 24));
    std::fs::write(&history, h).unwrap();

    let mut args = run_args(&scene, &cut, &["-f", "obj,glb", "--resume"]);
    args.retain(|a| a != "-q");
    let r = drapery(&args);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(r.stdout.contains("resumed after frame 10"), "{}", r.stdout);
    // Temporary files of a write cut short may remain; everything else is identical.
    for e in std::fs::read_dir(&cut).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        if name.starts_with('.') && name.contains(".tmp") {
            std::fs::remove_file(cut.join(name)).unwrap();
        }
    }
    assert_same_folders(&full, &cut);
}

#[test]
fn resume_without_a_run_starts_from_frame_zero() {
    let scene = examples().join("three_particles.toml");
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    assert_eq!(drapery(&run_args(&scene, &a, &[])).code, Some(0));
    let r = drapery(&run_args(&scene, &b, &["--resume"]));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert_same_folders(&a, &b);
}

#[test]
fn a_folder_of_another_scene_is_refused_unless_overwrite() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let chain = examples().join("chain.toml");
    let three = examples().join("three_particles.toml");
    assert_eq!(
        drapery(&run_args(&chain, &out, &["-f", "ply,usd"])).code,
        Some(0)
    );
    let before = contents(&out);
    assert!(before.contains_key("frame_00100.ply") && before.contains_key("chain.usda"));
    for extra in [&[][..], &["--resume"][..]] {
        let r = drapery(&run_args(&three, &out, extra));
        assert_one_error(&r, &["another scene", "--overwrite"]);
        assert!(contents(&out) == before, "a refused run changed the folder");
    }
    // Both flags at once is a usage error.
    let r = drapery(&run_args(&three, &out, &["--resume", "--overwrite"]));
    assert_eq!(r.code, Some(2));

    let r = drapery(&run_args(&three, &out, &["--overwrite"]));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let after = contents(&out);
    let frames: Vec<&String> = after.keys().filter(|n| n.starts_with("frame_")).collect();
    // three_particles: 2 s at 30 frames per second = 61 OBJ frames, no PLY left over.
    let reference = tmp.path().join("ref");
    assert_eq!(drapery(&run_args(&three, &reference, &[])).code, Some(0));
    assert_same_folders(&reference, &out);
    assert!(frames.iter().all(|n| n.ends_with(".obj")), "{frames:?}");

    // Frames without a state (e.g. from elsewhere) are not resumed over.
    let stray = tmp.path().join("stray");
    std::fs::create_dir(&stray).unwrap();
    std::fs::write(stray.join("frame_00000.obj"), "v 0 0 0\n").unwrap();
    let r = drapery(&run_args(&three, &stray, &["--resume"]));
    assert_one_error(&r, &["no state.bin", "--overwrite"]);
    let r = drapery(&run_args(&three, &stray, &[]));
    assert_one_error(&r, &["already holds frames", "--overwrite"]);
}

#[test]
fn an_edited_mesh_or_a_damaged_state_is_not_resumed() {
    let tmp = tempfile::tempdir().unwrap();
    for f in ["chain.toml", "chain.obj"] {
        std::fs::copy(examples().join(f), tmp.path().join(f)).unwrap();
    }
    let scene = tmp.path().join("chain.toml");
    let out = tmp.path().join("out");
    let r = drapery(&run_args(&scene, &out, &["--stop-after-frames", "5"]));
    assert_one_error(&r, &["stopped after frame 5"]);

    // Same scene text, one mesh vertex moved: another scene.
    let mesh = std::fs::read_to_string(tmp.path().join("chain.obj")).unwrap();
    let edited = mesh.replacen("v 0.0 1.0 0.0", "v 0.0 1.0 0.001", 1);
    assert_ne!(mesh, edited);
    std::fs::write(tmp.path().join("chain.obj"), &edited).unwrap();
    let r = drapery(&run_args(&scene, &out, &["--resume"]));
    assert_one_error(&r, &["another scene"]);
    std::fs::write(tmp.path().join("chain.obj"), &mesh).unwrap();

    // A damaged state is named.
    let state = out.join("state.bin");
    let mut bytes = std::fs::read(&state).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x40;
    std::fs::write(&state, &bytes).unwrap();
    let r = drapery(&run_args(&scene, &out, &["--resume"]));
    assert_one_error(&r, &["state.bin", "damaged", "--overwrite"]);
}
