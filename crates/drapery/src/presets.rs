//! The standard benchmark scenes, shared by `drapery bench`, `cargo bench` and the tests.
//!
//! Every scene is a 1 m square cloth of `n × n` vertices and 0.1 kg (stretch 1000 N/m, shear
//! 100 N/m, bend 1 N/m, damping 0.01), meant to be stepped once per frame at dt = 1/60 s:
//!
//! * [`Preset::Hang`]: vertical, hanging from its two top corners;
//! * [`Preset::Drape`]: horizontal, 0.4 m above a fixed sphere of radius 0.3 m;
//! * [`Preset::Pile`]: tilted, 0.6 m above the ground plane, so that it folds onto itself;
//! * [`Preset::Twist`]: horizontal, without gravity, its left and right edges handles turning
//!   in opposite directions about the x axis (a turn each in 4 s) while moving 0.1 m inward
//!   each: the cloth wrings itself into self-contact.
//!
//! Drape, pile and twist have collisions on (thickness 5 mm, self-collision, friction 0.3).
//!
//! Two textile scenes on the shell model, whose size `N` is the **edge length in mm**:
//!
//! * [`Preset::Cantilever`]: the cantilever of `tests/it/textile.rs`, a 16 cm × 4 cm strip
//!   (B = 10⁻⁴ N·m, 0.1 kg/m², stretch 5000 N/m) clamped level at one end, sagging;
//! * [`Preset::Cusick`]: the Cusick drape test of `tests/it/drape.rs`, a 30 cm disc of the
//!   `cotton` preset falling onto an 18 cm support cylinder (mesh collider, no
//!   self-collision, thickness 2 mm, friction 0.3).
//!
//! The rotating sphere of issue 18 (the size of the IPC paper's scene), stepped at dt = 0.01 s,
//! 4 steps per frame (25 frames per second), defined once as scene text ([`spin_scene`]) so
//! that `drapery run` and `drapery check --scene` can run the very scene the bench times:
//!
//! * [`Preset::Spin`]: a 1.6 m cloth of `n × n` vertices (0.1 kg/m², the springs above)
//!   dropped from 2 cm onto a sphere of radius 0.5 m spinning about the vertical axis at
//!   180°/s, friction 0.4, self-collision on (thickness 2 mm: below half a diagonal of the
//!   290² grid, so that the flat cloth has no close pairs with itself);
//! * [`Preset::SpinFree`]: the same cloth without collisions. The bench warms it up as
//!   [`Preset::Spin`] ([`Preset::warm_up_scene`]) and times it from that draped state, so that
//!   the ratio of the two is what contacts cost on the same cloth doing the same work.

use crate::animation::{Interpolation, Keyframe, Motion, Track};
use crate::collision::colliders::{Collider, Plane, Shape, Sphere, TriangleMesh};
use crate::collision::settings::{CollisionSettings, Obstacle};
use crate::constraints::handles::HandleDesc;
use crate::model::{ClothDesc, ClothModel, MassSpec, Material, Model, Shell};
use crate::{Error, Mesh, Result, Simulation, SolverSettings, Vec3};
use glam::DQuat;

/// Which standard scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// Hanging from two corners.
    Hang,
    /// Falling onto a sphere.
    Drape,
    /// Falling onto the ground and folding.
    Pile,
    /// Wrung by two handles turning opposite ways.
    Twist,
    /// A shell strip clamped at one end (size: edge length in mm).
    Cantilever,
    /// A shell disc draping over the Cusick support (size: edge length in mm).
    Cusick,
    /// Dropped onto a spinning sphere (issue 18).
    Spin,
    /// The spinning sphere's cloth without collisions.
    SpinFree,
}

impl Preset {
    /// Parses `KIND-SIZE` (`hang-64`, `drape-128`, ...) into the preset and the grid size.
    pub fn parse(name: &str) -> Result<(Preset, usize)> {
        let bad = |why: String| Error::Invalid(format!("scene '{name}': {why}"));
        let (kind, n) = name
            .rsplit_once('-')
            .ok_or_else(|| bad("expected KIND-SIZE, e.g. hang-64".into()))?;
        let n: usize = n
            .parse()
            .ok()
            .filter(|&n| (2..=2048).contains(&n))
            .ok_or_else(|| bad("the size must be a whole number from 2 to 2048".into()))?;
        let preset = match kind {
            "hang" => Preset::Hang,
            "drape" => Preset::Drape,
            "pile" => Preset::Pile,
            "twist" => Preset::Twist,
            "cantilever" => Preset::Cantilever,
            "cusick" => Preset::Cusick,
            "spin" => Preset::Spin,
            "spin-free" => Preset::SpinFree,
            _ => {
                return Err(bad(format!(
                    "unknown kind '{kind}' (hang, drape, pile, twist, cantilever, cusick, spin or spin-free)"
                )));
            }
        };
        Ok((preset, n))
    }

    /// Untimed frames to run before timing, so that the collision scenes are in contact.
    pub fn warm_up_frames(self) -> usize {
        match self {
            Preset::Hang => 5,
            Preset::Drape => 30,
            Preset::Pile => 40,
            Preset::Twist => 90,
            Preset::Cantilever => 5,
            Preset::Cusick => 30,
            Preset::Spin | Preset::SpinFree => 25,
        }
    }

    /// The scene whose warm-up frames come before this one's timed frames: [`Preset::Spin`]
    /// for [`Preset::SpinFree`] (timed from the draped state), the scene itself otherwise.
    pub fn warm_up_scene(self) -> Preset {
        match self {
            Preset::SpinFree => Preset::Spin,
            p => p,
        }
    }

    /// The step, s, and steps per frame: 0.01 s and 4 for the spinning sphere, one step of
    /// 1/60 s per frame for the others.
    pub fn step(self) -> (f64, usize) {
        match self {
            Preset::Spin | Preset::SpinFree => (SPIN_DT, SPIN_STEPS_PER_FRAME),
            _ => (1.0 / 60.0, 1),
        }
    }

    /// The model of this scene at `n × n` vertices (cantilever, cusick: edge length `n` mm).
    pub fn model(self, n: usize) -> Result<Model> {
        match self {
            Preset::Cantilever => return cantilever(n as f64 * 1e-3),
            Preset::Cusick => return cusick(n as f64 * 1e-3),
            Preset::Spin => return spin(n),
            Preset::SpinFree => {
                let mut m = spin(n)?;
                m.collision = None;
                m.obstacles.clear();
                return Ok(m);
            }
            _ => {}
        }
        let material = Material {
            stretch_stiffness: 1000.0,
            shear_stiffness: 100.0,
            bend_stiffness: 1.0,
            damping: 0.01,
            air_drag: 0.0,
            mass: MassSpec::Density(0.1),
            ..Default::default()
        };
        let (center, normal, pins, obstacle) = match self {
            Preset::Twist => (Vec3::new(0.0, 1.0, 0.0), Vec3::Y, vec![], None),
            Preset::Hang => (
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::Z,
                vec![0, (n - 1) as u32],
                None,
            ),
            Preset::Drape => (
                Vec3::new(0.0, 0.4, 0.0),
                Vec3::Y,
                vec![],
                Some(Shape::Sphere(Sphere {
                    center: Vec3::ZERO,
                    radius: 0.3,
                })),
            ),
            _ => (
                Vec3::new(0.0, 0.6, 0.0),
                Vec3::new(0.0, 0.3, 1.0),
                vec![],
                Some(Shape::Plane(Plane {
                    point: Vec3::ZERO,
                    normal: Vec3::Y,
                })),
            ),
        };
        let name = match self {
            Preset::Hang => "hang",
            Preset::Drape => "drape",
            Preset::Pile => "pile",
            _ => "twist",
        };
        let mesh = Mesh::grid([1.0, 1.0], [n, n], center, normal)?;
        let (handles, gravity) = match self {
            Preset::Twist => (twist_handles(&mesh.positions)?, Vec3::ZERO),
            _ => (Vec::new(), Vec3::new(0.0, -9.81, 0.0)),
        };
        let cloth = ClothDesc {
            name: name.into(),
            mesh,
            material,
            pins,
            initial_velocity: Vec3::ZERO,
            handles,
        };
        let mut model = Model::new(vec![cloth], gravity)?;
        if self == Preset::Twist {
            model.collision = Some(CollisionSettings {
                thickness: 0.005,
                self_collision: true,
                friction: 0.3,
                stiffness: 1000.0,
            });
        }
        if let Some(shape) = obstacle {
            model.collision = Some(CollisionSettings {
                thickness: 0.005,
                self_collision: true,
                friction: 0.3,
                stiffness: 1000.0,
            });
            model.obstacles = vec![Obstacle {
                name: None,
                collider: Collider::fixed(shape),
                friction: 0.3,
            }];
        }
        Ok(model)
    }

    /// The simulation of this scene with the default solver at PCG tolerance `tolerance`.
    pub fn simulation(self, n: usize, tolerance: f64) -> Result<Simulation> {
        let settings = SolverSettings {
            tolerance,
            max_iterations: 20_000,
            ..Default::default()
        };
        Simulation::new(self.model(n)?, settings)
    }
}

/// The spinning sphere's step, s.
const SPIN_DT: f64 = 0.01;
/// Frames per second of the spinning sphere.
const SPIN_FPS: f64 = 25.0;
/// Steps per frame of the spinning sphere: 1/(25 × 0.01).
const SPIN_STEPS_PER_FRAME: usize = 4;

/// The rotating-sphere scene at `n × n` vertices as scene text, `frames` frames long, at PCG
/// tolerance `tolerance` (the bench's solver settings: at most 20 000 iterations, one Newton
/// iteration). The one definition of the scene: [`Preset::Spin`] reads it back.
pub fn spin_scene(n: usize, frames: usize, tolerance: f64) -> String {
    let duration = frames as f64 / SPIN_FPS;
    format!(
        r#"# drapery bench scene spin-{n}: the rotating sphere of issue 18 (the IPC paper's scene).
# A 1.6 m cloth of {n} x {n} vertices dropped from 2 cm onto a sphere of radius 0.5 m spinning
# about the vertical axis at 180 degrees per second, friction 0.4, self-collision on.
# Written by `drapery bench --write-scenes`; run with `drapery run`, verify with `drapery check --scene`.

[simulation]
duration = {duration:?}
dt = {SPIN_DT:?}
frame_rate = {SPIN_FPS:?}

[solver]
tolerance = {tolerance:e}
max_iterations = 20000

[collision]
thickness = 0.002
self_collision = true
friction = 0.4
stiffness = 1000.0

[[cloth]]
name = "spin"
grid = {{ size = [1.6, 1.6], resolution = [{n}, {n}], center = [0.0, 0.52, 0.0], normal = [0.0, 1.0, 0.0] }}
density = 0.1
stretch_stiffness = 1000.0
shear_stiffness = 100.0
bend_stiffness = 1.0
damping = 0.01

[[collider]]
shape = "sphere"
center = [0.0, 0.0, 0.0]
radius = 0.5
friction = 0.4
angular_velocity = [0.0, {omega:?}, 0.0]
"#,
        omega = std::f64::consts::PI,
    )
}

/// [`Preset::Spin`]'s model: [`spin_scene`] read back.
fn spin(n: usize) -> Result<Model> {
    let name = format!("spin-{n}.toml");
    crate::scene::Scene::from_str(&spin_scene(n, 1, 1e-3), std::path::Path::new(&name))?.model()
}

/// The cantilever: a 16 cm strip past a level clamp at x = 0, 4 cm wide, at edge length `h` m,
/// its first two columns pinned.
fn cantilever(h: f64) -> Result<Model> {
    let (length, width) = (0.16, 0.04);
    let nx = (length / h).round() as usize + 2;
    let nz = (width / h).round() as usize + 1;
    let total = (nx - 1) as f64 * h;
    let mesh = Mesh::grid(
        [total, width],
        [nx, nz],
        Vec3::new(total / 2.0 - h, 0.0, 0.0),
        Vec3::Y,
    )?;
    let pins = (0..nz as u32)
        .flat_map(|r| [r * nx as u32, r * nx as u32 + 1])
        .collect();
    let material = Material {
        model: ClothModel::Shell,
        shell: Shell {
            stretch_modulus: [5000.0, 5000.0],
            poisson: 0.0,
            shear_modulus: None,
            bending_rigidity: [1e-4, 1e-4],
            damping: 0.05,
        },
        damping: 0.0,
        air_drag: 2.0 * 0.1 * h * h,
        mass: MassSpec::Density(0.1),
        ..Default::default()
    };
    let cloth = ClothDesc {
        name: "cantilever".into(),
        mesh,
        material,
        pins,
        initial_velocity: Vec3::ZERO,
        handles: Vec::new(),
    };
    Model::new(vec![cloth], Vec3::new(0.0, -9.81, 0.0))
}

/// The Cusick drape test: a 30 cm `cotton` disc at edge length `h` m with a ring of vertices on
/// the support's rim (as `examples/cusick.toml`), 3 mm above the top (y = 0) of a closed support
/// cylinder of 18 cm diameter.
fn cusick(h: f64) -> Result<Model> {
    let f = crate::textile::fabrics::fabric("cotton")
        .ok_or_else(|| Error::Invalid("no cotton preset".into()))?;
    let mesh = crate::textile::drape::disc_with_ring(0.15, h, 0.09)?
        .placed(Vec3::new(0.0, 0.003, 0.0), Vec3::Y);
    let support = crate::textile::drape::support(0.09, 0.01, 128)?.placed(Vec3::ZERO, Vec3::Y);
    let material = Material {
        damping: 0.0,
        air_drag: 2.0 * f.density * h * h,
        ..f.material()
    };
    let cloth = ClothDesc {
        name: "cusick".into(),
        mesh,
        material,
        pins: Vec::new(),
        initial_velocity: Vec3::ZERO,
        handles: Vec::new(),
    };
    let mut model = Model::new(vec![cloth], Vec3::new(0.0, -9.81, 0.0))?;
    model.collision = Some(CollisionSettings {
        thickness: 0.002,
        self_collision: false,
        friction: 0.3,
        stiffness: 1000.0,
    });
    model.obstacles = vec![Obstacle {
        name: None,
        collider: Collider::fixed(Shape::Mesh(TriangleMesh::new(
            support.positions.clone(),
            support.triangles(),
        ))),
        friction: 0.3,
    }];
    Ok(model)
}

/// The twist's handles: the vertices at x = -0.5 and x = +0.5, each turning one turn about +x
/// (the left one counter-clockwise, the right one clockwise) in 4 s, keyed every eighth of a
/// turn, while moving 0.1 m toward the middle.
fn twist_handles(x: &[Vec3]) -> Result<Vec<HandleDesc>> {
    [-1.0f64, 1.0]
        .into_iter()
        .map(|side| {
            let keys = (0..=8)
                .map(|k| {
                    let f = k as f64 / 8.0;
                    Keyframe {
                        time: 4.0 * f,
                        translation: Vec3::new(-side * 0.1 * f, 0.0, 0.0),
                        rotation: DQuat::from_rotation_x(-side * std::f64::consts::TAU * f),
                    }
                })
                .collect();
            Ok(HandleDesc {
                vertices: (0..x.len() as u32)
                    .filter(|&i| (x[i as usize].x - 0.5 * side).abs() < 1e-9)
                    .collect(),
                pivot: None,
                motion: Motion::Keyframed(Track::new(keys, Interpolation::Linear, "twist")?),
                release: None,
                attach: None,
            })
        })
        .collect()
}

/// A unit direction for particle `i`, pseudo-random (splitmix64) and fixed: issue 18's
/// rounding test (`pile_contact_work_does_not_depend_on_rounding`) and `examples/rounding.rs`
/// move a scene's start by a tiny distance along it, particle by particle.
pub fn jitter_direction(i: u64) -> Vec3 {
    let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut next = || {
        z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut y = z;
        y = (y ^ (y >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        y = (y ^ (y >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        y ^= y >> 31;
        (y >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    Vec3::new(next(), next(), next()).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    #[test]
    fn names_parse_and_bad_names_are_refused() {
        assert_eq!(Preset::parse("hang-64").unwrap(), (Preset::Hang, 64));
        assert_eq!(Preset::parse("pile-2").unwrap(), (Preset::Pile, 2));
        assert_eq!(Preset::parse("twist-128").unwrap(), (Preset::Twist, 128));
        assert_eq!(Preset::parse("cusick-10").unwrap(), (Preset::Cusick, 10));
        assert_eq!(Preset::parse("spin-290").unwrap(), (Preset::Spin, 290));
        assert_eq!(
            Preset::parse("spin-free-129").unwrap(),
            (Preset::SpinFree, 129)
        );
        assert_eq!(
            Preset::parse("cantilever-5").unwrap(),
            (Preset::Cantilever, 5)
        );
        for bad in [
            "hang",
            "hang-1",
            "hang-x",
            "swing-64",
            "drape-5000",
            "spin-free",
            "free-64",
        ] {
            assert!(Preset::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn hang_is_pinned_at_two_corners_and_collision_scenes_have_an_obstacle() {
        let m = Preset::Hang.model(8).unwrap();
        assert_eq!(m.pinned.iter().filter(|&&p| p).count(), 2);
        assert!(m.collision.is_none());
        for p in [Preset::Drape, Preset::Pile] {
            let m = p.model(8).unwrap();
            assert!(m.collision.is_some_and(|c| c.self_collision));
            assert_eq!(m.obstacles.len(), 1);
            assert!((m.total_mass() - 0.1).abs() < 1e-12);
        }
    }

    #[test]
    fn twist_edges_are_handles_that_meet_after_a_turn_each() {
        let n = 9;
        let m = Preset::Twist.model(n).unwrap();
        assert!(m.collision.is_some_and(|c| c.self_collision) && m.gravity() == Vec3::ZERO);
        let h = m.handles();
        assert_eq!(h.len(), 2);
        for (hd, side) in h.iter().zip([-1.0, 1.0]) {
            assert_eq!(hd.particles.len(), n);
            // at 4 s: a whole turn (back to the start) and 0.1 m inward
            for k in 0..n {
                let d = hd.position(k, 4.0) - hd.rest[k];
                assert!(
                    (d - Vec3::new(-side * 0.1, 0.0, 0.0)).length() < 1e-12,
                    "{d}"
                );
            }
            // at 1 s, a quarter turn: the edge stands vertical (its z extent turned into y)
            let ys: Vec<f64> = (0..n).map(|k| hd.position(k, 1.0).y).collect();
            let spread = ys.iter().cloned().fold(f64::MIN, f64::max)
                - ys.iter().cloned().fold(f64::MAX, f64::min);
            assert!((spread - 1.0).abs() < 1e-9, "{spread}");
        }
    }

    /// Issue 18's rounding runs as (PCG tolerance, move of the start in m): 14 tolerances from
    /// 0.9e-3 to 1.2e-3, then 1e-3 with the start moved by ±1e-9 m.
    fn rounding_runs() -> Vec<(f64, f64)> {
        ((0..14).map(|k| (0.9e-3 + k as f64 * 0.3e-3 / 13.0, 0.0)))
            .chain([(1.0e-3, 1e-9), (1.0e-3, -1e-9)])
            .collect()
    }

    /// Mean self-contact stencils and CCD hits per step over the pile's first second (60 steps
    /// of 1/60 s) at `n × n` vertices and PCG tolerance `tolerance`, its initial positions
    /// moved by `moved` m along [`jitter_direction`].
    fn pile_rounding_run(n: usize, tolerance: f64, moved: f64) -> [f64; 2] {
        let mut sim = Preset::Pile.simulation(n, tolerance).unwrap();
        let x: Vec<Vec3> = (sim.positions().iter().enumerate())
            .map(|(i, p)| *p + moved * jitter_direction(i as u64))
            .collect();
        sim.set_positions(&x).unwrap();
        let mut sum = [0.0; 2];
        for _ in 0..60 {
            let r = sim.step(1.0 / 60.0).unwrap();
            sum[0] += r.self_contacts as f64 / 60.0;
            sum[1] += r.ccd_hits as f64 / 60.0;
        }
        sum
    }

    /// [`rounding_runs`] and each one's [`pile_rounding_run`] at `n × n` vertices.
    fn pile_rounding_runs(n: usize) -> (Vec<(f64, f64)>, Vec<[f64; 2]>) {
        let runs = rounding_runs();
        let means = (runs.par_iter())
            .map(|&(tolerance, moved)| pile_rounding_run(n, tolerance, moved))
            .collect();
        (runs, means)
    }

    /// Issue 18, rounding amplification (docs/ROUNDING.md, forty-second session): pile-128's
    /// first second at 14 PCG tolerances from 0.9e-3 to 1.2e-3, and at 1e-3 with its initial
    /// positions moved by ±1e-9 m. Runs that differ only by rounding must do the same amount of
    /// contact work: every run's mean self-contact stencils and CCD hits per step lie within 2×
    /// of the median run's (CCD hits: or under one per step). With the landing as one
    /// linearized step (`max_newton_iterations = 1`, docs/MATH.md §10) the ±1e-9 m runs made
    /// 2.2 times the median's stencils.
    #[test]
    fn pile_contact_work_does_not_depend_on_rounding() {
        let (runs, means) = pile_rounding_runs(128);
        // The fail-safe has almost nothing left to stop on the pile (0 to 0.47 CCD hits per
        // step): a run may then have up to one hit per step more than twice the median, not
        // one whole hit more than zero.
        for k in 0..2 {
            let mut m: Vec<f64> = means.iter().map(|r| r[k]).collect();
            m.sort_by(f64::total_cmp);
            let median = 0.5 * (m[7] + m[8]);
            let floor = [0.0, 1.0][k];
            assert!(median > 0.0 || k == 1, "the pile has contacts: {means:?}");
            for (r, run) in means.iter().zip(&runs) {
                assert!(
                    r[k] <= (2.0 * median).max(floor) && r[k] >= 0.5 * median,
                    "{} per step {} at {run:?}, median {median}: {means:?}",
                    ["self-contacts", "CCD hits"][k],
                    r[k]
                );
            }
        }
    }

    /// The same runs at 64²: the landing no longer throws the bottom rows along the ground
    /// (docs/MATH.md §10), and the sheet lies down without folding onto itself in every run.
    /// With the landing as one linearized step it made 50 to 57 self-contact stencils per step
    /// over the first second in every run; now each run makes under 20, and no CCD hit.
    #[test]
    fn pile_64_lands_without_folding_whatever_the_rounding() {
        let (runs, means) = pile_rounding_runs(64);
        for (r, run) in means.iter().zip(&runs) {
            assert!(r[0] < 20.0 && r[1] == 0.0, "{r:?} at {run:?}");
        }
    }

    /// pile-128's self-contact stencils over steps 10 to 14 of h = 1/60 s (its ground contact
    /// and the folding after it) with `linear_solver` at the default tolerance.
    fn pile_contact_work(linear_solver: crate::LinearSolver) -> f64 {
        let settings = SolverSettings {
            max_iterations: 20_000,
            linear_solver,
            ..Default::default()
        };
        let mut sim = Simulation::new(Preset::Pile.model(128).unwrap(), settings).unwrap();
        let counts: Vec<usize> = (0..15)
            .map(|_| sim.step(1.0 / 60.0).unwrap().self_contacts)
            .collect();
        counts[10..].iter().sum::<usize>() as f64
    }

    /// docs/MATH.md §11, impacts: at a loose tolerance the pile's landing (step 9, its first
    /// contact) is solved to 1e-6.
    #[test]
    fn the_pile_s_landing_step_is_solved_tight_at_a_loose_tolerance() {
        let mut sim = Preset::Pile.simulation(64, 1e-3).unwrap();
        let reports: Vec<_> = (0..10).map(|_| sim.step(1.0 / 60.0).unwrap()).collect();
        assert!(reports[..9].iter().all(|r| r.obstacle_contacts == 0));
        assert!(reports[9].obstacle_contacts > 0);
        assert!(reports[9].residual <= 1e-6, "{}", reports[9].residual);
    }

    /// docs/ROUNDING.md, seventeenth and forty-second sessions: at the scenes' default PCG
    /// tolerance (1e-6) pile-128's ground contact does the contact work of the exact linear
    /// solve. Over steps 10 to 14 (the contact and the folding after it) the direct solver
    /// makes 381, 127, 127, 1 and 0 self-contact stencils; PCG's sum must lie within a fifth of
    /// that.
    #[test]
    fn pile_contact_work_at_the_default_tolerance_is_the_exact_solves() {
        let exact = pile_contact_work(crate::LinearSolver::Direct);
        let pcg = pile_contact_work(crate::LinearSolver::Pcg);
        assert!(exact > 300.0, "the pile folds on contact: {exact}");
        assert!(
            (pcg - exact).abs() <= 0.2 * exact,
            "stencils over steps 10-14: PCG {pcg}, direct {exact}"
        );
    }

    /// docs/ROUNDING.md, "Physics or artefact": two pile-32 runs 1e-9 m apart, direct solver.
    /// In free fall the step does not amplify their distance δ; after the ground contact δ
    /// grows from 1e-7 to 1e-4 m in a physical time that does not shrink with the step: at
    /// h = 1/960 s it takes at least a quarter of what it takes at h = 1/60 s, where an
    /// amplification of the step (a fixed factor per step, ×100 in ROUNDING.md) would take 16
    /// times fewer seconds.
    #[test]
    fn pile_divergence_is_a_rate_per_second_not_per_step() {
        let grow = |sub: usize| -> f64 {
            let h = 1.0 / (60.0 * sub as f64);
            let settings = SolverSettings {
                linear_solver: crate::LinearSolver::Direct,
                ..Default::default()
            };
            let mut sims = [0.0, 1e-9].map(|moved| {
                let mut sim = Simulation::new(Preset::Pile.model(32).unwrap(), settings).unwrap();
                let x: Vec<Vec3> = (sim.positions().iter().enumerate())
                    .map(|(i, p)| *p + moved * Vec3::new(1.0, (i % 7) as f64 / 7.0, -0.5))
                    .collect();
                sim.set_positions(&x).unwrap();
                sim
            });
            let apart = |sims: &[Simulation; 2]| {
                (sims[0].positions().iter().zip(sims[1].positions()))
                    .map(|(a, b)| a.distance(*b))
                    .fold(0.0, f64::max)
            };
            let start = apart(&sims);
            let mut crossed: [Option<f64>; 2] = [None; 2];
            for s in 0..18 * sub {
                for sim in &mut sims {
                    sim.step(h).unwrap();
                }
                let t = (s + 1) as f64 * h;
                let d = apart(&sims);
                if t < 0.14 {
                    // free fall (the lowest row reaches the ground at 0.157 s)
                    assert!(d <= start * (1.0 + 1e-6), "free fall amplifies: {d} at {t}");
                }
                for (c, level) in crossed.iter_mut().zip([1e-7, 1e-4]) {
                    if c.is_none() && d > level {
                        *c = Some(t);
                    }
                }
            }
            match crossed {
                [Some(a), Some(b)] => b - a,
                _ => panic!("at h = {h} the runs do not diverge to 1e-4 m in 0.3 s: {crossed:?}"),
            }
        };
        let (coarse, fine) = (grow(1), grow(16));
        assert!(
            fine >= 0.25 * coarse && fine <= 4.0 * coarse,
            "1e-7 → 1e-4 m takes {coarse} s at h = 1/60 and {fine} s at h = 1/960"
        );
    }

    #[test]
    fn textile_scenes_have_their_mass_pins_and_support() {
        // cantilever at 1 cm: 16 + 2 columns, 5 rows, two columns pinned; 0.1 kg/m² over
        // 17 cm × 4 cm
        let m = Preset::Cantilever.model(10).unwrap();
        assert_eq!(m.pinned.len(), 18 * 5);
        assert_eq!(m.pinned.iter().filter(|&&p| p).count(), 10);
        assert!((m.total_mass() - 0.1 * 0.17 * 0.04).abs() < 1e-12);
        // cusick at 1 cm: 15 rings; mass ρ × the inscribed 90-gon's area; one support
        let m = Preset::Cusick.model(10).unwrap();
        let f = crate::textile::fabrics::fabric("cotton").unwrap();
        let n = 90.0;
        let area = 0.5 * n * 0.15 * 0.15 * (std::f64::consts::TAU / n).sin();
        assert!((m.total_mass() - f.density * area).abs() < 1e-12);
        assert_eq!(m.obstacles.len(), 1);
        assert!(m.collision.is_some_and(|c| !c.self_collision));
    }

    /// docs/MATH.md §25: the 65² spin cloth (1090 N/m, 0.1 kg/m²) carried by the turning
    /// sphere's friction. Its weight stretches it by about ρ g L / k ≈ 0.1 % and its speeds
    /// (≤ 5 m/s) load it with ρ v² ≈ 2.5 N/m, 0.2 %: no edge may end 25 % shorter or 30 % longer
    /// than at rest. With friction applied after the solve alone, sticking and sliding
    /// neighbours were displaced against each other by up to the surface speed times the step:
    /// edges at 0.30 to 2.34 of their rest length over frames 5–12 (0.90 to 1.10 with it in
    /// the solve).
    #[test]
    fn the_spinning_sphere_carries_the_cloth_without_crushing_it() {
        let n = 65;
        let mut sim = Preset::Spin.simulation(n, 1e-3).unwrap();
        let (h, per_frame) = Preset::Spin.step();
        let edges = sim.model().edges();
        let rest: Vec<f64> = (edges.iter())
            .map(|&[a, b]| (sim.positions()[a as usize] - sim.positions()[b as usize]).length())
            .collect();
        for frame in 1..=12 {
            for _ in 0..per_frame {
                sim.step(h).unwrap();
            }
            if frame < 5 {
                continue;
            }
            let x = sim.positions();
            let (lo, hi) =
                (edges.iter().zip(&rest)).fold((f64::MAX, 0.0f64), |(lo, hi), (e, r)| {
                    let l = (x[e[0] as usize] - x[e[1] as usize]).length() / r;
                    (lo.min(l), hi.max(l))
                });
            assert!(
                lo > 0.75 && hi < 1.3,
                "frame {frame}: edges at {lo:.3} to {hi:.3} of rest"
            );
        }
    }

    /// The spinning sphere's text is a scene `drapery run` reads: 100 frames at 25 per second
    /// are 400 steps of 0.01 s; the model is the 1.6 m cloth over a sphere of radius 0.5 m
    /// turning at π rad/s about +y with friction 0.4; spin-free is the same cloth alone.
    #[test]
    fn spin_scene_text_is_the_preset() {
        let n = 9;
        let text = spin_scene(n, 100, 1e-3);
        let scene = crate::scene::Scene::from_str(&text, std::path::Path::new("s.toml")).unwrap();
        assert_eq!(scene.frame_count(), 100);
        assert_eq!(scene.steps_per_frame(), 4);
        assert!((scene.step_size() - 0.01).abs() < 1e-15);
        assert_eq!(Preset::Spin.step(), (scene.step_size(), 4));
        let m = Preset::Spin.model(n).unwrap();
        assert_eq!(m.particle_count(), n * n);
        let (lo, hi) =
            m.x.iter()
                .fold((Vec3::MAX, Vec3::MIN), |(a, b), p| (a.min(*p), b.max(*p)));
        assert!(
            ((hi - lo) - Vec3::new(1.6, 0.0, 1.6)).length() < 1e-12,
            "{lo} {hi}"
        );
        assert!((m.total_mass() - 0.1 * 1.6 * 1.6).abs() < 1e-12);
        let c = m.collision.unwrap();
        assert!(c.self_collision && c.friction == 0.4);
        assert_eq!(m.obstacles.len(), 1);
        let o = &m.obstacles[0];
        assert_eq!(o.friction, 0.4);
        // a point on the equator at +x moves toward −z: 180°/s about +y at 0.5 m
        let p = o.collider.transform_point(Vec3::new(0.5, 0.0, 0.0), 0.5);
        assert!((p - Vec3::new(0.0, 0.0, -0.5)).length() < 1e-12, "{p}");
        let free = Preset::SpinFree.model(n).unwrap();
        assert!(free.collision.is_none() && free.obstacles.is_empty());
        assert_eq!(free.x, m.x);
        assert_eq!(Preset::SpinFree.warm_up_scene(), Preset::Spin);
    }

    /// Friction drags the cloth round with the sphere: after a second (a third of a turn of the
    /// sphere) the cloth's angular momentum about the vertical axis has the sphere's sign, and
    /// no cloth vertex is inside the sphere.
    #[test]
    fn the_spinning_sphere_turns_the_cloth_its_way() {
        let mut sim = Preset::Spin.simulation(17, 1e-3).unwrap();
        let (h, steps) = Preset::Spin.step();
        for _ in 0..25 * steps {
            sim.step(h).unwrap();
        }
        let m = sim.model();
        let l: f64 = (0..m.particle_count())
            .map(|i| m.mass[i] * m.x[i].cross(m.v[i]).y)
            .sum();
        assert!(l > 0.0, "angular momentum about +y {l}");
        let inside = m.x.iter().filter(|p| p.length() < 0.5).count();
        assert_eq!(inside, 0);
    }
}
