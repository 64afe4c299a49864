//! Static equilibria reached by running the implicit step to rest.

use crate::common::*;
use drapery::math::Vec3;
use drapery::mesh::Mesh;
use drapery::model::{ClothDesc, MassSpec, Material, Model};
use drapery::{Simulation, SolverSettings};

#[test]
fn a_hanging_chain_settles_to_weight_below_over_k_per_spring() {
    let (n, m, k, g) = (10usize, 0.05, 200.0, 9.81);
    let positions = (0..n)
        .map(|i| Vec3::new(0.0, -(i as f64) * 0.1, 0.0))
        .collect();
    let lines = (0..n as u32 - 1).map(|i| [i, i + 1]).collect();
    let mesh = Mesh {
        positions,
        faces: vec![],
        lines,
        face_uv: Vec::new(),
    };
    let material = Material {
        stretch_stiffness: k,
        shear_stiffness: 0.0,
        bend_stiffness: 0.0,
        damping: 0.5,
        air_drag: 0.02,
        mass: MassSpec::PerVertex(m),
        ..Default::default()
    };
    let model = Model::new(
        vec![ClothDesc {
            name: "chain".into(),
            mesh,
            material,
            pins: vec![0],
            initial_velocity: Vec3::ZERO,
            handles: Vec::new(),
        }],
        Vec3::new(0.0, -g, 0.0),
    )
    .unwrap();
    let mut sim = Simulation::new(
        model,
        SolverSettings {
            tolerance: 1e-12,
            ..Default::default()
        },
    )
    .unwrap();
    for _ in 0..3000 {
        sim.step(0.01).unwrap();
    }
    for s in 0..n - 1 {
        let len = (sim.model().positions()[s] - sim.model().positions()[s + 1]).length();
        let below = (n - 1 - s) as f64 * m * g;
        let expect = 0.1 + below / k;
        assert!((len - expect).abs() < 1e-9, "spring {s}: {len} vs {expect}");
    }
}

#[test]
fn a_cloth_pinned_at_two_corners_settles_with_pin_reactions_equal_to_its_weight() {
    let mut mat = material(MassSpec::Density(0.2));
    mat.damping = 0.05;
    mat.air_drag = 0.002;
    let mut sim = hanging_cloth(
        12,
        SolverSettings {
            tolerance: 1e-10,
            ..Default::default()
        },
        mat,
    );
    for _ in 0..1500 {
        sim.step(0.01).unwrap();
    }
    let f = sim.total_force();
    let weight = sim.model().total_mass() * sim.model().gravity();
    let mut reaction = Vec3::ZERO;
    for (i, fi) in f.iter().enumerate() {
        if sim.model().pins()[i] {
            reaction -= *fi;
        }
    }
    // the pins hold the cloth up: reaction + weight = 0
    assert!(
        (reaction + weight).length() < 1e-4 * weight.length(),
        "reaction {reaction:?}, weight {weight:?}"
    );
    // the two pins share it about equally (the lumped masses are not exactly mirror-symmetric:
    // quads are split along one diagonal)
    assert!(
        (f[0].y - f[11].y).abs() < 1e-3 * weight.length(),
        "{} vs {}",
        f[0].y,
        f[11].y
    );
    assert!(sim.model().kinetic_energy() < 1e-10);
}
