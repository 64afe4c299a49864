//! A small z-buffer rasterizer: near-plane clipping, perspective projection, scan of each
//! triangle's bounding box with edge functions, Gouraud-interpolated colours, depth = 1/z.

use super::camera::View;
use crate::math::Vec3;

/// A colour buffer (linear RGB, 0..1) with a depth buffer holding 1/depth (0 = infinitely far).
pub(crate) struct Target {
    pub width: usize,
    pub height: usize,
    pub color: Vec<[f32; 3]>,
    pub inv_depth: Vec<f32>,
}

/// A vertex in view space with its colour.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Vertex {
    pub view: Vec3,
    pub color: [f32; 3],
}

fn lerp(a: &Vertex, b: &Vertex, t: f64) -> Vertex {
    let tf = t as f32;
    Vertex {
        view: a.view + (b.view - a.view) * t,
        color: [0, 1, 2].map(|k| a.color[k] + (b.color[k] - a.color[k]) * tf),
    }
}

impl Target {
    pub fn new(width: usize, height: usize, background: impl Fn(f64) -> [f32; 3]) -> Target {
        let mut color = Vec::with_capacity(width * height);
        for y in 0..height {
            let c = background((y as f64 + 0.5) / height as f64);
            color.extend(std::iter::repeat_n(c, width));
        }
        Target {
            width,
            height,
            color,
            inv_depth: vec![0.0; width * height],
        }
    }

    fn project(&self, view: &View, v: &Vertex) -> [f64; 3] {
        let z = v.view.z;
        [
            0.5 * self.width as f64 + view.focal * v.view.x / z,
            0.5 * self.height as f64 - view.focal * v.view.y / z,
            1.0 / z,
        ]
    }

    /// Draws a triangle given in view space, clipped against the near plane.
    pub fn triangle(&mut self, view: &View, tri: [Vertex; 3]) {
        if tri.iter().any(|v| !v.view.is_finite()) {
            return;
        }
        let near = view.near;
        let inside = |v: &Vertex| v.view.z >= near;
        let mut poly: Vec<Vertex> = Vec::with_capacity(4);
        if tri.iter().all(inside) {
            poly.extend_from_slice(&tri);
        } else {
            for i in 0..3 {
                let (a, b) = (&tri[i], &tri[(i + 1) % 3]);
                if inside(a) {
                    poly.push(*a);
                }
                if inside(a) != inside(b) {
                    let t = (near - a.view.z) / (b.view.z - a.view.z);
                    poly.push(lerp(a, b, t));
                }
            }
        }
        if poly.len() < 3 {
            return;
        }
        let p: Vec<([f64; 3], [f32; 3])> = poly
            .iter()
            .map(|v| (self.project(view, v), v.color))
            .collect();
        for k in 1..p.len() - 1 {
            self.fill(p[0], p[k], p[k + 1]);
        }
    }

    /// Fills a projected triangle: (x, y, 1/z) per vertex with a colour.
    fn fill(&mut self, a: ([f64; 3], [f32; 3]), b: ([f64; 3], [f32; 3]), c: ([f64; 3], [f32; 3])) {
        let (pa, pb, pc) = (a.0, b.0, c.0);
        let area = (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pb[1] - pa[1]) * (pc[0] - pa[0]);
        if !(area.abs() > 1e-12) || !area.is_finite() {
            return;
        }
        let (w, h) = (self.width as f64, self.height as f64);
        let x0 = pa[0].min(pb[0]).min(pc[0]).floor().max(0.0);
        let x1 = pa[0].max(pb[0]).max(pc[0]).ceil().min(w);
        let y0 = pa[1].min(pb[1]).min(pc[1]).floor().max(0.0);
        let y1 = pa[1].max(pb[1]).max(pc[1]).ceil().min(h);
        if !(x0 < x1 && y0 < y1) {
            return;
        }
        let edge = |p: [f64; 3], q: [f64; 3], x: f64, y: f64| {
            (q[0] - p[0]) * (y - p[1]) - (q[1] - p[1]) * (x - p[0])
        };
        // Perspective-correct colour: interpolate colour/z and 1/z linearly on screen.
        let cz = |v: &([f64; 3], [f32; 3])| v.1.map(|c| c as f64 * v.0[2]);
        let (ca, cb, cc) = (cz(&a), cz(&b), cz(&c));
        for y in y0 as usize..y1 as usize {
            let py = y as f64 + 0.5;
            for x in x0 as usize..x1 as usize {
                let px = x as f64 + 0.5;
                let wa = edge(pb, pc, px, py) / area;
                let wb = edge(pc, pa, px, py) / area;
                let wc = 1.0 - wa - wb;
                if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                    continue;
                }
                let iz = wa * pa[2] + wb * pb[2] + wc * pc[2];
                let i = y * self.width + x;
                if !(iz as f32 > self.inv_depth[i]) {
                    continue;
                }
                self.inv_depth[i] = iz as f32;
                self.color[i] =
                    [0, 1, 2].map(|k| ((wa * ca[k] + wb * cb[k] + wc * cc[k]) / iz) as f32);
            }
        }
    }

    /// Draws a depth-tested line segment given in view space, `thickness` pixels wide, slightly
    /// in front of surfaces it lies on.
    pub fn line(&mut self, view: &View, a: Vec3, b: Vec3, color: [f32; 3], thickness: usize) {
        let near = view.near;
        if !(a.is_finite() && b.is_finite()) || (a.z < near && b.z < near) {
            return;
        }
        let clip = |p: Vec3, q: Vec3| {
            if p.z >= near {
                p
            } else {
                p + (q - p) * ((near - p.z) / (q.z - p.z))
            }
        };
        let (a, b) = (clip(a, b), clip(b, a));
        let proj = |p: Vec3| {
            [
                0.5 * self.width as f64 + view.focal * p.x / p.z,
                0.5 * self.height as f64 - view.focal * p.y / p.z,
                1.0 / p.z,
            ]
        };
        let (pa, pb) = (proj(a), proj(b));
        let len = ((pb[0] - pa[0]).abs()).max((pb[1] - pa[1]).abs());
        if !len.is_finite() || len > 1e6 {
            return;
        }
        let steps = len.ceil().max(1.0) as usize;
        let r = thickness as isize / 2;
        for s in 0..=steps {
            let t = s as f64 / steps as f64;
            let x = pa[0] + (pb[0] - pa[0]) * t;
            let y = pa[1] + (pb[1] - pa[1]) * t;
            let iz = ((pa[2] + (pb[2] - pa[2]) * t) * 1.001) as f32;
            for dy in -r..thickness as isize - r {
                for dx in -r..thickness as isize - r {
                    let (xi, yi) = (x.floor() as isize + dx, y.floor() as isize + dy);
                    if xi < 0 || yi < 0 || xi >= self.width as isize || yi >= self.height as isize {
                        continue;
                    }
                    let i = yi as usize * self.width + xi as usize;
                    if iz > self.inv_depth[i] {
                        self.inv_depth[i] = iz;
                        self.color[i] = color;
                    }
                }
            }
        }
    }
}
