//! End-to-end tests of the `drapery` command: shipped examples, `validate`, help, and one test
//! per class of bad input (one error line naming the file and the field, exit code 1, no frames).

use assert_cmd::Command;
use drapery::io::obj::read_obj;
use drapery::scene::Scene;
use std::path::{Path, PathBuf};

fn drapery() -> Command {
    Command::new(env!("CARGO_BIN_EXE_drapery"))
}

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

struct Out {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

fn run(args: &[&std::ffi::OsStr]) -> Out {
    let o = drapery().args(args).output().expect("the binary runs");
    Out {
        code: o.status.code(),
        stdout: String::from_utf8_lossy(&o.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
    }
}

fn frame_files(dir: &Path) -> Vec<String> {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut v: Vec<String> = rd
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("frame_"))
        .collect();
    v.sort();
    v
}

/// A scratch folder holding a scene (and meshes), with an output folder path inside it.
struct Case {
    dir: tempfile::TempDir,
}

impl Case {
    fn new() -> Case {
        Case {
            dir: tempfile::tempdir().expect("temp dir"),
        }
    }
    fn file(&self, name: &str, content: impl AsRef<[u8]>) -> PathBuf {
        let p = self.dir.path().join(name);
        std::fs::write(&p, content).expect("write test file");
        p
    }
    fn out(&self) -> PathBuf {
        self.dir.path().join("out")
    }
    /// Runs the scene and checks the bad-input contract: exit code 1, exactly one stderr line
    /// `error: …` containing every `want`, no output folder and no frames.
    fn assert_rejected(&self, scene: &Path, wants: &[&str]) {
        let out = self.out();
        let r = run(&[
            "run".as_ref(),
            scene.as_os_str(),
            "--output".as_ref(),
            out.as_os_str(),
        ]);
        assert_eq!(r.code, Some(1), "stderr: {}", r.stderr);
        let lines: Vec<&str> = r.stderr.lines().collect();
        assert_eq!(
            lines.len(),
            1,
            "one error line expected, got {:?}",
            r.stderr
        );
        assert!(lines[0].starts_with("error: "), "{}", lines[0]);
        assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
        for w in wants {
            assert!(lines[0].contains(w), "{:?} lacks {w:?}", lines[0]);
        }
        assert!(frame_files(&out).is_empty(), "frames written on bad input");
        assert!(!out.exists(), "output folder created on bad input");
        // `validate` rejects it the same way.
        let v = run(&["validate".as_ref(), scene.as_os_str()]);
        assert_eq!(v.code, Some(1), "validate: {}", v.stderr);
        assert_eq!(v.stderr.lines().count(), 1, "{}", v.stderr);
    }
}

const GOOD: &str = r#"
[simulation]
duration = 0.1
dt = 0.01
frame_rate = 20

[[cloth]]
name = "sheet"
mesh = "m.obj"
vertex_mass = 0.01
stretch_stiffness = 100
pin = [0]
"#;

const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

/// A case with `scene.toml` = `GOOD` edited by `edit`, and `m.obj` = `mesh`.
fn case(edit: impl Fn(&str) -> String, mesh: &[u8]) -> (Case, PathBuf) {
    let c = Case::new();
    c.file("m.obj", mesh);
    let s = c.file("scene.toml", edit(GOOD));
    (c, s)
}

fn same(s: &str) -> String {
    s.to_string()
}

// ----------------------------------------------------------------------------- examples

/// Runs an example end to end and checks frame count, frame 0 = input, pins held, motion.
fn run_example(name: &str) {
    let scene_path = examples().join(name);
    let scene = Scene::load(&scene_path).expect("example loads");
    let c = Case::new();
    let out = c.out();
    let r = run(&[
        "run".as_ref(),
        scene_path.as_os_str(),
        "--output".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(r.code, Some(0), "stderr: {}", r.stderr);
    let frames = scene.frame_count() + 1;
    let files = frame_files(&out);
    assert_eq!(files.len(), frames, "{files:?}");
    assert_eq!(files[0], "frame_00000.obj");
    assert_eq!(files[frames - 1], format!("frame_{:05}.obj", frames - 1));
    assert_eq!(r.stdout.lines().count(), 1, "{}", r.stdout);
    assert!(
        r.stdout.contains(&format!("{frames} frames")),
        "{}",
        r.stdout
    );
    assert!(
        r.stdout.contains(&format!("{} steps", scene.step_count())),
        "{}",
        r.stdout
    );

    let input: Vec<_> = scene
        .cloths
        .iter()
        .flat_map(|c| c.mesh.positions.iter().copied())
        .collect();
    let first = read_obj(&out.join(&files[0])).expect("frame 0 reads back");
    assert_eq!(first.positions.len(), input.len());
    for (a, b) in first.positions.iter().zip(&input) {
        for k in 0..3 {
            assert_eq!(
                a[k].to_bits(),
                b[k].to_bits(),
                "frame 0 differs from the input"
            );
        }
    }
    let text = std::fs::read_to_string(out.join(&files[0])).unwrap();
    for cl in &scene.cloths {
        assert!(
            text.contains(&format!("\no {}\n", cl.name)),
            "o {} missing",
            cl.name
        );
    }
    let last = read_obj(&out.join(&files[frames - 1])).expect("last frame reads back");
    assert_eq!(last.faces, first.faces);
    assert_eq!(last.lines, first.lines);
    let mut offset = 0;
    let mut moved = false;
    for cl in &scene.cloths {
        for (i, p0) in cl.mesh.positions.iter().enumerate() {
            let p = last.positions[offset + i];
            assert!(p.is_finite());
            if cl.pins.contains(&(i as u32)) {
                assert_eq!(p, *p0, "pinned vertex {i} of '{}' moved", cl.name);
            } else if (p - *p0).length() > 1e-3 {
                moved = true;
            }
        }
        offset += cl.mesh.positions.len();
    }
    assert!(moved, "nothing moved under gravity");
}

#[test]
fn example_hang_runs_end_to_end() {
    run_example("hang.toml");
}

#[test]
fn example_chain_runs_end_to_end() {
    run_example("chain.toml");
}

#[test]
fn example_three_particles_runs_end_to_end() {
    run_example("three_particles.toml");
}

#[test]
fn example_obj_cloth_runs_end_to_end() {
    run_example("obj_cloth.toml");
}

#[test]
fn quiet_run_prints_nothing_and_threads_are_accepted() {
    let (c, s) = case(same, QUAD.as_bytes());
    let out = c.out();
    let r = run(&[
        "run".as_ref(),
        s.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--threads".as_ref(),
        "1".as_ref(),
        "--quiet".as_ref(),
        "--format".as_ref(),
        "obj".as_ref(),
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert_eq!(r.stdout, "");
    assert_eq!(r.stderr, "");
    assert_eq!(frame_files(&out).len(), 3);
}

// ----------------------------------------------------------------------------- validate, help

#[test]
fn validate_reports_counts_without_writing_anything() {
    let r = run(&[
        "validate".as_ref(),
        examples().join("hang.toml").as_os_str(),
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let o = &r.stdout;
    // 33 × 33 grid: 2·32·33 stretch, 2·32·32 shear, 2·31·33 bend springs.
    for want in [
        "cloth 'sheet': 1089 vertices, 1024 faces, 0 line elements, 6206 springs (2112 stretch, 2048 shear, 2046 bend), 2 pinned, mass 0.1 kg",
        "colliders: none",
        "total: 1 cloths, 1089 vertices, 6206 springs, mass 0.1 kg",
        "2 steps per frame",
        "60 frames after frame 0 (61 files)",
        "120 steps",
    ] {
        assert!(o.contains(want), "{o}\nlacks {want:?}");
    }
    let r = run(&[
        "validate".as_ref(),
        examples().join("chain.toml").as_os_str(),
    ]);
    assert!(
        r.stdout
            .contains("10 vertices, 0 faces, 9 line elements, 9 springs"),
        "{}",
        r.stdout
    );
}

#[test]
fn help_explains_every_option() {
    let r = run(&["--help".as_ref()]);
    assert_eq!(r.code, Some(0));
    assert!(r.stdout.contains("run") && r.stdout.contains("validate"));
    let r = run(&["run".as_ref(), "--help".as_ref()]);
    assert_eq!(r.code, Some(0));
    for opt in [
        "--output",
        "--format",
        "--threads",
        "--quiet",
        "--resume",
        "--overwrite",
        "SCENE",
    ] {
        assert!(r.stdout.contains(opt), "run --help lacks {opt}");
    }
    for f in ["obj", "glb", "usd", "ply"] {
        assert!(r.stdout.contains(f), "run --help lacks format {f}");
    }
}

#[test]
fn usage_errors_keep_clap_exit_code_two() {
    let (c, s) = case(same, QUAD.as_bytes());
    let r = run(&["run".as_ref(), s.as_os_str()]);
    assert_eq!(r.code, Some(2));
    assert!(r.stderr.contains("--output"));
    let out = c.out();
    let r = run(&[
        "run".as_ref(),
        s.as_os_str(),
        "--output".as_ref(),
        out.as_os_str(),
        "--threads".as_ref(),
        "0".as_ref(),
    ]);
    assert_eq!(r.code, Some(2));
    assert!(!out.exists());
}

#[test]
fn unknown_formats_are_refused_before_writing() {
    let (c, s) = case(same, QUAD.as_bytes());
    let out = c.out();
    let r = run(&[
        "run".as_ref(),
        s.as_os_str(),
        "--output".as_ref(),
        out.as_os_str(),
        "--format".as_ref(),
        "obj,fbx".as_ref(),
    ]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(r.stderr.contains("'fbx'"), "{}", r.stderr);
    assert!(r.stderr.contains("obj, glb, usd, ply"), "{}", r.stderr);
    assert!(!r.stderr.contains("panicked"));
    assert!(!out.exists());
}

// ----------------------------------------------------------------------------- bad scene files

#[test]
fn missing_scene_file_is_named() {
    let c = Case::new();
    let s = c.dir.path().join("nope.toml");
    c.assert_rejected(&s, &["nope.toml"]);
}

#[test]
fn malformed_toml_names_the_line() {
    let (c, s) = case(|t| t.replace("dt = 0.01", "dt = = 0.01"), QUAD.as_bytes());
    c.assert_rejected(&s, &["scene.toml", "line 4"]);
}

#[test]
fn binary_scene_file_is_rejected() {
    let c = Case::new();
    let s = c.file("scene.toml", [0xffu8, 0xfe, 0x00, 0x13, 0x37]);
    c.assert_rejected(&s, &["scene.toml", "not a text"]);
}

#[test]
fn unknown_field_is_named_with_its_line() {
    let (c, s) = case(
        |t| t.replace("stretch_stiffness", "stretch_stifness"),
        QUAD.as_bytes(),
    );
    c.assert_rejected(&s, &["scene.toml", "line 11", "stretch_stifness"]);
}

#[test]
fn unknown_table_is_an_error() {
    let (c, s) = case(
        |t| format!("{t}\n[collisions]\nthickness = 0.01\n"),
        QUAD.as_bytes(),
    );
    c.assert_rejected(&s, &["scene.toml", "collisions"]);
}

#[test]
fn missing_field_is_named() {
    let (c, s) = case(|t| t.replace("frame_rate = 20\n", ""), QUAD.as_bytes());
    c.assert_rejected(&s, &["scene.toml", "frame_rate"]);
    let (c, s) = case(|t| t.replace("vertex_mass = 0.01\n", ""), QUAD.as_bytes());
    c.assert_rejected(
        &s,
        &[
            "scene.toml",
            "line 7, cloth[0].density",
            "vertex_mass",
            "density",
        ],
    );
}

#[test]
fn zero_or_negative_step_is_refused() {
    for dt in ["0", "-0.01", "0.0"] {
        let (c, s) = case(
            |t| t.replace("dt = 0.01", &format!("dt = {dt}")),
            QUAD.as_bytes(),
        );
        c.assert_rejected(&s, &["scene.toml", "simulation.dt", "> 0"]);
    }
}

#[test]
fn negative_stiffness_or_mass_is_refused() {
    let (c, s) = case(
        |t| t.replace("stretch_stiffness = 100", "stretch_stiffness = -1"),
        QUAD.as_bytes(),
    );
    c.assert_rejected(&s, &["scene.toml", "cloth[0].stretch_stiffness", "-1"]);
    let (c, s) = case(
        |t| t.replace("vertex_mass = 0.01", "vertex_mass = -0.01"),
        QUAD.as_bytes(),
    );
    c.assert_rejected(&s, &["scene.toml", "cloth[0].vertex_mass", "> 0"]);
}

#[test]
fn frame_rate_that_does_not_divide_the_step_is_refused() {
    let (c, s) = case(
        |t| t.replace("frame_rate = 20", "frame_rate = 30"),
        QUAD.as_bytes(),
    );
    c.assert_rejected(&s, &["scene.toml", "frame_rate", "dt"]);
}

#[test]
fn pins_out_of_range_are_refused() {
    let (c, s) = case(|t| t.replace("pin = [0]", "pin = [0, 4]"), QUAD.as_bytes());
    c.assert_rejected(&s, &["scene.toml", "cloth[0].pin", "4 is out of range"]);
    let (c, s) = case(|t| t.replace("pin = [0]", "pin = [-1]"), QUAD.as_bytes());
    c.assert_rejected(&s, &["scene.toml", "pin", "-1"]);
}

// ----------------------------------------------------------------------------- bad meshes

#[test]
fn missing_mesh_is_named() {
    let (c, s) = case(|t| t.replace("m.obj", "gone.obj"), QUAD.as_bytes());
    c.assert_rejected(&s, &["scene.toml", "cloth[0] 'sheet'", "gone.obj"]);
}

#[test]
fn unreadable_mesh_is_named() {
    let (c, s) = case(|t| t.replace("m.obj", "adir"), QUAD.as_bytes());
    std::fs::create_dir(c.dir.path().join("adir")).unwrap();
    c.assert_rejected(&s, &["scene.toml", "adir"]);
}

fn bad_mesh(mesh: &[u8], wants: &[&str]) {
    let (c, s) = case(same, mesh);
    let mut all = vec!["m.obj"];
    all.extend_from_slice(wants);
    c.assert_rejected(&s, &all);
}

#[test]
fn mesh_with_a_bad_number_names_the_line() {
    bad_mesh(
        b"v 0 0 0\nv 1 0 0\nv 1 1.2.3 0\nv 0 1 0\nf 1 2 3 4\n",
        &["line 3", "1.2.3"],
    );
}

#[test]
fn mesh_with_nan_or_infinite_coordinates_names_the_line() {
    bad_mesh(
        b"v 0 0 0\nv 1 0 0\nv 1 NaN 0\nv 0 1 0\nf 1 2 3 4\n",
        &["line 3", "non-finite"],
    );
    bad_mesh(
        b"v 0 0 0\nv inf 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
        &["line 2", "non-finite"],
    );
    bad_mesh(
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1e999 0\nf 1 2 3 4\n",
        &["line 4", "non-finite"],
    );
}

#[test]
fn mesh_with_face_indices_out_of_range_names_the_line() {
    bad_mesh(
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 5\n",
        &["line 5", "5"],
    );
    bad_mesh(
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 0 1 2\n",
        &["line 5", "0"],
    );
    bad_mesh(
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nl 1 -9\n",
        &["line 5", "-9"],
    );
}

#[test]
fn mesh_with_degenerate_faces_names_the_line() {
    bad_mesh(
        b"v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 4\nf 1 2 3\n",
        &["line 6", "degenerate"],
    );
    bad_mesh(
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 2 4\n",
        &["line 5", "degenerate"],
    );
}

#[test]
fn mesh_with_large_polygons_is_refused() {
    bad_mesh(
        b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\nf 1 2 3 4 5\n",
        &["line 6", "5 vertices", "quads"],
    );
}

#[test]
fn mesh_without_vertices_is_refused() {
    bad_mesh(b"# empty\n", &["no vertices"]);
    bad_mesh(b"", &["no vertices"]);
}

#[test]
fn binary_garbage_mesh_is_refused() {
    let mut junk = b"v 0 0 0\n".to_vec();
    junk.extend((0..200u32).map(|i| (i.wrapping_mul(2654435761) >> 13) as u8));
    bad_mesh(&junk, &["binary"]);
    bad_mesh(&[0xc3, 0x28, b'\n'], &["not a text"]);
}

// ----------------------------------------------------------------------------- blow-up

#[test]
fn a_blown_up_simulation_names_the_frame_and_keeps_earlier_frames() {
    // One free particle on a spring leaves at ~1e308 m/s: its position and the spring force
    // overflow during the first step, which must fail cleanly.
    let (c, s) = case(
        |t| {
            t.replace(
                "pin = [0]",
                "pin = [0]\ninitial_velocity = [1e308, 1e308, 1e308]",
            )
            .replace("stretch_stiffness = 100", "stretch_stiffness = 1e300")
        },
        b"v 0 0 0\nv 1 0 0\nl 1 2\n",
    );
    let out = c.out();
    let r = run(&[
        "run".as_ref(),
        s.as_os_str(),
        "--output".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(r.code, Some(1), "stdout: {} stderr: {}", r.stdout, r.stderr);
    assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
    assert!(r.stderr.starts_with("error: frame 1: "), "{}", r.stderr);
    assert!(!r.stderr.contains("panicked"));
    assert_eq!(frame_files(&out), vec!["frame_00000.obj".to_string()]);
    let f0 = read_obj(&out.join("frame_00000.obj")).unwrap();
    assert_eq!(f0.positions[1].x, 1.0);
}
