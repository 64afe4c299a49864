//! `shape = "box"`: an oriented box, `center`, `half_extents` along its local axes and an
//! optional `rotation` (local axes to world, `[x, y, z, w]`).

use super::{Keys, Kind, Local, sign};
use crate::collision::tessellate::TessellateOptions;
use crate::error::Result;
use crate::fingerprint::Fnv;
use crate::math::Vec3;
use glam::DQuat;

/// An oriented box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cuboid {
    /// Center.
    pub center: Vec3,
    /// Half of the side lengths along the box's local axes (negative counts as zero).
    pub half_extents: Vec3,
    /// Orientation: local axes to world.
    pub rotation: DQuat,
}

impl Kind for Cuboid {
    const NAME: &'static str = "box";
    const KEYS: &'static [&'static str] = &["center", "half_extents", "rotation"];

    fn parse(k: &Keys) -> Result<Cuboid> {
        let center = k.vec3("center")?;
        let h = k.vec3("half_extents")?;
        if !(h.min_element() > 0.0) {
            return Err(k.error(
                "half_extents",
                format!(
                    "must be three finite numbers > 0, got [{}, {}, {}]",
                    h.x, h.y, h.z
                ),
            ));
        }
        Ok(Cuboid {
            center,
            half_extents: h,
            rotation: k.opt_quat("rotation")?.unwrap_or(DQuat::IDENTITY),
        })
    }

    fn center(&self) -> Vec3 {
        self.center
    }

    fn closest(&self, p: Vec3, _t: f64) -> Local {
        let h = self.half_extents.max(Vec3::ZERO);
        let l = self.rotation.inverse() * (p - self.center);
        let (d, n, q) = box_local(l, h);
        Local {
            side: sign(d),
            ..Local::solid(d, self.rotation * n, self.center + self.rotation * q)
        }
    }

    /// 12 triangles, counter-clockwise seen from outside.
    fn tessellate(&self, _t: f64, _o: &TessellateOptions) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let h = self.half_extents.max(Vec3::ZERO);
        let mut v = Vec::with_capacity(24);
        let mut tris = Vec::with_capacity(12);
        for k in 0..3 {
            let (a, b) = ((k + 1) % 3, (k + 2) % 3);
            for s in [1.0, -1.0] {
                let mut loop_ = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
                if s < 0.0 {
                    loop_.reverse();
                }
                let first = v.len() as u32;
                for (p, q) in loop_ {
                    let mut l = Vec3::ZERO;
                    l[k] = s * h[k];
                    l[a] = p * h[a];
                    l[b] = q * h[b];
                    v.push(self.center + self.rotation * l);
                }
                tris.push([first, first + 1, first + 2]);
                tris.push([first, first + 2, first + 3]);
            }
        }
        (v, tris)
    }

    fn hash(&self, h: &mut Fnv) {
        h.bytes(b"box");
        super::hash_vec(h, self.center);
        super::hash_vec(h, self.half_extents);
        for q in self.rotation.to_array() {
            h.u64(q.to_bits());
        }
    }

    fn describe(&self) -> String {
        let r = self.rotation;
        format!(
            "box center {} half_extents {} rotation [{}, {}, {}, {}]",
            super::v3(self.center),
            super::v3(self.half_extents),
            r.x,
            r.y,
            r.z,
            r.w
        )
    }
}

/// Signed distance, normal and closest point for an axis-aligned box `[-h, h]`.
fn box_local(l: Vec3, h: Vec3) -> (f64, Vec3, Vec3) {
    let q = l.abs() - h;
    if q.max_element() > 0.0 {
        // outside: closest point is the clamp
        let c = l.clamp(-h, h);
        let d = (l - c).length();
        (d, (l - c) / d, c)
    } else {
        // inside: nearest face
        let k = if q.x >= q.y && q.x >= q.z {
            0
        } else if q.y >= q.z {
            1
        } else {
            2
        };
        let s = if l[k] < 0.0 { -1.0 } else { 1.0 };
        let mut n = Vec3::ZERO;
        n[k] = s;
        let mut c = l;
        c[k] = s * h[k];
        (q[k], n, c)
    }
}
