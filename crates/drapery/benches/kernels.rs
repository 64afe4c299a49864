//! Kernel micro-benchmarks (divan) for regression tracking: assembly, block SpMV (full and
//! upper-triangle storage), one
//! multigrid V-cycle, the multigrid's value refresh, one PCG solve, the broad phase, and two memory-bandwidth references
//! (a read-only sum and a STREAM-style triad over arrays much larger than the caches) to
//! compare the SpMV's bytes per second with. Run with `cargo bench --bench kernels`; the
//! scenes are [`drapery::presets`].

use divan::Bencher;
use divan::counter::BytesCount;
use drapery::Simulation;
use drapery::collision::broad_phase::candidates;
use drapery::linalg::BlockMatrix;
use drapery::linalg::amg::Multigrid;
use drapery::linalg::pcg::{self, PcgScratch, PcgSettings, Preconditioner};
use drapery::linalg::sym::SymBlockMatrix;
use drapery::math::Vec3;
use drapery::presets::Preset;
use rayon::prelude::*;

const H: f64 = 1.0 / 60.0;

fn main() {
    divan::main();
}

/// Runs `f` on a worker of rayon's pool, as [`Simulation::step`] does, so that the parallel
/// loops inside fork from within the pool.
fn in_pool<T: Send>(f: impl FnOnce() -> T + Send) -> T {
    let mut out = None;
    rayon::scope(|_| out = Some(f()));
    out.expect("ran")
}

/// The hanging cloth after a few steps, with its matrix assembled at that state.
fn hang(n: usize) -> Simulation {
    let mut sim = Preset::Hang.simulation(n, 1e-3).unwrap();
    for _ in 0..3 {
        sim.step(H).unwrap();
    }
    sim.assemble_matrix(H);
    sim
}

/// Bytes one product streams at least once: the blocks and their column indices, the row
/// offsets, `x` and `y`.
fn spmv_bytes(a: &BlockMatrix) -> usize {
    a.nnz_blocks() * (72 + 4) + (a.n() + 1) * 4 + 2 * a.n() * 24
}

#[divan::bench(args = [64, 128, 256])]
fn assembly(bencher: Bencher, n: usize) {
    let mut sim = hang(n);
    bencher.bench_local(|| sim.assemble_matrix(H));
}

#[divan::bench(args = [64, 128, 256])]
fn spmv(bencher: Bencher, n: usize) {
    let sim = hang(n);
    let a = sim.matrix();
    let x: Vec<Vec3> = sim.velocities().to_vec();
    let mut y = vec![Vec3::ZERO; a.n()];
    bencher
        .counter(BytesCount::new(spmv_bytes(a)))
        .bench_local(|| in_pool(|| a.mul_vec(divan::black_box(&x), &mut y)));
}

/// The product through the upper triangle ([`SymBlockMatrix`], what PCG and the multigrid
/// use); bytes counted as its blocks and column indices, row offsets, `x` and `y`.
#[divan::bench(args = [64, 128, 256])]
fn sym_spmv(bencher: Bencher, n: usize) {
    let sim = hang(n);
    let a = sim.matrix();
    let mut sym = SymBlockMatrix::from_pattern(a);
    sym.set_values(a);
    let x: Vec<Vec3> = sim.velocities().to_vec();
    let mut y = vec![Vec3::ZERO; a.n()];
    let mut partial = Vec::new();
    let bytes = sym.nnz_blocks() * (72 + 4) + (a.n() + 1) * 4 + 2 * a.n() * 24;
    bencher.counter(BytesCount::new(bytes)).bench_local(|| {
        in_pool(|| sym.mul_then(divan::black_box(&x), &mut y, &mut partial, |_, v| (v, [])))
    });
}

#[divan::bench(args = [64, 128, 256])]
fn vcycle(bencher: Bencher, n: usize) {
    let sim = hang(n);
    let s = sim.model().pin_filter();
    let mut mg = Multigrid::default();
    mg.refresh(sim.matrix(), &s);
    let r: Vec<Vec3> = sim
        .model()
        .velocities()
        .iter()
        .zip(&s)
        .map(|(v, f)| *f * *v)
        .collect();
    let mut out = vec![Vec3::ZERO; r.len()];
    bencher.bench_local(|| in_pool(|| mg.apply(&s, divan::black_box(&r), &mut out)));
}

/// Recomputing the multigrid's values for a matrix of the same pattern (done every solve).
#[divan::bench(args = [64, 128, 256])]
fn amg_values(bencher: Bencher, n: usize) {
    let sim = hang(n);
    let s = sim.model().pin_filter();
    let mut mg = Multigrid::default();
    mg.refresh(sim.matrix(), &s);
    bencher.bench_local(|| mg.refresh(divan::black_box(sim.matrix()), &s));
}

#[divan::bench(args = [64, 128])]
fn pcg_solve(bencher: Bencher, n: usize) {
    let sim = hang(n);
    let s = sim.model().pin_filter();
    let a = sim.matrix();
    let b: Vec<Vec3> = sim
        .total_force()
        .iter()
        .zip(&s)
        .map(|(f, si)| *si * (H * *f))
        .collect();
    let z = vec![Vec3::ZERO; b.len()];
    let settings = PcgSettings {
        tolerance: 1e-3,
        max_iterations: 10_000,
        preconditioner: Preconditioner::Multigrid,
        keep_coarse: false,
    };
    let mut w = PcgScratch::default();
    let mut x = vec![Vec3::ZERO; b.len()];
    bencher.bench_local(|| {
        in_pool(|| {
            x.iter_mut().for_each(|e| *e = Vec3::ZERO);
            let stats = pcg::solve(a, &b, &s, &z, &mut x, &settings, &mut w);
            assert!(stats.converged);
        })
    });
}

/// Broad-phase candidates of the pile after it has folded onto itself (trees built anew).
#[divan::bench(args = [32, 64])]
fn broad_phase(bencher: Bencher, n: usize) {
    let mut sim = Preset::Pile.simulation(n, 1e-3).unwrap();
    for _ in 0..Preset::Pile.warm_up_frames() {
        sim.step(H).unwrap();
    }
    let x0 = sim.positions().to_vec();
    let x1: Vec<Vec3> = x0
        .iter()
        .zip(sim.model().velocities())
        .map(|(x, v)| *x + H * *v)
        .collect();
    let (tris, edges) = (sim.model().triangles(), sim.model().edges());
    bencher.bench_local(|| candidates(&x0, &x1, &tris, &edges, 0.005));
}

/// Elements of the bandwidth reference arrays: 3 × 64 MiB of f64.
const STREAM_LEN: usize = 8 << 20;
const STREAM_CHUNK: usize = 1 << 14;

#[divan::bench]
fn stream_read(bencher: Bencher) {
    let a: Vec<f64> = (0..STREAM_LEN).map(|i| i as f64).collect();
    bencher
        .counter(BytesCount::new(8 * STREAM_LEN))
        .bench_local(|| {
            // eight independent sums, so that the loop waits on memory and not on the adder
            a.par_chunks(STREAM_CHUNK)
                .map(|c| {
                    let mut acc = [0.0f64; 8];
                    for e in c.chunks_exact(8) {
                        for k in 0..8 {
                            acc[k] += e[k];
                        }
                    }
                    acc.iter().sum::<f64>()
                })
                .sum::<f64>()
        });
}

#[divan::bench]
fn stream_triad(bencher: Bencher) {
    let b: Vec<f64> = (0..STREAM_LEN).map(|i| i as f64).collect();
    let c = b.clone();
    let mut a = vec![0.0; STREAM_LEN];
    bencher
        .counter(BytesCount::new(24 * STREAM_LEN))
        .bench_local(|| {
            a.par_chunks_mut(STREAM_CHUNK)
                .zip(b.par_chunks(STREAM_CHUNK).zip(c.par_chunks(STREAM_CHUNK)))
                .for_each(|(a, (b, c))| {
                    for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                        *a = b + 0.5 * c;
                    }
                })
        });
}
