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
    let stiffness = k.number_or("stitch_stiffness", DEFAULT_STIFFNESS)?;
    let damping = k.number_or("stitch_damping", DEFAULT_DAMPING)?;
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

#[cfg(test)]
mod tests {
    use crate::garment::Pattern;
    use crate::model::{ClothModel, MassSpec};
    use crate::scene::Scene;
    use std::path::Path;

    /// The material keys of a `[[garment]]` (shell model, a fabric preset, a strain limit, a
    /// pressure) reach the cloth of every one of its panels.
    #[test]
    fn shell_model_fabric_and_strain_limit_reach_every_panel() {
        let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
        let text = "[simulation]\nduration = 0.1\ndt = 0.01\nframe_rate = 10\n\n\
                    [[garment]]\nname = \"top\"\npattern = \"garments/top_specification.json\"\n\
                    edge_length = 0.05\nmodel = \"shell\"\nmaterial = \"cotton\"\n\
                    strain_limit = 0.07\npressure = 3.0\n";
        let scene = Scene::from_str(text, &examples.join("garment_material.toml")).unwrap();
        let panels = Pattern::load(examples.join("garments/top_specification.json"))
            .unwrap()
            .panels;
        assert!(panels.len() >= 2);
        assert_eq!(scene.cloths.len(), panels.len());
        let cotton = crate::textile::fabrics::fabric("cotton").unwrap();
        for (c, p) in scene.cloths.iter().zip(&panels) {
            assert_eq!(c.name, format!("top.{}", p.name));
            let m = &c.material;
            assert_eq!(m.model, ClothModel::Shell, "{}", c.name);
            assert_eq!(m.mass, MassSpec::Density(cotton.density), "{}", c.name);
            assert_eq!(
                m.shell.stretch_modulus, cotton.stretch_modulus,
                "{}",
                c.name
            );
            assert_eq!(m.shell.poisson, cotton.poisson, "{}", c.name);
            assert_eq!(
                m.shell.shear_modulus,
                Some(cotton.shear_modulus),
                "{}",
                c.name
            );
            assert_eq!(
                m.shell.bending_rigidity, cotton.bending_rigidity,
                "{}",
                c.name
            );
            assert_eq!(m.strain_limit, Some(0.07), "{}", c.name);
            assert_eq!(m.pressure, 3.0, "{}", c.name);
        }
        // and a springs key on a shell garment is an error naming the garment's field
        let bad = text.replace("strain_limit", "stretch_stiffness = 5.0\nstrain_limit");
        let e = Scene::from_str(&bad, &examples.join("g.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("garment[0].stretch_stiffness"), "{e}");
    }
}
