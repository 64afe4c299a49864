//! `[[stitch]]` tables: two sides `{ cloth, vertices }` paired one to one, an optional
//! `stiffness` and `damping`. Errors name `stitch[i].key` (`stitch[0].b.vertices`); the model
//! checks the rest (cloth names, counts, ranges, a vertex stitched to itself).

use crate::collision::colliders::Keys;
use crate::error::Result;
use crate::forces::stitch::{DEFAULT_DAMPING, DEFAULT_STIFFNESS};
use crate::model::{StitchDesc, StitchEnd};
use std::path::Path;

const KEYS: &[&str] = &["a", "b", "stiffness", "damping"];
const SIDE_KEYS: &[&str] = &["cloth", "vertices"];

/// One side, `name` = `a` or `b`, of stitch `keys`.
fn side(keys: &Keys, table: &toml::Table, name: &str, dir: &Path) -> Result<StitchEnd> {
    let shape = "must be a table { cloth = \"NAME\", vertices = [...] }";
    let t = table
        .get(name)
        .ok_or_else(|| keys.error(name, format!("missing: {shape}")))?
        .as_table()
        .ok_or_else(|| keys.error(name, shape))?;
    let k = Keys::new(t, keys.path(name), dir);
    k.only(SIDE_KEYS, "a stitch side")?;
    let cloth = k.string("cloth")?.to_string();
    let vertices = k.indices("vertices")?;
    Ok(StitchEnd { cloth, vertices })
}

/// One `[[stitch]]` table (index `i`).
pub(super) fn stitch(i: usize, table: &toml::Table, dir: &Path) -> Result<StitchDesc> {
    let keys = Keys::new(table, format!("stitch[{i}]"), dir);
    keys.only(KEYS, "[[stitch]]")?;
    Ok(StitchDesc {
        a: side(&keys, table, "a", dir)?,
        b: side(&keys, table, "b", dir)?,
        stiffness: keys.number_or("stiffness", DEFAULT_STIFFNESS)?,
        damping: keys.number_or("damping", DEFAULT_DAMPING)?,
    })
}

#[cfg(test)]
mod tests {
    use super::super::Scene;
    use std::path::Path;

    /// Two 3 × 3 cloths (9 vertices each) and `stitches`.
    fn scene(stitches: &str) -> String {
        let cloth = |name: &str, y: f64| {
            format!(
                "[[cloth]]\nname = \"{name}\"\ngrid = {{ size = [1, 1], resolution = [3, 3], center = [0, {y}, 0] }}\nvertex_mass = 0.01\n\n"
            )
        };
        format!(
            "[simulation]\nduration = 1\ndt = 0.01\nframe_rate = 25\n\n{}{}{stitches}",
            cloth("front", 1.0),
            cloth("back", 1.1)
        )
    }

    fn err(stitches: &str) -> String {
        Scene::from_str(&scene(stitches), Path::new("dir/s.toml"))
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn stitches_become_global_pairs_with_the_defaults() {
        let text = scene(
            "[[stitch]]\na = { cloth = \"front\", vertices = [0, 1, 2] }\nb = { cloth = \"back\", vertices = [6, 7, 8] }\n\n\
             [[stitch]]\na = { cloth = \"back\", vertices = [0] }\nb = { cloth = \"back\", vertices = [2] }\nstiffness = 50\ndamping = 0.5\n",
        );
        let s = Scene::from_str(&text, Path::new("s.toml")).unwrap();
        let m = s.model().unwrap();
        let pairs: Vec<(u32, u32, f64, f64)> = m
            .stitches()
            .iter()
            .map(|p| (p.a, p.b, p.stiffness, p.damping))
            .collect();
        // back's particles start after front's 9
        assert_eq!(
            pairs,
            vec![
                (0, 15, 1000.0, 0.0),
                (1, 16, 1000.0, 0.0),
                (2, 17, 1000.0, 0.0),
                (9, 11, 50.0, 0.5)
            ]
        );
        let sim = s.build().unwrap();
        assert!(sim.forces().iter().any(|f| f.name() == "stitches"));
    }

    #[test]
    fn bad_stitches_are_one_line_errors_naming_the_stitch() {
        let ok = "[[stitch]]\na = { cloth = \"front\", vertices = [0, 1] }\nb = { cloth = \"back\", vertices = [6, 7] }\n\n";
        // the second stitch's `b` is on line 22 of the scene
        let cases = [
            (
                format!(
                    "{ok}[[stitch]]\na = {{ cloth = \"front\", vertices = [0, 1, 2, 3, 4] }}\nb = {{ cloth = \"back\", vertices = [0, 1, 2, 3] }}\n"
                ),
                "dir/s.toml: line 22, stitch[1].b.vertices: 4 vertices, but a has 5",
            ),
            (
                ok.replace("\"back\"", "\"bak\""),
                "dir/s.toml: line 18, stitch[0].b.cloth: no cloth named 'bak' (the cloths are 'front', 'back')",
            ),
            (
                ok.replace("[6, 7]", "[6, 9]"),
                "dir/s.toml: line 18, stitch[0].b.vertices: vertex 9 is out of range (cloth 'back' has 9 vertices)",
            ),
            (
                ok.replace(
                    "\"back\", vertices = [6, 7]",
                    "\"front\", vertices = [6, 1]",
                ),
                "dir/s.toml: line 18, stitch[0].b.vertices: pair 1 stitches vertex 1 of cloth 'front' to itself",
            ),
            (
                ok.replace("[6, 7]", "[6, -7]"),
                "dir/s.toml: line 18, stitch[0].b.vertices: must be an array of vertex indices ≥ 0",
            ),
            (
                ok.replace("[0, 1]", "[]").replace("[6, 7]", "[]"),
                "dir/s.toml: line 17, stitch[0].a.vertices: is empty",
            ),
            (
                format!("{ok}stiffness = -1\n"),
                "dir/s.toml: line 20, stitch[0].stiffness: must be a finite number > 0, got -1",
            ),
            (
                format!("{ok}damping = -1\n"),
                "dir/s.toml: line 20, stitch[0].damping: must be a finite number ≥ 0, got -1",
            ),
            (
                format!("{ok}strength = 1\n"),
                "dir/s.toml: line 20, stitch[0].strength: unknown key of [[stitch]]",
            ),
            (
                ok.replace("cloth = \"back\", ", "cloth = \"back\", vertex = 1, "),
                "dir/s.toml: line 18, stitch[0].b.vertex: unknown key of a stitch side",
            ),
            (
                ok.replace("b = { cloth = \"back\", vertices = [6, 7] }\n", ""),
                "stitch[0].b: missing",
            ),
        ];
        for (text, want) in cases {
            let e = err(&text);
            assert!(
                e.starts_with(want) || (e.starts_with("dir/s.toml") && e.contains(want)),
                "{e:?} lacks {want:?}"
            );
            assert!(!e.contains('\n'), "{e:?} is one line");
        }
    }
}
