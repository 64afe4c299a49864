//! One implicit step of a cloth hanging from two corners, 64×64, 128×128 and 256×256 vertices
//! (1 m, 0.1 kg, stretch 1000 N/m, dt = 1/60 s), with the block-Jacobi and the multigrid
//! preconditioner in the same run: median wall time of the step, its split between assembly
//! and solve, the multigrid setup (value refresh) included in the solve, and the CG iterations.
//! Run with `cargo bench --bench step`.

use drapery::linalg::amg::Multigrid;
use drapery::linalg::pcg::Preconditioner;
use drapery::presets::Preset;
use drapery::{Simulation, SolverSettings};
use std::time::Instant;

fn hanging(n: usize, tolerance: f64, preconditioner: Preconditioner) -> Simulation {
    let model = Preset::Hang.model(n).unwrap();
    let settings = SolverSettings {
        tolerance,
        max_iterations: 20000,
        preconditioner,
        ..Default::default()
    };
    Simulation::new(model, settings).unwrap()
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let h = 1.0 / 60.0;
    println!(
        "{:>8} {:>9} {:>9} {:>13} {:>9} {:>9} {:>9} {:>9} {:>9}",
        "grid",
        "vertices",
        "tolerance",
        "precond",
        "step ms",
        "assembly",
        "solve",
        "setup",
        "CG iters"
    );
    let rows = [
        (64usize, 1e-3, 60),
        (64, 1e-6, 60),
        (128, 1e-3, 30),
        (128, 1e-6, 30),
        (256, 1e-3, 6),
    ];
    for (n, tolerance, steps) in rows {
        for p in [Preconditioner::BlockJacobi, Preconditioner::Multigrid] {
            let mut sim = hanging(n, tolerance, p);
            // the multigrid setup, measured apart on each step's matrix (its structure is
            // built on the first step, then only the values are refreshed)
            let mut mg = Multigrid::default();
            let filter = sim.model().pin_filter();
            let (mut total, mut asm, mut sol, mut cg, mut setup) =
                (vec![], vec![], vec![], vec![], vec![]);
            for _ in 0..steps {
                let t = Instant::now();
                let r = sim.step(h).expect("step");
                total.push(t.elapsed().as_secs_f64() * 1e3);
                asm.push(r.assembly_seconds * 1e3);
                sol.push(r.solve_seconds * 1e3);
                cg.push(r.cg_iterations as f64);
                if p == Preconditioner::Multigrid {
                    mg.refresh(sim.matrix(), &filter);
                    if mg.times.values > 0.0 {
                        setup.push(mg.times.values * 1e3);
                    }
                }
            }
            let setup = if setup.is_empty() {
                "-".to_string()
            } else {
                format!("{:.2}", median(&mut setup))
            };
            println!(
                "{:>8} {:>9} {:>9.0e} {:>13} {:>9.2} {:>9.2} {:>9.2} {:>9} {:>9.0}",
                format!("{n}x{n}"),
                n * n,
                tolerance,
                format!("{p:?}"),
                median(&mut total),
                median(&mut asm),
                median(&mut sol),
                setup,
                median(&mut cg)
            );
        }
    }
}
