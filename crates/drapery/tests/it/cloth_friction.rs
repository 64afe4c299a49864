//! Coulomb friction between cloths: a sheet sliding on a pinned sheet, a sheet on a tilted pinned
//! sheet, and the same bits on one or two threads.

use crate::common::{bits, on_threads};
use drapery::collision::check::count_self_intersections;
use drapery::collision::settings::CollisionSettings;
use drapery::math::Vec3;
use drapery::mesh::Mesh;
use drapery::model::{ClothDesc, MassSpec, Material, Model};
use drapery::{Simulation, SolverSettings};

const H: f64 = 1.0 / 60.0;
const THICKNESS: f64 = 0.01;
/// Height of the free sheet above the floor: where the repulsion carries its weight (a few µm
/// inside the thickness), so that it starts at rest instead of being thrown up.
const REST: f64 = THICKNESS - 3e-6;

fn material() -> Material {
    Material {
        stretch_stiffness: 500.0,
        shear_stiffness: 50.0,
        bend_stiffness: 0.5,
        damping: 0.02,
        air_drag: 0.0,
        mass: MassSpec::Density(0.2),
        ..Default::default()
    }
}

/// A floor sheet (every vertex pinned) through the origin with unit normal `normal`, and a small
/// free sheet resting on it with `velocity`, centred at `offset` from the incentre of the floor's
/// first triangle. The floor is one 4 m quad (two triangles), so the free sheet stays more than a
/// metre away from the floor's edges and vertices: its contacts are vertices over the interior
/// of a triangle, with the triangle's normal. (Over a finer floor the sheet also feels a drag of
/// its own, from the contacts at its border and between nearly parallel edges, and from vertices
/// that lose every contact for a step; README, "Known limitations". It would blur what friction
/// does.)
fn sheet_on_sheet(normal: Vec3, offset: Vec3, velocity: Vec3, mu: f64) -> Simulation {
    let floor = Mesh::grid([4.0, 4.0], [2, 2], Vec3::ZERO, normal).unwrap();
    let pins = (0..floor.positions.len() as u32).collect();
    let [a, b, c] = floor.triangles()[0].map(|i| floor.positions[i as usize]);
    let (la, lb, lc) = ((b - c).length(), (c - a).length(), (a - b).length());
    let incentre = (a * la + b * lb + c * lc) / (la + lb + lc);
    let top = Mesh::grid(
        [0.2, 0.2],
        [6, 6],
        incentre + offset + normal * REST,
        normal,
    )
    .unwrap();
    let cloths = vec![
        ClothDesc {
            name: "floor".into(),
            mesh: floor,
            material: material(),
            pins,
            initial_velocity: Vec3::ZERO,
            handles: Vec::new(),
        },
        ClothDesc {
            name: "top".into(),
            mesh: top,
            material: material(),
            pins: vec![],
            initial_velocity: velocity,
            handles: Vec::new(),
        },
    ];
    let model = Model::new(cloths, Vec3::new(0.0, -9.81, 0.0))
        .unwrap()
        .with_collisions(
            CollisionSettings {
                thickness: THICKNESS,
                self_collision: true,
                friction: mu,
                stiffness: 1000.0,
            },
            vec![],
        )
        .unwrap();
    Simulation::new(
        model,
        SolverSettings {
            tolerance: 1e-6,
            ..Default::default()
        },
    )
    .unwrap()
}

/// Mass-weighted mean position and velocity of the free sheet.
fn top_centre(s: &Simulation) -> (Vec3, Vec3) {
    let c = &s.model().cloths()[1];
    let (mut x, mut v, mut m) = (Vec3::ZERO, Vec3::ZERO, 0.0);
    for i in c.range() {
        x += s.model().positions()[i] * s.model().masses()[i];
        v += s.model().velocities()[i] * s.model().masses()[i];
        m += s.model().masses()[i];
    }
    (x / m, v / m)
}

/// Steps, checking after each that nothing intersects; returns the free sheet's mean velocity
/// after every step.
fn run(s: &mut Simulation, steps: usize) -> Vec<Vec3> {
    let tris = s.model().triangles();
    (0..steps)
        .map(|k| {
            s.step(H).unwrap_or_else(|e| panic!("step {k}: {e}"));
            assert_eq!(
                count_self_intersections(s.model().positions(), &tris),
                0,
                "step {k}"
            );
            top_centre(s).1
        })
        .collect()
}

#[test]
fn friction_stops_a_sheet_sliding_on_a_pinned_sheet_and_never_reverses_it() {
    let (v0, g, mu) = (1.0, 9.81, 0.5);
    let mut result = Vec::new();
    for mu in [mu, 0.0] {
        let mut s = sheet_on_sheet(Vec3::Y, Vec3::X * -0.3, Vec3::X * v0, mu);
        let start = top_centre(&s).0;
        let speeds = run(&mut s, 30);
        let end = top_centre(&s).0;
        // it stays on the floor, resting at the thickness
        assert!(
            (end.y - THICKNESS).abs() < 1e-4,
            "μ = {mu}: height {}",
            end.y
        );
        // friction slows the sliding, never turns it around
        for (k, w) in speeds.iter().enumerate() {
            assert!(
                w.x >= -1e-9,
                "μ = {mu}: moving backwards ({w:?}) after step {k}"
            );
        }
        result.push(((end - start).x, speeds));
    }
    let ((with, speeds), (without, free)) = (&result[0], &result[1]);
    // kinetic friction takes μ g h off the speed each step while it slides...
    let drop = speeds[2].x - speeds[3].x;
    assert!(
        (drop - mu * g * H).abs() < 0.02 * mu * g * H,
        "speed lost in one step: {drop} m/s, Coulomb says {}",
        mu * g * H
    );
    // ...and static friction holds it once it has stopped: v0²/(2 μ g) = 0.10 m
    assert!(speeds[20..].iter().all(|w| w.length() < 1e-6), "{speeds:?}");
    let coulomb = v0 * v0 / (2.0 * mu * g);
    assert!(
        (with - coulomb).abs() < 0.1 * coulomb,
        "with μ = 0.5 the sheet slid {with} m, Coulomb says {coulomb} m"
    );
    // without friction it keeps its speed
    assert!(free.iter().all(|w| (w.x - v0).abs() < 1e-3), "{free:?}");
    assert!(
        (without - 30.0 * H * v0).abs() < 0.01,
        "with μ = 0 the sheet slid {without} m"
    );
}

#[test]
fn a_sheet_sticks_on_a_pinned_sheet_below_the_friction_angle_and_slides_above_it() {
    // μ = 0.5: tan 15° = 0.27 sticks, tan 40° = 0.84 slides with a = g (sin θ - μ cos θ)
    let mu = 0.5;
    let mut travel = Vec::new();
    for degrees in [15.0f64, 40.0] {
        let a = degrees.to_radians();
        let normal = Vec3::new(-a.sin(), a.cos(), 0.0);
        let uphill = Vec3::new(a.cos(), a.sin(), 0.0);
        let mut s = sheet_on_sheet(normal, uphill * 0.3, Vec3::ZERO, mu);
        let start = top_centre(&s).0;
        run(&mut s, 30);
        let moved = top_centre(&s).0 - start;
        // along the slope, positive downhill
        travel.push((-moved.dot(uphill), a));
    }
    let (stuck, _) = travel[0];
    let (slid, a) = travel[1];
    assert!(stuck.abs() < 1e-4, "at 15° the sheet moved {stuck} m");
    // implicit Euler: x_k = x_0 + h Σ v_j, v_j = j a h
    let expected = 9.81 * (a.sin() - mu * a.cos()) * H * H * (30.0 * 31.0 / 2.0);
    assert!(
        (slid - expected).abs() < 0.05 * expected,
        "at 40° the sheet slid {slid} m, Coulomb says {expected} m"
    );
}

#[test]
fn sliding_with_friction_gives_the_same_bits_on_one_and_two_threads() {
    let run_on = |threads: usize| {
        on_threads(threads, || {
            let mut s = sheet_on_sheet(Vec3::Y, Vec3::X * -0.3, Vec3::X, 0.5);
            for _ in 0..10 {
                s.step(H).unwrap();
            }
            bits(s.model().positions().iter().chain(s.model().velocities()))
        })
    };
    assert_eq!(run_on(1), run_on(2));
}
