//! The keys of one `[[collider]]` table as each collider kind reads them: typed getters whose
//! errors are [`Error::Field`]s naming the key (`collider[0].radius`), which the scene loader
//! words with the file and the line.

use crate::animation::{Interpolation, Keyframe, Motion, Track};
use crate::error::{Error, Result};
use crate::math::Vec3;
use glam::DQuat;
use std::path::{Path, PathBuf};

/// One collider's table, its field path (`collider[0]`) and the folder its files are relative to.
pub struct Keys<'a> {
    table: &'a toml::Table,
    field: String,
    dir: &'a Path,
}

fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

impl<'a> Keys<'a> {
    /// The keys of `table`, reported as `field.KEY`, files relative to `dir`.
    pub fn new(table: &'a toml::Table, field: impl Into<String>, dir: &'a Path) -> Keys<'a> {
        Keys {
            table,
            field: field.into(),
            dir,
        }
    }

    /// `collider[0]`.
    pub fn field(&self) -> &str {
        &self.field
    }

    /// `collider[0].key`.
    pub fn path(&self, key: &str) -> String {
        format!("{}.{key}", self.field)
    }

    /// An error about `key`.
    pub fn error(&self, key: &str, message: impl Into<String>) -> Error {
        Error::field(self.path(key), message)
    }

    /// True when the table has `key`.
    pub fn has(&self, key: &str) -> bool {
        self.table.contains_key(key)
    }

    fn get(&self, key: &str) -> Result<&'a toml::Value> {
        self.table
            .get(key)
            .ok_or_else(|| self.error(key, "missing (this shape needs it)"))
    }

    fn numbers<const N: usize>(&self, key: &str, v: &toml::Value) -> Result<[f64; N]> {
        let bad = || self.error(key, format!("must be an array of {N} numbers"));
        let a = v.as_array().ok_or_else(bad)?;
        if a.len() != N {
            return Err(bad());
        }
        let mut out = [0.0; N];
        for (o, x) in out.iter_mut().zip(a) {
            *o = number(x).ok_or_else(bad)?;
        }
        Ok(out)
    }

    /// A required finite number.
    pub fn number(&self, key: &str) -> Result<f64> {
        number(self.get(key)?).ok_or_else(|| self.error(key, "must be a number"))
    }

    /// An optional number.
    pub fn opt_number(&self, key: &str) -> Result<Option<f64>> {
        self.has(key).then(|| self.number(key)).transpose()
    }

    /// An optional number, `default` when the key is absent.
    pub fn number_or(&self, key: &str, default: f64) -> Result<f64> {
        Ok(self.opt_number(key)?.unwrap_or(default))
    }

    /// An optional pair given as `[a, b]` or as one number for both.
    pub fn opt_pair(&self, key: &str) -> Result<Option<[f64; 2]>> {
        let Some(v) = self.table.get(key) else {
            return Ok(None);
        };
        match number(v) {
            Some(x) => Ok(Some([x, x])),
            None => self
                .numbers::<2>(key, v)
                .map_err(|_| self.error(key, "must be a number or an array of 2 numbers"))
                .map(Some),
        }
    }

    /// A required number > 0.
    pub fn positive(&self, key: &str) -> Result<f64> {
        crate::validate::positive(&self.path(key), self.number(key)?)
    }

    /// A required finite vector.
    pub fn vec3(&self, key: &str) -> Result<Vec3> {
        let a = self.numbers::<3>(key, self.get(key)?)?;
        crate::validate::finite3(&self.path(key), Vec3::from_array(a))
    }

    /// An optional finite vector.
    pub fn opt_vec3(&self, key: &str) -> Result<Option<Vec3>> {
        self.has(key).then(|| self.vec3(key)).transpose()
    }

    /// An optional rotation `[x, y, z, w]`, normalized; zero or not finite is an error.
    pub fn opt_quat(&self, key: &str) -> Result<Option<DQuat>> {
        let Some(v) = self.table.get(key) else {
            return Ok(None);
        };
        quat(&self.path(key), self.numbers::<4>(key, v)?).map(Some)
    }

    /// An error naming the first key of the table not in `known` ("unknown key of `what`").
    pub fn only(&self, known: &[&str], what: &str) -> Result<()> {
        match self.table.keys().find(|key| !known.contains(&key.as_str())) {
            Some(key) => Err(self.error(
                key,
                format!(
                    "unknown key of {what} (expected one of {})",
                    known.join(", ")
                ),
            )),
            None => Ok(()),
        }
    }

    /// A required array of vertex indices (whole numbers ≥ 0).
    pub fn indices(&self, key: &str) -> Result<Vec<u32>> {
        let list = self
            .table
            .get(key)
            .ok_or_else(|| self.error(key, "missing: an array of vertex indices"))?;
        let bad = || self.error(key, "must be an array of vertex indices ≥ 0");
        list.as_array()
            .ok_or_else(bad)?
            .iter()
            .map(|v| {
                v.as_integer()
                    .and_then(|i| u32::try_from(i).ok())
                    .ok_or_else(bad)
            })
            .collect()
    }

    /// A required string.
    pub fn string(&self, key: &str) -> Result<&'a str> {
        self.get(key)?
            .as_str()
            .ok_or_else(|| self.error(key, "must be a string"))
    }

    /// An optional keyframe track: `keyframes = [{ time, translation, rotation }, ...]` and
    /// `interpolation = "linear" | "smooth"` (errors name `FIELD.keyframes[i].KEY`).
    pub fn track(&self) -> Result<Option<Track>> {
        let Some(v) = self.table.get("keyframes") else {
            if self.has("interpolation") {
                return Err(self.error("interpolation", "given without `keyframes`"));
            }
            return Ok(None);
        };
        let list = v.as_array().ok_or_else(|| {
            self.error(
                "keyframes",
                "must be an array of tables { time, translation, rotation }",
            )
        })?;
        let mut keys = Vec::with_capacity(list.len());
        for (i, item) in list.iter().enumerate() {
            let field = format!("{}.keyframes[{i}]", self.field);
            let table = item.as_table().ok_or_else(|| {
                Error::field(&field, "must be a table { time, translation, rotation }")
            })?;
            let k = Keys::new(table, field, self.dir);
            k.only(&["time", "translation", "rotation"], "a keyframe")?;
            let rotation = match table.get("rotation") {
                Some(r) => {
                    let q = k.numbers::<4>("rotation", r)?;
                    DQuat::from_xyzw(q[0], q[1], q[2], q[3])
                }
                None => DQuat::IDENTITY,
            };
            keys.push(Keyframe {
                time: k.number("time")?,
                translation: match table.get("translation") {
                    Some(t) => Vec3::from_array(k.numbers::<3>("translation", t)?),
                    None => Vec3::ZERO,
                },
                rotation,
            });
        }
        let interpolation = match self.table.get("interpolation") {
            None => Interpolation::default(),
            Some(v) => Interpolation::parse(
                v.as_str()
                    .ok_or_else(|| self.error("interpolation", "must be a string"))?,
                &self.path("interpolation"),
            )?,
        };
        Track::new(keys, interpolation, &self.field).map(Some)
    }

    /// The motion: `keyframes` (and `interpolation`), or constant `velocity` and
    /// `angular_velocity` (each optional), not both.
    pub fn motion(&self) -> Result<Motion> {
        if let Some(track) = self.track()? {
            for key in ["velocity", "angular_velocity"] {
                if self.has(key) {
                    return Err(self.error(
                        key,
                        "give either keyframes or velocity / angular_velocity, not both",
                    ));
                }
            }
            return Ok(Motion::Keyframed(track));
        }
        Ok(Motion::constant(
            self.opt_vec3("velocity")?.unwrap_or(Vec3::ZERO),
            self.opt_vec3("angular_velocity")?.unwrap_or(Vec3::ZERO),
        ))
    }

    /// A required file name, as a path relative to the scene's folder.
    pub fn file(&self, key: &str) -> Result<PathBuf> {
        Ok(self.dir.join(self.string(key)?))
    }
}

/// `[x, y, z, w]` as a unit quaternion; an error naming `field` when zero or not finite.
pub fn quat(field: &str, q: [f64; 4]) -> Result<DQuat> {
    let len = q.iter().map(|e| e * e).sum::<f64>().sqrt();
    if !(len > 0.0 && len.is_finite()) {
        return Err(Error::field(
            field,
            format!(
                "must be a finite non-zero quaternion [x, y, z, w], got [{}, {}, {}, {}]",
                q[0], q[1], q[2], q[3]
            ),
        ));
    }
    Ok(DQuat::from_xyzw(
        q[0] / len,
        q[1] / len,
        q[2] / len,
        q[3] / len,
    ))
}
