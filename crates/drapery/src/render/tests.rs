use super::*;
use crate::mesh::Mesh;

fn sheet(normal: Vec3) -> RenderScene {
    let m = Mesh::grid([1.0, 1.0], [8, 8], Vec3::ZERO, normal).unwrap();
    let info = ClothInfo {
        name: "s".into(),
        offset: 0,
        mesh: m.clone(),
    };
    RenderScene::from_frame(&[info], &m.positions).unwrap()
}

fn front_cam() -> Camera {
    Camera::new(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 40.0).unwrap()
}

fn is_orange(p: [u8; 3]) -> bool {
    p[0] as i32 > p[2] as i32 + 60
}
fn is_blue(p: [u8; 3]) -> bool {
    p[2] as i32 > p[0] as i32 + 60
}

#[test]
fn sheet_facing_the_camera_covers_the_centre_in_the_front_colour() {
    let img = render(&sheet(Vec3::Z), &front_cam(), 64, 48).unwrap();
    assert_eq!(img.rgb.len(), 64 * 48 * 3);
    let c = img.pixel(32, 24);
    assert!(is_orange(c), "centre {c:?}");
    // The sheet spans ±0.5 m at 3 m with a 40° field of view: the corners show background.
    for (x, y) in [(0, 0), (63, 0), (0, 47), (63, 47)] {
        let p = img.pixel(x, y);
        assert!(!is_orange(p) && !is_blue(p), "corner {x},{y} {p:?}");
    }
}

#[test]
fn flipped_sheet_shows_the_back_colour() {
    let front = render(&sheet(Vec3::Z), &front_cam(), 32, 32).unwrap();
    let back = render(&sheet(-Vec3::Z), &front_cam(), 32, 32).unwrap();
    let (f, b) = (front.pixel(16, 16), back.pixel(16, 16));
    assert!(is_orange(f) && is_blue(b), "front {f:?} back {b:?}");
    // Seen from behind, the front-facing sheet shows its back.
    let behind = Camera::new(Vec3::new(0.0, 0.0, -3.0), Vec3::ZERO, 40.0).unwrap();
    assert!(is_blue(
        render(&sheet(Vec3::Z), &behind, 32, 32)
            .unwrap()
            .pixel(16, 16)
    ));
}

#[test]
fn auto_camera_frames_a_draped_sheet_and_the_picture_is_not_blank() {
    // A sheet hanging in the x-y plane and a collider ground below it.
    let mut s = sheet(Vec3::Z);
    for p in &mut s.meshes[0].positions {
        p.z = 0.2 * (3.0 * p.x).sin();
        p.y += 1.0;
    }
    s.add_collider(
        vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(-1.0, 0.0, 1.0),
        ],
        vec![[0, 2, 1], [0, 3, 2]],
    );
    let imgs = render_frames(std::slice::from_ref(&s), None, 80, 60).unwrap();
    let img = &imgs[0];
    if let Some(p) = std::env::var_os("DRAPERY_RENDER_DUMP") {
        write_png(std::path::Path::new(&p), img).unwrap();
    }
    let distinct: std::collections::HashSet<[u8; 3]> = img
        .rgb
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    assert!(distinct.len() > 20, "only {} colours", distinct.len());
    let cloth = img
        .rgb
        .chunks_exact(3)
        .filter(|c| is_orange([c[0], c[1], c[2]]))
        .count();
    let grey = img
        .rgb
        .chunks_exact(3)
        .filter(|c| {
            let d = (c[0] as i32 - c[2] as i32).abs();
            d < 12 && c[0] < 170 && c[0] > 40
        })
        .count();
    assert!(cloth > 80 * 60 / 40, "cloth covers {cloth} pixels");
    assert!(grey > 80 * 60 / 50, "collider covers {grey} pixels");
    // The whole scene is inside the picture: the border rows/columns show no cloth.
    for x in 0..80 {
        assert!(!is_orange(img.pixel(x, 0)) && !is_orange(img.pixel(x, 59)));
    }
}

#[test]
fn png_decodes_back_to_the_same_pixels() {
    let img = render(&sheet(Vec3::Z), &front_cam(), 40, 30).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("still.png");
    write_png(&path, &img).unwrap();
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (40, 30));
    assert_eq!(&buf[..info.buffer_size()], &img.rgb[..]);
}

#[test]
fn gif_has_every_frame_at_the_right_size_with_close_colours() {
    let mut scenes = Vec::new();
    for k in 0..4 {
        let mut s = sheet(Vec3::Z);
        for p in &mut s.meshes[0].positions {
            p.z += 0.3 * k as f64 * p.x;
        }
        scenes.push(s);
    }
    let imgs = render_frames(&scenes, Some(&front_cam()), 48, 36).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("preview.gif");
    write_gif(&path, &imgs, 24.0).unwrap();
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = opts.read_info(std::fs::File::open(&path).unwrap()).unwrap();
    let mut n = 0;
    while let Some(f) = dec.read_next_frame().unwrap() {
        assert_eq!((f.width, f.height), (48, 36));
        assert_eq!(f.delay, 4);
        let src = &imgs[n];
        for (a, b) in f.buffer.chunks_exact(4).zip(src.rgb.chunks_exact(3)) {
            for k in 0..3 {
                assert!((a[k] as i32 - b[k] as i32).abs() <= 24, "{a:?} vs {b:?}");
            }
        }
        n += 1;
    }
    assert_eq!(n, 4);
}

#[test]
fn bad_sizes_cameras_and_inputs_are_errors_and_near_geometry_is_clipped() {
    let s = sheet(Vec3::Z);
    assert!(render(&s, &front_cam(), 0, 10).is_err());
    assert!(render(&s, &front_cam(), 10, MAX_SIDE + 1).is_err());
    assert!(Camera::new(Vec3::ZERO, Vec3::ZERO, 40.0).is_err());
    assert!(Camera::new(Vec3::Z, Vec3::ZERO, 180.0).is_err());
    assert!(render_frames(&[RenderScene::default()], None, 10, 10).is_err());
    assert!(gif_bytes(&[], 10.0).is_err());
    let mut bad = s.clone();
    bad.meshes[0].triangles.push([0, 1, 999]);
    assert!(render(&bad, &front_cam(), 10, 10).is_err());
    // Camera inside the sheet's plane region, looking along it: crosses the near plane.
    let inside = Camera::new(Vec3::new(0.0, 0.0, 0.01), Vec3::new(0.0, 0.0, -1.0), 90.0).unwrap();
    let mut tilted = s.clone();
    for p in &mut tilted.meshes[0].positions {
        p.z = p.y; // a slope through the eye's depth
    }
    let img = render(&tilted, &inside, 32, 32).unwrap();
    assert_eq!(img.rgb.len(), 32 * 32 * 3);
    // Looking straight down y still works (up is replaced).
    let down = Camera::new(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, 40.0).unwrap();
    render(&sheet(Vec3::Y), &down, 16, 16).unwrap();
}

#[test]
fn big_preview_dump() {
    let Some(p) = std::env::var_os("DRAPERY_RENDER_DUMP_BIG") else {
        return;
    };
    let (cloths, frames) = crate::io::gltf::tests::sample_animation();
    let mut scenes = Vec::new();
    for f in &frames {
        let mut s = RenderScene::from_frame(&cloths, f).unwrap();
        s.add_collider(
            vec![
                Vec3::new(-2.0, -1.0, -2.0),
                Vec3::new(2.0, -1.0, -2.0),
                Vec3::new(2.0, -1.0, 2.0),
                Vec3::new(-2.0, -1.0, 2.0),
            ],
            vec![[0, 2, 1], [0, 3, 2]],
        );
        scenes.push(s);
    }
    let imgs = render_frames(&scenes, None, 480, 360).unwrap();
    let p = std::path::PathBuf::from(p);
    write_png(&p.with_extension("png"), &imgs[8]).unwrap();
    write_gif(&p.with_extension("gif"), &imgs, 12.0).unwrap();
}
