// scratch (not committed): DC of the Cusick scene at edge length h (args: h [steps])
use drapery::math::Vec3;
use drapery::scene::Scene;
use drapery::textile::drape::drape_coefficient;
use std::path::PathBuf;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let h: f64 = args[1].parse().unwrap();
    let density = drapery::textile::fabrics::fabric("cotton").unwrap().density;
    let text = format!(
        r#"
[simulation]
duration = 3.0
dt = 0.01
frame_rate = 10
[solver]
tolerance = 1e-6
max_iterations = 2000
[collision]
thickness = 0.002
self_collision = false
friction = 0.3
[[collider]]
shape = "mesh"
mesh = "cusick_support.obj"
[[cloth]]
name = "specimen"
disc = {{ radius = 0.15, edge_length = {h}, center = [0.0, 0.003, 0.0], normal = [0.0, 1.0, 0.0] }}
material = "cotton"
air_drag = {drag}
"#,
        drag = 2.0 * density * h * h
    );
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/cusick.toml");
    let scene = Scene::from_str(&text, &path).unwrap();
    let mut sim = scene.start().unwrap();
    let dt = scene.step_size();
    let tri = scene.cloths[0].mesh.triangles();
    let t = std::time::Instant::now();
    for s in 0..scene.step_count() {
        sim.step(dt).unwrap();
        if (s + 1) % 50 == 0 {
            let dc = drape_coefficient(sim.positions(), &tri, Vec3::Y, 0.09, 0.15).unwrap();
            let miny = sim
                .positions()
                .iter()
                .map(|p| p.y)
                .fold(f64::INFINITY, f64::min);
            let (si, pen) = sim.intersections();
            eprintln!(
                "h {h} step {} DC {dc:.4} miny {miny:.4} inter {si} {pen} {:.0}s",
                s + 1,
                t.elapsed().as_secs_f64()
            );
        }
    }
    let speed = sim
        .velocities()
        .iter()
        .map(|v| v.length())
        .fold(0.0, f64::max);
    let dc = drape_coefficient(sim.positions(), &tri, Vec3::Y, 0.09, 0.15).unwrap();
    // folds: maxima of the projected radius of the outer ring's vertices, by angle
    let x0 = &scene.cloths[0].mesh.positions;
    let mut outer: Vec<(f64, f64)> = x0
        .iter()
        .zip(sim.positions())
        .filter(|(p, _)| (p.x * p.x + p.z * p.z).sqrt() > 0.15 - 1e-9)
        .map(|(p, q)| (p.z.atan2(p.x), (q.x * q.x + q.z * q.z).sqrt()))
        .collect();
    outer.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = outer.len();
    let folds = (0..n)
        .filter(|&i| outer[i].1 > outer[(i + n - 1) % n].1 && outer[i].1 >= outer[(i + 1) % n].1)
        .count();
    println!("h {h}: DC {dc:.4} speed {speed:.2e} folds {folds} (outer ring {n})");
}
