//! Exact orientation predicates for the intersection checker.
//!
//! [`orient3d`] and [`orient2d`] return the *exact* sign of the orientation determinant of
//! finite `f64` points (provided no intermediate product overflows or underflows): a fast
//! floating-point evaluation is used when a forward error bound proves its sign, otherwise the
//! determinant is recomputed exactly as a sum of `f64` terms (exact products via fused
//! multiply-add, exact sums via non-overlapping expansions, after Shewchuk's "Adaptive Precision
//! Floating-Point Arithmetic").

use crate::math::Vec3;

/// `a + b = s + e` exactly.
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    (s, e)
}

/// `a × b = p + e` exactly (fused multiply-add gives the rounding error).
#[inline]
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

/// Adds `b` to the non-overlapping expansion `e` (increasing magnitude), exactly.
fn grow(e: &mut Vec<f64>, b: f64) {
    let mut q = b;
    for h in e.iter_mut() {
        let (s, err) = two_sum(q, *h);
        *h = err;
        q = s;
    }
    e.push(q);
    e.retain(|&h| h != 0.0);
}

/// Sign (-1, 0, 1) of the exact sum of `terms`.
fn exact_sign(terms: &[f64]) -> i32 {
    let mut e = Vec::with_capacity(terms.len());
    for &t in terms {
        grow(&mut e, t);
    }
    // the largest-magnitude non-zero component carries the sign
    match e.last() {
        Some(&v) if v > 0.0 => 1,
        Some(&v) if v < 0.0 => -1,
        _ => 0,
    }
}

/// `a - b` as an exact two-term sum.
#[inline]
fn diff(a: f64, b: f64) -> [f64; 2] {
    let (s, e) = two_sum(a, -b);
    [s, e]
}

/// Pushes the exact terms of `sign × u × v × w` (each factor a two-term sum).
fn push_product(out: &mut Vec<f64>, sign: f64, u: [f64; 2], v: [f64; 2], w: [f64; 2]) {
    for ui in u {
        for vj in v {
            let (p, e) = two_product(ui, vj);
            for x in [p, e] {
                for wk in w {
                    let (q, f) = two_product(x, wk);
                    out.push(sign * q);
                    out.push(sign * f);
                }
            }
        }
    }
}

/// Sign of `det[a-d; b-d; c-d]`: positive when `d` lies below the plane through `a, b, c`
/// (seen so that `a, b, c` turn counter-clockwise from above), zero when the four points are
/// coplanar, negative otherwise. Exact for finite input.
pub fn orient3d(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> i32 {
    let (ad, bd, cd) = (a - d, b - d, c - d);
    let m1 = bd.y * cd.z - bd.z * cd.y;
    let m2 = cd.y * ad.z - cd.z * ad.y;
    let m3 = ad.y * bd.z - ad.z * bd.y;
    let det = ad.x * m1 + bd.x * m2 + cd.x * m3;
    let perm = ad.x.abs() * ((bd.y * cd.z).abs() + (bd.z * cd.y).abs())
        + bd.x.abs() * ((cd.y * ad.z).abs() + (cd.z * ad.y).abs())
        + cd.x.abs() * ((ad.y * bd.z).abs() + (ad.z * bd.y).abs());
    let bound = 16.0 * f64::EPSILON * perm;
    if det > bound {
        return 1;
    }
    if det < -bound {
        return -1;
    }
    if !det.is_finite() {
        return 0;
    }
    let [adx, ady, adz] = [diff(a.x, d.x), diff(a.y, d.y), diff(a.z, d.z)];
    let [bdx, bdy, bdz] = [diff(b.x, d.x), diff(b.y, d.y), diff(b.z, d.z)];
    let [cdx, cdy, cdz] = [diff(c.x, d.x), diff(c.y, d.y), diff(c.z, d.z)];
    let mut t = Vec::with_capacity(192);
    push_product(&mut t, 1.0, adx, bdy, cdz);
    push_product(&mut t, -1.0, adx, bdz, cdy);
    push_product(&mut t, 1.0, bdx, cdy, adz);
    push_product(&mut t, -1.0, bdx, cdz, ady);
    push_product(&mut t, 1.0, cdx, ady, bdz);
    push_product(&mut t, -1.0, cdx, adz, bdy);
    exact_sign(&t)
}

/// Sign of `det[a-c; b-c]` for 2D points `[x, y]`: positive when `a, b, c` turn
/// counter-clockwise. Exact for finite input.
pub fn orient2d(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i32 {
    let (acx, acy, bcx, bcy) = (a[0] - c[0], a[1] - c[1], b[0] - c[0], b[1] - c[1]);
    let det = acx * bcy - acy * bcx;
    let bound = 8.0 * f64::EPSILON * ((acx * bcy).abs() + (acy * bcx).abs());
    if det > bound {
        return 1;
    }
    if det < -bound {
        return -1;
    }
    if !det.is_finite() {
        return 0;
    }
    let one = [1.0, 0.0];
    let mut t = Vec::with_capacity(32);
    push_product(&mut t, 1.0, diff(a[0], c[0]), diff(b[1], c[1]), one);
    push_product(&mut t, -1.0, diff(a[1], c[1]), diff(b[0], c[0]), one);
    exact_sign(&t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn orientation_of_simple_configurations() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!(orient3d(a, b, c, -Vec3::Z), 1);
        assert_eq!(orient3d(a, b, c, Vec3::Z), -1);
        assert_eq!(orient3d(a, b, c, Vec3::new(0.3, 0.7, 0.0)), 0);
        assert_eq!(orient2d([0.0, 0.0], [1.0, 0.0], [0.0, 1.0]), 1);
        assert_eq!(orient2d([0.0, 0.0], [1.0, 1.0], [2.0, 2.0]), 0);
    }

    #[test]
    fn nearly_degenerate_cases_are_exact() {
        // points on the line y = x, perturbed by one ulp: the naive determinant is unreliable
        let c = [24.0, 24.0];
        let b = [12.0, 12.0];
        for i in 0..64 {
            let x = 0.5 + i as f64 * f64::EPSILON;
            for (dy, want) in [(0.0, 0), (f64::EPSILON, 1), (-f64::EPSILON, -1)] {
                let a = [x, x + dy * x];
                if a[1] == x {
                    assert_eq!(orient2d(a, b, c), 0);
                } else {
                    assert_eq!(orient2d(a, b, c), want, "{a:?}");
                }
            }
        }
        // exactly coplanar points with non-representable combinations
        let p = Vec3::new(0.1, 0.2, 0.3);
        let u = Vec3::new(1.0, 0.0, 0.5);
        let v = Vec3::new(0.0, 1.0, 0.25);
        // d = p + 3u - 2v, computed exactly (small integers times exact binary fractions)
        let d = Vec3::new(0.1 + 3.0, 0.2 - 2.0, 0.3 + 1.5 - 0.5);
        let s = orient3d(p, p + u, p + v, d);
        // sign must agree with the exact determinant of (p, p+u, p+v, d) — check antisymmetry
        assert_eq!(s, -orient3d(p + u, p, p + v, d));
        assert_eq!(s, orient3d(p + u, p + v, p, d));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1000))]

        #[test]
        fn orient3d_is_antisymmetric_and_agrees_with_clear_cases(
            a in prop::array::uniform3(-1.0..1.0f64),
            b in prop::array::uniform3(-1.0..1.0f64),
            c in prop::array::uniform3(-1.0..1.0f64),
            s in -1.0..1.0f64, t in -1.0..1.0f64, tiny in -1e-15..1e-15f64,
        ) {
            let (a, b, c) = (Vec3::from_array(a), Vec3::from_array(b), Vec3::from_array(c));
            // d almost on the plane of a, b, c
            let n = (b - a).cross(c - a);
            let d = a + (b - a) * s + (c - a) * t + n * tiny;
            let o = orient3d(a, b, c, d);
            prop_assert_eq!(o, -orient3d(b, a, c, d));
            prop_assert_eq!(o, orient3d(b, c, a, d));
            prop_assert_eq!(o, -orient3d(a, b, d, c));
            let far = a + n;
            prop_assert_eq!(orient3d(a, b, c, far), if n.length() > 0.0 { -1 } else { 0 });
        }
    }
}
