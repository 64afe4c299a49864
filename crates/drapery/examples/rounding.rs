//! Rounding amplification sweep (issue 18): runs a pile preset at several PCG tolerances and
//! initial perturbations for the first second and prints per-step counts and the spread of
//! the runs' positions.
//!
//! `cargo run --release -p drapery --example rounding -- N FRAMES [OPTION]... [TOL|pPERT|TOLpPERT]...`
//! e.g. `-- 64 60 0.9e-3 1e-3 p1e-9 1e-6p1e-9` (a `p` value perturbs the initial positions by
//! that many metres, a fixed pseudo-random direction per particle; the tolerance is 1e-3 unless
//! given before the `p`). Prints each run's counts per step (`step:self/ccd/held`) and, per
//! frame, the largest distance of any run's positions to the first run's.
//!
//! Options (docs/ROUNDING.md, "Physics or artefact"):
//! * `--sub K`: K steps of h = 1/(60 K) s per frame (default 1);
//! * `--direct`: the direct linear solver instead of PCG (the tolerance is then unused);
//! * `--scene pile|pile-noself|pile-shell|free|pinch`: the pile (default); the pile without
//!   self-collision (the ground only); the pile on the shell model (docs/MATH.md §20, 21:
//!   stretch modulus 1000 N/m, Poisson 0, bending rigidity `--bend B` N·m, default 1e-3); the
//!   pile's cloth falling without any collision; `pinch`:
//!   the same cloth horizontal, no gravity, no collision, its edges x = ±0.5 m moving toward
//!   each other at 0.75 m/s each (1.5 m/s closing, the pile's impact speed);
//! * `--seed S`: every run's positions first moved by S m in another fixed pseudo-random
//!   direction per particle (so that the reference run of `pinch` is not exactly flat);
//! * `--every`: print the spread after every step, with its time, instead of every frame.
//!
//! The last lines give, for the first two runs, the time at which their distance first
//! exceeds 1e-7, 1e-6, ... 1e-2 m (ln-interpolated between steps), the growth rate between
//! 1e-7 and 1e-4 m, `ln(1e3) / (t(1e-4) - t(1e-7))` in 1/s, and, from the first run, the largest
//! compression of a stretch spring `1 - ℓ/L` per frame.

use drapery::animation::Motion;
use drapery::collision::settings::CollisionSettings;
use drapery::constraints::handles::HandleDesc;
use drapery::model::{ClothModel, Shell, SpringKind};
use drapery::presets::{Preset, jitter_direction};
use drapery::{ClothDesc, LinearSolver, Material, Model, Simulation, SolverSettings, Vec3};

fn main() -> drapery::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args[0].parse().unwrap();
    let frames: usize = args[1].parse().unwrap();
    let (mut sub, mut direct, mut scene, mut seed, mut every) = (1usize, false, "pile", 0.0, false);
    let mut bend = 1e-3;
    let mut rest = args[2..].iter();
    let mut runs: Vec<(f64, f64)> = Vec::new();
    while let Some(a) = rest.next() {
        match a.as_str() {
            "--sub" => sub = rest.next().unwrap().parse().unwrap(),
            "--direct" => direct = true,
            "--scene" => scene = rest.next().unwrap().as_str(),
            "--seed" => seed = rest.next().unwrap().parse().unwrap(),
            "--every" => every = true,
            "--bend" => bend = rest.next().unwrap().parse().unwrap(),
            _ => runs.push(match a.split_once('p') {
                Some(("", p)) => (1e-3, p.parse().unwrap()),
                Some((t, p)) => (t.parse().unwrap(), p.parse().unwrap()),
                None => (a.parse().unwrap(), 0.0),
            }),
        }
    }
    let h = 1.0 / (60.0 * sub as f64);
    let mut sims = Vec::new();
    for &(tol, pert) in &runs {
        let settings = SolverSettings {
            tolerance: tol,
            max_iterations: 20_000,
            linear_solver: if direct {
                LinearSolver::Direct
            } else {
                LinearSolver::Pcg
            },
            ..Default::default()
        };
        let mut sim = Simulation::new(model(scene, n, bend)?, settings)?;
        let x: Vec<Vec3> = sim
            .positions()
            .iter()
            .enumerate()
            .map(|(i, p)| {
                *p + seed * jitter_direction(i as u64 + (1 << 40))
                    + pert * jitter_direction(i as u64)
            })
            .collect();
        sim.set_positions(&x)?;
        sims.push(sim);
    }
    let mut lines = vec![String::new(); runs.len()];
    let (mut spread, mut compression) = (String::new(), String::new());
    let mut pair: Vec<(f64, f64)> = Vec::new(); // (time, distance of run 1 to run 0)
    for s in 0..frames * sub {
        for (sim, line) in sims.iter_mut().zip(&mut lines) {
            let r = sim.step(h)?;
            *line += &format!(
                " {}:{}/{}/{}",
                s, r.self_contacts, r.ccd_hits, r.obstacle_contacts
            );
        }
        let t = (s + 1) as f64 * h;
        let dist = |sim: &Simulation| {
            sim.positions()
                .iter()
                .zip(sims[0].positions())
                .map(|(a, b)| (*a - *b).length())
                .fold(0.0f64, f64::max)
        };
        if sims.len() > 1 {
            pair.push((t, dist(&sims[1])));
        }
        let end_of_frame = (s + 1) % sub == 0;
        if every || end_of_frame {
            let d = sims.iter().map(dist).fold(0.0f64, f64::max);
            spread += &format!(" {t:.4}:{d:.1e}");
        }
        if end_of_frame {
            compression += &format!(" {t:.4}:{:.3}", largest_compression(sims[0].model()));
        }
    }
    for (&(tol, pert), line) in runs.iter().zip(&lines) {
        println!("tol {tol:e} pert {pert:e}:{line}");
    }
    println!("spread:{spread}");
    println!("compression (1 - l/L, stretch springs, run 0):{compression}");
    let crossing = |level: f64| {
        let k = pair.iter().position(|&(_, d)| d > level)?;
        let (t1, d1) = pair[k];
        let (t0, d0) = if k == 0 { (0.0, level) } else { pair[k - 1] };
        let f = if d0 > 0.0 && d0 < level {
            (level / d0).ln() / (d1 / d0).ln()
        } else {
            1.0
        };
        Some(t0 + f * (t1 - t0))
    };
    let levels = [1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2];
    let times: Vec<Option<f64>> = levels.iter().map(|&l| crossing(l)).collect();
    let shown: Vec<String> = levels
        .iter()
        .zip(&times)
        .map(|(l, t)| match t {
            Some(t) => format!("{l:.0e}@{t:.4}"),
            None => format!("{l:.0e}@-"),
        })
        .collect();
    println!("h {h:.3e} crossings: {}", shown.join(" "));
    if let (Some(a), Some(b)) = (times[0], times[3]) {
        println!(
            "h {h:.3e} growth 1e-7..1e-4: {:.0} /s over {:.4} s",
            1e3f64.ln() / (b - a),
            b - a
        );
    }
    Ok(())
}

/// The scene's model (see the module doc).
fn model(scene: &str, n: usize, bend: f64) -> drapery::Result<Model> {
    let pile = Preset::Pile.model(n)?;
    let c = &pile.cloths()[0];
    let mut cloth = ClothDesc {
        name: c.name.clone(),
        mesh: c.mesh.clone(),
        material: c.material,
        pins: Vec::new(),
        initial_velocity: Vec3::ZERO,
        handles: Vec::new(),
    };
    match scene {
        "pile" => Ok(pile),
        "pile-noself" => {
            let c: &CollisionSettings = pile.collision().unwrap();
            let settings = CollisionSettings {
                self_collision: false,
                ..*c
            };
            let obstacles = pile.obstacles().to_vec();
            Model::new(vec![cloth], pile.gravity())?.with_collisions(settings, obstacles)
        }
        "free" => Model::new(vec![cloth], pile.gravity()),
        "pile-shell" => {
            cloth.material = Material {
                model: ClothModel::Shell,
                shell: Shell {
                    stretch_modulus: [1000.0, 1000.0],
                    poisson: 0.0,
                    shear_modulus: None,
                    bending_rigidity: [bend, bend],
                    damping: 0.0,
                },
                ..cloth.material
            };
            let obstacles = pile.obstacles().to_vec();
            Model::new(vec![cloth], pile.gravity())?
                .with_collisions(*pile.collision().unwrap(), obstacles)
        }
        "pinch" => {
            let mesh = drapery::Mesh::grid([1.0, 1.0], [n, n], Vec3::ZERO, Vec3::Y)?;
            let edge = |side: f64| HandleDesc {
                vertices: (0..mesh.positions.len() as u32)
                    .filter(|&i| (mesh.positions[i as usize].x - 0.5 * side).abs() < 1e-9)
                    .collect(),
                pivot: None,
                motion: Motion::constant(Vec3::new(-0.75 * side, 0.0, 0.0), Vec3::ZERO),
                release: None,
                attach: None,
            };
            cloth.handles = vec![edge(-1.0), edge(1.0)];
            cloth.mesh = mesh;
            Model::new(vec![cloth], Vec3::ZERO)
        }
        _ => panic!("unknown scene {scene}"),
    }
}

/// The largest `1 - ℓ/L` over the stretch springs (0 when none is compressed).
fn largest_compression(m: &Model) -> f64 {
    let (s, x) = (m.springs(), m.positions());
    (0..s.len())
        .filter(|&k| s.kind[k] == SpringKind::Stretch)
        .map(|k| 1.0 - (x[s.i[k] as usize] - x[s.j[k] as usize]).length() / s.rest[k])
        .fold(0.0f64, f64::max)
}
