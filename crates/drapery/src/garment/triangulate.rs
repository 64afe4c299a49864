//! Panels to triangle meshes: outlines subdivided by arc length (stitched edges with matching
//! counts), interior points on a triangular lattice, a constrained Delaunay triangulation
//! (`spade`), then the panel placed in 3-D.

use super::pattern::{Curve, Panel, Pattern, Point2, dist, orient};
use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::mesh::{Face, MAX_GENERATED_VERTICES, Mesh};
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
        // segment count per edge, then equalised across stitches; a panel whose outline alone
        // would exceed the vertex limit (a coordinate or a unit off by orders of magnitude) is
        // an error before anything is allocated
        let mut counts: Vec<Vec<usize>> = Vec::with_capacity(self.panels.len());
        for p in &self.panels {
            let mut row = Vec::with_capacity(p.edges.len());
            let mut total = 0.0;
            for e in &p.edges {
                let n = (e.curve.length() * scale / edge_length).round();
                total += n;
                if total.is_nan() || total > MAX_GENERATED_VERTICES as f64 {
                    return Err(self.too_large(p, edge_length, "its outline", total));
                }
                // a curve gets at least two segments, a line one
                let least = if matches!(e.curve, Curve::Line { .. }) {
                    1
                } else {
                    2
                };
                row.push((n as usize).max(least));
            }
            counts.push(row);
        }
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

    /// The error of a panel whose mesh would exceed [`MAX_GENERATED_VERTICES`]: `what` would
    /// have `count` points at edge length `h`.
    fn too_large(&self, panel: &Panel, h: f64, what: &str, count: f64) -> Error {
        Error::input(
            &self.origin,
            format!(
                "panel `{}`: at edge length {h} m {what} would have {count:.3e} points; at most {MAX_GENERATED_VERTICES} vertices are allowed (check the panel's coordinates, properties.units_in_meter and edge_length)",
                panel.name
            ),
        )
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
        let (rows, cols) = (
            ((hi[1] - lo[1]) / dy).floor(),
            ((hi[0] - lo[0]) / h).floor() + 1.0,
        );
        let lattice = (rows + 1.0) * (cols + 1.0);
        if lattice.is_nan() || lattice > MAX_GENERATED_VERTICES as f64 {
            return Err(self.too_large(panel, h, "the lattice over its bounding box", lattice));
        }
        let (rows, cols) = (rows as usize, cols as usize);
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
        // inside = an odd number of outline crossings from the outer face (flood fill)
        let mut odd: Vec<Option<bool>> = vec![None; cdt.num_all_faces()];
        let mut queue = std::collections::VecDeque::new();
        for f in cdt.inner_faces() {
            for e in f.adjacent_edges() {
                if e.rev().face().is_outer() && odd[f.fix().index()].is_none() {
                    odd[f.fix().index()] = Some(e.is_constraint_edge());
                    queue.push_back(f);
                }
            }
        }
        while let Some(f) = queue.pop_front() {
            let here = odd[f.fix().index()] == Some(true);
            for e in f.adjacent_edges() {
                if let Some(g) = e.rev().face().as_inner()
                    && odd[g.fix().index()].is_none()
                {
                    odd[g.fix().index()] = Some(here != e.is_constraint_edge());
                    queue.push_back(g);
                }
            }
        }
        let mut tris = Vec::new();
        for f in cdt.inner_faces() {
            if odd[f.fix().index()] != Some(true) {
                continue;
            }
            let [a, b, c] = f.vertices().map(|v| v.fix().index() as u32);
            // spade's inner faces wind counter-clockwise; follow the outline's winding
            tris.push(if ccw { [a, b, c] } else { [a, c, b] });
        }
        flip_slivers(&flat, &mut tris, h);
        let mut faces: Vec<Face> = tris.into_iter().map(Face::Tri).collect();
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
        // the panel's own 2-D coordinates are its texture coordinates (warp along its x)
        let face_uv = (faces.iter())
            .map(|f| {
                let mut uv = [[0.0; 2]; 4];
                for (c, &i) in f.indices().iter().enumerate() {
                    uv[c] = [flat[i as usize][0], flat[i as usize][1]];
                }
                uv
            })
            .collect();
        Ok(PanelMesh {
            name: panel.name.clone(),
            mesh: Mesh {
                positions,
                faces,
                lines: Vec::new(),
                face_uv,
            },
            flat,
            edges,
        })
    }
}

/// Replaces each sliver triangle `(p, q, r)` (a middle vertex `q` all but on its longest edge
/// `r–p`, as rounding leaves along a straight outline edge) and its neighbour `(p, r, x)`
/// across that edge by `(p, q, x)` and `(q, r, x)`. Triangles keep their common winding.
fn flip_slivers(flat: &[Point2], tris: &mut [[u32; 3]], h: f64) {
    let tiny = 1e-8 * h * h;
    let area2 = |t: [u32; 3]| {
        orient(
            flat[t[0] as usize],
            flat[t[1] as usize],
            flat[t[2] as usize],
        )
        .abs()
    };
    // passes until nothing flips (a sliver next to another flips once that one has)
    loop {
        let mut flipped = false;
        for s in 0..tris.len() {
            if area2(tris[s]) >= tiny {
                continue;
            }
            // rotate the sliver so that its longest edge is r → p
            let t = tris[s];
            let len = |k: usize| dist(flat[t[k] as usize], flat[t[(k + 1) % 3] as usize]);
            let k = (0..3).max_by(|&a, &b| len(a).total_cmp(&len(b))).unwrap(); // t[k] → t[k+1]
            let (r, p, q) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let neighbour = (0..tris.len())
                .find(|&i| i != s && (0..3).any(|j| tris[i][j] == p && tris[i][(j + 1) % 3] == r));
            let Some(n) = neighbour else { continue };
            let x = *tris[n].iter().find(|&&v| v != p && v != r).unwrap();
            let (a, b) = ([p, q, x], [q, r, x]);
            if area2(a) >= tiny && area2(b) >= tiny {
                tris[s] = a;
                tris[n] = b;
                flipped = true;
            }
        }
        if !flipped {
            return;
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::garment::pattern::Curve;
    use crate::garment::pattern::tests::{assert_mentions, spec, square};
    use std::collections::HashMap;
    use std::f64::consts::PI;

    fn examples() -> std::path::PathBuf {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/garments")
    }

    /// Area inside a panel's exact outline (m²), by Green's theorem on a fine uniform sampling
    /// in each curve's own parameter.
    fn exact_area(p: &Pattern, panel: &Panel) -> f64 {
        let ring = panel.sampled_outline(20_000);
        let s = 1.0 / p.units_in_meter;
        let n = ring.len();
        let twice: f64 = (0..n)
            .map(|i| {
                let (a, b) = (ring[i], ring[(i + 1) % n]);
                a[0] * b[1] - a[1] * b[0]
            })
            .sum();
        (0.5 * twice * s * s).abs()
    }

    fn flat_area(m: &PanelMesh) -> f64 {
        m.mesh
            .triangles()
            .iter()
            .map(|t| {
                0.5 * orient(
                    m.flat[t[0] as usize],
                    m.flat[t[1] as usize],
                    m.flat[t[2] as usize],
                )
                .abs()
            })
            .sum()
    }

    fn mesh_area(m: &PanelMesh) -> f64 {
        let x = &m.mesh.positions;
        m.mesh
            .triangles()
            .iter()
            .map(|t| {
                0.5 * (x[t[1] as usize] - x[t[0] as usize])
                    .cross(x[t[2] as usize] - x[t[0] as usize])
                    .length()
            })
            .sum()
    }

    fn assert_area(p: &Pattern, g: &Garment, expected: Option<&[f64]>) {
        for (k, (panel, m)) in p.panels.iter().zip(&g.panels).enumerate() {
            let exact = exact_area(p, panel);
            if let Some(e) = expected {
                assert!(
                    (exact - e[k]).abs() < 1e-6 * e[k],
                    "{}: Green {exact} vs analytic {}",
                    panel.name,
                    e[k]
                );
            }
            for got in [flat_area(m), mesh_area(m)] {
                assert!(
                    (got - exact).abs() < 0.005 * exact,
                    "{}: triangulated {got} m² vs outline {exact} m²",
                    panel.name
                );
            }
        }
    }

    /// Every triangle has positive area with the outline's winding; every mesh edge borders two
    /// triangles in opposite directions except the outline's segments, which border one.
    fn assert_well_formed(m: &PanelMesh) {
        let n = m.edges.iter().map(|e| e.len() - 1).sum::<usize>();
        let ring: Vec<Point2> = (0..n).map(|i| m.flat[i]).collect();
        let sign = (0..n)
            .map(|i| orient([0.0, 0.0], ring[i], ring[(i + 1) % n]))
            .sum::<f64>()
            .signum();
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for t in m.mesh.triangles() {
            let a = orient(
                m.flat[t[0] as usize],
                m.flat[t[1] as usize],
                m.flat[t[2] as usize],
            );
            assert!(
                a * sign > 0.0,
                "{}: triangle {t:?} has signed area {a}",
                m.name
            );
            for k in 0..3 {
                *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        let mut boundary = Vec::new();
        for (&(a, b), &c) in &directed {
            assert_eq!(c, 1, "{}: directed edge {a}->{b} used {c} times", m.name);
            if !directed.contains_key(&(b, a)) {
                boundary.push((a, b));
            }
        }
        boundary.sort();
        let mut outline: Vec<(u32, u32)> = m
            .edges
            .iter()
            .flat_map(|e| e.windows(2).map(|w| (w[0], w[1])))
            .collect();
        outline.sort();
        assert_eq!(
            boundary, outline,
            "{}: the mesh boundary is not the outline",
            m.name
        );
        m.mesh.validate(&m.name).unwrap();
    }

    /// Distance from `q` to the exact curve (pattern units).
    fn distance_to_curve(c: &Curve, q: Point2) -> f64 {
        dist(c.point(closest_parameter(c, q)), q)
    }

    /// Arc length of the exact curve from its start to parameter `t` (fine polyline).
    fn arc_length_to(c: &Curve, t: f64) -> f64 {
        let n = 20_000;
        (0..n)
            .map(|i| {
                dist(
                    c.point(t * i as f64 / n as f64),
                    c.point(t * (i + 1) as f64 / n as f64),
                )
            })
            .sum()
    }

    /// Parameter of the point of the curve closest to `q`: nearest of a fine sampling, then
    /// refined by golden-section search around it.
    fn closest_parameter(c: &Curve, q: Point2) -> f64 {
        let n = 4000;
        let d = |t: f64| dist(c.point(t), q);
        let i = (0..=n)
            .min_by(|&a, &b| d(a as f64 / n as f64).total_cmp(&d(b as f64 / n as f64)))
            .unwrap();
        let (mut lo, mut hi) = (
            ((i as f64) - 1.0).max(0.0) / n as f64,
            ((i as f64) + 1.0).min(n as f64) / n as f64,
        );
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..200 {
            let (a, b) = (hi - g * (hi - lo), lo + g * (hi - lo));
            if d(a) < d(b) { hi = b } else { lo = a }
        }
        0.5 * (lo + hi)
    }

    fn assert_on_curves(p: &Pattern, g: &Garment) {
        for (panel, m) in p.panels.iter().zip(&g.panels) {
            for (e, verts) in panel.edges.iter().zip(&m.edges) {
                for &v in verts {
                    let q = m.flat[v as usize].map(|x| x * p.units_in_meter);
                    let off = distance_to_curve(&e.curve, q) / p.units_in_meter;
                    assert!(off < 1e-9, "{}: vertex {v} is {off} m off its edge", m.name);
                }
            }
        }
    }

    #[test]
    fn example_garments_load_triangulate_and_sew_edge_to_edge() {
        for (file, panels, gap, h) in [
            ("skirt_specification.json", 2, [0.0, 0.0, 0.30], 0.02),
            ("skirt_specification.json", 2, [0.0, 0.0, 0.30], 0.0125),
            ("top_specification.json", 4, [0.0; 3], 0.02),
            ("top_specification.json", 4, [0.0; 3], 0.03),
        ] {
            let p = Pattern::load(examples().join(file)).unwrap();
            assert_eq!(p.panels.len(), panels);
            let g = p.triangulate(h).unwrap();
            assert_area(&p, &g, None);
            assert_on_curves(&p, &g);
            g.panels.iter().for_each(assert_well_formed);
            assert_eq!(g.stitches.len(), p.stitches.len());
            for (s, spec) in g.stitches.iter().zip(&p.stitches) {
                let [a, b] = spec.sides;
                assert_eq!(
                    g.panels[a.panel].edges[a.edge].len(),
                    g.panels[b.panel].edges[b.edge].len()
                );
                assert_eq!(s.pairs.len(), g.panels[a.panel].edges[a.edge].len());
                // the example panels are placed so that the seams meet (the skirt's front and
                // back 30 cm apart in z): paired vertices coincide up to that gap
                for &[u, v] in &s.pairs {
                    let d = g.panels[s.panels[0]].mesh.positions[u as usize]
                        - g.panels[s.panels[1]].mesh.positions[v as usize];
                    let d = [d.x.abs(), d.y.abs(), d.z.abs()];
                    assert!(
                        (0..3).all(|k| (d[k] - gap[k]).abs() < 1e-9),
                        "{file}: stitched pair {u}, {v} apart by {d:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn curved_panels_have_their_analytic_area() {
        let r = 20.0; // cm
        let half_disk = format!(
            r#""half": {{"vertices": [[-{r}, 0], [{r}, 0]], "edges": [
            {{"endpoints": [0, 1], "curvature": {{"type": "circle", "params": [{r}, 0, 0]}}}},
            {{"endpoints": [1, 0]}}]}}"#
        );
        // chord 24, radius 20, large arc: angle 2π − 2·asin(0.6)
        let big = r#""big": {"vertices": [[-12, 0], [12, 0]], "edges": [{"endpoints": [0, 1]},
            {"endpoints": [1, 0], "curvature": {"type": "circle", "params": [20, 1, 1]}}]}"#;
        // a 30 cm square whose bottom edge bulges out by a parabola of relative height 0.2:
        // area 900 + 0.2·30²/3 (the parabolic segment is 2/3 of its bounding rectangle)
        let bulge = r#""bulge": {"vertices": [[0, 0], [30, 0], [30, 30], [0, 30]], "edges": [
            {"endpoints": [0, 1], "curvature": {"type": "quadratic", "params": [[0.5, -0.2]]}},
            {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]}"#;
        // a cubic dent with control points at (1/3, 0.3) and (2/3, 0.3) on the top edge (running
        // in −x, so its left is −y): x is linear in t, the depth 0.3·L·3t(1−t), the area lost
        // 0.3·L²/2
        let cubic = r#""cubic": {"vertices": [[0, 0], [30, 0], [30, 30], [0, 30]], "edges": [
            {"endpoints": [0, 1]}, {"endpoints": [1, 2]},
            {"endpoints": [2, 3], "curvature": {"type": "cubic", "params": [[0.3333333333333333, 0.3], [0.6666666666666666, 0.3]]}},
            {"endpoints": [3, 0]}]}"#;
        let text = spec(&format!("{half_disk}, {big}, {bulge}, {cubic}"), "");
        let p = Pattern::parse(&text, "curves.json").unwrap();
        let theta = 2.0 * PI - 2.0 * 0.6f64.asin();
        let by_name = |n: &str| match n {
            "half" => PI * r * r / 2.0,
            "big" => 400.0 * (theta - theta.sin()) / 2.0,
            "bulge" => 900.0 + 0.2 * 900.0 / 3.0,
            "cubic" => 900.0 - 0.3 * 900.0 / 2.0,
            _ => unreachable!(),
        } * 1e-4;
        let expected: Vec<f64> = p.panels.iter().map(|q| by_name(&q.name)).collect();
        for h in [0.02, 0.01] {
            let g = p.triangulate(h).unwrap();
            assert_area(&p, &g, Some(&expected));
            assert_on_curves(&p, &g);
            g.panels.iter().for_each(assert_well_formed);
        }
    }

    #[test]
    fn stitches_pair_edges_by_arc_length_in_garmentcode_orientation() {
        // a 20 cm square and a 20 cm panel whose stitched edge is a longer curve
        let curvy = r#""curvy": {"vertices": [[0, 0], [20, 0], [20, 20], [0, 20]], "edges": [
            {"endpoints": [0, 1]}, {"endpoints": [1, 2], "curvature": {"type": "cubic", "params": [[0.1, -0.6], [0.6, 0.4]]}},
            {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]}"#;
        let sq = square("sq", 20.0);
        for right_wrong in [false, true] {
            let tail = if right_wrong {
                r#", "right_wrong""#
            } else {
                ""
            };
            let text = spec(
                &format!("{sq}, {curvy}"),
                &format!(
                    r#"[{{"panel": "sq", "edge": 0}}, {{"panel": "curvy", "edge": 1}}{tail}]"#
                ),
            );
            let p = Pattern::parse(&text, "pair.json").unwrap();
            let g = p.triangulate(0.03).unwrap();
            let (sq_m, cu_m) = (&g.panels[1], &g.panels[0]);
            assert_eq!((sq_m.name.as_str(), cu_m.name.as_str()), ("sq", "curvy"));
            let (ea, eb) = (&sq_m.edges[0], &cu_m.edges[1]);
            // both get the count of the longer (curved) edge
            let longer = (p.panels[0].edges[1].curve.length() / 100.0 / 0.03).round() as usize + 1;
            assert_eq!((ea.len(), eb.len()), (longer, longer));
            let s = &g.stitches[0];
            assert_eq!(s.panels, [1, 0]);
            // default: the first edge runs backwards (its end meets the second's start)
            let first = if right_wrong {
                ea[0]
            } else {
                *ea.last().unwrap()
            };
            assert_eq!(s.pairs[0], [first, eb[0]]);
            // pairs sit at equal fractions of the exact arc length along the two edges, each
            // taken in its stitching direction
            let fraction = |m: &PanelMesh, c: &Curve, v: u32, backwards: bool| {
                let q = m.flat[v as usize].map(|x| x * 100.0);
                let f = arc_length_to(c, closest_parameter(c, q)) / arc_length_to(c, 1.0);
                if backwards { 1.0 - f } else { f }
            };
            let (ca, cb) = (&p.panels[1].edges[0].curve, &p.panels[0].edges[1].curve);
            for (k, &[u, v]) in s.pairs.iter().enumerate() {
                let (x, y) = (
                    fraction(sq_m, ca, u, !right_wrong),
                    fraction(cu_m, cb, v, false),
                );
                assert!(
                    (x - y).abs() < 1e-4
                        && (x - k as f64 / (s.pairs.len() - 1) as f64).abs() < 1e-4,
                    "pair {k}: at {x} of one edge, {y} of the other"
                );
            }
        }
    }

    #[test]
    fn slivers_along_a_straight_edge_are_flipped_into_sound_triangles() {
        // one sliver: q lies 1e-15 off the chord p–r (rounding along a straight outline edge);
        // then a chain of two, where the first can only flip once the second has
        let one = (
            vec![[0.0, 0.0], [1.0, -1e-15], [2.0, 0.0], [1.0, 1.0]],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        let chain = (
            vec![
                [0.0, 0.0],
                [1.0, -1e-15],
                [2.0, -1e-15],
                [3.0, 0.0],
                [1.5, 1.0],
            ],
            vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]],
        );
        for (flat, mut tris) in [one, chain] {
            let area = |t: [u32; 3]| {
                0.5 * orient(
                    flat[t[0] as usize],
                    flat[t[1] as usize],
                    flat[t[2] as usize],
                )
            };
            let before: f64 = tris.iter().map(|&t| area(t)).sum();
            flip_slivers(&flat, &mut tris, 1.0);
            assert!(tris.iter().all(|&t| area(t) > 0.1), "{tris:?}");
            assert!((tris.iter().map(|&t| area(t)).sum::<f64>() - before).abs() < 1e-12);
            // the outer boundary 0 → 1 → … → last → 0 is kept
            let mut edges: Vec<(u32, u32)> = tris
                .iter()
                .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
                .collect();
            let all = edges.clone();
            edges.retain(|&(a, b)| !all.contains(&(b, a)));
            edges.sort();
            let n = flat.len() as u32;
            let ring: Vec<(u32, u32)> = (0..n).map(|i| (i, (i + 1) % n)).collect();
            let mut ring = ring;
            ring.sort();
            assert_eq!(edges, ring);
        }
    }

    #[test]
    fn an_outline_that_crosses_itself_only_once_subdivided_coarsely_is_an_error() {
        // a tall parabolic arch A → B and a return path that reaches A from below the arch but
        // above its chord: simple as drawn, crossed by the arch's chord A–apex at 2 segments
        let pocket = r#""pocket": {"vertices": [[0, 0], [20, 0], [20, -5], [5, -5], [3, 4.13]], "edges": [
            {"endpoints": [0, 1], "curvature": {"type": "quadratic", "params": [[0.5, 1.0]]}},
            {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 4]}, {"endpoints": [4, 0]}]}"#;
        let p = Pattern::parse(&spec(pocket, ""), "pocket.json").unwrap();
        let e = p.triangulate(0.5).unwrap_err().to_string();
        assert_mentions(
            &e,
            &["pocket.json", "panel `pocket`", "crosses itself", "smaller"],
        );
        let g = p.triangulate(0.005).unwrap();
        assert_area(&p, &g, None);
        assert_well_formed(&g.panels[0]);
    }

    /// A coordinate or an edge length orders of magnitude off is an error naming the file and
    /// the panel, before anything of the mesh's size is allocated (found by mutating the
    /// example patterns: a vertex at 1e308 cm ran out of memory).
    #[test]
    fn a_panel_beyond_the_vertex_limit_is_an_error() {
        for (side, h, what) in [
            (1e12, 0.01, "its outline"),
            (1e308, 0.01, "its outline"),
            (100.0, 1e-4, "the lattice"),
        ] {
            let text = spec(&square("huge", side), "");
            let e = Pattern::parse(&text, "huge.json")
                .unwrap()
                .triangulate(h)
                .unwrap_err()
                .to_string();
            assert_mentions(&e, &["huge.json", "panel `huge`", what, "at most 16777216"]);
        }
        // a fine panel well within the limit is meshed: a 1 m square at 5 mm has 800 outline
        // points and about 1 / (h · h √3/2) = 46 188 lattice points inside
        let text = spec(&square("fine", 100.0), "");
        let g = Pattern::parse(&text, "fine.json")
            .unwrap()
            .triangulate(5e-3)
            .unwrap();
        let n = g.panels[0].mesh.vertex_count();
        assert!((44_000..49_000).contains(&n), "{n} vertices");
    }

    #[test]
    fn an_edge_stitched_twice_and_a_bad_edge_length_are_errors() {
        let two = format!("{}, {}", square("a", 10.0), square("b", 10.0));
        let text = spec(
            &two,
            r#"[{"panel": "a", "edge": 1}, {"panel": "b", "edge": 3}], [{"panel": "a", "edge": 1}, {"panel": "b", "edge": 2}]"#,
        );
        let e = Pattern::parse(&text, "twice.json")
            .unwrap()
            .triangulate(0.01)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("twice.json") && e.contains("stitch 1") && e.contains("panel `a`"),
            "{e}"
        );
        let e = Pattern::parse(&text, "twice.json")
            .unwrap()
            .triangulate(0.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("twice.json") && e.contains("edge_length"), "{e}");
    }
}
