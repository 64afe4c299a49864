//! What a run should say about its starting state before the first step
//! ([`crate::Simulation::start_check`]): intersections the steps will not untangle, and cloth
//! pairs that start closer than the collision thickness. Values and texts only; the front ends
//! print them (`drapery run`, `drapery validate`) or raise them as Python warnings.

use super::tangles::Tangled;

/// The starting state's collision facts, from one search for the starting tangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StartCheck {
    /// Intersecting cloth triangle pairs, as `drapery check` counts them (the two ends of a
    /// stitched pair as one vertex).
    pub intersecting_pairs: usize,
    /// Cloth vertices inside solid colliders or closed meshes.
    pub inside: usize,
    /// What the first steps untangle ([`crate::Simulation::tangled`]).
    pub tangled: Tangled,
    /// Cloth pairs closer than the thickness and the distance of the closest
    /// ([`crate::Simulation::close_pairs`]); `None` without self-collision.
    pub close_pairs: Option<(usize, f64)>,
    /// `collision.thickness`, m.
    pub thickness: f64,
}

impl StartCheck {
    /// Whether the state intersects beyond what the steps untangle: pinned or handle vertices
    /// inside a collider, or crossings without self-collision.
    pub fn intersects_untreated(&self) -> bool {
        self.intersecting_pairs > self.tangled.crossings || self.inside > self.tangled.inside
    }

    /// One line per problem a run should be warned about (none for a clean start), without the
    /// scene's name, which the front end adds.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.intersects_untreated() {
            out.push(format!(
                "frame 0 intersects ({} intersecting cloth triangle pairs, {} vertices inside colliders), not all of it being untangled (pinned or handle vertices inside a collider, or crossings without self_collision)",
                self.intersecting_pairs, self.inside
            ));
        }
        if let Some((count @ 1.., closest)) = self.close_pairs {
            out.push(format!(
                "collision.thickness: {count} cloth pairs that share no vertex start closer than the thickness ({} m; the closest {closest:.3e} m apart), so the cloth pushes itself apart from the first step (a thickness beyond the mesh's own spacing, or layers placed closer than it)",
                self.thickness
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use crate::scene::Scene;
    use std::path::Path;

    /// An 11 × 11 grid of spacing 5 cm centred at the origin (the nearest primitive sharing no
    /// vertex is `0.05/√2` = 3.5 cm away), with more keys of its `[[cloth]]` and more tables.
    fn sim(thickness: f64, cloth: &str, tables: &str) -> crate::Simulation {
        let text = format!(
            "[simulation]\nduration = 0.1\ndt = 0.01\nframe_rate = 10\n\
             [collision]\nthickness = {thickness}\nself_collision = true\n\
             [[cloth]]\nname = \"a\"\ndensity = 0.1\n{cloth}\n\
             grid = {{ size = [0.5, 0.5], resolution = [11, 11], normal = [0.0, 1.0, 0.0] }}\n{tables}"
        );
        Scene::from_str(&text, Path::new("start.toml"))
            .unwrap()
            .build()
            .unwrap()
    }

    #[test]
    fn a_clean_start_has_no_warning_and_a_thick_one_names_the_field() {
        let clean = sim(0.01, "", "").start_check().unwrap();
        assert_eq!(clean.close_pairs.map(|c| c.0), Some(0));
        assert!(clean.warnings().is_empty(), "{:?}", clean.warnings());
        let thick = sim(0.04, "", "").start_check().unwrap();
        let w = thick.warnings();
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].starts_with("collision.thickness: "), "{}", w[0]);
        // the closest pair is a vertex and the triangle across its diagonal, h/√2 apart
        let closest = thick.close_pairs.unwrap().1;
        assert!((closest - 0.05 / 2f64.sqrt()).abs() < 1e-12, "{closest}");
    }

    /// A sphere around the middle of the sheet: its free vertices inside are pushed out (no
    /// warning), a pinned one (the centre, vertex 60) is not (a warning, and the counts say
    /// which).
    #[test]
    fn only_what_the_steps_leave_is_a_warning() {
        let sphere = "[[collider]]\nshape = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 0.06\n";
        let free = sim(0.01, "", sphere).start_check().unwrap();
        // the vertices within 6 cm of the centre on a 5 cm grid: the centre and its 4 neighbours
        assert_eq!((free.inside, free.tangled.inside), (5, 5));
        assert!(!free.intersects_untreated());
        assert!(free.warnings().is_empty(), "{:?}", free.warnings());
        let pinned = sim(0.01, "pin = [60]", sphere).start_check().unwrap();
        assert_eq!((pinned.inside, pinned.tangled.inside), (5, 4));
        let w = pinned.warnings();
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].starts_with("frame 0 intersects (0 intersecting cloth triangle pairs, 5 vertices inside colliders)"), "{}", w[0]);
    }

    /// A vertical sheet through the middle of the horizontal one: with self-collision the
    /// steps untangle every crossing (no warning, and the count, taken from the tangles' own
    /// search, is the checker's); without it the crossings stay and are a warning.
    #[test]
    fn crossed_sheets_are_counted_as_the_checker_counts_them() {
        let through = "[[cloth]]\nname = \"b\"\ndensity = 0.1\n\
             grid = { size = [0.5, 0.5], resolution = [11, 11], center = [0.017, 0.013, 0.0], normal = [1.0, 0.0, 0.0] }\n";
        let crossed = sim(0.01, "", through);
        let (pairs, inside) = crossed.intersections();
        assert!(pairs > 10 && inside == 0, "{pairs} {inside}");
        let c = crossed.start_check().unwrap();
        assert_eq!((c.intersecting_pairs, c.tangled.crossings), (pairs, pairs));
        assert!(c.warnings().is_empty(), "{:?}", c.warnings());
        let text = format!(
            "[simulation]\nduration = 0.1\ndt = 0.01\nframe_rate = 10\n\
             [collision]\nthickness = 0.01\nself_collision = false\n\
             [[cloth]]\nname = \"a\"\ndensity = 0.1\n\
             grid = {{ size = [0.5, 0.5], resolution = [11, 11], normal = [0.0, 1.0, 0.0] }}\n{through}"
        );
        let unsewn = Scene::from_str(&text, Path::new("crossed.toml"))
            .unwrap()
            .build()
            .unwrap()
            .start_check()
            .unwrap();
        assert_eq!(
            (unsewn.intersecting_pairs, unsewn.tangled.crossings),
            (pairs, 0)
        );
        let w = unsewn.warnings();
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with(&format!("frame 0 intersects ({pairs} intersecting")),
            "{}",
            w[0]
        );
    }

    #[test]
    fn without_collisions_there_is_nothing_to_check() {
        let text = "[simulation]\nduration = 0.1\ndt = 0.01\nframe_rate = 10\n\
             [[cloth]]\nname = \"a\"\ndensity = 0.1\n\
             grid = { size = [0.5, 0.5], resolution = [11, 11] }\n";
        let s = Scene::from_str(text, Path::new("none.toml")).unwrap();
        assert_eq!(s.build().unwrap().start_check(), None);
    }
}
