//! `drapery run --format pc2`: one point cache per cloth whose every sample is the f32 of the
//! OBJ frame's vertices, and which a killed and resumed run ends byte-identical.

mod common;

use common::{assert_one_error, assert_same_folders, drapery, examples, run_args};
use drapery::io::pc2::read_pc2;
use std::path::{Path, PathBuf};

/// `examples/<name>.toml` with its duration replaced, written into `dir` (the examples used here
/// generate their grids, so they need no mesh file beside them).
fn short_scene(dir: &Path, name: &str, duration: &str) -> PathBuf {
    let text = std::fs::read_to_string(examples().join(format!("{name}.toml"))).unwrap();
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("duration"))
        .unwrap();
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(
        &path,
        text.replacen(line, &format!("duration = {duration}"), 1),
    )
    .unwrap();
    path
}

/// The vertices of an OBJ frame per object (`o NAME`), parsed from the text as f64.
fn obj_objects(path: &Path) -> Vec<(String, Vec<[f64; 3]>)> {
    let mut objects: Vec<(String, Vec<[f64; 3]>)> = Vec::new();
    for line in std::fs::read_to_string(path).unwrap().lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("o") => objects.push((words.next().unwrap().to_string(), Vec::new())),
            Some("v") => {
                let v: Vec<f64> = words.map(|w| w.parse().unwrap()).collect();
                assert_eq!(v.len(), 3, "{line}");
                objects.last_mut().unwrap().1.push([v[0], v[1], v[2]]);
            }
            _ => {}
        }
    }
    objects
}

/// Runs `name` for `duration` s with `--format obj,pc2` and checks that DIR/<cloth>.pc2 holds,
/// for every cloth, one sample per frame equal to the f32 of the OBJ frame's vertices.
/// Returns the cloth names and point counts.
fn caches_match_the_obj_frames(name: &str, duration: &str) -> Vec<(String, usize)> {
    let tmp = tempfile::tempdir().unwrap();
    let scene = short_scene(tmp.path(), name, duration);
    let out = tmp.path().join("out");
    let r = drapery(&run_args(&scene, &out, &["-f", "obj,pc2"]));
    assert_eq!(r.code, Some(0), "{}", r.stderr);

    let mut frames = Vec::new();
    while out.join(format!("frame_{:05}.obj", frames.len())).exists() {
        frames.push(obj_objects(
            &out.join(format!("frame_{:05}.obj", frames.len())),
        ));
    }
    assert!(frames.len() > 2);
    let mut cloths = Vec::new();
    for (c, (cloth, x0)) in frames[0].iter().enumerate() {
        let path = out.join(format!("{cloth}.pc2"));
        assert_eq!(&std::fs::read(&path).unwrap()[..12], b"POINTCACHE2\0");
        let pc2 = read_pc2(&path).unwrap();
        assert_eq!(pc2.header.points, x0.len(), "{cloth}");
        assert_eq!(
            pc2.header.samples,
            frames.len(),
            "{cloth}: a sample per frame"
        );
        assert_eq!((pc2.header.start_frame, pc2.header.sample_rate), (0.0, 1.0));
        assert_eq!(
            std::fs::metadata(&path).unwrap().len(),
            32 + 12 * (x0.len() * frames.len()) as u64,
            "{cloth}: nothing after the samples"
        );
        for (k, frame) in frames.iter().enumerate() {
            let (obj_name, x) = &frame[c];
            assert_eq!(obj_name, cloth);
            assert_eq!(pc2.samples[k].len(), x.len());
            for (i, (p, q)) in pc2.samples[k].iter().zip(x).enumerate() {
                for d in 0..3 {
                    assert_eq!(
                        p[d].to_bits(),
                        (q[d] as f32).to_bits(),
                        "{cloth} frame {k} vertex {i}: {p:?} vs {q:?}"
                    );
                }
            }
        }
        assert_ne!(
            pc2.samples[0],
            pc2.samples[frames.len() - 1],
            "nothing moved"
        );
        cloths.push((cloth.clone(), x0.len()));
    }
    // No cache besides the cloths'.
    let caches = std::fs::read_dir(&out)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().extension() == Some("pc2".as_ref()))
        .count();
    assert_eq!(caches, cloths.len());
    cloths
}

#[test]
fn hang_cache_samples_are_the_f32_of_the_obj_frames() {
    let cloths = caches_match_the_obj_frames("hang", "0.25");
    assert_eq!(cloths, vec![("sheet".to_string(), 33 * 33)]);
}

#[test]
fn two_cloths_give_one_cache_each_with_their_point_counts() {
    let cloths = caches_match_the_obj_frames("two_sheets", "0.1");
    assert_eq!(
        cloths,
        vec![
            ("lower".to_string(), 21 * 21),
            ("upper".to_string(), 17 * 17)
        ]
    );
}

/// Exit code of the hidden `--abort-after-frame`.
const ABORTED: i32 = 134;

#[test]
fn a_killed_run_resumes_to_a_byte_identical_cache() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = short_scene(tmp.path(), "two_sheets", "0.2");
    let (full, cut) = (tmp.path().join("full"), tmp.path().join("cut"));
    let r = drapery(&run_args(&scene, &full, &["-f", "obj,pc2"]));
    assert_eq!(r.code, Some(0), "{}", r.stderr);

    let r = drapery(&run_args(
        &scene,
        &cut,
        &["-f", "pc2,obj", "--abort-after-frame", "5"],
    ));
    assert_eq!(r.code, Some(ABORTED), "{}", r.stderr);
    assert!(!cut.join("frame_00006.obj").exists());
    // The caches hold exactly the frames the state names: 0 to 5.
    for cloth in ["lower", "upper"] {
        assert_eq!(
            read_pc2(&cut.join(format!("{cloth}.pc2")))
                .unwrap()
                .header
                .samples,
            6
        );
    }

    // What a kill a little later would leave: in `lower.pc2` a whole sample 6 (here a wrong
    // one) already counted by the header though the state still names frame 5; in `upper.pc2`
    // half a sample written and not yet counted.
    let lower = cut.join("lower.pc2");
    let mut b = std::fs::read(&lower).unwrap();
    b.extend(std::iter::repeat_n(0x3c, 21 * 21 * 12));
    b[28..32].copy_from_slice(&7i32.to_le_bytes());
    std::fs::write(&lower, b).unwrap();
    assert_eq!(read_pc2(&lower).unwrap().header.samples, 7);
    let upper = cut.join("upper.pc2");
    let mut b = std::fs::read(&upper).unwrap();
    b.extend(std::iter::repeat_n(0xa5, 17 * 17 * 6));
    std::fs::write(&upper, b).unwrap();
    assert_eq!(read_pc2(&upper).unwrap().header.samples, 6);

    let r = drapery(&run_args(&scene, &cut, &["-f", "obj,pc2", "--resume"]));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert_same_folders(&full, &cut);
}

#[test]
fn a_cache_that_does_not_match_the_state_stops_the_resume_naming_it() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = short_scene(tmp.path(), "hang", "0.1");
    let out = tmp.path().join("out");
    let r = drapery(&run_args(
        &scene,
        &out,
        &["-f", "pc2", "--stop-after-frames", "3"],
    ));
    assert_one_error(&r, &["stopped after frame 3"]);
    // Frames 0 to 3 are needed to continue; cut the cache to 2 samples.
    let cache = out.join("sheet.pc2");
    let mut b = std::fs::read(&cache).unwrap();
    b.truncate(32 + 2 * 33 * 33 * 12);
    b[28..32].copy_from_slice(&2i32.to_le_bytes());
    std::fs::write(&cache, &b).unwrap();
    let r = drapery(&run_args(&scene, &out, &["-f", "pc2", "--resume"]));
    assert_one_error(&r, &["sheet.pc2", "holds 2 samples, 4 are needed"]);
}

#[test]
fn a_cloth_name_that_cannot_name_a_file_is_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(short_scene(tmp.path(), "hang", "0.1")).unwrap();
    let scene = tmp.path().join("slash.toml");
    std::fs::write(
        &scene,
        text.replace("name = \"sheet\"", "name = \"../sheet\""),
    )
    .unwrap();
    let out = tmp.path().join("out");
    let r = drapery(&run_args(&scene, &out, &["-f", "obj,pc2"]));
    assert_one_error(&r, &["slash.toml", "cloth[0].name", "'../sheet'", "pc2"]);
    assert!(!out.exists());
    // Other formats do not name files after cloths.
    let r = drapery(&run_args(&scene, &out, &["-f", "obj"]));
    assert_eq!(r.code, Some(0), "{}", r.stderr);
}
