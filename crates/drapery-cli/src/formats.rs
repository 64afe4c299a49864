//! The output formats of `drapery run` and their writers.
//!
//! A per-frame format writes a file in [`FrameWriter::frame`] (on the writer thread, see
//! [`crate::writer`]); a whole-run format keeps what it needs in memory and writes in
//! [`FrameWriter::finish`], at the end of the run. Writers see only the cloths (names and
//! topology) and the positions, never the simulation, so a frame can be written while the next
//! one is being stepped. Adding a format is one `Format` variant and one writer.
//!
//! A per-frame writer learns where the run starts from its first frame: frame 0 starts a new
//! run, a later frame `k` continues a resumed one whose frames `0..k` are on disk.

use clap::ValueEnum;
use drapery::Vec3;
use drapery::collision::settings::Obstacle;
use drapery::io::frames::frame_path;
use drapery::io::gltf::write_glb_scene;
use drapery::io::obj::ObjWriter;
use drapery::io::pc2::Pc2Writer;
use drapery::io::ply::write_ply;
use drapery::io::usd::write_usda_with;
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
    /// PC2 point cache (f32 positions), one file per cloth: DIR/<cloth name>.pc2, a sample
    /// appended per frame.
    Pc2,
}

impl Format {
    fn extension(self) -> &'static str {
        match self {
            Format::Usd => "usda",
            other => other.name(),
        }
    }

    /// The name on the command line (`obj`, `glb`, `usd`, `ply`, `pc2`).
    pub fn name(self) -> &'static str {
        match self {
            Format::Obj => "obj",
            Format::Glb => "glb",
            Format::Usd => "usd",
            Format::Ply => "ply",
            Format::Pc2 => "pc2",
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

/// `DIR/<cloth name>.pc2`: one point cache per cloth, sample `k` = frame `k` (start frame 0,
/// sample rate 1), the f32 of the positions. Each frame appends a sample to every cache; a
/// resumed run first cuts the caches back to the frames before the one it starts with.
struct Pc2Caches {
    dir: PathBuf,
    /// One per cloth, opened at the first frame.
    caches: Vec<Pc2Writer>,
}

impl FrameWriter for Pc2Caches {
    fn frame(&mut self, k: usize, cloths: &[ClothInfo], x: &[Vec3]) -> drapery::Result<()> {
        if self.caches.is_empty() {
            self.caches = cloths
                .iter()
                .map(|c| {
                    let path = pc2_path(&self.dir, &c.name);
                    let points = c.mesh.positions.len();
                    match k {
                        0 => Pc2Writer::create(&path, points, 0.0, 1.0),
                        _ => Pc2Writer::open(&path, points, Some(k)),
                    }
                })
                .collect::<drapery::Result<_>>()?;
        }
        for (cache, c) in self.caches.iter_mut().zip(cloths) {
            let shown = cache.path().display();
            let samples = cache.header().samples;
            if samples != k {
                return Err(drapery::Error::Invalid(format!(
                    "{shown}: frame {k} would be sample {samples}"
                )));
            }
            let Some(xc) = x.get(c.range()) else {
                return Err(drapery::Error::Invalid(format!(
                    "{shown}: the frame has {} positions, cloth '{}' needs {:?}",
                    x.len(),
                    c.name,
                    c.range()
                )));
            };
            cache.append(xc)?;
        }
        Ok(())
    }
}

/// The file name of the point cache of the cloth `name`: `<name>.pc2`.
pub fn pc2_file(name: &str) -> String {
    format!("{name}.pc2")
}

fn pc2_path(dir: &Path, name: &str) -> PathBuf {
    dir.join(pc2_file(name))
}

/// Checks, before anything is written, that every cloth name can name its file in the output
/// folder: a format writing one file per cloth (pc2) refuses a name with a path separator.
/// The error gives the cloth's field (`cloth[1].name: …`).
pub fn check_cloth_names(formats: &[Format], cloths: &[ClothInfo]) -> drapery::Result<()> {
    if !formats.contains(&Format::Pc2) {
        return Ok(());
    }
    for (i, c) in cloths.iter().enumerate() {
        if c.name.contains(['/', '\\', '\0']) {
            return Err(drapery::Error::field(
                format!("cloth[{i}].name"),
                format!(
                    "'{}' cannot name a file: --format pc2 writes DIR/<cloth name>.pc2",
                    c.name
                ),
            ));
        }
    }
    Ok(())
}

/// `DIR/<stem>.glb` or `DIR/<stem>.usda`, written once at the end from every frame, with the
/// colliders: fixed ones as they are, moving ones animated at every frame's time (glb: node
/// translation/rotation channels; usd: time-sampled xform ops).
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
        let bounds = frames
            .first()
            .and_then(|x| drapery::render::bounds(x.iter()));
        let colliders = crate::colliders::collider_tracks(
            &self.obstacles,
            frames.len(),
            self.frame_rate,
            bounds,
        );
        let (path, rate) = (&self.path, self.frame_rate);
        match self.format {
            Format::Glb => write_glb_scene(path, cloths, frames, rate, &colliders),
            _ => write_usda_with(path, cloths, frames, rate, &colliders),
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
        Format::Pc2 => Box::new(Pc2Caches {
            dir,
            caches: Vec::new(),
        }),
        Format::Glb | Format::Usd => Box::new(WholeRun {
            format,
            path: dir.join(format!("{stem}.{}", format.extension())),
            frame_rate,
            obstacles: obstacles.to_vec(),
        }),
    }
}
