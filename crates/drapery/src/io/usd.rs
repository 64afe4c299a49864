//! USD ASCII (`.usda`) animation caches.
//!
//! [`write_usda`] writes one stage: y up, metres, `timeCodesPerSecond = framesPerSecond =` the
//! frame rate, time codes `0 ..= frames-1` (time code k is frame k). Under the default prim
//! `/drapery` (an Xform) each cloth is a `Mesh` whose name is the cloth's name made into a valid
//! USD identifier (see [`prim_name`]), with its polygons (`faceVertexCounts` /
//! `faceVertexIndices`, local 0-based indices, triangles and quads kept as they are),
//! `points` time-sampled once per frame, a time-sampled `extent`, `subdivisionScheme = "none"`
//! and `doubleSided = true`. Line elements are not written (USD meshes have no line elements).
//!
//! [`write_usda_with`] also writes colliders ([`MovingMesh`]) as `Mesh` prims after the cloths
//! (names unique among all prims): a fixed one with constant `points`; a rigidly moving one with
//! constant `points` in its own frame and time-sampled `double3 xformOp:translate` and
//! `quatd xformOp:orient` (`xformOpOrder = ["xformOp:translate", "xformOp:orient"]`: a point `p`
//! is at `R p + t`); a deforming one with time-sampled `points` and `extent`, like a cloth.
//!
//! Points are `point3f` (f32): every value is printed with the shortest decimal form that reads
//! back to the same f32.

use super::gltf::{MeshMotion, MovingMesh};
use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::model::ClothInfo;
use glam::DQuat;
use std::fmt::Write as _;
use std::path::Path;

/// Makes a valid USD prim name (`[A-Za-z_][A-Za-z0-9_]*`) from `name`: every other character
/// becomes `_`, and a leading digit (or an empty name) gets a `_` prefix.
pub fn prim_name(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

/// Unique prim names for the cloths, in order: [`prim_name`], then `_2`, `_3`, … on clashes.
pub fn prim_names(cloths: &[ClothInfo]) -> Vec<String> {
    unique_prim_names(cloths.iter().map(|c| c.name.as_str()))
}

/// Unique prim names for `names`, in order: [`prim_name`], then `_2`, `_3`, … on clashes.
fn unique_prim_names<'a>(names: impl Iterator<Item = &'a str>) -> Vec<String> {
    let mut used = std::collections::HashSet::new();
    names
        .map(|n| {
            let base = prim_name(n);
            let mut name = base.clone();
            let mut k = 2;
            while !used.insert(name.clone()) {
                name = format!("{base}_{k}");
                k += 1;
            }
            name
        })
        .collect()
}

/// Checks the frames and the frame rate shared by the animated writers.
pub(crate) fn check_frames(
    what: &str,
    cloths: &[ClothInfo],
    frames: &[Vec<Vec3>],
    frame_rate: f64,
) -> Result<()> {
    if !(frame_rate > 0.0 && frame_rate.is_finite()) {
        return Err(Error::Invalid(format!(
            "{what}: frame rate must be a finite number > 0, got {frame_rate}"
        )));
    }
    if frames.is_empty() {
        return Err(Error::Invalid(format!("{what}: no frames to write")));
    }
    if cloths.is_empty() {
        return Err(Error::Invalid(format!("{what}: no cloths to write")));
    }
    for (k, f) in frames.iter().enumerate() {
        super::ply::check_ranges(cloths, f.len(), &format!("{what}: frame {k}"))?;
        for c in cloths {
            if let Some(i) = f[c.range()].iter().position(|p| !(p.as_vec3().is_finite())) {
                return Err(Error::Invalid(format!(
                    "{what}: frame {k}, cloth '{}': vertex {i} is not finite (in f32)",
                    c.name
                )));
            }
        }
    }
    for c in cloths {
        let n = c.mesh.positions.len();
        if c.mesh
            .faces
            .iter()
            .any(|f| f.indices().iter().any(|&v| v as usize >= n))
        {
            return Err(Error::Invalid(format!(
                "{what}: cloth '{}' has a face index out of range",
                c.name
            )));
        }
    }
    Ok(())
}

/// Formats an f64 as a USD number: integers without a fraction, others in full.
fn num(v: f64) -> String {
    format!("{v}")
}

fn push_point(out: &mut String, p: Vec3) {
    let q = p.as_vec3();
    let _ = write!(out, "({}, {}, {})", q.x, q.y, q.z);
}

fn push_points(out: &mut String, pts: &[Vec3]) {
    out.push('[');
    for (i, p) in pts.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        push_point(out, *p);
    }
    out.push(']');
}

fn push_extent(out: &mut String, pts: &[Vec3]) {
    let (lo, hi) = pts.iter().fold(
        (Vec3::splat(f64::INFINITY), Vec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    push_points(out, &[lo, hi]);
}

/// The points of a `Mesh` prim: constant, or one sample per frame.
enum Points<'a> {
    Constant(&'a [Vec3]),
    Sampled(Vec<&'a [Vec3]>),
}

/// Writes the attribute `decl` (type and name) of `points`, each value written by `value`:
/// constant, or one time sample per frame.
fn attribute(s: &mut String, decl: &str, points: &Points<'_>, value: fn(&mut String, &[Vec3])) {
    match points {
        Points::Constant(p) => {
            let _ = write!(s, "        {decl} = ");
            value(s, p);
            s.push('\n');
        }
        Points::Sampled(frames) => {
            let _ = writeln!(s, "        {decl}.timeSamples = {{");
            for (k, p) in frames.iter().enumerate() {
                let _ = write!(s, "            {k}: ");
                value(s, p);
                s.push_str(",\n");
            }
            s.push_str("        }\n");
        }
    }
}

/// Writes one `Mesh` prim (inside `/drapery`); `xform` adds time-sampled translate/orient ops.
fn mesh_prim(
    s: &mut String,
    name: &str,
    counts: &[usize],
    indices: &[u32],
    points: &Points<'_>,
    xform: Option<&[(DQuat, Vec3)]>,
) {
    let list = |v: &mut String, items: &mut dyn Iterator<Item = String>| {
        v.push_str(&items.collect::<Vec<_>>().join(", "));
    };
    let _ = writeln!(s, "    def Mesh \"{name}\"\n    {{");
    s.push_str("        uniform bool doubleSided = 1\n");
    s.push_str("        int[] faceVertexCounts = [");
    list(s, &mut counts.iter().map(|c| c.to_string()));
    s.push_str("]\n        int[] faceVertexIndices = [");
    list(s, &mut indices.iter().map(|c| c.to_string()));
    s.push_str("]\n");
    attribute(s, "float3[] extent", points, push_extent);
    s.push_str("        uniform token orientation = \"rightHanded\"\n");
    attribute(s, "point3f[] points", points, push_points);
    s.push_str("        uniform token subdivisionScheme = \"none\"\n");
    if let Some(poses) = xform {
        s.push_str("        double3 xformOp:translate.timeSamples = {\n");
        for (k, (_, t)) in poses.iter().enumerate() {
            let _ = writeln!(s, "            {k}: ({}, {}, {}),", t.x, t.y, t.z);
        }
        s.push_str("        }\n        quatd xformOp:orient.timeSamples = {\n");
        for (k, (r, _)) in poses.iter().enumerate() {
            let _ = writeln!(s, "            {k}: ({}, {}, {}, {}),", r.w, r.x, r.y, r.z);
        }
        s.push_str("        }\n");
        s.push_str(
            "        uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:orient\"]\n",
        );
    }
    s.push_str("    }\n");
}

/// Writes the frames as a USD ASCII stage (see the module documentation).
pub fn write_usda(
    path: &Path,
    cloths: &[ClothInfo],
    frames: &[Vec<Vec3>],
    frame_rate: f64,
) -> Result<()> {
    write_usda_with(path, cloths, frames, frame_rate, &[])
}

/// [`write_usda`] plus colliders, fixed or moving (see the module documentation).
pub fn write_usda_with(
    path: &Path,
    cloths: &[ClothInfo],
    frames: &[Vec<Vec3>],
    frame_rate: f64,
    colliders: &[MovingMesh],
) -> Result<()> {
    let what = path.display().to_string();
    check_frames(&what, cloths, frames, frame_rate)?;
    for m in colliders {
        m.check(&what, frames.len())?;
    }
    let names = unique_prim_names(
        (cloths.iter().map(|c| c.name.as_str())).chain(colliders.iter().map(|m| m.name.as_str())),
    );
    let mut s = String::new();
    s.push_str("#usda 1.0\n(\n");
    s.push_str("    defaultPrim = \"drapery\"\n");
    s.push_str("    doc = \"Cloth animation written by drapery\"\n");
    let _ = writeln!(s, "    endTimeCode = {}", frames.len() - 1);
    let _ = writeln!(s, "    framesPerSecond = {}", num(frame_rate));
    s.push_str("    metersPerUnit = 1\n");
    s.push_str("    startTimeCode = 0\n");
    let _ = writeln!(s, "    timeCodesPerSecond = {}", num(frame_rate));
    s.push_str("    upAxis = \"Y\"\n)\n\n");
    s.push_str("def Xform \"drapery\"\n{\n");
    for (c, name) in cloths.iter().zip(&names) {
        let counts: Vec<usize> = c.mesh.faces.iter().map(|f| f.indices().len()).collect();
        let indices: Vec<u32> = (c.mesh.faces.iter())
            .flat_map(|f| f.indices().iter().copied())
            .collect();
        let points = Points::Sampled(frames.iter().map(|f| &f[c.range()]).collect());
        mesh_prim(&mut s, name, &counts, &indices, &points, None);
    }
    for (m, name) in colliders.iter().zip(&names[cloths.len()..]) {
        let counts = vec![3; m.triangles.len()];
        let indices: Vec<u32> = m.triangles.iter().flatten().copied().collect();
        let (points, xform) = match &m.motion {
            MeshMotion::Fixed => (Points::Constant(&m.positions), None),
            MeshMotion::Rigid(poses) => (Points::Constant(&m.positions), Some(poses.as_slice())),
            MeshMotion::Deforming(f) => {
                (Points::Sampled(f.iter().map(Vec::as_slice).collect()), None)
            }
        };
        mesh_prim(&mut s, name, &counts, &indices, &points, xform);
    }
    s.push_str("}\n");
    super::write_atomic(path, s.as_bytes())
}

/// One mesh read back by [`read_usda`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UsdaMesh {
    /// Prim name.
    pub name: String,
    /// `faceVertexCounts`.
    pub face_vertex_counts: Vec<u32>,
    /// `faceVertexIndices`.
    pub face_vertex_indices: Vec<u32>,
    /// `points.timeSamples`: (time code, points), in file order.
    pub samples: Vec<(f64, Vec<Vec3>)>,
    /// Constant `points` (empty when there are none).
    pub points: Vec<Vec3>,
    /// `xformOp:translate.timeSamples`: (time code, translation), in file order.
    pub translations: Vec<(f64, Vec3)>,
    /// `xformOp:orient.timeSamples`: (time code, rotation), in file order.
    pub orientations: Vec<(f64, DQuat)>,
    /// `xformOpOrder`.
    pub xform_op_order: Vec<String>,
}

/// What [`read_usda`] understands of a stage written by [`write_usda`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UsdaStage {
    /// `timeCodesPerSecond`.
    pub time_codes_per_second: f64,
    /// `startTimeCode`.
    pub start_time_code: f64,
    /// `endTimeCode`.
    pub end_time_code: f64,
    /// `upAxis`.
    pub up_axis: String,
    /// The meshes, in file order.
    pub meshes: Vec<UsdaMesh>,
}

/// Reads back a stage in the layout [`write_usda`] produces (one statement per line, one time
/// sample per line). A test helper, not a general USD parser.
pub fn read_usda(path: &Path) -> Result<UsdaStage> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path.display(), e))?;
    parse_usda(&text).map_err(|m| Error::input(path.display(), m))
}

fn parse_numbers(s: &str) -> std::result::Result<Vec<f64>, String> {
    s.split([',', '(', ')', '[', ']'])
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f64>().map_err(|_| format!("bad number '{t}'")))
        .collect()
}

fn triples(v: &[f64], t: f64) -> std::result::Result<Vec<Vec3>, String> {
    if !v.len().is_multiple_of(3) {
        return Err(format!("time {t}: point list is not made of triples"));
    }
    Ok(v.chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect())
}

fn parse_usda(text: &str) -> std::result::Result<UsdaStage, String> {
    let mut lines = text.lines();
    if lines.next().map(str::trim) != Some("#usda 1.0") {
        return Err("first line is not '#usda 1.0'".into());
    }
    let mut st = UsdaStage::default();
    // the time-sampled attribute being read: 0 points, 1 translate, 2 orient
    let mut block: Option<usize> = None;
    for line in lines {
        let l = line.trim();
        let value = |key: &str| -> Option<String> {
            l.strip_prefix(key)
                .and_then(|r| r.trim_start().strip_prefix('='))
                .map(|v| v.trim().trim_matches('"').to_string())
        };
        let number = |key: &str| -> std::result::Result<Option<f64>, String> {
            match value(key) {
                None => Ok(None),
                Some(v) => v
                    .parse::<f64>()
                    .map(Some)
                    .map_err(|_| format!("bad {key} '{v}'")),
            }
        };
        if let Some(b) = block {
            if l == "}" {
                block = None;
                continue;
            }
            let (t, rest) = l.split_once(':').ok_or("bad time sample line")?;
            let t: f64 = t
                .trim()
                .parse()
                .map_err(|_| format!("bad time code '{t}'"))?;
            let v = parse_numbers(rest)?;
            let m = st.meshes.last_mut().ok_or("time samples outside a mesh")?;
            match b {
                0 => m.samples.push((t, triples(&v, t)?)),
                1 if v.len() == 3 => m.translations.push((t, Vec3::new(v[0], v[1], v[2]))),
                2 if v.len() == 4 => m
                    .orientations
                    .push((t, DQuat::from_xyzw(v[1], v[2], v[3], v[0]))),
                _ => return Err(format!("time {t}: bad xform op value")),
            }
        } else if let Some(v) = number("timeCodesPerSecond")? {
            st.time_codes_per_second = v;
        } else if let Some(v) = number("startTimeCode")? {
            st.start_time_code = v;
        } else if let Some(v) = number("endTimeCode")? {
            st.end_time_code = v;
        } else if let Some(v) = value("upAxis") {
            st.up_axis = v;
        } else if let Some(rest) = l.strip_prefix("def Mesh ") {
            st.meshes.push(UsdaMesh {
                name: rest.trim().trim_matches('"').to_string(),
                ..UsdaMesh::default()
            });
        } else if let Some(v) = value("int[] faceVertexCounts") {
            let m = st
                .meshes
                .last_mut()
                .ok_or("faceVertexCounts outside a mesh")?;
            m.face_vertex_counts = parse_numbers(&v)?.iter().map(|&x| x as u32).collect();
        } else if let Some(v) = value("int[] faceVertexIndices") {
            let m = st
                .meshes
                .last_mut()
                .ok_or("faceVertexIndices outside a mesh")?;
            m.face_vertex_indices = parse_numbers(&v)?.iter().map(|&x| x as u32).collect();
        } else if let Some(v) = value("point3f[] points") {
            let m = st.meshes.last_mut().ok_or("points outside a mesh")?;
            m.points = triples(&parse_numbers(&v)?, 0.0)?;
        } else if let Some(v) = value("uniform token[] xformOpOrder") {
            let m = st.meshes.last_mut().ok_or("xformOpOrder outside a mesh")?;
            m.xform_op_order = v
                .trim_matches(['[', ']'])
                .split(',')
                .map(|t| t.trim().trim_matches('"').to_string())
                .collect();
        } else if l.starts_with("point3f[] points.timeSamples") {
            block = Some(0);
        } else if l.starts_with("double3 xformOp:translate.timeSamples") {
            block = Some(1);
        } else if l.starts_with("quatd xformOp:orient.timeSamples") {
            block = Some(2);
        }
    }
    Ok(st)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::mesh::{Face, Mesh};

    pub(crate) fn animated() -> (Vec<ClothInfo>, Vec<Vec<Vec3>>) {
        let a = Mesh::grid([1.0, 0.5], [4, 3], Vec3::new(0.0, 1.0, 0.0), Vec3::Z).unwrap();
        let b = Mesh {
            positions: vec![Vec3::X, Vec3::Y, Vec3::Z],
            faces: vec![Face::Tri([0, 1, 2])],
            lines: vec![],
            face_uv: Vec::new(),
        };
        let mut base = a.positions.clone();
        base.extend_from_slice(&b.positions);
        let frames = (0..5)
            .map(|k| {
                base.iter()
                    .enumerate()
                    .map(|(i, p)| *p + Vec3::new(0.0, -0.1 * k as f64, 0.01 * (i * k) as f64 / 3.0))
                    .collect()
            })
            .collect();
        let cloths = vec![
            ClothInfo {
                material: Default::default(),
                name: "flag-1.v2".into(),
                offset: 0,
                mesh: a,
            },
            ClothInfo {
                material: Default::default(),
                name: "9lives".into(),
                offset: 12,
                mesh: b,
            },
        ];
        (cloths, frames)
    }

    #[test]
    fn names_become_valid_unique_identifiers() {
        assert_eq!(prim_name("flag-1.v2"), "flag_1_v2");
        assert_eq!(prim_name("9lives"), "_9lives");
        assert_eq!(prim_name(""), "_");
        assert_eq!(prim_name("été"), "_t_");
        let (mut c, _) = animated();
        c[1].name = "flag_1_v2".into();
        assert_eq!(prim_names(&c), ["flag_1_v2", "flag_1_v2_2"]);
    }

    #[test]
    fn stage_round_trips_every_frame_at_f32_precision() {
        let (cloths, frames) = animated();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.usda");
        write_usda(&path, &cloths, &frames, 24.0).unwrap();
        let st = read_usda(&path).unwrap();
        assert_eq!(st.time_codes_per_second, 24.0);
        assert_eq!((st.start_time_code, st.end_time_code), (0.0, 4.0));
        assert_eq!(st.up_axis, "Y");
        assert_eq!(st.meshes.len(), 2);
        assert_eq!(st.meshes[0].name, "flag_1_v2");
        assert_eq!(st.meshes[1].name, "_9lives");
        assert_eq!(st.meshes[0].face_vertex_counts, vec![4; 6]);
        assert_eq!(st.meshes[1].face_vertex_indices, vec![0, 1, 2]);
        for (c, m) in cloths.iter().zip(&st.meshes) {
            assert_eq!(m.samples.len(), frames.len());
            for (k, (t, pts)) in m.samples.iter().enumerate() {
                assert_eq!(*t, k as f64);
                let expect: Vec<Vec3> = frames[k][c.range()]
                    .iter()
                    .map(|p| p.as_vec3().as_dvec3())
                    .collect();
                // f32 values printed shortest-round-trip read back exactly as the same f32.
                let got: Vec<Vec3> = pts.iter().map(|p| p.as_vec3().as_dvec3()).collect();
                assert_eq!(got, expect);
            }
        }
    }

    #[test]
    fn moving_colliders_have_time_sampled_xform_ops_and_fixed_ones_constant_points() {
        use crate::collision::tessellate::{TessellateOptions, tessellate};
        use crate::io::gltf::tests::{moving_colliders, near_f32};
        let (cloths, frames) = animated();
        let (colliders, times, mut meshes) = moving_colliders(frames.len(), 24.0);
        meshes[1].name = "flag_1_v2".into(); // clashes with the first cloth's prim name
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("moving.usda");
        write_usda_with(&path, &cloths, &frames, 24.0, &meshes).unwrap();
        let st = read_usda(&path).unwrap();
        let names: Vec<&str> = st.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(
            names,
            ["flag_1_v2", "_9lives", "spinner", "flag_1_v2_2", "wobble"]
        );
        let o = TessellateOptions::default();

        // rigid: translate then orient at every time code moves its points onto the collider's
        // tessellation at that frame's time
        let spin = &st.meshes[2];
        assert_eq!(spin.xform_op_order, ["xformOp:translate", "xformOp:orient"]);
        assert!(spin.samples.is_empty());
        let (_, tris) = tessellate(&colliders[0], 0.0, &o);
        assert_eq!(spin.face_vertex_counts, vec![3; tris.len()]);
        assert_eq!(
            spin.face_vertex_indices,
            tris.iter().flatten().copied().collect::<Vec<_>>()
        );
        assert_eq!(spin.translations.len(), times.len());
        assert_eq!(spin.orientations.len(), times.len());
        for (k, &t) in times.iter().enumerate() {
            let ((ta, tr), (ra, r)) = (spin.translations[k], spin.orientations[k]);
            assert_eq!((ta, ra), (k as f64, k as f64));
            assert!((r.length() - 1.0).abs() < 1e-12);
            let (want, _) = tessellate(&colliders[0], t, &o);
            assert_eq!(want.len(), spin.points.len());
            for (i, (p, w)) in spin.points.iter().zip(&want).enumerate() {
                let got = r * *p + tr;
                assert!(
                    near_f32(got, *w, p.length() + tr.length()),
                    "time {k} vertex {i}: {got} vs {w}"
                );
            }
        }
        assert_ne!(spin.translations[0].1, spin.translations[1].1);

        // fixed: constant points, the f32 of its tessellation, no xform ops
        let post = &st.meshes[3];
        let (want, _) = tessellate(&colliders[1], 0.0, &o);
        let f32s = |v: &[Vec3]| v.iter().map(|p| p.as_vec3().to_array()).collect::<Vec<_>>();
        assert_eq!(f32s(&post.points), f32s(&want));
        assert!(post.samples.is_empty() && post.translations.is_empty());
        assert!(post.orientations.is_empty() && post.xform_op_order.is_empty());

        // deforming: time-sampled points, the f32 of each frame's tessellation
        let wobble = &st.meshes[4];
        assert!(wobble.points.is_empty() && wobble.xform_op_order.is_empty());
        assert_eq!(wobble.samples.len(), times.len());
        for (k, &t) in times.iter().enumerate() {
            assert_eq!(wobble.samples[k].0, k as f64);
            assert_eq!(
                f32s(&wobble.samples[k].1),
                f32s(&tessellate(&colliders[0], t, &o).0)
            );
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let (cloths, mut frames) = animated();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.usda");
        assert!(write_usda(&path, &cloths, &frames, 0.0).is_err());
        assert!(write_usda(&path, &cloths, &[], 30.0).is_err());
        frames[2][3].y = f64::NAN;
        assert!(write_usda(&path, &cloths, &frames, 30.0).is_err());
        frames[2].truncate(10);
        assert!(write_usda(&path, &cloths, &frames, 30.0).is_err());
        assert!(!path.exists());
    }
}
