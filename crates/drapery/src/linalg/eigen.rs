//! Small dense symmetric matrices: eigen-decomposition by cyclic Jacobi rotations, and the
//! projection onto the positive semi-definite cone that a force's local Hessian gets before it
//! enters the implicit matrix (docs/MATH.md, shell forces).
//!
//! The size is a compile-time constant (a membrane triangle is 9 × 9, a hinge 12 × 12); the
//! rotations visit the pairs in a fixed order, so the result has the same bits everywhere.

/// Sweeps of rotations before giving up (Jacobi converges quadratically: 6 to 10 sweeps reach
/// rounding for these sizes).
const SWEEPS: usize = 50;

/// Eigenvalues `λ` and eigenvectors (columns of `q`) of the symmetric `a`: `a = q diag(λ) qᵀ`.
/// Only the upper triangle of `a` is read.
pub fn symmetric_eigen<const N: usize>(a: &[[f64; N]; N]) -> ([f64; N], [[f64; N]; N]) {
    let mut m = *a;
    for i in 0..N {
        for j in 0..i {
            m[i][j] = m[j][i];
        }
    }
    let mut q = [[0.0; N]; N];
    for (i, row) in q.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let scale = m.iter().flatten().fold(0.0f64, |s, &v| s.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return (std::array::from_fn(|i| m[i][i]), q);
    }
    for _ in 0..SWEEPS {
        let off: f64 = (0..N)
            .flat_map(|i| (i + 1..N).map(move |j| (i, j)))
            .map(|(i, j)| m[i][j] * m[i][j])
            .sum();
        if off <= (f64::EPSILON * scale).powi(2) {
            break;
        }
        for p in 0..N {
            for r in p + 1..N {
                let apr = m[p][r];
                if apr == 0.0 {
                    continue;
                }
                // the rotation that zeroes m[p][r] (Golub & Van Loan, Algorithm 8.4.1)
                let tau = (m[r][r] - m[p][p]) / (2.0 * apr);
                let t = tau.signum() / (tau.abs() + (1.0 + tau * tau).sqrt());
                let t = if tau == 0.0 { 1.0 } else { t };
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = t * c;
                for k in 0..N {
                    let (mkp, mkr) = (m[k][p], m[k][r]);
                    m[k][p] = c * mkp - s * mkr;
                    m[k][r] = s * mkp + c * mkr;
                }
                for k in 0..N {
                    let (mpk, mrk) = (m[p][k], m[r][k]);
                    m[p][k] = c * mpk - s * mrk;
                    m[r][k] = s * mpk + c * mrk;
                }
                for row in q.iter_mut() {
                    let (qp, qr) = (row[p], row[r]);
                    row[p] = c * qp - s * qr;
                    row[r] = s * qp + c * qr;
                }
            }
        }
    }
    (std::array::from_fn(|i| m[i][i]), q)
}

/// Replaces the symmetric `a` by its nearest positive semi-definite matrix in the Frobenius
/// norm: negative eigenvalues are set to zero. A matrix with none is returned as it was (to
/// the bit), so a convex stencil costs one decomposition and changes nothing.
pub fn project_psd<const N: usize>(a: &mut [[f64; N]; N]) {
    let (lambda, q) = symmetric_eigen(a);
    if lambda.iter().all(|&l| l >= 0.0) {
        return;
    }
    for i in 0..N {
        for j in 0..N {
            let mut s = 0.0;
            for k in 0..N {
                if lambda[k] > 0.0 {
                    s += q[i][k] * lambda[k] * q[j][k];
                }
            }
            a[i][j] = s;
        }
    }
    for i in 0..N {
        for j in 0..i {
            let mean = 0.5 * (a[i][j] + a[j][i]);
            a[i][j] = mean;
            a[j][i] = mean;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn random_symmetric<const N: usize>(v: &[f64]) -> [[f64; N]; N] {
        let mut a = [[0.0; N]; N];
        let mut k = 0;
        for i in 0..N {
            for j in i..N {
                a[i][j] = v[k];
                a[j][i] = v[k];
                k += 1;
            }
        }
        a
    }

    fn max_diff<const N: usize>(a: &[[f64; N]; N], b: &[[f64; N]; N]) -> f64 {
        (0..N)
            .flat_map(|i| (0..N).map(move |j| (i, j)))
            .map(|(i, j)| (a[i][j] - b[i][j]).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn two_by_two_matches_the_closed_form() {
        // [[2, 1], [1, 2]] has eigenvalues 1 and 3
        let (mut l, _) = symmetric_eigen(&[[2.0, 1.0], [1.0, 2.0]]);
        l.sort_by(f64::total_cmp);
        assert!((l[0] - 1.0).abs() < 1e-14 && (l[1] - 3.0).abs() < 1e-14, "{l:?}");
        // an indefinite one projects to its positive part: λ = 3 with (1, 1)/√2
        let mut a = [[1.0, 2.0], [2.0, 1.0]];
        project_psd(&mut a);
        let want = [[1.5, 1.5], [1.5, 1.5]];
        assert!(max_diff(&a, &want) < 1e-14, "{a:?}");
    }

    proptest! {
        #[test]
        fn decomposition_reconstructs_and_is_orthonormal(v in prop::collection::vec(-5.0f64..5.0, 78)) {
            let a: [[f64; 12]; 12] = random_symmetric(&v);
            let (l, q) = symmetric_eigen(&a);
            let mut back = [[0.0; 12]; 12];
            let mut qtq = [[0.0; 12]; 12];
            for i in 0..12 {
                for j in 0..12 {
                    back[i][j] = (0..12).map(|k| q[i][k] * l[k] * q[j][k]).sum();
                    qtq[i][j] = (0..12).map(|k| q[k][i] * q[k][j]).sum();
                }
            }
            let mut eye = [[0.0; 12]; 12];
            for (i, row) in eye.iter_mut().enumerate() {
                row[i] = 1.0;
            }
            prop_assert!(max_diff(&back, &a) < 1e-12 * 60.0, "reconstruction {}", max_diff(&back, &a));
            prop_assert!(max_diff(&qtq, &eye) < 1e-13, "orthogonality {}", max_diff(&qtq, &eye));
        }

        #[test]
        fn projection_is_psd_idempotent_and_closest(v in prop::collection::vec(-5.0f64..5.0, 45)) {
            let a: [[f64; 9]; 9] = random_symmetric(&v);
            let mut p = a;
            project_psd(&mut p);
            let (l, _) = symmetric_eigen(&p);
            let scale = l.iter().fold(1.0f64, |s, x| s.max(x.abs()));
            prop_assert!(l.iter().all(|&x| x >= -1e-12 * scale), "{l:?}");
            // the removed part a - p is negative semi-definite and orthogonal to p
            let d: [[f64; 9]; 9] = std::array::from_fn(|i| std::array::from_fn(|j| a[i][j] - p[i][j]));
            let (ld, _) = symmetric_eigen(&d);
            prop_assert!(ld.iter().all(|&x| x <= 1e-12 * scale), "{ld:?}");
            let inner: f64 = (0..9).flat_map(|i| (0..9).map(move |j| (i, j))).map(|(i, j)| d[i][j] * p[i][j]).sum();
            prop_assert!(inner.abs() < 1e-10 * scale * scale, "{inner}");
            // projecting again changes nothing beyond rounding
            let mut pp = p;
            project_psd(&mut pp);
            prop_assert!(max_diff(&pp, &p) < 1e-12 * scale);
        }

        #[test]
        fn a_psd_matrix_is_left_bit_for_bit(v in prop::collection::vec(-5.0f64..5.0, 36)) {
            // BᵀB + I is positive definite
            let b: [[f64; 6]; 6] = std::array::from_fn(|i| std::array::from_fn(|j| v[6 * i + j]));
            let a: [[f64; 6]; 6] = std::array::from_fn(|i| std::array::from_fn(|j| {
                (0..6).map(|k| b[k][i] * b[k][j]).sum::<f64>() + if i == j { 1.0 } else { 0.0 }
            }));
            let mut p = a;
            project_psd(&mut p);
            prop_assert_eq!(p, a);
        }
    }
}
