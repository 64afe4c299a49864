//! PLY frame caches: one binary little-endian PLY file per frame (`DIR/frame_00000.ply`, …).
//!
//! Layout written by [`write_ply`]:
//!
//! ```text
//! ply
//! format binary_little_endian 1.0
//! comment drapery cloth frame
//! comment cloth <name> <first vertex> <vertex count>      (one line per cloth)
//! element vertex N
//! property double x
//! property double y
//! property double z
//! element face F
//! property list uchar int vertex_indices
//! element edge E                                          (only when some cloth has lines)
//! property int vertex1
//! property int vertex2
//! end_header
//! ```
//!
//! All cloths go into one file: vertices are the global particle array (cloth after cloth, so
//! face indices are global), faces keep their polygon (3 or 4 vertices), and line elements are
//! written as the conventional `edge` element (`vertex1`, `vertex2`) when there are any.
//! Positions are written at full f64 precision.

use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::model::ClothInfo;
use std::path::Path;

/// Checks that every cloth's particle range lies inside `x`; returns the particle count used.
pub(crate) fn check_ranges(cloths: &[ClothInfo], len: usize, what: &str) -> Result<()> {
    for c in cloths {
        let r = c.range();
        if r.end > len {
            return Err(Error::Invalid(format!(
                "{what}: cloth '{}' needs particles {}..{} but the frame has {len}",
                c.name, r.start, r.end
            )));
        }
    }
    Ok(())
}

/// Writes one frame as a binary little-endian PLY file (see the module documentation).
/// `x` is the global position array; it must cover every cloth's particle range.
pub fn write_ply(path: &Path, cloths: &[ClothInfo], x: &[Vec3]) -> Result<()> {
    check_ranges(cloths, x.len(), &path.display().to_string())?;
    if x.len() > i32::MAX as usize {
        return Err(Error::Invalid(format!(
            "{}: too many vertices for PLY int indices",
            path.display()
        )));
    }
    let face_count: usize = cloths.iter().map(|c| c.mesh.faces.len()).sum();
    let edge_count: usize = cloths.iter().map(|c| c.mesh.lines.len()).sum();
    let mut header =
        String::from("ply\nformat binary_little_endian 1.0\ncomment drapery cloth frame\n");
    for c in cloths {
        // Names contain no white space (the model checks), but stay safe for foreign input.
        let name: String = c
            .name
            .chars()
            .map(|ch| {
                if ch.is_whitespace() || ch.is_control() {
                    '_'
                } else {
                    ch
                }
            })
            .collect();
        header.push_str(&format!(
            "comment cloth {name} {} {}\n",
            c.offset,
            c.mesh.positions.len()
        ));
    }
    header.push_str(&format!(
        "element vertex {}\nproperty double x\nproperty double y\nproperty double z\n",
        x.len()
    ));
    header.push_str(&format!(
        "element face {face_count}\nproperty list uchar int vertex_indices\n"
    ));
    if edge_count > 0 {
        header.push_str(&format!(
            "element edge {edge_count}\nproperty int vertex1\nproperty int vertex2\n"
        ));
    }
    header.push_str("end_header\n");

    let mut out = Vec::with_capacity(header.len() + x.len() * 24 + face_count * 17);
    out.extend_from_slice(header.as_bytes());
    for p in x {
        for v in [p.x, p.y, p.z] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    for c in cloths {
        let n = c.mesh.positions.len();
        for (fi, f) in c.mesh.faces.iter().enumerate() {
            let idx = f.indices();
            out.push(idx.len() as u8);
            for &v in idx {
                if v as usize >= n {
                    return Err(Error::Invalid(format!(
                        "cloth '{}': face {} refers to vertex {v} but the mesh has {n}",
                        c.name,
                        fi + 1
                    )));
                }
                out.extend_from_slice(&((v as usize + c.offset) as i32).to_le_bytes());
            }
        }
    }
    for c in cloths {
        let n = c.mesh.positions.len();
        for l in &c.mesh.lines {
            for &v in l {
                if v as usize >= n {
                    return Err(Error::Invalid(format!(
                        "cloth '{}': a line element refers to vertex {v} but the mesh has {n}",
                        c.name
                    )));
                }
                out.extend_from_slice(&((v as usize + c.offset) as i32).to_le_bytes());
            }
        }
    }
    super::write_atomic(path, &out)
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
}

#[derive(Debug)]
struct Property {
    name: String,
    /// `Some(count type)` for a list property.
    list: Option<Scalar>,
    ty: Scalar,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
}

impl Cursor<'_> {
    fn read(&mut self, ty: Scalar) -> Option<f64> {
        let n = ty.size();
        let b = self.data.get(self.pos..self.pos + n)?;
        self.pos += n;
        Some(match ty {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        })
    }
}

/// Reads a binary little-endian PLY file: the `vertex` element's `x`, `y`, `z` and the `face`
/// element's vertex index lists (`vertex_indices` or `vertex_index`). Other elements and
/// properties are skipped. Meant for round trips of [`write_ply`] output and simple foreign files.
pub fn read_ply(path: &Path) -> Result<(Vec<Vec3>, Vec<Vec<u32>>)> {
    let data = std::fs::read(path).map_err(|e| Error::io(path.display(), e))?;
    parse_ply(&data).map_err(|m| Error::input(path.display(), m))
}

fn parse_ply(data: &[u8]) -> std::result::Result<(Vec<Vec3>, Vec<Vec<u32>>), String> {
    const END: &[u8] = b"end_header";
    let end = data
        .windows(END.len())
        .position(|w| w == END)
        .ok_or("no end_header line")?;
    let mut body = end + END.len();
    if data.get(body) == Some(&b'\r') {
        body += 1;
    }
    if data.get(body) != Some(&b'\n') {
        return Err("end_header is not followed by a newline".into());
    }
    body += 1;
    let header = std::str::from_utf8(&data[..end]).map_err(|_| "header is not UTF-8")?;
    let mut lines = header.lines().map(str::trim);
    if lines.next() != Some("ply") {
        return Err("not a PLY file (first line is not 'ply')".into());
    }
    let mut elements: Vec<Element> = Vec::new();
    let mut format_ok = false;
    for (no, line) in lines.enumerate() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let bad = || format!("header line {}: cannot read '{line}'", no + 2);
        match words.first().copied() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                if words.get(1) != Some(&"binary_little_endian") {
                    return Err(format!(
                        "unsupported PLY format '{}' (only binary_little_endian is read)",
                        words.get(1).unwrap_or(&"")
                    ));
                }
                format_ok = true;
            }
            Some("element") => {
                let (Some(name), Some(count), None) = (words.get(1), words.get(2), words.get(3))
                else {
                    return Err(bad());
                };
                let count = count.parse::<usize>().map_err(|_| bad())?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let el = elements.last_mut().ok_or_else(bad)?;
                let prop = if words.get(1) == Some(&"list") {
                    let (Some(ct), Some(it), Some(name)) =
                        (words.get(2), words.get(3), words.get(4))
                    else {
                        return Err(bad());
                    };
                    Property {
                        name: name.to_string(),
                        list: Some(Scalar::parse(ct).ok_or_else(bad)?),
                        ty: Scalar::parse(it).ok_or_else(bad)?,
                    }
                } else {
                    let (Some(ty), Some(name)) = (words.get(1), words.get(2)) else {
                        return Err(bad());
                    };
                    Property {
                        name: name.to_string(),
                        list: None,
                        ty: Scalar::parse(ty).ok_or_else(bad)?,
                    }
                };
                el.props.push(prop);
            }
            Some(_) => return Err(bad()),
        }
    }
    if !format_ok {
        return Err("no format line in the header".into());
    }
    let mut cur = Cursor { data, pos: body };
    let short = || "file is shorter than its header says".to_string();
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    for el in &elements {
        let xyz: Vec<Option<usize>> = ["x", "y", "z"]
            .iter()
            .map(|n| {
                el.props
                    .iter()
                    .position(|p| p.name == *n && p.list.is_none())
            })
            .collect();
        let face_prop = el.props.iter().position(|p| {
            p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index")
        });
        let is_vertex = el.name == "vertex";
        let is_face = el.name == "face";
        if is_vertex && xyz.iter().any(Option::is_none) {
            return Err("the vertex element lacks an x, y or z property".into());
        }
        // Bound the reservation by what the file could possibly hold.
        let cap = el.count.min(data.len());
        if is_vertex {
            positions.reserve(cap);
        }
        if is_face {
            faces.reserve(cap);
        }
        for _ in 0..el.count {
            let mut p = [0.0f64; 3];
            for (pi, prop) in el.props.iter().enumerate() {
                match prop.list {
                    None => {
                        let v = cur.read(prop.ty).ok_or_else(short)?;
                        if is_vertex {
                            for (k, slot) in xyz.iter().enumerate() {
                                if *slot == Some(pi) {
                                    p[k] = v;
                                }
                            }
                        }
                    }
                    Some(ct) => {
                        let n = cur.read(ct).ok_or_else(short)?;
                        if !(n >= 0.0 && n <= u32::MAX as f64) {
                            return Err(format!("bad list length {n} in element '{}'", el.name));
                        }
                        let n = n as usize;
                        let keep = is_face && face_prop == Some(pi);
                        let mut list = Vec::with_capacity(if keep { n.min(64) } else { 0 });
                        for _ in 0..n {
                            let v = cur.read(prop.ty).ok_or_else(short)?;
                            if keep {
                                if !(v >= 0.0 && v <= u32::MAX as f64 && v.fract() == 0.0) {
                                    return Err(format!("bad vertex index {v} in a face"));
                                }
                                list.push(v as u32);
                            }
                        }
                        if keep {
                            faces.push(list);
                        }
                    }
                }
            }
            if is_vertex {
                positions.push(Vec3::from_array(p));
            }
        }
    }
    for (fi, f) in faces.iter().enumerate() {
        if let Some(&v) = f.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(format!(
                "face {} refers to vertex {v} but there are {} vertices",
                fi + 1,
                positions.len()
            ));
        }
    }
    Ok((positions, faces))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Face, Mesh};

    fn cloths() -> (Vec<ClothInfo>, Vec<Vec3>) {
        let a = Mesh::grid([1.0, 1.0], [3, 3], Vec3::ZERO, Vec3::Z).unwrap();
        let b = Mesh {
            positions: vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE],
            faces: vec![Face::Tri([0, 1, 2])],
            lines: vec![[2, 3]],
            face_uv: Vec::new(),
        };
        let mut x = a.positions.clone();
        x.extend_from_slice(&b.positions);
        // Move things a bit so the frame differs from the rest shape.
        for (i, p) in x.iter_mut().enumerate() {
            *p += Vec3::new(0.1 * i as f64, -1.0 / 3.0, 1e-9 * i as f64);
        }
        let infos = vec![
            ClothInfo {
                material: Default::default(),
                name: "a".into(),
                offset: 0,
                mesh: a,
            },
            ClothInfo {
                material: Default::default(),
                name: "b".into(),
                offset: 9,
                mesh: b,
            },
        ];
        (infos, x)
    }

    #[test]
    fn written_frame_reads_back_exactly_with_global_face_indices() {
        let (infos, x) = cloths();
        let dir = tempfile::tempdir().unwrap();
        let path = crate::io::frames::frame_path(dir.path(), 7, "ply");
        assert!(path.ends_with("frame_00007.ply"));
        write_ply(&path, &infos, &x).unwrap();
        let (pos, faces) = read_ply(&path).unwrap();
        assert_eq!(pos, x);
        assert_eq!(faces.len(), 4 + 1);
        assert_eq!(faces[0], infos[0].mesh.faces[0].indices().to_vec());
        assert_eq!(faces[4], vec![9, 10, 11]);
        let text = std::fs::read(&path).unwrap();
        let head = String::from_utf8_lossy(&text[..300]);
        assert!(head.contains("format binary_little_endian 1.0"));
        assert!(head.contains("element edge 1"));
    }

    #[test]
    fn short_frames_and_garbage_are_errors_not_panics() {
        let (infos, x) = cloths();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.ply");
        assert!(write_ply(&path, &infos, &x[..5]).is_err());
        write_ply(&path, &infos, &x).unwrap();
        let full = std::fs::read(&path).unwrap();
        for cut in [0, 3, 50, full.len() / 2, full.len() - 1] {
            std::fs::write(&path, &full[..cut]).unwrap();
            assert!(read_ply(&path).is_err(), "cut at {cut}");
        }
        std::fs::write(&path, b"ply\nformat ascii 1.0\nend_header\n").unwrap();
        assert!(read_ply(&path).is_err());
        std::fs::write(&path, b"ply\nformat binary_little_endian 1.0\nelement vertex 99999999999\nproperty double x\nend_header\n").unwrap();
        assert!(read_ply(&path).is_err());
    }
}
