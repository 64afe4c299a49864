//! Which shapes the multigrid-preconditioned CG leaves in its error (BENCHMARKS.md,
//! "Twenty-ninth session").
//!
//! `cargo run --release -p drapery --example error_modes -- SCENE.toml STATE N K` builds the
//! scene, restores the saved state STATE (`-` for the scene's start), assembles the step's
//! matrix `A` there, and solves `A x = A x*` for a fixed pseudo-random `x*` from zero with K
//! and then 2K CG iterations. The cloth must be the scene's first, an `N × N` grid (vertex
//! `r N + c`). For patches of 5 × 5 and 9 × 9 grid vertices it prints the share of the error
//! `x − x*` (its squared norm, summed over the patches) that the best translation of each patch
//! captures, and the share that the best rigid motion (translation and infinitesimal rotation
//! about the patch's centroid, at the current positions) captures. What the translations miss
//! and rigid motions catch is what a coarse space of translations alone leaves to CG.

/// The command's allocator (crates/drapery-cli/src/main.rs).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

use drapery::linalg::pcg::{self, PcgScratch, PcgSettings, Preconditioner};
use drapery::scene::Scene;
use drapery::snapshot::Snapshot;
use drapery::{Mat3, Vec3};

/// Shares of `Σ |e|²` over the `m × m` patches of an `n × n` grid that the best translation
/// and the best rigid motion of each patch capture.
fn shares(e: &[Vec3], p: &[Vec3], n: usize, m: usize) -> (f64, f64) {
    let (mut total, mut translation, mut rigid) = (0.0, 0.0, 0.0);
    for r0 in (0..n + 1 - m).step_by(m) {
        for c0 in (0..n + 1 - m).step_by(m) {
            let ids: Vec<usize> = (0..m * m).map(|q| (r0 + q / m) * n + c0 + q % m).collect();
            let count = ids.len() as f64;
            let centre = ids.iter().fold(Vec3::ZERO, |s, &i| s + p[i]) / count;
            let mean = ids.iter().fold(Vec3::ZERO, |s, &i| s + e[i]) / count;
            let e2: f64 = ids.iter().map(|&i| e[i].length_squared()).sum();
            total += e2;
            translation += count * mean.length_squared();
            // rotation ω of the centred fit `e_i − mean ≈ ω × r_i`: Σ (|r|² I − r rᵀ) ω = Σ r × d
            let (mut normal, mut rhs) = (Mat3::ZERO, Vec3::ZERO);
            for &i in &ids {
                let r = p[i] - centre;
                rhs += r.cross(e[i] - mean);
                normal += Mat3::from_diagonal(Vec3::splat(r.length_squared()))
                    - Mat3::from_cols(r * r.x, r * r.y, r * r.z);
            }
            let omega = if normal.determinant().abs() > 1e-30 {
                normal.inverse() * rhs
            } else {
                Vec3::ZERO
            };
            let miss: f64 = (ids.iter())
                .map(|&i| (e[i] - mean - omega.cross(p[i] - centre)).length_squared())
                .sum();
            rigid += e2 - miss;
        }
    }
    (translation / total, rigid / total)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, scene, state, n, k] = &args[..] else {
        return Err("usage: error_modes SCENE.toml STATE|- N K".into());
    };
    let (n, k): (usize, usize) = (n.parse()?, k.parse()?);
    let scene = Scene::load(std::path::Path::new(scene))?;
    let mut sim = scene.build()?;
    if state != "-" {
        sim.restore_snapshot(&Snapshot::from_bytes(&std::fs::read(state)?)?)?;
    }
    sim.assemble_matrix(scene.step_size());
    let a = sim.matrix().clone();
    let s = sim.model().pin_filter();
    if n * n > a.n() {
        return Err(format!("{n} × {n} is more than the {} particles", a.n()).into());
    }
    let want: Vec<Vec3> = (0..a.n())
        .map(|i| {
            let h = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            let f = |k: u32| ((h >> k) & 0xffff) as f64 / 65535.0 - 0.5;
            Vec3::new(f(0), f(16), f(32))
        })
        .collect();
    let mut b = vec![Vec3::ZERO; a.n()];
    a.mul_vec(&want, &mut b);
    let z = vec![Vec3::ZERO; a.n()];
    let mut scratch = PcgScratch::default();
    // the strength of connection a simulation's multigrid uses
    scratch.multigrid().params.strength = drapery::step::MULTIGRID_STRENGTH;
    for iterations in [k, 2 * k] {
        let settings = PcgSettings {
            tolerance: 1e-14,
            max_iterations: iterations,
            preconditioner: Preconditioner::Multigrid,
            keep_coarse: false,
        };
        let mut x = vec![Vec3::ZERO; a.n()];
        let t0 = std::time::Instant::now();
        let stats = pcg::solve(&a, &b, &s, &z, &mut x, &settings, &mut scratch);
        let took = t0.elapsed().as_secs_f64();
        let mg = scratch.multigrid();
        println!(
            "levels {:?} blocks {:?}; solve {:.1} ms, setup {:.1} ms",
            mg.level_sizes(),
            mg.level_blocks(),
            1e3 * took,
            1e3 * (mg.times.structure + mg.times.values)
        );
        let e: Vec<Vec3> = x.iter().zip(&want).map(|(x, w)| *x - *w).collect();
        for m in [5, 9] {
            let (t, r) = shares(&e, sim.positions(), n, m);
            println!(
                "{} CG iterations, relative residual {:.3e}; {m}×{m} patches: error share in translations {t:.3}, in rigid motions {r:.3}",
                stats.iterations, stats.relative_residual
            );
        }
    }
    Ok(())
}
