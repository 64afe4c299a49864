//! The GarmentCode pattern specification: the JSON that `pygarment` writes
//! (`*_specification.json`), read into [`Pattern`].
//!
//! The layout, as pygarment writes and reads it:
//! ```json
//! { "pattern": {
//!     "panels": { "front": {
//!         "translation": [0, 40, 15],            // pattern units
//!         "rotation": [0, 180, 0],               // degrees, R = Rz·Ry·Rx
//!         "vertices": [[-30, 0], [30, 0], ...],  // 2-D, pattern units
//!         "edges": [ { "endpoints": [0, 1],
//!                      "curvature": { "type": "circle", "params": [80, 0, 1] } }, ... ] } },
//!     "stitches": [ [ {"panel": "front", "edge": 1}, {"panel": "back", "edge": 3} ], ... ] },
//!   "properties": { "units_in_meter": 100, "curvature_coords": "relative" } }
//! ```
//! Conventions (those of pygarment's mesh generator, which GarmentCodeData was simulated with):
//! - Bézier control points (`quadratic`: one, `cubic`: two; a bare `[x, y]` list is an old-style
//!   quadratic) are relative to the edge: `start + x·(end − start) + y·perp`, where
//!   `perp = (−(end − start).y, (end − start).x)` is the edge vector turned a quarter left.
//!   With `properties.curvature_coords = "absolute"` they are panel coordinates instead.
//! - With `properties.normalize_panel_translation = true` (old data), each panel's vertices are
//!   moved so that their mean is the origin and that mean is added to the translation's x and y
//!   (unrotated, as pygarment does).
//! - A `circle` edge has `params = [radius, large_arc, right]`: an SVG-style arc from start to
//!   end (radius in pattern units, raised to half the chord if smaller) that turns
//!   counter-clockwise (increasing angle, y up) when `right` is 1, so a small arc bulges to
//!   the right of the edge's direction.
//! - `rotation` is Euler angles in degrees composed as `R = Rz(z)·Ry(y)·Rx(x)` (pygarment's
//!   `euler_xyz_to_R`); a panel point `(x, y)` goes to `R·(x, y, 0) + translation`.
//! - A stitch is `[side0, side1]` or `[side0, side1, "right_wrong"]`. By default the first edge
//!   runs backwards against the second (edge 0's end meets edge 1's start); with `right_wrong`
//!   both run forwards.
//! - Lengths are in pattern units; `units_in_meter` (100 when absent: centimetres) converts.

use crate::error::{Error, Result};
use serde_json::Value;
use std::path::Path;

/// A 2-D point in panel coordinates.
pub type Point2 = [f64; 2];

/// One edge's exact shape, in absolute panel coordinates (pattern units).
#[derive(Clone, Debug, PartialEq)]
pub enum Curve {
    /// A straight segment.
    Line {
        /// Start point.
        start: Point2,
        /// End point.
        end: Point2,
    },
    /// A quadratic Bézier curve.
    Quadratic {
        /// Start, control and end points.
        points: [Point2; 3],
    },
    /// A cubic Bézier curve.
    Cubic {
        /// Start, two control points, end.
        points: [Point2; 4],
    },
    /// A circular arc.
    Arc {
        /// Centre of the circle.
        center: Point2,
        /// Radius (after raising it to half the chord if it was smaller).
        radius: f64,
        /// Angle of the start point about the centre (radians).
        start_angle: f64,
        /// Signed angle swept from start to end (radians, > 0 counter-clockwise).
        sweep: f64,
    },
}

fn lerp(a: Point2, b: Point2, t: f64) -> Point2 {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
}

impl Curve {
    /// The point at parameter `t ∈ [0, 1]` (0 at the edge's start, 1 at its end).
    pub fn point(&self, t: f64) -> Point2 {
        match self {
            Curve::Line { start, end } => lerp(*start, *end, t),
            Curve::Quadratic { points: [a, b, c] } => lerp(lerp(*a, *b, t), lerp(*b, *c, t), t),
            Curve::Cubic {
                points: [a, b, c, d],
            } => {
                let (ab, bc, cd) = (lerp(*a, *b, t), lerp(*b, *c, t), lerp(*c, *d, t));
                lerp(lerp(ab, bc, t), lerp(bc, cd, t), t)
            }
            Curve::Arc {
                center,
                radius,
                start_angle,
                sweep,
            } => {
                let a = start_angle + sweep * t;
                [center[0] + radius * a.cos(), center[1] + radius * a.sin()]
            }
        }
    }

    /// Whether the parameter is proportional to arc length (lines and arcs).
    pub fn is_uniform(&self) -> bool {
        matches!(self, Curve::Line { .. } | Curve::Arc { .. })
    }

    /// Arc length (exact for lines and arcs, from a fine polyline for Bézier curves).
    pub fn length(&self) -> f64 {
        match self {
            Curve::Line { start, end } => dist(*start, *end),
            Curve::Arc { radius, sweep, .. } => radius * sweep.abs(),
            _ => {
                let table = self.length_table();
                *table.last().unwrap()
            }
        }
    }

    /// Number of samples in a Bézier curve's arc-length table.
    const TABLE: usize = 4096;

    /// Cumulative polyline length at `t = i / TABLE`, `i = 0..=TABLE`.
    fn length_table(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(Self::TABLE + 1);
        let mut prev = self.point(0.0);
        let mut s = 0.0;
        out.push(0.0);
        for i in 1..=Self::TABLE {
            let p = self.point(i as f64 / Self::TABLE as f64);
            s += dist(prev, p);
            out.push(s);
            prev = p;
        }
        out
    }

    /// Parameters of `n + 1` points spaced evenly by arc length, `t[0] = 0`, `t[n] = 1`.
    pub fn arc_length_parameters(&self, n: usize) -> Vec<f64> {
        if self.is_uniform() {
            return (0..=n).map(|i| i as f64 / n as f64).collect();
        }
        let table = self.length_table();
        let total = *table.last().unwrap();
        let mut out = Vec::with_capacity(n + 1);
        let mut j = 0;
        for i in 0..=n {
            if i == 0 || i == n {
                out.push(i as f64 / n as f64);
                continue;
            }
            let s = total * i as f64 / n as f64;
            while j + 1 < Self::TABLE && table[j + 1] < s {
                j += 1;
            }
            let span = table[j + 1] - table[j];
            let f = if span > 0.0 {
                (s - table[j]) / span
            } else {
                0.0
            };
            out.push((j as f64 + f.clamp(0.0, 1.0)) / Self::TABLE as f64);
        }
        out
    }
}

pub(crate) fn dist(a: Point2, b: Point2) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// One outline edge of a panel.
#[derive(Clone, Debug, PartialEq)]
pub struct Edge {
    /// Indices of its start and end vertices in the panel's `vertices`.
    pub endpoints: [usize; 2],
    /// Its exact shape.
    pub curve: Curve,
}

/// One panel: a closed outline of edges in its own plane, and its placement in 3-D.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// The panel's name (its key in `pattern.panels`).
    pub name: String,
    /// 2-D vertices, pattern units.
    pub vertices: Vec<Point2>,
    /// The outline, in loop order: each edge ends where the next starts.
    pub edges: Vec<Edge>,
    /// Translation, pattern units.
    pub translation: [f64; 3],
    /// XYZ Euler angles in degrees (`R = Rz·Ry·Rx`).
    pub rotation: [f64; 3],
}

impl Panel {
    /// The rotation matrix (rows) of the panel's Euler angles: `Rz(z)·Ry(y)·Rx(x)`.
    pub fn rotation_matrix(&self) -> [[f64; 3]; 3] {
        let [x, y, z] = self.rotation.map(f64::to_radians);
        let (sx, cx) = x.sin_cos();
        let (sy, cy) = y.sin_cos();
        let (sz, cz) = z.sin_cos();
        let rz = [[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]];
        let ry = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]];
        let rx = [[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]];
        matmul(matmul(rz, ry), rx)
    }

    /// Closed outline sampled with `per_edge` points per edge (each edge's end omitted).
    pub(crate) fn sampled_outline(&self, per_edge: usize) -> Vec<Point2> {
        let mut out = Vec::with_capacity(per_edge * self.edges.len());
        for e in &self.edges {
            for i in 0..per_edge {
                out.push(e.curve.point(i as f64 / per_edge as f64));
            }
        }
        out
    }
}

fn matmul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

/// One side of a stitch: a panel (index into [`Pattern::panels`]) and one of its edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeRef {
    /// Panel index.
    pub panel: usize,
    /// Edge index within the panel.
    pub edge: usize,
}

/// A stitch between two edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StitchSpec {
    /// The two edges.
    pub sides: [EdgeRef; 2],
    /// `right_wrong`: both edges run forwards; otherwise the first runs backwards.
    pub right_wrong: bool,
}

/// A GarmentCode pattern specification.
#[derive(Clone, Debug, PartialEq)]
pub struct Pattern {
    /// Where it was read from (used in error messages).
    pub origin: String,
    /// Pattern units per metre.
    pub units_in_meter: f64,
    /// The panels, in `pattern.panel_order` if given, else by name.
    pub panels: Vec<Panel>,
    /// The stitches, in file order.
    pub stitches: Vec<StitchSpec>,
}

/// Number of samples per edge for the self-crossing check at load time.
const CHECK_SAMPLES: usize = 32;

impl Pattern {
    /// Reads a pattern specification file.
    pub fn load(path: impl AsRef<Path>) -> Result<Pattern> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path.display(), e))?;
        Pattern::parse(&text, &path.display().to_string())
    }

    /// Parses a pattern specification from text; `origin` names it in errors.
    pub fn parse(text: &str, origin: &str) -> Result<Pattern> {
        let bad = |m: String| Error::input(origin, m);
        let root: Value = serde_json::from_str(text).map_err(|e| bad(format!("not JSON: {e}")))?;
        let not_pattern =
            || bad("not a GarmentCode pattern specification (no `pattern.panels` object)".into());
        let pattern = root.get("pattern").ok_or_else(not_pattern)?;
        let panels_json = pattern
            .get("panels")
            .and_then(Value::as_object)
            .ok_or_else(not_pattern)?;
        let props = root.get("properties");
        let units_in_meter = match props.and_then(|p| p.get("units_in_meter")) {
            None => 100.0,
            Some(v) => match v.as_f64() {
                Some(u) if u.is_finite() && u > 0.0 => u,
                _ => {
                    return Err(bad(format!(
                        "properties.units_in_meter must be a number > 0, got {v}"
                    )));
                }
            },
        };
        let absolute = props
            .and_then(|p| p.get("curvature_coords"))
            .and_then(Value::as_str)
            == Some("absolute");
        let center = props
            .and_then(|p| p.get("normalize_panel_translation"))
            .and_then(Value::as_bool)
            == Some(true);

        // panel order: pattern.panel_order when it names exactly the panels, else by name
        let mut names: Vec<&String> = panels_json.keys().collect();
        if let Some(order) = pattern.get("panel_order").and_then(Value::as_array) {
            let listed: Vec<&String> = order
                .iter()
                .filter_map(|v| v.as_str())
                .filter_map(|s| panels_json.get_key_value(s).map(|(k, _)| k))
                .collect();
            let mut sorted = listed.clone();
            sorted.sort();
            sorted.dedup();
            if sorted.len() == names.len() && listed.len() == names.len() {
                names = listed;
            }
        }
        let mut panels = Vec::with_capacity(names.len());
        for name in names {
            panels.push(parse_panel(
                name,
                &panels_json[name],
                absolute,
                center,
                origin,
            )?);
        }

        let mut stitches = Vec::new();
        if let Some(list) = pattern.get("stitches") {
            let list = list
                .as_array()
                .ok_or_else(|| bad("pattern.stitches must be a list".into()))?;
            for (i, s) in list.iter().enumerate() {
                stitches.push(parse_stitch(i, s, &panels, origin)?);
            }
        }
        let p = Pattern {
            origin: origin.to_string(),
            units_in_meter,
            panels,
            stitches,
        };
        for panel in &p.panels {
            p.check_simple(panel, &panel.sampled_outline(CHECK_SAMPLES), "")?;
        }
        Ok(p)
    }

    /// Index of the panel named `name`.
    pub fn panel_index(&self, name: &str) -> Option<usize> {
        self.panels.iter().position(|p| p.name == name)
    }

    /// Errors if the closed polygon `ring` (an outline of `panel`) crosses itself.
    pub(crate) fn check_simple(&self, panel: &Panel, ring: &[Point2], hint: &str) -> Result<()> {
        if let Some((i, j)) = first_crossing(ring) {
            return Err(Error::input(
                &self.origin,
                format!(
                    "panel `{}`: its outline crosses itself (segments {i} and {j} of {}){hint}",
                    panel.name,
                    ring.len()
                ),
            ));
        }
        Ok(())
    }
}

fn num(v: Option<&Value>) -> Option<f64> {
    v.and_then(Value::as_f64).filter(|x| x.is_finite())
}

fn point(v: &Value) -> Option<Point2> {
    let a = v.as_array()?;
    if a.len() != 2 {
        return None;
    }
    Some([num(a.first())?, num(a.get(1))?])
}

fn vec3(v: Option<&Value>) -> Option<[f64; 3]> {
    let a = v?.as_array()?;
    if a.len() != 3 {
        return None;
    }
    Some([num(a.first())?, num(a.get(1))?, num(a.get(2))?])
}

fn parse_panel(name: &str, v: &Value, absolute: bool, center: bool, origin: &str) -> Result<Panel> {
    let bad = |m: String| Error::input(origin, format!("panel `{name}`: {m}"));
    let vertices: Vec<Point2> = v
        .get("vertices")
        .and_then(Value::as_array)
        .ok_or_else(|| bad("`vertices` must be a list of [x, y]".into()))?
        .iter()
        .enumerate()
        .map(|(i, p)| point(p).ok_or_else(|| bad(format!("vertices[{i}] must be [x, y], got {p}"))))
        .collect::<Result<_>>()?;
    let mut translation = match v.get("translation") {
        None => [0.0; 3],
        t => vec3(t).ok_or_else(|| bad("`translation` must be [x, y, z]".into()))?,
    };
    let mut vertices = vertices;
    let mut offset = [0.0; 2];
    if center && !vertices.is_empty() {
        for k in 0..2 {
            offset[k] = vertices.iter().map(|p| p[k]).sum::<f64>() / vertices.len() as f64;
            vertices.iter_mut().for_each(|p| p[k] -= offset[k]);
            translation[k] += offset[k];
        }
    }
    // absolute control points are in the file's coordinates, before any centring
    let absolute = absolute.then_some(offset);
    let rotation = match v.get("rotation") {
        None => [0.0; 3],
        r => vec3(r).ok_or_else(|| bad("`rotation` must be [x, y, z] (degrees)".into()))?,
    };
    let edges_json = v
        .get("edges")
        .and_then(Value::as_array)
        .ok_or_else(|| bad("`edges` must be a list".into()))?;
    if edges_json.len() < 2 {
        return Err(bad(format!(
            "an outline needs at least 2 edges, got {}",
            edges_json.len()
        )));
    }
    let mut edges = Vec::with_capacity(edges_json.len());
    for (i, e) in edges_json.iter().enumerate() {
        let bad_e = |m: String| bad(format!("edges[{i}]: {m}"));
        let ends = e
            .get("endpoints")
            .and_then(Value::as_array)
            .filter(|a| a.len() == 2)
            .ok_or_else(|| bad_e("`endpoints` must be [start, end]".into()))?;
        let mut endpoints = [0usize; 2];
        for (k, x) in ends.iter().enumerate() {
            endpoints[k] = x
                .as_u64()
                .map(|x| x as usize)
                .filter(|&x| x < vertices.len())
                .ok_or_else(|| {
                    bad_e(format!(
                        "endpoint {x} is not a vertex index (the panel has {} vertices)",
                        vertices.len()
                    ))
                })?;
        }
        let (a, b) = (vertices[endpoints[0]], vertices[endpoints[1]]);
        if dist(a, b) == 0.0 {
            return Err(bad_e("its endpoints coincide".into()));
        }
        let curve = parse_curve(a, b, e.get("curvature"), absolute).map_err(bad_e)?;
        edges.push(Edge { endpoints, curve });
    }
    for i in 0..edges.len() {
        let next = (i + 1) % edges.len();
        if edges[i].endpoints[1] != edges[next].endpoints[0] {
            return Err(bad(format!(
                "edges do not form a loop: edges[{i}] ends at vertex {} but edges[{next}] starts at vertex {}",
                edges[i].endpoints[1], edges[next].endpoints[0]
            )));
        }
    }
    Ok(Panel {
        name: name.to_string(),
        vertices,
        edges,
        translation,
        rotation,
    })
}

/// A control point given relative to the edge `a → b` (or, with `absolute = Some(offset)`, in
/// the file's panel coordinates, from which `offset` is subtracted) in panel coordinates.
fn control(a: Point2, b: Point2, p: Point2, absolute: Option<Point2>) -> Point2 {
    if let Some(o) = absolute {
        return [p[0] - o[0], p[1] - o[1]];
    }
    let e = [b[0] - a[0], b[1] - a[1]];
    [
        a[0] + p[0] * e[0] - p[1] * e[1],
        a[1] + p[0] * e[1] + p[1] * e[0],
    ]
}

fn parse_curve(
    a: Point2,
    b: Point2,
    c: Option<&Value>,
    absolute: Option<Point2>,
) -> std::result::Result<Curve, String> {
    let Some(c) = c.filter(|c| !c.is_null()) else {
        return Ok(Curve::Line { start: a, end: b });
    };
    if let Some(p) = point(c) {
        // old style: a bare quadratic control point
        return Ok(Curve::Quadratic {
            points: [a, control(a, b, p, absolute), b],
        });
    }
    let kind = c.get("type").and_then(Value::as_str);
    let params = c.get("params").and_then(Value::as_array);
    let (Some(kind), Some(params)) = (kind, params) else {
        return Err(format!(
            "`curvature` must be {{\"type\": ..., \"params\": [...]}}, got {c}"
        ));
    };
    let points = || -> std::result::Result<Vec<Point2>, String> {
        params
            .iter()
            .map(|p| {
                point(p)
                    .map(|p| control(a, b, p, absolute))
                    .ok_or_else(|| format!("curvature control point must be [x, y], got {p}"))
            })
            .collect()
    };
    match kind {
        "quadratic" => match points()?.as_slice() {
            [p] => Ok(Curve::Quadratic { points: [a, *p, b] }),
            other => Err(format!(
                "a quadratic curvature has 1 control point, got {}",
                other.len()
            )),
        },
        "cubic" => match points()?.as_slice() {
            [p, q] => Ok(Curve::Cubic {
                points: [a, *p, *q, b],
            }),
            other => Err(format!(
                "a cubic curvature has 2 control points, got {}",
                other.len()
            )),
        },
        "circle" => {
            let vals: Vec<f64> = params.iter().filter_map(|x| num(Some(x))).collect();
            let flag = |x: f64| x != 0.0;
            match vals.as_slice() {
                &[r, large, right] if params.len() == 3 && r > 0.0 => {
                    Ok(arc(a, b, r, flag(large), flag(right)))
                }
                _ => Err(format!(
                    "a circle curvature has params [radius > 0, large_arc, right], got {}",
                    Value::Array(params.clone())
                )),
            }
        }
        other => Err(format!(
            "unknown curvature type `{other}` (expected quadratic, cubic or circle)"
        )),
    }
}

/// The SVG arc from `a` to `b` with radius `r` (raised to half the chord if smaller), the
/// large-arc flag and sweep = `right` (counter-clockwise, y up).
fn arc(a: Point2, b: Point2, r: f64, large: bool, right: bool) -> Curve {
    let d = [b[0] - a[0], b[1] - a[1]];
    let chord = d[0].hypot(d[1]);
    let half = chord / 2.0;
    let radius = r.max(half);
    let h = (radius * radius - half * half).max(0.0).sqrt();
    let left = [-d[1] / chord, d[0] / chord];
    let sign = if large != right { 1.0 } else { -1.0 };
    let mid = lerp(a, b, 0.5);
    let center = [mid[0] + sign * h * left[0], mid[1] + sign * h * left[1]];
    let start_angle = (a[1] - center[1]).atan2(a[0] - center[0]);
    let end_angle = (b[1] - center[1]).atan2(b[0] - center[0]);
    let tau = std::f64::consts::TAU;
    let mut sweep = (end_angle - start_angle).rem_euclid(tau); // in [0, 2π)
    if !right {
        sweep -= tau; // clockwise: in [−2π, 0)
    }
    if sweep == 0.0 {
        sweep = tau; // (cannot happen for distinct endpoints, kept for safety)
    }
    Curve::Arc {
        center,
        radius,
        start_angle,
        sweep,
    }
}

fn parse_stitch(i: usize, s: &Value, panels: &[Panel], origin: &str) -> Result<StitchSpec> {
    let bad = |m: String| Error::input(origin, format!("stitch {i}: {m}"));
    let list = s
        .as_array()
        .filter(|l| l.len() == 2 || l.len() == 3)
        .ok_or_else(|| {
            bad(format!(
                "must be [{{panel, edge}}, {{panel, edge}}], got {s}"
            ))
        })?;
    let right_wrong = match list.get(2) {
        None => false,
        Some(Value::String(t)) if t == "right_wrong" => true,
        Some(other) => {
            return Err(bad(format!(
                "third entry must be \"right_wrong\", got {other}"
            )));
        }
    };
    let mut sides = [EdgeRef { panel: 0, edge: 0 }; 2];
    for k in 0..2 {
        let side = &list[k];
        let name = side.get("panel").and_then(Value::as_str).ok_or_else(|| {
            bad(format!(
                "side {k} must be {{\"panel\": NAME, \"edge\": INDEX}}"
            ))
        })?;
        let panel = panels.iter().position(|p| p.name == name).ok_or_else(|| {
            bad(format!(
                "side {k} names panel `{name}`, which does not exist"
            ))
        })?;
        let n = panels[panel].edges.len();
        let edge = side
            .get("edge")
            .and_then(Value::as_u64)
            .map(|e| e as usize)
            .filter(|&e| e < n)
            .ok_or_else(|| {
                bad(format!(
                    "side {k} names edge {} of panel `{name}`, which has {n} edges",
                    side.get("edge").unwrap_or(&Value::Null)
                ))
            })?;
        sides[k] = EdgeRef { panel, edge };
    }
    Ok(StitchSpec { sides, right_wrong })
}

/// Index pair `(i, j)` of the first two non-adjacent segments of the closed polygon `ring`
/// that touch or cross, or of adjacent segments that fold back onto each other.
pub(crate) fn first_crossing(ring: &[Point2]) -> Option<(usize, usize)> {
    let n = ring.len();
    let seg = |i: usize| (ring[i], ring[(i + 1) % n]);
    // bounding boxes to skip most pairs
    let boxes: Vec<[f64; 4]> = (0..n)
        .map(|i| {
            let (a, b) = seg(i);
            [
                a[0].min(b[0]),
                a[1].min(b[1]),
                a[0].max(b[0]),
                a[1].max(b[1]),
            ]
        })
        .collect();
    for i in 0..n {
        for j in i + 1..n {
            let (bi, bj) = (boxes[i], boxes[j]);
            if bi[0] > bj[2] || bj[0] > bi[2] || bi[1] > bj[3] || bj[1] > bi[3] {
                continue;
            }
            let (a, b) = seg(i);
            let (c, d) = seg(j);
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            if adjacent {
                // shared vertex: only a fold back (collinear overlap) or a repeated point is bad
                let (p, q, r) = if j == i + 1 { (a, b, d) } else { (c, d, b) };
                let cross = orient(p, q, r);
                let back = (q[0] - p[0]) * (r[0] - q[0]) + (q[1] - p[1]) * (r[1] - q[1]);
                if p == q || q == r || (cross == 0.0 && back < 0.0) {
                    return Some((i, j));
                }
            } else if segments_touch(a, b, c, d) {
                return Some((i, j));
            }
        }
    }
    None
}

pub(crate) fn orient(a: Point2, b: Point2, c: Point2) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn on_segment(a: Point2, b: Point2, p: Point2) -> bool {
    p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

fn segments_touch(a: Point2, b: Point2, c: Point2, d: Point2) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return true;
    }
    (o1 == 0.0 && on_segment(a, b, c))
        || (o2 == 0.0 && on_segment(a, b, d))
        || (o3 == 0.0 && on_segment(c, d, a))
        || (o4 == 0.0 && on_segment(c, d, b))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A specification with the given panels (JSON object body) and stitches (JSON list body).
    pub(crate) fn spec(panels: &str, stitches: &str) -> String {
        format!(
            r#"{{"pattern": {{"panels": {{{panels}}}, "stitches": [{stitches}]}},
                "properties": {{"units_in_meter": 100, "curvature_coords": "relative"}}}}"#
        )
    }

    /// A square panel `name` of side `s` cm with its lower left corner at the origin.
    pub(crate) fn square(name: &str, s: f64) -> String {
        format!(
            r#""{name}": {{"translation": [0, 0, 0], "rotation": [0, 0, 0],
                "vertices": [[0, 0], [{s}, 0], [{s}, {s}], [0, {s}]],
                "edges": [{{"endpoints": [0, 1]}}, {{"endpoints": [1, 2]}},
                          {{"endpoints": [2, 3]}}, {{"endpoints": [3, 0]}}]}}"#
        )
    }

    /// Asserts that the error text `e` mentions every one of `words`.
    pub(crate) fn assert_mentions(e: &str, words: &[&str]) {
        for w in words {
            assert!(e.contains(w), "`{w}` missing from: {e}");
        }
    }

    fn close(a: Point2, b: Point2) -> bool {
        dist(a, b) < 1e-12
    }

    #[test]
    fn bezier_control_points_are_relative_to_the_edge_and_turned_left() {
        // edge (0,0) → (2,0): relative (0.5, 0.25) is (1, 0.25·2) = (1, 0.5), left of +x
        let c = parse_curve(
            [0.0, 0.0],
            [2.0, 0.0],
            Some(&serde_json::json!({"type": "quadratic", "params": [[0.5, 0.25]]})),
            None,
        )
        .unwrap();
        assert_eq!(
            c,
            Curve::Quadratic {
                points: [[0.0, 0.0], [1.0, 0.5], [2.0, 0.0]]
            }
        );
        // the same on the edge (0,0) → (0,2): left of +y is −x
        let c = parse_curve(
            [0.0, 0.0],
            [0.0, 2.0],
            Some(&serde_json::json!([0.5, 0.25])),
            None,
        )
        .unwrap();
        assert!(close(c.point(0.5), [-0.25, 1.0]), "{:?}", c.point(0.5));
        // cubic: the curve passes through de Casteljau's midpoint (P0 + 3P1 + 3P2 + P3)/8
        let c = parse_curve(
            [0.0, 0.0],
            [4.0, 0.0],
            Some(&serde_json::json!({"type": "cubic", "params": [[0.25, 0.5], [0.75, 0.5]]})),
            None,
        )
        .unwrap();
        assert!(close(c.point(0.5), [2.0, 1.5]), "{:?}", c.point(0.5));
        // absolute coordinates when the file says so
        let c = parse_curve(
            [0.0, 0.0],
            [2.0, 0.0],
            Some(&serde_json::json!([1.0, 3.0])),
            Some([0.0, 0.0]),
        )
        .unwrap();
        assert_eq!(
            c,
            Curve::Quadratic {
                points: [[0.0, 0.0], [1.0, 3.0], [2.0, 0.0]]
            }
        );
    }

    #[test]
    fn circle_arcs_follow_the_svg_flags_with_right_counter_clockwise() {
        let arc_of = |r: f64, large: u8, right: u8| {
            parse_curve(
                [0.0, 0.0],
                [2.0, 0.0],
                Some(&serde_json::json!({"type": "circle", "params": [r, large, right]})),
                None,
            )
            .unwrap()
        };
        // half circle on a chord of 2: right = 1 bulges right of +x (below), right = 0 above
        assert!(close(arc_of(1.0, 0, 1).point(0.5), [1.0, -1.0]));
        assert!(close(arc_of(1.0, 0, 0).point(0.5), [1.0, 1.0]));
        // a radius below half the chord is raised to it (SVG)
        assert!(close(arc_of(0.3, 0, 1).point(0.5), [1.0, -1.0]));
        // radius 2 on a chord of 2: centre at distance √3 from the chord; sagitta 2 − √3 for
        // the small arc, 2 + √3 for the large one, on the side `right` says for either
        let s = 3f64.sqrt();
        assert!(close(arc_of(2.0, 0, 1).point(0.5), [1.0, -(2.0 - s)]));
        assert!(close(arc_of(2.0, 1, 1).point(0.5), [1.0, -(2.0 + s)]));
        assert!(close(arc_of(2.0, 0, 0).point(0.5), [1.0, 2.0 - s]));
        assert!(close(arc_of(2.0, 1, 0).point(0.5), [1.0, 2.0 + s]));
        for (large, right) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            let c = arc_of(2.0, large, right);
            assert!(close(c.point(0.0), [0.0, 0.0]) && close(c.point(1.0), [2.0, 0.0]));
            let angle = if large == 1 {
                2.0 * PI - PI / 3.0
            } else {
                PI / 3.0
            };
            assert!((c.length() - 2.0 * angle).abs() < 1e-12);
        }
    }
    use std::f64::consts::PI;

    #[test]
    fn rotation_is_z_y_x_euler_degrees() {
        let mut p = Panel {
            name: "p".into(),
            vertices: vec![],
            edges: vec![],
            translation: [0.0; 3],
            rotation: [0.0, 90.0, 0.0],
        };
        let apply = |p: &Panel, v: [f64; 3]| {
            let r = p.rotation_matrix();
            [0, 1, 2].map(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2])
        };
        let near = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() < 1e-12);
        // Ry(90°) takes x to −z
        assert!(near(apply(&p, [1.0, 0.0, 0.0]), [0.0, 0.0, -1.0]));
        // Rz(0)·Ry(90°)·Rx(90°): y → z (by Rx) → x (by Ry); an X·Y·Z product would give z
        p.rotation = [90.0, 90.0, 0.0];
        assert!(near(apply(&p, [0.0, 1.0, 0.0]), [1.0, 0.0, 0.0]));
    }

    #[test]
    fn reads_panels_stitches_and_units() {
        let text = spec(
            &format!("{}, {}", square("b", 10.0), square("a", 20.0)),
            r#"[{"panel": "a", "edge": 1}, {"panel": "b", "edge": 3}, "right_wrong"]"#,
        );
        let p = Pattern::parse(&text, "t.json").unwrap();
        assert_eq!(p.units_in_meter, 100.0);
        assert_eq!(
            p.panels.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(),
            ["a", "b"]
        );
        assert_eq!(
            p.panels[0].edges[1].curve,
            Curve::Line {
                start: [20.0, 0.0],
                end: [20.0, 20.0]
            }
        );
        assert_eq!(
            p.stitches,
            vec![StitchSpec {
                sides: [EdgeRef { panel: 0, edge: 1 }, EdgeRef { panel: 1, edge: 3 }],
                right_wrong: true
            }]
        );
    }

    #[test]
    fn centred_panels_keep_their_place_when_unrotated() {
        let panel = r#""p": {"translation": [1, 2, 3], "vertices": [[10, 0], [30, 0], [30, 20]],
            "edges": [{"endpoints": [0, 1], "curvature": [20, -5]}, {"endpoints": [1, 2]}, {"endpoints": [2, 0]}]}"#;
        let text = |centre: bool| {
            format!(
                r#"{{"pattern": {{"panels": {{{panel}}}}}, "properties": {{"units_in_meter": 100,
                "curvature_coords": "absolute", "normalize_panel_translation": {centre}}}}}"#
            )
        };
        let (a, b) = (
            Pattern::parse(&text(false), "a").unwrap(),
            Pattern::parse(&text(true), "b").unwrap(),
        );
        let (a, b) = (&a.panels[0], &b.panels[0]);
        let mean: Point2 = [0, 1].map(|k| b.vertices.iter().map(|v| v[k]).sum::<f64>() / 3.0);
        assert!(mean[0].abs() < 1e-12 && mean[1].abs() < 1e-12);
        assert!(
            (b.translation[0] - (1.0 + 70.0 / 3.0)).abs() < 1e-12
                && (b.translation[1] - (2.0 + 20.0 / 3.0)).abs() < 1e-12
        );
        // every point of every edge lands in the same place
        for (ea, eb) in a.edges.iter().zip(&b.edges) {
            for t in [0.0, 0.3, 0.5, 1.0] {
                let (pa, pb) = (ea.curve.point(t), eb.curve.point(t));
                let wa = [pa[0] + a.translation[0], pa[1] + a.translation[1]];
                let wb = [pb[0] + b.translation[0], pb[1] + b.translation[1]];
                assert!(dist(wa, wb) < 1e-12, "{wa:?} vs {wb:?}");
            }
        }
    }

    fn load_err(text: &str) -> String {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad_specification.json");
        std::fs::write(&path, text).unwrap();
        let e = Pattern::load(&path).unwrap_err().to_string();
        assert!(e.contains("bad_specification.json"), "no file name in: {e}");
        assert_eq!(e.lines().count(), 1, "not one line: {e}");
        e
    }

    #[test]
    fn rejects_stitches_naming_a_missing_panel_or_edge() {
        let e = load_err(&spec(
            &square("front", 10.0),
            r#"[{"panel": "front", "edge": 1}, {"panel": "back", "edge": 3}]"#,
        ));
        assert!(
            e.contains("stitch 0") && e.contains("`back`") && e.contains("does not exist"),
            "{e}"
        );
        let two = format!("{}, {}", square("front", 10.0), square("back", 10.0));
        let e = load_err(&spec(
            &two,
            r#"[{"panel": "front", "edge": 1}, {"panel": "back", "edge": 3}], [{"panel": "front", "edge": 3}, {"panel": "back", "edge": 4}]"#,
        ));
        assert_mentions(&e, &["stitch 1", "edge 4", "`back`", "4 edges"]);
    }

    #[test]
    fn rejects_a_self_crossing_outline() {
        let bowtie = r#""bow": {"vertices": [[0, 0], [10, 10], [10, 0], [0, 10]],
            "edges": [{"endpoints": [0, 1]}, {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]}"#;
        let e = load_err(&spec(&format!("{}, {bowtie}", square("ok", 5.0)), ""));
        assert!(
            e.contains("panel `bow`") && e.contains("crosses itself"),
            "{e}"
        );
        // a curved edge that loops across the opposite side of a square
        let loopy = r#""loopy": {"vertices": [[0, 0], [10, 0], [10, 10], [0, 10]],
            "edges": [{"endpoints": [0, 1], "curvature": {"type": "quadratic", "params": [[0.5, 3.0]]}},
                      {"endpoints": [1, 2]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]}"#;
        let e = load_err(&spec(loopy, ""));
        assert!(
            e.contains("panel `loopy`") && e.contains("crosses itself"),
            "{e}"
        );
    }

    #[test]
    fn rejects_files_that_are_not_pattern_specifications() {
        for text in [
            r#"{"scene": {"cloth": []}}"#,
            r#"[1, 2, 3]"#,
            r#"{"pattern": {"panels": []}}"#,
        ] {
            let e = load_err(text);
            assert!(e.contains("not a GarmentCode pattern specification"), "{e}");
        }
        let e = load_err("{ not json");
        assert!(e.contains("not JSON"), "{e}");
        let broken_loop = r#""gap": {"vertices": [[0, 0], [10, 0], [10, 10], [0, 10]],
            "edges": [{"endpoints": [0, 1]}, {"endpoints": [2, 3]}, {"endpoints": [3, 0]}]}"#;
        let e = load_err(&spec(broken_loop, ""));
        assert!(e.contains("panel `gap`") && e.contains("loop"), "{e}");
        let e = load_err(&spec(&square("sq", 1.0).replace("[0, 1]", "[0, 7]"), ""));
        assert!(e.contains("panel `sq`") && e.contains("edges[0]"), "{e}");
    }
}
