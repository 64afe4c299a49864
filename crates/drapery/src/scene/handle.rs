//! `[[cloth.handle]]` tables: vertices (by index or by a box around their rest positions), an
//! optional pivot, a motion (keyframes, or constant velocities) and an optional release time.
//! Errors name `cloth[i].handle[k].key`; the model checks the rest (ranges, overlaps, release).

use crate::collision::colliders::Keys;
use crate::constraints::handles::HandleDesc;
use crate::error::Result;
use crate::math::Vec3;
use std::path::Path;

const KEYS: &[&str] = &[
    "vertices",
    "region",
    "pivot",
    "keyframes",
    "interpolation",
    "velocity",
    "angular_velocity",
    "release",
    "attach",
];

/// One `[[cloth.handle]]` of cloth `cloth` (index `i`, rest positions `positions`), and the
/// name of the collider it is attached to (`attach`), which the loader resolves once the
/// colliders are read.
pub(super) fn handle(
    i: usize,
    k: usize,
    table: &toml::Table,
    positions: &[Vec3],
    dir: &Path,
) -> Result<(HandleDesc, Option<String>)> {
    let keys = Keys::new(table, format!("cloth[{i}].handle[{k}]"), dir);
    keys.only(KEYS, "[[cloth.handle]]")?;
    let vertices = match (table.get("vertices"), table.get("region")) {
        (Some(_), Some(_)) => {
            return Err(keys.error("region", "give either vertices or region, not both"));
        }
        (None, None) => {
            return Err(keys.error(
                "vertices",
                "missing: give `vertices = [...]` or `region = { min = [x, y, z], max = [x, y, z] }`",
            ));
        }
        (Some(_), None) => keys.indices("vertices")?,
        (None, Some(r)) => {
            let region = r.as_table().ok_or_else(|| {
                keys.error(
                    "region",
                    "must be a table { min = [x, y, z], max = [x, y, z] }",
                )
            })?;
            let rk = Keys::new(region, keys.path("region"), dir);
            let (lo, hi) = (rk.vec3("min")?, rk.vec3("max")?);
            let inside: Vec<u32> = positions
                .iter()
                .enumerate()
                .filter(|(_, p)| p.cmpge(lo).all() && p.cmple(hi).all())
                .map(|(i, _)| i as u32)
                .collect();
            if inside.is_empty() {
                return Err(keys.error(
                    "region",
                    format!(
                        "selects no vertex: no rest vertex of the cloth lies in min {:?} max {:?}",
                        lo.to_array(),
                        hi.to_array()
                    ),
                ));
            }
            inside
        }
    };
    let release = keys
        .has("release")
        .then(|| keys.number("release"))
        .transpose()?;
    let attach = keys
        .has("attach")
        .then(|| keys.string("attach"))
        .transpose()?;
    if attach.is_some() {
        let motion_keys = [
            "pivot",
            "keyframes",
            "interpolation",
            "velocity",
            "angular_velocity",
        ];
        if let Some(key) = motion_keys.into_iter().find(|key| keys.has(key)) {
            return Err(keys.error(
                key,
                "an attached handle follows its collider: give either attach or a motion, not both",
            ));
        }
    }
    Ok((
        HandleDesc {
            vertices,
            pivot: keys.opt_vec3("pivot")?,
            motion: keys.motion()?,
            release,
            attach: None,
        },
        attach.map(str::to_string),
    ))
}

/// Sets each attached handle's collider index from its name; an unknown name is an error
/// naming the handle's `attach`.
pub(super) fn resolve_attachments(
    cloths: &mut [crate::model::ClothDesc],
    names: &[(usize, usize, String)],
    obstacles: &[crate::collision::settings::Obstacle],
) -> Result<()> {
    for (i, k, name) in names {
        let index = obstacles
            .iter()
            .position(|o| o.name.as_deref() == Some(name.as_str()))
            .ok_or_else(|| {
                let known: Vec<String> = obstacles
                    .iter()
                    .filter_map(|o| o.name.as_ref().map(|n| format!("'{n}'")))
                    .collect();
                crate::Error::field(
                    format!("cloth[{i}].handle[{k}].attach"),
                    format!(
                        "no collider is named '{name}' (named colliders: {})",
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    ),
                )
            })?;
        cloths[*i].handles[*k].attach = Some(index);
    }
    Ok(())
}
