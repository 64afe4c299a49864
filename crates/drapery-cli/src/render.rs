//! `drapery render DIR --output preview.gif`: pictures of the frames of a run.
//!
//! Reads `DIR/frame_*.obj` (or `DIR/frame_*.ply` when there is no OBJ frame), draws them with
//! the library's rasterizer ([`drapery::render`]) from one camera for every frame (the automatic
//! camera framing all frames of the folder, or `--eye/--target/--fov`), and writes an animated
//! GIF (every frame, or every `--every`-th) or one PNG (`--frame N`, default the last frame).
//! With `--scene`, the scene's colliders are drawn too, each posed at its frame's time.

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use drapery::Vec3;
use drapery::io::frames::{find_frames, read_frame};
use drapery::model::ClothInfo;
use drapery::render::{
    AUTO_FOV_Y_DEG, Camera, RenderScene, auto_camera, render, write_gif, write_png,
};
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Default GIF frame rate, frames per second.
pub const DEFAULT_FPS: f64 = 25.0;

/// Arguments of `drapery render`.
#[derive(Args)]
pub struct RenderArgs {
    /// Folder of frames written by `drapery run` (frame_*.obj, or frame_*.ply if no OBJ).
    pub dir: PathBuf,
    /// Picture to write: `.gif` (animation of the frames) or `.png` (one frame).
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// Draw only frame N (its number in frame_N.obj). Default: every frame for a GIF, the last
    /// frame for a PNG.
    #[arg(long, value_name = "N")]
    pub frame: Option<usize>,
    /// Image size in pixels.
    #[arg(long, value_name = "WxH", default_value = "640x480")]
    pub size: String,
    /// GIF playback rate, frames per second (GIF timing is in 1/100 s, so at most 50).
    #[arg(long, value_name = "FPS", default_value_t = DEFAULT_FPS)]
    pub fps: f64,
    /// GIF: draw every K-th frame only (frames 0, K, 2K, …).
    #[arg(long, value_name = "K", default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub every: u32,
    /// Camera position x,y,z in metres (with --target). Default: an automatic three-quarter view
    /// that frames every frame of the folder.
    #[arg(
        long,
        value_name = "X,Y,Z",
        requires = "target",
        allow_hyphen_values = true
    )]
    pub eye: Option<String>,
    /// Point the camera looks at, x,y,z in metres (with --eye).
    #[arg(
        long,
        value_name = "X,Y,Z",
        requires = "eye",
        allow_hyphen_values = true
    )]
    pub target: Option<String>,
    /// Vertical field of view in degrees (with --eye; default 35).
    #[arg(long, value_name = "DEG", requires = "eye")]
    pub fov: Option<f64>,
    /// The scene of the run: also draw its colliders (grey), posed at each frame's time
    /// (frame k at k / frame_rate). Planes are drawn as squares under the cloth.
    #[arg(long, value_name = "SCENE.toml")]
    pub scene: Option<PathBuf>,
}

enum Picture {
    Png,
    Gif,
}

fn parse_size(s: &str) -> Result<(u32, u32)> {
    let bad = || anyhow!("--size: expected WxH such as 640x480, got '{s}'");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    let max = drapery::render::MAX_SIDE;
    if w == 0 || h == 0 || w > max || h > max {
        bail!("--size: each side must be between 1 and {max} pixels, got '{s}'");
    }
    Ok((w, h))
}

fn parse_vec3(opt: &str, s: &str) -> Result<Vec3> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| anyhow!("{opt}: expected three numbers x,y,z, got '{s}'"))?;
    if v.len() != 3 || !v.iter().all(|c| c.is_finite()) {
        bail!("{opt}: expected three finite numbers x,y,z, got '{s}'");
    }
    Ok(Vec3::new(v[0], v[1], v[2]))
}

/// The frame files of a run folder by frame number: OBJ frames, or PLY frames if there is none
/// ([`find_frames`]), and their extension; an error when there is no frame.
pub fn frame_files(dir: &Path) -> Result<(BTreeMap<usize, PathBuf>, &'static str)> {
    match find_frames(dir) {
        Ok(Some(f)) => Ok((f.files, f.ext)),
        Ok(None) => bail!(
            "{}: no frames to render (no frame_*.obj or frame_*.ply files)",
            dir.display()
        ),
        Err(drapery::Error::Io { cause, .. }) => {
            Err(cause).with_context(|| format!("{}: cannot read the frame folder", dir.display()))
        }
        Err(e) => Err(e.into()),
    }
}

/// One frame file as a scene to draw.
fn load_frame(path: &Path) -> Result<RenderScene> {
    let mesh = read_frame(path)?;
    let cloth = ClothInfo {
        material: Default::default(),
        name: "frame".into(),
        offset: 0,
        mesh,
    };
    Ok(RenderScene::from_frame(
        std::slice::from_ref(&cloth),
        &cloth.mesh.positions,
    )?)
}

/// Renders the frames of a run folder to a PNG or GIF.
pub fn render_cmd(args: RenderArgs) -> Result<()> {
    let out = &args.output;
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let picture = match ext.as_str() {
        "png" => Picture::Png,
        "gif" => Picture::Gif,
        "" => bail!(
            "{}: no picture format: give a file name ending in .png or .gif",
            out.display()
        ),
        other => bail!(
            "{}: unknown picture format '.{other}' (use .png or .gif)",
            out.display()
        ),
    };
    let (width, height) = parse_size(&args.size)?;
    if !(args.fps > 0.0 && args.fps.is_finite()) {
        bail!("--fps must be a number > 0, got {}", args.fps);
    }
    let camera = match (&args.eye, &args.target) {
        (Some(eye), Some(target)) => {
            let eye = parse_vec3("--eye", eye)?;
            let target = parse_vec3("--target", target)?;
            let fov = args.fov.unwrap_or(AUTO_FOV_Y_DEG);
            Some(Camera::new(eye, target, fov).map_err(|e| anyhow!("camera: {e}"))?)
        }
        _ => None,
    };

    let scene = match &args.scene {
        Some(p) => Some(drapery::scene::Scene::load(p)?),
        None => None,
    };
    let (files, kind) = frame_files(&args.dir)?;
    let (first, last) = (
        *files.keys().next().unwrap_or(&0),
        *files.keys().next_back().unwrap_or(&0),
    );
    let drawn: BTreeSet<usize> = match (args.frame, &picture) {
        (Some(n), _) => {
            if !files.contains_key(&n) {
                bail!(
                    "{}: there is no frame {n} (the folder holds frames {first} to {last} as {kind})",
                    args.dir.display()
                );
            }
            BTreeSet::from([n])
        }
        (None, Picture::Png) => BTreeSet::from([last]),
        (None, Picture::Gif) => files
            .keys()
            .copied()
            .filter(|k| (k - first) % args.every as usize == 0)
            .collect(),
    };

    // Every frame is read when the automatic camera must frame them all.
    let to_load: Vec<(usize, &PathBuf)> = files
        .iter()
        .filter(|(k, _)| camera.is_none() || drawn.contains(k))
        .map(|(k, p)| (*k, p))
        .collect();
    let mut scenes: Vec<RenderScene> = to_load
        .par_iter()
        .map(|(_, p)| load_frame(p))
        .collect::<Result<_>>()?;
    if let Some(sc) = &scene {
        // Planes are sized from the cloth of the first loaded frame, the same in every picture.
        let cloth_bounds = scenes.first().and_then(|s| s.bounds());
        for ((k, _), s) in to_load.iter().zip(scenes.iter_mut()) {
            let t = *k as f64 / sc.frame_rate;
            for m in crate::colliders::collider_meshes(&sc.obstacles, t, cloth_bounds) {
                s.add_collider(m.positions, m.triangles);
            }
        }
    }
    let camera = match camera {
        Some(c) => c,
        None => auto_camera(&scenes, width, height)?,
    };
    let images = to_load
        .par_iter()
        .zip(&scenes)
        .filter(|((k, _), _)| drawn.contains(k))
        .map(|(_, s)| render(s, &camera, width, height))
        .collect::<drapery::Result<Vec<_>>>()?;
    match picture {
        Picture::Png => write_png(out, &images[0])?,
        Picture::Gif => write_gif(out, &images, args.fps)?,
    }
    Ok(())
}
