//! PCG, the direct solver and a dense solve agree; block Jacobi helps.

use crate::common::*;
use drapery::SolverSettings;
use drapery::linalg::BlockMatrix;
use drapery::linalg::direct::DirectSolver;
use drapery::linalg::pcg::{self, PcgScratch, PcgSettings, Preconditioner};
use drapery::linalg::split::{Coupling, Split};
use drapery::math::{Mat3, Vec3, outer};
use drapery::model::MassSpec;

fn random_spd(n: usize, rng: &mut Lcg) -> BlockMatrix {
    let mut pairs = Vec::new();
    for i in 0..n as u32 {
        for _ in 0..3 {
            let j = ((rng.next() * 0.5 + 0.5) * n as f64) as u32 % n as u32;
            if j != i {
                pairs.push((i, j));
            }
        }
    }
    let mut a = BlockMatrix::from_pairs(n, &pairs);
    let mut rowsum = vec![0.0; n];
    for i in 0..n {
        let (cols, _) = a.row(i);
        for &j in cols.to_vec().iter() {
            let j = j as usize;
            if j > i {
                let b = Mat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3());
                a.add(i, j, b);
                a.add(j, i, b.transpose());
                let s: f64 = b.to_cols_array().iter().map(|e| e.abs()).sum();
                rowsum[i] += s;
                rowsum[j] += s;
            }
        }
    }
    for i in 0..n {
        let r = Mat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3());
        a.add(
            i,
            i,
            0.5 * (r + r.transpose()) + Mat3::from_diagonal(Vec3::splat(rowsum[i] + 3.0)),
        );
    }
    a
}

/// Dense reference of the filtered system: (S A S + I - S) y = S (b - A z), x = z + y.
fn dense_filtered(a: &BlockMatrix, b: &[Vec3], s: &[Mat3], z: &[Vec3]) -> Vec<Vec3> {
    let n = a.n();
    let d = a.to_dense();
    let zf = flat(z);
    let mut az = vec![0.0; 3 * n];
    for r in 0..3 * n {
        az[r] = (0..3 * n).map(|c| d[r][c] * zf[c]).sum();
    }
    let mut m = vec![vec![0.0; 3 * n]; 3 * n];
    let mut rhs = vec![0.0; 3 * n];
    for i in 0..n {
        let r = s[i] * (b[i] - Vec3::new(az[3 * i], az[3 * i + 1], az[3 * i + 2]));
        for k in 0..3 {
            rhs[3 * i + k] = r[k];
        }
        for j in 0..n {
            let mut blk = s[i] * block(&d, i, j) * s[j];
            if i == j {
                blk += Mat3::IDENTITY - s[i];
            }
            for r in 0..3 {
                for c in 0..3 {
                    m[3 * i + r][3 * j + c] = blk.col(c)[r];
                }
            }
        }
    }
    let y = unflat(&dense_solve(m, rhs));
    (0..n).map(|i| z[i] + s[i] * y[i]).collect()
}

#[test]
fn pcg_direct_and_dense_agree_on_random_filtered_spd_systems() {
    let mut rng = Lcg(7);
    for trial in 0..20 {
        let n = 5 + trial;
        let a = random_spd(n, &mut rng);
        let b: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        // a pinned particle, a plane-constrained one, the rest free
        let normal = rng.vec3().normalize();
        let mut s = vec![Mat3::IDENTITY; n];
        let mut z = vec![Vec3::ZERO; n];
        s[0] = Mat3::ZERO;
        z[0] = rng.vec3();
        s[1] = Mat3::IDENTITY - outer(normal, normal);
        z[1] = 0.3 * normal;
        let reference = dense_filtered(&a, &b, &s, &z);
        let mut x = vec![Vec3::ZERO; n];
        let settings = PcgSettings {
            tolerance: 1e-13,
            max_iterations: 1000,
            preconditioner: Preconditioner::BlockJacobi,
            keep_coarse: false,
        };
        let stats = pcg::solve(
            &a,
            &b,
            &s,
            &z,
            &mut x,
            &settings,
            &mut PcgScratch::default(),
        );
        assert!(stats.converged);
        let mut xd = vec![Vec3::ZERO; n];
        DirectSolver::default()
            .solve(&a, &b, &s, &z, &mut xd, true)
            .unwrap();
        for i in 0..n {
            assert!(
                (x[i] - reference[i]).length() < 1e-9,
                "pcg trial {trial} particle {i}"
            );
            assert!(
                (xd[i] - reference[i]).length() < 1e-9,
                "direct trial {trial} particle {i}"
            );
        }
        // constraints hold exactly: the filtered-out part equals z
        assert_eq!(x[0], z[0]);
        assert!((x[1].dot(normal) - 0.3).abs() < 1e-12);
    }
}

#[test]
fn pcg_and_direct_agree_on_a_real_cloth_matrix_and_it_is_positive_definite() {
    let mut sim = hanging_cloth(
        16,
        SolverSettings::default(),
        material(MassSpec::Density(0.1)),
    );
    for _ in 0..10 {
        sim.step(1.0 / 60.0).unwrap();
    }
    let a = sim.matrix().clone();
    assert!(a.asymmetry() < 1e-9);
    let n = a.n();
    let mut rng = Lcg(3);
    let b: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
    let s = sim.model().pin_filter();
    let z = vec![Vec3::ZERO; n];
    let mut x = vec![Vec3::ZERO; n];
    let settings = PcgSettings {
        tolerance: 1e-12,
        max_iterations: 5000,
        preconditioner: Preconditioner::BlockJacobi,
        keep_coarse: false,
    };
    assert!(
        pcg::solve(
            &a,
            &b,
            &s,
            &z,
            &mut x,
            &settings,
            &mut PcgScratch::default()
        )
        .converged
    );
    let mut xd = vec![Vec3::ZERO; n];
    // Cholesky succeeding is itself the proof that the filtered A is positive definite
    DirectSolver::default()
        .solve(&a, &b, &s, &z, &mut xd, true)
        .unwrap();
    let scale = xd.iter().fold(0.0f64, |m, v| m.max(v.length()));
    for i in 0..n {
        assert!((x[i] - xd[i]).length() < 1e-8 * scale);
    }
    // quadratic form check with random vectors
    for _ in 0..20 {
        let w: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        let mut aw = vec![Vec3::ZERO; n];
        a.mul_vec(&w, &mut aw);
        assert!(w.iter().zip(&aw).map(|(p, q)| p.dot(*q)).sum::<f64>() > 0.0);
    }
}

#[test]
fn block_jacobi_pcg_takes_fewer_iterations_than_plain_cg_on_a_64x64_cloth() {
    let mut sim = hanging_cloth(
        64,
        SolverSettings::default(),
        material(MassSpec::Density(0.1)),
    );
    sim.step(1.0 / 60.0).unwrap();
    let a = sim.matrix().clone();
    let n = a.n();
    let mut rng = Lcg(11);
    let b: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
    let s = sim.model().pin_filter();
    let z = vec![Vec3::ZERO; n];
    let mut iters = Vec::new();
    for p in [Preconditioner::Identity, Preconditioner::BlockJacobi] {
        let mut x = vec![Vec3::ZERO; n];
        let settings = PcgSettings {
            tolerance: 1e-8,
            max_iterations: 10000,
            preconditioner: p,
            keep_coarse: false,
        };
        let st = pcg::solve(
            &a,
            &b,
            &s,
            &z,
            &mut x,
            &settings,
            &mut PcgScratch::default(),
        );
        assert!(st.converged);
        iters.push(st.iterations);
    }
    assert!(
        iters[1] < iters[0],
        "block Jacobi {} vs plain CG {}",
        iters[1],
        iters[0]
    );
}

/// The solve of `A = P + C` with the preconditioner built from `P` alone (the system without
/// its contacts' coupling, as the integrator does with cloth–cloth contacts outside the model's
/// pattern) still solves the whole system, under filters as well.
#[test]
fn a_preconditioner_built_from_the_uncoupled_matrix_still_solves_the_coupled_system() {
    let mut rng = Lcg(11);
    for trial in 0..10 {
        let n = 12 + trial;
        let base = random_spd(n, &mut rng);
        // contact-like coupling between two particles: [[C, -C], [-C, C]], C positive definite
        let (p, q) = (0usize, n - 1);
        let r = Mat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3());
        let c = r * r.transpose() + Mat3::IDENTITY;
        let mut pre = base.clone();
        pre.add(p, p, c);
        pre.add(q, q, c);
        let mut coupling = Coupling::new(n, &[(p as u32, q as u32)]);
        coupling.matrix_mut().add(p, q, -c);
        coupling.matrix_mut().add(q, p, -c);
        let a = Split {
            p: &pre,
            coupling: Some(&coupling),
        };
        let merged = a.merged();
        let b: Vec<Vec3> = (0..n).map(|_| rng.vec3()).collect();
        // free, then a pinned particle and one held against a plane (the coupled ones on odd
        // trials)
        let mut s = vec![Mat3::IDENTITY; n];
        let mut z = vec![Vec3::ZERO; n];
        if trial % 2 == 1 {
            let (pin, held) = if trial % 4 == 1 { (p, q) } else { (1, 2) };
            s[pin] = Mat3::ZERO;
            z[pin] = rng.vec3();
            let nrm = rng.vec3().normalize();
            s[held] = Mat3::IDENTITY - outer(nrm, nrm);
            z[held] = nrm * 0.3;
        }
        let reference = dense_filtered(&merged, &b, &s, &z);
        for preconditioner in [Preconditioner::BlockJacobi, Preconditioner::Multigrid] {
            let settings = PcgSettings {
                tolerance: 1e-12,
                max_iterations: 1000,
                preconditioner,
                keep_coarse: false,
            };
            let mut x = vec![Vec3::ZERO; n];
            let stats =
                pcg::solve_split(a, &b, &s, &z, &mut x, &settings, &mut PcgScratch::default());
            assert!(stats.converged, "trial {trial} {preconditioner:?}");
            for i in 0..n {
                assert!(
                    (x[i] - reference[i]).length() < 1e-8,
                    "trial {trial} {preconditioner:?} particle {i}: {} against {}",
                    x[i],
                    reference[i]
                );
            }
        }
    }
}
