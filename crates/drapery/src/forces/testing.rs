//! Finite-difference checks shared by the force tests.

use super::*;
use crate::math::Mat3;

/// The time the force tests evaluate at (no force here depends on it yet).
pub const T: f64 = 0.25;

/// The state `(T, x, v)`.
pub fn at<'a>(x: &'a [Vec3], v: &'a [Vec3]) -> State<'a> {
    State { t: T, x, v }
}

/// Central-difference force `-∂E/∂x`.
pub fn fd_gradient(force: &dyn Force, x: &[Vec3]) -> Vec<Vec3> {
    let mut g = vec![Vec3::ZERO; x.len()];
    let mut xp = x.to_vec();
    for i in 0..x.len() {
        for d in 0..3 {
            let e = 1e-6 * (1.0 + x[i][d].abs());
            xp[i][d] = x[i][d] + e;
            let ep = force.energy(T, &xp);
            xp[i][d] = x[i][d] - e;
            let em = force.energy(T, &xp);
            xp[i][d] = x[i][d];
            g[i][d] = -(ep - em) / (2.0 * e);
        }
    }
    g
}

/// `-∂Ψ/∂v` by central differences (step 1e-6) of the dissipation potential `Ψ`: the force
/// of a damping that has one.
pub fn fd_dissipation_force(force: &dyn Force, x: &[Vec3], v: &[Vec3]) -> Vec<Vec3> {
    let mut g = vec![Vec3::ZERO; v.len()];
    let mut vp = v.to_vec();
    let e = 1e-6;
    for i in 0..v.len() {
        for k in 0..3 {
            vp[i][k] = v[i][k] + e;
            let up = force.dissipation(&at(x, &vp));
            vp[i][k] = v[i][k] - e;
            let dn = force.dissipation(&at(x, &vp));
            vp[i][k] = v[i][k];
            g[i][k] = -(up - dn) / (2.0 * e);
        }
    }
    g
}

/// Dense `∂f/∂x` (wrt = false) or `∂f/∂v` (wrt = true) by central differences.
pub fn fd_jacobian(force: &dyn Force, x: &[Vec3], v: &[Vec3], wrt_v: bool) -> Vec<Vec<f64>> {
    fd_jacobian_step(force, x, v, wrt_v, 1e-6)
}

/// [`fd_jacobian`] with the relative step `step`. A force linear in `v` takes a step of 1 in `v`:
/// its central difference is then exact up to rounding, which a small step would divide by the
/// step (the rounding of a large elastic part of the same force).
pub fn fd_jacobian_step(
    force: &dyn Force,
    x: &[Vec3],
    v: &[Vec3],
    wrt_v: bool,
    step: f64,
) -> Vec<Vec<f64>> {
    let n = x.len();
    let mut jac = vec![vec![0.0; 3 * n]; 3 * n];
    let (mut xp, mut vp) = (x.to_vec(), v.to_vec());
    for j in 0..n {
        for d in 0..3 {
            let base = if wrt_v { v[j][d] } else { x[j][d] };
            let e = step * (1.0 + base.abs());
            let mut eval = |delta: f64| {
                if wrt_v {
                    vp[j][d] = base + delta;
                } else {
                    xp[j][d] = base + delta;
                }
                let mut f = vec![Vec3::ZERO; n];
                force.add_force(&at(&xp, &vp), &mut f);
                if wrt_v {
                    vp[j][d] = base;
                } else {
                    xp[j][d] = base;
                }
                f
            };
            let fp = eval(e);
            let fm = eval(-e);
            for i in 0..n {
                for r in 0..3 {
                    jac[3 * i + r][3 * j + d] = (fp[i][r] - fm[i][r]) / (2.0 * e);
                }
            }
        }
    }
    jac
}

/// The force's own Jacobian `a ∂f/∂x + b ∂f/∂v`, assembled densely.
pub fn assembled(force: &dyn Force, x: &[Vec3], v: &[Vec3], a: f64, b: f64) -> Vec<Vec<f64>> {
    let mut pairs = Vec::new();
    force.add_pattern(&mut pairs);
    let mut m = BlockMatrix::from_pairs(x.len(), &pairs);
    force.add_jacobian(&at(x, v), a, b, &mut m);
    m.to_dense()
}

/// Max entry-wise difference, relative to the largest entry of `reference` (or 1).
pub fn rel_diff(got: &[Vec<f64>], reference: &[Vec<f64>]) -> f64 {
    let scale = reference
        .iter()
        .flatten()
        .fold(1.0f64, |m, v| m.max(v.abs()));
    let diff = got
        .iter()
        .flatten()
        .zip(reference.iter().flatten())
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    diff / scale
}

/// Checks `add_jacobian_product` against the assembled matrix times `w`.
pub fn check_product(force: &dyn Force, x: &[Vec3], v: &[Vec3], a: f64, b: f64, w: &[Vec3]) -> f64 {
    let dense = assembled(force, x, v, a, b);
    let mut out = vec![Vec3::ZERO; x.len()];
    force.add_jacobian_product(&at(x, v), a, b, w, &mut out);
    let wf: Vec<f64> = w.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    let mut worst = 0.0f64;
    let mut scale = 1.0f64;
    for r in 0..3 * x.len() {
        let expect: f64 = dense[r].iter().zip(&wf).map(|(m, q)| m * q).sum();
        worst = worst.max((out[r / 3][r % 3] - expect).abs());
        scale = scale.max(expect.abs());
    }
    worst / scale
}

/// The matrix `a ∂f/∂x + b ∂f/∂v` that [`Force::add_linearization`] assembles, densely.
pub fn linearized(force: &dyn Force, x: &[Vec3], v: &[Vec3], a: f64, b: f64) -> Vec<Vec<f64>> {
    let mut pairs = Vec::new();
    force.add_pattern(&mut pairs);
    let mut m = BlockMatrix::from_pairs(x.len(), &pairs);
    let (mut f, mut out) = (vec![Vec3::ZERO; x.len()], vec![Vec3::ZERO; x.len()]);
    let at = Linearization {
        t: T,
        x,
        v,
        matrix: (a, b),
        product: (1.0, 1.0),
        w: v,
    };
    force.add_linearization(&at, &mut f, &mut m, &mut out);
    m.to_dense()
}

fn same_bits<const N: usize>(
    a: impl Iterator<Item = [f64; N]>,
    b: impl Iterator<Item = [f64; N]>,
) -> bool {
    a.zip(b)
        .all(|(p, q)| p.iter().zip(&q).all(|(s, t)| s.to_bits() == t.to_bits()))
}

/// Whether [`Force::add_linearization`] gives the same bits as the three separate calls,
/// both adding to the same starting values (built from `start`, one per particle).
pub fn linearization_is_bitwise_separate(
    force: &dyn Force,
    at: &Linearization,
    start: &[Vec3],
) -> bool {
    let n = at.x.len();
    let mut pairs = Vec::new();
    force.add_pattern(&mut pairs);
    let mut m0 = BlockMatrix::from_pairs(n, &pairs);
    for (k, blk) in m0.values.iter_mut().enumerate() {
        *blk = Mat3::from_cols(start[k % n], start[(k + 1) % n], start[(k + 2) % n]);
    }
    let mut f0 = start.to_vec();
    let mut out0: Vec<Vec3> = start.iter().map(|s| Vec3::new(s.z, s.x, s.y)).collect();
    let (mut m1, mut f1, mut out1) = (m0.clone(), f0.clone(), out0.clone());
    linearize_separately(force, at, &mut f0, &mut m0, &mut out0);
    force.add_linearization(at, &mut f1, &mut m1, &mut out1);
    let vecs = |v: &[Vec3]| {
        v.iter()
            .map(|p| p.to_array())
            .collect::<Vec<_>>()
            .into_iter()
    };
    let mats = |m: &BlockMatrix| {
        m.values
            .iter()
            .map(|b| b.to_cols_array())
            .collect::<Vec<_>>()
            .into_iter()
    };
    same_bits(vecs(&f0), vecs(&f1))
        && same_bits(vecs(&out0), vecs(&out1))
        && same_bits(mats(&m0), mats(&m1))
}

/// Dense matrix of `n` particles from 3-particle stencils' blocks (`[i][j]` = row `i`,
/// column `j` of the stencil), summed.
pub fn dense_blocks(
    n: usize,
    stencils: impl Iterator<Item = ([u32; 3], [[Mat3; 3]; 3])>,
) -> Vec<Vec<f64>> {
    let mut out = vec![vec![0.0; 3 * n]; 3 * n];
    for (p, blocks) in stencils {
        for (i, &pi) in p.iter().enumerate() {
            for (j, &pj) in p.iter().enumerate() {
                for r in 0..3 {
                    for c in 0..3 {
                        out[3 * pi as usize + r][3 * pj as usize + c] += blocks[i][j].col(c)[r];
                    }
                }
            }
        }
    }
    out
}

/// A vector with components in `(-r, r)`.
pub fn arb_vec3(r: f64) -> impl proptest::strategy::Strategy<Value = Vec3> {
    use proptest::strategy::Strategy;
    (-r..r, -r..r, -r..r).prop_map(|(a, b, c)| Vec3::new(a, b, c))
}
