//! The output formats of `drapery run` and their writers.
//!
//! A per-frame format writes a file in [`FrameWriter::frame`] (on the writer thread, see
//! [`crate::writer`]); a whole-run format keeps what it needs in memory and writes in
//! [`FrameWriter::finish`], at the end of the run. Writers see only the cloths (names and
//! topology) and the positions, never the simulation, so a frame can be written while the next
//! one is being stepped. Adding a format is one `Format` variant and one writer.

use clap::ValueEnum;
use drapery::Vec3;
use drapery::collision::settings::Obstacle;
use drapery::io::frames::frame_path;
use drapery::io::gltf::{StaticMesh, write_glb_with};
use drapery::io::obj::ObjWriter;
use drapery::io::ply::write_ply;
use drapery::io::usd::write_usda;
use drapery::model::ClothInfo;
use std::path::{Path, PathBuf};

/// Output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, ValueEnum)]
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

    /// The name on the command line (`obj`, `glb`, `usd`, `ply`).
    pub fn name(self) -> &'static str {
        match self {
            Format::Obj => "obj",
            Format::Glb => "glb",
            Format::Usd => "usd",
            Format::Ply => "ply",
        }
    }
}

/// A sink for frames. `Send`: per-frame writers run on the writer thread.
pub trait FrameWriter: Send {
    /// Frame `k` (0-based; frame 0 is the initial state) with positions `x`. The cloths are the
    /// same in every call.
    fn frame(&mut self, _k: usize, _cloths: &[ClothInfo], _x: &[Vec3]) -> drapery::Result<()> {
        Ok(())
    }
    /// True for whole-run formats: the run then keeps every frame's positions in memory and
    /// hands them to [`FrameWriter::finish`].
    fn whole_run(&self) -> bool {
        false
    }
    /// Called once at the end with the positions of frames `0..frames.len()` (empty unless some
    /// writer is [`FrameWriter::whole_run`]); also after a failed step, with the frames done.
    fn finish(&mut self, _cloths: &[ClothInfo], _frames: &[Vec<Vec3>]) -> drapery::Result<()> {
        Ok(())
    }
}

/// `DIR/frame_NNNNN.obj`, one per frame, each written atomically.
struct ObjFrames {
    dir: PathBuf,
    /// Made at the first frame (the cloths are the same in every frame).
    obj: Option<ObjWriter>,
}

impl FrameWriter for ObjFrames {
    fn frame(&mut self, k: usize, cloths: &[ClothInfo], x: &[Vec3]) -> drapery::Result<()> {
        let obj = self.obj.get_or_insert_with(|| ObjWriter::new(cloths));
        obj.write(&frame_path(&self.dir, k, "obj"), x)
    }
}

/// `DIR/frame_NNNNN.ply`, one binary PLY per frame, each written atomically.
struct PlyFrames {
    dir: PathBuf,
}

impl FrameWriter for PlyFrames {
    fn frame(&mut self, k: usize, cloths: &[ClothInfo], x: &[Vec3]) -> drapery::Result<()> {
        write_ply(&frame_path(&self.dir, k, "ply"), cloths, x)
    }
}

/// `DIR/<stem>.glb` or `DIR/<stem>.usda`, written once at the end from every frame. The glb
/// also holds the colliders, as static meshes in their pose at frame 0.
struct WholeRun {
    format: Format,
    path: PathBuf,
    frame_rate: f64,
    obstacles: Vec<Obstacle>,
}

impl FrameWriter for WholeRun {
    fn whole_run(&self) -> bool {
        true
    }
    fn finish(&mut self, cloths: &[ClothInfo], frames: &[Vec<Vec3>]) -> drapery::Result<()> {
        match self.format {
            Format::Glb => {
                let bounds = frames
                    .first()
                    .and_then(|x| drapery::render::bounds(x.iter()));
                let meshes = crate::colliders::collider_meshes(&self.obstacles, 0.0, bounds);
                let extra: Vec<StaticMesh<'_>> = meshes
                    .iter()
                    .map(|m| StaticMesh {
                        name: &m.name,
                        positions: &m.positions,
                        triangles: &m.triangles,
                    })
                    .collect();
                write_glb_with(&self.path, cloths, frames, self.frame_rate, &extra)
            }
            _ => write_usda(&self.path, cloths, frames, self.frame_rate),
        }
    }
}

/// The writer of one format.
pub fn writer_for(
    format: Format,
    dir: &Path,
    stem: &str,
    frame_rate: f64,
    obstacles: &[Obstacle],
) -> Box<dyn FrameWriter> {
    let dir = dir.to_path_buf();
    match format {
        Format::Obj => Box::new(ObjFrames { dir, obj: None }),
        Format::Ply => Box::new(PlyFrames { dir }),
        Format::Glb | Format::Usd => Box::new(WholeRun {
            format,
            path: dir.join(format!("{stem}.{}", format.extension())),
            frame_rate,
            obstacles: obstacles.to_vec(),
        }),
    }
}
