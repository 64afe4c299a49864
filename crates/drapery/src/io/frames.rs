//! The frame files of a run folder: how they are named, how to find them, how to read one.
//!
//! Frame `k` of a run in a per-frame format is `DIR/frame_KKKKK.EXT` (`frame_00000.obj` is the
//! initial state; five digits at least, more past 99999), written atomically (see
//! [`crate::io::write_atomic`]): a run cut short leaves whole frame files and possibly a
//! temporary `.frame_KKKKK.EXT.tmpPID`, never a partial frame file under the frame's name.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The extensions of the per-frame formats, in the order [`find_frames`] prefers them.
pub const FRAME_EXTENSIONS: [&str; 2] = ["obj", "ply"];

/// `frame_00007.EXT`: the file name of frame `k`.
pub fn frame_name(k: usize, ext: &str) -> String {
    format!("frame_{k:05}.{ext}")
}

/// `DIR/frame_00007.EXT`: the path of frame `k` in `dir`.
pub fn frame_path(dir: &Path, k: usize, ext: &str) -> PathBuf {
    dir.join(frame_name(k, ext))
}

/// The frame number and extension of a frame file name (`frame_00012.ply` → `(12, "ply")`);
/// `None` for any other name, temporary files included.
pub fn parse_frame_name(name: &str) -> Option<(usize, &str)> {
    let (num, ext) = name.strip_prefix("frame_")?.split_once('.')?;
    if num.is_empty() || !num.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some((num.parse().ok()?, ext))
}

/// True for the files a run writes per frame in [`FRAME_EXTENSIONS`]: `frame_<digits>.obj` /
/// `.ply`, and the temporary files of atomic writes of those (`.frame_00003.obj.tmp123`), so
/// that a folder holding only the leftovers of a killed run still counts as holding a run.
pub fn is_frame_file(name: &str) -> bool {
    let name = name.strip_prefix('.').unwrap_or(name);
    let Some(rest) = name.strip_prefix("frame_") else {
        return false;
    };
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    let ext = &rest[digits..];
    digits > 0
        && FRAME_EXTENSIONS
            .iter()
            .any(|e| ext.strip_prefix('.').is_some_and(|x| x.starts_with(e)))
}

/// The frames of a run folder in one format.
#[derive(Clone, Debug, PartialEq)]
pub struct Frames {
    /// Their extension: one of [`FRAME_EXTENSIONS`].
    pub ext: &'static str,
    /// Frame number → file, in frame order (not necessarily without gaps).
    pub files: BTreeMap<usize, PathBuf>,
}

impl Frames {
    /// The highest frame number.
    pub fn last(&self) -> Option<usize> {
        self.files.keys().next_back().copied()
    }

    /// The end of the unbroken run of frames from frame 0: the highest `k` such that frames
    /// `0..=k` are all there (`None` when frame 0 is missing).
    pub fn last_complete(&self) -> Option<usize> {
        let mut last = None;
        for (i, &k) in self.files.keys().enumerate() {
            if k != i {
                break;
            }
            last = Some(k);
        }
        last
    }
}

/// The frames in `dir`: the OBJ frames, or the PLY frames when there is no OBJ frame; `None`
/// when there is neither. Other files (temporary files of atomic writes among them) are
/// ignored. An [`Error::Io`] naming `dir` when it cannot be read.
pub fn find_frames(dir: &Path) -> Result<Option<Frames>> {
    let err = |e| Error::io(dir.display(), e);
    let mut by_ext: [BTreeMap<usize, PathBuf>; 2] = Default::default();
    for e in std::fs::read_dir(dir).map_err(err)? {
        let e = e.map_err(err)?;
        let name = e.file_name().to_string_lossy().into_owned();
        let Some((k, ext)) = parse_frame_name(&name) else {
            continue;
        };
        if let Some(i) = FRAME_EXTENSIONS.iter().position(|&x| x == ext) {
            by_ext[i].insert(k, e.path());
        }
    }
    Ok(FRAME_EXTENSIONS
        .into_iter()
        .zip(by_ext)
        .find(|(_, files)| !files.is_empty())
        .map(|(ext, files)| Frames { ext, files }))
}

/// One frame file as one mesh, read by its extension: an OBJ (objects merged into one mesh)
/// or a PLY (polygons of more than four vertices fanned into triangles).
pub fn read_frame(path: &Path) -> Result<Mesh> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("obj") => crate::io::obj::read_obj(path),
        #[cfg(not(feature = "formats"))]
        Some("ply") => Err(Error::input(
            path.display(),
            "reading PLY frames needs drapery's `formats` feature",
        )),
        #[cfg(feature = "formats")]
        Some("ply") => {
            let (positions, polys) = crate::io::ply::read_ply(path)?;
            use crate::mesh::Face;
            let mut faces = Vec::with_capacity(polys.len());
            for p in polys {
                match p[..] {
                    [a, b, c] => faces.push(Face::Tri([a, b, c])),
                    [a, b, c, d] => faces.push(Face::Quad([a, b, c, d])),
                    _ if p.len() > 4 => {
                        faces.extend((1..p.len() - 1).map(|i| Face::Tri([p[0], p[i], p[i + 1]])))
                    }
                    _ => {}
                }
            }
            let n = positions.len();
            if faces
                .iter()
                .flat_map(|f| f.indices())
                .any(|&i| i as usize >= n)
            {
                return Err(Error::input(path.display(), "a face index is out of range"));
            }
            Ok(Mesh {
                positions,
                faces,
                lines: Vec::new(),
                face_uv: Vec::new(),
            })
        }
        _ => Err(Error::input(
            path.display(),
            "not a frame file (expected .obj or .ply)",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_to_their_frame_number() {
        assert_eq!(frame_name(7, "obj"), "frame_00007.obj");
        assert_eq!(frame_name(123456, "ply"), "frame_123456.ply");
        for (k, ext) in [(0, "obj"), (42, "ply"), (123456, "obj")] {
            assert_eq!(parse_frame_name(&frame_name(k, ext)), Some((k, ext)));
            assert!(is_frame_file(&frame_name(k, ext)));
        }
        for other in [
            "frame_.obj",
            "frame_12",
            "frame_1a.obj",
            "frames_00001.obj",
            "x.obj",
        ] {
            assert_eq!(parse_frame_name(other), None, "{other}");
        }
        assert_eq!(parse_frame_name(".frame_00003.obj.tmp99"), None);
        assert!(is_frame_file(".frame_00003.obj.tmp99"));
        for other in [
            "frame_00003.glb",
            "state.bin",
            "hang.usda",
            "frame_x.obj",
            "frame_1obj",
        ] {
            assert!(!is_frame_file(other), "{other}");
        }
    }

    /// A PLY frame of one triangle.
    fn triangle_ply() -> Vec<u8> {
        let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n\
property double x\nproperty double y\nproperty double z\nelement face 1\n\
property list uchar int vertex_indices\nend_header\n"
            .to_vec();
        for v in [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            for c in v {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        b.push(3);
        for i in [0i32, 1, 2] {
            b.extend_from_slice(&i.to_le_bytes());
        }
        b
    }

    #[test]
    fn a_folder_with_a_gap_and_a_partial_write_gives_its_whole_frames() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        assert_eq!(find_frames(dir).unwrap(), None);
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        for k in [0, 1, 2, 4] {
            std::fs::write(frame_path(dir, k, "obj"), obj).unwrap();
        }
        // A write cut short: the temporary file of frame 5, never renamed.
        std::fs::write(dir.join(".frame_00005.obj.tmp4242"), "v 0 0").unwrap();
        for name in ["state.bin", "frame_00009.glb", "frame_x.obj"] {
            std::fs::write(dir.join(name), "x").unwrap();
        }
        let f = find_frames(dir).unwrap().unwrap();
        assert_eq!(f.ext, "obj");
        assert_eq!(
            f.files.keys().copied().collect::<Vec<_>>(),
            vec![0, 1, 2, 4]
        );
        assert_eq!(f.files[&4], dir.join("frame_00004.obj"));
        assert_eq!((f.last(), f.last_complete()), (Some(4), Some(2)));
        let mesh = read_frame(&f.files[&1]).unwrap();
        assert_eq!((mesh.vertex_count(), mesh.faces.len()), (3, 1));

        // PLY frames are found when there is no OBJ frame.
        let ply_dir = dir.join("ply");
        std::fs::create_dir(&ply_dir).unwrap();
        std::fs::write(frame_path(&ply_dir, 1, "ply"), triangle_ply()).unwrap();
        let f = find_frames(&ply_dir).unwrap().unwrap();
        assert_eq!((f.ext, f.last(), f.last_complete()), ("ply", Some(1), None));
        if cfg!(feature = "formats") {
            let mesh = read_frame(&f.files[&1]).unwrap();
            assert_eq!((mesh.vertex_count(), mesh.faces.len()), (3, 1));
        } else {
            let e = read_frame(&f.files[&1]).unwrap_err().to_string();
            assert!(e.contains("`formats` feature"), "{e}");
        }

        let e = find_frames(&dir.join("missing")).unwrap_err();
        assert!(matches!(e, Error::Io { .. }), "{e}");
        let e = read_frame(&dir.join("state.bin")).unwrap_err().to_string();
        assert!(e.contains("state.bin") && e.contains(".obj or .ply"), "{e}");
    }
}
