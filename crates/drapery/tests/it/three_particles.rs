//! The seeds' 3-particle cloth (docs/MATH.md §6): assembly, signs and the solve checked by hand.

use crate::common::*;
use drapery::forces::{Force, Springs, State};
use drapery::linalg::BlockMatrix;
use drapery::math::{Mat3, Vec3};
use drapery::mesh::Mesh;
use drapery::model::{ClothDesc, MassSpec, Material, Model};
use drapery::{Simulation, SolverSettings};

const K: f64 = 50.0;

fn positions() -> Vec<Vec3> {
    // spring 0-1 stretched to 1.2 along x, spring 1-2 compressed to 0.5 along y (rest 1 each)
    vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.2, 0.0, 0.0),
        Vec3::new(1.2, -0.5, 0.0),
    ]
}

fn springs(clamp: bool) -> Springs {
    Springs {
        i: vec![0, 1],
        j: vec![1, 2],
        rest: vec![1.0, 1.0],
        k: vec![K, K],
        clamp_compression: clamp,
        sums: Default::default(),
    }
}

/// The state at positions `x` (and velocities `x`: springs do not read them).
fn at(x: &[Vec3]) -> State<'_> {
    State { t: 0.0, x, v: x }
}

fn assemble(s: &Springs, x: &[Vec3]) -> BlockMatrix {
    let mut pairs = Vec::new();
    s.add_pattern(&mut pairs);
    let mut m = BlockMatrix::from_pairs(3, &pairs);
    s.add_jacobian(&at(x), 1.0, 0.0, &mut m);
    m
}

#[test]
fn three_particle_forces_match_hand_values() {
    let x = positions();
    let mut f = vec![Vec3::ZERO; 3];
    springs(true).add_force(&at(&x), &mut f);
    // f0 = -k (ℓ - L) n with n = (x0 - x1)/ℓ = -x̂: pulls 0 toward 1.
    assert!((f[0] - Vec3::new(0.2 * K, 0.0, 0.0)).length() < 1e-12);
    // spring 1-2 compressed by 0.5 pushes 1 up (+y) and 2 down.
    assert!((f[1] - Vec3::new(-0.2 * K, 0.5 * K, 0.0)).length() < 1e-12);
    assert!((f[2] - Vec3::new(0.0, -0.5 * K, 0.0)).length() < 1e-12);
}

#[test]
fn three_particle_stiffness_matrix_matches_hand_blocks() {
    let x = positions();
    // H01 = k diag(1, 1 - 1/1.2, 1 - 1/1.2); H12 = k diag(1 - 1/0.5, 1, 1 - 1/0.5), clamped to k diag(0, 1, 0)
    let h01 = Mat3::from_diagonal(Vec3::new(K, K / 6.0, K / 6.0));
    for (clamp, h12) in [
        (false, Mat3::from_diagonal(Vec3::new(-K, K, -K))),
        (true, Mat3::from_diagonal(Vec3::new(0.0, K, 0.0))),
    ] {
        let d = assemble(&springs(clamp), &x).to_dense();
        let expect = [
            [-h01, h01, Mat3::ZERO],
            [h01, -h01 - h12, h12],
            [Mat3::ZERO, h12, -h12],
        ];
        for i in 0..3 {
            for j in 0..3 {
                let got = block(&d, i, j);
                assert!(
                    (got - expect[i][j])
                        .to_cols_array()
                        .iter()
                        .all(|e| e.abs() < 1e-12),
                    "clamp {clamp} block {i}{j}: {got:?}"
                );
            }
        }
        // symmetric, block rows sum to zero
        for r in 0..9 {
            for c in 0..9 {
                assert!((d[r][c] - d[c][r]).abs() < 1e-12);
            }
        }
        for i in 0..3 {
            let sum = block(&d, i, 0) + block(&d, i, 1) + block(&d, i, 2);
            assert!(sum.to_cols_array().iter().all(|e| e.abs() < 1e-12));
        }
    }
}

#[test]
fn unclamped_three_particle_matrix_is_the_central_difference_of_the_force() {
    let x = positions();
    let s = springs(false);
    let d = assemble(&s, &x).to_dense();
    for j in 0..9 {
        let e = 1e-6;
        let mut xp = x.clone();
        xp[j / 3][j % 3] += e;
        let mut fp = vec![Vec3::ZERO; 3];
        s.add_force(&at(&xp), &mut fp);
        xp[j / 3][j % 3] -= 2.0 * e;
        let mut fm = vec![Vec3::ZERO; 3];
        s.add_force(&at(&xp), &mut fm);
        for i in 0..9 {
            let fd = (fp[i / 3][i % 3] - fm[i / 3][i % 3]) / (2.0 * e);
            assert!(
                (fd - d[i][j]).abs() < 1e-6 * K,
                "entry {i},{j}: {fd} vs {}",
                d[i][j]
            );
        }
    }
}

#[test]
fn one_step_of_the_three_particle_cloth_equals_the_hand_assembled_dense_solve() {
    let x = positions();
    let masses = [0.1, 0.2, 0.3];
    let g = Vec3::new(0.0, -9.81, 0.0);
    let h = 0.01;
    let v0 = vec![
        Vec3::new(0.1, 0.0, 0.0),
        Vec3::new(0.0, 0.2, 0.0),
        Vec3::new(-0.3, 0.0, 0.1),
    ];
    let mesh = Mesh {
        positions: x.clone(),
        faces: vec![],
        lines: vec![[0, 1], [1, 2]],
        face_uv: Vec::new(),
    };
    let material = Material {
        stretch_stiffness: K,
        shear_stiffness: 0.0,
        bend_stiffness: 0.0,
        damping: 0.0,
        air_drag: 0.0,
        mass: MassSpec::PerVertex(1.0),
        ..Default::default()
    };
    let mut model = Model::new(
        vec![ClothDesc {
            name: "three".into(),
            mesh,
            material,
            pins: vec![],
            initial_velocity: Vec3::ZERO,
            handles: Vec::new(),
        }],
        g,
    )
    .unwrap();
    model.set_masses(&masses).unwrap();
    model.set_velocities(&v0).unwrap();
    model.set_rest_lengths(&[1.0, 1.0]).unwrap();
    let mut sim = Simulation::new(
        model,
        SolverSettings {
            tolerance: 1e-13,
            ..Default::default()
        },
    )
    .unwrap();
    sim.step(h).unwrap();

    // By hand: A = M - h² K (K clamped), b = h (f + h K v0).
    let kd = assemble(&springs(true), &x).to_dense();
    let mut f = vec![Vec3::ZERO; 3];
    springs(true).add_force(&at(&x), &mut f);
    let v0f = flat(&v0);
    let mut a = vec![vec![0.0; 9]; 9];
    let mut b = vec![0.0; 9];
    for r in 0..9 {
        for c in 0..9 {
            a[r][c] = -h * h * kd[r][c];
        }
        a[r][r] += masses[r / 3];
        let kv: f64 = (0..9).map(|c| kd[r][c] * v0f[c]).sum();
        b[r] = h * (f[r / 3][r % 3] + masses[r / 3] * g[r % 3] + h * kv);
    }
    let dv = dense_solve(a, b);
    for i in 0..3 {
        let v1 = v0[i] + Vec3::new(dv[3 * i], dv[3 * i + 1], dv[3 * i + 2]);
        assert!(
            (sim.model().velocities()[i] - v1).length() < 1e-10,
            "v{i}: {:?} vs {:?}",
            sim.model().velocities()[i],
            v1
        );
        assert!((sim.model().positions()[i] - (x[i] + h * v1)).length() < 1e-12);
    }
}
