//! `drapery bench`: a one-frame smoke run of every standard scene and of every preset in
//! contact, and its one-line errors.

mod common;

use common::{assert_one_error, drapery};

/// The default scene list, as `drapery bench --help` documents it ("default: all standard
/// scenes hang-32,…").
fn documented_scenes() -> Vec<String> {
    let r = drapery(&["bench", "--help"]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    // The help may be wrapped (to the terminal, or 100 columns): read it as one line.
    let text = r.stdout.split_whitespace().collect::<Vec<_>>().join(" ");
    let (_, rest) = text
        .split_once("default: all standard scenes")
        .expect("the help names the default scenes");
    let list = rest.split_whitespace().next().unwrap_or_default();
    list.split(',').map(str::to_string).collect()
}

/// One row of the table.
struct Row {
    scene: String,
    vertices: usize,
    frame_ms: f64,
    steps: usize,
    cg: f64,
    assembly_ms: f64,
    solve_ms: f64,
    collision_ms: f64,
    output_ms: f64,
    wait_ms: f64,
}

/// The rows after the header line; panics on a row that does not read as one.
fn table(stdout: &str) -> Vec<Row> {
    let mut lines = stdout.lines().skip_while(|l| !l.starts_with("scene "));
    let header: Vec<&str> = lines
        .next()
        .expect("no table header")
        .split_whitespace()
        .collect();
    assert_eq!(header[..3], ["scene", "vertices", "ms/frame"], "{stdout}");
    lines
        .map(|l| {
            let c: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(c.len(), 11, "{l}");
            let num = |i: usize| -> f64 { c[i].parse().unwrap_or_else(|_| panic!("{l}")) };
            Row {
                scene: c[0].to_string(),
                vertices: c[1].parse().unwrap(),
                frame_ms: num(2),
                steps: c[3].parse().unwrap(),
                cg: num(4),
                assembly_ms: num(5),
                solve_ms: num(6),
                collision_ms: num(7),
                output_ms: num(8),
                wait_ms: num(9),
            }
        })
        .collect()
}

/// What every row must say: a scene of n × n vertices, one step per frame, finite times, the
/// step's time positive and at least that of its stages, collision time only with collisions.
fn check_row(r: &Row) {
    if r.scene == "skirt" {
        // the example as `drapery validate` counts it: 8 steps per frame at 240 Hz and 30 fps
        let scene = drapery::scene::Scene::load(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/skirt.toml"),
        )
        .unwrap();
        let vertices: usize = scene.cloths.iter().map(|c| c.mesh.positions.len()).sum();
        assert_eq!((r.vertices, r.steps), (vertices, scene.steps_per_frame()));
        assert_eq!(r.steps, 8);
        assert!(
            r.frame_ms > 0.0 && r.collision_ms > 0.0 && r.cg >= 0.0,
            "skirt"
        );
        return;
    }
    let (kind, n) = r.scene.rsplit_once('-').unwrap();
    let n: usize = n.parse().unwrap();
    // the textile scenes' size is the edge length in mm: a 160 mm × 40 mm strip plus the
    // clamp's column, a 150 mm disc of ⌈150/n⌉ rings of 6k vertices
    let vertices = match kind {
        "cantilever" => (160 / n + 2) * (40 / n + 1),
        "cusick" => 1 + 3 * 150_usize.div_ceil(n) * (150_usize.div_ceil(n) + 1),
        _ => n * n,
    };
    assert_eq!(r.vertices, vertices, "{}", r.scene);
    // the spinning sphere: 25 frames per second at dt = 0.01 s
    let steps = if kind.starts_with("spin") { 4 } else { 1 };
    assert_eq!(r.steps, steps, "{}", r.scene);
    for (what, ms) in [
        ("ms/frame", r.frame_ms),
        ("assembly", r.assembly_ms),
        ("solve", r.solve_ms),
        ("output", r.output_ms),
    ] {
        assert!(ms.is_finite() && ms > 0.0, "{}: {what} {ms}", r.scene);
    }
    assert!(r.wait_ms.is_finite() && r.wait_ms >= 0.0);
    assert!(
        r.cg.is_finite() && r.cg >= 0.0,
        "{}: CG/step {}",
        r.scene,
        r.cg
    );
    // The table rounds to 0.01 ms.
    assert!(
        r.frame_ms + 0.015 >= r.assembly_ms + r.solve_ms + r.collision_ms,
        "{}: the frame is shorter than its stages",
        r.scene
    );
    if ["hang", "cantilever", "spin-free"].contains(&kind) {
        assert_eq!(r.collision_ms, 0.0, "{}: no collisions", r.scene);
    } else {
        assert!(r.collision_ms > 0.0, "{}: no collision time", r.scene);
    }
}

#[test]
fn every_standard_scene_runs_one_frame() {
    let r = drapery(&["bench", "--frames", "1", "--runs", "1", "--warm-up", "0"]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(
        r.stdout
            .starts_with("drapery bench: 1 timed frames x 1 runs per scene, 0 warm-up frames"),
        "{}",
        r.stdout
    );
    let rows = table(&r.stdout);
    let names: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    let standard = documented_scenes();
    assert_eq!(standard.len(), 15, "{standard:?}");
    assert_eq!(names, standard);
    rows.iter().for_each(check_row);
    // The first step from rest starts the PCG from zero against gravity: it must iterate (the
    // spin scenes' later steps of the frame, in free fall, start from the exact warm start;
    // the table rounds to 0.1)
    assert!(rows.iter().all(|r| r.cg >= 1.0 / r.steps as f64 - 0.05));
}

#[test]
fn every_preset_runs_one_frame_after_its_warm_up() {
    // The presets' own warm-up puts drape and pile in contact before the timed frame.
    let r = drapery(&[
        "bench",
        "--scenes",
        "hang-8,drape-8,pile-8,twist-8,cantilever-20,cusick-20,spin-8,spin-free-8",
        "--frames",
        "1",
        "--runs",
        "1",
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let rows = table(&r.stdout);
    let names: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    assert_eq!(
        names,
        [
            "hang-8",
            "drape-8",
            "pile-8",
            "twist-8",
            "cantilever-20",
            "cusick-20",
            "spin-8",
            "spin-free-8"
        ]
    );
    rows.iter().for_each(check_row);
}

/// `--write-scenes` writes the spin scene that `drapery validate` reads as the bench's scene:
/// 8 × 8 vertices, 100 frames of 4 steps; scenes without a scene file are refused.
#[test]
fn write_scenes_writes_the_spin_scene_as_a_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let r = drapery(&[
        "bench",
        "--scenes",
        "spin-8",
        "--frames",
        "100",
        "--write-scenes",
        d,
    ]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    let path = dir.path().join("spin-8.toml");
    let scene = drapery::scene::Scene::load(&path).unwrap();
    assert_eq!((scene.frame_count(), scene.steps_per_frame()), (100, 4));
    let model = scene.model().unwrap();
    assert_eq!(model.particle_count(), 64);
    let preset = drapery::presets::Preset::Spin.model(8).unwrap();
    assert_eq!(model.positions(), preset.positions());
    assert_eq!(model.obstacles().len(), 1);
    assert_eq!(model.collision().map(|c| c.friction), Some(0.4));
    let r = drapery(&["bench", "--scenes", "hang-8", "--write-scenes", d]);
    assert_one_error(&r, &["hang-8", "no scene file"]);
}

#[test]
fn bad_bench_requests_are_one_line_errors_before_anything_runs() {
    let r = drapery(&["bench", "--scenes", "hang-8,swing-8", "--frames", "1"]);
    assert_one_error(&r, &["swing-8", "unknown kind 'swing'"]);
    assert_eq!(r.stdout, "", "a scene ran before the bad name was found");
    let r = drapery(&["bench", "--scenes", "hang-1"]);
    assert_one_error(&r, &["hang-1", "size"]);
    let r = drapery(&["bench", "--frames", "0"]);
    assert_one_error(&r, &["--frames and --runs must be at least 1"]);
}
