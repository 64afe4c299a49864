//! What the fail-safe's listing of cloth pairs costs, by margin (issue 18; BENCHMARKS.md,
//! "Thirty-seventh session").
//!
//! `cargo run --release -p drapery --example margin_cost -- N FILE` restores the saved `spin-N`
//! state FILE, takes the step's motion to be `x₁ = x₀ + h v₀`, and times (median of 7) the
//! listing the fail-safe's first round makes, [`SweptBoxes::close`], with four margins: the
//! thickness (what the fail-safe uses, so that its pairs are also the next step's proximity
//! candidates), half of it, the CCD tolerance alone (a thousandth of it), and the thickness
//! on boxes at the end positions (a static listing of the next step's candidates). It prints the
//! time to build the trees (fresh leaf orders, as after a restore) and to list, the pairs
//! `close` keeps and the pairs whose boxes meet. The difference between the thickness and
//! the tolerance alone is what the thickness costs the traversal.

mod common;

use drapery::collision::broad_phase::SweptBoxes;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (Some(n), Some(file)) = (args.get(1), args.get(2)) else {
        return Err("usage: margin_cost N FILE".into());
    };
    let n: usize = n.parse()?;
    let state = common::spin_motion(n, file)?;
    let (thickness, x0, x1) = (state.thickness, &state.x0, &state.x1);
    let (tris, edges) = (state.sim.model().triangles(), state.sim.model().edges());
    let cases = [
        ("thickness", thickness, false),
        ("half the thickness", 0.5 * thickness, false),
        ("CCD tolerance", 1e-3 * thickness, false),
        ("thickness, end boxes", thickness, true),
    ];
    for (name, margin, at_end) in cases {
        let start = if at_end { x1 } else { x0 };
        let mut times = Vec::new();
        let mut counts = (0, 0);
        for _ in 0..7 {
            let t0 = Instant::now();
            let boxes = SweptBoxes::new(start, x1, &tris, &edges, margin);
            let t1 = Instant::now();
            let close = boxes.close(start, x1);
            let t2 = Instant::now();
            let all = boxes.all();
            times.push([t1 - t0, t2 - t1].map(|d| d.as_secs_f64() * 1e3));
            counts = (close.vt.len() + close.ee.len(), all.vt.len() + all.ee.len());
        }
        times.sort_by(|a, b| a[1].total_cmp(&b[1]));
        let [trees, list] = times[times.len() / 2];
        println!(
            "{n}² {name}: trees {trees:.1} ms, close {list:.1} ms; pairs kept {}, boxes meeting {}",
            counts.0, counts.1
        );
    }
    Ok(())
}
