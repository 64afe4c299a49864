//! Steps that must fail, and fail cleanly: the energy blow-up test and the solver's "not
//! positive definite" report, driven through the public API (docs/MATH.md §3, §11, §17).

use drapery::linalg::pcg::Preconditioner;
use drapery::math::Vec3;
use drapery::mesh::Mesh;
use drapery::model::{ClothDesc, MassSpec, Material, Model};
use drapery::{Error, LinearSolver, Simulation, SolverSettings};

/// Two particles joined by one line element, particle 0 at the origin and particle 1 at
/// `(1, 0, 0)`; the only spring has stiffness `k` and damping `c`; masses `mass`; particle 0
/// pinned when `pinned`.
fn rod(k: f64, c: f64, mass: f64, pinned: bool, velocity: Vec3, gravity: Vec3) -> Model {
    let mesh = Mesh {
        positions: vec![Vec3::ZERO, Vec3::X],
        faces: vec![],
        lines: vec![[0, 1]],
        face_uv: Vec::new(),
    };
    let cloth = ClothDesc {
        name: "rod".into(),
        mesh,
        material: Material {
            stretch_stiffness: k,
            shear_stiffness: 0.0,
            bend_stiffness: 0.0,
            damping: c,
            air_drag: 0.0,
            mass: MassSpec::PerVertex(mass),
            ..Default::default()
        },
        pins: if pinned { vec![0] } else { vec![] },
        initial_velocity: velocity,
        handles: Vec::new(),
    };
    Model::new(vec![cloth], gravity).unwrap()
}

fn reason(e: Error) -> (u64, f64, String) {
    match e {
        Error::StepFailed { step, time, reason } => (step, time, reason),
        other => panic!("expected a failed step, got {other}"),
    }
}

/// The number after `word` in `text` (as the blow-up message prints it, `{:.3e}`).
fn number_after(text: &str, word: &str) -> f64 {
    let rest = &text[text
        .find(word)
        .unwrap_or_else(|| panic!("no '{word}' in {text}"))
        + word.len()..];
    let token = rest.split_whitespace().next().unwrap();
    token
        .parse()
        .unwrap_or_else(|_| panic!("'{token}' in {text}"))
}

// The blow-up. With the damping position Jacobian in the matrix (docs/MATH.md §3), a pair
// approaching along its spring at speed s lowers the transverse diagonal of A = M - h D - h² K
// by h² c s / ℓ. With m = 1 kg, h = 0.1 s, c = 100 N·s/m, ℓ = 1 m and s = 1 - 1e-5 m/s that
// diagonal is 1 - s = 1e-5 kg: gravity across the spring (h m g = 0.1 N·s) then gets a velocity
// change of 0.1 / 1e-5 = 1e4 m/s, and a kinetic energy of ½ (1e4)² = 5e7 J out of a step that
// started with ½ s² ≈ 0.5 J and no stored energy (no stiffness): far beyond 1e4 times
// (0.5 + ½ M_total g² h² = 0.01) J. The direct LU solves this nearly singular system without
// complaint, so it is the blow-up test that must catch it.
const S: f64 = 1.0 - 1e-5;
const H: f64 = 0.1;

fn damped_rod(position_jacobian: bool) -> Simulation {
    let model = rod(
        0.0,
        100.0,
        1.0,
        true,
        Vec3::new(-S, 0.0, 0.0),
        Vec3::new(0.0, -1.0, 0.0),
    );
    let settings = SolverSettings {
        linear_solver: LinearSolver::Direct,
        damping_x_jacobian: position_jacobian,
        ..SolverSettings::default()
    };
    Simulation::new(model, settings).unwrap()
}

#[test]
fn a_nearly_singular_damping_position_jacobian_trips_the_blow_up_test_and_the_state_is_kept() {
    let mut sim = damped_rod(true);
    let (x0, v0) = (sim.positions().to_vec(), sim.velocities().to_vec());
    let before = sim.snapshot();
    let err = sim.step(H).unwrap_err();
    let (step, time, why) = reason(err);
    assert_eq!((step, time), (0, 0.0));
    assert!(
        why.starts_with("energy blow-up: kinetic energy grew from "),
        "{why}"
    );
    assert!(why.contains("vertex 1 of cloth 'rod'"), "{why}");
    // the energies the message reports are the ones the linear algebra predicts
    let ke0 = number_after(&why, "grew from");
    let ke1 = number_after(&why, "J to");
    assert!((ke0 - 0.5 * S * S).abs() <= 1e-3 * ke0, "{ke0} in {why}");
    // x: (m + h c) Δv = h c s (the damping pushes the pair apart), y: (1 - s) Δv = -h m g
    let vx = -S + H * 100.0 * S / (1.0 + H * 100.0);
    let vy = -H / (1.0 - S);
    let predicted = 0.5 * (vx * vx + vy * vy);
    assert!(
        (ke1 - predicted).abs() <= 2e-3 * predicted,
        "{ke1} vs {predicted}"
    );
    // transactional: the state is exactly the one before the step, and nothing advanced
    assert_eq!(sim.model().positions(), x0);
    assert_eq!(sim.model().velocities(), v0);
    assert_eq!((sim.steps(), sim.time()), (0, 0.0));
    assert_eq!(sim.snapshot(), before);
    // so the same step fails again with the same message
    let (_, _, again) = reason(sim.step(H).unwrap_err());
    assert_eq!(again, why);
}

#[test]
fn without_the_damping_position_jacobian_the_same_rod_steps_and_loses_energy() {
    // Baraff & Witkin's symmetric matrix (the default) is at least M: the step is bounded by
    // docs/MATH.md §1 and the damping only takes energy out.
    let mut sim = damped_rod(false);
    let ke0 = sim.model().kinetic_energy();
    sim.step(H).unwrap();
    let ke1 = sim.model().kinetic_energy();
    // at most the work of gravity over the step on top of what it had
    assert!(ke1 < ke0 + 0.5 * (H * 1.0).powi(2) * 2.0, "{ke0} -> {ke1}");
    assert!(
        sim.model().velocities()[1].y < 0.0 && sim.model().velocities()[1].y > -H * 1.0 - 1e-12
    );
}

// "Not positive definite". A = M - h² K with h² k a power of two and a mass below half an ulp of
// it: the rounded diagonal m + h² k is h² k exactly, so along the spring A is exactly singular
// (a rigid translation of the free pair is in its kernel). Gravity along the spring makes the
// right-hand side such a translation, so the first search direction c has cᵀ A c = 0 exactly,
// whatever the preconditioner (they all map a uniform x-vector to a uniform x-vector here), and
// conjugate gradient must stop and say so (docs/MATH.md §11).
fn pair(mass: f64, preconditioner: Preconditioner, linear_solver: LinearSolver) -> Simulation {
    let model = rod(
        64.0,
        0.0,
        mass,
        false,
        Vec3::ZERO,
        Vec3::new(-1.0, 0.0, 0.0),
    );
    let settings = SolverSettings {
        preconditioner,
        linear_solver,
        ..SolverSettings::default()
    };
    Simulation::new(model, settings).unwrap()
}

#[test]
fn a_numerically_singular_matrix_is_reported_as_not_positive_definite_by_every_preconditioner() {
    let h = 0.125; // h² k = 1
    for p in [
        Preconditioner::Identity,
        Preconditioner::Jacobi,
        Preconditioner::BlockJacobi,
        Preconditioner::Multigrid,
    ] {
        let mut sim = pair(2f64.powi(-100), p, LinearSolver::Pcg);
        let x0 = sim.positions().to_vec();
        let (step, _, why) = reason(sim.step(h).unwrap_err());
        assert_eq!(step, 0);
        assert!(
            why.starts_with(
                "the system matrix is not positive definite (Newton iteration 1, 0 CG iterations"
            ),
            "{p:?}: {why}"
        );
        assert_eq!(sim.model().positions(), x0, "{p:?}");
        assert!(
            sim.model().velocities().iter().all(|v| *v == Vec3::ZERO),
            "{p:?}"
        );
    }
}

#[test]
fn the_same_pair_with_a_mass_the_diagonal_can_hold_steps_as_a_free_fall() {
    // the control: with a real mass the matrix is positive definite, the pair falls together
    // (a uniform motion does not stretch the spring) with v = g h exactly
    let h = 0.125;
    for p in [Preconditioner::Identity, Preconditioner::Multigrid] {
        let mut sim = pair(0.25, p, LinearSolver::Pcg);
        sim.step(h).unwrap();
        for v in sim.model().velocities() {
            assert!(
                (*v - Vec3::new(-h, 0.0, 0.0)).length() < 1e-12,
                "{p:?}: {v}"
            );
        }
    }
}

#[test]
fn sparse_cholesky_reports_the_same_singular_matrix_as_not_positive_definite() {
    // along the spring the filtered matrix is [[1, -1], [-1, 1]] exactly: its second pivot is 0
    let mut sim = pair(
        2f64.powi(-100),
        Preconditioner::Multigrid,
        LinearSolver::Direct,
    );
    let (step, _, why) = reason(sim.step(0.125).unwrap_err());
    assert_eq!(step, 0);
    assert!(
        why.starts_with("sparse Cholesky failed: the system matrix is not positive definite"),
        "{why}"
    );
    assert!(sim.model().velocities().iter().all(|v| *v == Vec3::ZERO));
}
