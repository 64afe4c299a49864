//! Counts of the rotating-sphere scene (issue 18), step by step, for profiling with counts
//! instead of wall time (BENCHMARKS.md, "Ninth session").
//!
//! `cargo run --release -p drapery --example spin_counts -- N save FRAMES FILE` runs `spin-N`
//! for FRAMES frames (4 steps each) from the start and saves the state to FILE;
//! `... -- N steps STEPS FILE [free]` restores FILE and runs STEPS steps of `spin-N` (or, with
//! `free`, of the same cloth without collisions, `spin-free-N`), printing each step's counts
//! and their sums. Under `perf stat -e instructions:u` the second form measures STEPS steps
//! from the same state (building the model and reading FILE are the rest).

use drapery::presets::Preset;
use drapery::snapshot::Snapshot;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: spin_counts N save FRAMES FILE | N steps STEPS FILE [free]";
    if args.len() < 4 {
        return Err(usage.into());
    }
    let n: usize = args[0].parse()?;
    let count: usize = args[2].parse()?;
    let file = &args[3];
    let (h, per_frame) = Preset::Spin.step();
    match args[1].as_str() {
        "save" => {
            let mut sim = Preset::Spin.simulation(n, 1e-3)?;
            for _ in 0..count * per_frame {
                sim.step(h)?;
            }
            std::fs::write(file, sim.snapshot().to_bytes())?;
        }
        "steps" => {
            let free = args.get(4).is_some_and(|a| a == "free");
            let preset = if free { Preset::SpinFree } else { Preset::Spin };
            let mut sim = preset.simulation(n, 1e-3)?;
            sim.restore_snapshot(&Snapshot::from_bytes(&std::fs::read(file)?)?)?;
            println!(
                "step newton solves cg cg/solve held stencils prox_pairs bp_builds ccd_pairs ccd_rounds ccd_hits setups"
            );
            let mut sum = [0usize; 11];
            for k in 0..count {
                let r = sim.step(h)?;
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
        }
        _ => return Err(usage.into()),
    }
    Ok(())
}
