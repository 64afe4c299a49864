//! PC2 point caches (`POINTCACHE2`), the vertex animation format that Blender's Mesh Cache
//! modifier and 3ds Max's Point Cache modifier read: one file per mesh, every sample holding
//! every vertex's position.
//!
//! Layout (little endian):
//!
//! ```text
//! offset  type      field
//!  0      char[12]  signature "POINTCACHE2\0"
//! 12      i32       version, 1
//! 16      i32       number of points (vertices) per sample
//! 20      f32       start frame: the frame of sample 0
//! 24      f32       sample rate: frames between two samples
//! 28      i32       number of samples
//! 32      f32 × 3 × points × samples: x, y, z of point 0, 1, … of sample 0, then sample 1, …
//! ```
//!
//! Start frame and sample rate are in frames of the application playing the cache (Blender's
//! reader takes sample `(frame − start) / rate` in its time mode); a cache with a sample per
//! output frame has start 0 and rate 1.
//!
//! [`Pc2Writer`] grows a file sample by sample and keeps it valid whenever the process is
//! killed: [`Pc2Writer::append`] writes the sample's data, then the new sample count into the
//! header, so the header never counts a sample that is not wholly in the file (bytes past the
//! counted samples are ignored by readers and cut by [`Pc2Writer::open`]).

use crate::error::{Error, Result};
use crate::math::Vec3;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The first 12 bytes of a PC2 file.
pub const SIGNATURE: &[u8; 12] = b"POINTCACHE2\0";
/// The only version there is.
pub const VERSION: i32 = 1;
/// Bytes before the first sample.
pub const HEADER_LEN: u64 = 32;
/// Offset of the sample count in the header.
const SAMPLES_AT: u64 = 28;

/// The header fields of a PC2 file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pc2Header {
    /// Points (vertices) per sample.
    pub points: usize,
    /// The frame of sample 0.
    pub start_frame: f32,
    /// Frames between two samples.
    pub sample_rate: f32,
    /// Samples the file holds.
    pub samples: usize,
}

impl Pc2Header {
    fn to_bytes(self) -> [u8; HEADER_LEN as usize] {
        let mut b = [0u8; HEADER_LEN as usize];
        b[..12].copy_from_slice(SIGNATURE);
        b[12..16].copy_from_slice(&VERSION.to_le_bytes());
        b[16..20].copy_from_slice(&(self.points as i32).to_le_bytes());
        b[20..24].copy_from_slice(&self.start_frame.to_le_bytes());
        b[24..28].copy_from_slice(&self.sample_rate.to_le_bytes());
        b[28..32].copy_from_slice(&(self.samples as i32).to_le_bytes());
        b
    }

    /// Reads and checks the header (signature, version, counts).
    fn parse(b: &[u8; HEADER_LEN as usize], path: &Path) -> Result<Pc2Header> {
        let bad = |m: String| Error::input(path.display(), m);
        if &b[..12] != SIGNATURE {
            return Err(bad(format!(
                "not a PC2 point cache: the signature is {:?}, expected \"POINTCACHE2\\0\"",
                String::from_utf8_lossy(&b[..12])
            )));
        }
        let i32_at = |at: usize| i32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
        let f32_at = |at: usize| f32::from_bits(i32_at(at) as u32);
        let version = i32_at(12);
        if version != VERSION {
            return Err(bad(format!(
                "PC2 version {version} is not supported (only version {VERSION})"
            )));
        }
        let count = |at: usize, what: &str| {
            usize::try_from(i32_at(at))
                .map_err(|_| bad(format!("the header's {what} is negative ({})", i32_at(at))))
        };
        Ok(Pc2Header {
            points: count(16, "number of points")?,
            start_frame: f32_at(20),
            sample_rate: f32_at(24),
            samples: count(28, "number of samples")?,
        })
    }

    /// Bytes of one sample.
    fn sample_len(&self) -> u64 {
        self.points as u64 * 12
    }

    /// The file length with `samples` samples; `None` beyond u64.
    fn len_with(&self, samples: usize) -> Option<u64> {
        (samples as u64)
            .checked_mul(self.sample_len())?
            .checked_add(HEADER_LEN)
    }
}

/// A PC2 file read whole: its header and its samples (`samples[s][i]` is point `i` of sample `s`).
#[derive(Clone, Debug, PartialEq)]
pub struct Pc2 {
    /// The header.
    pub header: Pc2Header,
    /// The samples the header counts, each with `header.points` positions.
    pub samples: Vec<Vec<[f32; 3]>>,
}

/// Opens `path`, reads and checks its header, and checks that the file holds every sample the
/// header counts. Returns the file positioned after the header.
fn open_checked(path: &Path, write: bool) -> Result<(File, Pc2Header)> {
    let io = |e| Error::io(path.display(), e);
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .write(write)
        .open(path)
        .map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    if len < HEADER_LEN {
        return Err(Error::input(
            path.display(),
            format!(
                "not a PC2 point cache: {len} bytes, shorter than the {HEADER_LEN}-byte header"
            ),
        ));
    }
    let mut raw = [0u8; HEADER_LEN as usize];
    file.read_exact(&mut raw).map_err(io)?;
    let header = Pc2Header::parse(&raw, path)?;
    let need = header.len_with(header.samples);
    if need.is_none_or(|need| len < need) {
        let whole = (len - HEADER_LEN) / header.sample_len().max(1);
        return Err(Error::input(
            path.display(),
            format!(
                "the header counts {} samples of {} points but the file holds only {whole} whole samples",
                header.samples, header.points
            ),
        ));
    }
    Ok((file, header))
}

/// Reads a PC2 file: the header and the samples it counts (bytes past them are ignored, as
/// every reader does). Errors name the file: a bad signature or version, a header counting more
/// samples than the file holds.
pub fn read_pc2(path: &Path) -> Result<Pc2> {
    let (mut file, header) = open_checked(path, false)?;
    let mut raw = vec![0u8; (header.len_with(header.samples).unwrap_or(0) - HEADER_LEN) as usize];
    file.read_exact(&mut raw)
        .map_err(|e| Error::io(path.display(), e))?;
    let f32s = |c: &[u8]| f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
    let len = header.sample_len() as usize;
    let samples = (0..header.samples)
        .map(|s| {
            raw[s * len..(s + 1) * len]
                .chunks_exact(12)
                .map(|p| [f32s(&p[0..4]), f32s(&p[4..8]), f32s(&p[8..12])])
                .collect()
        })
        .collect();
    Ok(Pc2 { header, samples })
}

/// A PC2 file being written sample by sample (see the module documentation).
#[derive(Debug)]
pub struct Pc2Writer {
    path: PathBuf,
    file: File,
    header: Pc2Header,
}

impl Pc2Writer {
    /// Creates (or replaces) `path` as a cache of `points` points with no sample yet. The
    /// header is written whole or not at all.
    pub fn create(
        path: &Path,
        points: usize,
        start_frame: f32,
        sample_rate: f32,
    ) -> Result<Pc2Writer> {
        let invalid = |m: String| Err(Error::Invalid(format!("{}: {m}", path.display())));
        if points > i32::MAX as usize {
            return invalid(format!(
                "{points} points are too many for PC2 (at most 2^31 − 1)"
            ));
        }
        if !(start_frame.is_finite() && sample_rate.is_finite() && sample_rate > 0.0) {
            return invalid(format!(
                "start frame {start_frame} and sample rate {sample_rate}: both must be finite, the rate > 0"
            ));
        }
        let header = Pc2Header {
            points,
            start_frame,
            sample_rate,
            samples: 0,
        };
        super::write_atomic(path, &header.to_bytes())?;
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(|e| Error::io(path.display(), e))?;
        Ok(Pc2Writer {
            path: path.to_path_buf(),
            file,
            header,
        })
    }

    /// Opens an existing cache to append to it. Checks the signature, the version and that it
    /// holds `points` points per sample; keeps the samples its header counts, or only the first
    /// `keep` of them (an error when it has fewer), and cuts the file after them. The sample
    /// count is lowered before the file is cut, so the file stays valid if killed in between.
    pub fn open(path: &Path, points: usize, keep: Option<usize>) -> Result<Pc2Writer> {
        let (file, header) = open_checked(path, true)?;
        if header.points != points {
            return Err(Error::input(
                path.display(),
                format!(
                    "holds {} points per sample, expected {points}",
                    header.points
                ),
            ));
        }
        let keep = keep.unwrap_or(header.samples);
        if keep > header.samples {
            return Err(Error::input(
                path.display(),
                format!("holds {} samples, {keep} are needed", header.samples),
            ));
        }
        let mut w = Pc2Writer {
            path: path.to_path_buf(),
            file,
            header,
        };
        if keep < header.samples {
            w.write_count(keep)?;
            w.header.samples = keep;
        }
        let len = header.len_with(keep).unwrap_or(HEADER_LEN);
        w.file
            .set_len(len)
            .and_then(|()| w.file.sync_all())
            .map_err(|e| Error::io(path.display(), e))?;
        Ok(w)
    }

    /// Appends one sample: the f32 of `x` (one position per point), then the sample count.
    pub fn append(&mut self, x: &[Vec3]) -> Result<()> {
        let invalid = |m: String| Err(Error::Invalid(format!("{}: {m}", self.path.display())));
        if x.len() != self.header.points {
            return invalid(format!(
                "a sample of {} points for a cache of {}",
                x.len(),
                self.header.points
            ));
        }
        let samples = self.header.samples + 1;
        let Some(end) = self
            .header
            .len_with(samples)
            .filter(|_| samples <= i32::MAX as usize)
        else {
            return invalid("too many samples for PC2 (at most 2^31 − 1)".into());
        };
        let mut raw = Vec::with_capacity(self.header.sample_len() as usize);
        for (i, p) in x.iter().enumerate() {
            let f = p.as_vec3();
            if !f.is_finite() {
                return invalid(format!(
                    "sample {}: point {i} ({}, {}, {}) is not finite as f32",
                    self.header.samples, p.x, p.y, p.z
                ));
            }
            for c in [f.x, f.y, f.z] {
                raw.extend_from_slice(&c.to_le_bytes());
            }
        }
        let at = end - self.header.sample_len();
        self.file
            .seek(SeekFrom::Start(at))
            .and_then(|_| self.file.write_all(&raw))
            .and_then(|()| self.file.sync_data())
            .map_err(|e| Error::io(self.path.display(), e))?;
        self.write_count(samples)?;
        self.header.samples = samples;
        Ok(())
    }

    /// Rewrites the sample count in the header (synced).
    fn write_count(&mut self, samples: usize) -> Result<()> {
        self.file
            .seek(SeekFrom::Start(SAMPLES_AT))
            .and_then(|_| self.file.write_all(&(samples as i32).to_le_bytes()))
            .and_then(|()| self.file.sync_data())
            .map_err(|e| Error::io(self.path.display(), e))
    }

    /// The header as it is on disk.
    pub fn header(&self) -> Pc2Header {
        self.header
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn i32_at(b: &[u8], at: usize) -> i32 {
        i32::from_le_bytes(b[at..at + 4].try_into().unwrap())
    }

    fn f32_at(b: &[u8], at: usize) -> f32 {
        f32::from_le_bytes(b[at..at + 4].try_into().unwrap())
    }

    /// `s` samples of `n` points, distinct in every coordinate.
    fn frames(s: usize, n: usize) -> Vec<Vec<Vec3>> {
        (0..s)
            .map(|k| {
                (0..n)
                    .map(|i| Vec3::new(i as f64 / 3.0, -(k as f64) / 7.0, 1e-3 * (i * k) as f64))
                    .collect()
            })
            .collect()
    }

    fn write(path: &Path, frames: &[Vec<Vec3>]) -> Pc2Writer {
        let mut w = Pc2Writer::create(path, frames[0].len(), 0.0, 1.0).unwrap();
        for x in frames {
            w.append(x).unwrap();
        }
        w
    }

    fn f32_of(x: &[Vec3]) -> Vec<[f32; 3]> {
        x.iter()
            .map(|p| [p.x as f32, p.y as f32, p.z as f32])
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        /// Random positions come back as their f32 (round to nearest), bit for bit, and the
        /// header bytes are where the format puts them.
        #[test]
        fn samples_round_trip_to_f32_and_the_header_is_the_format(
            xs in prop::collection::vec(
                prop::collection::vec(
                    (-1e3f64..1e3, -1e-3f64..1e-3, prop::num::f64::NORMAL.prop_filter("f32 range", |v| v.abs() < 1e30)),
                    5,
                ),
                1..5,
            ),
            start in -100.0f32..100.0,
            rate in 0.01f32..10.0,
        ) {
            let tmp = tempfile::tempdir().unwrap();
            let path = tmp.path().join("c.pc2");
            let frames: Vec<Vec<Vec3>> = xs
                .iter()
                .map(|f| f.iter().map(|&(a, b, c)| Vec3::new(a, b, c)).collect())
                .collect();
            let mut w = Pc2Writer::create(&path, 5, start, rate).unwrap();
            for x in &frames {
                w.append(x).unwrap();
            }
            let b = std::fs::read(&path).unwrap();
            prop_assert_eq!(&b[..12], b"POINTCACHE2\0");
            prop_assert_eq!(i32_at(&b, 12), 1);
            prop_assert_eq!(i32_at(&b, 16), 5);
            prop_assert_eq!(f32_at(&b, 20).to_bits(), start.to_bits());
            prop_assert_eq!(f32_at(&b, 24).to_bits(), rate.to_bits());
            prop_assert_eq!(i32_at(&b, 28) as usize, frames.len());
            prop_assert_eq!(b.len(), 32 + frames.len() * 5 * 12);
            // The data, read straight from the bytes: sample s, point i, coordinate c.
            for (s, x) in frames.iter().enumerate() {
                for (i, p) in x.iter().enumerate() {
                    for c in 0..3 {
                        let got = f32_at(&b, 32 + (s * 5 + i) * 12 + 4 * c);
                        prop_assert_eq!(got.to_bits(), (p[c] as f32).to_bits());
                    }
                }
            }
            let r = read_pc2(&path).unwrap();
            prop_assert_eq!(r.header, w.header());
            prop_assert_eq!(r.header, Pc2Header { points: 5, start_frame: start, sample_rate: rate, samples: frames.len() });
            let want: Vec<Vec<[f32; 3]>> = frames.iter().map(|x| f32_of(x)).collect();
            prop_assert_eq!(r.samples, want);
        }
    }

    #[test]
    fn a_new_cache_has_no_sample_and_a_cache_of_no_points_counts_its_samples() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("a.pc2");
        let mut w = Pc2Writer::create(&path, 3, 0.0, 1.0).unwrap();
        assert_eq!(std::fs::metadata(&path).unwrap().len(), 32);
        assert_eq!(read_pc2(&path).unwrap().samples.len(), 0);
        w.append(&frames(1, 3)[0]).unwrap();
        assert_eq!(read_pc2(&path).unwrap().samples.len(), 1);

        let empty = tmp.path().join("empty.pc2");
        let mut w = Pc2Writer::create(&empty, 0, 0.0, 1.0).unwrap();
        w.append(&[]).unwrap();
        w.append(&[]).unwrap();
        let r = read_pc2(&empty).unwrap();
        assert_eq!((r.header.samples, r.samples.len()), (2, 2));
    }

    /// A kill inside `append` leaves the new sample's bytes (or part of them) after the samples
    /// the header counts: readers see the whole samples only, and `open` cuts the rest.
    #[test]
    fn a_file_cut_in_the_middle_of_a_sample_reopens_to_its_whole_samples() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("c.pc2");
        let n = 7;
        let all = frames(5, n);
        drop(write(&path, &all[..3]));
        let whole = std::fs::read(&path).unwrap();
        assert_eq!(whole.len(), 32 + 3 * n * 12);
        // Half of sample 3 written, the count not yet updated (what a kill there leaves).
        let mut cut = whole.clone();
        cut.extend(std::iter::repeat_n(0x5a, n * 12 / 2));
        std::fs::write(&path, &cut).unwrap();
        let r = read_pc2(&path).unwrap();
        assert_eq!(r.header.samples, 3);
        assert_eq!(
            r.samples,
            all[..3].iter().map(|x| f32_of(x)).collect::<Vec<_>>()
        );

        let mut w = Pc2Writer::open(&path, n, None).unwrap();
        assert_eq!(w.header().samples, 3);
        assert_eq!(
            std::fs::read(&path).unwrap(),
            whole,
            "the partial sample is cut"
        );
        w.append(&all[3]).unwrap();
        w.append(&all[4]).unwrap();
        drop(w);
        let mut fresh = tmp.path().join("fresh.pc2");
        drop(write(&fresh, &all));
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(&fresh).unwrap()
        );

        // Resuming at an earlier frame keeps the first `keep` samples only.
        let w = Pc2Writer::open(&path, n, Some(2)).unwrap();
        assert_eq!(w.header().samples, 2);
        assert_eq!(std::fs::read(&path).unwrap().len(), 32 + 2 * n * 12);
        fresh = tmp.path().join("two.pc2");
        drop(write(&fresh, &all[..2]));
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(&fresh).unwrap()
        );
        // More than it holds is an error, and changes nothing.
        let e = Pc2Writer::open(&path, n, Some(3)).unwrap_err().to_string();
        assert!(
            e.contains("c.pc2") && e.contains("holds 2 samples, 3 are needed"),
            "{e}"
        );
        assert_eq!(
            std::fs::read(&path).unwrap(),
            std::fs::read(&fresh).unwrap()
        );
    }

    #[test]
    fn bad_files_are_errors_naming_the_file() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("bad.pc2");
        let n = 4;
        drop(write(&path, &frames(2, n)));
        let good = std::fs::read(&path).unwrap();
        let expect = |bytes: &[u8], points: usize, wants: &[&str]| {
            std::fs::write(&path, bytes).unwrap();
            let read = read_pc2(&path).map(|_| ());
            let open = Pc2Writer::open(&path, points, None).map(|_| ());
            for e in [read, open] {
                let e = e.unwrap_err().to_string();
                assert!(e.starts_with(&path.display().to_string()), "{e}");
                for w in wants {
                    assert!(e.contains(w), "{e:?} lacks {w:?}");
                }
            }
            assert_eq!(
                std::fs::read(&path).unwrap(),
                bytes,
                "a refused file is left alone"
            );
        };
        let mut b = good.clone();
        b[..12].copy_from_slice(b"POINTCACHE3\0");
        expect(&b, n, &["signature", "POINTCACHE3"]);
        let mut b = good.clone();
        b[11] = b' '; // no NUL terminator: Blender's reader compares the C string
        expect(&b, n, &["signature"]);
        let mut b = good.clone();
        b[12..16].copy_from_slice(&2i32.to_le_bytes());
        expect(&b, n, &["version 2"]);
        let mut b = good.clone();
        b[28..32].copy_from_slice(&3i32.to_le_bytes());
        expect(&b, n, &["counts 3 samples", "only 2 whole samples"]);
        let mut b = good.clone();
        b[16..20].copy_from_slice(&(-1i32).to_le_bytes());
        expect(&b, n, &["number of points is negative"]);
        expect(&good[..20], n, &["shorter than the 32-byte header"]);
        // A valid file of another point count can be read but not continued.
        std::fs::write(&path, &good).unwrap();
        assert_eq!(read_pc2(&path).unwrap().header.points, n);
        let e = Pc2Writer::open(&path, n + 1, None).unwrap_err().to_string();
        assert!(e.starts_with(&path.display().to_string()), "{e}");
        assert!(e.contains("holds 4 points per sample, expected 5"), "{e}");
        // A missing file: an I/O error naming it.
        let e = read_pc2(&tmp.path().join("none.pc2"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("none.pc2"), "{e}");
    }

    #[test]
    fn wrong_samples_are_refused_before_anything_is_written() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("c.pc2");
        let mut w = write(&path, &frames(1, 3));
        let before = std::fs::read(&path).unwrap();
        let e = w.append(&frames(1, 2)[0]).unwrap_err().to_string();
        assert!(
            e.contains("c.pc2") && e.contains("2 points for a cache of 3"),
            "{e}"
        );
        let e = w
            .append(&[Vec3::ZERO, Vec3::new(0.0, 1e39, 0.0), Vec3::ZERO])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("point 1") && e.contains("not finite as f32"),
            "{e}"
        );
        assert_eq!(std::fs::read(&path).unwrap(), before);
        assert_eq!(w.header().samples, 1);
        assert!(Pc2Writer::create(&path, 3, 0.0, 0.0).is_err());
    }
}
