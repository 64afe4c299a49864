//! The frame loop of `drapery.run`: the CLI's run without its resume state, pure Rust (no
//! Python), so that `cargo test` checks it without building the extension.
//!
//! Frame `k` is the state after `k · steps_per_frame` steps of [`Scene::step_size`], frame 0 the
//! initial state, up to [`Scene::frame_count`], as `drapery run` does; each frame is written
//! with the library's writers under the CLI's names ([`frame_path`]): OBJ by
//! [`ObjWriter`], PLY by [`write_ply`], and a sample appended to each cloth's point cache
//! `<cloth name>.pc2` by [`Pc2Writer`]. The files are byte for byte the CLI's.

use drapery::io::frames::frame_path;
use drapery::io::obj::ObjWriter;
use drapery::io::pc2::Pc2Writer;
use drapery::io::ply::write_ply;
use drapery::model::ClothInfo;
use drapery::scene::Scene;
use drapery::{Simulation, StartCheck};
use std::path::{Path, PathBuf};

/// A per-frame output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum FrameFormat {
    /// Wavefront OBJ, `frame_KKKKK.obj`.
    Obj,
    /// Binary little-endian PLY with f64 positions, `frame_KKKKK.ply`.
    Ply,
    /// One PC2 point cache per cloth, `<cloth name>.pc2` (f32, a sample per frame).
    Pc2,
}

impl FrameFormat {
    /// Reads format names (`"obj"`, `"ply"`, `"pc2"`); duplicates are dropped. An error naming the
    /// first name that is not one, or when none is given.
    pub fn parse_list<S: AsRef<str>>(names: &[S]) -> Result<Vec<FrameFormat>, String> {
        let mut out = Vec::new();
        for name in names {
            let f = match name.as_ref() {
                "obj" => FrameFormat::Obj,
                "ply" => FrameFormat::Ply,
                "pc2" => FrameFormat::Pc2,
                "glb" | "usd" => {
                    return Err(format!(
                        "format '{}': drapery.run writes the per-frame formats obj, ply and pc2; \
                         for glb and usd use the drapery command",
                        name.as_ref()
                    ));
                }
                other => {
                    return Err(format!(
                        "unknown format '{other}' (drapery.run writes obj, ply and pc2)"
                    ));
                }
            };
            out.push(f);
        }
        if out.is_empty() {
            return Err("no output format given (obj, ply, pc2)".into());
        }
        out.sort();
        out.dedup();
        Ok(out)
    }
}

/// Why a run stopped.
#[derive(Debug)]
pub enum RunError {
    /// The scene could not be built into a simulation.
    Build(drapery::Error),
    /// A step of frame `frame` failed; frames before it are on disk.
    Step {
        /// The frame being stepped.
        frame: usize,
        /// The library's error.
        error: drapery::Error,
        /// The output folder.
        dir: PathBuf,
    },
    /// A frame file (or the output folder) could not be written.
    Write(drapery::Error),
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::Build(e) | RunError::Write(e) => write!(f, "{e}"),
            // The CLI's wording.
            RunError::Step { frame, error, dir } => write!(
                f,
                "frame {frame}: {error}; frames 0 to {} are in {}",
                frame - 1,
                dir.display()
            ),
        }
    }
}

/// The files of one frame in each format.
struct FrameFiles {
    dir: PathBuf,
    cloths: Vec<ClothInfo>,
    obj: Option<ObjWriter>,
    ply: bool,
    /// One per cloth, in order (empty without pc2).
    pc2: Vec<Pc2Writer>,
}

impl FrameFiles {
    fn write(&mut self, k: usize, x: &[drapery::Vec3]) -> drapery::Result<()> {
        if let Some(obj) = &mut self.obj {
            obj.write(&frame_path(&self.dir, k, "obj"), x)?;
        }
        if self.ply {
            write_ply(&frame_path(&self.dir, k, "ply"), &self.cloths, x)?;
        }
        for (cache, c) in self.pc2.iter_mut().zip(&self.cloths) {
            cache.append(&x[c.range()])?;
        }
        Ok(())
    }
}

/// New point caches `dir/<cloth name>.pc2` with no sample yet (start frame 0, a sample per
/// frame, as the CLI's); a name that cannot name a file is an error naming the cloth.
fn pc2_caches(dir: &Path, cloths: &[ClothInfo]) -> drapery::Result<Vec<Pc2Writer>> {
    if let Some((i, c)) = cloths
        .iter()
        .enumerate()
        .find(|(_, c)| c.name.contains(['/', '\\', '\0']))
    {
        return Err(drapery::Error::field(
            format!("cloth[{i}].name"),
            format!(
                "'{}' cannot name a file: pc2 writes <cloth name>.pc2",
                c.name
            ),
        ));
    }
    cloths
        .iter()
        .map(|c| {
            let path = dir.join(format!("{}.pc2", c.name));
            Pc2Writer::create(&path, c.mesh.positions.len(), 0.0, 1.0)
        })
        .collect()
}

/// A run in progress: frame 0 is written by [`FrameRun::start`], each further frame by one
/// [`FrameRun::next_frame`].
pub struct FrameRun {
    sim: Simulation,
    /// The check of the scene's start, before the pre-roll.
    fresh: Option<StartCheck>,
    files: FrameFiles,
    frames: usize,
    done: usize,
    steps_per_frame: usize,
    h: f64,
}

impl FrameRun {
    /// Builds the simulation, creates `dir` (existing frame files of the same names are
    /// replaced) and writes frame 0.
    pub fn start(scene: &Scene, dir: &Path, formats: &[FrameFormat]) -> Result<FrameRun, RunError> {
        // the scene's own start check (its close pairs), before the pre-roll settles it
        let mut sim = scene.build().map_err(RunError::Build)?;
        let fresh = (scene.preroll_steps() > 0)
            .then(|| sim.start_check())
            .flatten();
        (sim.preroll(scene.preroll_steps(), scene.step_size())).map_err(RunError::Build)?;
        std::fs::create_dir_all(dir)
            .map_err(|e| RunError::Write(drapery::Error::io(dir.display(), e)))?;
        let cloths = sim.model().cloths().to_vec();
        let pc2 = match formats.contains(&FrameFormat::Pc2) {
            true => pc2_caches(dir, &cloths).map_err(RunError::Write)?,
            false => Vec::new(),
        };
        let mut files = FrameFiles {
            dir: dir.to_path_buf(),
            obj: formats
                .contains(&FrameFormat::Obj)
                .then(|| ObjWriter::new(&cloths)),
            ply: formats.contains(&FrameFormat::Ply),
            pc2,
            cloths,
        };
        files.write(0, sim.positions()).map_err(RunError::Write)?;
        Ok(FrameRun {
            sim,
            fresh,
            files,
            frames: scene.frame_count(),
            done: 0,
            steps_per_frame: scene.steps_per_frame(),
            h: scene.step_size(),
        })
    }

    /// Steps the next frame and writes it; its number, or `None` when every frame is written.
    pub fn next_frame(&mut self) -> Result<Option<usize>, RunError> {
        if self.done >= self.frames {
            return Ok(None);
        }
        let k = self.done + 1;
        for _ in 0..self.steps_per_frame {
            self.sim.step(self.h).map_err(|error| RunError::Step {
                frame: k,
                error,
                dir: self.files.dir.clone(),
            })?;
        }
        self.files
            .write(k, self.sim.positions())
            .map_err(RunError::Write)?;
        self.done = k;
        Ok(Some(k))
    }

    /// Frames after frame 0 of the whole run.
    pub fn frame_count(&self) -> usize {
        self.frames
    }

    /// What to warn of at frame 0 ([`Simulation::start_check`] there), with the close pairs of
    /// the scene's start (before the pre-roll, where the cloth had not yet settled into
    /// contact).
    pub fn start_check(&self) -> Option<StartCheck> {
        Some(self.sim.start_check()?.with_start(self.fresh))
    }

    /// The simulation, at the last frame written.
    pub fn simulation(&self) -> &Simulation {
        &self.sim
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drapery::io::obj::read_obj;
    use drapery::io::pc2::read_pc2;
    use drapery::io::ply::read_ply;

    /// A small sheet pinned at one corner: 2 steps per frame, 3 frames.
    const SCENE: &str = r#"
[simulation]
duration = 0.05
dt = 0.008333333333333333
frame_rate = 60

[[cloth]]
name = "sheet"
grid = { size = [0.5, 0.5], resolution = [5, 5], center = [0.0, 1.0, 0.0] }
density = 0.1
pin = [0]
initial_velocity = [0.0, 0.0, 0.3]
"#;

    /// Steps `sim` by `frames` frames of `scene`.
    fn advance(sim: &mut Simulation, scene: &Scene, frames: usize) {
        for _ in 0..frames * scene.steps_per_frame() {
            sim.step(scene.step_size()).unwrap();
        }
    }

    fn scene() -> Scene {
        Scene::from_str(SCENE, Path::new("test.toml")).unwrap()
    }

    #[test]
    fn format_names_are_checked_and_put_in_order() {
        assert_eq!(
            FrameFormat::parse_list(&["pc2", "ply", "obj", "ply"]).unwrap(),
            vec![FrameFormat::Obj, FrameFormat::Ply, FrameFormat::Pc2]
        );
        let e = FrameFormat::parse_list(&["obj", "glb"]).unwrap_err();
        assert!(e.contains("'glb'") && e.contains("drapery command"), "{e}");
        assert!(
            FrameFormat::parse_list(&["png"])
                .unwrap_err()
                .contains("'png'")
        );
        assert!(FrameFormat::parse_list::<&str>(&[]).is_err());
    }

    #[test]
    fn frame_k_is_the_state_after_k_frames_of_steps_in_every_format() {
        let scene = scene();
        assert_eq!((scene.steps_per_frame(), scene.frame_count()), (2, 3));
        let dir = tempfile::tempdir().unwrap();
        let all = [FrameFormat::Obj, FrameFormat::Ply, FrameFormat::Pc2];
        let mut run = FrameRun::start(&scene, dir.path(), &all).unwrap();
        let mut written = vec![];
        while let Some(k) = run.next_frame().unwrap() {
            written.push(k);
        }
        assert_eq!(written, vec![1, 2, 3]);

        let pc2 = read_pc2(&dir.path().join("sheet.pc2")).unwrap();
        assert_eq!(pc2.samples.len(), 4);
        assert_eq!((pc2.header.start_frame, pc2.header.sample_rate), (0.0, 1.0));
        let mut reference = scene.build().unwrap();
        for k in 0..=3 {
            if k > 0 {
                advance(&mut reference, &scene, 1);
            }
            let want = reference.positions();
            let (ply, _) = read_ply(&frame_path(dir.path(), k, "ply")).unwrap();
            let obj = read_obj(&frame_path(dir.path(), k, "obj")).unwrap();
            assert_eq!(ply.len(), want.len());
            for ((p, o), w) in ply.iter().zip(&obj.positions).zip(want) {
                for c in 0..3 {
                    assert_eq!(p[c].to_bits(), w[c].to_bits(), "frame {k} (ply)");
                    assert_eq!(o[c].to_bits(), w[c].to_bits(), "frame {k} (obj)");
                }
            }
            // the cache's sample k: the f32 of frame k
            let sample: Vec<[f32; 3]> = want.iter().map(|w| w.as_vec3().to_array()).collect();
            assert_eq!(pc2.samples[k], sample, "frame {k} (pc2)");
        }
        // The cloth moved between frame 0 and frame 3 (the comparison above is not vacuous).
        let first = read_ply(&frame_path(dir.path(), 0, "ply")).unwrap().0;
        assert!(first.iter().zip(reference.positions()).any(|(a, b)| a != b));
        assert!(!frame_path(dir.path(), 4, "obj").exists());
    }

    #[test]
    fn an_unwritable_folder_is_a_write_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("not_a_folder");
        std::fs::write(&file, b"x").unwrap();
        let Err(e) = FrameRun::start(&scene(), &file, &[FrameFormat::Obj]) else {
            panic!("a file as output folder was accepted");
        };
        assert!(matches!(e, RunError::Write(_)), "{e:?}");
        assert!(e.to_string().contains("not_a_folder"), "{e}");
    }
}
