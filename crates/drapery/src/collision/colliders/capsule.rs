//! `shape = "capsule"`: every point within `radius` of the segment `a b`.

use super::{Keys, Kind, Local};
use crate::collision::distance::point_segment;
use crate::collision::tessellate::{TessellateOptions, capsule_mesh, unit_or};
use crate::error::Result;
use crate::fingerprint::Fnv;
use crate::math::Vec3;

/// All points within `radius` of the segment `a b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    /// First end of the axis.
    pub a: Vec3,
    /// Second end of the axis.
    pub b: Vec3,
    /// Radius, m (negative counts as zero).
    pub radius: f64,
}

impl Kind for Capsule {
    const NAME: &'static str = "capsule";
    const KEYS: &'static [&'static str] = &["a", "b", "radius"];

    fn parse(k: &Keys) -> Result<Capsule> {
        Ok(Capsule {
            a: k.vec3("a")?,
            b: k.vec3("b")?,
            radius: k.positive("radius")?,
        })
    }

    /// The axis' midpoint.
    fn center(&self) -> Vec3 {
        (self.a + self.b) * 0.5
    }

    fn closest(&self, p: Vec3, _t: f64) -> Local {
        let s = point_segment(p, self.a, self.b);
        super::ball(p, s.q, self.radius.max(0.0))
    }

    fn tessellate(&self, _t: f64, o: &TessellateOptions) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let (a, b) = (self.a, self.b);
        let u = unit_or(b - a, Vec3::Z);
        let half = 0.5 * (b - a).length();
        capsule_mesh(
            (a + b) * 0.5,
            u,
            if half.is_finite() { half } else { 0.0 },
            self.radius.max(0.0),
            o.segments,
        )
    }

    fn hash(&self, h: &mut Fnv) {
        h.bytes(b"capsule");
        super::hash_vec(h, self.a);
        super::hash_vec(h, self.b);
        h.u64(self.radius.to_bits());
    }

    fn describe(&self) -> String {
        format!(
            "capsule a {} b {} radius {} m",
            super::v3(self.a),
            super::v3(self.b),
            self.radius
        )
    }
}
