//! Pictures of the frames: a small z-buffer triangle rasterizer with Gouraud-shaded Lambert
//! lighting from a head light (the light sits at the camera), cloth front faces in one colour and
//! back faces in another (front = counter-clockwise as seen from the camera, the mesh winding
//! convention), colliders in grey, cloth line elements as dark lines, over a vertical background
//! gradient; 2×2 supersampled. Encoded as PNG or animated GIF ([`write_png`], [`write_gif`]).

mod camera;
mod encode;
mod raster;

pub use camera::{AUTO_FOV_Y_DEG, Camera, bounds};
pub use encode::{gif_bytes, png_bytes, write_gif, write_png};

use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::model::ClothInfo;
use raster::{Target, Vertex};

/// An 8-bit RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` RGB triples.
    pub rgb: Vec<u8>,
}

impl Image {
    /// The pixel at column `x`, row `y` (black outside the image).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        if x >= self.width || y >= self.height {
            return [0; 3];
        }
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }
}

/// How a mesh is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshKind {
    /// Cloth: [`FRONT_COLOR`] / [`BACK_COLOR`] by facing.
    Cloth,
    /// Collider: [`COLLIDER_COLOR`] on both sides.
    Collider,
}

/// Cloth front-face colour (linear RGB, 0..1).
pub const FRONT_COLOR: [f32; 3] = [0.92, 0.48, 0.22];
/// Cloth back-face colour.
pub const BACK_COLOR: [f32; 3] = [0.24, 0.52, 0.86];
/// Collider colour.
pub const COLLIDER_COLOR: [f32; 3] = [0.62, 0.62, 0.60];
/// Line-element colour.
pub const LINE_COLOR: [f32; 3] = [0.15, 0.15, 0.18];

/// One mesh to draw.
#[derive(Clone, Debug)]
pub struct RenderMesh {
    /// How it is coloured.
    pub kind: MeshKind,
    /// Vertex positions, m.
    pub positions: Vec<Vec3>,
    /// Triangles (counter-clockwise = front).
    pub triangles: Vec<[u32; 3]>,
    /// Line segments.
    pub lines: Vec<[u32; 2]>,
}

/// Everything drawn in one picture.
#[derive(Clone, Debug, Default)]
pub struct RenderScene {
    /// The meshes.
    pub meshes: Vec<RenderMesh>,
}

impl RenderScene {
    /// The cloths at one frame (`x` = the global position array; quads split in two).
    pub fn from_frame(cloths: &[ClothInfo], x: &[Vec3]) -> Result<RenderScene> {
        crate::io::ply::check_ranges(cloths, x.len(), "render")?;
        Ok(RenderScene {
            meshes: cloths
                .iter()
                .map(|c| RenderMesh {
                    kind: MeshKind::Cloth,
                    positions: x[c.range()].to_vec(),
                    triangles: c.mesh.triangles(),
                    lines: c.mesh.lines.clone(),
                })
                .collect(),
        })
    }

    /// Adds a collider mesh.
    pub fn add_collider(&mut self, positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) {
        self.meshes.push(RenderMesh {
            kind: MeshKind::Collider,
            positions,
            triangles,
            lines: Vec::new(),
        });
    }

    /// Bounding box of every finite vertex.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        bounds(self.meshes.iter().flat_map(|m| &m.positions))
    }
}

/// Supersampling factor per axis.
const SUPERSAMPLE: usize = 2;
/// Largest image side accepted, pixels.
pub const MAX_SIDE: u32 = 16384;

fn background(t: f64) -> [f32; 3] {
    let top = [0.96, 0.97, 0.99];
    let bottom = [0.74, 0.77, 0.82];
    [0, 1, 2].map(|k| (top[k] + (bottom[k] - top[k]) * t) as f32)
}

/// Area-weighted vertex normals (zero for vertices on no triangle).
fn vertex_normals(m: &RenderMesh) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; m.positions.len()];
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let f = (b - a).cross(c - a);
        if f.is_finite() {
            for &i in t {
                n[i as usize] += f;
            }
        }
    }
    n.iter().map(|v| v.normalize_or_zero()).collect()
}

/// Renders one picture `width × height` of the scene seen by `camera`.
pub fn render(scene: &RenderScene, camera: &Camera, width: u32, height: u32) -> Result<Image> {
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(Error::Invalid(format!(
            "image size must be between 1 and {MAX_SIDE} pixels per side, got {width} × {height}"
        )));
    }
    for (mi, m) in scene.meshes.iter().enumerate() {
        let n = m.positions.len();
        if m.triangles.iter().flatten().any(|&i| i as usize >= n)
            || m.lines.iter().flatten().any(|&i| i as usize >= n)
        {
            return Err(Error::Invalid(format!(
                "render: mesh {mi} has an index out of range"
            )));
        }
    }
    let (sw, sh) = (width as usize * SUPERSAMPLE, height as usize * SUPERSAMPLE);
    let view = camera.view(sh as f64)?;
    let mut target = Target::new(sw, sh, background);
    for m in &scene.meshes {
        let normals = vertex_normals(m);
        let vs: Vec<Vec3> = m.positions.iter().map(|p| view.to_view(*p)).collect();
        for t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let face = (b - a).cross(c - a);
            let front = face.dot(view.eye - a) > 0.0;
            let base = match (m.kind, front) {
                (MeshKind::Collider, _) => COLLIDER_COLOR,
                (MeshKind::Cloth, true) => FRONT_COLOR,
                (MeshKind::Cloth, false) => BACK_COLOR,
            };
            let fnorm = face.normalize_or_zero();
            let verts = t.map(|i| {
                let i = i as usize;
                let p = m.positions[i];
                let mut n = normals[i];
                if n.dot(fnorm) < 0.2 {
                    n = fnorm; // creases and folded-over vertices: use the face normal
                }
                let l = (view.eye - p).normalize_or_zero();
                let shade = (0.30 + 0.70 * n.dot(l).abs()) as f32;
                Vertex {
                    view: vs[i],
                    color: base.map(|c| c * shade),
                }
            });
            target.triangle(&view, verts);
        }
        for l in &m.lines {
            let [a, b] = l.map(|i| vs[i as usize]);
            target.line(&view, a, b, LINE_COLOR, SUPERSAMPLE);
        }
    }
    // Box-filter down to the output size.
    let mut rgb = Vec::with_capacity(width as usize * height as usize * 3);
    let s2 = (SUPERSAMPLE * SUPERSAMPLE) as f32;
    for y in 0..height as usize {
        for x in 0..width as usize {
            let mut acc = [0.0f32; 3];
            for dy in 0..SUPERSAMPLE {
                for dx in 0..SUPERSAMPLE {
                    let c = target.color[(y * SUPERSAMPLE + dy) * sw + x * SUPERSAMPLE + dx];
                    for k in 0..3 {
                        acc[k] += c[k];
                    }
                }
            }
            for a in acc {
                rgb.push(((a / s2).clamp(0.0, 1.0) * 255.0 + 0.5) as u8);
            }
        }
    }
    Ok(Image { width, height, rgb })
}

/// Renders a sequence of scenes with one camera: `camera`, or when `None` the automatic camera
/// framing the bounding box of every scene together (so the view does not jump between frames).
pub fn render_frames(
    scenes: &[RenderScene],
    camera: Option<&Camera>,
    width: u32,
    height: u32,
) -> Result<Vec<Image>> {
    let cam = match camera {
        Some(c) => *c,
        None => auto_camera(scenes, width, height)?,
    };
    scenes
        .iter()
        .map(|s| render(s, &cam, width, height))
        .collect()
}

/// The automatic camera for these scenes and image size (see [`Camera::framing`]).
pub fn auto_camera(scenes: &[RenderScene], width: u32, height: u32) -> Result<Camera> {
    let b = bounds(
        scenes
            .iter()
            .flat_map(|s| s.meshes.iter().flat_map(|m| &m.positions)),
    )
    .ok_or_else(|| Error::Invalid("render: nothing to frame (no finite vertex)".into()))?;
    Camera::framing(b.0, b.1, width.max(1) as f64 / height.max(1) as f64)
}

#[cfg(test)]
mod tests;
