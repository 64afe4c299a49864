//! The run state that makes `drapery run --resume` possible.
//!
//! After every frame's files are on disk, `DIR/state.bin` is rewritten atomically with what is
//! needed to continue bit for bit: the scene fingerprint, the output formats, the frame index,
//! the step count, the simulated time and every position and velocity as exact f64 bits.
//! When a whole-run format (glb, usd) is requested, the positions of every frame done are also
//! appended to `DIR/history.bin` (raw little-endian f64, `3 × particles` per frame) before the
//! state is written; the state tells how many frames of it are valid, so bytes appended by a
//! killed run after its last state are cut off on resume.
//!
//! `state.bin` layout (little endian): the magic `DRAPERY-STATE-2\n`, then u64 fingerprint,
//! u64 frame, u64 steps, u64 time bits, u32 length + UTF-8 format list (`obj,glb`), u32
//! length + UTF-8 whole-run file stem (`hang`), u64
//! particle count n, 3n f64 positions, 3n f64 velocities, 3n f64 warm-start velocity changes, and a u64 FNV-1a checksum of
//! everything before it.

use anyhow::{Context, Result, bail};
use drapery::Vec3;
use drapery::collision::colliders::Shape;
use drapery::collision::settings::Obstacle;
use drapery::scene::Scene;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

const MAGIC: &[u8] = b"DRAPERY-STATE-2\n";
/// The state file in a run folder.
pub const STATE_FILE: &str = "state.bin";
/// The frame history kept for whole-run formats.
pub const HISTORY_FILE: &str = "history.bin";

/// FNV-1a, 64 bits.
#[derive(Clone, Copy)]
pub struct Fnv(u64);

impl Fnv {
    pub fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    pub fn bytes(&mut self, b: &[u8]) -> &mut Fnv {
        for &x in b {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
        self
    }
    pub fn u64(&mut self, v: u64) -> &mut Fnv {
        self.bytes(&v.to_le_bytes())
    }
    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// The fingerprint of a scene: FNV-1a 64 over the drapery version, the scene file's bytes and
/// every cloth's mesh as loaded (name, positions to the bit, faces, line elements) and, when the
/// scene has collisions, the collision settings and every collider (mesh colliders' vertices
/// and triangles included), so editing the scene or any mesh it uses changes it.
pub fn fingerprint(scene: &Scene, scene_text: &[u8]) -> u64 {
    let mut h = Fnv::new();
    h.bytes(b"drapery ")
        .bytes(env!("CARGO_PKG_VERSION").as_bytes())
        .u64(scene_text.len() as u64)
        .bytes(scene_text);
    for c in &scene.cloths {
        h.u64(c.name.len() as u64).bytes(c.name.as_bytes());
        h.u64(c.mesh.positions.len() as u64);
        for p in &c.mesh.positions {
            for k in 0..3 {
                h.u64(p[k].to_bits());
            }
        }
        h.u64(c.mesh.faces.len() as u64);
        for f in &c.mesh.faces {
            h.u64(f.indices().len() as u64);
            for &i in f.indices() {
                h.u64(i as u64);
            }
        }
        h.u64(c.mesh.lines.len() as u64);
        for l in &c.mesh.lines {
            h.u64(l[0] as u64).u64(l[1] as u64);
        }
    }
    // Collisions (only when the scene has them, so older fingerprints stay valid): the
    // settings and every collider as loaded, mesh collider vertices and triangles included.
    if let Some(c) = &scene.collision {
        h.bytes(b"collision");
        for x in [c.thickness, c.friction, c.stiffness] {
            h.u64(x.to_bits());
        }
        h.u64(c.self_collision as u64);
        h.u64(scene.obstacles.len() as u64);
        for o in &scene.obstacles {
            hash_obstacle(&mut h, o);
        }
    }
    h.finish()
}

fn hash_obstacle(h: &mut Fnv, o: &Obstacle) {
    let vec = |h: &mut Fnv, v: Vec3| {
        for k in 0..3 {
            h.u64(v[k].to_bits());
        }
    };
    let c = &o.collider;
    h.u64(o.friction.to_bits());
    vec(h, c.motion.velocity);
    vec(h, c.motion.angular_velocity);
    match &c.shape {
        Shape::Plane { point, normal } => {
            h.bytes(b"plane");
            vec(h, *point);
            vec(h, *normal);
        }
        Shape::Sphere { center, radius } => {
            h.bytes(b"sphere");
            vec(h, *center);
            h.u64(radius.to_bits());
        }
        Shape::Capsule { a, b, radius } => {
            h.bytes(b"capsule");
            vec(h, *a);
            vec(h, *b);
            h.u64(radius.to_bits());
        }
        Shape::Box {
            center,
            half_extents,
            rotation,
        } => {
            h.bytes(b"box");
            vec(h, *center);
            vec(h, *half_extents);
            for q in rotation.to_array() {
                h.u64(q.to_bits());
            }
        }
        Shape::Mesh(m) => {
            h.bytes(b"mesh");
            vec(h, m.pivot());
            h.u64(m.vertices().len() as u64);
            for p in m.vertices() {
                vec(h, *p);
            }
            h.u64(m.triangles().len() as u64);
            for t in m.triangles() {
                for &i in t {
                    h.u64(i as u64);
                }
            }
        }
    }
}

/// What `state.bin` holds.
#[derive(Clone, Debug, PartialEq)]
pub struct RunState {
    pub fingerprint: u64,
    /// The last frame whose files are complete.
    pub frame: u64,
    pub steps: u64,
    pub time: f64,
    /// Output formats of the run, comma separated.
    pub formats: String,
    /// File stem of the whole-run outputs (`hang` for `hang.glb`).
    pub stem: String,
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    /// The solver's warm start (previous velocity change).
    pub warm_start: Vec<Vec3>,
}

fn push_vecs(out: &mut Vec<u8>, v: &[Vec3]) {
    for p in v {
        for k in 0..3 {
            out.extend_from_slice(&p[k].to_le_bytes());
        }
    }
}

impl RunState {
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(64 + 48 * self.x.len());
        out.extend_from_slice(MAGIC);
        for v in [
            self.fingerprint,
            self.frame,
            self.steps,
            self.time.to_bits(),
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for text in [&self.formats, &self.stem] {
            out.extend_from_slice(&(text.len() as u32).to_le_bytes());
            out.extend_from_slice(text.as_bytes());
        }
        out.extend_from_slice(&(self.x.len() as u64).to_le_bytes());
        push_vecs(&mut out, &self.x);
        push_vecs(&mut out, &self.v);
        push_vecs(&mut out, &self.warm_start);
        let sum = Fnv::new().bytes(&out).finish();
        out.extend_from_slice(&sum.to_le_bytes());
        out
    }

    pub fn from_bytes(b: &[u8]) -> std::result::Result<RunState, String> {
        let damaged = || "damaged or not a drapery state file".to_string();
        if b.len() < MAGIC.len() + 8 || !b.starts_with(MAGIC) {
            return Err(damaged());
        }
        let (body, sum) = b.split_at(b.len() - 8);
        if Fnv::new().bytes(body).finish().to_le_bytes() != sum {
            return Err(damaged());
        }
        let mut r = Reader {
            b: body,
            at: MAGIC.len(),
        };
        let fingerprint = r.u64().ok_or_else(damaged)?;
        let frame = r.u64().ok_or_else(damaged)?;
        let steps = r.u64().ok_or_else(damaged)?;
        let time = f64::from_bits(r.u64().ok_or_else(damaged)?);
        let formats = r.text().ok_or_else(damaged)?;
        let stem = r.text().ok_or_else(damaged)?;
        let n = r.u64().ok_or_else(damaged)? as usize;
        if n.checked_mul(72) != Some(body.len().saturating_sub(r.at)) {
            return Err(damaged());
        }
        let x = decode_vecs(r.take(24 * n).ok_or_else(damaged)?);
        let v = decode_vecs(r.take(24 * n).ok_or_else(damaged)?);
        let warm_start = decode_vecs(r.take(24 * n).ok_or_else(damaged)?);
        Ok(RunState {
            fingerprint,
            frame,
            steps,
            time,
            formats,
            stem,
            x,
            v,
            warm_start,
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

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.b.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(s)
    }
    fn text(&mut self) -> Option<String> {
        let len = self.take(4)?;
        let len = u32::from_le_bytes([len[0], len[1], len[2], len[3]]) as usize;
        String::from_utf8(self.take(len)?.to_vec()).ok()
    }
    fn u64(&mut self) -> Option<u64> {
        self.take(8)
            .map(|s| u64::from_le_bytes(s.try_into().unwrap_or([0; 8])))
    }
}

fn decode_vecs(raw: &[u8]) -> Vec<Vec3> {
    raw.chunks_exact(24)
        .map(|c| {
            let f = |i: usize| f64::from_le_bytes(c[8 * i..8 * i + 8].try_into().unwrap_or([0; 8]));
            Vec3::new(f(0), f(1), f(2))
        })
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
            .map(decode_vecs)
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

    #[test]
    fn fnv1a_matches_the_reference_values() {
        assert_eq!(Fnv::new().finish(), 0xcbf29ce484222325);
        assert_eq!(Fnv::new().bytes(b"a").finish(), 0xaf63dc4c8601ec8c);
        assert_eq!(Fnv::new().bytes(b"foobar").finish(), 0x85944171f73967e8);
    }

    #[test]
    fn state_round_trips_bits_and_detects_damage() {
        let s = RunState {
            fingerprint: 0x1234_5678_9abc_def0,
            frame: 7,
            steps: 14,
            time: 7.0 / 60.0,
            formats: "obj,glb".into(),
            stem: "hang".into(),
            x: vec![
                Vec3::new(0.1, -0.0, f64::MIN_POSITIVE),
                Vec3::new(1e300, 2.5, -3.0),
            ],
            v: vec![Vec3::new(1.0 / 3.0, 0.0, -1e-300), Vec3::ZERO],
            warm_start: vec![
                Vec3::new(0.25, -0.0, 1e-5),
                Vec3::new(f64::MIN_POSITIVE, 2.0, 3.0),
            ],
        };
        let b = s.to_bytes();
        let r = RunState::from_bytes(&b).unwrap();
        assert_eq!(r, s);
        assert_eq!(r.x[0].y.to_bits(), (-0.0f64).to_bits());
        for i in [0, MAGIC.len() + 3, b.len() / 2, b.len() - 1] {
            let mut bad = b.clone();
            bad[i] ^= 1;
            assert!(
                RunState::from_bytes(&bad).is_err(),
                "flip at {i} not detected"
            );
        }
        assert!(RunState::from_bytes(&b[..b.len() - 9]).is_err());
        assert!(RunState::from_bytes(b"").is_err());
    }
}
