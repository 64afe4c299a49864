//! `drapery run SCENE.toml --output DIR`: simulate and write frames.
//!
//! Everything (formats, scene, meshes, model) is checked before the output folder is created.
//! Frame `k` is the state at `k / frame_rate`, from frame 0 (the initial state) to the frame at
//! `duration`. Output goes through the writers of [`crate::formats`]: per-frame formats (obj,
//! ply; pc2, which appends a sample per frame to one cache per cloth) are written on the
//! writer thread ([`crate::writer`]) while the next frame is stepped; whole-run formats (glb,
//! usd) are written at the end.
//!
//! For each frame the writer thread writes the frame's files, then (for whole-run formats) appends
//! its positions to the history, then saves the run state (see [`crate::state`]), in that order,
//! so the state on disk never claims a frame whose files are not written and `--resume`
//! continues a killed run to the same bits. A folder holding another run is refused unless
//! `--overwrite`.

use crate::formats::{Format, FrameWriter, check_cloth_names, pc2_file, writer_for};
use crate::state::{HISTORY_FILE, History, RunState, STATE_FILE};
use crate::writer::{Sink, Writer};
use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use drapery::fingerprint::fingerprint;
use drapery::io::frames::is_frame_file;
use drapery::model::ClothInfo;
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
    /// DIR/<scene stem>.usda, written at the end, also after a blow-up), `pc2` one point cache
    /// per cloth (DIR/<cloth name>.pc2, a sample appended per frame).
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
    /// Continue the run in DIR from its last complete frame (DIR/state.bin); the result is
    /// bit for bit that of an uninterrupted run. Needs the same scene, meshes and formats.
    /// Starts from frame 0 when DIR holds no run yet.
    #[arg(long, conflicts_with = "overwrite")]
    pub resume: bool,
    /// Replace what DIR holds: delete its frame_* files, state.bin, history.bin, the
    /// scene's .glb/.usda and its cloths' .pc2 first. Without --overwrite or --resume, a DIR
    /// that already holds frames or a state file is refused.
    #[arg(long)]
    pub overwrite: bool,
    /// Testing: stop with an error after frame N is written (as if killed).
    #[arg(long, hide = true, value_name = "N")]
    pub stop_after_frames: Option<usize>,
    /// Testing (the kill-and-resume test): end the process abruptly, as a kill would, right
    /// after frame N's files, history and state are on disk. The writer thread ends it there
    /// while the step loop may be frames ahead; nothing else runs (no whole-run file, no
    /// summary, no destructor). Exit code [`ABORT_EXIT_CODE`]; an exit rather than an abort
    /// so that no core dump is written.
    #[arg(long, hide = true, value_name = "N")]
    pub abort_after_frame: Option<usize>,
}

/// The exit code of `--abort-after-frame`.
pub const ABORT_EXIT_CODE: i32 = 134;

/// The file name stem of whole-run outputs: the scene file's stem (`hang` for `hang.toml`).
fn run_stem(scene: &Path) -> String {
    scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "drapery".into())
}

/// Whether DIR holds frames or a run state.
fn holds_a_run(dir: &Path) -> Result<bool> {
    let rd = match std::fs::read_dir(dir) {
        Ok(rd) => rd,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(false),
        Err(e) => {
            return Err(e)
                .with_context(|| format!("{}: cannot read the output folder", dir.display()));
        }
    };
    for e in rd.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if is_frame_file(&name) || name == STATE_FILE || name == HISTORY_FILE {
            return Ok(true);
        }
    }
    Ok(false)
}

/// `--overwrite`: deletes frame files, the state, the history, the whole-run files of this
/// scene and of the run recorded in the state, and the point caches of this scene's cloths.
fn clear_run(dir: &Path, stem: &str, cloths: &[ClothInfo]) -> Result<()> {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    let mut whole = vec![format!("{stem}.glb"), format!("{stem}.usda")];
    whole.extend(cloths.iter().map(|c| pc2_file(&c.name)));
    if let Ok(Some(old)) = RunState::load(dir) {
        whole.push(format!("{}.glb", old.stem));
        whole.push(format!("{}.usda", old.stem));
    }
    for e in rd.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if is_frame_file(&name)
            || name == STATE_FILE
            || name == HISTORY_FILE
            || whole.contains(&name)
        {
            std::fs::remove_file(e.path())
                .with_context(|| format!("{}: cannot delete", e.path().display()))?;
        }
    }
    Ok(())
}

/// Where the run starts: fresh, or after the frame of a saved state.
// (one value per run: boxing the saved state would save nothing)
#[allow(clippy::large_enum_variant)]
enum Start {
    Fresh,
    Resume(RunState),
}

/// Decides how to start in DIR from `--resume` / `--overwrite` and what DIR holds; refuses
/// (before anything is written) when the run would mix with another.
fn plan_start(args: &RunArgs, fp: u64, formats: &str, n: usize, frames: usize) -> Result<Start> {
    let dir = &args.output;
    let shown = dir.display();
    if args.overwrite || !holds_a_run(dir)? {
        return Ok(Start::Fresh);
    }
    let state = RunState::load(dir)?;
    match state {
        None if args.resume => bail!(
            "{shown}: holds frames but no {STATE_FILE} to resume from; use --overwrite to start over"
        ),
        None => bail!(
            "{shown}: already holds frames; use --overwrite to replace them (or another folder)"
        ),
        Some(st) if st.fingerprint != fp => bail!(
            "{shown}: holds a run of another scene (or the scene or its meshes changed since); \
             use --overwrite to replace it"
        ),
        Some(st) if !args.resume => {
            if st.frame as usize >= frames {
                bail!(
                    "{shown}: already holds the complete run of this scene; use --overwrite to run it again"
                )
            }
            bail!(
                "{shown}: already holds frames 0 to {} of this scene; use --resume to continue or --overwrite to start over",
                st.frame
            )
        }
        Some(st) if st.formats != formats => bail!(
            "{shown}: the run was started with --format {}; resume it with the same formats",
            st.formats
        ),
        Some(st) if st.snapshot.particle_count() != n || st.frame as usize > frames => {
            bail!("{shown}: {STATE_FILE} does not match the scene; use --overwrite to start over")
        }
        Some(st) => Ok(Start::Resume(st)),
    }
}

/// What the writer thread does for each frame of a run: the per-frame files, the history (for
/// whole-run formats), then the state, which names the frame.
struct RunOutput {
    dir: PathBuf,
    cloths: Vec<ClothInfo>,
    writers: Vec<Box<dyn FrameWriter>>,
    history: History,
    /// `--abort-after-frame`.
    abort_after: Option<usize>,
}

impl Sink for RunOutput {
    /// The state after the frame; its positions are the frame's.
    type Job = RunState;

    fn write(&mut self, state: RunState) -> Result<()> {
        let x = state.snapshot.positions();
        for w in self.writers.iter_mut() {
            w.frame(state.frame as usize, &self.cloths, x)?;
        }
        self.history.push(x)?;
        state.save(&self.dir)?;
        if self.abort_after == Some(state.frame as usize) {
            std::process::exit(ABORT_EXIT_CODE);
        }
        Ok(())
    }
}

/// Runs a scene.
pub fn run(args: RunArgs) -> Result<()> {
    // Canonical order (obj, glb, usd, ply, pc2), so that `glb,obj` resumes a run of `obj,glb`.
    let mut formats: Vec<Format> = args.format.clone();
    formats.sort();
    formats.dedup();
    // Before anything else may start rayon's default pool.
    if let Some(n) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
            .map_err(|e| anyhow!("cannot start {n} threads: {e}"))?;
    }
    let scene = Scene::load(&args.scene)?;
    let mut sim = scene.build()?;
    let scene_text = std::fs::read(&args.scene)
        .with_context(|| format!("{}: cannot read", args.scene.display()))?;
    let fp = fingerprint(&scene, &scene_text);
    let format_list = formats
        .iter()
        .map(|f| f.name())
        .collect::<Vec<_>>()
        .join(",");
    check_cloth_names(&formats, sim.model().cloths())
        .map_err(|e| anyhow!("{}: {e}", args.scene.display()))?;
    let frames = scene.frame_count();
    let dir = &args.output;
    let stem = run_stem(&args.scene);
    let begin = plan_start(
        &args,
        fp,
        &format_list,
        sim.model().particle_count(),
        frames,
    )?;

    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create the output folder", dir.display()))?;
    if args.overwrite {
        clear_run(dir, &stem, sim.model().cloths())?;
    }
    let (mut whole_run, per_frame): (Vec<Box<dyn FrameWriter>>, Vec<_>) = formats
        .iter()
        .map(|&f| writer_for(f, dir, &stem, scene.frame_rate, &scene.obstacles))
        .partition(|w| w.whole_run());
    let keep_history = !whole_run.is_empty();
    let (mut untangling, mut start_check) = (None, None);
    if matches!(begin, Start::Fresh) {
        // `[simulation] preroll`: settle with everything held at its pose at t = 0; frame 0 is
        // the settled state (a resumed run restores its snapshot instead); cloth starting
        // inside colliders or crossed is untangled there
        // the scene's own start (its close pairs), then frame 0's facts, each from one search
        // for what is tangled
        let fresh = (scene.preroll_steps() > 0)
            .then(|| sim.start_check())
            .flatten();
        sim.preroll(scene.preroll_steps(), scene.step_size())
            .with_context(|| format!("{}: pre-roll", args.scene.display()))?;
        start_check = sim.start_check().map(|c| c.with_start(fresh));
        let now = start_check.map(|c| c.tangled).unwrap_or_default();
        let before = fresh.map_or(now, |c| c.tangled);
        untangling = (before != drapery::Tangled::default()).then_some((before, now));
    }
    let (first, history) = match begin {
        Start::Fresh => (
            0,
            if keep_history {
                History::create(dir)?
            } else {
                History::none()
            },
        ),
        Start::Resume(st) => {
            sim.restore_snapshot(&st.snapshot)?;
            let k = st.frame as usize;
            let h = if keep_history {
                History::resume(dir, k + 1, sim.model().particle_count())?
            } else {
                History::none()
            };
            (k + 1, h)
        }
    };
    let snapshot = |k: usize, sim: &drapery::Simulation| {
        RunState::new(
            fp,
            k as u64,
            format_list.clone(),
            stem.clone(),
            sim.snapshot(),
        )
    };
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
    // steps that ended with edges over their strain limit (the projection's cap), and the most
    let (mut strain_steps, mut strain_most) = (0usize, 0usize);
    let mut steps: u64 = 0;
    let mut writer = Writer::start(RunOutput {
        dir: dir.clone(),
        cloths: sim.model().cloths().to_vec(),
        writers: per_frame,
        history,
        abort_after: args.abort_after_frame,
    })?;
    // Hands frame k to the writer; `--stop-after-frames k` then waits until it is on disk.
    let emit = |k: usize, sim: &drapery::Simulation, writer: &mut Writer<RunOutput>| {
        writer.send(snapshot(k, sim))?;
        if args.stop_after_frames == Some(k) && k < frames {
            writer.finish()?;
            bail!("stopped after frame {k} (--stop-after-frames)");
        }
        Ok(())
    };
    if first == 0 {
        if let Some((before, now)) = untangling {
            let when = if scene.preroll_steps() > 0 {
                "after the pre-roll"
            } else {
                "at frame 0 (no pre-roll: the first steps untangle)"
            };
            progress.suspend(|| {
                eprintln!(
                    "{}: the cloth starts tangled ({} vertices inside colliders, {} crossed cloth triangle pairs); {when}: {} inside, {} crossed",
                    args.scene.display(),
                    before.inside,
                    before.crossings,
                    now.inside,
                    now.crossings
                )
            });
        }
        // what the first steps will not untangle, and a thickness beyond the mesh's spacing
        for w in start_check.map(|c| c.warnings()).unwrap_or_default() {
            progress.suspend(|| eprintln!("warning: {}: {w}", args.scene.display()));
        }
        emit(0, &sim, &mut writer)?;
    }
    progress.set_position(first.saturating_sub(1) as u64);
    let mut failure = None;
    'frames: for k in first.max(1)..=frames {
        for _ in 0..steps_per_frame {
            match sim.step(h) {
                Ok(report) => {
                    steps += 1;
                    cg_total += report.cg_iterations as u64;
                    cg_max = cg_max.max(report.cg_iterations);
                    if report.strain_over > 0 {
                        strain_steps += 1;
                        strain_most = strain_most.max(report.strain_over);
                    }
                }
                Err(e) => {
                    failure = Some(anyhow!(
                        "frame {k}: {e}; frames 0 to {} are in {}",
                        k - 1,
                        dir.display()
                    ));
                    break 'frames;
                }
            }
        }
        emit(k, &sim, &mut writer)?;
        progress.set_message(format!("{:.3} s", k as f64 / scene.frame_rate));
        progress.inc(1);
    }
    // Every frame handed off is on disk (or the writer's error is the run's).
    let history = writer.finish()?.sink.history;
    if failure.is_some() {
        progress.abandon();
    }
    // Whole-run files are written even after a blow-up, with the frames done.
    let mut finish_error = None;
    for w in whole_run.iter_mut() {
        if let Err(e) = w.finish(sim.model().cloths(), &history.frames) {
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
        let resumed = if first > 0 {
            format!(", resumed after frame {}", first - 1)
        } else {
            String::new()
        };
        println!(
            "{} frames written to {} ({}{resumed}): {} steps in {:.2} s wall, CG iterations per step mean {:.1}, max {}",
            frames + 1 - first,
            dir.display(),
            format_list,
            steps,
            start.elapsed().as_secs_f64(),
            mean,
            cg_max,
        );
    }
    if strain_steps > 0 {
        eprintln!(
            "warning: the strain limit was not reached on {strain_steps} steps (at most {strain_most} edges over at a step's end: the projection stopped at its pass cap)"
        );
    }
    Ok(())
}
