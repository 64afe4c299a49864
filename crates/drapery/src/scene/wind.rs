//! `[[wind]]` tables: the air's `velocity = [x, y, z]` (m/s) or
//! `keyframes = [{ time, velocity }, ...]` (piecewise linear, held outside the keys), its
//! `density` (kg/m³), the normal `drag` coefficient and the `lift` coefficient (default 0: no
//! lift). Errors name `wind[i].key`
//! (`wind[0].keyframes[1].velocity`); the model checks the values.

use crate::collision::colliders::Keys;
use crate::error::Result;
use crate::forces::wind::{AirVelocity, DEFAULT_DENSITY, DEFAULT_DRAG, DEFAULT_LIFT, Wind};
use std::path::Path;

const KEYS: &[&str] = &["velocity", "keyframes", "density", "drag", "lift"];
const KEYFRAME_KEYS: &[&str] = &["time", "velocity"];

/// `keyframes = [{ time, velocity }, ...]` of wind `keys`.
fn keyframes(keys: &Keys, value: &toml::Value, dir: &Path) -> Result<AirVelocity> {
    let shape = "must be an array of tables { time, velocity }";
    let list = value
        .as_array()
        .ok_or_else(|| keys.error("keyframes", shape))?;
    let mut out = Vec::with_capacity(list.len());
    for (k, item) in list.iter().enumerate() {
        let field = keys.path(&format!("keyframes[{k}]"));
        let table = item
            .as_table()
            .ok_or_else(|| crate::Error::field(&field, "must be a table { time, velocity }"))?;
        let key = Keys::new(table, field, dir);
        key.only(KEYFRAME_KEYS, "a wind keyframe")?;
        out.push((key.number("time")?, key.vec3("velocity")?));
    }
    Ok(AirVelocity::Keyframes(out))
}

/// One `[[wind]]` table (index `i`).
pub(super) fn wind(i: usize, table: &toml::Table, dir: &Path) -> Result<Wind> {
    let keys = Keys::new(table, format!("wind[{i}]"), dir);
    keys.only(KEYS, "[[wind]]")?;
    let velocity = match (table.get("velocity"), table.get("keyframes")) {
        (Some(_), None) => AirVelocity::Constant(keys.vec3("velocity")?),
        (None, Some(k)) => keyframes(&keys, k, dir)?,
        (Some(_), Some(_)) => {
            return Err(keys.error("keyframes", "give either velocity or keyframes, not both"));
        }
        (None, None) => {
            return Err(keys.error(
                "velocity",
                "missing: give velocity = [x, y, z] or keyframes = [{ time, velocity }, ...]",
            ));
        }
    };
    Ok(Wind {
        velocity,
        density: keys.number_or("density", DEFAULT_DENSITY)?,
        drag: keys.number_or("drag", DEFAULT_DRAG)?,
        lift: keys.number_or("lift", DEFAULT_LIFT)?,
    })
}

#[cfg(test)]
mod tests {
    use super::super::Scene;
    use crate::math::Vec3;
    use std::path::Path;

    /// A horizontal 1 m × 1 m sheet of `density` kg/m² (stiff, no bending), `gravity`, and
    /// `extra` tables.
    fn scene(density: f64, gravity: &str, duration: f64, extra: &str) -> String {
        format!(
            "[simulation]\nduration = {duration}\ndt = 0.01\nframe_rate = 50\ngravity = {gravity}\n\n\
             [[cloth]]\nname = \"sheet\"\n\
             grid = {{ size = [1, 1], resolution = [5, 5], center = [0, 0, 0], normal = [0, 1, 0] }}\n\
             density = {density}\nstretch_stiffness = 10000\nshear_stiffness = 1000\nbend_stiffness = 0\n\n{extra}"
        )
    }

    /// Loads `text` from a file in a temporary folder (end to end, as the command does) and
    /// runs it to its end; the mean velocity of the sheet.
    fn run(text: &str) -> Vec3 {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("wind.toml");
        std::fs::write(&path, text).unwrap();
        let scene = Scene::load(&path).unwrap();
        let mut sim = scene.start().unwrap();
        for _ in 0..scene.step_count() {
            sim.step(scene.step_size()).unwrap();
        }
        let v = sim.velocities();
        v.iter().sum::<Vec3>() / v.len() as f64
    }

    #[test]
    fn a_sheet_falling_face_on_in_still_air_reaches_its_terminal_velocity() {
        let (sigma, g, rho, cd) = (0.1, 9.81, 1.2, 1.3);
        let text = scene(
            sigma,
            "[0, -9.81, 0]",
            1.5,
            &format!("[[wind]]\nvelocity = [0, 0, 0]\ndensity = {rho}\ndrag = {cd}\n"),
        );
        // m g = ½ ρ C_d A v², m = σ A (reached within 1e-4: tanh(g t / v) at t = 1.5 s)
        let terminal = (2.0 * sigma * g / (rho * cd)).sqrt();
        let v = run(&text);
        assert!(
            (v.y + terminal).abs() < 1e-4 * terminal,
            "{v} vs terminal {terminal}"
        );
        assert!(v.x.abs() + v.z.abs() < 1e-6 * terminal, "{v}");
    }

    #[test]
    fn a_sheet_in_a_steady_wind_without_gravity_reaches_the_wind_velocity() {
        // face-on wind along the sheet's normal, made of two winds that add
        let text = scene(
            0.01,
            "[0, 0, 0]",
            2.0,
            "[[wind]]\nvelocity = [0, 1.5, 0]\n\n[[wind]]\nkeyframes = [{ time = 0, velocity = [0, 0, 0] }, { time = 0.2, velocity = [0, 0.5, 0] }]\n",
        );
        // dv/dt = (ρ C_d / 2σ)(V - v)²: V - v = 1/(1/V + 60 t) after the gust, under 1 % of V at 2 s
        let v = run(&text);
        assert!((v - Vec3::new(0.0, 2.0, 0.0)).length() < 0.01 * 2.0, "{v}");
        assert!(
            v.y < 2.0,
            "{v}: the air drags, never pushes past its own speed"
        );
    }

    /// Wind (with lift) and pressure (on an open sheet: a sail) step to the same bits on 1 and 2
    /// threads.
    #[test]
    fn wind_and_pressure_give_the_same_bits_on_any_number_of_threads() {
        let text = scene(
            0.1,
            "[0, -9.81, 0]",
            0.2,
            "[[wind]]\nkeyframes = [{ time = 0, velocity = [1, 0, 0] }, { time = 0.1, velocity = [0, 3, 1] }]\nlift = 0.7\n",
        )
        .replace("bend_stiffness = 0\n", "bend_stiffness = 0\npressure = 20\n");
        let scene = Scene::from_str(&text, Path::new("s.toml")).unwrap();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut sim = scene.start().unwrap();
                for _ in 0..scene.step_count() {
                    sim.step(scene.step_size()).unwrap();
                }
                let names: Vec<&str> = sim.forces().iter().map(|f| f.name()).collect();
                assert!(names.contains(&"wind") && names.contains(&"pressure"));
                (sim.positions().iter().chain(sim.velocities()))
                    .flat_map(|p| p.to_array().map(f64::to_bits))
                    .collect::<Vec<_>>()
            })
        };
        let one = run(1);
        assert_eq!(one, run(2));
        assert_ne!(one, run_plain(&scene));
    }

    /// The scene's bits without its winds and pressure.
    fn run_plain(scene: &Scene) -> Vec<u64> {
        let mut plain = scene.clone();
        plain.wind.clear();
        for c in &mut plain.cloths {
            c.material.pressure = 0.0;
        }
        let mut sim = plain.start().unwrap();
        for _ in 0..plain.step_count() {
            sim.step(plain.step_size()).unwrap();
        }
        (sim.positions().iter().chain(sim.velocities()))
            .flat_map(|p| p.to_array().map(f64::to_bits))
            .collect()
    }

    #[test]
    fn lift_is_read_and_defaults_to_none() {
        let path = Path::new("s.toml");
        let text = |extra: &str| {
            scene(
                0.1,
                "[0, -9.81, 0]",
                1.0,
                &format!("[[wind]]\nvelocity = [1, 0, 0]\n{extra}"),
            )
        };
        let plain = Scene::from_str(&text(""), path).unwrap();
        assert_eq!(plain.wind[0].lift, 0.0);
        let lifted = Scene::from_str(&text("lift = 0.75\n"), path).unwrap();
        assert_eq!(lifted.wind[0].lift, 0.75);
    }

    #[test]
    fn no_wind_table_means_no_air_force() {
        let path = Path::new("s.toml");
        let plain = Scene::from_str(&scene(0.1, "[0, -9.81, 0]", 1.0, ""), path).unwrap();
        assert!(plain.wind.is_empty());
        let sim = plain.build().unwrap();
        assert!(sim.forces().iter().all(|f| f.name() != "wind"));
        let windy = scene(
            0.1,
            "[0, -9.81, 0]",
            1.0,
            "[[wind]]\nvelocity = [1, 0, 0]\n",
        );
        let sim = Scene::from_str(&windy, path).unwrap().build().unwrap();
        assert!(sim.forces().iter().any(|f| f.name() == "wind"));
    }

    #[test]
    fn bad_winds_are_one_line_errors_naming_the_field() {
        let base = scene(0.1, "[0, -9.81, 0]", 1.0, "");
        // [[wind]] is on line 15, its first key on line 16
        let cases = [
            (
                "velocity = [1, 2]\n",
                "dir/s.toml: line 16, wind[0].velocity: must be an array of 3 numbers",
            ),
            (
                "velocity = [1, 2, 3]\ndensity = -1\n",
                "dir/s.toml: line 17, wind[0].density: must be a finite number > 0, got -1",
            ),
            (
                "velocity = [1, 2, 3]\ndrag = -0.5\n",
                "dir/s.toml: line 17, wind[0].drag: must be a finite number ≥ 0, got -0.5",
            ),
            (
                "velocity = [1, 2, 3]\nlift = -1\n",
                "dir/s.toml: line 17, wind[0].lift: must be a finite number ≥ 0, got -1",
            ),
            (
                "velocity = [1, 2, 3]\nlift = \"some\"\n",
                "dir/s.toml: line 17, wind[0].lift: must be a number",
            ),
            (
                "velocity = [1, 2, 3]\nlift = 0.5\n\n[[wind]]\nvelocity = [0, 0, 0]\n",
                "wind[1].lift: 0 differs from wind[0]'s 0.5",
            ),
            (
                "velocity = [1, 2, 3]\nspeed = 1\n",
                "dir/s.toml: line 17, wind[0].speed: unknown key of [[wind]]",
            ),
            (
                "density = 1\n",
                "dir/s.toml: line 15, wind[0].velocity: missing",
            ),
            (
                "velocity = [1, 2, 3]\nkeyframes = []\n",
                "wind[0].keyframes: give either velocity or keyframes, not both",
            ),
            (
                "keyframes = [{ time = 1, velocity = [0, 0, 0] }, { time = 0.5, velocity = [1, 0, 0] }]\n",
                "wind[0].keyframes[1].time: 0.5 is not after the previous keyframe's 1",
            ),
            (
                "keyframes = [{ time = 1, velocity = [0, 0] }]\n",
                "wind[0].keyframes[0].velocity: must be an array of 3 numbers",
            ),
            ("keyframes = []\n", "wind[0].keyframes: is empty"),
            (
                "velocity = [1, 2, 3]\n\n[[wind]]\nvelocity = [0, 0, 0]\ndensity = 1.0\n",
                "wind[1].density: 1 differs from wind[0]'s 1.2",
            ),
        ];
        for (table, want) in cases {
            let text = format!("{base}[[wind]]\n{table}");
            let e = Scene::from_str(&text, Path::new("dir/s.toml"))
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with(want) || (e.starts_with("dir/s.toml: ") && e.contains(want)),
                "{e:?} lacks {want:?}"
            );
            assert!(!e.contains('\n'), "{e:?} is one line");
        }
    }
}
