//! Small dense symmetric matrices: eigen-decomposition (Householder reduction to tridiagonal
//! form, then the implicit QL algorithm), and the projection onto the positive semi-definite
//! cone that a force's local Hessian gets before it enters the implicit matrix (docs/MATH.md,
//! shell forces).
//!
//! The size is a compile-time constant (a membrane triangle's reduced Hessian is 6 × 6, a
//! hinge's 9 × 9); every loop runs in a fixed order with plain `+ − × ÷ √`, so the result has
//! the same bits everywhere. The algorithm is the one of EISPACK's `tred2` and `tql2` (Bowdler,
//! Martin, Reinsch & Wilkinson 1968; Golub & Van Loan §8.3). It replaced cyclic Jacobi
//! rotations, which the tests keep as the reference: the projection took 2.5 times less time on
//! `examples/cusick.toml` (BENCHMARKS.md, sixteenth session).

/// Implicit QL iterations per eigenvalue before accepting the current one (it converges
/// cubically: two or three iterations reach rounding).
const QL_ITERATIONS: usize = 30;

/// `√(a² + b²)` with the correctly rounded square root (not `libm`'s `hypot`, whose bits depend
/// on the platform). The arguments here are bounded well inside the range where `a²` is exact
/// enough (docs on [`tridiagonal_ql`]).
#[inline]
fn norm2(a: f64, b: f64) -> f64 {
    (a * a + b * b).sqrt()
}

/// The `N × N` identity.
fn identity<const N: usize>() -> [[f64; N]; N] {
    std::array::from_fn(|i| std::array::from_fn(|j| if i == j { 1.0 } else { 0.0 }))
}

/// Householder reduction of the symmetric `a` (full storage, both triangles equal) to a
/// tridiagonal `T = Qᵀ a Q`: returns `Q`, the diagonal of `T` and its off-diagonal
/// (`off[i] = T[i][i+1]`, `off[N-1] = 0`).
fn tridiagonalize<const N: usize>(mut a: [[f64; N]; N]) -> ([[f64; N]; N], [f64; N], [f64; N]) {
    let mut q = identity();
    let mut v = [0.0; N];
    let mut p = [0.0; N];
    for k in 0..N.saturating_sub(2) {
        // the reflection H = I − β v vᵀ that maps column k below the diagonal to (α, 0, …)
        let norm = (k + 1..N).map(|i| a[i][k] * a[i][k]).sum::<f64>().sqrt();
        if norm == 0.0 {
            continue;
        }
        let x0 = a[k + 1][k];
        let alpha = if x0 > 0.0 { -norm } else { norm };
        v[k + 1] = x0 - alpha;
        for i in k + 2..N {
            v[i] = a[i][k];
        }
        let vtv: f64 = (k + 1..N).map(|i| v[i] * v[i]).sum();
        if vtv == 0.0 {
            continue;
        }
        let beta = 2.0 / vtv;
        // the trailing block B ← H B H = B − v wᵀ − w vᵀ with p = β B v, w = p − (β vᵀp / 2) v
        for i in k + 1..N {
            p[i] = beta * (k + 1..N).map(|j| a[i][j] * v[j]).sum::<f64>();
        }
        let half = 0.5 * beta * (k + 1..N).map(|i| v[i] * p[i]).sum::<f64>();
        for i in k + 1..N {
            p[i] -= half * v[i];
        }
        for i in k + 1..N {
            for j in i..N {
                let value = a[i][j] - v[i] * p[j] - p[i] * v[j];
                a[i][j] = value;
                a[j][i] = value;
            }
        }
        a[k + 1][k] = alpha;
        a[k][k + 1] = alpha;
        for i in k + 2..N {
            a[i][k] = 0.0;
            a[k][i] = 0.0;
        }
        // Q ← Q H
        for row in q.iter_mut() {
            let s = beta * (k + 1..N).map(|j| row[j] * v[j]).sum::<f64>();
            for j in k + 1..N {
                row[j] -= s * v[j];
            }
        }
    }
    let diagonal = std::array::from_fn(|i| a[i][i]);
    let off = std::array::from_fn(|i| if i + 1 < N { a[i][i + 1] } else { 0.0 });
    (q, diagonal, off)
}

/// The implicit QL algorithm with Wilkinson-like shifts on the tridiagonal `(d, e)` (`e[i]`
/// couples `i` and `i + 1`, `e[N-1] = 0`), applying its rotations to the columns of `q`: on
/// return `d` holds the eigenvalues and `q` the eigenvectors. An off-diagonal element at most
/// `ε · max(|d_l| + |e_l|)` splits the matrix. The shifts keep `|p| ≲ 1/ε` times the matrix's
/// scale, so `norm2` neither overflows nor underflows for the finite Hessians it gets.
fn tridiagonal_ql<const N: usize>(d: &mut [f64; N], e: &mut [f64; N], q: &mut [[f64; N]; N]) {
    let mut shift_sum = 0.0;
    let mut largest = 0.0f64;
    for l in 0..N {
        largest = largest.max(d[l].abs() + e[l].abs());
        let small = |x: f64| x.abs() <= f64::EPSILON * largest;
        // the first negligible off-diagonal from l on (e[N-1] = 0 always is)
        let mut m = l;
        while m + 1 < N && !small(e[m]) {
            m += 1;
        }
        if m > l {
            for _ in 0..QL_ITERATIONS {
                // the shift: the eigenvalue of the leading 2 × 2 block nearer d[l]
                let g = d[l];
                let t = (d[l + 1] - g) / (2.0 * e[l]);
                let r = norm2(t, 1.0);
                let r = if t < 0.0 { -r } else { r };
                d[l] = e[l] / (t + r);
                d[l + 1] = e[l] * (t + r);
                let next = d[l + 1];
                let h = g - d[l];
                for di in d.iter_mut().skip(l + 2) {
                    *di -= h;
                }
                shift_sum += h;
                // the QL sweep from m up to l, chasing the bulge with plane rotations
                let mut p = d[m];
                let (mut c, mut c2, mut c3) = (1.0, 1.0, 1.0);
                let (mut s, mut s2) = (0.0, 0.0);
                let e_next = e[l + 1];
                for i in (l..m).rev() {
                    c3 = c2;
                    c2 = c;
                    s2 = s;
                    let g = c * e[i];
                    let h = c * p;
                    let r = norm2(p, e[i]);
                    e[i + 1] = s * r;
                    s = e[i] / r;
                    c = p / r;
                    p = c * d[i] - s * g;
                    d[i + 1] = h + s * (c * g + s * d[i]);
                    for row in q.iter_mut() {
                        let (qi, qn) = (row[i], row[i + 1]);
                        row[i + 1] = s * qi + c * qn;
                        row[i] = c * qi - s * qn;
                    }
                }
                let p = -s * s2 * c3 * e_next * e[l] / next;
                e[l] = s * p;
                d[l] = c * p;
                if small(e[l]) {
                    break;
                }
            }
        }
        d[l] += shift_sum;
        e[l] = 0.0;
    }
}

/// Eigenvalues `λ` and eigenvectors (columns of `q`) of the symmetric `a`: `a = q diag(λ) qᵀ`,
/// in no particular order. Only the upper triangle of `a` is read.
pub fn symmetric_eigen<const N: usize>(a: &[[f64; N]; N]) -> ([f64; N], [[f64; N]; N]) {
    let mut m = *a;
    for i in 0..N {
        for j in 0..i {
            m[i][j] = m[j][i];
        }
    }
    let scale = m.iter().flatten().fold(0.0f64, |s, &v| s.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return (std::array::from_fn(|i| m[i][i]), identity());
    }
    let (mut q, mut d, mut e) = tridiagonalize(m);
    tridiagonal_ql(&mut d, &mut e, &mut q);
    (d, q)
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

    /// The reference: cyclic Jacobi rotations (Golub & Van Loan, Algorithm 8.4.3), slow and
    /// independent of the Householder–QL code; eigenvalues and eigenvectors (columns).
    fn jacobi<const N: usize>(a: &[[f64; N]; N]) -> ([f64; N], [[f64; N]; N]) {
        let mut m = *a;
        let mut q = identity();
        for _ in 0..100 {
            let off: f64 = (0..N)
                .flat_map(|i| (i + 1..N).map(move |j| (i, j)))
                .map(|(i, j)| m[i][j] * m[i][j])
                .sum();
            let scale = m.iter().flatten().fold(0.0f64, |s, &v| s.max(v.abs()));
            if off <= (f64::EPSILON * scale).powi(2) {
                break;
            }
            for p in 0..N {
                for r in p + 1..N {
                    if m[p][r] == 0.0 {
                        continue;
                    }
                    let tau = (m[r][r] - m[p][p]) / (2.0 * m[p][r]);
                    let t = if tau == 0.0 {
                        1.0
                    } else {
                        tau.signum() / (tau.abs() + (1.0 + tau * tau).sqrt())
                    };
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

    /// Matrices that take the code's special paths: a diagonal one (no reflection, no QL
    /// iteration), an already tridiagonal one, a zero column below the diagonal, a repeated
    /// eigenvalue, and the sizes 1 and 2.
    #[test]
    fn ql_handles_the_special_shapes() {
        let diagonal = [[3.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 2.0]];
        assert_eq!(symmetric_eigen(&diagonal).0, [3.0, -1.0, 2.0]);
        // the path graph's Laplacian-like [[2,-1,0,0],[-1,2,-1,0],...]: λ_k = 2 − 2 cos(kπ/5)
        let mut path = [[0.0; 4]; 4];
        for i in 0..4 {
            path[i][i] = 2.0;
            if i + 1 < 4 {
                path[i][i + 1] = -1.0;
                path[i + 1][i] = -1.0;
            }
        }
        let (mut l, _) = symmetric_eigen(&path);
        l.sort_by(f64::total_cmp);
        for (k, x) in l.iter().enumerate() {
            let want = 2.0 - 2.0 * (std::f64::consts::PI * (k + 1) as f64 / 5.0).cos();
            assert!((x - want).abs() < 1e-14, "{l:?}");
        }
        let zero_column = [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 2.0, 1.0, 1.0],
            [0.0, 1.0, 2.0, 1.0],
            [0.0, 1.0, 1.0, 2.0],
        ];
        let repeated = [[2.0, 1.0, 1.0], [1.0, 2.0, 1.0], [1.0, 1.0, 2.0]]; // 1, 1, 4
        let one = [[-7.5]];
        for check in [
            agrees_with_jacobi(&zero_column, 1e-14),
            agrees_with_jacobi(&repeated, 1e-14),
            agrees_with_jacobi(&one, 0.0),
            agrees_with_jacobi(&[[1.0, 2.0], [2.0, -3.0]], 1e-14),
        ] {
            check.unwrap();
        }
        let (mut l, _) = symmetric_eigen(&repeated);
        l.sort_by(f64::total_cmp);
        assert!(
            (l[0] - 1.0).abs() < 1e-14 && (l[1] - 1.0).abs() < 1e-14 && (l[2] - 4.0).abs() < 1e-14,
            "{l:?}"
        );
    }

    #[test]
    fn two_by_two_matches_the_closed_form() {
        // [[2, 1], [1, 2]] has eigenvalues 1 and 3
        let (mut l, _) = symmetric_eigen(&[[2.0, 1.0], [1.0, 2.0]]);
        l.sort_by(f64::total_cmp);
        assert!(
            (l[0] - 1.0).abs() < 1e-14 && (l[1] - 3.0).abs() < 1e-14,
            "{l:?}"
        );
        // an indefinite one projects to its positive part: λ = 3 with (1, 1)/√2
        let mut a = [[1.0, 2.0], [2.0, 1.0]];
        project_psd(&mut a);
        let want = [[1.5, 1.5], [1.5, 1.5]];
        assert!(max_diff(&a, &want) < 1e-14, "{a:?}");
    }

    /// Sorted eigenvalues of both algorithms agree within `tol` times the largest magnitude,
    /// and the QL decomposition reconstructs `a` with orthonormal vectors.
    fn agrees_with_jacobi<const N: usize>(
        a: &[[f64; N]; N],
        tol: f64,
    ) -> Result<(), TestCaseError> {
        let (lu, q) = symmetric_eigen(a);
        let (mut lj, _) = jacobi(a);
        let mut l = lu;
        l.sort_by(f64::total_cmp);
        lj.sort_by(f64::total_cmp);
        let scale = lj.iter().fold(f64::MIN_POSITIVE, |s, x| s.max(x.abs()));
        for (x, y) in l.iter().zip(&lj) {
            prop_assert!((x - y).abs() <= tol * scale, "{l:?} against {lj:?}");
        }
        for i in 0..N {
            for j in 0..N {
                let b: f64 = (0..N).map(|k| q[i][k] * lu[k] * q[j][k]).sum();
                prop_assert!(
                    (b - a[i][j]).abs() <= tol * scale,
                    "reconstruction at {i} {j}"
                );
                let o: f64 = (0..N).map(|k| q[k][i] * q[k][j]).sum();
                let eye = if i == j { 1.0 } else { 0.0 };
                prop_assert!((o - eye).abs() <= 1e-13, "orthogonality at {i} {j}: {o}");
            }
        }
        Ok(())
    }

    proptest! {
        #[test]
        fn ql_agrees_with_jacobi_on_random_matrices(v in prop::collection::vec(-5.0f64..5.0, 78)) {
            agrees_with_jacobi::<6>(&random_symmetric(&v), 1e-13)?;
            agrees_with_jacobi::<9>(&random_symmetric(&v), 1e-13)?;
            agrees_with_jacobi::<12>(&random_symmetric(&v), 1e-13)?;
        }

        /// Low rank (a Hessian near rest is nearly `g gᵀ`), repeated zero eigenvalues, one
        /// negative direction, and entries spanning nine orders of magnitude.
        #[test]
        fn ql_agrees_with_jacobi_on_low_rank_and_graded_matrices(
            u in prop::collection::vec(-1.0f64..1.0, 27),
            w in prop::array::uniform3(-3.0f64..3.0),
            exponent in -6.0f64..3.0,
        ) {
            let mut a = [[0.0; 9]; 9];
            for (r, weight) in w.iter().enumerate() {
                for i in 0..9 {
                    for j in 0..9 {
                        a[i][j] += weight * u[9 * r + i] * u[9 * r + j];
                    }
                }
            }
            agrees_with_jacobi::<9>(&a, 1e-13)?;
            let graded: [[f64; 9]; 9] = std::array::from_fn(|i| std::array::from_fn(|j| {
                a[i][j] * 10f64.powf(exponent * (i + j) as f64 / 16.0)
            }));
            agrees_with_jacobi::<9>(&graded, 1e-12)?;
        }

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
            let eye: [[f64; 12]; 12] = identity();
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

        /// The projection is the positive part of a matrix built from a known spectrum with one
        /// to eight negative eigenvalues, and exactly symmetric.
        #[test]
        fn projection_is_the_positive_part_of_a_known_spectrum(
            u in prop::collection::vec(-1.0f64..1.0, 81),
            negatives in 1usize..9,
        ) {
            // a = Σ_k w_k u_k u_kᵀ with u_k orthonormalized by Gram–Schmidt, w known
            let mut basis: Vec<[f64; 9]> = Vec::new();
            for k in 0..9 {
                let mut v: [f64; 9] = std::array::from_fn(|i| u[9 * k + i] + if i == k { 2.0 } else { 0.0 });
                // two passes ("twice is enough"): with one, the regression file's second case
                // had a basis orthonormal only to 5.9e-12, and `want` was not the positive
                // part of `a` (the check failed at 1.7e-11); with two, to 2.2e-16
                for _pass in 0..2 {
                    for b in &basis {
                        let d: f64 = (0..9).map(|i| v[i] * b[i]).sum();
                        for i in 0..9 {
                            v[i] -= d * b[i];
                        }
                    }
                }
                let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                basis.push(v.map(|x| x / n));
            }
            let w: [f64; 9] = std::array::from_fn(|k| if k < negatives { -1.0 - k as f64 } else { 0.5 + k as f64 });
            let a: [[f64; 9]; 9] = std::array::from_fn(|i| std::array::from_fn(|j| {
                (0..9).map(|k| w[k] * basis[k][i] * basis[k][j]).sum()
            }));
            let want: [[f64; 9]; 9] = std::array::from_fn(|i| std::array::from_fn(|j| {
                (0..9).filter(|&k| w[k] > 0.0).map(|k| w[k] * basis[k][i] * basis[k][j]).sum()
            }));
            let mut p = a;
            project_psd(&mut p);
            // rounding relative to the spectrum, as in the other tests here: an absolute 1e-12
            // failed at 1.2e-12 for eigenvalues up to 8.5 (the regression file's case)
            let scale = w.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            prop_assert!(max_diff(&p, &want) < 1e-12 * scale, "{}", max_diff(&p, &want));
            for i in 0..9 {
                for j in 0..9 {
                    prop_assert_eq!(p[i][j], p[j][i]);
                }
            }
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
