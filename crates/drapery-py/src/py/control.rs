//! Handles and colliders driven from Python between steps (`Simulation.set_handle_pose`,
//! `set_collider_pose` and their readers): which object an argument names, the pose arguments,
//! and the motion that takes an object from its pose now to a new one.
//!
//! A pose is a [`Motion`]'s `(T, R)`: the point at `x₀` at `t = 0` is at `c + T + R (x₀ - c)`,
//! `c` the collider's center or the handle's pivot. A new pose is reached along a two-key
//! linear track (lerp, slerp) from the pose at the current time and held afterwards, so a
//! collider never jumps (a jump would tunnel through the cloth) and handle vertices move at a
//! finite velocity.

use super::arrays::{float_array, floats};
use drapery::animation::{Interpolation, Keyframe, Motion, Track};
use drapery::{Model, Vec3};
use glam::DQuat;
use numpy::PyArray1;
use pyo3::exceptions::{PyIndexError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// The collider that `collider` names: an index into the scene's colliders or a collider's
/// `name`.
pub fn collider_index(model: &Model, collider: &Bound<'_, PyAny>) -> PyResult<usize> {
    let obstacles = model.obstacles();
    if let Ok(name) = collider.extract::<String>() {
        return obstacles
            .iter()
            .position(|o| o.name.as_deref() == Some(name.as_str()))
            .ok_or_else(|| {
                let names: Vec<&str> = obstacles.iter().filter_map(|o| o.name.as_deref()).collect();
                let known = match names.is_empty() {
                    true => "the scene names no collider".to_string(),
                    false => format!("the scene's named colliders: {}", names.join(", ")),
                };
                PyValueError::new_err(format!("collider: no collider named '{name}' ({known})"))
            });
    }
    let i = collider.extract::<i64>().map_err(|_| {
        PyTypeError::new_err(format!(
            "collider: expected a collider index (int) or name (str), got {}",
            type_name(collider)
        ))
    })?;
    in_range(i, obstacles.len(), "collider", "the scene has", "collider")
}

/// The handle that `handle` names: an index into [`Model::handles`] (every cloth's handles, in
/// scene order) or a `(cloth name, k)` pair, the cloth's `k`-th `[[cloth.handle]]`.
pub fn handle_index(model: &Model, handle: &Bound<'_, PyAny>) -> PyResult<usize> {
    let n = model.handles().len();
    if handle.is_instance_of::<PyTuple>() {
        let (cloth, k): (String, i64) = handle.extract().map_err(|_| {
            PyTypeError::new_err(format!(
                "handle: expected an index (int) or a (cloth name, index) pair, got {}",
                handle.repr().map(|r| r.to_string()).unwrap_or_default()
            ))
        })?;
        let Some(c) = model.cloths().iter().position(|c| c.name == cloth) else {
            let names: Vec<&str> = model.cloths().iter().map(|c| c.name.as_str()).collect();
            return Err(PyValueError::new_err(format!(
                "handle: no cloth named '{cloth}' (the scene's cloths: {})",
                names.join(", ")
            )));
        };
        let mine: Vec<usize> = (0..n).filter(|&i| handle_cloth(model, i) == c).collect();
        let owner = format!("cloth '{cloth}' has");
        let k = in_range(k, mine.len(), "handle", &owner, "handle")?;
        return Ok(mine[k]);
    }
    let i = handle.extract::<i64>().map_err(|_| {
        PyTypeError::new_err(format!(
            "handle: expected an index (int) or a (cloth name, index) pair, got {}",
            type_name(handle)
        ))
    })?;
    in_range(i, n, "handle", "the scene has", "handle")
}

/// `i` as an index below `n`, or an IndexError: `collider: 5 is out of range: the scene has 2
/// colliders`.
fn in_range(i: i64, n: usize, arg: &str, owner: &str, what: &str) -> PyResult<usize> {
    match usize::try_from(i) {
        Ok(u) if u < n => Ok(u),
        _ => {
            let plural = if n == 1 { "" } else { "s" };
            let numbered = match n {
                0 => String::new(),
                _ => format!(", numbered 0 to {}", n - 1),
            };
            Err(PyIndexError::new_err(format!(
                "{arg}: {i} is out of range: {owner} {n} {what}{plural}{numbered}"
            )))
        }
    }
}

fn type_name(a: &Bound<'_, PyAny>) -> String {
    a.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_default()
}

/// The index in [`Model::cloths`] of the cloth that handle `i` holds.
pub fn handle_cloth(model: &Model, i: usize) -> usize {
    let first = model.handles()[i].particles[0] as usize;
    model
        .cloths()
        .iter()
        .position(|c| c.range().contains(&first))
        .unwrap_or_default()
}

/// Every handle as `(cloth name, k)`: the `k`-th handle of that cloth, in [`Model::handles`]
/// order.
pub fn handle_names(model: &Model) -> Vec<(String, usize)> {
    let mut seen = vec![0usize; model.cloths().len()];
    (0..model.handles().len())
        .map(|i| {
            let c = handle_cloth(model, i);
            seen[c] += 1;
            (model.cloths()[c].name.clone(), seen[c] - 1)
        })
        .collect()
}

/// The arguments `translation` (3 numbers) and `rotation` (a quaternion `[x, y, z, w]`,
/// normalized; `None`: no rotation) as a pose; a ValueError naming the argument when a number
/// is not finite or the quaternion is zero.
pub fn pose_arg(
    translation: &Bound<'_, PyAny>,
    rotation: Option<&Bound<'_, PyAny>>,
) -> PyResult<(Vec3, DQuat)> {
    let t = finite(floats(translation, &[3], "translation")?, "translation")?;
    let Some(rotation) = rotation else {
        return Ok((Vec3::new(t[0], t[1], t[2]), DQuat::IDENTITY));
    };
    let q = finite(floats(rotation, &[4], "rotation")?, "rotation")?;
    let q = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
    let length = q.length();
    if length == 0.0 {
        return Err(PyValueError::new_err(
            "rotation: the zero quaternion is not a rotation (give a nonzero [x, y, z, w]; no rotation is [0, 0, 0, 1])",
        ));
    }
    if !length.is_finite() {
        return Err(PyValueError::new_err(
            "rotation: too large to normalize (give a unit quaternion [x, y, z, w])",
        ));
    }
    Ok((Vec3::new(t[0], t[1], t[2]), q / length))
}

/// `v`, or a ValueError naming `arg` when a number is not finite.
fn finite(v: Vec<f64>, arg: &str) -> PyResult<Vec<f64>> {
    if v.iter().all(|x| x.is_finite()) {
        return Ok(v);
    }
    let shown: Vec<String> = v.iter().map(|x| x.to_string()).collect();
    Err(PyValueError::new_err(format!(
        "{arg}: must be finite, got [{}]",
        shown.join(", ")
    )))
}

/// The motion that goes linearly from `motion`'s pose at `now` to `to`, reached at `until`
/// and held afterwards (before `now`: the pose at `now`). `until` must be finite and later
/// than `now` (else a ValueError naming `time`); `field` names the object in other errors.
pub fn ramp(
    motion: &Motion,
    now: f64,
    until: f64,
    to: (Vec3, DQuat),
    field: &str,
) -> PyResult<Motion> {
    if !(until.is_finite() && until > now) {
        return Err(PyValueError::new_err(format!(
            "time: must be a finite time later than sim.time = {now} s, got {until}"
        )));
    }
    let (rotation, translation) = motion.pose(now);
    let keys = vec![
        Keyframe {
            time: now,
            translation,
            rotation,
        },
        Keyframe {
            time: until,
            translation: to.0,
            rotation: to.1,
        },
    ];
    let track = Track::new(keys, Interpolation::Linear, field)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(Motion::Keyframed(track))
}

/// A pose as Python sees it: translation (3,), rotation `[x, y, z, w]` (4,), float64 arrays.
pub type PosePair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// `motion`'s pose at `t` as new arrays.
pub fn pose_arrays<'py>(py: Python<'py>, motion: &Motion, t: f64) -> PosePair<'py> {
    let (rotation, translation) = motion.pose(t);
    (
        float_array(py, &translation.to_array()),
        float_array(py, &rotation.to_array()),
    )
}
