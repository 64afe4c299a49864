//! Mesh topology: vertices, polygon faces (triangles and quads) and line elements, and the
//! connectivity the spring model is generated from (edges, quad diagonals, bend pairs).
//!
//! Faces and lines keep their input order; every derived list (edges, bend pairs) is produced
//! in a deterministic order (first appearance while walking the faces, then the lines).

use crate::error::{Error, Result};
use crate::math::Vec3;
use std::collections::HashMap;

/// Largest mesh drapery generates itself (a grid, a garment's panels), in vertices (2²⁴), so
/// that a typo in a size or a unit cannot exhaust memory.
pub const MAX_GENERATED_VERTICES: usize = 1 << 24;

/// A polygon face: a triangle or a quad, vertex indices in winding order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Face {
    /// Three vertices.
    Tri([u32; 3]),
    /// Four vertices, in order around the quad.
    Quad([u32; 4]),
}

impl Face {
    /// The vertex indices of the face, in winding order.
    pub fn indices(&self) -> &[u32] {
        match self {
            Face::Tri(v) => v,
            Face::Quad(v) => v,
        }
    }

    /// The face split into triangles: itself, or a quad `(a,b,c,d)` as `(a,b,c)` and `(a,c,d)`.
    pub fn triangles(&self) -> impl Iterator<Item = [u32; 3]> {
        let (first, second) = match *self {
            Face::Tri(t) => (t, None),
            Face::Quad([a, b, c, d]) => ([a, b, c], Some([a, c, d])),
        };
        std::iter::once(first).chain(second)
    }
}

/// A surface/curve mesh: positions, faces (triangles, quads) and line elements (springs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions in metres.
    pub positions: Vec<Vec3>,
    /// Faces in input order.
    pub faces: Vec<Face>,
    /// Line elements (`l` in OBJ), in input order.
    pub lines: Vec<[u32; 2]>,
    /// Texture coordinates of each face's corners (`vt` in OBJ; a grid's or a pattern panel's
    /// own 2-D coordinates), one entry per face, a triangle's fourth unused; empty when the
    /// mesh has none. The shell model takes its warp (`u`) and weft (`v`) directions from them.
    pub face_uv: Vec<[[f64; 2]; 4]>,
}

/// A unit vector in the plane normal to the unit `n`: the global x axis projected into it, or
/// z when x is (nearly) along `n`.
fn in_plane_axis(n: Vec3) -> Vec3 {
    let mut u = Vec3::X - n * n.x;
    if u.length() < 1e-6 {
        u = Vec3::Z - n * n.z;
    }
    u.normalize()
}

/// Unordered vertex pair key.
fn key(a: u32, b: u32) -> (u32, u32) {
    if a < b { (a, b) } else { (b, a) }
}

impl Mesh {
    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// All triangles, quads split along their `a–c` diagonal.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        self.faces.iter().flat_map(|f| f.triangles()).collect()
    }

    /// The texture coordinates of the corners of [`Mesh::triangles`], in the same order (`None`
    /// when the mesh has none).
    pub fn triangle_uvs(&self) -> Option<Vec<[[f64; 2]; 3]>> {
        if self.face_uv.len() != self.faces.len() {
            return None;
        }
        let mut out = Vec::with_capacity(self.faces.len() * 2);
        for (f, uv) in self.faces.iter().zip(&self.face_uv) {
            out.push([uv[0], uv[1], uv[2]]);
            if let Face::Quad(_) = f {
                out.push([uv[0], uv[2], uv[3]]);
            }
        }
        Some(out)
    }

    /// Checks indices, finiteness and degeneracy. `what` names the mesh in messages.
    pub fn validate(&self, what: &str) -> Result<()> {
        let n = self.positions.len();
        if n == 0 {
            return Err(Error::input(what, "mesh has no vertices"));
        }
        for (i, p) in self.positions.iter().enumerate() {
            if !p.is_finite() {
                return Err(Error::input(
                    what,
                    format!(
                        "vertex {} has a non-finite coordinate ({}, {}, {})",
                        i + 1,
                        p.x,
                        p.y,
                        p.z
                    ),
                ));
            }
        }
        for (fi, f) in self.faces.iter().enumerate() {
            let idx = f.indices();
            for &v in idx {
                if v as usize >= n {
                    return Err(Error::input(
                        what,
                        format!(
                            "face {} refers to vertex {} but the mesh has {} vertices",
                            fi + 1,
                            v as u64 + 1,
                            n
                        ),
                    ));
                }
            }
            for a in 0..idx.len() {
                for b in a + 1..idx.len() {
                    if idx[a] == idx[b] {
                        return Err(Error::input(
                            what,
                            format!(
                                "face {} is degenerate: vertex {} appears twice",
                                fi + 1,
                                idx[a] + 1
                            ),
                        ));
                    }
                }
            }
            for t in f.triangles() {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                let area2 = (b - a).cross(c - a).length();
                let scale = (b - a).length_squared().max((c - a).length_squared());
                if !(area2 > 1e-12 * scale) {
                    return Err(Error::input(
                        what,
                        format!("face {} is degenerate (zero area)", fi + 1),
                    ));
                }
            }
        }
        for (li, l) in self.lines.iter().enumerate() {
            for &v in l {
                if v as usize >= n {
                    return Err(Error::input(
                        what,
                        format!(
                            "line element {} refers to vertex {} but the mesh has {} vertices",
                            li + 1,
                            v as u64 + 1,
                            n
                        ),
                    ));
                }
            }
            if l[0] == l[1] {
                return Err(Error::input(
                    what,
                    format!(
                        "line element {} joins vertex {} to itself",
                        li + 1,
                        l[0] + 1
                    ),
                ));
            }
            if (self.positions[l[0] as usize] - self.positions[l[1] as usize]).length() == 0.0 {
                return Err(Error::input(
                    what,
                    format!("line element {} has zero length", li + 1),
                ));
            }
        }
        Ok(())
    }

    /// Unique undirected edges: polygon sides in face order, then line elements not already
    /// present. These carry the stretch springs.
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let mut seen: HashMap<(u32, u32), ()> = HashMap::new();
        let mut out = Vec::new();
        let mut push = |a: u32, b: u32, out: &mut Vec<[u32; 2]>| {
            if seen.insert(key(a, b), ()).is_none() {
                out.push([a, b]);
            }
        };
        for f in &self.faces {
            let idx = f.indices();
            for k in 0..idx.len() {
                push(idx[k], idx[(k + 1) % idx.len()], &mut out);
            }
        }
        for l in &self.lines {
            push(l[0], l[1], &mut out);
        }
        out
    }

    /// Both diagonals of every quad (shear springs), in face order.
    pub fn quad_diagonals(&self) -> Vec<[u32; 2]> {
        let mut out = Vec::new();
        for f in &self.faces {
            if let Face::Quad([a, b, c, d]) = *f {
                out.push([a, c]);
                out.push([b, d]);
            }
        }
        out
    }

    /// Bend pairs: for every edge `(a, b)` shared by two faces F1 and F2, the springs
    /// `(across(F1, a), across(F2, a))` and `(across(F1, b), across(F2, b))`, where
    /// `across(F, a)` is the vertex of F joined to `a` other than `b` (for a triangle: the vertex
    /// opposite the edge). Duplicates are removed, so a triangle pair gives one spring joining the
    /// two opposite vertices, and on a quad grid every vertex is joined to the vertices two steps
    /// away along both grid lines. Edges shared by more than two faces take every pair of faces.
    pub fn bend_pairs(&self) -> Vec<[u32; 2]> {
        let mut edge_faces: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
        let mut order = Vec::new();
        for (fi, f) in self.faces.iter().enumerate() {
            let idx = f.indices();
            for k in 0..idx.len() {
                let e = key(idx[k], idx[(k + 1) % idx.len()]);
                let list = edge_faces.entry(e).or_default();
                if list.is_empty() {
                    order.push(e);
                }
                list.push(fi);
            }
        }
        let across = |f: &Face, a: u32, b: u32| -> u32 {
            let idx = f.indices();
            let n = idx.len();
            let p = idx.iter().position(|&v| v == a).expect("vertex in face");
            let next = idx[(p + 1) % n];
            let prev = idx[(p + n - 1) % n];
            match f {
                Face::Tri(_) => *idx
                    .iter()
                    .find(|&&v| v != a && v != b)
                    .expect("third vertex"),
                Face::Quad(_) => {
                    if next == b {
                        prev
                    } else {
                        next
                    }
                }
            }
        };
        let mut seen: HashMap<(u32, u32), ()> = HashMap::new();
        let mut out = Vec::new();
        for e in order {
            let list = &edge_faces[&e];
            for x in 0..list.len() {
                for y in x + 1..list.len() {
                    let (f1, f2) = (&self.faces[list[x]], &self.faces[list[y]]);
                    for (a, b) in [(e.0, e.1), (e.1, e.0)] {
                        let p = across(f1, a, b);
                        let q = across(f2, a, b);
                        if p != q && seen.insert(key(p, q), ()).is_none() {
                            out.push([p, q]);
                        }
                    }
                }
            }
        }
        out
    }

    /// Area of each vertex's share of the surface: a third of every triangle it belongs to
    /// (quads split in two along `a–c`).
    pub fn vertex_areas(&self) -> Vec<f64> {
        let mut area = vec![0.0; self.positions.len()];
        for t in self.triangles() {
            let [a, b, c] = t.map(|i| self.positions[i as usize]);
            let third = 0.5 * (b - a).cross(c - a).length() / 3.0;
            for i in t {
                area[i as usize] += third;
            }
        }
        area
    }

    /// A rectangular grid of quads.
    ///
    /// `size` is the extent along the two in-plane axes (m), `resolution` the number of
    /// vertices along each (at least 2). The in-plane axes are `u` = the x axis projected on the
    /// plane (the z axis if `normal` is along x) and `w = u × normal`. Vertex (row `r`, column
    /// `c`) has index `r * resolution[0] + c`; columns run along `+u`, rows along `+w`, starting
    /// at `center - size/2`. With `normal = +z`, `u = +x` and `w = -y`: row 0 is the top edge,
    /// so vertices `0` and `resolution[0] - 1` are the top corners.
    pub fn grid(
        size: [f64; 2],
        resolution: [usize; 2],
        center: Vec3,
        normal: Vec3,
    ) -> Result<Mesh> {
        let [nx, ny] = resolution;
        if nx < 2 || ny < 2 {
            return Err(Error::Invalid(format!(
                "grid resolution must be at least 2 × 2, got {nx} × {ny}"
            )));
        }
        if nx.saturating_mul(ny) > u32::MAX as usize / 2 {
            return Err(Error::Invalid(format!(
                "grid resolution {nx} × {ny} is too large"
            )));
        }
        if !(size[0] > 0.0 && size[1] > 0.0 && size[0].is_finite() && size[1].is_finite()) {
            return Err(Error::Invalid(format!(
                "grid size must be positive and finite, got [{}, {}]",
                size[0], size[1]
            )));
        }
        let len = normal.length();
        if !(len > 0.0 && len.is_finite() && center.is_finite()) {
            return Err(Error::Invalid(
                "grid normal must be a non-zero finite vector and center finite".into(),
            ));
        }
        let n = normal / len;
        let u = in_plane_axis(n);
        let w = u.cross(n);
        let mut positions = Vec::with_capacity(nx * ny);
        for r in 0..ny {
            for c in 0..nx {
                let s = c as f64 / (nx - 1) as f64 - 0.5;
                let t = r as f64 / (ny - 1) as f64 - 0.5;
                positions.push(center + u * (s * size[0]) + w * (t * size[1]));
            }
        }
        let mut faces = Vec::with_capacity((nx - 1) * (ny - 1));
        let mut face_uv = Vec::with_capacity((nx - 1) * (ny - 1));
        // u runs along the grid's first axis, v along its second (metres from the centre)
        let uv = |r: usize, c: usize| {
            [
                (c as f64 / (nx - 1) as f64 - 0.5) * size[0],
                (r as f64 / (ny - 1) as f64 - 0.5) * size[1],
            ]
        };
        for r in 0..ny - 1 {
            for c in 0..nx - 1 {
                let i = (r * nx + c) as u32;
                let nxu = nx as u32;
                faces.push(Face::Quad([i, i + nxu, i + nxu + 1, i + 1]));
                face_uv.push([uv(r, c), uv(r + 1, c), uv(r + 1, c + 1), uv(r, c + 1)]);
            }
        }
        Ok(Mesh {
            positions,
            faces,
            lines: Vec::new(),
            face_uv,
        })
    }

    /// This mesh, lying in the plane z = 0, moved to the plane through `center` normal to
    /// `normal` (non-zero): x goes to the grid's `u` axis ([`Mesh::grid`]), y to `normal × u`,
    /// so counter-clockwise faces seen from +z face `normal`. Texture coordinates are set to
    /// the original (x, y), so warp and weft follow x and y.
    pub fn placed(&self, center: Vec3, normal: Vec3) -> Mesh {
        let n = normal.normalize();
        let u = in_plane_axis(n);
        let v = n.cross(u);
        let face_uv = (self.faces.iter())
            .map(|f| {
                let mut uv = [[0.0; 2]; 4];
                for (k, &i) in f.indices().iter().enumerate() {
                    let p = self.positions[i as usize];
                    uv[k] = [p.x, p.y];
                }
                uv
            })
            .collect();
        Mesh {
            positions: (self.positions.iter())
                .map(|p| center + u * p.x + v * p.y + n * p.z)
                .collect(),
            faces: self.faces.clone(),
            lines: self.lines.clone(),
            face_uv,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sorted(mut v: Vec<[u32; 2]>) -> Vec<(u32, u32)> {
        let mut k: Vec<_> = v.drain(..).map(|[a, b]| key(a, b)).collect();
        k.sort();
        k
    }

    #[test]
    fn grid_has_expected_counts_of_edges_diagonals_and_bend_pairs() {
        let (nx, ny) = (5usize, 4usize);
        let m = Mesh::grid([1.0, 1.0], [nx, ny], Vec3::ZERO, Vec3::Z).unwrap();
        assert_eq!(m.positions.len(), nx * ny);
        assert_eq!(m.edges().len(), (nx - 1) * ny + nx * (ny - 1));
        assert_eq!(m.quad_diagonals().len(), 2 * (nx - 1) * (ny - 1));
        // bend springs join vertices two apart along each grid line
        assert_eq!(m.bend_pairs().len(), (nx - 2) * ny + nx * (ny - 2));
        let idx = |r: usize, c: usize| (r * nx + c) as u32;
        let mut expect = Vec::new();
        for r in 0..ny {
            for c in 0..nx - 2 {
                expect.push([idx(r, c), idx(r, c + 2)]);
            }
        }
        for r in 0..ny - 2 {
            for c in 0..nx {
                expect.push([idx(r, c), idx(r + 2, c)]);
            }
        }
        assert_eq!(sorted(m.bend_pairs()), sorted(expect));
    }

    #[test]
    fn grid_row_zero_is_the_top_edge_for_a_vertical_sheet() {
        let m = Mesh::grid([2.0, 1.0], [3, 3], Vec3::new(0.0, 1.0, 0.0), Vec3::Z).unwrap();
        assert!((m.positions[0] - Vec3::new(-1.0, 1.5, 0.0)).length() < 1e-12);
        assert!((m.positions[2] - Vec3::new(1.0, 1.5, 0.0)).length() < 1e-12);
        assert!((m.positions[8] - Vec3::new(1.0, 0.5, 0.0)).length() < 1e-12);
    }

    #[test]
    fn two_triangles_sharing_an_edge_give_one_bend_spring_between_opposite_vertices() {
        let m = Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)],
            faces: vec![Face::Tri([0, 1, 2]), Face::Tri([1, 3, 2])],
            lines: vec![],
            face_uv: Vec::new(),
        };
        assert_eq!(sorted(m.bend_pairs()), vec![(0, 3)]);
        assert_eq!(m.edges().len(), 5);
    }

    #[test]
    fn vertex_areas_sum_to_the_surface_area() {
        let m = Mesh::grid([2.0, 3.0], [7, 5], Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)).unwrap();
        let total: f64 = m.vertex_areas().iter().sum();
        assert!((total - 6.0).abs() < 1e-12);
    }

    #[test]
    fn validation_rejects_out_of_range_and_degenerate_faces() {
        let mut m = Mesh::grid([1.0, 1.0], [2, 2], Vec3::ZERO, Vec3::Z).unwrap();
        assert!(m.validate("m").is_ok());
        m.faces.push(Face::Tri([0, 1, 9]));
        assert!(m.validate("m").unwrap_err().to_string().contains("face 2"));
        m.faces.pop();
        m.faces.push(Face::Tri([0, 1, 1]));
        assert!(m.validate("m").is_err());
        m.faces.pop();
        m.positions[0].x = f64::NAN;
        assert!(
            m.validate("m")
                .unwrap_err()
                .to_string()
                .contains("vertex 1")
        );
    }
}
