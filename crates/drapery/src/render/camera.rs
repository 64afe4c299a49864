//! Pinhole cameras: explicit (eye, target, field of view) or framing a bounding box.

use crate::error::{Error, Result};
use crate::math::Vec3;

/// A perspective camera looking from `eye` at `target`, `up` giving the roll.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Camera position, m.
    pub eye: Vec3,
    /// Point looked at (projected to the image centre), m.
    pub target: Vec3,
    /// Approximate up direction (y by default).
    pub up: Vec3,
    /// Vertical field of view, degrees (0 < fov < 180).
    pub fov_y_deg: f64,
}

/// The view basis of a camera: right, up and forward unit vectors.
#[derive(Clone, Copy, Debug)]
pub(crate) struct View {
    pub eye: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
    /// Focal length in (supersampled) pixels.
    pub focal: f64,
    /// Near clipping distance, m.
    pub near: f64,
}

/// Default vertical field of view of the automatic camera, degrees.
pub const AUTO_FOV_Y_DEG: f64 = 35.0;

impl Camera {
    /// A camera with `up = +y`; checks the values.
    pub fn new(eye: Vec3, target: Vec3, fov_y_deg: f64) -> Result<Camera> {
        let c = Camera {
            eye,
            target,
            up: Vec3::Y,
            fov_y_deg,
        };
        c.check()?;
        Ok(c)
    }

    /// A camera framing the box `[min, max]` whole for an image of aspect `width / height`:
    /// a three-quarter view from +z and +y (y up), looking at the box centre, far enough that
    /// the box's bounding sphere fits the narrower field of view.
    pub fn framing(min: Vec3, max: Vec3, aspect: f64) -> Result<Camera> {
        if !(min.is_finite() && max.is_finite() && min.cmple(max).all()) {
            return Err(Error::Invalid(
                "cannot frame an empty or non-finite bounding box".into(),
            ));
        }
        if !(aspect > 0.0 && aspect.is_finite()) {
            return Err(Error::Invalid(format!("bad image aspect ratio {aspect}")));
        }
        let center = 0.5 * (min + max);
        let radius = (0.5 * (max - min).length()).max(1e-3);
        let half_y = (AUTO_FOV_Y_DEG * 0.5).to_radians();
        let half_x = (half_y.tan() * aspect).atan();
        let dist = radius / half_y.min(half_x).sin() * 1.05;
        let dir = Vec3::new(0.55, 0.45, 1.0).normalize();
        Camera::new(center + dir * dist, center, AUTO_FOV_Y_DEG)
    }

    fn check(&self) -> Result<()> {
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return Err(Error::Invalid(
                "camera eye, target and up must be finite".into(),
            ));
        }
        if (self.target - self.eye).length() <= 0.0 {
            return Err(Error::Invalid("camera eye and target coincide".into()));
        }
        if self.up.length() <= 0.0 {
            return Err(Error::Invalid("camera up vector is zero".into()));
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return Err(Error::Invalid(format!(
                "camera field of view must be in (0, 180) degrees, got {}",
                self.fov_y_deg
            )));
        }
        Ok(())
    }

    /// The view basis for an image `height` pixels high.
    pub(crate) fn view(&self, height: f64) -> Result<View> {
        self.check()?;
        let forward = (self.target - self.eye).normalize();
        let mut right = forward.cross(self.up.normalize());
        if right.length() < 1e-9 {
            // Looking along `up`: pick another roll.
            right = forward.cross(Vec3::Z);
            if right.length() < 1e-9 {
                right = forward.cross(Vec3::X);
            }
        }
        let right = right.normalize();
        let up = right.cross(forward);
        let focal = 0.5 * height / (0.5 * self.fov_y_deg.to_radians()).tan();
        let near = 1e-4 * (self.target - self.eye).length();
        Ok(View {
            eye: self.eye,
            right,
            up,
            forward,
            focal,
            near,
        })
    }
}

impl View {
    /// View-space coordinates: (right, up, depth along forward).
    pub fn to_view(self, p: Vec3) -> Vec3 {
        let d = p - self.eye;
        Vec3::new(d.dot(self.right), d.dot(self.up), d.dot(self.forward))
    }
}

/// Bounding box of the finite points, or `None` when there are none.
pub fn bounds<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Option<(Vec3, Vec3)> {
    points
        .into_iter()
        .filter(|p| p.is_finite())
        .fold(None, |acc, p| match acc {
            None => Some((*p, *p)),
            Some((lo, hi)) => Some((lo.min(*p), hi.max(*p))),
        })
}
