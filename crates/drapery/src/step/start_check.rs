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
    /// ([`crate::Simulation::close_pairs`]); `None` without self-collision, and after steps
    /// (`settled`): cloth that settled in contact lies within the thickness, which is no fault
    /// of the scene. A front end that pre-rolls takes them from the check before the pre-roll.
    pub close_pairs: Option<(usize, f64)>,
    /// `collision.thickness`, m.
    pub thickness: f64,
    /// Whether the state comes from steps (a pre-roll, or a restored run's) rather than from
    /// the scene: its intersections were then made by the steps, not placed by the scene.
    pub settled: bool,
    /// After steps, how many of `intersecting_pairs` have a triangle with a vertex in a
    /// stitched neighbourhood ([`crate::collision::seams::Seams`]), which repulsion and the
    /// fail-safe let through so that the seam can close; 0 before any step.
    pub by_seam: usize,
}

impl StartCheck {
    /// Whether the state intersects beyond what the steps untangle: pinned or handle vertices
    /// inside a collider, or crossings without self-collision.
    pub fn intersects_untreated(&self) -> bool {
        self.intersecting_pairs > self.tangled.crossings || self.inside > self.tangled.inside
    }

    /// This check, made after a pre-roll, with the close pairs of `before`, the check of the
    /// scene's start made before it (`None` when there was no pre-roll: this check is then the
    /// start's and keeps its own). What `drapery run` and Python's `drapery.run` warn of at
    /// frame 0.
    pub fn with_start(mut self, before: Option<StartCheck>) -> StartCheck {
        if let Some(b) = before {
            self.close_pairs = b.close_pairs;
        }
        self
    }

    /// One line per problem a run should be warned about (none for a clean start), without the
    /// scene's name, which the front end adds.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.intersects_untreated() && !self.settled {
            out.push(format!(
                "frame 0 intersects ({} intersecting cloth triangle pairs, {} vertices inside colliders), not all of it being untangled (pinned or handle vertices inside a collider, or crossings without self_collision)",
                self.intersecting_pairs, self.inside
            ));
        } else if self.intersects_untreated() {
            let mut why = Vec::new();
            if self.by_seam > 0 {
                why.push(format!("{} of the pairs lie by a seam: its neighbourhood is let through itself so that it can close, and pinned vertices or vertices pressed by a collider crossed it (for a garment, try another edge_length)", self.by_seam));
            }
            if self.intersecting_pairs > self.tangled.crossings + self.by_seam {
                why.push("cloth crossed in the steps (crossings without self_collision, or cloth pushed through by pinned or handle vertices)".into());
            }
            if self.inside > self.tangled.inside {
                why.push("pinned or handle vertices inside a collider".into());
            }
            out.push(format!(
                "frame 0 intersects after the pre-roll ({} intersecting cloth triangle pairs, {} vertices inside colliders), which the steps do not undo: {}",
                self.intersecting_pairs,
                self.inside,
                why.join("; ")
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

    /// After a step the close pairs are contacts, not a fault of the scene (none reported), and
    /// crossings made since are told apart: those with a triangle in a stitched neighbourhood
    /// (a stitch in the middle of sheet `a`) from the others. Sheet `b` starts 1 m away and,
    /// after one step, is put back vertical through the middle of `a`.
    #[test]
    fn after_steps_the_crossings_by_a_seam_are_told_apart() {
        use crate::Vec3;
        let far = "[[cloth]]\nname = \"b\"\ndensity = 0.1\n\
             grid = { size = [0.5, 0.5], resolution = [11, 11], center = [0.017, 0.013, 1.0], normal = [1.0, 0.0, 0.0] }\n\
             [[stitch]]\na = { cloth = \"a\", vertices = [60] }\nb = { cloth = \"a\", vertices = [62] }\n";
        let mut s = sim(0.01, "", far);
        let fresh = s.start_check().unwrap();
        assert!(!fresh.settled && fresh.intersecting_pairs == 0, "{fresh:?}");
        assert!(fresh.close_pairs.is_some());
        let x0 = s.positions().to_vec();
        s.step(1e-3).unwrap();
        let mut x = s.positions().to_vec();
        let b = s.model().cloths()[1].offset;
        (b..x.len()).for_each(|i| x[i] = x0[i] - Vec3::new(0.0, 0.0, 1.0));
        s.set_positions(&x).unwrap();
        let c = s.start_check().unwrap();
        assert!(c.settled && c.close_pairs.is_none(), "{c:?}");
        assert_eq!(c.intersecting_pairs, s.intersections().0);
        // by brute force: crossing pairs with a triangle that has a vertex sharing a triangle
        // with vertex 60 or 62
        let tris = s.model().triangles();
        let hood: Vec<u32> = (tris.iter())
            .filter(|t| t.contains(&60) || t.contains(&62))
            .flatten()
            .copied()
            .collect();
        let corners = |t: [u32; 3]| t.map(|i| x[i as usize]);
        let mut by_seam = 0;
        for (i, &t) in tris.iter().enumerate() {
            for &u in &tris[i + 1..] {
                let touch = |t: [u32; 3]| t.iter().any(|p| hood.contains(p));
                let shared = t.iter().any(|p| u.contains(p));
                if !shared
                    && (touch(t) || touch(u))
                    && crate::collision::check::triangles_intersect(corners(t), corners(u))
                {
                    by_seam += 1;
                }
            }
        }
        assert!(
            by_seam > 0 && by_seam < c.intersecting_pairs,
            "{by_seam} {c:?}"
        );
        assert_eq!(c.by_seam, by_seam);
        let w = c.warnings();
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].contains(&format!("{by_seam} of the pairs lie by a seam")),
            "{}",
            w[0]
        );
        assert!(w[0].contains("cloth crossed in the steps"), "{}", w[0]);
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
