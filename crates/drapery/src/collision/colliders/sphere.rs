//! `shape = "sphere"`: a ball of `radius` around `center`.

use super::{Keys, Kind, Local};
use crate::collision::tessellate::{TessellateOptions, capsule_mesh};
use crate::error::Result;
use crate::fingerprint::Fnv;
use crate::math::Vec3;

/// A ball.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Center.
    pub center: Vec3,
    /// Radius, m (negative counts as zero).
    pub radius: f64,
}

impl Kind for Sphere {
    const NAME: &'static str = "sphere";
    const KEYS: &'static [&'static str] = &["center", "radius"];

    fn parse(k: &Keys) -> Result<Sphere> {
        Ok(Sphere {
            center: k.vec3("center")?,
            radius: k.positive("radius")?,
        })
    }

    fn center(&self) -> Vec3 {
        self.center
    }

    fn closest(&self, p: Vec3, _t: f64) -> Local {
        super::ball(p, self.center, self.radius.max(0.0))
    }

    fn tessellate(&self, _t: f64, o: &TessellateOptions) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        capsule_mesh(self.center, Vec3::Z, 0.0, self.radius.max(0.0), o.segments)
    }

    fn hash(&self, h: &mut Fnv) {
        h.bytes(b"sphere");
        super::hash_vec(h, self.center);
        h.u64(self.radius.to_bits());
    }

    fn describe(&self) -> String {
        format!(
            "sphere center {} radius {} m",
            super::v3(self.center),
            self.radius
        )
    }
}
