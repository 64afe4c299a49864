//! Binary glTF 2.0 (`.glb`) animations that any glTF viewer plays as is.
//!
//! Layout written by [`write_glb`] / [`write_glb_with`]:
//!
//! - one node and one mesh per cloth, named after the cloth. Its base `POSITION` is frame 0;
//!   frame k ≥ 1 is morph target k-1, holding `frame_k - frame_0` (so there are `frames - 1`
//!   targets, named `frame_00001`, … in `mesh.extras.targetNames`, which Blender uses for its
//!   shape keys);
//! - triangles (quads split along `a–c`) in one `TRIANGLES` primitive with `u32` indices; line
//!   elements, when a cloth has any, in a second `LINES` primitive sharing the same vertices and
//!   targets; a cloth with neither is written as `POINTS`;
//! - one animation, `drapery`, with one channel per cloth on `weights`, `STEP` interpolation,
//!   one key per frame at `k / frame_rate` seconds; the key of frame k sets weight k-1 to 1 and
//!   every other weight to 0 (frame 0: all 0). All channels share the time and weight accessors;
//! - no normals: glTF viewers must then compute flat normals from the morphed positions
//!   (three.js and Blender do), which is correct for every frame; materials are double sided;
//! - colliders ([`MovingMesh`], passed to [`write_glb_scene`]) get a grey material: a fixed one
//!   is a plain node; a rigidly moving one is a node whose mesh is in the node's own frame, with
//!   `translation` and `rotation` channels sampled at every frame time, `LINEAR` interpolation
//!   (the node's own translation and rotation are those of frame 0); a deforming one has morph
//!   targets and a `weights` channel exactly like a cloth.
//!
//! Positions are f32 (what glTF allows); every `POSITION` accessor carries exact min/max.

use crate::collision::colliders::Collider;
use crate::collision::tessellate::{TessellateOptions, tessellate};
use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::model::ClothInfo;
use glam::DQuat;
use serde_json::{Value, json};
use std::path::Path;

/// A mesh that does not move (a collider), written next to the cloths.
#[derive(Clone, Copy, Debug)]
pub struct StaticMesh<'a> {
    /// Node and mesh name.
    pub name: &'a str,
    /// Vertex positions, m.
    pub positions: &'a [Vec3],
    /// Triangles, counter-clockwise seen from the outside.
    pub triangles: &'a [[u32; 3]],
}

/// How a [`MovingMesh`] moves over the frames of an output.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshMotion {
    /// It does not move: `positions` are its world positions in every frame.
    Fixed,
    /// It moves rigidly: `positions` are in its own frame, and in frame `k` a vertex `p` is at
    /// `R p + t` with `(R, t)` the k-th entry (one entry per frame).
    Rigid(Vec<(DQuat, Vec3)>),
    /// Its vertices move on their own: the world positions of every frame (one entry per frame,
    /// the first equal to `positions`).
    Deforming(Vec<Vec<Vec3>>),
}

/// A mesh written next to the cloths (a collider), fixed or moving.
#[derive(Clone, Debug, PartialEq)]
pub struct MovingMesh {
    /// Node, mesh (glTF) or prim (USD) name.
    pub name: String,
    /// Vertex positions, m (world positions, or the mesh's own frame for [`MeshMotion::Rigid`]).
    pub positions: Vec<Vec3>,
    /// Triangles, counter-clockwise seen from the outside.
    pub triangles: Vec<[u32; 3]>,
    /// How it moves.
    pub motion: MeshMotion,
}

/// True when the collider's shape changes with time (its vertices move in its own frame), so
/// that outputs must hold its vertices at every frame rather than a rigid transform.
fn deforms(c: &Collider) -> bool {
    c.shape.deforms()
}

impl MovingMesh {
    /// The collider tessellated for the frames at `times` (s): [`MeshMotion::Fixed`] (its
    /// tessellation at `times[0]`) when its pose is the same at every time and its shape does
    /// not deform; [`MeshMotion::Rigid`] (the shape's own tessellation, and per time the
    /// rotation `R` and translation `c + T - R c` of its motion's pose `(R, T)` about its center
    /// `c`) when it moves rigidly; [`MeshMotion::Deforming`] (its tessellation at every time)
    /// when its shape deforms. In every case [`MovingMesh::frame`] `k` is
    /// [`tessellate`]`(collider, times[k], options)` up to rounding.
    pub fn from_collider(
        name: impl Into<String>,
        collider: &Collider,
        times: &[f64],
        options: &TessellateOptions,
    ) -> MovingMesh {
        let name = name.into();
        let t0 = times.first().copied().unwrap_or(0.0);
        if deforms(collider) {
            let frames: Vec<Vec<Vec3>> = times
                .iter()
                .map(|&t| tessellate(collider, t, options).0)
                .collect();
            let (positions, triangles) = tessellate(collider, t0, options);
            return MovingMesh {
                name,
                positions,
                triangles,
                motion: MeshMotion::Deforming(frames),
            };
        }
        let first = collider.motion.pose(t0);
        if times.iter().all(|&t| collider.motion.pose(t) == first) {
            let (positions, triangles) = tessellate(collider, t0, options);
            return MovingMesh {
                name,
                positions,
                triangles,
                motion: MeshMotion::Fixed,
            };
        }
        let c = collider.center();
        let poses = times
            .iter()
            .map(|&t| {
                let (r, tr) = collider.motion.pose(t);
                (r, c + tr - r * c)
            })
            .collect();
        let (positions, triangles) = collider.shape.tessellate(t0, options);
        MovingMesh {
            name,
            positions,
            triangles,
            motion: MeshMotion::Rigid(poses),
        }
    }

    /// The world positions in frame `k` (the last frame's after the last; `positions` when fixed).
    pub fn frame(&self, k: usize) -> Vec<Vec3> {
        match &self.motion {
            MeshMotion::Fixed => self.positions.clone(),
            MeshMotion::Rigid(p) => match p.get(k).or(p.last()) {
                Some(&(r, t)) => self.positions.iter().map(|&x| r * x + t).collect(),
                None => self.positions.clone(),
            },
            MeshMotion::Deforming(f) => f.get(k).or(f.last()).unwrap_or(&self.positions).clone(),
        }
    }

    /// Checks what the writers need: a non-empty mesh, triangle indices in range, finite
    /// values, and for a moving mesh one entry per frame of `frames` frames.
    pub(crate) fn check(&self, what: &str, frames: usize) -> Result<()> {
        let bad = |m: &str| Err(Error::Invalid(format!("{what}: mesh '{}' {m}", self.name)));
        let n = self.positions.len();
        let finite = |p: &[Vec3]| p.iter().all(|v| v.as_vec3().is_finite());
        if n == 0 || self.triangles.is_empty() {
            return bad("is empty");
        }
        if self.triangles.iter().flatten().any(|&v| v as usize >= n) {
            return bad("has a triangle index out of range");
        }
        if !finite(&self.positions) {
            return bad("has a non-finite vertex");
        }
        match &self.motion {
            MeshMotion::Fixed => {}
            MeshMotion::Rigid(p) => {
                if p.len() != frames {
                    return bad(&format!("has {} poses for {frames} frames", p.len()));
                }
                if !p.iter().all(|(r, t)| {
                    r.as_quat().is_finite() && t.as_vec3().is_finite() && r.is_normalized()
                }) {
                    return bad("has a non-finite or non-unit pose");
                }
            }
            MeshMotion::Deforming(f) => {
                if f.len() != frames {
                    return bad(&format!(
                        "has {} vertex frames for {frames} frames",
                        f.len()
                    ));
                }
                if !f.iter().all(|x| x.len() == n && finite(x)) {
                    return bad("has a vertex frame of another size or with a non-finite vertex");
                }
            }
        }
        Ok(())
    }
}

/// The rotations as glTF quaternions `[x, y, z, w]` in f32, each on the side (`q` or `-q`, the
/// same rotation) nearest to the one before, so that interpolation takes the short way.
fn gltf_rotations(poses: &[(DQuat, Vec3)]) -> Vec<[f32; 4]> {
    let mut prev: Option<DQuat> = None;
    poses
        .iter()
        .map(|&(r, _)| {
            let q = match prev {
                Some(p) if p.dot(r) < 0.0 => -r,
                _ => r,
            };
            prev = Some(q);
            q.as_quat().to_array()
        })
        .collect()
}

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({
            "buffer": 0,
            "byteOffset": self.bin.len(),
            "byteLength": bytes.len(),
        });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    fn accessor(&mut self, a: Value) -> usize {
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn vec3(&mut self, data: &[[f32; 3]]) -> usize {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        let mut bytes = Vec::with_capacity(data.len() * 12);
        for p in data {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
                bytes.extend_from_slice(&p[k].to_le_bytes());
            }
        }
        // -0.0 and 0.0 compare equal; write +0 so the JSON bound is unambiguous.
        let clean = |v: [f32; 3]| v.map(|x| if x == 0.0 { 0.0 } else { x as f64 });
        let view = self.view(&bytes, Some(ARRAY_BUFFER));
        self.accessor(json!({
            "bufferView": view,
            "componentType": FLOAT,
            "count": data.len(),
            "type": "VEC3",
            "min": clean(lo),
            "max": clean(hi),
        }))
    }

    fn indices(&mut self, idx: &[u32]) -> usize {
        let bytes: Vec<u8> = idx.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(ELEMENT_ARRAY_BUFFER));
        self.accessor(json!({
            "bufferView": view,
            "componentType": UNSIGNED_INT,
            "count": idx.len(),
            "type": "SCALAR",
        }))
    }

    fn scalars(&mut self, v: &[f32], bounds: bool) -> usize {
        self.floats(v, 1, bounds)
    }

    /// Animation data: `v` holds `v.len() / ncomp` elements of `ncomp` (1, 3 or 4) floats, in a
    /// buffer view without target; `bounds` (scalars only) adds min/max.
    fn floats(&mut self, v: &[f32], ncomp: usize, bounds: bool) -> usize {
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, None);
        let kind = match ncomp {
            1 => "SCALAR",
            3 => "VEC3",
            _ => "VEC4",
        };
        let mut a = json!({
            "bufferView": view,
            "componentType": FLOAT,
            "count": v.len() / ncomp,
            "type": kind,
        });
        if bounds {
            let lo = v.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = v.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            a["min"] = json!([lo as f64]);
            a["max"] = json!([hi as f64]);
        }
        self.accessor(a)
    }
}

fn f32s(p: &[Vec3]) -> Vec<[f32; 3]> {
    p.iter().map(|v| v.as_vec3().to_array()).collect()
}

/// Writes the cloth animation as a `.glb` file (see the module documentation).
pub fn write_glb(
    path: &Path,
    cloths: &[ClothInfo],
    frames: &[Vec<Vec3>],
    frame_rate: f64,
) -> Result<()> {
    write_glb_with(path, cloths, frames, frame_rate, &[])
}

/// [`write_glb`] plus static meshes (colliders) written as unanimated nodes.
pub fn write_glb_with(
    path: &Path,
    cloths: &[ClothInfo],
    frames: &[Vec<Vec3>],
    frame_rate: f64,
    extra: &[StaticMesh<'_>],
) -> Result<()> {
    let meshes: Vec<MovingMesh> = extra
        .iter()
        .map(|m| MovingMesh {
            name: m.name.to_string(),
            positions: m.positions.to_vec(),
            triangles: m.triangles.to_vec(),
            motion: MeshMotion::Fixed,
        })
        .collect();
    write_glb_scene(path, cloths, frames, frame_rate, &meshes)
}

/// [`write_glb`] plus colliders, fixed or moving (see the module documentation).
pub fn write_glb_scene(
    path: &Path,
    cloths: &[ClothInfo],
    frames: &[Vec<Vec3>],
    frame_rate: f64,
    colliders: &[MovingMesh],
) -> Result<()> {
    let bytes = glb_bytes(
        &path.display().to_string(),
        cloths,
        frames,
        frame_rate,
        colliders,
    )?;
    super::write_atomic(path, &bytes)
}

/// Morph targets `frame_k - frame_0` (k ≥ 1) of one mesh whose frames are `frames`: the base
/// positions accessor and one `{ "POSITION": accessor }` per target.
fn morph_targets<'a>(
    b: &mut Builder,
    what: &str,
    name: &str,
    mut frames: impl Iterator<Item = &'a [Vec3]>,
) -> Result<(usize, Vec<Value>)> {
    let first = frames.next().unwrap_or(&[]);
    let pos = b.vec3(&f32s(first));
    let mut tgt = Vec::new();
    for f in frames {
        let d: Vec<[f32; 3]> = f
            .iter()
            .zip(first)
            .map(|(p, q)| (*p - *q).as_vec3().to_array())
            .collect();
        if d.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::Invalid(format!(
                "{what}: '{name}' moves too far for f32"
            )));
        }
        tgt.push(json!({ "POSITION": b.vec3(&d) }));
    }
    Ok((pos, tgt))
}

/// The `.glb` file contents [`write_glb_scene`] writes; `what` names the output in errors.
pub fn glb_bytes(
    what: &str,
    cloths: &[ClothInfo],
    frames: &[Vec<Vec3>],
    frame_rate: f64,
    colliders: &[MovingMesh],
) -> Result<Vec<u8>> {
    super::usd::check_frames(what, cloths, frames, frame_rate)?;
    for c in cloths {
        if c.mesh.positions.is_empty() {
            return Err(Error::Invalid(format!(
                "{what}: cloth '{}' has no vertices",
                c.name
            )));
        }
        let n = c.mesh.positions.len();
        if c.mesh.lines.iter().flatten().any(|&v| v as usize >= n) {
            return Err(Error::Invalid(format!(
                "{what}: cloth '{}' has a line index out of range",
                c.name
            )));
        }
    }
    let nf = frames.len();
    for m in colliders {
        m.check(what, nf)?;
    }
    let targets = nf - 1;
    let mut b = Builder::default();
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    // nodes animated by morph weights, and rigid nodes with their keys
    let mut weighted = Vec::new();
    let mut rigid: Vec<(usize, &[(DQuat, Vec3)])> = Vec::new();
    let target_names: Vec<String> = (1..nf).map(|k| format!("frame_{k:05}")).collect();
    let morph = |mut mesh: Value| {
        if targets > 0 {
            mesh["weights"] = json!(vec![0.0; targets]);
            mesh["extras"] = json!({ "targetNames": target_names });
        }
        mesh
    };
    for c in cloths {
        let r = c.range();
        let (pos, tgt) =
            morph_targets(&mut b, what, &c.name, frames.iter().map(|f| &f[r.clone()]))?;
        let tris: Vec<u32> = c.mesh.triangles().into_iter().flatten().collect();
        let lines: Vec<u32> = c.mesh.lines.iter().flatten().copied().collect();
        let mut prims = Vec::new();
        let mut prim = |mode: u32, idx: Option<usize>| {
            let mut p = json!({ "attributes": { "POSITION": pos }, "mode": mode, "material": 0 });
            if let Some(i) = idx {
                p["indices"] = json!(i);
            }
            if targets > 0 {
                p["targets"] = json!(tgt);
            }
            prims.push(p);
        };
        if !tris.is_empty() {
            let i = b.indices(&tris);
            prim(4, Some(i));
        }
        if !lines.is_empty() {
            let i = b.indices(&lines);
            prim(1, Some(i));
        }
        if tris.is_empty() && lines.is_empty() {
            prim(0, None);
        }
        meshes.push(morph(json!({ "name": c.name, "primitives": prims })));
        weighted.push(nodes.len());
        nodes.push(json!({ "name": c.name, "mesh": meshes.len() - 1 }));
    }
    for m in colliders {
        let (pos, tgt) = match &m.motion {
            MeshMotion::Deforming(f) => {
                morph_targets(&mut b, what, &m.name, f.iter().map(Vec::as_slice))?
            }
            _ => (b.vec3(&f32s(&m.positions)), Vec::new()),
        };
        let idx: Vec<u32> = m.triangles.iter().flatten().copied().collect();
        let i = b.indices(&idx);
        let mut prim =
            json!({ "attributes": { "POSITION": pos }, "indices": i, "mode": 4, "material": 1 });
        let mut mesh = json!({ "name": m.name, "primitives": [] });
        let mut node = json!({ "name": m.name });
        match &m.motion {
            MeshMotion::Fixed => {}
            MeshMotion::Deforming(_) => {
                if targets > 0 {
                    prim["targets"] = json!(tgt);
                    mesh = morph(mesh);
                    weighted.push(nodes.len());
                }
            }
            MeshMotion::Rigid(poses) => {
                node["translation"] = json!(poses[0].1.as_vec3().to_array());
                node["rotation"] = json!(gltf_rotations(&poses[..1])[0]);
                if targets > 0 {
                    rigid.push((nodes.len(), poses));
                }
            }
        }
        mesh["primitives"] = json!([prim]);
        meshes.push(mesh);
        node["mesh"] = json!(meshes.len() - 1);
        nodes.push(node);
    }
    let mut root = json!({
        "asset": { "version": "2.0", "generator": concat!("drapery ", env!("CARGO_PKG_VERSION")) },
        "scene": 0,
        "scenes": [{ "name": "drapery", "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [
            {
                "name": "cloth",
                "doubleSided": true,
                "pbrMetallicRoughness": {
                    "baseColorFactor": [0.85, 0.45, 0.25, 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 0.8
                }
            },
            {
                "name": "collider",
                "doubleSided": true,
                "pbrMetallicRoughness": {
                    "baseColorFactor": [0.6, 0.6, 0.6, 1.0],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 0.9
                }
            }
        ],
    });
    if targets > 0 {
        let times: Vec<f32> = (0..nf).map(|k| (k as f64 / frame_rate) as f32).collect();
        if times.windows(2).any(|w| !(w[1] > w[0])) || !times.iter().all(|t| t.is_finite()) {
            return Err(Error::Invalid(format!(
                "{what}: frame times at {frame_rate} frames/s are not distinct in f32"
            )));
        }
        let input = b.scalars(&times, true);
        let mut weights = vec![0.0f32; nf * targets];
        for k in 1..nf {
            weights[k * targets + (k - 1)] = 1.0;
        }
        let output = b.scalars(&weights, false);
        let mut samplers: Vec<Value> = Vec::new();
        let mut channels: Vec<Value> = Vec::new();
        let mut channel = |node: usize, path: &str, output: usize, interpolation: &str| {
            channels.push(
                json!({ "sampler": samplers.len(), "target": { "node": node, "path": path } }),
            );
            samplers
                .push(json!({ "input": input, "interpolation": interpolation, "output": output }));
        };
        for &n in &weighted {
            channel(n, "weights", output, "STEP");
        }
        for &(n, poses) in &rigid {
            let t: Vec<f32> = poses
                .iter()
                .flat_map(|(_, t)| t.as_vec3().to_array())
                .collect();
            let r: Vec<f32> = gltf_rotations(poses).into_iter().flatten().collect();
            let t = b.floats(&t, 3, false);
            let r = b.floats(&r, 4, false);
            channel(n, "translation", t, "LINEAR");
            channel(n, "rotation", r, "LINEAR");
        }
        root["animations"] =
            json!([{ "name": "drapery", "channels": channels, "samplers": samplers }]);
    }
    while !b.bin.len().is_multiple_of(4) {
        b.bin.push(0);
    }
    root["buffers"] = json!([{ "byteLength": b.bin.len() }]);
    root["bufferViews"] = Value::Array(b.views);
    root["accessors"] = Value::Array(b.accessors);
    let mut js = serde_json::to_vec(&root)
        .map_err(|e| Error::Invalid(format!("{what}: cannot encode glTF JSON: {e}")))?;
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let total = 12 + 8 + js.len() + 8 + b.bin.len();
    if total > u32::MAX as usize {
        return Err(Error::Invalid(format!(
            "{what}: the animation needs {total} bytes, more than a .glb file can hold (4 GiB); write fewer frames"
        )));
    }
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&js);
    out.extend_from_slice(&(b.bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b.bin);
    Ok(out)
}

/// One mesh of a `.glb` read back by [`read_glb`], evaluated at every animation key.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GlbMesh {
    /// Node name.
    pub name: String,
    /// Indices of the `TRIANGLES` primitive (empty when there is none).
    pub triangles: Vec<u32>,
    /// Positions at each key of the animation (base + Σ weight × target, then moved by the
    /// node's translation and rotation at that key), or once when the node is not animated.
    pub frames: Vec<Vec<[f32; 3]>>,
    /// The base `POSITION` of the mesh, in the node's frame.
    pub base: Vec<[f32; 3]>,
    /// The node's animated `translation` at each key (empty without such a channel).
    pub translations: Vec<[f32; 3]>,
    /// The node's animated `rotation` `[x, y, z, w]` at each key (empty without such a channel).
    pub rotations: Vec<[f32; 4]>,
    /// Interpolations of the node's channels (e.g. `STEP`), in channel order.
    pub interpolations: Vec<String>,
}

/// What [`read_glb`] understands of a `.glb` file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GlbScene {
    /// Key times of the first animation, s (empty without animation).
    pub times: Vec<f32>,
    /// Interpolation of every sampler (e.g. `STEP`).
    pub interpolations: Vec<String>,
    /// One entry per node with a mesh, in node order.
    pub meshes: Vec<GlbMesh>,
}

/// Reads a `.glb` file the way a viewer plays it: parses the container, the JSON and the
/// accessors, and evaluates each node's morph weights, translation and rotation at every key of
/// the first animation.
/// Handles what [`write_glb`] writes (float/uint accessors, one buffer), for tests.
pub fn read_glb(path: &Path) -> Result<GlbScene> {
    let data = std::fs::read(path).map_err(|e| Error::io(path.display(), e))?;
    parse_glb(&data).map_err(|m| Error::input(path.display(), m))
}

type R<T> = std::result::Result<T, String>;

fn u32_at(d: &[u8], at: usize) -> R<u32> {
    d.get(at..at + 4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .ok_or_else(|| "truncated file".to_string())
}

fn idx(v: &Value, key: &str) -> R<usize> {
    v.get(key)
        .and_then(Value::as_u64)
        .map(|x| x as usize)
        .ok_or_else(|| format!("missing or bad '{key}'"))
}

struct Doc<'a> {
    json: Value,
    bin: &'a [u8],
}

impl Doc<'_> {
    fn get(&self, list: &str, i: usize) -> R<&Value> {
        self.json
            .get(list)
            .and_then(|l| l.get(i))
            .ok_or_else(|| format!("{list}[{i}] does not exist"))
    }

    /// Reads accessor `i` as f64 components: (components per element, values).
    fn accessor(&self, i: usize) -> R<(usize, Vec<f64>)> {
        let a = self.get("accessors", i)?;
        let count = idx(a, "count")?;
        let ncomp = match a.get("type").and_then(Value::as_str) {
            Some("SCALAR") => 1,
            Some("VEC2") => 2,
            Some("VEC3") => 3,
            Some("VEC4") => 4,
            t => return Err(format!("accessor {i}: unsupported type {t:?}")),
        };
        let ct = idx(a, "componentType")? as u32;
        if ct != FLOAT && ct != UNSIGNED_INT {
            return Err(format!("accessor {i}: unsupported componentType {ct}"));
        }
        let v = self.get("bufferViews", idx(a, "bufferView")?)?;
        if idx(v, "buffer")? != 0 {
            return Err(format!("accessor {i}: only buffer 0 is read"));
        }
        let start = v.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
        let len = idx(v, "byteLength")?;
        let view = start
            .checked_add(len)
            .and_then(|end| self.bin.get(start..end))
            .ok_or_else(|| format!("accessor {i}: buffer view outside the BIN chunk"))?;
        let off = a.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
        let elem = 4 * ncomp;
        let stride = v
            .get("byteStride")
            .and_then(Value::as_u64)
            .map(|s| s as usize)
            .unwrap_or(elem);
        if count == 0 || stride < elem {
            return Err(format!("accessor {i}: empty or bad stride"));
        }
        let need = (count - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(off + elem))
            .ok_or_else(|| format!("accessor {i}: too large"))?;
        if need > view.len() {
            return Err(format!("accessor {i}: runs past its buffer view"));
        }
        let mut out = Vec::with_capacity(count * ncomp);
        for e in 0..count {
            for k in 0..ncomp {
                let at = off + e * stride + 4 * k;
                let b = [view[at], view[at + 1], view[at + 2], view[at + 3]];
                out.push(if ct == FLOAT {
                    f32::from_le_bytes(b) as f64
                } else {
                    u32::from_le_bytes(b) as f64
                });
            }
        }
        Ok((ncomp, out))
    }

    fn vec3s(&self, i: usize) -> R<Vec<[f32; 3]>> {
        let (n, v) = self.accessor(i)?;
        if n != 3 {
            return Err(format!("accessor {i} is not VEC3"));
        }
        Ok(v.chunks_exact(3)
            .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32])
            .collect())
    }
}

/// The channels of one node: key count, interpolations, and the outputs of its `weights`,
/// `translation` and `rotation` channels.
#[derive(Clone, Default)]
struct NodeAnim {
    keys: Option<usize>,
    interpolations: Vec<String>,
    values: [Option<Vec<f64>>; 3],
}

fn parse_glb(data: &[u8]) -> R<GlbScene> {
    if data.get(0..4) != Some(b"glTF") {
        return Err("not a binary glTF file (bad magic)".into());
    }
    if u32_at(data, 4)? != 2 {
        return Err("not glTF version 2".into());
    }
    if u32_at(data, 8)? as usize != data.len() {
        return Err("header length does not match the file size".into());
    }
    let jlen = u32_at(data, 12)? as usize;
    if data.get(16..20) != Some(b"JSON") {
        return Err("first chunk is not JSON".into());
    }
    let js = data.get(20..20 + jlen).ok_or("truncated JSON chunk")?;
    let json: Value = serde_json::from_slice(js).map_err(|e| format!("bad JSON chunk: {e}"))?;
    let bstart = 20 + jlen;
    let bin = if bstart < data.len() {
        let blen = u32_at(data, bstart)? as usize;
        if data.get(bstart + 4..bstart + 8) != Some(b"BIN\0") {
            return Err("second chunk is not BIN".into());
        }
        data.get(bstart + 8..bstart + 8 + blen)
            .ok_or("truncated BIN chunk")?
    } else {
        &[][..]
    };
    let doc = Doc { json, bin };
    let empty = Vec::new();
    let nodes = doc
        .json
        .get("nodes")
        .and_then(Value::as_array)
        .unwrap_or(&empty);
    let anim = doc
        .json
        .get("animations")
        .and_then(|a| a.get(0))
        .cloned()
        .unwrap_or(Value::Null);
    let mut scene = GlbScene::default();
    let mut anims: Vec<NodeAnim> = vec![NodeAnim::default(); nodes.len()];
    if let Some(channels) = anim.get("channels").and_then(Value::as_array) {
        let samplers = anim
            .get("samplers")
            .and_then(Value::as_array)
            .unwrap_or(&empty);
        let interpolation = |s: &Value| {
            s.get("interpolation")
                .and_then(Value::as_str)
                .unwrap_or("LINEAR")
                .to_string()
        };
        scene.interpolations = samplers.iter().map(interpolation).collect();
        for ch in channels {
            let t = ch.get("target").ok_or("channel without target")?;
            let path = t.get("path").and_then(Value::as_str).unwrap_or("");
            let (want, ncomp) = match path {
                "weights" => (0, 0),
                "translation" => (1, 3),
                "rotation" => (2, 4),
                _ => continue,
            };
            let node = idx(t, "node")?;
            let s = samplers
                .get(idx(ch, "sampler")?)
                .ok_or("channel refers to a missing sampler")?;
            let (_, times) = doc.accessor(idx(s, "input")?)?;
            let (n, out) = doc.accessor(idx(s, "output")?)?;
            if scene.times.is_empty() {
                scene.times = times.iter().map(|&t| t as f32).collect();
            }
            let a = anims
                .get_mut(node)
                .ok_or("channel targets a missing node")?;
            if a.keys.is_some_and(|k| k != times.len()) {
                return Err(format!("node {node}: channels with different key counts"));
            }
            a.keys = Some(times.len());
            a.interpolations.push(interpolation(s));
            if ncomp > 0 && (n != ncomp || out.len() != ncomp * times.len()) {
                return Err(format!(
                    "node {node}: {path} output does not match its keys"
                ));
            }
            a.values[want] = Some(out);
        }
    }
    for (ni, node) in nodes.iter().enumerate() {
        let Some(mi) = node.get("mesh").and_then(Value::as_u64) else {
            continue;
        };
        let mesh = doc.get("meshes", mi as usize)?;
        let prims = mesh
            .get("primitives")
            .and_then(Value::as_array)
            .ok_or("mesh without primitives")?;
        let p0 = prims.first().ok_or("mesh without primitives")?;
        let base = doc.vec3s(idx(&p0["attributes"], "POSITION")?)?;
        let mut targets = Vec::new();
        if let Some(ts) = p0.get("targets").and_then(Value::as_array) {
            for t in ts {
                let d = doc.vec3s(idx(t, "POSITION")?)?;
                if d.len() != base.len() {
                    return Err("morph target size differs from the base".into());
                }
                targets.push(d);
            }
        }
        let mut triangles = Vec::new();
        for p in prims {
            if p.get("mode").and_then(Value::as_u64).unwrap_or(4) == 4 {
                let (_, v) = doc.accessor(idx(p, "indices")?)?;
                triangles = v.iter().map(|&x| x as u32).collect();
            }
        }
        let a = &anims[ni];
        let keys = a.keys.unwrap_or(1);
        let nt = targets.len();
        if let Some(w) = &a.values[0]
            && w.len() != keys * nt
        {
            return Err(format!(
                "node {ni}: {} weights for {keys} keys × {nt} targets",
                w.len()
            ));
        }
        let fixed = |key: &str, n: usize, default: &[f64]| -> R<Vec<f64>> {
            match node.get(key) {
                None => Ok(default.to_vec()),
                Some(v) => v
                    .as_array()
                    .filter(|a| a.len() == n)
                    .and_then(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<_>>>())
                    .ok_or_else(|| format!("node {ni}: bad {key}")),
            }
        };
        let t0 = fixed("translation", 3, &[0.0; 3])?;
        let r0 = fixed("rotation", 4, &[0.0, 0.0, 0.0, 1.0])?;
        let at = |which: usize, n: usize, k: usize, default: &[f64]| -> Vec<f64> {
            match &a.values[which] {
                Some(v) => v[k * n..(k + 1) * n].to_vec(),
                None => default.to_vec(),
            }
        };
        let mut frames = Vec::with_capacity(keys);
        for k in 0..keys {
            let mut pos = base.clone();
            if let Some(w) = &a.values[0] {
                for (j, t) in targets.iter().enumerate() {
                    let wj = w[k * nt + j] as f32;
                    if wj != 0.0 {
                        for (p, d) in pos.iter_mut().zip(t) {
                            for c in 0..3 {
                                p[c] += wj * d[c];
                            }
                        }
                    }
                }
            }
            let t = at(1, 3, k, &t0);
            let r = at(2, 4, k, &r0);
            let t = Vec3::new(t[0], t[1], t[2]);
            let r = DQuat::from_xyzw(r[0], r[1], r[2], r[3]);
            if t != Vec3::ZERO || r != DQuat::IDENTITY {
                for p in pos.iter_mut() {
                    let q = r * Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64) + t;
                    *p = q.as_vec3().to_array();
                }
            }
            frames.push(pos);
        }
        let f32s =
            |v: &Option<Vec<f64>>| -> Vec<f32> { v.iter().flatten().map(|&x| x as f32).collect() };
        let translations = f32s(&a.values[1])
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        let rotations = f32s(&a.values[2])
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect();
        scene.meshes.push(GlbMesh {
            name: node
                .get("name")
                .and_then(Value::as_str)
                .unwrap_or("")
                .to_string(),
            triangles,
            frames,
            base,
            translations,
            rotations,
            interpolations: a.interpolations.clone(),
        });
    }
    Ok(scene)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::io::usd::tests::animated;

    fn close(a: [f32; 3], b: Vec3) -> bool {
        (0..3).all(|k| ((a[k] as f64) - b[k]).abs() <= 1e-6 * (1.0 + b[k].abs()))
    }

    #[test]
    fn animation_round_trips_positions_at_f32_precision() {
        let (cloths, frames) = animated();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.glb");
        write_glb(&path, &cloths, &frames, 25.0).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len() % 4, 0);
        let g = read_glb(&path).unwrap();
        assert_eq!(g.times, vec![0.0, 0.04, 0.08, 0.12, 0.16]);
        assert!(g.interpolations.iter().all(|i| i == "STEP"));
        assert_eq!(g.meshes.len(), 2);
        for (c, m) in cloths.iter().zip(&g.meshes) {
            assert_eq!(m.name, c.name);
            let tris: Vec<u32> = c.mesh.triangles().into_iter().flatten().collect();
            assert_eq!(m.triangles, tris);
            assert_eq!(m.frames.len(), frames.len());
            for (k, f) in m.frames.iter().enumerate() {
                for (a, b) in f.iter().zip(&frames[k][c.range()]) {
                    assert!(close(*a, *b), "frame {k}: {a:?} vs {b}");
                }
            }
        }
    }

    #[test]
    fn single_frame_and_static_meshes_have_no_animation() {
        let (cloths, frames) = animated();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("one.glb");
        let ground = [
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
        ];
        let extra = [StaticMesh {
            name: "ground",
            positions: &ground,
            triangles: &[[0, 2, 1]],
        }];
        write_glb_with(&path, &cloths, &frames[..1], 30.0, &extra).unwrap();
        let g = read_glb(&path).unwrap();
        assert!(g.times.is_empty());
        assert_eq!(g.meshes.len(), 3);
        assert_eq!(g.meshes[2].name, "ground");
        assert_eq!(g.meshes[2].triangles, vec![0, 2, 1]);
        assert_eq!(g.meshes[0].frames.len(), 1);
    }

    #[test]
    fn bad_inputs_and_corrupt_files_are_errors() {
        let (cloths, frames) = animated();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.glb");
        assert!(write_glb(&path, &cloths, &frames, f64::NAN).is_err());
        let bad = [StaticMesh {
            name: "g",
            positions: &[Vec3::ZERO],
            triangles: &[[0, 1, 2]],
        }];
        assert!(write_glb_with(&path, &cloths, &frames, 30.0, &bad).is_err());
        write_glb(&path, &cloths, &frames, 30.0).unwrap();
        let full = std::fs::read(&path).unwrap();
        for cut in [0, 4, 12, 20, 100, full.len() / 2, full.len() - 4] {
            std::fs::write(&path, &full[..cut]).unwrap();
            assert!(read_glb(&path).is_err(), "cut at {cut}");
        }
    }

    /// Writes `sample.glb` and `sample.usda` (a small animated grid, a line-element rope, a
    /// static ground and the colliders of [`moving_colliders`]: one moving rigidly, one fixed,
    /// one deforming) into `$DRAPERY_SAMPLE_DIR` when it is set, for
    /// `scripts/validate-outputs.sh`, into a temporary folder otherwise; and checks that both
    /// files read back to what was written: names, topology, key times and every position of
    /// every frame (to f32 precision: glTF stores f32, and frames k ≥ 1 as f32 differences from
    /// frame 0; USD prints the f32 values, which read back exactly).
    #[test]
    fn sample_outputs() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = std::env::var_os("DRAPERY_SAMPLE_DIR")
            .map(std::path::PathBuf::from)
            .unwrap_or_else(|| tmp.path().to_path_buf());
        std::fs::create_dir_all(&dir).unwrap();
        let (cloths, frames) = sample_animation();
        let ground = [
            Vec3::new(-2.0, -1.0, -2.0),
            Vec3::new(2.0, -1.0, -2.0),
            Vec3::new(2.0, -1.0, 2.0),
            Vec3::new(-2.0, -1.0, 2.0),
        ];
        let ground_triangles = [[0, 2, 1], [0, 3, 2]];
        let (_, _, mut extra) = moving_colliders(frames.len(), 24.0);
        extra.insert(
            0,
            MovingMesh {
                name: "ground".into(),
                positions: ground.to_vec(),
                triangles: ground_triangles.to_vec(),
                motion: MeshMotion::Fixed,
            },
        );
        write_glb_scene(&dir.join("sample.glb"), &cloths, &frames, 24.0, &extra).unwrap();
        crate::io::usd::write_usda_with(&dir.join("sample.usda"), &cloths, &frames, 24.0, &extra)
            .unwrap();

        let g = read_glb(&dir.join("sample.glb")).unwrap();
        let times: Vec<f32> = (0..frames.len())
            .map(|k| (k as f64 / 24.0) as f32)
            .collect();
        assert_eq!(g.times, times);
        for m in &g.meshes[..2] {
            assert_eq!(m.interpolations, ["STEP"]);
        }
        let names: Vec<&str> = g.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(
            names,
            ["sheet", "rope", "ground", "spinner", "post", "wobble"]
        );
        let sheet_triangles: Vec<u32> = cloths[0].mesh.triangles().into_iter().flatten().collect();
        assert_eq!(
            sheet_triangles.len(),
            3 * 2 * 5 * 4,
            "a 6×5 grid has 20 quads"
        );
        assert_eq!(g.meshes[0].triangles, sheet_triangles);
        assert!(
            g.meshes[1].triangles.is_empty(),
            "the rope has line elements only"
        );
        for (c, m) in cloths.iter().zip(&g.meshes) {
            assert_eq!(m.frames.len(), frames.len(), "{}", c.name);
            for (k, f) in m.frames.iter().enumerate() {
                assert_eq!(f.len(), c.mesh.positions.len());
                for (a, b) in f.iter().zip(&frames[k][c.range()]) {
                    assert!(close(*a, *b), "{} frame {k}: {a:?} vs {b}", c.name);
                }
            }
        }
        let static_ground: Vec<[f32; 3]> = ground.iter().map(|p| p.as_vec3().to_array()).collect();
        assert_eq!(g.meshes[2].frames, vec![static_ground]);
        assert_eq!(g.meshes[2].triangles, vec![0, 2, 1, 0, 3, 2]);

        let u = crate::io::usd::read_usda(&dir.join("sample.usda")).unwrap();
        assert_eq!(u.time_codes_per_second, 24.0);
        assert_eq!((u.start_time_code, u.end_time_code), (0.0, 11.0));
        let names: Vec<&str> = u.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(
            names,
            ["sheet", "rope", "ground", "spinner", "post", "wobble"]
        );
        assert_eq!(u.meshes[0].face_vertex_counts, vec![4; 20]);
        let quads: Vec<u32> = (cloths[0].mesh.faces.iter())
            .flat_map(|f| f.indices().to_vec())
            .collect();
        assert_eq!(u.meshes[0].face_vertex_indices, quads);
        assert!(u.meshes[1].face_vertex_counts.is_empty());
        for (c, m) in cloths.iter().zip(&u.meshes) {
            assert_eq!(m.samples.len(), frames.len());
            for (k, (t, pts)) in m.samples.iter().enumerate() {
                assert_eq!(*t, k as f64);
                let want: Vec<[f32; 3]> = frames[k][c.range()]
                    .iter()
                    .map(|p| p.as_vec3().to_array())
                    .collect();
                let got: Vec<[f32; 3]> = pts.iter().map(|p| p.as_vec3().to_array()).collect();
                assert_eq!(got, want, "{} frame {k}", c.name);
            }
        }
    }

    /// A box spinning and translating (`Motion::constant`), a fixed capsule, and the box's
    /// world tessellation at every frame as a deforming mesh, for `n` frames at `fps`: the
    /// colliders, the frame times and the meshes (`spinner`, `post`, `wobble`).
    pub(crate) fn moving_colliders(
        n: usize,
        fps: f64,
    ) -> (Vec<Collider>, Vec<f64>, Vec<MovingMesh>) {
        use crate::collision::colliders::{Motion, Shape};
        let spinner = Collider::moving(
            Shape::cuboid(
                Vec3::new(0.3, 0.5, -0.2),
                Vec3::new(0.2, 0.1, 0.3),
                DQuat::from_scaled_axis(Vec3::new(0.1, 0.2, 0.3)),
            ),
            Motion::constant(Vec3::new(0.5, -0.2, 1.0), Vec3::new(1.0, 8.0, -2.0)),
        );
        let post = Collider::fixed(Shape::capsule(
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.2),
            0.1,
        ));
        let times: Vec<f64> = (0..n).map(|k| k as f64 / fps).collect();
        let o = TessellateOptions::default();
        let wobble = MovingMesh {
            name: "wobble".into(),
            positions: tessellate(&spinner, 0.0, &o).0,
            triangles: tessellate(&spinner, 0.0, &o).1,
            motion: MeshMotion::Deforming(
                times
                    .iter()
                    .map(|&t| tessellate(&spinner, t, &o).0)
                    .collect(),
            ),
        };
        let meshes = vec![
            MovingMesh::from_collider("spinner", &spinner, &times, &o),
            MovingMesh::from_collider("post", &post, &times, &o),
            wobble,
        ];
        (vec![spinner, post], times, meshes)
    }

    /// `got` is `want` to f32 precision, for values made of terms up to `scale` in size.
    pub(crate) fn near_f32(got: Vec3, want: Vec3, scale: f64) -> bool {
        (got - want).abs().max_element() <= 8.0 * f32::EPSILON as f64 * (1.0 + scale)
    }

    #[test]
    fn moving_colliders_are_nodes_moved_by_their_channels_and_fixed_ones_have_none() {
        let (cloths, frames) = animated();
        let (colliders, times, meshes) = moving_colliders(frames.len(), 25.0);
        assert!(matches!(meshes[0].motion, MeshMotion::Rigid(_)));
        assert_eq!(meshes[1].motion, MeshMotion::Fixed);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("moving.glb");
        write_glb_scene(&path, &cloths, &frames, 25.0, &meshes).unwrap();
        let g = read_glb(&path).unwrap();
        let names: Vec<&str> = g.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["flag-1.v2", "9lives", "spinner", "post", "wobble"]);
        let want_times: Vec<f32> = times.iter().map(|&t| t as f32).collect();
        assert_eq!(g.times, want_times);
        let o = TessellateOptions::default();

        // the rigid collider: its node's translation and rotation at key k, applied to its
        // mesh, give the collider's tessellation at t_k
        let spin = &g.meshes[2];
        assert_eq!(spin.interpolations, ["LINEAR", "LINEAR"]);
        assert_eq!(
            (spin.translations.len(), spin.rotations.len()),
            (times.len(), times.len())
        );
        let (_, tris) = tessellate(&colliders[0], 0.0, &o);
        assert_eq!(
            spin.triangles,
            tris.iter().flatten().copied().collect::<Vec<_>>()
        );
        for (k, &t) in times.iter().enumerate() {
            let [x, y, z, w] = spin.rotations[k].map(|c| c as f64);
            let r = DQuat::from_xyzw(x, y, z, w);
            assert!((r.length() - 1.0).abs() < 1e-6);
            if k > 0 {
                let [a, b, c, d] = spin.rotations[k - 1].map(|c| c as f64);
                assert!(
                    r.dot(DQuat::from_xyzw(a, b, c, d)) > 0.0,
                    "key {k} flips sign"
                );
            }
            let tr = Vec3::from_array(spin.translations[k].map(|c| c as f64));
            let (want, _) = tessellate(&colliders[0], t, &o);
            assert_eq!(want.len(), spin.base.len());
            for (i, (b, w)) in spin.base.iter().zip(&want).enumerate() {
                let p = Vec3::from_array(b.map(|c| c as f64));
                let scale = p.length() + tr.length();
                assert!(
                    near_f32(r * p + tr, *w, scale),
                    "key {k} vertex {i}: {} vs {w}",
                    r * p + tr
                );
                let seen = Vec3::from_array(spin.frames[k][i].map(|c| c as f64));
                assert!(near_f32(seen, *w, scale), "viewer key {k} vertex {i}");
            }
            assert!(
                (k == 0) || spin.frames[k] != spin.frames[0],
                "key {k} did not move"
            );
        }

        // the fixed collider: a plain node, its world tessellation as is
        let post = &g.meshes[3];
        assert!(post.translations.is_empty() && post.rotations.is_empty());
        assert!(post.interpolations.is_empty());
        let (want, _) = tessellate(&colliders[1], 0.0, &o);
        assert_eq!(post.frames, vec![f32s(&want)]);

        // the deforming mesh: morph targets like a cloth
        let wobble = &g.meshes[4];
        assert_eq!(wobble.interpolations, ["STEP"]);
        for (k, &t) in times.iter().enumerate() {
            let (want, _) = tessellate(&colliders[0], t, &o);
            for (a, b) in wobble.frames[k].iter().zip(&want) {
                assert!(close(*a, *b), "wobble frame {k}: {a:?} vs {b}");
            }
        }

        // a moving mesh with a pose count other than the frame count is refused
        let mut short = meshes[0].clone();
        if let MeshMotion::Rigid(p) = &mut short.motion {
            p.pop();
        }
        let e = write_glb_scene(&path, &cloths, &frames, 25.0, &[short]).unwrap_err();
        assert!(
            e.to_string().contains("'spinner' has 4 poses for 5 frames"),
            "{e}"
        );
    }

    /// A 6×5 grid and a line-element rope falling and waving (deterministic fake motion).
    pub(crate) fn sample_animation() -> (Vec<ClothInfo>, Vec<Vec<Vec3>>) {
        use crate::mesh::Mesh;
        let sheet = Mesh::grid([1.0, 0.8], [6, 5], Vec3::new(0.0, 1.0, 0.0), Vec3::Z).unwrap();
        let rope = Mesh {
            positions: (0..4)
                .map(|i| Vec3::new(1.0, 1.5 - 0.2 * i as f64, 0.0))
                .collect(),
            faces: vec![],
            lines: vec![[0, 1], [1, 2], [2, 3]],
            face_uv: Vec::new(),
        };
        let n0 = sheet.positions.len();
        let mut base = sheet.positions.clone();
        base.extend_from_slice(&rope.positions);
        let frames = (0..12)
            .map(|k| {
                let t = k as f64 / 24.0;
                base.iter()
                    .map(|p| {
                        Vec3::new(
                            p.x,
                            p.y - 0.5 * 9.81 * t * t,
                            p.z + 0.1 * (6.0 * p.x + 10.0 * t).sin(),
                        )
                    })
                    .collect()
            })
            .collect();
        let cloths = vec![
            ClothInfo {
                material: Default::default(),
                name: "sheet".into(),
                offset: 0,
                mesh: sheet,
            },
            ClothInfo {
                material: Default::default(),
                name: "rope".into(),
                offset: n0,
                mesh: rope,
            },
        ];
        (cloths, frames)
    }
}
