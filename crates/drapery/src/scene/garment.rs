//! `[[garment]]` tables: a sewing pattern in the GarmentCode format ([`crate::garment`])
//! triangulated at `edge_length`, each panel a cloth named `GARMENT.PANEL` with the garment's
//! material, each pattern stitch a [`StitchDesc`] between those cloths.
//!
//! ```toml
//! [[garment]]
//! name = "skirt"
//! pattern = "garments/skirt_specification.json"
//! edge_length = 0.03             # m
//! translation = [0.0, 0.0, 0.0]  # optional offset of the whole garment, m
//! density = 0.15                 # or vertex_mass; and the stiffness and damping keys of [[cloth]]
//! stitch_stiffness = 1000.0      # optional, N/m
//! ```

use crate::collision::colliders::Keys;
use crate::error::Result;
use crate::forces::stitch::{DEFAULT_DAMPING, DEFAULT_STIFFNESS};
use crate::garment::Pattern;
use crate::math::Vec3;
use crate::model::{ClothDesc, StitchDesc, StitchEnd};
use std::path::Path;

/// The keys of `[[garment]]` besides the material's ([`super::material::KEYS`]).
const KEYS: &[&str] = &[
    "name",
    "pattern",
    "edge_length",
    "translation",
    "stitch_stiffness",
    "stitch_damping",
];

/// The cloths and stitches of garment `i`.
pub(super) fn garment(
    i: usize,
    table: &toml::Table,
    dir: &Path,
) -> Result<(Vec<ClothDesc>, Vec<StitchDesc>)> {
    let k = Keys::new(table, format!("garment[{i}]"), dir);
    let known: Vec<&str> = KEYS.iter().chain(super::material::KEYS).copied().collect();
    k.only(&known, "[[garment]]")?;
    let name = k.string("name")?;
    let edge_length = k.positive("edge_length")?;
    let offset = k.opt_vec3("translation")?.unwrap_or(Vec3::ZERO);
    let material = super::material::material(&k)?;
    let or = |key: &str, default: f64| -> Result<f64> {
        Ok(k.opt_number(key)?.unwrap_or(default))
    };
    let stiffness = or("stitch_stiffness", DEFAULT_STIFFNESS)?;
    let damping = or("stitch_damping", DEFAULT_DAMPING)?;
    let garment = Pattern::load(k.file("pattern")?)?.triangulate(edge_length)?;
    let cloth_name = |p: usize| format!("{name}.{}", garment.panels[p].name);
    let cloths = garment
        .panels
        .iter()
        .enumerate()
        .map(|(p, panel)| {
            let mut mesh = panel.mesh.clone();
            mesh.positions.iter_mut().for_each(|x| *x += offset);
            ClothDesc {
                name: cloth_name(p),
                mesh,
                material,
                pins: Vec::new(),
                initial_velocity: Vec3::ZERO,
                handles: Vec::new(),
            }
        })
        .collect();
    let stitches = garment
        .stitches
        .iter()
        .map(|s| StitchDesc {
            a: StitchEnd {
                cloth: cloth_name(s.panels[0]),
                vertices: s.pairs.iter().map(|p| p[0]).collect(),
            },
            b: StitchEnd {
                cloth: cloth_name(s.panels[1]),
                vertices: s.pairs.iter().map(|p| p[1]).collect(),
            },
            stiffness,
            damping,
        })
        .collect();
    Ok((cloths, stitches))
}
