//! `drapery bench`: the standard benchmark scenes, timed frame by frame.
//!
//! Scenes (one step per frame, dt = 1/60 s, a 1 m square cloth of 0.1 kg, stretch 1000 N/m):
//! `hang-N` hangs from two corners; `drape-N` falls on a sphere (self-collision on);
//! `pile-N` falls on the ground, tilted, and folds onto itself (self-collision on);
//! `twist-N` is wrung by two handles turning opposite ways (self-collision on).
//! Two textile scenes on the shell model, `N` their **edge length in mm**: `cantilever-N`, a
//! 16 cm strip clamped at one end sagging (tests/it/textile.rs), and `cusick-N`, a 30 cm
//! cotton disc (a ring of vertices on the support's rim) draping over an 18 cm support
//! (tests/it/drape.rs).
//! `spin-N`: the rotating sphere of issue 18, a 1.6 m cloth of N × N vertices dropped onto a
//! sphere of radius 0.5 m spinning at 180°/s (friction 0.4, self-collision on), at dt = 0.01 s,
//! 4 steps per frame; `spin-free-N` is the same cloth without collisions, warmed up as
//! `spin-N` and timed from that draped state (the cost of contacts is the ratio of the two).
//! `--write-scenes DIR` writes the spin scenes as scene files (`DIR/spin-N.toml`, `--frames`
//! frames long) instead of timing anything, for `drapery run` and `drapery check --scene`.
//! Shipped examples by name, read from the source tree's `examples/` (so these run from a
//! source checkout), pre-rolled untimed as `drapery run` does, then timed at their own step,
//! steps per frame and solver settings (`--tolerance` does not apply): `skirt`, the
//! GarmentCode skirt sewn around the hips (examples/skirt.toml).
//! Each scene is first advanced by some untimed warm-up frames (so that collision scenes are
//! in contact; `--warm-up` overrides the count), then `--frames` frames are timed. Each frame is written as OBJ to a temporary
//! folder through the same writer thread as `drapery run` ([`crate::writer`]): the loop steps,
//! hands the positions off, and steps the next frame while the writer writes.
//!
//! Columns, per frame: "ms/frame" is the wall time of the timed frames (steps and hand-offs,
//! until the writer has written the last frame) divided by their number; "output" is the writer
//! thread's time (formatting and the synced, atomic write), which runs overlapped with the next
//! step and so is not part of ms/frame unless the writer is the bottleneck; "wait" is the time
//! the loop blocked handing a frame off to a full channel (non-zero when the writer is the
//! bottleneck). A run reports the mean per frame; the table shows the median over `--runs`
//! runs. Peak memory is the process's peak resident set so far.

use crate::writer::{Sink, Writer};
use anyhow::{Context, Result, bail};
use clap::Args;
use drapery::Simulation;
use drapery::Vec3;
use drapery::io::obj::ObjWriter;
use drapery::presets::Preset;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct BenchArgs {
    /// Scenes to run, comma-separated (e.g. hang-64,drape-64); default: all standard scenes
    /// hang-32,hang-64,hang-128,hang-256,drape-64,drape-128,pile-64,pile-128,twist-64,twist-128,cantilever-5,cusick-5,skirt,spin-129,spin-290.
    #[arg(long, value_delimiter = ',')]
    scenes: Vec<String>,
    /// Timed frames per run.
    #[arg(long, default_value_t = 10)]
    frames: usize,
    /// Runs per scene (the table shows the median).
    #[arg(long, default_value_t = 3)]
    runs: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// PCG relative tolerance for every scene.
    #[arg(long, default_value_t = 1e-3)]
    tolerance: f64,
    /// Untimed frames before the timed ones (default: each scene's own, hang 5, drape 30,
    /// pile 40, twist 90, so that the collision scenes are in contact). `--warm-up 0` makes a quick
    /// smoke run.
    #[arg(long, value_name = "FRAMES")]
    warm_up: Option<usize>,
    /// Write the chosen spin scenes as scene files `DIR/spin-N.toml` of `--frames` frames (at
    /// `--tolerance`) instead of timing them.
    #[arg(long, value_name = "DIR")]
    write_scenes: Option<PathBuf>,
}

const STANDARD: &[&str] = &[
    "hang-32",
    "hang-64",
    "hang-128",
    "hang-256",
    "drape-64",
    "drape-128",
    "pile-64",
    "pile-128",
    "twist-64",
    "twist-128",
    "cantilever-5",
    "cusick-5",
    "skirt",
    "spin-129",
    "spin-290",
];

/// Benchmark scenes that are shipped examples: name and file in the source tree's `examples/`.
const EXAMPLES: &[(&str, &str)] = &[("skirt", "skirt.toml")];

/// A benchmark scene: a preset of some size, or a shipped example's scene file.
enum Bench {
    Preset(Preset, usize),
    Example(PathBuf),
}

/// Checks a scene name: `KIND-SIZE` or a shipped example's name.
fn parse(name: &str) -> Result<Bench> {
    if let Some((_, file)) = EXAMPLES.iter().find(|(n, _)| *n == name) {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
        return Ok(Bench::Example(dir.join(file)));
    }
    let (preset, n) = Preset::parse(name)?;
    Ok(Bench::Preset(preset, n))
}

/// A scene ready to time.
struct Built {
    sim: Simulation,
    /// The simulation timed after the warm-up, when it is not `sim` (it takes `sim`'s state).
    timed: Option<Simulation>,
    /// Untimed frames first.
    warm: usize,
    /// The step, s, and steps per frame.
    h: f64,
    steps: usize,
}

/// Builds a named scene with its warm-up frame count (`warm_up`, or the scene's own; an
/// example's pre-roll is done here, untimed).
fn scene(name: &str, tolerance: f64, warm_up: Option<usize>) -> Result<Built> {
    Ok(match parse(name)? {
        Bench::Preset(preset, n) => {
            let (h, steps) = preset.step();
            let warm = preset.warm_up_scene();
            let timed = (warm != preset)
                .then(|| preset.simulation(n, tolerance))
                .transpose()?;
            Built {
                sim: warm.simulation(n, tolerance)?,
                timed,
                warm: warm_up.unwrap_or(preset.warm_up_frames()),
                h,
                steps,
            }
        }
        Bench::Example(path) => {
            let scene = drapery::scene::Scene::load(&path)
                .with_context(|| format!("scene {name}: {}", path.display()))?;
            Built {
                sim: scene.start()?,
                timed: None,
                warm: warm_up.unwrap_or(0),
                h: scene.step_size(),
                steps: scene.steps_per_frame(),
            }
        }
    })
}

/// Peak resident set size of this process, MiB (Linux), if known.
fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

#[derive(Default, Clone, Copy)]
struct RunTimes {
    frame_ms: f64,
    assembly_ms: f64,
    solve_ms: f64,
    collision_ms: f64,
    output_ms: f64,
    wait_ms: f64,
    cg: f64,
    /// Vertices and steps per frame of the scene.
    vertices: usize,
    steps: usize,
}

/// The writer thread's work in a bench run: each frame written over the same OBJ file.
struct ObjFile {
    path: PathBuf,
    obj: ObjWriter,
}

impl Sink for ObjFile {
    type Job = Vec<Vec3>;
    fn write(&mut self, x: Vec<Vec3>) -> Result<()> {
        Ok(self.obj.write(&self.path, &x)?)
    }
}

fn run_once(args: &BenchArgs, name: &str, dir: &std::path::Path) -> Result<RunTimes> {
    let (frames, tolerance) = (args.frames, args.tolerance);
    let Built {
        mut sim,
        timed,
        warm,
        h,
        steps,
    } = scene(name, tolerance, args.warm_up)?;
    for _ in 0..warm * steps {
        sim.step(h)
            .with_context(|| format!("scene {name} (warm-up)"))?;
    }
    if let Some(mut next) = timed {
        next.set_positions(sim.positions())?;
        next.set_velocities(sim.velocities())?;
        sim = next;
    }
    let mut t = RunTimes::default();
    let mut writer = Writer::start(ObjFile {
        path: dir.join(format!("{name}.obj")),
        obj: ObjWriter::new(sim.model().cloths()),
    })?;
    let start = Instant::now();
    for _ in 0..frames {
        for _ in 0..steps {
            let r = sim.step(h).with_context(|| format!("scene {name}"))?;
            t.assembly_ms += r.assembly_seconds * 1e3;
            t.solve_ms += r.solve_seconds * 1e3;
            t.collision_ms += r.collision_seconds * 1e3;
            t.cg += r.cg_iterations as f64 / steps as f64;
        }
        writer.send(sim.positions().to_vec())?;
    }
    let done = writer.finish()?;
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    t.frame_ms = ms(start.elapsed());
    t.output_ms = ms(done.busy);
    t.wait_ms = ms(writer.wait);
    let f = frames as f64;
    Ok(RunTimes {
        frame_ms: t.frame_ms / f,
        assembly_ms: t.assembly_ms / f,
        solve_ms: t.solve_ms / f,
        collision_ms: t.collision_ms / f,
        output_ms: t.output_ms / f,
        wait_ms: t.wait_ms / f,
        cg: t.cg / f,
        vertices: sim.model().particle_count(),
        steps,
    })
}

/// `--write-scenes`: each spin scene as `DIR/NAME.toml`; other scenes are refused.
fn write_scenes(scenes: &[String], dir: &std::path::Path, frames: usize, tol: f64) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())?;
    for name in scenes {
        let n = match parse(name)? {
            Bench::Preset(Preset::Spin, n) => n,
            _ => bail!("--write-scenes: scene {name} has no scene file (only spin-N scenes do)"),
        };
        let path = dir.join(format!("{name}.toml"));
        let text = drapery::presets::spin_scene(n, frames, tol);
        drapery::io::write_atomic(&path, text.as_bytes())
            .with_context(|| path.display().to_string())?;
        println!("{}", path.display());
    }
    Ok(())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

pub fn bench(args: BenchArgs) -> Result<()> {
    if args.frames == 0 || args.runs == 0 {
        bail!("--frames and --runs must be at least 1");
    }
    if let Some(n) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .context("--threads")?;
    }
    let scenes: Vec<String> = if args.scenes.is_empty() {
        STANDARD.iter().map(|s| s.to_string()).collect()
    } else {
        args.scenes.clone()
    };
    for s in &scenes {
        parse(s)?; // check every name before running anything
    }
    if let Some(dir) = &args.write_scenes {
        return write_scenes(&scenes, dir, args.frames, args.tolerance);
    }
    let dir = std::env::temp_dir().join(format!("drapery-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| dir.display().to_string())?;
    let warm_up = match args.warm_up {
        Some(n) => format!(", {n} warm-up frames"),
        None => String::new(),
    };
    println!(
        "drapery bench: {} timed frames x {} runs per scene{warm_up}, presets 1 step per frame (dt = 1/60 s) but spin 4 (dt = 0.01 s), examples their own steps and solver, tolerance {:e}, {} threads",
        args.frames,
        args.runs,
        args.tolerance,
        rayon::current_num_threads()
    );
    println!(
        "output runs on a writer thread, overlapped with the next step; wait: the step loop blocked on the writer"
    );
    println!(
        "{:<13} {:>8} {:>10} {:>6} {:>8} {:>10} {:>9} {:>10} {:>8} {:>6} {:>9}",
        "scene",
        "vertices",
        "ms/frame",
        "steps",
        "CG/step",
        "assembly",
        "solve",
        "collision",
        "output",
        "wait",
        "peak MiB"
    );
    let result = (|| -> Result<()> {
        for s in &scenes {
            let runs: Vec<RunTimes> = (0..args.runs)
                .map(|_| run_once(&args, s, &dir))
                .collect::<Result<_>>()?;
            let m = |f: fn(&RunTimes) -> f64| median(runs.iter().map(f).collect());
            // the model's own vertex count (the textile scenes' size is an edge length)
            let (vertices, steps) = (runs[0].vertices, runs[0].steps);
            println!(
                "{:<13} {:>8} {:>10.2} {:>6} {:>8.1} {:>10.2} {:>9.2} {:>10.2} {:>8.2} {:>6.2} {:>9}",
                s,
                vertices,
                m(|r| r.frame_ms),
                steps,
                m(|r| r.cg),
                m(|r| r.assembly_ms),
                m(|r| r.solve_ms),
                m(|r| r.collision_ms),
                m(|r| r.output_ms),
                m(|r| r.wait_ms),
                peak_rss_mib().map_or("?".into(), |v| format!("{v:.0}"))
            );
        }
        Ok(())
    })();
    let _ = std::fs::remove_dir_all(&dir);
    result
}
