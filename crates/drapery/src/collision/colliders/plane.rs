//! `shape = "plane"`: the half-space below the plane through `point` with outward `normal`.

use super::{Keys, Kind, Local, unit_or_z};
use crate::collision::tessellate::{TessellateOptions, frame};
use crate::error::Result;
use crate::fingerprint::Fnv;
use crate::math::Vec3;

/// Half-space below the plane through `point` with outward `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// A point on the plane.
    pub point: Vec3,
    /// Outward normal (need not be unit length; zero counts as `+z`).
    pub normal: Vec3,
}

impl Kind for Plane {
    const NAME: &'static str = "plane";
    const KEYS: &'static [&'static str] = &["point", "normal"];

    fn parse(k: &Keys) -> Result<Plane> {
        let point = k.vec3("point")?;
        let normal = k.vec3("normal")?;
        if normal.length() == 0.0 {
            return Err(k.error("normal", "must be a non-zero vector"));
        }
        Ok(Plane { point, normal })
    }

    fn center(&self) -> Vec3 {
        self.point
    }

    fn closest(&self, p: Vec3, _t: f64) -> Local {
        let n = unit_or_z(self.normal);
        let d = (p - self.point).dot(n);
        Local::solid(d, n, p - n * d)
    }

    /// A square of `plane_half_size` around `plane_center` projected onto the plane.
    fn tessellate(&self, _t: f64, o: &TessellateOptions) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let n = unit_or_z(self.normal);
        let (e1, e2) = frame(n);
        let c = o.plane_center - n * (o.plane_center - self.point).dot(n);
        let s = o.plane_half_size;
        let v = vec![
            c + (-e1 - e2) * s,
            c + (e1 - e2) * s,
            c + (e1 + e2) * s,
            c + (-e1 + e2) * s,
        ];
        (v, vec![[0, 1, 2], [0, 2, 3]])
    }

    fn hash(&self, h: &mut Fnv) {
        h.bytes(b"plane");
        super::hash_vec(h, self.point);
        super::hash_vec(h, self.normal);
    }

    fn describe(&self) -> String {
        format!(
            "plane point {} normal {}",
            super::v3(self.point),
            super::v3(self.normal)
        )
    }
}
