use super::*;
use crate::mesh::Mesh;

fn sheet(normal: Vec3) -> RenderScene {
    let m = Mesh::grid([1.0, 1.0], [8, 8], Vec3::ZERO, normal).unwrap();
    let info = ClothInfo {
        material: Default::default(),
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

/// Where `p` lands in a `w × h` picture taken by `cam`, in pixels from the top-left corner
/// (a pinhole model written out here, independent of the renderer's): the forward axis looks at
/// the target, right is forward × up, and the focal length puts the vertical field of view on
/// the picture's height.
fn project(cam: &Camera, w: u32, h: u32, p: Vec3) -> (f64, f64) {
    let forward = (cam.target - cam.eye).normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    let d = p - cam.eye;
    let focal = 0.5 * h as f64 / (0.5 * cam.fov_y_deg.to_radians()).tan();
    let depth = d.dot(forward);
    (
        0.5 * w as f64 + focal * d.dot(right) / depth,
        0.5 * h as f64 - focal * d.dot(up) / depth,
    )
}

/// The picture's background at row `y` of `h`: the vertical gradient, averaged over the two
/// supersampled rows of the pixel.
fn background_at(y: u32, h: u32) -> [f64; 3] {
    let (top, bottom) = ([0.96, 0.97, 0.99], [0.74, 0.77, 0.82]);
    let row = |r: f64| -> [f64; 3] {
        let t = (r + 0.5) / (2 * h) as f64;
        [0, 1, 2].map(|k| top[k] + (bottom[k] - top[k]) * t)
    };
    let (a, b) = (row(2.0 * y as f64), row(2.0 * y as f64 + 1.0));
    [0, 1, 2].map(|k| 255.0 * 0.5 * (a[k] + b[k]))
}

/// Projected bounding box `(x0, y0, x1, y1)` of some points.
fn projected_box(cam: &Camera, w: u32, h: u32, pts: &[Vec3]) -> (f64, f64, f64, f64) {
    pts.iter().map(|p| project(cam, w, h, *p)).fold(
        (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), (x, y)| (a.min(x), b.min(y), c.max(x), d.max(y)),
    )
}

fn inside(b: (f64, f64, f64, f64), x: u32, y: u32, margin: f64) -> bool {
    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
    px >= b.0 - margin && px <= b.2 + margin && py >= b.1 - margin && py <= b.3 + margin
}

#[test]
fn the_sample_animation_is_drawn_where_its_geometry_projects() {
    // the glTF/USD sample (a falling, waving 6×5 sheet and a rope) over a ground, framed by the
    // automatic camera: in every frame the cloth's colours appear only inside the projected box
    // of the sheet, cover its projected area to within its outline, and every pixel outside all
    // projected boxes is the bare background.
    let (cloths, frames) = crate::io::gltf::tests::sample_animation();
    let ground = vec![
        Vec3::new(-2.0, -1.0, -2.0),
        Vec3::new(2.0, -1.0, -2.0),
        Vec3::new(2.0, -1.0, 2.0),
        Vec3::new(-2.0, -1.0, 2.0),
    ];
    let scenes: Vec<RenderScene> = frames
        .iter()
        .map(|f| {
            let mut s = RenderScene::from_frame(&cloths, f).unwrap();
            s.add_collider(ground.clone(), vec![[0, 2, 1], [0, 3, 2]]);
            s
        })
        .collect();
    let (w, h) = (240, 180);
    let cam = auto_camera(&scenes, w, h).unwrap();
    let images = render_frames(&scenes, None, w, h).unwrap();
    assert_eq!(images.len(), frames.len());
    let sheet = &cloths[0];
    let triangles = sheet.mesh.triangles();
    for (k, (img, x)) in images.iter().zip(&frames).enumerate() {
        let pts = &x[sheet.range()];
        let sheet_box = projected_box(&cam, w, h, pts);
        let rope_box = projected_box(&cam, w, h, &x[cloths[1].range()]);
        let ground_box = projected_box(&cam, w, h, &ground);
        let proj: Vec<(f64, f64)> = pts.iter().map(|p| project(&cam, w, h, *p)).collect();
        // projected area (the sheet does not fold over in this view) and outline length
        let area: f64 = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| proj[i as usize]);
                0.5 * ((b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)).abs()
            })
            .sum();
        let mut edge_count = std::collections::HashMap::new();
        for t in &triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edge_count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        let outline: f64 = edge_count
            .iter()
            .filter(|(_, n)| **n == 1)
            .map(|((a, b), _)| {
                let (p, q) = (proj[*a as usize], proj[*b as usize]);
                (q.0 - p.0).hypot(q.1 - p.1)
            })
            .sum();
        let mut cloth = 0usize;
        for y in 0..h {
            for x in 0..w {
                let p = img.pixel(x, y);
                if is_orange(p) || is_blue(p) {
                    cloth += 1;
                    assert!(
                        inside(sheet_box, x, y, 1.0),
                        "frame {k}: cloth colour at ({x}, {y})"
                    );
                }
                if ![sheet_box, rope_box, ground_box]
                    .iter()
                    .any(|b| inside(*b, x, y, 1.5))
                {
                    let want = background_at(y, h);
                    for c in 0..3 {
                        assert!(
                            (p[c] as f64 - want[c]).abs() <= 1.0,
                            "frame {k}: ({x}, {y}) is {p:?}, background {want:?}"
                        );
                    }
                }
            }
        }
        assert!(
            (cloth as f64 - area).abs() <= outline,
            "frame {k}: {cloth} cloth pixels for a projected area of {area:.0} (outline {outline:.0})"
        );
    }
}
