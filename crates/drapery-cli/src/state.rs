//! The run state that makes `drapery run --resume` possible.
//!
//! After every frame's files are on disk, `DIR/state.bin` is rewritten atomically with what is
//! needed to continue bit for bit: a library [`Snapshot`] of the simulation (positions,
//! velocities, warm start, time, step count; its bytes carry the magic and the checksum, see
//! [`drapery::snapshot`]) whose header holds what only the CLI knows: the scene fingerprint
//! ([`drapery::fingerprint`]), the frame index, the output formats and the whole-run file stem.
//! When a whole-run format (glb, usd) is requested, the positions of every frame done are also
//! appended to `DIR/history.bin` (raw little-endian f64, `3 × particles` per frame) before the
//! state is written; the state tells how many frames of it are valid, so bytes appended by a
//! killed run after its last state are cut off on resume.
//!
//! Header layout (little endian): u64 fingerprint, u64 frame, u32 length + UTF-8 format list
//! (`obj,glb`), then the UTF-8 whole-run file stem (`hang`) to the end.

use anyhow::{Context, Result, bail};
use drapery::Vec3;
use drapery::snapshot::Snapshot;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The state file in a run folder.
pub const STATE_FILE: &str = "state.bin";
/// The frame history kept for whole-run formats.
pub const HISTORY_FILE: &str = "history.bin";

/// What `state.bin` holds.
#[derive(Clone, Debug, PartialEq)]
pub struct RunState {
    pub fingerprint: u64,
    /// The last frame whose files are complete.
    pub frame: u64,
    /// Output formats of the run, comma separated.
    pub formats: String,
    /// File stem of the whole-run outputs (`hang` for `hang.glb`).
    pub stem: String,
    /// The simulation after the frame, its header holding the fields above.
    pub snapshot: Snapshot,
}

impl RunState {
    /// The state of a run after frame `frame`.
    pub fn new(
        fingerprint: u64,
        frame: u64,
        formats: String,
        stem: String,
        snapshot: Snapshot,
    ) -> RunState {
        let mut header = Vec::with_capacity(20 + formats.len() + stem.len());
        header.extend_from_slice(&fingerprint.to_le_bytes());
        header.extend_from_slice(&frame.to_le_bytes());
        header.extend_from_slice(&(formats.len() as u32).to_le_bytes());
        header.extend_from_slice(formats.as_bytes());
        header.extend_from_slice(stem.as_bytes());
        RunState {
            fingerprint,
            frame,
            formats,
            stem,
            snapshot: snapshot.with_header(header),
        }
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        self.snapshot.to_bytes()
    }

    pub fn from_bytes(b: &[u8]) -> std::result::Result<RunState, String> {
        let snapshot = Snapshot::from_bytes(b).map_err(|e| e.to_string())?;
        let h = snapshot.header();
        let u64_at = |at: usize| Some(u64::from_le_bytes(h.get(at..at + 8)?.try_into().ok()?));
        let fields = || -> Option<(u64, u64, String, String)> {
            let len = u32::from_le_bytes(h.get(16..20)?.try_into().ok()?) as usize;
            let formats = String::from_utf8(h.get(20..20usize.checked_add(len)?)?.to_vec()).ok()?;
            let stem = String::from_utf8(h.get(20 + len..)?.to_vec()).ok()?;
            Some((u64_at(0)?, u64_at(8)?, formats, stem))
        };
        let (fingerprint, frame, formats, stem) =
            fields().ok_or("damaged or not a drapery state file (no run header)")?;
        Ok(RunState {
            fingerprint,
            frame,
            formats,
            stem,
            snapshot,
        })
    }

    /// Writes `DIR/state.bin` atomically.
    pub fn save(&self, dir: &Path) -> Result<()> {
        drapery::io::write_atomic(&dir.join(STATE_FILE), &self.to_bytes())?;
        Ok(())
    }

    /// Reads `DIR/state.bin`, or `None` when there is none.
    pub fn load(dir: &Path) -> Result<Option<RunState>> {
        let path = dir.join(STATE_FILE);
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(e).with_context(|| format!("{}: cannot read", path.display())),
        };
        RunState::from_bytes(&bytes)
            .map(Some)
            .map_err(|m| anyhow::anyhow!("{}: {m}; start over with --overwrite", path.display()))
    }
}

fn push_vecs(out: &mut Vec<u8>, v: &[Vec3]) {
    for p in v {
        for k in 0..3 {
            out.extend_from_slice(&p[k].to_le_bytes());
        }
    }
}

/// One frame of the history: little-endian f64 triples.
fn decode_frame(raw: &[u8]) -> Vec<Vec3> {
    let f: Vec<f64> = raw
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
        .collect();
    f.chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect()
}

/// The positions of every frame done, appended to `DIR/history.bin` frame after frame.
pub struct History {
    path: PathBuf,
    file: Option<std::fs::File>,
    /// Every frame so far, in memory, for the whole-run writers.
    pub frames: Vec<Vec<Vec3>>,
}

impl History {
    /// A new, empty history (truncates the file).
    pub fn create(dir: &Path) -> Result<History> {
        let path = dir.join(HISTORY_FILE);
        let file = std::fs::File::create(&path)
            .with_context(|| format!("{}: cannot create", path.display()))?;
        Ok(History {
            path,
            file: Some(file),
            frames: Vec::new(),
        })
    }

    /// No file: nothing needs the history.
    pub fn none() -> History {
        History {
            path: PathBuf::new(),
            file: None,
            frames: Vec::new(),
        }
    }

    /// Reads the first `frames` frames of `n` particles and cuts the file there.
    pub fn resume(dir: &Path, frames: usize, n: usize) -> Result<History> {
        let path = dir.join(HISTORY_FILE);
        let what = || format!("{}: cannot resume the frame history", path.display());
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(&path)
            .with_context(what)?;
        let frame_bytes = n * 24;
        let need = (frames * frame_bytes) as u64;
        let len = file.metadata().with_context(what)?.len();
        if len < need {
            bail!(
                "{}: holds {} frames, the state needs {frames}; start over with --overwrite",
                path.display(),
                len / frame_bytes.max(1) as u64
            );
        }
        let mut raw = vec![0u8; need as usize];
        file.read_exact(&mut raw).with_context(what)?;
        file.set_len(need).with_context(what)?;
        file.seek(SeekFrom::End(0)).with_context(what)?;
        let frames = raw
            .chunks_exact(frame_bytes.max(1))
            .map(decode_frame)
            .collect();
        Ok(History {
            path,
            file: Some(file),
            frames,
        })
    }

    /// Appends one frame (to memory and, synced, to the file).
    pub fn push(&mut self, x: &[Vec3]) -> Result<()> {
        let Some(file) = self.file.as_mut() else {
            return Ok(());
        };
        let mut raw = Vec::with_capacity(24 * x.len());
        push_vecs(&mut raw, x);
        file.write_all(&raw)
            .and_then(|()| file.sync_data())
            .with_context(|| format!("{}: cannot write", self.path.display()))?;
        self.frames.push(x.to_vec());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sim_snapshot() -> Snapshot {
        let mut sim = drapery::presets::Preset::Hang.simulation(3, 1e-3).unwrap();
        sim.step(1.0 / 60.0).unwrap();
        sim.snapshot()
    }

    #[test]
    fn state_round_trips_and_names_damage() {
        let s = RunState::new(
            0x1234_5678_9abc_def0,
            7,
            "obj,glb".into(),
            "hang ✓".into(),
            sim_snapshot(),
        );
        let b = s.to_bytes();
        assert_eq!(RunState::from_bytes(&b).unwrap(), s);
        let mut bad = b.clone();
        let mid = b.len() / 2;
        bad[mid] ^= 0x40;
        let e = RunState::from_bytes(&bad).unwrap_err();
        assert!(e.contains("damaged"), "{e}");
        // A snapshot without the run header (another front end's) is not a run state.
        let foreign = sim_snapshot().with_header(b"frame 7".to_vec()).to_bytes();
        let e = RunState::from_bytes(&foreign).unwrap_err();
        assert!(e.contains("no run header"), "{e}");
    }
}
