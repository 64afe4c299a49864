//! One implicit step of a cloth hanging from two corners, 64×64 and 128×128 vertices
//! (1 m, 0.1 kg, stretch 1000 N/m, dt = 1/60 s): median wall time of the step, its split
//! between assembly and solve, and the CG iterations. Run with `cargo bench --bench step`.

use drapery::math::Vec3;
use drapery::mesh::Mesh;
use drapery::model::{ClothDesc, MassSpec, Material, Model};
use drapery::{Simulation, SolverSettings};
use std::time::Instant;

fn hanging(n: usize, tolerance: f64) -> Simulation {
    let mesh = Mesh::grid([1.0, 1.0], [n, n], Vec3::new(0.0, 1.0, 0.0), Vec3::Z).unwrap();
    let material = Material {
        stretch_stiffness: 1000.0,
        shear_stiffness: 100.0,
        bend_stiffness: 1.0,
        damping: 0.01,
        air_drag: 0.0,
        mass: MassSpec::Density(0.1),
    };
    let cloth = ClothDesc {
        name: "sheet".into(),
        mesh,
        material,
        pins: vec![0, (n - 1) as u32],
        initial_velocity: Vec3::ZERO,
    };
    Simulation::new(
        Model::new(vec![cloth], Vec3::new(0.0, -9.81, 0.0)).unwrap(),
        SolverSettings {
            tolerance,
            max_iterations: 20000,
            ..Default::default()
        },
    )
    .unwrap()
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let h = 1.0 / 60.0;
    println!(
        "{:>8} {:>9} {:>9} {:>11} {:>11} {:>11} {:>9}",
        "grid", "vertices", "tolerance", "step ms", "assembly", "solve", "CG iters"
    );
    for (n, tolerance) in [(64usize, 1e-3), (64, 1e-6), (128, 1e-3), (128, 1e-6)] {
        let mut sim = hanging(n, tolerance);
        let steps = if n <= 64 { 60 } else { 30 };
        let (mut total, mut asm, mut sol, mut cg) = (vec![], vec![], vec![], vec![]);
        for _ in 0..steps {
            let t = Instant::now();
            let r = sim.step(h).expect("step");
            total.push(t.elapsed().as_secs_f64() * 1e3);
            asm.push(r.assembly_seconds * 1e3);
            sol.push(r.solve_seconds * 1e3);
            cg.push(r.cg_iterations as f64);
        }
        println!(
            "{:>8} {:>9} {:>9.0e} {:>11.2} {:>11.2} {:>11.2} {:>9.0}",
            format!("{n}x{n}"),
            n * n,
            tolerance,
            median(&mut total),
            median(&mut asm),
            median(&mut sol),
            median(&mut cg)
        );
    }
}
