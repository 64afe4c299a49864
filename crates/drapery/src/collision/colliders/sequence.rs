//! `shape = "mesh"` with `sequence = "body/walk_####.obj"`: an animated triangle surface from
//! numbered OBJ files (`####` is the frame number, zero-padded to as many digits as there are
//! `#`), read from `sequence_start` (default 1) on until the next number is missing, played at
//! `sequence_frame_rate` files per second from `t = 0`. Every file has the vertex count and
//! faces of the first. Between two files each vertex moves on a straight line; before the first
//! the mesh holds the first shape, after the last the last. The surface velocity at a contact
//! is that of the moving triangle (its vertices' velocities, blended by the contact's
//! barycentric weights), so friction drags cloth along with a moving body.
//!
//! Like a static mesh it has no inside (see [`super::mesh`]); CCD against its triangles, whose
//! vertices move linearly within a step, keeps cloth from passing through.

use super::bvh::Bvh;
use super::mesh::{hash_mesh, read_triangles, surface_local, valid_triangles};
use super::{Keys, Kind, Local};
use crate::collision::broad_phase::Aabb;
use crate::collision::tessellate::TessellateOptions;
use crate::error::{Error, Result};
use crate::fingerprint::Fnv;
use crate::math::Vec3;

/// An animated triangle mesh (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshSequence {
    /// Vertex positions of every file, in order.
    frames: Vec<Vec<Vec3>>,
    triangles: Vec<[u32; 3]>,
    /// Files per second.
    rate: f64,
    pivot: Vec3,
    bvh: Bvh,
    /// Node boxes per interval `k` (valid for every blend of files `k` and `k + 1`), and one
    /// more for the last file alone.
    boxes: Vec<Vec<Aabb>>,
    /// Largest vertex speed per interval, m/s.
    speeds: Vec<f64>,
    /// Watertight ([`super::interior::is_closed`]): the surface has an inside.
    closed: bool,
}

impl MeshSequence {
    /// A sequence of vertex positions (at least one frame, each as long as the first) with the
    /// given triangles, played at `rate` frames per second from `t = 0`.
    pub fn new(frames: Vec<Vec<Vec3>>, triangles: Vec<[u32; 3]>, rate: f64) -> MeshSequence {
        let n = frames.first().map_or(0, Vec::len);
        let triangles = valid_triangles(n, triangles);
        let first = frames.first().cloned().unwrap_or_default();
        let bvh = Bvh::build(&first, &triangles);
        let mut boxes = Vec::with_capacity(frames.len());
        let mut speeds = Vec::with_capacity(frames.len());
        for k in 0..frames.len() {
            let next = frames.get(k + 1).unwrap_or(&frames[k]);
            boxes.push(bvh.boxes(&triangles, &[&frames[k], next]));
            let speed = frames[k]
                .iter()
                .zip(next)
                .map(|(a, b)| (*b - *a).length() * rate)
                .fold(0.0, f64::max);
            speeds.push(speed);
        }
        let closed = super::interior::is_closed(&triangles);
        MeshSequence {
            frames,
            triangles,
            rate,
            pivot: Vec3::ZERO,
            bvh,
            boxes,
            speeds,
            closed,
        }
    }

    /// The same sequence turning about `pivot` instead of the origin.
    pub fn with_pivot(mut self, pivot: Vec3) -> MeshSequence {
        self.pivot = pivot;
        self
    }

    /// The files' vertex positions.
    pub fn frames(&self) -> &[Vec<Vec3>] {
        &self.frames
    }

    /// Triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Files per second.
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// The interval `k` holding time `t` and the blend `s ∈ [0, 1]` between files `k` and `k + 1`
    /// (`s = 0` past either end).
    fn locate(&self, t: f64) -> (usize, f64) {
        let last = self.frames.len().saturating_sub(1);
        let f = t * self.rate;
        if !(f > 0.0) {
            return (0, 0.0);
        }
        if f >= last as f64 {
            return (last, 0.0);
        }
        let k = (f.floor() as usize).min(last.saturating_sub(1));
        (k, f - k as f64)
    }

    fn vertex(&self, k: usize, s: f64, i: usize) -> Vec3 {
        let a = self.frames[k][i];
        if s == 0.0 {
            return a;
        }
        a + s * (self.frames[k + 1][i] - a)
    }

    /// The velocity of vertex `i` in interval `k` (zero past the last file; `before`: zero
    /// before `t = 0`).
    fn vertex_velocity(&self, k: usize, before: bool, i: usize) -> Vec3 {
        if before {
            return Vec3::ZERO;
        }
        match self.frames.get(k + 1) {
            Some(b) => (b[i] - self.frames[k][i]) * self.rate,
            None => Vec3::ZERO,
        }
    }

    /// Vertex positions at time `t`.
    pub fn vertices_at(&self, t: f64) -> Vec<Vec3> {
        let (k, s) = self.locate(t);
        (0..self.frames[k].len())
            .map(|i| self.vertex(k, s, i))
            .collect()
    }

    fn corners(&self, k: usize, s: f64, ti: u32) -> [Vec3; 3] {
        self.triangles[ti as usize].map(|i| self.vertex(k, s, i as usize))
    }

    /// The closest triangle at `t`, its result and `(k, s)`.
    fn closest_at(
        &self,
        p: Vec3,
        t: f64,
    ) -> Option<(u32, crate::collision::distance::PointTriangle, usize, f64)> {
        let (k, s) = self.locate(t);
        let (ti, r) = self
            .bvh
            .closest(&self.boxes[k], p, |ti| self.corners(k, s, ti))?;
        Some((ti, r, k, s))
    }
}

/// `pattern` with its run of `#` replaced by `number`, zero-padded to the run's length.
pub fn numbered(pattern: &str, number: u64) -> Option<String> {
    let start = pattern.find('#')?;
    let len = pattern[start..].chars().take_while(|&c| c == '#').count();
    Some(format!(
        "{}{:0len$}{}",
        &pattern[..start],
        number,
        &pattern[start + len..]
    ))
}

impl Kind for MeshSequence {
    const NAME: &'static str = "mesh";
    const KEYS: &'static [&'static str] = &[
        "mesh",
        "center",
        "sequence",
        "sequence_start",
        "sequence_frame_rate",
    ];

    fn parse(k: &Keys) -> Result<MeshSequence> {
        let pivot = k.opt_vec3("center")?.unwrap_or(Vec3::ZERO);
        let field = k.path("sequence");
        let pattern = k.string("sequence")?;
        if !pattern.contains('#') {
            return Err(k.error(
                "sequence",
                format!(
                    "'{pattern}' has no '#' for the frame number (e.g. \"body/walk_####.obj\")"
                ),
            ));
        }
        let start = if k.has("sequence_start") {
            let s = k.number("sequence_start")?;
            if !(s >= 0.0 && s.fract() == 0.0 && s < 1e12) {
                return Err(k.error(
                    "sequence_start",
                    format!("must be a whole number ≥ 0, got {s}"),
                ));
            }
            s as u64
        } else {
            1
        };
        let rate = k.positive("sequence_frame_rate")?;
        let full = k.file("sequence")?;
        let (dir, name) = (
            full.parent()
                .map(std::path::Path::to_path_buf)
                .unwrap_or_default(),
            full.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default(),
        );
        if !name.contains('#') {
            return Err(k.error(
                "sequence",
                format!("'{pattern}': the '#' of the frame number must be in the file name"),
            ));
        }
        let file = |i: u64| -> Result<std::path::PathBuf> {
            numbered(&name, start + i)
                .map(|n| dir.join(n))
                .ok_or_else(|| Error::field(&field, "no '#'"))
        };
        let first = file(0)?;
        if !first.exists() {
            return Err(Error::field(
                &field,
                format!(
                    "the first file of the sequence, '{}', does not exist",
                    first.display()
                ),
            ));
        }
        let (v0, t0) = read_triangles(&first, &field)?;
        let mut frames = vec![v0];
        for i in 1.. {
            let f = file(i)?;
            if !f.exists() {
                break;
            }
            let (v, t) = read_triangles(&f, &field)?;
            if v.len() != frames[0].len() || t != t0 {
                return Err(Error::field(
                    &field,
                    format!(
                        "'{}' has {} vertices and {} triangles, but the first file '{}' has {} and {}: every file of a sequence needs the same vertices and faces",
                        f.display(),
                        v.len(),
                        t.len(),
                        first.display(),
                        frames[0].len(),
                        t0.len()
                    ),
                ));
            }
            frames.push(v);
        }
        Ok(MeshSequence::new(frames, t0, rate).with_pivot(pivot))
    }

    fn center(&self) -> Vec3 {
        self.pivot
    }

    fn closest(&self, p: Vec3, t: f64) -> Local {
        match self.closest_at(p, t) {
            None => Local::nowhere(p),
            Some((ti, r, k, s)) => {
                let tri = self.corners(k, s, ti);
                let [a, b, c] = self.triangles[ti as usize]
                    .map(|i| self.vertex_velocity(k, t < 0.0, i as usize));
                let v = a * r.bary[0] + b * r.bary[1] + c * r.bary[2];
                Local {
                    velocity: Some(v),
                    ..surface_local(p, tri, ti, r)
                }
            }
        }
    }

    fn tessellate(&self, t: f64, _o: &TessellateOptions) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        (self.vertices_at(t), self.triangles.clone())
    }

    fn solid(&self) -> bool {
        false
    }

    fn closed(&self) -> bool {
        self.closed
    }

    fn surface(&self, t: f64) -> Option<(Vec<Vec3>, &[[u32; 3]])> {
        Some((self.vertices_at(t), &self.triangles))
    }

    /// The closest point at `t_from`, moved with its triangle (same barycentric weights, same
    /// offset from the surface) to `t_to`.
    fn carry(&self, p: Vec3, t_from: f64, t_to: f64) -> Vec3 {
        let Some((ti, r, _, _)) = self.closest_at(p, t_from) else {
            return p;
        };
        let (k, s) = self.locate(t_to);
        let [a, b, c] = self.corners(k, s, ti);
        a * r.bary[0] + b * r.bary[1] + c * r.bary[2] + (p - r.q)
    }

    fn speed_bound(&self, t0: f64, t1: f64) -> f64 {
        if t0.max(t1) < 0.0 {
            return 0.0;
        }
        let (k0, _) = self.locate(t0.min(t1));
        let (k1, _) = self.locate(t0.max(t1));
        self.speeds[k0..=k1].iter().copied().fold(0.0, f64::max)
    }

    fn deforms(&self) -> bool {
        true
    }

    fn hash(&self, h: &mut Fnv) {
        h.bytes(b"mesh sequence");
        super::hash_vec(h, self.pivot);
        h.u64(self.rate.to_bits());
        h.u64(self.frames.len() as u64);
        for f in &self.frames {
            hash_mesh(h, f, &self.triangles);
        }
    }

    fn describe(&self) -> String {
        format!(
            "mesh sequence of {} files at {} per second, {} vertices, {} triangles{} (turns about {})",
            self.frames.len(),
            self.rate,
            self.frames.first().map_or(0, Vec::len),
            self.triangles.len(),
            if self.closed { ", closed" } else { "" },
            super::v3(self.pivot)
        )
    }
}
