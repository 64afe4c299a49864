//! Collisions end to end at the library level: obstacles, friction, self-contact, no tunneling.

use drapery::collision::check::{
    count_intersections_between, count_penetrations, count_self_intersections,
};
use drapery::collision::colliders::{Collider, Motion, Plane, Shape, Sphere, TriangleMesh};
use drapery::collision::settings::{CollisionSettings, Obstacle};
use drapery::math::Vec3;
use drapery::mesh::Mesh;
use drapery::model::{ClothDesc, MassSpec, Material, Model};
use drapery::{Simulation, SolverSettings};

fn sheet(name: &str, n: usize, size: f64, center: Vec3, normal: Vec3, velocity: Vec3) -> ClothDesc {
    ClothDesc {
        name: name.into(),
        mesh: Mesh::grid([size, size], [n, n], center, normal).unwrap(),
        material: Material {
            stretch_stiffness: 500.0,
            shear_stiffness: 50.0,
            bend_stiffness: 0.5,
            damping: 0.02,
            air_drag: 0.001,
            mass: MassSpec::Density(0.2),
            ..Default::default()
        },
        pins: vec![],
        initial_velocity: velocity,
        handles: Vec::new(),
    }
}

fn sim(
    cloths: Vec<ClothDesc>,
    obstacles: Vec<Obstacle>,
    collision: CollisionSettings,
) -> Simulation {
    let model = Model::new(cloths, Vec3::new(0.0, -9.81, 0.0))
        .unwrap()
        .with_collisions(collision, obstacles)
        .unwrap();
    Simulation::new(
        model,
        SolverSettings {
            tolerance: 1e-4,
            max_iterations: 5000,
            ..Default::default()
        },
    )
    .unwrap()
}

/// The plane y = 0 with Coulomb coefficient `friction`.
fn ground(friction: f64) -> Obstacle {
    Obstacle {
        name: None,
        collider: Collider::fixed(Shape::Plane(Plane {
            point: Vec3::ZERO,
            normal: Vec3::Y,
        })),
        friction,
    }
}

fn colliders(s: &Simulation) -> Vec<Collider> {
    s.model()
        .obstacles()
        .iter()
        .map(|o| o.collider.clone())
        .collect()
}

/// Runs `steps` steps of `h`, asserting after each that no cloth triangles intersect and no
/// particle is inside an analytic obstacle.
fn run_clean(s: &mut Simulation, steps: usize, h: f64) {
    let tris = s.model().triangles();
    for k in 0..steps {
        let r = s.step(h).unwrap_or_else(|e| panic!("step {k}: {e}"));
        let _ = r;
        assert_eq!(
            count_self_intersections(s.model().positions(), &tris),
            0,
            "self-intersection after step {k}"
        );
        assert_eq!(
            count_penetrations(s.model().positions(), &colliders(s), s.time(), 0.0),
            0,
            "penetration after step {k}"
        );
    }
}

#[test]
fn a_sheet_drapes_over_a_sphere_without_penetrating_it() {
    let sphere = Obstacle {
        name: None,
        collider: Collider::fixed(Shape::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 0.3,
        })),
        friction: 0.3,
    };
    let mut s = sim(
        vec![sheet(
            "sheet",
            21,
            1.0,
            Vec3::new(0.0, 0.4, 0.0),
            Vec3::Y,
            Vec3::ZERO,
        )],
        vec![sphere],
        CollisionSettings {
            thickness: 0.01,
            ..Default::default()
        },
    );
    run_clean(&mut s, 90, 1.0 / 60.0);
    // the centre of the sheet rests on top of the sphere, about one thickness above it
    let centre = s.model().positions()[10 * 21 + 10];
    assert!(
        (centre.length() - 0.31).abs() < 0.01,
        "centre at {centre:?}"
    );
    // the corners hang below the top of the sphere
    assert!(
        s.model().positions()[0].y < 0.1,
        "corner at {:?}",
        s.model().positions()[0]
    );
}

#[test]
fn a_fast_sheet_does_not_tunnel_through_a_zero_thickness_plate() {
    // plate: a 1 m square of two triangles in the plane y = 0
    let plate = TriangleMesh::new(
        vec![
            Vec3::new(-0.5, 0.0, -0.5),
            Vec3::new(0.5, 0.0, -0.5),
            Vec3::new(0.5, 0.0, 0.5),
            Vec3::new(-0.5, 0.0, 0.5),
        ],
        vec![[0, 2, 1], [0, 3, 2]],
    );
    let plate = Obstacle {
        name: None,
        collider: Collider::fixed(Shape::Mesh(plate)),
        friction: 0.2,
    };
    // 0.2 m sheet 5 cm above the plate, thrown down at 40 m/s: it would cross in one step
    let mut s = sim(
        vec![sheet(
            "fast",
            9,
            0.2,
            Vec3::new(0.0, 0.05, 0.0),
            Vec3::Y,
            Vec3::new(0.0, -40.0, 0.0),
        )],
        vec![plate],
        CollisionSettings {
            thickness: 0.005,
            ..Default::default()
        },
    );
    run_clean(&mut s, 30, 1.0 / 60.0);
    for p in s.model().positions() {
        assert!(p.y > 0.0, "a vertex went through the plate: {p:?}");
    }
}

#[test]
fn a_sheet_falling_on_the_ground_piles_up_without_intersecting_itself() {
    let ground = ground(0.5);
    // a sheet held almost upright, thrown sideways at the floor: its foot stops, the rest folds over it
    let mut s = sim(
        vec![sheet(
            "sheet",
            17,
            0.6,
            Vec3::new(0.0, 0.35, 0.0),
            Vec3::new(0.0, 0.2, 1.0),
            Vec3::new(0.0, -0.5, 1.0),
        )],
        vec![ground],
        CollisionSettings {
            thickness: 0.008,
            ..Default::default()
        },
    );
    run_clean(&mut s, 120, 1.0 / 60.0);
    let top = s
        .model()
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f64::MIN, f64::max);
    assert!(top < 0.2, "the sheet did not fall: top at {top}");
    assert!(s.model().positions().iter().all(|p| p.y > 0.0));
}

#[test]
fn friction_holds_a_sheet_on_a_tilted_plane_and_without_it_the_sheet_slides() {
    let tilt = 20f64.to_radians(); // tan 20° ≈ 0.36
    let normal = Vec3::new(-tilt.sin(), tilt.cos(), 0.0);
    let mut travel = Vec::new();
    for mu in [0.8, 0.0] {
        let plane = Obstacle {
            name: None,
            collider: Collider::fixed(Shape::Plane(Plane {
                point: Vec3::ZERO,
                normal,
            })),
            friction: mu,
        };
        let centre = normal * 0.008;
        let mut s = sim(
            vec![sheet("sheet", 9, 0.3, centre, normal, Vec3::ZERO)],
            vec![plane],
            CollisionSettings {
                thickness: 0.01,
                self_collision: false,
                ..Default::default()
            },
        );
        let x0 = s.model().positions()[40];
        run_clean(&mut s, 60, 1.0 / 60.0);
        travel.push((s.model().positions()[40] - x0).length());
    }
    assert!(
        travel[0] < 0.01,
        "with μ = 0.8 the sheet slid {} m",
        travel[0]
    );
    assert!(
        travel[1] > 0.5,
        "without friction the sheet slid only {} m",
        travel[1]
    );
}

#[test]
fn a_spinning_sphere_drags_the_sheet_around_by_friction() {
    // Lay a small sheet on top of a large still sphere, then spin the sphere at ω = 1.5 rad/s about +y (surface
    // points move toward decreasing atan2(z, x)): the part of the sheet resting on top turns with
    // the surface. (A sphere's pose does not depend on its rotation, so the spin can start mid-run.)
    let sphere = Obstacle {
        name: None,
        collider: Collider::fixed(Shape::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        })),
        friction: 0.8,
    };
    let mut s = sim(
        vec![sheet(
            "sheet",
            9,
            0.3,
            Vec3::new(0.0, 1.011, 0.0),
            Vec3::Y,
            Vec3::ZERO,
        )],
        vec![sphere],
        CollisionSettings {
            thickness: 0.01,
            ..Default::default()
        },
    );
    run_clean(&mut s, 30, 1.0 / 60.0);
    let cap: Vec<usize> = (0..s.model().positions().len())
        .filter(|&i| s.model().positions()[i].x.hypot(s.model().positions()[i].z) > 0.05)
        .collect();
    assert!(cap.len() >= 4);
    let before: Vec<f64> = cap
        .iter()
        .map(|&i| s.model().positions()[i].z.atan2(s.model().positions()[i].x))
        .collect();
    s.set_obstacle_motion(
        0,
        Motion::Constant {
            velocity: Vec3::ZERO,
            angular_velocity: Vec3::new(0.0, 1.5, 0.0),
        },
    )
    .unwrap();
    run_clean(&mut s, 30, 1.0 / 60.0);
    let turn: f64 = cap
        .iter()
        .zip(&before)
        .map(|(&i, a)| {
            (s.model().positions()[i].z.atan2(s.model().positions()[i].x) - a
                + std::f64::consts::PI)
                .rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI
        })
        .sum::<f64>()
        / cap.len() as f64;
    // the sphere turned by 0.75 rad; dragged by friction, the sheet turns the same way by more
    // than half of that (it slips while it spins up, and its edges barely touch). The linearized
    // step's spurious torque (README, "Known limitations") holds it back by a margin that moves
    // by a few hundredths of a radian with the order of the force sums (-0.39 to -0.43 seen)
    let half = -0.75 / 2.0;
    assert!(turn < half && turn > -0.8, "the sheet turned by {turn} rad");
}

#[test]
fn a_particle_moving_away_from_an_obstacle_is_not_held_by_it() {
    let ground = ground(1.0);
    let mut s = sim(
        vec![sheet(
            "sheet",
            5,
            0.2,
            Vec3::new(0.0, 0.005, 0.0),
            Vec3::Y,
            Vec3::new(0.0, 2.0, 0.0),
        )],
        vec![ground],
        CollisionSettings {
            thickness: 0.01,
            ..Default::default()
        },
    );
    s.step(0.01).unwrap();
    // thrown up at 2 m/s: after one step it rises by about 2 cm, with no adhesion
    assert!(
        s.model().positions().iter().all(|p| p.y > 0.02),
        "{:?}",
        s.model().positions()[12]
    );
}

#[test]
fn a_sheet_starting_deep_inside_a_sphere_is_pushed_out_at_the_push_speed_and_stays_out() {
    let sphere = Obstacle {
        name: None,
        collider: Collider::fixed(Shape::Sphere(Sphere {
            center: Vec3::new(0.0, 0.4, 0.0),
            radius: 0.3,
        })),
        friction: 0.3,
    };
    let mut s = sim(
        vec![sheet(
            "sheet",
            5,
            0.4,
            Vec3::new(0.0, 0.5, 0.0),
            Vec3::Y,
            Vec3::ZERO,
        )],
        vec![sphere],
        CollisionSettings {
            thickness: 0.01,
            ..Default::default()
        },
    );
    let (_, inside) = s.intersections();
    assert!(inside > 0, "the test needs a starting penetration");
    // the deepest vertex is 0.2 m in, pushed out at 0.5 m/s (plus the thickness): 0.42 s,
    // and no vertex inside is pushed faster than that (the vertices outside are the cloth's:
    // once the tension of the rising dome beats the friction that holds a corner on the
    // sphere, the corner slides off as fast as the cloth takes it)
    let (center, radius) = (Vec3::new(0.0, 0.4, 0.0), 0.3);
    for _ in 0..45 {
        let inside: Vec<usize> = (s.model().positions().iter().enumerate())
            .filter(|(_, p)| (**p - center).length() < radius)
            .map(|(i, _)| i)
            .collect();
        s.step(0.01).unwrap();
        if s.tangled().inside > 0 {
            assert!(
                inside
                    .iter()
                    .all(|&i| s.model().velocities()[i].length() <= 0.5 + 1e-9)
            );
        }
    }
    assert_eq!(s.tangled().inside, 0);
    assert_eq!(
        count_penetrations(s.model().positions(), &colliders(&s), s.time(), 0.0),
        0
    );
    // The sheet is now a dome over the sphere, its corners (outside from the start) held back
    // by friction: released, it springs back (up to about 20 m/s for a step or two on this
    // coarse, stiff sheet) and slides off without passing through the sphere.
    for _ in 0..100 {
        s.step(0.01).unwrap();
        assert_eq!(
            count_penetrations(s.model().positions(), &colliders(&s), s.time(), 0.0),
            0
        );
    }
}

#[test]
fn a_mesh_spinning_about_the_origin_of_its_file_carries_the_sheet_around_it() {
    // a 0.5 m plate modelled 0.6 m from the origin, turning at 1 rad/s about the vertical axis
    // through the origin (the OBJ origin, not its own centre): a sheet resting on it goes round
    // on a circle of radius 0.6 m
    let g = Mesh::grid([0.5, 0.5], [6, 6], Vec3::new(0.6, 0.0, 0.0), Vec3::Y).unwrap();
    let plate = TriangleMesh::new(g.positions.clone(), g.triangles());
    let (plate_vertices, plate_triangles) = (plate.vertices().to_vec(), plate.triangles().to_vec());
    let spin = Motion::Constant {
        velocity: Vec3::ZERO,
        angular_velocity: Vec3::Y,
    };
    let obstacle = Obstacle {
        name: None,
        collider: Collider {
            shape: Shape::Mesh(plate),
            motion: spin,
        },
        friction: 0.8,
    };
    let mut s = sim(
        vec![sheet(
            "sheet",
            7,
            0.2,
            Vec3::new(0.6, 0.01, 0.0),
            Vec3::Y,
            Vec3::ZERO,
        )],
        vec![obstacle],
        CollisionSettings {
            thickness: 0.01,
            ..Default::default()
        },
    );
    let tris = s.model().triangles();
    let h = 1.0 / 60.0;
    for k in 0..60 {
        s.step(h).unwrap_or_else(|e| panic!("step {k}: {e}"));
        let c = &s.model().obstacles()[0].collider;
        let posed: Vec<Vec3> = plate_vertices
            .iter()
            .map(|&p| c.transform_point(p, s.time()))
            .collect();
        assert_eq!(
            count_intersections_between(s.model().positions(), &tris, &posed, &plate_triangles),
            0,
            "the sheet went through the plate at step {k}"
        );
        // the plate's vertices stay on their circles about the axis through the origin
        for (p, q) in posed.iter().zip(&plate_vertices) {
            assert!((p.with_y(0.0).length() - q.with_y(0.0).length()).abs() < 1e-12);
        }
    }
    let n = s.model().positions().len() as f64;
    let centre = s.model().positions().iter().sum::<Vec3>() / n;
    // turned by 1 rad about +y: angle atan2(z, x) went from 0 to -1 (less a little slip while
    // the sheet spun up), at the same radius and resting on the plate
    let angle = centre.z.atan2(centre.x);
    assert!(
        (angle + 1.0).abs() < 0.1,
        "the sheet's centre turned to {angle} rad"
    );
    assert!(
        (centre.with_y(0.0).length() - 0.6).abs() < 0.03,
        "radius {}",
        centre.with_y(0.0).length()
    );
    assert!(centre.y > 0.0 && centre.y < 0.02, "height {}", centre.y);
}

#[test]
fn a_sheet_resting_on_the_ground_under_upward_gravity_lifts_off_freely_in_one_solve() {
    // Every contact would pull: the guess (no change of velocity) already says so, so the
    // active set releases them all before the first solve, and the sheet accelerates as if
    // the ground were not there.
    let ground = ground(0.5);
    let thickness = 0.01;
    let mut cloth = sheet(
        "sheet",
        6,
        0.3,
        Vec3::new(0.0, thickness, 0.0),
        Vec3::Y,
        Vec3::ZERO,
    );
    cloth.material.air_drag = 0.0;
    let model = Model::new(vec![cloth], Vec3::new(0.0, 9.81, 0.0))
        .unwrap()
        .with_collisions(
            CollisionSettings {
                thickness,
                ..Default::default()
            },
            vec![ground],
        )
        .unwrap();
    let mut s = Simulation::new(
        model,
        SolverSettings {
            tolerance: 1e-8,
            ..Default::default()
        },
    )
    .unwrap();
    let h = 0.01;
    let r = s.step(h).unwrap();
    assert_eq!(r.linear_solves, 1);
    assert_eq!(r.obstacle_contacts, 0);
    for (p, v) in s.model().positions().iter().zip(s.model().velocities()) {
        // free fall upward: v = g h, y = thickness + g h² (the flat sheet has no internal force)
        assert!((v.y - 9.81 * h).abs() < 1e-6, "{v}");
        assert!((p.y - (thickness + 9.81 * h * h)).abs() < 1e-8, "{p}");
    }
}

#[test]
fn a_sheet_resting_on_the_ground_keeps_every_contact_held_in_one_solve_per_step() {
    // The first step is a first contact (no particle had a normal force): every candidate is
    // held and none is predicted to pull. Every later step starts from the contacts that
    // pushed at the end of the previous one, which are all of them again: one solve per step.
    let thickness = 0.01;
    let n = 6;
    let cloth = sheet(
        "sheet",
        n,
        0.3,
        Vec3::new(0.0, thickness, 0.0),
        Vec3::Y,
        Vec3::ZERO,
    );
    let collision = CollisionSettings {
        thickness,
        ..Default::default()
    };
    let mut s = sim(vec![cloth], vec![ground(0.5)], collision);
    let h = 0.01;
    for k in 0..20 {
        let r = s.step(h).unwrap();
        assert_eq!(r.linear_solves, 1, "step {k}");
        assert_eq!(r.obstacle_contacts, n * n, "step {k}");
        for p in s.model().positions() {
            assert!((p.y - thickness).abs() < 1e-6, "step {k}: {p}");
        }
    }
}

/// `[simulation] preroll`: the cloth falls and settles on a box during the pre-roll while the
/// box, which moves at 1 m/s from t = 0 on, is held at its pose at 0 (so friction does not drag
/// the cloth); the clock then reads exactly 0 and the frames start from the settled state.
#[test]
fn preroll_settles_the_cloth_with_every_collider_held_at_its_first_pose() {
    let text = r#"
[simulation]
duration = 0.1
dt = 0.005
frame_rate = 20
preroll = 0.6

[collision]
thickness = 0.005
friction = 0.5

[[cloth]]
name = "sheet"
grid = { size = [0.3, 0.3], resolution = [7, 7], center = [0.0, 0.3, 0.0], normal = [0.0, 1.0, 0.0] }
density = 0.1

[[collider]]
shape = "box"
center = [0.0, 0.0, 0.0]
half_extents = [0.5, 0.1, 0.5]
velocity = [1.0, 0.0, 0.0]
"#;
    let scene =
        drapery::scene::Scene::from_str(text, std::path::Path::new("preroll.toml")).unwrap();
    assert_eq!(scene.preroll_steps(), 120);
    let sim = scene.start().unwrap();
    assert_eq!((sim.time(), sim.steps()), (0.0, 0));
    let x = sim.positions();
    // fallen 0.19 m onto the box top (y = 0.1) and resting at the thickness
    let min_y = x.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    assert!((min_y - 0.105).abs() < 0.004, "{min_y}");
    // not dragged along x: the box did not move during the pre-roll
    let cx = x.iter().map(|p| p.x).sum::<f64>() / x.len() as f64;
    assert!(cx.abs() < 1e-6, "{cx}");
    // at rest
    let vmax = sim
        .velocities()
        .iter()
        .map(|v| v.length())
        .fold(0.0, f64::max);
    assert!(vmax < 0.05, "{vmax}");
    // without a pre-roll the same scene starts in the air
    let scene0 = drapery::scene::Scene::from_str(
        &text.replace("preroll = 0.6", ""),
        std::path::Path::new("p.toml"),
    )
    .unwrap();
    assert_eq!(scene0.preroll_steps(), 0);
    assert!(
        scene0
            .start()
            .unwrap()
            .positions()
            .iter()
            .all(|p| p.y == 0.3)
    );
}

/// docs/MATH.md §14, rough rounds: where a cloth lands on the spinning sphere, the active set
/// releases contacts ring by ring over several rounds, and the rounds after one that flipped
/// many are solved only to 1e-4. They must end on the contacts of exact solves: the direct
/// solver's rounds (exact, so never rough) hold as many particles in every step of the
/// landing, and the cloth ends where it does.
#[test]
fn rough_rounds_end_on_the_contacts_of_exact_solves() {
    use drapery::presets::Preset;
    let n = 48;
    let (h, _) = Preset::Spin.step();
    let run = |linear_solver| {
        let settings = SolverSettings {
            tolerance: 1e-9,
            max_iterations: 20_000,
            linear_solver,
            ..Default::default()
        };
        Simulation::new(Preset::Spin.model(n).unwrap(), settings).unwrap()
    };
    let (mut pcg, mut direct) = (
        run(drapery::LinearSolver::Pcg),
        run(drapery::LinearSolver::Direct),
    );
    let (mut rough, mut contacts) = (0, 0);
    for k in 0..14 {
        let (a, b) = (pcg.step(h).unwrap(), direct.step(h).unwrap());
        assert_eq!(b.rough_solves, 0, "step {k}: exact solves are never rough");
        assert!(a.linear_solves < 8, "step {k}: the rounds ran out ({a:?})");
        assert_eq!(a.obstacle_contacts, b.obstacle_contacts, "step {k}");
        rough += a.rough_solves;
        contacts = contacts.max(a.obstacle_contacts);
        let apart = (pcg
            .model()
            .positions()
            .iter()
            .zip(direct.model().positions()))
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f64::max);
        assert!(apart < 1e-6, "step {k}: {apart} m apart");
    }
    assert!(contacts > 50, "the cloth lands: {contacts} contacts");
    assert!(rough > 0, "the landing took rough rounds");
}
