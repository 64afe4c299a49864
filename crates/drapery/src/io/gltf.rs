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
//! - static meshes (colliders) passed to [`write_glb_with`] become plain nodes with a grey material.
//!
//! Positions are f32 (what glTF allows); every `POSITION` accessor carries exact min/max.

use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::model::ClothInfo;
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
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, None);
        let mut a = json!({
            "bufferView": view,
            "componentType": FLOAT,
            "count": v.len(),
            "type": "SCALAR",
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
    let bytes = glb_bytes(
        &path.display().to_string(),
        cloths,
        frames,
        frame_rate,
        extra,
    )?;
    super::write_atomic(path, &bytes)
}

/// The `.glb` file contents [`write_glb_with`] writes; `what` names the output in errors.
pub fn glb_bytes(
    what: &str,
    cloths: &[ClothInfo],
    frames: &[Vec<Vec3>],
    frame_rate: f64,
    extra: &[StaticMesh<'_>],
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
    for m in extra {
        let n = m.positions.len();
        if n == 0 || m.triangles.is_empty() {
            return Err(Error::Invalid(format!(
                "{what}: static mesh '{}' is empty",
                m.name
            )));
        }
        if m.triangles.iter().flatten().any(|&v| v as usize >= n) {
            return Err(Error::Invalid(format!(
                "{what}: static mesh '{}' has a triangle index out of range",
                m.name
            )));
        }
        if m.positions.iter().any(|p| !p.as_vec3().is_finite()) {
            return Err(Error::Invalid(format!(
                "{what}: static mesh '{}' has a non-finite vertex",
                m.name
            )));
        }
    }
    let nf = frames.len();
    let targets = nf - 1;
    let mut b = Builder::default();
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    let target_names: Vec<String> = (1..nf).map(|k| format!("frame_{k:05}")).collect();
    for c in cloths {
        let r = c.range();
        let base = f32s(&frames[0][r.clone()]);
        let pos = b.vec3(&base);
        let mut tgt = Vec::with_capacity(targets);
        for f in &frames[1..] {
            let d: Vec<[f32; 3]> = f[r.clone()]
                .iter()
                .zip(&frames[0][r.clone()])
                .map(|(p, q)| (*p - *q).as_vec3().to_array())
                .collect();
            if d.iter().flatten().any(|v| !v.is_finite()) {
                return Err(Error::Invalid(format!(
                    "{what}: cloth '{}' moves too far for f32",
                    c.name
                )));
            }
            tgt.push(json!({ "POSITION": b.vec3(&d) }));
        }
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
        let mut mesh = json!({ "name": c.name, "primitives": prims });
        if targets > 0 {
            mesh["weights"] = json!(vec![0.0; targets]);
            mesh["extras"] = json!({ "targetNames": target_names });
        }
        meshes.push(mesh);
        nodes.push(json!({ "name": c.name, "mesh": meshes.len() - 1 }));
    }
    let cloth_nodes = nodes.len();
    for m in extra {
        let pos = b.vec3(&f32s(m.positions));
        let idx: Vec<u32> = m.triangles.iter().flatten().copied().collect();
        let i = b.indices(&idx);
        meshes.push(json!({
            "name": m.name,
            "primitives": [{ "attributes": { "POSITION": pos }, "indices": i, "mode": 4, "material": 1 }],
        }));
        nodes.push(json!({ "name": m.name, "mesh": meshes.len() - 1 }));
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
        let samplers: Vec<Value> = (0..cloth_nodes)
            .map(|_| json!({ "input": input, "interpolation": "STEP", "output": output }))
            .collect();
        let channels: Vec<Value> = (0..cloth_nodes)
            .map(|n| json!({ "sampler": n, "target": { "node": n, "path": "weights" } }))
            .collect();
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
    /// Positions at each key of the animation (base + Σ weight × target), or the base alone
    /// when the mesh is not animated.
    pub frames: Vec<Vec<[f32; 3]>>,
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
/// accessors, and evaluates each node's morph weights at every key of the first animation.
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
    // node -> (times, weights per key)
    let mut node_keys: Vec<Option<(usize, Vec<f64>)>> = vec![None; nodes.len()];
    if let Some(channels) = anim.get("channels").and_then(Value::as_array) {
        let samplers = anim
            .get("samplers")
            .and_then(Value::as_array)
            .unwrap_or(&empty);
        for s in samplers {
            scene.interpolations.push(
                s.get("interpolation")
                    .and_then(Value::as_str)
                    .unwrap_or("LINEAR")
                    .to_string(),
            );
        }
        for ch in channels {
            let t = ch.get("target").ok_or("channel without target")?;
            if t.get("path").and_then(Value::as_str) != Some("weights") {
                continue;
            }
            let node = idx(t, "node")?;
            let s = samplers
                .get(idx(ch, "sampler")?)
                .ok_or("channel refers to a missing sampler")?;
            let (_, times) = doc.accessor(idx(s, "input")?)?;
            let (_, w) = doc.accessor(idx(s, "output")?)?;
            if scene.times.is_empty() {
                scene.times = times.iter().map(|&t| t as f32).collect();
            }
            let slot = node_keys
                .get_mut(node)
                .ok_or("channel targets a missing node")?;
            *slot = Some((times.len(), w));
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
        let mut frames = Vec::new();
        match &node_keys[ni] {
            None => frames.push(base.clone()),
            Some((keys, w)) => {
                let nt = targets.len();
                if w.len() != keys * nt {
                    return Err(format!(
                        "node {ni}: {} weights for {keys} keys × {nt} targets",
                        w.len()
                    ));
                }
                for k in 0..*keys {
                    let mut pos = base.clone();
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
                    frames.push(pos);
                }
            }
        }
        scene.meshes.push(GlbMesh {
            name: node
                .get("name")
                .and_then(Value::as_str)
                .unwrap_or("")
                .to_string(),
            triangles,
            frames,
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

    /// Writes `sample.glb` and `sample.usda` (a small animated grid, a line-element rope and, in
    /// the glb, a static ground) into `$DRAPERY_SAMPLE_DIR` when it is set, for
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
        let extra = [StaticMesh {
            name: "ground",
            positions: &ground,
            triangles: &ground_triangles,
        }];
        write_glb_with(&dir.join("sample.glb"), &cloths, &frames, 24.0, &extra).unwrap();
        crate::io::usd::write_usda(&dir.join("sample.usda"), &cloths, &frames, 24.0).unwrap();

        let g = read_glb(&dir.join("sample.glb")).unwrap();
        let times: Vec<f32> = (0..frames.len())
            .map(|k| (k as f64 / 24.0) as f32)
            .collect();
        assert_eq!(g.times, times);
        assert!(g.interpolations.iter().all(|i| i == "STEP"));
        let names: Vec<&str> = g.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["sheet", "rope", "ground"]);
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
        assert_eq!(names, ["sheet", "rope"]);
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
                name: "sheet".into(),
                offset: 0,
                mesh: sheet,
            },
            ClothInfo {
                name: "rope".into(),
                offset: n0,
                mesh: rope,
            },
        ];
        (cloths, frames)
    }
}
