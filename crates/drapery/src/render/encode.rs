//! PNG and animated GIF encoding. GIF frames share one global palette of at most 256 colours
//! chosen by median cut over the 15-bit colour histogram of all frames (no dithering), so
//! colours do not flicker between frames.

use super::Image;
use crate::error::{Error, Result};
use std::path::Path;

fn check(img: &Image) -> Result<()> {
    if img.width == 0
        || img.height == 0
        || img.rgb.len() != img.width as usize * img.height as usize * 3
    {
        return Err(Error::Invalid(format!(
            "image {} × {} has {} bytes of RGB data",
            img.width,
            img.height,
            img.rgb.len()
        )));
    }
    Ok(())
}

/// The PNG file (8-bit RGB) of an image.
pub fn png_bytes(img: &Image) -> Result<Vec<u8>> {
    check(img)?;
    let err = |e: png::EncodingError| Error::Invalid(format!("PNG encoding failed: {e}"));
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, img.width, img.height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(err)?;
    w.write_image_data(&img.rgb).map_err(err)?;
    w.finish().map_err(err)?;
    Ok(out)
}

/// Writes an image as a PNG file (atomically).
pub fn write_png(path: &Path, img: &Image) -> Result<()> {
    let bytes = png_bytes(img)?;
    crate::io::write_atomic(path, &bytes)
}

fn key(c: &[u8]) -> usize {
    ((c[0] as usize >> 3) << 10) | ((c[1] as usize >> 3) << 5) | (c[2] as usize >> 3)
}

fn channel(key: usize, ch: usize) -> usize {
    (key >> (10 - 5 * ch)) & 31
}

/// Median cut: returns the palette (RGB triples) and the palette index of every 15-bit key.
fn palette(frames: &[Image]) -> (Vec<u8>, Vec<u8>) {
    let mut hist = vec![0u64; 1 << 15];
    for f in frames {
        for c in f.rgb.chunks_exact(3) {
            hist[key(c)] += 1;
        }
    }
    let colors: Vec<usize> = (0..hist.len()).filter(|&k| hist[k] > 0).collect();
    let mut boxes: Vec<Vec<usize>> = vec![colors];
    loop {
        if boxes.len() >= 256 {
            break;
        }
        // Split the box with the widest channel range (weighted by population).
        let mut best: Option<(usize, usize, u64)> = None;
        for (bi, b) in boxes.iter().enumerate() {
            if b.len() < 2 {
                continue;
            }
            for ch in 0..3 {
                let lo = b.iter().map(|&k| channel(k, ch)).min().unwrap_or(0);
                let hi = b.iter().map(|&k| channel(k, ch)).max().unwrap_or(0);
                let pop: u64 = b.iter().map(|&k| hist[k]).sum();
                let score = (hi - lo) as u64 * (pop as f64).sqrt() as u64 + (hi - lo) as u64;
                if hi > lo && best.is_none_or(|(_, _, s)| score > s) {
                    best = Some((bi, ch, score));
                }
            }
        }
        let Some((bi, ch, _)) = best else { break };
        let mut b = std::mem::take(&mut boxes[bi]);
        b.sort_by_key(|&k| channel(k, ch));
        let total: u64 = b.iter().map(|&k| hist[k]).sum();
        let mut acc = 0;
        let mut cut = 1;
        for (i, &k) in b.iter().enumerate() {
            acc += hist[k];
            if 2 * acc >= total {
                cut = (i + 1).clamp(1, b.len() - 1);
                break;
            }
        }
        let rest = b.split_off(cut);
        boxes[bi] = b;
        boxes.push(rest);
    }
    let mut pal = Vec::with_capacity(boxes.len() * 3);
    let mut lut = vec![0u8; 1 << 15];
    for (bi, b) in boxes.iter().enumerate() {
        let mut sum = [0u64; 3];
        let mut n = 0u64;
        for &k in b {
            for (ch, s) in sum.iter_mut().enumerate() {
                let v = channel(k, ch) as u64;
                *s += ((v << 3) | (v >> 2)) * hist[k];
            }
            n += hist[k];
            lut[k] = bi as u8;
        }
        for s in sum {
            pal.push((s / n.max(1)) as u8);
        }
    }
    if pal.is_empty() {
        pal.extend_from_slice(&[0, 0, 0]);
    }
    (pal, lut)
}

/// The animated GIF file of the frames (all the same size, at most 65535 pixels per side),
/// looping forever at `fps` frames per second (GIF delays are in 1/100 s; at least 2).
pub fn gif_bytes(frames: &[Image], fps: f64) -> Result<Vec<u8>> {
    let first = frames
        .first()
        .ok_or_else(|| Error::Invalid("GIF: no frames".into()))?;
    if !(fps > 0.0 && fps.is_finite()) {
        return Err(Error::Invalid(format!("GIF: bad frame rate {fps}")));
    }
    for f in frames {
        check(f)?;
        if (f.width, f.height) != (first.width, first.height) {
            return Err(Error::Invalid("GIF: frames differ in size".into()));
        }
    }
    let (w, h) = (first.width, first.height);
    if w > u16::MAX as u32 || h > u16::MAX as u32 {
        return Err(Error::Invalid(format!("GIF: {w} × {h} is too large")));
    }
    let err = |e: gif::EncodingError| Error::Invalid(format!("GIF encoding failed: {e}"));
    let (pal, lut) = palette(frames);
    let delay = (100.0 / fps).round().clamp(2.0, 65535.0) as u16;
    let mut out = Vec::new();
    {
        let mut enc = gif::Encoder::new(&mut out, w as u16, h as u16, &pal).map_err(err)?;
        enc.set_repeat(gif::Repeat::Infinite).map_err(err)?;
        for f in frames {
            let idx: Vec<u8> = f.rgb.chunks_exact(3).map(|c| lut[key(c)]).collect();
            let mut frame = gif::Frame::from_indexed_pixels(w as u16, h as u16, idx, None);
            frame.delay = delay;
            enc.write_frame(&frame).map_err(err)?;
        }
        enc.into_inner().map_err(err)?;
    }
    Ok(out)
}

/// Writes the frames as a looping animated GIF (atomically).
pub fn write_gif(path: &Path, frames: &[Image], fps: f64) -> Result<()> {
    let bytes = gif_bytes(frames, fps)?;
    crate::io::write_atomic(path, &bytes)
}
