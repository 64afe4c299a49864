//! `drapery render`: PNG stills and GIF animations of a run folder, decoded and inspected.

use assert_cmd::Command;
use std::path::{Path, PathBuf};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn drapery(args: &[&std::ffi::OsStr]) -> (Option<i32>, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_drapery"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Runs `example` into `dir` with `formats`.
fn run_example(example: &str, dir: &Path, formats: &str) {
    let scene = examples().join(example);
    let (code, err) = drapery(&[
        "run".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        dir.as_os_str(),
        "-f".as_ref(),
        formats.as_ref(),
        "-q".as_ref(),
    ]);
    assert_eq!(code, Some(0), "{err}");
}

struct Rgb {
    w: usize,
    h: usize,
    px: Vec<[u8; 3]>,
}

fn decode_png(path: &Path) -> Rgb {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let px = buf[..info.buffer_size()]
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    Rgb {
        w: info.width as usize,
        h: info.height as usize,
        px,
    }
}

fn decode_gif(path: &Path) -> Vec<Rgb> {
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = opts.read_info(std::fs::File::open(path).unwrap()).unwrap();
    let (w, h) = (dec.width() as usize, dec.height() as usize);
    let mut frames = Vec::new();
    while let Some(f) = dec.read_next_frame().unwrap() {
        assert_eq!(
            (f.width as usize, f.height as usize),
            (w, h),
            "partial GIF frame"
        );
        let px = f
            .buffer
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        frames.push(Rgb { w, h, px });
    }
    frames
}

/// Orange-ish: the cloth's front colour (0.92, 0.48, 0.22) at any shade.
fn is_cloth_front(p: [u8; 3]) -> bool {
    let [r, g, b] = p.map(i32::from);
    r > g && g > b && r - b > 60
}

/// The picture is not blank, and the cloth colour covers a good part of its central region.
fn assert_cloth_in_the_middle(img: &Rgb, what: &str) {
    let distinct: std::collections::HashSet<[u8; 3]> = img.px.iter().copied().collect();
    assert!(
        distinct.len() > 10,
        "{what}: blank picture ({} colours)",
        distinct.len()
    );
    let (x0, x1, y0, y1) = (img.w * 2 / 5, img.w * 3 / 5, img.h * 2 / 5, img.h * 3 / 5);
    let mut cloth = 0;
    let mut total = 0;
    for y in y0..y1 {
        for x in x0..x1 {
            total += 1;
            if is_cloth_front(img.px[y * img.w + x]) {
                cloth += 1;
            }
        }
    }
    assert!(
        cloth * 2 > total,
        "{what}: only {cloth} of {total} central pixels have the cloth colour"
    );
    // The corners show the background, not cloth.
    for &(x, y) in &[
        (0, 0),
        (img.w - 1, 0),
        (0, img.h - 1),
        (img.w - 1, img.h - 1),
    ] {
        assert!(
            !is_cloth_front(img.px[y * img.w + x]),
            "{what}: cloth at corner"
        );
    }
}

#[test]
fn png_still_and_gif_animation_of_a_run_show_the_cloth() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("hang");
    run_example("hang.toml", &dir, "obj");

    let still = tmp.path().join("still.png");
    let (code, err) = drapery(&[
        "render".as_ref(),
        dir.as_os_str(),
        "--frame".as_ref(),
        "30".as_ref(),
        "--output".as_ref(),
        still.as_os_str(),
        "--size".as_ref(),
        "200x150".as_ref(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let img = decode_png(&still);
    assert_eq!((img.w, img.h), (200, 150));
    assert_cloth_in_the_middle(&img, "still");

    let gif = tmp.path().join("preview.gif");
    let (code, err) = drapery(&[
        "render".as_ref(),
        dir.as_os_str(),
        "--output".as_ref(),
        gif.as_os_str(),
        "--size".as_ref(),
        "160x120".as_ref(),
        "--every".as_ref(),
        "4".as_ref(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let frames = decode_gif(&gif);
    assert_eq!(frames.len(), 16, "frames 0, 4, …, 60"); // 61 frames, every 4th
    for (i, f) in frames.iter().enumerate() {
        assert_eq!((f.w, f.h), (160, 120));
        assert_cloth_in_the_middle(f, &format!("gif frame {i}"));
    }
    assert_ne!(frames[0].px, frames[15].px, "the animation does not move");
}

#[test]
fn ply_frames_render_like_obj_frames_and_an_explicit_camera_is_used() {
    let tmp = tempfile::tempdir().unwrap();
    let (obj_dir, ply_dir) = (tmp.path().join("obj"), tmp.path().join("ply"));
    run_example("obj_cloth.toml", &obj_dir, "obj");
    run_example("obj_cloth.toml", &ply_dir, "ply");
    let render_png = |dir: &Path, name: &str, extra: &[&str]| {
        let out = tmp.path().join(name);
        let mut args: Vec<std::ffi::OsString> =
            vec!["render".into(), dir.into(), "-o".into(), out.clone().into()];
        args.extend(extra.iter().map(|s| s.into()));
        let a: Vec<&std::ffi::OsStr> = args.iter().map(|s| s.as_os_str()).collect();
        let (code, err) = drapery(&a);
        assert_eq!(code, Some(0), "{err}");
        out
    };
    // Default frame for a PNG: the last one; the automatic camera frames every frame.
    let from_obj = render_png(&obj_dir, "obj.png", &["--size", "160x120"]);
    let from_ply = render_png(&ply_dir, "ply.png", &["--size", "160x120"]);
    assert_eq!(
        std::fs::read(&from_obj).unwrap(),
        std::fs::read(&from_ply).unwrap()
    );
    // The sheet hangs from its edge at z = -0.4, y = 1, down to y ≈ 0.5: look at it from +z.
    let front = render_png(
        &ply_dir,
        "front.png",
        &[
            "--size",
            "120x120",
            "--eye",
            "0,0.75,1.5",
            "--target",
            "0,0.75,-0.4",
            "--fov",
            "30",
        ],
    );
    let img = decode_png(&front);
    assert_eq!((img.w, img.h), (120, 120));
    let saturated = |p: [u8; 3]| {
        let (mx, mn) = (p.iter().max().unwrap(), p.iter().min().unwrap());
        mx - mn > 60
    };
    let centre = img.px[60 * 120 + 60];
    assert!(saturated(centre), "no cloth at the centre: {centre:?}");
    assert!(!saturated(img.px[0]), "cloth in the corner");
}

/// One `error: …` line containing `want`, exit code 1, no picture written.
fn assert_refused(args: &[&std::ffi::OsStr], out: &Path, want: &str) {
    let (code, err) = drapery(args);
    assert_eq!(code, Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(err.contains(want), "{err:?} lacks {want:?}");
    assert!(!err.contains("panicked"));
    assert!(!out.exists());
}

#[test]
fn bad_render_requests_are_one_line_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let png = tmp.path().join("x.png");
    let r = |d: &Path, o: &Path, extra: &[&str]| {
        let mut v: Vec<std::ffi::OsString> = vec!["render".into(), d.into(), "-o".into(), o.into()];
        v.extend(extra.iter().map(|s| s.into()));
        v
    };
    let call = |v: Vec<std::ffi::OsString>, out: &Path, want: &str| {
        let a: Vec<&std::ffi::OsStr> = v.iter().map(|s| s.as_os_str()).collect();
        assert_refused(&a, out, want);
    };
    call(r(&empty, &png, &[]), &png, "no frames to render");
    call(
        r(&tmp.path().join("missing"), &png, &[]),
        &png,
        "cannot read the frame folder",
    );

    let dir = tmp.path().join("chain");
    run_example("chain.toml", &dir, "obj");
    call(
        r(&dir, &png, &["--frame", "101"]),
        &png,
        "there is no frame 101",
    );
    let jpg = tmp.path().join("x.jpg");
    call(r(&dir, &jpg, &[]), &jpg, "unknown picture format '.jpg'");
    call(r(&dir, &png, &["--size", "640"]), &png, "--size");
    call(r(&dir, &png, &["--size", "0x10"]), &png, "--size");
    call(r(&dir, &png, &["--fps", "0"]), &png, "--fps");
    call(
        r(&dir, &png, &["--eye", "1,2", "--target", "0,0,0"]),
        &png,
        "--eye",
    );
    call(
        r(&dir, &png, &["--eye", "0,0,0", "--target", "0,0,0"]),
        &png,
        "coincide",
    );
    // A broken frame file is named.
    std::fs::write(dir.join("frame_00003.obj"), "v 1 2\n").unwrap();
    call(r(&dir, &png, &[]), &png, "frame_00003.obj");
}
