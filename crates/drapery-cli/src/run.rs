//! `drapery run SCENE.toml --output DIR`: simulate and write frames.
//!
//! Everything (formats, scene, meshes, model) is checked before the output folder is created.
//! Frame `k` is the state at `k / frame_rate`, from frame 0 (the initial state) to the frame at
//! `duration`. Output goes through [`FrameWriter`]s: a per-frame format writes a file in
//! [`FrameWriter::frame`]; a whole-run format keeps what it needs in memory and writes in
//! [`FrameWriter::finish`]. Adding a format is one `Format` variant and one writer.

use anyhow::{Context, Result, anyhow, bail};
use clap::{Args, ValueEnum};
use drapery::Model;
use drapery::io::obj::write_obj;
use drapery::scene::Scene;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `drapery run`.
#[derive(Args)]
pub struct RunArgs {
    /// The scene file (TOML). Meshes are found relative to it.
    pub scene: PathBuf,
    /// Folder for the output frames (created if missing; existing frame files are overwritten).
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
    /// Output formats, comma separated. `obj` writes DIR/frame_00000.obj, frame_00001.obj, …
    /// (`glb`, `usd` and `ply` are reserved for a later release.)
    #[arg(
        short,
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "obj",
        value_name = "FORMATS"
    )]
    pub format: Vec<Format>,
    /// Worker threads for the solver (default: all cores).
    #[arg(short = 'j', long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
    /// No progress bar and no summary line (errors are still printed).
    #[arg(short, long)]
    pub quiet: bool,
}

/// Output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// Wavefront OBJ, one file per frame.
    Obj,
    /// glTF binary with morph targets, one file per run (not available yet).
    Glb,
    /// USD ASCII point cache, one file per run (not available yet).
    Usd,
    /// Binary PLY, one file per frame (not available yet).
    Ply,
}

impl Format {
    fn name(self) -> &'static str {
        match self {
            Format::Obj => "obj",
            Format::Glb => "glb",
            Format::Usd => "usd",
            Format::Ply => "ply",
        }
    }
}

/// A sink for frames.
pub trait FrameWriter {
    /// Frame `k` (0-based; frame 0 is the initial state) at simulated time `time`.
    fn frame(&mut self, k: usize, time: f64, model: &Model) -> drapery::Result<()>;
    /// Called once after the last frame (not after a failed step).
    fn finish(&mut self) -> drapery::Result<()> {
        Ok(())
    }
}

/// `DIR/frame_NNNNN.obj`, one per frame, each written atomically.
struct ObjFrames {
    dir: PathBuf,
}

impl FrameWriter for ObjFrames {
    fn frame(&mut self, k: usize, _time: f64, model: &Model) -> drapery::Result<()> {
        write_obj(&frame_path(&self.dir, k, "obj"), &model.cloths, &model.x)
    }
}

/// `DIR/frame_00007.EXT`.
pub fn frame_path(dir: &Path, k: usize, ext: &str) -> PathBuf {
    dir.join(format!("frame_{k:05}.{ext}"))
}

/// The writer of one format, or an error when the format is not available.
fn writer_for(format: Format, dir: &Path) -> Result<Box<dyn FrameWriter>> {
    match format {
        Format::Obj => Ok(Box::new(ObjFrames {
            dir: dir.to_path_buf(),
        })),
        other => bail!("format '{}' is not available yet", other.name()),
    }
}

/// Runs a scene.
pub fn run(args: RunArgs) -> Result<()> {
    let mut formats: Vec<Format> = Vec::new();
    for &f in &args.format {
        if !formats.contains(&f) {
            formats.push(f);
        }
    }
    for &f in &formats {
        // Reject unavailable formats before anything is loaded or written.
        writer_for(f, &args.output)?;
    }
    // Before anything else may start rayon's default pool.
    if let Some(n) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
            .map_err(|e| anyhow!("cannot start {n} threads: {e}"))?;
    }
    let scene = Scene::load(&args.scene)?;
    let mut sim = scene.build()?;

    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("{}: cannot create the output folder", args.output.display()))?;
    let mut writers = formats
        .iter()
        .map(|&f| writer_for(f, &args.output))
        .collect::<Result<Vec<_>>>()?;

    let frames = scene.frame_count();
    let steps_per_frame = scene.steps_per_frame();
    let h = scene.step_size();
    let progress = if args.quiet || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        let bar = ProgressBar::with_draw_target(Some(frames as u64), ProgressDrawTarget::stderr());
        if let Ok(style) = ProgressStyle::with_template(
            "{bar:30.cyan/blue} {pos}/{len} frames  t = {msg}  ETA {eta}",
        ) {
            bar.set_style(style);
        }
        bar
    };

    let start = Instant::now();
    let mut cg_total: u64 = 0;
    let mut cg_max: usize = 0;
    let mut steps: u64 = 0;
    for w in writers.iter_mut() {
        w.frame(0, 0.0, &sim.model)?;
    }
    for k in 1..=frames {
        for _ in 0..steps_per_frame {
            let report = sim.step(h).map_err(|e| {
                progress.abandon();
                anyhow!(
                    "frame {k}: {e}; frames 0 to {} are in {}",
                    k - 1,
                    args.output.display()
                )
            })?;
            steps += 1;
            cg_total += report.cg_iterations as u64;
            cg_max = cg_max.max(report.cg_iterations);
        }
        let time = k as f64 / scene.frame_rate;
        for w in writers.iter_mut() {
            w.frame(k, time, &sim.model)?;
        }
        progress.set_message(format!("{time:.3} s"));
        progress.inc(1);
    }
    for w in writers.iter_mut() {
        w.finish()?;
    }
    progress.finish_and_clear();
    if !args.quiet {
        let mean = if steps > 0 {
            cg_total as f64 / steps as f64
        } else {
            0.0
        };
        println!(
            "{} frames written to {} ({}): {} steps in {:.2} s wall, CG iterations per step mean {:.1}, max {}",
            frames + 1,
            args.output.display(),
            formats
                .iter()
                .map(|f| f.name())
                .collect::<Vec<_>>()
                .join(","),
            steps,
            start.elapsed().as_secs_f64(),
            mean,
            cg_max,
        );
    }
    Ok(())
}
