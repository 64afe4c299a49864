//! Starting tangles: cloth that starts inside a collider or crossed through other cloth, and
//! how the steps untangle it.
//!
//! At the first step ([`Tangles::find`]) two things are recorded:
//! * *inside*: the free cloth vertices strictly inside a collider (a solid's negative signed
//!   distance, or inside a closed mesh, [`crate::collision::colliders::interior`]). Each step
//!   prescribes their velocity toward the way out ([`Tangles::push`]: the closest surface point
//!   plus the thickness), like a moving pin, all at the rate that moves the farthest at
//!   [`PUSH_SPEED`] so that they come out together, and the fail-safe lets them through the
//!   collider's surface ([`Tangles::exempt`]). A vertex is released once it
//!   is outside and at least half the thickness from the surface; from then on the ordinary
//!   contact handling applies. Pinned and handle vertices are never pushed (their motion is
//!   prescribed) and not recorded.
//! * *crossings*: the pairs of cloth triangles that intersect (as the checker counts them,
//!   [`crate::collision::check::sewn_intersecting_pairs`]), with self-collision on. The contact
//!   pairs within a crossing's neighbourhood (the two triangles and every triangle touching
//!   them, [`Seams::around`]) are let through by the fail-safe and get no repulsion, as a
//!   seam's: repulsion pushes each vertex away on the side it is on, which near a crossing
//!   holds the cloth crossed, so the cloth's own forces (springs, gravity) pull the crossed
//!   part back through. A crossing is dropped at the first step that ends with its two
//!   triangles apart; from then on repulsion and the fail-safe keep them apart.
//!
//! Both lists only shrink ([`Tangles::update`], at the end of every step). They are part of the
//! state a snapshot holds, so a resumed run untangles exactly as the uninterrupted one.

use crate::collision::check::{sewn_intersecting_pairs, triangles_intersect};
use crate::collision::colliders::{Collider, Inside};
use crate::collision::seams::Seams;
use crate::math::Vec3;
use crate::model::Model;
use rayon::prelude::*;

use super::pose::Pose;

/// Fastest a vertex is pushed out of a collider, m/s.
pub const PUSH_SPEED: f64 = 0.5;

/// What is still tangled (see the module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct Tangles {
    /// Whether the starting tangles have been found (at the first step).
    pub found: bool,
    /// `(particle, obstacle)` of each vertex being pushed out, by increasing particle.
    pub inside: Vec<[u32; 2]>,
    /// Crossed cloth triangle pairs, increasing.
    pub crossings: Vec<[u32; 2]>,
    /// The crossings' neighbourhoods.
    hoods: Seams,
}

/// How many cloth vertices are inside colliders and how many cloth triangle pairs cross.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tangled {
    /// Cloth vertices (free ones: not pinned, not in a handle) inside a collider.
    pub inside: usize,
    /// Intersecting pairs of cloth triangles (within a cloth or between cloths).
    pub crossings: usize,
}

/// Which particles are pinned or in a handle (their motion is prescribed).
fn held(model: &Model) -> Vec<bool> {
    let mut held = model.pinned.clone();
    for h in &model.handles {
        h.particles.iter().for_each(|&p| held[p as usize] = true);
    }
    held
}

impl Tangles {
    /// Restored from a snapshot's lists.
    pub fn restored(
        found: bool,
        inside: Vec<[u32; 2]>,
        crossings: Vec<[u32; 2]>,
        triangles: &[[u32; 3]],
        n: usize,
    ) -> Tangles {
        let mut t = Tangles {
            found,
            inside,
            crossings,
            hoods: Seams::default(),
        };
        t.hoods = t.neighbourhoods(triangles, n);
        t
    }

    fn neighbourhoods(&self, triangles: &[[u32; 3]], n: usize) -> Seams {
        let groups: Vec<Vec<u32>> = (self.crossings.iter())
            .map(|&[a, b]| {
                let (a, b) = (triangles[a as usize], triangles[b as usize]);
                a.into_iter().chain(b).collect()
            })
            .collect();
        let groups: Vec<&[u32]> = groups.iter().map(|g| &g[..]).collect();
        Seams::around(n, triangles, &groups)
    }

    /// These tangles once found (at the first step), else the ones `model` has now at time `t`,
    /// found into `fresh`.
    pub fn or_find<'a>(
        &'a self,
        model: &Model,
        triangles: &[[u32; 3]],
        t: f64,
        fresh: &'a mut Option<Tangles>,
    ) -> &'a Tangles {
        if self.found {
            self
        } else {
            fresh.insert(Tangles::find(model, triangles, t))
        }
    }

    /// The tangles of `model` at its current state and time `t` (nothing without collisions).
    pub fn find(model: &Model, triangles: &[[u32; 3]], t: f64) -> Tangles {
        let Some(c) = &model.collision else {
            return Tangles {
                found: true,
                ..Tangles::default()
            };
        };
        let held = held(model);
        let insides: Vec<_> = (model.obstacles.iter())
            .map(|o| o.collider.inside_at(t))
            .collect();
        let inside: Vec<[u32; 2]> = (0..model.particle_count())
            .into_par_iter()
            .with_min_len(64)
            .filter_map(|i| {
                let k = (!held[i]).then(|| {
                    (insides.iter())
                        .position(|s| s.as_ref().is_some_and(|s| s.contains(model.x[i])))
                })??;
                Some([i as u32, k as u32])
            })
            .collect();
        let crossings = if c.self_collision {
            let sewn: Vec<[u32; 2]> = model.stitches.iter().map(|s| [s.a, s.b]).collect();
            sewn_intersecting_pairs(&model.x, triangles, &sewn)
        } else {
            Vec::new()
        };
        Tangles::restored(true, inside, crossings, triangles, model.particle_count())
    }

    /// The counts.
    pub fn counts(&self) -> Tangled {
        Tangled {
            inside: self.inside.len(),
            crossings: self.crossings.len(),
        }
    }

    /// Prescribes the velocity of every vertex being pushed out over the step of `pose` (see
    /// the module docs).
    pub fn push(&self, model: &Model, thickness: f64, pose: &mut Pose) {
        if self.inside.is_empty() {
            return;
        }
        let (t1, h) = (pose.t0 + pose.h, pose.h);
        let insides = insides(model, &self.inside, t1);
        let way: Vec<(u32, Vec3)> = (self.inside.par_iter())
            .filter(|&&[i, _]| !pose.pinned[i as usize])
            .map(|&[i, k]| {
                let x = model.x[i as usize];
                let o = &model.obstacles[k as usize].collider;
                let inside = insides[k as usize].as_ref().is_some_and(|s| s.contains(x));
                (i, way_out(o, inside, x, t1, thickness) - x)
            })
            .collect();
        // every vertex along its way at the rate that takes the farthest at PUSH_SPEED, so that
        // they all come out together (a vertex out early would be held by stretched springs
        // to those still inside, and snap when they come out)
        let farthest = way.iter().map(|(_, d)| d.length()).fold(0.0, f64::max);
        let rate = (1.0 / h).min(PUSH_SPEED / farthest);
        let moving: Vec<(u32, Vec3)> = way.into_iter().map(|(i, d)| (i, d * rate)).collect();
        for &(i, _) in &moving {
            pose.pinned[i as usize] = true;
        }
        pose.pins.moving.extend(moving);
        pose.pins.moving.sort_by_key(|&(i, _)| i);
        pose.surface_speed = pose.surface_speed.max(PUSH_SPEED);
    }

    /// Whether the contact pair of particles `ids` is let through (by the fail-safe; and by
    /// repulsion, which only sees cloth pairs): a cloth vertex being pushed out against a
    /// collider (particles from `n` on are colliders'), or a pair within a crossing's
    /// neighbourhood.
    pub fn exempt(&self, ids: &[u32; 4], n: usize) -> bool {
        let pushed =
            |p: u32| (p as usize) < n && self.inside.binary_search_by_key(&p, |e| e[0]).is_ok();
        (!self.inside.is_empty()
            && ids.iter().any(|&p| p as usize >= n)
            && ids.iter().any(|&p| pushed(p)))
            || self.hoods.exempt(ids)
    }

    /// What is still tangled after a step that ends at positions `x` at time `t1`.
    pub fn update(
        &self,
        model: &Model,
        triangles: &[[u32; 3]],
        x: &[Vec3],
        t1: f64,
        thickness: f64,
    ) -> Tangles {
        if self.inside.is_empty() && self.crossings.is_empty() {
            return self.clone();
        }
        let insides = insides(model, &self.inside, t1);
        let inside: Vec<[u32; 2]> = (self.inside.par_iter())
            .filter(|&&[i, k]| {
                let (p, o) = (x[i as usize], &model.obstacles[k as usize].collider);
                let deep = insides[k as usize].as_ref().is_some_and(|s| s.contains(p));
                deep || o.closest(p, t1).signed_distance.abs() < 0.5 * thickness
            })
            .copied()
            .collect();
        let corners = |t: u32| triangles[t as usize].map(|i| x[i as usize]);
        let crossings: Vec<[u32; 2]> = (self.crossings.par_iter())
            .filter(|&&[a, b]| triangles_intersect(corners(a), corners(b)))
            .copied()
            .collect();
        let hoods = if crossings == self.crossings {
            self.hoods.clone()
        } else {
            Seams::default()
        };
        let mut t = Tangles {
            found: true,
            inside,
            crossings,
            hoods,
        };
        if t.crossings != self.crossings {
            t.hoods = t.neighbourhoods(triangles, x.len());
        }
        t
    }
}

/// The insides at time `t` of the obstacles some vertex of `pushed` is being pushed out of.
fn insides<'a>(model: &'a Model, pushed: &[[u32; 2]], t: f64) -> Vec<Option<Inside<'a>>> {
    let mut used = vec![false; model.obstacles.len()];
    pushed.iter().for_each(|&[_, k]| used[k as usize] = true);
    (model.obstacles.iter().zip(used))
        .map(|(o, used)| used.then(|| o.collider.inside_at(t)).flatten())
        .collect()
}

/// Where a vertex at `x`, `inside` collider `o` or not (then within the release distance of its
/// surface), leaves it at time `t`: the closest surface point plus `margin` outward.
fn way_out(o: &Collider, inside: bool, x: Vec3, t: f64, margin: f64) -> Vec3 {
    let c = o.closest(x, t);
    // a solid's normal points out; a surface's points from the surface toward `x` (on the
    // surface: the face normal, outward for an outward-wound closed mesh)
    let out = if o.is_solid() || c.signed_distance == 0.0 || !inside {
        c.normal
    } else {
        -c.normal
    };
    c.point + out * margin
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Simulation;
    use crate::collision::check::count_intersections_between;
    use crate::collision::colliders::{Shape, mesh::welded};
    use crate::collision::tessellate::TessellateOptions;
    use crate::scene::Scene;
    use crate::snapshot::Snapshot;

    fn scene(text: &str) -> Scene {
        Scene::from_str(text, std::path::Path::new("t.toml")).unwrap()
    }

    /// A 1.2 m sheet at `y = 0.4` through a ball of radius 0.5 at the origin: the vertices
    /// within 0.3 m of the axis start inside. Pre-roll 0.6 s (the deepest is 0.1 m in).
    const BALL: &str = r#"
[simulation]
duration = 0.1
dt = 0.005
frame_rate = 20
preroll = 0.6
[collision]
thickness = 0.005
friction = 0.3
[[cloth]]
name = "sheet"
grid = { size = [1.2, 1.2], resolution = [33, 33], center = [0.019, 0.4, 0.018], normal = [0.0, 1.0, 0.0] }
density = 0.1
[[collider]]
shape = "sphere"
center = [0.0, 0.0, 0.0]
radius = 0.5
"#;

    /// The ball scene, its collider the analytic sphere or the sphere's closed tessellation.
    fn ball(mesh: bool) -> (Scene, Simulation) {
        let s = scene(BALL);
        let mut sim = s.build().unwrap();
        if mesh {
            let c = &mut sim.model.obstacles[0].collider;
            let o = TessellateOptions {
                segments: 64,
                ..TessellateOptions::default()
            };
            let (v, t) = c.shape.tessellate(0.0, &o);
            let (v, t) = welded(v, t);
            c.shape = Shape::Mesh(crate::collision::colliders::TriangleMesh::new(v, t));
            assert!(c.shape.is_closed());
        }
        (s, sim)
    }

    #[test]
    fn a_sheet_starting_half_inside_a_ball_or_a_closed_mesh_is_pushed_out_in_the_preroll() {
        for mesh in [false, true] {
            let (s, mut sim) = ball(mesh);
            // by construction: the vertices closer than 0.5 m to the center (none is within
            // 1.5 mm of the sphere, farther than the tessellation's 1.2 mm from it)
            let x = sim.positions().to_vec();
            assert!(x.iter().all(|p| (p.length() - 0.5).abs() > 0.0015));
            let put_inside = x.iter().filter(|p| p.length() < 0.5).count();
            assert!(put_inside > 200, "{put_inside}");
            assert_eq!(
                sim.tangled(),
                Tangled {
                    inside: put_inside,
                    crossings: 0
                },
                "mesh {mesh}"
            );
            assert_eq!(sim.intersections().1, put_inside, "the checker agrees");
            if mesh {
                for k in 0..50 {
                    let i = sim
                        .tangles
                        .inside
                        .first()
                        .map(|e| e[0] as usize)
                        .unwrap_or(0);
                    let before = sim.positions()[i];
                    sim.step(0.005).unwrap();
                    if k % 5 == 0 {
                        eprintln!(
                            "{k} {:?} {i} {before} -> {}",
                            sim.tangled(),
                            sim.positions()[i]
                        );
                    }
                }
            }
            sim.preroll(s.preroll_steps(), s.step_size()).unwrap();
            assert_eq!(sim.tangled().inside, 0, "mesh {mesh}");
            assert_eq!(sim.intersections(), (0, 0), "mesh {mesh}");
            assert!(
                sim.positions().iter().all(|p| p.length() > 0.49),
                "mesh {mesh}: every vertex outside the ball"
            );
            if mesh {
                let c = &sim.model().obstacles()[0].collider;
                let (v, t) = c.surface(0.0).unwrap();
                let tris = sim.triangles.clone();
                let n = count_intersections_between(sim.positions(), &tris, &v, t);
                assert_eq!(n, 0, "no cloth triangle through the mesh");
            }
            // and the run goes on from there
            for _ in 0..10 {
                sim.step(s.step_size()).unwrap();
            }
            assert_eq!(sim.intersections(), (0, 0), "mesh {mesh}");
        }
    }

    /// A sheet held flat at `y = 0.5` (every vertex pinned) and a free smaller one 2 cm below,
    /// whose middle vertex starts 2 cm above the first: the triangles around it cross the held
    /// sheet. A ground below.
    const CROSSED: &str = r#"
[simulation]
duration = 0.5
dt = 0.005
frame_rate = 20
preroll = 0.3
[collision]
thickness = 0.004
self_collision = true
[[cloth]]
name = "taut"
grid = { size = [0.5, 0.5], resolution = [11, 11], center = [0.0, 0.5, 0.0], normal = [0.0, 1.0, 0.0] }
density = 0.1
pin = [ALL]
[[cloth]]
name = "free"
grid = { size = [0.3, 0.3], resolution = [7, 7], center = [0.013, 0.48, 0.017], normal = [0.0, 1.0, 0.0] }
density = 0.1
[[collider]]
shape = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
"#;

    fn crossed() -> (Scene, Simulation) {
        let all: Vec<String> = (0..121).map(|i| i.to_string()).collect();
        let s = scene(&CROSSED.replace("ALL", &all.join(", ")));
        let mut sim = s.build().unwrap();
        let mut x = sim.positions().to_vec();
        // the free sheet's middle vertex (121 + 3·7 + 3) through the taut sheet
        x[121 + 24].y = 0.52;
        sim.set_positions(&x).unwrap();
        (s, sim)
    }

    #[test]
    fn sheets_starting_crossed_separate_in_the_preroll_and_stay_apart() {
        let (s, mut sim) = crossed();
        let start = sim.tangled();
        assert_eq!(start.inside, 0);
        // each of the 6 triangles around the lifted vertex crosses one or two taut triangles
        assert!(start.crossings >= 6, "{start:?}");
        assert_eq!(start.crossings, sim.intersections().0);
        sim.preroll(s.preroll_steps(), s.step_size()).unwrap();
        assert_eq!(sim.tangled(), Tangled::default());
        assert_eq!(sim.intersections(), (0, 0));
        let free_y = |sim: &Simulation| sim.positions()[121 + 24].y;
        assert!(
            free_y(&sim) < 0.5,
            "the middle vertex is back below the taut sheet"
        );
        for _ in 0..s.step_count() {
            sim.step(s.step_size()).unwrap();
            assert_eq!(sim.intersections(), (0, 0), "at t = {}", sim.time());
        }
    }

    #[test]
    fn a_run_resumed_while_untangling_gives_the_same_bits() {
        for scene in [0, 1] {
            let (s, mut a) = if scene == 0 { ball(false) } else { crossed() };
            let h = s.step_size();
            // no pre-roll: the first steps untangle
            for _ in 0..[8, 1][scene] {
                a.step(h).unwrap();
            }
            let t = a.tangled();
            assert!(t.inside + t.crossings > 0, "still untangling: {t:?}");
            let bytes = a.snapshot().to_bytes();
            let mut b = s.build().unwrap();
            if scene == 0 {
                b.model.obstacles = a.model.obstacles.clone();
            }
            b.restore_snapshot(&Snapshot::from_bytes(&bytes).unwrap())
                .unwrap();
            assert_eq!(b.tangled(), t);
            for _ in 0..40 {
                a.step(h).unwrap();
                b.step(h).unwrap();
            }
            assert_eq!(a.tangled(), b.tangled());
            let bits = |s: &Simulation| -> Vec<u64> {
                (s.positions().iter().chain(s.velocities()))
                    .flat_map(|p| p.to_array().map(f64::to_bits))
                    .collect()
            };
            assert_eq!(bits(&a), bits(&b), "scene {scene}");
        }
    }
}
