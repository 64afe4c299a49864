//! `drapery check DIR [--scene SCENE.toml]`: does anything pass through anything in a run?
//!
//! For every frame of DIR (`frame_*.obj`, or `frame_*.ply` when there is no OBJ frame) it
//! counts, with [`drapery::collision::frame_check::check_frame`]: intersecting cloth triangle
//! pairs (all cloths of the frame together, so cloth–cloth crossings count too) and, with
//! `--scene`, cloth vertices inside the scene's analytic colliders and cloth triangles crossing
//! its mesh colliders, each collider posed at the frame's time `k / frame_rate`; the triangles
//! of the two sides of a `[[stitch]]` pair meet at the seam and do not count as crossing there.
//! One line per frame with a problem, then a summary line; exit code 0 when every frame is
//! clean, 1 when anything intersects (or on an error).

use crate::render::frame_files;
use anyhow::{Result, bail};
use clap::Args;
use drapery::collision::colliders::Collider;
use drapery::collision::frame_check::{FrameCheck, check_frame};
use drapery::io::frames::read_frame;
use drapery::scene::Scene;
use rayon::prelude::*;
use std::path::PathBuf;

/// Default depth below which a vertex inside an analytic collider is not counted, m.
pub const DEFAULT_TOLERANCE: f64 = 1e-9;

/// Arguments of `drapery check`.
#[derive(Args)]
pub struct CheckArgs {
    /// Folder of frames written by `drapery run` (frame_*.obj, or frame_*.ply if no OBJ).
    pub dir: PathBuf,
    /// The scene of the run: also check the cloth against its colliders, posed at each frame's
    /// time (frame k at k / frame_rate). Without it only cloth–cloth intersections are counted.
    #[arg(long, value_name = "SCENE.toml")]
    pub scene: Option<PathBuf>,
    /// Depth in metres below which a vertex inside an analytic collider is not counted.
    #[arg(long, value_name = "M", default_value_t = DEFAULT_TOLERANCE)]
    pub tolerance: f64,
}

/// Checks the frames; `Ok(true)` when every frame is clean.
pub fn check(args: CheckArgs) -> Result<bool> {
    if !(args.tolerance >= 0.0 && args.tolerance.is_finite()) {
        bail!(
            "--tolerance must be a finite number ≥ 0, got {}",
            args.tolerance
        );
    }
    let scene = match &args.scene {
        Some(p) => Some(Scene::load(p)?),
        None => None,
    };
    let colliders: Vec<Collider> = scene
        .iter()
        .flat_map(|s| s.obstacles.iter().map(|o| o.collider.clone()))
        .collect();
    // stitched pairs (global indices, the frames' vertex order): a closed seam is not a crossing
    let stitches: Vec<[u32; 2]> = match &scene {
        Some(s) => s.model()?.stitches().iter().map(|p| [p.a, p.b]).collect(),
        None => Vec::new(),
    };
    let (files, kind) = frame_files(&args.dir)?;
    let frames: Vec<(usize, &PathBuf)> = files.iter().map(|(k, p)| (*k, p)).collect();
    let results: Vec<(usize, FrameCheck)> = frames
        .par_iter()
        .map(|&(k, path)| -> Result<(usize, FrameCheck)> {
            let mesh = read_frame(path)?;
            let (t, n_scene) = match &scene {
                Some(s) => (
                    k as f64 / s.frame_rate,
                    Some(
                        s.cloths
                            .iter()
                            .map(|c| c.mesh.vertex_count())
                            .sum::<usize>(),
                    ),
                ),
                None => (0.0, None),
            };
            if let Some(n) = n_scene
                && n != mesh.vertex_count()
            {
                bail!(
                    "{}: has {} vertices but the cloths of {} have {n}: not a run of this scene",
                    path.display(),
                    mesh.vertex_count(),
                    args.scene
                        .as_ref()
                        .map(|p| p.display().to_string())
                        .unwrap_or_default()
                );
            }
            let r = check_frame(
                &mesh.positions,
                &mesh.triangles(),
                &stitches,
                &colliders,
                t,
                args.tolerance,
            );
            Ok((k, r))
        })
        .collect::<Result<_>>()?;
    let mut out = String::new();
    let mut total = FrameCheck::default();
    let mut bad = 0usize;
    for (k, r) in &results {
        total.self_intersections += r.self_intersections;
        total.penetrations += r.penetrations;
        total.mesh_intersections += r.mesh_intersections;
        if r.is_clean() {
            continue;
        }
        bad += 1;
        let time = match &scene {
            Some(s) => format!(" (t = {} s)", *k as f64 / s.frame_rate),
            None => String::new(),
        };
        out.push_str(&format!("frame {k}{time}: {}\n", describe(r)));
    }
    let what = if scene.is_some() {
        format!("{} colliders", colliders.len())
    } else {
        "no scene: cloth only".to_string()
    };
    if bad == 0 {
        out.push_str(&format!(
            "{} frames ({kind}) in {} checked ({what}): no intersection\n",
            results.len(),
            args.dir.display(),
        ));
    } else {
        out.push_str(&format!(
            "{bad} of {} frames ({kind}) in {} intersect ({what}): {}\n",
            results.len(),
            args.dir.display(),
            describe(&total),
        ));
    }
    print!("{out}");
    Ok(bad == 0)
}

fn describe(r: &FrameCheck) -> String {
    format!(
        "{} intersecting cloth triangle pairs, {} vertices inside colliders, {} cloth–mesh-collider triangle pairs",
        r.self_intersections, r.penetrations, r.mesh_intersections
    )
}
