//! The same scene gives the same bits on one and on two worker threads, collisions included.

use assert_cmd::Command;
use std::path::Path;

/// Runs `scene` with `--threads threads` into `out` and returns every frame file's bytes.
fn run(scene: &Path, out: &Path, threads: &str) -> Vec<(String, Vec<u8>)> {
    let o = Command::new(env!("CARGO_BIN_EXE_drapery"))
        .args(["run", "--quiet", "--threads", threads, "--output"])
        .arg(out)
        .arg(scene)
        .output()
        .expect("the binary runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("frame_")
        })
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    files.sort();
    files
}

#[test]
fn two_sheets_falling_on_each_other_give_the_same_bits_on_one_and_two_threads() {
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let scene = std::fs::read_to_string(examples.join("two_sheets.toml")).unwrap();
    // long enough for the upper sheet to land on the lower one
    let scene = scene.replace("duration = 1.5", "duration = 0.7");
    assert!(scene.contains("duration = 0.7"));
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("two_sheets.toml");
    std::fs::write(&path, scene).unwrap();
    let one = run(&path, &tmp.path().join("one"), "1");
    let two = run(&path, &tmp.path().join("two"), "2");
    assert_eq!(one.len(), 43, "frames 0..=42 at 60 fps over 0.7 s");
    for ((name, a), (_, b)) in one.iter().zip(&two) {
        assert!(a == b, "{name} differs between one and two threads");
    }
    // the sheets did move (the comparison is not between two copies of the initial state)
    assert_ne!(one[0].1, one[42].1);
}
