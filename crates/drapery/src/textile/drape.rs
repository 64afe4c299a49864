//! The Cusick drape test in simulation: the specimen disc ([`disc`]) and the drape coefficient
//! of its draped shape ([`drape_coefficient`]).
//!
//! A disc of fabric of radius `R_d` (30 cm specimen: 0.15 m) rests centred on a support disc of
//! radius `R_s` (0.09 m); the unsupported ring drapes into folds and a light above casts its
//! shadow. The drape coefficient is the share of the unsupported ring the shadow still covers:
//!
//! ```text
//! DC = (A_shadow − π R_s²) / (π R_d² − π R_s²)
//! ```
//!
//! 1 for a stiff disc that stays flat, 0 for one that hangs straight down from the support's
//! rim. `A_shadow` is the area of the vertical projection of the cloth: the union of its
//! triangles projected on the plane normal to `up`, counted on a square grid ([`shadow`]).

use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::mesh::{Face, Mesh};

/// Cells along the longer side of the shadow's bounding box in [`drape_coefficient`].
pub const CELLS: usize = 4096;

/// The projected area of a triangle mesh and how far from the true area of the union it can be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shadow {
    /// The area of the union of the projected triangles (m²), counted on the grid: cells whose
    /// centre lies in some projected triangle.
    pub area: f64,
    /// A bound on `|area − exact area|` (m²): a cell is miscounted only if the outline of the
    /// union crosses it, so within `h/√2` of the outline; that band has area at most
    /// `√2 h P + π h²/2`, `P` the outline's length, bounded by the total projected length of
    /// the mesh's boundary and fold (silhouette) edges, counting only triangles whose
    /// projection has area.
    pub error_bound: f64,
    /// The grid's cell size `h` (m).
    pub cell: f64,
}

/// An orthonormal basis `(a, b)` of the plane normal to `up` (`up` need not be unit).
fn plane_basis(up: Vec3) -> Result<(Vec3, Vec3)> {
    let len = up.length();
    if !(len.is_finite() && len > 0.0) {
        return Err(Error::Invalid(format!(
            "drape: up must be a non-zero finite vector, got ({}, {}, {})",
            up.x, up.y, up.z
        )));
    }
    let n = up / len;
    let a = n.any_orthonormal_vector();
    Ok((a, n.cross(a)))
}

/// The shadow of a triangle mesh seen along `up`: the area of the union of its triangles
/// projected on the plane normal to `up`, counted on a grid of `cells` cells along the longer
/// side of the projection's bounding box, with a bound on the counting error.
///
/// Errors if `up` is zero or not finite, `cells` is 0, a triangle indexes past `positions` or a
/// position is not finite.
pub fn shadow(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    up: Vec3,
    cells: usize,
) -> Result<Shadow> {
    let (a, b) = plane_basis(up)?;
    if cells == 0 {
        return Err(Error::Invalid(
            "drape: the grid needs at least one cell".into(),
        ));
    }
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(Error::Invalid(format!("drape: vertex {i} is not finite")));
    }
    for (k, t) in triangles.iter().enumerate() {
        if let Some(&i) = t.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(Error::Invalid(format!(
                "drape: triangle {k} uses vertex {i}, but there are {} vertices",
                positions.len()
            )));
        }
    }
    let flat: Vec<[f64; 2]> = positions.iter().map(|p| [p.dot(a), p.dot(b)]).collect();
    let used: Vec<[f64; 2]> = triangles
        .iter()
        .flat_map(|t| t.iter().map(|&i| flat[i as usize]))
        .collect();
    if used.is_empty() {
        return Ok(Shadow {
            area: 0.0,
            error_bound: 0.0,
            cell: 0.0,
        });
    }
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in &used {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if span <= 0.0 {
        return Ok(Shadow {
            area: 0.0,
            error_bound: 0.0,
            cell: 0.0,
        });
    }
    let h = span / cells as f64;
    let dims = [
        (((hi[0] - lo[0]) / h).ceil() as usize).clamp(1, cells),
        (((hi[1] - lo[1]) / h).ceil() as usize).clamp(1, cells),
    ];
    let mut covered = vec![false; dims[0] * dims[1]];
    // orientation of each projected triangle (its normal along up), for the fold edges
    let mut orientation = Vec::with_capacity(triangles.len());
    for t in triangles {
        let [p, q, r] = t.map(|i| flat[i as usize]);
        let area2 = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
        orientation.push(if area2 > 0.0 {
            1.0
        } else if area2 < 0.0 {
            -1.0
        } else {
            0.0
        });
        if area2 == 0.0 {
            continue;
        }
        // cell (i, j) has its centre at lo + h (i + ½, j + ½)
        let tlo = [p[0].min(q[0]).min(r[0]), p[1].min(q[1]).min(r[1])];
        let thi = [p[0].max(q[0]).max(r[0]), p[1].max(q[1]).max(r[1])];
        let first = |k: usize| (((tlo[k] - lo[k]) / h - 0.5).ceil().max(0.0)) as usize;
        let last = |k: usize| {
            ((((thi[k] - lo[k]) / h - 0.5).floor()).min(dims[k] as f64 - 1.0)).max(-1.0) as isize
        };
        let (i0, i1, j0, j1) = (first(0), last(0), first(1), last(1));
        if i1 < i0 as isize || j1 < j0 as isize {
            continue;
        }
        // a centre is inside when it is on the inner side of all three edges (edge function
        // ≥ 0 for a counter-clockwise triangle, ≤ 0 for a clockwise one)
        let s = area2.signum();
        let edge = |u: [f64; 2], v: [f64; 2], x: f64, y: f64| {
            s * ((v[0] - u[0]) * (y - u[1]) - (v[1] - u[1]) * (x - u[0]))
        };
        for j in j0..=j1 as usize {
            let y = lo[1] + h * (j as f64 + 0.5);
            for i in i0..=i1 as usize {
                let x = lo[0] + h * (i as f64 + 0.5);
                if edge(p, q, x, y) >= 0.0 && edge(q, r, x, y) >= 0.0 && edge(r, p, x, y) >= 0.0 {
                    covered[j * dims[0] + i] = true;
                }
            }
        }
    }
    let count = covered.iter().filter(|&&c| c).count();
    // outline length bound: the union of the projected triangles is that of the ones with
    // area, so its outline lies on their edges that are not shared by exactly two of them
    // facing the same way: boundary edges and fold (silhouette) edges
    // (a BTreeMap: the outline is summed in the same order every run)
    let mut sides: std::collections::BTreeMap<(u32, u32), Vec<f64>> =
        std::collections::BTreeMap::new();
    for (t, &o) in triangles.iter().zip(&orientation) {
        if o == 0.0 {
            continue;
        }
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            sides.entry((u.min(v), u.max(v))).or_default().push(o);
        }
    }
    let mut outline = 0.0;
    for ((u, v), o) in &sides {
        let inner = o.len() == 2 && o[0] == o[1];
        if !inner {
            let (p, q) = (flat[*u as usize], flat[*v as usize]);
            outline += (q[0] - p[0]).hypot(q[1] - p[1]);
        }
    }
    Ok(Shadow {
        area: count as f64 * h * h,
        error_bound: std::f64::consts::SQRT_2 * h * outline + std::f64::consts::FRAC_PI_2 * h * h,
        cell: h,
    })
}

/// The Cusick drape coefficient `(A_shadow − π R_s²) / (π R_d² − π R_s²)` of a draped
/// specimen: `positions` and `triangles` the cloth, `up` the vertical (the light's direction
/// reversed), `support_radius` `R_s` and `sample_radius` `R_d` (m; 0.09 and 0.15 in BS 5058 /
/// ISO 9073-9). The shadow is counted on a grid of [`CELLS`] cells across ([`shadow`] gives the
/// error bound; with the 30 cm specimen it is a few tenths of a percent of the coefficient).
///
/// Errors if the radii are not finite with `0 ≤ R_s < R_d`, or as [`shadow`].
pub fn drape_coefficient(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    up: Vec3,
    support_radius: f64,
    sample_radius: f64,
) -> Result<f64> {
    if !(support_radius.is_finite()
        && sample_radius.is_finite()
        && support_radius >= 0.0
        && sample_radius > support_radius)
    {
        return Err(Error::Invalid(format!(
            "drape: need 0 ≤ support_radius < sample_radius, got {support_radius} and {sample_radius}"
        )));
    }
    let s = shadow(positions, triangles, up, CELLS)?;
    Ok(coefficient(s.area, support_radius, sample_radius))
}

/// `(A − π R_s²) / (π R_d² − π R_s²)`.
fn coefficient(area: f64, support_radius: f64, sample_radius: f64) -> f64 {
    let support = std::f64::consts::PI * support_radius * support_radius;
    let sample = std::f64::consts::PI * sample_radius * sample_radius;
    (area - support) / (sample - support)
}

/// A flat disc of `radius` (m) in the plane z = 0, centred at the origin, triangulated in
/// concentric rings about `edge_length` (m) apart: ring `k` (of `n = ⌈radius / edge_length⌉`)
/// has `6k` vertices on the circle of radius `k · radius / n`, so the edges along and across
/// the rings are all close to `radius / n`; the outer ring's vertices lie on the circle.
/// Triangles wind counter-clockwise seen from +z.
///
/// Errors if `radius` or `edge_length` is not a finite number > 0 or the disc would need more
/// than 2²⁴ vertices.
pub fn disc(radius: f64, edge_length: f64) -> Result<Mesh> {
    check_disc(radius, edge_length)?;
    let rings = (radius / edge_length).ceil() as usize;
    let radii = (1..=rings).map(|k| radius * k as f64 / rings as f64);
    Ok(zip_rings(radii.zip((1..=rings).map(|k| 6 * k)).collect()))
}

/// [`disc`] with a ring of vertices on the circle of radius `ring` (`0 < ring < radius`; the
/// rim of a drape tester's support): `n₁ = ⌈ring / edge_length⌉` rings evenly spaced inside it,
/// ring `k` with `6k` vertices, and `n₂ = ⌈(radius − ring) / edge_length⌉` evenly spaced from it
/// to the edge, each with 6 times its radius over that spacing (rounded) vertices, so both
/// parts' edges are close to their spacing (both at most `edge_length`, up to rounding).
///
/// Errors as [`disc`], and if `ring` is not strictly between 0 and `radius`.
pub fn disc_with_ring(radius: f64, edge_length: f64, ring: f64) -> Result<Mesh> {
    check_disc(radius, edge_length)?;
    if !(ring.is_finite() && ring > 0.0 && ring < radius) {
        return Err(Error::Invalid(format!(
            "disc: ring must lie strictly between 0 and the radius {radius}, got {ring}"
        )));
    }
    // a quotient within rounding above a whole number is that number
    let count = |length: f64| ((length / edge_length) * (1.0 - 1e-12)).ceil().max(1.0) as usize;
    let (inner, outer) = (count(ring), count(radius - ring));
    let spacing = (radius - ring) / outer as f64;
    let mut rings: Vec<(f64, usize)> = (1..=inner)
        .map(|k| (ring * k as f64 / inner as f64, 6 * k))
        .collect();
    for j in 1..=outer {
        let r = if j == outer {
            radius
        } else {
            ring + (radius - ring) * j as f64 / outer as f64
        };
        let m = (6.0 * (r / spacing).round()) as usize;
        rings.push((r, m.max(rings.last().map_or(6, |l| l.1))));
    }
    Ok(zip_rings(rings))
}

/// The argument checks of [`disc`] and [`disc_with_ring`].
fn check_disc(radius: f64, edge_length: f64) -> Result<()> {
    for (name, v) in [("radius", radius), ("edge_length", edge_length)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::Invalid(format!(
                "disc: {name} must be a finite number > 0, got {v}"
            )));
        }
    }
    if (radius / edge_length).ceil() > 2000.0 {
        return Err(Error::Invalid(format!(
            "disc: radius / edge_length = {} needs too many vertices (at most 2000 rings)",
            radius / edge_length
        )));
    }
    Ok(())
}

/// The disc whose rings are `(radius, vertex count)`, inside out, around a centre vertex: ring
/// `k`'s vertices at equal angles (odd rings start at 0, even ones half a step on, so the strips
/// zig-zag), and each strip between two rings zipped by increasing angle.
fn zip_rings(rings: Vec<(f64, usize)>) -> Mesh {
    let tau = std::f64::consts::TAU;
    // alternate rings are turned by half a step so the strips between them zig-zag
    let offset = |ring: usize| if ring.is_multiple_of(2) { 0.5 } else { 0.0 };
    let mut positions = vec![Vec3::ZERO];
    // first vertex index and vertex count of each ring
    let mut start = vec![0usize];
    let mut count = vec![1usize];
    for (k, &(r, m)) in rings.iter().enumerate() {
        let k = k + 1;
        start.push(positions.len());
        count.push(m);
        for i in 0..m {
            let a = tau * (i as f64 + offset(k)) / m as f64;
            positions.push(Vec3::new(r * a.cos(), r * a.sin(), 0.0));
        }
    }
    let angle = |v: usize, ring: usize| -> f64 {
        tau * ((v - start[ring]) as f64 + offset(ring)) / count[ring] as f64
    };
    let mut faces = Vec::new();
    for k in 1..=rings.len() {
        if k == 1 {
            let first = count[1];
            for i in 0..first {
                let a = start[1] + i;
                let b = start[1] + (i + 1) % first;
                faces.push(Face::Tri([0, a as u32, b as u32]));
            }
            continue;
        }
        // zip the inner ring (k−1) and the outer ring (k) by increasing angle
        let (inner, outer) = (k - 1, k);
        let (mi, mo) = (count[inner], count[outer]);
        let (mut i, mut o) = (0usize, 0usize);
        let at = |ring: usize, j: usize| start[ring] + j % count[ring];
        // unwrapped angle of the j-th vertex of a ring, continuing past 2π
        let unwrapped =
            |ring: usize, j: usize| angle(at(ring, j), ring) + tau * (j / count[ring]) as f64;
        while i < mi || o < mo {
            let advance_outer = if i == mi {
                true
            } else if o == mo {
                false
            } else {
                unwrapped(outer, o + 1) <= unwrapped(inner, i + 1)
            };
            if advance_outer {
                faces.push(Face::Tri([
                    at(inner, i) as u32,
                    at(outer, o) as u32,
                    at(outer, o + 1) as u32,
                ]));
                o += 1;
            } else {
                faces.push(Face::Tri([
                    at(inner, i) as u32,
                    at(outer, o) as u32,
                    at(inner, i + 1) as u32,
                ]));
                i += 1;
            }
        }
    }
    // a disc has no line elements
    Mesh {
        positions,
        faces,
        ..Mesh::default()
    }
}

/// The Cusick tester's support: a closed cylinder of `radius` (m) about the z axis, its flat top
/// at z = 0 and its bottom at z = −`height`, with `segments` vertices around each rim and a
/// centre vertex on each cap (a sharp rim: the top is flat out to the circle). Triangles wind
/// outward. For a mesh collider (`shape = "mesh"`).
///
/// Errors if `radius` or `height` is not a finite number > 0 or `segments` < 3.
pub fn support(radius: f64, height: f64, segments: usize) -> Result<Mesh> {
    for (name, v) in [("radius", radius), ("height", height)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::Invalid(format!(
                "support: {name} must be a finite number > 0, got {v}"
            )));
        }
    }
    if !(3..=1 << 20).contains(&segments) {
        return Err(Error::Invalid(format!(
            "support: segments must be from 3 to 2²⁰, got {segments}"
        )));
    }
    let m = segments as u32;
    let tau = std::f64::consts::TAU;
    // 0: top centre, 1: bottom centre, then the top rim (2..2+m), then the bottom rim
    let mut positions = vec![Vec3::ZERO, Vec3::new(0.0, 0.0, -height)];
    for z in [0.0, -height] {
        for i in 0..segments {
            let a = tau * i as f64 / segments as f64;
            positions.push(Vec3::new(radius * a.cos(), radius * a.sin(), z));
        }
    }
    let (top, bottom) = (|i: u32| 2 + i % m, |i: u32| 2 + m + i % m);
    let mut faces = Vec::with_capacity(4 * segments);
    for i in 0..m {
        faces.push(Face::Tri([0, top(i), top(i + 1)]));
        faces.push(Face::Tri([1, bottom(i + 1), bottom(i)]));
        faces.push(Face::Tri([top(i), bottom(i), bottom(i + 1)]));
        faces.push(Face::Tri([top(i), bottom(i + 1), top(i + 1)]));
    }
    Ok(Mesh {
        positions,
        faces,
        ..Mesh::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const RS: f64 = 0.09;
    const RD: f64 = 0.15;

    fn area_of(m: &Mesh) -> f64 {
        m.triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                0.5 * (b - a).cross(c - a).z
            })
            .sum()
    }

    #[test]
    fn disc_has_the_circle_s_area_and_even_edges() {
        for (r, e) in [(0.15, 0.005), (1.0, 0.05), (0.15, 0.02)] {
            let m = disc(r, e).unwrap();
            m.validate("disc").unwrap();
            // every triangle counter-clockwise, none degenerate
            for t in m.triangles() {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                assert!((b - a).cross(c - a).z > 0.1 * e * e, "{t:?}");
            }
            let area = area_of(&m);
            assert!((area / (PI * r * r) - 1.0).abs() < 0.005, "{area}");
            // the area is exactly the inscribed polygon's: n sides on the circle
            let n = 6 * (r / e).ceil() as usize;
            let polygon = 0.5 * n as f64 * r * r * (std::f64::consts::TAU / n as f64).sin();
            assert!((area - polygon).abs() < 1e-12 * polygon);
            // edge lengths stay within a factor of the target spacing radius / rings
            let spacing = r / (r / e).ceil();
            for [u, v] in m.edges() {
                let d = (m.positions[u as usize] - m.positions[v as usize]).length();
                assert!(d > 0.5 * spacing && d < 1.5 * spacing, "{d} vs {spacing}");
            }
            // a disc: V − E + F = 1, and boundary vertices on the circle
            let (v, ed, f) = (m.vertex_count(), m.edges().len(), m.faces.len());
            assert_eq!(v as isize - ed as isize + f as isize, 1);
            let outer = m
                .positions
                .iter()
                .filter(|p| (p.length() - r).abs() < 1e-12)
                .count();
            assert_eq!(outer, n);
        }
        assert!(disc(0.0, 0.01).is_err());
        assert!(disc(0.1, f64::NAN).is_err());
        assert!(disc(1.0, 1e-6).is_err());
    }

    /// With a ring on the support's rim: a valid disc with a ring of vertices on that circle,
    /// the circle's area, edges close to the two parts' spacings, counter-clockwise triangles.
    #[test]
    fn disc_with_a_ring_has_vertices_on_the_ring() {
        for (r, e, ring) in [
            (RD, 0.02, RS),
            (RD, 0.01, RS),
            (RD, 0.005, RS),
            (1.0, 0.07, 0.33),
        ] {
            let m = disc_with_ring(r, e, ring).unwrap();
            m.validate("disc").unwrap();
            for t in m.triangles() {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                assert!((b - a).cross(c - a).z > 0.1 * e * e, "{t:?}");
            }
            let (v, ed, f) = (m.vertex_count(), m.edges().len(), m.faces.len());
            assert_eq!(v as isize - ed as isize + f as isize, 1);
            let on = |radius: f64| {
                m.positions
                    .iter()
                    .filter(|p| (p.length() - radius).abs() < 1e-12)
                    .count()
            };
            let inner = (ring / e * (1.0 - 1e-12)).ceil() as usize;
            assert_eq!(on(ring), 6 * inner, "r {r}, e {e}");
            assert!(on(r) >= 6 * inner);
            let area = area_of(&m);
            assert!((area / (PI * r * r) - 1.0).abs() < 0.01, "{area}");
            // the plain disc's bounds, (0.5, 1.5) times the spacing, with spacings in [0.8 e, e]
            for [u, w] in m.edges() {
                let d = (m.positions[u as usize] - m.positions[w as usize]).length();
                assert!(d > 0.4 * e && d < 1.5 * e, "{d} against {e}");
            }
        }
        // at 1 cm the rings of the plain disc already fall on 9 cm: the same vertices
        let (plain, ringed) = (
            disc(RD, 0.01).unwrap(),
            disc_with_ring(RD, 0.01, RS).unwrap(),
        );
        assert_eq!(plain.faces, ringed.faces);
        for (p, q) in plain.positions.iter().zip(&ringed.positions) {
            assert!((*p - *q).length() < 1e-15);
        }
        for ring in [0.0, RD, 0.2, -0.1, f64::NAN] {
            assert!(disc_with_ring(RD, 0.01, ring).is_err(), "{ring}");
        }
    }

    fn tri(m: &Mesh) -> Vec<[u32; 3]> {
        m.triangles()
    }

    #[test]
    fn a_flat_specimen_has_coefficient_one() {
        let m = disc(RD, 0.005).unwrap();
        let s = shadow(&m.positions, &tri(&m), Vec3::Z, CELLS).unwrap();
        // the flat disc's shadow is the polygon itself
        let exact = area_of(&m);
        assert!(
            (s.area - exact).abs() <= s.error_bound,
            "{} vs {exact}",
            s.area
        );
        let dc = drape_coefficient(&m.positions, &tri(&m), Vec3::Z, RS, RD).unwrap();
        let expected = coefficient(exact, RS, RD);
        let bound = s.error_bound / (PI * (RD * RD - RS * RS));
        assert!(
            (dc - expected).abs() <= bound,
            "{dc} vs {expected} ± {bound}"
        );
        // and the polygon falls short of the circle by less than 0.1 %: DC ≈ 1
        assert!(
            (dc - 1.0).abs() < 2e-3 + bound && bound < 5e-3,
            "{dc}, bound {bound}"
        );
    }

    #[test]
    fn a_skirt_hanging_from_the_support_has_coefficient_zero() {
        // the support's disc plus a cylinder hanging from its rim down to the specimen's length
        let mut m = disc(RS, 0.005).unwrap();
        let n = 6 * (RS / 0.005_f64).ceil() as usize;
        let rim: Vec<u32> = (0..m.positions.len() as u32)
            .filter(|&i| (m.positions[i as usize].length() - RS).abs() < 1e-12)
            .collect();
        assert_eq!(rim.len(), n);
        let rows = 12;
        let drop = RD - RS;
        let mut previous = rim.clone();
        for r in 1..=rows {
            let z = -drop * r as f64 / rows as f64;
            let row: Vec<u32> = previous
                .iter()
                .map(|&i| {
                    let p = m.positions[i as usize];
                    m.positions.push(Vec3::new(p.x, p.y, z));
                    (m.positions.len() - 1) as u32
                })
                .collect();
            for k in 0..n {
                let (a, b) = (previous[k], previous[(k + 1) % n]);
                let (c, d) = (row[k], row[(k + 1) % n]);
                m.faces.push(Face::Tri([a, c, d]));
                m.faces.push(Face::Tri([a, d, b]));
            }
            previous = row;
        }
        let s = shadow(&m.positions, &tri(&m), Vec3::Z, CELLS).unwrap();
        let dc = drape_coefficient(&m.positions, &tri(&m), Vec3::Z, RS, RD).unwrap();
        let polygon = 0.5 * n as f64 * RS * RS * (std::f64::consts::TAU / n as f64).sin();
        let bound = s.error_bound / (PI * (RD * RD - RS * RS));
        let expected = coefficient(polygon, RS, RD);
        assert!(
            (dc - expected).abs() <= bound,
            "{dc} vs {expected} ± {bound}"
        );
        assert!(
            dc.abs() < 2e-3 + bound && bound < 5e-3,
            "{dc}, bound {bound}"
        );
    }

    /// A `2a × b` sheet folded in half over itself: the right half lies back over the left
    /// half 1 mm above it, so the shadow is the `a × b` left half.
    fn folded(a: f64, b: f64, n: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let cols = 2 * n + 1;
        let rows = n + 1;
        let mut positions = Vec::new();
        for j in 0..rows {
            for i in 0..cols {
                let x = 2.0 * a * i as f64 / (cols - 1) as f64;
                let y = b * j as f64 / (rows - 1) as f64;
                let (x, z) = if x <= a {
                    (x, 0.0)
                } else {
                    (2.0 * a - x, 1e-3)
                };
                positions.push(Vec3::new(x, y, z));
            }
        }
        let mut triangles = Vec::new();
        for j in 0..rows - 1 {
            for i in 0..cols - 1 {
                let v = (j * cols + i) as u32;
                let c = cols as u32;
                triangles.push([v, v + 1, v + c + 1]);
                triangles.push([v, v + c + 1, v + c]);
            }
        }
        (positions, triangles)
    }

    #[test]
    fn a_folded_sheet_casts_the_shadow_of_one_layer() {
        let (a, b) = (0.1, 0.07);
        let (p, t) = folded(a, b, 20);
        let s = shadow(&p, &t, Vec3::Z, 2048).unwrap();
        assert!(
            (s.area - a * b).abs() <= s.error_bound,
            "{} vs {}",
            s.area,
            a * b
        );
        // the bound counts the outline once over (boundary and the fold): 2(2a + b) + b
        let outline = 2.0 * (2.0 * a + b) + b;
        let bound = std::f64::consts::SQRT_2 * s.cell * outline + PI / 2.0 * s.cell * s.cell;
        assert!((s.error_bound - bound).abs() < 1e-12 * bound);
        // twice the shadow of the flat, unfolded sheet would be wrong by a·b: the union counts
        // overlapping layers once
        assert!(s.area < 1.01 * a * b);
        // the same fold seen along any up, rotated with the sheet, has the same shadow
        let q = glam::DQuat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
        let rotated: Vec<Vec3> = p.iter().map(|&v| q * v).collect();
        let r = shadow(&rotated, &t, q * Vec3::Z, 2048).unwrap();
        assert!((r.area - a * b).abs() <= r.error_bound);
        // and a sheet tilted by α about the y axis casts cos α of its area
        let alpha: f64 = 0.6;
        let tilt = glam::DQuat::from_rotation_y(alpha);
        let (flat, ft) = folded(a, b, 20);
        let unfolded: Vec<Vec3> = flat
            .iter()
            .map(|v| tilt * Vec3::new(v.x, v.y, 0.0))
            .collect();
        let only_left: Vec<[u32; 3]> = ft
            .into_iter()
            .filter(|t| t.iter().all(|&i| flat[i as usize].z == 0.0))
            .collect();
        let s = shadow(&unfolded, &only_left, Vec3::Z, 2048).unwrap();
        assert!((s.area - a * b * alpha.cos()).abs() <= s.error_bound);
    }

    #[test]
    fn an_annulus_shadow_gives_the_expected_coefficient() {
        // a flat disc of radius r between R_s and R_d: DC = (r² − R_s²)/(R_d² − R_s²)
        let m = disc(0.12, 0.004).unwrap();
        let dc = drape_coefficient(&m.positions, &tri(&m), Vec3::Z, RS, RD).unwrap();
        let s = shadow(&m.positions, &tri(&m), Vec3::Z, CELLS).unwrap();
        let bound = s.error_bound / (PI * (RD * RD - RS * RS));
        let expected = coefficient(area_of(&m), RS, RD);
        let analytic = (0.12_f64.powi(2) - RS * RS) / (RD * RD - RS * RS);
        assert!(
            (dc - expected).abs() <= bound,
            "{dc} vs {expected} ± {bound}"
        );
        assert!((expected - analytic).abs() < 1e-3 * analytic + 2e-3);
    }

    #[test]
    fn bad_input_is_an_error() {
        let m = disc(RD, 0.02).unwrap();
        let t = tri(&m);
        assert!(drape_coefficient(&m.positions, &t, Vec3::ZERO, RS, RD).is_err());
        assert!(drape_coefficient(&m.positions, &t, Vec3::Z, RD, RS).is_err());
        assert!(drape_coefficient(&m.positions, &t, Vec3::Z, -0.1, RD).is_err());
        assert!(drape_coefficient(&m.positions, &[[0, 1, 100_000]], Vec3::Z, RS, RD).is_err());
        let mut nan = m.positions.clone();
        nan[3].x = f64::NAN;
        assert!(drape_coefficient(&nan, &t, Vec3::Z, RS, RD).is_err());
        assert!(shadow(&m.positions, &t, Vec3::Z, 0).is_err());
        // no triangles: no shadow, and the coefficient says the cloth covers less than the
        // support
        assert_eq!(shadow(&m.positions, &[], Vec3::Z, 16).unwrap().area, 0.0);
    }

    #[test]
    fn the_support_is_a_closed_outward_cylinder() {
        let (r, h, n) = (0.09, 0.01, 64);
        let m = support(r, h, n).unwrap();
        m.validate("support").unwrap();
        // closed: every edge in exactly two triangles, opposite ways
        let mut count = std::collections::BTreeMap::new();
        for t in m.triangles() {
            for k in 0..3 {
                *count.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &c) in &count {
            assert_eq!((c, count.get(&(b, a))), (1, Some(&1)), "{a}–{b}");
        }
        // outward: the divergence theorem gives the polygon prism's volume, positive
        let volume: f64 = (m.triangles().iter())
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        let polygon = 0.5 * n as f64 * r * r * (std::f64::consts::TAU / n as f64).sin();
        assert!((volume - polygon * h).abs() < 1e-12 * volume, "{volume}");
        // the top is flat at z = 0 out to the rim
        let top: Vec<&Vec3> = m.positions.iter().filter(|p| p.z == 0.0).collect();
        assert_eq!(top.len(), n + 1);
        assert!(support(0.0, h, n).is_err() && support(r, h, 2).is_err());
    }
}
