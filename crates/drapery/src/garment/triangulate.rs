//! Panels to triangle meshes: outlines subdivided by arc length (stitched edges with matching
//! counts), interior points on a triangular lattice, a constrained Delaunay triangulation
//! (`spade`), then the panel placed in 3-D.

use super::pattern::{Curve, Panel, Pattern, Point2, dist, orient};
use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::mesh::{Face, Mesh};
use spade::{ConstrainedDelaunayTriangulation, Point2 as SPoint, Triangulation};

/// One panel as a triangle mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct PanelMesh {
    /// The panel's name.
    pub name: String,
    /// The mesh in 3-D (metres), placed by the panel's translation and rotation. Triangles
    /// wind the same way as the panel's outline.
    pub mesh: Mesh,
    /// The same vertices flat, in the panel's own plane (metres): the rest shape.
    pub flat: Vec<[f64; 2]>,
    /// Per outline edge (in the panel's edge order), its vertex indices from the edge's start
    /// to its end, both corners included.
    pub edges: Vec<Vec<u32>>,
}

/// One stitch: the vertex pairs of two panel edges, paired by arc length.
#[derive(Clone, Debug, PartialEq)]
pub struct Stitch {
    /// Panel indices (into [`Garment::panels`]) of the two sides.
    pub panels: [usize; 2],
    /// Vertex pairs `[vertex in panels[0], vertex in panels[1]]`, from the second edge's start
    /// to its end.
    pub pairs: Vec<[u32; 2]>,
}

/// A triangulated pattern.
#[derive(Clone, Debug, PartialEq)]
pub struct Garment {
    /// One mesh per panel, in the pattern's panel order.
    pub panels: Vec<PanelMesh>,
    /// One entry per stitch, in the pattern's order.
    pub stitches: Vec<Stitch>,
}

/// Interior points closer than this many edge lengths to the outline are dropped.
const MARGIN: f64 = 0.55;

impl Pattern {
    /// Triangulates every panel at about `edge_length` metres per triangle edge.
    ///
    /// Every outline edge is divided into segments of about that length by arc length; the two
    /// edges of a stitch get the same number (the larger of their own). The interior is filled
    /// by a constrained Delaunay triangulation of the outline and a triangular lattice of
    /// spacing `edge_length`. Errors name the file and the panel or stitch: an edge stitched
    /// twice, or an outline whose subdivision crosses itself (a smaller edge length helps).
    pub fn triangulate(&self, edge_length: f64) -> Result<Garment> {
        if !(edge_length.is_finite() && edge_length > 0.0) {
            return Err(Error::Invalid(format!(
                "{}: edge_length must be a number > 0, got {edge_length}",
                self.origin
            )));
        }
        let scale = 1.0 / self.units_in_meter;
        // segment count per edge, then equalised across stitches
        let mut counts: Vec<Vec<usize>> = self
            .panels
            .iter()
            .map(|p| {
                p.edges
                    .iter()
                    .map(|e| {
                        let n = (e.curve.length() * scale / edge_length).round() as usize;
                        // a curve gets at least two segments, a line one
                        let least = if matches!(e.curve, Curve::Line { .. }) {
                            1
                        } else {
                            2
                        };
                        n.max(least)
                    })
                    .collect()
            })
            .collect();
        let mut stitched: Vec<Vec<Option<usize>>> = self
            .panels
            .iter()
            .map(|p| vec![None; p.edges.len()])
            .collect();
        for (i, s) in self.stitches.iter().enumerate() {
            for side in s.sides {
                if let Some(j) = stitched[side.panel][side.edge] {
                    return Err(Error::input(
                        &self.origin,
                        format!(
                            "stitch {i}: edge {} of panel `{}` is already stitched by stitch {j}",
                            side.edge, self.panels[side.panel].name
                        ),
                    ));
                }
                stitched[side.panel][side.edge] = Some(i);
            }
            let [a, b] = s.sides;
            let n = counts[a.panel][a.edge].max(counts[b.panel][b.edge]);
            counts[a.panel][a.edge] = n;
            counts[b.panel][b.edge] = n;
        }
        let panels = self
            .panels
            .iter()
            .zip(&counts)
            .map(|(p, n)| self.triangulate_panel(p, n, edge_length))
            .collect::<Result<Vec<_>>>()?;
        let stitches = self
            .stitches
            .iter()
            .map(|s| {
                let [a, b] = s.sides;
                let mut ea = panels[a.panel].edges[a.edge].clone();
                let eb = &panels[b.panel].edges[b.edge];
                if !s.right_wrong {
                    ea.reverse();
                }
                Stitch {
                    panels: [a.panel, b.panel],
                    pairs: ea.iter().zip(eb).map(|(&u, &v)| [u, v]).collect(),
                }
            })
            .collect();
        Ok(Garment { panels, stitches })
    }

    fn triangulate_panel(&self, panel: &Panel, counts: &[usize], h: f64) -> Result<PanelMesh> {
        let scale = 1.0 / self.units_in_meter;
        // outline: each edge's points but its end (the next edge's start)
        let mut flat: Vec<Point2> = Vec::new();
        let mut starts = Vec::with_capacity(panel.edges.len());
        for (e, &n) in panel.edges.iter().zip(counts) {
            starts.push(flat.len() as u32);
            let ts = e.curve.arc_length_parameters(n);
            for &t in &ts[..n] {
                let p = e.curve.point(t);
                flat.push([p[0] * scale, p[1] * scale]);
            }
        }
        let n_outline = flat.len();
        let edges: Vec<Vec<u32>> = (0..panel.edges.len())
            .map(|k| {
                let end = starts.get(k + 1).copied().unwrap_or(0);
                (starts[k]..starts[k] + counts[k] as u32)
                    .chain(std::iter::once(end))
                    .collect()
            })
            .collect();
        self.check_simple(
            panel,
            &flat,
            &format!(" once subdivided at edge length {h} m (try a smaller one)"),
        )?;
        let ring_owned = flat.clone();
        let ring = &ring_owned[..];
        let area2: f64 = (0..n_outline)
            .map(|i| {
                let (a, b) = (ring[i], ring[(i + 1) % n_outline]);
                a[0] * b[1] - a[1] * b[0]
            })
            .sum();
        let ccw = area2 > 0.0;

        // interior lattice
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in ring {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let dy = h * 3f64.sqrt() / 2.0;
        let rows = ((hi[1] - lo[1]) / dy).floor() as usize;
        let cols = ((hi[0] - lo[0]) / h).floor() as usize + 1;
        let y0 = lo[1] + 0.5 * ((hi[1] - lo[1]) - rows as f64 * dy);
        let x0 = lo[0] + 0.5 * ((hi[0] - lo[0]) - (cols - 1) as f64 * h) - 0.25 * h;
        let grid = SegmentGrid::new(ring, lo, hi, h);
        let mut interior = Vec::new();
        for j in 0..=rows {
            let y = y0 + j as f64 * dy;
            let shift = if j % 2 == 1 { 0.5 * h } else { 0.0 };
            for i in 0..=cols {
                let p = [x0 + shift + i as f64 * h, y];
                if inside(ring, p) && grid.far_from(ring, p, MARGIN * h) {
                    interior.push(p);
                }
            }
        }
        flat.extend(interior);

        let points: Vec<SPoint<f64>> = flat.iter().map(|p| SPoint::new(p[0], p[1])).collect();
        let constraints: Vec<[usize; 2]> =
            (0..n_outline).map(|i| [i, (i + 1) % n_outline]).collect();
        let fail = |m: String| Error::input(&self.origin, format!("panel `{}`: {m}", panel.name));
        let cdt =
            ConstrainedDelaunayTriangulation::<SPoint<f64>>::bulk_load_cdt(points, constraints)
                .map_err(|e| fail(format!("triangulation failed: {e:?}")))?;
        if cdt.num_vertices() != flat.len() {
            return Err(fail("triangulation merged coincident points".into()));
        }
        let mut faces = Vec::new();
        for f in cdt.inner_faces() {
            let [a, b, c] = f.vertices().map(|v| v.fix().index() as u32);
            let (pa, pb, pc) = (flat[a as usize], flat[b as usize], flat[c as usize]);
            let centroid = [(pa[0] + pb[0] + pc[0]) / 3.0, (pa[1] + pb[1] + pc[1]) / 3.0];
            if !inside(ring, centroid) {
                continue;
            }
            let tri_ccw = orient(pa, pb, pc) > 0.0;
            faces.push(Face::Tri(if tri_ccw == ccw {
                [a, b, c]
            } else {
                [a, c, b]
            }));
        }
        // deterministic order: by sorted vertex triple
        faces.sort_by_key(|f| {
            let mut k = [0u32; 3];
            k.copy_from_slice(f.indices());
            k.sort();
            k
        });

        let r = panel.rotation_matrix();
        let t = panel.translation.map(|x| x * scale);
        let positions = flat
            .iter()
            .map(|p| {
                Vec3::new(
                    r[0][0] * p[0] + r[0][1] * p[1] + t[0],
                    r[1][0] * p[0] + r[1][1] * p[1] + t[1],
                    r[2][0] * p[0] + r[2][1] * p[1] + t[2],
                )
            })
            .collect();
        Ok(PanelMesh {
            name: panel.name.clone(),
            mesh: Mesh {
                positions,
                faces,
                lines: Vec::new(),
            },
            flat,
            edges,
        })
    }
}

/// Whether `p` is inside the closed polygon `ring` (even–odd rule).
fn inside(ring: &[Point2], p: Point2) -> bool {
    let n = ring.len();
    let mut odd = false;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                odd = !odd;
            }
        }
    }
    odd
}

fn point_segment_distance(p: Point2, a: Point2, b: Point2) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    dist(p, [a[0] + t * ab[0], a[1] + t * ab[1]])
}

/// Outline segments binned on a square grid, for distance queries.
struct SegmentGrid {
    lo: Point2,
    cell: f64,
    dims: [usize; 2],
    bins: Vec<Vec<u32>>,
}

impl SegmentGrid {
    fn new(ring: &[Point2], lo: Point2, hi: Point2, cell: f64) -> Self {
        let dims = [
            ((hi[0] - lo[0]) / cell).floor() as usize + 1,
            ((hi[1] - lo[1]) / cell).floor() as usize + 1,
        ];
        let mut g = SegmentGrid {
            lo,
            cell,
            dims,
            bins: vec![Vec::new(); dims[0] * dims[1]],
        };
        let n = ring.len();
        for i in 0..n {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            let (c0, c1) = (
                g.cell_of([a[0].min(b[0]), a[1].min(b[1])]),
                g.cell_of([a[0].max(b[0]), a[1].max(b[1])]),
            );
            for cy in c0[1]..=c1[1] {
                for cx in c0[0]..=c1[0] {
                    g.bins[cy * dims[0] + cx].push(i as u32);
                }
            }
        }
        g
    }

    fn cell_of(&self, p: Point2) -> [usize; 2] {
        [0, 1].map(|k| {
            (((p[k] - self.lo[k]) / self.cell).floor().max(0.0) as usize).min(self.dims[k] - 1)
        })
    }

    /// Whether every outline segment is at least `r` (≤ one cell) from `p`.
    fn far_from(&self, ring: &[Point2], p: Point2, r: f64) -> bool {
        let c = self.cell_of(p);
        let n = ring.len();
        for cy in c[1].saturating_sub(1)..=(c[1] + 1).min(self.dims[1] - 1) {
            for cx in c[0].saturating_sub(1)..=(c[0] + 1).min(self.dims[0] - 1) {
                for &i in &self.bins[cy * self.dims[0] + cx] {
                    let i = i as usize;
                    if point_segment_distance(p, ring[i], ring[(i + 1) % n]) < r {
                        return false;
                    }
                }
            }
        }
        true
    }
}
