//! `shape = "mesh"`: a triangle surface of zero thickness from an OBJ file (`mesh`), turning
//! about `center` (default: the origin of the file's coordinates).
//!
//! A mesh has no inside: its distance is unsigned (≥ 0), the normal points from the closest
//! surface point toward the query point (the gradient of the unsigned distance), and
//! [`super::Contact::side`] tells which side of the closest triangle (by its winding) the point
//! is on. Cloth passing through a mesh is caught by CCD against its triangles, not by the sign.

use super::bvh::Bvh;
use super::{Keys, Kind, Local, unit_or_z};
use crate::collision::broad_phase::Aabb;
use crate::collision::distance::PointTriangle;
use crate::collision::tessellate::TessellateOptions;
use crate::error::{Error, Result};
use crate::fingerprint::Fnv;
use crate::math::Vec3;
use std::path::Path;

/// A triangle mesh obstacle with a bounding-volume hierarchy for closest-point queries.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleMesh {
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    pivot: Vec3,
    bvh: Bvh,
    boxes: Vec<Aabb>,
    /// Watertight ([`super::interior::is_closed`]): the mesh has an inside.
    closed: bool,
}

impl TriangleMesh {
    /// A mesh from vertices and triangles, turning about the origin of the vertices'
    /// coordinates. Triangles referring to missing vertices are dropped.
    pub fn new(vertices: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> TriangleMesh {
        let triangles = valid_triangles(vertices.len(), triangles);
        let bvh = Bvh::build(&vertices, &triangles);
        let boxes = bvh.boxes(&triangles, &[&vertices]);
        let closed = super::interior::is_closed(&triangles);
        TriangleMesh {
            vertices,
            triangles,
            pivot: Vec3::ZERO,
            bvh,
            boxes,
            closed,
        }
    }

    /// The same mesh turning about `pivot` (in the vertices' coordinates) instead of the origin.
    pub fn with_pivot(mut self, pivot: Vec3) -> TriangleMesh {
        self.pivot = pivot;
        self
    }

    /// The point the mesh turns about, at `t = 0`.
    pub fn pivot(&self) -> Vec3 {
        self.pivot
    }

    /// Vertices in the pose at `t = 0`.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// Triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Closest triangle to `p` in the rest pose: `(triangle index, closest point result)`.
    pub fn closest_triangle(&self, p: Vec3) -> Option<(u32, PointTriangle)> {
        self.bvh.closest(&self.boxes, p, |i| {
            self.triangles[i as usize].map(|v| self.vertices[v as usize])
        })
    }
}

/// The mesh with vertices at the same position merged (the first of each kept, in order) and
/// the triangles left without area by the merge dropped: tessellations repeat their seam and
/// pole vertices.
#[cfg(test)]
pub(crate) fn welded(vertices: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut first = std::collections::HashMap::new();
    let mut kept = Vec::new();
    let map: Vec<u32> = vertices
        .iter()
        .map(|p| {
            let key = [p.x, p.y, p.z].map(|c| (c + 0.0).to_bits());
            *first.entry(key).or_insert_with(|| {
                kept.push(*p);
                kept.len() as u32 - 1
            })
        })
        .collect();
    let tris = triangles
        .into_iter()
        .map(|t| t.map(|i| map[i as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[2] != t[0])
        .collect();
    (kept, tris)
}

/// Triangles whose corners all exist.
pub(crate) fn valid_triangles(n: usize, triangles: Vec<[u32; 3]>) -> Vec<[u32; 3]> {
    triangles
        .into_iter()
        .filter(|t| t.iter().all(|&i| (i as usize) < n))
        .collect()
}

/// The surface result of a closest-triangle query: unsigned distance, the normal toward `p`
/// (the face normal when `p` is on the surface), the side by the winding.
pub(crate) fn surface_local(p: Vec3, tri: [Vec3; 3], ti: u32, r: PointTriangle) -> Local {
    let [a, b, c] = tri;
    let fnormal = (b - a).cross(c - a);
    let side = if (p - r.q).dot(fnormal) < 0.0 {
        -1.0
    } else {
        1.0
    };
    let n = if r.dist > 0.0 {
        (p - r.q) / r.dist
    } else {
        unit_or_z(fnormal)
    };
    Local {
        distance: r.dist,
        normal: n,
        point: r.q,
        side,
        triangle: Some(ti),
        velocity: None,
    }
}

/// Reads an OBJ file as vertices and triangles; errors name `field` (`collider[0].mesh`).
pub(crate) fn read_triangles(path: &Path, field: &str) -> Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let mesh = crate::io::obj::read_obj(path).map_err(|e| match e {
        Error::Io { path: p, cause } => Error::field(field, format!("cannot read '{p}': {cause}")),
        other => other,
    })?;
    if mesh.faces.is_empty() {
        return Err(Error::field(
            field,
            format!(
                "'{}' has no faces (a mesh collider needs triangles or quads)",
                path.display()
            ),
        ));
    }
    let triangles = mesh.triangles();
    Ok((mesh.positions, triangles))
}

impl Kind for TriangleMesh {
    const NAME: &'static str = "mesh";
    const KEYS: &'static [&'static str] = super::MeshSequence::KEYS;

    fn parse(k: &Keys) -> Result<TriangleMesh> {
        // the pivot is checked before the file is read
        let pivot = k.opt_vec3("center")?.unwrap_or(Vec3::ZERO);
        let (v, t) = read_triangles(&k.file("mesh")?, &k.path("mesh"))?;
        Ok(TriangleMesh::new(v, t).with_pivot(pivot))
    }

    fn center(&self) -> Vec3 {
        self.pivot
    }

    fn closest(&self, p: Vec3, _t: f64) -> Local {
        match self.closest_triangle(p) {
            None => Local::nowhere(p),
            Some((ti, r)) => {
                let tri = self.triangles[ti as usize].map(|v| self.vertices[v as usize]);
                surface_local(p, tri, ti, r)
            }
        }
    }

    fn tessellate(&self, _t: f64, _o: &TessellateOptions) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        (self.vertices.clone(), self.triangles.clone())
    }

    fn solid(&self) -> bool {
        false
    }

    fn closed(&self) -> bool {
        self.closed
    }

    fn surface(&self, _t: f64) -> Option<(Vec<Vec3>, &[[u32; 3]])> {
        Some((self.vertices.clone(), &self.triangles))
    }

    fn hash(&self, h: &mut Fnv) {
        h.bytes(b"mesh");
        super::hash_vec(h, self.pivot);
        hash_mesh(h, &self.vertices, &self.triangles);
    }

    fn describe(&self) -> String {
        format!(
            "mesh of {} vertices, {} triangles{} (turns about {})",
            self.vertices.len(),
            self.triangles.len(),
            if self.closed { ", closed" } else { "" },
            super::v3(self.pivot)
        )
    }
}

/// Feeds vertex and triangle counts and values to a fingerprint.
pub(crate) fn hash_mesh(h: &mut Fnv, vertices: &[Vec3], triangles: &[[u32; 3]]) {
    h.u64(vertices.len() as u64);
    for p in vertices {
        super::hash_vec(h, *p);
    }
    h.u64(triangles.len() as u64);
    for t in triangles {
        for &i in t {
            h.u64(i as u64);
        }
    }
}
