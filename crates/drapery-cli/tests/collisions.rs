//! Collisions end to end: every collision example is run, `drapery check --scene` must find no
//! intersection and no penetration in any frame, and each example has a physical assertion that
//! could fail. Then `validate`, the initial-intersection warning, `check` on bad frames, glb
//! colliders, render with colliders, the fingerprint, and one test per class of bad input.

use drapery::Vec3;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};

mod common;
use common::{BASE, assert_rejected, drapery, examples, run_and_check};

fn min_y(x: &[Vec3]) -> f64 {
    x.iter().map(|p| p.y).fold(f64::INFINITY, f64::min)
}
fn max_y(x: &[Vec3]) -> f64 {
    x.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max)
}

// ------------------------------------------------------------------------------ examples

#[test]
fn drape_sphere_rests_on_the_sphere_above_the_ground() {
    let (_t, scene, frames) = run_and_check("drape_sphere");
    let th = scene.collision.unwrap().thickness;
    let (first, last) = (&frames[0], frames.last().unwrap());
    let center = Vec3::new(0.0, 0.25, 0.0);
    for (k, x) in frames.iter().enumerate() {
        assert!(min_y(x) >= 0.0, "frame {k}: below the ground");
        for p in x {
            assert!(
                (*p - center).length() >= 0.25,
                "frame {k}: {p} inside the sphere"
            );
        }
    }
    // it fell: its top is now the sphere's top (0.5 m) plus about the thickness, and it hangs
    assert!(max_y(last) < max_y(first) - 0.05, "{}", max_y(last));
    assert!((max_y(last) - 0.5).abs() < 2.0 * th, "{}", max_y(last));
    assert!(
        min_y(last) < 0.1,
        "the edges should hang down: {}",
        min_y(last)
    );
    // resting on the sphere: some vertex within twice the thickness of its surface
    let closest = last
        .iter()
        .map(|p| (*p - center).length() - 0.25)
        .fold(f64::INFINITY, f64::min);
    assert!(closest < 2.0 * th, "{closest}");
}

/// Rotation angle about +y from `p` to `q` (counter-clockwise seen from above).
fn yaw(p: Vec3, q: Vec3) -> f64 {
    let d = (-q.z).atan2(q.x) - (-p.z).atan2(p.x);
    (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}

#[test]
fn spin_sphere_twists_the_sheet_the_way_the_sphere_turns() {
    let (_t, _scene, frames) = run_and_check("spin_sphere");
    let (first, last) = (&frames[0], frames.last().unwrap());
    let angles: Vec<f64> = first
        .iter()
        .zip(last)
        .filter(|(p, _)| p.x.hypot(p.z) > 0.2)
        .map(|(p, q)| yaw(*p, *q))
        .collect();
    let mean = angles.iter().sum::<f64>() / angles.len() as f64;
    // the sphere turns +1.5 rad/s about +y for 1.5 s (2.25 rad); friction drags the sheet the
    // same way
    assert!(mean > 0.3, "mean rotation {mean} rad");
    let forward = angles.iter().filter(|&&a| a > 0.0).count();
    assert!(forward * 10 >= angles.len() * 9, "{angles:?}");
}

#[test]
fn tablecloth_lies_on_the_table_and_hangs_over_its_edges() {
    let (_t, scene, frames) = run_and_check("tablecloth");
    let th = scene.collision.unwrap().thickness;
    let last = frames.last().unwrap();
    let n = 29;
    let centre = last[(n / 2) * n + n / 2];
    assert!(
        (centre.y - 0.75).abs() < 2.0 * th && centre.y >= 0.75,
        "centre {centre}"
    );
    for corner in [0, n - 1, n * (n - 1), n * n - 1] {
        assert!(last[corner].y < 0.65, "corner {corner} at {}", last[corner]);
    }
    assert!(min_y(last) >= 0.0);
}

#[test]
fn pile_falls_and_stacks_onto_itself() {
    let (_t, scene, frames) = run_and_check("pile");
    let th = scene.collision.unwrap().thickness;
    let (first, last) = (&frames[0], frames.last().unwrap());
    let mean = |x: &[Vec3]| x.iter().map(|p| p.y).sum::<f64>() / x.len() as f64;
    assert!(
        mean(last) < 0.2 * mean(first),
        "{} {}",
        mean(first),
        mean(last)
    );
    assert!(min_y(last) >= 0.0);
    // stacked: vertices with another vertex right below them (within 2 cm sideways), at least
    // 1.5 thicknesses lower
    let stacked = last
        .iter()
        .filter(|p| {
            last.iter()
                .any(|q| (p.x - q.x).hypot(p.z - q.z) < 0.02 && p.y - q.y > 1.5 * th)
        })
        .count();
    assert!(stacked >= 20, "only {stacked} stacked vertices");
}

#[test]
fn thrown_sheet_stops_at_the_zero_thickness_plate() {
    let (_t, _scene, frames) = run_and_check("thrown");
    // it reached the plate (the plate is the plane z = 0, the sheet starts at z = 0.25)...
    let closest = frames
        .iter()
        .flatten()
        .map(|p| p.z)
        .fold(f64::INFINITY, f64::min);
    assert!(
        closest < 0.02,
        "the sheet never reached the plate: {closest}"
    );
    // ...and no vertex is ever on the far side of it
    for (k, x) in frames.iter().enumerate() {
        for p in x {
            let over_plate = p.x.abs() <= 0.3 && (0.2..=0.8).contains(&p.y);
            assert!(
                !(over_plate && p.z <= 0.0),
                "frame {k}: {p} passed the plate"
            );
        }
    }
}

#[test]
fn two_sheets_land_one_on_the_other() {
    let (_t, scene, frames) = run_and_check("two_sheets");
    let n_lower = scene.cloths[0].mesh.vertex_count();
    let last = frames.last().unwrap();
    let (lower, upper) = last.split_at(n_lower);
    // Where the lower sheet rests on the sphere (centre (0, 0.25, 0), radius 0.25), the upper
    // sheet lies on top of it: every upper vertex close to a resting lower vertex is farther from
    // the centre.
    let c = Vec3::new(0.0, 0.25, 0.0);
    let mut overlapping = 0;
    for p in upper {
        for q in lower {
            if (*q - c).length() - 0.25 < 0.02 && (*p - *q).length() < 0.015 {
                overlapping += 1;
                assert!(
                    (*p - c).length() > (*q - c).length(),
                    "upper {p} is under lower {q}"
                );
            }
        }
    }
    assert!(overlapping > 10, "the sheets do not overlap: {overlapping}");
    // both fell: the upper sheet started at 0.75 m, the lower at 0.55 m; the sphere top is 0.5 m
    assert!(
        max_y(upper) < 0.65 && max_y(lower) < 0.6,
        "{} {}",
        max_y(upper),
        max_y(lower)
    );
    assert!(
        min_y(lower) < 0.1 && min_y(upper) < 0.3,
        "{} {}",
        min_y(lower),
        min_y(upper)
    );
}

// ------------------------------------------------------------------------ commands

/// A scratch folder with `scene.toml` = `text` (and any extra files).
fn scene_case(text: &str, files: &[(&str, &str)]) -> (tempfile::TempDir, PathBuf) {
    let t = tempfile::tempdir().expect("temp dir");
    for (name, content) in files {
        std::fs::write(t.path().join(name), content).expect("write");
    }
    let s = t.path().join("scene.toml");
    std::fs::write(&s, text).expect("write");
    (t, s)
}

/// `drapery run SCENE -o OUT -q`.
fn run_quiet(scene: &Path, out: &Path) -> common::Out {
    drapery(&[
        "run".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "-q".as_ref(),
    ])
}

const PLATE: &str = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 4 3 2\n";

#[test]
fn validate_prints_colliders_settings_and_the_initial_state() {
    let text = format!(
        "{BASE}\n[collision]\nthickness = 0.01\n\n\
         [[collider]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 0.25\nangular_velocity = [0, 2, 0]\n\n\
         [[collider]]\nshape = \"mesh\"\nmesh = \"plate.obj\"\nfriction = 0.9\n\n\
         [[collider]]\nshape = \"mesh\"\nmesh = \"plate.obj\"\ncenter = [0.5, 0, 0]\nangular_velocity = [0, 1, 0]\n"
    );
    let (_t, s) = scene_case(&text, &[("plate.obj", PLATE)]);
    let r = drapery(&["validate".as_ref(), s.as_os_str()]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    for want in [
        "collision: thickness 0.01 m, self_collision true, friction 0.3, stiffness 1000 N/m",
        "collider[0]: sphere center [0, 0, 0] radius 0.25 m, friction 0.3, angular_velocity [0, 2, 0] rad/s",
        "collider[1]: mesh of 4 vertices, 2 triangles (turns about [0, 0, 0]), friction 0.9",
        "collider[2]: mesh of 4 vertices, 2 triangles (turns about [0.5, 0, 0]), friction 0.3, angular_velocity [0, 1, 0] rad/s",
        "initial state: no intersection",
    ] {
        assert!(r.stdout.contains(want), "{want:?} not in\n{}", r.stdout);
    }
    let r = drapery(&[
        "validate".as_ref(),
        examples().join("hang.toml").as_os_str(),
    ]);
    assert!(
        r.stdout.contains("collision: off\ncolliders: none\n"),
        "{}",
        r.stdout
    );
}

/// A thickness above the grid's `h/√2` (the distance from a vertex to the nearest triangle it
/// does not touch; 7.07 cm on the 10 cm grid) starts with cloth pairs closer than it: one
/// warning line naming the scene and the field; below it none.
#[test]
fn a_run_whose_thickness_exceeds_the_mesh_spacing_warns_once() {
    for (thickness, warned) in [(0.069, false), (0.072, true)] {
        let text = format!("{BASE}\n[collision]\nthickness = {thickness}\nself_collision = true\n");
        let (t, s) = scene_case(&text, &[]);
        let out = t.path().join("out");
        let r = run_quiet(&s, &out);
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        let lines: Vec<&str> = r.stderr.lines().collect();
        if warned {
            assert_eq!(lines.len(), 1, "{}", r.stderr);
            let want = format!("warning: {}: collision.thickness: ", s.display());
            assert!(lines[0].starts_with(&want), "{}", lines[0]);
            assert!(
                lines[0].contains("the closest 7.071e-2 m apart"),
                "{}",
                lines[0]
            );
        } else {
            assert!(lines.is_empty(), "{}", r.stderr);
        }
    }
}

/// A pre-roll that lets a second sheet (2 cm above the first) fall onto it, both onto a
/// floor, ends with cloth pairs in contact, within the thickness: the run does not warn of them
/// (they are where contact holds cloth, not a fault of the scene). A thickness beyond the
/// mesh's spacing is still one warning, found at the scene's start, before the pre-roll.
#[test]
fn cloth_settled_into_contact_by_the_preroll_is_no_warning() {
    let upper = "[[cloth]]\nname = \"upper\"\ndensity = 0.1\n\
        grid = { size = [0.4, 0.4], resolution = [5, 5], center = [0.01, 0.52, 0.013], normal = [0.0, 1.0, 0.0] }\n\
        [[collider]]\nshape = \"plane\"\npoint = [0.0, 0.45, 0.0]\nnormal = [0.0, 1.0, 0.0]\n";
    for (thickness, warned) in [(0.01, false), (0.072, true)] {
        let text = format!(
            "{}\n{upper}\n[collision]\nthickness = {thickness}\nself_collision = true\n",
            BASE.replace("frame_rate = 20", "frame_rate = 20\npreroll = 0.5")
        );
        let (t, s) = scene_case(&text, &[]);
        if !warned {
            // the pre-roll did bring the sheets into contact
            let sim = drapery::scene::Scene::load(&s).unwrap().start().unwrap();
            let (close, _) = sim.close_pairs().unwrap();
            assert!(close > 0, "no pair within the thickness after the pre-roll");
        }
        let r = run_quiet(&s, &t.path().join("out"));
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        let lines: Vec<&str> = r.stderr.lines().collect();
        assert_eq!(lines.len(), usize::from(warned), "{}", r.stderr);
        if warned {
            let want = format!("warning: {}: collision.thickness: ", s.display());
            assert!(lines[0].starts_with(&want), "{}", lines[0]);
        }
    }
}

#[test]
fn a_run_starting_inside_a_collider_says_so_and_pushes_it_out_in_the_first_steps() {
    // the middle vertex of the sheet (y = 0.5) starts 1 mm inside a sphere around (0, 0.2, 0)
    let text =
        format!("{BASE}\n[[collider]]\nshape = \"sphere\"\ncenter = [0, 0.2, 0]\nradius = 0.301\n");
    let (t, s) = scene_case(&text, &[]);
    let out = t.path().join("out");
    let v = drapery(&["validate".as_ref(), s.as_os_str()]);
    assert!(
        v.stdout.contains(
            "initial state: tangled: 1 cloth vertices start inside colliders, 0 cloth triangle pairs start crossed; the first steps (no pre-roll) push"
        ),
        "{}",
        v.stdout
    );
    assert!(!v.stdout.contains("INTERSECTS"), "{}", v.stdout);
    let r = run_quiet(&s, &out);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{}", r.stderr);
    assert!(
        lines[0].contains("the cloth starts tangled (1 vertices inside colliders, 0 crossed cloth triangle pairs); at frame 0 (no pre-roll: the first steps untangle): 1 inside, 0 crossed"),
        "{}",
        lines[0]
    );
    assert!(out.join("frame_00002.obj").exists());
    // check finds the penetration in frame 0 only: the first steps pushed the vertex out
    let c = drapery(&[
        "check".as_ref(),
        out.as_os_str(),
        "--scene".as_ref(),
        s.as_os_str(),
    ]);
    assert_eq!(c.code, Some(1), "{}", c.stdout);
    assert!(
        c.stdout
            .contains("frame 0 (t = 0 s): 0 intersecting cloth triangle pairs, 1 vertices inside"),
        "{}",
        c.stdout
    );
    assert!(
        c.stdout.lines().last().unwrap().contains("1 of 3 frames"),
        "{}",
        c.stdout
    );
}

#[test]
fn check_finds_crossing_cloth_and_mesh_colliders_and_refuses_other_scenes() {
    let t = tempfile::tempdir().unwrap();
    let dir = t.path();
    // frame 0: two crossing triangles; frame 1: apart
    std::fs::write(
        dir.join("frame_00000.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0.2 0.2 -1\nv 0.2 0.2 1\nv 2 2 0.5\nf 1 2 3\nf 4 5 6\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("frame_00001.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 0.2 -1\nv 5 0.2 1\nv 6 2 0.5\nf 1 2 3\nf 4 5 6\n",
    )
    .unwrap();
    let r = drapery(&["check".as_ref(), dir.as_os_str()]);
    assert_eq!(r.code, Some(1), "{}{}", r.stdout, r.stderr);
    assert!(
        r.stdout
            .starts_with("frame 0: 1 intersecting cloth triangle pairs"),
        "{}",
        r.stdout
    );
    assert!(!r.stdout.contains("frame 1"), "{}", r.stdout);
    assert!(r.stdout.contains("1 of 2 frames (obj)"), "{}", r.stdout);
    // a mesh collider moving through the second frame's triangle (x = 5) at t = 1 / 20 s
    let plate = "v 5 0 0.5\nv 5 1 0.5\nv 5.5 0.5 0.5\nf 1 2 3\n";
    let scene = "[simulation]\nduration = 0.05\ndt = 0.05\nframe_rate = 20\n\n\
                 [[cloth]]\nname = \"c\"\nmesh = \"cloth.obj\"\nvertex_mass = 1\n\n\
                 [[collider]]\nshape = \"mesh\"\nmesh = \"plate.obj\"\nvelocity = [0, 0, -10]\n";
    let (t2, s) = scene_case(
        scene,
        &[
            ("plate.obj", plate),
            (
                "cloth.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 0 -1\nv 5 0 1\nv 6 2 0.5\nf 1 2 3\nf 4 5 6\n",
            ),
        ],
    );
    let r = drapery(&[
        "check".as_ref(),
        dir.as_os_str(),
        "--scene".as_ref(),
        s.as_os_str(),
    ]);
    assert_eq!(r.code, Some(1));
    assert!(
        r.stdout.contains("frame 1 (t = 0.05 s): 0 intersecting cloth triangle pairs, 0 vertices inside colliders, 1 cloth–mesh-collider triangle pairs"),
        "{}",
        r.stdout
    );
    // a scene whose cloth has another vertex count is refused
    let (_t3, other) = scene_case(BASE, &[]);
    let r = drapery(&[
        "check".as_ref(),
        dir.as_os_str(),
        "--scene".as_ref(),
        other.as_os_str(),
    ]);
    assert_eq!(r.code, Some(1));
    assert!(
        r.stderr.starts_with("error: ") && r.stderr.contains("has 6 vertices but the cloths of"),
        "{}",
        r.stderr
    );
    // no frames at all
    let r = drapery(&["check".as_ref(), t2.path().as_os_str()]);
    assert_eq!(r.code, Some(1));
    assert!(r.stderr.contains("no frames"), "{}", r.stderr);
}

#[test]
fn glb_holds_the_colliders_and_render_draws_them() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let scene = examples().join("thrown.toml");
    let r = drapery(&[
        "run".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "-f".as_ref(),
        "obj,glb".as_ref(),
        "-q".as_ref(),
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let glb = drapery::io::gltf::read_glb(&out.join("thrown.glb")).unwrap();
    let names: Vec<&str> = glb.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["sheet", "collider_0_mesh"]);
    let plate = &glb.meshes[1];
    assert_eq!(plate.triangles.len(), 8 * 3);
    assert!(plate.frames[0].iter().all(|p| p[2] == 0.0));
    // render with and without --scene: the collider adds grey pixels
    let grey = |png: &Path| {
        let d = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(png).unwrap()));
        let mut reader = d.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf[..info.buffer_size()]
            .chunks(3)
            .filter(|p| {
                let (r, g, b) = (p[0] as i32, p[1] as i32, p[2] as i32);
                (r - g).abs() < 6 && (g - b).abs() < 8 && r > 40 && r < 150
            })
            .count()
    };
    let with = tmp.path().join("with.png");
    let without = tmp.path().join("without.png");
    for (png, extra) in [(&with, true), (&without, false)] {
        let mut args: Vec<&OsStr> = vec![
            "render".as_ref(),
            out.as_os_str(),
            "-o".as_ref(),
            png.as_os_str(),
            "--frame".as_ref(),
            "10".as_ref(),
            "--size".as_ref(),
            "160x120".as_ref(),
            "--eye".as_ref(),
            "1.5,1,1.5".as_ref(),
            "--target".as_ref(),
            "0,0.5,0".as_ref(),
        ];
        if extra {
            args.extend(["--scene".as_ref(), scene.as_os_str()]);
        }
        let r = drapery(&args);
        assert_eq!(r.code, Some(0), "{}", r.stderr);
    }
    let (g1, g0) = (grey(&with), grey(&without));
    assert!(g1 > g0 + 200, "collider pixels: with {g1}, without {g0}");
}

#[test]
fn editing_a_mesh_collider_changes_the_fingerprint() {
    let text = format!("{BASE}\n[[collider]]\nshape = \"mesh\"\nmesh = \"plate.obj\"\n");
    let (t, s) = scene_case(&text, &[("plate.obj", PLATE)]);
    let out = t.path().join("out");
    let run = |extra: &str| {
        drapery(&[
            "run".as_ref(),
            s.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
            "-q".as_ref(),
            extra.as_ref(),
        ])
    };
    assert_eq!(run("--overwrite").code, Some(0));
    assert!(run("--resume").stderr.is_empty());
    std::fs::write(
        t.path().join("plate.obj"),
        PLATE.replace("v 1 0 1", "v 1 -0.1 1"),
    )
    .unwrap();
    let r = run("--resume");
    assert_eq!(r.code, Some(1));
    assert!(
        r.stderr.contains("holds a run of another scene"),
        "{}",
        r.stderr
    );
}

// --------------------------------------------------------------------------- bad input

#[test]
fn negative_thickness_or_friction_is_refused() {
    assert_rejected(
        "[collision]\nthickness = -0.005\n",
        &[],
        &[
            "scene.toml",
            "collision.thickness: must be a finite number > 0, got -0.005",
        ],
    );
    assert_rejected(
        "[collision]\nfriction = nan\n",
        &[],
        &["scene.toml", "collision.friction", "NaN"],
    );
    assert_rejected(
        "[[collider]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nfriction = -0.1\n",
        &[],
        &["collider[0].friction: must be a finite number ≥ 0, got -0.1"],
    );
}

#[test]
fn unknown_collision_keys_and_shapes_are_refused() {
    assert_rejected(
        "[collision]\nthicknes = 0.01\n",
        &[],
        &["scene.toml", "unknown field `thicknes`"],
    );
    assert_rejected(
        "[[collider]]\nshape = \"cone\"\ncenter = [0, 0, 0]\n",
        &[],
        &["scene.toml", "collider[0].shape: unknown shape 'cone'"],
    );
    assert_rejected(
        "[[collider]]\nshape = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 1, 0]\nradius = 1\n",
        &[],
        &["collider[0].radius: not a key of a plane"],
    );
}

#[test]
fn missing_collider_keys_are_named() {
    assert_rejected(
        "[[collider]]\nshape = \"plane\"\npoint = [0, 0, 0]\n\n[[collider]]\nshape = \"capsule\"\na = [0, 0, 0]\nradius = 1\n",
        &[],
        &["scene.toml", "collider[0].normal: missing"],
    );
    assert_rejected(
        "[[collider]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n\n[[collider]]\nshape = \"capsule\"\na = [0, 0, 0]\nradius = 1\n",
        &[],
        &["collider[1].b: missing"],
    );
}

#[test]
fn degenerate_shapes_are_refused() {
    assert_rejected(
        "[[collider]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = -1\n",
        &[],
        &["collider[0].radius: must be a finite number > 0, got -1"],
    );
    assert_rejected(
        "[[collider]]\nshape = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 0]\n",
        &[],
        &["collider[0].normal: must be a non-zero vector"],
    );
    assert_rejected(
        "[[collider]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n\n[[collider]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\n\n\
         [[collider]]\nshape = \"box\"\ncenter = [0, 0, 0]\nhalf_extents = [1, 0, 1]\n",
        &[],
        &["collider[2].half_extents: must be three finite numbers > 0, got [1, 0, 1]"],
    );
    assert_rejected(
        "[[collider]]\nshape = \"box\"\ncenter = [0, 0, 0]\nhalf_extents = [1, 1, 1]\nrotation = [0, 0, 0, 0]\n",
        &[],
        &["collider[0].rotation: must be a finite non-zero quaternion [x, y, z, w]"],
    );
    assert_rejected(
        "[[collider]]\nshape = \"capsule\"\na = [0, 0, 0]\nb = [0, nan, 0]\nradius = 1\n",
        &[],
        &["collider[0].b: must be finite"],
    );
    assert_rejected(
        "[[collider]]\nshape = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nangular_velocity = [0, inf, 0]\n",
        &[],
        &["collider[0].angular_velocity: must be finite"],
    );
}

#[test]
fn bad_mesh_colliders_name_the_file() {
    assert_rejected(
        "[[collider]]\nshape = \"mesh\"\nmesh = \"nope.obj\"\n",
        &[],
        &["scene.toml", "collider[0].mesh: cannot read", "nope.obj"],
    );
    assert_rejected(
        "[[collider]]\nshape = \"mesh\"\nmesh = \"bad.obj\"\n",
        &[("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")],
        &["bad.obj", "line 4"],
    );
    assert_rejected(
        "[[collider]]\nshape = \"mesh\"\nmesh = \"lines.obj\"\n",
        &[("lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n")],
        &["collider[0].mesh: ", "has no faces"],
    );
}
