//! The material keys that `[[cloth]]` and `[[garment]]` share: the mass, the cloth model and
//! its parameters, strain limit and pressure.
//!
//! ```toml
//! model = "shell"             # or "springs" (the default)
//! material = "cotton"         # a fabric preset (docs/MATERIALS.md); implies model = "shell"
//! density = 0.15              # kg/m² (or vertex_mass, kg)
//! stretch_modulus = [400, 300] # N/m, [warp, weft] or one number
//! poisson = 0.3
//! shear_modulus = 50.0        # N/m, optional
//! bending_rigidity = 1e-5     # N·m, [warp, weft] or one number
//! damping = 0.01              # shell: stiffness-proportional, s; springs: N·s/m
//! strain_limit = 0.05         # optional, either model
//! pressure = 500.0            # Pa, optional, either model
//! ```
//!
//! Keys of the other model are errors, so a typo of model does not silently drop them. The
//! values are validated by the model ([`crate::model::Model`]), one validator per fact.

use crate::collision::colliders::Keys;
use crate::error::Result;
use crate::model::{ClothModel, MassSpec, Material};

/// The keys read here.
pub(super) const KEYS: &[&str] = &[
    "vertex_mass",
    "density",
    "model",
    "material",
    "damping",
    "air_drag",
    "stretch_stiffness",
    "shear_stiffness",
    "bend_stiffness",
    "stretch_modulus",
    "poisson",
    "shear_modulus",
    "bending_rigidity",
    "strain_limit",
    "pressure",
];

/// Keys of the springs model only.
const SPRINGS: &[&str] = &["stretch_stiffness", "shear_stiffness", "bend_stiffness"];
/// Keys of the shell model only.
const SHELL: &[&str] = &[
    "stretch_modulus",
    "poisson",
    "shear_modulus",
    "bending_rigidity",
];

/// The material of the table behind `k`.
pub(super) fn material(k: &Keys) -> Result<Material> {
    let preset = match k.has("material") {
        true => Some(preset(k)?),
        false => None,
    };
    let model = match k.has("model") {
        false if preset.is_some() => ClothModel::Shell,
        false => ClothModel::Springs,
        true => match k.string("model")? {
            "springs" => ClothModel::Springs,
            "shell" => ClothModel::Shell,
            other => {
                return Err(k.error(
                    "model",
                    format!("unknown cloth model '{other}' (expected \"springs\" or \"shell\")"),
                ));
            }
        },
    };
    let (foreign, name) = match model {
        ClothModel::Springs => (SHELL, "shell"),
        ClothModel::Shell => (SPRINGS, "springs"),
    };
    if let Some(key) = foreign.iter().find(|key| k.has(key)) {
        return Err(k.error(
            key,
            format!("is a key of model = \"{name}\"; this cloth's model is the other one"),
        ));
    }
    if model == ClothModel::Springs && preset.is_some() {
        return Err(k.error(
            "material",
            "fabric presets set the shell model's keys: use model = \"shell\" (or leave model out)",
        ));
    }
    let base = preset.unwrap_or_default();
    let mass = match (k.opt_number("vertex_mass")?, k.opt_number("density")?) {
        (Some(m), None) => MassSpec::PerVertex(m),
        (None, Some(d)) => MassSpec::Density(d),
        (None, None) if preset.is_some() => base.mass,
        (Some(_), Some(_)) => {
            return Err(k.error(
                "density",
                "give either vertex_mass (kg per vertex) or density (kg/m²), not both",
            ));
        }
        (None, None) => {
            return Err(k.error(
                "density",
                "missing: give vertex_mass (kg per vertex) or density (kg/m²)",
            ));
        }
    };
    let or = |key: &str, default: f64| k.number_or(key, default);
    let d = Material::default();
    let mut m = Material {
        stretch_stiffness: or("stretch_stiffness", d.stretch_stiffness)?,
        shear_stiffness: or("shear_stiffness", d.shear_stiffness)?,
        bend_stiffness: or("bend_stiffness", d.bend_stiffness)?,
        damping: or("damping", d.damping)?,
        air_drag: or("air_drag", d.air_drag)?,
        mass,
        model,
        shell: base.shell,
        strain_limit: k.opt_number("strain_limit")?,
        pressure: or("pressure", d.pressure)?,
    };
    if model == ClothModel::Shell {
        let s = &mut m.shell;
        s.stretch_modulus = k.opt_pair("stretch_modulus")?.unwrap_or(s.stretch_modulus);
        s.poisson = or("poisson", s.poisson)?;
        if let Some(g) = k.opt_number("shear_modulus")? {
            s.shear_modulus = Some(g);
        }
        s.bending_rigidity = k
            .opt_pair("bending_rigidity")?
            .unwrap_or(s.bending_rigidity);
        s.damping = or("damping", s.damping)?;
        m.damping = 0.0;
    }
    Ok(m)
}

/// The preset named by `material`, as a shell material (mass by density).
fn preset(k: &Keys) -> Result<Material> {
    let name = k.string("material")?;
    let Some(f) = crate::textile::fabrics::fabric(name) else {
        return Err(k.error(
            "material",
            format!(
                "unknown fabric '{name}' (expected one of {})",
                crate::textile::fabrics::FABRICS.join(", ")
            ),
        ));
    };
    Ok(f.material())
}

#[cfg(test)]
mod tests {
    use crate::model::{ClothModel, MassSpec};
    use crate::scene::Scene;
    use crate::textile::fabrics::fabric;
    use std::path::Path;

    /// A scene whose cloth has the material keys `keys`.
    fn cloth(keys: &str) -> crate::Result<Scene> {
        let text = format!(
            "[simulation]\nduration = 1\ndt = 0.01\nframe_rate = 25\n\n[[cloth]]\nname = \"sheet\"\ngrid = {{ size = [1, 1], resolution = [3, 3] }}\n{keys}\n"
        );
        Scene::from_str(&text, Path::new("dir/s.toml"))
    }

    #[test]
    fn a_preset_fills_the_shell_keys_and_explicit_keys_win() {
        let cotton = fabric("cotton").unwrap();
        let s = cloth("material = \"cotton\"").unwrap();
        let m = &s.cloths[0].material;
        assert_eq!(m.model, ClothModel::Shell);
        assert_eq!(m.mass, MassSpec::Density(cotton.density));
        assert_eq!(m.shell.stretch_modulus, cotton.stretch_modulus);
        assert_eq!(m.shell.bending_rigidity, cotton.bending_rigidity);
        assert_eq!(m.shell.shear_modulus, Some(cotton.shear_modulus));
        let s = cloth(
            "material = \"cotton\"\ndensity = 0.5\nbending_rigidity = [1e-4, 2e-4]\nstretch_modulus = 300\nstrain_limit = 0.1\npressure = 20",
        )
        .unwrap();
        let m = &s.cloths[0].material;
        assert_eq!(m.mass, MassSpec::Density(0.5));
        assert_eq!(m.shell.bending_rigidity, [1e-4, 2e-4]);
        assert_eq!(m.shell.stretch_modulus, [300.0, 300.0]);
        assert_eq!(m.shell.poisson, cotton.poisson);
        assert_eq!((m.strain_limit, m.pressure), (Some(0.1), 20.0));
        // without a preset: Shell::default's values and the springs' keys untouched
        let s = cloth("model = \"shell\"\ndensity = 0.2\ndamping = 0.02").unwrap();
        let m = &s.cloths[0].material;
        assert_eq!((m.shell.damping, m.damping), (0.02, 0.0));
        let s = cloth("density = 0.2\ndamping = 0.02").unwrap();
        assert_eq!(s.cloths[0].material.model, ClothModel::Springs);
        assert_eq!(s.cloths[0].material.damping, 0.02);
    }

    #[test]
    fn wrong_material_keys_are_one_error_naming_the_field() {
        let cases = [
            (
                "model = \"cloth\"\ndensity = 1",
                "line 9, cloth[0].model: unknown cloth model 'cloth'",
            ),
            (
                "material = \"velvet\"",
                "cloth[0].material: unknown fabric 'velvet' (expected one of cotton,",
            ),
            (
                "model = \"springs\"\nmaterial = \"cotton\"",
                "cloth[0].material: fabric presets set the shell",
            ),
            (
                "density = 1\nstretch_modulus = 100",
                "cloth[0].stretch_modulus: is a key of model = \"shell\"",
            ),
            (
                "model = \"shell\"\ndensity = 1\nbend_stiffness = 1",
                "cloth[0].bend_stiffness: is a key of model = \"springs\"",
            ),
            (
                "model = \"shell\"\ndensity = 1\nstretch_modulus = [1, 2, 3]",
                "cloth[0].stretch_modulus: must be a number or an array of 2",
            ),
            (
                "model = \"shell\"\ndensity = 1\nstretch_modulus = -5",
                "cloth[0].stretch_modulus: must be a finite number > 0",
            ),
            (
                "model = \"shell\"\ndensity = 1\npoisson = 0.9\nstretch_modulus = [100, 200]",
                "cloth[0].poisson: must be finite with poisson²",
            ),
            (
                "model = \"shell\"\ndensity = 1\nbending_rigidity = -1e-5",
                "cloth[0].bending_rigidity:",
            ),
            (
                "model = \"shell\"\ndensity = 1\nshear_modulus = 0",
                "cloth[0].shear_modulus:",
            ),
            (
                "model = \"shell\"\ndensity = 1\ndamping = -1",
                "cloth[0].damping:",
            ),
            (
                "density = 1\nstiffnes = 3",
                "cloth[0].stiffnes: unknown key of [[cloth]] (expected one of name, mesh,",
            ),
        ];
        for (keys, want) in cases {
            let e = cloth(keys).unwrap_err().to_string();
            assert!(
                e.starts_with("dir/s.toml: line") && e.contains(want),
                "{keys}: {e}"
            );
            assert_eq!(e.lines().count(), 1, "{e}");
        }
    }
}
