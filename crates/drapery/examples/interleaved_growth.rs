//! Issue 18's growth criterion measured with both sizes interleaved in one process
//! (BENCHMARKS.md, "Thirty-seventh session").
//!
//! `cargo run --release -p drapery --example interleaved_growth -- [FRAMES] [SMALL] [LARGE]`
//! builds `spin-SMALL` and `spin-LARGE` (default 129 and 290, the benchmark's rotating sphere,
//! 4 steps of 0.01 s per frame) and runs FRAMES frames of each (default 100) in blocks of
//! `BLOCK` frames (from the environment, default 10): a block of one size, then a block of the
//! other, the order swapped every block. Only the steps are timed (no output is written).
//! Whole runs of the command one after the other (`scripts/growth.sh`) see the shared machine
//! in different states, which moved this ratio by ±10 % between runs minutes apart; here both
//! sizes see the same minutes.
//!
//! Prints, every 10 frames, both sizes' seconds so far and the growth so far
//!
//!   (t_LARGE / LARGE²) / (t_SMALL / SMALL²)
//!
//! and at the end the totals, the ms per step and the growth. At every switch the large cloth
//! has evicted the small one's data from the caches: with `BLOCK=1` spin-129's steps took about
//! 4.5 % longer than with `BLOCK=10` (62.3–63.3 against 59.4–60.4 ms), which made the growth look
//! that much smaller. Blocks of 10 frames leave a tenth of that.
//!
//! `SELF_COLLISION=off` builds both from the scene text with `self_collision = false` (obstacle
//! contact and friction as before), as `scripts/growth.sh` does (BENCHMARKS.md, "Thirty-eighth
//! session").

/// The command's allocator (crates/drapery-cli/src/main.rs), so that the times match it.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

use drapery::Simulation;
use drapery::presets::{Preset, spin_scene};
use drapery::scene::Scene;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |k: usize, default: usize| -> Result<usize, Box<dyn std::error::Error>> {
        match args.get(k) {
            Some(a) => Ok(a.parse().map_err(|_| format!("not a whole number: {a}"))?),
            None => Ok(default),
        }
    };
    let (frames, small, large) = (arg(0, 100)?, arg(1, 129)?, arg(2, 290)?);
    if frames == 0 || small == 0 || large == 0 {
        return Err("usage: interleaved_growth [FRAMES] [SMALL] [LARGE], all positive".into());
    }
    let block: usize = match std::env::var("BLOCK") {
        Ok(b) => b
            .parse()
            .map_err(|_| format!("BLOCK: not a whole number: {b}"))?,
        Err(_) => 10,
    };
    if block == 0 {
        return Err("BLOCK must be a positive whole number".into());
    }
    let self_collision = match std::env::var("SELF_COLLISION").as_deref() {
        Err(_) | Ok("on") => true,
        Ok("off") => false,
        Ok(other) => return Err(format!("SELF_COLLISION must be on or off, not '{other}'").into()),
    };
    let preset = Preset::Spin;
    let (h, per_frame) = preset.step();
    let build = |n: usize| -> Result<Simulation, Box<dyn std::error::Error>> {
        if self_collision {
            return Ok(preset.simulation(n, 1e-3)?);
        }
        let text = spin_scene(n, frames, 1e-3);
        let off = text.replace("self_collision = true", "self_collision = false");
        if off == text {
            return Err("the spin scene has no 'self_collision = true' to turn off".into());
        }
        Ok(Scene::from_str(&off, std::path::Path::new("spin.toml"))?.build()?)
    };
    let mut sims = [build(small)?, build(large)?];
    let sizes = [small, large].map(|n| (n * n) as f64);
    let mut seconds = [0.0f64; 2];
    let growth = |s: &[f64; 2]| (s[1] / sizes[1]) / (s[0] / sizes[0]);
    println!("frame s_{small} s_{large} growth_so_far");
    let mut done = 0;
    while done < frames {
        let count = block.min(frames - done);
        let order = if (done / block).is_multiple_of(2) {
            [0, 1]
        } else {
            [1, 0]
        };
        for k in order {
            let t0 = Instant::now();
            for _ in 0..count * per_frame {
                sims[k].step(h)?;
            }
            seconds[k] += t0.elapsed().as_secs_f64();
        }
        let before = done;
        done += count;
        if done / 10 > before / 10 || done == frames {
            println!(
                "{done} {:.2} {:.2} {:.3}",
                seconds[0],
                seconds[1],
                growth(&seconds)
            );
        }
    }
    let steps = (frames * per_frame) as f64;
    println!(
        "spin-{small} {:.2} s ({:.1} ms/step), spin-{large} {:.2} s ({:.1} ms/step), growth {:.3}",
        seconds[0],
        1e3 * seconds[0] / steps,
        seconds[1],
        1e3 * seconds[1] / steps,
        growth(&seconds)
    );
    Ok(())
}
