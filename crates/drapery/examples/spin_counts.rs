//! Counts of the rotating-sphere scene (issue 18), step by step, for profiling with counts
//! instead of wall time (BENCHMARKS.md, "Ninth session").
//!
//! `cargo run --release -p drapery --example spin_counts -- N save FRAMES FILE` runs `spin-N`
//! for FRAMES frames (4 steps each, or the SPIN_SCENE file's own) from the start, printing the cloth's shape after each frame
//! (see [`Shape`]), and saves the state to FILE (and after each earlier frame K to FILE.K);
//! `... -- N steps STEPS FILE [free]` restores FILE and runs STEPS steps of `spin-N` (or, with
//! `free`, of the same cloth without collisions, `spin-free-N`), printing each step's counts
//! and their sums, then each stage's mean ms per step over the steps after the first (the
//! first after a restore also builds the collision trees and the multigrid's structure from
//! scratch) and their total, and last the end state's FNV-1a fingerprint (the same for a
//! change that only makes the step faster). Under `valgrind --tool=callgrind` (with
//! `RAYON_NUM_THREADS=1`) the second form counts the instructions of STEPS steps from the same
//! state (building the model and reading FILE are the rest: subtract a run of 0 steps).
//!
//! `... -- N trace STEPS FILE` restores FILE (or, with `-` for FILE, starts from the scene's
//! start) and runs STEPS steps, printing after each the least principal stretch of any
//! triangle (the square root of the least eigenvalue of `FᵀF` against the first mesh, the
//! rest shape), how many triangles are under 1/√3 (where St Venant–Kirchhoff's compressive
//! force peaks, docs/MATH.md §20), the greatest principal stretch, the greatest speed, the least
//! principal stretch of the triangles around the fastest particle, and where the least and
//! greatest stretched triangles are (centroid and its distance from the origin).
//!
//! The shape printed after each frame (then, after a `|`, the frame's CG iterations, linear
//! solves, self-contact stencils and CCD hits summed over its steps, its wall time in ms and the
//! ms of its solve, detect and fail-safe stages, and how many of its steps were solved to
//! `FIRST_CONTACT_TOLERANCE`, first contacts and impacts): the mean hinge angle (degrees), the mean and 99th
//! percentile of `|θ|/h` (1/m, a curvature that compares resolutions), the share of hinges bent
//! over 30°, the least and greatest edge length over rest length, the share of edges shorter than
//! 0.8 of their rest length, the greatest speed (m/s), and where the shortest edge is (its first
//! vertex, and that vertex's distance from the origin, the sphere's centre). With `SPIN_SCENE=FILE.toml` in the environment both forms
//! run the scene in that file instead (a variant of `drapery bench --write-scenes`'s spin-N,
//! e.g. another material, same size N) (BENCHMARKS.md, "Tenth session").

/// The command's allocator (crates/drapery-cli/src/main.rs), so that the stage times match it.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

use drapery::forces::hinge::{dihedral_angle, interior_edges};
use drapery::presets::Preset;
use drapery::scene::Scene;
use drapery::snapshot::Snapshot;
use drapery::{Simulation, Vec3};

/// `spin-N` (or `spin-free-N`), or with the environment variable `SPIN_SCENE` set, the scene
/// in that file (a variant of `drapery bench --write-scenes`'s, for trying materials; for a
/// free variant, the file without its `[collision]` and `[[collider]]`), with its step and
/// steps per frame.
type Run = (Simulation, f64, usize);
fn simulation(n: usize, free: bool) -> Result<Run, Box<dyn std::error::Error>> {
    let Ok(path) = std::env::var("SPIN_SCENE") else {
        let preset = if free { Preset::SpinFree } else { Preset::Spin };
        let (h, per_frame) = preset.step();
        return Ok((preset.simulation(n, 1e-3)?, h, per_frame));
    };
    if free {
        return Err("with SPIN_SCENE, give the free variant as its own scene file".into());
    }
    let scene = Scene::load(std::path::Path::new(&path))?;
    Ok((scene.build()?, scene.step_size(), scene.steps_per_frame()))
}

/// How wrinkled the cloth is: the dihedral angles of its hinges (the interior edges of its
/// triangles), as angles and as curvatures `|θ| / h` with `h` the hinge's rest edge length
/// (the grid's spacing for the axis edges), so that two resolutions compare.
struct Shape {
    /// Hinges `[x0, x1, x2, x3]` (edge `x0 x1`) and their rest edge lengths, m.
    hinges: Vec<([u32; 4], f64)>,
    /// The mesh's edges and their rest lengths, m.
    edges: Vec<([u32; 2], f64)>,
}

impl Shape {
    fn new(sim: &Simulation) -> Shape {
        let mesh = &sim.model().cloths()[0].mesh;
        let x = &mesh.positions;
        let hinges = interior_edges(&mesh.triangles())
            .into_iter()
            .map(|(h, _)| (h, (x[h[1] as usize] - x[h[0] as usize]).length()))
            .collect();
        let edges = (mesh.edges().into_iter())
            .map(|e| (e, (x[e[1] as usize] - x[e[0] as usize]).length()))
            .collect();
        Shape { hinges, edges }
    }

    /// The least and greatest ratio of an edge's length to its rest length, the share of
    /// edges shorter than 0.8 of it, and the first vertex of the shortest edge.
    fn stretch(&self, x: &[Vec3]) -> ([f64; 3], usize) {
        let (mut lo, mut hi, mut short, mut at) = (f64::MAX, 0.0f64, 0usize, 0);
        for (e, len) in &self.edges {
            let r = (x[e[1] as usize] - x[e[0] as usize]).length() / len;
            if r < lo {
                (lo, at) = (r, e[0] as usize);
            }
            hi = hi.max(r);
            short += usize::from(r < 0.8);
        }
        ([lo, hi, short as f64 / self.edges.len().max(1) as f64], at)
    }

    /// `mean |θ| (deg), mean |θ|/h, 99th percentile of |θ|/h (1/m), share of hinges over 30°`.
    fn measure(&self, x: &[Vec3]) -> [f64; 4] {
        let mut curv = Vec::with_capacity(self.hinges.len());
        let (mut sum, mut over) = (0.0, 0usize);
        for (h, len) in &self.hinges {
            let t = dihedral_angle(h.map(|i| x[i as usize]))
                .unwrap_or(0.0)
                .abs();
            sum += t;
            over += usize::from(t > 30f64.to_radians());
            curv.push(t / len);
        }
        let m = self.hinges.len().max(1) as f64;
        curv.sort_by(f64::total_cmp);
        let p99 = curv.get(curv.len() * 99 / 100).copied().unwrap_or(0.0);
        [
            (sum / m).to_degrees(),
            curv.iter().sum::<f64>() / m,
            p99,
            over as f64 / m,
        ]
    }
}

/// The principal stretches of the cloth's triangles: the square roots of the eigenvalues of
/// `C = FᵀF`, found frame-free as the roots `λ` of `det(G − λ G₀) = 0` with `G`, `G₀` the Gram
/// matrices of a triangle's two edges now and at rest.
struct Stretches {
    /// Triangles and the rest Gram matrices `[e1·e1, e1·e2, e2·e2]`.
    tris: Vec<([u32; 3], [f64; 3])>,
}

impl Stretches {
    fn new(sim: &Simulation) -> Stretches {
        let mesh = &sim.model().cloths()[0].mesh;
        let x = &mesh.positions;
        let tris = (mesh.triangles().into_iter())
            .map(|t| (t, gram(t, x)))
            .collect();
        Stretches { tris }
    }

    /// `[least, greatest]` principal stretch of each triangle.
    fn principal(&self, x: &[Vec3]) -> Vec<[f64; 2]> {
        (self.tris.iter())
            .map(|(t, [a0, b0, c0])| {
                let [a, b, c] = gram(*t, x);
                // det(G − λ G₀) = p λ² − q λ + r
                let p = a0 * c0 - b0 * b0;
                let q = a * c0 + c * a0 - 2.0 * b * b0;
                let r = a * c - b * b;
                let d = (q * q - 4.0 * p * r).max(0.0).sqrt();
                let (lo, hi) = ((q - d) / (2.0 * p), (q + d) / (2.0 * p));
                [lo.max(0.0).sqrt(), hi.max(0.0).sqrt()]
            })
            .collect()
    }
}

/// `[e1·e1, e1·e2, e2·e2]` of triangle `t`'s edges from its first vertex.
fn gram(t: [u32; 3], x: &[Vec3]) -> [f64; 3] {
    let [i, j, k] = t.map(|p| x[p as usize]);
    let (e1, e2) = (j - i, k - i);
    [e1.dot(e1), e1.dot(e2), e2.dot(e2)]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage =
        "usage: spin_counts N save FRAMES FILE | N steps STEPS FILE [free] | N trace STEPS FILE";
    if args.len() < 4 {
        return Err(usage.into());
    }
    let n: usize = args[0].parse()?;
    let count: usize = args[2].parse()?;
    let file = &args[3];
    match args[1].as_str() {
        "save" => {
            let (mut sim, h, per_frame) = simulation(n, false)?;
            let shape = Shape::new(&sim);
            println!(
                "frame mean_angle_deg mean_curvature p99_curvature share_over_30deg min_stretch max_stretch share_under_0.8 max_speed shortest_x y z r | cg solves stencils ccd_hits ms ms_solve ms_detect ms_failsafe tight_steps"
            );
            for f in 1..=count {
                let (mut cg, mut solves, mut stencils, mut hits, mut tight) = (0, 0, 0, 0, 0);
                let mut times = drapery::StageTimes::default();
                let t0 = std::time::Instant::now();
                for _ in 0..per_frame {
                    let r = sim.step(h)?;
                    (cg, solves) = (cg + r.cg_iterations, solves + r.linear_solves);
                    (stencils, hits) = (stencils + r.self_contacts, hits + r.ccd_hits);
                    tight += (r.tolerance <= drapery::step::FIRST_CONTACT_TOLERANCE) as usize;
                    times.solve += r.stages.solve;
                    times.detect += r.stages.detect;
                    times.failsafe += r.stages.failsafe;
                }
                let ms = 1e3 * t0.elapsed().as_secs_f64();
                let [a, c, p99, o] = shape.measure(sim.positions());
                let ([lo, hi, short], at) = shape.stretch(sim.positions());
                let speed = (sim.velocities().iter()).fold(0.0f64, |m, v| m.max(v.length()));
                let p = sim.positions()[at];
                println!(
                    "{f} {a:.3} {c:.3} {p99:.2} {o:.5} {lo:.4} {hi:.4} {short:.5} {speed:.3} {:.3} {:.3} {:.3} {:.4} | {cg} {solves} {stencils} {hits} {ms:.0} {:.0} {:.0} {:.0} {tight}",
                    p.x,
                    p.y,
                    p.z,
                    p.length(),
                    1e3 * times.solve,
                    1e3 * times.detect,
                    1e3 * times.failsafe,
                );
                if f < count {
                    std::fs::write(format!("{file}.{f}"), sim.snapshot().to_bytes())?;
                }
            }
            std::fs::write(file, sim.snapshot().to_bytes())?;
        }
        "trace" => {
            let (mut sim, h, _) = simulation(n, false)?;
            let stretches = Stretches::new(&sim);
            if file != "-" {
                sim.restore_snapshot(&Snapshot::from_bytes(&std::fs::read(file)?)?)?;
            }
            println!(
                "step min_principal_stretch triangles_under_1/sqrt3 max_principal_stretch max_speed min_stretch_at_fastest least_at_x y z r greatest_at_x y z r"
            );
            for k in 0..count {
                sim.step(h)?;
                let s = stretches.principal(sim.positions());
                let lo = s.iter().fold(f64::MAX, |m, p| m.min(p[0]));
                let hi = s.iter().fold(0.0f64, |m, p| m.max(p[1]));
                let x = sim.positions();
                let centre = |i: usize| {
                    let t = stretches.tris[i].0.map(|p| x[p as usize]);
                    (t[0] + t[1] + t[2]) / 3.0
                };
                let imin = (0..s.len())
                    .min_by(|&a, &b| s[a][0].total_cmp(&s[b][0]))
                    .unwrap_or(0);
                let imax = (0..s.len())
                    .max_by(|&a, &b| s[a][1].total_cmp(&s[b][1]))
                    .unwrap_or(0);
                let (cmin, cmax) = (centre(imin), centre(imax));
                let under = s.iter().filter(|p| p[0] < 3f64.sqrt().recip()).count();
                let v = sim.velocities();
                let fast = (0..v.len())
                    .max_by(|&a, &b| v[a].length().total_cmp(&v[b].length()))
                    .unwrap_or(0);
                let near = (stretches.tris.iter().zip(&s))
                    .filter(|(t, _)| t.0.contains(&(fast as u32)))
                    .fold(f64::MAX, |m, (_, p)| m.min(p[0]));
                println!(
                    "{k} {lo:.4} {under} {hi:.4} {:.3} {near:.4} {:.3} {:.3} {:.3} {:.4} {:.3} {:.3} {:.3} {:.4}",
                    v[fast].length(),
                    cmin.x,
                    cmin.y,
                    cmin.z,
                    cmin.length(),
                    cmax.x,
                    cmax.y,
                    cmax.z,
                    cmax.length()
                );
            }
        }
        "steps" => {
            let free = args.get(4).is_some_and(|a| a == "free");
            let (mut sim, h, _) = simulation(n, free)?;
            sim.restore_snapshot(&Snapshot::from_bytes(&std::fs::read(file)?)?)?;
            println!(
                "step newton solves cg cg/solve held stencils prox_pairs bp_builds ccd_pairs ccd_rounds ccd_hits setups"
            );
            let mut sum = [0usize; 11];
            // the first step after a restore also builds the trees and the multigrid's
            // structure from scratch: the stage times leave it out (unless it is the only one)
            let mut times = drapery::StageTimes::default();
            for k in 0..count {
                let r = sim.step(h)?;
                let t = &r.stages;
                if k > 0 || count == 1 {
                    for (a, b) in times.fields_mut().into_iter().zip(t.fields()) {
                        *a += b;
                    }
                }
                let row = [
                    r.newton_iterations as usize,
                    r.linear_solves,
                    r.cg_iterations,
                    r.obstacle_contacts,
                    r.self_contacts,
                    r.proximity_candidates,
                    r.broad_phase_builds,
                    r.ccd_candidates,
                    r.ccd_rounds,
                    r.ccd_hits,
                    r.preconditioner_setups,
                ];
                for (s, x) in sum.iter_mut().zip(row) {
                    *s += x;
                }
                let per_solve = r.cg_iterations as f64 / r.linear_solves.max(1) as f64;
                println!(
                    "{k} {} {} {} {per_solve:.1} {} {} {} {} {} {} {} {}",
                    row[0],
                    row[1],
                    row[2],
                    row[3],
                    row[4],
                    row[5],
                    row[6],
                    row[7],
                    row[8],
                    row[9],
                    row[10]
                );
            }
            let m: Vec<String> = sum
                .iter()
                .map(|&s| format!("{:.1}", s as f64 / count as f64))
                .collect();
            println!("mean {}", m.join(" "));
            let (timed, which) = match count {
                0 | 1 => (1, "step 1".to_string()),
                _ => (count - 1, format!("steps 2-{count}")),
            };
            let ms: Vec<String> = (drapery::StageTimes::NAMES.iter().zip(times.fields()))
                .map(|(name, s)| format!("{name} {:.2}", 1e3 * s / timed as f64))
                .collect();
            let total: f64 = times.fields().into_iter().sum();
            println!(
                "ms/step ({which}) {} total {:.2}",
                ms.join(" "),
                1e3 * total / timed as f64
            );
            // the end state's fingerprint: a change that only makes the step faster keeps it
            let bytes = sim.snapshot().to_bytes();
            let state = drapery::fingerprint::Fnv::new().bytes(&bytes).finish();
            println!("state {state:016x}");
        }
        _ => return Err(usage.into()),
    }
    Ok(())
}
