//! Rounding amplification sweep (issue 18): runs a pile preset at several PCG tolerances and
//! initial perturbations for the first second and prints per-step counts and the spread of
//! the runs' positions.
//!
//! `cargo run --release -p drapery --example rounding -- N STEPS [TOL|pPERT|TOLpPERT]...`
//! e.g. `-- 64 60 0.9e-3 1e-3 p1e-9 1e-6p1e-9` (a `p` value perturbs the initial positions by
//! that many metres, a fixed pseudo-random direction per particle; the tolerance is 1e-3 unless
//! given before the `p`). Prints each run's counts per step (`step:self/ccd/held`) and, per
//! step, the largest distance of any run's positions to the first run's.

use drapery::Vec3;
use drapery::presets::Preset;

fn main() -> drapery::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args[0].parse().unwrap();
    let steps: usize = args[1].parse().unwrap();
    let runs: Vec<(f64, f64)> = args[2..]
        .iter()
        .map(|a| match a.split_once('p') {
            Some(("", p)) => (1e-3, p.parse().unwrap()),
            Some((t, p)) => (t.parse().unwrap(), p.parse().unwrap()),
            None => (a.parse().unwrap(), 0.0),
        })
        .collect();
    let mut frames: Vec<Vec<Vec<Vec3>>> = Vec::new();
    for &(tol, pert) in &runs {
        let mut sim = Preset::Pile.simulation(n, tol)?;
        if pert != 0.0 {
            let x: Vec<Vec3> = sim
                .positions()
                .iter()
                .enumerate()
                .map(|(i, p)| *p + pert * direction(i as u64))
                .collect();
            sim.set_positions(&x)?;
        }
        let mut f = Vec::new();
        let mut line = String::new();
        for s in 0..steps {
            let r = sim.step(1.0 / 60.0)?;
            line += &format!(
                " {}:{}/{}/{}",
                s, r.self_contacts, r.ccd_hits, r.obstacle_contacts
            );
            f.push(sim.positions().to_vec());
        }
        println!("tol {tol:e} pert {pert:e}:{line}");
        frames.push(f);
    }
    // per step: max over runs of the max distance to run 0
    let mut line = String::new();
    for s in 0..steps {
        let d = frames
            .iter()
            .map(|f| {
                f[s].iter()
                    .zip(&frames[0][s])
                    .map(|(a, b)| (*a - *b).length())
                    .fold(0.0f64, f64::max)
            })
            .fold(0.0f64, f64::max);
        line += &format!(" {s}:{d:.1e}");
    }
    println!("spread:{line}");
    Ok(())
}

/// A fixed unit direction per particle (splitmix64).
fn direction(i: u64) -> Vec3 {
    let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut next = || {
        z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut y = z;
        y = (y ^ (y >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        y = (y ^ (y >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        y ^= y >> 31;
        (y >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    Vec3::new(next(), next(), next()).normalize()
}
