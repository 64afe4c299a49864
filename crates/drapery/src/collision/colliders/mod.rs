//! Obstacles: one file per collider kind, each moving by a [`Motion`].
//!
//! A [`Collider`] is a [`Shape`] given in its pose at `t = 0` plus a [`Motion`] about the
//! shape's center `c` (the plane's `point`, the sphere's and box's `center`, the capsule's
//! midpoint, the mesh's pivot): a material point `x` of the shape is at `c + T(t) + R(t)(x - c)`
//! at time `t` (see [`crate::animation::motion`]).
//!
//! [`Collider::closest`] answers, for a query point `p` at time `t`: the signed distance (> 0
//! outside, < 0 inside), the unit normal (the gradient of the signed distance wherever it is
//! differentiable, pointing outward), the closest surface point and that point's velocity.
//! Solid kinds (plane, sphere, capsule, box) have an inside; surface kinds (meshes) have not:
//! their distance is unsigned and cloth passing through them is caught by CCD against their
//! triangles ([`Collider::surface`]), not by the sign.
//!
//! Each kind lives in its own file and implements [`Kind`]: its scene keys and their parsing,
//! the closest point in the kind's own frame, a triangle mesh for pictures and files, its
//! fingerprint and a one-line description. [`Shape`] lists the kinds; nothing outside this
//! folder matches on it, so a new kind is one new file and one line in each of the two lists
//! below ([`Shape`] and `dispatch!`).
//!
//! Degenerate parameters never produce NaN: a zero plane normal or a point at a sphere's center
//! uses `+z`, negative radii and half extents count as zero.

mod bvh;
mod capsule;
mod cuboid;
pub mod interior;
pub mod keys;
pub(crate) mod mesh;
mod plane;
mod sequence;
mod sphere;

pub use crate::animation::Motion;
pub use capsule::Capsule;
pub use cuboid::Cuboid;
pub use keys::Keys;
pub use mesh::TriangleMesh;
pub use plane::Plane;
pub use sequence::MeshSequence;
pub use sphere::Sphere;

use crate::collision::tessellate::TessellateOptions;
use crate::error::{Error, Result};
use crate::fingerprint::Fnv;
use crate::math::Vec3;
use glam::DQuat;

/// What a collider kind provides. Positions are in the kind's own frame (before its
/// [`Motion`]); `t` is the time, for kinds that change shape.
pub trait Kind: Sized {
    /// The `shape = "..."` name.
    const NAME: &'static str;
    /// The keys of `[[collider]]` this kind reads (beyond the common ones).
    const KEYS: &'static [&'static str];
    /// Reads the kind's keys.
    fn parse(k: &Keys) -> Result<Self>;
    /// The point its motion turns about.
    fn center(&self) -> Vec3;
    /// Closest point to `p` at time `t`.
    fn closest(&self, p: Vec3, t: f64) -> Local;
    /// Triangles for pictures and files at time `t`, counter-clockwise seen from outside.
    fn tessellate(&self, t: f64, o: &TessellateOptions) -> (Vec<Vec3>, Vec<[u32; 3]>);
    /// True for kinds with an inside (a signed distance); false for surfaces, which must
    /// provide [`Kind::surface`].
    fn solid(&self) -> bool {
        true
    }
    /// For surface kinds: true when the triangles are watertight, so that the surface encloses
    /// an inside ([`interior`]).
    fn closed(&self) -> bool {
        false
    }
    /// For surface kinds: the vertices at time `t` and the triangles, for CCD. `None` for solids.
    fn surface(&self, _t: f64) -> Option<(Vec<Vec3>, &[[u32; 3]])> {
        None
    }
    /// Where a point at `p` at `t_from`, moving with the surface, is at `t_to` (rigid kinds: it
    /// stays).
    fn carry(&self, p: Vec3, _t_from: f64, _t_to: f64) -> Vec3 {
        p
    }
    /// True for kinds that change shape over time (their triangles move in their own frame).
    fn deforms(&self) -> bool {
        false
    }
    /// Upper bound on the speed of the surface in the kind's frame over `[t0, t1]`.
    fn speed_bound(&self, _t0: f64, _t1: f64) -> f64 {
        0.0
    }
    /// Feeds the kind's name and parameters to a fingerprint.
    fn hash(&self, h: &mut Fnv);
    /// `sphere center [0, 0.25, 0] radius 0.25 m`.
    fn describe(&self) -> String;
}

/// A closest-point result in the kind's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Local {
    /// Signed distance (unsigned for surfaces).
    pub distance: f64,
    /// Unit normal.
    pub normal: Vec3,
    /// Closest surface point.
    pub point: Vec3,
    /// `+1` outside / in front, `-1` inside / behind.
    pub side: f64,
    /// The closest triangle of a mesh.
    pub triangle: Option<u32>,
    /// Velocity of the surface at `point` in the kind's frame, for kinds that change shape.
    pub velocity: Option<Vec3>,
}

pub(crate) fn sign(d: f64) -> f64 {
    if d < 0.0 { -1.0 } else { 1.0 }
}

impl Local {
    /// A solid's result.
    pub fn solid(distance: f64, normal: Vec3, point: Vec3) -> Local {
        Local {
            distance,
            normal,
            point,
            side: sign(distance),
            triangle: None,
            velocity: None,
        }
    }

    /// No surface at all (an empty mesh).
    pub fn nowhere(p: Vec3) -> Local {
        Local {
            distance: f64::INFINITY,
            normal: Vec3::Z,
            point: p,
            side: 1.0,
            triangle: None,
            velocity: None,
        }
    }
}

/// The collider kinds.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// `shape = "plane"`.
    Plane(Plane),
    /// `shape = "sphere"`.
    Sphere(Sphere),
    /// `shape = "capsule"`.
    Capsule(Capsule),
    /// `shape = "box"`.
    Box(Cuboid),
    /// `shape = "mesh"`.
    Mesh(TriangleMesh),
    /// `shape = "mesh"` with `sequence`: an animated mesh.
    Sequence(MeshSequence),
}

/// Calls `$e` with `$s` bound to the kind inside `$shape` (the one match over every kind).
macro_rules! dispatch {
    ($shape:expr, $s:ident => $e:expr) => {
        match $shape {
            Shape::Plane($s) => $e,
            Shape::Sphere($s) => $e,
            Shape::Capsule($s) => $e,
            Shape::Box($s) => $e,
            Shape::Mesh($s) => $e,
            Shape::Sequence($s) => $e,
        }
    };
}

/// Every kind's name and keys, in the order of [`Shape`] (a mesh sequence is a mesh with
/// `sequence`, so the mesh's keys are the sequence's).
const KINDS: [(&str, &[&str]); 5] = [
    (Plane::NAME, Plane::KEYS),
    (Sphere::NAME, Sphere::KEYS),
    (Capsule::NAME, Capsule::KEYS),
    (Cuboid::NAME, Cuboid::KEYS),
    (MeshSequence::NAME, MeshSequence::KEYS),
];

/// Parses the kind named `name` from its keys.
fn parse_kind(name: &str, k: &Keys) -> Option<Result<Shape>> {
    Some(match name {
        Plane::NAME => Plane::parse(k).map(Shape::Plane),
        Sphere::NAME => Sphere::parse(k).map(Shape::Sphere),
        Capsule::NAME => Capsule::parse(k).map(Shape::Capsule),
        Cuboid::NAME => Cuboid::parse(k).map(Shape::Box),
        TriangleMesh::NAME => match (k.has("mesh"), k.has("sequence")) {
            (_, false) => TriangleMesh::parse(k).map(Shape::Mesh),
            (false, true) => MeshSequence::parse(k).map(Shape::Sequence),
            (true, true) => Err(k.error("sequence", "give either mesh or sequence, not both")),
        },
        _ => return None,
    })
}

impl Shape {
    /// A plane through `point` with outward `normal`.
    pub fn plane(point: Vec3, normal: Vec3) -> Shape {
        Shape::Plane(Plane { point, normal })
    }
    /// A ball.
    pub fn sphere(center: Vec3, radius: f64) -> Shape {
        Shape::Sphere(Sphere { center, radius })
    }
    /// A capsule around the segment `a b`.
    pub fn capsule(a: Vec3, b: Vec3, radius: f64) -> Shape {
        Shape::Capsule(Capsule { a, b, radius })
    }
    /// An oriented box.
    pub fn cuboid(center: Vec3, half_extents: Vec3, rotation: DQuat) -> Shape {
        Shape::Box(Cuboid {
            center,
            half_extents,
            rotation,
        })
    }

    /// Names of every kind, as `shape = "..."` takes them.
    pub fn names() -> impl Iterator<Item = &'static str> {
        KINDS.iter().map(|(n, _)| *n)
    }

    /// Reads `shape = "NAME"` and that kind's keys from `k`, rejecting the keys of other kinds
    /// (`common` are the keys every collider may have).
    pub fn parse(name: &str, k: &Keys, table: &toml::Table, common: &[&str]) -> Result<Shape> {
        let Some(&(_, own)) = KINDS.iter().find(|(n, _)| *n == name) else {
            let names: Vec<String> = Shape::names().map(|n| format!("\"{n}\"")).collect();
            return Err(k.error(
                "shape",
                format!(
                    "unknown shape '{name}', expected one of {}",
                    names.join(", ")
                ),
            ));
        };
        for key in table.keys() {
            if common.contains(&key.as_str()) || own.contains(&key.as_str()) {
                continue;
            }
            let owners: Vec<&str> = KINDS
                .iter()
                .filter(|(_, keys)| keys.contains(&key.as_str()))
                .map(|(n, _)| *n)
                .collect();
            return Err(if owners.is_empty() {
                k.error(key, "unknown key of [[collider]]")
            } else {
                k.error(
                    key,
                    format!(
                        "not a key of a {name} (it belongs to {})",
                        owners.join(", ")
                    ),
                )
            });
        }
        parse_kind(name, k).unwrap_or_else(|| Err(Error::Invalid(format!("shape '{name}'"))))
    }

    /// The `shape = "..."` name.
    pub fn name(&self) -> &'static str {
        fn n<K: Kind>(_: &K) -> &'static str {
            K::NAME
        }
        dispatch!(self, s => n(s))
    }

    /// The point the motion turns about.
    pub fn center(&self) -> Vec3 {
        dispatch!(self, s => s.center())
    }

    /// Closest point to `p` at time `t`, in the shape's frame.
    pub fn closest(&self, p: Vec3, t: f64) -> Local {
        dispatch!(self, s => s.closest(p, t))
    }

    /// True for kinds with an inside (swept by conservative advancement, not CCD).
    pub fn is_solid(&self) -> bool {
        dispatch!(self, s => s.solid())
    }

    /// See [`Kind::closed`].
    pub fn is_closed(&self) -> bool {
        dispatch!(self, s => s.closed())
    }

    /// Surface kinds: vertices at `t` and triangles (see [`Kind::surface`]).
    pub fn surface(&self, t: f64) -> Option<(Vec<Vec3>, &[[u32; 3]])> {
        dispatch!(self, s => s.surface(t))
    }

    /// Triangles for pictures and files, in the shape's frame at `t`.
    pub fn tessellate(&self, t: f64, o: &TessellateOptions) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        dispatch!(self, s => s.tessellate(t, o))
    }

    /// See [`Kind::carry`].
    pub fn carry(&self, p: Vec3, t_from: f64, t_to: f64) -> Vec3 {
        dispatch!(self, s => s.carry(p, t_from, t_to))
    }

    /// See [`Kind::deforms`].
    pub fn deforms(&self) -> bool {
        dispatch!(self, s => s.deforms())
    }

    /// See [`Kind::speed_bound`].
    pub fn speed_bound(&self, t0: f64, t1: f64) -> f64 {
        dispatch!(self, s => s.speed_bound(t0, t1))
    }

    /// Feeds the shape to a fingerprint.
    // (not `std::hash::Hash`: a fingerprint of the exact bits, the same on every platform)
    #[allow(clippy::should_implement_trait)]
    pub fn hash(&self, h: &mut Fnv) {
        dispatch!(self, s => s.hash(h))
    }

    /// One line: `sphere center [0, 0.25, 0] radius 0.25 m`.
    pub fn describe(&self) -> String {
        dispatch!(self, s => s.describe())
    }
}

/// An obstacle: a shape and its motion.
#[derive(Clone, Debug, PartialEq)]
pub struct Collider {
    /// The shape at `t = 0`.
    pub shape: Shape,
    /// Its motion about the shape's center.
    pub motion: Motion,
}

/// The inside of a collider at one time ([`Collider::inside_at`]).
#[derive(Clone, Debug)]
pub enum Inside<'a> {
    /// A solid at a time: the points of negative signed distance.
    Solid(&'a Collider, f64),
    /// A closed surface, posed.
    Closed(interior::Interior<'a>),
}

impl Inside<'_> {
    /// True when `p` is strictly inside.
    pub fn contains(&self, p: Vec3) -> bool {
        match self {
            Inside::Solid(c, t) => c.closest(p, *t).signed_distance < 0.0,
            Inside::Closed(i) => i.contains(p),
        }
    }
}

/// Result of a closest-point query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Signed distance from the query point to the surface (< 0 inside). Unsigned for meshes.
    pub signed_distance: f64,
    /// Unit outward normal at the closest point (gradient of the signed distance).
    pub normal: Vec3,
    /// Closest point on the surface.
    pub point: Vec3,
    /// Velocity of the surface at `point`.
    pub velocity_at_point: Vec3,
    /// `+1` outside / on the front of the closest mesh triangle, `-1` inside / behind it.
    pub side: f64,
    /// For meshes, the index of the closest triangle.
    pub triangle: Option<u32>,
}

pub(crate) fn unit_or_z(v: Vec3) -> Vec3 {
    let l = v.length();
    if l > 0.0 && l.is_finite() {
        v / l
    } else {
        Vec3::Z
    }
}

/// The closest point of a ball of radius `r` around `c`.
pub(crate) fn ball(p: Vec3, c: Vec3, r: f64) -> Local {
    let n = unit_or_z(p - c);
    let d = (p - c).length() - r;
    Local::solid(d, n, c + n * r)
}

pub(crate) fn hash_vec(h: &mut Fnv, v: Vec3) {
    for k in 0..3 {
        h.u64(v[k].to_bits());
    }
}

pub(crate) fn v3(p: Vec3) -> String {
    format!("[{}, {}, {}]", p.x, p.y, p.z)
}

impl Collider {
    /// A collider that does not move.
    pub fn fixed(shape: Shape) -> Collider {
        Collider {
            shape,
            motion: Motion::Fixed,
        }
    }

    /// A collider moving by `motion`.
    pub fn moving(shape: Shape, motion: Motion) -> Collider {
        Collider { shape, motion }
    }

    /// The center the rotation is about, at `t = 0`.
    pub fn center(&self) -> Vec3 {
        self.shape.center()
    }

    /// Rotation and center at time `t`.
    fn pose(&self, t: f64) -> (DQuat, Vec3) {
        let (rot, tr) = self.motion.pose(t);
        (rot, self.center() + tr)
    }

    /// Position at time `t` of the point at `x` in the shape's frame (rigid motion only).
    pub fn transform_point(&self, x: Vec3, t: f64) -> Vec3 {
        let (rot, c) = self.pose(t);
        c + rot * (x - self.center())
    }

    /// The point at `x` in world coordinates at time `t`, in the shape's frame.
    fn to_local(&self, x: Vec3, t: f64) -> Vec3 {
        let (rot, c) = self.pose(t);
        self.center() + rot.inverse() * (x - c)
    }

    /// Where the point at `x` at time `t_from`, moving with the collider's surface, is at `t_to`.
    pub fn carry(&self, x: Vec3, t_from: f64, t_to: f64) -> Vec3 {
        let local = self.shape.carry(self.to_local(x, t_from), t_from, t_to);
        self.transform_point(local, t_to)
    }

    /// Closest point on the surface at time `t` to `p`. See the module docs.
    pub fn closest(&self, p: Vec3, t: f64) -> Contact {
        let (rot, c_t) = self.pose(t);
        let c0 = self.center();
        // query in the shape's frame
        let q = c0 + rot.inverse() * (p - c_t);
        let l = self.shape.closest(q, t);
        let point = c_t + rot * (l.point - c0);
        let (v, w) = self.motion.velocity(t);
        let mut velocity_at_point = v + w.cross(point - c_t);
        if let Some(lv) = l.velocity {
            velocity_at_point += rot * lv;
        }
        Contact {
            signed_distance: l.distance,
            normal: rot * l.normal,
            point,
            velocity_at_point,
            side: l.side,
            triangle: l.triangle,
        }
    }

    /// True for solids (see [`Shape::is_solid`]).
    pub fn is_solid(&self) -> bool {
        self.shape.is_solid()
    }

    /// Its inside at time `t` ([`interior`]): solids by the sign of the distance, closed
    /// surfaces by ray parity; `None` for an open surface, which has none.
    pub fn inside_at(&self, t: f64) -> Option<Inside<'_>> {
        if self.is_solid() {
            return Some(Inside::Solid(self, t));
        }
        if !self.shape.is_closed() {
            return None;
        }
        let (v, tris) = self.surface(t)?;
        Some(Inside::Closed(interior::Interior::closed(v, tris)))
    }

    /// Surface kinds: the triangles' corners in world coordinates at `t`, and the triangles.
    pub fn surface(&self, t: f64) -> Option<(Vec<Vec3>, &[[u32; 3]])> {
        let (v, tris) = self.shape.surface(t)?;
        Some((
            v.into_iter().map(|p| self.transform_point(p, t)).collect(),
            tris,
        ))
    }

    /// Upper bounds over `[t0, t1]` on the linear speed of the center plus the shape's own
    /// surface speed, and on the angular speed.
    pub fn speed_bound(&self, t0: f64, t1: f64) -> (f64, f64) {
        let (v, w) = self.motion.speed_bound(t0, t1);
        (v + self.shape.speed_bound(t0, t1), w)
    }
}

#[cfg(test)]
mod tests;
