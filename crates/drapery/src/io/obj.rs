//! Wavefront OBJ: meshes in ([`read_obj`]) and frames out ([`write_obj`]).
//!
//! Reading keeps what the simulator needs: `v` (positions), `f` (triangles and quads) and `l`
//! (line elements; a polyline `l a b c` becomes the segments `a–b`, `b–c`). Texture coordinates,
//! normals, groups, objects and materials are accepted and ignored; every object of the file is
//! merged into one mesh. Vertices keep their input order (all of them, referenced or not),
//! faces and line elements keep theirs.
//!
//! How: a first pass over the text checks every `v`, `f` and `l` line (numbers, index ranges,
//! arity) so that errors name the line, and writes a normalised copy in which each vertex is
//! tagged with its own input index. `tobj` parses that copy; it renumbers vertices by first use,
//! and the tags map its numbering back to the input order.
//!
//! Writing ([`write_obj`], [`ObjWriter`] for a sequence of frames) prints every coordinate in
//! its shortest round-trip form, so reading a written file back gives the same `f64` bits.

use crate::error::{Error, Result};
use crate::io::write_atomic;
use crate::math::Vec3;
use crate::mesh::{Face, Mesh};
use crate::model::ClothInfo;
use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;

/// Reads an OBJ file into a [`Mesh`] and validates it ([`Mesh::validate`]).
///
/// Errors are [`Error::Io`] when the file cannot be read and [`Error::Input`] naming the file
/// and the line (or the face/line element) at fault otherwise: binary data, bad numbers,
/// non-finite coordinates, indices out of range, polygons with more than four vertices,
/// degenerate faces, no vertices.
pub fn read_obj(path: &Path) -> Result<Mesh> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path.display(), e))?;
    parse_obj(&bytes, &path.display().to_string())
}

/// Where each face and line element came from, for messages.
struct Origins {
    face_lines: Vec<usize>,
    segment_lines: Vec<usize>,
    vertex_lines: Vec<usize>,
}

/// Parses OBJ bytes; `what` names the file in messages.
pub fn parse_obj(bytes: &[u8], what: &str) -> Result<Mesh> {
    let err = |msg: String| Error::input(what, msg);
    if let Some(pos) = bytes.iter().position(|&b| b == 0) {
        return Err(err(format!(
            "not a text OBJ file (binary data: NUL byte at offset {pos})"
        )));
    }
    let text = std::str::from_utf8(bytes).map_err(|e| {
        err(format!(
            "not a text OBJ file (binary data: invalid UTF-8 at offset {})",
            e.valid_up_to()
        ))
    })?;

    // Pass 1: count vertices so forward references can be range-checked.
    let total_vertices = text
        .lines()
        .filter(|l| l.split_whitespace().next() == Some("v"))
        .count();

    // Pass 2: check and normalise.
    let mut positions: Vec<Vec3> = Vec::with_capacity(total_vertices);
    let mut origins = Origins {
        face_lines: Vec::new(),
        segment_lines: Vec::new(),
        vertex_lines: Vec::with_capacity(total_vertices),
    };
    let mut normalised = String::with_capacity(text.len());
    // texture coordinates, and each face's corners' (None for a face without them)
    let mut texcoords: Vec<[f64; 2]> = Vec::new();
    let mut face_uv: Vec<Option<[[f64; 2]; 4]>> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let lineno = i + 1;
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        let args: Vec<&str> = words.collect();
        match keyword {
            "v" => {
                let p = parse_vertex(&args).map_err(|m| {
                    err(format!(
                        "line {lineno}: vertex {}: {m}",
                        positions.len() + 1
                    ))
                })?;
                let _ = writeln!(normalised, "v {} 0 0", positions.len());
                positions.push(p);
                origins.vertex_lines.push(lineno);
            }
            "f" => {
                let idx = parse_indices(&args, positions.len(), total_vertices)
                    .map_err(|m| err(format!("line {lineno}: face: {m}")))?;
                match idx.len() {
                    0..=2 => {
                        return Err(err(format!(
                            "line {lineno}: face has {} vertices; a face needs 3 or 4",
                            idx.len()
                        )));
                    }
                    3 | 4 => {}
                    n => {
                        return Err(err(format!(
                            "line {lineno}: polygon with {n} vertices; only triangles and quads are supported"
                        )));
                    }
                }
                face_uv.push(corner_uvs(&args, &texcoords));
                normalised.push('f');
                for v in &idx {
                    let _ = write!(normalised, " {}", v + 1);
                }
                normalised.push('\n');
                origins.face_lines.push(lineno);
            }
            "l" => {
                let idx = parse_indices(&args, positions.len(), total_vertices)
                    .map_err(|m| err(format!("line {lineno}: line element: {m}")))?;
                if idx.len() < 2 {
                    return Err(err(format!(
                        "line {lineno}: line element has {} vertices; it needs at least 2",
                        idx.len()
                    )));
                }
                for w in idx.windows(2) {
                    let _ = writeln!(normalised, "l {} {}", w[0] + 1, w[1] + 1);
                    origins.segment_lines.push(lineno);
                }
            }
            "o" | "g" => {
                normalised.push_str(line.trim());
                normalised.push('\n');
            }
            "vt" => {
                // `u v` (an optional w ignored); anything else leaves the faces that use it
                // without texture coordinates
                let c = |k: usize| args.get(k).and_then(|a| a.parse::<f64>().ok());
                texcoords.push(match (c(0), c(1)) {
                    (Some(u), Some(v)) if u.is_finite() && v.is_finite() => [u, v],
                    _ => [f64::NAN; 2],
                });
            }
            // vn, s, usemtl, mtllib, comments, …: not needed by the simulator.
            _ => {}
        }
    }
    if positions.is_empty() {
        return Err(err("mesh has no vertices (no 'v' lines)".into()));
    }

    let mut mesh = topology_with_tobj(&normalised, positions, &origins)
        .map_err(|m| err(format!("cannot read the faces: {m}")))?;
    // texture coordinates count only when every face has them
    if let Some(uv) = face_uv.into_iter().collect::<Option<Vec<_>>>() {
        mesh.face_uv = uv;
    }
    mesh.validate(what)
        .map_err(|e| with_line_numbers(e, &origins))?;
    Ok(mesh)
}

/// The texture coordinates of a face's corners (`v/vt` or `v/vt/vn`), when every corner has a
/// valid one (1-based, or negative counting back from the last read).
fn corner_uvs(args: &[&str], texcoords: &[[f64; 2]]) -> Option<[[f64; 2]; 4]> {
    let mut uv = [[0.0; 2]; 4];
    for (c, tok) in args.iter().take(4).enumerate() {
        let k: i64 = tok.split('/').nth(1)?.parse().ok()?;
        let at = match k {
            1.. => k as usize - 1,
            ..0 => texcoords.len().checked_sub(k.unsigned_abs() as usize)?,
            0 => return None,
        };
        uv[c] = *texcoords.get(at).filter(|t| t[0].is_finite())?;
    }
    Some(uv)
}

/// Parses the numbers of a `v` line: `x y z`, `x y z w` (divided by `w`) or `x y z r g b`.
fn parse_vertex(args: &[&str]) -> std::result::Result<Vec3, String> {
    if !matches!(args.len(), 3 | 4 | 6) {
        return Err(format!(
            "expected 3 coordinates (optionally w, or r g b), got {} numbers",
            args.len()
        ));
    }
    let mut c = [0.0f64; 6];
    for (k, s) in args.iter().enumerate() {
        c[k] = s
            .parse::<f64>()
            .map_err(|_| format!("'{s}' is not a number"))?;
    }
    let mut p = Vec3::new(c[0], c[1], c[2]);
    if args.len() == 4 {
        let w = c[3];
        if !(w != 0.0 && w.is_finite()) {
            return Err(format!("weight w must be finite and non-zero, got {w}"));
        }
        if w != 1.0 {
            p /= w;
        }
    }
    if !p.is_finite() {
        return Err(format!("non-finite coordinate ({}, {}, {})", p.x, p.y, p.z));
    }
    Ok(p)
}

/// Parses the vertex part of `v`, `v/vt`, `v//vn`, `v/vt/vn` tokens into 0-based indices.
/// Negative indices count back from the vertices read so far; positive ones may refer forward.
fn parse_indices(
    args: &[&str],
    read_so_far: usize,
    total: usize,
) -> std::result::Result<Vec<u32>, String> {
    let mut out = Vec::with_capacity(args.len());
    for tok in args {
        let head = tok.split('/').next().unwrap_or("");
        let k: i64 = head
            .parse()
            .map_err(|_| format!("'{tok}' is not a vertex index"))?;
        let idx = if k > 0 {
            let z = (k - 1) as u64;
            if z >= total as u64 {
                return Err(format!(
                    "vertex index {k} is out of range (the file has {total} vertices)"
                ));
            }
            z
        } else if k < 0 {
            let back = k.unsigned_abs();
            if back > read_so_far as u64 {
                return Err(format!(
                    "relative vertex index {k} points before the first vertex ({read_so_far} read so far)"
                ));
            }
            read_so_far as u64 - back
        } else {
            return Err("vertex index 0 is invalid (OBJ indices start at 1)".into());
        };
        let idx = u32::try_from(idx).map_err(|_| format!("vertex index {k} is too large"))?;
        out.push(idx);
    }
    Ok(out)
}

/// Runs `tobj` on the normalised text and maps its per-model numbering back to input indices
/// (each normalised vertex carries its input index as its x coordinate).
fn topology_with_tobj(
    normalised: &str,
    positions: Vec<Vec3>,
    origins: &Origins,
) -> std::result::Result<Mesh, String> {
    // (`..Default::default()`: whatever options a later tobj adds keep their defaults)
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: false,
        single_index: false,
        ignore_points: true,
        ignore_lines: false,
        ..Default::default()
    };
    let mut reader = std::io::BufReader::new(normalised.as_bytes());
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| e.to_string())?;
    let n = positions.len();
    let mut faces = Vec::with_capacity(origins.face_lines.len());
    let mut lines = Vec::with_capacity(origins.segment_lines.len());
    for model in &models {
        let m = &model.mesh;
        let global: Vec<u32> = m
            .positions
            .chunks_exact(3)
            .map(|c| c[0])
            .map(|tag| {
                if tag >= 0.0 && tag < n as f64 && tag.fract() == 0.0 {
                    Ok(tag as u32)
                } else {
                    Err(format!("internal: unexpected vertex tag {tag}"))
                }
            })
            .collect::<std::result::Result<_, _>>()?;
        let map = |local: u32| -> std::result::Result<u32, String> {
            global
                .get(local as usize)
                .copied()
                .ok_or_else(|| format!("internal: index {local} out of range"))
        };
        let arities: Vec<u32> = if m.face_arities.is_empty() {
            vec![3; m.indices.len() / 3]
        } else {
            m.face_arities.clone()
        };
        let mut at = 0usize;
        for arity in arities {
            let a = arity as usize;
            let idx = m
                .indices
                .get(at..at + a)
                .ok_or_else(|| "internal: face indices end early".to_string())?;
            at += a;
            match a {
                2 => lines.push([map(idx[0])?, map(idx[1])?]),
                3 => faces.push(Face::Tri([map(idx[0])?, map(idx[1])?, map(idx[2])?])),
                4 => faces.push(Face::Quad([
                    map(idx[0])?,
                    map(idx[1])?,
                    map(idx[2])?,
                    map(idx[3])?,
                ])),
                _ => return Err(format!("polygon with {a} vertices")),
            }
        }
    }
    if faces.len() != origins.face_lines.len() || lines.len() != origins.segment_lines.len() {
        return Err(format!(
            "internal: expected {} faces and {} line elements, tobj gave {} and {}",
            origins.face_lines.len(),
            origins.segment_lines.len(),
            faces.len(),
            lines.len()
        ));
    }
    Ok(Mesh {
        positions,
        faces,
        lines,
        face_uv: Vec::new(),
    })
}

/// Adds the source line to a [`Mesh::validate`] message that names a face, line element or
/// vertex by its 1-based number.
fn with_line_numbers(e: Error, origins: &Origins) -> Error {
    let Error::Input { path, message } = e else {
        return e;
    };
    let lookup = |prefix: &str, table: &[usize]| -> Option<usize> {
        let rest = message.strip_prefix(prefix)?;
        let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
        let k: usize = digits.parse().ok()?;
        table.get(k.checked_sub(1)?).copied()
    };
    let line = lookup("face ", &origins.face_lines)
        .or_else(|| lookup("line element ", &origins.segment_lines))
        .or_else(|| lookup("vertex ", &origins.vertex_lines));
    let message = match line {
        Some(l) => format!("line {l}: {message}"),
        None => message,
    };
    Error::Input { path, message }
}

/// Writes one frame: every cloth as `o NAME`, its vertices (positions taken from `x`, the
/// model's particle array) in order, then its faces and line elements in input order, with
/// 1-based indices over the whole file. Written atomically ([`write_atomic`]).
///
/// For a sequence of frames of the same cloths, [`ObjWriter`] writes the same bytes with less
/// work per frame.
pub fn write_obj(path: &Path, cloths: &[ClothInfo], x: &[Vec3]) -> Result<()> {
    ObjWriter::new(cloths).write(path, x)
}

/// The OBJ text [`write_obj`] writes.
pub fn obj_text(cloths: &[ClothInfo], x: &[Vec3]) -> std::result::Result<String, String> {
    let mut w = ObjWriter::new(cloths);
    w.format(x)?;
    Ok(w.text)
}

/// Writes OBJ frames of one set of cloths, as [`write_obj`] does. What is the same in every
/// frame (the `o` lines, faces and line elements) is formatted once, by [`ObjWriter::new`]; a
/// frame formats only its vertex positions, into a buffer kept from frame to frame.
///
/// Coordinates are printed by `zmij` in the shortest decimal form that reads back to the same
/// `f64` bits: `0.5`, `1.0`, `-0.0`, and very small or large magnitudes with an exponent
/// (`2.5e-8`, `1e+21`), as OBJ readers accept.
pub struct ObjWriter {
    cloths: Vec<Part>,
    /// The last frame's text.
    text: String,
}

/// One cloth's part of the file.
struct Part {
    name: String,
    range: Range<usize>,
    /// `o NAME`.
    head: String,
    /// The faces and line elements.
    tail: String,
}

/// The longest vertex line: `v`, three coordinates of at most 24 characters
/// (`-2.2250738585072014e-308`), three spaces and the newline.
const VERTEX_LINE_MAX: usize = 1 + 3 * (1 + 24) + 1;

impl ObjWriter {
    /// Formats what the frames of `cloths` share.
    pub fn new(cloths: &[ClothInfo]) -> ObjWriter {
        let mut base = 0u64;
        let parts = cloths
            .iter()
            .map(|c| {
                let mut tail = String::new();
                for f in &c.mesh.faces {
                    tail.push('f');
                    for &v in f.indices() {
                        let _ = write!(tail, " {}", base + v as u64 + 1);
                    }
                    tail.push('\n');
                }
                for l in &c.mesh.lines {
                    let _ = writeln!(
                        tail,
                        "l {} {}",
                        base + l[0] as u64 + 1,
                        base + l[1] as u64 + 1
                    );
                }
                base += c.mesh.positions.len() as u64;
                Part {
                    name: c.name.clone(),
                    range: c.range(),
                    head: format!("o {}\n", c.name),
                    tail,
                }
            })
            .collect();
        ObjWriter {
            cloths: parts,
            text: String::new(),
        }
    }

    /// Writes the frame with positions `x` (the model's particle array) to `path`, atomically
    /// ([`write_atomic`]).
    pub fn write(&mut self, path: &Path, x: &[Vec3]) -> Result<()> {
        self.format(x)
            .map_err(|m| Error::Invalid(format!("{}: {m}", path.display())))?;
        write_atomic(path, self.text.as_bytes())
    }

    /// Puts the frame's text in `self.text`.
    fn format(&mut self, x: &[Vec3]) -> std::result::Result<(), String> {
        let s = &mut self.text;
        s.clear();
        s.push_str("# drapery frame\n");
        let mut digits = zmij::Buffer::new();
        for c in &self.cloths {
            let pos = x.get(c.range.clone()).ok_or_else(|| {
                format!(
                    "cloth '{}' needs particles {:?} but the state has {}",
                    c.name,
                    c.range,
                    x.len()
                )
            })?;
            s.reserve(c.head.len() + pos.len() * VERTEX_LINE_MAX + c.tail.len());
            s.push_str(&c.head);
            for p in pos {
                s.push('v');
                for v in [p.x, p.y, p.z] {
                    s.push(' ');
                    s.push_str(digits.format(v));
                }
                s.push('\n');
            }
            s.push_str(&c.tail);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn parse(text: &str) -> Result<Mesh> {
        parse_obj(text.as_bytes(), "t.obj")
    }

    #[test]
    fn vertices_keep_input_order_even_when_faces_use_them_out_of_order() {
        let m = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 5 5 5\nf 3 4 1\nl 2 3\n").unwrap();
        assert_eq!(m.positions.len(), 5);
        assert_eq!(m.positions[1], Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(m.faces, vec![Face::Tri([2, 3, 0])]);
        assert_eq!(m.lines, vec![[1, 2]]);
    }

    #[test]
    fn objects_are_merged_and_polylines_split_into_segments() {
        let m = parse(
            "o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1/1 2//1 3 4\no b\nv 0 0 1\nv 0 0 2\nl -2 -1 1\n",
        )
        .unwrap();
        assert_eq!(m.faces, vec![Face::Quad([0, 1, 2, 3])]);
        assert_eq!(m.lines, vec![[4, 5], [5, 0]]);
    }

    #[test]
    fn texture_coordinates_are_read_per_face_corner() {
        let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 2 0\nvt 2 3\nvt 0 3\n";
        let m = parse(&format!("{quad}f 1/1 2/2 3/3/1 4/-1\nf 1/2 2/3 3/4\n")).unwrap();
        assert_eq!(
            m.face_uv,
            vec![
                [[0.0, 0.0], [2.0, 0.0], [2.0, 3.0], [0.0, 3.0]],
                [[2.0, 0.0], [2.0, 3.0], [0.0, 3.0], [0.0, 0.0]],
            ]
        );
        let tris = m.triangle_uvs().unwrap();
        assert_eq!(tris.len(), 3);
        assert_eq!(tris[1], [[0.0, 0.0], [2.0, 3.0], [0.0, 3.0]]);
        // a face without them (or with a bad one) leaves the whole mesh without
        for tail in [
            "f 1/1 2/2 3/3\nf 1 3 4\n",
            "vt 1\nf 1/5 2/2 3/3\n",
            "f 1/9 2/2 3/3\n",
        ] {
            let m = parse(&format!("{quad}{tail}")).unwrap();
            assert!(m.face_uv.is_empty() && m.triangle_uvs().is_none(), "{tail}");
        }
    }

    #[test]
    fn errors_name_the_line() {
        let cases = [
            ("v 0 0 0\nv 1 x 0\n", "line 2"),
            ("v 0 0 0\nv 1 nan 0\n", "line 2"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 7\n", "line 5"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 0\nf 1 2 4 5 3\n",
                "line 6",
            ),
            ("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "line 4"),
            ("# nothing\n", "no vertices"),
        ];
        for (text, want) in cases {
            let e = parse(text).unwrap_err().to_string();
            assert!(
                e.starts_with("t.obj: ") && e.contains(want),
                "{e:?} lacks {want:?}"
            );
        }
        let e = parse_obj(b"v 0 0 0\n\x00\x01", "t.obj")
            .unwrap_err()
            .to_string();
        assert!(e.contains("binary"), "{e}");
    }

    #[test]
    fn written_text_reads_back_to_the_same_bits() {
        let mesh = Mesh {
            positions: vec![
                Vec3::new(0.1 + 0.2, 1e-300, -0.0),
                Vec3::new(1.0 / 3.0, 1.0, 5e-324),
                Vec3::new(0.0, 1.0, 7.0),
                Vec3::new(-f64::MAX, f64::MIN_POSITIVE, 123_456_789.123_456_79),
                Vec3::new(-2.5e17, 0.0, 0.0),
            ],
            faces: vec![Face::Tri([0, 1, 2])],
            lines: vec![[3, 0], [4, 1]],
            face_uv: Vec::new(),
        };
        let info = ClothInfo {
            material: Default::default(),
            name: "c".into(),
            offset: 0,
            mesh: mesh.clone(),
        };
        let text = obj_text(&[info], &mesh.positions).unwrap();
        let back = parse(&text).unwrap();
        for (a, b) in mesh.positions.iter().zip(&back.positions) {
            for k in 0..3 {
                assert_eq!(a[k].to_bits(), b[k].to_bits());
            }
        }
        assert_eq!(back.faces, mesh.faces);
        assert_eq!(back.lines, mesh.lines);
    }

    /// Every finite f64: any bit pattern (mostly huge or tiny magnitudes), every class by
    /// proptest's float strategy (normal, subnormal, zero, both signs), cloth-sized values, and
    /// the edges.
    fn coordinate() -> impl Strategy<Value = f64> {
        use proptest::num::f64 as class;
        prop_oneof![
            any::<u64>()
                .prop_map(f64::from_bits)
                .prop_filter("finite", |v| v.is_finite()),
            class::NORMAL | class::SUBNORMAL | class::ZERO | class::POSITIVE | class::NEGATIVE,
            -2.0..2.0f64,
            prop::sample::select(vec![
                0.0,
                -0.0,
                5e-324,
                -5e-324,
                f64::MIN_POSITIVE,
                f64::MIN_POSITIVE.next_down(),
                f64::MAX,
                f64::MIN,
                1e-5,
                1e-4,
                1e15,
                1e16,
                1e21,
                9007199254740993.0,
            ]),
        ]
    }

    fn points(name: &str, positions: Vec<Vec3>) -> ClothInfo {
        ClothInfo {
            material: Default::default(),
            name: name.into(),
            offset: 0,
            mesh: Mesh {
                positions,
                faces: vec![],
                lines: vec![],
                face_uv: Vec::new(),
            },
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        #[test]
        fn written_file_reads_back_to_the_same_bits(
            coords in prop::collection::vec(coordinate(), 3..=90)
        ) {
            let x: Vec<Vec3> = coords
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect();
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("frame.obj");
            write_obj(&path, &[points("p", x.clone())], &x).unwrap();
            let back = read_obj(&path).unwrap();
            prop_assert_eq!(back.positions.len(), x.len());
            for (a, b) in x.iter().zip(&back.positions) {
                for k in 0..3 {
                    prop_assert_eq!(a[k].to_bits(), b[k].to_bits(), "{:?} came back as {:?}", a[k], b[k]);
                }
            }
        }
    }

    #[cfg(feature = "formats")]
    #[test]
    fn a_reused_writer_gives_each_frame_the_bytes_of_a_fresh_one() {
        let (cloths, frames) = crate::io::gltf::tests::sample_animation();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frame.obj");
        let mut w = ObjWriter::new(&cloths);
        // the last frames first: frame 0 (the grid at rest) has the shortest numbers, so bytes
        // left over from a longer frame would show
        for x in frames.iter().rev() {
            w.write(&path, x).unwrap();
            assert_eq!(
                std::fs::read_to_string(&path).unwrap(),
                obj_text(&cloths, x).unwrap()
            );
        }
        // the rope's segments come last, numbered over the whole file
        let text = std::fs::read_to_string(&path).unwrap();
        let tail: Vec<&str> = text.lines().rev().take(3).collect();
        assert_eq!(tail, ["l 33 34", "l 32 33", "l 31 32"]);
        let x = &frames[0][..frames[0].len() - 1];
        let short = w.write(&path, x).unwrap_err().to_string();
        assert!(
            short.contains("cloth 'rope' needs particles 30..34"),
            "{short}"
        );
    }

    #[test]
    fn tiny_and_huge_coordinates_have_exponents() {
        let x = vec![Vec3::new(-1e-7, 2.5e-300, 1e21)];
        let text = obj_text(&[points("p", x.clone())], &x).unwrap();
        assert_eq!(text, "# drapery frame\no p\nv -1e-7 2.5e-300 1e+21\n");
    }
}
