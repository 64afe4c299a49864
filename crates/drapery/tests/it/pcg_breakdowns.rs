//! The filtered PCG's two breakdowns (docs/MATH.md §11): `cᵀ S A c ≤ 0` ("the system matrix is
//! not positive definite") and `rᵀ P⁻¹ r ≤ 0` (the preconditioner is not), on matrices small
//! enough to follow the iteration by hand.

use drapery::linalg::BlockMatrix;
use drapery::linalg::pcg::{self, PcgScratch, PcgSettings, Preconditioner, SolveStats};
use drapery::math::{Mat3, Vec3};

const ALL: [Preconditioner; 4] = [
    Preconditioner::Identity,
    Preconditioner::Jacobi,
    Preconditioner::BlockJacobi,
    Preconditioner::Multigrid,
];

/// Two particles: diagonal blocks `d0 I` and `d1 I`, coupling `β I`.
fn two(d0: f64, d1: f64, beta: f64) -> BlockMatrix {
    let mut a = BlockMatrix::from_pairs(2, &[(0, 1)]);
    a.add(0, 0, Mat3::from_diagonal(Vec3::splat(d0)));
    a.add(1, 1, Mat3::from_diagonal(Vec3::splat(d1)));
    a.add(0, 1, Mat3::from_diagonal(Vec3::splat(beta)));
    a.add(1, 0, Mat3::from_diagonal(Vec3::splat(beta)));
    a
}

/// PCG from a zero guess, to 1e-10, on `A x = b` filtered by `s` with `z` prescribed.
fn solve(
    p: Preconditioner,
    a: &BlockMatrix,
    [b, z]: [&[Vec3]; 2],
    s: &[Mat3],
) -> (SolveStats, Vec<Vec3>) {
    let mut x = vec![Vec3::ZERO; a.n()];
    let settings = PcgSettings {
        tolerance: 1e-10,
        max_iterations: 100,
        preconditioner: p,
        keep_coarse: false,
    };
    let stats = pcg::solve(a, b, s, z, &mut x, &settings, &mut PcgScratch::default());
    (stats, x)
}

#[test]
fn a_negative_block_on_a_free_particle_is_reported_indefinite_by_every_preconditioner() {
    // A = diag(2 I, -I): the right-hand side lives on the negative particle, so every
    // preconditioner's first direction c lies there too and cᵀ A c = -|c|² < 0
    let a = two(2.0, -1.0, 0.0);
    let b = [Vec3::ZERO, Vec3::new(1.0, -2.0, 0.5)];
    let free = [Mat3::IDENTITY; 2];
    for p in ALL {
        let (stats, _) = solve(p, &a, [&b, &[Vec3::ZERO; 2]], &free);
        assert!(stats.indefinite, "{p:?}: {stats:?}");
        assert!(!stats.converged, "{p:?}");
        assert!(!stats.bad_preconditioner, "{p:?}");
        assert_eq!(stats.iterations, 0, "{p:?}");
    }
}

#[test]
fn indefiniteness_met_later_in_the_iteration_is_reported_too() {
    // plain CG on diag(2 I, -I) with b on both particles: c = b has cᵀAc = 2 - 1 > 0, then
    // α = 2, r = (-3, 3), β = 9, c = (6, 12) with cᵀAc = 72 - 144 < 0 (per coordinate)
    let a = two(2.0, -1.0, 0.0);
    let b = [Vec3::X, Vec3::X];
    let (stats, _) = solve(
        Preconditioner::Identity,
        &a,
        [&b, &[Vec3::ZERO; 2]],
        &[Mat3::IDENTITY; 2],
    );
    assert!(stats.indefinite && !stats.converged, "{stats:?}");
    assert_eq!(stats.iterations, 1);
}

#[test]
fn pinning_the_negative_particle_filters_the_indefiniteness_out() {
    // S A S + (I - S) is diag(2 I, I): positive definite, and the pinned particle gets z exactly
    let a = two(2.0, -1.0, 0.0);
    let b = [Vec3::new(1.0, 2.0, -4.0), Vec3::new(1.0, -2.0, 0.5)];
    let s = [Mat3::IDENTITY, Mat3::ZERO];
    let z = [Vec3::ZERO, Vec3::new(0.3, 0.0, -0.1)];
    for p in ALL {
        let (stats, x) = solve(p, &a, [&b, &z], &s);
        assert!(stats.converged && !stats.indefinite, "{p:?}: {stats:?}");
        assert_eq!(x[1], z[1], "{p:?}");
        assert!((x[0] - b[0] / 2.0).length() < 1e-9, "{p:?}: {:?}", x[0]);
    }
}

#[test]
fn a_preconditioner_that_is_not_positive_definite_is_reported_as_such() {
    // A = [[I, ½ I], [½ I, -4 I]], b = (x̂, 0). Jacobi and block Jacobi invert the diagonal:
    // P⁻¹ = diag(I, -¼ I). First iteration: c = b, cᵀAc = 1 > 0, α = 1, r = (0, -½ x̂); then
    // rᵀ P⁻¹ r = -1/16 < 0 with ‖r‖ = ½ far above the tolerance: a bad preconditioner, not
    // (yet) an indefinite matrix.
    let a = two(1.0, -4.0, 0.5);
    let b = [Vec3::X, Vec3::ZERO];
    for p in [Preconditioner::Jacobi, Preconditioner::BlockJacobi] {
        let (stats, x) = solve(p, &a, [&b, &[Vec3::ZERO; 2]], &[Mat3::IDENTITY; 2]);
        assert!(stats.bad_preconditioner, "{p:?}: {stats:?}");
        assert!(!stats.indefinite && !stats.converged, "{p:?}");
        assert_eq!(stats.iterations, 1, "{p:?}");
        assert_eq!(x, vec![Vec3::X, Vec3::ZERO], "{p:?}");
        assert!((stats.relative_residual - 0.5).abs() < 1e-15, "{p:?}");
    }
}
