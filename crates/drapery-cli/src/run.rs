//! `drapery run SCENE.toml --output DIR`: simulate and write frames.
//!
//! Everything (formats, scene, meshes, model) is checked before the output folder is created.
//! Frame `k` is the state at `k / frame_rate`, from frame 0 (the initial state) to the frame at
//! `duration`. Output goes through [`FrameWriter`]s: a per-frame format writes a file in
//! [`FrameWriter::frame`]; a whole-run format keeps what it needs in memory and writes in
//! [`FrameWriter::finish`]. Adding a format is one `Format` variant and one writer.

use anyhow::{Context, Result, anyhow};
use clap::{Args, ValueEnum};
use drapery::Model;
use drapery::Vec3;
use drapery::io::gltf::write_glb;
use drapery::io::obj::write_obj;
use drapery::io::ply::write_ply;
use drapery::io::usd::write_usda;
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
    /// Output formats, comma separated: `obj` and `ply` write one file per frame
    /// (DIR/frame_00000.obj, …), `glb` and `usd` one animation per run (DIR/<scene stem>.glb,
    /// DIR/<scene stem>.usda, written at the end, also after a blow-up).
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
    /// glTF binary with morph targets, one file per run: DIR/<scene stem>.glb.
    Glb,
    /// USD ASCII point cache, one file per run: DIR/<scene stem>.usda.
    Usd,
    /// Binary little-endian PLY (f64 positions), one file per frame: DIR/frame_00000.ply, ….
    Ply,
}

impl Format {
    fn extension(self) -> &'static str {
        match self {
            Format::Usd => "usda",
            other => other.name(),
        }
    }

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
    /// Frame `k` (0-based; frame 0 is the initial state).
    fn frame(&mut self, _k: usize, _model: &Model) -> drapery::Result<()> {
        Ok(())
    }
    /// True for whole-run formats: the run then keeps every frame's positions in memory and
    /// hands them to [`FrameWriter::finish`].
    fn whole_run(&self) -> bool {
        false
    }
    /// Called once at the end with the positions of frames `0..frames.len()` (empty unless some
    /// writer is [`FrameWriter::whole_run`]); also after a failed step, with the frames done.
    fn finish(&mut self, _model: &Model, _frames: &[Vec<Vec3>]) -> drapery::Result<()> {
        Ok(())
    }
}

/// `DIR/frame_NNNNN.obj`, one per frame, each written atomically.
struct ObjFrames {
    dir: PathBuf,
}

impl FrameWriter for ObjFrames {
    fn frame(&mut self, k: usize, model: &Model) -> drapery::Result<()> {
        write_obj(&frame_path(&self.dir, k, "obj"), &model.cloths, &model.x)
    }
}

/// `DIR/frame_NNNNN.ply`, one binary PLY per frame, each written atomically.
struct PlyFrames {
    dir: PathBuf,
}

impl FrameWriter for PlyFrames {
    fn frame(&mut self, k: usize, model: &Model) -> drapery::Result<()> {
        write_ply(&frame_path(&self.dir, k, "ply"), &model.cloths, &model.x)
    }
}

/// `DIR/<stem>.glb` or `DIR/<stem>.usda`, written once at the end from every frame.
struct WholeRun {
    format: Format,
    path: PathBuf,
    frame_rate: f64,
}

impl FrameWriter for WholeRun {
    fn whole_run(&self) -> bool {
        true
    }
    fn finish(&mut self, model: &Model, frames: &[Vec<Vec3>]) -> drapery::Result<()> {
        match self.format {
            Format::Glb => write_glb(&self.path, &model.cloths, frames, self.frame_rate),
            _ => write_usda(&self.path, &model.cloths, frames, self.frame_rate),
        }
    }
}

/// `DIR/frame_00007.EXT`.
pub fn frame_path(dir: &Path, k: usize, ext: &str) -> PathBuf {
    dir.join(format!("frame_{k:05}.{ext}"))
}

/// The file name stem of whole-run outputs: the scene file's stem (`hang` for `hang.toml`).
fn run_stem(scene: &Path) -> String {
    scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "drapery".into())
}

/// The writer of one format.
fn writer_for(format: Format, dir: &Path, stem: &str, frame_rate: f64) -> Box<dyn FrameWriter> {
    let dir = dir.to_path_buf();
    match format {
        Format::Obj => Box::new(ObjFrames { dir }),
        Format::Ply => Box::new(PlyFrames { dir }),
        Format::Glb | Format::Usd => Box::new(WholeRun {
            format,
            path: dir.join(format!("{stem}.{}", format.extension())),
            frame_rate,
        }),
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
    let stem = run_stem(&args.scene);
    let mut writers: Vec<Box<dyn FrameWriter>> = formats
        .iter()
        .map(|&f| writer_for(f, &args.output, &stem, scene.frame_rate))
        .collect();
    let keep_history = writers.iter().any(|w| w.whole_run());
    let mut history: Vec<Vec<Vec3>> = Vec::new();

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
    let mut emit = |k: usize,
                    sim: &drapery::Simulation,
                    history: &mut Vec<Vec<Vec3>>|
     -> drapery::Result<()> {
        for w in writers.iter_mut() {
            w.frame(k, &sim.model)?;
        }
        if keep_history {
            history.push(sim.model.x.clone());
        }
        Ok(())
    };
    emit(0, &sim, &mut history)?;
    let mut failure = None;
    'frames: for k in 1..=frames {
        for _ in 0..steps_per_frame {
            match sim.step(h) {
                Ok(report) => {
                    steps += 1;
                    cg_total += report.cg_iterations as u64;
                    cg_max = cg_max.max(report.cg_iterations);
                }
                Err(e) => {
                    failure = Some(anyhow!(
                        "frame {k}: {e}; frames 0 to {} are in {}",
                        k - 1,
                        args.output.display()
                    ));
                    break 'frames;
                }
            }
        }
        emit(k, &sim, &mut history)?;
        progress.set_message(format!("{:.3} s", k as f64 / scene.frame_rate));
        progress.inc(1);
    }
    if failure.is_some() {
        progress.abandon();
    }
    // Whole-run files are written even after a blow-up, with the frames done.
    let mut finish_error = None;
    for w in writers.iter_mut() {
        if let Err(e) = w.finish(&sim.model, &history) {
            finish_error.get_or_insert(e);
        }
    }
    if let Some(e) = failure {
        return Err(match finish_error {
            Some(f) => e.context(format!("also: {f}")),
            None => e,
        });
    }
    if let Some(e) = finish_error {
        return Err(e.into());
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
