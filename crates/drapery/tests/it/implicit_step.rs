//! The implicit step itself: exactness on linear forces, energy behaviour, pins, Newton, failures.

use crate::common::*;
use drapery::math::Vec3;
use drapery::mesh::Mesh;
use drapery::model::{ClothDesc, MassSpec, Material, Model};
use drapery::{Error, LinearSolver, Simulation, SolverSettings};
use proptest::prelude::*;

/// Particle 0 pinned at the origin, particle 1 of mass `m` on a zero-rest-length spring
/// (a linear force `f = -k x`), with linear air drag `c` on particle 1 and gravity `g`.
fn linear_spring(
    m: f64,
    k: f64,
    c: f64,
    g: Vec3,
    x1: Vec3,
    v1: Vec3,
    settings: SolverSettings,
) -> Simulation {
    let mesh = Mesh {
        positions: vec![Vec3::ZERO, x1],
        faces: vec![],
        lines: vec![[0, 1]],
        face_uv: Vec::new(),
    };
    let material = Material {
        stretch_stiffness: k,
        shear_stiffness: 0.0,
        bend_stiffness: 0.0,
        damping: 0.0,
        air_drag: c,
        mass: MassSpec::PerVertex(m),
        ..Default::default()
    };
    let mut model = Model::new(
        vec![ClothDesc {
            name: "spring".into(),
            mesh,
            material,
            pins: vec![0],
            initial_velocity: Vec3::ZERO,
            handles: Vec::new(),
        }],
        g,
    )
    .unwrap();
    model.set_rest_lengths(&[0.0]).unwrap();
    model.set_velocities(&[Vec3::ZERO, v1]).unwrap();
    Simulation::new(model, settings).unwrap()
}

#[test]
fn a_linear_spring_follows_the_exact_implicit_euler_recurrence() {
    let (m, k, c, h) = (0.3, 40.0, 0.05, 0.02);
    let g = Vec3::new(0.0, -9.81, 0.0);
    for solver in [LinearSolver::Pcg, LinearSolver::Direct] {
        let settings = SolverSettings {
            tolerance: 1e-14,
            linear_solver: solver,
            ..Default::default()
        };
        let mut sim = linear_spring(
            m,
            k,
            c,
            g,
            Vec3::new(0.3, -0.2, 0.1),
            Vec3::new(0.0, 1.0, -0.5),
            settings,
        );
        let (mut x, mut v) = (sim.model().positions()[1], sim.model().velocities()[1]);
        for step in 0..200 {
            sim.step(h).unwrap();
            // (m + h c + h² k) Δv = h (-k x + m g - c v - h k v)
            let dv = h * (-k * x + m * g - c * v - h * k * v) / (m + h * c + h * h * k);
            v += dv;
            x += h * v;
            let scale = x.length().max(1e-3);
            assert!(
                (sim.model().positions()[1] - x).length() <= 1e-12 * scale,
                "{solver:?} step {step}: {:?} vs {x:?}",
                sim.model().positions()[1]
            );
            assert!((sim.model().velocities()[1] - v).length() <= 1e-11 * v.length().max(1e-3));
            assert_eq!(sim.model().positions()[0], Vec3::ZERO);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn without_damping_a_step_never_increases_the_energy_of_a_linear_spring(
        m in 0.001..10.0f64, k in 0.1..1e5f64, h in 1e-4..0.1f64,
        x in prop::array::uniform3(-1.0..1.0f64), v in prop::array::uniform3(-5.0..5.0f64),
    ) {
        let x = Vec3::from_array(x);
        prop_assume!(x.length() > 1e-3);
        let mut sim = linear_spring(m, k, 0.0, Vec3::ZERO, x, Vec3::from_array(v), SolverSettings { tolerance: 1e-12, ..Default::default() });
        for _ in 0..20 {
            let e0 = sim.total_energy();
            sim.step(h).unwrap();
            let e1 = sim.total_energy();
            prop_assert!(e1 <= e0 * (1.0 + 1e-9) + 1e-300, "energy grew from {e0} to {e1}");
        }
    }
}

#[test]
fn pinned_particles_keep_their_positions_bit_for_bit() {
    let mut sim = hanging_cloth(
        12,
        SolverSettings::default(),
        material(MassSpec::Density(0.1)),
    );
    let (a, b) = (sim.model().positions()[0], sim.model().positions()[11]);
    let height = |s: &Simulation| {
        s.model()
            .positions()
            .iter()
            .zip(s.model().masses())
            .map(|(p, m)| p.y * m)
            .sum::<f64>()
            / s.model().total_mass()
    };
    let h0 = height(&sim);
    for _ in 0..50 {
        sim.step(1.0 / 60.0).unwrap();
    }
    assert_eq!(sim.model().positions()[0], a);
    assert_eq!(sim.model().positions()[11], b);
    assert_eq!(sim.model().velocities()[0], Vec3::ZERO);
    // and the rest of the cloth did sag: its centre of mass went down
    assert!(height(&sim) < h0 - 1e-4, "{} vs {h0}", height(&sim));
}

#[test]
fn newton_iterations_drive_the_backward_euler_residual_down() {
    // Large step on a stiff cloth: the linearized step leaves a residual that Newton removes.
    let h = 0.05;
    let residual = |sim: &Simulation, x0: &[Vec3], v0: &[Vec3]| -> f64 {
        // g(v) = M (v - v0) - h f(x0 + h v, v) on the free particles
        let f = sim.total_force();
        (0..f.len())
            .filter(|&i| !sim.model().pins()[i])
            .map(|i| {
                (sim.model().masses()[i] * (sim.model().velocities()[i] - v0[i]) - h * f[i])
                    .length()
            })
            .fold(0.0, f64::max)
            .max(
                (0..f.len())
                    .map(|i| {
                        (sim.model().positions()[i] - x0[i] - h * sim.model().velocities()[i])
                            .length()
                    })
                    .fold(0.0, f64::max),
            )
    };
    let mut results = Vec::new();
    for newton in [1u32, 8] {
        let settings = SolverSettings {
            newton_iterations: newton,
            tolerance: 1e-10,
            ..Default::default()
        };
        let mut sim = hanging_cloth(8, settings, material(MassSpec::Density(0.1)));
        for _ in 0..3 {
            sim.step(h).unwrap();
        }
        let (x0, v0) = (sim.positions().to_vec(), sim.velocities().to_vec());
        let report = sim.step(h).unwrap();
        results.push((residual(&sim, &x0, &v0), report.newton_iterations));
    }
    let (lin, _) = results[0];
    let (newton, iters) = results[1];
    assert!(iters >= 2);
    assert!(
        newton < 1e-2 * lin,
        "linearized residual {lin:e}, Newton residual {newton:e}"
    );
}

#[test]
fn a_solver_that_cannot_converge_fails_the_step_and_keeps_the_state() {
    let settings = SolverSettings {
        max_iterations: 1,
        tolerance: 1e-12,
        ..Default::default()
    };
    let mut sim = hanging_cloth(10, settings, material(MassSpec::Density(0.1)));
    let x0 = sim.positions().to_vec();
    let err = sim.step(1.0 / 60.0).unwrap_err();
    assert!(matches!(err, Error::StepFailed { step: 0, .. }), "{err}");
    assert!(err.to_string().contains("did not converge"), "{err}");
    assert_eq!(sim.model().positions(), x0);
    assert_eq!(sim.steps(), 0);
}

#[test]
fn a_non_finite_state_is_reported_with_the_vertex_and_cloth() {
    let mut sim = hanging_cloth(
        6,
        SolverSettings::default(),
        material(MassSpec::Density(0.1)),
    );
    // a non-finite state cannot be set; the step's own check (step::guard) names the vertex
    // and cloth of a state that became non-finite
    let mut v = sim.velocities().to_vec();
    v[7] = Vec3::new(f64::INFINITY, 0.0, 0.0);
    let err = sim.set_velocities(&v).unwrap_err().to_string();
    assert!(
        err.starts_with("velocities: particle 7 is not finite"),
        "{err}"
    );
    assert!(sim.velocities().iter().all(|u| u.is_finite()));
    sim.step(0.01).unwrap();
}

#[test]
fn zero_or_negative_steps_are_rejected() {
    let mut sim = hanging_cloth(
        4,
        SolverSettings::default(),
        material(MassSpec::Density(0.1)),
    );
    for h in [0.0, -0.01, f64::NAN] {
        assert!(sim.step(h).is_err());
    }
}

#[test]
fn the_damping_position_jacobian_needs_the_direct_solver_and_then_steps() {
    let bad = SolverSettings {
        damping_x_jacobian: true,
        ..Default::default()
    };
    assert!(bad.validate().is_err());
    let good = SolverSettings {
        damping_x_jacobian: true,
        linear_solver: LinearSolver::Direct,
        ..Default::default()
    };
    let mut m = material(MassSpec::Density(0.1));
    m.damping = 0.5;
    let mut with = hanging_cloth(8, good, m);
    let mut without = hanging_cloth(
        8,
        SolverSettings {
            linear_solver: LinearSolver::Direct,
            ..Default::default()
        },
        m,
    );
    for _ in 0..20 {
        with.step(0.01).unwrap();
        without.step(0.01).unwrap();
    }
    // same physics, different linearization: close but not identical
    let diff = with
        .positions()
        .iter()
        .zip(without.model().positions())
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    assert!(diff > 0.0 && diff < 0.05, "{diff}");
}

/// docs/MATH.md §10, "Where the linearization is far off": pile-32 (a 1 m sheet 17° from
/// upright, falling edge-first from 0.12 m) on a frictionless floor, PCG at 1e-6. At the first
/// contact the rows above push the held bottom rows, and the springs between them, at their
/// rest length, have no transverse stiffness in the matrix: the linearized step slides the
/// bottom rows along the floor, stretches their springs to three times their rest length and
/// multiplies the energy by about 140. The default lets that step iterate: the landing, which
/// is inelastic, then loses energy as backward Euler must, and every other step of the fall
/// stays one linearized step.
#[test]
fn a_sheet_landing_edge_first_loses_energy_where_its_step_iterates() {
    use drapery::model::SpringKind;
    use drapery::presets::Preset;
    let stretch = |sim: &Simulation| -> f64 {
        let (s, x) = (sim.model().springs(), sim.positions());
        (0..s.len())
            .filter(|&k| s.kind[k] == SpringKind::Stretch)
            .map(|k| (x[s.i[k] as usize] - x[s.j[k] as usize]).length() / s.rest[k])
            .fold(0.0, f64::max)
    };
    for most in [3, 1] {
        let pile = Preset::Pile.model(32).unwrap();
        let mut collision = *pile.collision().unwrap();
        collision.friction = 0.0;
        let mut obstacles = pile.obstacles().to_vec();
        obstacles[0].friction = 0.0;
        let model = pile.with_collisions(collision, obstacles).unwrap();
        let settings = SolverSettings {
            max_newton_iterations: most,
            ..Default::default()
        };
        let mut sim = Simulation::new(model, settings).unwrap();
        let h = 1.0 / 60.0;
        let (before, report) = loop {
            let before = sim.total_energy();
            let report = sim.step(h).unwrap();
            if report.obstacle_contacts > 0 {
                break (before, report);
            }
            assert_eq!(report.newton_iterations, 1, "falling at {}", sim.time());
        };
        let after = sim.total_energy();
        if most == 3 {
            assert!(report.newton_iterations > 1);
            assert!(
                after < before,
                "energy {before} J before the landing, {after} J after"
            );
            assert!(stretch(&sim) < 1.1, "stretch {}", stretch(&sim));
        } else {
            assert_eq!(report.newton_iterations, 1);
            assert!(after > 10.0 * before, "{before} J, {after} J");
            assert!(stretch(&sim) > 2.0, "stretch {}", stretch(&sim));
        }
    }
}
